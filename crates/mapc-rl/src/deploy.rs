//! Where a policy is deployed. A policy learned in one regime (the Simple Merge's: the main road yields to the
//! ramp and crawls) can hold the main road back where nothing needs it (docs/results.md, "A policy for any
//! merge" and "Multi-lane windows"), so a policy may carry the regime it is meant for: windows whose merge is not
//! in it are left to the human drivers, their AVs driving as humans do. The right of way is read from the network,
//! before any run; the congestion, where a rule asks for it, from the regime report's few all-human runs
//! ([`mapc_sim::merge_regimes`] on seeds `0..REGIME_SEEDS`, the same for every evaluation: deterministic).

use std::fmt;
use std::str::FromStr;

use mapc_graph::{JunctionId, RoadId};
use mapc_sim::{
    Congestion, MergePriority, MergeRegime, REGIME_SEEDS, SimSpec, merge_priorities, merge_regimes,
};
use serde::{Deserialize, Serialize};

use crate::error::RlError;

/// Which merges a policy controls.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Deploy {
    /// Every window (what a policy without a rule does).
    Everywhere,
    /// Only windows whose merges all make the main road yield to the merging road.
    MainRoadYields,
    /// Only windows whose merges all make the main road yield and are congested under the humans (the regime
    /// report's mean speed near the merge below half of free flow on its slowest approach): a merge that flows or
    /// is only dense is left to the humans.
    MainRoadYieldsCongested,
    /// The Simple Merge's regime, where a policy trained on one-lane merges meters the main road with profit:
    /// [`Deploy::MainRoadYieldsCongested`] at merges whose roads in and out have one lane each. On a multi-lane
    /// merge such a policy loses even where the humans congest it (docs/results.md, "Multi-lane windows").
    SimpleMergeRegime,
    /// Wherever the policy drives, but only if it beats the humans there on calibration seeds of its own (the
    /// evaluation calibrates it before the runs it reports): on its reward's measure (speed for a speed reward,
    /// else outflow) with disjoint 95 % intervals, and not lower in outflow with disjoint intervals. The rule that
    /// never loses by construction, for a policy whose regime no other rule describes.
    Measured,
}

/// What a rule reads of one measured merge: its right of way, its regime under humans where the rule asks, and
/// the road in or out of it with the most lanes.
struct MergeFacts {
    priority: MergePriority,
    regime: Option<MergeRegime>,
    widest: Option<(RoadId, usize)>,
}

impl Deploy {
    pub fn name(self) -> &'static str {
        match self {
            Deploy::Everywhere => "everywhere",
            Deploy::MainRoadYields => "main-road-yields",
            Deploy::MainRoadYieldsCongested => "main-road-yields-congested",
            Deploy::SimpleMergeRegime => "simple-merge-regime",
            Deploy::Measured => "measured",
        }
    }

    /// Whether the rule needs the human runs of the regime report.
    fn reads_congestion(self) -> bool {
        matches!(
            self,
            Deploy::MainRoadYieldsCongested | Deploy::SimpleMergeRegime
        )
    }

    /// Why the rule refuses `merge`; `None`: it admits it.
    fn refusal(self, merge: &MergeFacts) -> Option<String> {
        let p = &merge.priority;
        let yields = || (!p.main_road_yields()).then(|| format!("{} at {}", p.label(), p.name));
        let congested = || match &merge.regime {
            Some(r) if r.congestion == Congestion::Congested => None,
            Some(r) => Some(not_congested(r)),
            None => Some(format!("the regime at {} is unknown", p.name)),
        };
        let one_lane = || match merge.widest {
            Some((road, lanes)) if lanes > 1 => Some(format!(
                "{road} at {} has {lanes} lanes (the Simple Merge's regime has one lane per road)",
                p.name
            )),
            _ => None,
        };
        match self {
            Deploy::Everywhere | Deploy::Measured => None,
            Deploy::MainRoadYields => yields(),
            Deploy::MainRoadYieldsCongested => yields().or_else(congested),
            Deploy::SimpleMergeRegime => yields().or_else(one_lane).or_else(congested),
        }
    }

    /// The facts of every measured merge of `spec`, in its order.
    fn facts(self, spec: &SimSpec) -> Result<Vec<MergeFacts>, RlError> {
        let priorities = merge_priorities(spec).map_err(|e| RlError::Config(e.to_string()))?;
        let mut regimes: Vec<Option<MergeRegime>> = if self.reads_congestion() {
            let seeds: Vec<u64> = (0..REGIME_SEEDS as u64).collect();
            merge_regimes(spec, &seeds)
                .map_err(|e| RlError::Config(e.to_string()))?
                .merges
                .into_iter()
                .map(Some)
                .collect()
        } else {
            Vec::new()
        };
        regimes.resize(priorities.len(), None);
        let graph = &spec.graph;
        Ok(priorities
            .into_iter()
            .zip(regimes)
            .zip(&spec.measure_points)
            .map(|((priority, regime), point)| {
                // the roads out of the merge and, with the regime, the roads into it
                let into = regime
                    .iter()
                    .flat_map(|r| r.approaches.iter().map(|a| a.road));
                let widest = point
                    .roads
                    .iter()
                    .copied()
                    .chain(into)
                    .filter_map(|r| Some((r, graph.road(r)?.lanes.len())))
                    .max_by_key(|&(r, lanes)| (lanes, std::cmp::Reverse(r)));
                MergeFacts {
                    priority,
                    regime,
                    widest,
                }
            })
            .collect())
    }
}

/// `merge J3 (osm:123) is dense under humans, not congested (slowest: main road R5 at 79% of free flow, queue
/// 0 m mean; 3 human runs)`.
fn not_congested(regime: &MergeRegime) -> String {
    let slowest = regime
        .approaches
        .iter()
        .filter(|a| !a.speed_ratio.is_nan())
        .min_by(|a, b| a.speed_ratio.total_cmp(&b.speed_ratio));
    let detail = slowest.map_or_else(String::new, |a| {
        format!(
            "slowest: {} {} at {:.0}% of free flow, queue {:.0} m mean; ",
            if a.main_line {
                "main road"
            } else {
                "merging road"
            },
            a.road,
            100.0 * a.speed_ratio,
            a.mean_queue_m
        )
    });
    format!(
        "{} is {} under humans, not congested ({detail}{REGIME_SEEDS} human runs)",
        regime.name,
        regime.congestion.label()
    )
}

impl fmt::Display for Deploy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Deploy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "everywhere" => Ok(Deploy::Everywhere),
            "main-road-yields" | "main_road_yields" => Ok(Deploy::MainRoadYields),
            "main-road-yields-congested" | "main_road_yields_congested" => {
                Ok(Deploy::MainRoadYieldsCongested)
            }
            "simple-merge-regime" | "simple_merge_regime" => Ok(Deploy::SimpleMergeRegime),
            "measured" => Ok(Deploy::Measured),
            _ => Err(format!(
                "unknown deployment rule `{s}` (expected everywhere, main-road-yields, \
                 main-road-yields-congested, simple-merge-regime or measured)"
            )),
        }
    }
}

/// A window the rule leaves to the humans, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Withheld {
    /// The window's merge as the scenario names it (for a distributed policy: the merge whose approaches are
    /// left to the humans).
    pub window: String,
    /// `the main road has priority at merge J3 (osm:123)`.
    pub reason: String,
}

/// A scenario as a policy with `rule` drives it.
#[derive(Clone, Debug)]
pub struct Deployment {
    /// The scenario with only the admitted windows controlled; `None` when the rule admits none (the AVs then
    /// drive as humans everywhere: the human baseline).
    pub spec: Option<SimSpec>,
    pub withheld: Vec<Withheld>,
}

/// For a distributed policy, every AV of the control region is an agent: the rule keeps the roads whose next merge
/// downstream admits it, and an AV on any other road drives as a human. A merge the scenario does not measure has
/// no known right of way and admits nothing.
pub fn deploy_by_road(spec: &SimSpec, rule: Deploy) -> Result<Deployment, RlError> {
    if matches!(rule, Deploy::Everywhere | Deploy::Measured) {
        return deploy(spec, rule);
    }
    let merges = rule.facts(spec)?;
    let graph = &spec.graph;
    let roads: Vec<RoadId> = match &spec.control_region {
        Some(region) => region.clone(),
        None => graph.roads.iter().map(|r| r.id).collect(),
    };
    let next_merge = |mut road: RoadId| -> Option<&MergeFacts> {
        // a bound on the walk, for safety against a cycle
        for _ in 0..graph.roads.len() {
            let to = graph.road(road)?.to;
            if let Some(m) = merges.iter().find(|m| m.priority.junction == to) {
                return Some(m);
            }
            let mut next = graph.connections_from(road).map(|c| c.to_road);
            road = match (next.next(), next.next()) {
                (Some(only), None) => only,
                _ => return None,
            };
        }
        None
    };
    let mut region = Vec::new();
    let mut withheld: Vec<Withheld> = Vec::new();
    for road in roads {
        let Some(m) = next_merge(road) else { continue };
        match rule.refusal(m) {
            None => region.push(road),
            Some(reason) if !withheld.iter().any(|w| w.window == m.priority.name) => {
                withheld.push(Withheld {
                    window: m.priority.name.clone(),
                    reason,
                })
            }
            Some(_) => {}
        }
    }
    Ok(restricted(spec, region, withheld))
}

/// The windows of `spec` that `rule` admits. A scenario with one controlled region is one window made of its
/// measured merges.
pub fn deploy(spec: &SimSpec, rule: Deploy) -> Result<Deployment, RlError> {
    if matches!(rule, Deploy::Everywhere | Deploy::Measured) {
        return Ok(Deployment {
            spec: Some(spec.clone()),
            withheld: Vec::new(),
        });
    }
    let merges = rule.facts(spec)?;
    // why `rule` refuses a window made of `junctions`: a merge outside the rule, or one whose right of way is not
    // known (the scenario does not measure it), or no merge at all
    let refusal = |junctions: &[JunctionId]| -> Option<String> {
        if junctions.is_empty() {
            return Some("it has no measured merge, so its right of way is unknown".into());
        }
        junctions.iter().find_map(
            |j| match merges.iter().find(|m| m.priority.junction == *j) {
                Some(m) => rule.refusal(m),
                None => Some(format!(
                    "the right of way at {j} is unknown (not a measured merge)"
                )),
            },
        )
    };
    if spec.control_windows.is_empty() {
        let region: Vec<JunctionId> = merges.iter().map(|m| m.priority.junction).collect();
        return Ok(match refusal(&region) {
            Some(reason) => Deployment {
                spec: None,
                withheld: vec![Withheld {
                    window: merges
                        .first()
                        .map_or_else(|| "the control region".into(), |m| m.priority.name.clone()),
                    reason,
                }],
            },
            None => Deployment {
                spec: Some(spec.clone()),
                withheld: Vec::new(),
            },
        });
    }
    // a withheld window stays (its merges are still measured) but leaves the controlled region, so none of its
    // AVs takes a command
    let mut withheld = Vec::new();
    let mut region = Vec::new();
    for w in &spec.control_windows {
        match refusal(&w.merges) {
            Some(reason) => withheld.push(Withheld {
                window: format!("window {}", w.name),
                reason,
            }),
            None => region.extend(w.roads.iter().copied()),
        }
    }
    Ok(restricted(spec, region, withheld))
}

/// `spec` controlled on `region` only; no road left: the human baseline.
fn restricted(spec: &SimSpec, mut region: Vec<RoadId>, withheld: Vec<Withheld>) -> Deployment {
    if region.is_empty() {
        return Deployment {
            spec: None,
            withheld,
        };
    }
    region.sort();
    region.dedup();
    let mut kept = spec.clone();
    kept.control_region = Some(region);
    Deployment {
        spec: Some(kept),
        withheld,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corridor() -> SimSpec {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/i696_whole_corridor.toml");
        let rs = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
        mapc_sim::spec_from_scenario(&rs).unwrap()
    }

    /// The whole I-696 corridor has six merges; at two of them the main road yields (mapc sim's regime report):
    /// a distributed policy keeps exactly the roads that lead to those two.
    #[test]
    fn by_road_a_distributed_policy_keeps_the_approaches_of_merges_where_the_main_road_yields() {
        let spec = corridor();
        let merges = merge_priorities(&spec).unwrap();
        assert_eq!(merges.len(), 6);
        let yielding: Vec<_> = merges
            .iter()
            .filter(|m| m.main_road_yields())
            .map(|m| m.junction)
            .collect();
        assert_eq!(yielding.len(), 2, "{merges:?}");
        let d = deploy_by_road(&spec, Deploy::MainRoadYields).unwrap();
        assert_eq!(d.withheld.len(), 4, "{:?}", d.withheld);
        let region = d.spec.unwrap().control_region.unwrap();
        for road in &spec.graph.roads {
            let kept = region.contains(&road.id);
            if yielding.contains(&road.to) {
                assert!(kept, "{:?} leads to a yielding merge", road.id);
            }
            if merges
                .iter()
                .any(|m| m.junction == road.to && !m.main_road_yields())
            {
                assert!(
                    !kept,
                    "{:?} leads to a merge where the main road has priority",
                    road.id
                );
            }
        }
        // everywhere: the scenario as it is
        let all = deploy_by_road(&spec, Deploy::Everywhere).unwrap();
        assert_eq!(all.spec.unwrap().control_region, spec.control_region);
        assert!(all.withheld.is_empty());
        assert!(
            "anywhere"
                .parse::<Deploy>()
                .unwrap_err()
                .contains("main-road-yields")
        );
    }

    fn scenario(name: &str) -> SimSpec {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios")
            .join(name);
        let rs = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
        mapc_sim::spec_from_scenario(&rs).unwrap()
    }

    /// The multi-lane I-696 window makes its main road yield, as the one-lane window does, but it flows (dense
    /// under humans, docs/results.md "Multi-lane windows", where merge_robust lost 7.8 % by the right of way
    /// alone): the congested rule leaves it to the humans and says why, and keeps the one-lane window and the
    /// Simple Merge, congested, where the policy gains.
    #[test]
    fn the_congested_rule_leaves_a_flowing_merge_to_the_humans_and_keeps_the_jammed_ones() {
        let lanes = scenario("i696_window_lanes.toml");
        let by_right_of_way = deploy(&lanes, Deploy::MainRoadYields).unwrap();
        assert!(by_right_of_way.spec.is_some() && by_right_of_way.withheld.is_empty());
        let d = deploy(&lanes, Deploy::MainRoadYieldsCongested).unwrap();
        assert!(d.spec.is_none(), "the window flows: humans drive");
        assert_eq!(d.withheld.len(), 1, "{:?}", d.withheld);
        let reason = &d.withheld[0].reason;
        assert!(
            reason.contains("is dense under humans, not congested")
                && reason.contains("3 human runs"),
            "{reason}"
        );
        for jammed in ["i696_window.toml", "simple_merge.toml"] {
            let spec = scenario(jammed);
            for rule in [Deploy::MainRoadYieldsCongested, Deploy::SimpleMergeRegime] {
                let d = deploy(&spec, rule).unwrap();
                assert!(d.withheld.is_empty(), "{jammed} {rule}: {:?}", d.withheld);
                assert_eq!(
                    d.spec.unwrap().control_region,
                    spec.control_region,
                    "{jammed}"
                );
            }
        }
        // the right of way still comes first: I-210's merge, where no road yields, is refused for it
        let i210 = deploy(
            &scenario("i210_window_lanes.toml"),
            Deploy::MainRoadYieldsCongested,
        )
        .unwrap();
        assert!(i210.spec.is_none());
        assert!(
            i210.withheld[0].reason.starts_with("no road yields"),
            "{:?}",
            i210.withheld
        );
        assert_eq!(
            "main-road-yields-congested".parse::<Deploy>(),
            Ok(Deploy::MainRoadYieldsCongested)
        );
        assert_eq!(
            Deploy::MainRoadYieldsCongested.to_string(),
            "main-road-yields-congested"
        );
    }

    /// The two-lane merge at the Simple Merge's demand per lane is congested, with the ramp's priority: the
    /// congested rule admits it, the Simple Merge's regime does not (two lanes and an acceleration lane;
    /// merge_robust loses a third of the outflow there), nor the multi-lane I-696 window (its merging road has two lanes, the road out three).
    #[test]
    fn the_simple_merge_regime_asks_for_one_lane_per_road() {
        let jam = scenario("two_lane_merge_jam_av.toml");
        let d = deploy(&jam, Deploy::MainRoadYieldsCongested).unwrap();
        assert!(
            d.withheld.is_empty() && d.spec.is_some(),
            "{:?}",
            d.withheld
        );
        let d = deploy(&jam, Deploy::SimpleMergeRegime).unwrap();
        assert!(d.spec.is_none());
        // the road out: two main lanes and the acceleration lane
        assert!(
            d.withheld[0]
                .reason
                .starts_with("R4 at merge J2 (center) has 3 lanes"),
            "{:?}",
            d.withheld
        );
        let d = deploy(
            &scenario("i696_window_lanes.toml"),
            Deploy::SimpleMergeRegime,
        )
        .unwrap();
        assert!(d.spec.is_none());
        assert!(
            d.withheld[0].reason.contains("has 3 lanes"),
            "{:?}",
            d.withheld
        );
        assert_eq!(
            "simple-merge-regime".parse::<Deploy>(),
            Ok(Deploy::SimpleMergeRegime)
        );
    }

    /// A distributed policy under the congested rule: the approaches of a flowing merge leave its region.
    #[test]
    fn by_road_the_congested_rule_withholds_the_approaches_of_a_flowing_merge() {
        let lanes = scenario("i696_window_lanes.toml");
        assert!(
            deploy_by_road(&lanes, Deploy::MainRoadYields)
                .unwrap()
                .spec
                .is_some()
        );
        let d = deploy_by_road(&lanes, Deploy::MainRoadYieldsCongested).unwrap();
        assert!(d.spec.is_none(), "{:?}", d.withheld);
        assert!(
            d.withheld[0].reason.contains("not congested"),
            "{:?}",
            d.withheld
        );
        let one_lane = scenario("i696_window.toml");
        let d = deploy_by_road(&one_lane, Deploy::MainRoadYieldsCongested).unwrap();
        assert!(
            d.withheld.is_empty() && d.spec.is_some(),
            "{:?}",
            d.withheld
        );
    }

    /// A merge whose right of way the scenario does not measure admits nothing: the rule cannot be checked there.
    #[test]
    fn an_unmeasured_merge_is_left_to_the_humans() {
        let mut spec = corridor();
        spec.measure_points.clear();
        let d = deploy(&spec, Deploy::MainRoadYields).unwrap();
        assert!(d.spec.is_none());
        assert!(d.withheld[0].reason.contains("unknown"), "{:?}", d.withheld);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/i696_3merge.toml");
        let rs = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
        let mut three = mapc_sim::spec_from_scenario(&rs).unwrap();
        // keep J43's point only: the other two windows' merges are then unknown
        three
            .measure_points
            .retain(|p| p.name.contains("osm:61862553"));
        let d = deploy(&three, Deploy::MainRoadYields).unwrap();
        assert_eq!(d.withheld.len(), 2, "{:?}", d.withheld);
        assert!(d.withheld.iter().all(|w| w.reason.contains("unknown")));
        assert!(
            d.spec.is_some(),
            "J43 makes the main road yield: its window stays"
        );
    }
}
