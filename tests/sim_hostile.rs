//! Scenarios within every number's range that ask for too much work: a millisecond step over two days (1.7e8
//! steps), a fine step over a long horizon on a long corridor (too many vehicle-steps), a warm-up of a day and
//! more. Each is refused at once with one message naming the file, the key and the bound, exit code 2, by the
//! commands that read scenarios (before, they ran for hours).

mod common;

use common::{edited_scenario, refused, root};

/// `scenarios/<shipped>` with `edit` applied and its graph file found where it is shipped.
fn edited_with_graph(shipped: &str, name: &str, edit: impl Fn(String) -> String) -> String {
    let scenarios = root().join("scenarios");
    let path = edited_scenario(shipped, name, |t| {
        edit(t).replace("graph = \"", &format!("graph = \"{}/", scenarios.display()))
    });
    path.to_str().unwrap().to_string()
}

/// `mapc scenario show` and `mapc sim` refuse the scenario at `path` naming every one of `expected`.
fn refused_by_show_and_sim(path: &str, expected: &[&str]) {
    let mut expected = expected.to_vec();
    expected.push(path);
    refused(&["scenario", "show", path], &expected);
    refused(&["sim", "--scenario", path, "--seeds", "1"], &expected);
}

#[test]
fn a_millisecond_step_over_two_days_is_refused_with_the_steps_named() {
    let path = edited_scenario("simple_merge.toml", "millisecond-step", |t| {
        t.replace("step_s = 0.5", "step_s = 0.001")
            .replace("horizon_steps = 2000", "horizon_steps = 172800000")
    });
    refused_by_show_and_sim(
        path.to_str().unwrap(),
        &[
            "horizon_steps",
            "172800000 steps of step_s = 0.001 s",
            "limit of 1728000 steps",
        ],
    );
}

#[test]
fn too_many_vehicle_steps_are_refused_with_the_bound() {
    // the whole I-696 corridor, its main flow at 7200 veh/h, 47 h at 0.1 s: within the steps and the simulated
    // time, but over a thousand vehicles on the network for 1.7 million steps
    let path = edited_with_graph("i696_whole_corridor.toml", "vehicle-steps", |t| {
        t.replace("step_s = 0.5", "step_s = 0.1")
            .replace("horizon_steps = 2000", "horizon_steps = 1700000")
            .replacen("vehs_per_hour = 1800.0", "vehs_per_hour = 7200.0", 1)
    });
    refused_by_show_and_sim(
        &path,
        &["horizon_steps", "vehicle-steps", "limit of 1e9 of one run"],
    );
}

#[test]
fn a_warmup_of_a_day_is_refused_with_its_key() {
    let path = edited_scenario("simple_merge.toml", "day-warmup", |t| {
        t.replace(
            "horizon_steps = 2000",
            "horizon_steps = 2000\nwarmup_steps = 230200",
        )
    });
    refused_by_show_and_sim(
        path.to_str().unwrap(),
        &[
            "warmup_steps",
            "230200 steps of 0.5 s (32.0 h) exceed the limit of 6 h of warm-up",
        ],
    );
}
