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

use crate::analyze::threads::spawn_scoped;

/// A job with its number and the buffer its text goes to (reused).
type Job<J> = (u64, J, Vec<u8>);

/// Renders a job on the calling thread.
type Here<'scope, J> = Box<dyn FnMut(J, &mut Vec<u8>) + 'scope>;

pub struct Ordered<'scope, J> {
    /// `None` once finished: the helpers end when their queue is empty.
    jobs: Option<Sender<Job<J>>>,
    /// When no helper could be started: jobs are rendered on this thread.
    here: Option<Here<'scope, J>>,
    /// Helpers that started.
    #[cfg(test)]
    helpers: usize,
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

impl<'scope, J: Send + 'static> Ordered<'scope, J> {
    /// Starts `helpers` threads in `scope`; each renders jobs with its own
    /// state from `state`. Helpers the system will not start are done
    /// without; with none, this thread renders every job when it is asked.
    pub fn start<'env, S>(
        scope: &'scope Scope<'scope, 'env>,
        helpers: usize,
        state: impl Fn() -> S,
        render: impl Fn(&mut S, J, &mut Vec<u8>) + Send + Sync + Copy + 'scope,
    ) -> Ordered<'scope, J>
    where
        S: Send + 'scope,
    {
        let (jobs_tx, jobs_rx) = mpsc::channel::<Job<J>>();
        let (done_tx, done_rx) = mpsc::channel();
        let jobs_rx = Arc::new(Mutex::new(jobs_rx));
        let mut started = 0;
        for _ in 0..helpers.max(1) {
            let jobs = Arc::clone(&jobs_rx);
            let done = done_tx.clone();
            let mut s = state();
            let spawned = spawn_scoped(scope, move || {
                while let Some((n, job, mut out)) = next_job(&jobs) {
                    render(&mut s, job, &mut out);
                    if done.send((n, out)).is_err() {
                        return;
                    }
                }
            });
            if !spawned {
                break;
            }
            started += 1;
        }
        let here = (started == 0).then(|| {
            let mut s = state();
            Box::new(move |job: J, out: &mut Vec<u8>| render(&mut s, job, out)) as Here<'scope, J>
        });
        Ordered {
            jobs: Some(jobs_tx),
            here,
            #[cfg(test)]
            helpers: started,
            done: done_rx,
            asked: 0,
            written: 0,
            ready: BTreeMap::new(),
            spare: Vec::new(),
            max_out: started as u64 * 2 + 1,
        }
    }

    /// Helpers that started (0: jobs are rendered on the calling thread).
    #[cfg(test)]
    pub fn helpers(&self) -> usize {
        self.helpers
    }

    /// Hands a job to the helpers; writes what is ready, waiting while too
    /// many jobs are out.
    pub fn job(&mut self, job: J, out: &mut dyn Write) -> io::Result<()> {
        let mut buf = self.spare.pop().unwrap_or_default();
        if let Some(render) = &mut self.here {
            render(job, &mut buf);
            self.asked += 1;
            return self.file((self.asked - 1, buf), out);
        }
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
    use crate::analyze::threads::spawn_limit;

    /// Jobs that take longer the earlier they come still come out in
    /// order, between the plain texts.
    #[test]
    fn pieces_come_out_in_the_order_asked() {
        assert_eq!(forty_jobs(3), (3, expected_forty()));
    }

    /// The system starts fewer helpers than asked, or none: the text is the
    /// same, rendered by the helpers that started or by the calling thread.
    #[test]
    fn helpers_that_cannot_start_are_done_without() {
        for (allowed, helpers) in [(0, 0), (1, 1), (2, 2)] {
            spawn_limit::allow(Some(allowed));
            let got = forty_jobs(3);
            spawn_limit::allow(None);
            assert_eq!(got, (helpers, expected_forty()), "{allowed} spawns allowed");
        }
    }

    /// 40 jobs and some plain texts through `Ordered` with `helpers`
    /// helpers asked for: the helpers started and the text.
    fn forty_jobs(helpers: usize) -> (usize, String) {
        let mut out = Vec::new();
        let started = std::thread::scope(|s| {
            let mut o = Ordered::start(
                s,
                helpers,
                || (),
                |_: &mut (), n: u64, out: &mut Vec<u8>| {
                    std::thread::sleep(std::time::Duration::from_micros(200 * (20 - n % 20)));
                    out.extend_from_slice(format!("[{n}]").as_bytes());
                },
            );
            let started = o.helpers();
            for n in 0..40u64 {
                if n % 7 == 0 {
                    o.text(format!("<{n}>").as_bytes(), &mut out).unwrap();
                }
                o.job(n, &mut out).unwrap();
            }
            o.finish(&mut out).unwrap();
            started
        });
        (started, String::from_utf8(out).unwrap())
    }

    fn expected_forty() -> String {
        let mut want = String::new();
        for n in 0..40u64 {
            if n % 7 == 0 {
                want.push_str(&format!("<{n}>"));
            }
            want.push_str(&format!("[{n}]"));
        }
        want
    }
}
