//! Arbitrary bytes (gzip when they start with its magic), format detected,
//! read sequentially and in parallel with tiny blocks, rendered as ndjson,
//! JSON and table; the body is `emcy_decode::fuzzing::detect`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::detect(data));
