//! The scenario: network, vehicle types, demand, horizon and the controlled region, as written in TOML.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// SUMO's default time to teleport (s).
pub const SUMO_TIME_TO_TELEPORT_S: f64 = 300.0;

/// Bumped on any change that an older reader would misread.
pub const SCENARIO_VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    #[serde(default = "current_version")]
    pub version: u32,
    pub name: String,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// Simulation step in seconds.
    #[serde(default = "default_step_s")]
    pub step_s: f64,
    /// Episode length in steps.
    pub horizon_steps: u32,
    /// Steps simulated before metrics and control start.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub warmup_steps: u32,
    /// A human driver standing still this long at the front of its lane is teleported further along its route
    /// and counted (SUMO's `--time-to-teleport`; SUMO's default is [`SUMO_TIME_TO_TELEPORT_S`]). Absent or 0:
    /// never, as in the paper's runs; a run then reports the vehicles that stood longer than SUMO's bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_to_teleport_s: Option<f64>,
    pub network: NetworkSpec,
    pub vehicle_types: BTreeMap<String, VehicleType>,
    /// Named mixes of vehicle types (SUMO's `vTypeDistribution`): a flow whose `vehicle_type` names a mix draws
    /// each vehicle's type with these weights.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub vehicle_type_mixes: BTreeMap<String, BTreeMap<String, f64>>,
    pub flows: Vec<Flow>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_vehicles: Option<InitialVehicles>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<Control>,
    /// Where flows are measured besides the paper's whole-horizon outflow (optional: files without it read as
    /// before, with the default points).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measure: Option<Measure>,
    /// Demand above what an entry takes queues there, as SUMO runs it, instead of being refused (a SUMO user's
    /// scenario).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub queue_excess_demand: bool,
    /// The clock reads 0 at the first step, where SUMO's reads its `begin` ([`Scenario::clock_begin_s`]; a SUMO
    /// user's scenario); otherwise it starts two steps in, as Flow's rollouts did (the paper's scenarios).
    /// Departures are timed on it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sumo_clock: bool,
    /// SUMO's clock at the first step (a SUMO user's `begin`; the run's own clock still reads 0 there): the lights
    /// run their programs on it, and SUMO's outputs are stamped with it.
    #[serde(default, skip_serializing_if = "is_zero_m")]
    pub clock_begin_s: f64,
    /// SUMO 1.8's rules at junctions and in the lane-change pass (a SUMO user's scenario): among them a vehicle may
    /// change lanes while its back is still inside the junction behind, and on connections side by side
    /// (`SimSpec::sumo_junction_lane_changes` lists them all); otherwise the rules mapc's own scenarios were
    /// measured with (their figures in docs/).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sumo_junction_lane_changes: bool,
    /// Fixed-time programs that replace the network's of the same lights (SUMO runs the last program loaded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub light_programs: Vec<mapc_graph::TrafficLight>,
    /// Induction loops (SUMO's `inductionLoop`): each run reports their flow and occupancy.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub detectors: Vec<Detector>,
}

/// An induction loop (SUMO's E1 detector): a point on one lane that counts the vehicles passing it and the time
/// it is occupied, over intervals of `period_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Detector {
    pub id: String,
    /// The road, named as flows name them (a road id, a SUMO edge id, `osm:WAY`).
    pub road: String,
    /// Lane index on the road (0: rightmost).
    #[serde(default)]
    pub lane: u8,
    /// Distance from the lane's start (m); negative: from its end, as SUMO reads it.
    pub pos_m: f64,
    /// Length of its intervals (s; SUMO's `freq`).
    pub period_s: f64,
    /// Move a position off the lane onto its nearest end instead of refusing it (SUMO's `friendlyPos`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub friendly_pos: bool,
    /// The vehicle types it sees; empty: all.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vehicle_types: Vec<String>,
    /// Name of its SUMO output file (SUMO's `file`): `mapc sim --detector-output DIR` writes its intervals to
    /// that file name inside DIR (the name's folders are dropped).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
}

/// Measurement points. Every run reports, per hour of measured time (the horizon after the warm-up), the
/// vehicles past each merge listed here and past the corridor's end, besides the paper's outflow (vehicles that
/// left the network, over the whole horizon), which stays the headline figure.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Measure {
    /// Merge junctions (`J12`, `osm:NODE`, SUMO ids) whose flow is measured: the vehicles entering the road after
    /// the merge. Default: the merges of the controlled region (of the whole network without one).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub merges: Vec<String>,
}

fn current_version() -> u32 {
    SCENARIO_VERSION
}
fn default_step_s() -> f64 {
    0.5
}
fn is_zero(x: &u32) -> bool {
    *x == 0
}

/// Where the road network comes from. Relative paths are relative to the scenario file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum NetworkSpec {
    /// mapc's Simple Merge generator (`[network.simple_merge]`).
    SimpleMerge(SimpleMergeParams),
    /// mapc's lane-drop bottleneck generator (`[network.lane_drop]`).
    LaneDrop(LaneDropParams),
    /// Flow's bottleneck benchmark network (`[network.flow_bottleneck]`).
    FlowBottleneck(FlowBottleneckParams),
    /// A saved lane graph (`network.graph = "x.graph.json"`).
    Graph(PathBuf),
    /// A map imported on the fly (`network.map = "maps/x.net.xml"`).
    Map(PathBuf),
}

/// The paper's Simple Merge: a main road and a ramp joining it at `angle_deg`, one lane each. The defaults are the
/// original code's (MergeNetwork with INFLOW_EDGE_LEN = 100).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimpleMergeParams {
    /// Length of the entry road on the main road and on the ramp.
    pub inflow_edge_m: f64,
    /// Main road between its entry road and the merge.
    pub pre_merge_m: f64,
    /// Ramp between its entry road and the merge.
    pub merge_m: f64,
    /// Main road after the merge.
    pub post_merge_m: f64,
    pub angle_deg: f64,
    pub speed_limit_mps: f64,
    pub lanes: u8,
    /// Length driven inside the junction from the main road, as SUMO's netconvert builds it (radius 10 m).
    pub main_internal_m: f64,
    /// Length driven inside the junction from the ramp (its curve).
    pub ramp_internal_m: f64,
    /// netconvert's curve speed limit on the ramp's way through the junction.
    pub ramp_internal_speed_mps: f64,
    /// Length of netconvert's internal lane at the two junctions where an entry road meets the next road.
    pub through_internal_m: f64,
    /// Which road has the right of way at the merge.
    pub major: MajorRoad,
    /// When positive, the ramp (one lane) joins an acceleration lane: an extra rightmost lane of this length on
    /// the road after the merge, which then ends (a lane drop) before `post_merge_m` more of the main road's
    /// lanes. 0 (the default): the ramp joins the main road's lanes at the merge.
    #[serde(skip_serializing_if = "is_zero_m")]
    pub acceleration_lane_m: f64,
}

fn is_zero_m(x: &f64) -> bool {
    *x == 0.0
}

/// A lane-drop bottleneck in the spirit of Flow's bottleneck benchmark: a straight road of `lanes_before` lanes
/// whose rightmost lanes end after `upstream_m` (SUMO's lane drop: they have no connection onward), then
/// `downstream_m` of `lanes_after` lanes. Drivers in an ending lane must change lanes before its end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaneDropParams {
    /// The road before the drop (its rightmost lanes end at its end).
    pub upstream_m: f64,
    /// The road after the drop.
    pub downstream_m: f64,
    pub lanes_before: u8,
    pub lanes_after: u8,
    pub speed_limit_mps: f64,
    /// Length of the internal lane at the drop (netconvert's for a straight joint).
    pub through_internal_m: f64,
}

impl Default for LaneDropParams {
    fn default() -> Self {
        LaneDropParams {
            upstream_m: 600.0,
            downstream_m: 300.0,
            lanes_before: 3,
            lanes_after: 2,
            speed_limit_mps: 30.0,
            through_internal_m: 0.10,
        }
    }
}

/// Flow's bottleneck (its `BottleneckNetwork`): five roads in a line with 4s, 4s, 4s, 2s and s lanes (s the
/// scaling); at the end of the third and of the fourth road each pair of lanes merges into one at a zipper. The
/// lengths are Flow's edge lengths. netconvert builds the zippers with a radius, which takes that much off each
/// road at a zipper, and joins the roads with internal lanes: their lengths default to netconvert 1.8's build
/// (maps/flow_bottleneck/README.md), so the defaults give the network of `maps/flow_bottleneck.net.xml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlowBottleneckParams {
    pub scaling: u8,
    /// The five roads' lengths before netconvert shortens them at the zippers.
    pub lengths_m: [f64; 5],
    pub speed_limit_mps: f64,
    /// What a zipper takes off each road it joins.
    pub junction_radius_m: f64,
    /// Internal lanes at the first and at the second zipper.
    pub zipper_internal_m: [f64; 2],
    /// Internal lanes at the two straight joints before the zippers.
    pub through_internal_m: f64,
}

impl Default for FlowBottleneckParams {
    fn default() -> Self {
        FlowBottleneckParams {
            scaling: 1,
            lengths_m: [100.0, 310.0, 140.0, 280.0, 155.0],
            speed_limit_mps: 23.0,
            junction_radius_m: 20.0,
            zipper_internal_m: [40.06, 40.03],
            through_internal_m: 0.10,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MajorRoad {
    Main,
    Ramp,
    /// Neither yields (as in SUMO nets whose two approaches have the same priority).
    Both,
}

impl Default for SimpleMergeParams {
    fn default() -> Self {
        SimpleMergeParams {
            inflow_edge_m: 100.0,
            pre_merge_m: 500.0,
            merge_m: 100.0,
            post_merge_m: 100.0,
            angle_deg: 45.0,
            speed_limit_mps: 30.0,
            lanes: 1,
            main_internal_m: 24.53,
            ramp_internal_m: 22.95,
            ramp_internal_speed_mps: 15.67,
            through_internal_m: 0.10,
            // The original code gives the merge edges priority 1 and the highway -1: the ramp is major.
            major: MajorRoad::Ramp,
            acceleration_lane_m: 0.0,
        }
    }
}

/// A driver and vehicle: SUMO's IDM as configured by the original code (Flow's SumoCarFollowingParams defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VehicleType {
    /// Maximum acceleration, m/s².
    pub accel: f64,
    /// Comfortable deceleration, m/s².
    pub decel: f64,
    /// Desired time headway, s.
    pub tau: f64,
    /// Standstill gap to the leader, m.
    pub min_gap: f64,
    pub max_speed: f64,
    /// IDM acceleration exponent.
    pub delta: f64,
    /// Mean of the driver's speed factor (desired speed = factor × speed limit).
    pub speed_factor: f64,
    /// Standard deviation of the speed factor.
    pub speed_dev: f64,
    /// 0: a minor-road driver never forces a gap; 1: after waiting long, takes any gap that is physically safe.
    pub impatience: f64,
    pub length: f64,
    /// IDM integration sub-step, s (SUMO's `stepping`).
    pub idm_stepping_s: f64,
    /// An automated vehicle that a policy may control.
    pub controlled: bool,
    /// The car-following model: `idm` (the paper's, default) or `krauss` (SUMO's default driver).
    #[serde(skip_serializing_if = "CarFollowModel::is_idm")]
    pub car_follow_model: CarFollowModel,
    /// Krauss' dawdling in [0, 1] (SUMO's `sigma`; 0.5 when not given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// The hardest braking when the safe speed demands it, m/s² (SUMO's `emergencyDecel`; 9, or `decel` when
    /// larger, when not given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub emergency_decel: Option<f64>,
    /// LC2013's parameters of this type (SUMO's `lc*` attributes); absent: SUMO 1.8's defaults.
    #[serde(default, skip_serializing_if = "LaneChangeParams::is_default")]
    pub lane_change: LaneChangeParams,
}

/// [`LaneChangeParams`]' names in a scenario and SUMO's attributes, in the order of its fields.
pub const LANE_CHANGE_NAMES: [(&str, &str); 7] = [
    ("strategic", "lcStrategic"),
    ("cooperative", "lcCooperative"),
    ("speed_gain", "lcSpeedGain"),
    ("keep_right", "lcKeepRight"),
    ("lookahead_left", "lcLookaheadLeft"),
    ("speed_gain_right", "lcSpeedGainRight"),
    ("assertive", "lcAssertive"),
];

/// LC2013's per-type parameters (SUMO's `lcStrategic`, `lcCooperative`, `lcSpeedGain`, `lcKeepRight`,
/// `lcLookaheadLeft`, `lcSpeedGainRight`, `lcAssertive`); a value left out is SUMO 1.8's default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaneChangeParams {
    /// Scales the strategic look-ahead; negative: no strategic changes (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strategic: Option<f64>,
    /// Willingness to change lanes for others (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cooperative: Option<f64>,
    /// Eagerness to change lanes for speed (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_gain: Option<f64>,
    /// Eagerness to keep right (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keep_right: Option<f64>,
    /// Strategic look-ahead to the left relative to the right (2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lookahead_left: Option<f64>,
    /// Speed-gain wish to the right relative to the left (0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_gain_right: Option<f64>,
    /// Accepts gaps this many times smaller than the secure ones (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub assertive: Option<f64>,
}

impl LaneChangeParams {
    pub fn is_default(&self) -> bool {
        *self == LaneChangeParams::default()
    }

    fn slots(&mut self) -> [&mut Option<f64>; 7] {
        [
            &mut self.strategic,
            &mut self.cooperative,
            &mut self.speed_gain,
            &mut self.keep_right,
            &mut self.lookahead_left,
            &mut self.speed_gain_right,
            &mut self.assertive,
        ]
    }

    /// Each parameter given: its scenario name, its SUMO attribute and its value.
    pub fn given(&self) -> impl Iterator<Item = (&'static str, &'static str, f64)> {
        let mut copy = *self;
        let values = copy.slots().map(|v| *v);
        LANE_CHANGE_NAMES
            .into_iter()
            .zip(values)
            .filter_map(|((name, attr), v)| Some((name, attr, v?)))
    }

    /// The parameters read by SUMO attribute with `read` (`None`: not given).
    pub fn from_sumo<E>(
        mut read: impl FnMut(&'static str) -> Result<Option<f64>, E>,
    ) -> Result<LaneChangeParams, E> {
        let mut p = LaneChangeParams::default();
        for (slot, (_, attr)) in p.slots().into_iter().zip(LANE_CHANGE_NAMES) {
            *slot = read(attr)?;
        }
        Ok(p)
    }
}

/// The car-following models a vehicle type may drive with (SUMO's `carFollowModel`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CarFollowModel {
    /// The Intelligent Driver Model as SUMO 1.8 computes it (the paper's drivers).
    #[default]
    Idm,
    /// SUMO 1.8's default driver: safe speed from the reaction time, random dawdling.
    Krauss,
}

impl CarFollowModel {
    pub fn is_idm(&self) -> bool {
        *self == CarFollowModel::Idm
    }
}

impl Default for VehicleType {
    fn default() -> Self {
        VehicleType {
            accel: 2.6,
            decel: 4.5,
            tau: 1.0,
            min_gap: 2.5,
            max_speed: 30.0,
            delta: 4.0,
            speed_factor: 1.0,
            speed_dev: 0.1,
            impatience: 0.5,
            length: 5.0,
            idm_stepping_s: 0.25,
            controlled: false,
            car_follow_model: CarFollowModel::Idm,
            sigma: None,
            emergency_decel: None,
            lane_change: LaneChangeParams::default(),
        }
    }
}

/// Periodic departures (SUMO's `vehsPerHour`): one vehicle every 3600 / vehs_per_hour seconds from `begin_s`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flow {
    pub id: String,
    /// Entry road: `R3`, `osm-way:N` or a SUMO edge id.
    pub from: String,
    /// Last road of the route; by default the vehicle drives downstream to the end of the corridor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<String>,
    pub vehs_per_hour: f64,
    pub vehicle_type: String,
    pub depart_speed_mps: f64,
    #[serde(default)]
    pub begin_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_s: Option<f64>,
    /// SUMO's `departLane` as [`crate::DepartLane::parse`] reads it: `first` (the rightmost lane, the default),
    /// `best`, `random`, `free` or a lane index (0 = rightmost).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depart_lane: Option<String>,
    /// Roads the route passes between `from` and `to`, in order (a SUMO route's inner edges, a trip's `via`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub via: Vec<String>,
    /// Departures by chance (SUMO's `probability`): in each second a vehicle with this probability, at most one a
    /// step; `vehs_per_hour` is then its mean, 3600 x probability.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probability: Option<f64>,
    /// At most this many vehicles (SUMO's `number`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub number: Option<u64>,
    /// Where on the entry lane a vehicle is inserted (SUMO's `departPos`): the lane's start (default, `base`),
    /// `random` (a new place along the lane at each try), `free` (the first free place: behind the last vehicle at
    /// the lane's start, else the first gap wide enough) or `random_free` (up to ten random places a step, then
    /// the start).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depart_pos: Option<String>,
    /// SUMO's `departSpeed` rules instead of `depart_speed_mps`: `max` (the desired speed, lowered as SUMO lowers
    /// it for the road ahead) or `desired` (the desired speed, or wait).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depart_speed: Option<String>,
    /// A SUMO `<vehicle>` or `<trip>`: its one vehicle is named by the flow's id in SUMO's outputs, where a
    /// flow's vehicles are `ID.N`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub vehicle: bool,
}

/// Vehicles on the network at t = 0, evenly spaced along the network's roads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialVehicles {
    pub count: u32,
    pub vehicle_type: String,
    #[serde(default)]
    pub speed_mps: f64,
}

/// Which AVs a policy drives.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Control {
    /// At most this many AVs are controlled at once, the earliest to enter first.
    pub n_av: u32,
    /// Roads where AVs are controlled; empty means the whole network. An AV that leaves the region is never
    /// controlled again.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub region: Vec<String>,
    /// How a window region was cut, for display.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<WindowInfo>,
    /// Several controlled regions (`[[control.windows]]`), each with its own FIFO of up to `n_av` AVs; an AV is
    /// controlled by the window it is in. Exclusive with `region` and `window` (a one-window scenario keeps
    /// those).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub windows: Vec<ControlWindow>,
}

/// One controlled region of a several-window scenario: a window around `junction` (and, for a joined region,
/// around the further merges in `joined`) with its roads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlWindow {
    /// The merge junction the window is cut around (for a joined region, its first merge).
    pub junction: String,
    /// Further merges inside a region that joins overlapping windows, in driving order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joined: Vec<String>,
    /// The scenario whose lengths the window matches.
    pub matched_to: String,
    /// Main road before `junction`, merging road(s), main road after the last merge (m).
    pub upstream_m: f64,
    pub merge_m: f64,
    pub downstream_m: f64,
    /// The window's roads.
    pub region: Vec<String>,
}

impl ControlWindow {
    /// The merges of the window, in driving order.
    pub fn merges(&self) -> impl Iterator<Item = &String> {
        std::iter::once(&self.junction).chain(&self.joined)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowInfo {
    /// The merge junction the window is centred on.
    pub junction: String,
    /// The scenario whose lengths the window matches (`simple_merge` or a file).
    pub matched_to: String,
    pub upstream_m: f64,
    pub merge_m: f64,
    pub downstream_m: f64,
}
