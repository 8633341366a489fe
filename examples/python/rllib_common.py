"""What the two RLlib examples share: the env seeds of each runner, and the training loop with its log."""

import json
import os
import time


def runner_seed(cfg):
    """Every env runner and vector slot plays its own seeds."""
    return cfg["seed"] + 100_000 * getattr(cfg, "worker_index", 0) + 1_000 * getattr(cfg, "vector_index", 0)


def train(algo, iters, out):
    """Run `iters` iterations, printing and keeping one JSON row each (progress.jsonl in `out`); returns the rows
    and the wall time."""
    os.makedirs(out, exist_ok=True)
    start, log = time.perf_counter(), []
    for it in range(1, iters + 1):
        r = algo.train()
        runners = r.get("env_runners", {})
        row = {"iteration": it, "wall_s": round(time.perf_counter() - start, 1),
               "env_steps": r.get("num_env_steps_sampled_lifetime", runners.get("num_env_steps_sampled_lifetime")),
               "episode_return_mean": runners.get("episode_return_mean")}
        log.append(row)
        print(json.dumps(row), flush=True)
    with open(os.path.join(out, "progress.jsonl"), "w") as f:
        f.writelines(json.dumps(row) + "\n" for row in log)
    return log, time.perf_counter() - start
