//! Arbitrary bytes read as an IXXAT MiniMon V3 ASCII trace (format forced):
//! the reader's own body (well-formed frames, the title identifies the
//! format) and the whole pipeline with the invariants of
//! `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::ixxat(data));
