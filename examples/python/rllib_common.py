"""What the RLlib examples share: Ray's start on loopback, the env seeds of each runner, where the runners run, and
the training loop with its log."""

import json
import os
import socket
import time


def init_ray(address):
    """Join the Ray cluster at `address`, or start a local one whose processes talk over loopback only."""
    import ray

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
