//! Cutting windows out of a corridor ([`cut_windows`]): one window is a list of one.
//!
//! Every window spans an interval of the main road, `upstream_m` before its merge to `downstream_m` after it.
//! Windows are cut in driving order, each boundary recomputed on the graph the previous cuts left, so one
//! window alone is cut exactly as before several existed. Two windows whose intervals overlap by more than
//! [`SNAP_M`] are refused, the later one skipped, or both joined into one region ([`Overlap`]).

use super::fit::{Fit, FittedLength, Lengths, Part, fit_lengths, locate};
use super::{Boundary, SNAP_M, SourceShape, boundary_downstream, boundary_upstream, sum};
use crate::transform::{self, CorridorRoles, TransformError, pick_route::describe_junction};
use mapc_graph::{JunctionId, LaneGraph, RoadId};

/// One window asked for: its merge (any id `find_junction` takes), if not the source's, how much main road
/// before the merge it spans, and whether it may be cut shorter where the map has less ([`Fit`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WindowRequest {
    pub junction: String,
    pub upstream_m: Option<f64>,
    pub fit: Option<Fit>,
}

impl WindowRequest {
    pub fn at(junction: &str) -> WindowRequest {
        WindowRequest {
            junction: junction.to_string(),
            upstream_m: None,
            fit: None,
        }
    }

    /// The same window, fitted to what the map has.
    pub fn fitted(self, fit: Option<Fit>) -> WindowRequest {
        WindowRequest { fit, ..self }
    }
}

impl From<&str> for WindowRequest {
    fn from(junction: &str) -> WindowRequest {
        WindowRequest::at(junction)
    }
}

/// What to do with two windows whose main-road intervals overlap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overlap {
    /// An error naming both merges and the overlap (asked-for windows).
    Refuse,
    /// Keep the first along the corridor, skip the later one and say so (`--all`).
    SkipLater,
    /// One controlled region spanning both merges.
    Join,
}

/// One controlled region of a cut corridor: a window around one merge, or overlapping windows joined.
#[derive(Clone, Debug, PartialEq)]
pub struct CutRegion {
    /// Its merges, in driving order.
    pub merges: Vec<JunctionId>,
    /// Where each merge lies along the main road (m from the corridor's start).
    pub merge_at_m: Vec<f64>,
    /// Main road before the first merge, between the merges, after the last one.
    pub upstream_roads: Vec<RoadId>,
    pub between_roads: Vec<RoadId>,
    pub downstream_roads: Vec<RoadId>,
    /// Each merge's merging road inside the region, in driving order.
    pub merge_roads: Vec<Vec<RoadId>>,
    pub upstream_m: f64,
    /// Each merging road's length inside the region.
    pub merge_m: Vec<f64>,
    pub downstream_m: f64,
    /// Where each merge's merging-road traffic enters the corridor.
    pub merge_entries: Vec<RoadId>,
    /// The lengths `--fit` cut shorter than asked, by merge (empty without it).
    pub fitted: Vec<FittedLength>,
}

impl CutRegion {
    pub fn roads(&self) -> Vec<RoadId> {
        let mut r: Vec<RoadId> = self
            .upstream_roads
            .iter()
            .chain(&self.between_roads)
            .chain(self.merge_roads.iter().flatten())
            .chain(&self.downstream_roads)
            .copied()
            .collect();
        r.sort();
        r
    }
    /// The region's extent along the main road (m from the corridor's start).
    pub fn start_m(&self) -> f64 {
        self.merge_at_m[0] - self.upstream_m
    }
    pub fn end_m(&self) -> f64 {
        self.merge_at_m.last().unwrap() + self.downstream_m
    }
}

/// A corridor cut for several windows.
#[derive(Clone, Debug)]
pub struct WindowsCut {
    pub graph: LaneGraph,
    pub roles: CorridorRoles,
    /// The regions in driving order.
    pub regions: Vec<CutRegion>,
    /// Where main-road traffic enters.
    pub main_entry: RoadId,
    /// One line per boundary.
    pub notes: Vec<String>,
    /// Merges asked for but left out (with [`Overlap::SkipLater`]), and why.
    pub skipped: Vec<String>,
}

/// A merge located on the corridor before any cut, with the lengths of its window.
struct Located {
    junction: JunctionId,
    name: String,
    at_m: f64,
    lengths: Lengths,
    /// The upstream length asked for (the source's or `--upstream-m`) and the request's fit.
    asked_upstream_m: f64,
    fit: Option<Fit>,
    fitted: Vec<FittedLength>,
}

impl Located {
    fn start_m(&self) -> f64 {
        self.at_m - self.lengths.upstream_m
    }
    fn end_m(&self) -> f64 {
        self.at_m + self.lengths.downstream_m
    }
}

/// Cuts `chain` at boundary `b` (or notes the junction it falls on).
fn apply_boundary(
    g: &mut LaneGraph,
    what: &str,
    chain: &[RoadId],
    b: Boundary,
    notes: &mut Vec<String>,
) -> Result<(), TransformError> {
    match b {
        Boundary::Inside(k, offset) => {
            let (_, _, nj) = transform::cut_road(g, chain[k], offset)?;
            notes.push(format!(
                "{what}: cut road {} at {offset:.2} m from its start (new junction {nj})",
                chain[k]
            ));
        }
        Boundary::AtStartOf(k) => {
            let at = g.road(chain[k]).unwrap().from;
            notes.push(format!(
                "{what}: boundary at junction {}",
                describe_junction(g, at)
            ));
        }
        Boundary::AtEndOf(k) => {
            let at = g.road(chain[k]).unwrap().to;
            notes.push(format!(
                "{what}: boundary at junction {}",
                describe_junction(g, at)
            ));
        }
    }
    Ok(())
}

/// The boundaries of one region, cut on the current graph: upstream of its first merge, each merging road,
/// downstream of its last merge (in that order, so that a lone window is cut as it always was).
fn cut_region(
    g: &mut LaneGraph,
    merges: &[&Located],
    notes: &mut Vec<String>,
) -> Result<(), TransformError> {
    let prefix = |what: &str| {
        if merges.len() == 1 {
            what.to_string()
        } else {
            format!(
                "{what} ({})",
                merges
                    .iter()
                    .map(|m| m.junction.to_string())
                    .collect::<Vec<_>>()
                    .join("+")
            )
        }
    };
    let (first, last) = (merges[0], *merges.last().unwrap());
    let roles = CorridorRoles::of(g)?;
    let (i, feeder) = locate(g, &roles, first.junction)?;
    let before: Vec<RoadId> = roles.main[..i].to_vec();
    let b_up =
        boundary_upstream(g, &before, first.lengths.upstream_m).expect("checked before cutting");
    let b_merge =
        boundary_upstream(g, &feeder, first.lengths.merge_m).expect("checked before cutting");
    let (i_last, _) = locate(g, &roles, last.junction)?;
    let after: Vec<RoadId> = roles.main[i_last..].to_vec();
    let b_down =
        boundary_downstream(g, &after, last.lengths.downstream_m).expect("checked before cutting");
    apply_boundary(g, &prefix("upstream"), &before, b_up, notes)?;
    apply_boundary(g, &prefix("merging road"), &feeder, b_merge, notes)?;
    // The further merges' merging roads (a joined region), each on the graph as the previous cuts left it.
    for m in &merges[1..] {
        let roles = CorridorRoles::of(g)?;
        let (_, feeder) = locate(g, &roles, m.junction)?;
        let b = boundary_upstream(g, &feeder, m.lengths.merge_m).expect("checked before cutting");
        let what = format!("merging road into {}", m.junction);
        apply_boundary(g, &what, &feeder, b, notes)?;
    }
    apply_boundary(g, &prefix("downstream"), &after, b_down, notes)?;
    Ok(())
}

/// Roads at the end of `chain` (driving order) whose lengths add up to at most `limit` (+ [`SNAP_M`]).
fn take_back(g: &LaneGraph, chain: &[RoadId], limit: f64) -> Vec<RoadId> {
    let mut acc = 0.0;
    let mut out = Vec::new();
    for r in chain.iter().rev() {
        let len = g.road(*r).unwrap().length_m;
        if acc + len > limit + SNAP_M {
            break;
        }
        acc += len;
        out.insert(0, *r);
    }
    out
}

/// Roads at the start of `chain` whose lengths add up to at most `limit` (+ [`SNAP_M`]).
fn take_forward(g: &LaneGraph, chain: &[RoadId], limit: f64) -> Vec<RoadId> {
    let mut acc = 0.0;
    let mut out = Vec::new();
    for r in chain {
        let len = g.road(*r).unwrap().length_m;
        if acc + len > limit + SNAP_M {
            break;
        }
        acc += len;
        out.push(*r);
    }
    out
}

/// The roads of a region once every cut is made.
fn collect_region(g: &LaneGraph, roles: &CorridorRoles, merges: &[&Located]) -> CutRegion {
    let mut at = Vec::new();
    let mut merge_roads = Vec::new();
    let mut index = Vec::new();
    for m in merges {
        let (i, feeder) = locate(g, roles, m.junction).expect("located before cutting");
        at.push(sum(g, &roles.main[..i]));
        index.push(i);
        merge_roads.push((take_back(g, &feeder, m.lengths.merge_m), feeder[0]));
    }
    let (first, last) = (index[0], *index.last().unwrap());
    let upstream_roads = take_back(g, &roles.main[..first], merges[0].lengths.upstream_m);
    let between_roads = roles.main[first..last].to_vec();
    let downstream_m = merges.last().unwrap().lengths.downstream_m;
    let downstream_roads = take_forward(g, &roles.main[last..], downstream_m);
    CutRegion {
        merges: merges.iter().map(|m| m.junction).collect(),
        fitted: merges.iter().flat_map(|m| m.fitted.clone()).collect(),
        merge_at_m: at,
        upstream_m: sum(g, &upstream_roads),
        downstream_m: sum(g, &downstream_roads),
        merge_m: merge_roads.iter().map(|(r, _)| sum(g, r)).collect(),
        merge_entries: merge_roads.iter().map(|(_, e)| *e).collect(),
        merge_roads: merge_roads.into_iter().map(|(r, _)| r).collect(),
        upstream_roads,
        between_roads,
        downstream_roads,
    }
}

/// Groups windows (sorted along the corridor) into regions: one window each, or overlapping ones joined. A
/// window that overlaps the one before is refused, skipped or joined as `overlap` says, unless it asked for a
/// [`Fit`] (and is not joined): then it starts where the one before ends, if that leaves at least the floor.
fn group_windows(
    located: &mut [Located],
    overlap: Overlap,
    skipped: &mut Vec<String>,
) -> Result<Vec<Vec<usize>>, TransformError> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for k in 0..located.len() {
        let Some(group) = groups.last_mut() else {
            groups.push(vec![k]);
            continue;
        };
        let (prev, l) = (&located[*group.last().unwrap()], &located[k]);
        let gap_overlap = prev.end_m() - l.start_m();
        if gap_overlap <= SNAP_M {
            groups.push(vec![k]);
            continue;
        }
        // What is left of the main road between the window before and this merge.
        let room = l.at_m - prev.end_m();
        let fit = l.fit.filter(|_| overlap != Overlap::Join);
        if let Some(fit) = fit
            && room >= fit.floor_m(l.asked_upstream_m)
        {
            let reason = format!("the window at {} ends there", prev.name);
            let l = &mut located[k];
            l.fitted.retain(|f| f.part != Part::Upstream);
            l.fitted.insert(
                0,
                FittedLength {
                    junction: l.junction,
                    part: Part::Upstream,
                    asked_m: l.asked_upstream_m,
                    fitted_m: room,
                    reason,
                },
            );
            l.lengths.upstream_m = room;
            groups.push(vec![k]);
            continue;
        }
        let hint = match fit {
            Some(fit) if room > 0.0 => format!(
                "; --fit would leave it {room:.1} m, below its floor of {:.1} m",
                fit.floor_m(l.asked_upstream_m)
            ),
            None if room >= Fit::default().floor_m(l.asked_upstream_m) => format!(
                "; `--fit` starts the second where the first ends, {room:.1} m before its merge"
            ),
            _ => String::new(),
        };
        let message = format!(
            "the windows at {} and {} overlap by {gap_overlap:.1} m: the first ends {:.1} m along the main \
             road, the second starts at {:.1} m ({:.1} m before its merge){hint}",
            prev.name,
            l.name,
            prev.end_m(),
            l.start_m(),
            l.lengths.upstream_m
        );
        match overlap {
            Overlap::Refuse => return Err(TransformError::Cut(message)),
            Overlap::SkipLater => skipped.push(format!("{}: {message}", l.name)),
            Overlap::Join => group.push(k),
        }
    }
    Ok(groups)
}

/// Cut the windows of `requests` (each matched to `shape`, its upstream length possibly shortened, each
/// possibly fitted to what the map has) out of a corridor. Merges that do not fit are errors, or skipped with
/// [`Overlap::SkipLater`]; overlaps are handled as `overlap` says.
pub fn cut_windows(
    corridor: &LaneGraph,
    requests: &[WindowRequest],
    shape: &SourceShape,
    overlap: Overlap,
) -> Result<WindowsCut, TransformError> {
    let mut g = corridor.clone();
    let roles = CorridorRoles::of(&g)?;
    let mut located: Vec<Located> = Vec::new();
    let mut skipped = Vec::new();
    for r in requests {
        let j = g
            .find_junction(&r.junction)
            .map_err(|e| TransformError::NotACorridor(format!("--junction: {e}")))?;
        let name = describe_junction(&g, j);
        if located.iter().any(|l| l.junction == j) {
            return Err(TransformError::NotACorridor(format!(
                "{name} is asked for twice"
            )));
        }
        let up = r.upstream_m.unwrap_or(shape.upstream_m);
        if !(up.is_finite() && up > 0.0) {
            return Err(TransformError::Cut(format!(
                "{name}: the upstream length must be a positive number of metres, not {up}"
            )));
        }
        let (lengths, fitted) = match fit_lengths(&g, &roles, j, up, shape, r.fit) {
            Ok(fitted) => fitted,
            Err(e) if overlap == Overlap::SkipLater => {
                skipped.push(format!("{name}: {e}"));
                continue;
            }
            Err(e) => return Err(e),
        };
        let (i, _) = locate(&g, &roles, j)?;
        located.push(Located {
            junction: j,
            name,
            at_m: sum(&g, &roles.main[..i]),
            lengths,
            asked_upstream_m: up,
            fit: r.fit,
            fitted,
        });
    }
    if located.is_empty() {
        return Err(TransformError::Cut(format!(
            "no window fits on this corridor: {}",
            skipped.join("; ")
        )));
    }
    located.sort_by(|a, b| a.at_m.total_cmp(&b.at_m));
    let groups = group_windows(&mut located, overlap, &mut skipped)?;
    let groups: Vec<Vec<&Located>> = groups
        .iter()
        .map(|group| group.iter().map(|&k| &located[k]).collect())
        .collect();
    let mut notes = Vec::new();
    for group in &groups {
        cut_region(&mut g, group, &mut notes)?;
    }
    let problems = g.invariant_violations();
    if !problems.is_empty() {
        return Err(TransformError::Invariant {
            step: transform::CUT_AT.into(),
            violations: problems,
        });
    }
    // Read the roles again (cut pieces carry their road's role) and collect the roads within the boundaries.
    let roles = CorridorRoles::of(&g)?;
    let regions: Vec<CutRegion> = groups
        .iter()
        .map(|group| collect_region(&g, &roles, group))
        .collect();
    let pieces = mapc_graph::Topology::new(&g).component_count();
    if pieces != 1 {
        return Err(TransformError::Invariant {
            step: transform::CUT_AT.into(),
            violations: vec![format!("the cut corridor falls into {pieces} pieces")],
        });
    }
    Ok(WindowsCut {
        main_entry: roles.main[0],
        roles,
        graph: g,
        regions,
        notes,
        skipped,
    })
}
