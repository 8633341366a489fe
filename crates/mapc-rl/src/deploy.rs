//! Where a policy is deployed. A policy learned in one regime (the Simple Merge's: the main road yields to the
//! ramp) can hold the main road back where nothing needs it (docs/results.md, "A policy for any merge"), so a
//! policy may carry the regime it is meant for: windows whose merge is not in it are left to the human drivers,
//! their AVs driving as humans do. The right of way is read from the network, before any run.

use std::fmt;
use std::str::FromStr;

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
    /// The window's merge as the scenario names it.
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
    let refusal = |mut merges: std::slice::Iter<'_, MergePriority>,
                   junctions: Option<&[mapc_graph::JunctionId]>| {
        merges
            .find(|m| junctions.is_none_or(|js| js.contains(&m.junction)) && !rule.admits(m))
            .map(|m| format!("{} at {}", m.label(), m.name))
    };
    if spec.control_windows.is_empty() {
        return Ok(match refusal(merges.iter(), None) {
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
        match refusal(merges.iter(), Some(&w.merges)) {
            Some(reason) => withheld.push(Withheld {
                window: w.name.clone(),
                reason,
            }),
            None => region.extend(w.roads.iter().copied()),
        }
    }
    if region.is_empty() {
        return Ok(Deployment {
            spec: None,
            withheld,
        });
    }
    region.sort();
    region.dedup();
    let mut kept = spec.clone();
    kept.control_region = Some(region);
    Ok(Deployment {
        spec: Some(kept),
        withheld,
    })
}
