//! The one loop that classifies a block's lines into a [`LineSink`]: the
//! consumer itself when reading sequentially, a worker's recorder in
//! parallel.

use super::analysis::OutputError;
use crate::trace::detect::Detector;
use crate::trace::format::candump_log;
use crate::trace::lines::{self, Block, RawLine, too_long};
use crate::trace::{
    Fold, FoldBuffers, Folded, Folds, Format, Frame, FrameKind, IdCounts, Inner, Interest, Parsed,
    Reason, Scan, TimedLine, Timestamp,
};

/// A frame read in another format than the file's: (its format, the file's).
pub(super) type Foreign = Option<(Format, Format)>;

/// Receives classified lines; `idx` is the line's 0-based index in its block.
pub(super) trait LineSink {
    /// The ids to decode now (the consumer's can change mid-input).
    fn interest(&self) -> &Interest;
    /// Valid frames the consumer has no use for: counted only.
    fn plain_frames(&mut self, n: u64);
    /// `n` wanted frames that only move the input's first/last time (see
    /// [`content_matters`](super::interest::content_matters)), the first and last of their times.
    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp);
    /// The times of the block's first and last frames of any id
    /// ([`Detector::first_frame_time`], [`Detector::last_frame_time`]):
    /// the input's span.
    fn frame_times(&mut self, first: Option<Timestamp>, last: Option<Timestamp>);
    /// A run of lines whose repeated frames the reader folded, its plain
    /// and timed frames (the folded ones among them) to count as by
    /// `plain_frames` and `timed_frames`.
    fn folded(&mut self, idx: u64, run: &FoldedRun<'_>) -> Result<(), OutputError>;
    /// Vectors for a block's folds: a sink gives back the last block's.
    fn fold_buffers(&mut self) -> FoldBuffers {
        FoldBuffers::default()
    }
    /// Whether the sink takes the block's folds whole at its end
    /// ([`LineSink::block_folds`]): then every run's are kept till then.
    fn keeps_folds(&self) -> bool {
        false
    }
    /// The block's folds, every run's ([`FoldedRun::at`] says where each
    /// run's are): a sink that keeps them takes them whole.
    fn block_folds(&mut self, _folds: FoldBuffers) {}
    /// The counts every frame of the block is added to, by channel and id,
    /// lent for the block ([`LineSink::put_id_counts`] gives them back).
    fn take_id_counts(&mut self) -> IdCounts;
    /// The counts [`LineSink::take_id_counts`] lent, with the block's frames.
    fn put_id_counts(&mut self, ids: IdCounts);
    /// Frames of a run the reader handed over for their times alone
    /// (every frame it only counted when every frame is timed, and those
    /// on the ids the interest hands over), also counted by
    /// `plain_frames`, on `channel`, each at its index from `idx`. They
    /// come before the run's other frames; a run with folds carries its
    /// own ([`FoldedRun::handed`]). They begin at `at` in the block's
    /// ([`IdCounts::timed_lines`], given back with the counts).
    fn timed_lines(
        &mut self,
        idx: u64,
        channel: &[u8],
        lines: &[TimedLine],
        at: usize,
    ) -> Result<(), OutputError>;
    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError>;
    /// After a line outside a run or the frame that ended a run: `lines`
    /// lines of the block are read, the next begins at byte `pos`, and the
    /// detector is as it is there (a worker's recorder marks where the
    /// consumer may have to read the block's rest again).
    #[inline]
    fn line_end(&mut self, _lines: u64, _pos: usize, _detector: &Detector) {}
    fn skipped(&mut self);
    /// Frames a skipped line says were lost before they were logged
    /// (candump `DROPCOUNT`).
    fn dropped(&mut self, n: u64);
    /// The frame just handed on had a note after it on its line (see
    /// [`LineParser::take_annotated`](crate::trace::LineParser::take_annotated)).
    fn annotated(&mut self);
    fn malformed(&mut self, idx: u64, reason: Reason);
    /// A diagnostic about the frame on the same line, which the reader made
    /// good (a contradiction it resolved); the frame follows.
    fn warning(&mut self, idx: u64, reason: Reason);
    /// A line that is not a frame made the format known (an ASC header).
    fn format_known(&mut self);
    fn lines(&mut self, n: u64);
}

/// A run of lines of one layout with frames folded ([`Folds`]), and frames
/// kept inside it ([`Folds::keep_inside`]), without the frame that ended it.
pub(super) struct FoldedRun<'a> {
    pub plain: u64,
    /// Timed frames, the folded ones included.
    pub timed: u64,
    pub first: Timestamp,
    pub last: Timestamp,
    /// The last frame folded or kept inside (the latest time: a run's
    /// times only go forward).
    pub latest: Timestamp,
    pub channel: &'a [u8],
    pub folds: &'a [Fold],
    /// Their frames one by one, for a sink that cannot take them whole.
    pub frames: &'a [Folded],
    /// Frames that did not end the run (counted in neither `plain` nor
    /// `timed`), on `channel`: taken after the folds when those are taken
    /// whole, else in line order among their frames.
    pub inner: &'a [Inner],
    /// Frames handed over for their times ([`LineSink::timed_lines`]),
    /// counted in `plain`, on `channel`: in line order among the others.
    pub handed: &'a [TimedLine],
    /// Where `folds`, `frames` and `inner` begin in the block's.
    pub at: RunAt,
}

/// Where a [`FoldedRun`]'s folds and frames begin in its block's
/// ([`LineSink::block_folds`]), and its handed-over lines in the block's
/// ([`IdCounts::timed_lines`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RunAt {
    pub folds: usize,
    pub frames: usize,
    pub inner: usize,
    pub handed: usize,
}

/// The one loop that classifies lines, sequentially or on a worker: runs
/// of common lines through the parser's hot loop, anything else a line at
/// a time.
pub(super) fn classify_block(
    block: &Block,
    max_line: usize,
    detector: &mut Detector,
    sink: &mut impl LineSink,
) -> Result<(), OutputError> {
    classify_text(
        block.text(),
        block.too_long_before,
        max_line,
        detector,
        sink,
    )
}

/// [`classify_block`] of whole lines `bytes`, after a too-long line of
/// `too_long_before` bytes if one came right before them.
pub(super) fn classify_text(
    bytes: &[u8],
    too_long_before: Option<u64>,
    max_line: usize,
    detector: &mut Detector,
    sink: &mut impl LineSink,
) -> Result<(), OutputError> {
    // Every frame of the block is counted by channel and id: those the
    // reader only counts or times in its hot loop, the rest as they are
    // handed on ([`deliver`]).
    let mut ids = sink.take_id_counts();
    let read = classify_lines(bytes, too_long_before, max_line, detector, sink, &mut ids);
    sink.put_id_counts(ids);
    read
}

/// [`classify_text`] with the counts lent.
fn classify_lines(
    bytes: &[u8],
    too_long_before: Option<u64>,
    max_line: usize,
    detector: &mut Detector,
    sink: &mut impl LineSink,
    ids: &mut IdCounts,
) -> Result<(), OutputError> {
    // Read before the block moves the detector on (times may chain).
    let first = detector.first_frame_time(bytes, max_line);
    let mut idx = 0u64;
    let mut pos = 0usize;
    let keep = sink.keeps_folds();
    let mut folds = Folds::with_buffers(sink.fold_buffers(), keep);
    if let Some(n) = too_long_before {
        sink.malformed(idx, too_long(n, max_line));
        idx += 1;
    }
    // The block's handed-over lines stay in the counts' buffer, each run's
    // after the last: a worker's record points at them rather than copying
    // them (the copy and the second buffer's pages were 2-6% of a worker's
    // time with `--timing`: perf, the bench's segmented firmware trace).
    ids.timed_lines.clear();
    loop {
        // Started here: in the reader's hot loop it made every line slower.
        folds.next_run();
        let handed_at = ids.timed_lines.len();
        let mut run = detector.run(
            bytes.get(pos..).unwrap_or_default(),
            max_line,
            sink.interest(),
            &mut folds,
            ids,
        );
        pos += run.bytes;
        // A frame the interest lets stay inside a run with folds does not
        // end it: the reader goes on (with the same layout, so the same
        // channel), the stretches' counts and times adding up.
        let (mut plain, mut timed, mut inner) = (run.plain, run.timed, 0u64);
        let (first, mut last, channel) = (run.first_time, run.last_time, run.fold_channel);
        while let Some(frame) = run.frame.as_ref()
            && !frame.extended
            && sink.interest().keeps_inside(frame.id)
            && folds.keep_inside(frame, run.plain + run.timed)
        {
            inner += 1;
            ids.count(frame.key());
            // The frame's time, unless lines after it have one.
            last = frame.time;
            let handed = ids.timed_lines.len();
            run = detector.run(
                bytes.get(pos..).unwrap_or_default(),
                max_line,
                sink.interest(),
                &mut folds,
                ids,
            );
            pos += run.bytes;
            // The reader counts this stretch's lines from its start.
            // (A block holds fewer lines than a `u32` counts: see
            // `BlockReader::new`.)
            let before = u32::try_from(plain + timed + inner).unwrap_or(u32::MAX);
            for l in ids.timed_lines.get_mut(handed..).unwrap_or_default() {
                l.idx = l.idx.saturating_add(before);
            }
            plain += run.plain;
            timed += run.timed;
            if run.last_time.is_some() {
                last = run.last_time;
            }
        }
        let folded = match (folds.latest(), first, last) {
            (Some(latest), Some(first), Some(last)) => Some(FoldedRun {
                plain,
                timed,
                first,
                last,
                latest,
                channel,
                folds: folds.as_slice(),
                frames: folds.frames(),
                inner: folds.inner(),
                handed: ids.timed_lines.get(handed_at..).unwrap_or_default(),
                at: {
                    let (folds, frames, inner) = folds.run_start();
                    RunAt {
                        folds,
                        frames,
                        inner,
                        handed: handed_at,
                    }
                },
            }),
            _ => None,
        };
        if let Some(folded) = folded {
            sink.folded(idx, &folded)?;
            idx += plain + timed + inner;
        } else {
            // No folds, so one stretch: its lines handed over first (the
            // frames around them only count and move the input's times).
            let handed = ids.timed_lines.get(handed_at..).unwrap_or_default();
            if !handed.is_empty() {
                sink.timed_lines(idx, run.channel, handed, handed_at)?;
            }
            if plain > 0 {
                sink.plain_frames(plain);
                idx += plain;
            }
            if let (Some(first), Some(last)) = (first, last) {
                sink.timed_frames(timed, first, last);
                idx += timed;
            }
        }
        if let Some(frame) = run.frame {
            deliver(sink, ids, idx, &frame, None)?;
            idx += 1;
            sink.line_end(idx, pos, detector);
            continue;
        }
        let Some((raw, next)) = lines::line_at(bytes, pos, max_line) else {
            break;
        };
        pos = next;
        classify_line(raw, idx, detector, sink, ids, max_line)?;
        idx += 1;
        sink.line_end(idx, pos, detector);
    }
    let last = detector.last_frame_time(bytes, max_line);
    sink.frame_times(first, last);
    sink.lines(idx);
    sink.block_folds(folds.into_buffers());
    Ok(())
}

/// One line outside the parser's hot loop.
fn classify_line(
    raw: RawLine<'_>,
    idx: u64,
    detector: &mut Detector,
    sink: &mut impl LineSink,
    ids: &mut IdCounts,
    max_line: usize,
) -> Result<(), OutputError> {
    match raw {
        RawLine::TooLong(n) => sink.malformed(idx, too_long(n, max_line)),
        RawLine::Text(text) => match detector.scan(text, sink.interest()) {
            Scan::Plain(key) => {
                ids.count(key);
                sink.plain_frames(1);
            }
            Scan::Timed(t, key) => {
                ids.count(key);
                sink.timed_frames(1, t, t);
            }
            Scan::Frame(frame) => deliver(sink, ids, idx, &frame, None)?,
            Scan::Parse => {
                let known = detector.format().is_some();
                match detector.parse(text, sink.interest()) {
                    Parsed::Frame(frame) => {
                        if let Some(warning) = detector.take_warning() {
                            sink.warning(idx, warning);
                        }
                        if detector.take_annotated() {
                            sink.annotated();
                        }
                        let foreign = detector.take_foreign().zip(detector.format());
                        deliver(sink, ids, idx, &frame, foreign)?;
                    }
                    Parsed::Skipped => {
                        sink.skipped();
                        if let Some(n) = candump_log::dropped_frames(text) {
                            sink.dropped(n);
                        }
                        if detector.reads_deltas() && candump_log::is_elision_line(text) {
                            sink.warning(
                                idx,
                                "lines were left out here: their -td deltas are missing, so \
                                 every later time is early by their sum"
                                    .into(),
                            );
                        }
                        if !known && detector.format().is_some() {
                            sink.format_known();
                        }
                    }
                    Parsed::Malformed(reason) => sink.malformed(idx, reason),
                }
            }
        },
    }
    Ok(())
}

/// Hands a frame on as the consumer treats it: one it has no use for is
/// only counted, one that only moves the input's first/last time only timed
/// (so workers record neither); the rest, and every frame in another format
/// than the file's (its line gets a diagnostic), go to `frame`, which
/// applies the same rules in full. Every frame is counted in `ids`.
pub(super) fn deliver(
    sink: &mut impl LineSink,
    ids: &mut IdCounts,
    idx: u64,
    frame: &Frame<'_>,
    foreign: Foreign,
) -> Result<(), OutputError> {
    match frame.kind {
        FrameKind::Error => ids.error_frame(frame.channel),
        _ => ids.count(frame.key()),
    }
    if foreign.is_none() {
        let interest = sink.interest();
        // Remote requests on wanted ids go on too: on 0x700 + node they ask
        // for a node-guarding reply.
        let wanted = match frame.kind {
            FrameKind::Data | FrameKind::Remote => interest.wants(frame.id, frame.extended),
            FrameKind::Error => interest.wants_error_frames(),
            FrameKind::Fd => interest.wants_fd_on(frame.id, frame.extended),
        };
        if !wanted {
            sink.plain_frames(1);
            return Ok(());
        }
        if frame.kind != FrameKind::Error
            && let Some(t) = frame.time
            && interest.timed_only(frame.id, frame.extended, frame.data.as_slice())
        {
            sink.timed_frames(1, t, t);
            return Ok(());
        }
    }
    sink.frame(idx, frame, foreign)
}
