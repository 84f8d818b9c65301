//! Random CAN frames and their renderings in the three trace formats, with
//! random valid variations (padding, case, separators, fraction digits, -x
//! columns, ASC base dec...). Shared by the property tests: roundtrip, trc
//! and blf here, and the library's conservation test
//! (`src/analyze/tests/`), which includes this file with `#[path]`. So it
//! names the library's types as `crate::...`: the library root, or the
//! test binary's root, which imports them from `emcy_decode`.

use crate::{FrameKind, Timestamp};
use proptest::prelude::*;

#[derive(Clone, Debug)]
pub struct TestFrame {
    pub secs: u64,
    pub frac: u64,
    pub digits: u8,
    pub channel: String,
    pub id: u32,
    pub kind: FrameKind,
    pub extended: bool,
    pub data: Vec<u8>,
}

impl TestFrame {
    pub fn time(&self) -> Timestamp {
        Timestamp::from_parts(self.secs, self.frac, self.digits)
    }
    pub fn time_text(&self) -> String {
        format!(
            "{}.{:0w$}",
            self.secs,
            self.frac,
            w = usize::from(self.digits)
        )
    }
}

pub fn frame() -> impl Strategy<Value = TestFrame> {
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
                    // The class bits, as every reader gives them.
                    FrameKind::Error => (eid & 0x1FF, false),
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
pub struct LogStyle {
    pub lower: bool,
    pub dots: bool,
    pub pad: usize,
    pub suffix: Option<char>,
}

pub fn log_style() -> impl Strategy<Value = LogStyle> {
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

pub fn hex(data: &[u8], sep: &str, lower: bool) -> String {
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

pub fn render_log(f: &TestFrame, s: &LogStyle) -> String {
    let id = if f.kind == FrameKind::Error {
        // candump writes an error frame's class bits with the error flag.
        format!("{:08X}", 0x2000_0000 | f.id)
    } else if f.extended {
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
pub struct ScreenStyle {
    pub time: bool,
    pub extra: bool,
    pub ascii: bool,
}

pub fn screen_style() -> impl Strategy<Value = ScreenStyle> {
    (any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(time, extra, ascii)| ScreenStyle {
        time,
        extra,
        ascii,
    })
}

pub fn render_screen(f: &TestFrame, s: &ScreenStyle) -> String {
    let ts = if s.time {
        format!(" ({}) ", f.time_text())
    } else {
        " ".to_string()
    };
    let extra = if s.extra { "  RX - -" } else { "" };
    let id = if f.kind == FrameKind::Error {
        // candump writes an error frame's class bits with the error flag.
        format!("{:08X}", 0x2000_0000 | f.id)
    } else if f.extended {
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
pub struct AscStyle {
    pub dec: bool,
    pub tail: bool,
    /// Classic frames written as CANFD lines without the FDF flag (log2asc -f).
    pub canfd_classic: bool,
    pub name: Option<String>,
    pub channel: u8,
    pub tx: bool,
}

pub fn asc_style() -> impl Strategy<Value = AscStyle> {
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

pub fn render_asc(f: &TestFrame, s: &AscStyle) -> Vec<String> {
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

pub const FD_LENS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// The smallest CAN FD DLC whose length holds `n` bytes.
pub fn fd_dlc(n: usize) -> usize {
    FD_LENS.iter().position(|&l| l >= n).unwrap_or(15)
}
