//! The CoE monitor: CANopen over EtherCAT. A mailbox message repeated is
//! a retry, counted once; the others say what they carry, an emergency
//! (an EMCY of the station) or an SDO transfer, which the dispatcher hands
//! to the EMCY and SDO monitors as it would the same on CAN.

use super::context::Monitor;
use crate::analyze::event::Counts;
use crate::analyze::options::Options;
use crate::canopen::sdo::{self, Sdo};
use crate::trace::ethercat::{CoeMessage, CoeService, Retries};

#[derive(Default)]
pub(in crate::analyze) struct CoeMonitor {
    /// CoE messages seen last, per station: a repeat is a retry.
    retries: Retries,
}

/// What a CoE message carries for the other monitors.
pub(in crate::analyze) enum Carried<'m> {
    /// A retry of the message before: counted, nothing more.
    Retry,
    /// An emergency: an EMCY's eight bytes.
    Emergency(&'m [u8]),
    /// An SDO transfer, as on CAN.
    Sdo(Sdo),
    /// Nothing the analysis reads.
    Nothing,
}

impl Monitor for CoeMonitor {
    fn new(_opts: &Options) -> Self {
        CoeMonitor::default()
    }
}

impl CoeMonitor {
    /// What the CoE message `m` on `channel` carries.
    pub(in crate::analyze) fn message<'m>(
        &mut self,
        channel: &[u8],
        m: &'m CoeMessage,
        counts: &mut Counts,
    ) -> Carried<'m> {
        if self.retries.is_retry(channel, m) {
            counts.mailbox_retries += 1;
            return Carried::Retry;
        }
        match m.service {
            CoeService::Emergency => Carried::Emergency(m.data()),
            CoeService::SdoRequest | CoeService::SdoResponse => {
                let request = m.service == CoeService::SdoRequest;
                match sdo::parse_payload(m.station, request, m.data()) {
                    Some(access) => Carried::Sdo(access),
                    None => Carried::Nothing,
                }
            }
        }
    }
}
