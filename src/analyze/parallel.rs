//! Large inputs on several threads: workers read and classify blocks into
//! compact records; the consumer replays them in order. A block whose start
//! state or wanted ids differ from the consumer's at its turn is classified
//! again in order, so the result never depends on the split.

use std::collections::BTreeMap;
use std::io::{self, Read, Write};
use std::ops::Range;
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex, RwLock};

use super::analysis::OutputError;
use super::classify::{FoldedRun, Foreign, LineSink, RunAt, classify_block, classify_text};
use super::consumer::Consumer;
use super::interest::{SharedInterest, may_widen};
use super::threads::spawn_scoped;
use crate::trace::detect::Detector;
use crate::trace::lines::{Block, BlockReader};
use crate::trace::{
    Fold, FoldBuffers, Folded, Frame, FrameKind, IdCounts, Inner, Interest, Payload, Reason,
    TimedLine, Timestamp,
};

/// What a worker keeps of a line for the consumer.
enum BlockRecord {
    Frame {
        idx: u64,
        time: Option<Timestamp>,
        channel: Range<usize>,
        id: u32,
        kind: FrameKind,
        extended: bool,
        len: u8,
        data: Payload,
        foreign: Foreign,
    },
    Malformed {
        idx: u64,
        reason: Reason,
    },
    /// A diagnostic about a frame the reader made good.
    Warning {
        idx: u64,
        reason: Reason,
    },
    /// A wanted frame that only moves the input's first/last time (already
    /// counted in `plain_frames`).
    Time(Timestamp),
    /// A run's frames handed over for their times, `lines` of the
    /// block's timed lines, on `channel` of the channel bytes.
    TimedLines {
        idx: u64,
        channel: Range<usize>,
        lines: Range<usize>,
    },
    /// A run with folded frames ([`FoldedRun`]): its channel is `channel`
    /// of the channel bytes, its folds and frames those of the block's.
    Folded {
        idx: u64,
        plain: u64,
        timed: u64,
        first: Timestamp,
        last: Timestamp,
        latest: Timestamp,
        channel: Range<usize>,
        folds: Range<usize>,
        frames: Range<usize>,
        inner: Range<usize>,
        handed: Range<usize>,
    },
}

/// A worker's summary of one block.
struct BlockResult {
    seq: u64,
    /// The worker that read and parsed it, which gets the buffer back.
    worker: usize,
    block: Block,
    /// The detector state the block was parsed from, and the one after it.
    start_context: Option<u64>,
    /// The interest generation it was parsed with.
    interest_gen: u64,
    /// The frames after which the consumer may widen the interest
    /// ([`may_widen`]), in line order.
    cuts: Vec<Cut>,
    end: Detector,
    lines: u64,
    tally: Tally,
    /// Every frame of the block by channel and id: interest does not
    /// change them, so a block's rest read again after a cut has the same
    /// and these stand for the whole block.
    ids: IdCounts,
    /// The block's first and last frame times, of any id.
    frame_times: (Option<Timestamp>, Option<Timestamp>),
    records: Vec<BlockRecord>,
    /// Channel names of the frame records, back to back.
    channels: Vec<u8>,
    /// The folds of the folded runs, back to back, their frames and the
    /// frames kept inside the runs.
    folds: Vec<Fold>,
    folded: Vec<Folded>,
    inner: Vec<Inner>,
}

/// What a worker counted of a block's lines (or of its lines up to a
/// [`Cut`]) besides its records.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    /// Frames the consumer would ignore (not EMCY/boot candidates), counted only.
    plain_frames: u64,
    skipped: u64,
    /// Frames DROPCOUNT lines said were lost.
    dropped: u64,
    /// Frame lines with a note after the frame.
    annotated: u64,
    /// Malformed lines beyond the diagnostics limit: counted, not reported.
    unreported: u64,
    /// Warnings beyond the diagnostics limit: only counted as not shown.
    unreported_warnings: u64,
}

impl Tally {
    /// What `self`, a block's whole tally, counted after `part`, the
    /// tally up to a cut.
    fn after(self, part: Tally) -> Tally {
        // The part's counts were taken from the same counters earlier, so
        // none is larger; saturating all the same.
        Tally {
            plain_frames: self.plain_frames.saturating_sub(part.plain_frames),
            skipped: self.skipped.saturating_sub(part.skipped),
            dropped: self.dropped.saturating_sub(part.dropped),
            annotated: self.annotated.saturating_sub(part.annotated),
            unreported: self.unreported.saturating_sub(part.unreported),
            unreported_warnings: self
                .unreported_warnings
                .saturating_sub(part.unreported_warnings),
        }
    }
}

/// A frame after which the consumer may widen the interest: if it does,
/// the block's lines after it were filtered with an interest too narrow
/// and are classified again in order, from `pos`.
struct Cut {
    /// The frame's record.
    record: usize,
    /// Lines of the block up to and including the frame's.
    lines: u64,
    /// Where the line after it begins in the block's text.
    pos: usize,
    /// The block's tally up to there.
    tally: Tally,
    /// The detector there, when its state is not the block's first
    /// (a header line changed it before the frame).
    detector: Option<Detector>,
}

/// A consumed block's buffers, back to the worker that filled them: it
/// fills them again without allocating (fresh vectors growing by
/// `realloc` cost 9.6M instructions on a 20 MB heartbeat trace, 5% of all).
#[derive(Default)]
struct Spare {
    bytes: Vec<u8>,
    records: Vec<BlockRecord>,
    cuts: Vec<Cut>,
    channels: Vec<u8>,
    folds: Vec<Fold>,
    folded: Vec<Folded>,
    inner: Vec<Inner>,
    ids: IdCounts,
}

impl BlockResult {
    /// Its buffers, emptied.
    fn into_spare(self) -> Spare {
        let BlockResult {
            block,
            mut records,
            mut cuts,
            mut channels,
            mut folds,
            mut folded,
            mut inner,
            mut ids,
            ..
        } = self;
        ids.clear();
        records.clear();
        cuts.clear();
        channels.clear();
        folds.clear();
        folded.clear();
        inner.clear();
        Spare {
            bytes: block.bytes,
            records,
            cuts,
            channels,
            folds,
            folded,
            inner,
            ids,
        }
    }
}

/// The worker-side sink: keeps only what the consumer needs.
struct Recorder {
    interest: Interest,
    /// Frames that only move the input's first/last time are collapsed: the
    /// block's first one is recorded, of each later run only the last.
    time_kept: bool,
    time_pending: Option<Timestamp>,
    limit: usize,
    result: BlockResult,
    /// Malformed lines and warnings kept (they share the limit).
    diagnostics_kept: usize,
    /// The frame just recorded may widen the interest: its line's end is a
    /// [`Cut`].
    cut_pending: bool,
}

impl LineSink for Recorder {
    fn interest(&self) -> &Interest {
        &self.interest
    }

    fn plain_frames(&mut self, n: u64) {
        self.result.tally.plain_frames += n;
    }

    fn frame_times(&mut self, first: Option<Timestamp>, last: Option<Timestamp>) {
        self.result.frame_times = (first, last);
    }

    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp) {
        self.result.tally.plain_frames += n;
        self.time_only(first);
        self.time_only(last);
    }

    /// Kept for the consumer, who alone knows whether it can take them:
    /// the folds themselves come with the block ([`LineSink::block_folds`]).
    fn folded(&mut self, idx: u64, run: &FoldedRun<'_>) -> Result<(), OutputError> {
        self.flush_time();
        let channel = self.result.channels.len();
        self.result.channels.extend_from_slice(run.channel);
        let RunAt {
            folds,
            frames,
            inner,
            handed,
        } = run.at;
        self.result.records.push(BlockRecord::Folded {
            idx,
            plain: run.plain,
            timed: run.timed,
            first: run.first,
            last: run.last,
            latest: run.latest,
            channel: channel..self.result.channels.len(),
            folds: folds..folds + run.folds.len(),
            frames: frames..frames + run.frames.len(),
            inner: inner..inner + run.inner.len(),
            handed: handed..handed + run.handed.len(),
        });
        Ok(())
    }

    fn fold_buffers(&mut self) -> FoldBuffers {
        FoldBuffers {
            folds: std::mem::take(&mut self.result.folds),
            frames: std::mem::take(&mut self.result.folded),
            inner: std::mem::take(&mut self.result.inner),
        }
    }

    fn keeps_folds(&self) -> bool {
        true
    }

    fn block_folds(&mut self, folds: FoldBuffers) {
        self.result.folds = folds.folds;
        self.result.folded = folds.frames;
        self.result.inner = folds.inner;
    }

    fn take_id_counts(&mut self) -> IdCounts {
        std::mem::take(&mut self.result.ids)
    }

    fn put_id_counts(&mut self, ids: IdCounts) {
        self.result.ids = ids;
    }

    fn timed_lines(
        &mut self,
        idx: u64,
        channel: &[u8],
        lines: &[TimedLine],
        at: usize,
    ) -> Result<(), OutputError> {
        self.flush_time();
        let c = self.result.channels.len();
        self.result.channels.extend_from_slice(channel);
        // The lines stay where the reader put them, in the block's counts.
        self.result.records.push(BlockRecord::TimedLines {
            idx,
            channel: c..self.result.channels.len(),
            lines: at..at + lines.len(),
        });
        Ok(())
    }

    fn lines(&mut self, n: u64) {
        self.result.lines += n;
    }

    fn skipped(&mut self) {
        self.result.tally.skipped += 1;
    }

    fn dropped(&mut self, n: u64) {
        self.result.tally.dropped = self.result.tally.dropped.saturating_add(n);
    }

    fn annotated(&mut self) {
        self.result.tally.annotated += 1;
    }

    fn malformed(&mut self, idx: u64, reason: Reason) {
        // The consumer shows at most `limit` per input, in line order, so no
        // block needs to keep more than that.
        if self.diagnostics_kept < self.limit {
            self.diagnostics_kept += 1;
            self.result
                .records
                .push(BlockRecord::Malformed { idx, reason });
        } else {
            self.result.tally.unreported += 1;
        }
    }

    fn warning(&mut self, idx: u64, reason: Reason) {
        if self.diagnostics_kept < self.limit {
            self.diagnostics_kept += 1;
            self.result
                .records
                .push(BlockRecord::Warning { idx, reason });
        } else {
            self.result.tally.unreported_warnings += 1;
        }
    }

    // Workers start once the format is known.
    fn format_known(&mut self) {}

    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError> {
        self.flush_time();
        self.cut_pending = may_widen(frame, &self.interest);
        let start = self.result.channels.len();
        self.result.channels.extend_from_slice(frame.channel);
        self.result.records.push(BlockRecord::Frame {
            idx,
            time: frame.time,
            channel: start..self.result.channels.len(),
            id: frame.id,
            kind: frame.kind,
            extended: frame.extended,
            len: frame.len,
            data: frame.data.clone(),
            foreign,
        });
        Ok(())
    }

    #[inline]
    fn line_end(&mut self, lines: u64, pos: usize, detector: &Detector) {
        if !self.cut_pending {
            return;
        }
        self.cut_pending = false;
        let detector = (detector.context() != self.result.start_context).then(|| detector.fork());
        self.result.cuts.push(Cut {
            record: self.result.records.len().saturating_sub(1),
            lines,
            pos,
            tally: self.result.tally,
            detector,
        });
    }
}

impl Recorder {
    /// A time-only frame's time: the block's first is recorded, of each
    /// later run only the last (see [`Recorder::flush_time`]).
    fn time_only(&mut self, t: Timestamp) {
        if self.time_kept {
            self.time_pending = Some(t);
        } else {
            self.time_kept = true;
            self.result.records.push(BlockRecord::Time(t));
        }
    }

    /// Records the last time of a run of time-only frames (before the next
    /// frame record, and at the end of the block).
    fn flush_time(&mut self) {
        if let Some(t) = self.time_pending.take() {
            self.result.records.push(BlockRecord::Time(t));
        }
    }
}

impl<E: Write> Consumer<'_, '_, E> {
    /// Counts what a worker counted of a block's lines besides records.
    fn add_tally(&mut self, t: Tally) {
        self.counts.frames += t.plain_frames;
        self.counts.skipped += t.skipped;
        self.counts.dropped = self.counts.dropped.saturating_add(t.dropped);
        self.counts.annotated += t.annotated;
        self.counts.malformed += t.unreported;
        self.diags.suppressed += t.unreported + t.unreported_warnings;
    }

    /// Takes back what [`Consumer::add_tally`] added of a block's lines
    /// that are to be read again.
    fn take_tally(&mut self, t: Tally) {
        let c = &mut self.counts;
        c.frames = c.frames.saturating_sub(t.plain_frames);
        c.skipped = c.skipped.saturating_sub(t.skipped);
        c.dropped = c.dropped.saturating_sub(t.dropped);
        c.annotated = c.annotated.saturating_sub(t.annotated);
        c.malformed = c.malformed.saturating_sub(t.unreported);
        self.diags.suppressed = self
            .diags
            .suppressed
            .saturating_sub(t.unreported + t.unreported_warnings);
    }

    /// Replays a worker's block result as if its lines had been read here,
    /// up to the first cut after which the interest widened; then the rest
    /// of the block is classified again here, from the detector `r.end`
    /// (which the caller swapped for the state the block began in) or the
    /// one the cut kept. Returns the buffers, and the detector after the
    /// rest when it was read here.
    fn replay(
        &mut self,
        mut r: BlockResult,
        max_line: usize,
    ) -> Result<(Spare, Option<Detector>), OutputError> {
        self.add_tally(r.tally);
        self.ids.add(&r.ids);
        self.frame_times(r.frame_times.0, r.frame_times.1);
        let mut cuts = std::mem::take(&mut r.cuts);
        // The next cut to reach, and whether the interest widened at it.
        let mut cut_at = 0usize;
        let mut widened = false;
        for (n, record) in r.records.drain(..).enumerate() {
            match record {
                BlockRecord::Malformed { idx, reason } => self.malformed(idx, reason),
                BlockRecord::Warning { idx, reason } => self.warning(idx, reason),
                BlockRecord::Time(t) => self.time(t),
                BlockRecord::TimedLines {
                    idx,
                    channel,
                    lines,
                } => {
                    let channel = r.channels.get(channel).unwrap_or_default();
                    let at = lines.start;
                    let lines = r.ids.timed_lines.get(lines).unwrap_or_default();
                    self.timed_lines(idx, channel, lines, at)?;
                }
                BlockRecord::Folded {
                    idx,
                    plain,
                    timed,
                    first,
                    last,
                    latest,
                    channel,
                    folds,
                    frames,
                    inner,
                    handed,
                } => {
                    let run = FoldedRun {
                        plain,
                        timed,
                        first,
                        last,
                        latest,
                        channel: r.channels.get(channel).unwrap_or_default(),
                        folds: r.folds.get(folds.clone()).unwrap_or_default(),
                        frames: r.folded.get(frames.clone()).unwrap_or_default(),
                        inner: r.inner.get(inner.clone()).unwrap_or_default(),
                        handed: r.ids.timed_lines.get(handed.clone()).unwrap_or_default(),
                        at: RunAt {
                            folds: folds.start,
                            frames: frames.start,
                            inner: inner.start,
                            handed: handed.start,
                        },
                    };
                    self.folded(idx, &run)?;
                }
                BlockRecord::Frame {
                    idx,
                    time,
                    channel,
                    id,
                    kind,
                    extended,
                    len,
                    data,
                    foreign,
                } => {
                    let frame = Frame {
                        time,
                        channel: r.channels.get(channel).unwrap_or_default(),
                        id,
                        extended,
                        kind,
                        len,
                        data,
                    };
                    self.frame(idx, &frame, foreign)?;
                    if cuts.get(cut_at).is_some_and(|c| c.record == n) {
                        if self.wanted.widened > r.interest_gen {
                            widened = true;
                            break;
                        }
                        cut_at += 1;
                    }
                }
            }
        }
        let Some(cut) = cuts.get_mut(cut_at).filter(|_| widened) else {
            self.lines(r.lines);
            r.cuts = cuts;
            return Ok((r.into_spare(), None));
        };
        // The rest was filtered for fewer ids than are wanted now: read
        // it again here, as if the block had ended at the cut.
        self.take_tally(r.tally.after(cut.tally));
        self.lines(cut.lines);
        let mut detector = cut.detector.take().unwrap_or_else(|| r.end.fork());
        let rest = r.block.text().get(cut.pos..).unwrap_or_default();
        // The rest's frames are in the block's counts already.
        let counted = std::mem::take(&mut self.ids);
        let read = classify_text(rest, None, max_line, &mut detector, self);
        self.ids = counted;
        read?;
        r.cuts = cuts;
        Ok((r.into_spare(), Some(detector)))
    }
}

enum Message {
    Result(Box<BlockResult>),
    /// Reading failed after `seq` blocks.
    ReadError(u64, io::Error),
}

/// Workers classify blocks; the calling thread consumes their results in
/// order. A block whose start state differs from the state the previous
/// block ended in (an ASC header changed the base mid-file), or that was
/// parsed for an older set of wanted ids (an EMCY id moved by 0x1014), is
/// classified again here, so the result never depends on the split. Workers
/// the system will not start are done without; with none, this thread
/// reads the input alone. Returns the read error, if any, and the
/// detector's final state.
pub(super) fn run<R: Read + Send, E: Write>(
    blocks: BlockReader<R>,
    detector: Detector,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<(Option<String>, Detector), OutputError> {
    let threads = consumer.opts.threads.max(1);
    let max_line = consumer.opts.max_line;
    let limit = consumer.opts.max_diagnostics;
    let mut current = detector;
    let shared: SharedInterest = Arc::new(RwLock::new((
        consumer.wanted.generation,
        consumer.wanted.reading().clone(),
    )));
    consumer.wanted.shared = Some(Arc::clone(&shared));
    let feed_lock = Mutex::new(Feed {
        blocks,
        seq: 0,
        done: false,
        alone: false,
    });
    let feed = &feed_lock;
    let outcome = std::thread::scope(|scope| {
        let (result_tx, result_rx) = mpsc::channel::<Message>();
        let mut recycle = Vec::new();
        for _ in 0..threads {
            // Workers are numbered as they start: a block goes back to its own.
            let worker = recycle.len();
            let (recycle_tx, recycle_rx) = mpsc::channel::<Spare>();
            let mut det = current.fork();
            let tx = result_tx.clone();
            let shared = Arc::clone(&shared);
            let spawned = spawn_scoped(scope, move || {
                let mut out = 0usize;
                while let Some((seq, block, spare)) = next_job(feed, &recycle_rx, &mut out, &tx) {
                    let start_context = det.context();
                    let Ok((interest_gen, interest)) = shared.read().map(|g| g.clone()) else {
                        return;
                    };
                    let mut rec = Recorder {
                        interest,
                        limit,
                        time_kept: false,
                        time_pending: None,
                        diagnostics_kept: 0,
                        cut_pending: false,
                        result: BlockResult {
                            seq,
                            worker,
                            block: Block::default(),
                            start_context,
                            interest_gen,
                            cuts: spare.cuts,
                            end: det.fork(),
                            lines: 0,
                            tally: Tally::default(),
                            frame_times: (None, None),
                            records: spare.records,
                            channels: spare.channels,
                            folds: spare.folds,
                            folded: spare.folded,
                            inner: spare.inner,
                            ids: spare.ids,
                        },
                    };
                    // A recorder never fails: it only collects.
                    let _ = classify_block(&block, max_line, &mut det, &mut rec);
                    rec.flush_time();
                    let mut result = rec.result;
                    result.end = det.fork();
                    result.block = block;
                    if tx.send(Message::Result(Box::new(result))).is_err() {
                        return;
                    }
                }
            });
            if !spawned {
                break;
            }
            recycle.push(recycle_tx);
        }
        drop(result_tx);
        if recycle.is_empty() {
            return None;
        }
        consumer.reading.workers = recycle.len();
        Some(consume_in_order(
            result_rx,
            &recycle,
            feed,
            &mut current,
            consumer,
            max_line,
        ))
    });
    let outcome = match outcome {
        Some(outcome) => outcome,
        // No worker started, so no block was taken: all are read here.
        None => {
            let mut feed = feed_lock.into_inner().unwrap_or_else(|e| e.into_inner());
            read_here(&mut feed.blocks, &mut current, consumer, max_line)
        }
    };
    consumer.wanted.shared = None;
    outcome.map(|error| (error, current))
}

/// The whole input on this thread, block by block, as without workers.
fn read_here<R: Read, E: Write>(
    blocks: &mut BlockReader<R>,
    current: &mut Detector,
    consumer: &mut Consumer<'_, '_, E>,
    max_line: usize,
) -> Result<Option<String>, OutputError> {
    let mut buf = Vec::new();
    loop {
        match blocks.next_block(buf) {
            Ok(Some(block)) => {
                classify_block(&block, max_line, current, consumer)?;
                buf = block.bytes;
            }
            Ok(None) => return Ok(None),
            Err(e) => return Ok(Some(e.to_string())),
        }
    }
}

/// The input, read a block at a time by whichever worker is free. The
/// worker that reads a block parses it, into a buffer it had before: no
/// reader thread, and the bytes are in the parsing core's cache (no faster
/// on the 2-core CI machine than a reader thread, but 4 blocks in flight
/// instead of 5: peak memory on a 30% EMCY trace 24 -> 17 MiB).
struct Feed<R> {
    blocks: BlockReader<R>,
    seq: u64,
    done: bool,
    /// The consumer reads the rest alone: workers take no more blocks.
    alone: bool,
}

/// Blocks a worker may have out at once: one being parsed, one waiting to
/// be consumed. A block comes back (recycled) once consumed; waiting for
/// one keeps a slow consumer (30% EMCY) from letting parsed blocks pile up
/// in memory. A parsed EMCY-heavy block holds about as much in records as
/// in text (~1 MiB each), so this limit is what peak memory is made of.
const BLOCKS_PER_WORKER: usize = 2;

/// The next block for a worker, read into a buffer it had before; `None`
/// at the end of the input or after a read error (sent to the consumer).
fn next_job<R: Read>(
    feed: &Mutex<Feed<R>>,
    recycled: &Receiver<Spare>,
    out: &mut usize,
    tx: &mpsc::Sender<Message>,
) -> Option<(u64, Block, Spare)> {
    let buf = match recycled.try_recv() {
        Ok(b) => Some(b),
        Err(_) if *out < BLOCKS_PER_WORKER => None,
        Err(_) => Some(recycled.recv().ok()?),
    };
    let mut spare = match buf {
        Some(b) => {
            *out -= 1;
            b
        }
        None => Spare::default(),
    };
    let buf = std::mem::take(&mut spare.bytes);
    let mut feed = feed.lock().ok()?;
    if feed.done || feed.alone {
        return None;
    }
    match feed.blocks.next_block(buf) {
        Ok(Some(block)) => {
            let seq = feed.seq;
            feed.seq += 1;
            *out += 1;
            Some((seq, block, spare))
        }
        Ok(None) => {
            feed.done = true;
            None
        }
        Err(e) => {
            feed.done = true;
            let _ = tx.send(Message::ReadError(feed.seq, e));
            None
        }
    }
}

/// Of the last 64 blocks, how many may be read twice before the consumer
/// stops the workers and reads the rest alone: two threads that parse a
/// block each while the consumer parses one of them again burn twice the
/// CPU of one and are no faster (slower on a loaded machine).
const READ_AGAIN_IN_64: u32 = 8;

fn consume_in_order<R: Read, E: Write>(
    results: Receiver<Message>,
    recycle: &[mpsc::Sender<Spare>],
    feed: &Mutex<Feed<R>>,
    current: &mut Detector,
    consumer: &mut Consumer<'_, '_, E>,
    max_line: usize,
) -> Result<Option<String>, OutputError> {
    let mut next = 0u64;
    let mut pending: BTreeMap<u64, BlockResult> = BTreeMap::new();
    let mut read_error: Option<(u64, io::Error)> = None;
    // A bit per block consumed, the latest lowest: set when it was read
    // again (whole or from a cut).
    let mut window = 0u64;
    for message in results {
        match message {
            Message::Result(r) => {
                pending.insert(r.seq, *r);
            }
            Message::ReadError(seq, e) => read_error = Some((seq, e)),
        }
        while let Some(r) = pending.remove(&next) {
            let r_worker = r.worker;
            // A block parsed before the interest last widened may lack
            // frames wanted now; one parsed after a narrowing holds some
            // frames more, which the consumer skips as the sequential
            // reader would.
            let valid = r.start_context.is_some()
                && r.start_context == current.context()
                && r.interest_gen >= consumer.wanted.widened;
            let spare = if valid {
                let mut r = r;
                // `r.end` becomes the state the block began in.
                std::mem::swap(current, &mut r.end);
                let (spare, rest) = consumer.replay(r, max_line)?;
                window <<= 1;
                if let Some(detector) = rest {
                    *current = detector;
                    consumer.reading.rests_read_again += 1;
                    window |= 1;
                }
                spare
            } else {
                classify_block(&r.block, max_line, current, consumer)?;
                consumer.reading.blocks_read_again += 1;
                window = window << 1 | 1;
                r.into_spare()
            };
            consumer.reading.blocks += 1;
            if consumer.reading.blocks >= 64
                && window.count_ones() > READ_AGAIN_IN_64
                && !consumer.reading.fell_back
                && let Ok(mut feed) = feed.lock()
            {
                // Workers take no more blocks; what they took comes in
                // order as before, and the rest is read here below.
                feed.alone = true;
                consumer.reading.fell_back = true;
            }
            if let Some(worker) = recycle.get(r_worker) {
                let _ = worker.send(spare);
            }
            next += 1;
        }
    }
    if let Some((_, e)) = read_error {
        return Ok(Some(e.to_string()));
    }
    if !consumer.reading.fell_back {
        return Ok(None);
    }
    // Every worker has stopped (the results ended): the blocks after
    // theirs are read on this thread.
    let mut feed = feed.lock().unwrap_or_else(|e| e.into_inner());
    if feed.done {
        return Ok(None);
    }
    read_here(&mut feed.blocks, current, consumer, max_line)
}
