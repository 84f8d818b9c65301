//! The bus under the CANopen story: error frames grouped into bursts per
//! channel, the logging controller's bus-offs, and a node's bus-off,
//! which the node cannot tell while it is off and the trace shows only by
//! its silence, the errors around it and how it came back (EMCY 0x8140
//! "recovered from bus-off", or a boot-up).
//!
//! The dispatcher owns this state (it is a fact about the bus that every
//! monitor may read: the EMCY monitor names the burst a communication
//! error came in). Nothing here runs for a trace without error frames but
//! one comparison per frame ([`BusErrors::passed`]).

use super::event::{
    BURST_GAP_MS, Bus, BusOff, BusOffRecord, ChannelErrors, ErrorBurst, Evidence, EvidenceKind,
    MAX_BUS_OFFS_KEPT,
};
use crate::canopen::NodeId;
use crate::timeline::At;
use crate::trace::can_error::{ErrorFrame, ErrorKind};
use crate::trace::{Span, Timestamp};

/// Channels whose error frames are followed; error frames on more are
/// only counted ([`BusErrors::ignored`]), so a hostile input cannot grow
/// the state without bound.
pub(crate) const MAX_CHANNELS: usize = 256;

/// A node's recovery (EMCY 0x8140, a boot-up) this long after the last
/// error frame of a burst still belongs to the burst: a node that went
/// bus-off waits before it tries the bus again (CANopen stacks restart the
/// controller from their main loop, often after a delay of their own),
/// and the errors stop as soon as it is off.
pub(crate) const RIGHT_AFTER_MS: u64 = 10_000;

/// Nodes per channel whose bus-off was told for the current burst (one
/// bus-off per node and burst, however many ways it showed).
const MAX_TOLD: usize = 1024;

/// Something the bus state has to tell: the event and where it began.
#[derive(Debug, PartialEq)]
pub(crate) struct Told {
    pub(crate) channel: String,
    pub(crate) at: At,
    pub(crate) bus: Bus,
}

/// The error frames of an input, per channel.
#[derive(Default)]
pub(crate) struct BusErrors {
    channels: Vec<Channel>,
    /// When the earliest open burst closes if no error frame comes first.
    deadline: Option<Timestamp>,
    /// Error frames on channels past [`MAX_CHANNELS`].
    pub(crate) ignored: u64,
}

struct Channel {
    raw: Box<[u8]>,
    report: ChannelErrors,
    open: Option<OpenBurst>,
    /// The last closed burst: start, end, the line it began on.
    last: Option<(Option<Timestamp>, Option<Timestamp>, u64)>,
    /// The logging controller's bus-off going on.
    controller: Option<OpenBusOff>,
    /// Nodes whose bus-off was told since the current burst began.
    told: Vec<NodeId>,
}

struct OpenBurst {
    burst: ErrorBurst,
    line: u64,
}

struct OpenBusOff {
    start: At,
    evidence: Vec<Evidence>,
}

fn gap() -> Span {
    Span::from_millis(BURST_GAP_MS)
}

impl BusErrors {
    /// Whether any error frame was seen: no other method does anything
    /// until then.
    #[inline]
    pub(crate) fn any(&self) -> bool {
        !self.channels.is_empty()
    }

    /// Whether the trace's clock at `t` closes an open burst: the one check
    /// every timed frame pays.
    #[inline]
    pub(crate) fn passed(&self, t: Timestamp) -> bool {
        self.deadline.is_some_and(|d| t > d)
    }

    /// An error frame on `channel` at `at`: it joins the channel's burst or
    /// opens one (closing the one before when more than the gap passed).
    pub(crate) fn error_frame(
        &mut self,
        channel: &[u8],
        at: At,
        frame: &ErrorFrame,
        out: &mut Vec<Told>,
    ) {
        if let Some(t) = at.time
            && self.passed(t)
        {
            self.close_until(t, out);
        }
        let Some(c) = self.channel(channel) else {
            self.ignored += 1;
            return;
        };
        let open = c.open.get_or_insert_with(|| {
            c.told.clear();
            OpenBurst {
                burst: ErrorBurst {
                    start: at.time,
                    end: at.time,
                    frames: 0,
                    kinds: [0; ErrorKind::ALL.len()],
                    tx_errors_max: None,
                    rx_errors_max: None,
                },
                line: at.line,
            }
        });
        let b = &mut open.burst;
        b.frames += 1;
        if at.time.is_some() {
            b.end = b.end.max(at.time);
        }
        let r = &mut c.report;
        r.frames += 1;
        for kind in frame.kinds.iter() {
            b.kinds[kind.index()] += 1;
            r.kinds[kind.index()] += 1;
        }
        if let Some((tx, rx)) = frame.counters {
            b.tx_errors_max = b.tx_errors_max.max(Some(tx));
            b.rx_errors_max = b.rx_errors_max.max(Some(rx));
            r.tx_errors_max = r.tx_errors_max.max(Some(tx));
            r.rx_errors_max = r.rx_errors_max.max(Some(rx));
        }
        if frame.bus_off() && c.controller.is_none() {
            c.controller = Some(OpenBusOff {
                start: at,
                evidence: vec![
                    Evidence {
                        kind: EvidenceKind::BusError,
                        time: open.burst.start,
                        line: open.line,
                    },
                    Evidence {
                        kind: EvidenceKind::BusOffFrame,
                        time: at.time,
                        line: at.line,
                    },
                ],
            });
        } else if frame.recovered()
            && let Some(mut off) = c.controller.take()
        {
            off.evidence.push(Evidence {
                kind: EvidenceKind::RecoveryFrame,
                time: at.time,
                line: at.line,
            });
            out.push(c.bus_off(None, off.start, at.time, off.evidence));
        }
        self.refresh_deadline();
    }

    /// The trace's clock reached `t`: bursts more than the gap older close.
    pub(crate) fn close_until(&mut self, t: Timestamp, out: &mut Vec<Told>) {
        for c in &mut self.channels {
            let ends = c
                .open
                .as_ref()
                .and_then(|o| o.burst.end)
                .and_then(|end| end.checked_add_span(gap()));
            if ends.is_some_and(|d| t > d) {
                c.close(out);
            }
        }
        self.refresh_deadline();
    }

    /// The end of the input: every burst closes; a controller still off
    /// stays so (`end` null).
    pub(crate) fn finish(&mut self, out: &mut Vec<Told>) {
        for c in &mut self.channels {
            c.close(out);
            if let Some(off) = c.controller.take() {
                out.push(c.bus_off(None, off.start, None, off.evidence));
            }
        }
        self.deadline = None;
    }

    /// The start of the burst on `channel` that a node's frame at `t` came
    /// in or right after ([`RIGHT_AFTER_MS`]).
    pub(crate) fn burst_of(&self, channel: &[u8], t: Timestamp) -> Option<Timestamp> {
        let c = self.channels.iter().find(|c| &*c.raw == channel)?;
        c.burst_near(t).map(|(start, _)| start)
    }

    /// A node came back (`via` an EMCY 0x8140 or a boot-up, at `at`) after
    /// being last heard at `last_seen`: a bus-off of the node when the
    /// silence and a burst of error frames on its channel go together.
    /// A boot-up needs the silence to cover the burst's end and to last
    /// longer than the gap (a node that reset itself while the bus was
    /// fine is not off the bus); an EMCY 0x8140 is the node's own word and
    /// needs only the burst.
    pub(crate) fn node_back(
        &mut self,
        channel: &[u8],
        node: NodeId,
        at: At,
        via: EvidenceKind,
        last_seen: Option<At>,
    ) -> Option<Told> {
        let t = at.time?;
        let c = self.channels.iter_mut().find(|c| &*c.raw == channel)?;
        let ((start, _), (start_time, end_time)) = c.burst_near(t).zip(c.burst_span())?;
        if c.told.contains(&node) || c.told.len() >= MAX_TOLD {
            return None;
        }
        let silent_from = last_seen.and_then(|l| l.time.map(|time| (time, l.line)));
        if via == EvidenceKind::BootUp {
            let (from, _) = silent_from?;
            let covers_end = end_time.is_none_or(|end| from <= end);
            let long = from.checked_add_span(gap()).is_some_and(|d| t > d);
            if !covers_end || !long {
                return None;
            }
        }
        let mut evidence = vec![Evidence {
            kind: EvidenceKind::BusError,
            time: start_time,
            line: c.burst_line(),
        }];
        let mut off_from = At {
            time: Some(start),
            line: c.burst_line(),
        };
        if let Some((from, line)) = silent_from.filter(|(from, _)| *from <= t) {
            evidence.push(Evidence {
                kind: EvidenceKind::LastSeen,
                time: Some(from),
                line,
            });
            off_from = At {
                time: Some(from),
                line,
            };
        }
        evidence.push(Evidence {
            kind: via,
            time: at.time,
            line: at.line,
        });
        evidence.sort_by_key(|e| (e.time, e.line));
        c.told.push(node);
        Some(c.bus_off(Some(node), off_from, at.time, evidence))
    }

    /// The per-channel report, in the order channels first had an error.
    pub(crate) fn into_report(self) -> Vec<ChannelErrors> {
        self.channels.into_iter().map(|c| c.report).collect()
    }

    /// The channel's state, created on its first error frame; `None` past
    /// [`MAX_CHANNELS`].
    fn channel(&mut self, raw: &[u8]) -> Option<&mut Channel> {
        let i = match self.channels.iter().position(|c| &*c.raw == raw) {
            Some(i) => i,
            None if self.channels.len() < MAX_CHANNELS => {
                self.channels.push(Channel {
                    raw: raw.into(),
                    report: ChannelErrors {
                        channel: String::from_utf8_lossy(raw).into_owned(),
                        ..ChannelErrors::default()
                    },
                    open: None,
                    last: None,
                    controller: None,
                    told: Vec::new(),
                });
                self.channels.len() - 1
            }
            None => return None,
        };
        self.channels.get_mut(i)
    }

    fn refresh_deadline(&mut self) {
        self.deadline = self
            .channels
            .iter()
            .filter_map(|c| c.open.as_ref()?.burst.end?.checked_add_span(gap()))
            .min();
    }
}

impl Channel {
    /// Closes the open burst, if any.
    fn close(&mut self, out: &mut Vec<Told>) {
        let Some(open) = self.open.take() else {
            return;
        };
        self.report.bursts += 1;
        self.last = Some((open.burst.start, open.burst.end, open.line));
        out.push(Told {
            channel: self.report.channel.clone(),
            at: At {
                time: open.burst.start,
                line: open.line,
            },
            bus: Bus::Errors(open.burst),
        });
    }

    /// A bus-off to tell, counted in the report.
    fn bus_off(
        &mut self,
        node: Option<NodeId>,
        start: At,
        end: Option<Timestamp>,
        evidence: Vec<Evidence>,
    ) -> Told {
        self.report.bus_off_count += 1;
        if self.report.bus_offs.len() < MAX_BUS_OFFS_KEPT {
            self.report.bus_offs.push(BusOffRecord {
                node,
                start: start.time,
                end,
            });
        }
        Told {
            channel: self.report.channel.clone(),
            at: start,
            bus: Bus::BusOff(BusOff {
                node,
                start: start.time,
                end,
                evidence,
            }),
        }
    }

    /// The open burst's start and end so far, else the last closed one's.
    fn burst_span(&self) -> Option<(Option<Timestamp>, Option<Timestamp>)> {
        match (&self.open, self.last) {
            (Some(o), _) => Some((o.burst.start, None)),
            (None, Some((start, end, _))) => Some((start, end)),
            (None, None) => None,
        }
    }

    fn burst_line(&self) -> u64 {
        match (&self.open, self.last) {
            (Some(o), _) => o.line,
            (None, Some((_, _, line))) => line,
            (None, None) => 0,
        }
    }

    /// The burst a frame at `t` came in (the open one, begun by then) or
    /// right after (the last closed one, ended at most [`RIGHT_AFTER_MS`]
    /// before): its start, and whether it is still open.
    fn burst_near(&self, t: Timestamp) -> Option<(Timestamp, bool)> {
        if let Some(o) = &self.open
            && let Some(start) = o.burst.start
            && start <= t
        {
            return Some((start, true));
        }
        let (start, end, _) = self.last?;
        let (start, end) = (start?, end?);
        let until = end.checked_add_span(Span::from_millis(RIGHT_AFTER_MS))?;
        (start <= t && t <= until).then_some((start, false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::can_error::class;

    fn at(ms: u64, line: u64) -> At {
        At::ms(ms, line)
    }

    fn t(ms: u64) -> Timestamp {
        at(ms, 0).time.unwrap()
    }

    fn frame(classes: u32, data: [u8; 8]) -> ErrorFrame {
        ErrorFrame::decode(classes, &data)
    }

    fn bursts(out: &[Told]) -> Vec<&ErrorBurst> {
        out.iter()
            .filter_map(|t| match &t.bus {
                Bus::Errors(b) => Some(b),
                Bus::BusOff(_)
                | Bus::Lss(_)
                | Bus::Incident(_)
                | Bus::SyncMissed(_)
                | Bus::Sdo(_) => None,
            })
            .collect()
    }

    #[test]
    fn a_burst_closes_after_a_second_without_error_frames() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let prot = frame(class::PROTOCOL | class::COUNTERS, [0, 0, 4, 0, 0, 0, 90, 3]);
        bus.error_frame(b"can0", at(1000, 1), &prot, &mut out);
        bus.error_frame(b"can0", at(1900, 2), &prot, &mut out);
        // Exactly a second after the last: still the same burst.
        bus.error_frame(
            b"can0",
            at(2900, 3),
            &frame(class::NO_ACK, [0; 8]),
            &mut out,
        );
        assert!(out.is_empty());
        assert!(!bus.passed(t(3900)));
        assert!(bus.passed(t(3901)));
        bus.close_until(t(3901), &mut out);
        let b = bursts(&out);
        assert_eq!(b.len(), 1);
        assert_eq!(
            (b[0].start, b[0].end, b[0].frames),
            (Some(t(1000)), Some(t(2900)), 3)
        );
        assert_eq!(b[0].kinds[ErrorKind::ProtocolViolation.index()], 2);
        assert_eq!(b[0].kinds[ErrorKind::NoAck.index()], 1);
        assert_eq!(
            (b[0].tx_errors_max, b[0].rx_errors_max),
            (Some(90), Some(3))
        );
        assert_eq!(out[0].at.line, 1);
        assert!(!bus.passed(t(100_000)), "nothing open");
    }

    #[test]
    fn a_late_error_frame_closes_the_burst_before_and_opens_its_own() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let f = frame(class::BUS_ERROR, [0; 8]);
        bus.error_frame(b"can0", at(1000, 1), &f, &mut out);
        bus.error_frame(b"can0", at(5000, 2), &f, &mut out);
        assert_eq!(bursts(&out).len(), 1);
        bus.finish(&mut out);
        let b = bursts(&out);
        assert_eq!(b.len(), 2);
        assert_eq!(b[1].start, Some(t(5000)));
        // No counters reported: unknown, not zero.
        assert_eq!(b[1].tx_errors_max, None);
        let report = bus.into_report();
        assert_eq!((report[0].frames, report[0].bursts), (2, 2));
    }

    #[test]
    fn channels_have_bursts_of_their_own() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let f = frame(class::BUS_ERROR, [0; 8]);
        bus.error_frame(b"can0", at(1000, 1), &f, &mut out);
        bus.error_frame(b"can1", at(1500, 2), &f, &mut out);
        bus.close_until(t(2100), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].channel, "can0");
        bus.finish(&mut out);
        assert_eq!(out[1].channel, "can1");
    }

    #[test]
    fn channels_past_the_bound_are_only_counted() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let f = frame(class::BUS_ERROR, [0; 8]);
        for i in 0..MAX_CHANNELS + 3 {
            bus.error_frame(format!("c{i}").as_bytes(), at(1000, 1), &f, &mut out);
        }
        assert_eq!(bus.ignored, 3);
        assert_eq!(bus.into_report().len(), MAX_CHANNELS);
    }

    #[test]
    fn the_controller_is_off_from_its_bus_off_frame_to_its_restart() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        bus.error_frame(
            b"can0",
            at(1000, 1),
            &frame(class::PROTOCOL, [0; 8]),
            &mut out,
        );
        bus.error_frame(
            b"can0",
            at(1200, 2),
            &frame(class::BUS_OFF, [0; 8]),
            &mut out,
        );
        // A second bus-off frame changes nothing.
        bus.error_frame(
            b"can0",
            at(1300, 3),
            &frame(class::BUS_OFF, [0; 8]),
            &mut out,
        );
        assert!(out.is_empty());
        bus.error_frame(
            b"can0",
            at(1400, 4),
            &frame(class::RESTARTED, [0; 8]),
            &mut out,
        );
        let Bus::BusOff(off) = &out[0].bus else {
            panic!("{out:?}")
        };
        assert_eq!(
            (off.node, off.start, off.end),
            (None, Some(t(1200)), Some(t(1400)))
        );
        let kinds: Vec<_> = off.evidence.iter().map(|e| e.kind).collect();
        assert_eq!(
            kinds,
            [
                EvidenceKind::BusError,
                EvidenceKind::BusOffFrame,
                EvidenceKind::RecoveryFrame
            ]
        );
    }

    #[test]
    fn a_controller_still_off_at_the_end_has_no_end() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        bus.error_frame(
            b"can0",
            at(1000, 1),
            &frame(class::BUS_OFF, [0; 8]),
            &mut out,
        );
        bus.finish(&mut out);
        let offs: Vec<_> = out
            .iter()
            .filter_map(|t| match &t.bus {
                Bus::BusOff(o) => Some(o),
                Bus::Errors(_)
                | Bus::Lss(_)
                | Bus::Incident(_)
                | Bus::SyncMissed(_)
                | Bus::Sdo(_) => None,
            })
            .collect();
        assert_eq!(offs.len(), 1);
        assert_eq!(offs[0].end, None);
        assert_eq!(bus.into_report()[0].bus_off_count, 1);
    }

    #[test]
    fn an_emcy_8140_in_or_right_after_a_burst_is_a_bus_off_of_its_node() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let f = frame(class::PROTOCOL, [0; 8]);
        bus.error_frame(b"can0", at(10_000, 5), &f, &mut out);
        bus.error_frame(b"can0", at(10_500, 6), &f, &mut out);
        let emcy = EvidenceKind::Emcy(0x8140);
        // Inside the open burst.
        let told = bus
            .node_back(b"can0", 5, at(10_700, 7), emcy, Some(at(9_900, 4)))
            .expect("bus-off");
        let Bus::BusOff(off) = &told.bus else {
            panic!()
        };
        assert_eq!(
            (off.node, off.start, off.end),
            (Some(5), Some(t(9_900)), Some(t(10_700)))
        );
        let kinds: Vec<_> = off.evidence.iter().map(|e| e.kind).collect();
        assert_eq!(
            kinds,
            [EvidenceKind::LastSeen, EvidenceKind::BusError, emcy]
        );
        // Told once per node and burst.
        assert!(
            bus.node_back(b"can0", 5, at(10_800, 8), emcy, None)
                .is_none()
        );
        // Right after the burst closed, another node.
        bus.close_until(t(12_000), &mut out);
        assert!(
            bus.node_back(b"can0", 6, at(20_000, 9), emcy, None)
                .is_some()
        );
        // Too long after it.
        assert!(
            bus.node_back(b"can0", 7, at(20_501, 10), emcy, None)
                .is_none()
        );
        // Another channel had no burst.
        assert!(
            bus.node_back(b"can1", 5, at(10_700, 7), emcy, None)
                .is_none()
        );
        assert_eq!(bus.into_report()[0].bus_off_count, 2);
    }

    #[test]
    fn a_boot_up_is_a_bus_off_only_after_a_silence_over_the_burst() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        let f = frame(class::PROTOCOL, [0; 8]);
        bus.error_frame(b"can0", at(10_000, 5), &f, &mut out);
        bus.error_frame(b"can0", at(11_000, 6), &f, &mut out);
        bus.close_until(t(12_500), &mut out);
        let boot = EvidenceKind::BootUp;
        // Heard after the errors stopped: not silent over the burst.
        assert!(
            bus.node_back(b"can0", 5, at(13_000, 9), boot, Some(at(11_500, 8)))
                .is_none()
        );
        // Silent for less than the gap.
        assert!(
            bus.node_back(b"can0", 5, at(11_000, 9), boot, Some(at(10_500, 8)))
                .is_none()
        );
        // Never heard before: no silence to speak of.
        assert!(
            bus.node_back(b"can0", 5, at(13_000, 9), boot, None)
                .is_none()
        );
        let told = bus.node_back(b"can0", 5, at(14_000, 9), boot, Some(at(9_800, 4)));
        assert!(told.is_some());
    }

    #[test]
    fn the_burst_of_an_emcy_is_found_by_time() {
        let mut bus = BusErrors::default();
        let mut out = Vec::new();
        assert_eq!(bus.burst_of(b"can0", t(1000)), None);
        let f = frame(class::PROTOCOL, [0; 8]);
        bus.error_frame(b"can0", at(1000, 1), &f, &mut out);
        assert_eq!(bus.burst_of(b"can0", t(900)), None, "before it began");
        assert_eq!(bus.burst_of(b"can0", t(1500)), Some(t(1000)));
        bus.finish(&mut out);
        assert_eq!(bus.burst_of(b"can0", t(11_000)), Some(t(1000)));
        assert_eq!(bus.burst_of(b"can0", t(11_001)), None);
    }
}
