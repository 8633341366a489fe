//! Flow's bottleneck benchmark (scenarios/flow_bottleneck.toml on maps/flow_bottleneck.net.xml, netconvert's build
//! of Flow's network, and the built-in `flow_bottleneck` on mapc's generator of the same network): the humans'
//! capacity drop, lane changing off as Flow's benchmarks drive, and the export to SUMO keeping the zippers' right
//! of way.

mod common;
use common::*;

const SCENARIO: &str = "scenarios/flow_bottleneck.toml";

/// The `<request>` lines of junction `id` in a SUMO network file.
fn requests(net: &str, id: &str) -> Vec<String> {
    let at = net
        .find(&format!("<junction id=\"{id}\""))
        .unwrap_or_else(|| panic!("no junction {id}"));
    let end = at + net[at..].find("</junction>").unwrap();
    net[at..end]
        .lines()
        .filter(|l| l.trim_start().starts_with("<request"))
        .map(|l| l.trim().to_string())
        .collect()
}

#[test]
fn the_export_keeps_the_zippers_foes_where_two_lanes_of_one_road_merge() {
    let dir = scratch_dir("flow-bottleneck-export");
    assert_success(&run_mapc(&[
        "export",
        SCENARIO,
        "--sumo",
        dir.to_str().unwrap(),
    ]));
    let exported = std::fs::read_to_string(dir.join("flow_bottleneck.net.xml")).unwrap();
    let source = std::fs::read_to_string("maps/flow_bottleneck.net.xml").unwrap();
    for zipper in ["4", "5"] {
        let (ours, theirs) = (requests(&exported, zipper), requests(&source, zipper));
        assert!(!theirs.is_empty());
        // netconvert's own bits: each pair of lanes are each other's foes (none was, when only lanes of two
        // different roads counted, and SUMO then drove the pairs into each other)
        assert_eq!(ours, theirs, "junction {zipper}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_humans_lose_capacity_at_the_zippers() {
    let j = mapc_json(&["sim", SCENARIO, "--seeds", "4", "--json"]);
    let inflow = j["inflow"]["mean"].as_f64().unwrap();
    let outflow = j["outflow"]["mean"].as_f64().unwrap();
    // 2 300 veh/h enter; the one lane after the second zipper passes far fewer (about 1 840)
    assert!(inflow > 2250.0, "{inflow}");
    assert!(outflow < 0.9 * inflow && outflow > 1500.0, "{outflow}");
}

/// A run's report without what names the scenario or times the run.
fn figures(args: &[&str]) -> serde_json::Value {
    let mut j = mapc_json(args);
    let o = j.as_object_mut().unwrap();
    for k in ["scenario", "wall_s"] {
        o.remove(k);
    }
    j
}

#[test]
fn the_built_in_bottleneck_generates_the_network_netconvert_builds_from_flows_parameters() {
    // every figure of every seed, humans and AVs, the same on the generated network as on netconvert's
    for extra in [&[][..], &["--av-share", "0.1"][..]] {
        let run = |scenario: &str| {
            let mut args = vec!["sim", scenario, "--seeds", "3", "--json"];
            args.extend_from_slice(extra);
            figures(&args)
        };
        assert_eq!(run("flow_bottleneck"), run(SCENARIO), "{extra:?}");
    }
    // Flow's parameters at scaling 2: eight lanes, merged pairwise twice
    let dir = scratch_dir("flow-bottleneck-scaled");
    let scaled = dir.join("scaled.toml");
    let text = std::fs::read_to_string(SCENARIO)
        .unwrap()
        .replace(
            "map = \"../maps/flow_bottleneck.net.xml\"",
            "flow_bottleneck = { scaling = 2 }",
        )
        .replace("vehs_per_hour = 2300.0", "vehs_per_hour = 4600.0");
    std::fs::write(&scaled, text).unwrap();
    let j = mapc_json(&["scenario", "show", scaled.to_str().unwrap(), "--json"]);
    // roads: 8 x 100 + 8 x 310 + 8 x 120 + 4 x 240 + 2 x 135 (each road at a zipper 20 m shorter);
    // internal lanes: 16 x 0.1 + 8 x 40.06 + 4 x 40.03
    let total = j["network"]["total_lane_length_m"].as_f64().unwrap();
    assert!((total - 5952.2).abs() < 0.05, "{total}");
    let out = run_mapc(&["sim", scaled.to_str().unwrap(), "--seeds", "1", "--json"]);
    assert_success(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn with_lane_changing_off_as_flows_benchmarks_the_humans_keep_their_lanes_and_still_lose_capacity()
{
    let j = mapc_json(&[
        "sim",
        "scenarios/flow_bottleneck_lc_off.toml",
        "--seeds",
        "4",
        "--json",
    ]);
    assert_eq!(j["lane_changes"]["mean"].as_f64(), Some(0.0), "{j}");
    let outflow = j["outflow"]["mean"].as_f64().unwrap();
    assert!(outflow > 1500.0 && outflow < 1950.0, "{outflow}");
}

#[test]
fn a_bad_generator_parameter_is_refused_naming_its_key() {
    let dir = scratch_dir("flow-bottleneck-bad");
    let text = std::fs::read_to_string(SCENARIO).unwrap();
    for (network, needle) in [
        (
            "flow_bottleneck = { scaling = 0 }",
            "network.flow_bottleneck.scaling must be 1 to 16, not 0",
        ),
        (
            "flow_bottleneck = { speed_limit_mps = 1e308 }",
            "network.flow_bottleneck.speed_limit_mps: 1e308 is outside",
        ),
        (
            "flow_bottleneck = { junction_radius_m = 200.0 }",
            "lengths_m[2] = 140 leaves no road between zippers of radius 200",
        ),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(
            &path,
            text.replace("map = \"../maps/flow_bottleneck.net.xml\"", network),
        )
        .unwrap();
        let out = run_mapc(&["sim", path.to_str().unwrap(), "--seeds", "1"]);
        assert_eq!(out.status.code(), Some(2), "{network}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{network}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
