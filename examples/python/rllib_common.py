"""What the RLlib examples share: Ray's start on loopback, the env seeds of each runner, where the runners run, and
the training loop with its log."""

import json
import math
import os
import socket
import time


def init_ray(address, torch_threads=1):
    """Join the Ray cluster at `address`, or start a local one whose processes talk over loopback only. The
    driver's torch (the learner, when it runs in the driver) gets `torch_threads` threads: on a machine whose
    cores the env runners share, more threads spin in OpenMP barriers (measured on 2 busy cores: 14 s of CPU
    per 12 000-step PPO update with 2 threads, 0.8 s with 1)."""
    import ray
    import torch

    torch.set_num_threads(torch_threads)

    if address is None:
        # A local Ray takes the machine's outward address as its node address (even when given 127.0.0.1);
        # Ray's switch for single-machine clusters keeps every socket of a local Ray on loopback.
        import ray._private.ray_constants as ray_constants

        ray_constants.ENABLE_RAY_CLUSTER = False
    ray.init(address=address, include_dashboard=False, log_to_driver=False)


def runner_placement(algo):
    """Where each remote env runner of `algo` runs: (worker index, node IP, host name, pid), by index."""
    import ray

    def where(runner):
        return runner.worker_index, ray.util.get_node_ip_address(), socket.gethostname(), os.getpid()

    return sorted(algo.env_runner_group.foreach_env_runner(where, local_env_runner=False))


def runner_seed(cfg):
    """Every env runner and vector slot plays its own seeds."""
    return cfg["seed"] + 100_000 * getattr(cfg, "worker_index", 0) + 1_000 * getattr(cfg, "vector_index", 0)


def _round(x):
    """A metric as a JSON number, or None: RLlib's are numpy scalars when the rewards are numpy's, and NaN in an
    iteration where no episode ended."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) else round(x, 2)


def train(algo, iters, out, after_iteration=None):
    """Run `iters` iterations, printing and keeping one JSON row each (progress.jsonl in `out`), calling
    `after_iteration(it)` after each if given; returns the rows and the wall time."""
    os.makedirs(out, exist_ok=True)
    start, log = time.perf_counter(), []
    for it in range(1, iters + 1):
        r = algo.train()
        runners = r.get("env_runners", {})
        timers = r.get("timers", {})
        row = {"iteration": it, "wall_s": round(time.perf_counter() - start, 1),
               "env_steps": r.get("num_env_steps_sampled_lifetime", runners.get("num_env_steps_sampled_lifetime")),
               "episode_return_mean": _round(runners.get("episode_return_mean")),
               # RLlib's own split of an iteration: sampling by the runners, the learner's update
               "sample_s": _round(timers.get("env_runner_sampling_timer")),
               "learn_s": _round(timers.get("learner_update_timer")),
               "driver_cpu_s": round(time.process_time(), 1)}
        log.append(row)
        print(json.dumps(row), flush=True)
        if after_iteration is not None:
            after_iteration(it)
    with open(os.path.join(out, "progress.jsonl"), "w") as f:
        f.writelines(json.dumps(row) + "\n" for row in log)
    return log, time.perf_counter() - start
