//! Proximal policy optimisation: batch assembly, GAE, minibatch SGD with Adam, adaptive KL penalty.

pub mod config;
pub mod gae;
pub mod tensor;

use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use config::PpoConfig;
use gae::{EpisodeEnd, gae, standardize};
use tensor::{Adam, Architecture, LossCoeffs, LossStats, Minibatch, Model, loss_and_grad};

use crate::env::EpisodeMetrics;
use crate::error::RlError;
use crate::rng::{Rng, mix_seed};
use crate::rollout::{ActionMode, AgentsEnvFactory, EnvFactory, Episode, collect, collect_agents};

/// What one iteration's rollouts gave the trainer.
pub struct Collected {
    /// Training trajectories (one per episode, or one per agent in the distributed setting).
    pub trajectories: Vec<Episode>,
    /// Per simulated episode: its traffic figures and the sum of its rewards (over all agents).
    pub runs: Vec<(EpisodeMetrics, f64)>,
    /// Simulation steps taken (the schedule's and the log's `env_steps`).
    pub sim_steps: u64,
}

/// What one training iteration did (one row of the CSV log).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct IterationStats {
    pub iteration: u64,
    pub env_steps: u64,
    pub wall_s: f64,
    pub mean_return: f64,
    pub mean_outflow: f64,
    pub mean_speed: f64,
    pub policy_loss: f64,
    pub value_loss: f64,
    pub kl: f64,
    pub entropy: f64,
    pub kl_coeff: f64,
}

/// Everything a run needs to continue exactly where it stopped.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainerState {
    pub config: PpoConfig,
    pub model: Model,
    pub adam: Adam,
    pub kl_coeff: f32,
    /// Iterations completed.
    pub iteration: u64,
    pub env_steps: u64,
    /// Wall time spent so far (over all sessions of the run).
    pub wall_s: f64,
    /// Minibatch shuffling stream.
    pub rng: Rng,
    /// Minibatches whose gradient overflowed and was not applied (0 in a healthy run).
    #[serde(default)]
    pub skipped_minibatches: u64,
    /// Where this session's wall time went (not saved: a benchmark's figures).
    #[serde(skip)]
    pub timing: Timing,
}

/// Wall time of a session's iterations, by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Collecting the rollouts (simulation and the policy's forward passes).
    pub rollout_s: f64,
    /// The batch's advantages and the minibatch updates (forward, backward, Adam).
    pub update_s: f64,
}

impl TrainerState {
    pub fn new(config: PpoConfig, obs_dim: usize, act_dim: usize) -> Self {
        let arch = Architecture {
            obs_dim,
            act_dim,
            hidden: config.hidden.clone(),
            shared_value: config.shared_value,
        };
        let model = Model::new(arch, mix_seed(&[config.seed, 0xA11CE]));
        let adam = Adam::new(model.params.len());
        Self {
            kl_coeff: config.kl_coeff,
            rng: Rng::new(mix_seed(&[config.seed, 0x5EED5])),
            config,
            model,
            adam,
            iteration: 0,
            env_steps: 0,
            wall_s: 0.0,
            skipped_minibatches: 0,
            timing: Timing::default(),
        }
    }

    /// Environment and noise seeds of the episodes of iteration `it`.
    pub fn episode_seeds(&self, it: u64) -> Vec<(u64, u64)> {
        (0..self.config.episodes_per_iteration() as u64)
            .map(|k| {
                (
                    mix_seed(&[self.config.seed, it, k, 1]),
                    mix_seed(&[self.config.seed, it, k, 2]),
                )
            })
            .collect()
    }

    /// One iteration of the centralized setting: collect a batch with the current policy, then update it.
    pub fn iterate(&mut self, factory: &EnvFactory) -> Result<IterationStats, RlError> {
        let horizon = self.config.horizon;
        self.iterate_with(&|model, seeds| {
            let episodes = collect(factory, model, seeds, horizon, ActionMode::Sample, true)?;
            let runs = episodes
                .iter()
                .map(|e| (e.metrics, e.total_reward()))
                .collect();
            let sim_steps = episodes.iter().map(|e| e.len() as u64).sum();
            Ok(Collected {
                trajectories: episodes,
                runs,
                sim_steps,
            })
        })
    }

    /// One iteration of the distributed setting (every agent's trajectory trains the shared policy).
    pub fn iterate_agents(
        &mut self,
        factory: &AgentsEnvFactory,
    ) -> Result<IterationStats, RlError> {
        let horizon = self.config.horizon;
        self.iterate_with(&|model, seeds| {
            let episodes =
                collect_agents(factory, model, seeds, horizon, ActionMode::Sample, true)?;
            let runs = episodes
                .iter()
                .map(|e| (e.metrics, e.total_reward))
                .collect();
            let sim_steps = (episodes.len() * horizon) as u64;
            let trajectories = episodes
                .into_iter()
                .flat_map(|e| e.trajectories)
                .filter(|t| !t.is_empty())
                .collect();
            Ok(Collected {
                trajectories,
                runs,
                sim_steps,
            })
        })
    }

    /// One iteration with the given rollout collection (`collect(model, seeds)`).
    #[allow(clippy::type_complexity)]
    pub fn iterate_with(
        &mut self,
        collect: &dyn Fn(&Model, &[(u64, u64)]) -> Result<Collected, RlError>,
    ) -> Result<IterationStats, RlError> {
        let start = Instant::now();
        let it = self.iteration;
        let seeds = self.episode_seeds(it);
        let collected = collect(&self.model, &seeds)?;
        let collected_at = Instant::now();
        let episodes = &collected.trajectories;
        let batch = Batch::from_episodes(episodes, &self.config);
        let kl_coeff_used = self.kl_coeff;
        let sgd = self.update(&batch);
        // Adaptive KL penalty (RLlib's rule); an iteration without any step (no agent entered) updated nothing
        if batch.n > 0 {
            if sgd.kl > 2.0 * self.config.kl_target {
                self.kl_coeff *= 1.5;
            } else if sgd.kl < 0.5 * self.config.kl_target {
                self.kl_coeff *= 0.5;
            }
        }
        self.iteration += 1;
        self.env_steps += collected.sim_steps;
        self.wall_s += start.elapsed().as_secs_f64();
        self.timing.rollout_s += (collected_at - start).as_secs_f64();
        self.timing.update_s += collected_at.elapsed().as_secs_f64();
        let runs = &collected.runs;
        let n = runs.len() as f64;
        Ok(IterationStats {
            iteration: self.iteration,
            env_steps: self.env_steps,
            wall_s: self.wall_s,
            mean_return: runs.iter().map(|r| r.1).sum::<f64>() / n,
            mean_outflow: runs.iter().map(|r| r.0.outflow).sum::<f64>() / n,
            mean_speed: runs.iter().map(|r| r.0.speed).sum::<f64>() / n,
            policy_loss: sgd.policy_loss as f64,
            value_loss: sgd.value_loss as f64,
            kl: sgd.kl as f64,
            entropy: sgd.entropy as f64,
            kl_coeff: kl_coeff_used as f64,
        })
    }

    /// Minibatch SGD over the batch; returns the mean loss terms of the last epoch.
    fn update(&mut self, b: &Batch) -> LossStats {
        // on a worker of the pool, where each gradient's and Adam step's fork into two tasks is cheap (from
        // outside, every fork would wake a worker and wait for it)
        rayon::scope(|_| self.update_on_pool(b))
    }

    fn update_on_pool(&mut self, b: &Batch) -> LossStats {
        let c = &self.config;
        let coeffs = LossCoeffs {
            clip: c.clip,
            kl_coeff: self.kl_coeff,
            vf_coeff: c.vf_coeff,
            vf_clip: c.vf_clip,
            entropy_coeff: c.entropy_coeff,
        };
        let lr = c.lr_at(self.env_steps);
        let mut order: Vec<usize> = (0..b.n).collect();
        let records = b.records();
        let mut last = LossStats::default();
        let mb_size = c.minibatch.clamp(1, b.n.max(1));
        for epoch in 0..c.epochs {
            self.rng.shuffle(&mut order);
            let mut sum = LossStats::default();
            let mut count = 0usize;
            for idx in order.chunks(mb_size) {
                let mb = records.gather(idx);
                let (stats, grad) = sliced_loss_and_grad(&self.model, &mb, &coeffs, c.grad_slices);
                // One overflowing minibatch (a collapsing log-std) must not poison the weights and Adam's moments.
                if !grad.iter().all(|g| g.is_finite()) {
                    self.skipped_minibatches += 1;
                    continue;
                }
                self.adam.step(&mut self.model.params, &grad, lr);
                if epoch + 1 == c.epochs {
                    let w = idx.len() as f32;
                    sum.total += stats.total * w;
                    sum.policy_loss += stats.policy_loss * w;
                    sum.value_loss += stats.value_loss * w;
                    sum.kl += stats.kl * w;
                    sum.entropy += stats.entropy * w;
                    count += idx.len();
                }
            }
            if epoch + 1 == c.epochs && count > 0 {
                let w = count as f32;
                last = LossStats {
                    total: sum.total / w,
                    policy_loss: sum.policy_loss / w,
                    value_loss: sum.value_loss / w,
                    kl: sum.kl / w,
                    entropy: sum.entropy / w,
                };
            }
        }
        last
    }
}

/// The loss gradient of a minibatch computed on `slices` row ranges in parallel and averaged (weighted by rows,
/// combined in slice order, so the result depends on `slices` but not on the thread count).
fn sliced_loss_and_grad(
    model: &Model,
    mb: &OwnedMinibatch,
    c: &LossCoeffs,
    slices: usize,
) -> (LossStats, Vec<f32>) {
    let n = mb.n;
    let slices = slices.clamp(1, n.max(1));
    let bounds: Vec<(usize, usize)> = (0..slices)
        .map(|s| (s * n / slices, (s + 1) * n / slices))
        .filter(|(a, b)| b > a)
        .collect();
    let parts: Vec<(usize, LossStats, Vec<f32>)> = bounds
        .par_iter()
        .map(|&(lo, hi)| {
            let (s, g) = loss_and_grad(model, &mb.view(lo, hi), c);
            (hi - lo, s, g)
        })
        .collect();
    if parts.len() == 1 {
        let (_, s, g) = parts.into_iter().next().expect("one slice");
        return (s, g);
    }
    let mut grad = vec![0.0f32; model.params.len()];
    let mut stats = LossStats::default();
    for (rows, s, g) in &parts {
        let w = *rows as f32 / n as f32;
        for (acc, x) in grad.iter_mut().zip(g) {
            *acc += w * x;
        }
        stats.total += w * s.total;
        stats.policy_loss += w * s.policy_loss;
        stats.value_loss += w * s.value_loss;
        stats.kl += w * s.kl;
        stats.entropy += w * s.entropy;
    }
    (stats, grad)
}

/// A training batch: the episodes' steps, with advantages (standardised) and value targets.
pub struct Batch {
    pub n: usize,
    pub obs_dim: usize,
    pub act_dim: usize,
    pub obs: Vec<f32>,
    pub actions: Vec<f32>,
    pub log_probs: Vec<f32>,
    pub means: Vec<f32>,
    pub log_stds: Vec<f32>,
    pub values: Vec<f32>,
    pub advantages: Vec<f32>,
    pub value_targets: Vec<f32>,
}

/// A gathered minibatch.
pub struct OwnedMinibatch {
    n: usize,
    obs_dim: usize,
    act_dim: usize,
    obs: Vec<f32>,
    actions: Vec<f32>,
    log_probs: Vec<f32>,
    means: Vec<f32>,
    log_stds: Vec<f32>,
    values: Vec<f32>,
    advantages: Vec<f32>,
    value_targets: Vec<f32>,
}

impl OwnedMinibatch {
    fn view(&self, lo: usize, hi: usize) -> Minibatch<'_> {
        let (d, a) = (self.obs_dim, self.act_dim);
        Minibatch {
            n: hi - lo,
            obs: &self.obs[lo * d..hi * d],
            actions: &self.actions[lo * a..hi * a],
            old_log_prob: &self.log_probs[lo..hi],
            old_mean: &self.means[lo * a..hi * a],
            old_log_std: &self.log_stds[lo * a..hi * a],
            old_value: &self.values[lo..hi],
            advantages: &self.advantages[lo..hi],
            value_targets: &self.value_targets[lo..hi],
        }
    }
}

impl Batch {
    pub fn from_episodes(episodes: &[Episode], c: &PpoConfig) -> Self {
        let obs_dim = episodes.first().map_or(0, |e| e.obs.len() / e.len().max(1));
        let act_dim = episodes
            .first()
            .map_or(0, |e| e.actions.len() / e.len().max(1));
        let mut b = Batch {
            n: 0,
            obs_dim,
            act_dim,
            obs: vec![],
            actions: vec![],
            log_probs: vec![],
            means: vec![],
            log_stds: vec![],
            values: vec![],
            advantages: vec![],
            value_targets: vec![],
        };
        for e in episodes {
            let end = e.end.unwrap_or(EpisodeEnd::Terminal);
            let (adv, tgt) = gae(&e.rewards, &e.values, end, c.gamma, c.lambda);
            b.n += e.len();
            b.obs.extend_from_slice(&e.obs);
            b.actions.extend_from_slice(&e.actions);
            b.log_probs.extend_from_slice(&e.log_probs);
            b.means.extend_from_slice(&e.means);
            b.log_stds.extend_from_slice(&e.log_stds);
            b.values.extend_from_slice(&e.values);
            b.advantages.extend(adv);
            b.value_targets.extend(tgt);
        }
        standardize(&mut b.advantages);
        b
    }

    /// The batch row by row: each step's fields side by side, so that gathering a random row reads two or three
    /// cache lines instead of one per field (on a 40 000-step batch, larger than a core's cache, the gathers' misses
    /// were a tenth of an update).
    fn records(&self) -> Records {
        let (d, a) = (self.obs_dim, self.act_dim);
        let stride = d + 3 * a + 4;
        let mut data = Vec::with_capacity(self.n * stride);
        for i in 0..self.n {
            data.extend_from_slice(&self.obs[i * d..(i + 1) * d]);
            data.extend_from_slice(&self.actions[i * a..(i + 1) * a]);
            data.extend_from_slice(&self.means[i * a..(i + 1) * a]);
            data.extend_from_slice(&self.log_stds[i * a..(i + 1) * a]);
            data.extend_from_slice(&[
                self.log_probs[i],
                self.values[i],
                self.advantages[i],
                self.value_targets[i],
            ]);
        }
        Records {
            obs_dim: d,
            act_dim: a,
            stride,
            data,
        }
    }
}

/// A batch stored row by row ([`Batch::records`]).
struct Records {
    obs_dim: usize,
    act_dim: usize,
    stride: usize,
    data: Vec<f32>,
}

impl Records {
    fn gather(&self, idx: &[usize]) -> OwnedMinibatch {
        let (d, a, n) = (self.obs_dim, self.act_dim, idx.len());
        let mut mb = OwnedMinibatch {
            n,
            obs_dim: d,
            act_dim: a,
            obs: Vec::with_capacity(n * d),
            actions: Vec::with_capacity(n * a),
            log_probs: Vec::with_capacity(n),
            means: Vec::with_capacity(n * a),
            log_stds: Vec::with_capacity(n * a),
            values: Vec::with_capacity(n),
            advantages: Vec::with_capacity(n),
            value_targets: Vec::with_capacity(n),
        };
        for &i in idx {
            let row = &self.data[i * self.stride..(i + 1) * self.stride];
            let (obs, rest) = row.split_at(d);
            let (actions, rest) = rest.split_at(a);
            let (means, rest) = rest.split_at(a);
            let (log_stds, rest) = rest.split_at(a);
            mb.obs.extend_from_slice(obs);
            mb.actions.extend_from_slice(actions);
            mb.means.extend_from_slice(means);
            mb.log_stds.extend_from_slice(log_stds);
            mb.log_probs.push(rest[0]);
            mb.values.push(rest[1]);
            mb.advantages.push(rest[2]);
            mb.value_targets.push(rest[3]);
        }
        mb
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::{Env, EpisodeMetrics, Transition};

    /// A point on a line must be steered to a target: reward -|x - 0.5|, action is a velocity.
    struct Reach {
        x: f32,
        t: usize,
        total: f64,
    }

    impl Env for Reach {
        fn obs_dim(&self) -> usize {
            1
        }
        fn act_dim(&self) -> usize {
            1
        }
        fn reset(&mut self, seed: u64) -> Result<Vec<f32>, RlError> {
            self.x = (Rng::new(seed).uniform() as f32) * 2.0 - 1.0;
            self.t = 0;
            self.total = 0.0;
            Ok(vec![self.x])
        }
        fn step(&mut self, a: &[f32]) -> Result<Transition, RlError> {
            self.x = (self.x + 0.2 * a[0].clamp(-1.0, 1.0)).clamp(-1.0, 1.0);
            self.t += 1;
            let reward = -(self.x - 0.5).abs();
            self.total += reward as f64;
            Ok(Transition {
                obs: vec![self.x],
                reward,
                terminal: false,
            })
        }
        fn metrics(&self) -> EpisodeMetrics {
            EpisodeMetrics {
                outflow: self.total,
                inflow: 0.0,
                speed: 0.0,
                travel_time: 0.0,
            }
        }
    }

    fn reach_factory() -> Box<dyn Env> {
        Box::new(Reach {
            x: 0.0,
            t: 0,
            total: 0.0,
        })
    }

    fn tiny_config() -> PpoConfig {
        PpoConfig {
            hidden: vec![16, 16],
            horizon: 20,
            train_batch_size: 400,
            minibatch: 100,
            epochs: 8,
            lr: 3e-3,
            iterations: 30,
            seed: 3,
            ..PpoConfig::default()
        }
    }

    #[test]
    fn ppo_learns_to_reach_a_target() {
        let mut st = TrainerState::new(tiny_config(), 1, 1);
        let first = st.iterate(&reach_factory).unwrap();
        let mut last = first.clone();
        for _ in 1..30 {
            last = st.iterate(&reach_factory).unwrap();
        }
        // A random policy averages about -0.8 per step; reaching 0.5 quickly scores better than -0.25.
        assert!(first.mean_return < -8.0, "{first:?}");
        assert!(last.mean_return > -5.0, "{last:?}");
    }

    #[test]
    fn same_seed_same_run_for_any_thread_count() {
        let run = |threads: usize| {
            crate::on_threads(threads, || {
                let mut c = tiny_config();
                c.grad_slices = 3;
                let mut st = TrainerState::new(c, 1, 1);
                let s: Vec<IterationStats> = (0..3)
                    .map(|_| st.iterate(&reach_factory).unwrap())
                    .collect();
                (
                    st.model.params.clone(),
                    s.iter().map(|x| x.mean_return).collect::<Vec<_>>(),
                )
            })
        };
        assert_eq!(run(1), run(3));
    }
}
