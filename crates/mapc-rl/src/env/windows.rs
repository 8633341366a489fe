//! Several control windows on one corridor (a scenario with `[[control.windows]]`): each window keeps its own
//! FIFO of up to `N_AV` AVs and builds its observation exactly as the single-window environment
//! ([`super::merge::MergeEnv`]) does; one policy acts on every window's observation (zero-shot). An AV is
//! controlled by the window it is in and, once it has left that window, never again by it. The flow past every
//! merge is the simulation's own measurement (`mapc_sim::RunMetrics`), as for any run.

use mapc_graph::RoadId;
use mapc_sim::{SimSpec, Simulation, VehicleId};

use super::merge::MergeEnvConfig;
use super::obs::{AvView, ControlQueue, centralized_obs};
use crate::env::EpisodeMetrics;
use crate::error::RlError;

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

/// The centralized environment over every window of a several-window scenario.
pub struct WindowsEnv {
    spec: SimSpec,
    cfg: MergeEnvConfig,
    sim: Option<Simulation>,
    windows: Vec<Window>,
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
        Ok(WindowsEnv {
            spec,
            cfg,
            sim: None,
            windows,
            obs: Vec::new(),
        })
    }

    /// Steps of one episode: the scenario's warm-up and measured horizon (the whole simulation).
    pub fn horizon(&self) -> usize {
        (self.spec.warmup_steps + self.spec.horizon_steps) as usize
    }

    pub fn window_count(&self) -> usize {
        self.windows.len()
    }

    /// Starts an episode; returns every window's observation.
    pub fn reset(&mut self, seed: u64) -> Result<&[Vec<f32>], RlError> {
        let sim = super::episode_simulation(&self.spec, seed)?;
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
        let (n_av, norm, lanes) = (self.cfg.n_av, self.cfg.norm, self.cfg.lanes);
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
                .map(|&id| super::av_view(sim, id, norm.length, lanes))
                .collect();
            centralized_obs(&views, n_av, norm, lanes, obs);
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
            sim.step().map_err(super::sim_error)?;
        }
        self.observe();
        Ok(&self.obs)
    }

    /// The simulation of the current episode (after `reset`).
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref()
    }

    /// The episode's figures so far.
    pub fn metrics(&self) -> EpisodeMetrics {
        self.sim
            .as_ref()
            .map(|s| (&s.metrics()).into())
            .unwrap_or_default()
    }
}

#[cfg(test)]
#[path = "windows_tests.rs"]
mod tests;
