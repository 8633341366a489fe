#!/usr/bin/env python3
"""Where and by whom lanes are changed, in SUMO 1.8 and in mapc, on one seed of an exported scenario.

SUMO's changes come from its --lanechange-output (vehicle, time, edge, from and to lane, reason); mapc's from
its trace (a vehicle's lane index changing on the same road from one step to the next; mapc's trace has no
reason, its run's `lane_changes_by_reason` has the totals). Printed: per edge and direction the changes in each
simulator (SUMO's by reason), then how many vehicles changed 0, 1, 2, ... times, and the vehicles of SUMO that
changed most, each with its changes in order.

    mapc export SCENARIO --sumo /tmp/x
    sumo -c /tmp/x/NAME.sumocfg --seed 0 --lanechange-output /tmp/x/lc.xml
    mapc sim --scenario SCENARIO --seeds 1 --trace /tmp/x/trace.csv
    python3 tools/sumo_replay/lane_changes.py /tmp/x/NAME.mapc.json /tmp/x/lc.xml /tmp/x/trace.csv
"""
import argparse
import collections
import csv
import json
import xml.etree.ElementTree as ET

REASONS = (("strategic", "strategic"), ("cooperative", "cooperative"), ("speedGain", "speed gain"),
           ("keepRight", "keep right"))


def reason_of(text):
    for sumo_name, ours in REASONS:
        if sumo_name in text:
            return ours
    return text or "?"


def sumo_changes(path, start_s):
    """[(vehicle, time, edge, from lane, to lane, reason)] after `start_s`."""
    out = []
    for _, el in ET.iterparse(path):
        if el.tag == "change" and float(el.get("time")) > start_s + 1e-9:
            from_lane, to_lane = el.get("from"), el.get("to")
            edge = from_lane.rsplit("_", 1)[0]
            out.append((el.get("id"), float(el.get("time")), edge, int(from_lane.rsplit("_", 1)[1]),
                        int(to_lane.rsplit("_", 1)[1]), reason_of(el.get("reason", ""))))
        el.clear()
    return out


def mapc_changes(path, edge_of):
    """[(vehicle, time, edge, from lane, to lane)] from a trace: the lane index changing on the same road."""
    out, last = [], {}
    with open(path) as f:
        for row in csv.DictReader(f):
            v, road, lane = row["vehicle_id"], row["road"], int(row.get("lane") or 0)
            before = last.get(v)
            if before is not None and before[0] == road and before[1] != lane and ">" not in road:
                out.append((v, float(row["time_s"]), edge_of.get(road, road), before[1], lane))
            last[v] = (road, lane)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("manifest", help="the export's NAME.mapc.json")
    ap.add_argument("lanechanges", help="SUMO's --lanechange-output")
    ap.add_argument("trace", help="mapc sim --trace of the same seed")
    ap.add_argument("--show", type=int, default=5, help="SUMO vehicles with the most changes to list")
    a = ap.parse_args()
    with open(a.manifest) as f:
        manifest = json.load(f)
    start_s = (manifest["setup_steps"] + manifest["warmup_steps"]) * manifest["step_s"]
    sumo = sumo_changes(a.lanechanges, start_s)
    mapc = mapc_changes(a.trace, manifest["edges"])
    places = collections.defaultdict(collections.Counter)
    for _, _, edge, fl, tl, reason in sumo:
        places[(edge, "left" if tl > fl else "right")]["SUMO " + reason] += 1
        places[(edge, "left" if tl > fl else "right")]["SUMO"] += 1
    for _, _, edge, fl, tl in mapc:
        places[(edge, "left" if tl > fl else "right")]["mapc"] += 1
    print("%d changes in SUMO, %d in mapc (after %.1f s)" % (len(sumo), len(mapc), start_s))
    print("edge, direction: SUMO (by reason) / mapc")
    for (edge, side), c in sorted(places.items(), key=lambda kv: -kv[1]["SUMO"] - kv[1]["mapc"]):
        reasons = ", ".join("%s %d" % (k[5:], n) for k, n in sorted(c.items()) if k.startswith("SUMO "))
        print("  %-28s %-5s SUMO %5d (%s) / mapc %5d" % (edge, side, c["SUMO"], reasons, c["mapc"]))
    for name, rows in (("SUMO", sumo), ("mapc", mapc)):
        per_vehicle = collections.Counter(r[0] for r in rows)
        histogram = collections.Counter(per_vehicle.values())
        print("%s: vehicles by changes made: %s" % (name, ", ".join(
            "%d x %d" % (n, histogram[n]) for n in sorted(histogram))))
    per_vehicle = collections.defaultdict(list)
    for v, t, edge, fl, tl, reason in sumo:
        per_vehicle[v].append("%.1f s %s %d->%d %s" % (t, edge, fl, tl, reason))
    for v in sorted(per_vehicle, key=lambda v: -len(per_vehicle[v]))[:a.show]:
        print("  SUMO %s: %s" % (v, "; ".join(per_vehicle[v])))


if __name__ == "__main__":
    main()
