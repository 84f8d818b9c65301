//! Reading helpers every binary format shares.

use std::io::{self, Read};

/// Reads until `buf` is full or the input ends; returns the bytes read.
/// `Read::read_exact` cannot say how much a short input held, which every
/// reader needs to report a cut-off header.
pub fn read_full(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match input.read(buf.get_mut(n..).unwrap_or_default()) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}
