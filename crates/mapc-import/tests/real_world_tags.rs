//! Property tests over what real extracts hold: `lanes=2;3`, `turn:lanes`, `oneway=reversible|-1` on links,
//! roundabouts, `*_link` chains, areas, turn-restriction relations, duplicate and out-of-order elements in OSM;
//! traffic lights, roundabouts, `type` and `param` elements and odd lane speeds in SUMO nets. Every case is read
//! (with the counted warning it deserves) or refused with a message naming the file and the element: never a
//! panic, never a silently wrong graph.

use mapc_import::{ImportOptions, MapFormat, import_bytes};
use proptest::prelude::*;
use std::fmt::Write;

/// Node positions along a real stretch of I-696 (around osm:61862553), 1e-7 degree steps apart.
fn node(i: usize) -> (f64, f64) {
    (
        42.4869153 + 0.0009 * i as f64,
        -83.4764083 + 0.0011 * i as f64,
    )
}

#[derive(Clone, Debug)]
struct Case {
    lanes: &'static str,
    turn_lanes: bool,
    oneway: &'static str,
    roundabout: bool,
    area: bool,
    restriction: bool,
    duplicate_node: u8, // 0 none, 1 same place, 2 elsewhere
    duplicate_way: u8,  // 0 none, 1 same way, 2 other nodes
    ways_first: bool,
}

fn case() -> impl Strategy<Value = Case> {
    (
        prop::sample::select(vec!["", "2", "2;3", "0", "x", "3;2;1"]),
        any::<bool>(),
        prop::sample::select(vec!["", "yes", "-1", "reversible", "alternating", "maybe"]),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        0..3u8,
        0..3u8,
        any::<bool>(),
    )
        .prop_map(
            |(lanes, turn_lanes, oneway, roundabout, area, restriction, dn, dw, ways_first)| Case {
                lanes,
                turn_lanes,
                oneway,
                roundabout,
                area,
                restriction,
                duplicate_node: dn,
                duplicate_way: dw,
                ways_first,
            },
        )
}

/// A motorway (way 1: nodes 1-4), a link joining it (way 2: 10-11-2, `*_link` chain with way 3: 12-10), and
/// the case's special way 4 on nodes 20.. (a ring when it is a roundabout).
fn osm(c: &Case) -> String {
    let mut nodes = String::new();
    let ids = [1, 2, 3, 4, 10, 11, 12, 20, 21, 22];
    for (k, id) in ids.iter().enumerate() {
        let (lat, lon) = node(k);
        let _ = writeln!(
            nodes,
            "  <node id=\"{id}\" lat=\"{lat:.7}\" lon=\"{lon:.7}\"/>"
        );
    }
    match c.duplicate_node {
        1 => {
            let (lat, lon) = node(1);
            let _ = writeln!(
                nodes,
                "  <node id=\"2\" lat=\"{lat:.7}\" lon=\"{lon:.7}\"/>"
            );
        }
        2 => nodes.push_str("  <node id=\"2\" lat=\"43.4869153\" lon=\"-83.4764083\"/>\n"),
        _ => {}
    }
    let tag = |k: &str, v: &str| format!("    <tag k=\"{k}\" v=\"{v}\"/>\n");
    let way = |id: i64, nds: &[i64], tags: &str| {
        let mut w = format!("  <way id=\"{id}\">\n");
        for n in nds {
            let _ = writeln!(w, "    <nd ref=\"{n}\"/>");
        }
        w.push_str(tags);
        w.push_str("  </way>\n");
        w
    };
    let mut t1 = tag("highway", "motorway");
    t1.push_str(&tag("oneway", "yes"));
    if !c.lanes.is_empty() {
        t1.push_str(&tag("lanes", c.lanes));
    }
    if c.turn_lanes {
        t1.push_str(&tag("turn:lanes", "through|through|through;right"));
    }
    let mut t2 = tag("highway", "motorway_link");
    if !c.oneway.is_empty() {
        t2.push_str(&tag("oneway", c.oneway));
    }
    let t3 = tag("highway", "motorway_link");
    let (ring, mut t4) = if c.roundabout {
        (
            vec![20, 21, 22, 20],
            format!(
                "{}{}",
                tag("highway", "primary"),
                tag("junction", "roundabout")
            ),
        )
    } else {
        (vec![20, 21, 22, 3], tag("highway", "primary"))
    };
    if c.area {
        t4.push_str(&tag("area", "yes"));
    }
    let mut ways = [
        way(1, &[1, 2, 3, 4], &t1),
        way(3, &[12, 10], &t3),
        way(2, &[10, 11, 2], &t2),
        way(4, &ring, &t4),
    ]
    .concat();
    match c.duplicate_way {
        1 => ways.push_str(&way(3, &[12, 10], &t3)),
        2 => ways.push_str(&way(3, &[10, 12], &t3)),
        _ => {}
    }
    let relation = if c.restriction {
        "  <relation id=\"9\">\n    <member type=\"way\" ref=\"2\" role=\"from\"/>\n    <member type=\"node\" ref=\"2\" role=\"via\"/>\n    <member type=\"way\" ref=\"1\" role=\"to\"/>\n    <tag k=\"type\" v=\"restriction\"/>\n    <tag k=\"restriction\" v=\"no_u_turn\"/>\n  </relation>\n"
    } else {
        ""
    };
    let body = if c.ways_first {
        format!("{ways}{nodes}")
    } else {
        format!("{nodes}{ways}")
    };
    format!("<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n{body}{relation}</osm>\n")
}

fn sumo(speed: &str, extras: u8) -> String {
    let net = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../maps/simple_merge.net.xml"),
    )
    .unwrap();
    let mut net = net.replacen(
        "<lane id=\"left_0\" index=\"0\" speed=\"30.00\"",
        &format!("<lane id=\"left_0\" index=\"0\" speed=\"{speed}\""),
        1,
    );
    if extras & 1 != 0 {
        net = net.replacen(
            "    <edge id=",
            "    <type id=\"highwayType\" priority=\"3\" numLanes=\"1\" speed=\"30.00\"/>\n    <edge id=",
            1,
        );
    }
    if extras & 2 != 0 {
        net = net.replacen(
            "</net>",
            "    <tlLogic id=\"center\" type=\"actuated\" programID=\"0\" offset=\"0\">\n        <phase duration=\"42\" state=\"GG\"/>\n    </tlLogic>\n    <roundabout nodes=\"a b\" edges=\"x y\"/>\n</net>",
            1,
        );
    }
    if extras & 4 != 0 {
        // `param` children of an edge, a lane and a junction, as netconvert writes them
        net = net.replacen(
            "shape=\"100.00,139.82 586.80,139.82\"/>",
            "shape=\"100.00,139.82 586.80,139.82\">\n            <param key=\"origId\" value=\"7\"/>\n        </lane>\n        <param key=\"note\" value=\"x\"/>",
            1,
        );
        net = net.replacen(
            "        <request index=\"0\"",
            "        <param key=\"k\" value=\"v\"/>\n        <request index=\"0\"",
            1,
        );
    }
    net
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn osm_tag_and_element_cases(c in case()) {
        let text = osm(&c);
        let result = import_bytes(text.as_bytes(), MapFormat::OsmXml, "case.osm", &ImportOptions::default());
        if c.duplicate_way == 2 {
            let e = result.expect_err("a way id with two node lists is refused").to_string();
            prop_assert!(e.contains("way 3 appears twice") && e.contains("<way id=\"3\">"), "{}", e);
            return Ok(());
        }
        // (ways are read in the first pass, so a duplicate way is found first)
        if c.duplicate_node == 2 {
            let e = result.expect_err("a node id at two places is refused").to_string();
            prop_assert!(e.starts_with("case.osm") && e.contains("node 2 appears twice"), "{}", e);
            return Ok(());
        }
        let g = result.unwrap();
        prop_assert!(g.invariant_violations().is_empty(), "{:?}", g.invariant_violations());
        let w = &g.warnings.counts;
        let count = |k: &str| w.get(k).copied().unwrap_or(0);
        prop_assert_eq!(count("duplicate_node"), usize::from(c.duplicate_node == 1));
        prop_assert_eq!(count("duplicate_way"), usize::from(c.duplicate_way == 1));
        prop_assert_eq!(count("area_dropped"), usize::from(c.area));
        let dropped = matches!(c.oneway, "reversible" | "alternating");
        prop_assert_eq!(count("oneway_reversible_dropped"), usize::from(dropped));
        prop_assert_eq!(count("oneway_unknown"), usize::from(c.oneway == "maybe"));
        prop_assert_eq!(count("lanes_multiple_values"), usize::from(c.lanes.contains(';')));
        prop_assert_eq!(count("lanes_unparsed"), usize::from(matches!(c.lanes, "0" | "x")));
        prop_assert_eq!(count("turn_restriction_ignored"), usize::from(c.restriction));
        // Lanes of the motorway: the first of several values, else turn:lanes, else the class default.
        let motorway = g.find_roads("osm-way:1").unwrap();
        let lanes = g.road(motorway[0]).unwrap().lanes.len();
        let expected = match c.lanes {
            "2" | "2;3" => 2,
            "3;2;1" => 3,
            _ if c.turn_lanes => 3,
            _ => 2,
        };
        prop_assert_eq!(lanes, expected);
        // The link is driven against its drawing with oneway=-1, not at all when reversible.
        let link = g.find_roads("osm-way:2");
        if dropped {
            prop_assert!(link.is_err());
        } else {
            let r = g.road(link.unwrap()[0]).unwrap();
            let first = g.junction(r.from).unwrap().provenance.osm_nodes[0];
            prop_assert_eq!(first, if c.oneway == "-1" { 2 } else { 10 });
        }
        // Areas and rings: an area is gone; a roundabout ring is one-way roads that close on themselves.
        let special = g.find_roads("osm-way:4");
        prop_assert_eq!(special.is_err(), c.area);
        if let (Ok(ring), true) = (special, c.roundabout) {
            prop_assert!(ring.iter().all(|r| g.road(*r).unwrap().provenance.osm_ways == vec![4]));
            prop_assert_eq!(ring.len(), 1, "a ring touching nothing is one road");
        }
    }

    #[test]
    fn sumo_element_cases(speed in prop::sample::select(vec!["30.00", "0", "0.00", "400", "13.9"]), extras in 0..8u8) {
        let text = sumo(speed, extras);
        let result = import_bytes(text.as_bytes(), MapFormat::SumoNet, "case.net.xml", &ImportOptions::default());
        if speed.parse::<f64>().unwrap() == 0.0 {
            let e = result.expect_err("speed 0 is refused").to_string();
            prop_assert!(e.starts_with("case.net.xml") && e.contains("lane `left_0` has speed 0") && e.contains("line "), "{}", e);
            return Ok(());
        }
        match result {
            Ok(g) => {
                prop_assert!(g.invariant_violations().is_empty());
                let count = |k: &str| g.warnings.counts.get(k).copied().unwrap_or(0);
                prop_assert_eq!(count("traffic_light_ignored"), usize::from(extras & 2 != 0));
                prop_assert_eq!(count("speed_implausible"), usize::from(speed == "400"));
                // the speed is kept as the file says, never replaced
                let left = g.find_roads("left").unwrap()[0];
                prop_assert_eq!(g.road(left).unwrap().lanes[0].speed_mps, speed.parse::<f64>().unwrap());
            }
            Err(e) => prop_assert!(false, "{}", e),
        }
    }
}
