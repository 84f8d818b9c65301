//! Arbitrary bytes read as a pcap / pcapng capture (format forced): the reader's own
//! body (well-formed frames, no endless loop, bounded buffers) and the whole
//! pipeline with the invariants of `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::pcap(data));
