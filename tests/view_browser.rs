//! `mapc view`'s page in a real browser: headless Chromium (Debian's package; `.ci/run` installs it) opens the
//! page from disk, plays it to the end, and takes screenshots at two times. The page writes what it drew into
//! `#mapc-status`, which `--dump-dom` prints.
//!
//! Without Chromium the test says so and passes, except in CI (`CI` set), where it fails: CI must run it.

use mapc_viz::pngstats::read_png;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{assert_success, run_mapc as mapc, scratch_dir};

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("MAPC_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |d| d.join(name)))
        .find(|p| p.is_file())
}

/// Run headless Chromium on `url` with `extra` arguments; its own profile folder, so parallel runs do not meet.
fn browse(browser: &Path, profile: &Path, url: &str, extra: &[&str]) -> String {
    let out = Command::new("timeout")
        .arg("180")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--no-first-run",
            "--window-size=1400,1000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed on {url}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The `data-NAME` attribute of the page's status element in a dumped DOM.
fn status_attr(dom: &str, name: &str) -> String {
    let at = dom.find("id=\"mapc-status\"").unwrap_or_else(|| {
        panic!(
            "no #mapc-status in the page: {}",
            &dom[..dom.len().min(400)]
        )
    });
    let tag = &dom[at..at + dom[at..].find('>').unwrap()];
    let key = format!("data-{name}=\"");
    let start = tag
        .find(&key)
        .unwrap_or_else(|| panic!("the page wrote no data-{name}: {tag}"))
        + key.len();
    tag[start..start + tag[start..].find('"').unwrap()].to_string()
}

#[test]
fn the_page_plays_in_chromium_and_draws_vehicles_moving() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs Chromium for the browser test (.ci/run installs Debian's chromium)"
        );
        eprintln!("skipped: no chromium on PATH (apt-get install chromium, or set MAPC_CHROMIUM)");
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
