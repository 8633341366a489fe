//! Vehicle-by-vehicle comparison with SUMO (docs/calibration.md): reads states of the Simple Merge as JSON lines
//! (one line per step: `{"t": s, "veh": [[id, lane, pos, speed, speed_factor, waiting_s, ...], ...]}`, lanes
//! named as in SUMO's merge network; `tools/sumo_replay/record_states.py` writes them), replays each state in mapc,
//! takes one step and prints every vehicle's next speed as JSON lines (`{"t": s, "next": {id: speed}}`).
//!
//! `cargo run --release -p mapc-sim --example replay_step -- STATES.jsonl > NEXT.jsonl`

use mapc_scenario::ResolvedScenario;
use mapc_sim::replay::{ReplicaVehicle, replay_simple_merge_step};
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
        let at = |what: &dyn std::fmt::Display| format!("{path}:{}: {what}", n + 1);
        let v: serde_json::Value = serde_json::from_str(&line?).map_err(|e| at(&e))?;
        let t = v["t"].as_f64().ok_or_else(|| at(&"no time `t`"))?;
        let vehicles = parse_vehicles(&v).map_err(|e| at(&e))?;
        let next: serde_json::Map<String, serde_json::Value> =
            replay_simple_merge_step(&spec, human, t, &vehicles)?
                .into_iter()
                .map(|(id, speed)| (id, speed.into()))
                .collect();
        writeln!(out, "{}", serde_json::json!({"t": t, "next": next}))?;
    }
    Ok(())
}

fn parse_vehicles(v: &serde_json::Value) -> Result<Vec<ReplicaVehicle>, &'static str> {
    let num = |r: &[serde_json::Value], i: usize| {
        r.get(i)
            .and_then(|x| x.as_f64())
            .ok_or("a vehicle row needs [id, lane, pos, speed, speed_factor, waiting_s]")
    };
    v["veh"]
        .as_array()
        .ok_or("veh")?
        .iter()
        .map(|row| {
            let r = row.as_array().ok_or("row")?;
            Ok(ReplicaVehicle {
                id: r.first().and_then(|x| x.as_str()).ok_or("id")?.to_string(),
                lane: r.get(1).and_then(|x| x.as_str()).ok_or("lane")?.to_string(),
                pos: num(r, 2)?,
                speed: num(r, 3)?,
                speed_factor: num(r, 4)?,
                waiting_s: num(r, 5)?,
            })
        })
        .collect()
}
