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
