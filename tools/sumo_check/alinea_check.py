"""`sumo_check alinea`: ALINEA metering a scenario's light in mapc (`mapc eval --controller alinea`) and in SUMO
1.8 (`alinea.py` through TraCI, on mapc's export: the light's program and the loops), beside each simulator's
humans. mapc names the light and the detectors it meters with (its defaults, or the `--alinea-*` given); SUMO's
runs use the same ones, and each loop's interval is its `freq` in the export's additional file."""
import os
import xml.etree.ElementTree as ET


def loop_periods(export_dir):
    periods = {}
    for name in os.listdir(export_dir):
        if name.endswith(".add.xml"):
            for el in ET.parse(os.path.join(export_dir, name)).getroot().iter("inductionLoop"):
                periods[el.get("id")] = float(el.get("freq") or el.get("period"))
    return periods


def compare(a, mapc, seeds, export_dir, manifest, points, mapc_h, sumo_h, result, check):
    n = len(seeds)
    # (the humans are `mapc_h`, run once by the caller: eval's own baseline would run them again)
    args = ["eval", "--controller", "alinea", "--scenario", a.scenario, "--seeds", str(n), "--no-baseline"]
    for name in ("light", "detectors", "setpoint", "gain", "green"):
        value = getattr(a, "alinea_" + name)
        if value is not None:
            args += ["--alinea-" + name, value]
    ev = check.mapc_json(mapc, args)
    periods = loop_periods(export_dir)
    missing = [d for d in ev["detectors"] if d not in periods]
    if missing:
        raise SystemExit("the export has no loop %s" % ", ".join(missing))
    cfg = dict(light=ev["light"], detectors=ev["detectors"], periods=periods, setpoint=ev["setpoint"],
               gain_veh_h=ev["gain_veh_h"], green_s=ev["green_s"], min_rate_veh_h=ev["min_rate_veh_h"],
               max_rate_veh_h=ev["max_rate_veh_h"])
    # (its runs give the per-run columns: lane changes, their reasons, the merges' flows)
    mapc_a = check.summary_of_mapc(dict(ev["alinea"], runs=ev["alinea_runs"]), n, points)
    sumo_a_runs = check.run_sumo(export_dir, manifest, seeds, None, a.jobs, alinea=cfg)
    sumo_a = check.summary_of_runs(sumo_a_runs, points)
    rates = [r for run in sumo_a_runs for r in run["meter_rates"]]
    sumo_rate = sum(rates) / len(rates) if rates else float("nan")
    result.update(alinea=cfg, mapc_alinea=mapc_a, sumo_alinea=sumo_a, sumo_alinea_runs=sumo_a_runs,
                  mapc_mean_rate=ev["mean_rate_veh_h"], sumo_mean_rate=sumo_rate)
    print("ALINEA on light %s, loops %s, set-point %.0f %%, K_R %g veh/h; mean rate %.0f veh/h in mapc, %.0f in SUMO"
          % (cfg["light"], ", ".join(cfg["detectors"]), 100 * cfg["setpoint"], cfg["gain_veh_h"],
             ev["mean_rate_veh_h"], sumo_rate))
    check.print_table([("mapc humans", mapc_h), ("mapc ALINEA", mapc_a), ("SUMO humans", sumo_h),
                       ("SUMO ALINEA", sumo_a)],
                      [("ALINEA vs humans, mapc", mapc_a, mapc_h), ("ALINEA vs humans, SUMO", sumo_a, sumo_h),
                       ("mapc vs SUMO, humans", mapc_h, sumo_h), ("mapc vs SUMO, ALINEA", mapc_a, sumo_a)],
                      points)
