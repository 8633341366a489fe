//! SUMO 1.8's command line on the scenario `mapc bench` measures, for the side-by-side speed figure. A SUMO
//! user's scenario runs as the user runs it (`sumo -c X.sumocfg`, or `sumo -n N -r R -a A`); a mapc scenario is
//! exported first (`mapc_sumo`, as `mapc export --sumo` does). Each seed runs with `--seed S
//! --duration-log.statistics true` (and no schema validation); its vehicle-steps are SUMO's own count (UPS x
//! duration), its CPU time and peak memory the kernel's for the child process. A user's files run from a copy of
//! the folder that holds them, so that the outputs they ask for do not overwrite the user's own.

use anyhow::{Context, bail};
use std::path::{Path, PathBuf};
use std::process::Command;

/// What SUMO did over the seeds.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SumoRuns {
    pub binary: PathBuf,
    /// First line of `sumo --version`.
    pub version: String,
    /// SUMO's input options, as run (`-c CFG`, or `-n NET -r R`).
    pub command: String,
    pub seeds: u64,
    pub wall_s: f64,
    /// User + system CPU time of the SUMO processes.
    pub cpu_s: f64,
    /// Vehicles moved, summed over steps and seeds (SUMO's "UPS" times its "Duration").
    pub vehicle_steps: f64,
    /// Largest resident memory of one SUMO run (MiB).
    pub peak_rss_mib: f64,
}

/// Where SUMO is: `explicit` (an error when it is not there), else SUMO 1.8 in the virtual environment
/// tools/sumo_check makes (`$MAPC_SUMO_VENV`, or `~/.cache/mapc/sumo-1.8.0`), else `sumo` on the PATH; none:
/// `Ok(None)`. The pip package's Python launcher is replaced by the binary it starts, so that Python's start-up
/// is not timed.
pub fn find_sumo(explicit: Option<&Path>) -> anyhow::Result<Option<PathBuf>> {
    if let Some(p) = explicit {
        if !p.is_file() {
            bail!("--sumo {}: no such file", p.display());
        }
        return Ok(Some(package_binary(p).unwrap_or_else(|| p.to_path_buf())));
    }
    let venv = std::env::var_os("MAPC_SUMO_VENV")
        .map(PathBuf::from)
        .or_else(|| {
            let cache = std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
            Some(cache.join("mapc/sumo-1.8.0"))
        });
    if let Some(launcher) = venv.map(|v| v.join("bin/sumo")).filter(|p| p.is_file()) {
        return Ok(Some(package_binary(&launcher).unwrap_or(launcher)));
    }
    let on_path = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("sumo"))
            .find(|p| p.is_file())
    });
    Ok(on_path.map(|p| package_binary(&p).unwrap_or(p)))
}

/// For the pip package's launcher `VENV/bin/sumo` (a Python script), the binary it runs,
/// `VENV/lib/python3.*/site-packages/sumo/bin/sumo`.
fn package_binary(launcher: &Path) -> Option<PathBuf> {
    let head = std::fs::read(launcher).ok()?;
    if !head.starts_with(b"#!") {
        return None;
    }
    let lib = launcher.parent()?.parent()?.join("lib");
    let mut found: Vec<PathBuf> = std::fs::read_dir(lib)
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("site-packages/sumo/bin/sumo"))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    found.pop()
}

/// What SUMO runs: the user's own files, or mapc's export of a scenario.
pub enum SumoInput<'a> {
    /// `sumo -c CFG`.
    Config(&'a Path),
    /// `sumo -n NET -r R1,R2 -a A1`.
    Files {
        net: &'a Path,
        routes: &'a [PathBuf],
        additional: &'a [PathBuf],
    },
    /// A mapc scenario, exported into the working folder first.
    Export(&'a mapc_scenario::ResolvedScenario),
}

/// Run SUMO on `input` for seeds `0..seeds`, one after another, in the working folder `dir` (an export is written
/// there).
pub fn run_sumo(
    sumo: &Path,
    input: SumoInput<'_>,
    dir: &Path,
    seeds: u64,
) -> anyhow::Result<SumoRuns> {
    let version = Command::new(sumo)
        .arg("--version")
        .output()
        .with_context(|| format!("running {} --version", sumo.display()))?;
    let version = String::from_utf8_lossy(&version.stdout)
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let joined = |ps: &[PathBuf]| {
        ps.iter()
            .map(|p| absolute(p).display().to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let files: Vec<String> = match input {
        SumoInput::Config(cfg) => {
            let run_cfg = scratch_copy(cfg, dir)?.unwrap_or_else(|| absolute(cfg));
            vec!["-c".into(), run_cfg.display().to_string()]
        }
        SumoInput::Files {
            net,
            routes,
            additional,
        } => {
            let mut given = vec![net.to_path_buf()];
            given.extend(routes.iter().cloned());
            given.extend(additional.iter().cloned());
            let run = if additional.iter().any(|a| additional_writes_outside(a)) {
                given
            } else {
                scratch_files(&given, dir)?.unwrap_or(given)
            };
            let (net, rest) = run.split_first().expect("a net is given");
            let (routes, additional) = rest.split_at(routes.len());
            let mut v = vec!["-n".into(), absolute(net).display().to_string()];
            v.extend(["-r".into(), joined(routes)]);
            if !additional.is_empty() {
                v.extend(["-a".into(), joined(additional)]);
            }
            v
        }
        SumoInput::Export(rs) => {
            let summary = mapc_sumo::export_scenario(rs, dir)?;
            let cfg = summary
                .files
                .iter()
                .find(|f| f.ends_with(".sumocfg"))
                .context("the export wrote no .sumocfg")?;
            vec!["-c".into(), cfg.clone()]
        }
    };
    let shown = files.join(" ");
    let before = children_usage();
    let start = std::time::Instant::now();
    let mut vehicle_steps = 0.0;
    for seed in 0..seeds {
        let out = Command::new(sumo)
            .current_dir(dir)
            .args(&files)
            .args(["--seed", &seed.to_string()])
            .args(["--duration-log.statistics", "true", "--no-step-log", "true"])
            // schema checks would fetch sumo.dlr.de's schemas: no network needed, and less load time charged
            .args(["--xml-validation", "never", "--xml-validation.net", "never"])
            .output()
            .with_context(|| format!("running {}", sumo.display()))?;
        let text = String::from_utf8_lossy(&out.stdout);
        if !out.status.success() {
            bail!(
                "{} {shown} --seed {seed} failed ({}): {}",
                sumo.display(),
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        vehicle_steps += moved_vehicles(&text).with_context(|| {
            format!(
                "SUMO's output has no `Duration:` and `UPS:` lines:\n{}",
                text.trim()
            )
        })?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let after = children_usage();
    Ok(SumoRuns {
        binary: sumo.to_path_buf(),
        version,
        command: shown,
        seeds,
        wall_s,
        cpu_s: after.0 - before.0,
        vehicle_steps,
        peak_rss_mib: after.1,
    })
}

/// Vehicles moved in one run, from `--duration-log.statistics`' `Duration: 1.03s` (or `830ms`) and
/// `UPS: 64301.1` (vehicle updates per second of that duration).
fn moved_vehicles(stdout: &str) -> Option<f64> {
    let value = |key: &str| {
        stdout
            .lines()
            .map(str::trim)
            .find_map(|l| l.strip_prefix(key))
            .map(str::trim)
    };
    let duration = value("Duration:")?;
    let duration_s = match duration.strip_suffix("ms") {
        Some(ms) => ms.trim().parse::<f64>().ok()? / 1000.0,
        None => duration.strip_suffix('s')?.trim().parse::<f64>().ok()?,
    };
    let ups: f64 = value("UPS:")?.parse().ok()?;
    Some(ups * duration_s)
}

/// CPU time (user + system, s) of this process's finished children, and the largest resident memory of one of
/// them (MiB).
fn children_usage() -> (f64, f64) {
    // SAFETY: getrusage only writes the struct it is given
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) } != 0 {
        return (f64::NAN, f64::NAN);
    }
    (cpu_seconds(&u), u.ru_maxrss as f64 / 1024.0)
}

/// User + system time of a usage record (s).
pub fn cpu_seconds(u: &libc::rusage) -> f64 {
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(u.ru_utime) + tv(u.ru_stime)
}

/// The configuration `cfg` in a copy of its folder under `dir`, so that the outputs it asks of SUMO (trip info,
/// routes, the loops' files), written beside the files that name them, land in the copy and not over the user's
/// own. `None` where the configuration names a file outside its folder (the copy would not hold it): SUMO then
/// runs on the user's files in place.
fn scratch_copy(cfg: &Path, dir: &Path) -> anyhow::Result<Option<PathBuf>> {
    let conf = mapc_scenario::sumo::config::read(cfg).map_err(|e| anyhow::anyhow!("{e}"))?;
    let Some(home) = folder_of(cfg) else {
        return Ok(None);
    };
    // (outputs named outside the folder, or absolute, go where they always went: SUMO runs in place)
    if conf.outputs.iter().any(|o| leaves_folder(o))
        || conf
            .additional_files
            .iter()
            .any(|a| additional_writes_outside(a))
    {
        return Ok(None);
    }
    let mut files = vec![cfg.to_path_buf(), conf.net_file.clone()];
    files.extend(conf.route_files.iter().cloned());
    files.extend(conf.additional_files.iter().cloned());
    Ok(copy_holding(&home, &files, dir)?.map(|copied| copied[0].clone()))
}

/// Whether an additional file's elements write a file (an induction loop's `file`, ...) absolute or outside
/// its folder; an additional file that cannot be read says yes (SUMO runs in place and reports it).
fn additional_writes_outside(path: &Path) -> bool {
    fn any_file(e: &mapc_import::SumoElement) -> bool {
        ["file", "output"]
            .iter()
            .any(|k| e.get(k).is_some_and(leaves_folder))
            || e.children.iter().any(any_file)
    }
    mapc_import::read_sumo_xml(
        path,
        &["routes", "additional", "additionals", "add"],
        "a SUMO additional file",
    )
    .map_or(true, |root| any_file(&root))
}

/// A file name that is absolute or climbs out of the folder it is relative to.
fn leaves_folder(name: &str) -> bool {
    name.split([',', ' '])
        .map(str::trim)
        .filter(|n| !n.is_empty())
        .any(|n| {
            let p = Path::new(n);
            p.is_absolute()
                || p.components()
                    .any(|c| matches!(c, std::path::Component::ParentDir))
        })
}

/// The net, route and additional files of `sumo -n -r -a` in a copy of the folder that holds them all (as
/// [`scratch_copy`]: an induction loop writes its file beside the additional file that defines it), in the order
/// given; `None` where they share no folder small enough to copy.
fn scratch_files(files: &[PathBuf], dir: &Path) -> anyhow::Result<Option<Vec<PathBuf>>> {
    let folders: Vec<PathBuf> = files.iter().filter_map(|f| folder_of(f)).collect();
    if folders.len() != files.len() || folders.is_empty() {
        return Ok(None);
    }
    let mut home = folders[0].clone();
    while !folders.iter().all(|f| f.starts_with(&home)) {
        if !home.pop() {
            return Ok(None);
        }
    }
    copy_holding(&home, files, dir)
}

/// The canonical folder of a file.
fn folder_of(file: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(file)
        .ok()?
        .parent()
        .map(Path::to_path_buf)
}

/// `home` copied to `dir/scenario` and `files` (which must lie in it) as they are in the copy; `None`, copying
/// nothing, where a file lies outside `home` or `home` is larger than [`SCRATCH_BUDGET`] (a home folder, say).
/// The working folder `dir`, where it lies inside `home`, is left out of the copy.
fn copy_holding(
    home: &Path,
    files: &[PathBuf],
    dir: &Path,
) -> anyhow::Result<Option<Vec<PathBuf>>> {
    // (files with only the file system's root in common run in place)
    if home.parent().is_none() {
        return Ok(None);
    }
    let dir_abs = std::fs::canonicalize(dir).ok();
    let mut inside = Vec::with_capacity(files.len());
    for f in files {
        let rel = std::fs::canonicalize(f)
            .ok()
            .and_then(|f| f.strip_prefix(home).ok().map(Path::to_path_buf));
        match rel {
            Some(rel) => inside.push(rel),
            None => return Ok(None),
        }
    }
    let mut budget = SCRATCH_BUDGET;
    if !fits(home, dir_abs.as_deref(), &mut budget) {
        return Ok(None);
    }
    let scratch = dir.join("scenario");
    // (a file that cannot be copied, unreadable or gone meanwhile: SUMO runs on the user's files in place)
    if copy_tree(home, &scratch, dir_abs.as_deref()).is_err() {
        std::fs::remove_dir_all(&scratch).ok();
        return Ok(None);
    }
    Ok(Some(
        inside.into_iter().map(|rel| scratch.join(rel)).collect(),
    ))
}

/// The most [`copy_holding`] copies: files, and bytes.
const SCRATCH_BUDGET: (u64, u64) = (10_000, 256 << 20);

/// Whether the files under `from` (but `skip`) fit in what is left of `budget`, which they use up.
fn fits(from: &Path, skip: Option<&Path>, budget: &mut (u64, u64)) -> bool {
    let Ok(entries) = std::fs::read_dir(from) else {
        return false;
    };
    for entry in entries {
        let Ok(entry) = entry else { return false };
        let path = entry.path();
        if skip.is_some_and(|s| path == s) {
            continue;
        }
        let Ok(kind) = entry.file_type() else {
            return false;
        };
        if kind.is_dir() {
            if !fits(&path, skip, budget) {
                return false;
            }
        } else if let Some(meta) = std::fs::metadata(&path).ok().filter(|m| m.is_file()) {
            if budget.0 == 0 || budget.1 < meta.len() {
                return false;
            }
            *budget = (budget.0 - 1, budget.1 - meta.len());
        }
    }
    true
}

/// Copies the files under `from` into `to` (folders made as needed), leaving out `skip`; a link to a file is
/// copied as the file, a link to a folder left out.
fn copy_tree(from: &Path, to: &Path, skip: Option<&Path>) -> anyhow::Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let entry = entry.with_context(|| format!("reading {}", from.display()))?;
        let path = entry.path();
        if skip.is_some_and(|s| path == s) {
            continue;
        }
        let target = to.join(entry.file_name());
        let kind = entry
            .file_type()
            .with_context(|| format!("reading {}", path.display()))?;
        if kind.is_dir() {
            copy_tree(&path, &target, skip)?;
        } else if kind.is_file() || std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
            std::fs::copy(&path, &target)
                .with_context(|| format!("copying {} to {}", path.display(), target.display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sumo_statistics_are_read_in_seconds_and_milliseconds() {
        let out = "Performance: \n Duration: 1.50s\n Real time factor: 717.563\n UPS: 48000.0\nVehicles: \n";
        assert_eq!(moved_vehicles(out), Some(72000.0));
        let out = " Duration: 250ms\n UPS: 1000\n";
        assert_eq!(moved_vehicles(out), Some(250.0));
        assert_eq!(moved_vehicles("Simulation ended at time: 1001.00\n"), None);
    }

    #[test]
    fn a_configuration_runs_from_a_copy_of_its_folder_unless_it_reaches_outside() {
        let root = std::env::temp_dir().join(format!("mapc-scratch-test-{}", std::process::id()));
        let home = root.join("study");
        std::fs::create_dir_all(home.join("nets")).unwrap();
        std::fs::write(home.join("nets/a.net.xml"), "<net/>").unwrap();
        std::fs::write(home.join("a.rou.xml"), "<routes/>").unwrap();
        std::fs::write(root.join("outside.rou.xml"), "<routes/>").unwrap();
        let cfg = |routes: &str| {
            format!(
                "<configuration><input><net-file value=\"nets/a.net.xml\"/>\
                 <route-files value=\"{routes}\"/></input><output>\
                 <tripinfo-output value=\"trips.xml\"/></output></configuration>"
            )
        };
        std::fs::write(home.join("a.sumocfg"), cfg("a.rou.xml")).unwrap();
        std::fs::write(home.join("b.sumocfg"), cfg("../outside.rou.xml")).unwrap();
        let work = root.join("work");
        std::fs::create_dir_all(&work).unwrap();
        let copied = scratch_copy(&home.join("a.sumocfg"), &work)
            .unwrap()
            .unwrap();
        assert_eq!(copied, work.join("scenario/a.sumocfg"));
        assert!(work.join("scenario/nets/a.net.xml").is_file());
        assert!(work.join("scenario/a.rou.xml").is_file());
        // a file named outside the folder: SUMO runs on the user's files where they are
        assert_eq!(
            scratch_copy(&home.join("b.sumocfg"), &root.join("work2")).unwrap(),
            None
        );
        // an output named outside the folder: in place too
        std::fs::write(
            home.join("c.sumocfg"),
            cfg("a.rou.xml").replace("trips.xml", "../results/trips.xml"),
        )
        .unwrap();
        assert_eq!(
            scratch_copy(&home.join("c.sumocfg"), &root.join("work4")).unwrap(),
            None
        );
        // `sumo -n -r`: the folder that holds both, the files in the order given
        let work3 = root.join("work3");
        std::fs::create_dir_all(&work3).unwrap();
        let given = [home.join("nets/a.net.xml"), root.join("outside.rou.xml")];
        let copied = scratch_files(&given, &work3).unwrap().unwrap();
        assert_eq!(
            copied,
            [
                work3.join("scenario/study/nets/a.net.xml"),
                work3.join("scenario/outside.rou.xml")
            ]
        );
        assert!(copied.iter().all(|f| f.is_file()));
        std::fs::remove_dir_all(&root).unwrap();
    }
}
