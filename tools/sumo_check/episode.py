"""One SUMO 1.8 episode of an exported scenario, the way the paper's Flow code ran it (REFERENCE.md sec. 2):
sumo with the export's sumocfg and the seed, the set-up steps (the initial vehicles enter in the second), then the
horizon; every vehicle gets speed mode 9 when it departs, and on a one-lane network lane-change mode 512 (on a
network with a road of several lanes SUMO's default mode, LC2013 as mapc drives it); the mean speed of the vehicles
in the network is sampled before each step (steps with mean 0 skipped); departures and arrivals are counted per
step; a lane change is a vehicle's lane index changing on the same edge from one horizon step to the next. With a policy, the controlled AVs are chosen and observed before each step and their accelerations are
applied as Flow did: next speed max(v + a dt, 0) through slowDown, capped by SUMO's safe speed (speed mode 9)."""
import os

SPEED_MODE = 9
LANE_CHANGE_MODE = 512


def sumo_command(manifest, export_dir, seed):
    cfg = os.path.join(export_dir, manifest["files"]["config"])
    return ["sumo", "-c", cfg, "--seed", str(seed), "--no-step-log", "true", "--no-warnings", "false"]


def run_episode(traci, manifest, export_dir, seed, policy=None, label="sumo_check"):
    import subprocess

    import traci.constants as tc
    # SUMO's own progress lines would interleave with the table; its warnings (stderr) stay visible.
    traci.start(sumo_command(manifest, export_dir, seed), label=label, stdout=subprocess.DEVNULL)
    conn = traci.getConnection(label)
    try:
        return _episode(conn, tc, manifest, policy)
    finally:
        conn.close()


def _episode(conn, tc, manifest, policy):
    V, S = conn.vehicle, conn.simulation
    step_s = manifest["step_s"]
    S.subscribe([tc.VAR_DEPARTED_VEHICLES_IDS, tc.VAR_ARRIVED_VEHICLES_IDS])
    av_types = set(manifest["av_types"])
    region = set(manifest["control_edges"]) | set(manifest.get("control_internal_edges", []))
    is_av = {}
    entry = {}
    min_gap = {}
    multi_lane = any(conn.edge.getLaneNumber(e) > 1 for e in conn.edge.getIDList() if not e.startswith(":"))

    def on_departed(ids):
        for v in ids:
            V.setSpeedMode(v, SPEED_MODE)
            if not multi_lane:
                V.setLaneChangeMode(v, LANE_CHANGE_MODE)
            V.subscribe(v, [tc.VAR_SPEED, tc.VAR_ROAD_ID, tc.VAR_LANE_INDEX])
            t = V.getTypeID(v)
            is_av[v] = t in av_types
            min_gap[v] = V.getMinGap(v)
            entry[v] = len(entry)

    for _ in range(manifest["setup_steps"]):
        conn.simulationStep()
        on_departed(S.getSubscriptionResults()[tc.VAR_DEPARTED_VEHICLES_IDS])
    for _ in range(manifest["warmup_steps"]):
        conn.simulationStep()
        on_departed(S.getSubscriptionResults()[tc.VAR_DEPARTED_VEHICLES_IDS])

    from policy import ControlQueue
    queue = ControlQueue()
    speeds, departed, arrived = [], 0, 0
    controlled_steps = 0
    lane_changes, lane_of = 0, {}
    for _ in range(manifest["horizon_steps"]):
        state = V.getAllSubscriptionResults()
        for v, r in state.items():
            now = (r[tc.VAR_ROAD_ID], r[tc.VAR_LANE_INDEX])
            before = lane_of.get(v)
            if before is not None and before[0] == now[0] and before[1] != now[1]:
                lane_changes += 1
            lane_of[v] = now
        if state:
            m = sum(r[tc.VAR_SPEED] for r in state.values()) / len(state)
            if m > 0:
                speeds.append(m)
        if policy is not None:
            controlled_steps += _act(V, policy, queue, state, tc, region, is_av, entry, min_gap, step_s)
        conn.simulationStep()
        res = S.getSubscriptionResults()
        dep = res[tc.VAR_DEPARTED_VEHICLES_IDS]
        arr = res[tc.VAR_ARRIVED_VEHICLES_IDS]
        on_departed(dep)
        departed += len(dep)
        arrived += len(arr)
    horizon_s = manifest["horizon_steps"] * step_s
    return dict(outflow=3600.0 * arrived / horizon_s, inflow=3600.0 * departed / horizon_s,
                speed=sum(speeds) / len(speeds) if speeds else 0.0, arrived=arrived, departed=departed,
                lane_changes=lane_changes, lane_changes_per_veh=lane_changes / departed if departed else 0.0,
                controlled_av_steps=controlled_steps)


def _act(V, policy, queue, state, tc, region, is_av, entry, min_gap, step_s):
    """Choose, observe and drive the controlled AVs; returns how many were driven."""
    present = sorted((v for v, r in state.items()
                      if is_av.get(v) and (not region or r[tc.VAR_ROAD_ID] in region)), key=entry.get)
    controlled = queue.update(present, policy.n_av)
    length = policy.norm_length
    views = []
    for v in controlled:
        speed = state[v][tc.VAR_SPEED]
        leader = follower = None
        lead = V.getLeader(v, length)
        if lead is not None and lead[0]:
            # SUMO measures from the ego's front plus its min gap; mapc bumper to bumper.
            leader = (V.getSpeed(lead[0]), lead[1] + min_gap[v])
        fol = V.getFollower(v, length)
        if fol is not None and fol[0]:
            follower = (V.getSpeed(fol[0]), fol[1] + min_gap.get(fol[0], 0.0))
        views.append((speed, leader, follower))
    action = policy.mean_action(policy.observe(views))
    for k, v in enumerate(controlled):
        a = policy.clamp(action[k])
        v_now = state[v][tc.VAR_SPEED]
        V.slowDown(v, max(v_now + a * step_s, 0.0), 1e-3)
    return len(controlled)
