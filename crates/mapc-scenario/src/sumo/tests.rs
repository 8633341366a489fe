//! Reading SUMO scenarios: the shipped ones (scenarios/sumo/), and every refusal with its file, line and element.

use super::*;
use crate::ResolvedScenario;
use crate::model::CarFollowModel;

fn shipped(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/sumo")
        .join(rel)
}

/// A folder with the highway_ramp network and `files` beside it.
fn with_files(tag: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mapc_sumo_{tag}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        shipped("highway_ramp/highway.net.xml"),
        dir.join("highway.net.xml"),
    )
    .unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

const CFG: &str = r#"<configuration><input><net-file value="highway.net.xml"/><route-files value="r.rou.xml"/></input>
<time><end value="600"/><step-length value="0.5"/></time></configuration>"#;

/// The error reading `routes` (a route file) with the highway_ramp network.
fn refusal(tag: &str, routes: &str) -> String {
    let dir = with_files(tag, &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
    match from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()) {
        Ok(_) => panic!("{tag}: read"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_highway_ramp_scenario_reads_as_sumo_runs_it() {
    let r = from_sumocfg(
        &shipped("highway_ramp/highway-ramp.sumocfg"),
        &ReadOptions::default(),
    )
    .unwrap();
    let s = &r.scenario;
    assert_eq!(s.step_s, 0.1);
    assert_eq!(s.horizon_steps, 16_000);
    assert_eq!(s.vehicle_types.len(), 6);
    let truck = &s.vehicle_types["truck"];
    assert_eq!(truck.car_follow_model, CarFollowModel::Krauss);
    assert_eq!(
        (truck.sigma, truck.length, truck.decel),
        (Some(0.3), 10.0, 3.5)
    );
    // no vClass: a passenger car's defaults where the type is silent (emergency decel max(9, decel))
    assert_eq!(
        (truck.emergency_decel, truck.speed_dev, truck.tau),
        (Some(9.0), 0.1, 1.0)
    );
    assert_eq!(s.flows.len(), 24);
    let exit = s.flows.iter().find(|f| f.id == "f_1_truck_exit").unwrap();
    assert_eq!(
        (exit.from.as_str(), exit.via.as_slice(), exit.to.as_deref()),
        ("M1", &["M2".to_string()][..], Some("offr"))
    );
    assert_eq!(
        (exit.vehs_per_hour, exit.begin_s, exit.end_s),
        (18.0, 0.0, Some(1600.0))
    );
    let rs = ResolvedScenario::from_sumo(r, "highway_ramp").unwrap();
    assert_eq!(rs.flow_via[0].len(), 1);
}

#[test]
fn a_value_mapc_does_not_simulate_is_refused_with_its_place_and_dropped_when_skipping() {
    // ramp_game reads as it is: its main flows' `departPos="free"`; its additional file's outputs (a timed
    // event, edge data) are said not to be written
    let game = shipped("ramp_game/ramp.sumocfg");
    let r = from_sumocfg(&game, &ReadOptions::default()).unwrap();
    let w = r.warnings.join("\n");
    assert!(
        w.contains("<timedEvent>") && w.contains("<edgeData>"),
        "{w}"
    );
    let highway = r
        .scenario
        .flows
        .iter()
        .find(|f| f.id == "highway1")
        .unwrap();
    assert_eq!(highway.depart_pos.as_deref(), Some("free"));
    // what mapc does not simulate is refused with its place, and dropped with --skip-unsupported
    let routes = "<routes>\n<flow id=\"f\" from=\"M1\" to=\"M3\" vehsPerHour=\"100\" departPos=\"last\"/></routes>";
    let dir = with_files("skip", &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
    let e = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("r.rou.xml: line 2, column 1, in <flow id=\"f\">"),
        "{e}"
    );
    let skip = ReadOptions {
        skip_unsupported: true,
    };
    let w = from_sumocfg(&dir.join("s.sumocfg"), &skip)
        .unwrap()
        .warnings
        .join("\n");
    assert!(w.contains("departPos=\"last\""), "{w}");
    // ramp_metering_1x3 reads as it is: its light, random places, best lanes, its induction loops
    let cfg = shipped("ramp_metering_1x3/1ramp_1x3.sumocfg");
    let r = from_sumocfg(&cfg, &ReadOptions::default()).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.scenario.detectors.len(), 18);
    let d = &r.scenario.detectors[0];
    assert_eq!(
        (d.id.as_str(), d.road.as_str(), d.lane, d.pos_m, d.period_s),
        ("bottle_neck_sens_0", "acceleration_area", 0, 58.75, 40.0)
    );
    // its `file` keeps the name; resolving drops the folders
    assert_eq!(
        d.file.as_deref(),
        Some("induction_loop_data//bottle_neck_sens_0.xml")
    );
    // no end: the last departure and an hour to drain
    assert_eq!(r.scenario.horizon_steps, 7200);
    let main = r
        .scenario
        .flows
        .iter()
        .find(|f| f.id == "main_con")
        .unwrap();
    assert_eq!(
        (
            main.depart_speed.as_deref(),
            main.depart_lane.as_deref(),
            main.depart_pos.as_deref()
        ),
        (Some("max"), Some("best"), Some("random"))
    );
    // the ramp meter: the additional file's program (`rl`) replaces the network's (`0`), as SUMO runs the last
    let meter = r
        .scenario
        .light_programs
        .iter()
        .find(|l| l.id == "ramp_meter")
        .unwrap();
    assert_eq!(meter.program, "rl");
    let states: Vec<&str> = meter.phases.iter().map(|p| p.state.as_str()).collect();
    assert_eq!(states, ["G", "r"]);
    assert!(
        r.graph
            .connections
            .iter()
            .any(|c| c.signal.as_ref().is_some_and(|s| s.light == "ramp_meter"))
    );
}

#[test]
fn mixes_probabilities_periods_numbers_and_trips_become_flows() {
    let dir = with_files(
        "kinds",
        &[
            (
                "r.rou.xml",
                r#"<routes>
  <vTypeDistribution id="mix">
    <vType id="car" probability="0.8" speedFactor="normc(1.1,0.05,0.2,2)"/>
    <vType id="lorry" vClass="truck" probability="0.2"/>
  </vTypeDistribution>
  <route id="exit" edges="M1 M2 offr"/>
  <flow id="p" type="mix" route="exit" begin="0" end="600" probability="0.1"/>
  <flow id="q" from="onr" to="M3" begin="10" end="610" period="4"/>
  <flow id="n" route="exit" begin="0" end="300" number="30"/>
  <trip id="t" depart="5" from="M1" to="offr"/>
  <vehicle id="v" depart="7"><route edges="onr M2 M3"/></vehicle>
</routes>"#,
            ),
            ("s.sumocfg", CFG),
        ],
    );
    let r = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()).unwrap();
    let s = &r.scenario;
    assert_eq!(s.vehicle_type_mixes["mix"]["lorry"], 0.2);
    assert_eq!(
        (
            s.vehicle_types["car"].speed_factor,
            s.vehicle_types["car"].speed_dev
        ),
        (1.1, 0.05)
    );
    // vClass truck: SUMO 1.8's truck
    let lorry = &s.vehicle_types["lorry"];
    assert_eq!(
        (
            lorry.length,
            lorry.accel,
            lorry.decel,
            lorry.emergency_decel
        ),
        (7.1, 1.3, 4.0, Some(7.0))
    );
    let f = |id: &str| s.flows.iter().find(|f| f.id == id).unwrap();
    assert_eq!(
        (f("p").probability, f("p").vehs_per_hour),
        (Some(0.1), 360.0)
    );
    assert_eq!(
        (f("q").vehs_per_hour, f("q").to.as_deref()),
        (900.0, Some("M3"))
    );
    assert_eq!((f("n").number, f("n").vehs_per_hour), (Some(30), 360.0));
    assert_eq!((f("t").number, f("t").begin_s), (Some(1), 5.0));
    assert_eq!(
        (f("v").from.as_str(), f("v").to.as_deref()),
        ("onr", Some("M3"))
    );
    // the default type is SUMO's passenger car
    assert_eq!(s.vehicle_types["DEFAULT_VEHTYPE"].max_speed, 200.0 / 3.6);
    ResolvedScenario::from_sumo(r, "kinds").unwrap();
}

#[test]
fn bad_demand_is_refused_with_file_line_and_element() {
    let cases = [
        (
            "disconnected",
            r#"<routes><route id="r" edges="M1 M3"/><flow id="f" route="r" vehsPerHour="100"/></routes>"#,
            "line 1, column 9, in <route id=\"r\">: edge `M1` does not lead into `M3`",
        ),
        (
            "no_type",
            r#"<routes><flow id="f" type="lorry" from="M1" to="M3" vehsPerHour="100"/></routes>"#,
            "in <flow id=\"f\">: type `lorry` is not defined",
        ),
        (
            "no_route",
            r#"<routes><flow id="f" route="gone" vehsPerHour="100"/></routes>"#,
            "route `gone` is not defined",
        ),
        (
            "two_rates",
            r#"<routes><flow id="f" from="M1" to="M3" vehsPerHour="100" period="3"/></routes>"#,
            "two rates: vehsPerHour and period",
        ),
        (
            "no_rate",
            r#"<routes><flow id="f" from="M1" to="M3" begin="0"/></routes>"#,
            "a flow without a rate",
        ),
        (
            "probability",
            r#"<routes><flow id="f" from="M1" to="M3" probability="1.5"/></routes>"#,
            "probability 1.5: above 1",
        ),
        (
            "bad_value",
            "<routes>\n<vType id=\"a\" accel=\"fast\"/></routes>",
            "line 2, column 1, in <vType id=\"a\">: `accel` is `fast`, not a number",
        ),
        (
            "person",
            "<routes>\n\n<person id=\"p\" depart=\"0\"/></routes>",
            "line 3, column 1, in <person id=\"p\">: <person>: not simulated",
        ),
        (
            "stop",
            r#"<routes><vehicle id="v" depart="1" route="x"><stop lane="M2_0" duration="5"/></vehicle></routes>"#,
            "<stop>",
        ),
        (
            "no_edge",
            r#"<routes><trip id="t" depart="0" from="M1" to="Nowhere"/></routes>"#,
            "edge `Nowhere` is not in the network",
        ),
        (
            "lc_param",
            r#"<routes><vType id="a" lcSublane="2"/></routes>"#,
            "`lcSublane=\"2\"`: a lane-change parameter mapc does not simulate",
        ),
        (
            "lc_range",
            r#"<routes><vType id="a" lcAssertive="0"/></routes>"#,
            "lane-change assertive",
        ),
        (
            "model",
            r#"<routes><vType id="a" carFollowModel="Wiedemann"/></routes>"#,
            "carFollowModel `Wiedemann`",
        ),
        (
            "bounds",
            r#"<routes><vType id="a" speedFactor="normc(1,0.1,0.5,1.5)"/></routes>"#,
            "not from 0.5",
        ),
        (
            "speed_factor",
            r#"<routes><vType id="a" speedFactor="fast"/></routes>"#,
            "speedFactor `fast`",
        ),
        (
            "loop_lane",
            r#"<routes><inductionLoop id="d" lane="M1_7" pos="10" freq="60" file="d.xml"/></routes>"#,
            "in <inductionLoop id=\"d\">: the network has no lane `M1_7`",
        ),
        (
            "loop_pos",
            r#"<routes><inductionLoop id="d" lane="M1_0" pos="500" freq="60" file="d.xml"/></routes>"#,
            "position 500 m is off the 192.91 m lane",
        ),
        (
            "loop_freq",
            r#"<routes><inductionLoop id="d" lane="M1_0" pos="10" file="d.xml"/></routes>"#,
            "<inductionLoop> without `freq`",
        ),
        (
            "loop_file",
            r#"<routes><inductionLoop id="d" lane="M1_0" pos="10" freq="60"/></routes>"#,
            "without `file`",
        ),
        (
            "loop_twice",
            r#"<routes><inductionLoop id="d" lane="M1_0" pos="10" freq="60" file="a"/><inductionLoop id="d" lane="M1_1" pos="10" freq="60" file="a"/></routes>"#,
            "a second detector `d`",
        ),
    ];
    for (tag, routes, expected) in cases {
        let e = refusal(tag, routes);
        assert!(e.contains(expected), "{tag}: {e}");
        assert!(e.contains("r.rou.xml"), "{tag}: no file named: {e}");
    }
}

#[test]
fn options_mapc_does_not_simulate_are_refused_by_name() {
    let routes = r#"<routes><flow id="f" from="M1" to="M3" vehsPerHour="100"/></routes>"#;
    for (option, expected) in [
        (
            r#"<lateral-resolution value="0.8"/>"#,
            "option `lateral-resolution`: the sublane model",
        ),
        (r#"<mesosim value="true"/>"#, "option `mesosim`"),
        (
            r#"<step-method.ballistic value="true"/>"#,
            "option `step-method.ballistic`",
        ),
        (
            r#"<default.carfollowmodel value="ACC"/>"#,
            "car-following model `ACC`",
        ),
        (
            r#"<default.action-step-length value="1"/>"#,
            "default.action-step-length 1",
        ),
    ] {
        let cfg = CFG.replace(
            "</configuration>",
            &format!("<processing>{option}</processing></configuration>"),
        );
        let dir = with_files("opt", &[("r.rou.xml", routes), ("s.sumocfg", &cfg)]);
        let e = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(expected) && e.contains("s.sumocfg: line"),
            "{option}: {e}"
        );
    }
    let cfg = CFG.replace("r.rou.xml", "missing.rou.xml");
    let dir = with_files("missing", &[("s.sumocfg", &cfg)]);
    let e = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("missing.rou.xml") && e.contains("not a file"),
        "{e}"
    );
}

#[test]
fn induction_loops_read_as_sumo_places_them() {
    // a negative position counts from the lane's end; a friendly one off the lane goes to its end
    let routes = r#"<routes><flow id="f" from="M1" to="M3" vehsPerHour="900"/>
<inductionLoop id="back" lane="M1_1" pos="-12.91" freq="30" file="out/../../d.xml" vTypes="DEFAULT_VEHTYPE"/>
<e1Detector id="far" lane="M1_0" pos="900" friendlyPos="true" period="60" file="e.xml"/></routes>"#;
    let dir = with_files("loops", &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
    let r = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()).unwrap();
    let rs = ResolvedScenario::from_sumo(r, "s.sumocfg").unwrap();
    let [back, far] = &rs.detectors[..] else {
        panic!("{:?}", rs.detectors)
    };
    assert!((back.pos_m - 180.0).abs() < 1e-9, "{back:?}");
    assert_eq!((back.lane, back.period_s), (1, 30.0));
    assert_eq!(back.vehicle_types, ["DEFAULT_VEHTYPE"]);
    // an output named by the file stays in the output folder: its folders are dropped
    assert_eq!(back.file.as_deref(), Some("d.xml"));
    assert!((far.pos_m - 192.91).abs() < 1e-9, "{far:?}");
    assert_eq!(far.period_s, 60.0);
}

#[test]
fn a_trip_is_routed_by_travel_time_as_sumo_routes_it() {
    // one road at 5 m/s or two at 30 m/s: SUMO 1.8's duarouter takes the two (scenarios/sumo/route_choice)
    let r = from_sumocfg(
        &shipped("route_choice/route_choice.sumocfg"),
        &ReadOptions::default(),
    )
    .unwrap();
    let trip = &r.scenario.flows[0];
    assert_eq!(
        (trip.from.as_str(), trip.to.as_deref()),
        ("in", Some("out"))
    );
    assert_eq!(trip.via, ["fast1", "fast2"]);
}

#[test]
fn a_types_lane_change_parameters_are_read() {
    let routes = r#"<routes><vType id="eager" lcSpeedGain="2.5" lcKeepRight="0" lcStrategic="-1" lcAssertive="1.5"/>
<flow id="f" type="eager" from="M1" to="M3" vehsPerHour="600"/></routes>"#;
    let dir = with_files("lc", &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
    let r = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()).unwrap();
    let lc = r.scenario.vehicle_types["eager"].lane_change;
    assert_eq!(
        (lc.speed_gain, lc.keep_right, lc.strategic, lc.assertive),
        (Some(2.5), Some(0.0), Some(-1.0), Some(1.5))
    );
    assert_eq!((lc.cooperative, lc.lookahead_left), (None, None));
}

#[test]
fn a_route_of_one_edge_reads_as_a_flow_that_ends_on_it() {
    // a route of a single edge once panicked on its empty middle; then its vehicles drove on down the corridor
    // (a flow without a destination), where SUMO's arrive at the edge's end
    let routes = r#"<routes><vType id="car"/><route id="r" edges="M1"/>
<flow id="f" type="car" route="r" begin="0" end="60" vehsPerHour="600"/>
<vehicle id="v" type="car" depart="1"><route edges="M2"/></vehicle></routes>"#;
    let dir = with_files("one_edge", &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
    let r = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()).unwrap();
    let flows: Vec<_> = r
        .scenario
        .flows
        .iter()
        .map(|f| (f.from.as_str(), f.via.len(), f.to.as_deref()))
        .collect();
    assert_eq!(flows, [("M1", 0, Some("M1")), ("M2", 0, Some("M2"))]);
}

#[test]
fn elements_inside_a_nested_routes_container_read_as_sumo_reads_them() {
    // some users' files wrap routes in an <additionals> root; SUMO 1.8 reads the elements wherever they stand
    let nested = r#"<additionals><routes><vType id="car"/><route id="r" edges="M1 M2"/></routes>
<flow id="f" type="car" route="r" begin="0" end="60" vehsPerHour="600"/></additionals>"#;
    let flat = r#"<routes><vType id="car"/><route id="r" edges="M1 M2"/>
<flow id="f" type="car" route="r" begin="0" end="60" vehsPerHour="600"/></routes>"#;
    let read = |tag: &str, routes: &str| {
        let dir = with_files(tag, &[("r.rou.xml", routes), ("s.sumocfg", CFG)]);
        let r = from_sumocfg(&dir.join("s.sumocfg"), &ReadOptions::default()).unwrap();
        (r.scenario.flows, r.scenario.vehicle_types)
    };
    let (flows, types) = read("nested", nested);
    assert_eq!(flows.len(), 1);
    assert!(types.contains_key("car"));
    assert_eq!((flows, types), read("flat", flat));
}

#[test]
fn lights_run_on_sumos_clock_which_reads_the_begin_at_the_first_step() {
    // sumo-rl's 3x3 grid: a 66 s cycle (24 + 2 + 1 + 36 + 2 + 1). SUMO starts a light's program at the begin as
    // if it had run since 0: begun at 33 s, light 5 is 6 s into its fourth phase
    let grid = shipped("sumo_rl_3x3grid");
    let dir = std::env::temp_dir().join(format!("mapc_sumo_begin_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("g.sumocfg");
    let phase_at_first_step = |begin: u32| {
        std::fs::write(
            &cfg,
            format!(
                r#"<configuration><input><net-file value="{}"/><route-files value="{}"/></input>
<time><begin value="{begin}"/><end value="{}"/></time></configuration>"#,
                grid.join("3x3Grid2lanes.net.xml").display(),
                grid.join("routes14000.rou.xml").display(),
                begin + 600
            ),
        )
        .unwrap();
        let r = from_sumocfg(&cfg, &ReadOptions::default()).unwrap();
        assert_eq!(r.scenario.clock_begin_s, begin as f64);
        let rs = ResolvedScenario::from_sumo(r, "g.sumocfg").unwrap();
        let light = rs.graph.lights.iter().find(|l| l.id == "5").unwrap();
        let cycle: f64 = light.phases.iter().map(|p| p.duration_s).sum();
        assert_eq!(cycle, 66.0);
        // the phase the run's clock finds at 0 s (phases: 24, 2, 1, 36, 2, 1 s)
        let into = (0.0 - light.offset_s).rem_euclid(cycle);
        let mut left = into;
        light
            .phases
            .iter()
            .position(|p| {
                let here = left < p.duration_s;
                left -= p.duration_s;
                here
            })
            .unwrap()
    };
    assert_eq!(phase_at_first_step(0), 0);
    assert_eq!(phase_at_first_step(33), 3);
    assert_eq!(phase_at_first_step(66 * 10 + 25), 1);
}

#[test]
fn the_outputs_a_configuration_asks_for_are_named_with_the_flag_that_writes_them() {
    // highway_ramp's analysis configuration asks SUMO for trip infos, floating-car data and a summary
    let r = from_sumocfg(
        &shipped("highway_ramp/highway-ramp-analysis.sumocfg"),
        &ReadOptions::default(),
    )
    .unwrap();
    for option in ["tripinfo-output", "fcd-output", "summary-output"] {
        assert!(
            r.warnings.iter().any(|w| w.contains(&format!(
                "option `{option}` not written; `mapc sim --{option} FILE` writes it"
            ))),
            "{option}: {:?}",
            r.warnings
        );
    }
}
