//! Vehicle-by-vehicle comparison with another simulator (docs/calibration.md): reads states of the Simple Merge
//! as JSON lines (one line per step: `{"t": s, "veh": [[id, lane, pos, speed, speed_factor, waiting_s], ...]}`,
//! lanes named as in SUMO's merge network), replays each state in mapc, takes one step and prints every vehicle's
//! next speed as JSON lines (`{"t": s, "next": {id: speed}}`).
//!
//! `cargo run --release -p mapc-sim --example replay_step -- STATES.jsonl > NEXT.jsonl`

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};
use std::io::{BufRead, Write};

/// SUMO lane of the Simple Merge -> (road the route starts at, lane index along that route).
fn route_lane(lane: &str) -> Option<(&'static str, usize)> {
    Some(match lane {
        "inflow_highway_0" => ("R0", 0),
        ":left_0_0" => ("R0", 1),
        "left_0" => ("R0", 2),
        ":center_1_0" => ("R0", 3),
        "center_0" => ("R0", 4),
        "inflow_merge_0" => ("R2", 0),
        ":bottom_0_0" => ("R2", 1),
        "bottom_0" => ("R2", 2),
        ":center_0_0" => ("R2", 3),
        _ => return None,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: replay_step STATES.jsonl")?;
    let rs = ResolvedScenario::load("simple_merge")?;
    let mut spec = spec_from_scenario(&rs)?;
    spec.flows.clear();
    spec.initial.clear();
    let human = spec
        .vehicle_types
        .iter()
        .position(|t| t.name == "human")
        .ok_or("no human type")?;
    let out = std::io::stdout();
    let mut out = out.lock();
    for line in std::io::BufReader::new(std::fs::File::open(&path)?).lines() {
        let v: serde_json::Value = serde_json::from_str(&line?)?;
        let t = v["t"].as_f64().ok_or("t")?;
        let mut s = spec.clone();
        s.start_time_s = t;
        let mut sim = Simulation::from_spec(s, 0)?;
        let mut ids = Vec::new();
        for row in v["veh"].as_array().ok_or("veh")? {
            let r = row.as_array().ok_or("row")?;
            let Some((from, k)) = route_lane(r[1].as_str().ok_or("lane")?) else {
                continue;
            };
            let id = sim.place_replica(
                human,
                from.parse()?,
                k,
                r[2].as_f64().ok_or("pos")?,
                r[3].as_f64().ok_or("speed")?,
                r[4].as_f64().ok_or("sf")?,
                r[5].as_f64().ok_or("wait")?,
            )?;
            ids.push((r[0].as_str().ok_or("id")?.to_string(), id));
        }
        sim.step()?;
        let next: serde_json::Map<String, serde_json::Value> = ids
            .iter()
            .filter_map(|(name, id)| sim.vehicle(*id).map(|vv| (name.clone(), vv.speed.into())))
            .collect();
        writeln!(out, "{}", serde_json::json!({"t": t, "next": next}))?;
    }
    Ok(())
}
