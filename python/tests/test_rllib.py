"""mapc.rllib, the adapter that makes RLlib's env runners step mapc's vector env: its envs without Ray (reached
through Gymnasium's registration as RLlib reaches them), and with Ray installed an RLlib env runner sampling
through it, whose episodes are mapc's episodes of the seeds it reports."""

import gymnasium as gym
import numpy as np
import pytest

import mapc
import mapc.rllib
from mapc.rllib import SEED_STRIDE, env_creator


def as_rllib_registers_it(env_id, config):
    """Register `env_id` as RLlib's SingleAgentEnvRunner registers a creator (its single and vector entry
    points, `num_envs` added to the env config)."""
    gym.register(env_id, entry_point=lambda: env_creator(config),
                 vector_entry_point=lambda num_envs: env_creator(dict(config) | {"num_envs": num_envs}))


def test_the_vector_entry_point_gives_mapcs_vector_env_with_the_runners_seed_range():
    as_rllib_registers_it("mapc-rllib-test-v0", {"scenario": "simple_merge", "reward": "flow"})
    venv = gym.make_vec("mapc-rllib-test-v0", num_envs=3, vectorization_mode=mapc.rllib.VECTORIZE_MODE)
    assert isinstance(venv, mapc.MergeVecEnv) and venv.num_envs == 3
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    obs, info = venv.reset(seed=2)
    assert list(info["seed"]) == [2 * SEED_STRIDE + k for k in range(3)]

    # the same episodes as mapc's vector env started at that seed, bit for bit
    plain = mapc.make_vec_env("simple_merge", num_envs=3, reward="flow")
    plain_obs, _ = plain.reset(seed=2 * SEED_STRIDE)
    assert np.array_equal(obs, plain_obs)
    rng = np.random.default_rng(3)
    for _ in range(50):
        a = rng.uniform(-4.5, 2.6, size=venv.action_space.shape).astype(np.float32)
        ours, theirs = venv.step(a), plain.step(a)
        assert np.array_equal(ours[0], theirs[0]) and np.array_equal(ours[1], theirs[1])

    single = gym.make("mapc-rllib-test-v0")
    assert isinstance(single.unwrapped, mapc.MergeEnv)


def test_two_runners_play_different_episodes():
    # RLlib resets runner i's env with seed config.seed + i: their episodes' seeds must not meet
    seeds = []
    for worker_index in (1, 2):
        venv = env_creator({"num_envs": 4})
        _, info = venv.reset(seed=worker_index)
        seeds.append(set(info["seed"]))
    assert not seeds[0] & seeds[1]


def test_a_bad_env_config_is_refused_naming_the_key():
    with pytest.raises(mapc.MapcError, match="unknown key.*scenaro"):
        env_creator({"scenaro": "simple_merge"})
    with pytest.raises(mapc.MapcError, match="seed -1"):
        env_creator({"num_envs": 2}).reset(seed=-1)


def test_an_rllib_env_runner_samples_mapcs_episodes_through_the_vector_env():
    pytest.importorskip("torch")
    pytest.importorskip("ray.rllib")
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner
    from ray.tune.registry import register_env

    register_env("mapc_merge_test", env_creator)
    config = (
        PPOConfig()
        .environment("mapc_merge_test", env_config={"scenario": "simple_merge"}, normalize_actions=False)
        .env_runners(num_env_runners=0, num_envs_per_env_runner=2, gym_env_vectorize_mode=mapc.rllib.VECTORIZE_MODE)
        .debugging(seed=5)
    )
    runner = SingleAgentEnvRunner(config=config, worker_index=0)
    assert isinstance(runner.env.unwrapped, mapc.MergeVecEnv)
    horizon = runner.env.unwrapped.horizon
    # one whole episode per sub-environment and a step of the next (the autoreset)
    episodes = runner.sample(num_timesteps=2 * horizon + 4, explore=True)
    done = [e for e in episodes if e.is_done]
    assert len(done) == 2
    for e in done:
        seed = e.get_infos(0)["seed"]
        assert seed in (5 * SEED_STRIDE, 5 * SEED_STRIDE + 1)
        assert len(e) == horizon and e.is_truncated and not e.is_terminated
        # the runner's actions replayed through mapc's single env give its rewards, bit for bit
        env = mapc.make_env("simple_merge")
        obs, _ = env.reset(seed=int(seed))
        assert np.array_equal(obs, e.get_observations(0))
        rewards = [env.step(a)[1] for a in e.get_actions()]
        assert np.array_equal(np.asarray(rewards, np.float32), np.asarray(e.get_rewards(), np.float32))
    runner.stop()
