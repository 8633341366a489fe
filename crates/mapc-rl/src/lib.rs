//! mapc-rl: reinforcement learning for merge control — the environment layer on the simulator, PPO (its
//! gradient written out, tested against burn's autodiff) and policy evaluation.
//!
//! Glossary
//! - **AV**: autonomous vehicle; **controlled AV**: one of the first `N_AV` AVs (by entry time, FIFO) inside the
//!   control region, whose acceleration the policy sets.
//! - **Observation**: five values per controlled AV (own speed, leader speed difference and gap, follower speed
//!   difference and gap), normalised by `V` (max speed) and `L` (network lane length), zero-padded to `5 N_AV`.
//!   Leader and follower are those in the AV's own lane (on a multi-lane road the policy sets accelerations only;
//!   lane changes stay with the lane-change model). **Adjacent lanes** (`--features lanes`, not in the paper):
//!   ten more values per AV, the leader and follower on the lanes to its left and right, each lane flagged as
//!   present (a missing lane reads as an empty one).
//! - **Centralized / distributed policy**: one policy sets the accelerations of the `N_AV` controlled AVs from
//!   their joint observation (`env::merge`), or one policy shared by every AV acts on each AV's own observation
//!   (its five values plus the optional augmentations) and every AV is an **agent** with its own reward and
//!   trajectory (`env::distributed`, the paper's section 4.3).
//! - **Episode**: one simulation of `horizon` steps (2000 x 0.5 s); cutting it there is a *truncation*, and the
//!   value of the last state is bootstrapped from the value network.
//! - **Return**: sum of rewards of an episode. **Advantage**: GAE estimate of how much better an action was than
//!   the value network expected.
//! - **Iteration**: one batch of episodes collected with the current policy, then `epochs` passes of minibatch SGD.
//! - **Checkpoint**: weights, optimiser state, KL coefficient, RNG state and the observation spec (`PolicySpec`),
//!   enough to resume a run exactly or to evaluate the policy on another scenario.
//! - **Outflow / inflow**: vehicles leaving / entering the network per hour over the episode.
//! - **Window**: one controlled region around a merge; a scenario may have several (`[[control.windows]]`), each
//!   with its own FIFO of `N_AV` AVs and its own observation (`env::windows`). **Flow past a merge**: vehicles
//!   entering the road after the merge per hour.
//!
//! Layout: `ppo::tensor` holds all tensor code (the loss gradient written out, its matrix products with fused
//! multiply-adds, the same bits on every machine; plain `f32` for rollout inference),
//! `ppo::gae` the advantage estimation, `rollout` the `Env` trait and parallel collection, `env` the merge
//! environment on `mapc-sim`, `run` a training run on disk, `eval` evaluation against the human baseline (every run's
//! figures, per-merge flows included, are the simulation's own measurement), `eval_windows` the several-window
//! episode it runs (one FIFO per window).

pub mod checkpoint;
pub mod deploy;
pub mod env;
pub mod error;
pub mod eval;
pub mod eval_windows;
pub mod limits;
pub mod log;
pub mod ppo;
pub mod rng;
pub mod rollout;
pub mod run;
pub mod stats;

pub use checkpoint::{Checkpoint, PolicySpec};
pub use env::{Env, EpisodeMetrics};
pub use error::RlError;
pub use ppo::{IterationStats, PpoConfig, TrainerState};

/// Runs `f` on a rayon pool of `threads` workers (the determinism tests compare thread counts).
#[cfg(test)]
pub(crate) fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
        .install(f)
}
