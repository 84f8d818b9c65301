//! Reading helpers every binary format shares.

use std::io::{self, Read};

/// Reads until `buf` is full or the input ends; returns the bytes read.
/// `Read::read_exact` cannot say how much a short input held, which every
/// reader needs to report a cut-off header.
pub fn read_full(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    fill(input, buf, false).map(|(n, _)| n)
}

/// [`read_full`] for a reader that a cancel may stop (`--follow`, a live
/// pipe): the bytes read, and the [`cancelled`](crate::cancel::cancelled)
/// error when a cancel cut the input there, after the bytes read before it,
/// which `read_full` would lose. A binary reader then reads what it holds
/// to its end, as at the end of a file, but does not report what the stop
/// cut (an object it cut is not counted, as a line it cut is not).
pub fn read_until_stopped(
    input: &mut impl Read,
    buf: &mut [u8],
) -> io::Result<(usize, Option<io::Error>)> {
    fill(input, buf, true)
}

/// Reads until `buf` is full or the input ends; when `stoppable`, a
/// cancel ends it too, its error returned beside the bytes read.
fn fill(
    input: &mut impl Read,
    buf: &mut [u8],
    stoppable: bool,
) -> io::Result<(usize, Option<io::Error>)> {
    let mut n = 0;
    while n < buf.len() {
        match input.read(buf.get_mut(n..).unwrap_or_default()) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) if stoppable && crate::cancel::is_cancelled(&e) => return Ok((n, Some(e))),
            Err(e) => return Err(e),
        }
    }
    Ok((n, None))
}
