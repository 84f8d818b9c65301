//! Arbitrary bytes as a DCF/EDS file for a node the first byte picks, and
//! as `--pdo` / `--dcf` option text (`emcy_decode::fuzzing::dcf`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| emcy_decode::fuzzing::dcf(data));
