//! Arbitrary bytes read as a BUSMASTER log (format forced): the reader's own
//! body (well-formed frames, scan and parse agree) and the whole pipeline
//! with the invariants of `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::busmaster(data));
