//! The renderers: each implements the analysis's [`Sink`] trait and prints
//! what a run reports in one format (table, JSON, NDJSON, SVG, HTML). The
//! JSON key names are a public contract (docs/guide/output.md).
//!
//! [`Sink`]: crate::analyze::Sink

pub mod chart;
pub mod csv;
pub mod explain;
pub mod format;
pub mod html;
pub mod json;
pub mod jsonw;
pub mod ndjson;
pub mod ordered;
pub mod svg;
pub mod table;
pub mod timefmt;
