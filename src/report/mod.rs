//! The renderers: each implements the analysis's [`Sink`] trait and prints
//! what a run reports in one format (table, JSON, NDJSON, SVG, HTML). The
//! JSON key names are a public contract (README).
//!
//! [`Sink`]: crate::analyze::Sink

pub(crate) mod chart;
pub(crate) mod csv;
pub(crate) mod explain;
pub(crate) mod format;
pub(crate) mod html;
pub(crate) mod json;
pub(crate) mod jsonw;
pub(crate) mod ndjson;
pub(crate) mod ordered;
pub(crate) mod svg;
pub(crate) mod table;
pub(crate) mod timefmt;
