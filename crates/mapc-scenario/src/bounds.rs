//! What a scenario may ask of the simulator: demand that its entry roads can take, a horizon and a warm-up of sane
//! length, and a bounded amount of work (steps, and steps times the vehicles on the network). They bound a run's
//! work and memory, so an absurd number (a typo such as `vehs_per_hour = 1e9` or `step_s = 0.001` over two days)
//! is refused with the flow or key named instead of running for hours or until the machine runs out of memory.

use std::collections::BTreeMap;

/// The longest simulated time a scenario may ask for (warm-up plus horizon): a week. The work of a run is bounded
/// by [`MAX_STEPS`] and [`MAX_VEHICLE_STEPS`]; this bound keeps times sane numbers and lets SUMO users' long
/// horizons run as they are (sumo-rl's `3x3grid` ends at 260 000 s, 72 h).
pub const MAX_SIMULATED_S: f64 = 7.0 * 24.0 * 3600.0;
/// The longest warm-up: six hours of simulated time (a 500 km corridor at 30 m/s fills in under five; the
/// shipped scenarios warm up for at most 500 s).
pub const MAX_WARMUP_S: f64 = 6.0 * 3600.0;
/// The most steps (warm-up plus horizon) of one run, whatever its step: two days at 0.1 s (each step costs
/// time even on an empty network; the shipped scenarios take 3000 at most).
pub const MAX_STEPS: u64 = 1_728_000;
/// The most vehicle-steps (steps times the vehicles expected on the network, [`expected_vehicles`]) of one run:
/// a thousand times the largest shipped scenario's (the whole I-696 corridor, about a million), some three minutes
/// of one core (docs/perf.md: 5.7 million vehicle-steps a second).
pub const MAX_VEHICLE_STEPS: f64 = 1e9;

/// The most vehicles per hour one entry lane can take: the simulator inserts at most one vehicle per entry lane
/// and step (SUMO's insertion), so demand above this can only pile up.
/// Where demand above an entry's capacity queues (a SUMO user's scenario), a flow may still ask for at most this
/// many vehicles a step: each departure is counted one by one, and no road takes more.
pub const MOST_QUEUED_VEHICLES_A_STEP: f64 = 64.0;

pub fn entry_capacity_vph(step_s: f64) -> f64 {
    3600.0 / step_s
}

/// The key of a flow's entry in [`check_demand`]: the road, or the road and lane for a flow that departs on one
/// lane given by its index (each entry lane takes its own vehicle per step), or the road's lanes together for a
/// flow whose lane is chosen at insertion (`random`, `free`).
pub fn entry_key(road: &str, depart_lane: Option<&str>) -> String {
    if departs_on_any_lane(depart_lane) {
        return format!("{road} (any lane)");
    }
    match depart_lane.and_then(|l| l.parse::<u8>().ok()) {
        Some(lane) => format!("{road} lane {lane}"),
        None => road.to_string(),
    }
}

/// Whether a flow's `depart_lane` lets each vehicle enter on any lane of its road (`random`, `free`).
pub fn departs_on_any_lane(depart_lane: Option<&str>) -> bool {
    matches!(depart_lane, Some("random" | "free"))
}

/// How many lanes of its entry road a flow may depart on: all of them for `random` and `free`, else one.
pub fn entry_lanes(depart_lane: Option<&str>, road_lanes: usize) -> u32 {
    if departs_on_any_lane(depart_lane) {
        road_lanes.max(1) as u32
    } else {
        1
    }
}

/// One flow as the demand check sees it.
pub struct FlowDemand<'a> {
    pub id: &'a str,
    /// What identifies the entry (flows with the same key share its insertions per step): [`entry_key`].
    pub entry: String,
    /// How many lanes the entry has, each taking one vehicle per step ([`entry_lanes`]).
    pub lanes: u32,
    /// The entry road, whatever lane the flow departs on: all its flows together share its lanes.
    pub road: String,
    /// How many lanes the entry road has.
    pub road_lanes: u32,
    pub vehs_per_hour: f64,
}

/// A refused demand: the key to name and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    pub key: String,
    pub message: String,
}

/// Flows entering at the same entry (road, lane or the road's lanes together) must together stay within one
/// insertion per lane and step, and so must all the flows of one road whatever lanes they depart on (a `first`
/// flow and a `free` one on a two-lane road share its two lanes).
pub fn check_demand(flows: &[FlowDemand], step_s: f64) -> Result<(), Refusal> {
    let mut per_entry: BTreeMap<&str, (f64, Vec<&str>, u32)> = BTreeMap::new();
    let mut per_road: BTreeMap<&str, (f64, Vec<&str>, u32)> = BTreeMap::new();
    for f in flows {
        let e = per_entry.entry(&f.entry).or_default();
        e.0 += f.vehs_per_hour;
        e.1.push(f.id);
        e.2 = e.2.max(f.lanes);
        let r = per_road.entry(&f.road).or_default();
        r.0 += f.vehs_per_hour;
        r.1.push(f.id);
        r.2 = r.2.max(f.road_lanes);
    }
    for groups in [per_entry, per_road] {
        for (entry, (total, ids, lanes)) in groups {
            within_capacity(entry, total, &ids, lanes, step_s)?;
        }
    }
    Ok(())
}

/// Refuses `total` veh/h of the flows `ids` at `entry` beyond one vehicle per lane of its `lanes` and step.
fn within_capacity(
    entry: &str,
    total: f64,
    ids: &[&str],
    lanes: u32,
    step_s: f64,
) -> Result<(), Refusal> {
    let capacity = entry_capacity_vph(step_s) * lanes.max(1) as f64;
    // a relative tolerance: 7200 veh/h split over several flows may sum a hair above 7200
    if total <= capacity * (1.0 + 1e-9) {
        return Ok(());
    }
    let names = ids
        .iter()
        .map(|id| format!("`{id}`"))
        .collect::<Vec<_>>()
        .join(", ");
    let what = if ids.len() == 1 {
        format!("flow {names} asks for {total} veh/h")
    } else {
        format!("flows {names} ask for {total} veh/h in all")
    };
    Err(Refusal {
        key: "flows".into(),
        message: format!(
            "{what} at entry road {entry}, which takes at most {} per {step_s} s step \
             ({capacity} veh/h); the rest could only wait to enter",
            if lanes > 1 {
                format!("one vehicle per lane on its {lanes} lanes")
            } else {
                "one vehicle".to_string()
            }
        ),
    })
}

/// The warm-up must stay within [`MAX_WARMUP_S`], warm-up plus horizon within [`MAX_SIMULATED_S`] and
/// [`MAX_STEPS`].
pub fn check_horizon(warmup_steps: u64, horizon_steps: u64, step_s: f64) -> Result<(), Refusal> {
    let warmup_s = warmup_steps as f64 * step_s;
    if warmup_s > MAX_WARMUP_S {
        return Err(Refusal {
            key: "warmup_steps".into(),
            message: format!(
                "{warmup_steps} steps of {step_s} s ({:.1} h) exceed the limit of {:.0} h of warm-up",
                warmup_s / 3600.0,
                MAX_WARMUP_S / 3600.0
            ),
        });
    }
    let steps = warmup_steps.saturating_add(horizon_steps);
    let total_s = steps as f64 * step_s;
    if total_s > MAX_SIMULATED_S {
        return Err(Refusal {
            key: "horizon_steps".into(),
            message: format!(
                "warm-up and horizon ({warmup_steps} + {horizon_steps} steps of {step_s} s = {:.1} h) exceed the \
                 limit of {:.0} h of simulated time",
                total_s / 3600.0,
                MAX_SIMULATED_S / 3600.0
            ),
        });
    }
    if steps > MAX_STEPS {
        return Err(Refusal {
            key: "horizon_steps".into(),
            message: format!(
                "warm-up and horizon ({warmup_steps} + {horizon_steps} steps of step_s = {step_s} s) exceed the \
                 limit of {MAX_STEPS} steps of one run; raise step_s or shorten the run"
            ),
        });
    }
    Ok(())
}

/// The vehicles a scenario keeps on its network at free flow: its initial vehicles plus its flows (veh/h in all)
/// over the free-flow travel time of its longest route (`fill_s`), by Little's law. Congestion keeps more, but
/// only up to the network's capacity; this is the estimate [`check_work`] bounds.
pub fn expected_vehicles(initial: u32, total_vehs_per_hour: f64, fill_s: f64) -> f64 {
    initial as f64 + total_vehs_per_hour / 3600.0 * fill_s
}

/// [`check_work`] of scenario `sc`, whose longest route takes `fill_s` at free flow.
pub fn check_scenario_work(sc: &crate::Scenario, fill_s: f64) -> Result<(), Refusal> {
    let (steps, vehicles) = scenario_work(sc, fill_s);
    check_work(steps, vehicles)
}

/// A run's steps (warm-up and horizon) and its [`expected_vehicles`]; their product estimates its vehicle-steps.
pub fn scenario_work(sc: &crate::Scenario, fill_s: f64) -> (u64, f64) {
    let initial = sc.initial_vehicles.as_ref().map_or(0, |iv| iv.count);
    let vehs_per_hour = sc.flows.iter().map(|f| f.vehs_per_hour).sum();
    let steps = sc.warmup_steps as u64 + sc.horizon_steps as u64;
    (steps, expected_vehicles(initial, vehs_per_hour, fill_s))
}

/// The run's steps times its [`expected_vehicles`] must stay within [`MAX_VEHICLE_STEPS`].
pub fn check_work(steps: u64, expected_vehicles: f64) -> Result<(), Refusal> {
    let work = steps as f64 * expected_vehicles;
    if work <= MAX_VEHICLE_STEPS {
        return Ok(());
    }
    Err(Refusal {
        key: "horizon_steps".into(),
        message: format!(
            "warm-up and horizon ({steps} steps) times the {expected_vehicles:.0} vehicles its flows and initial \
             vehicles keep on the network at free flow make {work:.2e} vehicle-steps, beyond the limit of \
             {MAX_VEHICLE_STEPS:.0e} of one run; raise step_s, shorten warmup_steps or horizon_steps, or lower the \
             flows"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flow departing on one lane of a road as wide as the entry's lanes need.
    fn flow<'a>(id: &'a str, entry: &str, vph: f64) -> FlowDemand<'a> {
        FlowDemand {
            id,
            entry: entry.into(),
            lanes: 1,
            road: entry.into(),
            road_lanes: 8,
            vehs_per_hour: vph,
        }
    }

    #[test]
    fn demand_within_one_insertion_per_step_passes() {
        let flows = [flow("a", "R1", 3600.0), flow("b", "R1", 3600.0)];
        assert!(check_demand(&flows, 0.5).is_ok());
        let flows = [flow("a", "R1", 7200.0), flow("b", "R2", 7200.0)];
        assert!(check_demand(&flows, 0.5).is_ok());
    }

    #[test]
    fn demand_above_it_names_the_flows_and_the_limit() {
        let err = check_demand(&[flow("main", "R1", 1e9)], 0.5).unwrap_err();
        assert!(
            err.message.contains("`main`") && err.message.contains("7200 veh/h"),
            "{err:?}"
        );
        let err =
            check_demand(&[flow("a", "R1", 4000.0), flow("b", "R1", 4000.0)], 0.5).unwrap_err();
        assert!(
            err.message.contains("`a`, `b`") && err.message.contains("8000"),
            "{err:?}"
        );
    }

    #[test]
    fn a_flow_departing_on_any_lane_gets_every_lane_of_its_road() {
        let key = entry_key("R1", Some("free"));
        assert_eq!(key, entry_key("R1", Some("random")));
        assert_ne!(key, entry_key("R1", None));
        let flow = |vph| FlowDemand {
            id: "main",
            entry: key.clone(),
            lanes: entry_lanes(Some("free"), 3),
            road: "R1".into(),
            road_lanes: 3,
            vehs_per_hour: vph,
        };
        assert!(check_demand(&[flow(3.0 * 7200.0)], 0.5).is_ok());
        let err = check_demand(&[flow(3.0 * 7200.0 + 1.0)], 0.5).unwrap_err();
        assert!(
            err.message.contains("one vehicle per lane on its 3 lanes")
                && err.message.contains("21600 veh/h"),
            "{err:?}"
        );
        assert_eq!(entry_lanes(Some("first"), 3), 1);
        assert_eq!(entry_lanes(Some("2"), 3), 1);
    }

    #[test]
    fn flows_on_different_lanes_of_one_road_each_get_a_lane() {
        let lanes: Vec<String> = (0..5)
            .map(|l| entry_key("R1", Some(&l.to_string())))
            .collect();
        let flows: Vec<FlowDemand> = lanes
            .iter()
            .map(|key| FlowDemand {
                id: "main",
                entry: key.clone(),
                lanes: 1,
                road: "R1".into(),
                road_lanes: 5,
                vehs_per_hour: 2000.0,
            })
            .collect();
        assert!(check_demand(&flows, 0.5).is_ok());
        // the same demand without lanes is one lane's worth too much
        let road = entry_key("R1", Some("best"));
        assert_eq!(road, "R1");
        let one: Vec<FlowDemand> = (0..5).map(|_| flow("main", &road, 2000.0)).collect();
        assert!(check_demand(&one, 0.5).is_err());
    }

    #[test]
    fn flows_departing_differently_on_one_road_share_its_lanes() {
        let on_two_lanes = |id, depart_lane: Option<&str>, vph| FlowDemand {
            id,
            entry: entry_key("R1", depart_lane),
            lanes: entry_lanes(depart_lane, 2),
            road: "R1".into(),
            road_lanes: 2,
            vehs_per_hour: vph,
        };
        let fits = [
            on_two_lanes("first", Some("first"), 7200.0),
            on_two_lanes("free", Some("free"), 7200.0),
        ];
        assert!(check_demand(&fits, 0.5).is_ok());
        // each entry within its own lanes, the road's two lanes asked for three lanes' worth
        let over = [
            on_two_lanes("first", Some("first"), 7200.0),
            on_two_lanes("free", Some("free"), 14400.0),
        ];
        let err = check_demand(&over, 0.5).unwrap_err();
        assert_eq!(
            err.message,
            "flows `first`, `free` ask for 21600 veh/h in all at entry road R1, which takes at most one vehicle \
             per lane on its 2 lanes per 0.5 s step (14400 veh/h); the rest could only wait to enter"
        );
        let over = [
            on_two_lanes("lane0", Some("0"), 7200.0),
            on_two_lanes("lane1", Some("1"), 7200.0),
            on_two_lanes("random", Some("random"), 1.0),
        ];
        assert!(check_demand(&over, 0.5).is_err());
    }

    /// The lane drop's three-lane entry with a `free` flow taking all its lanes and a `first` flow beside it.
    #[test]
    fn a_scenario_mixing_depart_lanes_beyond_its_road_is_refused_with_file_flows_and_road() {
        let mut scenario = crate::Scenario::lane_drop();
        scenario.flows.truncate(2);
        scenario.flows[0].depart_lane = Some("free".into());
        scenario.flows[0].vehs_per_hour = 21600.0;
        scenario.flows[1].depart_lane = Some("first".into());
        let resolve = |s: &crate::Scenario| {
            crate::ResolvedScenario::resolve(s.clone(), std::path::Path::new("."), "mixed.toml")
        };
        let err = resolve(&scenario).expect_err("refused").to_string();
        assert!(
            err.starts_with(
                "mixed.toml: flows: flows `lane0`, `lane1` ask for 23100 veh/h in all at entry road"
            ) && err.contains("on its 3 lanes per 0.5 s step (21600 veh/h)"),
            "{err}"
        );
        scenario.flows[0].vehs_per_hour = 21600.0 - 1500.0;
        assert!(resolve(&scenario).is_ok());
    }

    #[test]
    fn horizon_beyond_a_week_is_refused_with_the_limit() {
        assert!(check_horizon(0, 2000, 0.5).is_ok());
        // sumo-rl's 3x3grid: 72 h at 1 s
        assert!(check_horizon(0, 260_000, 1.0).is_ok());
        assert!(check_horizon(0, 604_800, 1.0).is_ok());
        let err = check_horizon(10, 604_800, 1.0).unwrap_err();
        assert!(err.message.contains("168 h"), "{err:?}");
    }

    #[test]
    fn a_warmup_beyond_six_hours_is_refused_with_its_key() {
        assert!(check_horizon(43_200, 2000, 0.5).is_ok());
        let err = check_horizon(230_200, 2000, 0.5).unwrap_err();
        assert_eq!(err.key, "warmup_steps");
        assert_eq!(
            err.message,
            "230200 steps of 0.5 s (32.0 h) exceed the limit of 6 h of warm-up"
        );
    }

    #[test]
    fn steps_beyond_the_limit_are_refused_whatever_the_step() {
        assert!(check_horizon(0, 1_000_000, 0.1).is_ok());
        // two days at 1 ms: within the simulated time, 1.7e8 steps
        let err = check_horizon(0, 172_800_000, 0.001).unwrap_err();
        assert_eq!(err.key, "horizon_steps");
        assert!(
            err.message.contains("step_s = 0.001 s") && err.message.contains("1728000 steps"),
            "{err:?}"
        );
    }

    #[test]
    fn work_beyond_the_limit_names_the_vehicle_steps() {
        // the Simple Merge: 2000 veh/h over a 23 s fill, 2000 steps
        let vehicles = expected_vehicles(0, 2000.0, 700.0 / 30.0);
        assert!((vehicles - 12.96).abs() < 0.01, "{vehicles}");
        assert!(check_work(2000, vehicles).is_ok());
        let err = check_work(MAX_STEPS, 2000.0).unwrap_err();
        assert!(
            err.message.contains("2000 vehicles")
                && err.message.contains("3.46e9 vehicle-steps")
                && err.message.contains("limit of 1e9"),
            "{err:?}"
        );
    }
}

#[cfg(test)]
mod shipped_tests {
    use super::*;
    use crate::ResolvedScenario;

    /// Every shipped scenario is well within the bounds on time, steps and work (a tenth of the work's).
    #[test]
    fn every_shipped_scenario_is_well_within_the_bounds() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let mut names: Vec<String> = ["simple_merge", "two_lane_merge", "lane_drop"]
            .map(String::from)
            .to_vec();
        for sub in [dir.clone(), dir.join("merges"), dir.join("fitted")] {
            for e in std::fs::read_dir(sub).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "toml")
                    && mapc_graph::filekind::sniff_path(&p) == Some(mapc_graph::MapcFile::Scenario)
                {
                    names.push(p.display().to_string());
                }
            }
        }
        assert!(names.len() > 20, "{names:?}");
        for name in names {
            let rs = ResolvedScenario::load(&name).unwrap_or_else(|e| panic!("{e}"));
            let sc = &rs.scenario;
            let fill_s = crate::timing::HorizonFit::of_resolved(&rs).fill_s;
            let steps = sc.warmup_steps as u64 + sc.horizon_steps as u64;
            let initial = sc.initial_vehicles.as_ref().map_or(0, |iv| iv.count);
            let vph = sc.flows.iter().map(|f| f.vehs_per_hour).sum();
            let work = steps as f64 * expected_vehicles(initial, vph, fill_s);
            eprintln!("{name}: {steps} steps, {work:.3e} vehicle-steps");
            assert!(work < MAX_VEHICLE_STEPS / 10.0, "{name}: {work}");
            assert!(steps < MAX_STEPS / 10, "{name}: {steps}");
        }
    }
}
