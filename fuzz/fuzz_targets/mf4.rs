//! Arbitrary bytes read as an MF4 (ASAM MDF 4) file (format forced): the
//! reader's own body (well-formed frames, no endless loop, bounded queues
//! and metadata) and the whole pipeline with the invariants of
//! `emcy_decode::fuzzing::reader`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::mf4(data));
