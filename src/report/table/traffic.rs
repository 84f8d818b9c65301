//! The bus's traffic at the end of an input: a **Bus** table, a row per
//! channel (frames, error frames, load, SYNC), and with `--timing` a
//! **Timing** table, a row per identifier.

use std::io::{self, Write};

use super::fit::{CHANNEL_MAX, Fit, display_width};
use super::page::{Page, write_in_two_passes};
use crate::analyze::InputReport;
use crate::analyze::traffic::{ChannelReport, IdReport};
use crate::report::timefmt::human_span;
use crate::text::printable;

/// Whether the Bus table has a row for `c`: where the channel has anything
/// to say past its error frames (which the Bus errors table tells) and the
/// input's frame count (the `bus:` line): SYNC, `--timing`, or other
/// channels to tell it from.
fn shows(input: &InputReport, c: &ChannelReport) -> bool {
    c.timed || sync(c).is_some() || input.channels.len() > 1
}

/// Whether the Bus table has any row.
pub(super) fn shows_bus(input: &InputReport) -> bool {
    input.channels.iter().any(|c| shows(input, c))
}

/// The Bus table: a row per channel [`shows`] lets through.
pub(super) fn write_bus<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    write_in_two_passes(
        page,
        ("Bus", true),
        (&BUS_HEADER, &BUS_RIGHT, &BUS_FIT),
        || input.channels.iter().filter(|c| shows(input, c)),
        |cells, c| {
            cells[0] = printable(&c.channel).into_owned();
            cells[1] = c.frames.to_string();
            cells[2] = c.error_frames.to_string();
            cells[3] = match &c.load {
                Some(l) => format!(
                    "{:.1}% mean, {:.1}% peak ({})",
                    l.mean_percent,
                    l.peak_percent,
                    rate_text(l.bit_rate)
                ),
                None => "-".to_string(),
            };
            (cells[4], cells[5]) = match sync(c) {
                Some(s) => (
                    period_text(s),
                    s.missed.map_or("-".to_string(), |n| n.to_string()),
                ),
                None => ("-".to_string(), "-".to_string()),
            };
            std::array::from_fn(|i| display_width(&cells[i]))
        },
    )
}

/// The Timing table (`--timing`): every identifier of every channel.
pub(super) fn write_timing<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let rows = || {
        input
            .channels
            .iter()
            .filter(|c| c.timed)
            .flat_map(|c| c.ids.iter().map(move |id| (c, id)))
    };
    write_in_two_passes(
        page,
        ("Timing", true),
        (&TIMING_HEADER, &TIMING_RIGHT, &TIMING_FIT),
        rows,
        |cells, (c, id)| {
            cells[0] = printable(&c.channel).into_owned();
            cells[1] = if id.extended {
                format!("0x{:08X}", id.cob_id)
            } else {
                format!("0x{:03X}", id.cob_id)
            };
            cells[2] = id.service.to_string();
            cells[3] = id.node.map_or("-".to_string(), |n| n.to_string());
            cells[4] = id.count.to_string();
            cells[5] = id.period.map_or("-".to_string(), human_span);
            cells[6] = id.jitter.map_or("-".to_string(), human_span);
            cells[7] = id.max_gap.map_or("-".to_string(), human_span);
            cells[8] = match (id.period, id.missed) {
                (Some(_), Some(n)) => n.to_string(),
                _ => "-".to_string(),
            };
            std::array::from_fn(|i| display_width(&cells[i]))
        },
    )
}

/// The SYNC of a channel, once it has a period.
fn sync(c: &ChannelReport) -> Option<&IdReport> {
    c.ids
        .iter()
        .find(|id| id.service == "sync" && id.period.is_some())
}

/// `10 ms ± 12 µs`: the period and the jitter.
pub(super) fn period_text(id: &IdReport) -> String {
    let period = id.period.map_or("-".to_string(), human_span);
    match id.jitter.filter(|j| j.attos() != 0) {
        Some(j) => format!("{period} ± {}", human_span(j)),
        None => period,
    }
}

/// `500 kbit/s`, `1 Mbit/s`, `83.333 kbit/s`.
pub(super) fn rate_text(rate: u32) -> String {
    if rate.is_multiple_of(1_000_000) {
        format!("{} Mbit/s", rate / 1_000_000)
    } else if rate.is_multiple_of(1000) {
        format!("{} kbit/s", rate / 1000)
    } else {
        format!("{rate} bit/s")
    }
}

const BUS_HEADER: [&str; 6] = [
    "CHANNEL",
    "FRAMES",
    "ERROR FRAMES",
    "LOAD",
    "SYNC PERIOD",
    "SYNC MISSED",
];

const BUS_RIGHT: [bool; 6] = [false, true, true, false, false, true];

const BUS_FIT: Fit = Fit {
    drop: &[2],
    flex: &[(3, 40, 12), (0, CHANNEL_MAX, 7)],
};

const TIMING_HEADER: [&str; 9] = [
    "CHANNEL", "COB-ID", "SERVICE", "NODE", "FRAMES", "PERIOD", "JITTER", "MAX GAP", "MISSED",
];

const TIMING_RIGHT: [bool; 9] = [false, false, false, true, true, true, true, true, true];

/// Jitter and the largest gap go first when narrow: the period and the
/// missed cycles say most.
const TIMING_FIT: Fit = Fit {
    drop: &[6, 7, 3],
    flex: &[(0, CHANNEL_MAX, 7)],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_rates_in_words() {
        assert_eq!(rate_text(500_000), "500 kbit/s");
        assert_eq!(rate_text(1_000_000), "1 Mbit/s");
        assert_eq!(rate_text(83_333), "83333 bit/s");
    }
}
