//! A distribution of merges: a Simple Merge scenario whose demand, right of way, lengths, speed limit and AV share
//! are drawn per episode, so that one policy learns merges in every regime (congested or free-flowing, ramp or main
//! road with priority) instead of one.
//!
//! The file is TOML with its format name and version inside:
//!
//! ```toml
//! format = "mapc-merge-distribution"
//! version = 1
//! name = "merge_mix"
//! base = "simple_merge"          # a built-in scenario or a scenario file with a `[network.simple_merge]`
//!
//! [draw]
//! main_vph = [1000.0, 2400.0]    # main road demand, humans and AVs together (uniform)
//! ramp_vph = [100.0, 500.0]
//! av_share = [0.05, 0.15]        # of the main road's demand
//! ramp_major = 0.5               # probability that the ramp has the right of way (when not both have)
//! both_major = 0.25              # probability that neither yields
//! speed_limit_mps = [22.0, 30.0]
//! pre_merge_m = [300.0, 600.0]
//! merge_m = [60.0, 200.0]
//! post_merge_m = [60.0, 300.0]
//! ```
//!
//! A draw is a function of the seed alone (`MergeDistribution::sample`), so a training run that draws its
//! episode's scenario from the episode's seed stays reproducible bit for bit.

use std::path::{Path, PathBuf};

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::model::{MajorRoad, NetworkSpec, Scenario};
use crate::{ResolvedScenario, ScenarioError};

/// The format name a distribution file carries.
pub const DISTRIBUTION_FORMAT: &str = "mapc-merge-distribution";
/// Bumped on any change an older reader would misread.
pub const DISTRIBUTION_VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MergeDistribution {
    pub format: String,
    pub version: u32,
    pub name: String,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// The scenario every draw starts from: `simple_merge` or a scenario file (relative to this file).
    pub base: String,
    pub draw: Draws,
}

/// Closed ranges `[low, high]` drawn uniformly; a range with `low == high` fixes the value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Draws {
    pub main_vph: [f64; 2],
    pub ramp_vph: [f64; 2],
    pub av_share: [f64; 2],
    /// Probability that the ramp is the major road (when not both are).
    pub ramp_major: f64,
    /// Probability that both roads are major (neither yields).
    #[serde(default)]
    pub both_major: f64,
    pub speed_limit_mps: [f64; 2],
    pub pre_merge_m: [f64; 2],
    pub merge_m: [f64; 2],
    pub post_merge_m: [f64; 2],
}

/// One draw's values, for logs and tests.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DrawnMerge {
    pub main_vph: f64,
    pub ramp_vph: f64,
    pub av_share: f64,
    pub major: MajorRoad,
    pub speed_limit_mps: f64,
    pub pre_merge_m: f64,
    pub merge_m: f64,
    pub post_merge_m: f64,
}

/// The roles of the base scenario's flows, found by their entry road and vehicle type.
#[derive(Clone, Debug)]
struct FlowRoles {
    main_human: usize,
    main_av: usize,
    ramp: Vec<usize>,
}

/// A distribution ready to draw from: the parsed file and its base scenario.
#[derive(Clone, Debug)]
pub struct LoadedDistribution {
    pub file: MergeDistribution,
    pub origin: String,
    base: Scenario,
    base_dir: PathBuf,
    roles: FlowRoles,
}

impl LoadedDistribution {
    /// Reads and checks a distribution file.
    pub fn load(path: &Path) -> Result<LoadedDistribution, ScenarioError> {
        let text = mapc_graph::input::read_to_string(path).map_err(|source| ScenarioError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let file: MergeDistribution = toml::from_str(&text).map_err(|e| ScenarioError::Toml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let invalid = |key: &str, message: String| ScenarioError::Invalid {
            path: path.to_path_buf(),
            key: key.to_string(),
            message,
        };
        if file.format != DISTRIBUTION_FORMAT {
            return Err(invalid(
                "format",
                format!("expected `{DISTRIBUTION_FORMAT}`, found `{}`", file.format),
            ));
        }
        if file.version != DISTRIBUTION_VERSION {
            return Err(invalid(
                "version",
                format!(
                    "distribution version {}, but this mapc reads version {DISTRIBUTION_VERSION}",
                    file.version
                ),
            ));
        }
        check_draws(&file.draw)
            .map_err(|(key, message)| invalid(&format!("draw.{key}"), message))?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let base = match Scenario::builtin(&file.base) {
            Some(s) => s,
            None => Scenario::load(&base_dir.join(&file.base))?,
        };
        if !matches!(base.network, NetworkSpec::SimpleMerge(_)) {
            return Err(invalid(
                "base",
                format!(
                    "`{}` is not a Simple Merge scenario ([network.simple_merge])",
                    file.base
                ),
            ));
        }
        let roles = flow_roles(&base).map_err(|m| invalid("base", m))?;
        Ok(LoadedDistribution {
            origin: path.display().to_string(),
            file,
            base,
            base_dir,
            roles,
        })
    }

    /// The values of draw `seed`.
    pub fn draw(&self, seed: u64) -> DrawnMerge {
        let d = &self.file.draw;
        // a fixed salt keeps the draws apart from the simulator's own use of the same seed
        let mut rng = StdRng::seed_from_u64(seed ^ 0x6d65_7267_655f_6d69);
        let mut uniform = |r: [f64; 2]| {
            let u: f64 = rng.random::<f64>();
            r[0] + (r[1] - r[0]) * u
        };
        let main_vph = uniform(d.main_vph);
        let ramp_vph = uniform(d.ramp_vph);
        let av_share = uniform(d.av_share);
        // one draw decides: both major with `both_major`, else the ramp with `ramp_major` (so a file without
        // `both_major` draws what it drew before the key existed)
        let u = uniform([0.0, 1.0]);
        let major = if u < d.both_major {
            MajorRoad::Both
        } else if (u - d.both_major) / (1.0 - d.both_major) < d.ramp_major {
            MajorRoad::Ramp
        } else {
            MajorRoad::Main
        };
        DrawnMerge {
            main_vph,
            ramp_vph,
            av_share,
            major,
            speed_limit_mps: uniform(d.speed_limit_mps),
            pre_merge_m: uniform(d.pre_merge_m),
            merge_m: uniform(d.merge_m),
            post_merge_m: uniform(d.post_merge_m),
        }
    }

    /// The scenario of draw `seed`.
    pub fn sample(&self, seed: u64) -> Scenario {
        let m = self.draw(seed);
        let mut s = self.base.clone();
        s.name = format!("{}#{seed}", self.file.name);
        if let NetworkSpec::SimpleMerge(p) = &mut s.network {
            p.speed_limit_mps = m.speed_limit_mps;
            p.pre_merge_m = m.pre_merge_m;
            p.merge_m = m.merge_m;
            p.post_merge_m = m.post_merge_m;
            p.major = m.major;
        }
        s.flows[self.roles.main_human].vehs_per_hour = m.main_vph * (1.0 - m.av_share);
        s.flows[self.roles.main_av].vehs_per_hour = m.main_vph * m.av_share;
        // the base's ramp flows keep their proportions
        let base_ramp: f64 = self
            .roles
            .ramp
            .iter()
            .map(|&i| self.base.flows[i].vehs_per_hour)
            .sum();
        for &i in &self.roles.ramp {
            s.flows[i].vehs_per_hour = m.ramp_vph * self.base.flows[i].vehs_per_hour / base_ramp;
        }
        s
    }

    /// The resolved scenario of draw `seed` (its network built).
    pub fn resolve(&self, seed: u64) -> Result<ResolvedScenario, ScenarioError> {
        ResolvedScenario::resolve(
            self.sample(seed),
            &self.base_dir,
            &format!("{}#{seed}", self.origin),
        )
    }
}

fn check_draws(d: &Draws) -> Result<(), (&'static str, String)> {
    let ranges = [
        ("main_vph", d.main_vph, 0.0, 7200.0),
        ("ramp_vph", d.ramp_vph, 0.0, 7200.0),
        ("av_share", d.av_share, 0.0, 1.0),
        ("speed_limit_mps", d.speed_limit_mps, 1.0, 70.0),
        ("pre_merge_m", d.pre_merge_m, 10.0, 100_000.0),
        ("merge_m", d.merge_m, 10.0, 100_000.0),
        ("post_merge_m", d.post_merge_m, 10.0, 100_000.0),
    ];
    for (key, [lo, hi], min, max) in ranges {
        if !(lo.is_finite() && hi.is_finite() && min <= lo && lo <= hi && hi <= max) {
            return Err((
                key,
                format!(
                    "[{}, {}] must satisfy {min} <= low <= high <= {max}",
                    crate::ranges::show(lo),
                    crate::ranges::show(hi)
                ),
            ));
        }
    }
    if !(0.0..=1.0).contains(&d.ramp_major) {
        return Err((
            "ramp_major",
            format!(
                "a probability in [0, 1], not {}",
                crate::ranges::show(d.ramp_major)
            ),
        ));
    }
    Ok(())
}

/// The base's main-road human and AV flows and its ramp flows.
fn flow_roles(base: &Scenario) -> Result<FlowRoles, String> {
    use crate::generator::{MAIN_ENTRY, RAMP_ENTRY};
    let controlled = |i: usize| {
        base.vehicle_types
            .get(&base.flows[i].vehicle_type)
            .is_some_and(|t| t.controlled)
    };
    let main: Vec<usize> = (0..base.flows.len())
        .filter(|&i| base.flows[i].from == MAIN_ENTRY)
        .collect();
    let ramp: Vec<usize> = (0..base.flows.len())
        .filter(|&i| base.flows[i].from == RAMP_ENTRY)
        .collect();
    let one = |pick: Vec<usize>, what: &str| match pick.as_slice() {
        [i] => Ok(*i),
        _ => Err(format!(
            "the base needs exactly one {what} flow from `{MAIN_ENTRY}`, it has {}",
            pick.len()
        )),
    };
    let main_human = one(
        main.iter().copied().filter(|&i| !controlled(i)).collect(),
        "human",
    )?;
    let main_av = one(
        main.iter().copied().filter(|&i| controlled(i)).collect(),
        "AV",
    )?;
    if ramp.is_empty()
        || ramp
            .iter()
            .map(|&i| base.flows[i].vehs_per_hour)
            .sum::<f64>()
            <= 0.0
    {
        return Err(format!("the base needs a flow from `{RAMP_ENTRY}`"));
    }
    Ok(FlowRoles {
        main_human,
        main_av,
        ramp,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, text: &str) -> PathBuf {
        let p = dir.join("mix.toml");
        std::fs::write(&p, text).unwrap();
        p
    }

    const MIX: &str = r#"
format = "mapc-merge-distribution"
version = 1
name = "mix"
base = "simple_merge"
[draw]
main_vph = [1000.0, 2400.0]
ramp_vph = [100.0, 500.0]
av_share = [0.05, 0.15]
ramp_major = 0.5
speed_limit_mps = [22.0, 30.0]
pre_merge_m = [300.0, 600.0]
merge_m = [60.0, 200.0]
post_merge_m = [60.0, 300.0]
"#;

    #[test]
    fn draws_are_a_function_of_the_seed_and_stay_in_their_ranges() {
        let dir = std::env::temp_dir().join(format!("mapc-dist-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let d = LoadedDistribution::load(&write(&dir, MIX)).unwrap();
        assert_eq!(
            mapc_graph::filekind::sniff(MIX.as_bytes()),
            Some(mapc_graph::MapcFile::MergeDistribution)
        );
        let mut ramp_major = 0;
        for seed in 0..200 {
            let a = d.draw(seed);
            assert_eq!(a, d.draw(seed));
            assert!((1000.0..=2400.0).contains(&a.main_vph));
            assert!((0.05..=0.15).contains(&a.av_share));
            ramp_major += (a.major == MajorRoad::Ramp) as u32;
            let s = d.sample(seed);
            let total: f64 = s
                .flows
                .iter()
                .filter(|f| f.from == "inflow_highway")
                .map(|f| f.vehs_per_hour)
                .sum();
            assert!((total - a.main_vph).abs() < 1e-9);
            d.resolve(seed).unwrap();
        }
        // both regimes are drawn
        assert!((60..140).contains(&ramp_major), "{ramp_major}");
        assert_ne!(d.draw(1), d.draw(2));
        // with `both_major`, a quarter of the draws has no yielding road, and the rest keep their odds
        let both = LoadedDistribution::load(&write(
            &dir,
            &MIX.replace("ramp_major = 0.5", "ramp_major = 0.5\nboth_major = 0.25"),
        ))
        .unwrap();
        let majors: Vec<MajorRoad> = (0..400).map(|s| both.draw(s).major).collect();
        let count = |m: MajorRoad| majors.iter().filter(|&&x| x == m).count();
        assert!(
            (70..130).contains(&count(MajorRoad::Both)),
            "{}",
            count(MajorRoad::Both)
        );
        assert!(
            (110..190).contains(&count(MajorRoad::Ramp)),
            "{}",
            count(MajorRoad::Ramp)
        );
        both.resolve(0).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn bad_ranges_and_formats_name_their_key() {
        let dir = std::env::temp_dir().join(format!("mapc-dist-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = LoadedDistribution::load(&write(
            &dir,
            &MIX.replace("[100.0, 500.0]", "[500.0, 100.0]"),
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("draw.ramp_vph"), "{e}");
        let e = LoadedDistribution::load(&write(&dir, &MIX.replace("version = 1", "version = 9")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("version"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
