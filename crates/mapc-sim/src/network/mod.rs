//! The simulator's own view of a lane graph: one simulator lane per graph lane (with its road, index and
//! neighbours), one internal lane per lane-level connection, links with their right of way and merge foes, and
//! routes as lane sequences over a sequence of roads.
//!
//! Lane numbering: lane 0 of every road first (simulator lane `i` is lane 0 of graph road `i`), then the other
//! lanes of each road, then the internal lanes. On a graph with one lane per road this is exactly the
//! one-lane-per-road network (same indices, same links, same order).

pub mod best_lanes;
pub mod signals;

use crate::error::SimError;
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
    /// A lane of the road at this index of `LaneGraph::roads` (its index on the road is `SimLane::index`).
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
    /// Index on its road (0 = rightmost); 0 for via lanes.
    pub index: u8,
    /// The road's lane to the right (index - 1) and to the left (index + 1); none for via lanes.
    pub right: Option<LaneIdx>,
    pub left: Option<LaneIdx>,
    /// Links ending on this road lane (for followers behind its start).
    pub in_links: Vec<LinkIdx>,
    /// For a via lane: another connection runs beside it from its road to the same road. SUMO builds such
    /// connections as one internal edge of several lanes, which has a lane changer.
    pub beside_another: bool,
}

#[derive(Clone, Debug)]
pub struct SimLink {
    pub junction: mapc_graph::JunctionId,
    pub from_lane: LaneIdx,
    pub via_lane: LaneIdx,
    pub to_lane: LaneIdx,
    /// Drives on without yielding; zipper links too (SUMO counts `Z` as a priority state: no slowing for
    /// foes, no stop line), their turns taken by [`SimLink::zipper`].
    pub major: bool,
    /// One stream of a zipper merge: never waited at, its driver follows the foe that reaches the merge first.
    pub zipper: bool,
    /// Links into the same lane from another lane: they merge with this one.
    pub foes: Vec<LinkIdx>,
    /// The other links of its junction it yields to by the net's request table (a SUMO net): those that cross
    /// it, a left turn's oncoming stream. Read on a yielding green (`g`) and at an unsignalised minor link.
    pub crossing_foes: Vec<LinkIdx>,
    /// Its driver yields inside the junction (SUMO's `cont`): SUMO 1.8 skips the slow approach to the foe
    /// visibility point there.
    pub yields_inside: bool,
    /// The fixed-time light that controls it: (index into [`Network::lights`], index in its phases' states).
    pub signal: Option<(u32, u32)>,
}

#[derive(Clone, Debug)]
pub struct Network {
    pub lanes: Vec<SimLane>,
    pub links: Vec<SimLink>,
    pub road_ids: Vec<RoadId>,
    /// Lane 0 of each road.
    pub road_lane: HashMap<RoadId, LaneIdx>,
    /// Per graph road, its simulator lanes by index (right to left).
    pub road_lanes: Vec<Vec<LaneIdx>>,
    /// Some road has more than one lane (lane changing runs only then).
    pub multi_lane: bool,
    /// Lane labels for messages: `R3` (`R3_1` where some road has more lanes); via lanes `R1>R2` (`R1_0>R2_1`).
    pub lane_names: Vec<String>,
    /// The road of each lane for traces, lane index aside: `R3`; via lanes `R1>R2`.
    pub road_labels: Vec<String>,
    /// The graph's fixed-time traffic lights ([`signals`]).
    pub lights: Vec<mapc_graph::TrafficLight>,
    /// Best lanes' links already computed ([`Network::best_lane_path`]).
    pub best_links_memo: best_lanes::BestLinksMemo,
    /// Via lanes side by side between two roads whose links all have priority, right to left: SUMO builds each
    /// such group as one internal edge of several lanes and lets vehicles change lanes on it
    /// (`MSEdge::allowsLaneChanging`). Used under SUMO's junction rules only.
    pub via_groups: Vec<Vec<LaneIdx>>,
    /// Per lane: for a via lane of `via_groups`, its place among them; `None` for every other lane.
    pub via_beside: Vec<Option<ViaBeside>>,
    /// Some lane leads back to itself (a city grid, a ring): the moves cannot all see their leaders moved first
    /// ([`Network::compute_downstream`]'s order breaks each loop at one place).
    pub cyclic: bool,
}

/// A via lane's place in its group of [`Network::via_groups`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViaBeside {
    /// The index, on the road it leads to, of the lane it leads to: a vehicle on it reads that road's best lanes
    /// there (SUMO's LC2013 on an internal lane reads its successor's entry).
    pub index: u8,
    /// The via lanes of the group to its right and to its left.
    pub right: Option<LaneIdx>,
    pub left: Option<LaneIdx>,
    /// Its group's index in [`Network::via_groups`].
    pub group: u32,
}

/// The links between the same two roads, by the index of the lane they leave: their via lanes are marked
/// [`SimLane::beside_another`] where there are several, and form [`Network::via_groups`] (with
/// [`Network::via_beside`]) unless they lead to lanes that are not side by side, one of them yields, or one merges
/// with a link from another road (the last unlike SUMO, which lets a vehicle change in beside a foe's connection
/// and does not check collisions inside junctions by default).
fn side_by_side_groups(
    lanes: &mut [SimLane],
    links: &[SimLink],
) -> (Vec<Vec<LaneIdx>>, Vec<Option<ViaBeside>>) {
    let mut by_roads: std::collections::BTreeMap<(usize, usize), Vec<&SimLink>> =
        Default::default();
    for k in links {
        if let (LaneKind::Road(a), LaneKind::Road(b)) = (
            lanes[k.from_lane as usize].kind,
            lanes[k.to_lane as usize].kind,
        ) {
            by_roads.entry((a, b)).or_default().push(k);
        }
    }
    let mut groups = Vec::new();
    let mut beside = vec![None; lanes.len()];
    for (_, mut ks) in by_roads {
        for k in &ks {
            lanes[k.via_lane as usize].beside_another = ks.len() > 1;
        }
        // a connection that merges with another road's keeps its lane: mapc's junction model keeps the two
        // streams apart only for the vehicles that entered them, not for one changing in beside a foe
        if ks.len() < 2 || ks.iter().any(|k| !k.major || !k.foes.is_empty()) {
            continue;
        }
        ks.sort_by_key(|k| {
            (
                lanes[k.from_lane as usize].index,
                lanes[k.to_lane as usize].index,
            )
        });
        let to_index = |k: &SimLink| lanes[k.to_lane as usize].index as usize;
        if ks.windows(2).any(|w| to_index(w[1]) != to_index(w[0]) + 1) {
            continue;
        }
        let group: Vec<LaneIdx> = ks.iter().map(|k| k.via_lane).collect();
        for (i, k) in ks.iter().enumerate() {
            beside[k.via_lane as usize] = Some(ViaBeside {
                index: to_index(k) as u8,
                right: i.checked_sub(1).map(|j| group[j]),
                left: group.get(i + 1).copied(),
                group: groups.len() as u32,
            });
        }
        groups.push(group);
    }
    (groups, beside)
}

impl Network {
    /// Build from a lane graph: every graph lane a simulator lane, every lane-level connection a link.
    pub fn from_graph(g: &LaneGraph) -> Result<Network, SimError> {
        let multi_lane = g.roads.iter().any(|r| r.lanes.len() > 1);
        let mut lanes = Vec::with_capacity(g.roads.len() + g.connections.len());
        let mut road_lane = HashMap::new();
        let mut lane_names = Vec::new();
        let mut road_labels = Vec::new();
        let mut road_lanes: Vec<Vec<LaneIdx>> = Vec::with_capacity(g.roads.len());
        let lane_name = |r: &mapc_graph::Road, i: usize| {
            if multi_lane {
                format!("{}_{i}", r.id)
            } else {
                r.id.to_string()
            }
        };
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
            if r.lanes.is_empty() || r.lanes.len() > u8::MAX as usize {
                return Err(SimError::Network(format!(
                    "road {} has {} lanes",
                    r.id,
                    r.lanes.len()
                )));
            }
            road_lane.insert(r.id, i as LaneIdx);
            road_lanes.push(vec![i as LaneIdx]);
            lanes.push(road_sim_lane(i, 0, r.length_m, speed));
            lane_names.push(lane_name(r, 0));
            road_labels.push(r.id.to_string());
        }
        // the other lanes of each road after every road's lane 0 (so one-lane graphs keep their indices)
        for (i, r) in g.roads.iter().enumerate() {
            for (k, lane) in r.lanes.iter().enumerate().skip(1) {
                let speed = if lane.speed_mps > 0.0 {
                    lane.speed_mps
                } else {
                    r.speed_mps()
                };
                road_lanes[i].push(lanes.len() as LaneIdx);
                lanes.push(road_sim_lane(i, k as u8, r.length_m, speed));
                lane_names.push(lane_name(r, k));
                road_labels.push(r.id.to_string());
            }
            for k in 0..road_lanes[i].len() {
                let l = road_lanes[i][k] as usize;
                lanes[l].right = k.checked_sub(1).map(|j| road_lanes[i][j]);
                lanes[l].left = road_lanes[i].get(k + 1).copied();
            }
        }
        let road_index: HashMap<RoadId, usize> =
            g.roads.iter().enumerate().map(|(i, r)| (r.id, i)).collect();
        // One link per lane-level connection (repeated connections collapse into one).
        let mut links: Vec<SimLink> = Vec::new();
        let mut seen: HashMap<mapc_graph::ConnectionLanes, LinkIdx> = HashMap::new();
        // per link, the connections its own yields to
        let mut yields: Vec<&Vec<mapc_graph::ConnectionLanes>> = Vec::new();
        for c in &g.connections {
            if seen.contains_key(&c.lanes()) {
                continue;
            }
            let (Some(&fr), Some(&tr)) = (road_index.get(&c.from_road), road_index.get(&c.to_road))
            else {
                return Err(SimError::Network(format!(
                    "connection {} -> {} at {} names a missing road",
                    c.from_road, c.to_road, c.junction
                )));
            };
            let (Some(&from), Some(&to)) = (
                road_lanes[fr].get(c.from_lane as usize),
                road_lanes[tr].get(c.to_lane as usize),
            ) else {
                return Err(SimError::Network(format!(
                    "connection {} lane {} -> {} lane {} at {} names a missing lane",
                    c.from_road, c.from_lane, c.to_road, c.to_lane, c.junction
                )));
            };
            let link_idx = links.len() as LinkIdx;
            let via = lanes.len() as LaneIdx;
            let from_speed = lanes[from as usize].speed_limit;
            let to_speed = lanes[to as usize].speed_limit;
            let mut via_lane = road_sim_lane(0, 0, c.via_length_m.max(MIN_VIA_LENGTH_M), 0.0);
            via_lane.kind = LaneKind::Via(link_idx);
            via_lane.speed_limit = c
                .via_speed_mps
                .filter(|s| *s > 0.0)
                .unwrap_or(from_speed.min(to_speed));
            via_lane.via_target = Some(to);
            lanes.push(via_lane);
            lane_names.push(format!(
                "{}>{}",
                lane_names[from as usize], lane_names[to as usize]
            ));
            road_labels.push(format!("{}>{}", c.from_road, c.to_road));
            lanes[from as usize].out_links.push(link_idx);
            lanes[to as usize].in_links.push(link_idx);
            links.push(SimLink {
                junction: c.junction,
                from_lane: from,
                via_lane: via,
                to_lane: to,
                major: c.right_of_way != RightOfWay::Minor,
                zipper: c.right_of_way == RightOfWay::Zipper,
                foes: Vec::new(),
                crossing_foes: Vec::new(),
                yields_inside: c.yields_inside,
                signal: c.signal.as_ref().and_then(|s| {
                    g.lights
                        .iter()
                        .position(|l| l.id == s.light)
                        .map(|l| (l as u32, s.index))
                }),
            });
            seen.insert(c.lanes(), link_idx);
            yields.push(&c.yields_to);
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
        for (i, ys) in yields.iter().enumerate() {
            let crossing: Vec<LinkIdx> = ys
                .iter()
                .filter_map(|k| seen.get(k))
                .copied()
                .filter(|&j| j as usize != i && !links[i].foes.contains(&j))
                .collect();
            links[i].crossing_foes = crossing;
        }
        let (via_groups, via_beside) = side_by_side_groups(&mut lanes, &links);
        let mut net = Network {
            lanes,
            links,
            road_ids: g.roads.iter().map(|r| r.id).collect(),
            road_lane,
            road_lanes,
            multi_lane,
            lane_names,
            road_labels,
            lights: g.lights.clone(),
            best_links_memo: Default::default(),
            via_groups,
            via_beside,
            cyclic: false,
        };
        net.compute_downstream();
        Ok(net)
    }

    /// Longest downstream distance per lane, the moves' order (downstream lanes first). On a network with loops
    /// (a city grid) each loop is cut where the depth-first walk meets it again: the distance counts the lanes
    /// after the cut as ending there, and [`Network::cyclic`] is set. Without loops, every lane's successors are
    /// done when it is, and the distances are the longest paths.
    fn compute_downstream(&mut self) {
        let n = self.lanes.len();
        let mut state = vec![0u8; n]; // 0 new, 1 on stack, 2 done
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
                        1 => self.cyclic = true,
                        _ => {}
                    }
                } else {
                    // (a successor still on the walk's stack closes a loop: it is left out)
                    let best = succ
                        .iter()
                        .filter(|&&s| state[s as usize] == 2)
                        .map(|&s| self.lanes[s as usize].downstream_m)
                        .fold(0.0, f64::max);
                    self.lanes[lane].downstream_m = self.lanes[lane].length + best;
                    state[lane] = 2;
                    stack.pop();
                }
            }
        }
    }

    pub(crate) fn successors(&self, lane: LaneIdx) -> Vec<LaneIdx> {
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
    /// diverge: highest priority, then most lanes, then the smallest turning angle), starting on the rightmost of
    /// the first road's lanes that go furthest on it ([`Network::best_lanes`] with the shortest look-ahead), each
    /// road's link taken as a vehicle entering it would ([`Network::best_lane_path`]).
    pub fn route(
        &self,
        g: &LaneGraph,
        from: RoadId,
        to: Option<RoadId>,
    ) -> Result<Vec<LaneIdx>, SimError> {
        let roads = self.route_roads(g, from, &[], to)?;
        let (part, dead_end) = self.best_lane_path(self.start_lane(&roads), &roads, 0.0);
        self.past_dead_ends(&roads, part, dead_end)
    }

    /// `part`, a lane path from the start of `roads` that stops at a dead end where `dead_end`, on to the end of
    /// `roads`: a lane that ends on the way (one gained and dropped again far down a corridor) is left by a lane
    /// change on its road, so the line goes on from the nearest lane of that road that continues, in its place.
    pub fn past_dead_ends(
        &self,
        roads: &[usize],
        mut part: Vec<LaneIdx>,
        mut dead_end: bool,
    ) -> Result<Vec<LaneIdx>, SimError> {
        let (mut lanes, mut base) = (Vec::new(), 0);
        while dead_end {
            let k = base + part.iter().filter(|&&l| self.road_of(l).is_some()).count() - 1;
            let ending = part.pop().expect("a path holds its start");
            lanes.append(&mut part);
            let i = self.lanes[ending as usize].index as usize;
            let next = self.best_lanes(&roads[k..], 0.0);
            let Some(j) = (0..next.len())
                .filter(|&j| next[j].next_link.is_some())
                .min_by_key(|&j| (j.abs_diff(i), j))
            else {
                return Err(SimError::Network(format!(
                    "no connection from {} to {}",
                    self.road_ids[roads[k]],
                    self.road_ids[roads[k + 1]]
                )));
            };
            (part, dead_end) = self.best_lane_path(self.road_lanes[roads[k]][j], &roads[k..], 0.0);
            base = k;
        }
        lanes.append(&mut part);
        Ok(lanes)
    }

    /// The lanes a vehicle drives on the lane [`Network::route`] starts on, without changing lanes; `true` where
    /// they stop at a lane that does not continue on the route (the vehicle must change lanes before its end).
    pub fn route_without_changes(
        &self,
        g: &LaneGraph,
        from: RoadId,
        via: &[RoadId],
        to: Option<RoadId>,
    ) -> Result<(Vec<LaneIdx>, Vec<usize>, bool), SimError> {
        let roads = self.route_roads(g, from, via, to)?;
        let (lanes, dead_end) = self.best_lane_path(self.start_lane(&roads), &roads, 0.0);
        Ok((lanes, roads, dead_end))
    }

    /// The rightmost of the first road's lanes that go furthest on `roads`.
    fn start_lane(&self, roads: &[usize]) -> LaneIdx {
        let first = self.best_lanes(roads, 0.0);
        let top = first.iter().map(|q| q.length).fold(f64::MIN, f64::max);
        let start = first.iter().position(|q| q.length == top).unwrap_or(0);
        self.road_lanes[roads[0]][start]
    }

    /// The roads (indices into `LaneGraph::roads`) of the route from `from` through each of `via` in order to
    /// `to` (see [`Network::route`]); without `to`, on along the through roads after the last.
    pub fn route_roads(
        &self,
        g: &LaneGraph,
        from: RoadId,
        via: &[RoadId],
        to: Option<RoadId>,
    ) -> Result<Vec<usize>, SimError> {
        let index = |r: RoadId| -> Result<usize, SimError> {
            self.road_lane
                .get(&r)
                .map(|&i| i as usize)
                .ok_or_else(|| SimError::Network(format!("unknown road {r}")))
        };
        let mut start = index(from)?;
        let mut head = Vec::new();
        let mut last_id = from;
        for &v in via {
            let goal = index(v)?;
            if goal == start {
                continue;
            }
            let mut leg = self.road_path(start, goal).ok_or_else(|| {
                SimError::Network(format!(
                    "no route from {last_id} to {v}: the roads do not connect"
                ))
            })?;
            leg.pop();
            head.extend(leg);
            start = goal;
            last_id = v;
        }
        let mut rest = self.route_roads_from(g, start, last_id, to)?;
        if head.is_empty() {
            return Ok(rest);
        }
        head.append(&mut rest);
        Ok(head)
    }

    /// [`Self::route_roads`] from the road at index `start` (whose id is `from`) without stops.
    fn route_roads_from(
        &self,
        g: &LaneGraph,
        start: usize,
        from: RoadId,
        to: Option<RoadId>,
    ) -> Result<Vec<usize>, SimError> {
        match to {
            Some(to) => {
                let Some(&goal) = self.road_lane.get(&to) else {
                    return Err(SimError::Network(format!("unknown road {to}")));
                };
                self.road_path(start, goal as usize)
                    .ok_or_else(|| SimError::Network(format!("no route from {from} to {to}")))
            }
            None => {
                let mut path = vec![start];
                let mut cur = start;
                for _ in 0..self.lanes.len() {
                    let Some(next) = self.through_road(g, cur) else {
                        break;
                    };
                    path.push(next);
                    cur = next;
                }
                Ok(path)
            }
        }
    }

    /// Roads reached from the end of road `r` (any lane), in link order, each once.
    fn next_roads(&self, r: usize) -> Vec<usize> {
        let mut out = Vec::new();
        for to in self.roads_after(r) {
            if !out.contains(&to) {
                out.push(to);
            }
        }
        out
    }

    /// The road each link out of road `r` leads onto, in link order, repeated where several do.
    fn roads_after(&self, r: usize) -> impl Iterator<Item = usize> + '_ {
        self.road_lanes[r].iter().flat_map(move |&l| {
            self.lanes[l as usize]
                .out_links
                .iter()
                .map(move |&k| self.road_of(self.links[k as usize].to_lane).unwrap())
        })
    }

    /// Breadth-first road path (corridors have few alternatives; the first found is the fewest roads).
    fn road_path(&self, start: usize, goal: usize) -> Option<Vec<usize>> {
        if start == goal {
            return Some(vec![start]);
        }
        // a road that follows `start` (most legs between a route's consecutive roads) is the search's first find
        if self.roads_after(start).any(|r| r == goal) {
            return Some(vec![start, goal]);
        }
        const UNSEEN: usize = usize::MAX;
        let mut prev = vec![UNSEEN; self.road_lanes.len()];
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(cur) = queue.pop_front() {
            if cur == goal {
                let mut path = vec![cur];
                let mut c = cur;
                while prev[c] != UNSEEN {
                    c = prev[c];
                    path.push(c);
                }
                path.reverse();
                return Some(path);
            }
            for nxt in self.next_roads(cur) {
                if nxt != start && prev[nxt] == UNSEEN {
                    prev[nxt] = cur;
                    queue.push_back(nxt);
                }
            }
        }
        None
    }

    /// The road a through driver takes at the end of road `r`.
    pub fn through_road(&self, g: &LaneGraph, r: usize) -> Option<usize> {
        let from_road = &g.roads[r];
        self.next_roads(r).into_iter().min_by(|&a, &b| {
            let (ra, rb) = (&g.roads[a], &g.roads[b]);
            rb.priority
                .cmp(&ra.priority)
                .then(rb.lanes.len().cmp(&ra.lanes.len()))
                .then(turn_angle(from_road, ra).total_cmp(&turn_angle(from_road, rb)))
                .then(ra.id.cmp(&rb.id))
        })
    }
}

fn road_sim_lane(road: usize, index: u8, length: f64, speed_limit: f64) -> SimLane {
    SimLane {
        kind: LaneKind::Road(road),
        length,
        speed_limit,
        out_links: Vec::new(),
        via_target: None,
        downstream_m: 0.0,
        index,
        right: None,
        left: None,
        in_links: Vec::new(),
        beside_another: false,
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
