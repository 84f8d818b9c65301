//! Many small files (`emcy-decode logs/*.log`): each is analysed on its own
//! thread into a recording, and the recordings are replayed into the one
//! sink in argument order, so the output is byte for byte what reading
//! them one after another gives. Only small files go this way (a recording
//! holds a file's events); big ones are read in order with block
//! parallelism instead.

use std::collections::BTreeMap;
use std::io;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use super::analysis::{Analysis, OutputError};
use super::diagnostics::DiagnosticLog;
use super::event::{
    BootEvent, Bus, BusEvent, Diagnostic, EmcyEvent, Health, HealthEvent, InputReport,
};
use super::options::Options;
use super::sink::Sink;
use super::threads::spawn_scoped;
use crate::canopen::NodeId;
use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{Emcy, Warning};
use crate::canopen::profile::Decoded;
use crate::canopen::profile_choice::Chosen;
use crate::timeline::State;
use crate::trace::Timestamp;
use crate::trace::input::{ReadMode, Source};

/// One event, owned.
enum Recorded {
    Begin(String),
    Emcy(Box<OwnedEmcy>),
    Boot {
        file: String,
        line: u64,
        time: Option<Timestamp>,
        channel: String,
        node: NodeId,
        cleared: Vec<u16>,
    },
    Health(Box<OwnedHealth>),
    Bus(Box<OwnedBus>),
    End,
}

struct OwnedBus {
    file: String,
    line: u64,
    time: Option<Timestamp>,
    channel: String,
    bus: Bus,
}

struct OwnedHealth {
    file: String,
    line: u64,
    time: Option<Timestamp>,
    channel: String,
    node: NodeId,
    health: Health,
}

struct OwnedEmcy {
    file: String,
    line: u64,
    time: Option<Timestamp>,
    channel: String,
    node: NodeId,
    cob_id: Option<u32>,
    data: Vec<u8>,
    emcy: Emcy,
    info: CodeInfo,
    description: String,
    transition: Option<u8>,
    state: State,
    active: Vec<u16>,
    active_total: usize,
    cleared: Vec<u16>,
    warnings: Vec<Warning>,
    profile: Chosen,
    decoded: Option<Decoded>,
    bus_error: Option<Timestamp>,
}

/// A sink that keeps everything for a later replay.
#[derive(Default)]
struct Recorder {
    events: Vec<Recorded>,
}

impl Sink for Recorder {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.events.push(Recorded::Begin(file.to_string()));
        Ok(())
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        self.events.push(Recorded::Emcy(Box::new(OwnedEmcy {
            file: ev.file.to_string(),
            line: ev.line,
            time: ev.time,
            channel: ev.channel.to_string(),
            node: ev.node,
            cob_id: ev.cob_id,
            data: ev.data.to_vec(),
            emcy: *ev.emcy,
            info: *ev.info,
            description: ev.description.to_string(),
            transition: ev.transition,
            state: ev.state,
            active: ev.active.to_vec(),
            active_total: ev.active_total,
            cleared: ev.cleared.to_vec(),
            warnings: ev.warnings.to_vec(),
            profile: ev.profile,
            decoded: ev.decoded.cloned(),
            bus_error: ev.bus_error,
        })));
        Ok(())
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        self.events.push(Recorded::Boot {
            file: ev.file.to_string(),
            line: ev.line,
            time: ev.time,
            channel: ev.channel.to_string(),
            node: ev.node,
            cleared: ev.cleared.to_vec(),
        });
        Ok(())
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        self.events.push(Recorded::Health(Box::new(OwnedHealth {
            file: ev.file.to_string(),
            line: ev.line,
            time: ev.time,
            channel: ev.channel.to_string(),
            node: ev.node,
            health: ev.health.clone(),
        })));
        Ok(())
    }

    fn bus(&mut self, ev: &BusEvent<'_>) -> io::Result<()> {
        self.events.push(Recorded::Bus(Box::new(OwnedBus {
            file: ev.file.to_string(),
            line: ev.line,
            time: ev.time,
            channel: ev.channel.to_string(),
            bus: ev.bus.clone(),
        })));
        Ok(())
    }

    fn end_input(&mut self, _input: &InputReport) -> io::Result<()> {
        self.events.push(Recorded::End);
        Ok(())
    }

    fn finish(&mut self, _inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        Ok(())
    }
}

/// What one file's analysis left for the replay.
pub struct FileResult {
    events: Vec<Recorded>,
    /// What the analysis wrote to stderr.
    stderr: Vec<u8>,
    diagnostics: Vec<Diagnostic>,
    /// `None` when the file could not be opened (the message is in stderr).
    pub analysis: Option<Analysis>,
}

impl FileResult {
    /// Replays the file into the real sink and stderr.
    pub fn replay<E: io::Write>(
        self,
        sink: &mut dyn Sink,
        log: &mut DiagnosticLog<E>,
    ) -> Result<Option<Analysis>, OutputError> {
        log.replay(&self.stderr, self.diagnostics);
        for ev in self.events {
            match ev {
                Recorded::Begin(file) => sink.begin_input(&file),
                Recorded::Emcy(e) => sink.emcy(&EmcyEvent {
                    file: &e.file,
                    line: e.line,
                    time: e.time,
                    channel: &e.channel,
                    node: e.node,
                    cob_id: e.cob_id,
                    data: &e.data,
                    emcy: &e.emcy,
                    info: &e.info,
                    description: &e.description,
                    transition: e.transition,
                    state: e.state,
                    active: &e.active,
                    active_total: e.active_total,
                    cleared: &e.cleared,
                    warnings: &e.warnings,
                    profile: e.profile,
                    decoded: e.decoded.as_ref(),
                    bus_error: e.bus_error,
                }),
                Recorded::Boot {
                    file,
                    line,
                    time,
                    channel,
                    node,
                    cleared,
                } => sink.boot(&BootEvent {
                    file: &file,
                    line,
                    time,
                    channel: &channel,
                    node,
                    cleared: &cleared,
                }),
                Recorded::Health(h) => sink.health(&HealthEvent {
                    file: &h.file,
                    line: h.line,
                    time: h.time,
                    channel: &h.channel,
                    node: h.node,
                    health: &h.health,
                }),
                Recorded::Bus(b) => sink.bus(&BusEvent {
                    file: &b.file,
                    line: b.line,
                    time: b.time,
                    channel: &b.channel,
                    bus: &b.bus,
                }),
                Recorded::End => match &self.analysis {
                    Some(a) => sink.end_input(&a.report),
                    None => Ok(()),
                },
            }
            .map_err(OutputError)?;
        }
        Ok(self.analysis)
    }
}

/// Analyses one file completely, recording its output (`quiet`: as the
/// run's log would print it, so stderr does not depend on the threads).
fn record(source: &Source, opts: &Options, quiet: bool) -> FileResult {
    let mut log = DiagnosticLog::new(Vec::new());
    log.quiet = quiet;
    let mut recorder = Recorder::default();
    // A Recorder never fails to write.
    let analysis = super::analyze_source(
        source,
        ReadMode::Finite,
        opts,
        |_| 1,
        |_, reader| reader,
        &mut recorder,
        &mut log,
    )
    .ok();
    let diagnostics = std::mem::take(&mut log.collected);
    FileResult {
        events: recorder.events,
        stderr: log.into_inner(),
        diagnostics,
        analysis,
    }
}

/// Analyses `sources` on up to `threads` threads and hands each result to
/// `emit` in order, as soon as it and all before it are done. At most
/// `2 * threads` results wait for their turn, so memory stays bounded.
/// `quiet` is the run's `--quiet`. Threads the system will not start are
/// done without; with none, this thread reads the files one by one.
pub fn run_parallel(
    sources: &[Source],
    opts: &Options,
    threads: usize,
    quiet: bool,
    mut emit: impl FnMut(FileResult) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let next = AtomicUsize::new(0);
    let window = 2 * threads.max(1);
    // Tickets bound how far workers run ahead of the emitter.
    let (ticket_tx, ticket_rx) = mpsc::sync_channel::<()>(window);
    for _ in 0..window {
        let _ = ticket_tx.send(());
    }
    let ticket_rx = std::sync::Mutex::new(ticket_rx);
    let (tx, rx) = mpsc::channel::<(usize, FileResult)>();
    std::thread::scope(|scope| {
        let mut started = 0;
        // No more threads than files: each would only wait.
        for _ in 0..threads.clamp(1, sources.len().max(1)) {
            let tx = tx.clone();
            let (next, ticket_rx) = (&next, &ticket_rx);
            let spawned = spawn_scoped(scope, move || {
                loop {
                    let got_ticket = ticket_rx.lock().map(|r| r.recv().is_ok()).unwrap_or(false);
                    if !got_ticket || opts.cancel.is_cancelled() {
                        return;
                    }
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(source) = sources.get(i) else {
                        return;
                    };
                    if tx.send((i, record(source, opts, quiet))).is_err() {
                        return;
                    }
                }
            });
            if !spawned {
                break;
            }
            started += 1;
        }
        drop(tx);
        if started == 0 {
            return sources
                .iter()
                .take_while(|_| !opts.cancel.is_cancelled())
                .try_for_each(|source| emit(record(source, opts, quiet)));
        }
        let mut waiting = BTreeMap::new();
        let mut turn = 0;
        let result = (|| {
            for (i, res) in rx.iter() {
                waiting.insert(i, res);
                while let Some(res) = waiting.remove(&turn) {
                    emit(res)?;
                    turn += 1;
                    let _ = ticket_tx.send(());
                }
            }
            Ok(())
        })();
        // On an output error, let the workers stop: no more tickets.
        drop(ticket_tx);
        result
    })
}
