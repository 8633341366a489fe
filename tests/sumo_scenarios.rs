//! A SUMO user's scenario through the binary: `mapc sim X.sumocfg` and `mapc sim --net --routes` run it, other
//! commands take it as a scenario, and bad input is refused with the file, the line and the element, exit 2.

mod common;
use common::*;

const HIGHWAY_RAMP: &str = "scenarios/sumo/highway_ramp/highway-ramp.sumocfg";

#[test]
fn a_sumocfg_runs_as_it_is_and_as_its_files() {
    let j = mapc_json(&["sim", HIGHWAY_RAMP, "--seeds", "2", "--json"]);
    for r in j["runs"].as_array().unwrap() {
        // SUMO 1.8 inserts 456 vehicles in this run
        assert_eq!(r["departed"], 456, "{r}");
    }
    let files = mapc_json(&[
        "sim",
        "--net",
        "scenarios/sumo/highway_ramp/highway.net.xml",
        "--routes",
        "scenarios/sumo/highway_ramp/highway-ramp.rou.xml",
        "--seeds",
        "1",
        "--json",
    ]);
    // SUMO's defaults: a 1 s step, no end (the last departure and an hour)
    assert!(
        files["runs"][0]["departed"].as_u64().unwrap() > 400,
        "{files}"
    );
    // another command takes the configuration as its scenario
    let out = run_mapc(&["scenario", "show", HIGHWAY_RAMP, "--json"]);
    assert_success(&out);
}

#[test]
fn bad_sumo_input_is_refused_with_its_place_and_exit_2() {
    let dir = scratch_dir("sumo-bad");
    std::fs::copy(
        root().join("scenarios/sumo/highway_ramp/highway.net.xml"),
        dir.join("highway.net.xml"),
    )
    .unwrap();
    std::fs::write(
        dir.join("bad.rou.xml"),
        "<routes>\n  <flow id=\"f\" type=\"lorry\" from=\"M1\" to=\"M3\" vehsPerHour=\"100\"/>\n</routes>\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("bad.sumocfg"),
        "<configuration><input><net-file value=\"highway.net.xml\"/><route-files value=\"bad.rou.xml\"/></input></configuration>",
    )
    .unwrap();
    let cfg = dir.join("bad.sumocfg");
    refused(
        &["sim", cfg.to_str().unwrap()],
        &[
            "bad.rou.xml: line 2, column 3, in <flow id=\"f\">",
            "type `lorry` is not defined",
        ],
    );
    // a refused element, and the flag that drops it
    std::fs::write(
        dir.join("bad.rou.xml"),
        "<routes>\n<person id=\"p\" depart=\"0\"/>\n<flow id=\"f\" from=\"M1\" to=\"M3\" vehsPerHour=\"100\"/>\n</routes>\n",
    )
    .unwrap();
    refused(
        &["sim", cfg.to_str().unwrap()],
        &["line 2", "<person id=\"p\">", "--skip-unsupported"],
    );
    let out = run_mapc(&[
        "sim",
        cfg.to_str().unwrap(),
        "--skip-unsupported",
        "--seeds",
        "1",
    ]);
    assert_success(&out);
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: dropped: <person>"));
    // a file the configuration names that is not there
    std::fs::write(
        dir.join("bad.sumocfg"),
        "<configuration><net-file value=\"highway.net.xml\"/><route-files value=\"gone.rou.xml\"/></configuration>",
    )
    .unwrap();
    refused(
        &["sim", cfg.to_str().unwrap()],
        &["gone.rou.xml", "not a file"],
    );
}

/// The attributes SUMO 1.8 writes on a `<tripinfo>` and a summary `<step>` (read from its own files).
const TRIPINFO_ATTRS: &[&str] = &[
    "id",
    "depart",
    "departLane",
    "departPos",
    "departSpeed",
    "departDelay",
    "arrival",
    "arrivalLane",
    "arrivalPos",
    "arrivalSpeed",
    "duration",
    "routeLength",
    "waitingTime",
    "waitingCount",
    "stopTime",
    "timeLoss",
    "rerouteNo",
    "devices",
    "vType",
    "speedFactor",
    "vaporized",
];
const STEP_ATTRS: &[&str] = &[
    "time",
    "loaded",
    "inserted",
    "running",
    "waiting",
    "ended",
    "arrived",
    "collisions",
    "teleports",
    "halting",
    "stopped",
    "meanWaitingTime",
    "meanTravelTime",
    "meanSpeed",
    "meanSpeedRelative",
    "duration",
];

/// The attribute names of the first `<name ` element in `xml`, in order.
fn attrs_of(xml: &str, name: &str) -> Vec<String> {
    let start = xml
        .find(&format!("<{name} "))
        .unwrap_or_else(|| panic!("no <{name}> in {xml}"));
    let tag = &xml[start..start + xml[start..].find("/>").unwrap()];
    tag.split('"')
        .step_by(2)
        .filter_map(|part| {
            part.trim()
                .rsplit(' ')
                .next()
                .and_then(|k| k.strip_suffix('='))
        })
        .map(str::to_string)
        .collect()
}

#[test]
fn sumo_outputs_have_sumos_elements_and_attributes() {
    let dir = scratch_dir("sumo-outputs");
    let trip = dir.join("trip.xml");
    let summary = dir.join("summary.xml");
    let out = run_mapc(&[
        "sim",
        HIGHWAY_RAMP,
        "--seeds",
        "1",
        "--tripinfo-output",
        trip.to_str().unwrap(),
        "--summary-output",
        summary.to_str().unwrap(),
    ]);
    assert_success(&out);
    let trip = std::fs::read_to_string(&trip).unwrap();
    assert_eq!(attrs_of(&trip, "tripinfo"), TRIPINFO_ATTRS);
    // SUMO 1.8 has 449 of the 456 arrive in this run; vehicles are named `flow.N`
    assert_eq!(trip.matches("<tripinfo ").count(), 449);
    assert!(trip.contains("id=\"f_1_passenger_through.0\""));
    let summary = std::fs::read_to_string(&summary).unwrap();
    assert_eq!(attrs_of(&summary, "step"), STEP_ATTRS);
    assert_eq!(summary.matches("<step ").count(), 16_000);
}

/// The attributes SUMO 1.8 writes on a floating-car data `<vehicle>` (read from its own file).
const FCD_ATTRS: &[&str] = &[
    "id", "x", "y", "angle", "type", "speed", "pos", "lane", "slope",
];

#[test]
fn fcd_output_has_sumos_elements_and_its_first_step() {
    let dir = scratch_dir("fcd-output");
    let fcd = dir.join("fcd.xml");
    let out = run_mapc(&[
        "sim",
        HIGHWAY_RAMP,
        "--seeds",
        "1",
        "--fcd-output",
        fcd.to_str().unwrap(),
    ]);
    assert_success(&out);
    let fcd = std::fs::read_to_string(&fcd).unwrap();
    assert_eq!(attrs_of(&fcd, "vehicle"), FCD_ATTRS);
    assert_eq!(fcd.matches("<timestep ").count(), 16_000);
    assert!(fcd.trim_end().ends_with("</fcd-export>"));
    // SUMO 1.8's own first step of this scenario (`sumo -c highway-ramp.sumocfg --fcd-output`), byte for byte:
    // the first two vehicles at their departure, on the main road and on the ramp that climbs at 26.57 degrees
    let sumo_first = "    <timestep time=\"0.00\">
        <vehicle id=\"f_1_passenger_through.0\" x=\"104.43\" y=\"95.20\" angle=\"90.00\" type=\"passenger\" speed=\"0.00\" pos=\"4.60\" lane=\"M1_0\" slope=\"0.00\"/>
        <vehicle id=\"f_2_passenger_through.0\" x=\"104.80\" y=\"0.61\" angle=\"63.43\" type=\"passenger\" speed=\"0.00\" pos=\"4.60\" lane=\"onr_0\" slope=\"0.00\"/>
    </timestep>
    <timestep time=\"0.10\">
";
    assert!(fcd.contains(sumo_first), "{}", &fcd[..fcd.len().min(1200)]);
    // each step's vehicles in the order of their ids, as SUMO's vehicle table has them
    for step in fcd.split("<timestep ").skip(1).take(2000) {
        let ids: Vec<&str> = step
            .split("<vehicle id=\"")
            .skip(1)
            .map(|v| &v[..v.find('"').unwrap()])
            .collect();
        assert!(ids.is_sorted(), "{ids:?}");
    }
}

/// A mapc scenario's floating-car data names the lanes `mapc export --sumo` writes, internal lanes too, so that it
/// reads beside SUMO's run of the export.
#[test]
fn fcd_of_a_mapc_scenario_names_the_exported_lanes() {
    let dir = scratch_dir("fcd-export-names");
    let fcd = dir.join("fcd.xml");
    let export = dir.join("export");
    let scenario = "scenarios/simple_merge.toml";
    assert_success(&run_mapc(&[
        "sim",
        scenario,
        "--seeds",
        "1",
        "--fcd-output",
        fcd.to_str().unwrap(),
    ]));
    assert_success(&run_mapc(&[
        "export",
        scenario,
        "--sumo",
        export.to_str().unwrap(),
    ]));
    let net = std::fs::read_dir(&export)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(".net.xml"))
        .unwrap();
    let net = std::fs::read_to_string(net).unwrap();
    let fcd = std::fs::read_to_string(fcd).unwrap();
    let lanes: std::collections::BTreeSet<&str> = fcd
        .split(" lane=\"")
        .skip(1)
        .map(|r| &r[..r.find('"').unwrap()])
        .collect();
    assert!(lanes.iter().any(|l| l.starts_with(':')), "{lanes:?}");
    for lane in &lanes {
        assert!(
            net.contains(&format!("<lane id=\"{lane}\"")),
            "{lane} not in the export"
        );
    }
}

/// `--sumo-outputs DIR`: the outputs the configuration names, under their names, from the same run as the flags
/// write them; only a SUMO configuration names outputs.
#[test]
fn sumo_outputs_writes_what_the_configuration_names() {
    let dir = scratch_dir("sumo-outputs-dir");
    let outs = dir.join("outs");
    let analysis = "scenarios/sumo/highway_ramp/highway-ramp-analysis.sumocfg";
    let out = run_mapc(&[
        "sim",
        analysis,
        "--seeds",
        "1",
        "--sumo-outputs",
        outs.to_str().unwrap(),
    ]);
    assert_success(&out);
    // (written, so not said to be unwritten)
    assert!(!String::from_utf8_lossy(&out.stderr).contains("not written"));
    let mut names: Vec<String> = std::fs::read_dir(&outs)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["summary.xml", "trip_info.xml", "vehicle_traces.xml"]
    );
    let trip = dir.join("trip.xml");
    assert_success(&run_mapc(&[
        "sim",
        analysis,
        "--seeds",
        "1",
        "--tripinfo-output",
        trip.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read(outs.join("trip_info.xml")).unwrap(),
        std::fs::read(&trip).unwrap()
    );
    let fcd = std::fs::read_to_string(outs.join("vehicle_traces.xml")).unwrap();
    assert!(fcd.contains("<fcd-export"));
    // a mapc scenario names no outputs: refused, nothing written
    let none = dir.join("none");
    let out = run_mapc(&[
        "sim",
        "scenarios/simple_merge.toml",
        "--seeds",
        "1",
        "--sumo-outputs",
        none.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("is not one"));
    assert!(!none.exists());
    // two outputs of one file name (the folders dropped) would write over each other: refused, nothing written
    let copy = dir.join("copy");
    std::fs::create_dir_all(&copy).unwrap();
    for f in ["highway.net.xml", "highway-ramp.rou.xml"] {
        std::fs::copy(format!("scenarios/sumo/highway_ramp/{f}"), copy.join(f)).unwrap();
    }
    let cfg = std::fs::read_to_string(analysis)
        .unwrap()
        .replace("\"summary.xml\"", "\"sub/trip_info.xml\"");
    std::fs::write(copy.join("a.sumocfg"), cfg).unwrap();
    let clash = dir.join("clash");
    let out = run_mapc(&[
        "sim",
        copy.join("a.sumocfg").to_str().unwrap(),
        "--seeds",
        "1",
        "--sumo-outputs",
        clash.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("`summary-output` and `tripinfo-output` both name `trip_info.xml`"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!clash.exists());
}

/// A trace asked beside SUMO's outputs: all of them are written, from the first seed's one run (the trip-info used
/// to be left out, without a word, whenever `--trace` was given).
#[test]
fn a_trace_and_sumos_outputs_are_written_together_from_the_same_run() {
    let dir = scratch_dir("trace-and-outputs");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let sim = |extra: &[&str]| {
        let mut args = vec!["sim", HIGHWAY_RAMP, "--seeds", "2"];
        args.extend_from_slice(extra);
        assert_success(&run_mapc(&args));
    };
    sim(&[
        "--trace",
        &path("both.csv"),
        "--tripinfo-output",
        &path("both_trip.xml"),
        "--summary-output",
        &path("both_summary.xml"),
        "--fcd-output",
        &path("both_fcd.xml"),
    ]);
    sim(&["--trace", &path("trace.csv")]);
    sim(&[
        "--tripinfo-output",
        &path("trip.xml"),
        "--summary-output",
        &path("summary.xml"),
    ]);
    sim(&["--fcd-output", &path("fcd.xml")]);
    let read = |name: &str| {
        std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name} not written: {e}"))
    };
    assert_eq!(read("both.csv"), read("trace.csv"));
    assert_eq!(read("both_trip.xml"), read("trip.xml"));
    assert_eq!(read("both_summary.xml"), read("summary.xml"));
    assert_eq!(read("both_fcd.xml"), read("fcd.xml"));
}

#[test]
fn a_configuration_named_cfg_is_known_by_its_root_element() {
    // eccles_interchange: `interchangeSim.cfg`, 1 000 vehicles each with its own route on an OSM interchange
    let j = mapc_json(&[
        "scenario",
        "show",
        "scenarios/sumo/eccles_interchange/interchangeSim.cfg",
        "--json",
    ]);
    assert_eq!(j["flows"].as_array().unwrap().len(), 1000);
}

#[test]
fn from_sumo_writes_a_scenario_that_runs_as_the_configuration() {
    let dir = scratch_dir("from-sumo");
    let out = dir.join("ramp_metering.toml");
    let cfg = "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg";
    assert_success(&run_mapc(&[
        "scenario",
        "from-sumo",
        cfg,
        "-o",
        out.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&out).unwrap();
    // the additional file's light program and SUMO's queueing go with the scenario
    assert!(text.contains("[[light_programs]]") && text.contains("queue_excess_demand = true"));
    let runs = |s: &str| mapc_json(&["sim", s, "--seeds", "2", "--json"])["runs"].clone();
    assert_eq!(runs(out.to_str().unwrap()), runs(cfg));
}

/// The attributes SUMO 1.8 writes on an induction loop's `<interval>` (read from its own file).
const E1_ATTRS: [&str; 10] = [
    "begin",
    "end",
    "id",
    "nVehContrib",
    "flow",
    "occupancy",
    "speed",
    "harmonicMeanSpeed",
    "length",
    "nVehEntered",
];

#[test]
fn induction_loops_write_sumos_files_and_their_flows() {
    let cfg = "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg";
    let dir = scratch_dir("sumo-detectors");
    let out = run_mapc(&[
        "sim",
        cfg,
        "--seeds",
        "1",
        "--json",
        "--detector-output",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let detectors = j["detectors"].as_array().unwrap();
    assert_eq!(detectors.len(), 18);
    // each loop's file under its own name (the folders of `induction_loop_data/x.xml` dropped), 180 intervals
    // of 40 s over the 7 200 s run
    let xml = std::fs::read_to_string(dir.join("outflow_sens_0.xml")).unwrap();
    assert!(xml.contains("det_e1_file.xsd"), "{xml}");
    assert_eq!(attrs_of(&xml, "interval"), E1_ATTRS);
    assert_eq!(xml.matches("<interval ").count(), 180);
    // the file and the JSON count the same vehicles
    let passed: u64 = xml
        .split("nVehContrib=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].parse::<u64>().unwrap())
        .sum();
    let flow = detectors
        .iter()
        .find(|d| d["id"] == "outflow_sens_0")
        .unwrap()["flow"]["mean"]
        .as_f64()
        .unwrap();
    assert!(
        (flow - passed as f64 / 2.0).abs() < 1e-9,
        "{flow} vs {passed}"
    );
    // every ramp vehicle passes both loops of the one-lane passage
    let of = |id: &str| {
        detectors.iter().find(|d| d["id"] == id).unwrap()["flow"]["mean"]
            .as_f64()
            .unwrap()
    };
    assert!((of("passage_sens") - of("passage_queue_sens")).abs() <= 0.5);
    assert!(of("passage_sens") > 600.0, "{detectors:?}");
}

#[test]
fn av_share_puts_avs_into_a_sumo_users_scenario_for_a_policy() {
    // a tenth of every flow's vehicles become AVs; the total demand is the configuration's
    let j = mapc_json(&[
        "sim",
        HIGHWAY_RAMP,
        "--seeds",
        "1",
        "--av-share",
        "0.1",
        "--json",
    ]);
    let departed = j["runs"][0]["departed"].as_u64().unwrap();
    assert!((440..=470).contains(&departed), "{departed}");
    // a policy drives them: the Simple Merge's centralized policy, zero-shot on the user's freeway
    let e = mapc_json(&[
        "eval",
        "--policy",
        "policies/simple_merge_outflow.json",
        "--scenario",
        HIGHWAY_RAMP,
        "--av-share",
        "0.1",
        "--seeds",
        "2",
        "--json",
    ]);
    // the AVs drive as humans in the baseline: a policy run that differs from it was driven
    assert_ne!(
        e["outflow"]["mean"], e["baseline"]["outflow"]["mean"],
        "no AV was driven: {e}"
    );
    // a share outside [0, 1] is refused
    refused(
        &["sim", HIGHWAY_RAMP, "--av-share", "1.5", "--seeds", "1"],
        &["AV share 1.5 is outside [0, 1]"],
    );
}

#[test]
fn depart_pos_free_inserts_at_the_lane_start_behind_the_last_vehicle_as_sumo_does() {
    // ramp_game runs from its own configuration: its main flows depart with departPos="free"
    let dir = scratch_dir("sumo-free");
    let trip = dir.join("trip.xml");
    let out = run_mapc(&[
        "sim",
        "scenarios/sumo/ramp_game/ramp.sumocfg",
        "--seeds",
        "1",
        "--tripinfo-output",
        trip.to_str().unwrap(),
    ]);
    assert_success(&out);
    let trip = std::fs::read_to_string(&trip).unwrap();
    let main: Vec<&str> = trip
        .lines()
        .filter(|l| l.contains("id=\"highway1."))
        .collect();
    assert!(main.len() > 100, "{} main-road trips", main.len());
    // SUMO's freeInsertion puts the front at 0 behind the last vehicle when there is room (the base place
    // would be one length in)
    let at_start = main
        .iter()
        .filter(|l| l.contains("departPos=\"0.00\""))
        .count();
    assert!(
        at_start * 2 > main.len(),
        "{at_start} of {} at the lane start",
        main.len()
    );
}

#[test]
fn a_types_lc_parameters_change_how_it_changes_lanes() {
    // highway_ramp with every vType given lcSpeedGain="0": no lane change for speed is left
    let dir = scratch_dir("sumo-lc-params");
    for f in [
        "highway.net.xml",
        "highway-ramp.rou.xml",
        "highway-ramp.sumocfg",
    ] {
        std::fs::copy(format!("scenarios/sumo/highway_ramp/{f}"), dir.join(f)).unwrap();
    }
    let routes = dir.join("highway-ramp.rou.xml");
    let text = std::fs::read_to_string(&routes).unwrap();
    std::fs::write(
        &routes,
        text.replace("<vType ", "<vType lcSpeedGain=\"0\" "),
    )
    .unwrap();
    let reasons = |cfg: &str| {
        let j = mapc_json(&["sim", cfg, "--seeds", "1", "--json"]);
        j["runs"][0]["lane_changes_by_reason"]["speed_gain"]
            .as_u64()
            .unwrap()
    };
    assert!(reasons(HIGHWAY_RAMP) > 20);
    assert_eq!(
        reasons(dir.join("highway-ramp.sumocfg").to_str().unwrap()),
        0
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sumo_users_scenario_exports_with_its_drivers_mixes_and_departure_rules() {
    // ramp_game: Krauss drivers, a truck mix, flows by probability, departPos free and random
    let dir = export_for_sumo(
        "scenarios/sumo/ramp_game/ramp.sumocfg",
        "sumo-export-users",
        &[],
    );
    let routes = std::fs::read_to_string(dir.join("ramp.rou.xml")).unwrap();
    assert!(
        routes.contains(r#"<vType id="truck" carFollowModel="Krauss""#),
        "{routes}"
    );
    assert!(routes.contains(r#"sigma="0.5000""#));
    assert!(routes.contains(r#"<vTypeDistribution id="highway1_types">"#));
    assert!(routes.contains(r#"<vType id="truck@highway1_types" probability="0.200000""#));
    assert!(routes.contains(r#"probability="0.220000""#));
    assert!(routes.contains(r#"departPos="free""#) && routes.contains(r#"departPos="random""#));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn av_share_exports_the_avs_and_the_approach_they_are_controlled_on() {
    // highway_ramp has no controlled region of its own: --av-share gives it the approach to its on-ramp merge
    let dir = export_for_sumo(HIGHWAY_RAMP, "sumo-export-avs", &["--av-share", "0.1"]);
    let manifest_path = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(".mapc.json"))
        .expect("a manifest");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(manifest_path).unwrap()).unwrap();
    let av_types = manifest["av_types"].as_array().unwrap();
    assert!(
        av_types
            .iter()
            .any(|t| t.as_str().unwrap().ends_with("_av")),
        "{manifest}"
    );
    let region = manifest["control_edges"].as_array().unwrap();
    let net = std::fs::read_to_string(
        std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.to_string_lossy().ends_with(".net.xml"))
            .unwrap(),
    )
    .unwrap();
    let edges = net.matches("<edge id=\"").count() - net.matches("function=\"internal\"").count();
    assert!(
        !region.is_empty() && region.len() < edges,
        "{} of {edges} edges",
        region.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shipped_eccles_policy_drives_a_sumo_users_interchange_faster_than_its_humans() {
    // every tenth of the interchange's 1 000 vehicles an AV, controlled on the approach to its zippers
    let e = mapc_json(&[
        "eval",
        "--policy",
        "policies/eccles_av10_speed.json",
        "--scenario",
        "scenarios/sumo/eccles_interchange/interchangeSim.cfg",
        "--av-share",
        "0.1",
        "--seeds",
        "3",
        "--json",
    ]);
    let of = |v: &serde_json::Value| v["mean"].as_f64().unwrap();
    let (speed, human_speed) = (of(&e["speed"]), of(&e["baseline"]["speed"]));
    let (trip, human_trip) = (of(&e["travel_time"]), of(&e["baseline"]["travel_time"]));
    assert!(speed > 1.02 * human_speed, "{speed} against {human_speed}");
    assert!(trip < 0.97 * human_trip, "{trip} against {human_trip}");
}

#[test]
fn flows_by_number_export_without_an_end_as_sumo_1_8_takes_them() {
    // eccles: 1 000 vehicles, each a flow of one; SUMO 1.8 refuses a flow with a rate, an end and a number
    let dir = export_for_sumo(
        "scenarios/sumo/eccles_interchange/interchangeSim.cfg",
        "sumo-export-number",
        &[],
    );
    let routes = std::fs::read_to_string(dir.join("interchangeSim.rou.xml")).unwrap();
    let flows: Vec<&str> = routes.lines().filter(|l| l.contains("<flow ")).collect();
    assert_eq!(flows.len(), 1000);
    for f in flows {
        assert!(f.contains("number=\"1\"") && !f.contains(" end="), "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_measured_rule_leaves_a_policy_that_loses_to_the_humans() {
    // the Simple Merge's policy loses on this freeway (docs/results.md, zero-shot): its calibration withholds it
    let e = mapc_json(&[
        "eval",
        "--policy",
        "policies/simple_merge_outflow.json",
        "--scenario",
        HIGHWAY_RAMP,
        "--av-share",
        "0.1",
        "--deploy",
        "measured",
        "--seeds",
        "2",
        "--json",
    ]);
    assert_eq!(e["outflow"], e["baseline"]["outflow"], "{e}");
    let reason = e["withheld"][0]["reason"].as_str().unwrap();
    assert!(reason.contains("20 calibration seeds"), "{reason}");
}

#[test]
fn a_distributed_policy_trains_and_drives_on_a_sumo_users_scenario_with_its_lanes_observed() {
    // ramp_game: every tenth vehicle an AV, each one an agent on the approach to the metered merge
    let dir = scratch_dir("sumo-distributed");
    let run = dir.join("run");
    let cfg = "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg";
    assert_success(&run_mapc(&[
        "train",
        "--scenario",
        cfg,
        "--av-share",
        "0.1",
        "--distributed",
        "--features",
        "lanes",
        "--preset",
        "fast",
        "--iters",
        "1",
        "--batch",
        "600",
        "--horizon",
        "600",
        "-o",
        run.to_str().unwrap(),
    ]));
    let ck = run.join("checkpoint.json");
    let spec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&ck).unwrap()).unwrap();
    // one agent per AV, each observing its own lane and the lanes beside it (15 values)
    let features = &spec["spec"]["distributed"]["features"];
    assert_eq!(
        features["lanes"],
        serde_json::Value::Bool(true),
        "{features}"
    );
    assert_eq!(spec["spec"]["obs_dim"], 15);
    let e = mapc_json(&[
        "eval",
        "--policy",
        ck.to_str().unwrap(),
        "--scenario",
        cfg,
        "--av-share",
        "0.1",
        "--seeds",
        "2",
        "--json",
    ]);
    // an untrained policy drives its AVs otherwise than the humans would: the runs differ from the baseline
    assert_ne!(e["speed"], e["baseline"]["speed"], "no AV was driven: {e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sumo_vehicle_keeps_its_id_in_the_trip_info_and_a_flows_are_numbered() {
    // eccles: 1 000 `<vehicle>`s; SUMO names each by its id (`m60-m62_161`), a flow's vehicles `flow.N`
    let text = trip_info("scenarios/sumo/eccles_interchange/interchangeSim.cfg");
    assert!(
        text.contains("<tripinfo id=\"m60-m62_161\" "),
        "no vehicle named by its id"
    );
    assert!(!text.contains("id=\"m60-m62_161.0\""));
    let text = trip_info("scenarios/sumo/ramp_game/ramp.sumocfg");
    assert!(
        text.contains("<tripinfo id=\"highway1.0\" "),
        "a flow's first vehicle"
    );
}

/// The trip-info file of seed 0 of a scenario.
fn trip_info(scenario: &str) -> String {
    // a folder per call: the tests run at once
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = scratch_dir(&format!("sumo-trip-info-{call}"));
    let trips = dir.join("trips.xml");
    assert_success(&run_mapc(&[
        "sim",
        scenario,
        "--seeds",
        "1",
        "--tripinfo-output",
        trips.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&trips).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    text
}

#[test]
fn a_vehicle_departs_at_the_first_step_at_or_after_its_time_as_sumo_stamps_it() {
    // eccles (steps of 1 s): `m62-m60-b_788` asks for 1.09 s. SUMO 1.8's clock reads 0 at its first step, which
    // inserts what is due by 0; this vehicle enters in the step that begins at 2 s, and its trip info says so
    // (depart 2.00, a delay of 0.91 s), as SUMO 1.8 writes it
    let text = trip_info("scenarios/sumo/eccles_interchange/interchangeSim.cfg");
    let line = text
        .lines()
        .find(|l| l.contains("<tripinfo id=\"m62-m60-b_788\" "))
        .expect("the vehicle's trip");
    assert!(
        line.contains(" depart=\"2.00\" ") && line.contains(" departDelay=\"0.91\" "),
        "{line}"
    );
    // every arrival at its lane's end, as SUMO reports it (not where the last step took the vehicle)
    let net =
        std::fs::read_to_string("scenarios/sumo/eccles_interchange/interchange.net.xml").unwrap();
    for line in text.lines().filter(|l| l.contains("<tripinfo ")) {
        let attr = |name: &str| {
            let at = line.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
            line[at..].split('"').next().unwrap().to_string()
        };
        let lane = attr("arrivalLane");
        let decl = net
            .find(&format!("<lane id=\"{lane}\" "))
            .unwrap_or_else(|| panic!("{lane} not in the network"));
        let length = net[decl..]
            .split("length=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert_eq!(
            attr("arrivalPos").parse::<f64>().unwrap(),
            length.parse::<f64>().unwrap(),
            "{line}"
        );
    }
}

/// `path` gzip-compressed into `to`.
fn gzip(path: &std::path::Path, to: &std::path::Path) {
    use std::io::Write;
    let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&std::fs::read(path).unwrap()).unwrap();
    std::fs::write(to, z.finish().unwrap()).unwrap();
}

#[test]
fn gzip_compressed_nets_and_routes_run_as_the_plain_files() {
    // SUMO reads any XML input compressed; users ship `.net.xml.gz` and `.rou.xml.gz`
    let dir = scratch_dir("sumo-gz");
    let src = root().join("scenarios/sumo/route_choice");
    gzip(
        &src.join("diamond.net.xml"),
        &dir.join("diamond.net.xml.gz"),
    );
    gzip(&src.join("trips.rou.xml"), &dir.join("trips.rou.xml.gz"));
    let cfg = dir.join("gz.sumocfg");
    std::fs::write(
        &cfg,
        std::fs::read_to_string(src.join("route_choice.sumocfg"))
            .unwrap()
            .replace("diamond.net.xml", "diamond.net.xml.gz")
            .replace("trips.rou.xml", "trips.rou.xml.gz"),
    )
    .unwrap();
    let runs = |cfg: &str| {
        let j = mapc_json(&["sim", cfg, "--seeds", "3", "--json"]);
        j["runs"].clone()
    };
    let plain = runs("scenarios/sumo/route_choice/route_choice.sumocfg");
    assert!(plain[0]["arrived"].as_u64().unwrap() > 0, "{plain}");
    assert_eq!(runs(cfg.to_str().unwrap()), plain);
    // a compressed net imports as a map too
    let graph = dir.join("g.graph.json");
    let import = run_mapc(&[
        "import",
        dir.join("diamond.net.xml.gz").to_str().unwrap(),
        "-o",
        graph.to_str().unwrap(),
    ]);
    assert!(
        import.status.success(),
        "{}",
        String::from_utf8_lossy(&import.stderr)
    );
    // a compressed file cut short is refused, named
    let gz = std::fs::read(dir.join("trips.rou.xml.gz")).unwrap();
    std::fs::write(dir.join("trips.rou.xml.gz"), &gz[..gz.len() / 2]).unwrap();
    refused(
        &["sim", cfg.to_str().unwrap(), "--seeds", "1"],
        &["trips.rou.xml.gz", "gzip-compressed"],
    );
}
