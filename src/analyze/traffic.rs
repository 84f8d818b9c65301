//! The traffic of each channel: frames and error frames, and per
//! identifier how many frames, how regularly they came (period, jitter,
//! largest gap, missed cycles) and, with a bit rate, the load they put on
//! the wire.
//!
//! The counts come from the readers ([`IdCounts`]: every frame by channel
//! and identifier, on every run). SYNC's frames come here on every run,
//! and with `--timing` every frame of the input: the frames the analysis
//! decodes, and the others with their times only (the candump hot loop's
//! [`TimedLine`]s; the other readers decode them). A SYNC producer that
//! skips cycles is a `sync_missed` event ([`Traffic::frame`] says when).
//!
//! Times are kept as the reader's ticks where they can be (one
//! precision: intervals are integer subtractions), and SYNC's lines are
//! timed in batches ([`Traffic::lines_until_gap`]): so timed, SYNC costs a
//! 1 kHz bus's default path 2-7% more instructions, where decoding each
//! SYNC frame cost 40-50% (callgrind, the bench's bus traces).
//!
//! Memory is bounded per identifier: counts, running sums and a thinned
//! sample of at most 256 intervals for the median, nothing per frame.

use crate::canopen::NodeId;
use crate::canopen::cob_id::{self, SYNC_ID};
use crate::timeline::At;
// Intervals seen before a period is trusted (to call a gap a miss), as for
// a heartbeat's: the median of fewer is one odd interval from wrong.
use crate::timeline::heartbeat::LEARN_FROM;
use crate::trace::id_counts::{MAX_CHANNELS, MAX_EXTENDED};
use crate::trace::{FrameKind, IdCounts, Span, Ticks, TimedLine, Timestamp};

/// Identifiers timed over all channels (at most [`MAX_EXTENDED`] of them
/// extended per channel, the bound the counts have); frames on more are
/// counted, not timed. An identifier holds at most about 2 KiB (its sample
/// of intervals), so the timing of an input stays under 40 MiB.
pub(crate) const MAX_IDS: usize = 16_384;

/// A gap this many periods long (x 3/2) skipped at least one cycle.
const MISSED_FACTOR: f64 = 1.5;

/// Load is measured over windows of this many seconds.
const WINDOW_SECS: u64 = 1;

/// The traffic of one input.
pub(crate) struct Traffic {
    /// `--timing`: every frame comes here, every identifier is reported.
    every_frame: bool,
    channels: Vec<ChannelTraffic>,
    /// The channel of the last frame (most inputs have one).
    last: usize,
    /// Identifiers followed so far, over all channels.
    ids: usize,
}

struct ChannelTraffic {
    name: Box<[u8]>,
    /// Index into `ids` plus one, by standard identifier (0: none yet).
    standard: Box<[u16; 2048]>,
    extended: Vec<(u32, u16)>,
    ids: Vec<IdTraffic>,
    load: Load,
}

/// One identifier's frames on a channel.
struct IdTraffic {
    /// Its service is sent in cycles (SYNC, TIME, PDOs, heartbeats, and
    /// ids outside the predefined set): it has a period, and gaps that
    /// miss cycles. EMCY, SDO, NMT and LSS frames come when something
    /// happens; their intervals say nothing.
    cyclic: bool,
    last: Option<FrameTime>,
    /// The line of the last frame: where a missed cycle's gap began.
    last_line: u64,
    median: Median,
    /// Sum of |interval - period| over the intervals that missed no cycle,
    /// in microseconds, and how many (jitter: their mean).
    deviation: f64,
    regular: u64,
    max_gap: Option<Span>,
    /// `max_gap` in microseconds (compared with every interval).
    max_gap_us: f64,
    missed: u64,
}

/// A frame's interval as [`IdTraffic::judge`] finds it.
#[derive(Clone, Copy)]
struct Judged {
    /// In microseconds (the exact span is made only for a new largest gap).
    interval: Option<f64>,
    /// The period it is judged against.
    period: Option<f64>,
    /// Whether the interval missed cycles of it.
    missed: bool,
}

/// Microseconds below this come out of [`micros`] exactly: `n` of them
/// are `n` × 5^12 × 2^12 attoseconds, an exact `f64` while `n` × 5^12 is
/// under 2^53, so the division by 10^12 gives `n` again.
const EXACT_MICROS: u64 = 1 << 25;

/// A frame [`Traffic::take`] left alone: it would end a gap in SYNC.
struct EndsGap;

/// A frame's time as it came: a line's [`Ticks`] (the candump hot loop
/// hands lines over so) or a decoded frame's [`Timestamp`], as ticks of
/// its own precision where they fit. Two ticks of one precision subtract
/// as integers; timestamps take 128-bit arithmetic, which with the
/// conversion cost every SYNC line about 400 instructions more
/// (callgrind, the bench's commissioning trace), more than the line's
/// reading and counting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FrameTime {
    Ticks(Ticks),
    Stamp(Timestamp),
}

impl FrameTime {
    /// A decoded frame's time.
    pub(crate) fn of(t: Timestamp) -> FrameTime {
        t.ticks().map_or(FrameTime::Stamp(t), FrameTime::Ticks)
    }

    pub(crate) fn timestamp(self) -> Timestamp {
        match self {
            FrameTime::Ticks(t) => t.timestamp(),
            FrameTime::Stamp(t) => t,
        }
    }

    /// The time from `earlier` to `self` in microseconds; `None` when
    /// negative.
    #[inline(always)]
    fn micros_since(self, earlier: FrameTime) -> Option<f64> {
        if let (FrameTime::Ticks(now), FrameTime::Ticks(then)) = (self, earlier)
            && now.digits == then.digits
        {
            let n = now.value.checked_sub(then.value)?;
            // Microsecond ticks (candump's) are the microseconds: the
            // division below gives `n` exactly for these, and its latency
            // was a sixth of the time `--timing` spends here (perf, the
            // bench's commissioning trace).
            if now.digits == 6 && n < EXACT_MICROS {
                return Some(n as f64);
            }
            return Some(match now.attos_i64(n) {
                Some(attos) => attos as f64 / 1e12,
                None => micros(now.span(n)),
            });
        }
        let span = self.timestamp().since(earlier.timestamp());
        (!span.is_negative()).then(|| micros(span))
    }

    /// The time from `earlier` to `self`, exactly (negative when it goes
    /// back).
    fn since(self, earlier: FrameTime) -> Span {
        if let (FrameTime::Ticks(now), FrameTime::Ticks(then)) = (self, earlier)
            && now.digits == then.digits
            && let Some(n) = now.value.checked_sub(then.value)
        {
            return now.span(n);
        }
        self.timestamp().since(earlier.timestamp())
    }
}

/// Bits on the wire per window of [`WINDOW_SECS`].
#[derive(Default)]
struct Load {
    bits: u64,
    window: Option<Window>,
    peak_bits: u64,
    first: Option<FrameTime>,
    last: Option<FrameTime>,
}

/// The current window of a [`Load`]: from a frame's time for
/// [`WINDOW_SECS`], and the bits in it.
#[derive(Clone, Copy)]
struct Window {
    start: FrameTime,
    /// Where the window ends in the start's ticks (when it has them and the
    /// end fits): a frame of the same precision is in the window when its
    /// ticks lie in `start..end`. Integers compared, where the span since
    /// the start converted to microseconds cost every frame of `--timing`
    /// about 20 instructions (callgrind, the bench's commissioning trace).
    end: Option<u64>,
    bits: u64,
}

/// SYNC skipped cycles: told as a `sync_missed` event.
#[derive(Clone, Debug, PartialEq)]
pub struct SyncMissed {
    /// The last SYNC before the gap, and the one that ended it (`None`:
    /// the gap lasted to the end of the input).
    pub start: At,
    pub end: Option<At>,
    /// The period (the median interval) the gap is measured against.
    pub period: Span,
    /// Cycles with no SYNC: the gap over the period, less the one that
    /// ended it.
    pub missed: u64,
}

/// A channel's traffic over an input: the JSON `channel` object.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelReport {
    pub channel: String,
    /// Every frame, error frames included.
    pub frames: u64,
    pub error_frames: u64,
    /// Every frame was timed (`--timing`): the identifiers have their
    /// periods, gaps and misses, and the channel its load.
    pub timed: bool,
    /// Bits on the wire over the channel's span, as a percentage of the
    /// bit rate: the mean and the busiest window; `None` without a rate.
    pub load: Option<LoadReport>,
    /// Every identifier that had a frame: standard ids, then extended, each
    /// by id.
    pub ids: Vec<IdReport>,
    /// Frames on extended identifiers past the bound the counts have
    /// ([`MAX_EXTENDED`](crate::trace::id_counts::MAX_EXTENDED)): counted
    /// for the channel, not per id.
    pub other_ids: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadReport {
    pub bit_rate: u32,
    pub bits: u64,
    pub mean_percent: f64,
    pub peak_percent: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct IdReport {
    pub cob_id: u32,
    pub extended: bool,
    pub service: &'static str,
    pub node: Option<NodeId>,
    pub count: u64,
    /// The median interval; `None` for a service that is not cyclic, under
    /// [`LEARN_FROM`] intervals, or not timed.
    pub period: Option<Span>,
    /// The mean absolute deviation of the intervals from the period, those
    /// that missed a cycle left out.
    pub jitter: Option<Span>,
    /// `None` when not timed (or a single frame).
    pub max_gap: Option<Span>,
    /// Gaps of more than 1.5 periods (each counted once however many
    /// cycles it skipped); `None` when not timed.
    pub missed: Option<u64>,
}

impl Traffic {
    pub(crate) fn new(every_frame: bool) -> Self {
        Traffic {
            every_frame,
            channels: Vec::new(),
            last: 0,
            ids: 0,
        }
    }

    /// Whether every frame comes here (`--timing`); else the frames the
    /// interest hands over for their times (SYNC's) only.
    #[inline]
    pub(crate) fn wants(&self) -> bool {
        self.every_frame
    }

    /// Lines handed over for their times ([`TimedLine`]), of the channel
    /// at `c`, the first at line `first_line`, timed in order up to the
    /// first that would end a gap in SYNC (an event its caller must tell in
    /// line order, through [`Traffic::frame_in`]): how many were timed. One
    /// tight loop: a SYNC line taken one call at a time cost the default
    /// path about 200 instructions more (callgrind, the bench's
    /// commissioning trace).
    pub(crate) fn lines_until_gap(
        &mut self,
        c: usize,
        first_line: u64,
        lines: &[TimedLine],
    ) -> usize {
        lines
            .iter()
            .position(|l| {
                let time = l.time().map(FrameTime::Ticks);
                let line = first_line + u64::from(l.idx);
                // A timed line is a classic data frame on a standard id.
                self.take(c, l.id(), false, FrameKind::Data, l.len, time, line, true)
                    .is_err()
            })
            .unwrap_or(lines.len())
    }

    fn channel(&mut self, name: &[u8]) -> Option<&mut ChannelTraffic> {
        let i = self.channel_index(name)?;
        self.channels.get_mut(i)
    }

    /// The index of channel `name` for [`Traffic::frame_in`], made on its
    /// first frame; `None` past [`MAX_CHANNELS`].
    pub(crate) fn channel_index(&mut self, name: &[u8]) -> Option<usize> {
        let i = match self.channels.get(self.last) {
            Some(c) if *c.name == *name => self.last,
            _ => match self.channels.iter().position(|c| *c.name == *name) {
                Some(i) => i,
                None if self.channels.len() < MAX_CHANNELS => {
                    self.channels.push(ChannelTraffic::new(name));
                    self.channels.len() - 1
                }
                // Those past the bound the counts have: the counts tell
                // how many frames they had.
                None => return None,
            },
        };
        self.last = i;
        Some(i)
    }

    /// An error frame on `channel`: with `--timing`, bits on the wire.
    pub(crate) fn error_frame(&mut self, channel: &[u8], time: Option<Timestamp>) {
        if !self.every_frame {
            return;
        }
        if let Some(c) = self.channel(channel) {
            c.load
                .frame(time.map(FrameTime::of), bits(false, FrameKind::Error, 0));
        }
    }

    /// A frame (`--timing`). A SYNC that ends a gap of missed cycles gives
    /// the event to tell.
    #[inline]
    pub(crate) fn frame(
        &mut self,
        channel: &[u8],
        id: u32,
        extended: bool,
        kind: FrameKind,
        len: u8,
        at: At,
    ) -> Option<SyncMissed> {
        let c = self.channel_index(channel)?;
        let time = at.time.map(FrameTime::of);
        self.frame_in(c, id, extended, kind, len, time, at.line)
    }

    /// [`Traffic::frame`] on the channel [`Traffic::channel_index`] gave
    /// (a run of frames on one channel finds it once: comparing its name
    /// for every frame was a tenth of `--timing`'s instructions).
    #[inline]
    #[allow(clippy::too_many_arguments)] // A frame's fields, taken apart.
    pub(crate) fn frame_in(
        &mut self,
        c: usize,
        id: u32,
        extended: bool,
        kind: FrameKind,
        len: u8,
        time: Option<FrameTime>,
        line: u64,
    ) -> Option<SyncMissed> {
        self.take(c, id, extended, kind, len, time, line, false)
            .ok()
            .flatten()
    }

    /// A frame on the channel at `c` into its identifier's statistics
    /// (and, with `--timing`, the load); a gap in SYNC it ends is the event
    /// to tell. With `before_gap`, a frame that would end one is left
    /// alone ([`EndsGap`]: nothing changed).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // A frame's fields, taken apart.
    fn take(
        &mut self,
        c: usize,
        id: u32,
        extended: bool,
        kind: FrameKind,
        len: u8,
        time: Option<FrameTime>,
        line: u64,
        before_gap: bool,
    ) -> Result<Option<SyncMissed>, EndsGap> {
        let Some(channel) = self.channels.get_mut(c) else {
            return Ok(None);
        };
        // (An id made just now has no last frame, so ends no gap.)
        let slot = channel.id(id, extended, &mut self.ids);
        let sync = id == SYNC_ID && !extended;
        let mut gap = None;
        if let (Some(now), Some(t)) = (time, slot.and_then(|i| channel.ids.get_mut(i))) {
            let judged = t.judge(now);
            if before_gap && sync && judged.missed {
                return Err(EndsGap);
            }
            gap = t.take(now, line, judged).filter(|_| sync);
        }
        // The load needs every frame: with `--timing` only.
        if self.every_frame {
            channel.load.frame(time, bits(extended, kind, len));
        }
        Ok(gap)
    }

    /// The end of the input at `end` (the last frame's time): a SYNC
    /// producer silent since more than 1.5 periods before it stopped.
    pub(crate) fn finish(&mut self, end: Option<Timestamp>) -> Vec<(String, SyncMissed)> {
        let mut out = Vec::new();
        let Some(end) = end else {
            return out;
        };
        for c in &mut self.channels {
            let Some(&i) = c.standard.get(SYNC_ID as usize) else {
                continue;
            };
            let Some(t) = (i as usize).checked_sub(1).and_then(|i| c.ids.get_mut(i)) else {
                continue;
            };
            if let Some(missed) = t.silent_until(end) {
                out.push((String::from_utf8_lossy(&c.name).into_owned(), missed));
            }
        }
        out
    }

    /// The channels' reports, by name as the node reports are (the order
    /// channels first had a frame in is the binary readers' to know only
    /// for the frames they hand on): the counts `ids` has, with the timing
    /// followed here; `bit_rate` from `--bitrate` or the trace's header.
    pub(crate) fn into_report(
        mut self,
        ids: &IdCounts,
        bit_rate: Option<u32>,
    ) -> Vec<ChannelReport> {
        let mut reports: Vec<ChannelReport> = ids
            .channels()
            .map(|counts| {
                let timed = self
                    .channels
                    .iter()
                    .position(|c| *c.name == *counts.name())
                    .map(|i| self.channels.swap_remove(i));
                ChannelReport {
                    channel: String::from_utf8_lossy(counts.name()).into_owned(),
                    frames: counts.frames(),
                    error_frames: counts.error_frames(),
                    timed: self.every_frame,
                    load: bit_rate
                        .filter(|_| self.every_frame)
                        .and_then(|rate| timed.as_ref().and_then(|t| t.load.report(rate))),
                    ids: counts
                        .ids()
                        .map(|(id, extended, count)| {
                            let traffic = timed.as_ref().and_then(|t| t.get(id, extended));
                            IdReport::new(id, extended, count, traffic)
                        })
                        .collect(),
                    other_ids: counts.other,
                }
            })
            .collect();
        reports.sort_by(|a, b| a.channel.cmp(&b.channel));
        reports
    }
}

impl ChannelTraffic {
    fn new(name: &[u8]) -> Self {
        ChannelTraffic {
            name: name.into(),
            standard: Box::new([0; 2048]),
            extended: Vec::new(),
            ids: Vec::new(),
            load: Load::default(),
        }
    }

    /// The index in `ids` of `id`'s traffic, made while the input follows
    /// fewer than [`MAX_IDS`] (`followed`, counting the one made). The
    /// count is kept off the common path: counting every frame's id there
    /// cost `--timing` 2 instructions a frame (callgrind, the bench's
    /// segmented firmware trace).
    #[inline(always)]
    fn id(&mut self, id: u32, extended: bool, followed: &mut usize) -> Option<usize> {
        // A standard id already followed: the common case, inline.
        if !extended
            && let Some(&slot) = self.standard.get(id as usize)
            && slot != 0
        {
            return Some(usize::from(slot) - 1);
        }
        self.new_or_extended_id(id, extended, followed)
    }

    /// [`ChannelTraffic::id`] of an extended id, or of a standard one not
    /// followed yet.
    #[inline(never)]
    fn new_or_extended_id(
        &mut self,
        id: u32,
        extended: bool,
        followed: &mut usize,
    ) -> Option<usize> {
        let room = *followed < MAX_IDS;
        let known = self.ids.len();
        let slot = if extended {
            match self.extended.binary_search_by_key(&id, |e| e.0) {
                Ok(i) => self.extended.get(i).map(|e| e.1),
                Err(i) if room && self.extended.len() < MAX_EXTENDED => {
                    let slot = self.new_id(id, true);
                    self.extended.insert(i, (id, slot));
                    Some(slot)
                }
                Err(_) => None,
            }
        } else {
            match self.standard.get(id as usize).copied() {
                Some(0) if room => {
                    let slot = self.new_id(id, false);
                    if let Some(s) = self.standard.get_mut(id as usize) {
                        *s = slot;
                    }
                    Some(slot)
                }
                Some(0) | None => None,
                Some(slot) => Some(slot),
            }
        };
        *followed += self.ids.len() - known;
        // Past the bounds: counted (by the counts), not timed.
        slot.map(|slot| usize::from(slot) - 1)
    }

    /// A new identifier's slot (its index in `ids` plus one); at most
    /// 2048 + [`MAX_EXTENDED`] of them, so it fits.
    fn new_id(&mut self, cob_id: u32, extended: bool) -> u16 {
        let (service, _) = cob_id::service(cob_id, extended);
        self.ids.push(IdTraffic {
            cyclic: !matches!(
                service,
                "emcy" | "sdo_request" | "sdo_response" | "nmt" | "lss_request" | "lss_response"
            ),
            last: None,
            last_line: 0,
            median: Median::default(),
            deviation: 0.0,
            regular: 0,
            max_gap: None,
            max_gap_us: 0.0,
            missed: 0,
        });
        self.ids.len() as u16
    }

    /// The timing of an identifier, if it was followed.
    fn get(&self, id: u32, extended: bool) -> Option<&IdTraffic> {
        let slot = if extended {
            let i = self.extended.binary_search_by_key(&id, |e| e.0).ok()?;
            self.extended.get(i)?.1
        } else {
            *self.standard.get(id as usize)?
        };
        self.ids.get(usize::from(slot).checked_sub(1)?)
    }
}

impl IdTraffic {
    /// What a frame at `now` would be to the statistics, nothing changed:
    /// its interval since the last frame (none for the first, or one that
    /// goes back in time), and whether it missed cycles of the period
    /// known so far.
    #[inline(always)]
    fn judge(&self, now: FrameTime) -> Judged {
        let interval = self.last.and_then(|last| now.micros_since(last));
        let period = if self.cyclic { self.period() } else { None };
        let missed = matches!((interval, period), (Some(us), Some(p)) if misses(us, p));
        Judged {
            interval,
            period,
            missed,
        }
    }

    /// The frame at `now`, line `line`, as `judged`, into the statistics;
    /// a gap of missed cycles is the event to tell.
    #[inline(always)]
    fn take(&mut self, now: FrameTime, line: u64, judged: Judged) -> Option<SyncMissed> {
        let last = self.last.replace(now);
        let start_line = std::mem::replace(&mut self.last_line, line);
        let us = judged.interval?;
        if self.max_gap.is_none() || us > self.max_gap_us {
            self.max_gap = last.map(|last| now.since(last));
            self.max_gap_us = us;
        }
        if !self.cyclic {
            return None;
        }
        self.median.push(us);
        let period = judged.period?;
        if judged.missed {
            self.missed += 1;
            return Some(SyncMissed {
                start: At {
                    time: last.map(FrameTime::timestamp),
                    line: start_line,
                },
                end: Some(At {
                    time: Some(now.timestamp()),
                    line,
                }),
                period: Span::from_micros(period.round() as i64),
                missed: ((us / period).round() as u64).saturating_sub(1).max(1),
            });
        }
        self.deviation += (us - period).abs();
        self.regular += 1;
        None
    }

    /// The period an interval is judged against, once there is one.
    fn period(&self) -> Option<f64> {
        self.median.current().filter(|p| *p > 0.0)
    }

    /// Silent from the last frame to `end` for more than 1.5 periods.
    fn silent_until(&mut self, end: Timestamp) -> Option<SyncMissed> {
        let last = self.last?.timestamp();
        let period = self.period()?;
        let us = micros(end.since(last));
        misses(us, period).then(|| {
            self.missed += 1;
            SyncMissed {
                start: At {
                    time: Some(last),
                    line: self.last_line,
                },
                end: None,
                period: Span::from_micros(period.round() as i64),
                // The cycles due before the end, the one at it not yet.
                missed: ((us / period).round() as u64).saturating_sub(1).max(1),
            }
        })
    }
}

impl IdReport {
    /// The report of `count` frames on `cob_id`, with the timing `traffic`
    /// followed if it was.
    fn new(cob_id: u32, extended: bool, count: u64, traffic: Option<&IdTraffic>) -> IdReport {
        let (service, node) = cob_id::service(cob_id, extended);
        let mut report = IdReport {
            cob_id,
            extended,
            service,
            node,
            count,
            period: None,
            jitter: None,
            max_gap: None,
            missed: None,
        };
        let Some(t) = traffic else {
            return report;
        };
        // Under LEARN_FROM intervals no period is trusted, and intervals
        // that do not keep to one have none: said as none.
        let period = (t.cyclic && t.median.count >= LEARN_FROM as u64)
            .then(|| t.median.period())
            .flatten();
        report.period = period.map(|p| Span::from_micros(p.round() as i64));
        // Deviation from a period the intervals did not keep to is none.
        report.jitter = (t.regular > 0 && period.is_some())
            .then(|| Span::from_micros((t.deviation / t.regular as f64).round() as i64));
        report.max_gap = t.max_gap;
        report.missed = Some(t.missed);
        report
    }
}

/// Whether an interval of `us` microseconds missed a cycle of `period`.
fn misses(us: f64, period: f64) -> bool {
    us > MISSED_FACTOR * period
}

/// A span in microseconds, for the statistics (exact to well under a
/// microsecond for any gap a trace can hold).
fn micros(s: Span) -> f64 {
    // Through i64 when it fits (gaps under 9 s): converting an i128 to
    // f64 is a library call, a tenth of `--timing`'s instructions.
    let attos = s.attos();
    match i64::try_from(attos) {
        Ok(a) => a as f64 / 1e12,
        Err(_) => attos as f64 / 1e12,
    }
}

impl Load {
    #[inline(always)]
    fn frame(&mut self, time: Option<FrameTime>, bits: u64) {
        self.bits += bits;
        let Some(t) = time else {
            return;
        };
        // Ticks after ticks store their two fields: a whole `FrameTime`
        // stored was copied through the stack, each frame waiting on the
        // stores before it (perf put a fifth of the consumer's samples on
        // that copy with `--timing`, the bench's segmented firmware trace).
        match (&mut self.last, t) {
            (Some(FrameTime::Ticks(last)), FrameTime::Ticks(now)) => *last = now,
            (last, t) => *last = Some(t),
        }
        match &mut self.window {
            Some(w) if w.holds(t) => w.bits += bits,
            _ => self.new_window(t, bits),
        }
    }

    /// A frame at `t` outside the current window (or the first) starts
    /// the next; the one it ends may be the peak.
    #[inline(never)]
    fn new_window(&mut self, t: FrameTime, bits: u64) {
        self.first.get_or_insert(t);
        if let Some(w) = &self.window {
            self.peak_bits = self.peak_bits.max(w.bits);
        }
        let end = match t {
            FrameTime::Ticks(start) => 10u64
                .checked_pow(u32::from(start.digits))
                .and_then(|second| second.checked_mul(WINDOW_SECS))
                .and_then(|window| start.value.checked_add(window)),
            FrameTime::Stamp(_) => None,
        };
        self.window = Some(Window {
            start: t,
            end,
            bits,
        });
    }

    fn report(&self, bit_rate: u32) -> Option<LoadReport> {
        let rate = f64::from(bit_rate);
        let span = match (self.first, self.last) {
            (Some(a), Some(b)) => b.since(a).as_f64(),
            _ => 0.0,
        };
        let peak = self.peak_bits.max(self.window.map_or(0, |w| w.bits));
        // A span under a window is measured as one window.
        let secs = span.max(WINDOW_SECS as f64);
        Some(LoadReport {
            bit_rate,
            bits: self.bits,
            mean_percent: 100.0 * self.bits as f64 / (rate * secs),
            peak_percent: 100.0 * peak as f64 / (rate * WINDOW_SECS as f64),
        })
    }
}

impl Window {
    /// Whether a frame at `t` is in the window: not before its start, and
    /// less than [`WINDOW_SECS`] after it.
    #[inline(always)]
    fn holds(&self, t: FrameTime) -> bool {
        // Each field taken where it lies: a tuple of the three copied both
        // times into it, 5 instructions a frame more (callgrind, `--timing`,
        // the bench's segmented firmware trace).
        if let FrameTime::Ticks(now) = t
            && let FrameTime::Ticks(start) = &self.start
            && let Some(end) = self.end
            && now.digits == start.digits
        {
            return start.value <= now.value && now.value < end;
        }
        let span = t.since(self.start);
        !span.is_negative() && span.attos() < i128::from(WINDOW_SECS) * 1_000_000_000_000_000_000
    }
}

/// The bits a frame puts on the wire at the nominal bit rate: its fields
/// (ISO 11898-1) and the most stuff bits they can need, one per four bits
/// of the stuffed part after the first (start of frame to CRC). Real
/// frames need fewer, so load is an upper bound, within about 10% of the
/// truth for typical data. CAN FD frames are counted at the nominal rate
/// too (the trace does not say the data phase's): an upper bound again.
pub(crate) fn bits(extended: bool, kind: FrameKind, len: u8) -> u64 {
    // Classic data frames, nearly every frame, from a table: the fields
    // summed for each cost `--timing` about 25 instructions a frame
    // (callgrind, the bench's commissioning trace).
    if kind == FrameKind::Data {
        let table = if extended {
            &EXTENDED_DATA_BITS
        } else {
            &STANDARD_DATA_BITS
        };
        return u64::from(table[usize::from(len.min(8))]);
    }
    wire_bits(extended, kind, len)
}

/// [`bits`] of classic data frames of 0 to 8 bytes, by length.
const STANDARD_DATA_BITS: [u16; 9] = data_bits(false);
const EXTENDED_DATA_BITS: [u16; 9] = data_bits(true);

const fn data_bits(extended: bool) -> [u16; 9] {
    let mut table = [0u16; 9];
    let mut len = 0;
    while len < table.len() {
        table[len] = wire_bits(extended, FrameKind::Data, len as u8) as u16;
        len += 1;
    }
    table
}

/// [`bits`], field by field.
const fn wire_bits(extended: bool, kind: FrameKind, len: u8) -> u64 {
    let data = match kind {
        FrameKind::Remote | FrameKind::Error => 0,
        FrameKind::Data => 8 * (if len < 8 { len } else { 8 }) as u64,
        FrameKind::Fd => 8 * (if len < 64 { len } else { 64 }) as u64,
    };
    if matches!(kind, FrameKind::Error) {
        // An error flag (6 bits, up to 12 with the others' echo) and the
        // error delimiter (8), then intermission (3).
        return 23;
    }
    // Arbitration and control: SOF, id, RTR or SRR/IDE/RTR, IDE/r0, DLC.
    let head = if extended { 39 } else { 19 };
    let crc = match kind {
        FrameKind::Fd if len > 16 => 21 + 5,
        FrameKind::Fd => 17 + 4,
        _ => 15,
    };
    let stuffed = head + data + crc;
    // CRC delimiter, ACK slot and delimiter, end of frame, intermission.
    let tail = 1 + 2 + 7 + 3;
    stuffed + (stuffed - 1) / 4 + tail
}

/// Intervals kept for the median: when full, every other is dropped and
/// from then on only every other interval is kept (then every fourth, ...),
/// so the sample spreads evenly over the whole input in bounded memory.
const SAMPLE: usize = 256;

/// The median of a stream of intervals, from an evenly thinned sample of
/// them: exact for a steady period (every kept value is the period), and
/// robust to the gaps and bursts a real bus has. The period a new interval
/// is judged against is the median of the first [`LEARN_FROM`], then of
/// the sample each time it is thinned (sorting 256 values once per 128 or
/// more intervals).
#[derive(Default)]
struct Median {
    count: u64,
    sample: Vec<f64>,
    /// Keep one interval in this many; `skip` more to pass over first.
    stride: u64,
    skip: u64,
    current: Option<f64>,
}

impl Median {
    #[inline]
    fn push(&mut self, x: f64) {
        self.count += 1;
        if self.skip > 0 {
            self.skip -= 1;
            return;
        }
        self.stride = self.stride.max(1);
        self.skip = self.stride - 1;
        self.sample.push(x);
        if self.sample.len() == LEARN_FROM && self.current.is_none() {
            self.current = steady_median(&self.sample);
        }
        if self.sample.len() >= SAMPLE {
            let mut i = 0;
            self.sample.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.stride *= 2;
            self.skip = self.stride - 1;
            self.current = steady_median(&self.sample);
        }
    }

    /// The period new intervals are judged against, once learnt from
    /// intervals steady enough to have one.
    fn current(&self) -> Option<f64> {
        self.current
    }

    /// The median of the sample.
    #[cfg(test)]
    fn value(&self) -> f64 {
        median(&mut self.sample.clone())
    }

    /// The period, if the sample shows one ([`steady_median`]).
    fn period(&self) -> Option<f64> {
        steady_median(&self.sample)
    }
}

/// The median of `sample` if the intervals keep to it: at least three in
/// four within a quarter of it. A producer with a cycle does (a late frame
/// and a missed cycle are the exceptions); ids sent at random, or by a
/// node that sends on change, do not, and have no period to miss.
fn steady_median(sample: &[f64]) -> Option<f64> {
    let m = median(&mut sample.to_vec());
    let near = sample.iter().filter(|x| (**x - m).abs() <= m / 4.0).count();
    (m > 0.0 && 4 * near >= 3 * sample.len()).then_some(m)
}

/// The median of `values` (reordered); zero for none.
fn median(values: &mut [f64]) -> f64 {
    values.sort_unstable_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => values[n / 2],
        _ => (values[n / 2 - 1] + values[n / 2]) / 2.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::FrameKey;

    /// Traffic with the counts the classifier keeps beside it.
    pub(super) struct Counted {
        pub(super) t: Traffic,
        pub(super) ids: IdCounts,
    }

    impl Counted {
        pub(super) fn new(every_frame: bool) -> Self {
            Counted {
                t: Traffic::new(every_frame),
                ids: IdCounts::new(),
            }
        }

        pub(super) fn frame(
            &mut self,
            channel: &[u8],
            id: u32,
            extended: bool,
            kind: FrameKind,
            len: u8,
            at: At,
        ) -> Option<SyncMissed> {
            self.ids.count(FrameKey::new(channel, id, extended));
            self.t.frame(channel, id, extended, kind, len, at)
        }

        pub(super) fn error_frame(&mut self, channel: &[u8], time: Option<Timestamp>) {
            self.ids.error_frame(channel);
            self.t.error_frame(channel, time);
        }

        pub(super) fn report(self, bit_rate: Option<u32>) -> Vec<ChannelReport> {
            self.t.into_report(&self.ids, bit_rate)
        }
    }
    use proptest::prelude::*;

    fn at(ms: u64, line: u64) -> At {
        At::ms(ms, line)
    }

    #[test]
    fn frame_bits_by_iso_11898() {
        // 8 data bytes, standard id: 19 + 64 + 15 = 98 stuffed bits, at
        // most 24 stuff bits, 13 after: 135 (the usual worst case).
        assert_eq!(bits(false, FrameKind::Data, 8), 135);
        // Empty standard frame: 34 stuffed, 8 stuff, 13: 55.
        assert_eq!(bits(false, FrameKind::Data, 0), 55);
        // Extended with 8 bytes: 39 + 64 + 15 = 118, 29 stuff, 13: 160.
        assert_eq!(bits(true, FrameKind::Data, 8), 160);
        assert_eq!(bits(false, FrameKind::Remote, 8), 55, "no data bits");
        assert_eq!(bits(false, FrameKind::Data, 200), 135, "at most 8 bytes");
        assert_eq!(bits(false, FrameKind::Error, 8), 23);
        assert!(bits(false, FrameKind::Fd, 64) > bits(false, FrameKind::Fd, 16));
    }

    #[test]
    fn the_median_of_few_values_is_exact() {
        let mut m = Median::default();
        assert_eq!(m.value(), 0.0);
        for (x, want) in [(5.0, 5.0), (1.0, 3.0), (9.0, 5.0), (3.0, 4.0), (7.0, 5.0)] {
            m.push(x);
            assert_eq!(m.value(), want);
        }
        assert_eq!(m.current(), None, "judged by nothing before 8 intervals");
    }

    #[test]
    fn intervals_at_random_have_no_period() {
        let mut m = Median::default();
        // A spread of intervals from 1 to 64 ms (a pseudo-random walk).
        let mut x: u64 = 7;
        for _ in 0..1000 {
            x = x * 1_103_515_245 % 2_147_483_648 + 12_345;
            m.push(1000.0 + (x % 63_000) as f64);
        }
        assert_eq!(m.current(), None);
        assert_eq!(m.period(), None);
        // A node steady for a while, then at random: no period, no jitter.
        let mut t = Counted::new(true);
        let mut ms = 0;
        let mut x: u64 = 7;
        for line in 0..300 {
            ms += if line < 20 {
                100
            } else {
                x = x * 1_103_515_245 % 2_147_483_648 + 12_345;
                1 + x % 5000
            };
            t.frame(
                b"can0",
                0x70F,
                false,
                FrameKind::Data,
                1,
                At::ms(ms, line + 1),
            );
        }
        let r = t.report(None);
        assert_eq!((r[0].ids[0].period, r[0].ids[0].jitter), (None, None));
        // One late frame in eight still has one.
        let mut m = Median::default();
        for i in 0..64 {
            m.push(if i % 8 == 7 { 25.0 } else { 10.0 });
        }
        assert_eq!(m.period(), Some(10.0));
    }

    #[test]
    fn the_sample_is_thinned_evenly_and_stays_bounded() {
        let mut m = Median::default();
        // A period that changes halfway: the median sees both halves.
        for i in 0..100_000u32 {
            m.push(if i < 60_000 { 100.0 } else { 200.0 });
            assert!(m.sample.len() < SAMPLE);
        }
        assert_eq!(m.value(), 100.0);
        // 60% of the intervals at one period, 40% at another: no steady one.
        assert_eq!(m.period(), None);
        assert!(m.sample.contains(&200.0), "the later half is sampled");
    }

    proptest! {
        #[test]
        fn the_median_finds_a_period_among_jitter_and_gaps(
            period in 1_000u32..2_000_000,
            jitter in proptest::collection::vec(-50i32..50, 50..400),
            gaps in proptest::collection::vec(0usize..400, 0..5),
        ) {
            let mut m = Median::default();
            for (i, j) in jitter.iter().enumerate() {
                let mut x = f64::from(period) + f64::from(*j);
                if gaps.contains(&i) {
                    x *= 3.0;
                }
                m.push(x);
            }
            let err = (m.value() - f64::from(period)).abs();
            prop_assert!(err <= 50.0, "{} for {}", m.value(), period);
            if jitter.iter().all(|j| *j == 0) {
                prop_assert_eq!(m.value(), f64::from(period), "a steady period is exact");
            }
        }
    }

    #[test]
    fn sync_gaps_are_told_once_per_gap() {
        let mut t = Counted::new(false);
        let sync = |t: &mut Counted, ms, line| {
            t.frame(b"can0", SYNC_ID, false, FrameKind::Data, 0, at(ms, line))
        };
        let mut told = Vec::new();
        let mut ms = 0;
        for line in 1..=20 {
            told.extend(sync(&mut t, ms, line));
            ms += 10;
        }
        assert!(told.is_empty(), "a steady 10 ms SYNC: {told:?}");
        // Three cycles skipped: one event, three missed.
        ms += 30;
        let gap = sync(&mut t, ms, 21).expect("a gap of 40 ms");
        assert_eq!(gap.missed, 3);
        assert_eq!(gap.period, Span::from_micros(10_000));
        assert_eq!(gap.start, at(ms - 40, 20));
        assert_eq!(gap.end, Some(at(ms, 21)));
        // 14 ms is under 1.5 periods: late, not missed.
        ms += 14;
        assert_eq!(sync(&mut t, ms, 22), None);
        // Silent to the end of the input.
        let end = Timestamp::from_parts((ms + 100) / 1000, (ms + 100) % 1000, 3);
        let at_end = t.t.finish(Some(end));
        assert_eq!(at_end.len(), 1);
        assert_eq!(at_end[0].1.end, None);
        assert_eq!(at_end[0].1.missed, 9);
        let report = t.report(Some(500_000));
        assert_eq!(report[0].frames, 22, "counted, timed or not");
        let sync = &report[0].ids[0];
        assert_eq!(
            (sync.service, sync.count, sync.missed),
            ("sync", 22, Some(2))
        );
        assert_eq!(sync.max_gap, Some(Span::from_millis(40)));
        assert!(report[0].load.is_none(), "no bits counted, no load");
    }

    #[test]
    fn without_timing_frames_are_counted_not_timed() {
        let mut t = Counted::new(false);
        assert!(!t.t.wants());
        assert!(Traffic::new(true).wants());
        t.error_frame(b"can0", None);
        // The classifier counts a frame the traffic is not given.
        t.ids.count(FrameKey::new(b"can0", 0x181, false));
        let r = t.report(Some(500_000));
        assert_eq!((r[0].frames, r[0].error_frames, r[0].timed), (2, 1, false));
        let id = &r[0].ids[0];
        assert_eq!(
            (id.cob_id, id.count, id.missed, id.max_gap),
            (0x181, 1, None, None)
        );
        assert!(r[0].load.is_none(), "no load without timing");
    }

    #[test]
    fn times_at_the_end_of_the_clock_are_no_overflow() {
        let mut t = Counted::new(true);
        for (i, atto) in [0u64, 5, 7].iter().enumerate() {
            let at = At {
                time: Timestamp::from_raw(u64::MAX, *atto, 18),
                line: i as u64 + 1,
            };
            t.frame(b"can0", 0x181, false, FrameKind::Data, 8, at);
        }
        let r = t.report(Some(1_000_000));
        assert_eq!(r[0].frames, 3);
        assert_eq!(r[0].load.map(|l| l.bits), Some(3 * 135));
    }

    #[test]
    fn data_frame_bits_come_from_the_table_as_the_fields_give_them() {
        for extended in [false, true] {
            for len in 0..=12u8 {
                assert_eq!(
                    bits(extended, FrameKind::Data, len),
                    wire_bits(extended, FrameKind::Data, len),
                    "{extended} {len}"
                );
            }
        }
    }

    /// A window holds the frames less than a second after its first, in
    /// ticks and as timestamps alike: the frame a second after starts the
    /// next, and one that goes back in time starts one too.
    #[test]
    fn a_window_is_one_second_from_its_first_frame_exactly() {
        let ticks = |micros: u64| FrameTime::Ticks(Ticks::new(micros, 6).expect("6 digits"));
        // Seven digits do not fit the 6-digit ticks of the others: the
        // window compares spans then.
        let stamp = |micros: u64| {
            FrameTime::Stamp(Timestamp::from_parts(
                micros / 1_000_000,
                micros % 1_000_000 * 10,
                7,
            ))
        };
        for time in [ticks as fn(u64) -> FrameTime, stamp] {
            let mut load = Load::default();
            let start = 1_700_000_000_000_000;
            load.frame(Some(time(start)), 10);
            load.frame(Some(time(start + 999_999)), 20);
            assert_eq!(load.window.map(|w| w.bits), Some(30));
            load.frame(Some(time(start + 1_000_000)), 40);
            assert_eq!(
                (load.peak_bits, load.window.map(|w| w.bits)),
                (30, Some(40))
            );
            load.frame(Some(time(start + 999_999)), 5);
            assert_eq!((load.peak_bits, load.window.map(|w| w.bits)), (40, Some(5)));
            assert_eq!(load.bits, 75);
        }
    }

    proptest! {
        /// Microsecond ticks give their count as the microseconds, as the
        /// attoseconds divided down give them, within [`EXACT_MICROS`].
        #[test]
        fn microsecond_ticks_are_their_microseconds(then in 0u64..1 << 60, n in 0u64..EXACT_MICROS) {
            let at = |v: u64| FrameTime::Ticks(Ticks::new(v, 6).expect("6 digits"));
            let us = at(then + n).micros_since(at(then));
            prop_assert_eq!(us, Some(micros(Ticks::new(0, 6).expect("6 digits").span(n))));
            prop_assert_eq!(us, Some(n as f64));
            prop_assert_eq!(at(then).micros_since(at(then + n + 1)), None);
        }
    }

    #[test]
    fn load_is_bits_over_the_bit_rate_per_window() {
        let mut t = Counted::new(true);
        // 100 frames of 8 bytes in each of two seconds, 200 in a third.
        let mut line = 0;
        for (second, n) in [(0, 100), (1, 100), (2, 200)] {
            for i in 0..n {
                line += 1;
                let ms = second * 1000 + i * 1000 / n;
                t.frame(b"can0", 0x181, false, FrameKind::Data, 8, at(ms, line));
            }
        }
        t.error_frame(b"can0", None);
        let report = t.report(Some(125_000));
        let c = &report[0];
        assert_eq!((c.frames, c.error_frames), (401, 1));
        let load = c.load.expect("a bit rate");
        assert_eq!(load.bits, 400 * 135 + 23);
        // The busiest second: 200 x 135 bits of 125 000.
        assert!((load.peak_percent - 21.6).abs() < 0.01, "{load:?}");
        assert!(load.mean_percent < load.peak_percent);
        let id = &c.ids[0];
        assert_eq!(
            (id.cob_id, id.service, id.node, id.count),
            (0x181, "tpdo1", Some(1), 400)
        );
    }

    #[test]
    fn channels_and_extended_ids_are_bounded() {
        let mut t = Counted::new(true);
        for i in 0..(MAX_CHANNELS as u32 + 3) {
            let name = format!("can{i}");
            t.frame(name.as_bytes(), 1, false, FrameKind::Data, 0, at(0, 1));
        }
        assert_eq!(t.ids.others(), 3);
        assert_eq!(t.report(None).len(), MAX_CHANNELS);
        let mut t = Counted::new(true);
        for id in 0..(MAX_EXTENDED as u32 + 2) {
            t.frame(b"can0", id, true, FrameKind::Data, 0, at(0, 1));
        }
        let r = t.report(None);
        assert_eq!(r[0].ids.len(), MAX_EXTENDED);
        assert_eq!(r[0].other_ids, 2);
        assert_eq!(r[0].frames, MAX_EXTENDED as u64 + 2);
        // Every standard id on nine channels: 18 432 ids, 16 384 followed.
        let mut t = Counted::new(true);
        for c in 0..9 {
            let name = format!("can{c}");
            for id in 0..2048 {
                t.frame(name.as_bytes(), id, false, FrameKind::Data, 0, at(0, 1));
            }
        }
        let r = t.report(None);
        let ids = || r.iter().flat_map(|c| &c.ids);
        let timed = ids().filter(|i| i.missed.is_some()).count();
        assert_eq!((ids().count(), timed), (9 * 2048, MAX_IDS));
        assert!(r.iter().all(|c| c.frames == 2048), "every frame counted");
    }
}

#[cfg(test)]
mod event_driven {
    use super::tests::Counted;
    use super::*;

    #[test]
    fn event_driven_services_have_no_period_and_miss_nothing() {
        let mut t = Counted::new(true);
        for (i, ms) in [0u64, 10, 20, 30, 40, 50, 60, 70, 80, 90, 500]
            .iter()
            .enumerate()
        {
            let at = At::ms(*ms, i as u64 + 1);
            t.frame(b"can0", 0x085, false, FrameKind::Data, 8, at);
            t.frame(b"can0", 0x185, false, FrameKind::Data, 8, at);
        }
        let r = t.report(None);
        let emcy = &r[0].ids[0];
        assert_eq!(
            (emcy.service, emcy.period, emcy.missed),
            ("emcy", None, Some(0))
        );
        assert_eq!(emcy.max_gap, Some(Span::from_millis(410)));
        let pdo = &r[0].ids[1];
        assert_eq!((pdo.service, pdo.missed), ("tpdo1", Some(1)));
        assert_eq!(pdo.period, Some(Span::from_micros(10_000)));
    }
}
