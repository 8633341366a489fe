//! # mapc-scenario: what to simulate, and how a real map becomes it
//!
//! Glossary:
//! - **scenario**: a network plus vehicle types, flows (demand), initial vehicles, step, horizon and the controlled
//!   region; written as TOML (`scenarios/*.toml`).
//! - **flow**: periodic departures from an entry road at `vehs_per_hour` (SUMO's semantics), of one vehicle type.
//! - **vehicle type**: IDM driver parameters; `controlled = true` marks an AV a policy may drive.
//! - **controlled region**: the roads where AVs are driven by a policy (a transfer window), and `n_av`, how many.
//! - **corridor**: a single-lane main road with the roads merging into it (what `simplify` makes of a highway).
//! - **merge distribution**: a Simple Merge whose demand, right of way, lengths, speed limit and AV share are
//!   drawn per episode from the seed (`distribution`), to train one policy over many merges.
//! - **window**: a piece of a corridor around one merge whose lengths match a source scenario's; a scenario may
//!   have several (`[[control.windows]]`), each its own controlled region, or a **joined** region spanning
//!   merges whose windows overlap.
//! - **fitted window** (`--fit`): a window cut shorter than its source where the map has less (a 194 m ramp,
//!   530 m before the merge), each length down to a floor (half the source's by default).
//! - **resolved scenario**: a scenario with its network built or loaded into a [`mapc_graph::LaneGraph`].
//! - **entry capacity**: one vehicle per step per entry road, per entry lane for flows departing on a lane index,
//!   per lane of the road for `random` and `free` (`bounds.rs`); demand above it is refused, like a horizon past
//!   48 h.
//! - **allowed range**: every number of a scenario (times, counts, speeds, lengths, driver parameters) lies in
//!   one (`ranges.rs`), checked on loading; outside it, the key, the value and the range are named.
//! - **fill time**: the free-flow travel time of the longest route (`timing.rs`); a horizon that leaves too little
//!   after it is warned about, and `mapc window` picks a warm-up for it.

pub mod bounds;
pub mod compile;
pub mod compile_error;
pub mod compile_files;
mod depart_lane;
pub mod distribution;
pub mod generator;
pub mod model;
pub mod ranges;
pub mod simplify;
pub mod sumo;
pub mod timing;
pub mod transform;
pub mod window;

pub use depart_lane::DepartLane;
pub use model::*;

use mapc_graph::{JunctionId, LaneGraph, RoadId};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: {key}: {message}")]
    Invalid {
        path: PathBuf,
        key: String,
        message: String,
    },
    #[error("{path}: network: {source}")]
    Graph {
        path: PathBuf,
        source: mapc_graph::GraphFileError,
    },
    #[error("{path}: network: {message}")]
    Network { path: PathBuf, message: String },
    #[error(transparent)]
    Sumo(#[from] sumo::SumoError),
    #[error(
        "no scenario file `{0}` and no built-in scenario of that name (built-in: simple_merge, two_lane_merge, lane_drop)"
    )]
    Unknown(String),
}

/// A scenario with its network in hand, its road references checked.
#[derive(Clone, Debug)]
pub struct ResolvedScenario {
    pub scenario: Scenario,
    pub graph: LaneGraph,
    /// Where the scenario came from: a file path, or `builtin:NAME`.
    pub origin: String,
    /// Each flow's entry road and optional last road.
    pub flow_roads: Vec<(RoadId, Option<RoadId>)>,
    /// Per flow, the roads its route passes between its first and last (each `via` entry's pieces, in order).
    pub flow_via: Vec<Vec<RoadId>>,
    /// What reading the scenario dropped or ignored (a SUMO scenario's unsupported elements and options), a line
    /// each.
    pub notes: Vec<String>,
    /// Demand above what an entry takes queues there (a SUMO scenario, as SUMO runs it) instead of being refused.
    pub queue_excess_demand: bool,
    /// The control region's roads (empty: the whole network); with several windows, all their roads.
    pub region_roads: Vec<RoadId>,
    /// The windows of a several-window scenario (`control.windows`), in the file's order; empty otherwise.
    pub windows: Vec<ResolvedWindow>,
    /// The merges whose flow every run measures (`measure.merges`, or the region's merges).
    pub measure_junctions: Vec<JunctionId>,
}

/// One controlled region of a several-window scenario, its references checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedWindow {
    /// How the scenario names its first merge (`osm:NODE`, a SUMO id or `J12`).
    pub name: String,
    /// Its merge junctions, in driving order.
    pub merges: Vec<JunctionId>,
    /// Its roads, sorted.
    pub roads: Vec<RoadId>,
}

impl Scenario {
    /// The paper's Simple Merge exactly (docs/reference.md sec. 1).
    pub fn simple_merge() -> Scenario {
        let human = VehicleType::default();
        let av = VehicleType {
            controlled: true,
            ..VehicleType::default()
        };
        let flow = |id: &str, from: &str, vph: f64, vtype: &str, speed: f64| Flow {
            id: id.to_string(),
            from: from.to_string(),
            to: None,
            vehs_per_hour: vph,
            vehicle_type: vtype.to_string(),
            depart_speed_mps: speed,
            begin_s: 1.0,
            end_s: None,
            depart_lane: None,
            ..Flow::default()
        };
        Scenario {
            version: SCENARIO_VERSION,
            name: generator::SIMPLE_MERGE.to_string(),
            description: "The Simple Merge of Cui et al. (AAMAS 2021): 600 m main road, 200 m ramp (the major road), \
                          100 m after the merge; 2000 veh/h on the main road (10% AVs), 200 veh/h on the ramp."
                .to_string(),
            step_s: 0.5,
            horizon_steps: 2000,
            warmup_steps: 0,
            time_to_teleport_s: None,
            network: NetworkSpec::SimpleMerge(SimpleMergeParams::default()),
            vehicle_types: [("human".to_string(), human), ("av".to_string(), av)].into_iter().collect(),
            vehicle_type_mixes: Default::default(),
            flows: vec![
                flow("main_human", generator::MAIN_ENTRY, 1800.0, "human", 10.0),
                flow("main_av", generator::MAIN_ENTRY, 200.0, "av", 10.0),
                flow("ramp_human", generator::RAMP_ENTRY, 200.0, "human", 7.5),
            ],
            initial_vehicles: Some(InitialVehicles { count: 5, vehicle_type: "human".to_string(), speed_mps: 0.0 }),
            control: Some(Control { n_av: 5, region: vec![], window: None, windows: vec![] }),
            measure: None,
            queue_excess_demand: false,
            light_programs: Vec::new(),
        }
    }

    /// The Simple Merge's geometry with a two-lane main road; the one-lane ramp joins through a 200 m
    /// acceleration lane that ends before the last 100 m (SUMO nets' motorway on-ramp). Humans only, demand on
    /// both main lanes.
    pub fn two_lane_merge() -> Scenario {
        let base = Scenario::simple_merge();
        let flow = |id: &str, from: &str, vph: f64, speed: f64, lane: Option<&str>| Flow {
            id: id.to_string(),
            from: from.to_string(),
            to: None,
            vehs_per_hour: vph,
            vehicle_type: "human".to_string(),
            depart_speed_mps: speed,
            begin_s: 1.0,
            end_s: None,
            depart_lane: lane.map(str::to_string),
            ..Flow::default()
        };
        Scenario {
            name: generator::TWO_LANE_MERGE.to_string(),
            description: "The Simple Merge with a two-lane main road: the one-lane ramp joins through a 200 m \
                          acceleration lane that then ends; 1200 veh/h on each main lane, 400 veh/h on the ramp, \
                          humans only."
                .to_string(),
            network: NetworkSpec::SimpleMerge(SimpleMergeParams {
                lanes: 2,
                acceleration_lane_m: 200.0,
                ..SimpleMergeParams::default()
            }),
            vehicle_types: base
                .vehicle_types
                .into_iter()
                .filter(|(name, _)| name == "human")
                .collect(),
            flows: vec![
                flow("main_right", generator::MAIN_ENTRY, 1200.0, 10.0, Some("0")),
                flow("main_left", generator::MAIN_ENTRY, 1200.0, 10.0, Some("1")),
                flow("ramp", generator::RAMP_ENTRY, 400.0, 7.5, None),
            ],
            initial_vehicles: None,
            control: None,
            ..base
        }
    }

    /// A lane-drop bottleneck in the spirit of Flow's bottleneck: 600 m of three lanes whose rightmost lane then
    /// ends, 300 m of two lanes after; 1500 veh/h on each of the three lanes (more than two lanes carry), humans
    /// only.
    pub fn lane_drop() -> Scenario {
        let base = Scenario::simple_merge();
        let params = LaneDropParams::default();
        let flows = (0..params.lanes_before)
            .map(|lane| Flow {
                id: format!("lane{lane}"),
                from: generator::LANE_DROP_UPSTREAM.to_string(),
                to: None,
                vehs_per_hour: 1500.0,
                vehicle_type: "human".to_string(),
                depart_speed_mps: 10.0,
                begin_s: 1.0,
                end_s: None,
                depart_lane: Some(lane.to_string()),
                ..Flow::default()
            })
            .collect();
        Scenario {
            name: generator::LANE_DROP.to_string(),
            description: "A lane-drop bottleneck: 600 m of three lanes whose rightmost lane then ends, 300 m of two \
                          lanes after; 1500 veh/h on each of the three lanes, humans only."
                .to_string(),
            network: NetworkSpec::LaneDrop(params),
            vehicle_types: base
                .vehicle_types
                .into_iter()
                .filter(|(name, _)| name == "human")
                .collect(),
            flows,
            initial_vehicles: None,
            control: None,
            ..base
        }
    }

    pub fn builtin(name: &str) -> Option<Scenario> {
        match name {
            generator::SIMPLE_MERGE => Some(Scenario::simple_merge()),
            generator::TWO_LANE_MERGE => Some(Scenario::two_lane_merge()),
            generator::LANE_DROP => Some(Scenario::lane_drop()),
            _ => None,
        }
    }

    pub fn from_toml(text: &str, path: &Path) -> Result<Scenario, ScenarioError> {
        let s: Scenario = toml::from_str(text).map_err(|e| ScenarioError::Toml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if s.version != SCENARIO_VERSION {
            return Err(ScenarioError::Invalid {
                path: path.to_path_buf(),
                key: "version".into(),
                message: format!(
                    "scenario version {}, but this mapc reads version {SCENARIO_VERSION}",
                    s.version
                ),
            });
        }
        Ok(s)
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a scenario always serialises to TOML")
    }

    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let bytes = mapc_graph::input::read(path).map_err(|source| ScenarioError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        // another of mapc's files, or a map, whatever its name: say what it is rather than fail on TOML syntax
        let not_a_scenario = |message: String| ScenarioError::Toml {
            path: path.to_path_buf(),
            message,
        };
        if let Some(kind) = mapc_graph::filekind::sniff(&bytes)
            && kind != mapc_graph::MapcFile::Scenario
        {
            return Err(not_a_scenario(format!(
                "is {}, not a scenario",
                kind.name()
            )));
        }
        if let Some(map) = mapc_graph::filekind::sniff_map(&bytes) {
            return Err(not_a_scenario(mapc_graph::filekind::map_given_for(
                map,
                path,
                mapc_graph::MapcFile::Scenario,
            )));
        }
        let text = String::from_utf8(bytes).map_err(|e| ScenarioError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
        })?;
        Scenario::from_toml(&text, path)
    }

    pub fn save(&self, path: &Path) -> Result<(), ScenarioError> {
        mapc_graph::write_atomically(path, self.to_toml().as_bytes()).map_err(|source| {
            ScenarioError::Io {
                path: path.to_path_buf(),
                source,
            }
        })
    }
}

impl ResolvedScenario {
    /// A scenario file, a SUMO configuration (`.sumocfg`), or the name of a built-in scenario (`simple_merge`).
    pub fn load(file_or_name: &str) -> Result<ResolvedScenario, ScenarioError> {
        ResolvedScenario::load_with(file_or_name, &sumo::ReadOptions::default())
    }

    /// [`ResolvedScenario::load`], a SUMO configuration read with `sumo_options`.
    pub fn load_with(
        file_or_name: &str,
        sumo_options: &sumo::ReadOptions,
    ) -> Result<ResolvedScenario, ScenarioError> {
        let path = Path::new(file_or_name);
        if path.is_file() && sumo::is_sumo_config(path) {
            let read = sumo::from_sumocfg(path, sumo_options)?;
            return ResolvedScenario::from_sumo(read, file_or_name);
        }
        if path.exists() {
            let scenario = Scenario::load(path)?;
            let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
            return ResolvedScenario::resolve(scenario, &base, file_or_name);
        }
        match Scenario::builtin(file_or_name) {
            Some(s) => {
                ResolvedScenario::resolve(s, Path::new("."), &format!("builtin:{file_or_name}"))
            }
            None => Err(ScenarioError::Unknown(file_or_name.to_string())),
        }
    }

    /// Build or load the network (paths relative to `base_dir`) and check every reference. `origin` names the
    /// scenario in errors.
    pub fn resolve(
        scenario: Scenario,
        base_dir: &Path,
        origin: &str,
    ) -> Result<ResolvedScenario, ScenarioError> {
        let path = PathBuf::from(origin);
        // the numbers first: a scenario with an absurd one is refused before its network is built
        check_ranges(&scenario, &path)?;
        let graph = match &scenario.network {
            NetworkSpec::SimpleMerge(p) => {
                generator::simple_merge(p).map_err(|message| ScenarioError::Network {
                    path: path.clone(),
                    message,
                })?
            }
            NetworkSpec::LaneDrop(p) => {
                generator::lane_drop(p).map_err(|message| ScenarioError::Network {
                    path: path.clone(),
                    message,
                })?
            }
            NetworkSpec::Graph(g) => {
                LaneGraph::load(&base_dir.join(g)).map_err(|source| ScenarioError::Graph {
                    path: path.clone(),
                    source,
                })?
            }
            NetworkSpec::Map(m) => {
                mapc_import::import_path(&base_dir.join(m), &mapc_import::ImportOptions::default())
                    .map_err(|e| ScenarioError::Network {
                        path: path.clone(),
                        message: e.to_string(),
                    })?
            }
        };
        ResolvedScenario::on_network(scenario, graph, origin)
    }

    /// A SUMO scenario read ([`sumo::from_sumocfg`], [`sumo::from_files`]) on its network, checked.
    /// Demand above what an entry takes is SUMO's to queue, as SUMO does: a note, not a refusal.
    pub fn from_sumo(
        read: sumo::FromSumo,
        origin: &str,
    ) -> Result<ResolvedScenario, ScenarioError> {
        check_ranges(&read.scenario, Path::new(origin))?;
        let mut rs = ResolvedScenario::on_network(read.scenario, read.graph, origin)?;
        rs.notes.splice(0..0, read.warnings);
        Ok(rs)
    }

    /// A scenario on a network in hand (a graph about to be written beside it, as the scenario names it), checked
    /// as [`ResolvedScenario::resolve`] checks one read from files.
    pub fn resolve_with(
        scenario: Scenario,
        graph: LaneGraph,
        origin: &str,
    ) -> Result<ResolvedScenario, ScenarioError> {
        check_ranges(&scenario, Path::new(origin))?;
        ResolvedScenario::on_network(scenario, graph, origin)
    }

    /// Every reference of `scenario` checked against its network `graph`.
    fn on_network(
        scenario: Scenario,
        mut graph: LaneGraph,
        origin: &str,
    ) -> Result<ResolvedScenario, ScenarioError> {
        let mut notes = Vec::new();
        let queue_excess_demand = scenario.queue_excess_demand;
        for (i, program) in scenario.light_programs.iter().enumerate() {
            match graph.lights.iter_mut().find(|l| l.id == program.id) {
                Some(l) => *l = program.clone(),
                None => {
                    return Err(ScenarioError::Invalid {
                        path: PathBuf::from(origin),
                        key: format!("light_programs[{i}]"),
                        message: format!("the network has no traffic light `{}`", program.id),
                    });
                }
            }
        }
        let path = PathBuf::from(origin);
        let invalid = |key: String, message: String| ScenarioError::Invalid {
            path: path.clone(),
            key,
            message,
        };
        let find_road = |key: String, r: &str| -> Result<RoadId, ScenarioError> {
            let found = graph
                .find_roads(r)
                .map_err(|e| invalid(key.clone(), e.to_string()))?;
            Ok(found[0])
        };
        for (name, mix) in &scenario.vehicle_type_mixes {
            if scenario.vehicle_types.contains_key(name) {
                return Err(invalid(
                    format!("vehicle_type_mixes.{name}"),
                    "a mix cannot have the name of a vehicle type".into(),
                ));
            }
            if mix.is_empty() {
                return Err(invalid(
                    format!("vehicle_type_mixes.{name}"),
                    "an empty mix".into(),
                ));
            }
            for (t, w) in mix {
                if !scenario.vehicle_types.contains_key(t) {
                    return Err(invalid(
                        format!("vehicle_type_mixes.{name}.{t}"),
                        format!("no vehicle type `{t}`"),
                    ));
                }
                if !(w.is_finite() && *w > 0.0) {
                    return Err(invalid(
                        format!("vehicle_type_mixes.{name}.{t}"),
                        format!("weight {w}: must be a positive number"),
                    ));
                }
            }
        }
        let mut flow_roads = Vec::new();
        let mut flow_via = Vec::new();
        for (i, f) in scenario.flows.iter().enumerate() {
            if !scenario.vehicle_types.contains_key(&f.vehicle_type)
                && !scenario.vehicle_type_mixes.contains_key(&f.vehicle_type)
            {
                return Err(invalid(
                    format!("flows[{i}].vehicle_type"),
                    format!("no vehicle type `{}`", f.vehicle_type),
                ));
            }
            if let Some(p) = f.probability
                && !(p > 0.0 && p <= 1.0)
            {
                return Err(invalid(
                    format!("flows[{i}].probability"),
                    format!(
                        "flow `{}`: probability {p}: must lie in (0, 1] (per second)",
                        f.id
                    ),
                ));
            }
            if let Some(rule) = f.depart_pos.as_deref()
                && !matches!(rule, "base" | "random" | "random_free")
            {
                return Err(invalid(
                    format!("flows[{i}].depart_pos"),
                    format!(
                        "flow `{}`: `{rule}`: `base`, `random` or `random_free`",
                        f.id
                    ),
                ));
            }
            if let Some(rule) = f.depart_speed.as_deref()
                && rule != "max"
                && rule != "desired"
            {
                return Err(invalid(
                    format!("flows[{i}].depart_speed"),
                    format!(
                        "flow `{}`: `{rule}`: `max` or `desired` (or a number in depart_speed_mps)",
                        f.id
                    ),
                ));
            }
            if f.number == Some(0) {
                return Err(invalid(
                    format!("flows[{i}].number"),
                    format!("flow `{}`: a number of vehicles must be at least 1", f.id),
                ));
            }
            let mut via = Vec::new();
            for (k, r) in f.via.iter().enumerate() {
                let found = graph
                    .find_roads(r)
                    .map_err(|e| invalid(format!("flows[{i}].via[{k}]"), e.to_string()))?;
                via.extend(found);
            }
            flow_via.push(via);
            let from = find_road(format!("flows[{i}].from"), &f.from)?;
            let to = match &f.to {
                Some(t) => {
                    // The last piece of a way the route ends on.
                    let found = graph
                        .find_roads(t)
                        .map_err(|e| invalid(format!("flows[{i}].to"), e.to_string()))?;
                    Some(*found.last().unwrap())
                }
                None => None,
            };
            // a lane index too large for a lane is refused below with the road's lanes named
            if let Some(text) = f.depart_lane.as_deref()
                && let Err(message) = DepartLane::parse(text)
                && text.parse::<u32>().is_err()
            {
                return Err(invalid(
                    format!("flows[{i}].depart_lane"),
                    format!("flow `{}`: {message}", f.id),
                ));
            }
            if let Some(lane) = f.depart_lane.as_deref().and_then(|l| l.parse::<u32>().ok()) {
                let lanes = graph.road(from).map_or(0, |r| r.lanes.len());
                if lane as usize >= lanes {
                    return Err(invalid(
                        format!("flows[{i}].depart_lane"),
                        format!(
                            "flow `{}` departs on lane {lane}, but its entry road `{}` ({from}) has {lanes} lane(s) \
                             (0 to {})",
                            f.id,
                            f.from,
                            lanes.saturating_sub(1)
                        ),
                    ));
                }
            }
            flow_roads.push((from, to));
        }
        let demand: Vec<bounds::FlowDemand> = scenario
            .flows
            .iter()
            .zip(&flow_roads)
            .map(|(f, (from, _))| {
                let road_lanes = graph.road(*from).map_or(1, |r| r.lanes.len());
                bounds::FlowDemand {
                    id: &f.id,
                    entry: bounds::entry_key(&from.to_string(), f.depart_lane.as_deref()),
                    lanes: bounds::entry_lanes(f.depart_lane.as_deref(), road_lanes),
                    road: from.to_string(),
                    road_lanes: road_lanes as u32,
                    vehs_per_hour: f.vehs_per_hour,
                }
            })
            .collect();
        // queued demand is still counted departure by departure: a flow past what any road takes is refused
        let most = bounds::MOST_QUEUED_VEHICLES_A_STEP * 3600.0 / scenario.step_s;
        if queue_excess_demand
            && let Some((i, f)) = scenario
                .flows
                .iter()
                .enumerate()
                .find(|(_, f)| !(f.vehs_per_hour <= most))
        {
            return Err(invalid(
                format!("flows[{i}].vehs_per_hour"),
                format!(
                    "flow `{}`: {} veh/h, more than {} vehicles a {} s step, which no road takes",
                    f.id,
                    f.vehs_per_hour,
                    bounds::MOST_QUEUED_VEHICLES_A_STEP,
                    scenario.step_s
                ),
            ));
        }
        let demand_fits = match bounds::check_demand(&demand, scenario.step_s) {
            Err(r) if queue_excess_demand => {
                notes.push(format!("{}: {} (they queue, as in SUMO)", r.key, r.message));
                Ok(())
            }
            other => other,
        };
        demand_fits
            .and_then(|()| {
                bounds::check_horizon(
                    scenario.warmup_steps as u64,
                    scenario.horizon_steps as u64,
                    scenario.step_s,
                )
            })
            .and_then(|()| {
                let entries: Vec<RoadId> = flow_roads.iter().map(|&(from, _)| from).collect();
                let fill_s = timing::HorizonFit::of(&scenario, &graph, &entries).fill_s;
                bounds::check_scenario_work(&scenario, fill_s)
            })
            .map_err(|r| invalid(r.key, r.message))?;
        if let Some(iv) = &scenario.initial_vehicles
            && !scenario.vehicle_types.contains_key(&iv.vehicle_type)
        {
            return Err(invalid(
                "initial_vehicles.vehicle_type".into(),
                format!("no vehicle type `{}`", iv.vehicle_type),
            ));
        }
        let mut region_roads = Vec::new();
        if let Some(c) = &scenario.control {
            for (i, r) in c.region.iter().enumerate() {
                let found = graph
                    .find_roads(r)
                    .map_err(|e| invalid(format!("control.region[{i}]"), e.to_string()))?;
                region_roads.extend(found);
            }
            region_roads.sort();
            region_roads.dedup();
        }
        let windows = match &scenario.control {
            Some(c) if !c.windows.is_empty() => {
                if !c.region.is_empty() || c.window.is_some() {
                    return Err(invalid(
                        "control.windows".into(),
                        "a scenario with `windows` lists its roads there, not in `region` or `window`".into(),
                    ));
                }
                let windows = resolve_windows(&graph, &c.windows, &invalid)?;
                region_roads = windows.iter().flat_map(|w| w.roads.clone()).collect();
                region_roads.sort();
                windows
            }
            _ => Vec::new(),
        };
        let measure_junctions = match scenario.measure.as_ref().filter(|m| !m.merges.is_empty()) {
            Some(m) => m
                .merges
                .iter()
                .enumerate()
                .map(|(i, j)| {
                    graph
                        .find_junction(j)
                        .map_err(|e| invalid(format!("measure.merges[{i}]"), e.to_string()))
                })
                .collect::<Result<Vec<_>, _>>()?,
            None => timing::region_merges(&graph, &region_roads),
        };
        Ok(ResolvedScenario {
            scenario,
            graph,
            origin: origin.to_string(),
            flow_roads,
            flow_via,
            notes,
            queue_excess_demand,
            region_roads,
            windows,
            measure_junctions,
        })
    }
}

/// Every number of `scenario` within its range ([`ranges::check_scenario`]); `path` names the scenario.
fn check_ranges(scenario: &Scenario, path: &Path) -> Result<(), ScenarioError> {
    ranges::check_scenario(scenario).map_err(|r| ScenarioError::Invalid {
        path: path.to_path_buf(),
        key: r.key,
        message: r.message,
    })
}

/// The windows of `control.windows` resolved against `graph`: each merge a junction, each road found, no road in
/// two windows.
fn resolve_windows(
    graph: &LaneGraph,
    windows: &[ControlWindow],
    invalid: &dyn Fn(String, String) -> ScenarioError,
) -> Result<Vec<ResolvedWindow>, ScenarioError> {
    let mut owner: std::collections::HashMap<RoadId, usize> = Default::default();
    let mut out = Vec::new();
    for (k, w) in windows.iter().enumerate() {
        let mut merges = Vec::new();
        for (i, m) in w.merges().enumerate() {
            let key = if i == 0 {
                format!("control.windows[{k}].junction")
            } else {
                format!("control.windows[{k}].joined[{}]", i - 1)
            };
            merges.push(
                graph
                    .find_junction(m)
                    .map_err(|e| invalid(key, e.to_string()))?,
            );
        }
        if w.region.is_empty() {
            return Err(invalid(
                format!("control.windows[{k}].region"),
                "is empty".into(),
            ));
        }
        let mut roads = Vec::new();
        for (i, r) in w.region.iter().enumerate() {
            let key = format!("control.windows[{k}].region[{i}]");
            let found = graph
                .find_roads(r)
                .map_err(|e| invalid(key.clone(), e.to_string()))?;
            for road in found {
                if let Some(&other) = owner.get(&road)
                    && other != k
                {
                    return Err(invalid(
                        key,
                        format!("road {road} is also in control.windows[{other}]"),
                    ));
                }
                owner.insert(road, k);
                roads.push(road);
            }
        }
        roads.sort();
        roads.dedup();
        out.push(ResolvedWindow {
            name: w.junction.clone(),
            merges,
            roads,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_simple_merge_resolves() {
        let r = ResolvedScenario::load("simple_merge").unwrap();
        assert_eq!(r.flow_roads.len(), 3);
        assert_eq!(r.origin, "builtin:simple_merge");
    }

    /// `scenarios/simple_merge.toml` is what the generator makes; MAPC_BLESS=1 rewrites it.
    #[test]
    fn shipped_simple_merge_file_is_the_builtin() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/simple_merge.toml");
        let expected = format!(
            "# The paper's Simple Merge, as mapc's generator builds it (regenerate: MAPC_BLESS=1 cargo test -p mapc-scenario).\n{}",
            Scenario::simple_merge().to_toml()
        );
        if std::env::var_os("MAPC_BLESS").is_some() {
            assert!(
                std::env::var_os("CI").is_none(),
                "MAPC_BLESS is set in CI: golden files would be rewritten, not checked"
            );
            std::fs::write(&path, &expected).unwrap();
        }
        let shipped = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            shipped, expected,
            "scenarios/simple_merge.toml differs from the generator's; rerun with MAPC_BLESS=1"
        );
        assert_eq!(Scenario::load(&path).unwrap(), Scenario::simple_merge());
    }

    #[test]
    fn toml_round_trip_is_exact() {
        let s = Scenario::simple_merge();
        let back = Scenario::from_toml(&s.to_toml(), Path::new("x.toml")).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn unknown_keys_and_bad_references_are_named() {
        let text = Scenario::simple_merge()
            .to_toml()
            .replace("horizon_steps", "horizon_stepz");
        let err = Scenario::from_toml(&text, Path::new("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains("horizon_stepz"),
            "{err}"
        );

        let mut s = Scenario::simple_merge();
        s.flows[1].vehicle_type = "robot".into();
        let err = ResolvedScenario::resolve(s, Path::new("."), "s.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "s.toml: flows[1].vehicle_type: no vehicle type `robot`"
        );

        let mut s = Scenario::simple_merge();
        s.flows[0].from = "nowhere".into();
        let err = ResolvedScenario::resolve(s, Path::new("."), "s.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("s.toml: flows[0].from: no road `nowhere`"),
            "{err}"
        );
    }

    /// `control.windows` resolves each window's roads; a road in two windows, or windows beside `region`, are
    /// errors naming the key.
    #[test]
    fn several_windows_resolve_and_bad_ones_are_named() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let path = dir.join("i696_3merge.toml");
        let r = ResolvedScenario::load(path.to_str().unwrap()).unwrap();
        assert_eq!(r.windows.len(), 3);
        assert_eq!(r.windows[0].name, "osm:61862553");
        assert_eq!(
            r.windows[0].merges,
            vec![r.graph.find_junction("osm:61862553").unwrap()]
        );
        let union: usize = r.windows.iter().map(|w| w.roads.len()).sum();
        assert_eq!(union, r.region_roads.len());

        let mut s = r.scenario.clone();
        let c = s.control.as_mut().unwrap();
        let stolen = c.windows[0].region[0].clone();
        c.windows[2].region.push(stolen.clone());
        let err = ResolvedScenario::resolve(s, &dir, "m.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            format!(
                "m.toml: control.windows[2].region[3]: road {stolen} is also in control.windows[0]"
            )
        );

        let mut s = r.scenario.clone();
        s.control.as_mut().unwrap().region = vec!["R54".into()];
        let err = ResolvedScenario::resolve(s, &dir, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("m.toml: control.windows: "), "{err}");

        let mut s = r.scenario.clone();
        s.control.as_mut().unwrap().windows[1].junction = "osm:1".into();
        let err = ResolvedScenario::resolve(s, &dir, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("m.toml: control.windows[1].junction: ") && err.contains("osm:1"),
            "{err}"
        );
    }
}
