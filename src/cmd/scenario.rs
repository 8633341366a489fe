//! `mapc scenario show`: print a scenario resolved (network built, references checked).

use mapc_scenario::ResolvedScenario;

#[derive(clap::Subcommand)]
pub enum Command {
    /// Print a scenario with its network summarised and every reference checked.
    Show(ShowArgs),
    /// Compile a SUMO scenario (`.sumocfg`, or --net with --routes) into a mapc scenario file that every command
    /// takes.
    FromSumo(FromSumoArgs),
}

#[derive(clap::Args)]
pub struct FromSumoArgs {
    /// The SUMO configuration (omit with --net).
    pub config: Option<String>,
    #[command(flatten)]
    pub sumo: super::common::SumoInputArgs,
    /// The scenario file to write (its network is named relative to it).
    #[arg(short, long)]
    pub output: std::path::PathBuf,
}

#[derive(clap::Args)]
pub struct ShowArgs {
    /// A scenario file or a built-in name (simple_merge).
    #[arg(default_value = "simple_merge")]
    pub scenario: String,
    /// Print JSON instead of TOML and a summary.
    #[arg(long)]
    pub json: bool,
}

pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Show(a) => show(a),
        Command::FromSumo(a) => from_sumo(a),
    }
}

/// The SUMO scenario checked as every command reads it, then written as TOML with its network's path relative to
/// the output's folder (absolute where it has no relative path).
fn from_sumo(a: FromSumoArgs) -> anyhow::Result<()> {
    use std::path::Path;
    let name = match (&a.config, &a.sumo.net) {
        (Some(c), _) => c.clone(),
        (None, Some(_)) => String::new(),
        (None, None) => anyhow::bail!("give a SUMO configuration, or --net with --routes"),
    };
    let rs = super::common::load_scenario_or_sumo(&name, &a.sumo)?;
    let mut scenario = rs.scenario.clone();
    if let mapc_scenario::NetworkSpec::Map(net) = &scenario.network {
        // the network as the scenario file will find it (read, its path is the working folder's)
        let net = std::fs::canonicalize(net).unwrap_or_else(|_| net.clone());
        let out_dir = a
            .output
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let out_dir = std::fs::canonicalize(out_dir).unwrap_or_else(|_| out_dir.to_path_buf());
        let relative = net
            .strip_prefix(&out_dir)
            .map(Path::to_path_buf)
            .unwrap_or(net);
        scenario.network = mapc_scenario::NetworkSpec::Map(relative);
    }
    scenario.save(&a.output)?;
    println!(
        "wrote {}: {} flows, {} vehicle types, {} steps of {} s",
        a.output.display(),
        scenario.flows.len(),
        scenario.vehicle_types.len(),
        scenario.horizon_steps,
        scenario.step_s
    );
    Ok(())
}

fn show(a: ShowArgs) -> anyhow::Result<()> {
    let r = ResolvedScenario::load(&a.scenario)?;
    let g = &r.graph;
    let road_text = |id: mapc_graph::RoadId| {
        let road = g.road(id).expect("resolved roads exist");
        format!("{id} ({}, {:.1} m)", road.label(), road.length_m)
    };
    if a.json {
        let flows: Vec<_> = r
            .scenario
            .flows
            .iter()
            .zip(&r.flow_roads)
            .map(|(f, (from, to))| {
                serde_json::json!({"id": f.id, "from_road": from.to_string(), "to_road": to.map(|t| t.to_string())})
            })
            .collect();
        let out = serde_json::json!({
            "origin": r.origin,
            "scenario": r.scenario,
            "network": {
                "junctions": g.junctions.len(),
                "roads": g.roads.len(),
                "total_lane_length_m": g.total_lane_length_m(),
            },
            "flows": flows,
            "region_roads": r.region_roads.iter().map(|x| x.to_string()).collect::<Vec<_>>(),
            "windows": r.windows.iter().map(|w| serde_json::json!({
                "junction": w.name,
                "merges": w.merges.iter().map(|j| j.to_string()).collect::<Vec<_>>(),
                "roads": w.roads.iter().map(|x| x.to_string()).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("# {} (from {})", r.scenario.name, r.origin);
    println!(
        "# network: {} junctions, {} roads, {:.2} m of lanes",
        g.junctions.len(),
        g.roads.len(),
        g.total_lane_length_m()
    );
    for (f, (from, to)) in r.scenario.flows.iter().zip(&r.flow_roads) {
        let to = to
            .map(road_text)
            .unwrap_or_else(|| "end of corridor".into());
        println!(
            "# flow {}: {} veh/h of {} from {} to {}",
            f.id,
            f.vehs_per_hour,
            f.vehicle_type,
            road_text(*from),
            to
        );
    }
    if !r.windows.is_empty() {
        let n_av = r.scenario.control.as_ref().map_or(0, |c| c.n_av);
        for (k, w) in r.windows.iter().enumerate() {
            let roads: Vec<String> = w.roads.iter().map(|x| road_text(*x)).collect();
            let merges: Vec<String> = w.merges.iter().map(|j| j.to_string()).collect();
            println!(
                "# window {k} at {} (merges {}; up to {n_av} AVs): {}",
                w.name,
                merges.join(", "),
                roads.join(", ")
            );
        }
    } else if !r.region_roads.is_empty() {
        let roads: Vec<String> = r.region_roads.iter().map(|x| road_text(*x)).collect();
        println!("# controlled region: {}", roads.join(", "));
    }
    print!("{}", r.scenario.to_toml());
    Ok(())
}
