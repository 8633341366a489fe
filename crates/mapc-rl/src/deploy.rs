//! Where a policy is deployed. A policy learned in one regime (the Simple Merge's: the main road yields to the
//! ramp) can hold the main road back where nothing needs it (docs/results.md, "A policy for any merge"), so a
//! policy may carry the regime it is meant for: windows whose merge is not in it are left to the human drivers,
//! their AVs driving as humans do. The right of way is read from the network, before any run.

use std::fmt;
use std::str::FromStr;

use mapc_graph::{JunctionId, RoadId};
use mapc_sim::{MergePriority, SimSpec, merge_priorities};
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
}

impl Deploy {
    pub fn name(self) -> &'static str {
        match self {
            Deploy::Everywhere => "everywhere",
            Deploy::MainRoadYields => "main-road-yields",
        }
    }

    fn admits(self, merge: &MergePriority) -> bool {
        match self {
            Deploy::Everywhere => true,
            Deploy::MainRoadYields => merge.main_road_yields(),
        }
    }
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
            _ => Err(format!(
                "unknown deployment rule `{s}` (expected everywhere or main-road-yields)"
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
    if rule == Deploy::Everywhere {
        return deploy(spec, rule);
    }
    let merges = merge_priorities(spec).map_err(|e| RlError::Config(e.to_string()))?;
    let graph = &spec.graph;
    let roads: Vec<RoadId> = match &spec.control_region {
        Some(region) => region.clone(),
        None => graph.roads.iter().map(|r| r.id).collect(),
    };
    let next_merge = |mut road: RoadId| -> Option<&MergePriority> {
        // a bound on the walk, for safety against a cycle
        for _ in 0..graph.roads.len() {
            let to = graph.road(road)?.to;
            if let Some(m) = merges.iter().find(|m| m.junction == to) {
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
        match next_merge(road) {
            Some(m) if rule.admits(m) => region.push(road),
            Some(m) if !withheld.iter().any(|w| w.window == m.name) => withheld.push(Withheld {
                window: m.name.clone(),
                reason: format!("{} at {}", m.label(), m.name),
            }),
            _ => {}
        }
    }
    Ok(restricted(spec, region, withheld))
}

/// The windows of `spec` that `rule` admits. A scenario with one controlled region is one window made of its
/// measured merges.
pub fn deploy(spec: &SimSpec, rule: Deploy) -> Result<Deployment, RlError> {
    if rule == Deploy::Everywhere {
        return Ok(Deployment {
            spec: Some(spec.clone()),
            withheld: Vec::new(),
        });
    }
    let merges = merge_priorities(spec).map_err(|e| RlError::Config(e.to_string()))?;
    // why `rule` refuses a window made of `junctions`: a merge outside the rule, or one whose right of way is not
    // known (the scenario does not measure it), or no merge at all
    let refusal = |junctions: &[JunctionId]| -> Option<String> {
        if junctions.is_empty() {
            return Some("it has no measured merge, so its right of way is unknown".into());
        }
        junctions
            .iter()
            .find_map(|j| match merges.iter().find(|m| m.junction == *j) {
                Some(m) if rule.admits(m) => None,
                Some(m) => Some(format!("{} at {}", m.label(), m.name)),
                None => Some(format!(
                    "the right of way at {j} is unknown (not a measured merge)"
                )),
            })
    };
    if spec.control_windows.is_empty() {
        let region: Vec<JunctionId> = merges.iter().map(|m| m.junction).collect();
        return Ok(match refusal(&region) {
            Some(reason) => Deployment {
                spec: None,
                withheld: vec![Withheld {
                    window: merges
                        .first()
                        .map_or_else(|| "the control region".into(), |m| m.name.clone()),
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
