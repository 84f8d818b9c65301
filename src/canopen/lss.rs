//! Layer setting services (CiA 305): how a master gives an unconfigured
//! node its node-id and bit rate. The master sends on 0x7E5, the nodes
//! answer on 0x7E4; byte 0 is the command specifier.

/// The master's requests.
pub const MASTER_ID: u32 = 0x7E5;
/// The nodes' answers.
pub const SLAVE_ID: u32 = 0x7E4;

/// One part of a node's identity (object 0x1018), as the selective
/// services name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Vendor,
    Product,
    Revision,
    Serial,
    /// Identify remote slave gives ranges: the low and high bound.
    RevisionLow,
    RevisionHigh,
    SerialLow,
    SerialHigh,
    NodeId,
}

impl Part {
    pub fn slug(self) -> &'static str {
        match self {
            Part::Vendor => "vendor_id",
            Part::Product => "product_code",
            Part::Revision => "revision",
            Part::Serial => "serial",
            Part::RevisionLow => "revision_low",
            Part::RevisionHigh => "revision_high",
            Part::SerialLow => "serial_low",
            Part::SerialHigh => "serial_high",
            Part::NodeId => "node_id",
        }
    }
}

/// An LSS frame, decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lss {
    /// Every node to the waiting or the configuration state.
    SwitchGlobal {
        configuration: bool,
    },
    /// One part of the identity of the node to switch to configuration.
    SwitchSelective {
        part: Part,
        value: u32,
    },
    /// The node whose identity matched is in configuration.
    SwitchSelectiveAnswer,
    ConfigureNodeId {
        node: u8,
    },
    /// The answer to configure node-id, bit timing or store: `error` 0 is
    /// success, 0xFF a manufacturer's error (`specific`).
    Answer {
        service: Service,
        error: u8,
        specific: u8,
    },
    ConfigureBitTiming {
        table: u8,
        index: u8,
    },
    /// Switch to the configured bit rate after `delay_ms` (twice: before
    /// and after the switch).
    ActivateBitTiming {
        delay_ms: u16,
    },
    Store,
    Inquire {
        part: Part,
    },
    InquireAnswer {
        part: Part,
        value: u32,
    },
    /// Is a node with this identity (range) there?
    IdentifyRemote {
        part: Part,
        value: u32,
    },
    /// A node in the range is there.
    IdentifyAnswer,
    IdentifyNonConfigured,
    /// A node without a node-id is there.
    NonConfiguredAnswer,
    Fastscan,
    /// A command specifier CiA 305 does not define.
    Unknown {
        cs: u8,
    },
}

/// The services whose answer is an error code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Service {
    ConfigureNodeId,
    ConfigureBitTiming,
    Store,
}

impl Lss {
    /// Decodes a frame on 0x7E5 (`from_master`) or 0x7E4. Short frames
    /// read missing bytes as zero: nothing here can fail.
    pub fn decode(from_master: bool, data: &[u8]) -> Lss {
        let byte = |i: usize| data.get(i).copied().unwrap_or(0);
        let value = u32::from_le_bytes([byte(1), byte(2), byte(3), byte(4)]);
        let cs = byte(0);
        let answer = |service| Lss::Answer {
            service,
            error: byte(1),
            specific: byte(2),
        };
        let inquiry = |cs: u8| match cs {
            0x5A => Some(Part::Vendor),
            0x5B => Some(Part::Product),
            0x5C => Some(Part::Revision),
            0x5D => Some(Part::Serial),
            0x5E => Some(Part::NodeId),
            _ => None,
        };
        if from_master {
            match cs {
                0x04 => Lss::SwitchGlobal {
                    configuration: byte(1) == 1,
                },
                0x40..=0x43 => Lss::SwitchSelective {
                    part: [Part::Vendor, Part::Product, Part::Revision, Part::Serial]
                        [usize::from(cs - 0x40)],
                    value,
                },
                0x11 => Lss::ConfigureNodeId { node: byte(1) },
                0x13 => Lss::ConfigureBitTiming {
                    table: byte(1),
                    index: byte(2),
                },
                0x15 => Lss::ActivateBitTiming {
                    delay_ms: u16::from_le_bytes([byte(1), byte(2)]),
                },
                0x17 => Lss::Store,
                0x46..=0x4B => Lss::IdentifyRemote {
                    part: [
                        Part::Vendor,
                        Part::Product,
                        Part::RevisionLow,
                        Part::RevisionHigh,
                        Part::SerialLow,
                        Part::SerialHigh,
                    ][usize::from(cs - 0x46)],
                    value,
                },
                0x4C => Lss::IdentifyNonConfigured,
                0x51 => Lss::Fastscan,
                _ => match inquiry(cs) {
                    Some(part) => Lss::Inquire { part },
                    None => Lss::Unknown { cs },
                },
            }
        } else {
            match cs {
                0x44 => Lss::SwitchSelectiveAnswer,
                0x11 => answer(Service::ConfigureNodeId),
                0x13 => answer(Service::ConfigureBitTiming),
                0x17 => answer(Service::Store),
                0x4F => Lss::IdentifyAnswer,
                0x50 => Lss::NonConfiguredAnswer,
                _ => match inquiry(cs) {
                    // A node-id answer is one byte.
                    Some(Part::NodeId) => Lss::InquireAnswer {
                        part: Part::NodeId,
                        value: u32::from(byte(1)),
                    },
                    Some(part) => Lss::InquireAnswer { part, value },
                    None => Lss::Unknown { cs },
                },
            }
        }
    }

    /// The service's stable name (the JSON `service`).
    pub fn slug(&self) -> &'static str {
        match self {
            Lss::SwitchGlobal { .. } => "switch_state_global",
            Lss::SwitchSelective { .. } | Lss::SwitchSelectiveAnswer => "switch_state_selective",
            Lss::ConfigureNodeId { .. }
            | Lss::Answer {
                service: Service::ConfigureNodeId,
                ..
            } => "configure_node_id",
            Lss::ConfigureBitTiming { .. }
            | Lss::Answer {
                service: Service::ConfigureBitTiming,
                ..
            } => "configure_bit_timing",
            Lss::ActivateBitTiming { .. } => "activate_bit_timing",
            Lss::Store
            | Lss::Answer {
                service: Service::Store,
                ..
            } => "store_configuration",
            Lss::Inquire { .. } | Lss::InquireAnswer { .. } => "inquire",
            Lss::IdentifyRemote { .. } | Lss::IdentifyAnswer => "identify_remote_slave",
            Lss::IdentifyNonConfigured | Lss::NonConfiguredAnswer => {
                "identify_non_configured_slave"
            }
            Lss::Fastscan => "fastscan",
            Lss::Unknown { .. } => "unknown",
        }
    }

    /// The service in words, for the table: "configure node-id 5",
    /// "answer: node-id configured".
    pub fn words(&self) -> String {
        match *self {
            Lss::SwitchGlobal { configuration } => format!(
                "switch all to {} state",
                if configuration {
                    "configuration"
                } else {
                    "waiting"
                }
            ),
            Lss::SwitchSelective { part, value } => {
                format!("switch selective: {} 0x{value:08X}", part.slug())
            }
            Lss::SwitchSelectiveAnswer => "answer: selected node in configuration".to_string(),
            Lss::ConfigureNodeId { node } => format!("configure node-id {node}"),
            Lss::Answer {
                service,
                error,
                specific,
            } => {
                let what = match service {
                    Service::ConfigureNodeId => "node-id",
                    Service::ConfigureBitTiming => "bit timing",
                    Service::Store => "store",
                };
                format!("answer: {what} {}", result_words(service, error, specific))
            }
            Lss::ConfigureBitTiming { table, index } => match bit_rate(table, index) {
                Some(rate) => format!("configure bit timing {rate}"),
                None => format!("configure bit timing table {table} index {index}"),
            },
            Lss::ActivateBitTiming { delay_ms } => {
                format!("activate bit timing (switch delay {delay_ms} ms)")
            }
            Lss::Store => "store configuration".to_string(),
            Lss::Inquire { part } => format!("inquire {}", part.slug()),
            Lss::InquireAnswer { part, value } => match part {
                Part::NodeId => format!("answer: node_id {value}"),
                _ => format!("answer: {} 0x{value:08X}", part.slug()),
            },
            Lss::IdentifyRemote { part, value } => {
                format!("identify remote slave: {} 0x{value:08X}", part.slug())
            }
            Lss::IdentifyAnswer => "answer: a slave in the range is there".to_string(),
            Lss::IdentifyNonConfigured => "identify non-configured slaves".to_string(),
            Lss::NonConfiguredAnswer => "answer: a non-configured slave is there".to_string(),
            Lss::Fastscan => "fastscan".to_string(),
            Lss::Unknown { cs } => format!("unknown command specifier 0x{cs:02X}"),
        }
    }
}

/// An answer's error code in words: `ok`, or what CiA 305 says it means.
pub fn result_words(service: Service, error: u8, specific: u8) -> String {
    match (service, error) {
        (_, 0) => "ok".to_string(),
        (_, 0xFF) => format!("failed (manufacturer error 0x{specific:02X})"),
        (Service::ConfigureNodeId, 1) => "failed: node-id out of range".to_string(),
        (Service::ConfigureBitTiming, 1) => "failed: bit timing not supported".to_string(),
        (Service::Store, 1) => "failed: store not supported".to_string(),
        (Service::Store, 2) => "failed: storage media access error".to_string(),
        (_, e) => format!("failed (error {e})"),
    }
}

/// The bit rate of CiA 305's table 0 (the only standard table).
pub fn bit_rate(table: u8, index: u8) -> Option<&'static str> {
    if table != 0 {
        return None;
    }
    match index {
        0 => Some("1 Mbit/s"),
        1 => Some("800 kbit/s"),
        2 => Some("500 kbit/s"),
        3 => Some("250 kbit/s"),
        4 => Some("125 kbit/s"),
        6 => Some("50 kbit/s"),
        7 => Some("20 kbit/s"),
        8 => Some("10 kbit/s"),
        9 => Some("automatic bit rate detection"),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn master(bytes: &[u8]) -> Lss {
        Lss::decode(true, bytes)
    }

    fn slave(bytes: &[u8]) -> Lss {
        Lss::decode(false, bytes)
    }

    #[test]
    fn every_master_command_specifier() {
        assert_eq!(
            master(&[0x04, 1]),
            Lss::SwitchGlobal {
                configuration: true
            }
        );
        assert_eq!(
            master(&[0x04, 0]),
            Lss::SwitchGlobal {
                configuration: false
            }
        );
        let parts = [Part::Vendor, Part::Product, Part::Revision, Part::Serial];
        for (cs, part) in (0x40..=0x43).zip(parts) {
            assert_eq!(
                master(&[cs, 0x78, 0x56, 0x34, 0x12]),
                Lss::SwitchSelective {
                    part,
                    value: 0x1234_5678
                }
            );
        }
        assert_eq!(master(&[0x11, 5]), Lss::ConfigureNodeId { node: 5 });
        assert_eq!(
            master(&[0x13, 0, 2]),
            Lss::ConfigureBitTiming { table: 0, index: 2 }
        );
        assert_eq!(
            master(&[0x15, 0xE8, 0x03]),
            Lss::ActivateBitTiming { delay_ms: 1000 }
        );
        assert_eq!(master(&[0x17]), Lss::Store);
        let ranges = [
            Part::Vendor,
            Part::Product,
            Part::RevisionLow,
            Part::RevisionHigh,
            Part::SerialLow,
            Part::SerialHigh,
        ];
        for (cs, part) in (0x46..=0x4B).zip(ranges) {
            assert_eq!(
                master(&[cs, 1, 0, 0, 0]),
                Lss::IdentifyRemote { part, value: 1 }
            );
        }
        assert_eq!(master(&[0x4C]), Lss::IdentifyNonConfigured);
        assert_eq!(master(&[0x51]), Lss::Fastscan);
        let inquiries = [
            Part::Vendor,
            Part::Product,
            Part::Revision,
            Part::Serial,
            Part::NodeId,
        ];
        for (cs, part) in (0x5A..=0x5E).zip(inquiries) {
            assert_eq!(master(&[cs]), Lss::Inquire { part });
        }
        assert_eq!(master(&[0x99]), Lss::Unknown { cs: 0x99 });
        // The slave's specifiers from the master are unknown.
        assert_eq!(master(&[0x44]), Lss::Unknown { cs: 0x44 });
    }

    #[test]
    fn every_slave_command_specifier() {
        assert_eq!(slave(&[0x44]), Lss::SwitchSelectiveAnswer);
        for (cs, service) in [
            (0x11, Service::ConfigureNodeId),
            (0x13, Service::ConfigureBitTiming),
            (0x17, Service::Store),
        ] {
            assert_eq!(
                slave(&[cs, 0xFF, 7]),
                Lss::Answer {
                    service,
                    error: 0xFF,
                    specific: 7
                }
            );
        }
        assert_eq!(slave(&[0x4F]), Lss::IdentifyAnswer);
        assert_eq!(slave(&[0x50]), Lss::NonConfiguredAnswer);
        assert_eq!(
            slave(&[0x5A, 0x78, 0x56, 0x34, 0x12]),
            Lss::InquireAnswer {
                part: Part::Vendor,
                value: 0x1234_5678
            }
        );
        assert_eq!(
            slave(&[0x5E, 5, 0xAA, 0xAA, 0xAA]),
            Lss::InquireAnswer {
                part: Part::NodeId,
                value: 5
            }
        );
        assert_eq!(slave(&[0x04]), Lss::Unknown { cs: 0x04 });
        assert_eq!(slave(&[]), Lss::Unknown { cs: 0 });
    }

    proptest::proptest! {
        /// Any frame either way decodes (short ones too), to a service
        /// that is unknown exactly when CiA 305 defines no such specifier
        /// in that direction.
        #[test]
        fn every_frame_decodes_and_unknown_is_what_cia_305_leaves_out(
            from_master in proptest::prelude::any::<bool>(),
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..9),
        ) {
            let lss = Lss::decode(from_master, &data);
            let cs = data.first().copied().unwrap_or(0);
            let defined = if from_master {
                matches!(cs, 0x04 | 0x11 | 0x13 | 0x15 | 0x17 | 0x40..=0x43 | 0x46..=0x4C | 0x51 | 0x5A..=0x5E)
            } else {
                matches!(cs, 0x11 | 0x13 | 0x17 | 0x44 | 0x4F | 0x50 | 0x5A..=0x5E)
            };
            proptest::prop_assert_eq!(lss == Lss::Unknown { cs }, !defined);
            proptest::prop_assert!(!lss.words().is_empty());
        }
    }

    #[test]
    fn answers_and_bit_rates_in_words() {
        let r = |s, e, x| result_words(s, e, x);
        assert_eq!(r(Service::ConfigureNodeId, 0, 0), "ok");
        assert_eq!(
            r(Service::ConfigureNodeId, 1, 0),
            "failed: node-id out of range"
        );
        assert_eq!(
            r(Service::ConfigureBitTiming, 1, 0),
            "failed: bit timing not supported"
        );
        assert_eq!(
            r(Service::Store, 2, 0),
            "failed: storage media access error"
        );
        assert_eq!(
            r(Service::Store, 0xFF, 0x12),
            "failed (manufacturer error 0x12)"
        );
        assert_eq!(bit_rate(0, 2), Some("500 kbit/s"));
        assert_eq!(bit_rate(0, 5), None);
        assert_eq!(bit_rate(1, 0), None);
        assert_eq!(slave(&[0x11, 0]).words(), "answer: node-id ok");
        assert_eq!(master(&[0x11, 5]).slug(), "configure_node_id");
        assert_eq!(slave(&[0x11, 0]).slug(), "configure_node_id");
    }
}
