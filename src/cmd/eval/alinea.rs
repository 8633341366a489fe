//! `mapc eval --controller alinea`: the humans with ALINEA metering a light, over the same seeds as the humans
//! alone, each reported as mean and 95 % CI (the controller is a baseline, reported like the humans).

use mapc_sim::{AlineaConfig, MeanCi, RunMetrics, SimSpec, Summary};
use rayon::prelude::*;

/// ALINEA's options.
#[derive(clap::Args, Debug, Clone)]
pub struct AlineaArgs {
    /// The metered traffic light (its SUMO id). Default: the network's only light.
    #[arg(long, value_name = "ID")]
    pub alinea_light: Option<String>,
    /// Detectors whose occupancy ALINEA holds at the set-point (comma-separated ids). Default: on the first road
    /// downstream of the light that has detectors, the furthest on each lane.
    #[arg(long, value_name = "ID,ID", value_delimiter = ',')]
    pub alinea_detectors: Vec<String>,
    /// Target occupancy downstream, a fraction in (0, 1).
    #[arg(long, default_value_t = 0.20)]
    pub alinea_setpoint: f64,
    /// Gain K_R: veh/h of metering rate per percentage point of occupancy error.
    #[arg(long, default_value_t = 70.0)]
    pub alinea_gain: f64,
    /// Green time of each metering cycle (s).
    #[arg(long, default_value_t = 2.0)]
    pub alinea_green: f64,
}

impl AlineaArgs {
    pub fn config(&self) -> AlineaConfig {
        AlineaConfig {
            light: self.alinea_light.clone(),
            detectors: self.alinea_detectors.clone(),
            setpoint: self.alinea_setpoint,
            gain_veh_h: self.alinea_gain,
            green_s: self.alinea_green,
            ..AlineaConfig::default()
        }
    }
}

/// Run ALINEA on `seeds`, and the humans beside it unless `baseline` is false, and print them.
pub fn run(
    scenario: &str,
    spec: &SimSpec,
    seeds: &[u64],
    args: &AlineaArgs,
    baseline: bool,
    json: bool,
    trace: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let cfg = args.config();
    // refused before any run: a set-point, light or detector that does not hold
    let alinea =
        mapc_sim::Alinea::new(spec, &cfg).map_err(|e| anyhow::anyhow!("{scenario}: {e}"))?;
    let start = std::time::Instant::now();
    let humans = if baseline {
        Some(mapc_sim::run_baseline_spec(spec, seeds)?)
    } else {
        None
    };
    let metered = seeds
        .par_iter()
        .map(|&seed| mapc_sim::run_with_alinea(spec, seed, &cfg))
        .collect::<Result<Vec<_>, _>>()?;
    let rates: Vec<f64> = metered
        .iter()
        .flat_map(|(_, r)| r.iter().copied())
        .collect();
    let mean_rate = rates.iter().sum::<f64>() / rates.len().max(1) as f64;
    let metered: Vec<RunMetrics> = metered.into_iter().map(|(m, _)| m).collect();
    let mut trace_note = None;
    if let Some(path) = trace {
        // the first seed under ALINEA, as `--trace` writes a policy's
        super::super::common::write_trace_file(path, |w| {
            trace_note = mapc_sim::trace_with_alinea(spec, seeds[0], &cfg, w)?.note;
            Ok(())
        })?;
    }
    // each figure over the seeds computed where every run's summary is (`Summary::of`)
    let (h, a) = (humans.as_deref().map(Summary::of), Summary::of(&metered));
    let detectors: Vec<&str> = alinea
        .detectors()
        .iter()
        .map(|&d| spec.detectors[d].id.as_str())
        .collect();
    let light = cfg
        .light
        .clone()
        .unwrap_or_else(|| spec.graph.lights[0].id.clone());
    if json {
        let out = serde_json::json!({
            "scenario": scenario, "seeds": seeds.len(), "controller": "alinea",
            "light": light, "detectors": detectors, "setpoint": cfg.setpoint, "gain_veh_h": cfg.gain_veh_h,
            "green_s": cfg.green_s, "min_rate_veh_h": cfg.min_rate_veh_h, "max_rate_veh_h": cfg.max_rate_veh_h,
            "mean_rate_veh_h": mean_rate,
            "humans": h, "alinea": a, "alinea_runs": metered, "wall_s": start.elapsed().as_secs_f64(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "ALINEA on {scenario} ({} seeds): light `{light}`, occupancy of {} held at {:.0} %, K_R {} veh/h, {} s \
         green; mean rate {mean_rate:.0} veh/h",
        seeds.len(),
        detectors.join(", "),
        100.0 * cfg.setpoint,
        cfg.gain_veh_h,
        cfg.green_s
    );
    let pm = |m: &MeanCi| {
        if m.n < 2 {
            format!("{:9.2} (n = 1)", m.mean)
        } else {
            format!("{:9.2} ± {:6.2}", m.mean, m.ci95)
        }
    };
    for (name, f) in [("human", h.as_ref()), ("ALINEA", Some(&a))] {
        let Some(f) = f else { continue };
        println!(
            "  {name:<7} outflow {} veh/h  inflow {} veh/h  speed {} m/s  trip {} s",
            pm(&f.outflow),
            pm(&f.inflow),
            pm(&f.speed),
            pm(&f.travel_time)
        );
    }
    if let Some(p) = trace {
        println!(
            "  trace of seed {} under ALINEA written to {}{}",
            seeds[0],
            p.display(),
            trace_note.map(|n| format!(" ({n})")).unwrap_or_default()
        );
    }
    let Some(h) = h else {
        return Ok(());
    };
    let change = |x: &MeanCi, y: &MeanCi| 100.0 * (y.mean - x.mean) / x.mean;
    let disjoint = |x: &MeanCi, y: &MeanCi| (x.mean - y.mean).abs() > x.ci95 + y.ci95;
    println!(
        "  ALINEA vs human: outflow {:+.1} % (CIs {}), trip time {:+.1} % (CIs {})",
        change(&h.outflow, &a.outflow),
        if disjoint(&h.outflow, &a.outflow) {
            "disjoint"
        } else {
            "overlap"
        },
        change(&h.travel_time, &a.travel_time),
        if disjoint(&h.travel_time, &a.travel_time) {
            "disjoint"
        } else {
            "overlap"
        },
    );
    Ok(())
}
