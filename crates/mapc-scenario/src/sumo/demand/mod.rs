//! SUMO's demand as mapc flows: `vType`s and `vTypeDistribution`s become vehicle types and mixes, `route`s the
//! roads a flow passes (`from`, `via`, `to`), and each `flow`, `vehicle` and `trip` one mapc flow (a vehicle or a
//! trip is a flow of one). Rates as SUMO 1.8 reads them: `vehsPerHour`, `period` (3600 / period veh/h),
//! `probability` (per second) or `number` over [begin, end).

use super::config::SumoConfig;
use super::vtypes::{default_vtype, num, vtype};
use super::{ReadOptions, SumoError};
use crate::model::{CarFollowModel, Flow, NetworkSpec, Scenario, VehicleType};
use mapc_graph::LaneGraph;
use mapc_import::SumoElement;
use std::collections::{BTreeMap, BTreeSet, HashMap};

mod paths;

/// SUMO's name of the type a vehicle without `type` drives.
const DEFAULT_VTYPE: &str = "DEFAULT_VEHTYPE";
/// A flow with neither `end` nor `number` runs a day (SUMO 1.8).
const DEFAULT_FLOW_S: f64 = 86_400.0;
use crate::bounds::MOST_QUEUED_VEHICLES_A_STEP as MOST_VEHICLES_A_STEP;
/// Without an `end`, a run lasts this long after its last departure (SUMO runs until the network is empty).
pub const DRAIN_AFTER_LAST_DEPARTURE_S: f64 = 3600.0;

/// Everything of the files, keyed by id.
struct Demand<'a> {
    types: BTreeMap<String, VehicleType>,
    /// The network's lights.
    light_ids: BTreeSet<String>,
    mixes: BTreeMap<String, BTreeMap<String, f64>>,
    routes: HashMap<String, &'a SumoElement>,
    departures: Vec<&'a SumoElement>,
    /// Static light programs of the additional files, in file order (the last of a light runs, as in SUMO).
    lights: Vec<mapc_graph::TrafficLight>,
    /// Induction loops, in file order.
    detectors: Vec<crate::model::Detector>,
    /// The network's roads for routing trips (built at the first trip).
    routes_by_road: std::cell::OnceCell<mapc_graph::topology::RoadRoutes>,
    /// Kinds of element or attribute dropped, once each.
    skipped: BTreeSet<String>,
    /// Attributes dropped (skipping), each with the first value seen.
    skipped_attrs: BTreeMap<String, String>,
}

/// The mapc scenario of `config`'s files (`files`: route and additional files, read), on the network `graph`
/// (SUMO's net, imported).
pub fn scenario(
    config: &SumoConfig,
    files: &[SumoElement],
    graph: &LaneGraph,
    options: &ReadOptions,
    warnings: &mut Vec<String>,
) -> Result<Scenario, SumoError> {
    let model = if config.default_car_follow_model == "IDM" {
        CarFollowModel::Idm
    } else {
        CarFollowModel::Krauss
    };
    let mut d = Demand {
        light_ids: graph.lights.iter().map(|l| l.id.clone()).collect(),
        types: BTreeMap::new(),
        mixes: BTreeMap::new(),
        routes: HashMap::new(),
        departures: Vec::new(),
        lights: Vec::new(),
        detectors: Vec::new(),
        routes_by_road: std::cell::OnceCell::new(),
        skipped: BTreeSet::new(),
        skipped_attrs: BTreeMap::new(),
    };
    for f in files {
        for e in &f.children {
            d.read_top(e, config, graph, model, options)?;
        }
    }
    // a program of the additional files replaces the network's (SUMO runs the last one loaded): the scenario
    // carries it, and resolving the scenario applies it
    let lights = std::mem::take(&mut d.lights);
    let mut flows = Vec::new();
    let mut last_departure: f64 = 0.0;
    for e in d.departures.clone() {
        let (flow, last) = d.flow(e, config, graph, options)?;
        last_departure = last_departure.max(last);
        if let Some(flow) = flow {
            flows.push(flow);
        }
    }
    if flows.iter().any(|f| f.vehicle_type == DEFAULT_VTYPE)
        && !d.types.contains_key(DEFAULT_VTYPE)
        && !d.mixes.contains_key(DEFAULT_VTYPE)
    {
        d.types.insert(
            DEFAULT_VTYPE.into(),
            default_vtype(config.default_speed_dev, model),
        );
    }
    let begin = config.begin_s;
    // SUMO 1.8 leaves out a vehicle whose departure lies before the run's begin (RESCO's Cologne files hold the
    // whole day's vehicles, its configurations run an hour of it)
    let before = flows.len();
    flows.retain(|f| !(f.vehicle && f.begin_s < begin));
    if flows.len() < before {
        warnings.push(format!(
            "{} vehicles depart before the begin ({begin} s): left out, as SUMO leaves them out",
            before - flows.len()
        ));
    }
    let end = config
        .end_s
        .unwrap_or(last_departure + DRAIN_AFTER_LAST_DEPARTURE_S);
    let duration = end - begin;
    if !(duration > 0.0) {
        return Err(SumoError::File {
            path: config.path.clone().unwrap_or_default(),
            message: format!("the run ends at {end} s, not after its begin {begin} s"),
        });
    }
    // a single vehicle's rate: one in the run (what the demand checks add up per entry)
    for f in &mut flows {
        if f.number == Some(1) && f.vehs_per_hour == 0.0 {
            f.vehs_per_hour = 3600.0 / duration;
        }
        f.begin_s -= begin;
        f.end_s = f.end_s.map(|e| e - begin);
    }
    warnings.extend(d.skipped.iter().map(|s| format!("dropped: {s}")));
    warnings.extend(
        d.skipped_attrs
            .iter()
            .map(|(kind, first)| format!("dropped: {kind} (such as {first})")),
    );
    let name = config
        .path
        .as_deref()
        .and_then(|p| p.file_name())
        .and_then(|n| n.to_str())
        .map_or("sumo", |n| {
            n.trim_end_matches(".sumocfg").trim_end_matches(".cfg")
        })
        .to_string();
    let steps = (duration / config.step_s).round();
    if steps > u32::MAX as f64 {
        return Err(SumoError::File {
            path: config.path.clone().unwrap_or_default(),
            message: format!("{duration} s is too many steps of {} s", config.step_s),
        });
    }
    Ok(Scenario {
        name,
        description: format!(
            "SUMO scenario {} (net {})",
            config
                .path
                .as_deref()
                .map_or("from files".into(), |p| p.display().to_string()),
            config.net_file.display()
        ),
        step_s: config.step_s,
        horizon_steps: steps as u32,
        warmup_steps: 0,
        time_to_teleport_s: (config.time_to_teleport_s > 0.0).then_some(config.time_to_teleport_s),
        network: NetworkSpec::Map(config.net_file.clone()),
        vehicle_types: d.types,
        vehicle_type_mixes: d.mixes,
        flows,
        version: crate::model::SCENARIO_VERSION,
        initial_vehicles: None,
        control: None,
        measure: None,
        queue_excess_demand: true,
        sumo_clock: true,
        clock_begin_s: begin,
        sumo_junction_lane_changes: true,
        light_programs: lights,
        detectors: std::mem::take(&mut d.detectors),
    })
}

/// An `inductionLoop` (or `e1Detector`) as SUMO 1.8 reads it: `id`, `lane`, `pos`, `freq` (`period` in later
/// SUMO), `file`, `friendlyPos`, `vTypes`.
fn induction_loop(e: &SumoElement, graph: &LaneGraph) -> Result<crate::model::Detector, SumoError> {
    let need = |key: &str| {
        e.get(key)
            .ok_or_else(|| SumoError::at(&e.place, format!("<{}> without `{key}`", e.name)))
    };
    let id = need("id")?.to_string();
    let lane_id = need("lane")?;
    let (edge, index) = lane_id
        .rsplit_once('_')
        .and_then(|(edge, i)| Some((edge, i.parse::<u8>().ok()?)))
        .ok_or_else(|| {
            SumoError::at(
                &e.place,
                format!("`{lane_id}` is not a lane id (EDGE_INDEX)"),
            )
        })?;
    let road = graph
        .find_roads(edge)
        .map_err(|_| SumoError::at(&e.place, format!("the network has no lane `{lane_id}`")))?[0];
    let r = graph.road(road).expect("a road found in the graph");
    let Some(lane) = r.lane_of_sumo_index(index as u32) else {
        return Err(SumoError::at(&e.place, no_car_lane(lane_id, r)));
    };
    let pos_m =
        num(e, "pos")?.ok_or_else(|| SumoError::at(&e.place, "<inductionLoop> without `pos`"))?;
    let friendly_pos = match e.get("friendlyPos") {
        None => false,
        Some(v) => mapc_import::sumo_bool(v).ok_or_else(|| {
            SumoError::at(&e.place, format!("friendlyPos=\"{v}\" is not a boolean"))
        })?,
    };
    crate::resolved::detector_position(pos_m, r.length_m, friendly_pos)
        .map_err(|m| SumoError::at(&e.place, m))?;
    let period_s = match (num(e, "freq")?, num(e, "period")?) {
        (Some(f), None) | (None, Some(f)) => f,
        (Some(_), Some(_)) => {
            return Err(SumoError::at(&e.place, "both `freq` and `period`"));
        }
        (None, None) => return Err(SumoError::at(&e.place, "<inductionLoop> without `freq`")),
    };
    if !(period_s > 0.0 && period_s.is_finite()) {
        return Err(SumoError::at(
            &e.place,
            format!("freq=\"{period_s}\" must be positive"),
        ));
    }
    Ok(crate::model::Detector {
        id,
        road: edge.to_string(),
        lane,
        pos_m,
        period_s,
        friendly_pos,
        vehicle_types: e
            .get("vTypes")
            .map(|t| t.split_whitespace().map(str::to_string).collect())
            .unwrap_or_default(),
        file: Some(need("file")?.to_string()),
    })
}

/// Why a SUMO lane id names no lane of road `r`: none such, or one closed to cars that the import left out.
fn no_car_lane(lane_id: &str, r: &mapc_graph::Road) -> String {
    if r.provenance.sumo_lanes.is_empty() {
        format!("the network has no lane `{lane_id}`")
    } else {
        format!(
            "the network has no lane `{lane_id}` for cars (its edge's lanes closed to cars, sidewalks and cycle or \
             bus lanes, are left out)"
        )
    }
}

impl<'a> Demand<'a> {
    fn unsupported(
        &mut self,
        e: &SumoElement,
        what: String,
        options: &ReadOptions,
    ) -> Result<(), SumoError> {
        if options.skip_unsupported {
            self.skipped.insert(what);
            Ok(())
        } else {
            Err(SumoError::at(
                &e.place,
                format!("{what}: not simulated by mapc; `--skip-unsupported` drops it"),
            ))
        }
    }

    /// A `vType`'s id and type, what it drops noted.
    fn read_vtype(
        &mut self,
        e: &SumoElement,
        config: &SumoConfig,
        model: CarFollowModel,
        options: &ReadOptions,
    ) -> Result<(String, VehicleType), SumoError> {
        let id = e
            .get("id")
            .ok_or_else(|| SumoError::at(&e.place, "<vType> without `id`"))?
            .to_string();
        let mut skipped = Vec::new();
        let t = vtype(
            e,
            config.default_speed_dev,
            model,
            options.skip_unsupported,
            &mut skipped,
        )?;
        self.skipped.extend(skipped);
        Ok((id, t))
    }

    fn read_top(
        &mut self,
        e: &'a SumoElement,
        config: &SumoConfig,
        graph: &LaneGraph,
        model: CarFollowModel,
        options: &ReadOptions,
    ) -> Result<(), SumoError> {
        let id = || {
            e.get("id")
                .map(str::to_string)
                .ok_or_else(|| SumoError::at(&e.place, format!("<{}> without `id`", e.name)))
        };
        match e.name.as_str() {
            "vType" => {
                let (id, t) = self.read_vtype(e, config, model, options)?;
                if self.types.insert(id.clone(), t).is_some() || self.mixes.contains_key(&id) {
                    return Err(SumoError::at(
                        &e.place,
                        format!("a second vehicle type `{id}`"),
                    ));
                }
            }
            "vTypeDistribution" => {
                let id = id()?;
                let mut mix = BTreeMap::new();
                for c in &e.children {
                    if c.name != "vType" {
                        continue;
                    }
                    let (tid, t) = self.read_vtype(c, config, model, options)?;
                    let p = num(c, "probability")?.unwrap_or(1.0);
                    self.types.insert(tid.clone(), t);
                    mix.insert(tid, p);
                }
                if let Some(list) = e.get("vTypes") {
                    let probs: Vec<f64> = match e.get("probabilities") {
                        Some(p) => p
                            .split_whitespace()
                            .map(|x| x.parse::<f64>())
                            .collect::<Result<_, _>>()
                            .map_err(|_| {
                                SumoError::at(
                                    &e.place,
                                    format!("`probabilities` is `{p}`, not numbers"),
                                )
                            })?,
                        None => Vec::new(),
                    };
                    for (k, t) in list.split_whitespace().enumerate() {
                        if !self.types.contains_key(t) {
                            return Err(SumoError::at(
                                &e.place,
                                format!("vTypes names `{t}`, a type not defined before"),
                            ));
                        }
                        mix.insert(t.to_string(), probs.get(k).copied().unwrap_or(1.0));
                    }
                }
                if mix.is_empty() || mix.values().any(|p| !(p.is_finite() && *p > 0.0)) {
                    return Err(SumoError::at(
                        &e.place,
                        "a distribution needs members with positive probabilities",
                    ));
                }
                if self.types.contains_key(&id) || self.mixes.insert(id.clone(), mix).is_some() {
                    return Err(SumoError::at(
                        &e.place,
                        format!("a second vehicle type `{id}`"),
                    ));
                }
            }
            "route" => {
                let id = id()?;
                if e.get("edges").is_none() {
                    return Err(SumoError::at(&e.place, "a route without `edges`"));
                }
                if self.routes.insert(id.clone(), e).is_some() {
                    return Err(SumoError::at(&e.place, format!("a second route `{id}`")));
                }
                for c in &e.children {
                    if c.name != "param" {
                        self.unsupported(c, format!("<{}> inside a route", c.name), options)?;
                    }
                }
            }
            "vehicle" | "flow" | "trip" => self.departures.push(e),
            "param" | "interval" if e.children.is_empty() => {}
            // outputs that change nothing in the run: read, and said once each not to be written
            "edgeData"
            | "laneData"
            | "timedEvent"
            | "laneAreaDetector"
            | "e2Detector"
            | "entryExitDetector"
            | "e3Detector"
            | "instantInductionLoop"
            | "routeProbe"
            | "vTypeProbe" => {
                self.skipped.insert(format!(
                    "<{}> (an output of SUMO's that mapc does not write; the run is the same)",
                    e.name
                ));
            }
            "tlLogic" if e.get("type").unwrap_or("static") == "static" => {
                let mut phases = Vec::new();
                for p in e.children.iter().filter(|c| c.name == "phase") {
                    let duration_s = num(p, "duration")?.filter(|d| *d > 0.0).ok_or_else(|| {
                        SumoError::at(&p.place, "a phase needs a positive `duration`")
                    })?;
                    let state = p
                        .get("state")
                        .ok_or_else(|| SumoError::at(&p.place, "a phase without `state`"))?
                        .to_string();
                    phases.push(mapc_graph::SignalPhase { duration_s, state });
                }
                if phases.is_empty() {
                    return Err(SumoError::at(&e.place, "a light program without phases"));
                }
                let id = id()?;
                if !self.light_ids.contains(&id) {
                    return Err(SumoError::at(
                        &e.place,
                        format!("the network has no traffic light `{id}`"),
                    ));
                }
                self.lights.push(mapc_graph::TrafficLight {
                    id,
                    program: e.get("programID").unwrap_or("0").to_string(),
                    offset_s: num(e, "offset")?.unwrap_or(0.0),
                    phases,
                });
            }
            "inductionLoop" | "e1Detector" => {
                let d = induction_loop(e, graph)?;
                if self.detectors.iter().any(|o| o.id == d.id) {
                    return Err(SumoError::at(
                        &e.place,
                        format!("a second detector `{}`", d.id),
                    ));
                }
                self.detectors.push(d);
            }
            other => self.unsupported(e, format!("<{other}>"), options)?,
        }
        Ok(())
    }

    /// One vehicle, flow or trip as a mapc flow, and the time of its last departure (`None`: dropped).
    fn flow(
        &mut self,
        e: &'a SumoElement,
        config: &SumoConfig,
        graph: &LaneGraph,
        options: &ReadOptions,
    ) -> Result<(Option<Flow>, f64), SumoError> {
        let id = e
            .get("id")
            .ok_or_else(|| SumoError::at(&e.place, format!("<{}> without `id`", e.name)))?
            .to_string();
        let vtype = e.get("type").unwrap_or(DEFAULT_VTYPE).to_string();
        if vtype != DEFAULT_VTYPE
            && !self.types.contains_key(&vtype)
            && !self.mixes.contains_key(&vtype)
        {
            return Err(SumoError::at(
                &e.place,
                format!("type `{vtype}` is not defined"),
            ));
        }
        for c in &e.children {
            if c.name != "param" && c.name != "route" {
                self.unsupported(c, format!("<{}> inside a <{}>", c.name, e.name), options)?;
                return Ok((None, 0.0));
            }
        }
        // an attribute mapc does not simulate: refused, or (skipping) SUMO's default instead
        let mut dropped: Vec<&str> = Vec::new();
        for (k, v) in &e.attrs {
            let fine = match k.as_str() {
                "id" | "type" | "route" | "from" | "to" | "via" | "begin" | "end" | "depart"
                | "vehsPerHour" | "period" | "probability" | "number" | "departLane" | "color"
                | "line" | "fromTaz" | "toTaz" | "insertionChecks" | "reroute" => true,
                "departSpeed" => v.trim().parse::<f64>().is_ok() || v == "max" || v == "desired",
                "departPos" => matches!(v.as_str(), "base" | "random" | "random_free" | "free"),
                "arrivalLane" => v == "current",
                "arrivalPos" => v == "max",
                "arrivalSpeed" => v == "current",
                // what SUMO's vehroute-output records of an earlier run (RESCO's Cologne files): SUMO 1.8 reads
                // such a file back and leaves these out
                "arrival" | "routeLength" => true,
                _ => false,
            };
            if !fine {
                if options.skip_unsupported {
                    // one warning per attribute, with its first value, not one per value (a file of thousands
                    // of vehicles)
                    self.skipped_attrs
                        .entry(format!("`{k}` on a <{}>", e.name))
                        .or_insert_with(|| format!("`{k}=\"{v}\"`"));
                } else {
                    self.unsupported(e, format!("`{k}=\"{v}\"` on a <{}>", e.name), options)?;
                }
                dropped.push(k);
            }
        }
        let path = self.path(e, graph)?;
        let (depart_speed_mps, depart_speed) = match e
            .get("departSpeed")
            .filter(|_| !dropped.contains(&"departSpeed"))
        {
            Some(rule @ ("max" | "desired")) => (0.0, Some(rule.to_string())),
            _ => (num(e, "departSpeed")?.unwrap_or(0.0), None),
        };
        if depart_speed_mps < 0.0 {
            return Err(SumoError::at(&e.place, "a negative departSpeed"));
        }
        let depart_lane = match e
            .get("departLane")
            .filter(|_| !dropped.contains(&"departLane"))
        {
            None | Some("first") => None,
            Some(l @ ("best" | "random" | "free")) => Some(l.to_string()),
            Some(l) if let Ok(sumo_index) = l.parse::<u32>() => {
                // SUMO's index on the departure edge; the road's own where lanes closed to cars were left out
                let road = graph
                    .find_roads(&path.from)
                    .ok()
                    .and_then(|roads| graph.road(roads[0]));
                match road.filter(|r| !r.provenance.sumo_lanes.is_empty()) {
                    Some(r) => match r.lane_of_sumo_index(sumo_index) {
                        Some(k) => Some(k.to_string()),
                        None => {
                            return Err(SumoError::at(
                                &e.place,
                                format!(
                                    "departLane=\"{l}\": {}",
                                    no_car_lane(&format!("{}_{l}", path.from), r)
                                ),
                            ));
                        }
                    },
                    None => Some(l.to_string()),
                }
            }
            Some(l) => {
                self.unsupported(e, format!("departLane `{l}`"), options)?;
                None
            }
        };
        let scale = config.scale;
        let mut flow = Flow {
            id: id.clone(),
            from: path.from,
            to: path.to,
            via: path.via,
            vehicle_type: vtype,
            depart_speed_mps,
            depart_speed,
            depart_lane,
            depart_pos: e
                .get("departPos")
                .filter(|p| *p != "base" && !dropped.contains(&"departPos"))
                .map(str::to_string),
            ..Flow::default()
        };
        let last;
        if e.name == "flow" {
            let begin = num(e, "begin")?.unwrap_or(config.begin_s);
            let rates: Vec<&str> = ["vehsPerHour", "period", "probability"]
                .into_iter()
                .filter(|k| e.get(k).is_some())
                .collect();
            let number = match e.get("number") {
                None => None,
                Some(n) => Some(n.trim().parse::<u64>().map_err(|_| {
                    SumoError::at(&e.place, format!("`number` is `{n}`, not a whole number"))
                })?),
            };
            let end = num(e, "end")?;
            if rates.len() > 1 {
                return Err(SumoError::at(
                    &e.place,
                    format!("a flow with two rates: {}", rates.join(" and ")),
                ));
            }
            if rates.is_empty() && (number.is_none() || end.is_none()) {
                return Err(SumoError::at(
                    &e.place,
                    "a flow without a rate: give vehsPerHour, period, probability, or number with end",
                ));
            }
            let end_s = match (end, number) {
                (Some(e), _) => e,
                (None, Some(_)) => f64::INFINITY,
                (None, None) => begin + DEFAULT_FLOW_S,
            };
            if !(end_s > begin) {
                return Err(SumoError::at(
                    &e.place,
                    format!("the flow ends at {end_s} s, not after its begin {begin} s"),
                ));
            }
            flow.begin_s = begin;
            flow.end_s = end_s.is_finite().then_some(end_s);
            flow.number = number.map(|n| ((n as f64) * scale).round() as u64);
            let positive = |key: &str| -> Result<f64, SumoError> {
                let v = num(e, key)?.expect("listed as given");
                if v > 0.0 {
                    Ok(v)
                } else {
                    Err(SumoError::at(
                        &e.place,
                        format!("`{key}` {v}: must be positive"),
                    ))
                }
            };
            flow.vehs_per_hour = match rates.first().copied() {
                Some("vehsPerHour") => positive("vehsPerHour")? * scale,
                Some("period") => 3600.0 / positive("period")? * scale,
                Some(_) => {
                    let p = positive("probability")?;
                    if p > 1.0 {
                        return Err(SumoError::at(&e.place, format!("probability {p}: above 1")));
                    }
                    let p = (p * scale).min(1.0);
                    flow.probability = Some(p);
                    3600.0 * p
                }
                // number over [begin, end): SUMO's period (end - begin) / number
                None => 3600.0 * flow.number.unwrap_or(0) as f64 / (end_s - begin),
            };
            if flow.number == Some(0) {
                return Ok((None, 0.0));
            }
            // demand above what any road takes queues, but each departure is still counted one by one
            let most = MOST_VEHICLES_A_STEP * 3600.0 / config.step_s;
            if !(flow.vehs_per_hour <= most) {
                return Err(SumoError::at(
                    &e.place,
                    format!(
                        "{:.0} veh/h: more than {MOST_VEHICLES_A_STEP} vehicles a {} s step, which no road takes",
                        flow.vehs_per_hour, config.step_s
                    ),
                ));
            }
            last = if end_s.is_finite() {
                end_s
            } else {
                begin + 3600.0 * flow.number.unwrap_or(0) as f64 / flow.vehs_per_hour
            };
        } else {
            let depart = match e.get("depart") {
                Some(t) => t
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        SumoError::at(
                            &e.place,
                            format!("depart `{t}`: mapc reads a time in seconds"),
                        )
                    })?,
                None => {
                    return Err(SumoError::at(
                        &e.place,
                        format!("a <{}> without `depart`", e.name),
                    ));
                }
            };
            flow.begin_s = depart;
            flow.number = Some(1);
            flow.vehicle = true;
            last = depart;
        }
        Ok((Some(flow), last))
    }
}
