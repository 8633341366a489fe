//! `mapc view`'s page in a real browser: headless Chromium (`common::browser`) opens the page from disk, plays it
//! to the end, and takes screenshots at two times.

use mapc_viz::pngstats::read_png;
use serde_json::Value;

mod common;

use common::browser::{browse, chromium_or_skip, status_attr};
use common::{assert_success, run_mapc as mapc, scratch_dir};

#[test]
fn the_page_plays_in_chromium_and_draws_vehicles_moving() {
    let Some(browser) = chromium_or_skip("the_page_plays_in_chromium_and_draws_vehicles_moving")
    else {
        return;
    };
    let dir = scratch_dir("view-browser");
    let page = dir.join("replay.html");
    let out = mapc(&[
        "view",
        "simple_merge",
        "--policy",
        "policies/simple_merge_outflow.json",
        "--compare",
        "-o",
        page.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    let url = format!("file://{}", page.display());

    // played at 50x on the browser's virtual clock: 40 s of it take the run to its last frame
    let dom = browse(
        &browser,
        &dir.join("profile-play"),
        &format!("{url}#play&rate=50"),
        &["--virtual-time-budget=40000", "--dump-dom"],
    );
    let frames_drawn: u64 = status_attr(&dom, "frames-drawn").parse().unwrap();
    assert!(frames_drawn > 100, "only {frames_drawn} frames drawn");
    assert_eq!(status_attr(&dom, "frame"), "2000", "played to the end");
    let vehicles: u64 = status_attr(&dom, "vehicles-drawn").parse().unwrap();
    assert!(vehicles > 10, "{vehicles} vehicles drawn at the end");
    // the page's own figures at the last frame are the run's (humans' pane first)
    let outflow = summary["panes"][0]["outflow_veh_h"].as_f64().unwrap();
    assert_eq!(status_attr(&dom, "outflow"), format!("{outflow:.3}"));

    // hovering (as #hover=ID points at it) names a vehicle, a road and a junction with their provenance
    let hover = |at: &str, profile: &str| {
        let dom = browse(
            &browser,
            &dir.join(profile),
            &format!("{url}#{at}"),
            &["--dump-dom"],
        );
        status_attr(&dom, "hover")
    };
    let vehicle = hover("t=0&hover=0", "profile-hover-vehicle");
    assert!(vehicle.starts_with("vehicle 0 · human"), "{vehicle}");
    let road = hover("hover=R0", "profile-hover-road");
    assert!(
        road.starts_with("road R0 · inflow_highway") && road.contains("sumo:inflow_highway"),
        "{road}"
    );
    let junction = hover("hover=J2", "profile-hover-junction");
    assert!(junction.starts_with("junction J2 · merge"), "{junction}");

    // two moments of the same page look different: the vehicles moved
    let shot = |t: &str| {
        let png = dir.join(format!("t{t}.png"));
        browse(
            &browser,
            &dir.join(format!("profile-{t}")),
            &format!("{url}#t={t}"),
            &[&format!("--screenshot={}", png.display())],
        );
        read_png(&png).unwrap()
    };
    let (s0, p0) = shot("0");
    let (s60, p60) = shot("60");
    assert_eq!((s0.width, s0.height), (s60.width, s60.height));
    assert!(
        s0.ink_fraction > 0.05 && s60.ink_fraction > 0.05,
        "blank page"
    );
    let changed = p0.iter().zip(&p60).filter(|(a, b)| a != b).count();
    assert!(
        changed > 2000,
        "only {changed} pixels differ between t = 0 and t = 60 s"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A SUMO user's ramp meter in the page: the bar at its stop line is green in the program's green phase and
/// red in its red one (G 5 s / r 5 s from the run's begin, two set-up steps before the first frame), and the
/// page knows each type's length (trucks are drawn longer).
#[test]
fn a_ramp_meter_shows_its_phase_and_types_their_length() {
    let Some(browser) = chromium_or_skip("a_ramp_meter_shows_its_phase_and_types_their_length")
    else {
        return;
    };
    let dir = scratch_dir("view-lights");
    let page = dir.join("meter.html");
    let out = mapc(&[
        "view",
        "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg",
        "-o",
        page.to_str().unwrap(),
    ]);
    assert_success(&out);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains(r#""lights":[{"id":"ramp_meter""#),
        "no light in the page"
    );
    assert!(
        html.contains(r#""length_m":5.0"#),
        "no type length in the page"
    );
    let url = format!("file://{}", page.display());
    // zoomed on the meter: the end of the on-ramp (R7)
    let count = |t: &str, rgb: [u8; 3]| {
        let png = dir.join(format!("meter{t}.png"));
        browse(
            &browser,
            &dir.join(format!("profile-{t}")),
            &format!("{url}#t={t}&zoom=6&at=-3.7,36.3"),
            &[&format!("--screenshot={}", png.display())],
        );
        let (_, pixels) = read_png(&png).unwrap();
        pixels.iter().filter(|p| **p == rgb).count()
    };
    const GREEN: [u8; 3] = [0x2e, 0xcc, 0x40];
    const RED: [u8; 3] = [0xff, 0x2d, 0x2d];
    // light time 301 s: 1 s into a green; 306 s: 1 s into a red
    let (green, red) = (count("303", GREEN), count("303", RED));
    assert!(
        green > 10 && red == 0,
        "t = 303 s: {green} green, {red} red pixels"
    );
    let (green, red) = (count("308", GREEN), count("308", RED));
    assert!(
        red > 10 && green == 0,
        "t = 308 s: {green} green, {red} red pixels"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
