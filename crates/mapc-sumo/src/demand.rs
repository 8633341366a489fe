//! The demand as SUMO routes (`.rou.xml`): one vehicle type per mapc type (IDM with mapc's parameters), one route
//! and one flow per mapc flow, and the initial vehicles; plus the `.sumocfg` with the options of the paper's runs.
//! Routes, departures and initial positions come from mapc-sim's own description of the scenario
//! ([`mapc_sim::SimSpec`]), so SUMO drives exactly the routes mapc drives.

use crate::names::SumoNames;
use crate::xml::{element, num, start};
use mapc_graph::{LaneGraph, RoadId};
use mapc_sim::{FlowSpec, Network, SimError, SimSpec};

/// IDM's integration sub-step in SUMO 1.8 (not settable there as a duration).
const SUMO_IDM_STEPPING_S: f64 = 0.25;

/// When the initial vehicles enter: after the first step, as the original rollouts added them (TraCI `add` after
/// `start_simulation`), so they are inserted in the second step, the one before the horizon's first.
pub fn initial_depart_s(step_s: f64) -> f64 {
    step_s
}

/// The roads a vehicle entering on `from` drives, as mapc-sim routes it.
pub fn route_roads(
    net: &Network,
    graph: &LaneGraph,
    from: RoadId,
    via: &[RoadId],
    to: Option<RoadId>,
) -> Result<Vec<RoadId>, SimError> {
    // Road by road, as mapc-sim routes a vehicle of a given entry lane: a lane that ends (an acceleration lane)
    // is left by a lane change, so the lane path may end early where the road path goes on.
    Ok(net
        .route_roads(graph, from, via, to)?
        .into_iter()
        .map(|r| net.road_ids[r])
        .collect())
}

fn edge_list(graph: &LaneGraph, names: &SumoNames, roads: &[RoadId]) -> String {
    roads
        .iter()
        .map(|r| {
            let i = graph
                .roads
                .binary_search_by_key(r, |x| x.id)
                .expect("a route's roads are the graph's");
            names.edges[i].clone()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The `.rou.xml` text; `flow_ids` names each of the spec's flows.
pub fn routes_xml(
    spec: &SimSpec,
    names: &SumoNames,
    flow_ids: &[String],
) -> Result<String, SimError> {
    let graph = &spec.graph;
    let net = Network::from_graph(graph)?;
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n");
    out.push_str("<!-- written by `mapc export` for SUMO 1.8 -->\n");
    start(&mut out, 0, "routes", &[]);
    for t in &spec.vehicle_types {
        element(&mut out, 4, "vType", &vtype_attrs(t, &t.name, None)?);
    }
    // a flow drawing its vehicles' types from a mix: SUMO 1.8's vTypeDistribution of copies of the types
    for (i, f) in spec.flows.iter().enumerate() {
        if f.type_mix.is_empty() {
            continue;
        }
        start(
            &mut out,
            4,
            "vTypeDistribution",
            &[("id", mix_id(&flow_ids[i]))],
        );
        let mut below = 0.0;
        for &(t, cumulative) in &f.type_mix {
            let vt = &spec.vehicle_types[t];
            let id = format!("{}@{}", vt.name, mix_id(&flow_ids[i]));
            element(
                &mut out,
                8,
                "vType",
                &vtype_attrs(vt, &id, Some(cumulative - below))?,
            );
            below = cumulative;
        }
        out.push_str("    </vTypeDistribution>\n");
    }
    // Initial vehicles first: SUMO wants a route file sorted by departure.
    let depart = initial_depart_s(spec.step_s);
    for (i, v) in spec.initial.iter().enumerate() {
        let roads = route_roads(&net, graph, v.road, &[], None)?;
        start(
            &mut out,
            4,
            "vehicle",
            &[
                ("id", format!("initial_{i}")),
                ("type", spec.vehicle_types[v.vehicle_type].name.clone()),
                ("depart", num(depart, 2)),
                ("departLane", "0".into()),
                ("departPos", num(v.pos_m, 4)),
                ("departSpeed", num(v.speed, 4)),
            ],
        );
        element(
            &mut out,
            8,
            "route",
            &[("edges", edge_list(graph, names, &roads))],
        );
        out.push_str("    </vehicle>\n");
    }
    let mut order: Vec<usize> = (0..spec.flows.len()).collect();
    order.sort_by(|&a, &b| spec.flows[a].begin_s.total_cmp(&spec.flows[b].begin_s));
    for i in order {
        let f = &spec.flows[i];
        let roads = route_roads(&net, graph, f.from, &f.via, f.to)?;
        // SUMO needs an end; mapc's open-ended flows run past any horizon.
        let end = if f.end_s.is_finite() {
            f.end_s
        } else {
            86_400.0
        };
        let vtype = if f.type_mix.is_empty() {
            spec.vehicle_types[f.vehicle_type].name.clone()
        } else {
            mix_id(&flow_ids[i])
        };
        let mut attrs = vec![
            ("id", flow_ids[i].clone()),
            ("type", vtype),
            ("begin", num(f.begin_s, 4)),
        ];
        // SUMO 1.8 takes a rate with an end or with a number, not both: a flow by number ends with its last
        // vehicle
        if f.number.is_none() {
            attrs.push(("end", num(end, 4)));
        }
        match f.probability {
            Some(p) => attrs.push(("probability", num(p, 6))),
            None => attrs.push(("vehsPerHour", num(f.vehs_per_hour, 4))),
        }
        if let Some(n) = f.number {
            attrs.push(("number", n.to_string()));
        }
        attrs.push(("departLane", depart_lane(graph, f)));
        attrs.push(("departSpeed", depart_speed(f.depart_speed)));
        match f.depart_pos {
            mapc_sim::spec::DepartPos::Base => {}
            mapc_sim::spec::DepartPos::Random => attrs.push(("departPos", "random".into())),
            mapc_sim::spec::DepartPos::RandomFree => {
                attrs.push(("departPos", "random_free".into()))
            }
            mapc_sim::spec::DepartPos::Free => attrs.push(("departPos", "free".into())),
        }
        start(&mut out, 4, "flow", &attrs);
        element(
            &mut out,
            8,
            "route",
            &[("edges", edge_list(graph, names, &roads))],
        );
        out.push_str("    </flow>\n");
    }
    out.push_str("</routes>\n");
    Ok(out)
}

/// SUMO's `departLane` of a flow: mapc's `depart_lane` on an entry road of several lanes; on a one-lane road
/// `free`, which there is lane 0 as any other choice is.
fn depart_lane(graph: &LaneGraph, f: &FlowSpec) -> String {
    let lanes = graph
        .roads
        .binary_search_by_key(&f.from, |r| r.id)
        .map_or(1, |i| graph.roads[i].lanes.len());
    if lanes <= 1 {
        return "free".into();
    }
    f.depart_lane.sumo_value()
}

/// The `.sumocfg`: the files, the step, and the options of the paper's runs (docs/reference.md): the scenario's
/// time to teleport (`-1` unless the scenario sets one: none, as in the paper's runs),
/// collisions checked inside junctions but not acted on, no min gap in the collision check; with `multi_lane`,
/// lane changes done in one step (`lanechange.duration` 0, SUMO 1.8's default, written out as mapc's LC2013
/// assumes it) by each vehicle type's default model, LC2013.
/// The scenario's induction loops as a SUMO additional file (`None` when it has none): each loop on its lane of
/// the exported network, at its position and with its interval, its types if it sees only some. All write their
/// intervals to `output_file`, which the export names (a name from a map never becomes a path).
pub fn detectors_xml(spec: &SimSpec, names: &SumoNames, output_file: &str) -> Option<String> {
    if spec.detectors.is_empty() {
        return None;
    }
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n");
    out.push_str(
        "<!-- written by `mapc export` for SUMO 1.8: the scenario's induction loops -->\n",
    );
    start(&mut out, 0, "additional", &[]);
    for d in &spec.detectors {
        let i = spec
            .graph
            .roads
            .binary_search_by_key(&d.road, |r| r.id)
            .expect("a detector's road is the graph's");
        let edge = &names.edges[i];
        let mut attrs = vec![
            ("id", d.id.clone()),
            ("lane", format!("{edge}_{}", d.lane)),
            ("pos", num(d.pos_m, 2)),
            ("freq", num(d.period_s, 2)),
            ("file", output_file.to_string()),
        ];
        if !d.vehicle_types.is_empty() {
            let types: Vec<&str> = d
                .vehicle_types
                .iter()
                .map(|&t| spec.vehicle_types[t].name.as_str())
                .collect();
            attrs.push(("vTypes", types.join(" ")));
        }
        element(&mut out, 4, "inductionLoop", &attrs);
    }
    out.push_str("</additional>\n");
    Some(out)
}

pub fn sumocfg(
    net_file: &str,
    routes_file: &str,
    additional_file: Option<&str>,
    step_s: f64,
    end_s: f64,
    multi_lane: bool,
    time_to_teleport_s: f64,
) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n");
    out.push_str("<!-- written by `mapc export` for SUMO 1.8; tools/sumo_check drives it with speed mode 9 -->\n");
    start(&mut out, 0, "configuration", &[]);
    let section = |out: &mut String, name: &str, items: &[(&str, String)]| {
        start(out, 4, name, &[]);
        for (k, v) in items {
            element(out, 8, k, &[("value", v.clone())]);
        }
        out.push_str(&format!("    </{name}>\n"));
    };
    let mut input = vec![
        ("net-file", net_file.to_string()),
        ("route-files", routes_file.to_string()),
    ];
    if let Some(additional) = additional_file {
        input.push(("additional-files", additional.to_string()));
    }
    section(&mut out, "input", &input);
    section(
        &mut out,
        "time",
        &[
            ("begin", "0".into()),
            ("end", num(end_s, 2)),
            ("step-length", num(step_s, 4)),
        ],
    );
    let mut processing = vec![
        (
            "time-to-teleport",
            if time_to_teleport_s > 0.0 {
                num(time_to_teleport_s, 2)
            } else {
                "-1".to_string()
            },
        ),
        ("collision.check-junctions", "true".into()),
        ("collision.action", "none".into()),
        ("collision.mingap-factor", "0".into()),
    ];
    if multi_lane {
        processing.push(("lanechange.duration", "0".into()));
    }
    section(&mut out, "processing", &processing);
    // The PyPI builds of SUMO ship without their XML schemas: validating would only warn that they are missing.
    section(
        &mut out,
        "report",
        &[
            ("no-step-log", "true".into()),
            ("xml-validation", "never".into()),
            ("xml-validation.net", "never".into()),
        ],
    );
    out.push_str("</configuration>\n");
    out
}

/// The id of flow `flow`'s type mix.
fn mix_id(flow: &str) -> String {
    format!("{flow}_types")
}

/// A vType's attributes in SUMO 1.8's terms: the type's car-following model (IDM, or Krauss with its `sigma`),
/// its parameters, its LC2013 parameters where given, and `probability` inside a distribution.
fn vtype_attrs(
    t: &mapc_sim::VehicleTypeSpec,
    id: &str,
    probability: Option<f64>,
) -> Result<Vec<(&'static str, String)>, SimError> {
    let krauss = t.car_follow_model == mapc_sim::spec::CarFollowModelKind::Krauss;
    // SUMO 1.8 reads IDM's `stepping` as a whole number and computes its sub-steps from its own default of
    // 0.25 s, which is what mapc's default mirrors; any other value has no SUMO 1.8 equivalent.
    if !krauss && t.idm_stepping_s != SUMO_IDM_STEPPING_S {
        return Err(SimError::Spec(format!(
            "vehicle type `{}`: idm_stepping_s = {} s, but SUMO 1.8's IDM only steps at {SUMO_IDM_STEPPING_S} s",
            t.name, t.idm_stepping_s
        )));
    }
    let mut a = vec![("id", id.to_string())];
    if let Some(p) = probability {
        a.push(("probability", num(p, 6)));
    }
    a.push((
        "carFollowModel",
        if krauss { "Krauss" } else { "IDM" }.into(),
    ));
    a.extend([
        ("accel", num(t.accel, 4)),
        ("decel", num(t.decel, 4)),
        ("emergencyDecel", num(t.emergency_decel, 4)),
        ("tau", num(t.tau, 4)),
        ("minGap", num(t.min_gap, 4)),
        ("maxSpeed", num(t.max_speed, 4)),
        ("length", num(t.length, 4)),
    ]);
    if krauss {
        a.push(("sigma", num(t.sigma, 4)));
    } else {
        a.push(("delta", num(t.delta, 4)));
    }
    a.extend([
        ("speedFactor", num(t.speed_factor, 4)),
        ("speedDev", num(t.speed_dev, 4)),
        ("impatience", num(t.impatience, 4)),
    ]);
    a.extend(t.lane_change.given().map(|(_, attr, v)| (attr, num(v, 4))));
    a.push(("color", if t.controlled { "red" } else { "yellow" }.into()));
    Ok(a)
}

/// SUMO's `departSpeed` of a flow: a number, or `max` / `desired`.
fn depart_speed(speed: f64) -> String {
    if speed == mapc_sim::spec::DEPART_SPEED_MAX {
        "max".into()
    } else if speed == mapc_sim::spec::DEPART_SPEED_DESIRED {
        "desired".into()
    } else {
        num(speed, 4)
    }
}
