//! Values no road has, in a SUMO net: refused at import with the file, the line and the lane named, rather than fed
//! on to the later stages (a speed of 1e-300 m/s made a warm-up of days, a length of 1e308 m one of infinity).

use mapc_import::{ImportOptions, MapFormat, import_bytes};

const SIMPLE_MERGE: &str = include_str!("../../../maps/simple_merge.net.xml");

/// The Simple Merge's net with lane `bottom_0`'s attribute `key` set to `value`.
fn with_bottom_lane(key: &str, value: &str) -> String {
    let lane = SIMPLE_MERGE
        .lines()
        .find(|l| l.contains("<lane id=\"bottom_0\""))
        .unwrap();
    let edited = match lane.find(&format!(" {key}=\"")) {
        Some(at) => {
            let start = at + key.len() + 3;
            let end = start + lane[start..].find('"').unwrap();
            format!("{}{value}{}", &lane[..start], &lane[end..])
        }
        None => lane.replacen(" shape=", &format!(" {key}=\"{value}\" shape="), 1),
    };
    SIMPLE_MERGE.replacen(lane, &edited, 1)
}

#[test]
fn a_lane_no_road_has_is_refused_naming_the_file_line_and_lane() {
    let line = SIMPLE_MERGE
        .lines()
        .position(|l| l.contains("<lane id=\"bottom_0\""))
        .unwrap()
        + 1;
    for (key, value, says) in [
        ("speed", "1e-300", "speed 1e-300 is outside [0.1, 1000] m/s"),
        ("speed", "1e308", "speed 1e308 is outside"),
        ("length", "1e308", "length 1e308 is outside [0, 1e6] m"),
        ("width", "1e-9", "width 1e-9 is outside [0.1, 100] m"),
        ("width", "5000", "width 5000 is outside"),
    ] {
        let text = with_bottom_lane(key, value);
        let err = import_bytes(
            text.as_bytes(),
            MapFormat::SumoNet,
            "bad.net.xml",
            &ImportOptions::default(),
        )
        .expect_err(value)
        .to_string();
        assert!(
            err.starts_with(&format!("bad.net.xml: line {line}, ")),
            "{err}"
        );
        assert!(err.contains(&format!("lane `bottom_0`: {says}")), "{err}");
    }
}

#[test]
fn a_long_or_fast_lane_a_road_may_have_is_kept_with_a_warning() {
    let text = with_bottom_lane("length", "150000");
    let g = import_bytes(
        text.as_bytes(),
        MapFormat::SumoNet,
        "long.net.xml",
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(g.warnings.counts.get("length_implausible"), Some(&1));
}
