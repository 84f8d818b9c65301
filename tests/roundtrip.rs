//! Property tests for the readers: random frames, rendered in each format with
//! random valid variations (padding, case, separators, fraction digits, -x
//! columns, ASC base dec...), read back through format detection, must come
//! back as the same frames.

use emcy_decode::trace::detect::Detector;
use emcy_decode::trace::{FrameKind, Interest, Parsed, Timestamp};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct TestFrame {
    secs: u64,
    frac: u64,
    digits: u8,
    channel: String,
    id: u32,
    kind: FrameKind,
    extended: bool,
    data: Vec<u8>,
}

impl TestFrame {
    fn time(&self) -> Timestamp {
        Timestamp::from_parts(self.secs, self.frac, self.digits)
    }
    fn time_text(&self) -> String {
        format!(
            "{}.{:0w$}",
            self.secs,
            self.frac,
            w = usize::from(self.digits)
        )
    }
}

fn frame() -> impl Strategy<Value = TestFrame> {
    let kind = prop_oneof![
        4 => Just(FrameKind::Data),
        1 => Just(FrameKind::Remote),
        1 => Just(FrameKind::Fd),
        1 => Just(FrameKind::Error),
    ];
    (
        kind,
        any::<bool>(),
        0u32..=0x7FF,
        0u32..=0x1FFF_FFFF,
        prop::collection::vec(any::<u8>(), 0..=64),
        0u64..=9_999_999_999,
        1u8..=9,
        any::<u64>(),
        "[a-z][a-z0-9_.-]{0,7}",
    )
        .prop_map(
            |(kind, ext, sid, eid, mut data, secs, digits, frac, channel)| {
                let frac = frac % 10u64.pow(u32::from(digits));
                let (id, extended) = match kind {
                    FrameKind::Error => (0x2000_0000 | (eid & 0x1FF), true),
                    FrameKind::Fd => (if ext { eid } else { sid }, ext),
                    _ => (if ext { eid } else { sid }, ext),
                };
                match kind {
                    FrameKind::Remote => data.clear(),
                    FrameKind::Fd => {}
                    FrameKind::Error => data.resize(8, 0),
                    FrameKind::Data => data.truncate(8),
                }
                TestFrame {
                    secs,
                    frac,
                    digits,
                    channel,
                    id,
                    kind,
                    extended,
                    data,
                }
            },
        )
}

#[derive(Clone, Debug)]
struct LogStyle {
    lower: bool,
    dots: bool,
    pad: usize,
    suffix: Option<char>,
}

fn log_style() -> impl Strategy<Value = LogStyle> {
    (
        any::<bool>(),
        any::<bool>(),
        0usize..4,
        prop::option::of(prop_oneof![Just('T'), Just('R')]),
    )
        .prop_map(|(lower, dots, pad, suffix)| LogStyle {
            lower,
            dots,
            pad,
            suffix,
        })
}

fn hex(data: &[u8], sep: &str, lower: bool) -> String {
    let parts: Vec<String> = data
        .iter()
        .map(|b| {
            if lower {
                format!("{b:02x}")
            } else {
                format!("{b:02X}")
            }
        })
        .collect();
    parts.join(sep)
}

fn render_log(f: &TestFrame, s: &LogStyle) -> String {
    let id = if f.extended {
        format!("{:08X}", f.id)
    } else {
        format!("{:03X}", f.id)
    };
    let id = if s.lower { id.to_lowercase() } else { id };
    let sep = if s.dots { "." } else { "" };
    let body = match f.kind {
        FrameKind::Remote => "R".to_string(),
        FrameKind::Fd => format!("#{}{}", 1, hex(&f.data, sep, s.lower)),
        _ => hex(&f.data, sep, s.lower),
    };
    let mut line = format!(
        "({}) {}{} {id}#{body}",
        f.time_text(),
        " ".repeat(s.pad),
        f.channel
    );
    if let Some(c) = s.suffix {
        line.push(' ');
        line.push(c);
    }
    line
}

#[derive(Clone, Debug)]
struct ScreenStyle {
    time: bool,
    extra: bool,
    ascii: bool,
}

fn screen_style() -> impl Strategy<Value = ScreenStyle> {
    (any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(time, extra, ascii)| ScreenStyle {
        time,
        extra,
        ascii,
    })
}

fn render_screen(f: &TestFrame, s: &ScreenStyle) -> String {
    let ts = if s.time {
        format!(" ({}) ", f.time_text())
    } else {
        " ".to_string()
    };
    let extra = if s.extra { "  RX - -" } else { "" };
    let id = if f.extended {
        format!("{:08X}", f.id)
    } else {
        format!("{:03X}", f.id)
    };
    let bytes = hex(&f.data, " ", false);
    let body = match f.kind {
        FrameKind::Remote => "[0]  remote request".to_string(),
        FrameKind::Fd => format!("[{:02}]  {bytes}", f.data.len()),
        FrameKind::Error => format!("[{}]  {bytes}   ERRORFRAME", f.data.len()),
        FrameKind::Data => {
            let mut b = format!("[{}]  {bytes}", f.data.len());
            if s.ascii && !f.data.is_empty() {
                let ascii: String = f
                    .data
                    .iter()
                    .map(|&c| {
                        if (0x20..0x7F).contains(&c) {
                            c as char
                        } else {
                            '.'
                        }
                    })
                    .collect();
                b.push_str(&format!("   '{ascii}'"));
            }
            b
        }
    };
    format!("{ts} {}{extra}  {id}   {body}", f.channel)
}

#[derive(Clone, Debug)]
struct AscStyle {
    dec: bool,
    tail: bool,
    /// Classic frames written as CANFD lines without the FDF flag (log2asc -f).
    canfd_classic: bool,
    name: Option<String>,
    channel: u8,
    tx: bool,
}

fn asc_style() -> impl Strategy<Value = AscStyle> {
    (
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        prop::option::of("[A-Za-z_][A-Za-z0-9_]{0,12}|[0-9]{1,4}"),
        1u8..=16,
        any::<bool>(),
    )
        .prop_map(|(dec, tail, canfd_classic, name, channel, tx)| AscStyle {
            dec,
            tail,
            canfd_classic,
            name,
            channel,
            tx,
        })
}

fn render_asc(f: &TestFrame, s: &AscStyle) -> Vec<String> {
    let num = |v: u32| {
        if s.dec {
            v.to_string()
        } else {
            format!("{v:X}")
        }
    };
    let mut data = f.data.clone();
    if f.kind == FrameKind::Fd {
        // ASC writes whole FD lengths (DLC 9-15 = 12..64 bytes): pad with zeros.
        data.resize(FD_LENS[fd_dlc(data.len())], 0);
    }
    let bytes: Vec<String> = data.iter().map(|b| num(u32::from(*b))).collect();
    let bytes = bytes.join(" ");
    let id = format!("{}{}", num(f.id), if f.extended { "x" } else { "" });
    let dir = if s.tx { "Tx" } else { "Rx" };
    let t = f.time_text();
    let ch = s.channel;
    let name = s.name.clone().unwrap_or_default();
    let tail = "   102203  133   {flags} e0006659 46500250 4b140250 20011736 2001040d";
    let line = match f.kind {
        FrameKind::Error => format!("{t} {ch}  ErrorFrame"),
        FrameKind::Remote => format!("{t} {ch}  {id}             {dir}   r"),
        FrameKind::Fd => {
            let n = data.len();
            let dlc = fd_dlc(n);
            format!(
                "{t} CANFD {ch:3} {dir} {id:>10}  {name}  1 0 {dlc:X} {n:2} {bytes}{}",
                tail.replace("{flags}", "303000")
            )
        }
        FrameKind::Data if s.canfd_classic => {
            let n = f.data.len();
            format!(
                "{t} CANFD {ch:3} {dir} {id:>10}  {name}  0 0 {n:X} {n:2} {bytes}{}",
                tail.replace("{flags}", "0")
            )
        }
        FrameKind::Data => {
            let extra = if s.tail {
                format!(
                    "  Length = 228000 BitCount = 118 ID = {}{}",
                    f.id,
                    if f.extended { "x" } else { "" }
                )
            } else {
                String::new()
            };
            format!(
                "{t} {ch}  {id:<15} {dir}   d {} {bytes}{extra}",
                f.data.len()
            )
        }
    };
    let base = if s.dec { "dec" } else { "hex" };
    vec![format!("base {base}  timestamps absolute"), line]
}

const FD_LENS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// The smallest CAN FD DLC whose length holds `n` bytes.
fn fd_dlc(n: usize) -> usize {
    FD_LENS.iter().position(|&l| l >= n).unwrap_or(15)
}

fn check(line: &str, f: &TestFrame, with_time: bool) -> Result<(), TestCaseError> {
    check_lines(&[line.to_string()], f, with_time, false)
}

fn check_lines(
    lines: &[String],
    f: &TestFrame,
    with_time: bool,
    asc: bool,
) -> Result<(), TestCaseError> {
    let mut detector = Detector::auto();
    let (last, header) = lines.split_last().expect("at least one line");
    for h in header {
        prop_assert_eq!(
            detector.parse(h.as_bytes(), &Interest::all()),
            Parsed::Skipped
        );
    }
    let line = last.as_str();
    let parsed = detector.parse(line.as_bytes(), &Interest::all());
    let Parsed::Frame(got) = parsed else {
        return Err(TestCaseError::fail(format!("{line:?} -> {parsed:?}")));
    };
    prop_assert_eq!(got.kind, f.kind, "{}", line);
    if asc && f.kind == FrameKind::Error {
        // ASC error frames carry no id.
        return Ok(());
    }
    prop_assert_eq!(got.id, f.id, "{}", line);
    prop_assert_eq!(got.extended, f.extended, "{}", line);
    if !asc {
        prop_assert_eq!(got.channel, f.channel.as_bytes(), "{}", line);
    }
    if f.kind != FrameKind::Remote {
        // An FD frame is padded up to the next valid FD length.
        let n = if f.kind == FrameKind::Fd && asc {
            usize::from(got.len)
        } else {
            f.data.len()
        };
        prop_assert_eq!(
            &got.data.as_slice()[..f.data.len().min(n)],
            f.data.as_slice(),
            "{}",
            line
        );
        prop_assert_eq!(usize::from(got.len), n, "{}", line);
    }
    if with_time {
        prop_assert_eq!(got.time, Some(f.time()), "{}", line);
    } else {
        prop_assert_eq!(got.time, None, "{}", line);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn candump_log_roundtrip(f in frame(), style in log_style()) {
        check(&render_log(&f, &style), &f, true)?;
    }

    #[test]
    fn candump_screen_roundtrip(f in frame(), style in screen_style()) {
        check(&render_screen(&f, &style), &f, style.time)?;
    }

    #[test]
    fn asc_roundtrip(f in frame(), style in asc_style()) {
        check_lines(&render_asc(&f, &style), &f, true, true)?;
    }
}
