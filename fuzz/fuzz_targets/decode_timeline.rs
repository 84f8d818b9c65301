//! Bytes as a script of frames through the EMCY decoder, the node timelines
//! (with and without error status bits), SDO parsing and the error history;
//! the body is `emcy_decode::fuzzing::decode_timeline`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::decode_timeline(data));
