//! SUMO's list of active lanes (`MSEdgeControl::myActiveLanes`), kept under SUMO's junction rules: the lane-change
//! pass visits the roads (and junction connections side by side) in the order their lanes stand in it. A lane
//! whose road has a lane changer joins at the front when it gets vehicles again, any other at the back; a lane
//! leaves when it empties. The order decides whether a driver asked to make room by a vehicle on another road
//! hears it before its own turn in the pass (and so changes lanes in the same step) or only after it.

use super::*;
use std::collections::VecDeque;

#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct ActiveLanes {
    order: VecDeque<LaneIdx>,
    active: Vec<bool>,
    /// Per lane, the vehicles that entered it in this step's moves.
    entered: Vec<u32>,
    /// The lanes of `entered` above 0 (each once).
    entered_lanes: Vec<LaneIdx>,
    /// Roads and groups already visited in this step's pass.
    visited_roads: Vec<bool>,
    visited_groups: Vec<bool>,
    /// Per lane, its rank among the lanes by SUMO's lane id: the order in which SUMO takes in the vehicles that
    /// entered lanes in a step.
    id_rank: Vec<u32>,
    /// Per lane, its rank in SUMO's numbering: the order in which SUMO activates the lanes vehicles were
    /// inserted on.
    number_rank: Vec<u32>,
    /// The lanes vehicles were put on since the last step's start ([`Simulation::place`]): the only lanes that
    /// can hold vehicles without being in the list then.
    pub(in crate::sim) placed: Vec<LaneIdx>,
    /// Buffers kept between steps so that the bookkeeping allocates nothing.
    joining: Vec<LaneIdx>,
    pub(in crate::sim) edges: Vec<ChangerEdge>,
}

/// A road or a group of junction connections side by side: what SUMO's lane changer works on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::sim) enum ChangerEdge {
    Road(usize),
    Group(usize),
}

impl Simulation {
    /// Whether the run keeps SUMO's list of active lanes: under SUMO's junction rules, on a network where lanes
    /// change.
    #[inline]
    pub(in crate::sim) fn keeps_active_lanes(&self) -> bool {
        self.spec.sumo_junction_lane_changes && self.net.multi_lane
    }

    /// The road or group whose lane changer covers `lane` (SUMO's `haveNeighbors`), if any.
    pub(in crate::sim) fn changer_edge(&self, lane: LaneIdx) -> Option<ChangerEdge> {
        let l = self.lane_at(lane as usize);
        match l.kind {
            LaneKind::Road(r) => (self.net.road_lanes[r].len() > 1).then_some(ChangerEdge::Road(r)),
            LaneKind::Via(_) => {
                self.net.via_beside[lane as usize].map(|b| ChangerEdge::Group(b.group as usize))
            }
        }
    }

    fn join_active(&mut self, lane: LaneIdx) {
        let a = &mut self.active_lanes;
        if a.active[lane as usize] {
            return;
        }
        a.active[lane as usize] = true;
        if self.changer_edge(lane).is_some() {
            self.active_lanes.order.push_front(lane);
        } else {
            self.active_lanes.order.push_back(lane);
        }
    }

    /// At a step's start (SUMO's `patchActiveLanes`, then `planMovements`): the lanes vehicles were inserted on
    /// join in SUMO's numbering order; the lanes that emptied leave.
    pub(in crate::sim) fn activate_lanes_at_step_start(&mut self) {
        let n = self.net.lanes.len();
        if self.active_lanes.active.len() != n {
            self.active_lanes.active = vec![false; n];
            self.active_lanes.entered = vec![0; n];
            (self.active_lanes.id_rank, self.active_lanes.number_rank) =
                sumo_lane_ranks(&self.spec.graph, &self.net);
        }
        let mut joining = std::mem::take(&mut self.active_lanes.joining);
        joining.clear();
        joining.extend(self.active_lanes.placed.drain(..).filter(|&l| {
            !self.active_lanes.active[l as usize] && !self.lane_veh[l as usize].is_empty()
        }));
        joining.sort_by_key(|&l| self.active_lanes.number_rank[l as usize]);
        joining.dedup();
        debug_assert_eq!(joining, {
            let mut all: Vec<LaneIdx> = (0..n as LaneIdx)
                .filter(|&l| {
                    !self.active_lanes.active[l as usize] && !self.lane_veh[l as usize].is_empty()
                })
                .collect();
            all.sort_by_key(|&l| self.active_lanes.number_rank[l as usize]);
            all
        });
        for &l in &joining {
            self.join_active(l);
        }
        self.active_lanes.joining = joining;
        self.leave_empty_lanes(|sim, l| sim.lane_veh[l as usize].len());
    }

    /// A vehicle entered `lane` in this step's moves.
    #[inline]
    pub(in crate::sim) fn note_entered(&mut self, lane: LaneIdx) {
        if let Some(e) = self.active_lanes.entered.get_mut(lane as usize) {
            if *e == 0 {
                self.active_lanes.entered_lanes.push(lane);
            }
            *e += 1;
        }
    }

    /// After the moves (SUMO's `executeMovements`): a lane left with none of its own vehicles leaves the list; then
    /// the lanes vehicles entered, by SUMO's lane id, join if none of their own vehicles stayed.
    pub(in crate::sim) fn activate_lanes_after_moves(&mut self) {
        if self.active_lanes.active.is_empty() {
            return;
        }
        let own = |sim: &Simulation, l: LaneIdx| {
            sim.lane_veh[l as usize].len() - sim.active_lanes.entered[l as usize] as usize
        };
        self.leave_empty_lanes(own);
        let mut entered = std::mem::take(&mut self.active_lanes.entered_lanes);
        entered.sort_by_key(|&l| self.active_lanes.id_rank[l as usize]);
        for &l in &entered {
            if own(self, l) == 0 && !self.lane_veh[l as usize].is_empty() {
                self.join_active(l);
            }
            self.active_lanes.entered[l as usize] = 0;
        }
        entered.clear();
        self.active_lanes.entered_lanes = entered;
    }

    fn leave_empty_lanes(&mut self, count: impl Fn(&Simulation, LaneIdx) -> usize) {
        let mut order = std::mem::take(&mut self.active_lanes.order);
        let mut active = std::mem::take(&mut self.active_lanes.active);
        // (a lane in the list is marked active: only a lane that leaves is marked again)
        order.retain(|&l| {
            debug_assert!(active[l as usize]);
            let keep = count(self, l) > 0;
            if !keep {
                active[l as usize] = false;
            }
            keep
        });
        self.active_lanes.active = active;
        self.active_lanes.order = order;
    }

    /// The roads and groups the lane-change pass visits, in the order of their first lane in the list (into
    /// `out`, cleared first).
    pub(in crate::sim) fn changer_edges_in_order(&mut self, out: &mut Vec<ChangerEdge>) {
        let a = &mut self.active_lanes;
        a.visited_roads.clear();
        a.visited_roads.resize(self.net.road_lanes.len(), false);
        a.visited_groups.clear();
        a.visited_groups.resize(self.net.via_groups.len(), false);
        out.clear();
        for i in 0..self.active_lanes.order.len() {
            let l = self.active_lanes.order[i];
            let Some(e) = self.changer_edge(l) else {
                // lanes without a lane changer stand behind every other
                break;
            };
            let seen = match e {
                ChangerEdge::Road(r) => &mut self.active_lanes.visited_roads[r],
                ChangerEdge::Group(g) => &mut self.active_lanes.visited_groups[g],
            };
            if !*seen {
                *seen = true;
                out.push(e);
            }
        }
    }

    /// The lanes of `edge`.
    pub(in crate::sim) fn changer_edge_lanes(&self, edge: ChangerEdge) -> &[LaneIdx] {
        match edge {
            ChangerEdge::Road(r) => &self.net.road_lanes[r],
            ChangerEdge::Group(g) => &self.net.via_groups[g],
        }
    }

    /// After the pass (SUMO's `changeLanes`): lanes of the visited roads that vehicles changed onto join at the
    /// front, the last of them first.
    pub(in crate::sim) fn activate_changed_onto(&mut self, edges: &[ChangerEdge]) {
        let mut to_add = Vec::new();
        for &e in edges {
            for i in 0..self.changer_edge_lanes(e).len() {
                let l = self.changer_edge_lanes(e)[i];
                if !self.lane_veh[l as usize].is_empty() && !self.active_lanes.active[l as usize] {
                    self.active_lanes.active[l as usize] = true;
                    to_add.push(l);
                }
            }
        }
        for l in to_add {
            self.active_lanes.order.push_front(l);
        }
    }
}

/// Each lane's rank by SUMO's lane id and in SUMO's numbering (the net file's order: internal lanes first, then
/// each edge's lanes). A road lane's SUMO id is its edge's (the road's first SUMO id, else its own id) and index;
/// a via lane's, `:` and its junction's, then the link's number there.
fn sumo_lane_ranks(g: &mapc_graph::LaneGraph, net: &Network) -> (Vec<u32>, Vec<u32>) {
    let (lanes, links) = (&net.lanes, &net.links);
    let road_name = |r: usize| {
        let road = &g.roads[r];
        road.provenance
            .sumo_ids
            .first()
            .cloned()
            .unwrap_or_else(|| road.id.to_string())
    };
    let junction_names: std::collections::HashMap<mapc_graph::JunctionId, &str> = g
        .junctions
        .iter()
        .filter_map(|x| Some((x.id, x.provenance.sumo_ids.first()?.as_str())))
        .collect();
    let junction_name = |j: mapc_graph::JunctionId| {
        junction_names
            .get(&j)
            .map_or_else(|| j.to_string(), |n| n.to_string())
    };
    // (id, numbering key) per lane
    let mut keys: Vec<(String, (u8, usize, usize))> = Vec::with_capacity(lanes.len());
    for l in lanes {
        keys.push(match l.kind {
            LaneKind::Road(r) => (
                format!("{}_{}", road_name(r), l.index),
                (1, r, l.index as usize),
            ),
            LaneKind::Via(k) => (
                format!(":{}_{k}", junction_name(links[k as usize].junction)),
                (0, k as usize, 0),
            ),
        });
    }
    let rank = |order: Vec<usize>| {
        let mut r = vec![0u32; order.len()];
        for (i, l) in order.into_iter().enumerate() {
            r[l] = i as u32;
        }
        r
    };
    let mut by_id: Vec<usize> = (0..lanes.len()).collect();
    by_id.sort_by(|&a, &b| keys[a].0.as_bytes().cmp(keys[b].0.as_bytes()));
    let mut by_number: Vec<usize> = (0..lanes.len()).collect();
    by_number.sort_by_key(|&a| keys[a].1);
    (rank(by_id), rank(by_number))
}
