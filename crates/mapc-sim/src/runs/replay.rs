//! Replaying another simulator's state for vehicle-by-vehicle comparisons (docs/calibration.md): put every
//! vehicle where the other simulator had it, take one step, read every vehicle's next speed.

use crate::error::SimError;
use crate::sim::Simulation;
use crate::spec::SimSpec;

/// One vehicle of a recorded state.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplicaVehicle {
    pub id: String,
    /// Lane name in the recording (SUMO's, e.g. `left_0`, `:center_1_0`).
    pub lane: String,
    /// Front position on that lane (m).
    pub pos: f64,
    pub speed: f64,
    pub speed_factor: f64,
    /// Time spent below 0.1 m/s so far (s).
    pub waiting_s: f64,
}

/// One line of a recorded state file (`tools/sumo_replay/record_states.py`): `{"t": s, "veh": [[id, lane, pos,
/// speed, speed_factor, waiting_s, ...], ...]}` (columns after the sixth are ignored). The error says what is
/// missing; the caller adds the file and line.
pub fn parse_state_line(line: &str) -> Result<(f64, Vec<ReplicaVehicle>), String> {
    let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
    let t = v["t"].as_f64().ok_or("no time `t`")?;
    const ROW: &str = "a vehicle row needs [id, lane, pos, speed, speed_factor, waiting_s]";
    let vehicles = v["veh"]
        .as_array()
        .ok_or("no vehicle list `veh`")?
        .iter()
        .map(|row| {
            let r = row.as_array().ok_or(ROW)?;
            let text = |i: usize| r.get(i).and_then(|x| x.as_str()).ok_or(ROW);
            let num = |i: usize| r.get(i).and_then(|x| x.as_f64()).ok_or(ROW);
            Ok(ReplicaVehicle {
                id: text(0)?.to_string(),
                lane: text(1)?.to_string(),
                pos: num(2)?,
                speed: num(3)?,
                speed_factor: num(4)?,
                waiting_s: num(5)?,
            })
        })
        .collect::<Result<Vec<_>, &str>>()?;
    Ok((t, vehicles))
}

/// A lane of SUMO's Simple Merge (`maps/simple_merge.net.xml`, the network of the SUMO 1.8 reference runs) as (road its route starts at, index of the
/// lane along that route) in mapc's built-in Simple Merge.
pub fn sumo_simple_merge_lane(lane: &str) -> Option<(&'static str, usize)> {
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

/// Replays a recorded Simple Merge state at `time_s` with vehicles of type `vtype` of `spec` (its flows and
/// initial vehicles are ignored), takes one step and returns every placed vehicle's next speed, in input order.
/// Vehicles on lanes the mapping does not know are left out.
pub fn replay_simple_merge_step(
    spec: &SimSpec,
    vtype: usize,
    time_s: f64,
    vehicles: &[ReplicaVehicle],
) -> Result<Vec<(String, f64)>, SimError> {
    let mut s = spec.clone();
    s.flows.clear();
    s.initial.clear();
    s.start_time_s = time_s;
    let mut sim = Simulation::from_spec(s, 0)?;
    let mut placed = Vec::with_capacity(vehicles.len());
    for v in vehicles {
        let Some((from, k)) = sumo_simple_merge_lane(&v.lane) else {
            continue;
        };
        let road = from
            .parse()
            .map_err(|e: String| SimError::Spec(format!("road {from}: {e}")))?;
        let id = sim.place_replica(vtype, road, k, v.pos, v.speed, v.speed_factor, v.waiting_s)?;
        placed.push((v.id.clone(), id));
    }
    sim.step()?;
    Ok(placed
        .into_iter()
        .filter_map(|(name, id)| sim.vehicle(id).map(|vv| (name, vv.speed)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_line_is_read_and_a_bad_one_says_what_is_missing() {
        let (t, v) = parse_state_line(
            r#"{"t": 400.5, "veh": [["flow_00.3", "left_0", 412.5, 7.25, 1.04, 0.0, "flow_00.2", 9.1]]}"#,
        )
        .unwrap();
        assert_eq!(t, 400.5);
        assert_eq!(v.len(), 1);
        assert_eq!(
            (v[0].id.as_str(), v[0].lane.as_str()),
            ("flow_00.3", "left_0")
        );
        assert_eq!(
            (v[0].pos, v[0].speed, v[0].speed_factor),
            (412.5, 7.25, 1.04)
        );
        let short = parse_state_line(r#"{"t": 1.0, "veh": [["a", "left_0", 3.0]]}"#).unwrap_err();
        assert!(short.contains("speed_factor"), "{short}");
        assert!(
            parse_state_line(r#"{"veh": []}"#)
                .unwrap_err()
                .contains("`t`")
        );
        assert!(parse_state_line("{").is_err());
    }
}
