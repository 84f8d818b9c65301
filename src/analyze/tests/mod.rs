//! Properties of the whole pipeline that need its insides (options such as
//! block size, threads and spill threshold; the ndjson renderer; the line
//! parsers): formerly integration tests, now unit tests.
//!
//! - [`conservation`]: no EMCY is lost or invented, whatever surrounds it;
//! - [`parallel`]: output never depends on how the input was split or how
//!   many threads read it.
//!
//! The random frames and their renderings are the integration tests'
//! (`tests/integration/support/frames.rs`), one file compiled in both.

#[path = "../../../tests/integration/support/frames.rs"]
mod frames;

mod conservation;
mod parallel;
