//! Vehicle by vehicle against SUMO 1.8's own run: scenarios/sumo/ramp_metering_1x3 made deterministic (sigma 0,
//! speed deviation 0, departPos `base`), where every vehicle of mapc drives as SUMO's did. The figures below were
//! recorded from SUMO 1.8 (`sumo -c` of that copy, seed 0, `--fcd-output` and `--tripinfo-output`; the copy is
//! what [`deterministic_1x3`] writes).

use super::*;
use crate::runs::scenario::spec_from_scenario;
use std::path::PathBuf;

/// ramp_metering_1x3 with its routes made deterministic, in a folder of its own; `end` s long.
fn deterministic_1x3(tag: &str, end: u32) -> PathBuf {
    let src = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_metering_1x3"
    ));
    let dir = std::env::temp_dir().join(format!("mapc_det1x3_{tag}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for f in ["1ramp_1x3.net.xml", "1ramp_1x3.add.xml"] {
        std::fs::copy(src.join(f), dir.join(f)).unwrap();
    }
    let routes = std::fs::read_to_string(src.join("1ramp_1x3.rou.xml"))
        .unwrap()
        .replace("sigma=\"0.9\"", "sigma=\"0\" speedDev=\"0\"")
        .replace("sigma=\"0.8\"", "sigma=\"0\" speedDev=\"0\"")
        .replace("departPos=\"random\"", "departPos=\"base\"");
    std::fs::write(dir.join("1ramp_1x3.rou.xml"), routes).unwrap();
    let cfg = std::fs::read_to_string(src.join("1ramp_1x3.sumocfg"))
        .unwrap()
        .replace(
            "<begin value=\"0\"/>",
            &format!("<begin value=\"0\"/><end value=\"{end}\"/>"),
        );
    std::fs::write(dir.join("1ramp_1x3.sumocfg"), cfg).unwrap();
    dir.join("1ramp_1x3.sumocfg")
}

/// The run of the copy up to `until` s, with each vehicle's flow and number recorded; `junction_changes`: SUMO's
/// lane changing on junction connections side by side.
fn run_until(tag: &str, until: f64, junction_changes: bool) -> Simulation {
    let cfg = deterministic_1x3(tag, 200);
    let rs = mapc_scenario::ResolvedScenario::load(cfg.to_str().unwrap()).unwrap();
    let mut spec = spec_from_scenario(&rs).unwrap();
    spec.sumo_junction_lane_changes = junction_changes;
    let mut sim = Simulation::from_spec(spec, 0).unwrap();
    sim.record_origins();
    step_until(&mut sim, until);
    sim
}

/// The vehicle number `n` of flow `flow` (0: main_con, 4: off_ramp_con).
fn vehicle(sim: &Simulation, flow: usize, n: u32) -> VehicleId {
    (0..sim.veh.len() as VehicleId)
        .find(|&id| sim.vehicle_origin(id) == Some((flow, n)))
        .expect("the vehicle was created")
}

#[test]
fn lane_changing_on_connections_side_by_side_slows_a_driver_as_sumo_does() {
    // main_con.2 crosses the three-lane connection from main_road to acceleration_area; beside it main_con.3 wants
    // its lane and asks it to let it in: SUMO's FCD has it at 20.97 m/s at 34 s (the end of the step that starts
    // then), 22.22 without the pass on the connection
    let speed_at_34 = |junction_changes: bool| {
        let sim = run_until(&format!("lc{junction_changes}"), 35.0, junction_changes);
        sim.veh[vehicle(&sim, 0, 2) as usize].speed
    };
    let with = speed_at_34(true);
    assert!((with - 20.97).abs() < 0.01, "{with}");
    let without = speed_at_34(false);
    assert!((without - 22.22).abs() < 0.01, "{without}");
}

#[test]
fn departures_are_tried_in_the_order_they_were_due_as_sumo_tries_them() {
    // at 38 s: off_ramp_con.1 (due 36.364 s, refused at 37 s) enters entry_0 first, then main_con.57 (37.335 s)
    // entry_2 and main_con.58 (37.990 s: SUMO's period of 655 ms) entry_1 (SUMO's trip-info)
    let sim = run_until("order", 39.0, true);
    let entered = |flow: usize, n: u32| {
        let v = &sim.veh[vehicle(&sim, flow, n) as usize];
        let entry = sim.routes[v.route as usize].lanes[0];
        // mapc stamps a departure with the end of its step, SUMO with its begin
        (
            v.depart_s - sim.spec.step_s,
            sim.lane_at(entry as usize).index,
        )
    };
    assert_eq!(entered(4, 1), (38.0, 0));
    assert_eq!(entered(0, 57), (38.0, 2));
    assert_eq!(entered(0, 58), (38.0, 1));
    let due = sim.veh[vehicle(&sim, 0, 58) as usize].due_s;
    assert!((due - 37.99).abs() < 1e-9, "{due}");
}

#[test]
fn connections_side_by_side_with_priority_form_groups_right_to_left() {
    let cfg = deterministic_1x3("groups", 10);
    let rs = mapc_scenario::ResolvedScenario::load(cfg.to_str().unwrap()).unwrap();
    let net = Network::from_graph(&rs.graph).unwrap();
    // each group by the SUMO edges its connections join, and its size: the acceleration lane ends before
    // end_main_road, so the three connections from the lanes beside it merge with nothing and form a group; the
    // off-ramp's diverge and the ramp's merge have one connection each
    let edge = |lane: LaneIdx| match net.lanes[lane as usize].kind {
        LaneKind::Road(r) => rs.graph.roads[r].provenance.sumo_ids[0].clone(),
        LaneKind::Via(_) => unreachable!("a connection's ends are roads"),
    };
    let mut groups: Vec<(String, String, usize)> = net
        .via_groups
        .iter()
        .map(|g| {
            let LaneKind::Via(k) = net.lanes[g[0] as usize].kind else {
                unreachable!("a group holds connections")
            };
            let lk = &net.links[k as usize];
            (edge(lk.from_lane), edge(lk.to_lane), g.len())
        })
        .collect();
    groups.sort();
    let want = [
        ("acceleration_area", "end_main_road", 3),
        ("entry", "off_ramp_up_stream", 4),
        ("main_road", "acceleration_area", 3),
        ("off_ramp_beginning", "off_ramp", 2),
        ("off_ramp_up_stream", "main_road", 3),
    ];
    let want: Vec<(String, String, usize)> = want
        .iter()
        .map(|&(a, b, n)| (a.to_string(), b.to_string(), n))
        .collect();
    assert_eq!(groups, want);
    for g in &net.via_groups {
        let places: Vec<_> = g
            .iter()
            .map(|&l| net.via_beside[l as usize].unwrap())
            .collect();
        for (i, b) in places.iter().enumerate() {
            assert_eq!(b.right, i.checked_sub(1).map(|j| g[j]));
            assert_eq!(b.left, g.get(i + 1).copied());
            if i > 0 {
                assert_eq!(b.index, places[i - 1].index + 1);
            }
        }
    }
}

#[test]
fn a_vehicle_on_a_dead_end_lane_drives_up_to_its_end_as_sumo_does() {
    // on_ramp_con.3 at the end of the acceleration lane, blocked: SUMO's FCD has it at the lane's very end,
    // 193.79 m, at 2.77 m/s after the step from 59 s (it stopped a tenth of a metre short before)
    let sim = run_until("dead_end", 60.0, true);
    let v = &sim.veh[vehicle(&sim, 2, 3) as usize];
    let len = sim.lane_at(v.lane as usize).length;
    assert!((v.pos - len).abs() < 0.01, "{} of {len}", v.pos);
    assert!((v.speed - 2.77).abs() < 0.01, "{}", v.speed);
}

/// scenarios/sumo/ramp_game made deterministic (one type, sigma 0, no speed deviation, each flow by probability
/// at its mean rate, departPos `base` for `random`), in a folder of its own.
fn deterministic_ramp_game() -> PathBuf {
    let src = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_game"
    ));
    let dir = std::env::temp_dir().join(format!("mapc_detrg_{}", std::process::id()));
    std::fs::create_dir_all(dir.join("ramp")).unwrap();
    std::fs::copy(src.join("ramp/ramp.net.xml"), dir.join("ramp/ramp.net.xml")).unwrap();
    let flow = |id: &str, route: &str, begin: u32, vph: u32, tail: &str| {
        format!(
            "<flow id=\"{id}\" route=\"{route}\" begin=\"{begin}\" end=\"90000\" vehsPerHour=\"{vph}\" departSpeed=\"max\"{tail}/>\n"
        )
    };
    let (free, lane0) = (
        " departLane=\"free\" departPos=\"free\"",
        " departLane=\"0\" departPos=\"base\"",
    );
    let mut routes = String::from(
        "<routes>\n<vType id=\"DEFAULT_VEHTYPE\" length=\"5.0\" minGap=\"2.5\" speedFactor=\"1\" speedDev=\"0\" sigma=\"0\"/>\n\
         <route id=\"highway\" edges=\"gneE2 offramp gneE3 gneE7 gneE8 gneE11\"/>\n\
         <route id=\"offramp\" edges=\"gneE2 offramp gneE4 gneE16 gneE18 gneE9\"/>\n\
         <route id=\"onramp\" edges=\"gneE15 gneE17 gneE18 gneE13 gneE14 gneE7 gneE8 gneE11\"/>\n",
    );
    for (id, route, begin, vph, tail) in [
        ("highway1", "highway", 0, 2500, free),
        ("offramp", "offramp", 0, 792, lane0),
        ("onramp", "onramp", 0, 792, ""),
        ("highway2", "highway", 200, 1440, free),
        ("offramp2", "offramp", 200, 180, lane0),
        ("onramp2", "onramp", 200, 144, ""),
    ] {
        routes.push_str(&flow(id, route, begin, vph, tail));
    }
    routes.push_str("</routes>\n");
    std::fs::write(dir.join("ramp/ramp.rou.xml"), routes).unwrap();
    std::fs::write(
        dir.join("ramp.sumocfg"),
        "<configuration><input><net-file value=\"ramp/ramp.net.xml\"/><route-files value=\"ramp/ramp.rou.xml\"/></input>\
         <time><begin value=\"0\"/><end value=\"400\"/><step-length value=\".2\"/></time></configuration>",
    )
    .unwrap();
    dir.join("ramp.sumocfg")
}

/// The deterministic ramp_game, resolved and ready to run with each vehicle's flow and number recorded.
fn deterministic_ramp_game_run() -> (mapc_scenario::ResolvedScenario, Simulation) {
    let cfg = deterministic_ramp_game();
    let rs = mapc_scenario::ResolvedScenario::load(cfg.to_str().unwrap()).unwrap();
    let spec = spec_from_scenario(&rs).unwrap();
    let mut sim = Simulation::from_spec(spec, 0).unwrap();
    sim.record_origins();
    (rs, sim)
}

/// Steps `sim` until its clock reads `t` (the end of the step that began a step earlier).
fn step_until(sim: &mut Simulation, t: f64) {
    while sim.time_s < t - 1e-9 {
        sim.step().unwrap();
    }
}

#[test]
fn roads_take_their_turn_in_the_lane_change_pass_in_sumos_order_of_active_lanes() {
    // highway1.6 on gneE3, 12 m before the on-ramp's merge, is asked by onramp.0 on the acceleration lane
    // downstream to make room; SUMO's pass visits the downstream road first (its lanes joined the active list
    // later, at the front), so highway1.6 moves left in the same step: on gneE3's lane 1 at 201.62 m after the
    // step from 27.8 s (SUMO's FCD at 28.0 s). Visited in the roads' own order, it stayed on lane 0.
    let (rs, mut sim) = deterministic_ramp_game_run();
    step_until(&mut sim, 28.2);
    let v = &sim.veh[vehicle(&sim, 0, 6) as usize];
    let gne_e3 = rs.graph.find_roads("gneE3").unwrap()[0];
    assert_eq!(sim.net.road_ids[sim.net.road_of(v.lane).unwrap()], gne_e3);
    assert!((v.pos - 201.62).abs() < 0.01, "{}", v.pos);
    assert_eq!(sim.lane_at(v.lane as usize).index, 1);
}

#[test]
fn a_minor_link_waits_while_a_merging_foes_back_is_still_in_the_junction_as_sumo_does() {
    // offramp.0 stands at gneJ14's minor link; onramp.4 on the major connection has entered gneE18, its back
    // still in the junction until 37.4 s. SUMO (its FCD and link output) keeps offramp.0 standing through the step
    // from 37.4 s (its leave speed, lowered for that link leader, makes onramp.5 approaching next a conflict) and
    // starts it in the step from 37.6 s at 0.52 m/s
    let (rs, mut sim) = deterministic_ramp_game_run();
    let gne_e16 = rs.graph.find_roads("gneE16").unwrap()[0];
    let at = |sim: &mut Simulation, t: f64| {
        step_until(sim, t);
        let v = &sim.veh[vehicle(sim, 1, 0) as usize];
        (
            sim.net.road_of(v.lane).map(|r| sim.net.road_ids[r]),
            v.pos,
            v.speed,
        )
    };
    let standing = at(&mut sim, 37.6);
    assert_eq!(standing.0, Some(gne_e16));
    assert!(
        (standing.1 - 37.18).abs() < 0.01 && standing.2 == 0.0,
        "{standing:?}"
    );
    let started = at(&mut sim, 37.8);
    assert_eq!(started.0, None, "on the junction's connection");
    assert!((started.2 - 0.52).abs() < 0.01, "{started:?}");
}

#[test]
fn a_driver_with_priority_slows_for_a_merging_foe_no_more_than_stopping_at_its_last_link_needs() {
    // offramp.0 has entered gneJ14 on the minor connection and leads onramp.5, approaching on the major one. SUMO
    // lowers onramp.5's speed for that junction leader only down to the speed at which it could still stop at the
    // link before (a metre before gneE17's end, where it expects priority): its FCD keeps it at 13.89 m/s through
    // 39.2 s, on gneE15 and then 1.69 m into gneE17 (mapc slowed it from 38.2 s before: 13.64 m/s), and has it at
    // 13.68 m/s after the step from 39.2 s, the stop speed 22.16 m before that link (FCD times: the step's begin)
    let (_, mut sim) = deterministic_ramp_game_run();
    for (t, want) in [(38.2, 13.89), (38.6, 13.89), (39.2, 13.89), (39.4, 13.68)] {
        step_until(&mut sim, t + 0.2);
        let v = &sim.veh[vehicle(&sim, 2, 5) as usize];
        assert!((v.speed - want).abs() < 0.01, "{t} s: {} m/s", v.speed);
    }
}
