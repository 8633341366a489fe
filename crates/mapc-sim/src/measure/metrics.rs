//! Per-run metrics and their summary over seeds (mean and Student-t 95% confidence interval); the runs
//! themselves are `scenario::run_baseline_spec`'s.

use mapc_graph::RoadId;
use serde::{Deserialize, Serialize};

/// What one run measured (definitions as the paper computed them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunMetrics {
    /// 3600 x vehicles that left the network during the horizon / horizon seconds.
    pub outflow_veh_h: f64,
    /// The same with vehicles that entered (initial vehicles and vehicles still waiting do not count).
    pub inflow_veh_h: f64,
    /// Mean over steps of the mean speed of the vehicles in the network (steps with none, or all stopped, skipped).
    pub avg_speed_mps: f64,
    /// Mean time from entering to leaving, over the vehicles that left.
    pub mean_travel_time_s: f64,
    /// Mean of travel time minus the time at each driver's desired speed over its whole route (past a lane's dead
    /// end, as it drives on after changing lanes), over the vehicles that left.
    pub mean_delay_s: f64,
    pub arrived: u64,
    pub departed: u64,
    pub steps: u64,
    /// Sum over steps of the vehicles in the network (work done, for speed figures).
    pub vehicle_steps: u64,
    /// 3600 x vehicles past the corridor's end (the main line's last road) during the horizon / horizon seconds.
    #[serde(default)]
    pub end_flow_veh_h: f64,
    /// The same past each measured merge (the spec's `measure_points`, in order).
    #[serde(default)]
    pub merge_flows_veh_h: Vec<f64>,
    /// Lane changes done after the warm-up (0 on networks of one-lane roads).
    #[serde(default)]
    pub lane_changes: u64,
    /// The same per vehicle-kilometre driven after the warm-up.
    #[serde(default)]
    pub lane_changes_per_veh_km: f64,
    /// `lane_changes` by the lane-change model's reason (their sum is `lane_changes`).
    #[serde(default)]
    pub lane_changes_by_reason: LaneChangeReasons,
    /// What each entry road took of its demand over the whole run (warm-up included).
    #[serde(default)]
    pub entries: Vec<EntryCounts>,
    /// Vehicles taken off a jammed lane after standing longer than the time to teleport, after the warm-up.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub teleports: u64,
    /// Vehicles in the network at the end that had stood still for longer than SUMO's default time to teleport
    /// (a gridlock that a run without teleports would otherwise hide).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub stuck: u64,
    /// Per induction loop (the spec's `detectors`, in order), vehicles passed whole per hour of measured time.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub detector_flows_veh_h: Vec<f64>,
    /// The same loops' occupancy over the measured time (per cent).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub detector_occupancy_pct: Vec<f64>,
}

/// Lines for people when vehicles were teleported or stood still to the end in some run, said before any figure.
pub fn standstill_lines(runs: &[RunMetrics]) -> Vec<String> {
    let n = runs.len().max(1) as f64;
    let mean = |f: fn(&RunMetrics) -> u64| runs.iter().map(f).sum::<u64>() as f64 / n;
    let mut out = Vec::new();
    if runs.iter().any(|r| r.teleports > 0) {
        out.push(format!(
            "{:.1} vehicles a run teleported after standing longer than the time to teleport (a jam that would \
             have stopped their road)",
            mean(|r| r.teleports)
        ));
    }
    if runs.iter().any(|r| r.stuck > 0) {
        out.push(format!(
            "warning: {:.1} vehicles a run stood still for over {:.0} s at its end: a gridlock; \
             `time_to_teleport_s` in the scenario resolves such vehicles as SUMO does",
            mean(|r| r.stuck),
            mapc_scenario::SUMO_TIME_TO_TELEPORT_S
        ));
    }
    out
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// One entry road's demand over a run: the vehicles due to depart there, inserted or still waiting at the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EntryCounts {
    pub road: RoadId,
    /// Vehicles of the flows from this road whose departure time has come.
    pub demand: u64,
    /// Of them, those that entered the network.
    pub inserted: u64,
    /// The others: still waiting to enter at the end of the run.
    pub waiting: u64,
}

/// An entry is blocked when more than this share of its demand is still waiting at the end of a run ...
const BLOCKED_WAITING_SHARE: f64 = 0.05;
/// ... and at least this many vehicles (a vehicle or two due in the last steps wait at any entry).
const BLOCKED_WAITING_MIN: f64 = 5.0;

/// One entry road's demand, mean over seeds, and whether the entry could not take it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EntrySummary {
    pub road: RoadId,
    pub demand: f64,
    pub inserted: f64,
    pub waiting: f64,
    /// The entry took much less than its demand (a share of it still waiting at the end): the run's figures
    /// measure what got in, not the demand.
    pub blocked: bool,
}

impl EntrySummary {
    /// Per entry road (in the order of the first run), the means over `runs`.
    pub fn of(runs: &[RunMetrics]) -> Vec<EntrySummary> {
        let Some(first) = runs.first() else {
            return Vec::new();
        };
        let n = runs.len() as f64;
        first
            .entries
            .iter()
            .map(|e| {
                let mean = |count: fn(&EntryCounts) -> u64| {
                    runs.iter()
                        .filter_map(|r| r.entries.iter().find(|x| x.road == e.road))
                        .map(|x| count(x) as f64)
                        .sum::<f64>()
                        / n
                };
                let (demand, waiting) = (mean(|x| x.demand), mean(|x| x.waiting));
                EntrySummary {
                    road: e.road,
                    demand,
                    inserted: mean(|x| x.inserted),
                    waiting,
                    blocked: waiting > BLOCKED_WAITING_SHARE * demand
                        && waiting >= BLOCKED_WAITING_MIN,
                }
            })
            .collect()
    }

    /// For people: `entry R3 took 394 of the 2100 vehicles that wanted to depart there; 1706 still wait to enter
    /// at the end ...`.
    pub fn line(&self, seeds: usize) -> String {
        format!(
            "entry {} took {:.0} of the {:.0} vehicles that wanted to depart there; {:.0} still wait to enter at \
             the end (mean over {seeds} seed{}): the figures measure what got in, not the demand",
            self.road,
            self.inserted,
            self.demand,
            self.waiting,
            if seeds == 1 { "" } else { "s" }
        )
    }

    /// The lines of the blocked entries among `entries`.
    pub fn blocked_lines(entries: &[EntrySummary], seeds: usize) -> Vec<String> {
        entries
            .iter()
            .filter(|e| e.blocked)
            .map(|e| e.line(seeds))
            .collect()
    }
}

/// Lane changes by why the lane-change model made them (SUMO's `--lanechange-output` reasons).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LaneChangeReasons {
    /// To stay on the route (a lane that ends, an acceleration lane).
    pub strategic: u64,
    /// To make room for a vehicle that must enter the lane.
    pub cooperative: u64,
    /// To drive faster.
    pub speed_gain: u64,
    /// The obligation to keep right.
    pub keep_right: u64,
}

impl LaneChangeReasons {
    /// Count one change made for `reason` (`None`: a change without a reason, which LC2013 never makes, counted
    /// nowhere so that the sum shows it).
    pub fn count(&mut self, reason: Option<crate::models::lc::Reason>) {
        use crate::models::lc::Reason;
        match reason {
            Some(Reason::Strategic) => self.strategic += 1,
            Some(Reason::Cooperative) => self.cooperative += 1,
            Some(Reason::SpeedGain) => self.speed_gain += 1,
            Some(Reason::KeepRight) => self.keep_right += 1,
            None => {}
        }
    }

    pub fn total(&self) -> u64 {
        self.strategic + self.cooperative + self.speed_gain + self.keep_right
    }
}

/// Mean and half-width of the 95% confidence interval (Student t with n - 1 degrees of freedom).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeanCi {
    pub mean: f64,
    pub ci95: f64,
    pub std: f64,
    pub n: usize,
}

impl MeanCi {
    /// The summary of no values (NaN), for records written before a figure existed.
    pub fn none() -> MeanCi {
        MeanCi::of(&[])
    }

    /// Summary of `xs`; one value gives a zero interval, none gives NaN.
    pub fn of(xs: &[f64]) -> MeanCi {
        let n = xs.len();
        if n == 0 {
            return MeanCi {
                mean: f64::NAN,
                ci95: f64::NAN,
                std: f64::NAN,
                n,
            };
        }
        // sequential sums in the given order: the same numbers for any thread count
        let mean = xs.iter().sum::<f64>() / n as f64;
        if n == 1 {
            return MeanCi {
                mean,
                ci95: 0.0,
                std: 0.0,
                n,
            };
        }
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
        let std = var.sqrt();
        let t = t_quantile_975(n - 1);
        MeanCi {
            mean,
            ci95: t * std / (n as f64).sqrt(),
            std,
            n,
        }
    }
}

/// The 97.5% quantile of Student's t with `dof` degrees of freedom.
pub fn t_quantile_975(dof: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, dof as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(1.959964)
}

/// Metrics over seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub outflow: MeanCi,
    pub inflow: MeanCi,
    pub speed: MeanCi,
    pub travel_time: MeanCi,
    pub delay: MeanCi,
    /// Past the corridor's end, per hour of measured time.
    #[serde(default = "MeanCi::none")]
    pub end_flow: MeanCi,
    /// Past each measured merge, per hour of measured time.
    #[serde(default)]
    pub merge_flows: Vec<MeanCi>,
    pub seeds: usize,
}

impl Summary {
    pub fn of(runs: &[RunMetrics]) -> Summary {
        let col = |f: fn(&RunMetrics) -> f64| MeanCi::of(&runs.iter().map(f).collect::<Vec<_>>());
        Summary {
            outflow: col(|r| r.outflow_veh_h),
            inflow: col(|r| r.inflow_veh_h),
            speed: col(|r| r.avg_speed_mps),
            travel_time: col(|r| r.mean_travel_time_s),
            delay: col(|r| r.mean_delay_s),
            end_flow: col(|r| r.end_flow_veh_h),
            merge_flows: (0..runs
                .iter()
                .map(|r| r.merge_flows_veh_h.len())
                .max()
                .unwrap_or(0))
                .map(|i| {
                    MeanCi::of(
                        &runs
                            .iter()
                            .map(|r| r.merge_flows_veh_h.get(i).copied().unwrap_or(f64::NAN))
                            .collect::<Vec<_>>(),
                    )
                })
                .collect(),
            seeds: runs.len(),
        }
    }
}

/// A baseline over seeds as `mapc sim --json` prints it (and the Python package's `simulate` returns it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BaselineReport {
    /// Where the scenario came from: a file path, or `builtin:NAME`.
    pub scenario: String,
    pub seeds: usize,
    pub first_seed: u64,
    pub outflow: MeanCi,
    pub inflow: MeanCi,
    pub speed: MeanCi,
    pub travel_time: MeanCi,
    pub delay: MeanCi,
    /// Vehicles past the corridor's end per hour of measured time.
    pub end_flow: MeanCi,
    /// Vehicles past each measured merge per hour of measured time.
    pub merges: Vec<MergeFlow>,
    /// Lane changes per run and per vehicle-km (0 on networks of one-lane roads).
    pub lane_changes: MeanCi,
    pub lane_changes_per_veh_km: MeanCi,
    /// Per entry road, its demand over the run and what it took (mean over seeds).
    pub entries: Vec<EntrySummary>,
    /// Per induction loop, its flow (vehicles passed whole per hour of measured time) and occupancy (%).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub detectors: Vec<DetectorSummary>,
    pub wall_s: f64,
    pub runs: Vec<RunMetrics>,
}

/// One induction loop over seeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DetectorSummary {
    pub id: String,
    pub flow: MeanCi,
    pub occupancy: MeanCi,
}

/// The flow past one measured merge over seeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeFlow {
    /// `merge J3 (osm:123)`.
    pub name: String,
    pub flow: MeanCi,
}

impl BaselineReport {
    pub fn of(
        scenario: &str,
        first_seed: u64,
        runs: Vec<RunMetrics>,
        wall_s: f64,
        spec: &crate::spec::SimSpec,
    ) -> BaselineReport {
        let merge_names = spec.measure_names();
        let s = Summary::of(&runs);
        let merges = s
            .merge_flows
            .iter()
            .enumerate()
            .map(|(i, &flow)| MergeFlow {
                name: merge_names
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| format!("merge {i}")),
                flow,
            })
            .collect();
        let col = |f: fn(&RunMetrics) -> f64| MeanCi::of(&runs.iter().map(f).collect::<Vec<_>>());
        let lane_changes = col(|r| r.lane_changes as f64);
        let lane_changes_per_veh_km = col(|r| r.lane_changes_per_veh_km);
        BaselineReport {
            scenario: scenario.to_string(),
            seeds: s.seeds,
            first_seed,
            outflow: s.outflow,
            inflow: s.inflow,
            speed: s.speed,
            travel_time: s.travel_time,
            delay: s.delay,
            end_flow: s.end_flow,
            merges,
            lane_changes,
            lane_changes_per_veh_km,
            entries: EntrySummary::of(&runs),
            detectors: spec
                .detectors
                .iter()
                .enumerate()
                .map(|(i, d)| {
                    let at = |v: &Vec<f64>| v.get(i).copied().unwrap_or(f64::NAN);
                    DetectorSummary {
                        id: d.id.clone(),
                        flow: MeanCi::of(
                            &runs
                                .iter()
                                .map(|r| at(&r.detector_flows_veh_h))
                                .collect::<Vec<_>>(),
                        ),
                        occupancy: MeanCi::of(
                            &runs
                                .iter()
                                .map(|r| at(&r.detector_occupancy_pct))
                                .collect::<Vec<_>>(),
                        ),
                    }
                })
                .collect(),
            wall_s,
            runs,
        }
    }
}
