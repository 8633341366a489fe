//! The regime of each measured merge under a scenario's demand, from a few all-human runs: which road has the
//! right of way, how fast the humans drive near the merge against free flow, and how long the queue before it
//! grows. A policy trained on the Simple Merge (the ramp major, the main road congested by its yielding) is only
//! worth transferring to a merge in a similar regime; this tells the user which one a scenario is in.

use super::kept::{self, KeptRun};
use super::observed::{Acc, Observation};
use crate::error::SimError;
use crate::measure::metrics::{EntrySummary, RunMetrics};
use crate::measure::points::MeasurePoint;
use crate::sim::Simulation;
use crate::spec::SimSpec;
use mapc_graph::{JunctionId, RoadId};
use rayon::prelude::*;
use serde::Serialize;

/// Seeds of the all-human runs a regime report observes (`mapc sim` and `mapc window` print it; a deployment
/// rule that asks for congestion reads it), `0..REGIME_SEEDS`.
pub const REGIME_SEEDS: usize = 3;
/// Vehicles this close before the merge count for the speed near it (m).
pub const NEAR_MERGE_M: f64 = 200.0;
/// A vehicle slower than this is queueing (m/s; 18 km/h).
pub const QUEUE_SPEED_MPS: f64 = 5.0;
/// A queue continues to the next vehicle behind only within this bumper-to-bumper gap (m).
const QUEUE_GAP_M: f64 = 30.0;
/// Mean speed near the merge over free flow at or above which it flows freely ...
const FREE_FLOW_RATIO: f64 = 0.85;
/// ... and below which it is congested (between: dense).
const CONGESTED_RATIO: f64 = 0.5;

/// How congested a merge is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Congestion {
    FreeFlow,
    Dense,
    Congested,
    /// No human came near it in the measured time.
    Unobserved,
}

impl Congestion {
    fn of(ratio: f64) -> Congestion {
        if ratio.is_nan() {
            Congestion::Unobserved
        } else if ratio >= FREE_FLOW_RATIO {
            Congestion::FreeFlow
        } else if ratio >= CONGESTED_RATIO {
            Congestion::Dense
        } else {
            Congestion::Congested
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Congestion::FreeFlow => "free flow",
            Congestion::Dense => "dense",
            Congestion::Congested => "congested",
            Congestion::Unobserved => "no traffic seen",
        }
    }
}

/// One road into a merge.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ApproachRegime {
    pub road: RoadId,
    /// On the corridor's main line (else a merging road).
    pub main_line: bool,
    /// Has the right of way at the merge (its links are major).
    pub major: bool,
    /// The humans' desired speed here: the speed limit times their mean speed factor, capped (m/s).
    pub free_flow_mps: f64,
    /// The humans' mean speed within [`NEAR_MERGE_M`] before the merge, over vehicles and measured steps (m/s).
    pub human_speed_mps: f64,
    /// `human_speed_mps / free_flow_mps`.
    pub speed_ratio: f64,
    pub congestion: Congestion,
    /// Length of the queue (vehicles slower than [`QUEUE_SPEED_MPS`], back to back from the merge) on this road,
    /// mean and largest over measured steps (m).
    pub mean_queue_m: f64,
    pub max_queue_m: f64,
}

/// One merge's regime.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeRegime {
    /// `merge J3 (osm:123)`.
    pub name: String,
    pub junction: JunctionId,
    pub approaches: Vec<ApproachRegime>,
    /// A zipper merge: the roads take turns.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub zipper: bool,
    /// The worst approach's congestion.
    pub congestion: Congestion,
}

/// The regimes of every measured merge and the demand's backlog, over `seeds`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegimeReport {
    pub seeds: usize,
    pub merges: Vec<MergeRegime>,
    /// Vehicles waiting to enter at the end of the run, mean over seeds (demand the entries could not take).
    pub waiting_to_enter: f64,
    /// Per entry road, its demand and what it took, mean over seeds.
    pub entries: Vec<EntrySummary>,
}

impl RegimeReport {
    /// For people: first a line per blocked entry (its figures would otherwise read as a merge's free flow),
    /// then [`RegimeReport::merge_lines`].
    pub fn lines(&self) -> Vec<String> {
        let mut out = EntrySummary::blocked_lines(&self.entries, self.seeds);
        out.extend(self.merge_lines());
        out
    }

    /// A line per merge: `merge J3: the merging road R7 has priority; dense (main R5 at 61% of free flow, queue
    /// 40 m mean / 180 m max; merging R7 ...)`; then the backlog, where no entry is blocked.
    pub fn merge_lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        for m in &self.merges {
            let prio: Vec<String> = m
                .approaches
                .iter()
                .filter(|a| a.major)
                .map(|a| format!("{} {}", role(a), a.road))
                .collect();
            let prio = if m.zipper {
                "the roads take turns (zipper)".to_string()
            } else if prio.is_empty() || prio.len() == m.approaches.len() {
                "no road has priority".to_string()
            } else {
                format!("{} has priority", prio.join(" and "))
            };
            let parts: Vec<String> = m
                .approaches
                .iter()
                .map(|a| {
                    format!(
                        "{} {}: humans at {:.1} of {:.1} m/s ({:.0}%), queue {:.0} m mean / {:.0} m max",
                        role(a),
                        a.road,
                        a.human_speed_mps,
                        a.free_flow_mps,
                        100.0 * a.speed_ratio,
                        a.mean_queue_m,
                        a.max_queue_m
                    )
                })
                .collect();
            out.push(format!(
                "{}: {prio}; {} ({})",
                m.name,
                m.congestion.label(),
                parts.join("; ")
            ));
        }
        if self.waiting_to_enter >= 1.0 && !self.entries.iter().any(|e| e.blocked) {
            out.push(format!(
                "{:.0} vehicles on average were still waiting to enter at the end of a run (many: demand above \
                 what the entries take)",
                self.waiting_to_enter
            ));
        }
        out
    }
}

fn role(a: &ApproachRegime) -> &'static str {
    if a.main_line {
        "main road"
    } else {
        "merging road"
    }
}

/// Runs the humans over `seeds` in parallel (every AV drives as a human: [`SimSpec::all_human`]) and observes
/// every measured merge of `spec` after the warm-up. Runs kept ([`super::kept`]) are not run again.
pub fn merge_regimes(spec: &SimSpec, seeds: &[u64]) -> Result<RegimeReport, SimError> {
    let humans = spec.all_human();
    let key = kept::key(&humans);
    // the job's later seeds on threads the report's own runs leave idle: kept, not reported
    let extra = kept::fill_round(key.as_deref(), seeds, rayon::current_num_threads());
    let all: Vec<u64> = seeds.iter().chain(&extra).copied().collect();
    let mut runs: Vec<(Vec<Vec<Acc>>, usize, RunMetrics)> = all
        .par_iter()
        .map(|&seed| {
            let run = match kept::get(key.as_deref(), seed) {
                Some(run) => run,
                None => {
                    let (regime, metrics) = observe(spec, &humans, seed)?;
                    let run = KeptRun { metrics, regime };
                    kept::put(key.as_deref(), seed, run.clone());
                    run
                }
            };
            Ok((run.regime.acc, run.regime.waiting, run.metrics))
        })
        .collect::<Result<_, SimError>>()?;
    runs.truncate(seeds.len());
    let sim = Simulation::from_spec(spec.clone(), 0)?;
    let shape = approaches(&sim);
    let humans: Vec<_> = spec
        .vehicle_types
        .iter()
        .filter(|t| !t.controlled)
        .collect();
    let types = if humans.is_empty() {
        spec.vehicle_types.iter().collect()
    } else {
        humans
    };
    let factor = types.iter().map(|t| t.speed_factor).sum::<f64>() / types.len().max(1) as f64;
    let max_speed = types.iter().map(|t| t.max_speed).fold(0.0, f64::max);
    let mut merges = Vec::new();
    let junctions = spec.measure_junctions();
    for (m, (point, roads)) in spec.measure_points.iter().zip(&shape).enumerate() {
        let mut out = Vec::new();
        for (a, &(road, lane, major)) in roads.iter().enumerate() {
            let mut acc = Acc::default();
            for (run, _, _) in &runs {
                let r = &run[m][a];
                acc.speed_sum += r.speed_sum;
                acc.speed_n += r.speed_n;
                acc.queue_sum += r.queue_sum;
                acc.queue_max = acc.queue_max.max(r.queue_max);
                acc.steps += r.steps;
            }
            let free = (sim.network().lanes[lane as usize].speed_limit * factor).min(max_speed);
            let speed = if acc.speed_n > 0 {
                acc.speed_sum / acc.speed_n as f64
            } else {
                f64::NAN
            };
            out.push(ApproachRegime {
                road,
                main_line: spec.main_line.contains(&road),
                major,
                free_flow_mps: free,
                human_speed_mps: speed,
                speed_ratio: speed / free,
                congestion: Congestion::of(speed / free),
                mean_queue_m: acc.queue_sum / acc.steps.max(1) as f64,
                max_queue_m: acc.queue_max,
            });
        }
        let worst = out
            .iter()
            .map(|a| a.speed_ratio)
            .filter(|r| !r.is_nan())
            .fold(f64::NAN, f64::min);
        merges.push(MergeRegime {
            name: point.name.clone(),
            junction: junctions[m].unwrap_or(JunctionId(0)),
            approaches: out,
            zipper: zipper_merge(&sim, point),
            congestion: Congestion::of(worst),
        });
    }
    let waiting = runs.iter().map(|(_, w, _)| *w as f64).sum::<f64>() / runs.len().max(1) as f64;
    let metrics: Vec<RunMetrics> = runs.into_iter().map(|(_, _, m)| m).collect();
    Ok(RegimeReport {
        seeds: seeds.len(),
        merges,
        waiting_to_enter: waiting,
        entries: EntrySummary::of(&metrics),
    })
}

/// Who has the right of way at a merge, read from the network alone (no run).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MergePriority {
    /// The measure point's name (`merge J3 (osm:123)`).
    pub name: String,
    pub junction: JunctionId,
    /// The main line's approach has priority.
    pub main_major: bool,
    /// A merging road's approach has priority.
    pub merging_major: bool,
    /// A zipper merge: the roads take turns.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub zipper: bool,
}

impl MergePriority {
    /// The Simple Merge's case: the main road yields to the merging road.
    pub fn main_road_yields(&self) -> bool {
        self.merging_major && !self.main_major
    }

    /// In words, as the regime report says it.
    pub fn label(&self) -> &'static str {
        if self.zipper {
            return "the roads take turns (zipper)";
        }
        match (self.main_major, self.merging_major) {
            (true, true) => "no road yields",
            (true, false) => "the main road has priority",
            (false, true) => "the merging road has priority",
            (false, false) => "every road yields",
        }
    }
}

/// Per measured merge of `spec`, in order, who has the right of way.
pub fn merge_priorities(spec: &SimSpec) -> Result<Vec<MergePriority>, SimError> {
    let sim = Simulation::from_spec(spec.clone(), 0)?;
    let shape = approaches(&sim);
    let junctions = spec.measure_junctions();
    Ok(spec
        .measure_points
        .iter()
        .zip(&shape)
        .zip(junctions)
        .map(|((point, roads), junction)| {
            let major = |main: bool| {
                roads
                    .iter()
                    .any(|&(r, _, m)| m && spec.main_line.contains(&r) == main)
            };
            MergePriority {
                name: point.name.clone(),
                junction: junction.unwrap_or(JunctionId(0)),
                main_major: major(true),
                merging_major: major(false),
                zipper: zipper_merge(&sim, point),
            }
        })
        .collect())
}

/// Whether a link into the measure point's roads is a zipper link.
fn zipper_merge(sim: &Simulation, point: &MeasurePoint) -> bool {
    let net = sim.network();
    net.links.iter().any(|l| {
        l.zipper
            && net
                .road_of(l.to_lane)
                .is_some_and(|to| point.roads.contains(&net.road_ids[to]))
    })
}

/// Per measure point, its approaches: (road, its lane, major).
fn approaches(sim: &Simulation) -> Vec<Vec<(RoadId, u32, bool)>> {
    let net = sim.network();
    sim.spec()
        .measure_points
        .iter()
        .map(|p| {
            let mut out: Vec<(RoadId, u32, bool)> = Vec::new();
            for link in &net.links {
                let (Some(from), Some(to)) =
                    (net.road_of(link.from_lane), net.road_of(link.to_lane))
                else {
                    continue;
                };
                if !p.roads.contains(&net.road_ids[to]) {
                    continue;
                }
                let road = net.road_ids[from];
                match out.iter_mut().find(|(r, _, _)| *r == road) {
                    Some(e) => e.2 |= link.major,
                    None => out.push((road, link.from_lane, link.major)),
                }
            }
            out.sort_by_key(|&(r, _, _)| r);
            out
        })
        .collect()
}

/// One seed of `humans` (`spec` with every AV a human), observed; `spec` tells which vehicles are AVs, whose
/// speeds the report leaves out.
fn observe(
    spec: &SimSpec,
    humans: &SimSpec,
    seed: u64,
) -> Result<(Observation, RunMetrics), SimError> {
    let mut sim = Simulation::from_spec(humans.clone(), seed)?;
    let shape = approaches(&sim);
    let mut acc: Vec<Vec<Acc>> = shape
        .iter()
        .map(|a| vec![Acc::default(); a.len()])
        .collect();
    // per lane of an approach road: (point, approach index)
    let net = sim.network();
    let mut slot: Vec<Option<(usize, usize)>> = vec![None; net.lanes.len()];
    for (p, roads) in shape.iter().enumerate() {
        for (a, &(road, _, _)) in roads.iter().enumerate() {
            let r = net.road_ids.iter().position(|&id| id == road);
            for &l in r.map_or(&[][..], |r| &net.road_lanes[r]) {
                slot[l as usize] = Some((p, a));
            }
        }
    }
    // by the run's type index (the types of `humans` are `spec`'s, in its order)
    let human_type: Vec<bool> = spec.vehicle_types.iter().map(|t| !t.controlled).collect();
    let all_controlled = !human_type.iter().any(|&h| h);
    // per approach, this step's (distance to the merge, speed, length) of vehicles on it
    let mut seen: Vec<Vec<Vec<(f64, f64, f64)>>> =
        shape.iter().map(|a| vec![Vec::new(); a.len()]).collect();
    while !sim.is_done() {
        if !sim.in_warmup() {
            seen.iter_mut().flatten().for_each(Vec::clear);
            for (lane, ids) in sim.lanes_in_order() {
                let Some((p, a)) = slot[lane as usize] else {
                    continue;
                };
                let end = sim.network().lanes[shape[p][a].1 as usize].length;
                for &id in ids {
                    let (pos, speed, length, vtype) = sim.vehicle_motion(id);
                    let dist = end - pos;
                    seen[p][a].push((dist, speed, length));
                    if (all_controlled || human_type[vtype]) && dist <= NEAR_MERGE_M {
                        acc[p][a].speed_sum += speed;
                        acc[p][a].speed_n += 1;
                    }
                }
            }
            for (p, roads) in seen.iter_mut().enumerate() {
                for (a, vs) in roads.iter_mut().enumerate() {
                    vs.sort_by(|x, y| x.0.total_cmp(&y.0));
                    let q = queue_length(vs);
                    let r = &mut acc[p][a];
                    r.queue_sum += q;
                    r.queue_max = r.queue_max.max(q);
                    r.steps += 1;
                }
            }
        }
        sim.step()?;
    }
    let seen = Observation {
        acc,
        waiting: sim.waiting_to_enter(),
    };
    Ok((seen, sim.metrics()))
}

/// The queue from the merge back: vehicles (distance to the merge, speed, length), nearest first, slower than
/// [`QUEUE_SPEED_MPS`] and each within [`QUEUE_GAP_M`] of the one ahead (the first within that of the merge).
fn queue_length(vs: &[(f64, f64, f64)]) -> f64 {
    let mut end = 0.0;
    for &(dist, speed, length) in vs {
        if speed >= QUEUE_SPEED_MPS || dist - end > QUEUE_GAP_M {
            break;
        }
        end = dist + length;
    }
    end
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queues_are_back_to_back_slow_vehicles_from_the_merge() {
        assert_eq!(queue_length(&[]), 0.0);
        assert_eq!(queue_length(&[(1.0, 0.0, 5.0), (8.0, 1.0, 5.0)]), 13.0);
        // a fast vehicle ends it, and so does a gap
        assert_eq!(queue_length(&[(1.0, 0.0, 5.0), (8.0, 20.0, 5.0)]), 6.0);
        assert_eq!(queue_length(&[(1.0, 0.0, 5.0), (80.0, 0.0, 5.0)]), 6.0);
        assert_eq!(queue_length(&[(50.0, 0.0, 5.0)]), 0.0);
    }

    /// 4000 veh/h of humans on the one-lane main road, which takes about 2000: the report says so first (its
    /// merge would read as flowing, the queue being at the entry), per entry road.
    #[test]
    fn a_blocked_entry_comes_first_in_the_report() {
        let mut spec = crate::tests::simple_merge_spec();
        let main = spec.flows[0].from;
        for f in spec.flows.iter_mut().filter(|f| f.from == main) {
            f.vehs_per_hour *= 2.0;
        }
        let r = merge_regimes(&spec, &[0]).unwrap();
        let lines = r.lines();
        assert!(
            lines[0].starts_with(&format!("entry {main} took")),
            "{lines:?}"
        );
        assert_eq!(
            lines
                .iter()
                .filter(|l| l.contains("still wait to enter"))
                .count(),
            1
        );
        let e = r.entries.iter().find(|e| e.road == main).unwrap();
        assert!(e.blocked && e.waiting > 300.0, "{e:?}");
        assert_eq!(e.demand, e.inserted + e.waiting);
        // the whole backlog is the blocked entry's: not said twice
        assert!(
            !lines
                .iter()
                .any(|l| l.contains("on average were still waiting")),
            "{lines:?}"
        );
    }

    #[test]
    fn the_simple_merge_ramp_has_priority_and_its_main_road_slows() {
        let spec = crate::tests::simple_merge_spec();
        let r = merge_regimes(&spec, &[0, 1]).unwrap();
        assert_eq!(r.merges.len(), 1, "{r:?}");
        let m = &r.merges[0];
        assert_eq!(m.approaches.len(), 2);
        let main = m.approaches.iter().find(|a| a.main_line).unwrap();
        let ramp = m.approaches.iter().find(|a| !a.main_line).unwrap();
        // the paper's merge: the ramp is major, the main road yields
        assert!(ramp.major && !main.major, "{m:?}");
        // the humans near the merge on the main road drive well below free flow
        assert!(main.speed_ratio < 0.85, "{main:?}");
        assert!(main.max_queue_m > 0.0, "{main:?}");
        assert!(!r.lines().is_empty());
    }
}
