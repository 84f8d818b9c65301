//! Ctrl-C ends reading, not the process: what was read is reported (the
//! per-node summary a user at the machine wants), then the exit status is 130.
//!
//! A live source (a pipe from candump, a followed file) may block in `read`
//! for as long as the bus is quiet, so a flag alone would not be seen:
//! [`Interruptible`] reads such a source on its own thread and turns Ctrl-C
//! into end-of-input while the reading thread is still blocked.

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The exit status of a run stopped by Ctrl-C (128 + SIGINT), as shells use.
pub const EXIT_INTERRUPTED: u8 = 130;

/// How often a waiting reader looks at the flag.
const POLL: Duration = Duration::from_millis(50);

/// Catches Ctrl-C from here on. Without a handler (it failed to install) the
/// default applies: the process ends at once.
pub fn catch() {
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Pretends Ctrl-C was pressed (tests of the readers below).
#[doc(hidden)]
pub fn simulate(on: bool) {
    INTERRUPTED.store(on, Ordering::SeqCst);
}

/// A regular file or other finite source: reading stops at the next read
/// after Ctrl-C, as if the input ended there.
pub struct StopOnInterrupt<R>(pub R);

impl<R: Read> Read for StopOnInterrupt<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if interrupted() {
            return Ok(0);
        }
        self.0.read(buf)
    }
}

/// A source that may block (stdin from a pipe or terminal): read on a
/// separate thread, so Ctrl-C ends the input even mid-`read`.
pub struct Interruptible {
    chunks: Receiver<io::Result<Vec<u8>>>,
    current: Vec<u8>,
    pos: usize,
    done: bool,
}

impl Interruptible {
    pub fn new(source: Box<dyn Read + Send>) -> Self {
        // A few chunks in flight: backpressure keeps memory bounded.
        let (tx, rx) = sync_channel(4);
        std::thread::spawn(move || pump(source, &tx));
        Interruptible {
            chunks: rx,
            current: Vec::new(),
            pos: 0,
            done: false,
        }
    }
}

fn pump(mut source: Box<dyn Read + Send>, tx: &SyncSender<io::Result<Vec<u8>>>) {
    loop {
        let mut buf = vec![0u8; 64 * 1024];
        match source.read(&mut buf) {
            Ok(0) => {
                let _ = tx.send(Ok(Vec::new()));
                return;
            }
            Ok(n) => {
                buf.truncate(n);
                if tx.send(Ok(buf)).is_err() {
                    return;
                }
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => {
                let _ = tx.send(Err(e));
                return;
            }
        }
    }
}

impl Read for Interruptible {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            if self.pos < self.current.len() {
                let n = buf.len().min(self.current.len() - self.pos);
                buf[..n].copy_from_slice(&self.current[self.pos..self.pos + n]);
                self.pos += n;
                return Ok(n);
            }
            if self.done || interrupted() {
                return Ok(0);
            }
            match self.chunks.recv_timeout(POLL) {
                Ok(Ok(chunk)) if chunk.is_empty() => self.done = true,
                Ok(Ok(chunk)) => {
                    self.current = chunk;
                    self.pos = 0;
                }
                Ok(Err(e)) => {
                    self.done = true;
                    return Err(e);
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => self.done = true,
            }
        }
    }
}

/// `--follow`: a file that is still being written (`candump -l` in another
/// terminal). At its end, wait for more instead of stopping; Ctrl-C ends it.
/// A file that shrinks (rotated or truncated) is read again from the start.
pub struct Follow {
    file: File,
    pos: u64,
    poll: Duration,
}

impl Follow {
    pub fn new(file: File) -> Self {
        Follow {
            file,
            pos: 0,
            poll: Duration::from_millis(200),
        }
    }
}

impl Read for Follow {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            if interrupted() {
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
    // The flag is process-wide; these tests only check the readers pass data
    // through while it is clear. Ctrl-C itself is tested through the binary
    // (tests/live.rs), where the flag belongs to the child process.
    use super::*;

    #[test]
    fn interruptible_passes_everything_through_and_ends() {
        let data: Vec<u8> = (0..200_000u32).map(|i| (i % 251) as u8).collect();
        let mut r = Interruptible::new(Box::new(io::Cursor::new(data.clone())));
        let mut out = Vec::new();
        r.read_to_end(&mut out).unwrap();
        assert_eq!(out, data);
    }

    #[test]
    fn interruptible_passes_errors_on() {
        struct Failing;
        impl Read for Failing {
            fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
                Err(io::Error::other("device gone"))
            }
        }
        let mut r = Interruptible::new(Box::new(Failing));
        let err = r.read(&mut [0u8; 8]).unwrap_err();
        assert_eq!(err.to_string(), "device gone");
        assert_eq!(r.read(&mut [0u8; 8]).unwrap(), 0);
    }

    #[test]
    fn follow_reads_what_is_appended() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grow.log");
        let mut w = File::create(&path).unwrap();
        w.write_all(b"first\n").unwrap();
        let mut f = Follow::new(File::open(&path).unwrap());
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
