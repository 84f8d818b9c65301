//! Arbitrary bytes read as a candump log (format forced); the body and
//! its invariants are `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::candump_log(data));
