//! Vehicle-by-vehicle comparison with SUMO (docs/calibration.md): reads states of the Simple Merge as JSON lines
//! (one line per step: `{"t": s, "veh": [[id, lane, pos, speed, speed_factor, waiting_s, ...], ...]}`, lanes
//! named as in SUMO's merge network; `tools/sumo_replay/record_states.py` writes them), replays each state in mapc,
//! takes one step and prints every vehicle's next speed as JSON lines (`{"t": s, "next": {id: speed}}`).
//!
//! `cargo run --release -p mapc-sim --example replay_step -- STATES.jsonl > NEXT.jsonl`

use mapc_scenario::ResolvedScenario;
use mapc_sim::runs::replay::{parse_state_line, replay_simple_merge_step};
use mapc_sim::spec_from_scenario;
use std::io::{BufRead, Write};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: replay_step STATES.jsonl")?;
    let spec = spec_from_scenario(&ResolvedScenario::load("simple_merge")?)?;
    let human = spec
        .vehicle_types
        .iter()
        .position(|t| t.name == "human")
        .ok_or("no human type")?;
    let out = std::io::stdout();
    let mut out = out.lock();
    for (n, line) in std::io::BufReader::new(std::fs::File::open(&path)?)
        .lines()
        .enumerate()
    {
        let (t, vehicles) =
            parse_state_line(&line?).map_err(|e| format!("{path}:{}: {e}", n + 1))?;
        let next: serde_json::Map<String, serde_json::Value> =
            replay_simple_merge_step(&spec, human, t, &vehicles)?
                .into_iter()
                .map(|(id, speed)| (id, speed.into()))
                .collect();
        writeln!(out, "{}", serde_json::json!({"t": t, "next": next}))?;
    }
    Ok(())
}
