//! The spooled DZ blocks inflated ahead on a second thread, in spool order,
//! while the reader untransposes and decodes the block before. Inflating
//! and decoding a block cost about the same (512 MiB of records in 4 MiB
//! blocks: 1.36 s to inflate, 1.1 s to decode plus 0.4 s to untranspose;
//! on one thread 2.06x the inflating alone); overlapped, a DZ file reads
//! in about the time its inflating takes. The untransposing is the
//! reader's: with it, the worker took 1.29x the inflating alone.
//!
//! The blocks come from the spool file by position (`pread`: the reader's
//! own reads and seeks on the same file are not disturbed). The hand-over
//! is a rendezvous, so besides the block being decoded only one more is
//! inflated at a time: memory stays a few blocks, each at most
//! [`MAX_INFLATED`]. Buffers go back to the worker to be reused (fresh
//! 4 MiB buffers cost page faults on every block). If the thread cannot be
//! started, or stops, the reader inflates on its own thread as before.

use std::fs::File;
use std::os::unix::fs::FileExt;
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

use super::block::{self, MAX_INFLATED};

/// One spooled DZ block to inflate: (spool item index, position, length).
pub(super) type Job = (usize, u64, u64);

/// What the worker made of a block: its spool item index and the data as
/// stored, inflated, with the record length to untranspose it by (the
/// reader does that: it balances the two threads), or why it could not.
pub(super) type Done = (usize, Result<(Vec<u8>, Option<usize>), String>);

pub(super) struct Ahead {
    done: Receiver<Done>,
    back: Sender<Vec<u8>>,
}

impl Ahead {
    /// Starts inflating `jobs` from `file`; `None` when no thread could be
    /// started (the caller inflates itself).
    pub(super) fn start(file: File, jobs: Vec<Job>) -> Option<Ahead> {
        let (tx, done) = sync_channel(0);
        let (back, spare) = channel();
        std::thread::Builder::new()
            .name("mf4-inflate".into())
            .spawn(move || work(&file, jobs, &tx, &spare))
            .ok()?;
        Some(Ahead { done, back })
    }

    /// The next block inflated, `None` when the worker is gone.
    pub(super) fn next(&self) -> Option<Done> {
        self.done.recv().ok()
    }

    /// A buffer the reader is done with, for the worker to fill again.
    pub(super) fn give_back(&self, buf: Vec<u8>) {
        if buf.capacity() > 0 {
            let _ = self.back.send(buf);
        }
    }
}

fn work(file: &File, jobs: Vec<Job>, tx: &SyncSender<Done>, spare: &Receiver<Vec<u8>>) {
    let mut zipped = Vec::new();
    for (i, pos, len) in jobs {
        let mut out = spare.try_recv().unwrap_or_default();
        let result = inflate(file, pos, len, &mut zipped, &mut out).map(|columns| (out, columns));
        if tx.send((i, result)).is_err() {
            // The reader is gone (done, or stopped).
            return;
        }
    }
}

fn inflate(
    file: &File,
    pos: u64,
    len: u64,
    zipped: &mut Vec<u8>,
    out: &mut Vec<u8>,
) -> Result<Option<usize>, String> {
    if len > MAX_INFLATED + 24 {
        return Err(format!("{len} bytes is too large to read"));
    }
    zipped.clear();
    zipped.resize(len as usize, 0);
    file.read_exact_at(zipped, pos)
        .map_err(|e| format!("cannot read it back from the temporary file: {e}"))?;
    let dz = block::Dz::read(zipped)?;
    let end = 24usize.saturating_add(usize::try_from(dz.len).unwrap_or(usize::MAX));
    let data = zipped.get(24..end.min(zipped.len())).unwrap_or_default();
    dz.inflate_stored(data, out)?;
    Ok(dz.columns())
}
