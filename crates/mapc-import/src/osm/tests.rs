//! The OSM importer on small hand-made ways.

use super::graph::*;
use super::tags::*;
use super::*;
use crate::ImportOptions;
use mapc_graph::{JunctionKind, RightOfWay, RoadId, Source, Warnings};
use std::collections::HashMap;

#[test]
fn maxspeed_units() {
    assert!((parse_maxspeed("70 mph").unwrap() - 31.2928).abs() < 1e-9);
    assert!((parse_maxspeed("100").unwrap() - 27.777_777_777_777_78).abs() < 1e-9);
    assert!((parse_maxspeed("50 km/h").unwrap() - 13.888_888_888_888_89).abs() < 1e-9);
    assert_eq!(parse_maxspeed("US:urban"), None);
    assert_eq!(parse_maxspeed("none"), None);
}

#[test]
fn no_speed_limit_is_netconverts_speedlimit_none() {
    let mut w = Warnings::default();
    let autobahn = way(1, &[], &[("highway", "motorway"), ("maxspeed", "none")]);
    assert_eq!(speeds(&autobahn, &mut w), (39.4444, 39.4444));
    let one_way = way(
        2,
        &[],
        &[("highway", "primary"), ("maxspeed:forward", "none")],
    );
    let (forward, backward) = speeds(&one_way, &mut w);
    assert_eq!(forward, 39.4444);
    assert!(backward < forward);
    // a number is read, not a warning
    assert!(w.is_empty(), "{w:?}");
}

#[test]
fn degrees_are_checked() {
    assert_eq!(parse_degrees("-83.4877071", 180.0).unwrap(), -834_877_071);
    assert!(
        parse_degrees("abc", 90.0)
            .unwrap_err()
            .contains("not a number")
    );
    assert!(parse_degrees("91", 90.0).is_err());
    assert!(parse_degrees("NaN", 90.0).is_err());
}

fn way(id: i64, nodes: &[i64], tags: &[(&str, &str)]) -> OsmWay {
    let mut t = WayTags::default();
    for (k, v) in tags {
        t.set(k, v);
    }
    OsmWay {
        id,
        nodes: nodes.to_vec(),
        tags: t,
    }
}

#[test]
fn lanes_per_direction() {
    let mut w = Warnings::default();
    let two = Directions {
        forward: true,
        backward: true,
    };
    let one = Directions {
        forward: true,
        backward: false,
    };
    assert_eq!(
        lane_counts(
            &way(1, &[], &[("highway", "primary"), ("lanes", "5")]),
            two,
            &mut w
        ),
        (3, 2)
    );
    assert_eq!(
        lane_counts(
            &way(
                1,
                &[],
                &[
                    ("highway", "primary"),
                    ("lanes", "5"),
                    ("lanes:forward", "2")
                ]
            ),
            two,
            &mut w
        ),
        (2, 3)
    );
    assert_eq!(
        lane_counts(
            &way(1, &[], &[("highway", "motorway"), ("lanes", "4")]),
            one,
            &mut w
        ),
        (4, 0)
    );
    assert!(w.is_empty());
    assert_eq!(
        lane_counts(&way(1, &[], &[("highway", "motorway")]), one, &mut w),
        (2, 2)
    );
    assert_eq!(w.counts["lanes_defaulted"], 1);
}

#[test]
fn oneway_rules() {
    let mut w = Warnings::default();
    let d = |tags: &[(&str, &str)], w: &mut Warnings| {
        let d = directions(&way(1, &[], tags), w);
        (d.forward, d.backward)
    };
    assert_eq!(d(&[("highway", "motorway")], &mut w), (true, false));
    assert_eq!(d(&[("highway", "primary")], &mut w), (true, true));
    assert_eq!(
        d(&[("highway", "primary"), ("oneway", "-1")], &mut w),
        (false, true)
    );
    assert_eq!(
        d(&[("highway", "motorway"), ("oneway", "no")], &mut w),
        (true, true)
    );
    assert!(w.is_empty());
}

/// A Y of three ways: 2 and 3 join way 1 at node 20, which is also where way 1 is split.
#[test]
fn split_merge_and_right_of_way() {
    let nodes: HashMap<i64, NodePos> = [
        (10, (42.0, -83.0)),
        (20, (42.0, -82.99)),
        (30, (42.0, -82.98)),
        (40, (41.995, -83.0)),
        (41, (41.998, -82.995)),
    ]
    .into_iter()
    .map(|(id, (lat, lon))| {
        (
            id,
            NodePos {
                lat_e7: (lat * 1e7_f64).round() as i32,
                lon_e7: (lon * 1e7_f64).round() as i32,
            },
        )
    })
    .collect();
    let ways = vec![
        way(1, &[10, 20, 30], &[("highway", "motorway"), ("lanes", "2")]),
        way(2, &[40, 41, 20, 99], &[("highway", "motorway_link")]),
    ];
    let mut data = OsmData::default();
    for w in ways {
        data.add_way(w).unwrap();
    }
    data.nodes = nodes;
    let g = build_graph(
        data,
        Source {
            file: "t".into(),
            format: mapc_graph::SourceFormat::OsmXml,
        },
        &ImportOptions::default(),
    )
    .unwrap();
    assert!(
        g.invariant_violations().is_empty(),
        "{:?}",
        g.invariant_violations()
    );
    assert_eq!(g.junctions.len(), 4);
    assert_eq!(g.roads.len(), 3);
    let merge = g.find_junction("osm:20").unwrap();
    assert_eq!(g.junction(merge).unwrap().kind, JunctionKind::Merge);
    assert_eq!(g.warnings.counts["way_clipped_at_missing_node"], 1);
    let major: Vec<_> = g
        .connections
        .iter()
        .filter(|c| c.right_of_way == RightOfWay::Major && c.junction == merge)
        .collect();
    assert!(
        major
            .iter()
            .all(|c| g.road(c.from_road).unwrap().class == "motorway")
    );
    let r0 = g.road(RoadId(0)).unwrap();
    assert!((r0.length_m - 828.5).abs() < 1.0, "{}", r0.length_m);
    assert_eq!(r0.provenance.osm_nodes, vec![10, 20]);
}

#[test]
fn absurd_speed_limits_fall_back_on_the_class_default_with_a_warning() {
    let (_, motorway_default, _) = class_defaults("motorway");
    for maxspeed in [
        "1e-300",
        "1e308",
        "0.0000001",
        "650",
        "99999999999999999999",
    ] {
        let mut w = Warnings::default();
        let (fwd, bwd) = speeds(
            &way(1, &[], &[("highway", "motorway"), ("maxspeed", maxspeed)]),
            &mut w,
        );
        assert_eq!(
            (fwd, bwd),
            (motorway_default, motorway_default),
            "{maxspeed}"
        );
        assert_eq!(w.total(), 1, "{maxspeed}: {:?}", w.counts);
    }
    let mut w = Warnings::default();
    let (fwd, _) = speeds(
        &way(1, &[], &[("highway", "motorway"), ("maxspeed", "5")]),
        &mut w,
    );
    assert!((fwd - 5.0 / 3.6).abs() < 1e-12 && w.is_empty());
}
