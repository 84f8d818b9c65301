//! Text rendered on helper threads and written in the order it was asked
//! for.
//!
//! The node objects at the end of a report list every error a node raised:
//! on a trace with millions of errors, rendering them was a fifth of the
//! run, on one thread, after everything else had finished. The thread that
//! reads the error history back now hands batches of errors to helpers and
//! writes their text, and its own, in order: the output is the same byte for
//! byte.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread::Scope;

/// A job with its number and the buffer its text goes to (reused).
type Job<J> = (u64, J, Vec<u8>);

pub struct Ordered<J> {
    /// `None` once finished: the helpers end when their queue is empty.
    jobs: Option<Sender<Job<J>>>,
    done: Receiver<(u64, Vec<u8>)>,
    /// Pieces asked for (jobs and text), and pieces written.
    asked: u64,
    written: u64,
    /// Pieces waiting for an earlier one.
    ready: BTreeMap<u64, Vec<u8>>,
    spare: Vec<Vec<u8>>,
    /// Jobs out at once: what bounds the memory of rendered text.
    max_out: u64,
}

impl<J: Send + 'static> Ordered<J> {
    /// Starts `helpers` threads in `scope`; each renders jobs with its own
    /// state from `state`.
    pub fn start<'scope, 'env, S>(
        scope: &'scope Scope<'scope, 'env>,
        helpers: usize,
        state: impl Fn() -> S,
        render: impl Fn(&mut S, J, &mut Vec<u8>) + Send + Sync + Copy + 'scope,
    ) -> Ordered<J>
    where
        S: Send + 'scope,
    {
        let (jobs_tx, jobs_rx) = mpsc::channel::<Job<J>>();
        let (done_tx, done_rx) = mpsc::channel();
        let jobs_rx = Arc::new(Mutex::new(jobs_rx));
        let helpers = helpers.max(1);
        for _ in 0..helpers {
            let jobs = Arc::clone(&jobs_rx);
            let done = done_tx.clone();
            let mut s = state();
            scope.spawn(move || {
                while let Some((n, job, mut out)) = next_job(&jobs) {
                    render(&mut s, job, &mut out);
                    if done.send((n, out)).is_err() {
                        return;
                    }
                }
            });
        }
        Ordered {
            jobs: Some(jobs_tx),
            done: done_rx,
            asked: 0,
            written: 0,
            ready: BTreeMap::new(),
            spare: Vec::new(),
            max_out: helpers as u64 * 2 + 1,
        }
    }

    /// Hands a job to the helpers; writes what is ready, waiting while too
    /// many jobs are out.
    pub fn job(&mut self, job: J, out: &mut dyn Write) -> io::Result<()> {
        let buf = self.spare.pop().unwrap_or_default();
        let jobs = self.jobs.as_ref().ok_or_else(stopped)?;
        jobs.send((self.asked, job, buf)).map_err(|_| stopped())?;
        self.asked += 1;
        while let Ok(piece) = self.done.try_recv() {
            self.file(piece, out)?;
        }
        while self.asked - self.written > self.max_out {
            self.wait(out)?;
        }
        Ok(())
    }

    /// Text that needs no helper, in its place among the jobs.
    pub fn text(&mut self, text: &[u8], out: &mut dyn Write) -> io::Result<()> {
        if self.written == self.asked {
            self.asked += 1;
            self.written += 1;
            return out.write_all(text);
        }
        let mut buf = self.spare.pop().unwrap_or_default();
        buf.extend_from_slice(text);
        self.asked += 1;
        self.file((self.asked - 1, buf), out)
    }

    /// Writes everything asked for; the helpers stop.
    pub fn finish(mut self, out: &mut dyn Write) -> io::Result<()> {
        self.jobs = None;
        while self.written < self.asked {
            self.wait(out)?;
        }
        Ok(())
    }

    fn wait(&mut self, out: &mut dyn Write) -> io::Result<()> {
        let piece = self.done.recv().map_err(|_| stopped())?;
        self.file(piece, out)
    }

    /// Keeps a finished piece; writes every piece now next in order.
    fn file(&mut self, (n, text): (u64, Vec<u8>), out: &mut dyn Write) -> io::Result<()> {
        self.ready.insert(n, text);
        while let Some(mut text) = self.ready.remove(&self.written) {
            out.write_all(&text)?;
            self.written += 1;
            text.clear();
            self.spare.push(text);
        }
        Ok(())
    }
}

fn next_job<J>(jobs: &Mutex<Receiver<Job<J>>>) -> Option<Job<J>> {
    jobs.lock().ok()?.recv().ok()
}

/// The helpers are gone: only when one of them panicked.
fn stopped() -> io::Error {
    io::Error::other("the rendering threads stopped")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jobs that take longer the earlier they come still come out in
    /// order, between the plain texts.
    #[test]
    fn pieces_come_out_in_the_order_asked() {
        let mut out = Vec::new();
        std::thread::scope(|s| {
            let mut o = Ordered::start(
                s,
                3,
                || (),
                |_: &mut (), n: u64, out: &mut Vec<u8>| {
                    std::thread::sleep(std::time::Duration::from_micros(200 * (20 - n % 20)));
                    out.extend_from_slice(format!("[{n}]").as_bytes());
                },
            );
            for n in 0..40u64 {
                if n % 7 == 0 {
                    o.text(format!("<{n}>").as_bytes(), &mut out).unwrap();
                }
                o.job(n, &mut out).unwrap();
            }
            o.finish(&mut out).unwrap();
        });
        let mut want = String::new();
        for n in 0..40u64 {
            if n % 7 == 0 {
                want.push_str(&format!("<{n}>"));
            }
            want.push_str(&format!("[{n}]"));
        }
        assert_eq!(String::from_utf8(out).unwrap(), want);
    }
}
