//! `mapc window --keep-lanes` at the I-696 merges whose main line passes a lane gained and dropped again far
//! down the corridor (beyond the best lanes' look-ahead): no lane goes from the corridor's start to its end
//! without a change, so the main line changes lanes on the road where its lane ends, as the drivers do. Both
//! windows were refused with "network: no connection from R114 to R110" (and "from R50 to R63").

mod common;

use common::{mapc_json, scratch_dir};

#[test]
fn keep_lanes_windows_are_cut_where_the_main_line_must_change_lanes() {
    let dir = scratch_dir("keep-lanes-windows");
    for junction in ["osm:61860349", "osm:62339771"] {
        let out = dir.join(format!("w_{}.toml", &junction[4..]));
        let report = mapc_json(&[
            "window",
            "maps/i696.osm",
            "--keep-lanes",
            "--junction",
            junction,
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(out.exists(), "{junction}: {report:#}");
        let sim = mapc_json(&[
            "sim",
            "--scenario",
            out.to_str().unwrap(),
            "--seeds",
            "1",
            "--json",
        ]);
        let run = &sim["runs"][0];
        assert!(run["arrived"].as_u64().unwrap() > 0, "{junction}: {sim:#}");
        assert!(
            run["lane_changes"].as_u64().unwrap() > 0,
            "{junction}: {sim:#}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
