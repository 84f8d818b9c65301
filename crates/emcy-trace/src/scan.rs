//! Word-at-a-time (SWAR) scanning for the readers' hot path: eight bytes per
//! step with plain integer arithmetic, no `unsafe`. Each function has a naive
//! twin in the tests and a property test that they agree.

const LO: u64 = 0x0101_0101_0101_0101;
const HI: u64 = 0x8080_8080_8080_8080;
const LOW7: u64 = 0x7F7F_7F7F_7F7F_7F7F;

/// The eight bytes at `at` as a little-endian word (first byte lowest).
#[inline(always)]
pub fn word(s: &[u8], at: usize) -> Option<u64> {
    let bytes: [u8; 8] = s.get(at..at + 8)?.try_into().ok()?;
    Some(u64::from_le_bytes(bytes))
}

/// High bit set in every byte of `x` that is greater than `n` (n < 128).
#[inline(always)]
fn bytes_above(x: u64, n: u8) -> u64 {
    // Masking to 7 bits first keeps the addition from carrying across bytes.
    (((x & LOW7) + LO * u64::from(127 - n)) | x) & HI
}

/// High bit set in every zero byte of `x` (exact, no false positives).
#[inline(always)]
fn zero_bytes(x: u64) -> u64 {
    !(((x & LOW7) + LOW7) | x | LOW7)
}

/// High bit set in every byte of `x` that is not an ASCII digit.
#[inline(always)]
pub fn non_digits(x: u64) -> u64 {
    bytes_above(x ^ (LO * u64::from(b'0')), 9)
}

/// High bit set in every byte of `x` that is not a hex digit (either case).
#[inline(always)]
fn non_hex(x: u64) -> u64 {
    // Letters: fold case, then a..f is 0x61..0x66, i.e. (x|0x20)^0x60 in 1..=6.
    let letters = (x | (LO * 0x20)) ^ (LO * 0x60);
    let not_letter = bytes_above(letters, 6) | zero_bytes(letters);
    non_digits(x) & not_letter
}

#[inline(always)]
fn first_marked(mask: u64) -> usize {
    (mask.trailing_zeros() / 8) as usize
}

/// Length of the run of ASCII digits starting at `from`.
#[inline]
pub fn digit_run(s: &[u8], from: usize) -> usize {
    let mut i = from;
    while let Some(x) = word(s, i) {
        let m = non_digits(x);
        if m != 0 {
            return i + first_marked(m) - from;
        }
        i += 8;
    }
    while let Some(b) = s.get(i) {
        if !b.is_ascii_digit() {
            break;
        }
        i += 1;
    }
    i.saturating_sub(from)
}

/// Length of the run of hex digits starting at `from`.
#[inline]
pub fn hex_run(s: &[u8], from: usize) -> usize {
    let mut i = from;
    while let Some(x) = word(s, i) {
        let m = non_hex(x);
        if m != 0 {
            return i + first_marked(m) - from;
        }
        i += 8;
    }
    while let Some(b) = s.get(i) {
        if !b.is_ascii_hexdigit() {
            break;
        }
        i += 1;
    }
    i.saturating_sub(from)
}

/// Length of the run of bytes above b' ' (no space, tab or control byte)
/// starting at `from`: a device name or token.
#[inline]
pub fn token_run(s: &[u8], from: usize) -> usize {
    let mut i = from;
    while let Some(x) = word(s, i) {
        // Bytes >= 0x80 count as "above" (UTF-8 in device names is fine).
        let small = !bytes_above(x, 0x20) & HI;
        if small != 0 {
            return i + first_marked(small) - from;
        }
        i += 8;
    }
    while let Some(&b) = s.get(i) {
        if b <= b' ' {
            break;
        }
        i += 1;
    }
    i.saturating_sub(from)
}

/// Length of the run of spaces and tabs starting at `from`.
#[inline]
pub fn blank_run(s: &[u8], from: usize) -> usize {
    let mut i = from;
    // Most runs are one to three blanks: bytes first, words for the long ones.
    for _ in 0..4 {
        match s.get(i) {
            Some(b' ' | b'\t') => i += 1,
            _ => return i - from,
        }
    }
    while let Some(x) = word(s, i) {
        let spaces = zero_bytes(x ^ (LO * u64::from(b' ')));
        let tabs = zero_bytes(x ^ (LO * u64::from(b'\t')));
        let other = !(spaces | tabs) & HI;
        if other != 0 {
            return i + first_marked(other) - from;
        }
        i += 8;
    }
    while let Some(&b) = s.get(i) {
        if b != b' ' && b != b'\t' {
            break;
        }
        i += 1;
    }
    i.saturating_sub(from)
}

/// True when every byte of `s` is a hex digit. Whole words, the last one
/// overlapping the previous, so no byte loop for lengths >= 8.
#[inline]
pub fn all_hex(s: &[u8]) -> bool {
    let n = s.len();
    if n < 8 {
        return s.iter().all(u8::is_ascii_hexdigit);
    }
    let mut bad = 0;
    let mut i = 0;
    while i + 8 <= n {
        bad |= word(s, i).map_or(HI, non_hex);
        i += 8;
    }
    if i < n {
        bad |= word(s, n - 8).map_or(HI, non_hex);
    }
    bad == 0
}

/// True when every byte of `line[start..end]` is a hex digit. Like
/// [`all_hex`], but a run shorter than a word is checked with one word
/// ending at `end` (bytes before `start` masked off) when the line has
/// eight bytes there: the data field of a frame line.
#[inline]
pub fn all_hex_at(line: &[u8], start: usize, end: usize) -> bool {
    let n = end.wrapping_sub(start);
    if n <= 16
        && start <= end
        && let Some(last) = end.checked_sub(8).and_then(|at| word(line, at))
    {
        // The run's last `min(n, 8)` bytes are the top of `last`; a longer
        // run also has its first eight bytes in a word of its own.
        let keep = if n == 0 {
            0
        } else {
            HI << (8 * (8 - n.min(8)))
        };
        let first = if n > 8 {
            word(line, start).map_or(HI, non_hex)
        } else {
            0
        };
        return (non_hex(last) & keep) | first == 0;
    }
    line.get(start..end).is_some_and(all_hex)
}

/// Keeps the first `n` bytes of a little-endian word (all when `n >= 8`).
#[inline(always)]
fn head_mask(n: usize) -> u64 {
    if n >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * n)) - 1
    }
}

/// Exactly these bytes (at most 16) at a given place of a line, compared a
/// word at a time: the fixed separators of a line layout (`) can0 `).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fixed {
    len: usize,
    /// The first eight bytes (masked to `len` when shorter); when longer,
    /// also the last eight.
    head: u64,
    tail: u64,
}

impl Fixed {
    /// The bytes `line[at..at + len]`; `None` when longer than 16 or when
    /// the line does not hold eight bytes from `at` (words are read whole).
    pub fn of(line: &[u8], at: usize, len: usize) -> Option<Fixed> {
        if len > 16 {
            return None;
        }
        Some(Fixed {
            len,
            head: word(line, at)? & head_mask(len),
            tail: if len > 8 {
                word(line, at + len - 8)?
            } else {
                0
            },
        })
    }

    /// How many bytes.
    pub fn width(&self) -> usize {
        self.len
    }

    /// Whether `line` has these bytes at `at` (and eight bytes to read there).
    #[inline]
    pub fn matches(&self, line: &[u8], at: usize) -> bool {
        word(line, at).is_some_and(|w| w & head_mask(self.len) == self.head)
            && (self.len <= 8 || word(line, at + self.len - 8) == Some(self.tail))
    }
}

/// A number `DIGITS.DIGITS` at fixed places (at least eight characters):
/// three overlapping words must show a non-digit at the dot and only there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decimal {
    probes: [(usize, u64); 3],
}

impl Decimal {
    /// For the number in `start..end` with its dot at `dot`.
    pub fn new(start: usize, dot: usize, end: usize) -> Option<Decimal> {
        let last = end
            .checked_sub(8)
            .filter(|l| *l >= start && end - start <= 24)?;
        let probe = |p: usize| {
            let mask = match dot.checked_sub(p) {
                Some(k) if k < 8 => 0x80u64 << (8 * k),
                _ => 0,
            };
            (p, mask)
        };
        Some(Decimal {
            probes: [probe(start), probe((start + 8).min(last)), probe(last)],
        })
    }

    /// Whether `line` has digits at every place but the dot, and a
    /// non-digit there (the caller checks it is a dot). Covers up to 24
    /// characters; longer numbers are never given a layout.
    #[inline]
    pub fn matches(&self, line: &[u8]) -> bool {
        self.probes
            .iter()
            .all(|&(at, expect)| word(line, at).map(non_digits) == Some(expect))
    }
}

/// True when `line[start..end]` (at most 16 bytes, `end >= 8`) is all spaces.
#[inline]
pub fn all_spaces_at(line: &[u8], start: usize, end: usize) -> bool {
    let n = end.wrapping_sub(start);
    if start > end || n > 16 {
        return false;
    }
    let spaces = LO * u64::from(b' ');
    let keep = if n == 0 {
        0
    } else {
        u64::MAX << (8 * (8 - n.min(8)))
    };
    let last = end.checked_sub(8).and_then(|at| word(line, at));
    let first_ok = n <= 8 || word(line, start) == Some(spaces);
    last.is_some_and(|w| (w ^ spaces) & keep == 0) && first_ok
}

/// Value of a run of at most 19 ASCII digits (caller validated them).
#[inline]
pub fn decimal_u64(digits: &[u8]) -> u64 {
    let mut v = 0u64;
    let mut rest = digits;
    while let Some((eight, tail)) = rest.split_first_chunk::<8>() {
        v = v
            .wrapping_mul(100_000_000)
            .wrapping_add(eight_digits(u64::from_le_bytes(*eight)));
        rest = tail;
    }
    rest.iter().fold(v, |v, &d| {
        v.wrapping_mul(10)
            .wrapping_add(u64::from(d.wrapping_sub(b'0')))
    })
}

/// The value of the digits in `start..end` with the one at `dot` left out
/// (a time's integer and fraction digits as one number), for digits the
/// caller validated; `None` past 19 digits (they could overflow). Six
/// fraction digits, what candump writes, take two words: the last two
/// integer digits and the fraction are one eight-digit word once the dot
/// is cut out.
#[inline(never)]
pub fn decimal_ticks(line: &[u8], start: usize, dot: usize, end: usize) -> Option<u64> {
    let int = line.get(start..dot)?;
    let frac = line.get(dot + 1..end)?;
    if int.len() + frac.len() > 19 {
        return None;
    }
    if frac.len() == 6
        && let Some(head) = dot.checked_sub(2).filter(|&h| h >= start)
    {
        // [i, i, '.', f, f, f, f, f] and [i, '.', f, f, f, f, f, f].
        let two = word(line, head)?;
        let six = word(line, dot - 1)?;
        let tail = eight_digits((two & 0xFFFF) | (six & !0xFFFF));
        // Ten integer digits (Unix seconds) leave eight: one word.
        let high = if head - start == 8 {
            eight_digits(word(line, start)?)
        } else {
            decimal_u64(line.get(start..head)?)
        };
        return Some(high.wrapping_mul(100_000_000).wrapping_add(tail));
    }
    let scale = 10u64.checked_pow(frac.len() as u32)?;
    decimal_u64(int)
        .checked_mul(scale)?
        .checked_add(decimal_u64(frac))
}

/// [`decimal_ticks`] of a time that starts at index 1 with ten integer
/// digits and six fraction digits (`(1700000000.001000)`, Unix seconds as
/// candump writes them), for digits the caller validated. Inlined into a
/// reader's loop in two words and no call: [`decimal_ticks`] cost 78
/// instructions a line there (callgrind, `--timing` on the bench's
/// segmented firmware trace), this about 20.
#[inline(always)]
pub fn unix_micros(line: &[u8]) -> Option<u64> {
    // Digits 1..9, then [i, i, '.', f, f, f, f, f] and [i, '.', f, f, f, f, f, f].
    let high = eight_digits(word(line, 1)?);
    let two = word(line, 9)?;
    let six = word(line, 10)?;
    let tail = eight_digits((two & 0xFFFF) | (six & !0xFFFF));
    Some(high.wrapping_mul(100_000_000).wrapping_add(tail))
}

/// Eight ASCII digits (first digit in the lowest byte) to their value, in
/// three multiplications: pairs, then quads, then the two halves.
#[inline(always)]
fn eight_digits(w: u64) -> u64 {
    let w = w.wrapping_sub(LO * u64::from(b'0'));
    let pairs = w.wrapping_mul(10).wrapping_add(w >> 8);
    let lo = (pairs & 0x0000_00FF_0000_00FF).wrapping_mul(100 + (1_000_000 << 32));
    let hi = ((pairs >> 16) & 0x0000_00FF_0000_00FF).wrapping_mul(1 + (10_000 << 32));
    lo.wrapping_add(hi) >> 32
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn naive_run(s: &[u8], from: usize, f: impl Fn(u8) -> bool) -> usize {
        s.get(from..)
            .map_or(0, |t| t.iter().take_while(|b| f(**b)).count())
    }

    #[test]
    fn every_byte_value_is_classified_like_std() {
        for b in 0..=255u8 {
            let s = [b; 9];
            assert_eq!(
                digit_run(&s, 0),
                if b.is_ascii_digit() { 9 } else { 0 },
                "{b:#x}"
            );
            assert_eq!(
                hex_run(&s, 0),
                if b.is_ascii_hexdigit() { 9 } else { 0 },
                "{b:#x}"
            );
            assert_eq!(token_run(&s, 0), if b > b' ' { 9 } else { 0 }, "{b:#x}");
            let blank = b == b' ' || b == b'\t';
            assert_eq!(blank_run(&s, 0), if blank { 9 } else { 0 }, "{b:#x}");
        }
    }

    #[test]
    fn runs_stop_at_the_first_other_byte() {
        assert_eq!(digit_run(b"1700000000.123456)", 0), 10);
        assert_eq!(digit_run(b"1700000000.123456)", 11), 6);
        assert_eq!(hex_run(b"1043080100000000 T", 0), 16);
        assert_eq!(hex_run(b"10430801000000g0", 0), 14);
        assert_eq!(token_run(b"vcan-0.1 081#00", 0), 8);
        assert_eq!(digit_run(b"", 0), 0);
        assert_eq!(digit_run(b"12", 5), 0);
    }

    #[test]
    fn whole_slices_of_hex() {
        assert!(all_hex(b""));
        assert!(all_hex(b"0a"));
        assert!(all_hex(b"1043080100000000"));
        assert!(all_hex(b"1043080100000000AB"));
        assert!(!all_hex(b"104308010000000G"));
        assert!(!all_hex(b"G043080100000000AB"));
        assert!(!all_hex(b"1043080100000000AG"));
        assert!(!all_hex(b"1g"));
    }

    #[test]
    fn decimal() {
        assert_eq!(decimal_u64(b"1700000000"), 1_700_000_000);
        assert_eq!(
            decimal_u64(b"9999999999999999999"),
            9_999_999_999_999_999_999
        );
        assert_eq!(decimal_u64(b""), 0);
    }

    proptest! {
        #[test]
        fn swar_runs_equal_naive_runs(s in prop::collection::vec(prop_oneof![
            any::<u8>(),
            b'0'..=b'9',
            prop::sample::select(b"abcdefABCDEF .#()".to_vec()),
        ], 0..40), from in 0usize..42) {
            prop_assert_eq!(digit_run(&s, from), naive_run(&s, from, |b| b.is_ascii_digit()));
            prop_assert_eq!(hex_run(&s, from), naive_run(&s, from, |b| b.is_ascii_hexdigit()));
            prop_assert_eq!(token_run(&s, from), naive_run(&s, from, |b| b > b' '));
            prop_assert_eq!(all_hex(&s), s.iter().all(u8::is_ascii_hexdigit));
            prop_assert_eq!(blank_run(&s, from), naive_run(&s, from, |b| b == b' ' || b == b'\t'));
            let end = from.min(s.len());
            for start in [0, end / 2, end.saturating_sub(3), end] {
                prop_assert_eq!(
                    all_hex_at(&s, start, end),
                    s[start..end].iter().all(u8::is_ascii_hexdigit),
                    "{}..{}", start, end
                );
            }
        }

        #[test]
        fn layout_pieces_equal_naive_checks(
            s in prop::collection::vec(prop::sample::select(b"0123456789. )x".to_vec()), 8..40),
            start in 0usize..20,
            len in 0usize..20,
            dot in 0usize..30,
        ) {
            let end = start + len;
            if let Some(f) = Fixed::of(&s, start, len) {
                prop_assert!(f.matches(&s, start));
                for at in 0..s.len() {
                    let naive = s.get(at..at + len) == s.get(start..end) && at + 8 <= s.len();
                    prop_assert_eq!(f.matches(&s, at), naive, "at {}", at);
                }
            }
            if end <= s.len() && end >= 8 && len <= 16 {
                prop_assert_eq!(all_spaces_at(&s, start, end), s[start..end].iter().all(|b| *b == b' '));
            }
            if let Some(d) = Decimal::new(start, dot, end) && end <= s.len() && dot >= start && dot < end && len <= 24 {
                let naive = (start..end).all(|i| (i == dot) != s[i].is_ascii_digit());
                prop_assert_eq!(d.matches(&s), naive);
            }
        }

        #[test]
        fn decimal_equals_the_naive_sum(digits in "[0-9]{0,19}") {
            let naive = digits.bytes().fold(0u64, |v, d| {
                v.wrapping_mul(10).wrapping_add(u64::from(d - b'0'))
            });
            prop_assert_eq!(decimal_u64(digits.as_bytes()), naive);
        }

        #[test]
        fn ticks_are_the_digits_without_the_dot(
            lead in "[(x ]{0,3}",
            int in "[0-9]{1,20}",
            frac in "[0-9]{0,12}",
            tail in "[) a-z]{0,9}",
        ) {
            let line = format!("{lead}{int}.{frac}{tail}");
            let (start, dot) = (lead.len(), lead.len() + int.len());
            let end = dot + 1 + frac.len();
            let naive = format!("{int}{frac}").parse::<u64>().ok()
                .filter(|_| int.len() + frac.len() <= 19);
            prop_assert_eq!(decimal_ticks(line.as_bytes(), start, dot, end), naive, "{}", line);
        }

        #[test]
        fn unix_micros_are_the_general_ticks(
            int in "[0-9]{10}",
            frac in "[0-9]{6}",
            tail in "[) a-z0-9#]{0,9}",
        ) {
            let line = format!("({int}.{frac}{tail}");
            let general = decimal_ticks(line.as_bytes(), 1, 11, 18);
            prop_assert!(general.is_some());
            prop_assert_eq!(unix_micros(line.as_bytes()), general, "{}", line);
        }
    }
}
