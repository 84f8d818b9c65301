//! The **Inventory** table at the end of an input: who is on the bus, as
//! each node answered the reads of its device type (0x1000) and identity
//! (0x1018), one row per node that answered any.

use std::io::{self, Write};

use super::fit::{CHANNEL_MAX, Fit, display_width};
use super::page::{Page, write_in_two_passes};
use crate::analyze::{Identified, IdentifiedText, InputReport};
use crate::canopen::device_profile;
use crate::canopen::profile::vendor_name;
use crate::text::printable;

pub(super) fn write_inventory<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let hex = |v: Option<Identified>| v.map_or("-".to_string(), |f| format!("0x{:08X}", f.value));
    write_in_two_passes(
        page,
        ("Inventory", true),
        (&HEADER, &RIGHT, &FIT),
        || {
            input
                .nodes
                .iter()
                .filter_map(|n| n.identity.as_ref().map(|id| (n, id)))
        },
        |cells, (n, id)| {
            cells[0] = printable(&n.channel).into_owned();
            cells[1] = n.node.to_string();
            cells[2] = id
                .device_type
                .map_or("-".to_string(), |t| device_profile::describe(t.value));
            cells[3] = match id.vendor_id {
                Some(v) => match vendor_name(v.value) {
                    Some(name) => format!("{name} (0x{:08X})", v.value),
                    None => format!("0x{:08X}", v.value),
                },
                None => "-".to_string(),
            };
            cells[4] = hex(id.product_code);
            cells[5] = hex(id.revision);
            cells[6] = hex(id.serial);
            let text = |t: &Option<IdentifiedText>| {
                t.as_ref()
                    .map_or("-".to_string(), |t| printable(&t.text).into_owned())
            };
            cells[7] = text(&id.name);
            cells[8] = text(&id.hardware_version);
            cells[9] = text(&id.software_version);
            std::array::from_fn(|i| display_width(&cells[i]))
        },
    )
}

const HEADER: [&str; 10] = [
    "CHANNEL", "NODE", "DEVICE", "VENDOR", "PRODUCT", "REVISION", "SERIAL", "NAME", "HARDWARE",
    "SOFTWARE",
];

const RIGHT: [bool; 10] = [
    false, true, false, false, false, false, false, false, false, false,
];

/// The hardware version, revision and product go first when narrow:
/// device, vendor, serial, name and software tell one node from another.
const FIT: Fit = Fit {
    drop: &[8, 5, 4],
    flex: &[
        (7, 30, 8),
        (9, 20, 8),
        (3, 40, 10),
        (2, 30, 10),
        (0, CHANNEL_MAX, 7),
    ],
};
