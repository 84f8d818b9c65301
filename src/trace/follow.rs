//! `--follow`: a file that is still being written (`candump -l` in another
//! terminal). At its end, wait for more instead of stopping; a cancel ends it.

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::time::Duration;

use super::cancel::Cancel;

/// A growing file, read to its end and then waited on.
/// A file that shrinks (rotated or truncated) is read again from the start.
pub(crate) struct Follow {
    file: File,
    pos: u64,
    poll: Duration,
    cancel: Cancel,
}

impl Follow {
    pub(crate) fn new(file: File, cancel: Cancel) -> Self {
        Follow {
            file,
            pos: 0,
            poll: Duration::from_millis(200),
            cancel,
        }
    }
}

impl Read for Follow {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            if self.cancel.is_cancelled() {
                return Ok(0);
            }
            let n = self.file.read(buf)?;
            if n > 0 {
                self.pos += n as u64;
                return Ok(n);
            }
            if self.file.metadata()?.len() < self.pos {
                self.pos = self.file.seek(SeekFrom::Start(0))?;
                continue;
            }
            std::thread::sleep(self.poll);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follow_reads_what_is_appended() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grow.log");
        let mut w = File::create(&path).unwrap();
        w.write_all(b"first\n").unwrap();
        let mut f = Follow::new(File::open(&path).unwrap(), Cancel::new());
        f.poll = Duration::from_millis(5);
        let mut buf = [0u8; 64];
        let n = f.read(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"first\n");
        let writer = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(30));
            w.write_all(b"second\n").unwrap();
        });
        let n = f.read(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"second\n");
        writer.join().unwrap();
    }
}
