//! Ending a read from outside: whoever holds a [`Cancel`] token (the
//! application, on Ctrl-C) can make every input read with it end, as if it
//! ended there; what was read is still reported.
//!
//! A live source (a pipe from candump, a followed file) may block in `read`
//! for as long as the bus is quiet, so a flag alone would not be seen:
//! [`Interruptible`] reads such a source on its own thread and ends the
//! input on a cancel while the reading thread is still blocked.
//!
//! A read ended by a cancel is not the end of the input: the last line read
//! may be cut anywhere. So once bytes were handed out, a cancelled reader
//! returns the [`cancelled`] error instead of `Ok(0)`, and the line reader
//! ends there without the unfinished line (see `lines::BlockReader`);
//! `Ok(0)` stays the real end, where a last line without newline is whole.

use std::fmt;
use std::io::{self, Read};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

/// How often a waiting reader looks at the token.
pub const POLL: Duration = Duration::from_millis(50);

/// A shared flag that ends reading: clones share it. Passed in by the
/// caller, so the library holds no process-wide state.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token nobody has cancelled yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Ends every read that holds a clone of this token. The program
    /// cancels from its signal handler, through [`Cancel::flag`].
    #[cfg(test)]
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the token was cancelled (its [`flag`](Self::flag) set).
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// The flag itself, for a signal handler to set (an atomic store is all
    /// a handler may do).
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.0)
    }
}

/// The error of a read stopped by a cancel (see the module header).
#[derive(Debug)]
struct Cancelled;

impl fmt::Display for Cancelled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("reading stopped by a signal")
    }
}

impl std::error::Error for Cancelled {}

/// A read stopped by a cancel, after some input was read: the input was cut,
/// it did not end. Not `Interrupted`, which readers retry.
pub fn cancelled() -> io::Error {
    io::Error::other(Cancelled)
}

/// Whether `e` is [`cancelled`] (also when passed on by gzip or a buffer).
pub fn is_cancelled(e: &io::Error) -> bool {
    e.get_ref().is_some_and(|inner| inner.is::<Cancelled>())
}

/// How a cancelled reader ends: `Ok(0)` when it handed out nothing (an
/// empty input, nothing cut), else [`cancelled`].
fn stop(passed: bool) -> io::Result<usize> {
    if passed { Err(cancelled()) } else { Ok(0) }
}

/// A regular file or other finite source: reading stops at the next read
/// after a cancel.
pub struct StopOnCancel<R> {
    inner: R,
    cancel: Cancel,
    /// Bytes were handed out: a cancel now cuts the input.
    passed: bool,
}

impl<R> StopOnCancel<R> {
    /// Reads `inner` until `cancel` is set.
    pub fn new(inner: R, cancel: Cancel) -> Self {
        StopOnCancel {
            inner,
            cancel,
            passed: false,
        }
    }
}

impl<R: Read> Read for StopOnCancel<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.cancel.is_cancelled() {
            return stop(self.passed);
        }
        let n = self.inner.read(buf)?;
        self.passed |= n > 0;
        Ok(n)
    }
}

/// A source that may block (stdin from a pipe or terminal): read on a
/// separate thread, so Ctrl-C ends the input even mid-`read`.
pub struct Interruptible {
    chunks: Receiver<io::Result<Vec<u8>>>,
    current: Vec<u8>,
    pos: usize,
    done: bool,
    cancel: Cancel,
    /// Bytes were handed out: a cancel now cuts the input.
    passed: bool,
}

impl Interruptible {
    /// Reads `source` on a thread of its own, so that a cancel ends a read that
    /// waits (a pipe, a terminal).
    pub fn new(source: Box<dyn Read + Send>, cancel: Cancel) -> Self {
        // A few chunks in flight: backpressure keeps memory bounded.
        let (tx, rx) = sync_channel(4);
        std::thread::spawn(move || pump(source, &tx));
        Interruptible {
            chunks: rx,
            current: Vec::new(),
            pos: 0,
            done: false,
            cancel,
            passed: false,
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
            let buffered = self.pos < self.current.len();
            if self.done && !buffered {
                return Ok(0);
            }
            // Stop at once: a chunk already received is not read on either.
            if self.cancel.is_cancelled() {
                return stop(self.passed);
            }
            if buffered {
                let n = buf.len().min(self.current.len() - self.pos);
                buf[..n].copy_from_slice(&self.current[self.pos..self.pos + n]);
                self.pos += n;
                self.passed |= n > 0;
                return Ok(n);
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
