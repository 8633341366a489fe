#!/usr/bin/env python3
"""Run a mapc scenario in SUMO 1.8 and put SUMO's figures beside mapc's (see README.md).

  sumo_check.py baseline SCENARIO [--seeds 0-99]           humans in mapc and in SUMO
  sumo_check.py policy SCENARIO --policy FILE [--seeds ..]  a mapc policy driving the AVs in mapc and in SUMO,
                                                           beside each simulator's humans

SCENARIO is what `mapc export` takes (a scenario file or a built-in name); the scenario is exported with
`mapc export SCENARIO --sumo WORK/export` first. Figures: mean ± 95 % CI (Student t) over the seeds, Welch t.
"""
import argparse
import contextlib
import json
import multiprocessing
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import stats  # noqa: E402

METRICS = (("outflow", "outflow veh/h"), ("inflow", "inflow veh/h"), ("speed", "avg speed m/s"),
           ("lane_changes_per_veh", "lane changes / veh"))
# Per run: lane changes in the horizon over the vehicles that departed in it (mapc: `lane_changes` / `departed`).
LANE_CHANGES = "lane_changes_per_veh"


def parse_seeds(text):
    seeds = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            seeds += range(int(a), int(b) + 1)
        else:
            seeds.append(int(part))
    return seeds


def run_mapc(mapc, args):
    """mapc's stdout; mapc's own one-line error and exit code 2 when it refuses (a missing scenario, say)."""
    try:
        out = subprocess.run(mapc + args, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit("sumo_check: no mapc binary at %s (cargo build --release, or --mapc BIN)" % mapc[0])
    if out.returncode != 0:
        sys.stderr.write(out.stderr)
        sys.exit(2)
    return out.stdout


def mapc_json(mapc, args):
    return json.loads(run_mapc(mapc, args + ["--json"]))


def export(mapc, scenario, work):
    out_dir = os.path.join(work, "export")
    run_mapc(mapc, ["export", scenario, "--sumo", out_dir])
    manifests = [f for f in os.listdir(out_dir) if f.endswith(".mapc.json")]
    with open(os.path.join(out_dir, manifests[0])) as f:
        return out_dir, json.load(f)


def _one(job):
    export_dir, manifest, seed, policy_path = job
    import traci
    from episode import run_episode
    from policy import Policy
    policy = Policy(policy_path) if policy_path else None
    label = "s%d_%d_%s" % (os.getpid(), seed, "p" if policy_path else "h")
    # traci prints its connection retries on stdout, where the table goes.
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
        r = run_episode(traci, manifest, export_dir, seed, policy, label=label)
    r["seed"] = seed
    return r


def run_sumo(export_dir, manifest, seeds, policy_path, jobs):
    t0 = time.time()
    with multiprocessing.Pool(jobs) as pool:
        runs = pool.map(_one, [(export_dir, manifest, s, policy_path) for s in seeds], chunksize=1)
    print("  SUMO %s: %d seeds in %.0f s" % ("policy" if policy_path else "humans", len(seeds), time.time() - t0),
          file=sys.stderr)
    return runs


def summary_of_runs(runs):
    out = {}
    for key, _ in METRICS:
        m, ci, sd = stats.mean_ci([r[key] for r in runs])
        out[key] = dict(mean=m, ci95=ci, std=sd, n=len(runs))
    return out


def summary_of_mapc(block, n):
    out = {k: dict(mean=block[k]["mean"], ci95=block[k]["ci95"], std=stats.sd_from_ci(block[k]["ci95"], n), n=n)
           for k, _ in METRICS if k != LANE_CHANGES}
    per_veh = [r["lane_changes"] / r["departed"] if r["departed"] else 0.0 for r in block["runs"]]
    m, ci, sd = stats.mean_ci(per_veh)
    out[LANE_CHANGES] = dict(mean=m, ci95=ci, std=sd, n=len(per_veh))
    return out


def fmt(s, decimals=2):
    return "%.*f ± %.*f" % (decimals, s["mean"], decimals, s["ci95"])


def welch_line(a, b):
    t, p = stats.welch(a["mean"], a["std"], a["n"], b["mean"], b["std"], b["n"])
    p_text = "p < 1e-15" if p < 1e-15 else "p %.2g" % p
    return "%+.2f %% (t %.1f, %s)" % (100.0 * (a["mean"] / b["mean"] - 1.0), t, p_text)


def print_table(columns, comparisons):
    names = [c[0] for c in columns]
    print("| metric | " + " | ".join(names) + " | " + " | ".join(c[0] for c in comparisons) + " |")
    print("|---" * (1 + len(columns) + len(comparisons)) + "|")
    for key, label in METRICS:
        if key == LANE_CHANGES and all(c[1][key]["mean"] == 0 for c in columns):
            continue  # one-lane roads: nobody changes lanes
        cells = [fmt(c[1][key], 3 if key == LANE_CHANGES else 2) for c in columns]
        comps = [welch_line(a[key], b[key]) for _, a, b in comparisons]
        print("| %s | %s | %s |" % (label, " | ".join(cells), " | ".join(comps)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["baseline", "policy"])
    ap.add_argument("scenario")
    ap.add_argument("--policy", help="a centralized mapc policy file (policies/*.json)")
    ap.add_argument("--seeds", default="0-99", help="SUMO seeds and as many mapc seeds from 0 (default 0-99)")
    ap.add_argument("--mapc", default=None, help="the mapc binary (default: target/release/mapc)")
    ap.add_argument("--work", default=None, help="folder for the export (default: a temporary one)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count(), help="SUMO processes at once")
    ap.add_argument("--json", dest="json_out", help="also write every run and summary here")
    a = ap.parse_args()
    if a.mode == "policy" and not a.policy:
        ap.error("policy mode needs --policy FILE")
    root = os.path.dirname(os.path.dirname(HERE))
    mapc = [a.mapc or os.path.join(root, "target", "release", "mapc")]
    seeds = parse_seeds(a.seeds)
    work = a.work or tempfile.mkdtemp(prefix="sumo_check_")
    try:
        compare(a, mapc, seeds, work)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)


def compare(a, mapc, seeds, work):
    export_dir, manifest = export(mapc, a.scenario, work)
    n = len(seeds)
    mapc_h = mapc_json(mapc, ["sim", "--scenario", a.scenario, "--seeds", str(n)])
    mapc_h = summary_of_mapc(mapc_h, n)
    sumo_h_runs = run_sumo(export_dir, manifest, seeds, None, a.jobs)
    sumo_h = summary_of_runs(sumo_h_runs)
    result = dict(scenario=a.scenario, seeds=a.seeds, mapc_humans=mapc_h, sumo_humans=sumo_h,
                  sumo_human_runs=sumo_h_runs)
    print("%s, %d seeds, SUMO %s" % (a.scenario, n, manifest["sumo_version"]))
    if a.mode == "baseline":
        print_table([("mapc humans", mapc_h), ("SUMO humans", sumo_h)],
                    [("mapc vs SUMO", mapc_h, sumo_h)])
    else:
        ev = mapc_json(mapc, ["eval", "--policy", a.policy, "--scenario", a.scenario, "--seeds", str(n)])
        mapc_p = summary_of_mapc(ev, n)
        sumo_p_runs = run_sumo(export_dir, manifest, seeds, a.policy, a.jobs)
        sumo_p = summary_of_runs(sumo_p_runs)
        result.update(policy=a.policy, mapc_policy=mapc_p, sumo_policy=sumo_p, sumo_policy_runs=sumo_p_runs)
        print("policy %s" % a.policy)
        print_table([("mapc humans", mapc_h), ("mapc policy", mapc_p), ("SUMO humans", sumo_h),
                     ("SUMO policy", sumo_p)],
                    [("policy vs humans, mapc", mapc_p, mapc_h), ("policy vs humans, SUMO", sumo_p, sumo_h),
                     ("mapc vs SUMO, humans", mapc_h, sumo_h), ("mapc vs SUMO, policy", mapc_p, sumo_p)])
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
