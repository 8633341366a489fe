//! SUMO 1.8's best lanes (`MSVehicle::updateBestLanes`): for each lane of the road a vehicle is on, how far its
//! route can be followed from that lane's start without a lane change, looking a bounded distance ahead.
//!
//! Glossary:
//! - **look-ahead**: the roads of the route examined, the current one first: at least 5 roads, and more while
//!   their summed length stays under 3000 m (or the type's brake distance at its highest speed, if longer);
//!   past 9 roads only while it stays under 200 m (or that brake distance). What lies beyond does not count: all
//!   lanes of the last road examined go equally far.
//! - **continuation**: the lanes a lane leads to on the following roads of the look-ahead, each road's link
//!   chosen towards the lane that goes furthest (fewest changes needed there on a tie).
//! - **best lane offset**: lanes to move (negative: right) to reach the road's best lane.
//!
//! Lengths count road lanes only (as SUMO's, which leave internal lanes out). The result depends only on the
//! route's roads from the current one and on the look-ahead, so the simulator computes it once per route suffix
//! and vehicle type and reuses it (SUMO recomputes it when a vehicle enters a new road).

use crate::network::{LaneIdx, LinkIdx, Network};

/// Roads always examined beyond the current one before the distance bound applies (SUMO's "motorway" rule).
const MOTORWAY_ROADS: usize = 4;
/// The distance bound of the look-ahead (m).
pub const MOTORWAY_LOOK_AHEAD_M: f64 = 3000.0;
/// Past this many roads beyond the current one, the look-ahead also stops at [`URBAN_LOOK_AHEAD_M`].
const URBAN_ROADS: usize = 8;
const URBAN_LOOK_AHEAD_M: f64 = 200.0;

/// One lane of the current road as the route sees it (SUMO's `LaneQ`, occupation aside: it changes every step).
#[derive(Clone, Debug, PartialEq)]
pub struct BestLane {
    /// Distance (m) from the lane's start the route can be followed on it and its continuation without a lane
    /// change (the whole look-ahead where it gets through).
    pub length: f64,
    /// Lanes to move (negative: right) to the road's best lane (SUMO's `bestLaneOffset`).
    pub best_lane_offset: i32,
    /// The link to the next road on the continuation; none where the lane does not continue on the route or the
    /// look-ahead ends with this road.
    pub next_link: Option<LinkIdx>,
    /// The last lane of the continuation has outgoing links (a short lane that turns off the route rather than
    /// ending; SUMO: `bestContinuations.back()->getLinkCont().size() != 0`).
    pub leads_elsewhere: bool,
    /// The road lanes of the continuation after this one (whose vehicles are its `nextOccupation`).
    pub continuation: Vec<LaneIdx>,
}

/// A lane while the look-ahead is folded back from its last road.
#[derive(Clone, Debug)]
struct Q {
    lane: LaneIdx,
    length: f64,
    /// The lane's own length (the length a lane keeps when its link onwards has a lower priority than the best's).
    current_length: f64,
    offset: i32,
    /// The lane has a link to the next road of the route.
    allows_continuation: bool,
    next_link: Option<LinkIdx>,
    continuation: Vec<LaneIdx>,
}

/// The links onwards of each lane's best lanes, by the roads the look-ahead examined and the brake distance's bits:
/// a network's routes share most of them (a thousand vehicles with their own routes through one interchange), and
/// each costs a backward pass over its look-ahead. Filled as routes are built; the same for any order of them.
#[derive(Debug, Default)]
pub struct BestLinksMemo(std::sync::Mutex<BestLinksMap>);

type BestLinksMap = rustc_hash::FxHashMap<(Vec<usize>, u64), Vec<Option<LinkIdx>>>;

impl Clone for BestLinksMemo {
    fn clone(&self) -> Self {
        let map = self.0.lock().unwrap_or_else(|e| e.into_inner()).clone();
        BestLinksMemo(std::sync::Mutex::new(map))
    }
}

impl Network {
    /// How many roads of `roads` (the current one first) the look-ahead examines for a vehicle whose brake
    /// distance at its highest speed, plus its min gap, is `max_brake_dist` (m).
    pub fn look_ahead_roads(&self, roads: &[usize], max_brake_dist: f64) -> usize {
        let mut seen = 0;
        let mut length = 0.0;
        for &r in roads {
            seen += 1;
            length += self.lanes[self.road_lanes[r][0] as usize].length;
            let motorway =
                seen <= MOTORWAY_ROADS || length < max_brake_dist.max(MOTORWAY_LOOK_AHEAD_M);
            let urban = seen <= URBAN_ROADS || length < max_brake_dist.max(URBAN_LOOK_AHEAD_M);
            if !(motorway && urban) {
                break;
            }
        }
        seen
    }

    /// The best lanes of `roads[0]`, one per lane by index, for a route that drives `roads` (see the module doc;
    /// `max_brake_dist` as in [`Network::look_ahead_roads`]).
    pub fn best_lanes(&self, roads: &[usize], max_brake_dist: f64) -> Vec<BestLane> {
        let n = self.look_ahead_roads(roads, max_brake_dist);
        if n == 0 {
            return Vec::new();
        }
        let mut next = self.fresh_qs(roads, n - 1);
        // the last road examined: lanes shorter than the longest are sent to it
        let best_length = next.iter().map(|q| q.length).fold(f64::MIN, f64::max);
        let best_index = next
            .iter()
            .position(|q| q.length == best_length)
            .unwrap_or(0);
        for (i, q) in next.iter_mut().enumerate() {
            if q.length < best_length {
                q.offset = best_index as i32 - i as i32;
            }
        }
        for k in (0..n - 1).rev() {
            let mut cur = self.fresh_qs(roads, k);
            self.fold_back(&mut cur, &next, roads[k]);
            next = cur;
        }
        next.into_iter()
            .map(|q| {
                let last = q.continuation.last().copied().unwrap_or(q.lane);
                BestLane {
                    length: q.length,
                    best_lane_offset: q.offset,
                    next_link: q.next_link,
                    leads_elsewhere: !self.lanes[last as usize].out_links.is_empty(),
                    continuation: q.continuation,
                }
            })
            .collect()
    }

    /// The lanes of road `roads[k]` before the fold: their own lengths, and whether they reach `roads[k + 1]`.
    fn fresh_qs(&self, roads: &[usize], k: usize) -> Vec<Q> {
        let next_road = roads.get(k + 1).copied();
        self.road_lanes[roads[k]]
            .iter()
            .map(|&l| {
                let lane = &self.lanes[l as usize];
                Q {
                    lane: l,
                    length: lane.length,
                    current_length: lane.length,
                    offset: 0,
                    allows_continuation: next_road.is_none_or(|nr| {
                        lane.out_links
                            .iter()
                            .any(|&k| self.road_of(self.links[k as usize].to_lane) == Some(nr))
                    }),
                    next_link: None,
                    continuation: Vec::new(),
                }
            })
            .collect()
    }

    /// One road of the backward pass: each lane of `cur` (on road `road`) takes the best lane of `next` it has a
    /// link to, then the road's best lane is chosen and every other lane's offset points to it.
    fn fold_back(&self, cur: &mut [Q], next: &[Q], road: usize) {
        let link_to = |from: &Q, to: LaneIdx| -> Option<LinkIdx> {
            self.lanes[from.lane as usize]
                .out_links
                .iter()
                .copied()
                .find(|&k| self.links[k as usize].to_lane == to)
        };
        let approached_from_road = |m: &Q| {
            self.lanes[m.lane as usize]
                .in_links
                .iter()
                .any(|&k| self.road_of(self.links[k as usize].from_lane) == Some(road))
        };
        let mut best_connected_length = -1.0_f64;
        let mut best_length = -1.0_f64;
        for m in next {
            if approached_from_road(m) && best_connected_length < m.length {
                best_connected_length = m.length;
            }
            if best_length < m.length {
                best_length = m.length;
            }
        }
        if !(best_connected_length > 0.0) {
            // no lane of this road reaches the next one: a disconnected route (routes are built over links, so
            // this does not happen); the lanes keep their own lengths
            return;
        }
        let mut best_this = 0usize;
        for j in 0..cur.len() {
            if cur[j].allows_continuation {
                let mut chosen: Option<(&Q, LinkIdx)> = None;
                for m in next {
                    let Some(link) = link_to(&cur[j], m.lane) else {
                        continue;
                    };
                    let better = chosen.is_none_or(|(c, _)| {
                        c.length < m.length
                            || (c.length == m.length && c.offset.abs() > m.offset.abs())
                    });
                    if better {
                        chosen = Some((m, link));
                    }
                }
                if let Some((m, link)) = chosen {
                    let q = &mut cur[j];
                    if m.length == best_connected_length && m.offset.abs() < 2 {
                        q.length += best_length;
                    } else {
                        q.length += m.length;
                    }
                    q.offset = m.offset;
                    q.next_link = Some(link);
                    q.continuation.push(m.lane);
                    q.continuation.extend_from_slice(&m.continuation);
                }
            }
            let (b, q) = (&cur[best_this], &cur[j]);
            if b.length < q.length
                || (b.length == q.length && b.offset.abs() > q.offset.abs())
                || (b.length == q.length
                    && b.offset.abs() == q.offset.abs()
                    && self.next_link_priority(b) < self.next_link_priority(q))
            {
                best_this = j;
            }
        }
        let best = cur[best_this].clone();
        let best_priority = self.next_link_priority(&best);
        for (i, q) in cur.iter_mut().enumerate() {
            let lower_priority = self.next_link_priority(q) < best_priority;
            if q.length < best.length
                || (q.length == best.length && q.offset.abs() > best.offset.abs())
                || lower_priority
            {
                q.offset = best_this as i32 - i as i32;
                if lower_priority {
                    // leave a lane whose link onwards yields to the best lane's before it ends
                    q.length = q.current_length;
                }
            } else {
                q.offset = 0;
            }
        }
    }

    /// SUMO's `nextLinkPriority`: 1 where the lane's link onwards is major, 0 where minor, -1 without one.
    fn next_link_priority(&self, q: &Q) -> i32 {
        q.next_link
            .map_or(-1, |k| i32::from(self.links[k as usize].major))
    }

    /// The lanes driven from road lane `start` (on `roads[0]`) along `roads` without changing lanes, taking at
    /// each road the link `next_link(k, lane index)` names for the lane reached on `roads[k]`; `true` when the
    /// path stops at a lane without one (it does not continue on the route).
    pub fn lane_path(
        &self,
        start: LaneIdx,
        roads: &[usize],
        mut next_link: impl FnMut(usize, usize) -> Option<LinkIdx>,
    ) -> (Vec<LaneIdx>, bool) {
        let mut lanes = vec![start];
        let mut cur = start;
        for k in 0..roads.len().saturating_sub(1) {
            let Some(link) = next_link(k, self.lanes[cur as usize].index as usize) else {
                return (lanes, true);
            };
            let lk = &self.links[link as usize];
            lanes.push(lk.via_lane);
            lanes.push(lk.to_lane);
            cur = lk.to_lane;
        }
        (lanes, false)
    }

    /// [`Network::lane_path`] following at each road the best lanes a vehicle computes on entering it (with the
    /// look-ahead of `max_brake_dist`).
    pub fn best_lane_path(
        &self,
        start: LaneIdx,
        roads: &[usize],
        max_brake_dist: f64,
    ) -> (Vec<LaneIdx>, bool) {
        let mut memo = self
            .best_links_memo
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        self.lane_path(start, roads, |k, i| {
            // the best lanes of a road depend on the roads its look-ahead examines and the one after them (whether
            // the last examined lanes continue): routes that share them share the links
            let n = self.look_ahead_roads(&roads[k..], max_brake_dist);
            let window = &roads[k..(k + n + 1).min(roads.len())];
            let key = (window.to_vec(), max_brake_dist.to_bits());
            let links = memo.entry(key).or_insert_with(|| {
                self.best_lanes(window, max_brake_dist)
                    .iter()
                    .map(|b| b.next_link)
                    .collect()
            });
            links.get(i).copied().flatten()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mapc_graph::{
        Connection, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection, Provenance,
        RightOfWay, Road, RoadId, Source, SourceFormat,
    };

    /// A straight chain of roads of `length` m with `lanes[i]` lanes each; lane j goes on to lane j of the next
    /// road where that exists (a road with fewer lanes drops the left ones).
    fn chain(lanes: &[usize], length: f64) -> LaneGraph {
        let mut g = LaneGraph::new(
            Source {
                file: "test".into(),
                format: SourceFormat::Generator,
            },
            Projection::Plane { offset: [0.0, 0.0] },
        );
        for i in 0..=lanes.len() as u32 {
            g.junctions.push(Junction {
                id: JunctionId(i),
                pos: [i as f64 * length, 0.0],
                kind: JunctionKind::Through,
                incoming: vec![],
                outgoing: vec![],
                provenance: Provenance::default(),
            });
        }
        for (i, &n) in lanes.iter().enumerate() {
            let x = i as f64 * length;
            g.roads.push(Road {
                id: RoadId(i as u32),
                from: JunctionId(i as u32),
                to: JunctionId(i as u32 + 1),
                class: "motorway".into(),
                name: None,
                ref_: None,
                priority: 1,
                lanes: (0..n as u8)
                    .map(|index| Lane {
                        shape: Vec::new(),
                        index,
                        speed_mps: 30.0,
                        width_m: 3.5,
                        length_m: length,
                        end: None,
                    })
                    .collect(),
                geometry: vec![[x, 0.0], [x + length, 0.0]],
                length_m: length,
                provenance: Provenance::default(),
            });
            if let Some(&m) = lanes.get(i + 1) {
                for lane in 0..n.min(m) as u8 {
                    g.connections.push(Connection {
                        via_lanes: Vec::new(),
                        yields_to: Vec::new(),
                        yields_inside: false,
                        junction: JunctionId(i as u32 + 1),
                        from_road: RoadId(i as u32),
                        from_lane: lane,
                        to_road: RoadId(i as u32 + 1),
                        to_lane: lane,
                        via_length_m: 5.0,
                        via_speed_mps: None,
                        right_of_way: RightOfWay::Major,
                        signal: None,
                        right_of_way_overridden: false,
                        provenance: Provenance::default(),
                    });
                }
            }
        }
        g.rebuild_junction_links();
        g
    }

    fn lengths_and_offsets(best: &[BestLane]) -> Vec<(f64, i32)> {
        best.iter()
            .map(|q| (q.length, q.best_lane_offset))
            .collect()
    }

    #[test]
    fn a_lane_drop_beyond_the_look_ahead_does_not_count() {
        // two lanes for 7 km, then one: the left lane ends 7 km from the start
        let g = chain(&[2, 2, 2, 2, 2, 2, 2, 1], 1000.0);
        let net = Network::from_graph(&g).unwrap();
        let roads: Vec<usize> = (0..8).collect();
        // from the first road, 5 roads (5 km) are examined: both lanes go all the way
        assert_eq!(net.look_ahead_roads(&roads, 0.0), 5);
        let first = net.best_lanes(&roads, 0.0);
        assert_eq!(lengths_and_offsets(&first), [(5000.0, 0), (5000.0, 0)]);
        assert_eq!(first[1].continuation.len(), 4);
        // from the fourth road the drop is seen: the left lane goes 4 km, 1 km short, and must go right
        let fourth = net.best_lanes(&roads[3..], 0.0);
        assert_eq!(lengths_and_offsets(&fourth), [(5000.0, 0), (4000.0, -1)]);
        // its continuation ends on the dropped lane, which has no link: it does not lead elsewhere
        assert!(!fourth[1].leads_elsewhere);
        assert_eq!(fourth[1].continuation.len(), 3);
        // on the road where it ends, the lane keeps only its own length
        let seventh = net.best_lanes(&roads[6..], 0.0);
        assert_eq!(lengths_and_offsets(&seventh), [(2000.0, 0), (1000.0, -1)]);
        assert!(seventh[1].next_link.is_none());
        // a brake distance above 3 km lengthens the look-ahead
        assert_eq!(net.look_ahead_roads(&roads, 6500.0), 7);
    }

    #[test]
    fn many_short_roads_stop_the_look_ahead_past_200_m() {
        let g = chain(&[2; 20], 30.0);
        let net = Network::from_graph(&g).unwrap();
        let roads: Vec<usize> = (0..20).collect();
        // 9 roads (270 m) at least; then at 200 m, or at the brake distance when longer
        assert_eq!(net.look_ahead_roads(&roads, 0.0), 9);
        assert_eq!(net.look_ahead_roads(&roads, 400.0), 14);
        // the route's end stops it too
        assert_eq!(net.look_ahead_roads(&roads[17..], 0.0), 3);
    }

    #[test]
    fn lengths_leave_internal_lanes_out_and_the_route_end_counts_whole() {
        let g = chain(&[2, 2, 2], 100.0);
        let net = Network::from_graph(&g).unwrap();
        let best = net.best_lanes(&[0, 1, 2], 0.0);
        assert_eq!(lengths_and_offsets(&best), [(300.0, 0), (300.0, 0)]);
        let path = net.best_lane_path(net.road_lanes[0][1], &[0, 1, 2], 0.0);
        assert_eq!(path.0.len(), 5);
        assert!(!path.1);
        assert!(path.0.iter().all(|&l| net.lanes[l as usize].index <= 1));
    }
}
