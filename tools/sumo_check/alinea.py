"""ALINEA ramp metering in SUMO 1.8 through TraCI, as mapc runs it (crates/mapc-sim/src/runs/alinea.rs): each
detector's occupancy is summed over its own interval (its `freq`, from the start of the run), the way SUMO's
induction loop writes it; once every detector has closed a new interval, the rate moves by
r = clamp(r + K_R (100 o_set - o_mean), r_min, r_max) veh/h per metered lane, and the light restarts a program of
`green_s` green and the red that makes the cycle last 3600 / r seconds. The meter starts at r_max.

Which light and which detectors are mapc's own choice (`mapc eval --controller alinea --json` names them), so
this file holds the control law only, not mapc's defaults."""


class Alinea:
    def __init__(self, conn, cfg, step_s):
        self.tl, self.loops = conn.trafficlight, conn.inductionloop
        self.light = cfg["light"]
        self.detectors = list(cfg["detectors"])
        self.periods = cfg["periods"]
        self.setpoint, self.gain = cfg["setpoint"], cfg["gain_veh_h"]
        self.r_min, self.r_max = cfg["min_rate_veh_h"], cfg["max_rate_veh_h"]
        self.green = cfg["green_s"]
        self.step_s = step_s
        self.links = len(self.tl.getRedYellowGreenState(self.light))
        self.rate = self.r_max
        self.sum = dict.fromkeys(self.detectors, 0.0)
        self.elapsed = dict.fromkeys(self.detectors, 0.0)
        self.fresh = dict.fromkeys(self.detectors)
        self.rates = []
        self._program()

    def _program(self):
        Logic, Phase = self.tl.Logic, self.tl.Phase
        cycle = 3600.0 / self.rate
        phases = [Phase(self.green, "G" * self.links)]
        if cycle > self.green + 1e-9:
            phases.append(Phase(cycle - self.green, "r" * self.links))
        self.tl.setProgramLogic(self.light, Logic("alinea", 0, 0, phases))
        self.tl.setProgram(self.light, "alinea")
        self.tl.setPhase(self.light, 0)

    def after_step(self):
        for d in self.detectors:
            # the share of the step the loop was occupied, in per cent
            self.sum[d] += self.loops.getLastStepOccupancy(d) * self.step_s
            self.elapsed[d] += self.step_s
            if self.elapsed[d] >= self.periods[d] - 1e-9:
                self.fresh[d] = self.sum[d] / self.elapsed[d]
                self.sum[d], self.elapsed[d] = 0.0, 0.0
        if all(v is not None for v in self.fresh.values()):
            occupancy = sum(self.fresh.values()) / len(self.fresh)
            self.fresh = dict.fromkeys(self.detectors)
            r = self.rate + self.gain * (100.0 * self.setpoint - occupancy)
            self.rate = min(max(r, self.r_min), self.r_max)
            self.rates.append(self.rate)
            self._program()
