//! ALINEA ramp metering (Papageorgiou, Hadj-Salem and Blosseville, 1991), the feedback law real freeways run:
//! every control interval the metering rate moves toward keeping the occupancy measured just downstream of the
//! merge at a set-point,
//!
//! ```text
//! r(k) = clamp( r(k-1) + K_R * (o_set - o_out(k)),  r_min, r_max )      [veh/h, occupancies in %]
//! ```
//!
//! and the ramp's traffic light lets vehicles pass at that rate: each cycle is a fixed green (one vehicle per lane)
//! and a red that makes the cycle last `3600 / r` seconds. Rates are per metered lane (per link of the light), so
//! one meter across four lanes passes up to four vehicles a cycle. The control interval is the downstream
//! detectors' own (a new `r` each time all of them have closed an interval); `o_out` is the mean of their
//! occupancies.

use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::sim::Simulation;
use crate::spec::SimSpec;
use mapc_graph::{LaneGraph, RoadId, SignalPhase};

/// ALINEA's settings. Defaults: the classic gain of 70 veh/h per per cent of occupancy, a set-point of 20 %
/// (about the critical occupancy of a freeway lane), rates between 200 and 1 800 veh/h, 2 s of green a cycle.
#[derive(Clone, Debug, PartialEq)]
pub struct AlineaConfig {
    /// The metered light (SUMO id); `None`: the network's only light.
    pub light: Option<String>,
    /// Detectors measuring downstream occupancy; empty: on the first road downstream of the meter that has
    /// detectors, the furthest one on each lane.
    pub detectors: Vec<String>,
    /// Target occupancy, a fraction in (0, 1).
    pub setpoint: f64,
    /// K_R: veh/h of rate (per metered lane) per percentage point of occupancy error.
    pub gain_veh_h: f64,
    /// Bounds of the rate, per metered lane.
    pub min_rate_veh_h: f64,
    pub max_rate_veh_h: f64,
    /// Green time of each cycle (s).
    pub green_s: f64,
}

impl Default for AlineaConfig {
    fn default() -> Self {
        AlineaConfig {
            light: None,
            detectors: Vec::new(),
            setpoint: 0.20,
            gain_veh_h: 70.0,
            min_rate_veh_h: 200.0,
            max_rate_veh_h: 1800.0,
            green_s: 2.0,
        }
    }
}

/// The next metering rate from the last one and the measured occupancy (%): ALINEA's law.
pub fn next_rate(cfg: &AlineaConfig, rate_veh_h: f64, occupancy_pct: f64) -> f64 {
    (rate_veh_h + cfg.gain_veh_h * (100.0 * cfg.setpoint - occupancy_pct))
        .clamp(cfg.min_rate_veh_h, cfg.max_rate_veh_h)
}

/// The light's program for `rate`: all its links green for `green_s`, then red for the rest of a `3600 / rate` s
/// cycle (green throughout when the cycle is no longer than the green).
pub fn meter_phases(cfg: &AlineaConfig, links: usize, rate_veh_h: f64) -> Vec<SignalPhase> {
    let cycle = 3600.0 / rate_veh_h;
    let green = SignalPhase {
        duration_s: cfg.green_s,
        state: "G".repeat(links),
    };
    if cycle <= cfg.green_s + 1e-9 {
        return vec![green];
    }
    vec![
        green,
        SignalPhase {
            duration_s: cycle - cfg.green_s,
            state: "r".repeat(links),
        },
    ]
}

/// ALINEA attached to one run.
#[derive(Clone, Debug)]
pub struct Alinea {
    cfg: AlineaConfig,
    light: usize,
    links: usize,
    /// Indices of its detectors in the spec.
    detectors: Vec<usize>,
    rate_veh_h: f64,
    /// Intervals of the simulation already read.
    seen_intervals: usize,
    /// Per detector, its latest occupancy not yet used.
    fresh: Vec<Option<f64>>,
    /// The rates it set, in order (for reports and tests).
    pub rates: Vec<f64>,
}

impl Alinea {
    /// Check `cfg` against `spec` (light, detectors, ranges) and find its defaults.
    pub fn new(spec: &SimSpec, cfg: &AlineaConfig) -> Result<Alinea, SimError> {
        let bad = |m: String| SimError::Spec(format!("ALINEA: {m}"));
        if !(cfg.setpoint > 0.0 && cfg.setpoint < 1.0) {
            return Err(bad(format!("set-point {} is not in (0, 1)", cfg.setpoint)));
        }
        if !(cfg.gain_veh_h > 0.0 && cfg.gain_veh_h.is_finite()) {
            return Err(bad(format!(
                "gain {} veh/h is not positive",
                cfg.gain_veh_h
            )));
        }
        if !(cfg.min_rate_veh_h > 0.0
            && cfg.min_rate_veh_h <= cfg.max_rate_veh_h
            && cfg.max_rate_veh_h.is_finite())
        {
            return Err(bad(format!(
                "rates {}..{} veh/h are not a positive range",
                cfg.min_rate_veh_h, cfg.max_rate_veh_h
            )));
        }
        if !(cfg.green_s > 0.0 && cfg.green_s.is_finite()) {
            return Err(bad(format!("green {} s is not positive", cfg.green_s)));
        }
        let lights = &spec.graph.lights;
        let light = match &cfg.light {
            Some(id) => lights.iter().position(|l| l.id == *id).ok_or_else(|| {
                bad(format!(
                    "the network has no traffic light `{id}` (it has: {})",
                    names(lights.iter().map(|l| l.id.as_str()))
                ))
            })?,
            None if lights.len() == 1 => 0,
            None if lights.is_empty() => {
                return Err(bad("the network has no traffic light to meter".into()));
            }
            None => {
                return Err(bad(format!(
                    "name the metered light (the network has {}: {})",
                    lights.len(),
                    names(lights.iter().map(|l| l.id.as_str()))
                )));
            }
        };
        let links = lights[light].phases.first().map_or(0, |p| p.state.len());
        let detectors = if cfg.detectors.is_empty() {
            downstream_detectors(spec, &lights[light].id).ok_or_else(|| {
                bad(format!(
                    "no detector downstream of light `{}`: name them",
                    lights[light].id
                ))
            })?
        } else {
            cfg.detectors
                .iter()
                .map(|id| {
                    spec.detectors
                        .iter()
                        .position(|d| d.id == *id)
                        .ok_or_else(|| {
                            bad(format!(
                                "no detector `{id}` (the scenario has: {})",
                                names(spec.detectors.iter().map(|d| d.id.as_str()))
                            ))
                        })
                })
                .collect::<Result<_, _>>()?
        };
        Ok(Alinea {
            cfg: cfg.clone(),
            light,
            links,
            fresh: vec![None; detectors.len()],
            detectors,
            // it starts unrestricted, as a meter switched on in free flow
            rate_veh_h: cfg.max_rate_veh_h,
            seen_intervals: 0,
            rates: Vec::new(),
        })
    }

    /// The detectors it reads (spec indices).
    pub fn detectors(&self) -> &[usize] {
        &self.detectors
    }

    /// Put the light on its first program.
    pub fn start(&mut self, sim: &mut Simulation) -> Result<(), SimError> {
        let phases = meter_phases(&self.cfg, self.links, self.rate_veh_h);
        sim.set_light_phases(self.light, phases)
    }

    /// After a step: once each of its detectors has closed a new interval, a new rate and program.
    pub fn after_step(&mut self, sim: &mut Simulation) -> Result<(), SimError> {
        let intervals = sim.detector_intervals();
        for i in &intervals[self.seen_intervals..] {
            if let Some(k) = self.detectors.iter().position(|&d| d == i.detector) {
                self.fresh[k] = Some(i.occupancy_pct);
            }
        }
        self.seen_intervals = intervals.len();
        if self.fresh.iter().all(Option::is_some) {
            let occupancy = self.fresh.iter().flatten().sum::<f64>() / self.fresh.len() as f64;
            self.fresh.iter_mut().for_each(|f| *f = None);
            self.rate_veh_h = next_rate(&self.cfg, self.rate_veh_h, occupancy);
            self.rates.push(self.rate_veh_h);
            let phases = meter_phases(&self.cfg, self.links, self.rate_veh_h);
            sim.set_light_phases(self.light, phases)?;
        }
        Ok(())
    }
}

fn names<'a>(ids: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = ids.collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

/// Past the merge the metered ramp joins or the lane drop downstream of the meter (the first road downstream of
/// `light`'s links that more than one road leads into, or that has fewer lanes than a road leading into it, and the
/// roads after it), the first road with detectors: the furthest detector of each lane.
fn downstream_detectors(spec: &SimSpec, light: &str) -> Option<Vec<usize>> {
    let g: &LaneGraph = &spec.graph;
    let lanes = |road: RoadId| g.road(road).map_or(0, |r| r.lanes.len());
    let is_merge_exit = |road: RoadId| {
        let mut from: Vec<RoadId> = g
            .connections
            .iter()
            .filter(|c| c.to_road == road)
            .map(|c| c.from_road)
            .collect();
        from.sort();
        from.dedup();
        from.len() > 1 || from.iter().any(|&f| lanes(f) > lanes(road))
    };
    // (road, past the merge)
    let mut frontier: Vec<(RoadId, bool)> = g
        .connections
        .iter()
        .filter(|c| c.signal.as_ref().is_some_and(|s| s.light == light))
        .map(|c| (c.to_road, is_merge_exit(c.to_road)))
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    while !frontier.is_empty() {
        frontier.sort();
        frontier.dedup();
        for &(road, _) in frontier.iter().filter(|f| f.1) {
            let mut best: Vec<(u8, f64, usize)> = Vec::new();
            for (i, d) in spec
                .detectors
                .iter()
                .enumerate()
                .filter(|(_, d)| d.road == road)
            {
                match best.iter_mut().find(|b| b.0 == d.lane) {
                    Some(b) if b.1 < d.pos_m => *b = (d.lane, d.pos_m, i),
                    Some(_) => {}
                    None => best.push((d.lane, d.pos_m, i)),
                }
            }
            if !best.is_empty() {
                best.sort_by_key(|b| b.0);
                return Some(best.into_iter().map(|b| b.2).collect());
            }
        }
        seen.extend(frontier.iter().map(|f| f.0));
        frontier = frontier
            .iter()
            .flat_map(|&(r, past)| {
                g.connections_from(r)
                    .map(move |c| (c.to_road, past || is_merge_exit(c.to_road)))
            })
            .filter(|(r, _)| !seen.contains(r))
            .collect();
    }
    None
}

/// One run of `spec` with ALINEA metering its light; the rates it set alongside.
pub fn run_with_alinea(
    spec: &SimSpec,
    seed: u64,
    cfg: &AlineaConfig,
) -> Result<(RunMetrics, Vec<f64>), SimError> {
    let mut alinea = Alinea::new(spec, cfg)?;
    let mut sim = Simulation::from_spec(spec.clone(), seed)?;
    sim.set_invariant_checks(false);
    alinea.start(&mut sim)?;
    while !sim.is_done() {
        sim.step()?;
        alinea.after_step(&mut sim)?;
    }
    Ok((sim.metrics(), alinea.rates))
}

/// [`run_with_alinea`] writing its trace as [`crate::trace_run`] writes the humans' (the same frames and rows;
/// a simulation error comes back as an I/O error of kind `Other` carrying its message).
pub fn trace_with_alinea(
    spec: &SimSpec,
    seed: u64,
    cfg: &AlineaConfig,
    out: &mut impl std::io::Write,
) -> std::io::Result<crate::TracedRun> {
    let alinea = std::cell::RefCell::new(Alinea::new(spec, cfg).map_err(std::io::Error::other)?);
    crate::runs::trace::trace_run_with(
        spec,
        seed,
        out,
        |sim| alinea.borrow_mut().start(sim),
        |sim| alinea.borrow_mut().after_step(sim),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worked by hand: at 1 000 veh/h with 25 % measured against a 20 % set-point, K_R = 70 takes
    /// 70 x 5 = 350 veh/h off: 650 veh/h, a 3600 / 650 = 5.538 s cycle of 2 s green and 3.538 s red.
    #[test]
    fn the_law_and_the_light_worked_by_hand() {
        let cfg = AlineaConfig::default();
        let r = next_rate(&cfg, 1000.0, 25.0);
        assert!((r - 650.0).abs() < 1e-9);
        let p = meter_phases(&cfg, 1, r);
        assert_eq!(p.len(), 2);
        assert_eq!((p[0].state.as_str(), p[0].duration_s), ("G", 2.0));
        assert_eq!(p[1].state, "r");
        assert!((p[1].duration_s - (3600.0 / 650.0 - 2.0)).abs() < 1e-9);
        // below the set-point the rate rises, up to its bound; above, it falls to its floor
        assert_eq!(next_rate(&cfg, 1700.0, 5.0), 1800.0);
        assert_eq!(next_rate(&cfg, 300.0, 60.0), 200.0);
        // at the highest rate the cycle is the green alone: always green
        let always = meter_phases(&cfg, 2, 1800.0);
        assert_eq!(always.len(), 1);
        assert_eq!(always[0].state, "GG");
    }
}
