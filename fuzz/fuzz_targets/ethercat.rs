//! Arbitrary bytes as an EtherCAT frame: the datagram and mailbox walk's own
//! checks, then the frame inside an Ethernet / VLAN / cooked / UDP packet of
//! a pcapng, through the pcap reader (hot loop and general path agree) and
//! the whole pipeline (`emcy_decode::fuzzing::ethercat`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::ethercat(data));
