//! SUMO users' city networks through the binary: streets both ways (a network with loops), signalised junctions
//! whose left turns yield, and trips from an edge to itself, on sumo-rl's 3x3 grid (scenarios/sumo/sumo_rl_3x3grid).

mod common;
use common::*;

const GRID: &str = "scenarios/sumo/sumo_rl_3x3grid";

/// The grid's configuration with its files named absolutely and its end at `end_s`, written to a scratch folder.
fn grid_until(name: &str, end_s: u32) -> std::path::PathBuf {
    let dir = scratch_dir(name);
    let src = root().join(GRID);
    let text = std::fs::read_to_string(src.join("3x3grid.sumocfg"))
        .unwrap()
        .replace(
            "value=\"3x3Grid2lanes",
            &format!("value=\"{}/3x3Grid2lanes", src.display()),
        )
        .replace(
            "value=\"routes14000",
            &format!("value=\"{}/routes14000", src.display()),
        )
        .replace(
            "<end value=\"260000\"/>",
            &format!("<end value=\"{end_s}\"/>"),
        );
    assert!(text.contains(&format!("<end value=\"{end_s}\"/>")));
    let cfg = dir.join("grid.sumocfg");
    std::fs::write(&cfg, text).unwrap();
    cfg
}

/// The lane graph `mapc import` makes of `net` (a path from the repository's root), and a road's mapc id by its
/// SUMO edge id.
fn imported(
    net: &str,
    name: &str,
) -> (
    serde_json::Value,
    impl Fn(&str) -> serde_json::Value + use<>,
) {
    let dir = scratch_dir(name);
    let graph = dir.join("g.graph.json");
    assert_success(&run_mapc(&[
        "import",
        root().join(net).to_str().unwrap(),
        "-o",
        graph.to_str().unwrap(),
    ]));
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&graph).unwrap()).unwrap();
    let roads = g["roads"].clone();
    let road = move |sumo: &str| {
        roads
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["provenance"]["sumo_ids"][0] == sumo)
            .unwrap_or_else(|| panic!("no road of edge {sumo}"))
            .clone()
    };
    (g, road)
}

fn run_of(cfg: &std::path::Path, first_seed: u32) -> serde_json::Value {
    let j = mapc_json(&[
        "sim",
        cfg.to_str().unwrap(),
        "--seeds",
        "1",
        "--first-seed",
        &first_seed.to_string(),
        "--json",
    ]);
    j["runs"][0].clone()
}

#[test]
fn a_city_grid_with_loops_runs_as_its_configuration_says() {
    // the streets run both ways: the lanes form loops, which the simulator once refused
    let run = run_of(&grid_until("grid-loops", 3000), 0);
    // one vehicle every 2 s, each on its own route, no teleports (time-to-teleport -1)
    assert_eq!(run["departed"], 1500, "{run}");
    let arrived = run["arrived"].as_u64().unwrap();
    // about a minute and a half of travel: those still driving at the end are the last ones in
    assert!((1400..1500).contains(&arrived), "{run}");
    assert!(run["lane_changes"].as_u64().unwrap() > 0, "{run}");
}

#[test]
fn a_left_turn_waiting_at_its_light_does_not_hold_a_vehicle_inside_the_junction() {
    // seed 8 at 9 505 s: a vehicle crossing straight on green entered the junction as a left-turner of the cross
    // street stood at its red stop line, merging into the same lane. Braking for that foe, it stopped inside; once
    // the turn had its yielding green it waited for the vehicle inside: neither moved again, and the grid filled.
    let run = run_of(&grid_until("grid-junction", 11_000), 8);
    let (departed, arrived) = (
        run["departed"].as_u64().unwrap(),
        run["arrived"].as_u64().unwrap(),
    );
    assert_eq!(departed, 5500, "{run}");
    // some 50 vehicles drive the grid at a time; the deadlock held over 250 by 11 000 s
    assert!(departed - arrived < 100, "{run}");
}

#[test]
fn a_trip_from_an_edge_to_itself_drives_that_edge() {
    // RESCO's Cologne trips include some from an edge to itself: SUMO routes them as that edge alone
    let dir = scratch_dir("grid-self-trip");
    let routes = dir.join("self.rou.xml");
    std::fs::write(
        &routes,
        r#"<routes>
    <trip id="self" depart="0" from="1Ei" to="1Ei"/>
    <trip id="across" depart="1" from="1Ei" to="0Wo"/>
</routes>
"#,
    )
    .unwrap();
    let trips = dir.join("trips.xml");
    assert_success(&run_mapc(&[
        "sim",
        "--net",
        root()
            .join(GRID)
            .join("3x3Grid2lanes.net.xml")
            .to_str()
            .unwrap(),
        "--routes",
        routes.to_str().unwrap(),
        "--seeds",
        "1",
        "--tripinfo-output",
        trips.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&trips).unwrap();
    let route_length = |id: &str| -> f64 {
        let line = text
            .lines()
            .find(|l| l.contains(&format!("<tripinfo id=\"{id}\" ")))
            .unwrap_or_else(|| panic!("no trip of {id}:\n{text}"));
        let at = line.find("routeLength=\"").unwrap() + "routeLength=\"".len();
        line[at..].split('"').next().unwrap().parse().unwrap()
    };
    let (alone, across) = (route_length("self"), route_length("across"));
    // 1Ei alone, against 1Ei, a junction and 0Ei... to 0Wo
    assert!(alone > 50.0 && alone < 300.0, "{text}");
    assert!(across > alone + 100.0, "{text}");
}

const INGOLSTADT: &str = "scenarios/sumo/resco_ingolstadt1/ingolstadt1.sumocfg";

#[test]
fn sidewalks_are_left_out_and_sumos_lane_ids_kept_in_its_outputs() {
    // Ingolstadt's streets have a sidewalk as lane 0 (`allow="pedestrian"`): once driven as a car lane, every
    // vehicle entered on it and changed lanes strategically off it (1.56 changes a vehicle; SUMO 1.8: 0.57)
    let (_, road) = imported(
        "scenarios/sumo/resco_ingolstadt1/ingolstadt1.net.xml",
        "ingolstadt-sidewalks",
    );
    let road = road("201963537#1");
    assert_eq!(road["lanes"].as_array().unwrap().len(), 3, "{road}");
    assert_eq!(
        road["provenance"]["sumo_lanes"],
        serde_json::json!([1, 2, 3])
    );

    let trips = scratch_dir("ingolstadt-sidewalks-run").join("trips.xml");
    let j = mapc_json(&[
        "sim",
        INGOLSTADT,
        "--seeds",
        "1",
        "--json",
        "--tripinfo-output",
        trips.to_str().unwrap(),
    ]);
    let run = &j["runs"][0];
    let per_vehicle = run["lane_changes"].as_f64().unwrap() / run["departed"].as_f64().unwrap();
    assert!(per_vehicle < 0.8, "{run}");
    // the trip info names SUMO's lanes: a car departs on the street's lane 1, 2 or 3, never its sidewalk
    let text = std::fs::read_to_string(&trips).unwrap();
    assert!(
        text.contains("departLane=\"201963537#1_1\""),
        "{text:.2000}"
    );
    assert!(!text.contains("departLane=\"201963537#1_0\""));
}

#[test]
fn a_vehicle_departing_before_the_begin_is_left_out_and_the_trips_are_stamped_on_sumos_clock() {
    // RESCO's Cologne files hold a day's vehicles as SUMO's vehroute-output wrote them (`arrival` recorded) and
    // their configurations run an hour of it: SUMO 1.8 leaves out the vehicles before the begin
    let dir = scratch_dir("grid-begin");
    std::fs::write(
        dir.join("r.rou.xml"),
        r#"<routes>
    <vehicle id="early" depart="50.00" arrival="120.00"><route edges="1Ei 0Ei 0Wo"/></vehicle>
    <vehicle id="late" depart="150.00" arrival="220.00"><route edges="1Ei 0Ei 0Wo"/></vehicle>
</routes>
"#,
    )
    .unwrap();
    let net = root().join(GRID).join("3x3Grid2lanes.net.xml");
    std::fs::write(
        dir.join("c.sumocfg"),
        format!(
            r#"<configuration><input><net-file value="{}"/><route-files value="r.rou.xml"/></input>
<time><begin value="100"/><end value="400"/></time></configuration>"#,
            net.display()
        ),
    )
    .unwrap();
    let trips = dir.join("trips.xml");
    let out = run_mapc(&[
        "sim",
        dir.join("c.sumocfg").to_str().unwrap(),
        "--seeds",
        "1",
        "--tripinfo-output",
        trips.to_str().unwrap(),
    ]);
    assert_success(&out);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("1 vehicles depart before the begin"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // stamped on SUMO's clock, which reads the begin at the first step
    let text = std::fs::read_to_string(&trips).unwrap();
    assert!(
        text.contains("<tripinfo id=\"late\" depart=\"150.00\""),
        "{text}"
    );
    assert!(!text.contains("id=\"early\""), "{text}");
}

#[test]
fn a_vehicle_held_by_its_red_light_does_not_hold_a_yielding_green() {
    // The grid's left turns drive on a yielding green (`g`) and merge with the straight stream of the cross street,
    // which then has red. Its first vehicle, standing at the red stop line, made a request as if it would pass, and
    // the left-turner waited for it a whole phase: the grid's trips 3.4 % longer than SUMO's, left-turners' 6 to
    // 10 s. SUMO's driver that stops for its light makes no request. Mean trip of seed 0 to 3 000 s: 110.7 s
    // before, 104.8 s after (SUMO 1.8 over the whole run: 108.5 s).
    let run = run_of(&grid_until("grid-red-request", 3000), 0);
    let mean = run["mean_travel_time_s"].as_f64().unwrap();
    assert!(mean < 108.0, "{run}");
}

#[test]
fn a_left_turn_on_a_yielding_green_waits_for_the_crossing_stream() {
    // The net's request table says which links a link yields to, crossing ones too: the grid's left turn from
    // 5Wi's lane 1 into 2Si yields to the straight stream of 5Si into 2Si's lane 0 and to 5Si's own left turn,
    // which cross it without merging into its lane
    let (g, road_of) = imported(&format!("{GRID}/3x3Grid2lanes.net.xml"), "grid-crossing");
    let road = |sumo: &str| road_of(sumo)["id"].clone();
    let (w5, s2, s5, e4) = (road("5Wi"), road("2Si"), road("5Si"), road("4Ei"));
    let left = g["connections"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["from_road"] == w5 && c["from_lane"] == 1 && c["to_road"] == s2)
        .expect("5Wi's left turn");
    let yields = left["yields_to"].as_array().expect("its request's foes");
    let yields_to =
        |from: &serde_json::Value, from_lane: u64, to: &serde_json::Value, to_lane: u64| {
            yields.iter().any(|k| {
                k["from_road"] == *from
                    && k["from_lane"] == from_lane
                    && k["to_road"] == *to
                    && k["to_lane"] == to_lane
            })
        };
    assert!(yields_to(&s5, 0, &s2, 0), "{left}");
    assert!(yields_to(&s5, 1, &e4, 1), "{left}");
    // a left turn of the grid yields inside its junction (`cont="1"`, an internal junction), a straight link not
    assert_eq!(left["yields_inside"], true, "{left}");
    let straight = g["connections"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["from_road"] == s5 && c["to_road"] == s2)
        .expect("5Si's straight link");
    assert!(straight.get("yields_inside").is_none(), "{straight}");
    let cont = |c: &&serde_json::Value| c["yields_inside"] == true;
    assert_eq!(
        g["connections"]
            .as_array()
            .unwrap()
            .iter()
            .filter(cont)
            .count(),
        36,
        "the net's 36 requests with cont=\"1\""
    );
    // and the left-turners wait for them: seed 0's mean trip to 3 000 s, 104.8 s without, 106.5 s with
    let run = run_of(&grid_until("grid-crossing-run", 3000), 0);
    let mean = run["mean_travel_time_s"].as_f64().unwrap();
    assert!(mean > 105.5, "{run}");
}

#[test]
fn the_streams_a_left_turn_crosses_make_their_requests() {
    // Ingolstadt's left turn from 201963537#1 yields, by its junction's request table, to the oncoming straight
    // links, which no link merging with them yields to: their vehicles made no request, and the left-turners saw
    // none to wait for (trips 14.5 % shorter than SUMO's over ten seeds). Seed 0's mean trip: 46.1 s before,
    // 53.1 s after; SUMO 1.8, seeds 0-9: 53.3 s.
    let j = mapc_json(&["sim", INGOLSTADT, "--seeds", "1", "--json"]);
    let mean = j["runs"][0]["mean_travel_time_s"].as_f64().unwrap();
    assert!(mean > 50.0, "{}", j["runs"][0]);
}

#[test]
fn a_sumo_users_run_is_not_told_to_set_mapcs_warm_up() {
    // the horizon's fit (the corridor outflow's warning, "set warmup_steps") is mapc's own scenarios' matter: a
    // configuration has no such key, and its figures are SUMO's; the fit stays in the JSON
    let cfg = grid_until("grid-no-warmup-warning", 800);
    let out = run_mapc(&["sim", cfg.to_str().unwrap(), "--seeds", "1", "--json"]);
    assert_success(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("warmup_steps"), "{err}");
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(j["horizon_warning"].is_string(), "{j}");
}

#[test]
fn the_empty_hours_after_the_last_vehicle_count_their_steps_and_change_nothing() {
    // the grid is empty from about 14 100 s: the steps after it take the short way (nothing plans, moves or
    // changes lanes), and the run is the same run with more steps
    let ended = run_of(&grid_until("grid-empty-a", 15_000), 3);
    let longer = run_of(&grid_until("grid-empty-b", 20_000), 3);
    assert_eq!(ended["arrived"], 7000, "{ended}");
    assert_eq!(
        (ended["steps"].as_u64(), longer["steps"].as_u64()),
        (Some(15_000), Some(20_000))
    );
    for key in [
        "arrived",
        "departed",
        "mean_travel_time_s",
        "lane_changes",
        "vehicle_steps",
    ] {
        assert_eq!(ended[key], longer[key], "{key}");
    }
}
