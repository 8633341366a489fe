//! Where the initial vehicles stand at time 0, and the check that no two of them overlap.
//!
//! Flow's uniform placement (the original's `InitialConfig` default) spaces the vehicles by the total length of
//! all roads divided by their count and lays them over every road, one after the other, in the order of the
//! network's edge starts: the Simple Merge's main line (with its internal lanes) first, then its ramp. mapc lays
//! them the same way: along the main line (internal lanes counted as driven length), then over the other roads
//! in the graph's road order (an imported network's edges are laid in the order of their ids in Flow). Since
//! the roads together are longer than the spacing times the count, every vehicle lands on a road.

use crate::error::SimError;
use crate::network::{LaneIdx, Network};
use crate::spec::{InitialVehicleSpec, VehicleTypeSpec};
use mapc_graph::{LaneGraph, RoadId};
use std::collections::HashSet;

/// Initial vehicles spaced evenly by the total length of all roads divided by their count, laid out from the
/// start of the main line and then over the other roads; a vehicle that would land inside a junction goes to
/// the start of the next road, and the ones after it move on by as much.
pub(crate) fn initial_placement(
    g: &LaneGraph,
    net: &Network,
    main_line: &[RoadId],
    count: usize,
    speed: f64,
    vehicle_type: usize,
) -> Result<Vec<InitialVehicleSpec>, SimError> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let Some(&first) = main_line.first() else {
        return Err(SimError::Spec(
            "initial vehicles need a flow to define the main line".into(),
        ));
    };
    // One stretch per run of connected lanes: the main line, then each other road on its own.
    let main_lanes = net.route(g, first, main_line.last().copied())?;
    let on_main: HashSet<LaneIdx> = main_lanes.iter().copied().collect();
    let mut stretches = vec![main_lanes];
    stretches.extend(
        g.roads
            .iter()
            .map(|r| net.road_lane[&r.id])
            .filter(|l| !on_main.contains(l))
            .map(|l| vec![l]),
    );
    let lanes: Vec<(usize, LaneIdx)> = stretches
        .iter()
        .enumerate()
        .flat_map(|(s, ls)| ls.iter().map(move |&l| (s, l)))
        .collect();
    let total: f64 = g.roads.iter().map(|r| r.length_m).sum();
    let spacing = total / count as f64;
    let mut out = Vec::with_capacity(count);
    // How far vehicles moved out of junctions have pushed the ones after them (Flow carries on from the road's
    // start, so the spacing behind a moved vehicle stays whole).
    let mut pushed = 0.0;
    for i in 0..count {
        let mut x = i as f64 * spacing + pushed;
        let mut placed = false;
        for (k, &(stretch, l)) in lanes.iter().enumerate() {
            let len = net.lanes[l as usize].length;
            if x < len {
                let (lane, pos) = match net.road_of(l) {
                    Some(_) => (l, x),
                    // inside a junction: the start of the next road (a route never ends in a junction)
                    None => {
                        debug_assert_eq!(lanes[k + 1].0, stretch);
                        pushed += len - x;
                        (lanes[k + 1].1, 0.0)
                    }
                };
                out.push(InitialVehicleSpec {
                    road: net.road_ids[net.road_of(lane).unwrap()],
                    pos_m: pos,
                    speed,
                    vehicle_type,
                });
                placed = true;
                break;
            }
            x -= len;
        }
        if !placed {
            return Err(SimError::Spec(format!(
                "initial vehicle {i} falls past the end of the roads"
            )));
        }
    }
    Ok(out)
}

/// Refuses initial vehicles that overlap: each must stand at least its leader's length plus its own minimum
/// gap behind any vehicle ahead of it on its road or, across junctions, on the roads it can drive into.
pub(crate) fn check_initial_spacing(
    net: &Network,
    initial: &[InitialVehicleSpec],
    vehicle_types: &[VehicleTypeSpec],
) -> Result<(), SimError> {
    let lane_of = |v: &InitialVehicleSpec| {
        net.road_lane
            .get(&v.road)
            .copied()
            .ok_or_else(|| SimError::Network(format!("unknown road {}", v.road)))
    };
    let lanes: Vec<LaneIdx> = initial.iter().map(lane_of).collect::<Result<_, _>>()?;
    let room = |t: usize| vehicle_types.get(t).map_or(0.0, |t| t.length + t.min_gap);
    let farthest = (0..vehicle_types.len()).map(room).fold(0.0, f64::max);
    for (i, a) in initial.iter().enumerate() {
        let Some(ta) = vehicle_types.get(a.vehicle_type) else {
            continue; // SimSpec::validate names it
        };
        // (lane, distance from a's front to the start of that lane), walked downstream while within reach
        let mut todo = vec![(lanes[i], -a.pos_m)];
        while let Some((lane, start)) = todo.pop() {
            for (j, b) in initial.iter().enumerate() {
                if j == i || lanes[j] != lane {
                    continue;
                }
                let ahead = start + b.pos_m;
                // b behind a, or on the same spot and reported from the lower index
                if ahead < 0.0 || (ahead == 0.0 && j < i) {
                    continue;
                }
                let need = vehicle_types
                    .get(b.vehicle_type)
                    .map_or(0.0, |tb| tb.length)
                    + ta.min_gap;
                if ahead < need {
                    return Err(SimError::Spec(format!(
                        "initial vehicles {i} and {j} overlap: {j} stands {ahead:.2} m ahead of {i} (on road {} at \
                         {:.2} m and road {} at {:.2} m), less than its length plus the minimum gap ({need} m)",
                        a.road, a.pos_m, b.road, b.pos_m
                    )));
                }
            }
            let end = start + net.lanes[lane as usize].length;
            if end < farthest {
                todo.extend(net.successors(lane).into_iter().map(|l| (l, end)));
            }
        }
    }
    Ok(())
}
