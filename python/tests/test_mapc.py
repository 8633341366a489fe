"""The Python package against the binary: Gymnasium's checks, the same figures bit for bit as `mapc sim` and
`mapc eval` on the same seeds, the vector env's autoreset, and mapc's errors as Python exceptions."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mapc

ROOT = pathlib.Path(__file__).resolve().parents[2]
POLICY = str(ROOT / "policies" / "simple_merge_outflow.json")
WINDOW = str(ROOT / "scenarios" / "i696_window.toml")


def mapc_binary():
    """The binary the Rust tests built (MAPC_BIN, else target/debug or target/release)."""
    candidates = [os.environ.get("MAPC_BIN")] + [str(ROOT / "target" / p / "mapc") for p in ("debug", "release")]
    for c in candidates:
        if c and os.path.isfile(c):
            return c
    pytest.fail("no mapc binary: build it with `cargo build` or set MAPC_BIN")


def binary_json(*args):
    out = subprocess.run([mapc_binary(), *args, "--json"], cwd=ROOT, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def test_the_env_passes_gymnasiums_checks():
    env = mapc.make_env("simple_merge")
    check_env(env, skip_render_check=True)
    assert env.observation_space.shape == (25,)
    assert env.action_space.shape == (5,)
    assert (env.action_space.low[0], env.action_space.high[0]) == (np.float32(-4.5), np.float32(2.6))


def test_a_window_scenario_is_an_env_too():
    env = mapc.make_env(WINDOW)
    obs, info = env.reset(seed=4)
    assert obs.shape == (25,) and info["seed"] == 4
    obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
    assert env.observation_space.contains(obs) and not terminated and not truncated


def test_simulate_gives_mapc_sims_figures_bit_for_bit():
    ours = mapc.simulate("simple_merge", seeds=3, first_seed=5)
    theirs = binary_json("sim", "--scenario", "simple_merge", "--seeds", "3", "--first-seed", "5")
    for key in ("outflow", "inflow", "speed", "travel_time", "delay", "runs", "seeds", "first_seed", "scenario"):
        assert ours[key] == theirs[key], key


def test_an_episode_driven_from_python_is_mapc_evals_episode():
    # the shipped policy's mean action, applied step by step through the Gymnasium API
    env, policy = mapc.make_env("simple_merge"), mapc.Policy(POLICY)
    obs, _ = env.reset(seed=2)
    truncated, steps = False, 0
    while not truncated:
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        assert not terminated
        steps += 1
    assert steps == env.horizon == 2000
    theirs = binary_json("eval", "--policy", POLICY, "--seeds", "1", "--first-seed", "2", "--no-baseline")
    assert info["outflow"] == theirs["outflow"]["mean"]
    assert info["inflow"] == theirs["inflow"]["mean"]
    assert info["speed"] == theirs["speed"]["mean"]
    # and evaluate() is mapc eval
    ours = mapc.evaluate(POLICY, "simple_merge", seeds=2, first_seed=2)
    theirs = binary_json("eval", "--policy", POLICY, "--seeds", "2", "--first-seed", "2")
    for key in ("outflow", "inflow", "speed", "baseline", "comparison", "seeds"):
        assert ours[key] == theirs[key], key


def test_the_same_seed_and_actions_give_the_same_episode():
    def run():
        env, rng = mapc.make_env("simple_merge", reward="flow"), np.random.default_rng(7)
        obs, _ = env.reset(seed=11)
        trace = [obs]
        for _ in range(300):
            obs, reward, *_ = env.step(rng.uniform(-4.5, 2.6, size=5))
            trace += [obs, np.float32(reward)]
        return np.concatenate([np.ravel(t) for t in trace]), env.metrics()

    (a, ma), (b, mb) = run(), run()
    assert np.array_equal(a, b) and ma == mb


def test_the_vector_env_steps_every_episode_and_resets_in_the_next_step():
    num = 3
    venv = mapc.make_vec_env("simple_merge", num_envs=num, seed=20)
    obs, info = venv.reset()
    assert obs.shape == (num, 25) and list(info["seed"]) == [20, 21, 22]
    # each sub-environment is the single env of its seed
    single = mapc.make_env("simple_merge")
    assert np.array_equal(obs[1], single.reset(seed=21)[0])
    actions = np.zeros((num, 5), np.float32)
    for step in range(venv.horizon):
        obs, rewards, terminated, truncated, infos = venv.step(actions)
        single_obs, single_reward, _, single_trunc, single_info = single.step(actions[1])
        assert np.array_equal(obs[1], single_obs) and rewards[1] == np.float32(single_reward)
        assert not terminated.any()
        assert truncated.all() == (step == venv.horizon - 1)
    assert infos["_outflow"].all() and infos["outflow"][1] == single_info["outflow"]
    assert list(infos["seed"]) == [20, 21, 22]
    # the next step starts each sub-environment's next episode (seed + num_envs), ignoring its action
    obs, rewards, terminated, truncated, infos = venv.step(np.full((num, 5), 2.6, np.float32))
    assert not truncated.any() and not rewards.any() and not infos
    assert np.array_equal(obs[0], mapc.make_env("simple_merge").reset(seed=20 + num)[0])


def test_mapcs_errors_are_python_exceptions_with_mapcs_message(tmp_path):
    with pytest.raises(mapc.MapcError, match="no_such.toml"):
        mapc.make_env("no_such.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('version = 1\nname = "x"\nhorizon_steps = 10\nflows = []\n[network]\ngraph = "gone.graph.json"\n'
                   "[vehicle_types.human]\n")
    with pytest.raises(mapc.MapcError, match="gone.graph.json"):
        mapc.simulate(str(bad), seeds=1)
    with pytest.raises(mapc.MapcError, match="unknown reward"):
        mapc.make_env("simple_merge", reward="happiness")
    env = mapc.make_env("simple_merge")
    with pytest.raises(mapc.MapcError, match="before reset"):
        env.step(np.zeros(5))
    env.reset(seed=0)
    with pytest.raises(mapc.MapcError, match="5 were expected"):
        env.step(np.zeros(3))
    with pytest.raises(mapc.MapcError, match="seeds must be at least 1"):
        mapc.simulate("simple_merge", seeds=0)
    with pytest.raises(mapc.MapcError, match="nope.json"):
        mapc.Policy(str(tmp_path / "nope.json"))
    # a map where a scenario or a policy is expected: what it is and how to make a scenario of it
    with pytest.raises(mapc.MapcError, match=r"i696.osm: is an OSM XML map, not a scenario: .*mapc pipeline"):
        mapc.make_env(str(ROOT / "maps" / "i696.osm"))
    with pytest.raises(mapc.MapcError, match=r"is a SUMO network \(net.xml\), not a scenario"):
        mapc.parallel_env(str(ROOT / "maps" / "simple_merge.net.xml"))
    with pytest.raises(mapc.MapcError, match=r"is an OSM PBF map, not a policy"):
        mapc.Policy(str(ROOT / "maps" / "i696.osm.pbf"))


def test_map_text_in_an_error_is_shown_not_obeyed_by_the_terminal(tmp_path):
    # a path (as any id or name from a map) holding an escape sequence that would retitle the terminal
    bad = tmp_path / "hostile.toml"
    bad.write_text('version = 1\nname = "x"\nhorizon_steps = 10\nflows = []\n[network]\n'
                   'graph = "gone\\u001b]0;pwned\\u0007\\u202e.graph.json"\n[vehicle_types.human]\n')
    with pytest.raises(mapc.MapcError) as err:
        mapc.simulate(str(bad), seeds=1)
    message = str(err.value)
    assert "gone\\u001b]0;pwned\\u0007\\u202e.graph.json" in message
    assert not any(ord(c) < 0x20 and c != "\n" or c == "\u202e" for c in message)


def test_an_action_that_is_not_a_number_is_refused_naming_its_place():
    # the single env: the index in the action; the episode goes on as if the bad step had not been tried
    env, twin = mapc.make_env("simple_merge"), mapc.make_env("simple_merge")
    env.reset(seed=1)
    twin.reset(seed=1)
    good = np.array([1.0, -1.0, 0.5, 2.0, -3.0], np.float32)
    for _ in range(60):
        env.step(good), twin.step(good)
    for slot, bad in [(0, np.nan), (3, np.inf), (4, -np.inf)]:
        action = good.copy()
        action[slot] = bad
        with pytest.raises(mapc.MapcError, match=rf"^action\[{slot}\] is (NaN|inf|-inf): .*finite acceleration"):
            env.step(action)
    for _ in range(40):
        a, b = env.step(good), twin.step(good)
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]
    # the vector env: the sub-environment and the index
    venv = mapc.make_vec_env("simple_merge", num_envs=3, seed=0)
    venv.reset()
    actions = np.zeros((3, 5), np.float32)
    actions[2, 1] = np.inf
    with pytest.raises(mapc.MapcError, match=r"^sub-environment 2: action\[1\] is inf"):
        venv.step(actions)
    # the parallel env: the agent
    penv = mapc.parallel_env("simple_merge")
    penv.reset(seed=3)
    while len(penv.agents) < 2:
        penv.step({a: np.array([1.0], np.float32) for a in penv.agents})
    actions = {a: np.array([1.0], np.float32) for a in penv.agents}
    actions[penv.agents[1]] = np.array([np.nan], np.float32)
    with pytest.raises(mapc.MapcError, match=rf"^agent {penv.agents[1]}: .*is NaN"):
        penv.step(actions)


def test_the_parallel_env_passes_pettingzoos_test_and_plays_mapc_evals_distributed_episode():
    from pettingzoo.test import parallel_api_test

    parallel_api_test(mapc.parallel_env("simple_merge"), num_cycles=2500)
    policy = mapc.Policy(ROOT / "policies" / "simple_merge_distributed.json")
    assert policy.features is not None and policy.act_dim == 1
    env = mapc.parallel_env("simple_merge", features=policy.features)
    obs, infos = env.reset(seed=3)
    assert env.agents == ["av_0"] and set(infos) == {"av_0"}
    seen, info = set(), {}
    while env.agents:
        actions = {a: policy.act(obs[a]) for a in env.agents}
        obs, rewards, terminations, truncations, infos = env.step(actions)
        assert set(obs) == set(rewards) == set(terminations) == set(truncations) == set(infos)
        seen |= set(obs)
        info = next(iter(infos.values()), info)
    assert len(seen) > 20
    theirs = binary_json("eval", "--policy", str(ROOT / "policies" / "simple_merge_distributed.json"),
                         "--seeds", "1", "--first-seed", "3", "--no-baseline")
    assert (info["outflow"], info["inflow"], info["speed"]) == (
        theirs["outflow"]["mean"], theirs["inflow"]["mean"], theirs["speed"]["mean"])
    with pytest.raises(mapc.MapcError, match="unknown feature"):
        mapc.parallel_env("simple_merge", features="telepathy")


def test_same_step_autoreset_returns_the_new_episode_and_the_last_observation():
    from gymnasium.vector import AutoresetMode

    venv = mapc.make_vec_env("simple_merge", num_envs=2, seed=5, autoreset_mode=AutoresetMode.SAME_STEP)
    single = mapc.make_env("simple_merge")
    venv.reset()
    single.reset(seed=6)
    actions = np.ones((2, 5), np.float32)
    for _ in range(venv.horizon):
        obs, rewards, _, truncated, infos = venv.step(actions)
        last, reward, *_ = single.step(actions[1])
        assert rewards[1] == np.float32(reward)
    assert truncated.all() and infos["_final_obs"].all()
    assert np.array_equal(infos["final_obs"][1], last)
    assert np.array_equal(obs[1], mapc.make_env("simple_merge").reset(seed=8)[0])


def _torch_layers(params, sizes):
    """A mapc MLP's layers as torch lays them out: (weight [out, in], bias [out])."""
    layers, at = [], 0
    for n_in, n_out in zip(sizes, sizes[1:]):
        w = np.asarray(params[at:at + n_in * n_out], np.float32).reshape(n_in, n_out).T
        b = np.asarray(params[at + n_in * n_out:at + n_in * n_out + n_out], np.float32)
        layers.append((w, b))
        at += n_in * n_out + n_out
    return layers, at


def test_a_policy_written_from_torch_layers_is_the_same_policy_to_mapc_eval(tmp_path):
    from mapc.export import gaussian_head, mapc_params

    ck = json.loads((ROOT / "policies" / "simple_merge_outflow.json").read_text())
    arch, params = ck["state"]["model"]["arch"], ck["state"]["model"]["params"]
    sizes = [arch["obs_dim"], *arch["hidden"], 2 * arch["act_dim"]]
    policy_layers, used = _torch_layers(params, sizes)
    value_layers, _ = _torch_layers(params[used:], [arch["obs_dim"], *arch["hidden"], 1])
    act = arch["act_dim"]
    w, b = policy_layers[-1]
    # a state-independent log-std, as torch libraries have: the means, and so mean actions, are unchanged
    raw = mapc_params(policy_layers[:-1], gaussian_head((w[:act], b[:act]), np.full(act, -0.5)),
                      value_layers[:-1], value_layers[-1])
    out = tmp_path / "from_torch.json"
    mapc._mapc.save_policy(str(out), raw, "simple_merge", "outflow", act, arch["hidden"])
    ours = mapc.evaluate(out, "simple_merge", seeds=3, baseline=False)
    shipped = mapc.evaluate(POLICY, "simple_merge", seeds=3, baseline=False)
    assert ours["outflow"] == shipped["outflow"] and ours["speed"] == shipped["speed"]
    with pytest.raises(mapc.MapcError, match="parameter bytes"):
        mapc._mapc.save_policy(str(tmp_path / "short.json"), raw[:-4], "simple_merge", "outflow", act, arch["hidden"])
    assert not (tmp_path / "short.json").exists()


def test_the_pipeline_from_python_writes_what_the_binary_writes(tmp_path):
    via = ["osm-way:59440544", "osm-way:8667198", "osm-way:8708084"]
    osm = str(ROOT / "maps" / "i696.osm")
    ours = mapc.import_map(osm, tmp_path / "py.graph.json")
    theirs = binary_json("import", osm, "-o", str(tmp_path / "bin.graph.json"))
    assert {k: v for k, v in ours.items() if k != "output"} == {k: v for k, v in theirs.items() if k != "output"}
    assert (tmp_path / "py.graph.json").read_bytes() == (tmp_path / "bin.graph.json").read_bytes()

    corridor = tmp_path / "i696.corridor.graph.json"
    ours = mapc.simplify(osm, corridor, via=via)
    theirs = binary_json("simplify", osm, *sum([["--via", v] for v in via], []), "-o", str(corridor))
    assert ours == theirs and len(ours["merges"]) == 5

    ours = mapc.window(corridor, "osm:61862553", tmp_path / "py" / "w.toml")
    theirs = binary_json("window", str(corridor), "--junction", "osm:61862553", "-o", str(tmp_path / "w.toml"))
    for key in ("junction", "osm_node", "upstream_m", "merge_m", "downstream_m", "region", "cuts"):
        assert ours[key] == theirs[key], key
    assert (tmp_path / "py" / "w.graph.json").read_bytes() == (tmp_path / "w.graph.json").read_bytes()
    # the written window is a scenario like any other
    assert mapc.simulate(tmp_path / "py" / "w.toml", seeds=1)["seeds"] == 1

    with pytest.raises(mapc.MapcError, match="nowhere.osm"):
        mapc.import_map(tmp_path / "nowhere.osm")
    with pytest.raises(mapc.MapcError, match="must be zero or a positive rate"):
        mapc.window(corridor, "osm:61862553", tmp_path / "bad.toml", main_vph=float("nan"))
    assert not (tmp_path / "bad.toml").exists()


def test_a_distributed_policy_written_from_its_layers_is_the_same_policy_to_mapc_eval(tmp_path):
    from mapc.export import save_distributed_policy

    shipped = ROOT / "policies" / "simple_merge_distributed.json"
    ck = json.loads(shipped.read_text())
    arch, params = ck["state"]["model"]["arch"], ck["state"]["model"]["params"]
    assert arch["shared_value"]
    layers, used = _torch_layers(params, [arch["obs_dim"], *arch["hidden"], 2 * arch["act_dim"] + 1])
    assert used == len(params)
    out = tmp_path / "distributed.json"
    save_distributed_policy(out, layers[:-1], layers[-1], features=mapc.Policy(shipped).features)
    ours = mapc.evaluate(out, "simple_merge", seeds=2, baseline=False)
    theirs = mapc.evaluate(shipped, "simple_merge", seeds=2, baseline=False)
    assert (ours["outflow"], ours["speed"]) == (theirs["outflow"], theirs["speed"])


def test_a_deployment_rule_from_python_is_mapc_evals(tmp_path):
    robust = str(ROOT / "policies" / "merge_robust.json")
    arizona = str(ROOT / "scenarios" / "merges" / "arizona_5134463770.toml")
    py = mapc.evaluate(robust, arizona, seeds=2)
    assert py["outflow"] == py["baseline"]["outflow"]
    assert "the main road has priority" in py["withheld"][0]["reason"]
    lifted = mapc.evaluate(robust, arizona, seeds=2, deploy="everywhere")
    cli = binary_json("eval", "--policy", robust, "--scenario", arizona, "--seeds", "2", "--deploy", "everywhere")
    assert lifted["outflow"] == cli["outflow"]
    assert "withheld" not in lifted
    with pytest.raises(mapc.MapcError, match="unknown deployment rule"):
        mapc.evaluate(robust, arizona, seeds=1, deploy="anywhere")


TWO_LANES = str(ROOT / "scenarios" / "two_lane_merge_av.toml")


def test_a_multi_lane_scenario_is_an_env_and_plays_mapc_evals_episode():
    # the two-lane merge: the policy sets accelerations, lane changes stay with the lane-change model
    env, policy = mapc.make_env(TWO_LANES), mapc.Policy(POLICY)
    obs, _ = env.reset(seed=1)
    assert obs.shape == (25,)
    truncated = False
    while not truncated:
        obs, _, _, truncated, info = env.step(policy.act(obs))
    theirs = binary_json("eval", "--policy", POLICY, "--scenario", TWO_LANES, "--seeds", "1", "--first-seed", "1",
                         "--no-baseline")
    assert (info["outflow"], info["inflow"], info["speed"]) == (
        theirs["outflow"]["mean"], theirs["inflow"]["mean"], theirs["speed"]["mean"])
    venv = mapc.make_vec_env(TWO_LANES, num_envs=2, seed=1)
    obs, _ = venv.reset()
    assert obs.shape == (2, 25)
    assert np.array_equal(obs[0], mapc.make_env(TWO_LANES).reset(seed=1)[0])
    obs, rewards, _, _, _ = venv.step(np.zeros((2, 5), dtype=np.float32))
    assert obs.shape == (2, 25) and rewards.shape == (2,)


def test_the_parallel_env_takes_a_multi_lane_scenario_and_the_adjacent_lanes():
    policy_path = ROOT / "policies" / "simple_merge_distributed.json"
    policy = mapc.Policy(policy_path)
    env = mapc.parallel_env(TWO_LANES, features=policy.features)
    obs, _ = env.reset(seed=2)
    info, seen = {}, set()
    while env.agents:
        obs, _, _, _, infos = env.step({a: policy.act(obs[a]) for a in env.agents})
        seen |= set(obs)
        info = next(iter(infos.values()), info)
    assert len(seen) > 20
    theirs = binary_json("eval", "--policy", str(policy_path), "--scenario", TWO_LANES, "--seeds", "1",
                         "--first-seed", "2", "--no-baseline")
    assert (info["outflow"], info["inflow"], info["speed"]) == (
        theirs["outflow"]["mean"], theirs["inflow"]["mean"], theirs["speed"]["mean"])
    # the adjacent lanes: ten more values per agent, a lane flag 0 or 1 for each side
    env = mapc.parallel_env(TWO_LANES, features="full,lanes")
    obs, _ = env.reset(seed=2)
    flags = set()
    for _ in range(300):
        for o in obs.values():
            assert o.shape == (19,)
            flags |= {float(o[9]), float(o[14])}
        obs, *_ = env.step({a: np.zeros(1, dtype=np.float32) for a in env.agents})
    assert flags == {0.0, 1.0}


def test_avs_in_a_sumo_users_scenario_from_python(tmp_path):
    cfg = str(ROOT / "scenarios" / "sumo" / "highway_ramp" / "highway-ramp.sumocfg")
    written = mapc.with_avs(cfg, 0.1, tmp_path / "avs.toml")
    text = pathlib.Path(written).read_text()
    # each flow split into its humans and an `_av` flow of an AV copy of its type
    assert "controlled = true" in text and '_av"' in text
    env = mapc.make_env(cfg, av_share=0.1, seed=3)
    obs, _ = env.reset()
    controlled = 0
    for _ in range(600):
        obs, _, done, truncated, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        controlled = max(controlled, int(np.count_nonzero(obs)))
        if done or truncated:
            break
    assert controlled > 0, "no AV was ever observed"
    with pytest.raises(mapc.MapcError, match=r"outside \[0, 1\]"):
        mapc.make_env(cfg, av_share=1.5)
