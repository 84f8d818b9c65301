//! Ending a read from outside: whoever holds a [`Cancel`] token (the
//! application, on Ctrl-C) can make every input read with it end, as if it
//! ended there; what was read is still reported.
//!
//! A live source (a pipe from candump, a followed file) may block in `read`
//! for as long as the bus is quiet, so a flag alone would not be seen:
//! [`Interruptible`] reads such a source on its own thread and turns a
//! cancel into end-of-input while the reading thread is still blocked.

use std::io::{self, Read};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

/// How often a waiting reader looks at the token.
pub(crate) const POLL: Duration = Duration::from_millis(50);

/// A shared flag that ends reading: clones share it. Passed in by the
/// caller, so the library holds no process-wide state.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token nobody has cancelled yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Ends every read that holds a clone of this token.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// A regular file or other finite source: reading stops at the next read
/// after a cancel, as if the input ended there.
pub(crate) struct StopOnCancel<R> {
    pub(crate) inner: R,
    pub(crate) cancel: Cancel,
}

impl<R: Read> Read for StopOnCancel<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.cancel.is_cancelled() {
            return Ok(0);
        }
        self.inner.read(buf)
    }
}

/// A source that may block (stdin from a pipe or terminal): read on a
/// separate thread, so Ctrl-C ends the input even mid-`read`.
pub(crate) struct Interruptible {
    chunks: Receiver<io::Result<Vec<u8>>>,
    current: Vec<u8>,
    pos: usize,
    done: bool,
    cancel: Cancel,
}

impl Interruptible {
    pub(crate) fn new(source: Box<dyn Read + Send>, cancel: Cancel) -> Self {
        // A few chunks in flight: backpressure keeps memory bounded.
        let (tx, rx) = sync_channel(4);
        std::thread::spawn(move || pump(source, &tx));
        Interruptible {
            chunks: rx,
            current: Vec::new(),
            pos: 0,
            done: false,
            cancel,
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
            if self.done || self.cancel.is_cancelled() {
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

#[cfg(test)]
mod tests {
    // Ctrl-C itself is tested through the binary (tests/integration/live.rs).
    use super::*;

    #[test]
    fn interruptible_passes_everything_through_and_ends() {
        let data: Vec<u8> = (0..200_000u32).map(|i| (i % 251) as u8).collect();
        let mut r = Interruptible::new(Box::new(io::Cursor::new(data.clone())), Cancel::new());
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
        let mut r = Interruptible::new(Box::new(Failing), Cancel::new());
        let err = r.read(&mut [0u8; 8]).unwrap_err();
        assert_eq!(err.to_string(), "device gone");
        assert_eq!(r.read(&mut [0u8; 8]).unwrap(), 0);
    }
}
