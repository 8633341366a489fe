//! Nearest-road queries with an R*-tree over road segments.

use crate::ids::RoadId;
use crate::model::LaneGraph;
use rstar::primitives::{GeomWithData, Line};
use rstar::{PointDistance, RTree};

type Segment = GeomWithData<Line<[f64; 2]>, RoadId>;

pub struct RoadIndex {
    tree: RTree<Segment>,
}

impl RoadIndex {
    pub fn new(g: &LaneGraph) -> RoadIndex {
        let segments: Vec<Segment> = g
            .roads
            .iter()
            .flat_map(|r| {
                r.geometry
                    .windows(2)
                    .map(move |w| GeomWithData::new(Line::new(w[0], w[1]), r.id))
            })
            .collect();
        RoadIndex {
            tree: RTree::bulk_load(segments),
        }
    }

    /// The road whose centre line passes nearest `pos`, with the distance in metres.
    pub fn nearest_road(&self, pos: [f64; 2]) -> Option<(RoadId, f64)> {
        self.tree
            .nearest_neighbor(pos)
            .map(|s| (s.data, s.geom().distance_2(&pos).sqrt()))
    }

    /// Every road with a segment within `radius_m` of `pos`, nearest first, each once.
    pub fn roads_within(&self, pos: [f64; 2], radius_m: f64) -> Vec<(RoadId, f64)> {
        let mut found: Vec<(RoadId, f64)> = Vec::new();
        for s in self.tree.locate_within_distance(pos, radius_m * radius_m) {
            let d = s.geom().distance_2(&pos).sqrt();
            match found.iter_mut().find(|(id, _)| *id == s.data) {
                Some(entry) => entry.1 = entry.1.min(d),
                None => found.push((s.data, d)),
            }
        }
        found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        found
    }
}
