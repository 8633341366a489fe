#!/usr/bin/env python3
"""Compare mapc's one-step predictions (replay_step's output) with SUMO's next states, per zone of the network.

    python3 tools/sumo_replay/compare.py STATES.jsonl NEXT.jsonl [--show N] [--tol 1e-3]
"""
import argparse
import collections
import json


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("states")
    ap.add_argument("nexts")
    ap.add_argument("--show", type=int, default=5)
    ap.add_argument("--tol", type=float, default=1e-3)
    args = ap.parse_args()
    states = [json.loads(l) for l in open(args.states)]
    nexts = [json.loads(l)["next"] for l in open(args.nexts)]
    total, bad = collections.Counter(), collections.Counter()
    examples = collections.defaultdict(list)
    for k in range(len(states) - 1):
        now = {r[0]: r for r in states[k]["veh"]}
        later = {r[0]: r for r in states[k + 1]["veh"]}
        for vid, r in now.items():
            if vid not in later or vid not in nexts[k]:
                continue
            lane, pos = r[1], r[2]
            zone = lane if lane != "left_0" else ("left_0 < 400 m" if pos < 400 else "left_0 >= 400 m")
            err = nexts[k][vid] - later[vid][3]
            total[zone] += 1
            if abs(err) > args.tol:
                bad[zone] += 1
                examples[zone].append((states[k]["t"], vid, round(pos, 2), round(r[3], 3),
                                       "sumo", round(later[vid][3], 3), "mapc", round(nexts[k][vid], 3)))
    all_n, all_bad = sum(total.values()), sum(bad.values())
    for zone in sorted(total):
        print(f"{zone:18s} {total[zone]:7d} vehicle-steps, {bad[zone]:5d} differ by more than {args.tol} m/s "
              f"({100 * bad[zone] / total[zone]:.2f} %)")
        for e in examples[zone][:args.show]:
            print("    ", e)
    print(f"all: {all_n} vehicle-steps, {100 * (1 - all_bad / max(all_n, 1)):.2f} % match")


if __name__ == "__main__":
    main()
