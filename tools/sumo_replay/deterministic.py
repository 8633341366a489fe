#!/usr/bin/env python3
"""SUMO 1.8 and mapc vehicle by vehicle on a deterministic copy of a SUMO user's scenario: with no dawdling, no
speed deviation and no random draws, both simulators should drive every vehicle alike, so the first vehicle and
step where they part points at a rule of SUMO's that mapc does not follow (docs/sumo_scenarios.md, section
"Five more rules").

    python3 tools/sumo_replay/deterministic.py copy CFG OUT          # OUT/NAME.sumocfg, deterministic
    sumo -c OUT/NAME.sumocfg --seed 0 --fcd-output fcd.xml --xml-validation never
    mapc sim OUT/NAME.sumocfg --seeds 1 --trace trace.csv
    mapc import NET -o g.json
    python3 tools/sumo_replay/deterministic.py first g.json fcd.xml trace.csv [--until T] [--show N]
    python3 tools/sumo_replay/deterministic.py follow g.json fcd.xml trace.csv VEHICLE [--from-time A --to-time B]

- `copy`: the configuration's folder copied to OUT, its route files rewritten: every vType gets sigma 0 and
  speedDev 0, a vTypeDistribution becomes its most probable type (under the distribution's id), a flow by probability
  one by period at the same mean rate (`vehsPerHour` = 3600 p), departPos `random` and `random_free` become
  `base`.
- `first`: per vehicle (mapc's trace ids matched to SUMO's by where and when each first appears, or, for one of
  each first seen on the same road in the same step, by that alone: an insertion on another lane), the first step
  where its road, lane (on a road), place or speed differ (by more than the FCD's rounding), earliest first.
- `follow`: one SUMO vehicle's steps beside mapc's, `<<` where they differ.

FCD and trace are read with `roads.py`'s readers (trace times one step earlier, so that both name a step alike).
mapc's own floating-car data may stand for the trace (`mapc sim OUT/NAME.sumocfg --seeds 1 --fcd-output
mapc_fcd.xml`): it names vehicles and lanes as SUMO does, so vehicles are matched by name and lane indices agree
where a road has lanes closed to cars.
Standard library only; SUMO is a reference, never needed by mapc.
"""
import argparse
import os
import shutil
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import roads  # noqa: E402

# the FCD writes two decimals
TOLERANCE = 0.011


def route_files(cfg_path):
    """The route files a configuration names, relative to its folder."""
    root = ET.parse(cfg_path).getroot()
    out = []
    for el in root.iter("route-files"):
        out += [f.strip() for f in el.get("value", "").split(",") if f.strip()]
    return out


def make_deterministic(routes_root):
    for dist in list(routes_root.iter("vTypeDistribution")):
        types = dist.findall("vType")
        if not types:
            continue
        # the most probable type (the first of equals)
        common = max(types, key=lambda t: (float(t.get("probability", "1")), -types.index(t)))
        common.set("id", dist.get("id"))
        common.attrib.pop("probability", None)
        index = list(routes_root).index(dist)
        routes_root.remove(dist)
        routes_root.insert(index, common)
    for vtype in routes_root.iter("vType"):
        vtype.set("sigma", "0")
        vtype.set("speedDev", "0")
    for el in routes_root.iter():
        if el.tag == "flow" and el.get("probability") is not None:
            p = float(el.attrib.pop("probability"))
            el.set("vehsPerHour", "%g" % (p * 3600))
        if el.get("departPos") in ("random", "random_free"):
            el.set("departPos", "base")


def cmd_copy(a):
    # the configuration is read before anything is copied: a missing or broken one copies nothing
    routes = route_files(a.cfg)
    src = os.path.dirname(os.path.abspath(a.cfg))
    out = os.path.abspath(a.out)
    if out == src or out.startswith(src + os.sep):
        raise SystemExit("deterministic.py copy: %s lies inside the configuration's folder %s" % (a.out, src))
    shutil.copytree(src, out, dirs_exist_ok=True)
    for rel in routes:
        path = os.path.join(a.out, rel)
        tree = ET.parse(path)
        make_deterministic(tree.getroot())
        tree.write(path, encoding="UTF-8", xml_declaration=True)
    print(os.path.join(a.out, os.path.basename(a.cfg)))


def rows(a, to_time):
    edges = roads.sumo_edges(a.graph)
    sumo = [(round(r[0], 2),) + tuple(r[1:]) for r in roads.fcd_rows(a.fcd, 0, to_time)]
    mapc = [(round(r[0], 2),) + tuple(r[1:]) for r in roads.mapc_rows(a.trace, edges, 0, to_time)]
    return sumo, mapc


def matched(sumo, mapc):
    """SUMO vehicle -> mapc vehicle, by the step, edge, lane and place (to 0.1 m) where each first appears; then,
    among the vehicles left, by the step and edge alone where one of each appears there (inserted on another lane
    or at another place: their first step is then a difference). Returns the map and how many the second pass
    matched."""
    def firsts(rs):
        f = {}
        for r in rs:
            f.setdefault(r[1], r)
        return f

    def one_to_one(sumo_firsts, mapc_firsts, key):
        by_key, sumo_by_key = {}, {}
        for v, r in mapc_firsts.items():
            by_key.setdefault(key(r), []).append(v)
        for v, r in sumo_firsts.items():
            sumo_by_key.setdefault(key(r), []).append(v)
        return {v: by_key[k][0] for k, vs in sumo_by_key.items() for v in vs
                if len(vs) == 1 and len(by_key.get(k, [])) == 1}

    sumo_firsts, mapc_firsts = firsts(sumo), firsts(mapc)
    # mapc's floating-car data names each vehicle as SUMO does
    named = {v: v for v in sumo_firsts if v in mapc_firsts}
    if len(named) * 2 > len(sumo_firsts):
        return named, 0
    out = one_to_one(sumo_firsts, mapc_firsts, lambda r: (r[0], r[2], r[3], round(r[4], 1)))
    taken = set(out.values())
    second = one_to_one({v: r for v, r in sumo_firsts.items() if v not in out},
                        {v: r for v, r in mapc_firsts.items() if v not in taken},
                        lambda r: (r[0], r[2]))
    out.update(second)
    return out, len(second)


def same(s, m):
    internal = s[2].startswith(":")
    same_edge = s[2] == m[2] or (internal and m[2].startswith(":"))
    return (same_edge and (internal or s[3] == m[3]) and abs(s[4] - m[4]) <= TOLERANCE
            and abs(s[5] - m[5]) <= TOLERANCE)


def fmt(r):
    return "%s %d %.2f %.2f" % (r[2], r[3], r[4], r[5])


def cmd_first(a):
    sumo, mapc = rows(a, a.until)
    names, by_road = matched(sumo, mapc)
    steps = {(r[1], r[0]): r for r in mapc}
    unmatched = sorted({r[1] for r in sumo} - set(names))
    print("%d SUMO vehicles matched (%d of them by their first step and road alone: another lane or place), %d not "
          "(first seen elsewhere in mapc)%s" % (
              len(names), by_road, len(unmatched), (": " + ", ".join(unmatched[:8])) if unmatched else ""))
    found, done = [], set()
    for r in sumo:
        v = r[1]
        if v in done or v not in names:
            continue
        m = steps.get((names[v], r[0]))
        if m is not None and not same(r, m):
            done.add(v)
            found.append((r[0], v, fmt(r), fmt(m)))
    found.sort()
    if not found:
        print("no difference before %g s" % a.until)
    for t, v, s, m in found[:a.show]:
        print("%8.2f  %-24s SUMO %-32s mapc %s" % (t, v, s, m))


def cmd_follow(a):
    sumo, mapc = rows(a, a.to_time)
    names, _ = matched(sumo, mapc)
    if a.vehicle not in names:
        raise SystemExit("deterministic.py: %s is not matched to a vehicle of mapc's" % a.vehicle)
    steps = {r[0]: r for r in mapc if r[1] == names[a.vehicle]}
    print("%s: mapc's vehicle %s" % (a.vehicle, names[a.vehicle]))
    for r in sumo:
        if r[1] == a.vehicle and a.from_time <= r[0] <= a.to_time:
            m = steps.get(r[0])
            mark = "" if m is not None and same(r, m) else "  <<"
            print("%8.2f  SUMO %-32s mapc %s%s" % (r[0], fmt(r), fmt(m) if m else "-", mark))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("copy")
    c.add_argument("cfg")
    c.add_argument("out")
    for name in ("first", "follow"):
        p = sub.add_parser(name)
        p.add_argument("graph")
        p.add_argument("fcd")
        p.add_argument("trace")
        if name == "first":
            p.add_argument("--until", type=float, default=float("inf"))
            p.add_argument("--show", type=int, default=10)
        else:
            p.add_argument("vehicle")
            p.add_argument("--from-time", type=float, default=0.0)
            p.add_argument("--to-time", type=float, default=float("inf"))
    a = ap.parse_args()
    try:
        {"copy": cmd_copy, "first": cmd_first, "follow": cmd_follow}[a.cmd](a)
    except (OSError, ET.ParseError, KeyError, ValueError) as e:
        raise SystemExit("deterministic.py %s: %s" % (a.cmd, e))


if __name__ == "__main__":
    main()
