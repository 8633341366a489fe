//! `mapc view` on a multi-lane scenario: the page's packed rows carry each vehicle's lane index, lane changes
//! included, and the page draws the lanes of the two-lane main road as separate lines (headless Chromium).

use base64::Engine;
use mapc_viz::pngstats::read_png;
use serde_json::Value;
use std::path::Path;

mod common;

use common::browser::{browse, chromium_or_skip};
use common::{assert_success, run_mapc as mapc, scratch_dir};

/// Write the page of `two_lane_merge` (seed 0) into `dir`; its path and its data.
fn two_lane_page(dir: &Path) -> (std::path::PathBuf, Value) {
    let page = dir.join("two_lane.html");
    assert_success(&mapc(&[
        "view",
        "two_lane_merge",
        "-o",
        page.to_str().unwrap(),
        "--json",
    ]));
    let html = std::fs::read_to_string(&page).unwrap();
    let start = html.find("id=\"mapc-data\">").unwrap() + "id=\"mapc-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    (page, serde_json::from_str(&html[start..end]).unwrap())
}

fn bytes(v: &Value) -> Vec<u8> {
    base64::engine::general_purpose::STANDARD
        .decode(v.as_str().unwrap())
        .unwrap()
}

fn u32s(v: &Value) -> Vec<u32> {
    bytes(v)
        .chunks(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn u16s(v: &Value) -> Vec<u16> {
    bytes(v)
        .chunks(2)
        .map(|c| u16::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn the_packed_rows_of_a_two_lane_merge_carry_lane_indices_that_change() {
    let dir = scratch_dir("view-lanes-data");
    let (_, data) = two_lane_page(&dir);
    let rep = &data["replays"][0];
    let road_label = u16s(&rep["rows"]["lane"]);
    let lane_index = bytes(&rep["rows"]["lane_index"]);
    assert_eq!(lane_index.len(), road_label.len());
    // the trace's road labels name roads, the lane is apart: every label is a road or connection of the network
    let roads: Vec<&str> = data["network"]["roads"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["id"].as_str().unwrap())
        .collect();
    for l in rep["lanes"].as_array().unwrap() {
        let name = l["name"].as_str().unwrap();
        assert!(name.split('>').all(|r| roads.contains(&r)), "{name}");
    }
    assert!(lane_index.iter().all(|&k| k < 3));
    // some vehicle moves from one lane of a road to another
    let (offset, count) = (
        u32s(&rep["vehicles"]["offset"]),
        u32s(&rep["vehicles"]["count"]),
    );
    let changers = offset
        .iter()
        .zip(&count)
        .filter(|&(&o, &n)| {
            let rows = o as usize..(o + n) as usize;
            rows.clone()
                .skip(1)
                .any(|k| road_label[k] == road_label[k - 1] && lane_index[k] != lane_index[k - 1])
        })
        .count();
    assert!(changers > 0, "no vehicle changes lane in the packed rows");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs of `rgb` (within 24 on each channel) down each pixel column.
fn runs_per_column(pixels: &[[u8; 3]], width: usize, rgb: [u8; 3]) -> Vec<usize> {
    let near = |p: &[u8; 3]| (0..3).all(|c| p[c].abs_diff(rgb[c]) <= 24);
    let height = pixels.len() / width;
    (0..width)
        .map(|x| {
            let mut runs = 0;
            let mut inside = false;
            for y in 0..height {
                let on = near(&pixels[y * width + x]);
                if on && !inside {
                    runs += 1;
                }
                inside = on;
            }
            runs
        })
        .collect()
}

#[test]
fn the_page_draws_the_two_lanes_of_the_main_road_apart() {
    let Some(browser) = chromium_or_skip("the_page_draws_the_two_lanes_of_the_main_road_apart")
    else {
        return;
    };
    let dir = scratch_dir("view-lanes-browser");
    let (page, data) = two_lane_page(&dir);
    // zoom in on the middle of the main road's first two-lane road, upstream of the merge
    let road = data["network"]["roads"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["lanes"] == 2)
        .expect("a two-lane road");
    let pts: Vec<f64> = road["pts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_f64().unwrap())
        .collect();
    let (x, y) = (
        (pts[0] + pts[pts.len() - 2]) / 2.0,
        (pts[1] + pts[pts.len() - 1]) / 2.0,
    );
    let png = dir.join("lanes.png");
    browse(
        &browser,
        &dir.join("profile"),
        &format!("file://{}#t=0&zoom=12&at={x},{y}", page.display()),
        &[&format!("--screenshot={}", png.display())],
    );
    let (stats, pixels) = read_png(&png).unwrap();
    let hex = road["color"].as_str().unwrap();
    let channel = |i: usize| u8::from_str_radix(&hex[1 + 2 * i..3 + 2 * i], 16).unwrap();
    let runs = runs_per_column(
        &pixels,
        stats.width as usize,
        [channel(0), channel(1), channel(2)],
    );
    let crossing = runs.iter().filter(|&&n| n > 0).count();
    let two_lines = runs.iter().filter(|&&n| n >= 2).count();
    assert!(
        crossing > 200,
        "the road is not on the screenshot ({crossing} columns)"
    );
    // one line per lane: most columns cross two lines of the road's colour (a vehicle may split one more)
    assert!(
        two_lines * 10 > crossing * 8,
        "{two_lines} of {crossing} columns cross two lane lines"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
