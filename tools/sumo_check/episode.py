"""One SUMO 1.8 episode of an exported scenario, the way the paper's Flow code ran it (docs/reference.md sec. 2):
sumo with the export's sumocfg and the seed, the set-up steps (the initial vehicles enter in the second), then the
horizon; every vehicle gets speed mode 9 when it departs, and on a one-lane network lane-change mode 512 (on a
network with a road of several lanes SUMO's default mode, LC2013 as mapc drives it); the mean speed of the vehicles
in the network is sampled before each step (steps with mean 0 skipped); departures and arrivals are counted per
step; a lane change is a vehicle's lane index changing on the same edge from one horizon step to the next; the
flow past each of mapc's measurement points and past the corridor's end is counted as mapc counts it (`Passages`).
With a policy, the controlled AVs are chosen and observed before each step and their accelerations are
applied as Flow did: next speed max(v + a dt, 0) through slowDown, capped by SUMO's safe speed (speed mode 9).
With ALINEA (`alinea.py`), the meter acts after every step from the first, as mapc's does."""
import os

SPEED_MODE = 9
LANE_CHANGE_MODE = 512


def sumo_command(manifest, export_dir, seed):
    cfg = os.path.join(export_dir, manifest["files"]["config"])
    return ["sumo", "-c", cfg, "--seed", str(seed), "--no-step-log", "true", "--no-warnings", "false"]


REASONS = ("strategic", "cooperative", "speed_gain", "keep_right")
# SUMO's names of the lane-change reasons in --lanechange-output (the first one a change's reason names).
SUMO_REASONS = (("strategic", "strategic"), ("cooperative", "cooperative"), ("speedGain", "speed_gain"),
                ("keepRight", "keep_right"))


def run_episode(traci, manifest, export_dir, seed, policy=None, label="sumo_check", alinea=None):
    import subprocess
    import tempfile

    import traci.constants as tc
    lc_dir = tempfile.mkdtemp(prefix="sumo_lc_")
    lc_file = os.path.join(lc_dir, "lanechanges.xml")
    # SUMO's own progress lines would interleave with the table; its warnings (stderr) stay visible.
    traci.start(sumo_command(manifest, export_dir, seed) + ["--lanechange-output", lc_file], label=label,
                stdout=subprocess.DEVNULL)
    conn = traci.getConnection(label)
    try:
        result = _episode(conn, tc, manifest, policy, alinea)
    finally:
        conn.close()
    start_s = (manifest["setup_steps"] + manifest["warmup_steps"]) * manifest["step_s"]
    result["lane_changes_by_reason"], result["lane_changes_output"] = lane_change_reasons(lc_file, start_s)
    os.remove(lc_file)
    os.rmdir(lc_dir)
    return result


def lane_change_reasons(path, start_s):
    """Lane changes in SUMO's --lanechange-output after `start_s` (the horizon): by reason (the first of ours the
    `reason` attribute names: SUMO writes its flags in this order), and all of them, whatever their reason."""
    import xml.etree.ElementTree as ET
    counts = dict.fromkeys(REASONS, 0)
    total = 0
    for _, el in ET.iterparse(path):
        if el.tag != "change":
            continue
        if float(el.get("time")) > start_s + 1e-9:
            total += 1
            reason = el.get("reason", "")
            for sumo_name, ours in SUMO_REASONS:
                if sumo_name in reason:
                    counts[ours] += 1
                    break
        el.clear()
    return counts, total


def _episode(conn, tc, manifest, policy, alinea_cfg=None):
    V, S = conn.vehicle, conn.simulation
    step_s = manifest["step_s"]
    meter = None
    if alinea_cfg is not None:
        from alinea import Alinea
        meter = Alinea(conn, alinea_cfg, step_s)

    def step():
        conn.simulationStep()
        if meter is not None:
            meter.after_step()
    S.subscribe([tc.VAR_DEPARTED_VEHICLES_IDS, tc.VAR_ARRIVED_VEHICLES_IDS])
    av_types = set(manifest["av_types"])
    region = set(manifest["control_edges"]) | set(manifest.get("control_internal_edges", []))
    is_av = {}
    entry = {}
    route_of = {}
    min_gap = {}
    multi_lane = any(conn.edge.getLaneNumber(e) > 1 for e in conn.edge.getIDList() if not e.startswith(":"))

    def on_departed(ids):
        for v in ids:
            V.setSpeedMode(v, SPEED_MODE)
            if not multi_lane:
                V.setLaneChangeMode(v, LANE_CHANGE_MODE)
            V.subscribe(v, [tc.VAR_SPEED, tc.VAR_ROAD_ID, tc.VAR_LANE_INDEX, tc.VAR_ROUTE_INDEX])
            route_of[v] = V.getRoute(v)
            t = V.getTypeID(v)
            is_av[v] = t in av_types
            min_gap[v] = V.getMinGap(v)
            entry[v] = len(entry)

    for _ in range(manifest["setup_steps"]):
        step()
        on_departed(S.getSubscriptionResults()[tc.VAR_DEPARTED_VEHICLES_IDS])
    for _ in range(manifest["warmup_steps"]):
        step()
        on_departed(S.getSubscriptionResults()[tc.VAR_DEPARTED_VEHICLES_IDS])

    from policy import ControlQueue
    queue = ControlQueue()
    points = Passages(manifest)
    points.start(V.getAllSubscriptionResults(), tc)
    speeds, departed, arrived = [], 0, 0
    controlled_steps = 0
    lane_changes, lane_of = 0, {}
    for _ in range(manifest["horizon_steps"]):
        state = V.getAllSubscriptionResults()
        points.seen(state, route_of, tc)
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
        step()
        res = S.getSubscriptionResults()
        dep = res[tc.VAR_DEPARTED_VEHICLES_IDS]
        arr = res[tc.VAR_ARRIVED_VEHICLES_IDS]
        points.arrived(arr, route_of)
        on_departed(dep)
        departed += len(dep)
        arrived += len(arr)
    points.seen(V.getAllSubscriptionResults(), route_of, tc)
    horizon_s = manifest["horizon_steps"] * step_s
    return dict(outflow=3600.0 * arrived / horizon_s, inflow=3600.0 * departed / horizon_s,
                speed=sum(speeds) / len(speeds) if speeds else 0.0, arrived=arrived, departed=departed,
                lane_changes=lane_changes, lane_changes_per_veh=lane_changes / departed if departed else 0.0,
                controlled_av_steps=controlled_steps, end_flow=3600.0 * points.end / horizon_s,
                merge_flows=[3600.0 * c / horizon_s for c in points.counts],
                meter_rates=meter.rates if meter is not None else [])


class Passages:
    """mapc's measurement points in SUMO: a vehicle passes a point when it enters one of the point's edges (its
    route index moves onto it; a vehicle that arrives has entered the rest of its route), and is past the
    corridor's end when it arrives from the manifest's end edge; counted over the horizon (after the warm-up)."""

    def __init__(self, manifest):
        self.point_of = {}
        for i, p in enumerate(manifest.get("measure_points", [])):
            for e in p["edges"]:
                self.point_of[e] = i
        self.counts = [0] * len(manifest.get("measure_points", []))
        self.end_edge = manifest.get("end_edge")
        self.end = 0
        self.index = {}

    def start(self, state, tc):
        for v, r in state.items():
            self.index[v] = r[tc.VAR_ROUTE_INDEX]

    def _entered(self, route, edges):
        for e in edges:
            p = self.point_of.get(e)
            if p is not None:
                self.counts[p] += 1

    def seen(self, state, route_of, tc):
        for v, r in state.items():
            now = r[tc.VAR_ROUTE_INDEX]
            before = self.index.get(v)
            if before is not None and now > before:
                self._entered(route_of[v], route_of[v][before + 1:now + 1])
            self.index[v] = now

    def arrived(self, ids, route_of):
        for v in ids:
            route = route_of.get(v)
            if route is None:
                continue
            before = self.index.pop(v, None)
            if before is not None:
                self._entered(route, route[before + 1:])
            if route[-1] == self.end_edge:
                self.end += 1


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
