//! The library in a few lines: every EMCY of one node in a trace, described
//! by a vendor profile, and the node's state at the end.
//!
//! `cargo run --example node_timeline -- fixtures/s300.log 1 kollmorgen`

use std::error::Error;
use std::fs::File;

use emcy_decode::{At, Emcy, NodeTimeline, Profile, Record, TraceReader};

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "fixtures/s300.log".into());
    let node: u16 = args.next().map_or(Ok(1), |n| n.parse())?;
    let profile = Profile::builtin(&args.next().unwrap_or_else(|| "cia402".into()))
        .ok_or("no such built-in profile")?;

    let mut timeline = NodeTimeline::new();
    for record in TraceReader::new(File::open(path)?) {
        let Record::Frame(frame) = record? else {
            continue;
        };
        if frame.emcy_node() != Some(node) {
            continue;
        }
        let emcy = Emcy::decode(&frame.data)?;
        let at = At {
            time: frame.time,
            line: frame.line,
        };
        let step = timeline.emcy(&emcy, at, &mut Vec::new());
        println!(
            "line {}: {:#06x} {}",
            frame.line,
            emcy.code,
            profile.describe(emcy.code)
        );
        for error in &step.closed {
            let lasted = error.duration().map_or("?".into(), |d| d.to_string());
            println!("  {:#06x} cleared after {lasted} s", error.code);
        }
    }
    println!("node {node} ends {}", timeline.state().slug());
    Ok(())
}
