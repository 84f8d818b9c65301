//! The output trait of the analysis: whatever prints or keeps its results
//! implements [`Sink`]. The analysis never knows which sink it feeds
//! (as ripgrep's searcher owns `Sink` and never imports the printer).

use std::io;

use super::event::{BootEvent, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport};

/// Receives events as they are decoded, then the per-input and final
/// summaries. Output errors (a closed pipe) stop the run.
pub trait Sink {
    fn begin_input(&mut self, _file: &str) -> io::Result<()> {
        Ok(())
    }
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()>;
    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()>;
    /// NMT, heartbeat, SDO abort and error history events; sinks that show
    /// only EMCYs leave them out.
    fn health(&mut self, _event: &HealthEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    /// Error bursts, bus-offs and LSS services; sinks that show only
    /// nodes leave them out.
    fn bus(&mut self, _event: &BusEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn end_input(&mut self, _input: &InputReport) -> io::Result<()> {
        Ok(())
    }
    fn finish(&mut self, inputs: &[InputReport], diagnostics: &[Diagnostic]) -> io::Result<()>;
}

/// `--view summary` for the JSON formats: node and input objects only.
pub struct WithoutEvents<R>(pub R);

impl<R: Sink> Sink for WithoutEvents<R> {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.0.begin_input(file)
    }
    fn emcy(&mut self, _event: &EmcyEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn boot(&mut self, _event: &BootEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        self.0.end_input(input)
    }
    fn finish(&mut self, inputs: &[InputReport], diagnostics: &[Diagnostic]) -> io::Result<()> {
        self.0.finish(inputs, diagnostics)
    }
}

/// Receives events and throws them away: for callers that need only the
/// per-input reports (`baseline`, `check`).
pub struct Discard;

impl Sink for Discard {
    fn emcy(&mut self, _: &EmcyEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn boot(&mut self, _: &BootEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn finish(&mut self, _: &[InputReport], _: &[Diagnostic]) -> io::Result<()> {
        Ok(())
    }
}
