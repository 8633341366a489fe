//! Every number of a shipped scenario set to an extreme (infinities and NaN as TOML writes them, ±1e308, 0, the
//! smallest and largest integers, ...): the scenario is either refused with one line naming the file and the key,
//! or it runs a short horizon to its end in process. A run that does not end within the timeout fails the test
//! (a flow beginning at -1e308 once made `mapc sim` run forever).

use mapc_scenario::{ResolvedScenario, Scenario};
use mapc_sim::{Simulation, spec_from_scenario};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;
use toml::Value;

/// One step of a path into the TOML tree.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

struct Shipped {
    path: PathBuf,
    table: toml::Table,
    /// Every number in the file: its path and whether TOML wrote it as an integer.
    numbers: Vec<(Vec<Step>, bool)>,
}

fn scenarios_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

fn numbers_in(v: &Value, at: &mut Vec<Step>, out: &mut Vec<(Vec<Step>, bool)>) {
    match v {
        Value::Integer(_) => out.push((at.clone(), true)),
        Value::Float(_) => out.push((at.clone(), false)),
        Value::Table(t) => {
            for (k, v) in t {
                at.push(Step::Key(k.clone()));
                numbers_in(v, at, out);
                at.pop();
            }
        }
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                at.push(Step::Index(i));
                numbers_in(v, at, out);
                at.pop();
            }
        }
        _ => {}
    }
}

/// The shipped scenarios (not the merge distributions), smallest networks first.
fn shipped() -> Vec<Shipped> {
    let mut files = Vec::new();
    for dir in [scenarios_dir(), scenarios_dir().join("merges")] {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml")
                && mapc_graph::filekind::sniff_path(&p) == Some(mapc_graph::MapcFile::Scenario)
            {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    files
        .into_iter()
        .map(|path| {
            let table: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
            let mut numbers = Vec::new();
            numbers_in(&Value::Table(table.clone()), &mut Vec::new(), &mut numbers);
            Shipped {
                path,
                table,
                numbers,
            }
        })
        .collect()
}

fn set(table: &mut toml::Table, path: &[Step], value: Value) {
    let mut at: &mut Value = match &path[0] {
        Step::Key(k) => table.get_mut(k).unwrap(),
        Step::Index(_) => unreachable!("a document starts with a key"),
    };
    for step in &path[1..] {
        at = match step {
            Step::Key(k) => at.get_mut(k.as_str()).unwrap(),
            Step::Index(i) => at.get_mut(*i).unwrap(),
        };
    }
    *at = value;
}

fn key_names(path: &[Step]) -> Vec<String> {
    path.iter()
        .filter_map(|s| match s {
            Step::Key(k) => Some(k.clone()),
            Step::Index(_) => None,
        })
        .collect()
}

const FLOATS: [f64; 12] = [
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e308,
    -1e308,
    0.0,
    -0.0,
    -1.0,
    5e-324,
    1e-308,
    1e6,
    -1e6,
];
const INTEGERS: [i64; 7] = [0, -1, 1, i64::MAX, i64::MIN, 4_294_967_295, 4_294_967_296];

/// Load `text` as the shipped file at `origin` would be, and run what is accepted for a short horizon.
fn load_and_run(text: String, origin: PathBuf, seed: u64) -> Result<u64, String> {
    let scenario = Scenario::from_toml(&text, &origin).map_err(|e| e.to_string())?;
    let base = origin.parent().unwrap().to_path_buf();
    let rs = ResolvedScenario::resolve(scenario, &base, origin.to_str().unwrap())
        .map_err(|e| e.to_string())?;
    let mut spec = spec_from_scenario(&rs).map_err(|e| format!("{}: {e}", rs.origin))?;
    spec.warmup_steps = spec.warmup_steps.min(20);
    spec.horizon_steps = spec.horizon_steps.min(40);
    let mut sim = Simulation::from_spec(spec, seed).map_err(|e| format!("{}: {e}", rs.origin))?;
    match sim.run() {
        Ok(m) => Ok(m.departed),
        // a run may end in the simulator's own error (one line, no panic) with extreme driver parameters
        Err(e) => Err(format!("{}: {e}", rs.origin)),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn extreme_numbers_are_refused_clearly_or_run_to_the_end(
        file in any::<prop::sample::Index>(),
        picks in prop::collection::vec((any::<prop::sample::Index>(), any::<bool>(), any::<prop::sample::Index>()), 1..3),
        seed in 0u64..4,
    ) {
        let files = shipped_files();
        let shipped = &files[file.index(files.len())];
        let mut table = shipped.table.clone();
        let mut mutated = Vec::new();
        for (leaf, as_float, value) in &picks {
            let (path, _) = &shipped.numbers[leaf.index(shipped.numbers.len())];
            let v = if *as_float {
                Value::Float(FLOATS[value.index(FLOATS.len())])
            } else {
                Value::Integer(INTEGERS[value.index(INTEGERS.len())])
            };
            set(&mut table, path, v.clone());
            mutated.push((key_names(path), v));
        }
        let text = toml::to_string(&table).unwrap();
        let origin = shipped.path.clone();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(load_and_run(text, origin, seed));
        });
        let outcome = rx.recv_timeout(Duration::from_secs(60));
        let outcome = match outcome {
            Ok(o) => o,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                return Err(TestCaseError::fail(format!("{mutated:?}: no result within 60 s")))
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(TestCaseError::fail(format!("{mutated:?}: panicked")))
            }
        };
        if let Err(message) = outcome {
            let file = shipped.path.to_str().unwrap();
            prop_assert!(message.contains(file), "{mutated:?}: {message}");
            prop_assert!(!message.contains("panicked"), "{mutated:?}: {message}");
            // TOML's own errors show the line in a small frame; every other refusal is one line
            if !message.contains("TOML parse error") {
                prop_assert_eq!(message.lines().count(), 1, "{:?}: {}", mutated, message);
            }
            // it names a key that was changed (or, for warm-up plus horizon, the horizon it adds up to)
            let named = mutated.iter().flat_map(|(keys, _)| keys).any(|k| message.contains(k.as_str()))
                || message.contains("horizon_steps");
            prop_assert!(named, "{:?}: {}", mutated, message);
        }
    }
}

fn shipped_files() -> &'static [Shipped] {
    static FILES: std::sync::OnceLock<Vec<Shipped>> = std::sync::OnceLock::new();
    FILES.get_or_init(shipped)
}

/// The reported case and its neighbours, as TOML writes them (`inf`, `nan`), on the Simple Merge.
#[test]
fn a_flow_beginning_outside_the_run_is_refused_with_the_key_the_value_and_the_range() {
    let path = scenarios_dir().join("simple_merge.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    for (begin, shown) in [
        ("-1e308", "-1e308"),
        ("-1e6", "-1e6"),
        ("-1", "-1"),
        ("inf", "inf"),
        ("-inf", "-inf"),
        ("nan", "NaN"),
        ("1e308", "1e308"),
    ] {
        let mutated = text.replacen("begin_s = 1.0", &format!("begin_s = {begin}"), 1);
        assert_ne!(mutated, text);
        let err = load_and_run(mutated, path.clone(), 0).unwrap_err();
        assert!(
            err.starts_with(path.to_str().unwrap())
                && err.contains(&format!(
                    "flows[0].begin_s: {shown} is outside the allowed range [0, 604800] s"
                )),
            "{begin}: {err}"
        );
    }
    // the shipped file itself runs, and so does a flow from t = 0
    assert!(load_and_run(text.clone(), path.clone(), 0).unwrap() > 0);
    let from_zero = text.replace("begin_s = 1.0", "begin_s = 0.0");
    assert!(load_and_run(from_zero, path, 0).unwrap() > 0);
}
