#!/usr/bin/env python3
"""Where a SUMO user's scenario loses its trip time, vehicle by vehicle: SUMO 1.8's and mapc's trip-info files of
the same seeds (`--tripinfo-output`, the same elements and attributes in both), each vehicle's mean duration over
the seeds in each simulator, grouped by where it enters and leaves (the edges of its departure and arrival
lanes), the groups ordered by how much of the whole difference they hold.

    for s in 0 1 2 3 4 5 6 7 8 9; do
      mapc sim CFG --seeds 1 --first-seed $s --tripinfo-output MAPC_DIR/$s.xml
      sumo -c CFG --seed $s --tripinfo-output SUMO_DIR/$s.xml --xml-validation never
    done
    # a configuration that names outputs of its own writes them beside it: redirect them (eccles_interchange:
    # --vehroute-output /tmp/routes.xml; ramp_game: --netstate-dump /tmp/n.xml, and its additional file's
    # tlsstate output, by running a copy of its folder)
    python3 tools/sumo_replay/trips.py MAPC_DIR SUMO_DIR [--show 12]

Standard library only; SUMO is a reference, never needed by mapc.
"""
import argparse
import collections
import os
import xml.etree.ElementTree as ET


def edge_of(lane):
    """A lane id's edge: `E_2` -> `E`, `:J_0_1` -> `:J_0`."""
    return lane.rsplit("_", 1)[0] if lane else "?"


def durations(folder):
    """vehicle -> (its durations over the files, (from edge, to edge))."""
    out = collections.defaultdict(lambda: ([], None))
    files = sorted(f for f in os.listdir(folder) if f.endswith(".xml"))
    if not files:
        raise SystemExit("no trip-info file (*.xml) in %s" % folder)
    for name in files:
        for el in ET.parse(os.path.join(folder, name)).getroot().iter("tripinfo"):
            runs, _ = out[el.get("id")]
            runs.append(float(el.get("duration")))
            out[el.get("id")] = (runs, (edge_of(el.get("departLane")), edge_of(el.get("arrivalLane"))))
    return out, len(files)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mapc")
    ap.add_argument("sumo")
    ap.add_argument("--show", type=int, default=12, help="groups to print (default 12)")
    a = ap.parse_args()
    (m, nm), (s, ns) = durations(a.mapc), durations(a.sumo)
    both = sorted(set(m) & set(s))
    groups = collections.defaultdict(lambda: [0, 0.0, 0.0])
    for v in both:
        (dm, od), (ds, _) = m[v], s[v]
        g = groups[od]
        g[0] += 1
        g[1] += sum(dm) / len(dm)
        g[2] += sum(ds) / len(ds)
    total_m = sum(g[1] for g in groups.values())
    total_s = sum(g[2] for g in groups.values())
    print("%d vehicles that arrived in both (mapc: %d files, SUMO: %d); mean trip %.1f s in mapc, %.1f s in SUMO "
          "(%+.2f %%)" % (len(both), nm, ns, total_m / max(len(both), 1), total_s / max(len(both), 1),
                          100.0 * (total_m / total_s - 1.0) if total_s else float("nan")))
    print("| enters at | leaves at | vehicles | mapc s | SUMO s | mapc vs SUMO | share of the difference |")
    print("|---|---|---|---|---|---|---|")
    diff = total_m - total_s
    rows = sorted(groups.items(), key=lambda kv: -abs(kv[1][1] - kv[1][2]))
    for (frm, to), (n, sm, ss) in rows[:a.show]:
        share = (sm - ss) / diff if diff else float("nan")
        print("| %s | %s | %d | %.1f | %.1f | %+.1f %% | %.0f %% |"
              % (frm, to, n, sm / n, ss / n, 100.0 * (sm / ss - 1.0), 100.0 * share))


if __name__ == "__main__":
    main()
