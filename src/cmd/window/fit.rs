//! `mapc window`'s report of a window's lengths against its source's, and what lengths other than the source's do
//! to what a transferred policy sees: its observation is scaled by constants kept from training (V, L and, for a
//! distributed policy, the distances to the merge), never by the window's lengths, so a fitted window is seen at
//! the same scale; what changes is the controlled region (where control starts, how many AVs fit in it) and, when
//! the corridor itself is shorter than the source before the merge, how far ahead a distance can read.

use mapc_rl::env::distributed::SIMPLE_MERGE_DIST_NORM;
use mapc_rl::env::merge::SIMPLE_MERGE_NORM;
use mapc_scenario::window::{FittedLength, Lengths, SourceShape};
use serde_json::{Value, json};

/// A window as the report needs it.
pub struct WindowLengths<'a> {
    pub lengths: Lengths,
    /// Main road between the merges of a joined region (0 for one merge).
    pub between_m: f64,
    /// Main road on the whole corridor before the (first) merge.
    pub corridor_before_m: f64,
    pub fitted: &'a [FittedLength],
}

fn region_m(l: &Lengths, between_m: f64) -> f64 {
    l.upstream_m + l.merge_m + l.downstream_m + between_m
}

/// The observation's side of the report (`--json`'s `observation`).
pub fn observation(shape: &SourceShape, w: &WindowLengths) -> Value {
    let source = Lengths {
        upstream_m: shape.upstream_m,
        merge_m: shape.merge_m,
        downstream_m: shape.downstream_m,
    };
    let (region, source_region) = (region_m(&w.lengths, w.between_m), region_m(&source, 0.0));
    let dist = SIMPLE_MERGE_DIST_NORM.junction;
    json!({
        "rescaled": false,
        "centralized_norm": {
            "max_speed_m_s": SIMPLE_MERGE_NORM.max_speed,
            "length_m": SIMPLE_MERGE_NORM.length,
            "from": "the policy's checkpoint (these: a policy trained on the Simple Merge)",
        },
        "control_region_m": region,
        "source_control_region_m": source_region,
        "control_region_ratio": region / source_region,
        "controlled_from_m_before_merge": w.lengths.upstream_m,
        "source_controlled_from_m_before_merge": source.upstream_m,
        "distributed_merge_distance_norm_m": dist,
        "corridor_before_merge_m": w.corridor_before_m,
        "max_merge_distance_feature": (w.corridor_before_m / dist).min(1.0),
    })
}

/// The report's lines: each length against the source's, then (when one differs) the observation's side.
pub fn lines(shape: &SourceShape, matched_to: &str, w: &WindowLengths) -> Vec<String> {
    let l = &w.lengths;
    let part = |name: &str, have: f64, source: f64, fitted: bool| {
        format!(
            "{name} {have:.1} m of {source:.1} m ({:.2}{})",
            have / source,
            if fitted { ", fitted" } else { "" }
        )
    };
    let is_fitted = |p: mapc_scenario::window::Part| w.fitted.iter().any(|f| f.part == p);
    use mapc_scenario::window::Part;
    let mut out = vec![format!(
        "against {matched_to}'s: {}, {}, {}",
        part(
            "upstream",
            l.upstream_m,
            shape.upstream_m,
            is_fitted(Part::Upstream)
        ),
        part(
            "merging road",
            l.merge_m,
            shape.merge_m,
            is_fitted(Part::MergingRoad)
        ),
        part(
            "downstream",
            l.downstream_m,
            shape.downstream_m,
            is_fitted(Part::Downstream)
        ),
    )];
    for f in w.fitted {
        out.push(format!(
            "fitted (--fit): {} {:.1} m short, {}",
            f.part.name(),
            f.short_by_m(),
            f.reason
        ));
    }
    let same = |a: f64, b: f64| (a - b).abs() <= mapc_scenario::window::SNAP_M;
    if same(l.upstream_m, shape.upstream_m)
        && same(l.merge_m, shape.merge_m)
        && same(l.downstream_m, shape.downstream_m)
    {
        return out;
    }
    let obs = observation(shape, w);
    out.push(format!(
        "observation: not rescaled: a policy divides speeds by its V and gaps by its L, kept from training \
         ({} m/s and {} m for one trained on the Simple Merge), not by the window's lengths; the controlled region \
         is {:.1} m of road against {:.1} m ({:.2}): AVs are controlled from {:.1} m before the merge instead of \
         {:.1} m{}",
        SIMPLE_MERGE_NORM.max_speed,
        SIMPLE_MERGE_NORM.length,
        obs["control_region_m"].as_f64().unwrap(),
        obs["source_control_region_m"].as_f64().unwrap(),
        obs["control_region_ratio"].as_f64().unwrap(),
        l.upstream_m,
        shape.upstream_m,
        if obs["control_region_ratio"].as_f64().unwrap() < 1.0 {
            ", and fewer fit in it at once"
        } else {
            ""
        }
    ));
    if w.corridor_before_m < SIMPLE_MERGE_DIST_NORM.junction {
        out.push(format!(
            "distributed policies divide the distance to the merge by {} m: with {:.1} m of corridor before this \
             merge it reads at most {:.2}",
            SIMPLE_MERGE_DIST_NORM.junction,
            w.corridor_before_m,
            obs["max_merge_distance_feature"].as_f64().unwrap()
        ));
    }
    out
}
