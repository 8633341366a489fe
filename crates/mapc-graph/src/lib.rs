//! # mapc-graph: the lane graph every mapc stage reads
//!
//! Glossary:
//! - **junction** (`J12`): a point where roads meet, start or end; its *kind* says what it does (merge: two roads
//!   in, one out; diverge: one in, two out; through; source; sink; complex).
//! - **road** (`R34`): one directed carriageway between two junctions, with its lanes, class (`motorway`, ...),
//!   name, ref, speed limit, centre line and length in metres.
//! - **lane**: one lane of a road, numbered from the right (0).
//! - **connection**: a lane-to-lane link across a junction, with the length driven inside the junction and the
//!   right of way (**major** drives on, **minor** yields).
//! - **provenance**: the OSM node and way ids or SUMO ids an element came from; ids themselves are opaque.
//! - **local frame**: metres east and north in UTM plus an offset, as SUMO's netconvert does ([`Projection`]).
//!
//! A graph is saved as versioned JSON (`*.graph.json`, [`FORMAT_NAME`] version [`FORMAT_VERSION`]); loading a file
//! of another version or format is an error that says so. Graphs, scenarios and policies are recognised by their
//! content, whatever their file name ([`filekind`]).

pub mod filekind;
pub mod ids;
pub mod index;
pub mod input;
pub mod io;
pub mod lookup;
pub mod markup;
pub mod model;
pub mod projection;
pub mod terminal;
pub mod topology;
pub mod validate;

pub use filekind::MapcFile;
pub use ids::{JunctionId, RoadId};
pub use index::RoadIndex;
pub use io::{
    GraphFileError, check_folder_creatable, check_writable, write_all_atomically, write_atomically,
    write_atomically_with,
};
pub use lookup::LookupError;
pub use model::*;
pub use projection::Projection;
pub use topology::Topology;

impl LaneGraph {
    /// An empty graph of the current format version.
    pub fn new(source: Source, projection: Projection) -> LaneGraph {
        LaneGraph {
            format: FORMAT_NAME.to_string(),
            version: FORMAT_VERSION,
            source,
            projection,
            junctions: Vec::new(),
            roads: Vec::new(),
            connections: Vec::new(),
            lights: Vec::new(),
            warnings: Warnings::default(),
        }
    }

    /// WGS84 `[lon, lat]` of a junction, when the graph has a geographic frame.
    pub fn junction_lonlat(&self, id: JunctionId) -> Option<[f64; 2]> {
        self.projection.to_lonlat(self.junction(id)?.pos)
    }

    pub fn count_kind(&self, kind: JunctionKind) -> usize {
        self.junctions.iter().filter(|j| j.kind == kind).count()
    }

    /// Connections leaving `road`.
    pub fn connections_from(&self, road: RoadId) -> impl Iterator<Item = &Connection> {
        self.connections.iter().filter(move |c| c.from_road == road)
    }
    /// Connections entering `road`.
    pub fn connections_to(&self, road: RoadId) -> impl Iterator<Item = &Connection> {
        self.connections.iter().filter(move |c| c.to_road == road)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::path::Path;

    /// A Y: two roads merge at J2 into one.
    pub(crate) fn tiny_merge() -> LaneGraph {
        let mut g = LaneGraph::new(
            Source {
                file: "test".into(),
                format: SourceFormat::Generator,
            },
            Projection::Plane { offset: [0.0, 0.0] },
        );
        let junction = |id, pos| Junction {
            id: JunctionId(id),
            pos,
            kind: JunctionKind::Through,
            incoming: vec![],
            outgoing: vec![],
            provenance: Provenance::sumo(format!("n{id}")),
        };
        g.junctions = vec![
            junction(0, [0.0, 0.0]),
            junction(1, [0.0, -100.0]),
            junction(2, [100.0, 0.0]),
            junction(3, [200.0, 0.0]),
        ];
        let road = |id, from: u32, to: u32, a: [f64; 2], b: [f64; 2], priority| Road {
            id: RoadId(id),
            from: JunctionId(from),
            to: JunctionId(to),
            class: "motorway".into(),
            name: None,
            ref_: None,
            priority,
            lanes: vec![Lane {
                shape: Vec::new(),
                index: 0,
                speed_mps: 30.0,
                width_m: 3.5,
                length_m: 100.0,
                end: None,
            }],
            geometry: vec![a, b],
            length_m: ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt(),
            provenance: Provenance::sumo(format!("e{id}")),
        };
        g.roads = vec![
            road(0, 0, 2, [0.0, 0.0], [100.0, 0.0], 1),
            road(1, 1, 2, [0.0, -100.0], [100.0, 0.0], 2),
            road(2, 2, 3, [100.0, 0.0], [200.0, 0.0], 1),
        ];
        for (from, row) in [(0, RightOfWay::Minor), (1, RightOfWay::Major)] {
            g.connections.push(Connection {
                via_lanes: Vec::new(),
                yields_to: Vec::new(),
                yields_inside: false,
                junction: JunctionId(2),
                from_road: RoadId(from),
                from_lane: 0,
                to_road: RoadId(2),
                to_lane: 0,
                via_length_m: 10.0,
                via_speed_mps: None,
                right_of_way: row,
                signal: None,
                right_of_way_overridden: false,
                provenance: Provenance::default(),
            });
        }
        g.rebuild_junction_links();
        g
    }

    #[test]
    fn junction_kinds_follow_the_roads() {
        let g = tiny_merge();
        assert_eq!(g.junction(JunctionId(2)).unwrap().kind, JunctionKind::Merge);
        assert_eq!(
            g.junction(JunctionId(0)).unwrap().kind,
            JunctionKind::Source
        );
        assert_eq!(g.junction(JunctionId(3)).unwrap().kind, JunctionKind::Sink);
        assert!(
            g.invariant_violations().is_empty(),
            "{:?}",
            g.invariant_violations()
        );
    }

    #[test]
    fn invariants_catch_a_dangling_road() {
        let mut g = tiny_merge();
        g.roads[2].to = JunctionId(99);
        assert!(
            g.invariant_violations()
                .iter()
                .any(|v| v.contains("missing junction J99"))
        );
    }

    #[test]
    fn lookups_by_mapc_and_sumo_ids() {
        let g = tiny_merge();
        assert_eq!(g.find_junction("J2").unwrap(), JunctionId(2));
        assert_eq!(g.find_junction("n1").unwrap(), JunctionId(1));
        assert!(g.find_junction("J9").is_err());
        assert_eq!(g.find_roads("e2").unwrap(), vec![RoadId(2)]);
        assert_eq!(g.find_roads("R1").unwrap(), vec![RoadId(1)]);
    }

    #[test]
    fn routes_and_distances() {
        let g = tiny_merge();
        assert_eq!(
            g.shortest_route(JunctionId(1), JunctionId(3)).unwrap(),
            vec![RoadId(1), RoadId(2)]
        );
        assert!(g.shortest_route(JunctionId(3), JunctionId(0)).is_none());
        let d = g.distances_from(JunctionId(0));
        assert!((d[&JunctionId(3)] - 200.0).abs() < 1e-9);
        assert_eq!(Topology::new(&g).component_count(), 1);
    }

    #[test]
    fn nearest_road_query() {
        let g = tiny_merge();
        let idx = RoadIndex::new(&g);
        let (rid, d) = idx.nearest_road([150.0, 3.0]).unwrap();
        assert_eq!(rid, RoadId(2));
        assert!((d - 3.0).abs() < 1e-9);
        assert_eq!(idx.roads_within([100.0, 0.0], 1.0).len(), 3);
    }

    #[test]
    fn file_round_trip_and_version_check() {
        let g = tiny_merge();
        let dir = std::env::temp_dir().join(format!("mapc-graph-test-{}", std::process::id()));
        let path = dir.join("tiny.graph.json");
        g.save(&path).unwrap();
        assert_eq!(LaneGraph::load(&path).unwrap(), g);

        let older = g.to_json().replacen("\"version\": 1", "\"version\": 0", 1);
        let err = LaneGraph::from_json(&older, Path::new("old.graph.json")).unwrap_err();
        assert!(
            matches!(err, GraphFileError::Version { found: 0, .. }),
            "{err}"
        );
        let err = LaneGraph::from_json("{\"type\": \"FeatureCollection\"}", Path::new("x.json"))
            .unwrap_err();
        assert!(err.to_string().contains("not a mapc graph file"), "{err}");
        let err = LaneGraph::from_json("{\"format\": ", Path::new("cut.json")).unwrap_err();
        assert!(err.to_string().starts_with("cut.json: line 1"), "{err}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
