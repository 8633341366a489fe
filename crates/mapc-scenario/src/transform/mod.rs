//! The corridor compiler's transformations: an ordered list of named steps, each taking the [`Corridor`] to its
//! next state and saying in one line what it did. After every step the invariants are checked ([`check`]): the
//! graph is sound (`LaneGraph::invariant_violations`, which includes "every junction lists its roads"), connected
//! once pruned, single-lane once collapsed (or, with `--keep-lanes`, every lane continuing or recorded as ending,
//! `LaneGraph::lane_continuity_violations`, once lane connections are settled), and the driving length of the main road and of every merging road is
//! unchanged within [`LENGTH_TOLERANCE_M`] unless the step exists to change it.
//!
//! Roles survive in the saved graph through provenance: a road's `made_by` names the step that gave it its role
//! ([`ROLE_MAIN`], [`ROLE_FEEDER`], [`ROLE_EXIT`]), so a corridor file can be read back with [`CorridorRoles`].

pub mod collapse_lanes;
pub mod connect_lanes;
pub mod cut_at;
pub mod diverges;
pub mod join_chains;
pub mod keep_feeders;
pub mod map_merges;
pub mod pick_route;
pub mod prune;
pub mod trim_feeders;

pub use cut_at::{CUT_AT, cut_road};

use mapc_graph::{
    Connection, JunctionId, LaneGraph, LookupError, Provenance, RightOfWay, RoadId, Topology,
};
use std::collections::HashSet;

/// How far a step that must keep lengths may change them (metres).
pub const LENGTH_TOLERANCE_M: f64 = 1.0;
/// `made_by` of the roads of the corridor's main road.
pub const ROLE_MAIN: &str = pick_route::NAME;
/// `made_by` of the roads of a merging road (a feeder).
pub const ROLE_FEEDER: &str = keep_feeders::NAME;
/// `made_by` of the roads of a kept exit.
pub const ROLE_EXIT: &str = diverges::KEEP_EXITS;

#[derive(Debug, thiserror::Error)]
pub enum TransformError {
    #[error("--via `{query}`: {source}")]
    Via { query: String, source: LookupError },
    #[error("{0}")]
    NoRoute(String),
    #[error("after step `{step}` the graph breaks its invariants: {}", violations.join("; "))]
    Invariant {
        step: String,
        violations: Vec<String>,
    },
    #[error("{0}")]
    NotACorridor(String),
    #[error("{0}")]
    Cut(String),
    /// A `--via` point the finished corridor does not pass: never a silent success.
    #[error("--via `{query}`: {why}")]
    ViaNotHonoured { query: String, why: String },
}

/// What `simplify` asks of the steps.
#[derive(Clone, Debug)]
pub struct SimplifyOptions {
    /// Points the main road must pass, in order: roads (`osm-way:N`, SUMO edges, `R3`) or junctions (`osm:N`,
    /// SUMO junctions, `J3`). Empty: the longest through route over `classes`.
    pub via: Vec<String>,
    /// Road classes the main road is chosen among where it is not pinned (a SUMO type `highway.X` counts as `X`).
    pub classes: Vec<String>,
    /// Merging roads are kept back to where they start in the map, or at most this long.
    pub feeder_length_m: Option<f64>,
    /// Keep diverging roads as exits (back to the next junction) instead of dropping them.
    pub keep_exits: bool,
    /// Keep footways, paths, service roads and the like ([`mapc_graph::MINOR_CLASSES`]) that meet the main road
    /// as merging roads; by default they are dropped, and a junction where only they join is no merge.
    pub minor_roads: bool,
    /// Keep every lane of the main and merging roads with their lane-level connections, lane drops, gains and
    /// acceleration lanes ([`connect_lanes`] instead of [`collapse_lanes`]).
    pub keep_lanes: bool,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        SimplifyOptions {
            via: Vec::new(),
            classes: ["motorway", "motorway_link", "trunk", "trunk_link"]
                .map(String::from)
                .to_vec(),
            feeder_length_m: None,
            keep_exits: false,
            minor_roads: false,
            keep_lanes: false,
        }
    }
}

impl SimplifyOptions {
    pub fn class_allowed(&self, class: &str) -> bool {
        let c = class.strip_prefix("highway.").unwrap_or(class);
        self.classes.iter().any(|k| k == c)
    }
}

/// The graph being transformed, with the roles its roads play.
#[derive(Clone, Debug)]
pub struct Corridor {
    pub graph: LaneGraph,
    /// The main road, in driving order.
    pub main: Vec<RoadId>,
    /// Each merging road as its pieces in driving order; the last piece ends on the main road.
    pub feeders: Vec<Vec<RoadId>>,
    /// Each kept exit as its pieces in driving order; the first starts on the main road.
    pub exits: Vec<Vec<RoadId>>,
    /// Set once roads outside the corridor are gone (connectivity is checked from then on).
    pub pruned: bool,
    /// Set once every road has one lane.
    pub single_lane: bool,
    /// Set once lane-level connections are settled with every lane kept: from then on every lane continues or is
    /// recorded as ending.
    pub lanes_connected: bool,
    /// Whether the map's lane connections are the importer's guess (OSM: the map has none), to be derived again
    /// on the corridor by [`connect_lanes`]; a SUMO net's are the net's own and kept.
    pub guessed_connections: bool,
}

impl Corridor {
    pub fn new(graph: LaneGraph) -> Corridor {
        let guessed_connections = matches!(
            graph.source.format,
            mapc_graph::SourceFormat::OsmXml | mapc_graph::SourceFormat::OsmPbf
        );
        Corridor {
            graph,
            main: vec![],
            feeders: vec![],
            exits: vec![],
            pruned: false,
            single_lane: false,
            lanes_connected: false,
            guessed_connections,
        }
    }

    /// Driving length of a chain of roads: the roads plus the connections between consecutive ones.
    pub fn chain_length_m(g: &LaneGraph, chain: &[RoadId]) -> f64 {
        let roads: f64 = chain
            .iter()
            .filter_map(|r| g.road(*r))
            .map(|r| r.length_m)
            .sum();
        let vias: f64 = chain
            .windows(2)
            .filter_map(|w| {
                g.connections
                    .iter()
                    .find(|c| c.from_road == w[0] && c.to_road == w[1])
            })
            .map(|c| c.via_length_m)
            .sum();
        roads + vias
    }

    fn role_lengths(&self) -> (f64, Vec<f64>) {
        (
            Self::chain_length_m(&self.graph, &self.main),
            self.feeders
                .iter()
                .map(|f| Self::chain_length_m(&self.graph, f))
                .collect(),
        )
    }
}

/// One named step: what it is called, whether it may change the main or merging roads' lengths, and the function.
pub struct Step {
    pub name: &'static str,
    pub changes_lengths: bool,
    pub apply: fn(&mut Corridor, &SimplifyOptions) -> Result<String, TransformError>,
}

/// What one step did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StepReport {
    pub step: String,
    pub summary: String,
}

/// The steps of `simplify`, in order, for these options.
pub fn simplify_steps(opts: &SimplifyOptions) -> Vec<Step> {
    let mut steps = vec![
        Step {
            name: pick_route::NAME,
            changes_lengths: true,
            apply: pick_route::apply,
        },
        Step {
            name: keep_feeders::NAME,
            changes_lengths: true,
            apply: keep_feeders::apply,
        },
        if opts.keep_exits {
            Step {
                name: diverges::KEEP_EXITS,
                changes_lengths: false,
                apply: diverges::keep_exits,
            }
        } else {
            Step {
                name: diverges::DROP_DIVERGES,
                changes_lengths: false,
                apply: diverges::drop_diverges,
            }
        },
        Step {
            name: prune::NAME,
            changes_lengths: false,
            apply: prune::apply,
        },
        if opts.keep_lanes {
            Step {
                name: connect_lanes::NAME,
                changes_lengths: false,
                apply: connect_lanes::apply,
            }
        } else {
            Step {
                name: collapse_lanes::NAME,
                changes_lengths: false,
                apply: collapse_lanes::apply,
            }
        },
        Step {
            name: join_chains::NAME,
            changes_lengths: false,
            apply: join_chains::apply,
        },
    ];
    if opts.feeder_length_m.is_some() {
        steps.push(Step {
            name: trim_feeders::NAME,
            changes_lengths: true,
            apply: trim_feeders::apply,
        });
    }
    steps
}

/// Run `steps` in order, checking the invariants after each.
pub fn run_steps(
    corridor: &mut Corridor,
    steps: &[Step],
    opts: &SimplifyOptions,
) -> Result<Vec<StepReport>, TransformError> {
    let mut reports = Vec::with_capacity(steps.len());
    for step in steps {
        let before = corridor.role_lengths();
        let summary = (step.apply)(corridor, opts)?;
        check(
            corridor,
            step.name,
            if step.changes_lengths {
                None
            } else {
                Some(&before)
            },
        )?;
        reports.push(StepReport {
            step: step.name.to_string(),
            summary,
        });
    }
    Ok(reports)
}

/// The invariants after a step; `lengths_before` is given when the step must keep lengths.
pub fn check(
    c: &Corridor,
    step: &str,
    lengths_before: Option<&(f64, Vec<f64>)>,
) -> Result<(), TransformError> {
    let mut violations = c.graph.invariant_violations();
    if c.pruned {
        let pieces = Topology::new(&c.graph).component_count();
        if pieces != 1 {
            violations.push(format!(
                "the corridor falls into {pieces} disconnected pieces"
            ));
        }
    }
    if c.single_lane {
        for r in c.graph.roads.iter().filter(|r| r.lanes.len() != 1) {
            violations.push(format!("road {} has {} lanes", r.id, r.lanes.len()));
        }
    }
    if c.lanes_connected {
        violations.extend(c.graph.lane_continuity_violations());
    }
    let chains = std::iter::once(&c.main).chain(&c.feeders).chain(&c.exits);
    for chain in chains {
        for w in chain.windows(2) {
            let (a, b) = (c.graph.road(w[0]), c.graph.road(w[1]));
            if let (Some(a), Some(b)) = (a, b) {
                if a.to != b.from {
                    violations.push(format!(
                        "roads {} and {} of one chain do not meet",
                        a.id, b.id
                    ));
                }
            } else {
                violations.push(format!(
                    "a chain names a missing road ({} or {})",
                    w[0], w[1]
                ));
            }
        }
    }
    if let Some((main_before, feeders_before)) = lengths_before {
        let (main_after, feeders_after) = c.role_lengths();
        if (main_after - main_before).abs() > LENGTH_TOLERANCE_M {
            violations.push(format!(
                "the main road's length went from {main_before:.2} m to {main_after:.2} m"
            ));
        }
        if feeders_before.len() != feeders_after.len() {
            violations.push(format!(
                "{} merging roads became {}",
                feeders_before.len(),
                feeders_after.len()
            ));
        } else {
            for (i, (b, a)) in feeders_before.iter().zip(&feeders_after).enumerate() {
                if (a - b).abs() > LENGTH_TOLERANCE_M {
                    violations.push(format!(
                        "merging road {} went from {b:.2} m to {a:.2} m",
                        i + 1
                    ));
                }
            }
        }
    }
    if violations.is_empty() {
        Ok(())
    } else {
        Err(TransformError::Invariant {
            step: step.to_string(),
            violations,
        })
    }
}

/// Add `step` to a provenance's `made_by` once.
pub fn mark(p: &mut Provenance, step: &str) {
    if !p.made_by.iter().any(|s| s == step) {
        p.made_by.push(step.to_string());
    }
}

/// A connection from `from` to `to` at their common junction when there is none (OSM input has none on some
/// joints); the right of way follows the road priorities at that junction.
pub fn ensure_connection(g: &mut LaneGraph, from: RoadId, to: RoadId, step: &str) {
    if g.connections
        .iter()
        .any(|c| c.from_road == from && c.to_road == to)
    {
        return;
    }
    let (Some(a), Some(b)) = (g.road(from), g.road(to)) else {
        return;
    };
    let junction = a.to;
    let _ = b;
    let top_priority = g
        .junction(junction)
        .map(|j| {
            j.incoming
                .iter()
                .filter_map(|r| g.road(*r))
                .map(|r| r.priority)
                .max()
                .unwrap_or(a.priority)
        })
        .unwrap_or(a.priority);
    let right_of_way = if a.priority >= top_priority {
        RightOfWay::Major
    } else {
        RightOfWay::Minor
    };
    g.connections.push(Connection {
        via_lanes: Vec::new(),
        yields_to: Vec::new(),
        yields_inside: false,
        junction,
        from_road: from,
        from_lane: 0,
        to_road: to,
        to_lane: 0,
        via_length_m: 0.0,
        via_speed_mps: None,
        right_of_way,
        signal: None,
        right_of_way_overridden: false,
        provenance: Provenance::made_by(step),
    });
    sort_connections(g);
}

pub fn sort_connections(g: &mut LaneGraph) {
    g.connections
        .sort_by_key(|c| (c.junction, c.from_road, c.from_lane, c.to_road, c.to_lane));
}

/// Remove roads (and their connections), then junctions left with no road.
pub fn remove_roads(g: &mut LaneGraph, gone: &HashSet<RoadId>) {
    g.roads.retain(|r| !gone.contains(&r.id));
    g.connections
        .retain(|c| !gone.contains(&c.from_road) && !gone.contains(&c.to_road));
    let used: HashSet<JunctionId> = g.roads.iter().flat_map(|r| [r.from, r.to]).collect();
    g.junctions.retain(|j| used.contains(&j.id));
    g.rebuild_junction_links();
}

/// The roles of a saved corridor graph, read back from the roads' `made_by`.
#[derive(Clone, Debug, PartialEq)]
pub struct CorridorRoles {
    pub main: Vec<RoadId>,
    pub feeders: Vec<Vec<RoadId>>,
    pub exits: Vec<Vec<RoadId>>,
}

impl CorridorRoles {
    pub fn of(g: &LaneGraph) -> Result<CorridorRoles, TransformError> {
        let with = |role: &str| -> Vec<RoadId> {
            g.roads
                .iter()
                .filter(|r| r.provenance.made_by.iter().any(|m| m == role))
                .map(|r| r.id)
                .collect()
        };
        let main_set = with(ROLE_MAIN);
        if main_set.is_empty() {
            return Err(TransformError::NotACorridor(format!(
                "the graph `{}` has no corridor (no road made by `{ROLE_MAIN}`); run `mapc simplify` on it first",
                g.source.file
            )));
        }
        let main = chains_of(g, &main_set);
        if main.len() != 1 {
            return Err(TransformError::NotACorridor(format!(
                "the main road of `{}` is broken into {} pieces",
                g.source.file,
                main.len()
            )));
        }
        let main = main.into_iter().next().unwrap();
        Ok(CorridorRoles {
            main,
            feeders: chains_of(g, &with(ROLE_FEEDER)),
            exits: chains_of(g, &with(ROLE_EXIT)),
        })
    }
}

/// Split a set of roads into chains in driving order (each chain: one road's end is the next one's start).
pub fn chains_of(g: &LaneGraph, roads: &[RoadId]) -> Vec<Vec<RoadId>> {
    let set: HashSet<RoadId> = roads.iter().copied().collect();
    let mut sorted: Vec<RoadId> = roads.to_vec();
    sorted.sort();
    let mut chains = Vec::new();
    let mut used = HashSet::new();
    for &r in &sorted {
        let road = g.road(r).unwrap();
        let has_pred = g.junction(road.from).is_some_and(|j| {
            j.incoming
                .iter()
                .any(|p| set.contains(p) && !used.contains(p) && *p != r)
        });
        if has_pred || used.contains(&r) {
            continue;
        }
        let mut chain = vec![r];
        used.insert(r);
        let mut cur = r;
        loop {
            let to = g.road(cur).unwrap().to;
            let next = g.junction(to).and_then(|j| {
                j.outgoing
                    .iter()
                    .find(|n| set.contains(n) && !used.contains(n))
            });
            match next {
                Some(&n) => {
                    used.insert(n);
                    chain.push(n);
                    cur = n;
                }
                None => break,
            }
        }
        chains.push(chain);
    }
    // Roads left over lie on a cycle; keep them as their own chains so nothing is lost silently.
    for &r in &sorted {
        if !used.contains(&r) {
            chains.push(vec![r]);
        }
    }
    chains
}

/// Small highways built in code for the unit tests.
#[cfg(test)]
pub(crate) mod test_maps {
    use mapc_graph::*;

    fn polyline_length(g: &[[f64; 2]]) -> f64 {
        g.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    }

    /// A test road: `(from, to, class, lanes, bends)`.
    pub type TestRoad<'a> = (u32, u32, &'a str, u8, &'a [[f64; 2]]);

    /// A map from junction positions and roads `(from, to, class, lanes, bends)`; roads are numbered in order,
    /// lengths are their drawn lengths, every pair of consecutive roads is connected lane 0 to lane 0.
    pub fn build(junctions: &[[f64; 2]], roads: &[TestRoad]) -> LaneGraph {
        let mut g = LaneGraph::new(
            Source {
                file: "test".into(),
                format: SourceFormat::Generator,
            },
            Projection::Plane { offset: [0.0, 0.0] },
        );
        g.junctions = junctions
            .iter()
            .enumerate()
            .map(|(i, p)| Junction {
                id: JunctionId(i as u32),
                pos: *p,
                kind: JunctionKind::Through,
                incoming: vec![],
                outgoing: vec![],
                provenance: Provenance::osm_node(1000 + i as i64),
            })
            .collect();
        g.roads = roads
            .iter()
            .enumerate()
            .map(|(i, &(from, to, class, lanes, bends))| {
                let mut geometry = vec![junctions[from as usize]];
                geometry.extend_from_slice(bends);
                geometry.push(junctions[to as usize]);
                let length_m = polyline_length(&geometry);
                Road {
                    id: RoadId(i as u32),
                    from: JunctionId(from),
                    to: JunctionId(to),
                    class: class.into(),
                    name: None,
                    ref_: None,
                    priority: if class == "motorway" { 13 } else { 12 },
                    lanes: (0..lanes)
                        .map(|index| Lane {
                            shape: Vec::new(),
                            index,
                            speed_mps: 30.0,
                            width_m: 3.5,
                            length_m,
                            end: None,
                        })
                        .collect(),
                    geometry,
                    length_m,
                    provenance: Provenance {
                        osm_ways: vec![500 + i as i64],
                        ..Default::default()
                    },
                }
            })
            .collect();
        g.rebuild_junction_links();
        let pairs: Vec<(RoadId, RoadId, JunctionId)> = g
            .roads
            .iter()
            .flat_map(|a| {
                g.roads
                    .iter()
                    .filter(move |b| b.from == a.to)
                    .map(move |b| (a.id, b.id, a.to))
            })
            .collect();
        for (a, b, j) in pairs {
            let row = if g.road(a).unwrap().class == "motorway" {
                RightOfWay::Major
            } else {
                RightOfWay::Minor
            };
            g.connections.push(Connection {
                via_lanes: Vec::new(),
                yields_to: Vec::new(),
                yields_inside: false,
                junction: j,
                from_road: a,
                from_lane: 0,
                to_road: b,
                to_lane: 0,
                via_length_m: 0.0,
                via_speed_mps: None,
                right_of_way: row,
                signal: None,
                right_of_way_overridden: false,
                provenance: Provenance::default(),
            });
        }
        super::sort_connections(&mut g);
        g
    }

    /// A 3 km motorway (J0 -> J7) with a joint at J1, an on-ramp of two pieces merging at J2, an exit at J5, a
    /// loop ramp that leaves at J5 and rejoins at J6, a short motorway elsewhere and a disconnected side road.
    pub fn highway() -> LaneGraph {
        let j = [
            [0.0, 0.0],       // J0 start
            [1000.0, 0.0],    // J1 joint
            [1500.0, 0.0],    // J2 merge
            [1300.0, -150.0], // J3 ramp joint
            [900.0, -400.0],  // J4 ramp start
            [2300.0, 0.0],    // J5 diverge
            [2600.0, 0.0],    // J6 loop rejoins
            [3000.0, 0.0],    // J7 end
            [2500.0, -300.0], // J8 exit end
            [0.0, 500.0],     // J9 other motorway
            [100.0, 500.0],   // J10
            [0.0, 900.0],     // J11 side road
            [300.0, 900.0],   // J12
        ];
        build(
            &j,
            &[
                (0, 1, "motorway", 3, &[]),                      // R0
                (1, 2, "motorway", 2, &[]),                      // R1
                (4, 3, "motorway_link", 1, &[[1100.0, -300.0]]), // R2
                (3, 2, "motorway_link", 1, &[]),                 // R3
                (2, 5, "motorway", 3, &[]),                      // R4
                (5, 8, "motorway_link", 1, &[]),                 // R5 exit
                (5, 6, "motorway", 2, &[]),                      // R6
                (6, 7, "motorway", 2, &[]),                      // R7
                (5, 6, "motorway_link", 1, &[[2450.0, 60.0]]),   // R8 collector, leaves and rejoins
                (9, 10, "motorway", 2, &[]),                     // R9
                (11, 12, "primary", 1, &[]),                     // R10
            ],
        )
    }
}
