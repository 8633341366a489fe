//! A scenario resolved: its network built or loaded (or a SUMO user's scenario read), every road, junction, type
//! and window it names checked against that network, its numbers and its work bounded.

use super::*;

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
    /// The induction loops on their roads, positions on the lane.
    pub detectors: Vec<ResolvedDetector>,
}

/// An induction loop with its road found and its position on the lane.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedDetector {
    pub id: String,
    pub road: RoadId,
    pub lane: u8,
    /// From the lane's start, within the lane (m).
    pub pos_m: f64,
    pub period_s: f64,
    pub vehicle_types: Vec<String>,
    /// The output file's name, folders dropped.
    pub file: Option<String>,
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
            NetworkSpec::FlowBottleneck(p) => {
                generator::flow_bottleneck(p).map_err(|message| ScenarioError::Network {
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

    /// This scenario with `share` of its flows' vehicles (those named in `only`; all when empty) driven as AVs
    /// ([`crate::av_share`]); a scenario without a `control` section gets the approach to each of its merges and
    /// lane drops as its controlled region ([`crate::approach`]; the whole network where it has none).
    pub fn with_av_share(
        self,
        share: f64,
        only: &[String],
    ) -> Result<ResolvedScenario, ScenarioError> {
        let origin = self.origin.clone();
        let had_control = self.scenario.control.is_some();
        let mut scenario =
            crate::av_share::with_av_share(self.scenario, share, only).map_err(|message| {
                ScenarioError::Invalid {
                    path: PathBuf::from(&origin),
                    key: "av_share".into(),
                    message,
                }
            })?;
        if let Some(c) = scenario.control.as_mut().filter(|_| !had_control) {
            c.region = crate::approach::approach_roads(&self.graph)
                .iter()
                .map(|r| r.to_string())
                .collect();
        }
        let mut rs = ResolvedScenario::on_network(scenario, self.graph, &origin)?;
        rs.notes.splice(0..0, self.notes);
        Ok(rs)
    }

    /// The scenario as a file anywhere can hold it: its network's path made absolute (a scenario file's are
    /// relative to its folder, a SUMO configuration's to the working folder).
    pub fn scenario_with_absolute_paths(&self) -> Scenario {
        let mut scenario = self.scenario.clone();
        let origin = Path::new(&self.origin);
        let base = if origin.is_file() && !sumo::is_sumo_config(origin) {
            origin.parent().map(Path::to_path_buf).unwrap_or_default()
        } else {
            PathBuf::new()
        };
        let absolute = |p: &Path| {
            let joined = base.join(p);
            std::fs::canonicalize(&joined).unwrap_or(joined)
        };
        scenario.network = match &scenario.network {
            NetworkSpec::Graph(g) => NetworkSpec::Graph(absolute(g)),
            NetworkSpec::Map(m) => NetworkSpec::Map(absolute(m)),
            other => other.clone(),
        };
        scenario
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
        // SUMO runs a light's program on its own clock, which reads `begin` at the first step: the cycle is
        // shifted by it so that the run's clock (0 there) finds the phase SUMO's finds
        if scenario.clock_begin_s != 0.0 {
            for l in &mut graph.lights {
                let cycle: f64 = l.phases.iter().map(|p| p.duration_s).sum();
                if cycle > 0.0 {
                    l.offset_s -= scenario.clock_begin_s.rem_euclid(cycle);
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
                && !matches!(rule, "base" | "random" | "random_free" | "free")
            {
                return Err(invalid(
                    format!("flows[{i}].depart_pos"),
                    format!(
                        "flow `{}`: `{rule}`: `base`, `random`, `random_free` or `free`",
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
                    // a generated network's lanes come from its own keys: name them
                    let from_keys = match &scenario.network {
                        NetworkSpec::SimpleMerge(p) => {
                            format!("; network.simple_merge.lanes = {}", p.lanes)
                        }
                        NetworkSpec::LaneDrop(p) => format!(
                            "; network.lane_drop.lanes_before = {}, lanes_after = {}",
                            p.lanes_before, p.lanes_after
                        ),
                        _ => String::new(),
                    };
                    return Err(invalid(
                        format!("flows[{i}].depart_lane"),
                        format!(
                            "flow `{}` departs on lane {lane}, but its entry road `{}` ({from}) has {lanes} lane(s) \
                             (0 to {}{from_keys})",
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
                .find(|(_, f)| f.vehs_per_hour.is_nan() || f.vehs_per_hour > most)
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
        let detectors = resolve_detectors(&scenario, &graph, &invalid)?;
        Ok(ResolvedScenario {
            detectors,
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

/// The induction loops of `scenario` on `graph`: roads, lanes, types and positions checked as SUMO checks them.
fn resolve_detectors(
    scenario: &Scenario,
    graph: &LaneGraph,
    invalid: &dyn Fn(String, String) -> ScenarioError,
) -> Result<Vec<ResolvedDetector>, ScenarioError> {
    let mut seen = std::collections::BTreeSet::new();
    scenario
        .detectors
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let key = |what: &str| format!("detectors[{i}].{what}");
            if !seen.insert(d.id.as_str()) {
                return Err(invalid(key("id"), format!("a second detector `{}`", d.id)));
            }
            let road = graph
                .find_roads(&d.road)
                .map_err(|e| invalid(key("road"), e.to_string()))?[0];
            let r = graph.road(road).expect("a road found in the graph");
            if d.lane as usize >= r.lanes.len() {
                return Err(invalid(
                    key("lane"),
                    format!(
                        "road `{}` has {} lanes, no lane {}",
                        d.road,
                        r.lanes.len(),
                        d.lane
                    ),
                ));
            }
            let pos = detector_position(d.pos_m, r.length_m, d.friendly_pos)
                .map_err(|m| invalid(key("pos_m"), m))?;
            if !(d.period_s > 0.0 && d.period_s.is_finite()) {
                return Err(invalid(
                    key("period_s"),
                    format!("{} s: must be positive", d.period_s),
                ));
            }
            if let Some(t) = d
                .vehicle_types
                .iter()
                .find(|t| !scenario.vehicle_types.contains_key(*t))
            {
                return Err(invalid(
                    key("vehicle_types"),
                    format!("no vehicle type `{t}`"),
                ));
            }
            Ok(ResolvedDetector {
                id: d.id.clone(),
                road,
                lane: d.lane,
                pos_m: pos,
                period_s: d.period_s,
                vehicle_types: d.vehicle_types.clone(),
                file: d.file.as_deref().and_then(safe_file_name),
            })
        })
        .collect()
}

/// Where a detector at `pos_m` lies on a lane of `length` m, as SUMO reads it: negative counts from the end; off
/// the lane is refused, or moved onto its nearest end with `friendly`.
pub fn detector_position(pos_m: f64, length: f64, friendly: bool) -> Result<f64, String> {
    let pos = if pos_m < 0.0 { pos_m + length } else { pos_m };
    if pos.is_finite() && (0.0..=length).contains(&pos) {
        return Ok(pos);
    }
    if friendly && pos.is_finite() {
        return Ok(pos.clamp(0.0, length));
    }
    Err(format!(
        "position {pos_m} m is off the {length:.2} m lane (a friendly position moves it onto the lane)"
    ))
}

/// The last component of a file name from an input, when it is a plain name (no `..`, no separators left): an
/// output named by a scenario stays inside the folder it is written to.
pub fn safe_file_name(name: &str) -> Option<String> {
    let last = name.rsplit(['/', '\\']).next()?;
    (!last.is_empty() && last != "." && last != ".." && !last.contains('\0'))
        .then(|| last.to_string())
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
