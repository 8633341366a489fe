#!/usr/bin/env python3
"""Run a mapc scenario in SUMO 1.8 and put SUMO's figures beside mapc's (see README.md).

  sumo_check.py baseline SCENARIO [--seeds 0-99]           humans in mapc and in SUMO
  sumo_check.py policy SCENARIO --policy FILE [--seeds ..]  a mapc policy driving the AVs in mapc and in SUMO,
                                                           beside each simulator's humans
  sumo_check.py scenario X.sumocfg [--seeds 0-19]          a SUMO user's scenario as it is, in SUMO 1.8 and in
                                                           mapc (`mapc sim X.sumocfg`)
  sumo_check.py alinea SCENARIO [--seeds ..] [--alinea-*]  ALINEA metering the scenario's light in mapc and in
                                                           SUMO (through TraCI), beside each simulator's humans

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
import recorded  # noqa: E402
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


def export(mapc, scenario, work, avs=()):
    out_dir = os.path.join(work, "export")
    run_mapc(mapc, ["export", scenario, "--sumo", out_dir] + list(avs))
    manifests = [f for f in os.listdir(out_dir) if f.endswith(".mapc.json")]
    with open(os.path.join(out_dir, manifests[0])) as f:
        return out_dir, json.load(f)


def export_digest(out_dir):
    """SHA-256 over the exported SUMO inputs (net, routes, sumocfg; names and bytes): SUMO's runs depend on
    nothing else, so runs recorded for the same digest and seeds can be reused (--sumo-runs)."""
    import hashlib
    h = hashlib.sha256()
    for name in sorted(os.listdir(out_dir)):
        if name.endswith(".mapc.json"):
            continue
        h.update(name.encode() + b"\0")
        with open(os.path.join(out_dir, name), "rb") as f:
            h.update(f.read() + b"\0")
    return h.hexdigest()


def _one(job):
    export_dir, manifest, seed, policy_path, alinea = job
    import traci
    from episode import run_episode
    from policy import Policy
    policy = Policy(policy_path) if policy_path else None
    label = "s%d_%d_%s" % (os.getpid(), seed, "p" if policy_path else "a" if alinea else "h")
    # traci prints its connection retries on stdout, where the table goes.
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
        r = run_episode(traci, manifest, export_dir, seed, policy, label=label, alinea=alinea)
    r["seed"] = seed
    return r


def run_sumo(export_dir, manifest, seeds, policy_path, jobs, alinea=None):
    t0 = time.time()
    with multiprocessing.Pool(jobs) as pool:
        runs = pool.map(_one, [(export_dir, manifest, s, policy_path, alinea) for s in seeds], chunksize=1)
    what = "policy" if policy_path else "ALINEA" if alinea else "humans"
    print("  SUMO %s: %d seeds in %.0f s" % (what, len(seeds), time.time() - t0), file=sys.stderr)
    return runs


def point_metrics(manifest):
    """The measurement points' rows: past each measured merge, then past the corridor's end (both per hour of the
    horizon after the warm-up, as mapc's `merges` and `end_flow`)."""
    rows = [("merge_flow_%d" % i, "past %s, veh/h after warm-up" % p["name"])
            for i, p in enumerate(manifest.get("measure_points", []))]
    if manifest.get("end_edge"):
        rows.append(("end_flow", "past the corridor's end, veh/h after warm-up"))
    return rows


REASONS = ("strategic", "cooperative", "speed_gain", "keep_right")


def reason_metrics(multi_lane):
    """Lane changes per vehicle by the lane-change model's reason (mapc's `lane_changes_by_reason`, SUMO's
    --lanechange-output), on networks with a road of several lanes."""
    if not multi_lane:
        return []
    return [("lc_" + r, "  of which %s / veh" % r.replace("_", " ")) for r in REASONS]


def _per_veh_reason(r, key):
    reasons = r.get("lane_changes_by_reason") or {}
    return reasons.get(key[3:], float("nan")) / r["departed"] if r["departed"] else 0.0


def _mean(values):
    m, ci, sd = stats.mean_ci(values)
    return dict(mean=m, ci95=ci, std=sd, n=len(values))


def _sumo_lane_changes_per_veh(r):
    """SUMO's lane changes per vehicle as its --lanechange-output counts them (every change, as mapc counts its
    own). The TraCI count (a vehicle on the same road in another lane from one step to the next) misses the
    changes made in the step a vehicle enters a road; it stands in for runs recorded before the output was read."""
    if "lane_changes_output" in r:
        total = r["lane_changes_output"]
    elif r.get("lane_changes_by_reason"):
        # runs saved before the total was kept: LC2013 gives every change one of the four reasons
        total = sum(r["lane_changes_by_reason"].values())
    else:
        return r[LANE_CHANGES]
    return total / r["departed"] if r["departed"] else 0.0


def summary_of_runs(runs, points):
    out = {key: _mean([r[key] for r in runs]) for key, _ in METRICS if key != LANE_CHANGES}
    out[LANE_CHANGES] = _mean([_sumo_lane_changes_per_veh(r) for r in runs])
    for key, _ in points:
        if key.startswith("lc_"):
            out[key] = _mean([_per_veh_reason(r, key) for r in runs])
        elif key == "end_flow":
            out[key] = _mean([r["end_flow"] for r in runs])
        else:
            i = int(key.rsplit("_", 1)[1])
            out[key] = _mean([r["merge_flows"][i] for r in runs])
    return out


def summary_of_mapc(block, n, points):
    out = {k: dict(mean=block[k]["mean"], ci95=block[k]["ci95"], std=stats.sd_from_ci(block[k]["ci95"], n), n=n)
           for k, _ in METRICS if k != LANE_CHANGES}
    nan = float("nan")
    # `mapc eval --json` gives the means only: the per-run columns are then left empty
    runs = block.get("runs")
    if runs is None:
        for key in [LANE_CHANGES] + [k for k, _ in points]:
            out[key] = dict(mean=nan, ci95=nan, std=nan, n=0)
        # a policy's `mapc eval` has {"flow": summary}; a controller's block has the summary itself
        end = block.get("end_flow") or {}
        end = end if "mean" in end else end.get("flow")
        if end and "end_flow" in out:
            out["end_flow"] = dict(mean=end["mean"], ci95=end["ci95"], std=stats.sd_from_ci(end["ci95"], n), n=n)
        return out
    out[LANE_CHANGES] = _mean([r["lane_changes"] / r["departed"] if r["departed"] else 0.0 for r in runs])
    for key, _ in points:
        if key.startswith("lc_"):
            out[key] = _mean([_per_veh_reason(r, key) for r in runs])
        elif key == "end_flow":
            out[key] = _mean([r.get("end_flow_veh_h", nan) for r in runs])
        else:
            i = int(key.rsplit("_", 1)[1])
            out[key] = _mean([(r.get("merge_flows_veh_h") or [nan] * (i + 1))[i] for r in runs])
    return out


def fmt(s, decimals=2):
    return "%.*f ± %.*f" % (decimals, s["mean"], decimals, s["ci95"])


def welch_line(a, b):
    if a["n"] == 0 or b["n"] == 0:
        return "n/a"
    if b["mean"] == 0:
        return "%+.3f (difference)" % (a["mean"] - b["mean"])
    t, p = stats.welch(a["mean"], a["std"], a["n"], b["mean"], b["std"], b["n"])
    p_text = "p < 1e-15" if p < 1e-15 else "p %.2g" % p
    return "%+.2f %% (t %.1f, %s)" % (100.0 * (a["mean"] / b["mean"] - 1.0), t, p_text)


def print_table(columns, comparisons, points=()):
    names = [c[0] for c in columns]
    print("| metric | " + " | ".join(names) + " | " + " | ".join(c[0] for c in comparisons) + " |")
    print("|---" * (1 + len(columns) + len(comparisons)) + "|")
    for key, label in list(METRICS) + list(points):
        if key == LANE_CHANGES and all(c[1][key]["mean"] == 0 for c in columns):
            continue  # one-lane roads: nobody changes lanes
        if key.startswith("lc_") and all(c[1][key]["mean"] == 0 for c in columns):
            continue
        cells = [fmt(c[1][key], 3 if key == LANE_CHANGES or key.startswith("lc_") else 2) for c in columns]
        comps = [welch_line(a[key], b[key]) for _, a, b in comparisons]
        print("| %s | %s | %s |" % (label, " | ".join(cells), " | ".join(comps)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["baseline", "policy", "scenario", "curve", "alinea"])
    ap.add_argument("scenario")
    ap.add_argument("--policy", help="a centralized mapc policy file (policies/*.json)")
    ap.add_argument("--seeds", default="0-99", help="SUMO seeds and as many mapc seeds from 0 (default 0-99)")
    ap.add_argument("--mapc", default=None, help="the mapc binary (default: target/release/mapc)")
    ap.add_argument("--work", default=None, help="folder for the export (default: a temporary one)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count(), help="SUMO processes at once")
    ap.add_argument("--json", dest="json_out", help="also write every run and summary here")
    ap.add_argument("--sumo-runs", help="baseline, scenario: reuse SUMO's runs from an earlier --json of the same "
                                        "export (inputs) and seeds instead of running SUMO")
    ap.add_argument("--skip-unsupported", action="store_true",
                    help="scenario: mapc drops what it does not simulate (SUMO still runs it)")
    ap.add_argument("--end", type=float, help="scenario: end time for SUMO where the configuration has none")
    ap.add_argument("--split-trip", type=float, help="scenario: also count the runs whose mean trip duration is "
                                                     "at most / above this many seconds (free / broken down)")
    ap.add_argument("--inflows", default="1000:3000:250",
                    help="curve: inflows LOW:HIGH:STEP in veh/h (every flow scaled to each)")
    ap.add_argument("--svg", help="curve: draw both curves into this file")
    ap.add_argument("--av-share", help="baseline/policy: this share of each flow's vehicles are AVs, as mapc's "
                                       "--av-share gives them (export, humans and policy alike)")
    for name in ("light", "detectors", "setpoint", "gain", "green"):
        ap.add_argument("--alinea-" + name, help="alinea: as `mapc eval --alinea-%s`" % name)
    a = ap.parse_args()
    if a.mode == "scenario":
        import scenario
        root = os.path.dirname(os.path.dirname(HERE))
        scenario.compare(a, [a.mapc or os.path.join(root, "target", "release", "mapc")], parse_seeds(a.seeds))
        return
    if a.mode == "curve":
        import curve
        root = os.path.dirname(os.path.dirname(HERE))
        work = a.work or tempfile.mkdtemp(prefix="sumo_curve_")
        try:
            curve.curve(a, [a.mapc or os.path.join(root, "target", "release", "mapc")], parse_seeds(a.seeds),
                        work, sys.modules[__name__])
        finally:
            if not a.work:
                shutil.rmtree(work, ignore_errors=True)
        return
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
    avs = ["--av-share", a.av_share] if a.av_share else []
    export_dir, manifest = export(mapc, a.scenario, work, avs)
    n = len(seeds)
    mapc_h = mapc_json(mapc, ["sim", "--scenario", a.scenario, "--seeds", str(n)] + avs)
    multi_lane = any(r["lane_changes"] > 0 for r in mapc_h["runs"])
    points = reason_metrics(multi_lane) + point_metrics(manifest)
    mapc_h = summary_of_mapc(mapc_h, n, points)
    digest = export_digest(export_dir)
    if a.sumo_runs:
        sumo_h_runs = recorded.reuse(a.sumo_runs, "export_sha256", digest, "sumo_human_runs", seeds, "export")
    else:
        sumo_h_runs = run_sumo(export_dir, manifest, seeds, None, a.jobs)
    sumo_h = summary_of_runs(sumo_h_runs, points)
    result = dict(scenario=a.scenario, seeds=a.seeds, export_sha256=digest, mapc_humans=mapc_h,
                  sumo_humans=sumo_h, sumo_human_runs=sumo_h_runs)
    print("%s, %d seeds, SUMO %s" % (a.scenario, n, manifest["sumo_version"]))
    if a.mode == "alinea":
        import alinea_check
        alinea_check.compare(a, mapc, seeds, export_dir, manifest, points, mapc_h, sumo_h, result,
                             sys.modules[__name__])
    elif a.mode == "baseline":
        print_table([("mapc humans", mapc_h), ("SUMO humans", sumo_h)],
                    [("mapc vs SUMO", mapc_h, sumo_h)], points)
    else:
        ev = mapc_json(mapc, ["eval", "--policy", a.policy, "--scenario", a.scenario, "--seeds", str(n)] + avs)
        mapc_p = summary_of_mapc(ev, n, points)
        sumo_p_runs = run_sumo(export_dir, manifest, seeds, a.policy, a.jobs)
        sumo_p = summary_of_runs(sumo_p_runs, points)
        result.update(policy=a.policy, mapc_policy=mapc_p, sumo_policy=sumo_p, sumo_policy_runs=sumo_p_runs)
        print("policy %s" % a.policy)
        print_table([("mapc humans", mapc_h), ("mapc policy", mapc_p), ("SUMO humans", sumo_h),
                     ("SUMO policy", sumo_p)],
                    [("policy vs humans, mapc", mapc_p, mapc_h), ("policy vs humans, SUMO", sumo_p, sumo_h),
                     ("mapc vs SUMO, humans", mapc_h, sumo_h), ("mapc vs SUMO, policy", mapc_p, sumo_p)],
                    points)
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
