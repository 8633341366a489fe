//! Several control windows on one corridor (a scenario with `[[control.windows]]`): each window keeps its own
//! FIFO of up to `N_AV` AVs and builds its observation exactly as the single-window environment
//! ([`super::merge::MergeEnv`]) does; one policy acts on every window's observation (zero-shot). An AV is
//! controlled by the window it is in and, once it has left that window, never again by it. The environment also
//! counts the flow past every window's merge.

use mapc_graph::{JunctionId, RoadId};
use mapc_sim::{SimSpec, Simulation, VehicleId};

use super::merge::MergeEnvConfig;
use super::obs::{AvView, ControlQueue, centralized_obs};
use crate::error::RlError;
use crate::rollout::EpisodeMetrics;

/// One window's state in an episode.
#[derive(Clone, Debug)]
struct Window {
    /// Its roads, sorted.
    roads: Vec<RoadId>,
    /// Its roads that lead out of it: a vehicle inside the junction at their end has left the window.
    exits: Vec<RoadId>,
    queue: ControlQueue,
    controlled: Vec<VehicleId>,
}

impl Window {
    fn contains(&self, road: RoadId, in_junction: bool) -> bool {
        self.roads.binary_search(&road).is_ok()
            && !(in_junction && self.exits.binary_search(&road).is_ok())
    }
}

/// Counts the vehicles that pass merges (that enter the road leaving each merge junction), from the end of
/// the warm-up on.
#[derive(Clone, Debug)]
pub struct MergeFlowCounter {
    /// The road leaving each merge.
    roads_after: Vec<RoadId>,
    counts: Vec<u64>,
    /// Each vehicle's road after the last step (`None`: not yet seen on a road).
    last_road: Vec<Option<RoadId>>,
    horizon_s: f64,
}

impl MergeFlowCounter {
    /// A counter for `merges` of `spec`'s graph.
    pub fn new(spec: &SimSpec, merges: &[JunctionId]) -> Result<MergeFlowCounter, RlError> {
        let roads_after = merges
            .iter()
            .map(|&j| {
                spec.graph
                    .junction(j)
                    .and_then(|jn| jn.outgoing.first().copied())
                    .ok_or_else(|| {
                        super::scenario_error(
                            spec,
                            format!("window merge {j} has no road after it"),
                        )
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(MergeFlowCounter {
            counts: vec![0; roads_after.len()],
            roads_after,
            last_road: Vec::new(),
            horizon_s: spec.horizon_steps as f64 * spec.step_s,
        })
    }

    /// Every window's merges of `spec`, in window order.
    pub fn merges_of(spec: &SimSpec) -> Vec<JunctionId> {
        spec.control_windows
            .iter()
            .flat_map(|w| w.merges.iter().copied())
            .collect()
    }

    /// Starts counting on a new episode's simulation (the vehicles already placed are not counted).
    pub fn reset(&mut self, sim: &Simulation) {
        self.counts.iter_mut().for_each(|c| *c = 0);
        self.last_road.clear();
        self.update(sim, false);
    }

    /// Notes where every vehicle is after a step; `counted`: the step was one the metrics count.
    pub fn update(&mut self, sim: &Simulation, counted: bool) {
        self.last_road.resize(sim.vehicle_count(), None);
        for id in sim.active_ids() {
            let Some(v) = sim.vehicle(id) else { continue };
            if v.in_junction {
                continue;
            }
            let before = self.last_road[id as usize].replace(v.road);
            if counted && before != Some(v.road) {
                for (k, r) in self.roads_after.iter().enumerate() {
                    if *r == v.road {
                        self.counts[k] += 1;
                    }
                }
            }
        }
    }

    /// Vehicles past each merge per hour of the horizon.
    pub fn flows_veh_h(&self) -> Vec<f64> {
        self.counts
            .iter()
            .map(|&c| 3600.0 * c as f64 / self.horizon_s.max(f64::MIN_POSITIVE))
            .collect()
    }
}

/// An episode's figures with the flow past every window's merge (veh/h, in [`MergeFlowCounter::merges_of`]'s
/// order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WindowsMetrics {
    pub metrics: EpisodeMetrics,
    pub merge_flows: Vec<f64>,
}

/// The centralized environment over every window of a several-window scenario.
pub struct WindowsEnv {
    spec: SimSpec,
    cfg: MergeEnvConfig,
    sim: Option<Simulation>,
    windows: Vec<Window>,
    counter: MergeFlowCounter,
    obs: Vec<Vec<f32>>,
}

impl WindowsEnv {
    /// An environment over the windows of `spec` (at least one).
    pub fn new(spec: SimSpec, cfg: MergeEnvConfig) -> Result<WindowsEnv, RlError> {
        super::validate_spec(&spec)?;
        if cfg.n_av == 0 {
            return Err(RlError::Config("N_AV must be at least 1".into()));
        }
        if spec.control_windows.is_empty() {
            return Err(super::scenario_error(
                &spec,
                "the scenario has no `[[control.windows]]`",
            ));
        }
        let g = &spec.graph;
        let windows = spec
            .control_windows
            .iter()
            .map(|w| {
                let mut roads = w.roads.clone();
                roads.sort();
                let mut exits: Vec<RoadId> = roads
                    .iter()
                    .copied()
                    .filter(|&r| {
                        let to = g.road(r).map(|road| road.to);
                        to.and_then(|j| g.junction(j)).is_some_and(|j| {
                            j.outgoing.iter().any(|o| roads.binary_search(o).is_err())
                        })
                    })
                    .collect();
                exits.sort();
                Window {
                    roads,
                    exits,
                    queue: ControlQueue::default(),
                    controlled: Vec::new(),
                }
            })
            .collect();
        let counter = MergeFlowCounter::new(&spec, &MergeFlowCounter::merges_of(&spec))?;
        Ok(WindowsEnv {
            spec,
            cfg,
            sim: None,
            windows,
            counter,
            obs: Vec::new(),
        })
    }

    pub fn horizon(&self) -> usize {
        self.spec.horizon_steps as usize
    }

    pub fn window_count(&self) -> usize {
        self.windows.len()
    }

    /// Starts an episode; returns every window's observation.
    pub fn reset(&mut self, seed: u64) -> Result<&[Vec<f32>], RlError> {
        let sim = super::episode_simulation(&self.spec, seed)?;
        self.counter.reset(&sim);
        self.sim = Some(sim);
        for w in &mut self.windows {
            w.queue.clear();
            w.controlled.clear();
        }
        self.observe();
        Ok(&self.obs)
    }

    /// Each window's controlled AVs (FIFO by entry into the network, as the single-window environment orders
    /// them) and its observation.
    fn observe(&mut self) {
        let sim = self.sim.as_ref().expect("reset before observe");
        let mut present: Vec<Vec<(u64, VehicleId)>> = vec![Vec::new(); self.windows.len()];
        for id in sim.active_ids() {
            let Some(v) = sim.vehicle(id) else { continue };
            if !(v.controlled && sim.in_control_region(id)) {
                continue;
            }
            if let Some(k) = self
                .windows
                .iter()
                .position(|w| w.contains(v.road, v.in_junction))
            {
                present[k].push((v.entry_order, id));
            }
        }
        let (n_av, norm) = (self.cfg.n_av, self.cfg.norm);
        self.obs.resize(self.windows.len(), Vec::new());
        for ((w, mut here), obs) in self.windows.iter_mut().zip(present).zip(&mut self.obs) {
            here.sort_unstable();
            let ids: Vec<u64> = here.iter().map(|&(_, id)| id as u64).collect();
            w.controlled = w
                .queue
                .update(&ids, n_av)
                .into_iter()
                .map(|id| id as VehicleId)
                .collect();
            let views: Vec<AvView> = w
                .controlled
                .iter()
                .map(|&id| AvView {
                    speed: sim.vehicle(id).map_or(0.0, |v| v.speed),
                    leader: sim.leader(id, norm.length).map(|n| (n.speed, n.gap_m)),
                    follower: sim.follower(id, norm.length).map(|n| (n.speed, n.gap_m)),
                })
                .collect();
            centralized_obs(&views, n_av, norm, obs);
        }
    }

    /// Each window's controlled AVs, in slot order.
    pub fn controlled(&self, window: usize) -> &[VehicleId] {
        &self.windows[window].controlled
    }

    /// Steps with each window's accelerations (`actions[k]` for window `k`, clipped to the bounds; a window
    /// without an action keeps its AVs on the driver model); returns every window's next observation.
    pub fn step(&mut self, actions: &[Option<Vec<f32>>]) -> Result<&[Vec<f32>], RlError> {
        let (lo, hi) = (self.cfg.accel_min, self.cfg.accel_max);
        for (w, action) in actions.iter().enumerate() {
            let Some(action) = action else { continue };
            super::check_actions(action.iter().copied(), |k| {
                format!("window {w} action[{k}]")
            })?;
        }
        let sim = self.sim.as_mut().expect("reset before step");
        for (w, action) in self.windows.iter().zip(actions) {
            let Some(action) = action else { continue };
            for (&id, &a) in w.controlled.iter().zip(action) {
                super::apply_action(sim, id, a, (lo, hi))?;
            }
        }
        if !sim.is_done() {
            let counted = !sim.in_warmup();
            sim.step().map_err(super::sim_error)?;
            self.counter.update(sim, counted);
        }
        self.observe();
        Ok(&self.obs)
    }

    /// The simulation of the current episode (after `reset`).
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref()
    }

    /// The episode's figures so far.
    pub fn metrics(&self) -> WindowsMetrics {
        WindowsMetrics {
            metrics: self
                .sim
                .as_ref()
                .map(|s| (&s.metrics()).into())
                .unwrap_or_default(),
            merge_flows: self.counter.flows_veh_h(),
        }
    }
}

/// The all-human episode of `seed` on `spec` (every AV driving as a human), with the flow past every window's
/// merge; its traffic figures are those of `mapc_sim::run_baseline_spec`.
pub fn human_windows_episode(spec: &SimSpec, seed: u64) -> Result<WindowsMetrics, RlError> {
    let mut sim =
        Simulation::from_spec(spec.clone(), seed).map_err(|e| super::scenario_error(spec, e))?;
    let mut counter = MergeFlowCounter::new(spec, &MergeFlowCounter::merges_of(spec))?;
    counter.reset(&sim);
    while !sim.is_done() {
        let counted = !sim.in_warmup();
        sim.step().map_err(super::sim_error)?;
        counter.update(&sim, counted);
    }
    Ok(WindowsMetrics {
        metrics: (&sim.metrics()).into(),
        merge_flows: counter.flows_veh_h(),
    })
}

#[cfg(test)]
#[path = "windows_tests.rs"]
mod tests;
