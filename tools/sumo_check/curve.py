"""`sumo_check curve SCENARIO --inflows 1200:3000:200`: a scenario's inflow-outflow curve in mapc and in SUMO 1.8,
point by point. At each inflow every flow of the scenario is scaled so that their rates add up to it (a copy of
the scenario in the work folder); mapc runs it (`mapc sim --json`) and SUMO runs its export (the baseline
episodes of `sumo_check baseline`), on the same seeds. Writes a table, `--json FILE` (every point) and
`--svg FILE` (both curves with their 95 % CIs)."""
import json
import os
import re
import sys

import stats


def scaled_copy(scenario, inflow, work):
    """The scenario with its flows scaled to `inflow` veh/h in all, its relative paths made absolute."""
    with open(scenario) as f:
        text = f.read()
    rates = [float(x) for x in re.findall(r"(?m)^vehs_per_hour\s*=\s*([0-9.eE+-]+)", text)]
    if not rates or sum(rates) <= 0:
        sys.exit("sumo_check curve: %s has no flow with `vehs_per_hour`" % scenario)
    k = inflow / sum(rates)
    text = re.sub(r"(?m)^(vehs_per_hour\s*=\s*)([0-9.eE+-]+)", lambda m: "%s%r" % (m.group(1), float(m.group(2)) * k),
                  text)
    base = os.path.dirname(os.path.abspath(scenario))
    text = re.sub(r'(?m)^((?:map|graph)\s*=\s*)"([^"]+)"',
                  lambda m: '%s"%s"' % (m.group(1), os.path.normpath(os.path.join(base, m.group(2)))), text)
    path = os.path.join(work, "inflow_%d.toml" % round(inflow))
    with open(path, "w") as f:
        f.write(text)
    return path


def parse_inflows(text):
    lo, hi, step = (float(x) for x in text.split(":"))
    out, q = [], lo
    while q <= hi + 1e-9:
        out.append(q)
        q += step
    return out


def svg(points, title):
    """Both curves, outflow against inflow, with their CIs as bars."""
    w, h, m = 640, 420, 60
    qs = [p["inflow"] for p in points]
    top = max(max(p["mapc"][0] + p["mapc"][1], p["sumo"][0] + p["sumo"][1]) for p in points)
    xmax, ymax = max(qs) * 1.05, max(top, max(qs)) * 1.05
    X = lambda q: m + (w - 2 * m) * q / xmax
    Y = lambda o: h - m - (h - 2 * m) * o / ymax
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" font-size="12">'
           % (w, h), '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="20" text-anchor="middle" font-size="14">%s</text>' % (w / 2, title),
           '<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (m, h - m, w - m, h - m),
           '<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (m, h - m, m, m),
           '<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#bbb" stroke-dasharray="4"/>'
           % (X(0), Y(0), X(min(xmax, ymax)), Y(min(xmax, ymax))),
           '<text x="%d" y="%d" text-anchor="middle">inflow (veh/h)</text>' % (w / 2, h - 15),
           '<text x="15" y="%d" transform="rotate(-90 15 %d)" text-anchor="middle">outflow (veh/h)</text>'
           % (h / 2, h / 2)]
    step = 500
    for t in range(0, int(xmax) + 1, step):
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (X(t), h - m + 16, t))
    for t in range(0, int(ymax) + 1, step):
        out.append('<text x="%d" y="%.1f" text-anchor="end">%d</text>' % (m - 6, Y(t) + 4, t))
    for key, colour, label in (("mapc", "#1f77b4", "mapc"), ("sumo", "#d62728", "SUMO 1.8")):
        pts = " ".join("%.1f,%.1f" % (X(p["inflow"]), Y(p[key][0])) for p in points)
        out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (pts, colour))
        for p in points:
            mean, ci = p[key]
            out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="%s"/>'
                       % (X(p["inflow"]), Y(mean - ci), X(p["inflow"]), Y(mean + ci), colour))
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (X(p["inflow"]), Y(mean), colour))
    out.append('<text x="%d" y="%d" fill="#1f77b4">mapc</text>' % (m + 10, m + 5))
    out.append('<text x="%d" y="%d" fill="#d62728">SUMO 1.8</text>' % (m + 10, m + 22))
    out.append('<text x="%d" y="%d" fill="#999">outflow = inflow</text>' % (m + 10, m + 39))
    out.append("</svg>")
    return "\n".join(out) + "\n"


def curve(a, mapc, seeds, work, sumo_check):
    points = []
    print("| inflow veh/h | mapc outflow | SUMO outflow | mapc vs SUMO |")
    print("|---|---|---|---|")
    for q in parse_inflows(a.inflows):
        scn = scaled_copy(a.scenario, q, work)
        point_work = os.path.join(work, "q%d" % round(q))
        os.makedirs(point_work)
        export_dir, manifest = sumo_check.export(mapc, scn, point_work)
        m = sumo_check.mapc_json(mapc, ["sim", "--scenario", scn, "--seeds", str(len(seeds))])
        mo = [r["outflow_veh_h"] for r in m["runs"]]
        s = sumo_check.run_sumo(export_dir, manifest, seeds, None, a.jobs)
        so = [r["outflow"] for r in s]
        mm, mci, _ = stats.mean_ci(mo)
        sm, sci, _ = stats.mean_ci(so)
        points.append(dict(inflow=q, mapc=(mm, mci), sumo=(sm, sci), mapc_runs=mo, sumo_runs=so))
        print("| %.0f | %.1f ± %.1f | %.1f ± %.1f | %+.1f %% |" % (q, mm, mci, sm, sci, 100 * (mm - sm) / sm))
        sys.stdout.flush()
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump(dict(scenario=a.scenario, seeds=a.seeds, points=points), f, indent=1)
    if a.svg:
        with open(a.svg, "w") as f:
            f.write(svg(points, "%s: outflow against inflow, %d seeds a point" % (
                os.path.basename(a.scenario), len(seeds))))
