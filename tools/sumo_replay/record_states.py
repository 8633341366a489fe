#!/usr/bin/env python3
"""Record SUMO 1.8's full state of the Simple Merge every step, for mapc's vehicle-by-vehicle replay.

Runs Flow's reference rollout of the Simple Merge (speed mode 9, 5 initial vehicles; the rollout's scripts,
`run_merge.py` and `build_merge.py`, are not part of this repository: `--sumo-ref DIR` or `MAPC_SUMO_REF` names
their folder) through TraCI and writes one JSON line per step: {"t": s, "veh": [[id, lane, pos, speed, speed_factor, waiting_s,
leader_id, leader_gap], ...]}. SUMO is a reference only; mapc never needs it.

    python3 tools/sumo_replay/record_states.py --seed 0 --out /tmp/states0.jsonl
    cargo run --release -p mapc-sim --example replay_step -- /tmp/states0.jsonl > /tmp/next0.jsonl
    python3 tools/sumo_replay/compare.py /tmp/states0.jsonl /tmp/next0.jsonl
"""
import argparse
import json
import os
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True)
    ap.add_argument("--sumo-ref", default=os.environ.get("MAPC_SUMO_REF"), required="MAPC_SUMO_REF" not in os.environ,
                    help="the folder of the reference rollout's run_merge.py")
    ap.add_argument("--cfg", default="/tmp/merge_net/merge.sumocfg",
                    help="the Simple Merge built by the reference's build_merge.py")
    args = ap.parse_args()
    sys.path.insert(0, os.path.abspath(args.sumo_ref))
    import run_merge as rm  # the reference's command line and initial vehicles
    import traci

    traci.start(rm.sumo_args(args.seed, args.cfg))
    veh, sim = traci.vehicle, traci.simulation
    factor = {}

    def departed(ids):
        for v in ids:
            veh.setSpeedMode(v, 9)
            veh.setLaneChangeMode(v, 512)
            factor[v] = veh.getSpeedFactor(v)

    traci.simulationStep()
    for vid, edge, pos in rm.INITIAL:
        veh.add(vid, "route%s_0" % edge, typeID="human", departLane="0", departPos=str(pos), departSpeed="0")
    traci.simulationStep()
    departed(sim.getDepartedIDList())
    with open(args.out, "w") as out:
        for _ in range(rm.HORIZON):
            rows = []
            for v in veh.getIDList():
                lead = veh.getLeader(v, 200)
                rows.append([v, veh.getLaneID(v), veh.getLanePosition(v), veh.getSpeed(v), factor.get(v, 1.0),
                             veh.getWaitingTime(v), lead[0] if lead else None, lead[1] if lead else None])
            out.write(json.dumps({"t": sim.getTime(), "veh": rows}) + "\n")
            traci.simulationStep()
            departed(sim.getDepartedIDList())
    traci.close()


if __name__ == "__main__":
    main()
