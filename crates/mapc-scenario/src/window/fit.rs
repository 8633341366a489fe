//! Fitting a window to what the map has (`mapc window --fit`): a real merge rarely offers exactly the source's
//! lengths, and a ramp a few metres shorter than the Simple Merge's 200 m is as good a transfer target as one of
//! 200 m. With a [`Fit`], each of the three lengths (main road before the merge, merging road, main road after)
//! becomes what the map has wherever that is shorter than asked, down to `floor` times the length asked; below
//! that floor, or without a [`Fit`], the window is refused with the shortfall and what `--fit` would do.

use super::{SourceShape, boundary_downstream, boundary_upstream, sum};
use crate::transform::{CorridorRoles, TransformError, pick_route::describe_junction};
use mapc_graph::{JunctionId, LaneGraph, RoadId};
use serde::Serialize;

/// Windows may be cut shorter than asked where the map has less, down to `floor` times the length asked.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// The shortest a fitted length may be, as a fraction of the length asked (0 < floor <= 1).
    pub floor: f64,
}

impl Fit {
    /// `--fit` without `--fit-floor`: half of each length.
    pub const DEFAULT_FLOOR: f64 = 0.5;

    /// A fit down to `floor` of each length; refused unless 0 < floor <= 1.
    pub fn new(floor: f64) -> Result<Fit, TransformError> {
        if !(floor.is_finite() && floor > 0.0 && floor <= 1.0) {
            return Err(TransformError::Cut(format!(
                "--fit-floor must be a fraction of the source's length above 0 and at most 1, not {floor}"
            )));
        }
        Ok(Fit { floor })
    }

    /// The shortest length a fit accepts for a window asking `asked_m`.
    pub fn floor_m(&self, asked_m: f64) -> f64 {
        self.floor * asked_m
    }
}

impl Default for Fit {
    fn default() -> Fit {
        Fit {
            floor: Fit::DEFAULT_FLOOR,
        }
    }
}

/// Which of a window's three lengths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// The main road before the merge.
    Upstream,
    /// The merging road.
    MergingRoad,
    /// The main road after the merge.
    Downstream,
}

impl Part {
    pub fn name(self) -> &'static str {
        match self {
            Part::Upstream => "upstream",
            Part::MergingRoad => "merging road",
            Part::Downstream => "downstream",
        }
    }
}

/// One length a fit cut shorter than asked.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FittedLength {
    pub junction: JunctionId,
    pub part: Part,
    /// What the window asked for (the source's length, or `--upstream-m`).
    pub asked_m: f64,
    /// What it got.
    pub fitted_m: f64,
    /// Why no more: the map ends there, or the window before along the corridor does.
    pub reason: String,
}

impl FittedLength {
    pub fn short_by_m(&self) -> f64 {
        self.asked_m - self.fitted_m
    }
}

/// A window's three lengths (m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lengths {
    pub upstream_m: f64,
    pub merge_m: f64,
    pub downstream_m: f64,
}

/// Where merge `j` sits: the index of the main road leaving it and its merging road; errors list the merges.
pub(super) fn locate(
    g: &LaneGraph,
    roles: &CorridorRoles,
    j: JunctionId,
) -> Result<(usize, Vec<RoadId>), TransformError> {
    let name = describe_junction(g, j);
    let Some(i) = roles
        .main
        .iter()
        .position(|r| g.road(*r).unwrap().from == j)
        .filter(|i| *i > 0)
    else {
        return Err(TransformError::NotACorridor(format!(
            "{name} is not inside the corridor's main road; merges on this corridor: {}",
            super::merge_list(g, roles)
        )));
    };
    let feeders: Vec<&Vec<RoadId>> = roles
        .feeders
        .iter()
        .filter(|f| g.road(*f.last().unwrap()).unwrap().to == j)
        .collect();
    if feeders.len() != 1 {
        let kind = g.junction(j).unwrap().kind;
        return Err(TransformError::NotACorridor(format!(
            "{name} is a {kind:?} junction with {} merging roads, not a merge; merges on this corridor: {}",
            feeders.len(),
            super::merge_list(g, roles)
        )));
    }
    Ok((i, feeders[0].clone()))
}

/// The lengths the window of `j` gets (upstream `up` m asked, the shape's merging road and downstream): each
/// as asked where the map has it (to [`super::SNAP_M`]), else, with `fit`, what the map has if that is at least the
/// floor; the fitted ones are listed. Refusals name the shortfall and what `--fit` would do.
pub(super) fn fit_lengths(
    g: &LaneGraph,
    roles: &CorridorRoles,
    j: JunctionId,
    up: f64,
    shape: &SourceShape,
    fit: Option<Fit>,
) -> Result<(Lengths, Vec<FittedLength>), TransformError> {
    let (i, feeder) = locate(g, roles, j)?;
    let name = describe_junction(g, j);
    let (before, after) = (&roles.main[..i], &roles.main[i..]);
    let mut fitted = Vec::new();
    let mut one = |part: Part, what: &str, have: f64, asked: f64, fits: bool| {
        if fits {
            return Ok(asked);
        }
        let refuse = |hint: String| {
            TransformError::Cut(format!(
                "{what} {name} is {have:.1} m long; the window needs {asked:.1} m ({:.1} m short; {hint})",
                asked - have
            ))
        };
        match fit {
            Some(f) if have >= f.floor_m(asked) => {
                fitted.push(FittedLength {
                    junction: j,
                    part,
                    asked_m: asked,
                    fitted_m: have,
                    reason: "the map has no more".into(),
                });
                Ok(have)
            }
            Some(f) => Err(refuse(format!(
                "below the --fit floor of {:.1} m, {} of it; `--fit-floor {}` would cut it",
                f.floor_m(asked),
                f.floor,
                floor_reaching(have, asked)
            ))),
            None => {
                let down_to = Fit::default().floor_m(asked);
                Err(refuse(if have >= down_to {
                    format!("`--fit` cuts what the map has down to {down_to:.1} m")
                } else {
                    format!(
                        "`--fit` cuts what the map has down to {down_to:.1} m, `--fit-floor {}` down to {have:.1} m",
                        floor_reaching(have, asked)
                    )
                }))
            }
        }
    };
    let upstream_m = one(
        Part::Upstream,
        "the main road before",
        sum(g, before),
        up,
        boundary_upstream(g, before, up).is_some(),
    )?;
    let merge_m = one(
        Part::MergingRoad,
        "the merging road into",
        sum(g, &feeder),
        shape.merge_m,
        boundary_upstream(g, &feeder, shape.merge_m).is_some(),
    )?;
    let downstream_m = one(
        Part::Downstream,
        "the main road after",
        sum(g, after),
        shape.downstream_m,
        boundary_downstream(g, after, shape.downstream_m).is_some(),
    )?;
    Ok((
        Lengths {
            upstream_m,
            merge_m,
            downstream_m,
        },
        fitted,
    ))
}

/// The largest `--fit-floor` (two decimals, rounded down) that accepts `have` m where `asked` m were asked.
fn floor_reaching(have: f64, asked: f64) -> String {
    let f = (have / asked * 100.0).floor() / 100.0;
    format!("{:.2}", f.max(0.01))
}
