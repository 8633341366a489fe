"""`sumo_check scenario CFG`: a SUMO user's scenario run as it is in SUMO 1.8 (`sumo -c CFG`) and in mapc
(`mapc sim CFG`), seed by seed, and the figures of both side by side with the goals of docs/sumo_scenarios.md.

Per run, from SUMO's summary output and lane-change output, and from mapc's `sim --json` runs:
  inserted, arrived         vehicles in the run
  trip duration             mean over the arrived (SUMO: the last step's meanTravelTime)
  speed                     mean over the steps with a vehicle of the running vehicles' mean speed
  lane changes / veh        lane changes over inserted vehicles
  flow at DETECTOR          each induction loop's vehicles passed per hour of the run (SUMO: its own output
                            files, the nVehContrib of every interval; mapc: `detectors` of `sim --json`)
"""
import json
import multiprocessing
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import recorded
import stats

GOALS = (("inserted", 0.01), ("arrived", 0.01), ("duration", 0.03), ("speed", 0.05), ("lane_changes_per_veh", 0.20))
DETECTOR_GOAL = 0.03
LABELS = {"inserted": "inserted veh", "arrived": "arrived veh", "duration": "trip duration s",
          "speed": "speed m/s", "lane_changes_per_veh": "lane changes / veh"}


def sumo18_copy(cfg, tmp):
    """The configuration's folder copied into `tmp`, with the one attribute SUMO 1.8 names otherwise: induction
    loops' `period` (SUMO 1.8's `freq`). Returns the copied configuration's path."""
    src = os.path.dirname(os.path.abspath(cfg))
    dst = os.path.join(tmp, "scenario")
    shutil.copytree(src, dst)
    for folder, _, names in os.walk(dst):
        for n in names:
            if n.endswith(".xml"):
                path = os.path.join(folder, n)
                with open(path, encoding="utf-8", errors="surrogateescape") as f:
                    text = f.read()
                fixed = re.sub(r"(<(?:inductionLoop|e1Detector)\b[^>]*?)\bperiod=", r"\1freq=", text)
                if fixed != text:
                    with open(path, "w", encoding="utf-8", errors="surrogateescape") as f:
                        f.write(fixed)
    return os.path.join(dst, os.path.basename(cfg))


def _sumo_one(job):
    cfg, seed, end, extra = job
    with tempfile.TemporaryDirectory(prefix="sumo_scn_") as tmp:
        cfg = sumo18_copy(cfg, tmp)
        summary = os.path.join(tmp, "summary.xml")
        changes = os.path.join(tmp, "lc.xml")
        cmd = ["sumo", "-c", os.path.abspath(cfg), "--seed", str(seed), "--no-step-log", "true",
               "--xml-validation", "never", "--xml-validation.net", "never",
               "--summary-output", summary, "--lanechange-output", changes, "--output-prefix", ""] + extra
        if end is not None:
            cmd += ["--end", str(end)]
        out = subprocess.run(cmd, capture_output=True, text=True, cwd=os.path.dirname(os.path.abspath(cfg)))
        if out.returncode != 0:
            # an exception, not SystemExit: the pool hands it to the caller instead of losing its worker
            raise RuntimeError("SUMO failed on %s seed %d:\n%s" % (cfg, seed, out.stderr[-2000:]))
        steps = ET.parse(summary).getroot().findall("step")
        last = steps[-1].attrib
        speeds = [float(s.get("meanSpeed")) for s in steps if int(s.get("running")) > 0]
        n_changes = sum(1 for _ in ET.parse(changes).getroot().iter("change"))
        inserted = int(last["inserted"])
        run = dict(seed=seed, inserted=inserted, arrived=int(last["arrived"]),
                   duration=float(last["meanTravelTime"]), speed=sum(speeds) / max(1, len(speeds)),
                   lane_changes_per_veh=n_changes / max(1, inserted), teleports=int(last.get("teleports", 0)))
        run.update(detector_flows(os.path.dirname(cfg)))
        return run


def detector_flows(folder):
    """`det:ID` -> vehicles per hour, from every E1 output file under `folder` (all its intervals)."""
    passed, span = {}, {}
    for sub, _, names in os.walk(folder):
        for n in names:
            if not n.endswith(".xml"):
                continue
            try:
                root = ET.parse(os.path.join(sub, n)).getroot()
            except ET.ParseError:
                continue
            if root.tag != "detector":
                continue
            for i in root.iter("interval"):
                key = "det:" + i.get("id")
                passed[key] = passed.get(key, 0) + int(i.get("nVehContrib"))
                b, e = float(i.get("begin")), float(i.get("end"))
                lo, hi = span.get(key, (b, e))
                span[key] = (min(lo, b), max(hi, e))
    return {k: 3600.0 * passed[k] / max(1e-9, span[k][1] - span[k][0]) for k in passed}


def run_sumo(cfg, seeds, end, extra, jobs):
    with multiprocessing.Pool(jobs) as pool:
        try:
            return pool.map(_sumo_one, [(cfg, s, end, extra) for s in seeds], chunksize=1)
        except RuntimeError as e:
            raise SystemExit("sumo_check: %s" % e)


def run_mapc(mapc, cfg, n, skip):
    args = mapc + ["sim", cfg, "--seeds", str(n), "--json"] + (["--skip-unsupported"] if skip else [])
    out = subprocess.run(args, capture_output=True, text=True)
    if out.returncode != 0:
        sys.stderr.write(out.stderr)
        raise SystemExit(2)
    d = json.loads(out.stdout)
    runs = []
    ids = [x["id"] for x in d.get("detectors", [])]
    for r in d["runs"]:
        run = dict(inserted=r["departed"], arrived=r["arrived"], duration=r["mean_travel_time_s"],
                   speed=r["avg_speed_mps"], lane_changes_per_veh=r["lane_changes"] / max(1, r["departed"]),
                   teleports=r.get("teleports", 0))
        run.update({"det:" + i: f for i, f in zip(ids, r.get("detector_flows_veh_h", []))})
        runs.append(run)
    return runs, d


def inputs_digest(cfg, end):
    """SHA-256 over what SUMO's runs depend on: the configuration, the files it names (net, route and additional
    files; names and bytes) and the end time asked, so that runs recorded for the same digest and seeds can be
    reused (--sumo-runs) while only mapc changes."""
    import hashlib
    folder = os.path.dirname(os.path.abspath(cfg))
    named = [os.path.abspath(cfg)]
    for e in ET.parse(cfg).getroot().iter():
        if e.tag in ("net-file", "route-files", "additional-files") and e.get("value"):
            named += [os.path.join(folder, v.strip()) for v in e.get("value").split(",") if v.strip()]
    h = hashlib.sha256(repr(end).encode() + b"\0")
    for path in named:
        h.update(os.path.relpath(path, folder).encode() + b"\0")
        with open(path, "rb") as f:
            h.update(f.read() + b"\0")
    return h.hexdigest()


def print_split(limit, sims):
    """Runs that broke down and runs that did not, told apart by their mean trip duration: how many of each and
    their mean trip, per simulator (a scenario at the edge of breakdown differs in how often, or in how much)."""
    print("  runs by mean trip duration, at most / above %g s:" % limit)
    for name, runs in sims:
        low = [r["duration"] for r in runs if r["duration"] <= limit]
        high = [r["duration"] for r in runs if r["duration"] > limit]
        mean = lambda x: "%.1f s" % (sum(x) / len(x)) if x else "-"
        print("    %-9s %4d runs, %s / %4d runs, %s" % (name, len(low), mean(low), len(high), mean(high)))


def compare(a, mapc, seeds):
    cfg = a.scenario
    t0 = time.time()
    mapc_runs, mapc_d = run_mapc(mapc, cfg, len(seeds), a.skip_unsupported)
    mapc_s = time.time() - t0
    end = a.end
    digest = inputs_digest(cfg, end)
    t0 = time.time()
    if a.sumo_runs:
        sumo_runs = recorded.reuse(a.sumo_runs, "inputs_sha256", digest, "sumo_runs", seeds,
                                   "inputs and --end")
    else:
        sumo_runs = run_sumo(cfg, seeds, end, [], a.jobs)
    sumo_s = time.time() - t0
    rows = []
    print("%s, %d seeds (mapc %.1f s, SUMO %.1f s wall on %d processes%s)" % (
        cfg, len(seeds), mapc_s, sumo_s, a.jobs, ", reused" if a.sumo_runs else ""))
    print("  %-20s %22s %22s %9s %7s  %s" % ("", "mapc", "SUMO 1.8", "diff", "goal", ""))
    detectors = sorted(k for k in mapc_runs[0] if k.startswith("det:") and all(k in r for r in sumo_runs))
    for key, goal in list(GOALS) + [(k, DETECTOR_GOAL) for k in detectors]:
        mm, mci, _ = stats.mean_ci([r[key] for r in mapc_runs])
        sm, sci, _ = stats.mean_ci([r[key] for r in sumo_runs])
        diff = (mm - sm) / sm if sm else float("nan")
        ok = abs(diff) <= goal
        rows.append(dict(metric=key, mapc=mm, mapc_ci=mci, sumo=sm, sumo_ci=sci, diff=diff, goal=goal, met=ok))
        print("  %-20s %14.3f ± %-6.3f %14.3f ± %-6.3f %+8.2f%% %6.0f%%  %s" % (
            LABELS.get(key, "flow at " + key[4:]), mm, mci, sm, sci, 100 * diff, 100 * goal, "ok" if ok else "MISSED"))
    if a.split_trip is not None:
        print_split(a.split_trip, (("mapc", mapc_runs), ("SUMO 1.8", sumo_runs)))
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump(dict(scenario=cfg, seeds=a.seeds, inputs_sha256=digest, rows=rows, mapc_runs=mapc_runs,
                           sumo_runs=sumo_runs), f,
                      indent=1)
