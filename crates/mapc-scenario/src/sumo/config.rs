//! A `.sumocfg` as SUMO 1.8 reads it: every option is an element with a `value` (`<end value="3600"/>`), in any
//! section; file names are relative to the configuration's folder and lists are separated by commas or spaces.

use super::SumoError;
use mapc_import::SumoElement;
use std::path::{Path, PathBuf};

/// SUMO 1.8's default seed.
pub const SUMO_DEFAULT_SEED: u64 = 23423;
/// SUMO 1.8's default `--time-to-teleport` (s).
pub const SUMO_DEFAULT_TIME_TO_TELEPORT_S: f64 = 300.0;

/// The options of a SUMO run mapc uses.
#[derive(Clone, Debug, PartialEq)]
pub struct SumoConfig {
    /// The configuration file, if the run has one.
    pub path: Option<PathBuf>,
    pub net_file: PathBuf,
    pub route_files: Vec<PathBuf>,
    pub additional_files: Vec<PathBuf>,
    pub begin_s: f64,
    /// `None`: SUMO runs until every vehicle has left.
    pub end_s: Option<f64>,
    pub step_s: f64,
    pub seed: u64,
    /// Negative: never.
    pub time_to_teleport_s: f64,
    /// `default.speeddev`; negative: each vClass's own.
    pub default_speed_dev: f64,
    /// `default.carfollowmodel` (`Krauss` unless set).
    pub default_car_follow_model: String,
    /// `scale`: demand multiplied by this.
    pub scale: f64,
    /// Options read but without effect in mapc, one line each.
    pub warnings: Vec<String>,
    /// The files SUMO itself writes for this configuration, as it names them (`*-output`, `output-prefix` and the
    /// logs: relative to the configuration's folder); mapc writes none of them.
    pub outputs: Vec<String>,
    /// The outputs mapc can write, by the option that names them (`tripinfo-output`, `summary-output`,
    /// `fcd-output`), with the name the configuration gives.
    pub named_outputs: Vec<(String, String)>,
}

impl SumoConfig {
    /// SUMO's defaults for a run of these files.
    pub fn for_files(net: &Path, routes: &[PathBuf], additional: &[PathBuf]) -> SumoConfig {
        SumoConfig {
            path: None,
            net_file: net.to_path_buf(),
            route_files: routes.to_vec(),
            additional_files: additional.to_vec(),
            begin_s: 0.0,
            end_s: None,
            step_s: 1.0,
            seed: SUMO_DEFAULT_SEED,
            time_to_teleport_s: SUMO_DEFAULT_TIME_TO_TELEPORT_S,
            default_speed_dev: -1.0,
            default_car_follow_model: "Krauss".into(),
            scale: 1.0,
            warnings: Vec::new(),
            outputs: Vec::new(),
            named_outputs: Vec::new(),
        }
    }
}

/// Options that only steer SUMO's own outputs, messages, GUI or checks: read and without effect on the run.
const WITHOUT_EFFECT: &[&str] = &[
    "verbose",
    "no-step-log",
    "no-warnings",
    "duration-log.statistics",
    "duration-log.disable",
    "xml-validation",
    "xml-validation.net",
    "xml-validation.routes",
    "gui-settings-file",
    "start",
    "quit-on-end",
    "delay",
    "window-size",
    "window-pos",
    "collision.action",
    "collision.check-junctions",
    "ignore-route-errors",
    "waiting-time-memory",
    "message-log",
    "error-log",
    "log",
    "output-prefix",
    "precision",
    "human-readable-time",
    "statistic-output",
    "emission-output",
    "queue-output",
    "lanechange-output",
    "netstate-dump",
    "vehroute-output",
    "random",
    "thread-rngs",
    "threads",
    "no-internal-links",
    "lanechange.duration",
];

/// The words of the warning for an output the configuration names and mapc writes only when asked
/// (`tripinfo-output`, ...): a front end that writes them anyway leaves out the warnings that contain them.
pub const OUTPUT_NOT_WRITTEN: &str = "not written; `mapc sim --";

/// Read a `.sumocfg`.
pub fn read(path: &Path) -> Result<SumoConfig, SumoError> {
    let root = mapc_import::read_sumo_xml(
        path,
        &["configuration", "sumoConfiguration"],
        "a SUMO configuration",
    )?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut options = Vec::new();
    collect(&root, &mut options);
    let mut c = SumoConfig::for_files(Path::new(""), &[], &[]);
    c.path = Some(path.to_path_buf());
    let mut net = None;
    let mut action_step: Option<(f64, String)> = None;
    for o in options {
        let value = o.get("value").unwrap_or("").trim();
        if o.name.ends_with("-output")
            || matches!(
                o.name.as_str(),
                "output-prefix" | "log" | "message-log" | "error-log"
            )
        {
            c.outputs.push(value.to_string());
        }
        let num = || -> Result<f64, SumoError> {
            value
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| SumoError::at(&o.place, format!("`{value}` is not a number")))
        };
        let flag = || -> Result<bool, SumoError> {
            mapc_import::sumo_bool(value)
                .ok_or_else(|| SumoError::at(&o.place, format!("`{value}` is not true or false")))
        };
        let refuse = |why: &str| {
            Err(SumoError::at(
                &o.place,
                format!("option `{}`: {why}", o.name),
            ))
        };
        match o.name.as_str() {
            "net-file" => net = Some(dir.join(value)),
            "route-files" => c.route_files = files(&dir, value),
            "additional-files" => c.additional_files = files(&dir, value),
            "begin" => c.begin_s = num()?,
            "end" => {
                let e = num()?;
                // SUMO's -1: no end
                c.end_s = (e >= 0.0).then_some(e);
            }
            "step-length" => {
                c.step_s = num()?;
                if !(c.step_s >= 0.001 && c.step_s <= 10.0) {
                    return Err(SumoError::at(
                        &o.place,
                        format!("step-length {value}: must lie in [0.001, 10] s"),
                    ));
                }
            }
            "seed" => {
                c.seed = value.parse().map_err(|_| {
                    SumoError::at(&o.place, format!("seed `{value}` is not a whole number"))
                })?
            }
            "time-to-teleport" => c.time_to_teleport_s = num()?,
            "time-to-teleport.highways" => {
                if num()? > 0.0 {
                    return refuse("mapc teleports only by time-to-teleport, not by road speed");
                }
            }
            "default.speeddev" => c.default_speed_dev = num()?,
            "default.carfollowmodel" => match value {
                "Krauss" | "IDM" => c.default_car_follow_model = value.into(),
                _ => {
                    return refuse(&format!(
                        "car-following model `{value}`: mapc has Krauss and IDM"
                    ));
                }
            },
            "step-method.ballistic" => {
                if flag()? {
                    return refuse(
                        "mapc updates positions as SUMO's default (Euler), not ballistically",
                    );
                }
            }
            // checked against the step once both are known
            "default.action-step-length" => action_step = Some((num()?, o.place.clone())),
            "max-depart-delay" => {
                if num()? >= 0.0 {
                    return refuse("mapc keeps every vehicle waiting until it can be inserted");
                }
            }
            "scale" => {
                c.scale = num()?;
                if !(c.scale > 0.0) {
                    return Err(SumoError::at(
                        &o.place,
                        format!("scale {value}: must be positive"),
                    ));
                }
            }
            "lateral-resolution" => {
                if num()? > 0.0 {
                    return refuse("the sublane model is not simulated");
                }
            }
            "mesosim" => {
                if flag()? {
                    return refuse("the mesoscopic model is not simulated");
                }
            }
            "device.rerouting.probability" => {
                if num()? > 0.0 {
                    return refuse("vehicles are not rerouted while driving");
                }
            }
            // written where the run asks for them (`mapc sim --tripinfo-output`), not into the user's folder
            "tripinfo-output" | "summary-output" | "fcd-output" => {
                c.warnings.push(format!(
                    "{}: option `{}` {OUTPUT_NOT_WRITTEN}{} FILE` writes it (`--sumo-outputs DIR`: every \
                     output the configuration names, into DIR)",
                    o.place, o.name, o.name
                ));
                if !value.is_empty() {
                    c.named_outputs.push((o.name.clone(), value.to_string()));
                }
            }
            name if WITHOUT_EFFECT.contains(&name) => {}
            name => c
                .warnings
                .push(format!("{}: option `{name}` ignored", o.place)),
        }
    }
    // the action step: accepted only where it is the step itself (0: the step, SUMO's default)
    if let Some((a, place)) = action_step
        && a > 0.0
        && (a - c.step_s).abs() > 1e-9
    {
        return Err(SumoError::at(
            &place,
            format!(
                "default.action-step-length {a}: mapc decides every step (it must equal step-length {})",
                c.step_s
            ),
        ));
    }
    c.net_file = net.ok_or_else(|| SumoError::File {
        path: path.to_path_buf(),
        message: "no `net-file`: a SUMO run needs a network".into(),
    })?;
    for f in std::iter::once(&c.net_file)
        .chain(&c.route_files)
        .chain(&c.additional_files)
    {
        if !f.is_file() {
            return Err(SumoError::File {
                path: path.to_path_buf(),
                message: format!("names `{}`, which is not a file", f.display()),
            });
        }
    }
    Ok(c)
}

/// Every element with a `value`, in file order (sections are optional in SUMO).
fn collect<'a>(e: &'a SumoElement, out: &mut Vec<&'a SumoElement>) {
    for c in &e.children {
        if c.get("value").is_some() {
            out.push(c);
        }
        collect(c, out);
    }
}

/// A list of file names (commas or spaces) relative to `dir`.
fn files(dir: &Path, value: &str) -> Vec<PathBuf> {
    value
        .split([',', ' '])
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| dir.join(s))
        .collect()
}
