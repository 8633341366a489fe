//! `trim_feeders`: with `--feeder-length`, a merging road longer than that is cut that far upstream of its merge
//! and the part before the cut removed; the cut becomes where its traffic enters.

use super::{Corridor, SimplifyOptions, TransformError, cut_road, mark, remove_roads};
use mapc_graph::RoadId;
use std::collections::HashSet;

pub const NAME: &str = "trim_feeders";

pub fn apply(c: &mut Corridor, opts: &SimplifyOptions) -> Result<String, TransformError> {
    let Some(limit) = opts.feeder_length_m else {
        return Ok("no --feeder-length".into());
    };
    let mut trimmed = 0;
    for i in 0..c.feeders.len() {
        let total = Corridor::chain_length_m(&c.graph, &c.feeders[i]);
        if total <= limit {
            continue;
        }
        // Walk back from the merge to the road holding the point `limit` upstream of it.
        let mut from_merge = 0.0;
        let mut cut: Option<(usize, f64)> = None;
        for (k, rid) in c.feeders[i].iter().enumerate().rev() {
            let len = c.graph.road(*rid).unwrap().length_m;
            if from_merge + len >= limit {
                cut = Some((k, len - (limit - from_merge)));
                break;
            }
            from_merge += len;
            if k > 0 {
                let (prev, next) = (c.feeders[i][k - 1], *rid);
                from_merge += c
                    .graph
                    .connections
                    .iter()
                    .find(|x| x.from_road == prev && x.to_road == next)
                    .map_or(0.0, |x| x.via_length_m);
            }
        }
        let Some((k, at_m)) = cut else { continue };
        let rid = c.feeders[i][k];
        let mut gone: HashSet<RoadId> = c.feeders[i][..k].iter().copied().collect();
        let keep_from = if at_m > 1e-9 {
            let (first, second, _) = cut_road(&mut c.graph, rid, at_m)?;
            gone.insert(first);
            mark(&mut c.graph.road_mut(second).unwrap().provenance, NAME);
            second
        } else {
            rid
        };
        let mut chain = vec![keep_from];
        chain.extend_from_slice(&c.feeders[i][k + 1..]);
        remove_roads(&mut c.graph, &gone);
        c.feeders[i] = chain;
        trimmed += 1;
    }
    Ok(format!("{trimmed} merging roads trimmed to {limit} m"))
}
