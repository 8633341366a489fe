//! Flow's bottleneck benchmark (scenarios/flow_bottleneck.toml on maps/flow_bottleneck.net.xml, netconvert's build
//! of Flow's network): the humans' capacity drop, and its export to SUMO keeping the zippers' right of way.

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
