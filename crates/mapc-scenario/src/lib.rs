//! # mapc-scenario: what to simulate, and how a real map becomes it
//!
//! Glossary:
//! - **scenario**: a network plus vehicle types, flows (demand), initial vehicles, step, horizon and the controlled
//!   region; written as TOML (`scenarios/*.toml`).
//! - **flow**: periodic departures from an entry road at `vehs_per_hour` (SUMO's semantics), of one vehicle type.
//! - **vehicle type**: IDM driver parameters; `controlled = true` marks an AV a policy may drive.
//! - **controlled region**: the roads where AVs are driven by a policy (a transfer window), and `n_av`, how many.
//! - **AV share** (`av_share`): a fraction of each flow's vehicles made AVs, as a flow of their own beside the
//!   humans'.
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
//!   a week.
//! - **allowed range**: every number of a scenario (times, counts, speeds, lengths, driver parameters) lies in
//!   one (`ranges.rs`), checked on loading; outside it, the key, the value and the range are named.
//! - **fill time**: the free-flow travel time of the longest route (`timing.rs`); a horizon that leaves too little
//!   after it is warned about, and `mapc window` picks a warm-up for it.

pub mod approach;
pub mod av_share;
pub mod bounds;
pub mod compile;
pub mod compile_error;
pub mod compile_files;
mod depart_lane;
pub mod distribution;
pub mod generator;
pub mod model;
pub mod ranges;
mod resolved;
pub mod simplify;
pub mod sumo;
pub mod timing;
pub mod transform;
pub mod window;

pub use depart_lane::DepartLane;
pub use model::*;
pub use resolved::{ResolvedScenario, ResolvedWindow};

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
        "no scenario file `{0}` and no built-in scenario of that name (built-in: simple_merge, two_lane_merge, lane_drop, flow_bottleneck)"
    )]
    Unknown(String),
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
            sumo_clock: false,
            clock_begin_s: 0.0,
            sumo_junction_lane_changes: false,
            light_programs: Vec::new(),
            detectors: Vec::new(),
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

    /// Flow's bottleneck benchmark at scaling 1 on its generated network: `scenarios/flow_bottleneck.toml`, whose
    /// network is netconvert's build of the same parameters (a test checks that both run the same). Flow's humans
    /// (its IDM defaults) enter on a random lane at 10 m/s, 2300 veh/h; the outflow is counted over the last 500 s
    /// of a 750 s run; AVs given by `--av-share` are controlled anywhere on the network.
    pub fn flow_bottleneck() -> Scenario {
        let base = Scenario::simple_merge();
        Scenario {
            name: generator::FLOW_BOTTLENECK.to_string(),
            description: "Flow's bottleneck benchmark (4 -> 2 -> 1 lanes at two zippers), humans at 2300 veh/h."
                .to_string(),
            warmup_steps: 500,
            horizon_steps: 1000,
            network: NetworkSpec::FlowBottleneck(FlowBottleneckParams::default()),
            vehicle_types: base
                .vehicle_types
                .into_iter()
                .filter(|(name, _)| name == "human")
                .collect(),
            flows: vec![Flow {
                id: "inflow".to_string(),
                from: "1".to_string(),
                to: Some("5".to_string()),
                vehs_per_hour: 2300.0,
                vehicle_type: "human".to_string(),
                depart_speed_mps: 10.0,
                depart_lane: Some("random".to_string()),
                ..Flow::default()
            }],
            initial_vehicles: None,
            control: Some(Control {
                n_av: 5,
                region: vec![],
                window: None,
                windows: vec![],
            }),
            ..base
        }
    }

    pub fn builtin(name: &str) -> Option<Scenario> {
        match name {
            generator::SIMPLE_MERGE => Some(Scenario::simple_merge()),
            generator::TWO_LANE_MERGE => Some(Scenario::two_lane_merge()),
            generator::LANE_DROP => Some(Scenario::lane_drop()),
            generator::FLOW_BOTTLENECK => Some(Scenario::flow_bottleneck()),
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
