//! The export of a multi-lane scenario (`two_lane_merge`) parsed back as XML (no SUMO needed): every lane of each
//! edge side by side at mapc's lengths, lane-level connections with their internal lanes, the acceleration lane
//! ending without a connection onward, the flows' `departLane` from mapc's `depart_lane`, and one-step lane changes.

use mapc_scenario::ResolvedScenario;
use quick_xml::events::Event;
use quick_xml::{Reader, XmlVersion};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Every element of `path` as (name, attributes), in document order.
fn elements(path: &Path) -> Vec<(String, HashMap<String, String>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut reader = Reader::from_str(&text);
    let mut out = Vec::new();
    loop {
        match reader.read_event().unwrap() {
            Event::Start(e) | Event::Empty(e) => {
                let attrs = e
                    .attributes()
                    .map(|a| {
                        let a = a.unwrap();
                        (
                            a.key.as_ref().to_string(),
                            a.normalized_value(XmlVersion::Implicit1_0)
                                .unwrap()
                                .into_owned(),
                        )
                    })
                    .collect();
                out.push((e.name().as_ref().to_string(), attrs));
            }
            Event::Eof => return out,
            _ => {}
        }
    }
}

fn points(shape: &str) -> Vec<[f64; 2]> {
    shape
        .split(' ')
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            [x.parse().unwrap(), y.parse().unwrap()]
        })
        .collect()
}

#[test]
fn two_lane_merge_exports_every_lane_its_connections_and_depart_lanes() {
    let rs = ResolvedScenario::load("two_lane_merge").unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-sumo-two-lane-{}", std::process::id()));
    mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let names = mapc_sumo::names::SumoNames::of(&rs.graph);
    let net = elements(&dir.join("two_lane_merge.net.xml"));

    // Lanes per normal edge, with mapc's lengths and speeds, side by side one lane width apart.
    let mut lanes: HashMap<String, Vec<&HashMap<String, String>>> = HashMap::new();
    for (name, a) in &net {
        if name == "lane" && !a["id"].starts_with(':') {
            let (edge, _) = a["id"].rsplit_once('_').unwrap();
            lanes.entry(edge.to_string()).or_default().push(a);
        }
    }
    let mut multi = 0;
    for (i, road) in rs.graph.roads.iter().enumerate() {
        let got = &lanes[&names.edges[i]];
        assert_eq!(got.len(), road.lanes.len(), "lanes of {}", names.edges[i]);
        for (k, (a, lane)) in got.iter().zip(&road.lanes).enumerate() {
            assert_eq!(a["index"], k.to_string());
            let length: f64 = a["length"].parse().unwrap();
            assert!(
                (length - lane.length_m).abs() < 1e-3,
                "{}: length {length}",
                a["id"]
            );
            let speed: f64 = a["speed"].parse().unwrap();
            assert!(
                (speed - lane.speed_mps).abs() < 0.01,
                "{}: speed {speed}",
                a["id"]
            );
        }
        if road.lanes.len() > 1 {
            multi += 1;
            for k in 1..got.len() {
                let (p, q) = (points(&got[k - 1]["shape"]), points(&got[k]["shape"]));
                let apart = (q[0][0] - p[0][0]).hypot(q[0][1] - p[0][1]);
                let width = (road.lanes[k - 1].width_m + road.lanes[k].width_m) / 2.0;
                assert!(
                    (apart - width).abs() < 0.01,
                    "{}: lanes {apart} m apart",
                    names.edges[i]
                );
            }
        }
    }
    assert!(
        multi >= 3,
        "the main road's edges have two lanes, the one after the merge three"
    );

    // One connection per lane-level connection of the graph, each through its own internal lane, and one on
    // from each internal lane.
    let connections: Vec<_> = net
        .iter()
        .filter(|(n, _)| n == "connection")
        .map(|(_, a)| a)
        .collect();
    let (through, onward): (Vec<_>, Vec<_>) = connections
        .iter()
        .partition(|a| !a["from"].starts_with(':'));
    assert_eq!(through.len(), rs.graph.connections.len());
    assert_eq!(onward.len(), rs.graph.connections.len());
    let edge_of = |id| {
        let i = rs
            .graph
            .roads
            .binary_search_by_key(&id, |r: &mapc_graph::Road| r.id)
            .unwrap();
        names.edges[i].clone()
    };
    for c in &rs.graph.connections {
        let (from, to) = (edge_of(c.from_road), edge_of(c.to_road));
        let found = through.iter().find(|a: &&&HashMap<String, String>| {
            a["from"] == from
                && a["to"] == to
                && a["fromLane"] == c.from_lane.to_string()
                && a["toLane"] == c.to_lane.to_string()
        });
        let found = found.unwrap_or_else(|| {
            panic!("no connection {from}_{} -> {to}_{}", c.from_lane, c.to_lane)
        });
        let via = found["via"].rsplit_once('_').unwrap().0;
        assert!(
            onward
                .iter()
                .any(|a| a["from"] == via && a["to"] == to && a["toLane"] == c.to_lane.to_string()),
            "internal edge {via} does not lead on to {to}_{}",
            c.to_lane
        );
    }
    // The acceleration lane (the rightmost lane of the road after the merge) has no connection onward.
    let post = rs
        .graph
        .roads
        .iter()
        .position(|r| r.lanes.len() == 3)
        .expect("the road after the merge has the acceleration lane");
    assert!(
        through
            .iter()
            .any(|a| a["from"] == names.edges[post] && a["fromLane"] == "1")
    );
    assert!(
        !through
            .iter()
            .any(|a| a["from"] == names.edges[post] && a["fromLane"] == "0")
    );

    // Flows depart on mapc's lanes; the vehicle type leaves the lane-change model at SUMO's default (LC2013).
    let routes = elements(&dir.join("two_lane_merge.rou.xml"));
    let depart: HashMap<&str, &str> = routes
        .iter()
        .filter(|(n, _)| n == "flow")
        .map(|(_, a)| (a["id"].as_str(), a["departLane"].as_str()))
        .collect();
    assert_eq!(
        depart,
        HashMap::from([("main_right", "0"), ("main_left", "1"), ("ramp", "free")])
    );
    for (n, a) in &routes {
        if n == "vType" {
            assert!(!a.contains_key("laneChangeModel"), "{a:?}");
            assert!(!a.keys().any(|k| k.starts_with("lc")), "{a:?}");
        }
    }
    let cfg = elements(&dir.join("two_lane_merge.sumocfg"));
    assert!(
        cfg.iter()
            .any(|(n, a)| n == "lanechange.duration" && a["value"] == "0")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn one_lane_config_is_unchanged() {
    let rs = ResolvedScenario::load("simple_merge").unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-sumo-one-lane-{}", std::process::id()));
    mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let cfg = elements(&dir.join("simple_merge.sumocfg"));
    assert!(!cfg.iter().any(|(n, _)| n == "lanechange.duration"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The lane-drop bottleneck exports its three lanes, the rightmost without a connection onward (SUMO's lane
/// drop), one flow per lane, and a manifest that names the corridor's end for `sumo_check`'s measurement.
#[test]
fn lane_drop_exports_the_ending_lane_without_a_connection_and_its_measurement_points() {
    let rs = ResolvedScenario::load("lane_drop").unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-sumo-lane-drop-{}", std::process::id()));
    mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let net = elements(&dir.join("lane_drop.net.xml"));
    let lanes_of = |edge: &str| {
        net.iter()
            .filter(|(n, a)| n == "lane" && a["id"].starts_with(&format!("{edge}_")))
            .count()
    };
    assert_eq!((lanes_of("upstream"), lanes_of("downstream")), (3, 2));
    let mut links: Vec<(String, String)> = net
        .iter()
        .filter(|(n, a)| n == "connection" && a["from"] == "upstream")
        .map(|(_, a)| (a["fromLane"].clone(), a["toLane"].clone()))
        .collect();
    links.sort();
    assert_eq!(
        links,
        vec![("1".into(), "0".into()), ("2".into(), "1".into())]
    );
    let routes = elements(&dir.join("lane_drop.rou.xml"));
    let mut depart: Vec<&str> = routes
        .iter()
        .filter(|(n, _)| n == "flow")
        .map(|(_, a)| a["departLane"].as_str())
        .collect();
    depart.sort();
    assert_eq!(depart, vec!["0", "1", "2"]);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("lane_drop.mapc.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["end_edge"], "downstream");
    assert_eq!(manifest["measure_points"], serde_json::json!([]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_sumo_users_side_by_side_connections_export_as_one_internal_edge_and_mapcs_own_one_per_connection()
 {
    // ramp_metering_1x3: the main road's three lanes go on through one internal edge of three lanes, as in the
    // user's network (`:merge_beginning_1`), so that SUMO keeps LC2013's memory there as mapc does under SUMO's
    // rules; the ramp's one connection has an edge of its own
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg"
    );
    let rs = ResolvedScenario::load(cfg).unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-sumo-side-by-side-{}", std::process::id()));
    let summary = mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let net_file = summary
        .files
        .iter()
        .find(|f| f.ends_with(".net.xml"))
        .unwrap();
    let net = elements(&dir.join(net_file));
    let mut internal_lanes: HashMap<String, Vec<String>> = HashMap::new();
    let mut current = String::new();
    for (name, a) in &net {
        match name.as_str() {
            "edge" => current = a.get("function").map_or(String::new(), |_| a["id"].clone()),
            "lane" if !current.is_empty() => internal_lanes
                .entry(current.clone())
                .or_default()
                .push(a["index"].clone()),
            _ => {}
        }
    }
    let vias: Vec<&HashMap<String, String>> = net
        .iter()
        .filter(|(n, a)| {
            n == "connection" && a["from"] == "main_road" && a["to"] == "acceleration_area"
        })
        .map(|(_, a)| a)
        .collect();
    assert_eq!(vias.len(), 3);
    let edge = vias[0]["via"].rsplit_once('_').unwrap().0.to_string();
    assert!(
        vias.iter()
            .all(|a| a["via"].starts_with(&format!("{edge}_")))
    );
    assert_eq!(internal_lanes[&edge], ["0", "1", "2"]);
    // each lane of it goes on to the lane its connection names
    for a in &vias {
        let lane = a["via"].rsplit_once('_').unwrap().1;
        assert!(net.iter().any(|(n, b)| n == "connection"
            && b["from"] == edge
            && b["fromLane"] == lane
            && b["toLane"] == a["toLane"]));
    }
    let ramp: Vec<_> = net
        .iter()
        .filter(|(n, a)| n == "connection" && a["from"] == "passage_area")
        .collect();
    assert_eq!(ramp.len(), 1);
    let ramp_edge = ramp[0].1["via"].rsplit_once('_').unwrap().0;
    assert_eq!(internal_lanes[ramp_edge], ["0"]);

    // mapc's own two-lane merge: one internal edge of one lane per connection
    let rs = ResolvedScenario::load("two_lane_merge").unwrap();
    let dir = dir.join("own");
    mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let net = elements(&dir.join("two_lane_merge.net.xml"));
    let mut lanes_per_internal: HashMap<String, usize> = HashMap::new();
    let mut current = String::new();
    for (name, a) in &net {
        match name.as_str() {
            "edge" => current = a.get("function").map_or(String::new(), |_| a["id"].clone()),
            "lane" if !current.is_empty() => {
                *lanes_per_internal.entry(current.clone()).or_default() += 1
            }
            _ => {}
        }
    }
    assert!(!lanes_per_internal.is_empty());
    assert!(lanes_per_internal.values().all(|&n| n == 1));
}
