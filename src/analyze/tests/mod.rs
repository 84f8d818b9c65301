//! Properties of the whole pipeline that need its insides (options such as
//! block size, threads and spill threshold; the ndjson renderer; the line
//! parsers): formerly integration tests, now unit tests.
//!
//! - [`conservation`]: no EMCY is lost or invented, whatever surrounds it;
//! - [`parallel`]: output never depends on how the input was split or how
//!   many threads read it;
//! - [`threads`]: nor on how many threads the system would start;
//! - [`active`]: an event's size does not grow with its node's active errors;
//! - [`folds`]: nor on the reader folding steady heartbeats;
//! - [`nodes_cap`]: the node table is bounded, and its end is an error.
//!
//! The random frames and their renderings are the integration tests'
//! (`tests/integration/support/frames.rs`), one file compiled in both.

#[path = "../../../tests/integration/support/frames.rs"]
mod frames;

mod active;
mod conservation;
mod folds;
mod nodes_cap;
mod parallel;
mod threads;
