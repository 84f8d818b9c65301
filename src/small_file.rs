//! Files opened by name that are not traces (a baseline, a user profile, a
//! DCF), read whole: with a bound, so that `/dev/zero`, a FIFO that never
//! ends or a trace given by mistake is one error naming the bound, never
//! gigabytes of memory. Below every layer: it imports nothing of ours.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// The whole file at `path`, at most `max` bytes. A file (or device) with
/// more is an error that says the bound and what the file should have been:
/// `larger than 16 MiB: not a DCF`. Only `max + 1` bytes are ever read.
pub fn read(path: &Path, max: u64, what: &str) -> io::Result<Vec<u8>> {
    let file = File::open(path)?;
    let mut bytes = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("larger than {}: not {what}", size(max)),
        ));
    }
    Ok(bytes)
}

/// [`read`] as UTF-8 text (an error otherwise, as `fs::read_to_string`).
pub fn read_to_string(path: &Path, max: u64, what: &str) -> io::Result<String> {
    String::from_utf8(read(path, max, what)?).map_err(|_| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// `16 MiB`, `64 KiB`, `100 bytes`: whole units only.
fn size(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 20 && b % (1 << 20) == 0 => format!("{} MiB", b >> 20),
        b if b >= 1 << 10 && b % (1 << 10) == 0 => format!("{} KiB", b >> 10),
        b => format!("{b} bytes"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_up_to_the_bound_is_read_a_larger_one_is_an_error_naming_it() {
        let dir = tempfile::tempdir().expect("a temp dir");
        let path = dir.path().join("f");
        std::fs::write(&path, b"0123456789").expect("written");
        assert_eq!(read(&path, 10, "a test").expect("read"), b"0123456789");
        let e = read(&path, 9, "a test").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert_eq!(e.to_string(), "larger than 9 bytes: not a test");
        assert_eq!(
            read_to_string(&path, 10, "a test").expect("text"),
            "0123456789"
        );
        std::fs::write(&path, b"\xff").expect("written");
        assert!(read_to_string(&path, 10, "a test").is_err());
        let missing = read(&dir.path().join("none"), 10, "a test").unwrap_err();
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
    }

    /// An endless device ends at the bound, not at the end of memory.
    #[cfg(unix)]
    #[test]
    fn an_endless_device_stops_at_the_bound() {
        let e = read(Path::new("/dev/zero"), 1 << 20, "a profile").unwrap_err();
        assert_eq!(e.to_string(), "larger than 1 MiB: not a profile");
    }

    #[test]
    fn sizes_are_shown_in_whole_units() {
        assert_eq!(size(16 << 20), "16 MiB");
        assert_eq!(size(64 << 10), "64 KiB");
        assert_eq!(size((1 << 20) + 1), "1048577 bytes");
        assert_eq!(size(0), "0 bytes");
    }
}
