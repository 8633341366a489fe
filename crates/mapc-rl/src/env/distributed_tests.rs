//! The distributed environment's observation and reward worked by hand, and whole episodes on the Simple Merge.

mod by_hand {
    use super::super::*;

    const NORM: ObsNorm = crate::env::merge::SIMPLE_MERGE_NORM;

    #[test]
    fn observation_by_hand() {
        let view = AgentView {
            av: AvView {
                speed: 15.0,
                leader: Some((45.0, 2000.0)),
                follower: None,
                ..AvView::default()
            },
            junction_dist: Some(150.0),
            congestion_speed: Some(6.0),
            merge_foe: Some((50.0, 9.0)),
        };
        let mut o = Vec::new();
        agent_obs(&view, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        // not clipped: the leader 2000 m ahead gives 2.11, its speed difference 1.0
        let want = [0.5, 1.0, 2000.0 / 947.68, 0.5, 1.0, 0.25, 0.2, 0.25, 0.3];
        assert_eq!(o.len(), Features::FULL.obs_dim());
        for (a, b) in o.iter().zip(want) {
            assert!((a - b as f32).abs() < 1e-6, "{o:?}");
        }
        // without augmentations: the five values only; defaults when nothing is ahead
        let none = Features::parse("none").unwrap();
        agent_obs(&view, none, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(o.len(), 5);
        let bare = AgentView {
            junction_dist: None,
            congestion_speed: None,
            merge_foe: None,
            ..view
        };
        agent_obs(&bare, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(&o[5..], &[1.0, 1.0, 1.0, 0.0]);
        // on a corridor the next merge may lie kilometres ahead: it reads as the training network's entry
        let far = AgentView {
            junction_dist: Some(2500.0),
            ..view
        };
        agent_obs(&far, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(o[5], 1.0);
    }

    #[test]
    fn features_parse_and_name() {
        assert_eq!(Features::parse("full").unwrap(), Features::FULL);
        let f = Features::parse("dist, merge").unwrap();
        assert!(f.dist && f.merge_info && !f.congestion);
        assert_eq!(f.obs_dim(), 8);
        assert_eq!(f.name(), "dist,merge");
        assert_eq!(Features::parse("none").unwrap().name(), "none");
        assert!(Features::parse("speed").is_err());
        // the adjacent lanes, alone or with the paper's three
        let l = Features::parse("lanes").unwrap();
        assert!(l.lanes && !l.dist && l.obs_dim() == 15);
        assert_eq!(l.name(), "lanes");
        let fl = Features::parse("full,lanes").unwrap();
        assert_eq!((fl.obs_dim(), fl.name()), (19, "full,lanes".to_string()));
        assert_eq!(Features::parse(&fl.name()).unwrap(), fl);
        assert_eq!(
            Features::parse("merge,lanes").unwrap().name(),
            "merge,lanes"
        );
        // a policy file without the field reads as the paper's observation
        let old: Features =
            serde_json::from_str(r#"{"dist":true,"congestion":true,"merge_info":true}"#).unwrap();
        assert_eq!(old, Features::FULL);
        assert!(
            !serde_json::to_string(&Features::FULL)
                .unwrap()
                .contains("lanes")
        );
    }

    #[test]
    fn reward_by_hand() {
        let r = AgentReward::PAPER;
        assert!((r.of(false, 0.5) - (-0.09 + 0.005)).abs() < 1e-12);
        assert_eq!(r.of(true, 0.5), 20.0);
    }
}

mod episodes {
    use super::super::*;
    use crate::ppo::tensor::{Architecture, Model, Scratch};
    use crate::rollout::{ActionMode, EpisodeSettings, run_agents_episode};

    fn simple_merge(horizon: u64) -> SimSpec {
        let rs = mapc_scenario::ResolvedScenario::load("simple_merge").unwrap();
        let mut spec = mapc_sim::spec_from_scenario(&rs).unwrap();
        spec.horizon_steps = horizon;
        spec
    }

    fn config() -> DistributedConfig {
        DistributedConfig {
            features: Features::FULL,
            reward: AgentReward::PAPER,
            norm: crate::env::merge::SIMPLE_MERGE_NORM,
            dist_norm: SIMPLE_MERGE_DIST_NORM,
            accel_min: crate::env::merge::ACCEL_MIN,
            accel_max: crate::env::merge::ACCEL_MAX,
        }
    }

    fn episode(seed: u64) -> crate::rollout::AgentsEpisode {
        episode_with(seed, config())
    }

    fn episode_with(seed: u64, cfg: DistributedConfig) -> crate::rollout::AgentsEpisode {
        let mut env = DistributedEnv::new(simple_merge(400), cfg).unwrap();
        let arch = Architecture {
            obs_dim: cfg.obs_dim(),
            act_dim: 1,
            hidden: vec![16, 8],
            shared_value: false,
        };
        let model = Model::new(arch, 7);
        let settings = EpisodeSettings {
            env_seed: seed,
            noise_seed: seed + 100,
            horizon: 400,
            mode: ActionMode::Sample,
            record: true,
        };
        run_agents_episode(
            &mut env,
            &|_| &model,
            &mut Scratch::default(),
            settings,
            &mut |_| Ok(()),
        )
        .unwrap()
    }

    #[test]
    fn every_agent_gets_one_trajectory_with_one_reward_per_action() {
        let ep = episode(3);
        // 200 AVs/h for 200 s: a few AVs enter, the first ones leave within the 400 steps
        assert!(ep.trajectories.len() >= 3, "{}", ep.trajectories.len());
        let mut terminal = 0;
        let mut steps = 0;
        for t in &ep.trajectories {
            assert!(!t.is_empty());
            assert_eq!(t.obs.len(), t.len() * Features::FULL.obs_dim());
            assert_eq!(t.actions.len(), t.len());
            assert_eq!(t.values.len(), t.len());
            steps += t.len() as u64;
            match t.end {
                Some(crate::ppo::gae::EpisodeEnd::Terminal) => {
                    // leaving pays the bonus in the last step, and only there
                    terminal += 1;
                    assert_eq!(*t.rewards.last().unwrap(), 20.0);
                    assert!(t.rewards[..t.len() - 1].iter().all(|&r| r < 0.0));
                }
                Some(crate::ppo::gae::EpisodeEnd::Truncated { bootstrap_value }) => {
                    assert!(bootstrap_value.is_finite());
                    assert!(t.rewards.iter().all(|&r| r < 0.0));
                }
                None => panic!("a trajectory without an end"),
            }
        }
        assert!(terminal >= 1, "no agent left the network");
        assert_eq!(steps, ep.agent_steps);
        let sum: f64 = ep
            .trajectories
            .iter()
            .flat_map(|t| &t.rewards)
            .map(|&r| r as f64)
            .sum();
        assert!((sum - ep.total_reward).abs() < 1e-6 * sum.abs().max(1.0));
    }

    #[test]
    fn distributed_training_is_the_same_for_any_thread_count() {
        let run = |threads: usize| {
            crate::on_threads(threads, || {
                let mut c = crate::ppo::PpoConfig::distributed_fast();
                c.train_batch_size = 600;
                c.horizon = 300;
                c.minibatch = 256;
                c.epochs = 2;
                c.hidden = vec![16, 8];
                let mut st = crate::ppo::TrainerState::new(c, config().obs_dim(), 1);
                let factory = || DistributedEnv::new(simple_merge(300), config()).unwrap();
                let returns: Vec<u64> = (0..2)
                    .map(|_| st.iterate_agents(&factory).unwrap().mean_return.to_bits())
                    .collect();
                (st.model.params.clone(), returns)
            })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn a_reward_share_moves_reward_between_agents_and_keeps_the_sum() {
        // two environments in lockstep with the same actions (rewards do not move vehicles)
        let mut shared_cfg = config();
        shared_cfg.reward.share = 1.0;
        let mut half_cfg = config();
        half_cfg.reward.share = 0.5;
        let envs = [config(), shared_cfg, half_cfg]
            .map(|c| DistributedEnv::new(simple_merge(600), c).unwrap());
        let [mut own, mut shared, mut half] = envs;
        let mut obs = own.reset(2).unwrap();
        assert_eq!(shared.reset(2).unwrap(), obs);
        assert_eq!(half.reset(2).unwrap(), obs);
        let (mut multi_agent_steps, mut unequal_steps) = (0, 0);
        for t in 0..600 {
            // brake and accelerate in turns, so agents' rewards differ (some leave, with the bonus)
            let a = if (t / 40) % 2 == 0 { -1.0 } else { 1.0 };
            let actions: Vec<(VehicleId, f32)> = obs.iter().map(|(id, _)| (*id, a)).collect();
            let (o, s, h) = (
                own.step(&actions).unwrap(),
                shared.step(&actions).unwrap(),
                half.step(&actions).unwrap(),
            );
            assert_eq!(o.obs, s.obs);
            assert_eq!(o.obs, h.obs);
            let n = o.rewards.len();
            if n > 1 {
                multi_agent_steps += 1;
            }
            if n == 0 {
                obs = o.obs;
                continue;
            }
            let mean = o.rewards.iter().map(|&(_, r, _)| r as f64).sum::<f64>() / n as f64;
            let spread = |rs: &[(VehicleId, f32, bool)]| {
                let max = rs.iter().map(|r| r.1).fold(f32::MIN, f32::max);
                let min = rs.iter().map(|r| r.1).fold(f32::MAX, f32::min);
                (max - min) as f64
            };
            if spread(&o.rewards) > 1.0 {
                unequal_steps += 1;
            }
            for ((x, y), z) in o.rewards.iter().zip(&s.rewards).zip(&h.rewards) {
                // same agents, same done flags; all get the mean, or halfway to it
                assert_eq!((x.0, x.2), (y.0, y.2));
                assert_eq!((x.0, x.2), (z.0, z.2));
                assert!((y.1 as f64 - mean).abs() < 1e-5, "{y:?} {mean}");
                let halfway = 0.5 * x.1 as f64 + 0.5 * mean;
                assert!((z.1 as f64 - halfway).abs() < 1e-5, "{z:?} {halfway}");
            }
            assert!(spread(&s.rewards) < 1e-6);
            obs = o.obs;
        }
        // the check saw steps with several agents whose own rewards differ (an exit bonus among time penalties)
        assert!(
            multi_agent_steps > 100 && unequal_steps > 0,
            "{multi_agent_steps} {unequal_steps}"
        );
    }

    #[test]
    fn a_reward_share_outside_zero_to_one_is_refused() {
        for share in [-0.1, 1.5, f64::NAN] {
            let mut cfg = config();
            cfg.reward.share = share;
            let err = DistributedEnv::new(simple_merge(10), cfg).err().unwrap();
            assert!(err.to_string().contains("reward share"), "{err}");
        }
    }

    #[test]
    fn waiting_vehicles_lower_the_collaborative_reward() {
        // the same episode (actions do not depend on rewards); counting the vehicles waiting at the entry as
        // standing can only lower the mean speed, and does when some wait
        let mut cfg = config();
        let plain = episode_with(11, cfg);
        cfg.reward.count_waiting = true;
        let counted = episode_with(11, cfg);
        assert_eq!(plain.agent_steps, counted.agent_steps);
        assert!(
            counted.total_reward < plain.total_reward,
            "{} {}",
            counted.total_reward,
            plain.total_reward
        );
    }

    #[test]
    fn the_same_seeds_give_the_same_episode() {
        let (a, b) = (episode(5), episode(5));
        assert_eq!(a.total_reward.to_bits(), b.total_reward.to_bits());
        assert_eq!(a.trajectories.len(), b.trajectories.len());
        for (x, y) in a.trajectories.iter().zip(&b.trajectories) {
            assert_eq!(x.actions, y.actions);
            assert_eq!(x.rewards, y.rewards);
        }
        assert_ne!(a.total_reward, episode(6).total_reward);
    }

    #[test]
    fn a_mixed_population_drives_each_agent_with_its_own_policy() {
        let cfg = config();
        let spec = simple_merge(400);
        let arch = Architecture {
            obs_dim: cfg.obs_dim(),
            act_dim: 1,
            hidden: vec![16, 8],
            shared_value: false,
        };
        let (a, b) = (Model::new(arch.clone(), 7), Model::new(arch, 8));
        let seeds = [3, 4];
        let odd = |id: VehicleId| id % 2 == 1;
        let run = |base: &Model, deviant: &Model, deviates: &(dyn Fn(VehicleId) -> bool + Sync)| {
            crate::eval::run_mixed_population(
                base,
                deviant,
                deviates,
                &spec,
                &cfg,
                &seeds,
                ActionMode::Sample,
            )
            .unwrap()
        };
        let all_a = run(&a, &b, &|_| false);
        let outcomes = |eps: &[crate::eval::MixedEpisode]| -> Vec<_> {
            eps.iter()
                .map(|e| {
                    let agents: Vec<_> = e
                        .agents
                        .iter()
                        .map(|x| (x.id, x.ret, x.left, x.steps))
                        .collect();
                    (e.metrics, agents)
                })
                .collect()
        };
        // the deviant policy is the base one: nothing changes but the labels
        assert_eq!(outcomes(&run(&a, &a, &odd)), outcomes(&all_a));
        // the odd agents on `b` among `a` is the even agents on `a` among `b`, agent for agent
        let mixed = run(&a, &b, &odd);
        let swapped = run(&b, &a, &|id| !odd(id));
        for (m, s) in mixed.iter().zip(&swapped) {
            assert_eq!(m.metrics, s.metrics);
            assert_eq!(m.agents.len(), s.agents.len());
            for (x, y) in m.agents.iter().zip(&s.agents) {
                assert_eq!(
                    (x.id, x.ret, x.left, x.steps),
                    (y.id, y.ret, y.left, y.steps)
                );
            }
        }
        assert_ne!(outcomes(&mixed), outcomes(&all_a));
        for e in &mixed {
            // the episodes hold both kinds of agent
            assert!(e.agents.iter().any(|x| odd(x.id)) && e.agents.iter().any(|x| !odd(x.id)));
            for x in &e.agents {
                // a step's reward lies in [-0.09, -0.08]; the exit bonus only in the step an agent leaves
                let steps_part = x.ret - if x.left { 20.0 } else { 0.0 };
                let n = (x.steps - x.left as usize) as f64;
                assert!(
                    steps_part >= -0.0901 * n - 1e-3 && steps_part <= -0.0799 * n + 1e-3,
                    "{x:?}"
                );
            }
        }
    }
}
