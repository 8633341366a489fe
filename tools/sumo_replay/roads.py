#!/usr/bin/env python3
"""Where on the road SUMO 1.8 and mapc differ, for one seed of a SUMO user's scenario: SUMO's FCD output beside
mapc's trace of the same configuration, mapc's roads named by their SUMO edges (the `provenance` of
`mapc import NET -o G.json`).

    sumo -c CFG --seed 0 --fcd-output fcd.xml --tripinfo-output sumo_trips.xml --xml-validation never
    mapc sim CFG --seeds 1 --trace trace.csv --tripinfo-output mapc_trips.xml
    mapc import NET -o g.json
    python3 tools/sumo_replay/roads.py time g.json fcd.xml trace.csv                   # vehicle-seconds per road
    python3 tools/sumo_replay/roads.py leave g.json fcd.xml trace.csv EDGE --lane 0 --from FROM_EDGE
    python3 tools/sumo_replay/roads.py stop-line g.json fcd.xml trace.csv EDGE --cycle 10 --phase 9
    python3 tools/sumo_replay/roads.py entries g.json fcd.xml trace.csv EDGE --cycle 10
    python3 tools/sumo_replay/roads.py departures sumo_trips.xml mapc_trips.xml --lane-prefix entry_ --until 3600
    python3 tools/sumo_replay/roads.py speeds g.json fcd.xml trace.csv EDGE1,EDGE2 --bucket 50
    python3 tools/sumo_replay/roads.py inserted g.json fcd.xml trace.csv EDGE

- `time`: per road, the vehicle-seconds spent on it and the vehicles seen on it, largest difference first.
- `leave`: for the vehicles coming from FROM_EDGE, where (per 20 m of EDGE) they leave its lane `--lane`:
  entering EDGE on another lane counts at their first place there.
- `stop-line`: at the steps whose time modulo `--cycle` is `--phase`, the distance to EDGE's end of the first
  vehicle on it if it stands (below 0.1 m/s): a queue at a light.
- `entries`: how many vehicles first appear on EDGE, per second of the `--cycle` (a light's cycle).
- `speeds`: per edge, position (per `--bucket` m) and lane, the mean speed in both.
- `inserted`: per lane of EDGE, the vehicles first seen there (inserted, on an entry road), their mean place and
  speed.
- `places`: SUMO's and mapc's floating-car data (`roads.py places fcd.xml mapc_fcd.xml`): at every step, lane and
  place both have a vehicle, how far apart they draw it and at which angle (the back on its lane, or behind).
- `departures`: per trip-info file, the vehicles that departed on lanes named `--lane-prefix...` before
  `--until`, and the mean departure delay of all of them.

FCD and trace may each be several files, comma-separated (runs of several seeds, pooled; mapc's `sim --first-seed
S --seeds 1 --trace` writes seed S's). The runs' `--end` (or horizon) and `--begin` must match; with `--from-time` and `--to-time` only the steps in
between count.
mapc's trace stamps a frame with the end of its step, SUMO's FCD with its begin: trace times are read one step
earlier, so that both name a step alike. In place of the trace, mapc's own floating-car data (`mapc sim
--fcd-output mapc_fcd.xml`) is read as SUMO's is: SUMO's lane ids (the lanes closed to cars counted, as on
Ingolstadt's sidewalks) and SUMO's vehicle names. A trace thinned by its budget (one frame in k) gives vehicle-seconds
scaled by k. Standard library only; SUMO is a reference, never needed by mapc.
"""
import argparse
import collections
import csv
import json
import xml.etree.ElementTree as ET


def sumo_edges(graph_path):
    """mapc road id -> its SUMO edge id."""
    with open(graph_path) as f:
        g = json.load(f)
    out = {}
    for r in g["roads"]:
        ids = r.get("provenance", {}).get("sumo_ids") or []
        out[r["id"]] = ids[0] if ids else r["id"]
    return out


def fcd_rows(path, from_time, to_time):
    """(time, vehicle, edge, lane index, pos, speed); a junction's lane has its own `:` edge."""
    t = None
    for _, el in ET.iterparse(path, events=("start",)):
        if el.tag == "timestep":
            t = float(el.get("time"))
        elif el.tag == "vehicle" and from_time <= t < to_time:
            edge, index = el.get("lane").rsplit("_", 1)
            yield t, el.get("id"), edge, int(index), float(el.get("pos")), float(el.get("speed"))


def is_xml(path):
    """Whether `path` is an XML file (mapc's `--fcd-output`) rather than a CSV trace, by its first character."""
    with open(path, "rb") as f:
        return f.read(1) == b"<"


def mapc_rows(path, edges, from_time, to_time):
    """mapc's rows: from its floating-car data (`mapc sim --fcd-output`: SUMO's lane ids and vehicle names, SUMO's
    time stamps) or from its trace."""
    if is_xml(path):
        return fcd_rows(path, from_time, to_time)
    return trace_rows(path, edges, from_time, to_time)


def trace_rows(path, edges, from_time, to_time):
    """The same rows from a mapc trace, its roads named by their SUMO edges, its times one step earlier."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    times = sorted({float(r["time_s"]) for r in rows[:10000]})
    step = min((b - a for a, b in zip(times, times[1:])), default=1.0)
    for r in rows:
        t = float(r["time_s"]) - step
        if not from_time <= t < to_time:
            continue
        road = r["road"]
        edge = ":" + road if ">" in road else edges.get(road, road)
        yield t, r["vehicle_id"], edge, int(r["lane"]), float(r["pos_on_road_m"]), float(r["speed_mps"])


def both(a):
    """SUMO's rows and mapc's; FCD and trace may each be several files, comma-separated (seeds pooled: each file's
    vehicle ids get its index as a prefix)."""
    edges = sumo_edges(a.graph)

    def pooled(paths, read):
        paths = paths.split(",")
        rows = []
        for k, path in enumerate(paths):
            for t, v, *rest in read(path):
                rows.append((t, v if len(paths) == 1 else "%d:%s" % (k, v), *rest))
        return rows

    return (("SUMO", pooled(a.fcd, lambda p: fcd_rows(p, a.from_time, a.to_time))),
            ("mapc", pooled(a.trace, lambda p: mapc_rows(p, edges, a.from_time, a.to_time))))


def step_of(rows):
    times = sorted({r[0] for r in rows[:10000]})
    return min((b - a for a, b in zip(times, times[1:])), default=1.0)


def cmd_time(a):
    per = {}
    for name, rows in both(a):
        secs, vehs, dt = collections.Counter(), collections.defaultdict(set), step_of(rows)
        for t, v, edge, _, _, _ in rows:
            if not edge.startswith(":"):
                secs[edge] += dt
                vehs[edge].add(v)
        per[name] = (secs, vehs)
    (_, (ss, sv)), (_, (ms, mv)) = per.items()
    print("vehicle-seconds: SUMO %.0f, mapc %.0f" % (sum(ss.values()), sum(ms.values())))
    print("%-40s %12s %12s %8s %8s %8s" % ("road", "SUMO veh-s", "mapc veh-s", "diff", "SUMO n", "mapc n"))
    for e in sorted(set(ss) | set(ms), key=lambda e: -abs(ms[e] - ss[e]))[:a.show]:
        print("%-40s %12.0f %12.0f %+7.1f%% %8d %8d" % (
            e, ss[e], ms[e], 100 * (ms[e] / ss[e] - 1) if ss[e] else 0.0, len(sv[e]), len(mv[e])))


def cmd_leave(a):
    for name, rows in both(a):
        came = {v for _, v, edge, _, _, _ in rows if edge == a.from_edge}
        left = {}
        on_lane = set()
        for t, v, edge, lane, pos, _ in sorted(rows, key=lambda r: (r[1], r[0])):
            if v not in came or v in left or edge != a.edge:
                continue
            if lane == a.lane:
                on_lane.add(v)
            else:
                left[v] = pos
        bins = collections.Counter(min(int(p // 20) * 20, a.last_bin) for p in left.values())
        print("%s: %d vehicles leave lane %d of %s; per 20 m from its start: %s" % (
            name, len(left), a.lane, a.edge, ", ".join("%d" % bins[b] for b in range(0, a.last_bin + 1, 20))))


def cmd_stop_line(a):
    edges_len = {}
    with open(a.graph) as f:
        for r in json.load(f)["roads"]:
            ids = r.get("provenance", {}).get("sumo_ids") or [r["id"]]
            edges_len[ids[0]] = r["length_m"]
    length = edges_len[a.edge]
    for name, rows in both(a):
        first = {}
        for t, v, edge, _, pos, speed in rows:
            if edge == a.edge and round(t) % a.cycle == a.phase:
                if t not in first or pos > first[t][0]:
                    first[t] = (pos, speed)
        dists = [length - p for p, s in first.values() if s < 0.1]
        mean = sum(dists) / len(dists) if dists else float("nan")
        print("%s: %d times a vehicle stood first; %.2f m before the end on average" % (name, len(dists), mean))


def cmd_entries(a):
    for name, rows in both(a):
        first = {}
        for t, v, edge, _, _, _ in rows:
            if edge == a.edge and v not in first:
                first[v] = t
        times = list(first.values())
        cycles = (max(times) - min(times)) / a.cycle if times else 0
        phases = collections.Counter(int(round(t)) % a.cycle for t in times)
        print("%s: %d vehicles, %.2f a cycle; by second of the cycle: %s" % (
            name, len(times), len(times) / cycles if cycles else 0.0,
            ", ".join("%d: %d" % (p, phases[p]) for p in sorted(phases))))


def cmd_speeds(a):
    edges = a.edges.split(",")
    per = {}
    for name, rows in both(a):
        sums = collections.defaultdict(list)
        for _, _, edge, lane, pos, speed in rows:
            if edge in edges:
                sums[(edge, int(pos // a.bucket), lane)].append(speed)
        per[name] = sums
    mean = lambda x: "%5.1f" % (sum(x) / len(x)) if x else "    -"
    for e in edges:
        keys = [k for d in per.values() for k in d if k[0] == e]
        if not keys:
            print("%s: no vehicle" % e)
            continue
        lanes = sorted({k[2] for k in keys})
        print("%s, mean speed m/s per %g m and lane, mapc / SUMO (samples)" % (e, a.bucket))
        for b in range(max(k[1] for k in keys) + 1):
            cells = []
            for lane in lanes:
                m, s = per["mapc"].get((e, b, lane), []), per["SUMO"].get((e, b, lane), [])
                cells.append("L%d %s/%s (%d/%d)" % (lane, mean(m), mean(s), len(m), len(s)))
            print("%6.0f  %s" % (b * a.bucket, "  ".join(cells)))


def cmd_inserted(a):
    for name, rows in both(a):
        first = {}
        for t, v, edge, lane, pos, speed in sorted(rows, key=lambda r: r[0]):
            if v not in first:
                first[v] = (edge, lane, pos, speed)
        by = collections.defaultdict(list)
        for edge, lane, pos, speed in first.values():
            if edge == a.edge:
                by[lane].append((pos, speed))
        print("%s: per lane of %s, vehicles first seen there, their mean place (m) and speed (m/s): %s" % (
            name, a.edge, "; ".join("L%d %d at %.1f, %.2f" % (
                lane, len(x), sum(p for p, _ in x) / len(x), sum(v for _, v in x) / len(x))
                for lane, x in sorted(by.items()))))


def cmd_departures(a):
    for path in a.tripinfo:
        d = [(float(e.get("depart")), float(e.get("departDelay")))
             for _, e in ET.iterparse(path) if e.tag == "tripinfo" and e.get("departLane", "").startswith(a.lane_prefix)]
        before = sum(1 for t, _ in d if t < a.until)
        print("%s: %d of %d departed before %.0f s; mean departure delay %.1f s" % (
            path, before, len(d), a.until, sum(x for _, x in d) / len(d) if d else float("nan")))


def fcd_places(path):
    """(time, vehicle) -> (lane, pos, x, y, angle) of an FCD file (SUMO's, or mapc's `--fcd-output`)."""
    out, t = {}, None
    for _, el in ET.iterparse(path, events=("start",)):
        if el.tag == "timestep":
            t = el.get("time")
        elif el.tag == "vehicle":
            out[(t, el.get("id"))] = (el.get("lane"), float(el.get("pos")), float(el.get("x")), float(el.get("y")),
                                      float(el.get("angle")))
    return out


def cmd_places(a):
    """Where both files have a vehicle at the same step, lane and place (to the FCD's rounding), how far apart
    they draw it and at which angles: mapc's geometry against SUMO's, whatever the dynamics."""
    sumo, mapc = fcd_places(a.fcd), fcd_places(a.mapc_fcd)
    dist, angle, behind = [], [], []
    for key, (lane, pos, x, y, ang) in sumo.items():
        m = mapc.get(key)
        if m is None or m[0] != lane or abs(m[1] - pos) > 0.011:
            continue
        dist.append(((m[2] - x) ** 2 + (m[3] - y) ** 2) ** 0.5)
        d = abs(m[4] - ang) % 360.0
        (behind if pos < a.length else angle).append(min(d, 360.0 - d))

    def stats(xs, unit):
        xs = sorted(xs)
        if not xs:
            return "none"
        return "%d rows, median %.3f %s, 95th percentile %.3f, largest %.3f" % (
            len(xs), xs[len(xs) // 2], unit, xs[int(0.95 * (len(xs) - 1))], xs[-1])

    print("distance between the points: %s" % stats(dist, "m"))
    print("angle, the back on the same lane: %s" % stats(angle, "degrees"))
    print("angle, the back on a lane behind (position below %.1f m): %s" % (a.length, stats(behind, "degrees")))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)

    def runs(p):
        p.add_argument("graph", help="mapc import NET -o G.json of the scenario's network")
        p.add_argument("fcd", help="SUMO's --fcd-output")
        p.add_argument("trace", help="mapc's --trace")
        p.add_argument("--from-time", type=float, default=0.0, help="count the steps from this time on")
        p.add_argument("--to-time", type=float, default=float("inf"), help="and before this one")
        return p

    runs(sub.add_parser("time")).add_argument("--show", type=int, default=12)
    p = runs(sub.add_parser("leave"))
    p.add_argument("edge")
    p.add_argument("--lane", type=int, default=0)
    p.add_argument("--from", dest="from_edge", required=True, help="the edge the vehicles come from")
    p.add_argument("--last-bin", type=int, default=160, help="the last 20 m bin (it holds the rest)")
    p = runs(sub.add_parser("stop-line"))
    p.add_argument("edge")
    p.add_argument("--cycle", type=int, default=10)
    p.add_argument("--phase", type=int, default=9)
    p = runs(sub.add_parser("entries"))
    p.add_argument("edge")
    p.add_argument("--cycle", type=int, default=10)
    p = runs(sub.add_parser("speeds"))
    p.add_argument("edges", help="edges, comma-separated")
    p.add_argument("--bucket", type=float, default=50.0, help="metres per row")
    runs(sub.add_parser("inserted")).add_argument("edge")
    p = sub.add_parser("departures")
    p.add_argument("tripinfo", nargs="+")
    p.add_argument("--lane-prefix", default="")
    p.add_argument("--until", type=float, default=3600.0)
    p = sub.add_parser("places")
    p.add_argument("fcd", help="SUMO's --fcd-output")
    p.add_argument("mapc_fcd", help="mapc's --fcd-output of the same configuration")
    p.add_argument("--length", type=float, default=5.0, help="the vehicles' length (m)")
    a = ap.parse_args()
    {"places": cmd_places, "time": cmd_time, "leave": cmd_leave, "stop-line": cmd_stop_line, "entries": cmd_entries,
     "speeds": cmd_speeds, "inserted": cmd_inserted, "departures": cmd_departures}[a.cmd](a)


if __name__ == "__main__":
    main()
