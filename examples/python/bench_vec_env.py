"""Environment steps per second seen from Python through mapc's vector env (docs/perf.md, docs/python.md).

    RAYON_NUM_THREADS=1 python examples/python/bench_vec_env.py
    RAYON_NUM_THREADS=2 python examples/python/bench_vec_env.py

Each sub-environment plays the Simple Merge with random accelerations; the figure counts every sub-environment's
step (an autoreset step included) over whole episodes, best of three.
"""

import os
import sys
import time

import numpy as np

import mapc


def rate(num_envs, episodes=1, scenario="simple_merge"):
    venv = mapc.make_vec_env(scenario, num_envs=num_envs, seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-4.5, 2.6, size=(venv.horizon, num_envs, venv.single_action_space.shape[0]))
    actions = actions.astype(np.float32)
    best = 0.0
    for _ in range(3):
        venv.reset(seed=0)
        start = time.perf_counter()
        for _ in range(episodes):
            for a in actions:
                venv.step(a)
        best = max(best, episodes * venv.horizon * num_envs / (time.perf_counter() - start))
    return best


if __name__ == "__main__":
    scenario = sys.argv[1] if len(sys.argv) > 1 else "simple_merge"
    threads = os.environ.get("RAYON_NUM_THREADS", "all")
    for n in (1, 2, 4, 8, 16):
        print(f"{scenario}: {n:2d} envs, {threads} threads: {rate(n, scenario=scenario):12,.0f} env-steps/s")
