//! Arbitrary bytes read as candump screen output (format forced); the body and
//! its invariants are `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::candump_screen(data));
