//! The simulator's own view of a lane graph: one lane per road, one internal lane per connection, links with
//! their right of way and merge foes, and routes as lane sequences.

use crate::SimError;
use mapc_graph::{LaneGraph, RightOfWay, RoadId};
use std::collections::HashMap;

/// Internal lanes shorter than this are lengthened to it (SUMO's shortest internal lane).
pub const MIN_VIA_LENGTH_M: f64 = 0.1;
/// Distance before a minor link from which a driver sees all foes and may go (SUMO's default visibility).
pub const FOE_VISIBILITY_M: f64 = 4.5;

pub type LaneIdx = u32;
pub type LinkIdx = u32;

/// What a simulator lane stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaneKind {
    /// Lane 0 of the road at this index of `LaneGraph::roads`.
    Road(usize),
    /// The internal lane of a link (the connection inside its junction).
    Via(LinkIdx),
}

#[derive(Clone, Debug)]
pub struct SimLane {
    pub kind: LaneKind,
    pub length: f64,
    pub speed_limit: f64,
    /// Links leaving the end of a road lane (empty for via lanes and sinks).
    pub out_links: Vec<LinkIdx>,
    /// For a via lane, the road lane it leads to.
    pub via_target: Option<LaneIdx>,
    /// Longest distance from the start of this lane to the end of the network.
    pub downstream_m: f64,
}

#[derive(Clone, Debug)]
pub struct SimLink {
    pub junction: mapc_graph::JunctionId,
    pub from_lane: LaneIdx,
    pub via_lane: LaneIdx,
    pub to_lane: LaneIdx,
    pub major: bool,
    /// Links of the same junction into the same road from another road: they merge with this one.
    pub foes: Vec<LinkIdx>,
}

#[derive(Clone, Debug)]
pub struct Network {
    pub lanes: Vec<SimLane>,
    pub links: Vec<SimLink>,
    pub road_ids: Vec<RoadId>,
    pub road_lane: HashMap<RoadId, LaneIdx>,
    /// Road labels for traces: `R3`; via lanes `R1>R2`.
    pub lane_names: Vec<String>,
}

impl Network {
    /// Build from a lane graph of one lane a road. A graph with several lanes on a road (`simplify --keep-lanes`,
    /// or a map as imported) is refused rather than simulated on one of its lanes.
    pub fn from_graph(g: &LaneGraph) -> Result<Network, SimError> {
        if let Some(r) = g.roads.iter().find(|r| r.lanes.len() > 1) {
            return Err(SimError::Network(format!(
                "the graph of `{}`: road {} has {} lanes; multi-lane simulation needs lane changing, which mapc-sim \
                 does not model yet (it drives one lane a road): simplify the map without --keep-lanes",
                g.source.file,
                r.id,
                r.lanes.len()
            )));
        }
        let mut lanes = Vec::with_capacity(g.roads.len() + g.connections.len());
        let mut road_lane = HashMap::new();
        let mut lane_names = Vec::new();
        for (i, r) in g.roads.iter().enumerate() {
            if !(r.length_m > 0.0) || !r.length_m.is_finite() {
                return Err(SimError::Network(format!(
                    "road {} has length {} m",
                    r.id, r.length_m
                )));
            }
            let speed = r.speed_mps();
            if !(speed > 0.0) {
                return Err(SimError::Network(format!(
                    "road {} has speed limit {} m/s",
                    r.id, speed
                )));
            }
            road_lane.insert(r.id, i as LaneIdx);
            lanes.push(SimLane {
                kind: LaneKind::Road(i),
                length: r.length_m,
                speed_limit: speed,
                out_links: Vec::new(),
                via_target: None,
                downstream_m: 0.0,
            });
            lane_names.push(r.id.to_string());
        }
        // One link per (from road, to road): several lane-level connections collapse into one.
        let mut links: Vec<SimLink> = Vec::new();
        let mut seen: HashMap<(RoadId, RoadId), LinkIdx> = HashMap::new();
        for c in &g.connections {
            if seen.contains_key(&(c.from_road, c.to_road)) {
                continue;
            }
            let (Some(&from), Some(&to)) = (road_lane.get(&c.from_road), road_lane.get(&c.to_road))
            else {
                return Err(SimError::Network(format!(
                    "connection {} -> {} at {} names a missing road",
                    c.from_road, c.to_road, c.junction
                )));
            };
            let link_idx = links.len() as LinkIdx;
            let via = lanes.len() as LaneIdx;
            let from_speed = lanes[from as usize].speed_limit;
            let to_speed = lanes[to as usize].speed_limit;
            lanes.push(SimLane {
                kind: LaneKind::Via(link_idx),
                length: c.via_length_m.max(MIN_VIA_LENGTH_M),
                speed_limit: c
                    .via_speed_mps
                    .filter(|s| *s > 0.0)
                    .unwrap_or(from_speed.min(to_speed)),
                out_links: Vec::new(),
                via_target: Some(to),
                downstream_m: 0.0,
            });
            lane_names.push(format!("{}>{}", c.from_road, c.to_road));
            lanes[from as usize].out_links.push(link_idx);
            links.push(SimLink {
                junction: c.junction,
                from_lane: from,
                via_lane: via,
                to_lane: to,
                major: c.right_of_way == RightOfWay::Major,
                foes: Vec::new(),
            });
            seen.insert((c.from_road, c.to_road), link_idx);
        }
        for i in 0..links.len() {
            let foes: Vec<LinkIdx> = (0..links.len())
                .filter(|&j| {
                    j != i
                        && links[j].to_lane == links[i].to_lane
                        && links[j].from_lane != links[i].from_lane
                })
                .map(|j| j as LinkIdx)
                .collect();
            links[i].foes = foes;
        }
        let mut net = Network {
            lanes,
            links,
            road_ids: g.roads.iter().map(|r| r.id).collect(),
            road_lane,
            lane_names,
        };
        net.compute_downstream()?;
        Ok(net)
    }

    /// Longest downstream distance per lane; fails on a cycle (a corridor never has one).
    fn compute_downstream(&mut self) -> Result<(), SimError> {
        let n = self.lanes.len();
        let mut state = vec![0u8; n]; // 0 new, 1 on stack, 2 done
        let mut order = Vec::with_capacity(n);
        for start in 0..n {
            if state[start] != 0 {
                continue;
            }
            let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
            state[start] = 1;
            while let Some(&mut (lane, ref mut k)) = stack.last_mut() {
                let succ = self.successors(lane as LaneIdx);
                if *k < succ.len() {
                    let s = succ[*k] as usize;
                    *k += 1;
                    match state[s] {
                        0 => {
                            state[s] = 1;
                            stack.push((s, 0));
                        }
                        1 => {
                            return Err(SimError::Network(format!(
                                "the network has a cycle through {}; only corridors without loops can be simulated",
                                self.lane_names[s]
                            )));
                        }
                        _ => {}
                    }
                } else {
                    state[lane] = 2;
                    order.push(lane);
                    stack.pop();
                }
            }
        }
        for &lane in &order {
            let best = self
                .successors(lane as LaneIdx)
                .iter()
                .map(|&s| self.lanes[s as usize].downstream_m)
                .fold(0.0, f64::max);
            self.lanes[lane].downstream_m = self.lanes[lane].length + best;
        }
        Ok(())
    }

    fn successors(&self, lane: LaneIdx) -> Vec<LaneIdx> {
        let l = &self.lanes[lane as usize];
        match l.kind {
            LaneKind::Road(_) => l
                .out_links
                .iter()
                .map(|&k| self.links[k as usize].via_lane)
                .collect(),
            LaneKind::Via(_) => l.via_target.into_iter().collect(),
        }
    }

    /// The road index in the graph of a road lane.
    pub fn road_of(&self, lane: LaneIdx) -> Option<usize> {
        match self.lanes[lane as usize].kind {
            LaneKind::Road(i) => Some(i),
            LaneKind::Via(_) => None,
        }
    }

    /// Route as lanes from `from` to `to` (or, without `to`, downstream to a sink taking the through road at each
    /// diverge: highest priority, then most lanes, then the smallest turning angle).
    pub fn route(
        &self,
        g: &LaneGraph,
        from: RoadId,
        to: Option<RoadId>,
    ) -> Result<Vec<LaneIdx>, SimError> {
        let &start = self
            .road_lane
            .get(&from)
            .ok_or_else(|| SimError::Network(format!("unknown road {from}")))?;
        let roads: Vec<RoadId> = match to {
            Some(to) => {
                if !self.road_lane.contains_key(&to) {
                    return Err(SimError::Network(format!("unknown road {to}")));
                }
                self.road_path(from, to)
                    .ok_or_else(|| SimError::Network(format!("no route from {from} to {to}")))?
            }
            None => {
                let mut path = vec![from];
                let mut cur = start;
                for _ in 0..self.lanes.len() {
                    let Some(next) = self.through_link(g, cur) else {
                        break;
                    };
                    let to_lane = self.links[next as usize].to_lane;
                    path.push(self.road_ids[self.road_of(to_lane).unwrap()]);
                    cur = to_lane;
                }
                path
            }
        };
        let mut lanes = vec![self.road_lane[&roads[0]]];
        for w in roads.windows(2) {
            let a = self.road_lane[&w[0]];
            let b = self.road_lane[&w[1]];
            let link = self.lanes[a as usize]
                .out_links
                .iter()
                .copied()
                .find(|&k| self.links[k as usize].to_lane == b)
                .ok_or_else(|| {
                    SimError::Network(format!("no connection from {} to {}", w[0], w[1]))
                })?;
            lanes.push(self.links[link as usize].via_lane);
            lanes.push(b);
        }
        Ok(lanes)
    }

    /// Breadth-first road path (corridors have few alternatives; the first found is the fewest roads).
    fn road_path(&self, from: RoadId, to: RoadId) -> Option<Vec<RoadId>> {
        let start = self.road_lane[&from];
        let goal = self.road_lane[&to];
        let mut prev: HashMap<LaneIdx, LaneIdx> = HashMap::new();
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(cur) = queue.pop_front() {
            if cur == goal {
                let mut path = vec![cur];
                let mut c = cur;
                while let Some(&p) = prev.get(&c) {
                    path.push(p);
                    c = p;
                }
                path.reverse();
                return Some(
                    path.into_iter()
                        .map(|l| self.road_ids[self.road_of(l).unwrap()])
                        .collect(),
                );
            }
            for &k in &self.lanes[cur as usize].out_links {
                let nxt = self.links[k as usize].to_lane;
                if nxt != start && !prev.contains_key(&nxt) {
                    prev.insert(nxt, cur);
                    queue.push_back(nxt);
                }
            }
        }
        None
    }

    /// The link a through driver takes at the end of road lane `lane`.
    pub fn through_link(&self, g: &LaneGraph, lane: LaneIdx) -> Option<LinkIdx> {
        let outs = &self.lanes[lane as usize].out_links;
        let from_road = &g.roads[self.road_of(lane)?];
        outs.iter().copied().min_by(|&a, &b| {
            let ra = &g.roads[self.road_of(self.links[a as usize].to_lane).unwrap()];
            let rb = &g.roads[self.road_of(self.links[b as usize].to_lane).unwrap()];
            rb.priority
                .cmp(&ra.priority)
                .then(rb.lanes.len().cmp(&ra.lanes.len()))
                .then(turn_angle(from_road, ra).total_cmp(&turn_angle(from_road, rb)))
                .then(ra.id.cmp(&rb.id))
        })
    }
}

/// Absolute heading change (radians) from the end of `a` to the start of `b`.
fn turn_angle(a: &mapc_graph::Road, b: &mapc_graph::Road) -> f64 {
    let heading = |p: [f64; 2], q: [f64; 2]| (q[1] - p[1]).atan2(q[0] - p[0]);
    let n = a.geometry.len();
    if n < 2 || b.geometry.len() < 2 {
        return 0.0;
    }
    let h1 = heading(a.geometry[n - 2], a.geometry[n - 1]);
    let h2 = heading(b.geometry[0], b.geometry[1]);
    let mut d = (h2 - h1).abs() % (2.0 * std::f64::consts::PI);
    if d > std::f64::consts::PI {
        d = 2.0 * std::f64::consts::PI - d;
    }
    d
}
