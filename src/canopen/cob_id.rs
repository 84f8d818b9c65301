//! What a standard identifier carries under CiA 301's predefined connection
//! set: the service and, for the services addressed to or sent by one
//! node, that node. A network may move an object to another COB-ID (a PDO
//! mapped elsewhere, an EMCY moved by 0x1014); the name is then what the
//! predefined set says, which is what a reader of a trace expects to see.

use super::NodeId;

/// SYNC (CiA 301 §7.2.5): the one standard id with no node in it.
pub const SYNC_ID: u32 = 0x080;

/// The service a standard identifier carries by the predefined connection
/// set, as the stable name in JSON, and the node it names (`None` for
/// broadcast services and ids outside the set).
pub fn service(id: u32, extended: bool) -> (&'static str, Option<NodeId>) {
    if extended {
        return ("other", None);
    }
    let node = (id & 0x7F) as NodeId;
    let named = |name| (name, Some(node));
    match id {
        0x000 => ("nmt", None),
        SYNC_ID => ("sync", None),
        0x081..=0x0FF => named("emcy"),
        0x100 => ("time", None),
        0x181..=0x1FF => named("tpdo1"),
        0x201..=0x27F => named("rpdo1"),
        0x281..=0x2FF => named("tpdo2"),
        0x301..=0x37F => named("rpdo2"),
        0x381..=0x3FF => named("tpdo3"),
        0x401..=0x47F => named("rpdo3"),
        0x481..=0x4FF => named("tpdo4"),
        0x501..=0x57F => named("rpdo4"),
        0x581..=0x5FF => named("sdo_response"),
        0x601..=0x67F => named("sdo_request"),
        0x701..=0x77F => named("heartbeat"),
        0x7E4 => ("lss_response", None),
        0x7E5 => ("lss_request", None),
        _ => ("other", None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_range_of_the_predefined_set() {
        for (id, want) in [
            (0x000, ("nmt", None)),
            (0x080, ("sync", None)),
            (0x081, ("emcy", Some(1))),
            (0x0FF, ("emcy", Some(127))),
            (0x100, ("time", None)),
            (0x185, ("tpdo1", Some(5))),
            (0x205, ("rpdo1", Some(5))),
            (0x285, ("tpdo2", Some(5))),
            (0x305, ("rpdo2", Some(5))),
            (0x385, ("tpdo3", Some(5))),
            (0x405, ("rpdo3", Some(5))),
            (0x485, ("tpdo4", Some(5))),
            (0x505, ("rpdo4", Some(5))),
            (0x585, ("sdo_response", Some(5))),
            (0x605, ("sdo_request", Some(5))),
            (0x705, ("heartbeat", Some(5))),
            (0x7E4, ("lss_response", None)),
            (0x7E5, ("lss_request", None)),
            // Node 0 is no node: the base ids are outside the set.
            (0x180, ("other", None)),
            (0x580, ("other", None)),
            (0x700, ("other", None)),
            (0x680, ("other", None)),
            (0x7FF, ("other", None)),
        ] {
            assert_eq!(service(id, false), want, "{id:#05x}");
        }
        assert_eq!(service(0x185, true), ("other", None), "extended ids");
    }
}
