//! Heartbeat and node guarding outages of one node.
//!
//! A node is supervised by its heartbeats or, once it answered a guard
//! request, by its guarding replies (life guarding); both are signs of
//! life to the same monitor. The timeout comes from, in this order:
//! `--heartbeat-timeout`; for heartbeats the consumer heartbeat time
//! (0x1016) some node was given for this one, else the node's producer
//! heartbeat time (0x1017) with a margin; for guarding the node's life
//! time, guard time (0x100C) times life time factor (0x100D); else what the
//! trace shows: [`LEARNT_FACTOR`] times the node's typical interval once
//! [`LEARN_FROM`] intervals are known. A gap over the timeout is an outage
//! from the deadline (last sign of life + timeout) to the next sign of life
//! (a heartbeat, guarding reply or boot-up); monitoring begins with the
//! first one.

use super::interval::At;
use crate::trace::{Span, Step, Timestamp};

/// Intervals seen before a timeout is learnt.
pub const LEARN_FROM: usize = 8;
/// A learnt timeout is this many typical intervals: jitter of a busy bus
/// stays well inside it, a node that misses two heartbeats does not.
pub const LEARNT_FACTOR: i128 = 3;
/// The producer time with a margin (x 3/2): a consumer timeout at the
/// producer time itself would flag every late heartbeat.
pub const PRODUCER_MARGIN: (i128, i128) = (3, 2);
/// Outages a node keeps for its report; more are counted only (a flapping
/// node could have millions).
pub const MAX_OUTAGES: usize = 256;
/// How far, in per mille, the measured period may be from the configured
/// one (0x1017, or the guard time) before the report says it drifts. A
/// node's clock is good to a per mille or two, and the measured period is
/// the median of its first intervals, so bus queueing of single frames
/// does not move it; a node whose timer restarts after each send (late by
/// its own processing time every period) shows up, as 1.44 s for 1.4 s
/// (29 per mille) does, while 1.41 s for 1.4 s (7 per mille) is usual.
pub const DRIFT_PER_MILLE: i128 = 20;

/// How a node's signs of life come.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Supervision {
    /// The node sends heartbeats.
    #[default]
    Heartbeat,
    /// The master guards it: remote requests answered by guarding replies.
    Guarding,
}

impl Supervision {
    /// The stable name in JSON (`via`).
    pub fn slug(self) -> &'static str {
        match self {
            Supervision::Heartbeat => "heartbeat",
            Supervision::Guarding => "guarding",
        }
    }

    /// What a sentence calls it (`node guarding lost: ...`).
    pub fn words(self) -> &'static str {
        match self {
            Supervision::Heartbeat => "heartbeat",
            Supervision::Guarding => "node guarding",
        }
    }
}

/// Where a node's timeout came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TimeoutSource {
    /// `--heartbeat-timeout`.
    Option,
    /// A consumer heartbeat time (0x1016) naming the node.
    Consumer,
    /// The node's producer heartbeat time (0x1017), with a margin.
    Producer,
    /// Guard time (0x100C) times life time factor (0x100D): node guarding.
    LifeTime,
    /// Learnt from the trace.
    Learnt,
}

impl TimeoutSource {
    /// The stable name in JSON.
    pub fn slug(self) -> &'static str {
        match self {
            TimeoutSource::Option => "option",
            TimeoutSource::Consumer => "consumer",
            TimeoutSource::Producer => "producer",
            TimeoutSource::LifeTime => "life_time",
            TimeoutSource::Learnt => "learnt",
        }
    }
}

/// A node went silent: its deadline passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lost {
    /// When the deadline passed.
    pub deadline: Timestamp,
    /// The last sign of life before it.
    pub last_seen: At,
}

/// A node that was lost was heard again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Back {
    pub lost: Lost,
    /// From the last sign of life before the outage to this one.
    pub silent: Span,
    /// It came back with a boot-up: it restarted.
    pub restarted: bool,
}

/// One outage: from the deadline to the next sign of life (`None`: silent
/// to the end of the trace).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outage {
    pub start: Timestamp,
    pub end: Option<Timestamp>,
}

impl Outage {
    pub fn duration(&self) -> Option<Span> {
        Some(self.end?.since(self.start))
    }
}

/// The heartbeat side of one node.
#[derive(Clone, Debug, Default)]
pub struct HeartbeatMonitor {
    /// The last sign of life with a time.
    last: Option<At>,
    option: Option<Span>,
    consumer: Option<Span>,
    producer: Option<Span>,
    /// Node guarding's guard time (0x100C) and life time factor (0x100D).
    guard_time: Option<Span>,
    life_time_factor: Option<u8>,
    supervision: Supervision,
    /// Intervals seen so far, up to [`LEARN_FROM`].
    samples: Vec<Span>,
    /// The typical interval (the median of the first [`LEARN_FROM`]).
    period: Option<Span>,
    /// The outage going on.
    lost: Option<Lost>,
    outages: Vec<Outage>,
    lost_count: u64,
    beats: u64,
    /// [`HeartbeatMonitor::timeout`] and the deadline it gives, kept up to
    /// date: asked for on every heartbeat.
    timeout: Option<(Span, TimeoutSource)>,
    deadline: Option<Timestamp>,
    /// The timeout split for adding, kept with it.
    step: Option<Step>,
}

impl HeartbeatMonitor {
    /// A node monitored with `--heartbeat-timeout` (`None`: not given).
    pub fn new(option: Option<Span>) -> Self {
        let mut m = HeartbeatMonitor {
            option,
            ..Self::default()
        };
        m.refresh();
        m
    }

    /// The timeout in force and where it came from.
    pub fn timeout(&self) -> Option<(Span, TimeoutSource)> {
        self.timeout
    }

    /// Recomputes the cached timeout and deadline after what they depend
    /// on changed.
    fn refresh(&mut self) {
        self.timeout = self.compute_timeout();
        self.step = self.timeout.and_then(|(t, _)| t.step());
        self.deadline = match (self.timeout, self.last.and_then(|l| l.time)) {
            (Some((timeout, _)), Some(last)) => last.checked_add_span(timeout),
            _ => None,
        };
    }

    fn compute_timeout(&self) -> Option<(Span, TimeoutSource)> {
        if let Some(t) = self.option {
            return Some((t, TimeoutSource::Option));
        }
        match self.supervision {
            Supervision::Heartbeat => {
                if let Some(t) = self.consumer {
                    return Some((t, TimeoutSource::Consumer));
                }
                if let Some(t) = self
                    .producer
                    .and_then(|p| p.scaled(PRODUCER_MARGIN.0, PRODUCER_MARGIN.1))
                {
                    return Some((t, TimeoutSource::Producer));
                }
            }
            Supervision::Guarding => {
                if let Some(t) = self.life_time() {
                    return Some((t, TimeoutSource::LifeTime));
                }
            }
        }
        let learnt = self.period?.scaled(LEARNT_FACTOR, 1)?;
        Some((learnt, TimeoutSource::Learnt))
    }

    /// The node's typical interval, once learnt.
    pub fn period(&self) -> Option<Span> {
        self.period
    }

    /// How the node's signs of life come.
    pub fn supervision(&self) -> Supervision {
        self.supervision
    }

    /// The node answered a guard request: from now on its guarding replies
    /// are what it is supervised by (its life time, not its heartbeat
    /// times, sets the timeout).
    pub fn guarded(&mut self) {
        if self.supervision != Supervision::Guarding {
            self.supervision = Supervision::Guarding;
            self.relearn();
            self.refresh();
        }
    }

    /// The period the trace configured: the producer heartbeat time
    /// (0x1017) for heartbeats, the guard time (0x100C) for guarding.
    pub fn configured_period(&self) -> Option<Span> {
        match self.supervision {
            Supervision::Heartbeat => self.producer,
            Supervision::Guarding => self.guard_time,
        }
    }

    /// The life time factor (0x100D) the trace configured, if any.
    pub fn life_time_factor(&self) -> Option<u8> {
        self.life_time_factor
    }

    /// Guard time times life time factor, when both are known and not 0.
    fn life_time(&self) -> Option<Span> {
        let factor = self.life_time_factor.filter(|&f| f > 0)?;
        self.guard_time?.scaled(i128::from(factor), 1)
    }

    /// Whether the measured period is more than [`DRIFT_PER_MILLE`] from
    /// the configured one (`false` when either is unknown).
    pub fn drifts(&self) -> bool {
        let (Some(measured), Some(configured)) = (self.period, self.configured_period()) else {
            return false;
        };
        let (m, c) = (measured.attos(), configured.attos());
        c > 0 && (m - c).abs() * 1000 > c * DRIFT_PER_MILLE
    }

    /// Node guarding's guard time (ms); 0: not guarded.
    pub fn set_guard_time_ms(&mut self, ms: u16) {
        let guard_time = (ms > 0).then(|| Span::from_millis(u64::from(ms)));
        if guard_time != self.guard_time && self.supervision == Supervision::Guarding {
            self.relearn();
        }
        self.guard_time = guard_time;
        self.refresh();
    }

    /// Node guarding's life time factor; 0: no life guarding.
    pub fn set_life_time_factor(&mut self, factor: u8) {
        self.life_time_factor = Some(factor);
        self.refresh();
    }

    /// When the node is lost unless heard from; `None` while lost, before
    /// its first heartbeat, or without a timeout.
    pub fn deadline(&self) -> Option<Timestamp> {
        if self.lost.is_some() {
            return None;
        }
        self.deadline
    }

    /// Whether the node ever sent a heartbeat or boot-up.
    pub fn monitored(&self) -> bool {
        self.beats > 0
    }

    /// A consumer heartbeat time (ms) for this node; 0 switches it off.
    pub fn set_consumer_ms(&mut self, ms: u16) {
        self.consumer = (ms > 0).then(|| Span::from_millis(u64::from(ms)));
        self.refresh();
    }

    /// The node's producer heartbeat time (ms); 0: it sends none.
    pub fn set_producer_ms(&mut self, ms: u16) {
        let producer = (ms > 0).then(|| Span::from_millis(u64::from(ms)));
        if producer != self.producer && self.supervision == Supervision::Heartbeat {
            self.relearn();
        }
        self.producer = producer;
        self.refresh();
    }

    /// The period configured changed: the typical interval is measured
    /// again from the next intervals, so it is compared with the
    /// configuration it was sent under, not the one before.
    fn relearn(&mut self) {
        self.period = None;
        self.samples.clear();
    }

    /// The trace's clock reached `now`: the node is lost if its deadline
    /// passed.
    pub fn check(&mut self, now: Timestamp) -> Option<Lost> {
        let deadline = self.deadline()?;
        if now <= deadline {
            return None;
        }
        let lost = Lost {
            deadline,
            last_seen: self.last?,
        };
        self.lost = Some(lost);
        self.lost_count += 1;
        if self.outages.len() < MAX_OUTAGES {
            self.outages.push(Outage {
                start: deadline,
                end: None,
            });
        }
        Some(lost)
    }

    /// A heartbeat (`boot`: a boot-up) at `at`. Returns the outage it ends
    /// (found now if no frame of the trace passed the deadline before).
    pub fn seen(&mut self, at: At) -> (Option<Lost>, Option<Back>) {
        self.seen_as(at, false)
    }

    /// A heartbeat at `at` before the deadline, once the period is known,
    /// that moves the deadline later: the common case, with nothing to
    /// report (`false`: not that case, nothing changed; use
    /// [`HeartbeatMonitor::seen`]).
    #[inline]
    pub fn steady(&mut self, at: At) -> bool {
        let (Some(now), Some(deadline), Some(step)) = (at.time, self.deadline, self.step) else {
            return false;
        };
        if self.lost.is_some() || self.period.is_none() || now > deadline {
            return false;
        }
        // A deadline that moves earlier (the clock went back) must be told
        // to the consumer's schedule, which only lets them move later.
        let Some(next) = now.checked_add_step(step).filter(|&next| next >= deadline) else {
            return false;
        };
        self.beats += 1;
        self.last = Some(at);
        self.deadline = Some(next);
        true
    }

    /// Whether heartbeats folded by the reader would each have been
    /// [`HeartbeatMonitor::steady`], one after the other: the first (at
    /// `first`) by the deadline, no gap between two over the timeout
    /// (`max_gap`, attoseconds; times of one layout carry the same digits,
    /// so comparing values is comparing times). And whether the deadline
    /// after the last (at `last`) is not passed at `latest`, the time of
    /// the last heartbeat folded with them (of any node): then no frame
    /// among them found the node lost either. `Some(that deadline)` when
    /// so.
    pub fn takes_fold(
        &self,
        first: Timestamp,
        max_gap: i128,
        last: Timestamp,
        latest: Timestamp,
    ) -> Option<Timestamp> {
        let (Some(deadline), Some(step), Some((timeout, _))) =
            (self.deadline, self.step, self.timeout)
        else {
            return None;
        };
        if self.lost.is_some() || self.period.is_none() || first > deadline {
            return None;
        }
        if max_gap > timeout.attos() {
            return None;
        }
        // Not earlier than the deadline now: see `steady`.
        last.checked_add_step(step)
            .filter(|&next| latest <= next && next >= deadline)
    }

    /// Takes `count` heartbeats [`HeartbeatMonitor::takes_fold`] accepted,
    /// the last at `last`, with the deadline it gave: as many
    /// [`HeartbeatMonitor::steady`] calls.
    pub fn fold(&mut self, count: u64, last: At, deadline: Timestamp) {
        self.beats += count;
        self.last = Some(last);
        self.deadline = Some(deadline);
    }

    /// A boot-up at `at`: a sign of life that restarts the node.
    pub fn boot(&mut self, at: At) -> (Option<Lost>, Option<Back>) {
        self.seen_as(at, true)
    }

    fn seen_as(&mut self, at: At, boot: bool) -> (Option<Lost>, Option<Back>) {
        self.beats += 1;
        let Some(now) = at.time else {
            return (None, None);
        };
        let newly = self.check(now);
        let back = self.lost.take().map(|lost| {
            if let Some(o) = self.outages.last_mut()
                && o.start == lost.deadline
            {
                o.end = Some(now);
            }
            Back {
                lost,
                silent: lost.last_seen.time.map_or(Span::ZERO, |t| now.since(t)),
                restarted: boot,
            }
        });
        if back.is_none()
            && !boot
            && self.period.is_none()
            && let Some(last) = self.last.and_then(|l| l.time)
        {
            self.learn(now.since(last));
        }
        self.last = Some(at);
        self.deadline = self.timeout.and_then(|(t, _)| now.checked_add_span(t));
        (newly, back)
    }

    fn learn(&mut self, interval: Span) {
        if self.period.is_some() || interval.is_negative() || interval == Span::ZERO {
            return;
        }
        self.samples.push(interval);
        if self.samples.len() >= LEARN_FROM {
            self.samples.sort();
            self.period = self.samples.get(LEARN_FROM / 2).copied();
            self.samples = Vec::new();
            self.refresh();
        }
    }

    /// The outages kept (the first [`MAX_OUTAGES`]).
    pub fn outages(&self) -> &[Outage] {
        &self.outages
    }

    /// Outages in all, the one going on included.
    pub fn lost_count(&self) -> u64 {
        self.lost_count
    }

    /// The last sign of life with a time.
    pub fn last_seen(&self) -> Option<At> {
        self.last
    }

    /// Silent past its deadline now.
    pub fn is_lost(&self) -> bool {
        self.lost.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Timestamp {
        Timestamp::from_parts(ms / 1000, ms % 1000, 3)
    }

    fn at(ms: u64) -> At {
        At {
            time: Some(t(ms)),
            line: ms,
        }
    }

    fn beats(m: &mut HeartbeatMonitor, from: u64, to: u64, every: u64) {
        let mut ms = from;
        while ms <= to {
            assert_eq!(m.seen(at(ms)), (None, None), "at {ms}");
            ms += every;
        }
    }

    #[test]
    fn no_timeout_no_deadline() {
        let mut m = HeartbeatMonitor::new(None);
        m.seen(at(0));
        m.seen(at(100));
        assert_eq!(m.timeout(), None);
        assert_eq!(m.deadline(), None);
        assert_eq!(m.check(t(100_000)), None);
        assert!(m.monitored());
    }

    #[test]
    fn learnt_from_the_typical_interval() {
        let mut m = HeartbeatMonitor::new(None);
        beats(&mut m, 0, 700, 100);
        assert_eq!(m.timeout(), None, "7 intervals are not enough");
        m.seen(at(800));
        assert_eq!(m.period(), Some(Span::from_millis(100)));
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(300), TimeoutSource::Learnt))
        );
        assert_eq!(m.deadline(), Some(t(1100)));
    }

    #[test]
    fn steady_and_folded_beats_never_move_the_deadline_earlier() {
        let mut m = HeartbeatMonitor::new(None);
        beats(&mut m, 1000, 1800, 100);
        assert_eq!(m.deadline(), Some(t(2100)));
        assert!(m.steady(at(1900)), "the common case");
        assert_eq!(m.deadline(), Some(t(2200)));
        // The clock goes back: the deadline would move earlier, which the
        // consumer's schedule must be told (the general path).
        assert!(!m.steady(at(500)), "clock back");
        assert_eq!(m.deadline(), Some(t(2200)), "nothing changed");
        let max_gap = Span::from_millis(100).attos();
        assert_eq!(
            m.takes_fold(t(500), max_gap, t(600), t(600)),
            None,
            "a fold back in time"
        );
        assert_eq!(
            m.takes_fold(t(2000), max_gap, t(2100), t(2150)),
            Some(t(2400)),
            "a fold later on"
        );
        assert_eq!(
            m.takes_fold(t(2000), 4 * max_gap, t(2400), t(2400)),
            None,
            "a gap over the timeout"
        );
        assert_eq!(
            m.takes_fold(t(2000), max_gap, t(2100), t(2500)),
            None,
            "its deadline passed at a later frame"
        );
        m.fold(3, at(2100), t(2400));
        assert_eq!(m.deadline(), Some(t(2400)));
    }

    #[test]
    fn learning_ignores_an_odd_interval() {
        let mut m = HeartbeatMonitor::new(None);
        beats(&mut m, 0, 300, 100);
        m.seen(at(1300)); // one long gap among eight
        beats(&mut m, 1400, 1800, 100);
        assert_eq!(m.period(), Some(Span::from_millis(100)));
    }

    #[test]
    fn timeout_sources_in_order() {
        let mut m = HeartbeatMonitor::new(None);
        beats(&mut m, 0, 800, 100);
        assert_eq!(m.timeout().map(|t| t.1), Some(TimeoutSource::Learnt));
        m.set_producer_ms(200);
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(300), TimeoutSource::Producer))
        );
        m.set_consumer_ms(250);
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(250), TimeoutSource::Consumer))
        );
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(1000)));
        m.set_consumer_ms(250);
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(1000), TimeoutSource::Option))
        );
        // Zero switches a source off.
        let mut m = HeartbeatMonitor::new(None);
        m.set_consumer_ms(250);
        m.set_consumer_ms(0);
        assert_eq!(m.timeout(), None);
    }

    #[test]
    fn outage_from_deadline_to_next_heartbeat() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(250)));
        beats(&mut m, 0, 1000, 100);
        // Another frame of the trace at 1200: still inside.
        assert_eq!(m.check(t(1200)), None);
        assert_eq!(
            m.check(t(1250)),
            None,
            "a gap equal to the timeout is not over it"
        );
        let lost = m.check(t(1300)).expect("lost");
        assert_eq!(lost.deadline, t(1250));
        assert_eq!(lost.last_seen, at(1000));
        assert!(m.is_lost());
        assert_eq!(m.check(t(1400)), None, "lost once");
        let (newly, back) = m.seen(at(2000));
        assert_eq!(newly, None);
        let back = back.expect("back");
        assert_eq!(back.lost, lost);
        assert_eq!(back.silent, Span::from_millis(1000));
        assert!(!back.restarted);
        assert_eq!(
            m.outages(),
            [Outage {
                start: t(1250),
                end: Some(t(2000))
            }]
        );
        assert_eq!(m.outages()[0].duration(), Some(Span::from_millis(750)));
        assert_eq!(m.lost_count(), 1);
        assert!(!m.is_lost());
        assert_eq!(m.deadline(), Some(t(2250)));
    }

    #[test]
    fn gap_found_at_the_next_heartbeat() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(250)));
        beats(&mut m, 0, 500, 100);
        let (newly, back) = m.seen(at(900));
        assert_eq!(
            newly,
            Some(Lost {
                deadline: t(750),
                last_seen: at(500)
            })
        );
        assert_eq!(back.map(|b| b.silent), Some(Span::from_millis(400)));
    }

    #[test]
    fn boot_up_after_an_outage_is_a_restart() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(250)));
        beats(&mut m, 0, 500, 100);
        m.check(t(800));
        let (_, back) = m.boot(at(3000));
        assert!(back.expect("back").restarted);
    }

    #[test]
    fn silent_to_the_end() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(250)));
        beats(&mut m, 0, 500, 100);
        assert!(m.check(t(5000)).is_some());
        assert_eq!(
            m.outages(),
            [Outage {
                start: t(750),
                end: None
            }]
        );
        assert!(m.is_lost());
        assert_eq!(m.outages()[0].duration(), None);
    }

    #[test]
    fn outages_kept_are_bounded_and_all_counted() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(10)));
        let n = MAX_OUTAGES as u64 + 10;
        for i in 0..n {
            m.seen(at(i * 100));
        }
        assert_eq!(m.lost_count(), n - 1);
        assert_eq!(m.outages().len(), MAX_OUTAGES);
    }

    #[test]
    fn frames_without_times_change_nothing() {
        let mut m = HeartbeatMonitor::new(Some(Span::from_millis(10)));
        assert_eq!(
            m.seen(At {
                time: None,
                line: 1
            }),
            (None, None)
        );
        assert!(m.monitored());
        assert_eq!(m.deadline(), None);
    }

    #[test]
    fn a_guarded_node_is_lost_after_its_life_time() {
        let mut m = HeartbeatMonitor::new(None);
        m.set_guard_time_ms(100);
        m.set_life_time_factor(3);
        // Heartbeat times do not apply to a guarded node, nor life time
        // to one that beats.
        m.set_producer_ms(1000);
        assert_eq!(m.timeout().map(|t| t.1), Some(TimeoutSource::Producer));
        m.guarded();
        assert_eq!(m.supervision(), Supervision::Guarding);
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(300), TimeoutSource::LifeTime))
        );
        assert_eq!(m.configured_period(), Some(Span::from_millis(100)));
        assert_eq!(m.life_time_factor(), Some(3));
        m.seen(at(1000));
        assert_eq!(m.check(t(1300)), None, "equal to the life time is not over");
        let lost = m.check(t(1301)).expect("lost after 300 ms");
        assert_eq!(lost.deadline, t(1300));
        let (_, back) = m.seen(at(1500));
        assert_eq!(back.map(|b| b.silent), Some(Span::from_millis(500)));
        // A factor of 0 switches life guarding off: the timeout is learnt.
        m.set_life_time_factor(0);
        assert_eq!(m.timeout(), None);
    }

    #[test]
    fn a_guarded_node_without_a_life_time_learns_its_timeout() {
        let mut m = HeartbeatMonitor::new(None);
        m.guarded();
        beats(&mut m, 0, 800, 100);
        assert_eq!(
            m.timeout(),
            Some((Span::from_millis(300), TimeoutSource::Learnt))
        );
        assert_eq!(m.configured_period(), None);
    }

    #[test]
    fn drift_is_a_measured_period_off_the_configured_one() {
        let beat_every = |period: u64| {
            let mut m = HeartbeatMonitor::new(None);
            m.set_producer_ms(1400);
            beats(&mut m, 0, 8 * period, period);
            m
        };
        let m = beat_every(1440);
        assert_eq!(m.period(), Some(Span::from_millis(1440)));
        assert!(m.drifts(), "29 per mille");
        assert!(!beat_every(1405).drifts(), "4 per mille");
        assert!(!beat_every(1428).drifts(), "20 per mille is not over");
        assert!(beat_every(1372 - 1).drifts(), "21 per mille, early");
        let mut unknown = HeartbeatMonitor::new(None);
        beats(&mut unknown, 0, 800, 100);
        assert!(!unknown.drifts(), "nothing configured");
    }

    #[test]
    fn a_new_configured_period_is_measured_again() {
        let mut m = HeartbeatMonitor::new(None);
        beats(&mut m, 0, 800, 100);
        assert_eq!(m.period(), Some(Span::from_millis(100)));
        m.set_producer_ms(200);
        assert_eq!(m.period(), None, "measured again");
        beats(&mut m, 1000, 2600, 200);
        assert_eq!(m.period(), Some(Span::from_millis(200)));
        assert!(!m.drifts());
        // The same value again keeps what was measured.
        m.set_producer_ms(200);
        assert_eq!(m.period(), Some(Span::from_millis(200)));
    }

    proptest::proptest! {
        /// Any heartbeat times with a fixed timeout: one outage per gap
        /// over it, from the deadline to the next heartbeat, in order and
        /// disjoint; a node is lost at the end exactly when the end is past
        /// its deadline.
        #[test]
        fn one_outage_per_gap_over_the_timeout(
            gaps in proptest::collection::vec(1u64..2000, 1..60),
            timeout in 1u64..1000,
            tail in 0u64..3000,
        ) {
            let mut m = HeartbeatMonitor::new(Some(Span::from_millis(timeout)));
            let mut now = 0;
            m.seen(at(now));
            let mut expected = Vec::new();
            for g in &gaps {
                // Another node's frame in the middle of the gap.
                m.check(t(now + g / 2));
                if *g > timeout {
                    expected.push(Outage { start: t(now + timeout), end: Some(t(now + g)) });
                }
                now += g;
                m.seen(at(now));
            }
            let end = now + tail;
            m.check(t(end));
            if tail > timeout {
                expected.push(Outage { start: t(now + timeout), end: None });
            }
            let kept: Vec<Outage> = expected.iter().copied().take(MAX_OUTAGES).collect();
            proptest::prop_assert_eq!(m.outages(), kept.as_slice());
            proptest::prop_assert_eq!(m.lost_count(), expected.len() as u64);
            proptest::prop_assert_eq!(m.is_lost(), tail > timeout);
        }
    }
}
