//! Tag interpretation: a way's highway class, directions, lanes and speed limits, with counted warnings where a
//! tag cannot be read.

use super::OsmWay;
use mapc_graph::Warnings;

/// Lane width given to every OSM lane (US interstate lanes are 12 ft).
pub const OSM_LANE_WIDTH_M: f64 = 3.65;
const MPH: f64 = 0.447_04;
const KMH: f64 = 1.0 / 3.6;
const KNOT: f64 = 0.514_444;
/// A speed limit above this (300 km/h) is a mistake in the data, not a road.
pub const MAX_PLAUSIBLE_SPEED_MPS: f64 = 300.0 / 3.6;
/// The limit of a road tagged `maxspeed=none` (no limit, as on much of the German Autobahn): netconvert's
/// `osm.speedlimit-none` default in SUMO 1.8, 39.4444 m/s (142 km/h).
pub const SPEED_LIMIT_NONE_MPS: f64 = 39.4444;
/// Nor is one below walking pace (1 km/h: `maxspeed=1e-300` reads as 1 km/h with an unknown unit, but
/// `maxspeed=0.0001` as a number).
pub const MIN_PLAUSIBLE_SPEED_MPS: f64 = 1.0 / 3.6;
/// Two consecutive nodes of a road further apart than this (10 km) are counted as `long_segment`: real highway
/// geometry has a node every few hundred metres at most, so this is a misplaced node.
pub const LONG_SEGMENT_M: f64 = 10_000.0;

/// The tags of a way that the importer reads; everything else is dropped while streaming.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WayTags {
    pub highway: String,
    pub oneway: Option<String>,
    pub junction: Option<String>,
    pub lanes: Option<String>,
    pub lanes_forward: Option<String>,
    pub lanes_backward: Option<String>,
    pub maxspeed: Option<String>,
    pub maxspeed_forward: Option<String>,
    pub maxspeed_backward: Option<String>,
    pub name: Option<String>,
    pub ref_: Option<String>,
    pub area: Option<String>,
    /// `turn:lanes` (and per direction): one `|`-separated entry per lane, read for the lane count when `lanes`
    /// is missing.
    pub turn_lanes: Option<String>,
    pub turn_lanes_forward: Option<String>,
    pub turn_lanes_backward: Option<String>,
}

impl WayTags {
    /// Record one `k=v` tag; returns false for tags the importer ignores.
    pub fn set(&mut self, k: &str, v: &str) -> bool {
        let slot = match k {
            "highway" => {
                self.highway = v.to_string();
                return true;
            }
            "oneway" => &mut self.oneway,
            "junction" => &mut self.junction,
            "lanes" => &mut self.lanes,
            "lanes:forward" => &mut self.lanes_forward,
            "lanes:backward" => &mut self.lanes_backward,
            "maxspeed" => &mut self.maxspeed,
            "maxspeed:forward" => &mut self.maxspeed_forward,
            "maxspeed:backward" => &mut self.maxspeed_backward,
            "name" => &mut self.name,
            "ref" => &mut self.ref_,
            "area" => &mut self.area,
            "turn:lanes" => &mut self.turn_lanes,
            "turn:lanes:forward" => &mut self.turn_lanes_forward,
            "turn:lanes:backward" => &mut self.turn_lanes_backward,
            _ => return false,
        };
        *slot = Some(v.to_string());
        true
    }
}

/// Class defaults: lanes per direction, speed limit (m/s) and priority rank. US values, as the maps are American.
pub fn class_defaults(class: &str) -> (u8, f64, i32) {
    match class {
        "motorway" => (2, 65.0 * MPH, 13),
        "motorway_link" => (1, 45.0 * MPH, 12),
        "trunk" => (2, 55.0 * MPH, 11),
        "trunk_link" => (1, 40.0 * MPH, 10),
        "primary" => (1, 45.0 * MPH, 9),
        "primary_link" => (1, 35.0 * MPH, 8),
        "secondary" => (1, 40.0 * MPH, 7),
        "secondary_link" => (1, 30.0 * MPH, 6),
        "tertiary" => (1, 35.0 * MPH, 6),
        "tertiary_link" => (1, 25.0 * MPH, 5),
        "unclassified" | "residential" => (1, 25.0 * MPH, 4),
        "living_street" => (1, 10.0 * MPH, 3),
        "service" => (1, 15.0 * MPH, 2),
        _ => (1, 25.0 * MPH, 1),
    }
}

/// `70 mph`, `100`, `100 km/h`, `20 knots` -> m/s. `None` for anything else (`US:urban`, `none`, `signals`).
pub fn parse_maxspeed(text: &str) -> Option<f64> {
    let t = text.split(';').next()?.trim();
    let digits_end = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let value: f64 = t[..digits_end].parse().ok()?;
    let unit = t[digits_end..].trim();
    let factor = match unit {
        "" | "km/h" | "kmh" | "kph" => KMH,
        "mph" => MPH,
        "knots" => KNOT,
        _ => return None,
    };
    (value > 0.0 && value.is_finite()).then_some(value * factor)
}

fn parse_lanes(text: &str) -> Option<u8> {
    let n: u32 = text.split(';').next()?.trim().parse().ok()?;
    (1..=16).contains(&n).then_some(n as u8)
}

/// Which directions a way can be driven in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Directions {
    pub(super) forward: bool,
    pub(super) backward: bool,
}

pub(super) fn directions(way: &OsmWay, warnings: &mut Warnings) -> Directions {
    let implied = matches!(way.tags.highway.as_str(), "motorway" | "motorway_link")
        || way.tags.junction.as_deref() == Some("roundabout");
    match way.tags.oneway.as_deref() {
        Some("yes" | "true" | "1") => Directions {
            forward: true,
            backward: false,
        },
        Some("-1" | "reverse") => Directions {
            forward: false,
            backward: true,
        },
        Some("no" | "false" | "0") => Directions {
            forward: true,
            backward: true,
        },
        None => Directions {
            forward: true,
            backward: !implied,
        },
        Some(other) => {
            warnings.add(
                "oneway_unknown",
                format!(
                    "way {}: oneway={other}, read as {}",
                    way.id,
                    if implied { "yes" } else { "no" }
                ),
            );
            Directions {
                forward: true,
                backward: !implied,
            }
        }
    }
}

/// Why a kept way cannot become roads, as (warning kind, reason): an area (`area=yes`: a square, not a line to
/// drive along) or a way whose direction changes with the time of day (`oneway=reversible|alternating`).
pub(super) fn unusable(way: &OsmWay) -> Option<(&'static str, String)> {
    if way.tags.area.as_deref() == Some("yes") {
        return Some((
            "area_dropped",
            format!("{} with area=yes", way.tags.highway),
        ));
    }
    match way.tags.oneway.as_deref() {
        Some(v @ ("reversible" | "alternating")) => Some((
            "oneway_reversible_dropped",
            format!("oneway={v}: its direction depends on the time"),
        )),
        _ => None,
    }
}

/// Lanes (forward, backward) of a way.
pub(super) fn lane_counts(way: &OsmWay, dirs: Directions, warnings: &mut Warnings) -> (u8, u8) {
    let (default, _, _) = class_defaults(&way.tags.highway);
    let t = &way.tags;
    let mut read = |key: &str, v: &Option<String>| -> Option<u8> {
        let text = v.as_deref()?;
        let n = parse_lanes(text);
        match n {
            None => warnings.add("lanes_unparsed", format!("way {}: {key}={text}", way.id)),
            // `2;3`: the tag holds several values (lanes that change along the way); the first is read
            Some(first) if text.contains(';') => warnings.add(
                "lanes_multiple_values",
                format!("way {}: {key}={text}, read as {first}", way.id),
            ),
            Some(_) => {}
        }
        n
    };
    // `turn:lanes` has one `|`-separated entry per lane: the lane count where `lanes` is missing
    let turn_count = |v: &Option<String>| -> Option<u8> {
        let n = v.as_deref()?.split('|').count();
        (1..=16).contains(&n).then_some(n as u8)
    };
    let total = read("lanes", &t.lanes);
    let fwd = read("lanes:forward", &t.lanes_forward).or_else(|| turn_count(&t.turn_lanes_forward));
    let bwd =
        read("lanes:backward", &t.lanes_backward).or_else(|| turn_count(&t.turn_lanes_backward));
    let one_way = dirs.forward != dirs.backward;
    let total = total.or_else(|| turn_count(&t.turn_lanes).filter(|_| one_way));
    let two_way = dirs.forward && dirs.backward;
    let result = if two_way {
        match (fwd, bwd, total) {
            (Some(f), Some(b), _) => Some((f, b)),
            (Some(f), None, Some(n)) => Some((f, n.saturating_sub(f).max(1))),
            (None, Some(b), Some(n)) => Some((n.saturating_sub(b).max(1), b)),
            (None, None, Some(n)) => Some((n.div_ceil(2).max(1), (n / 2).max(1))),
            _ => None,
        }
    } else if dirs.forward {
        fwd.or(total).map(|n| (n, 0))
    } else {
        bwd.or(total).map(|n| (0, n))
    };
    result.unwrap_or_else(|| {
        warnings.add(
            "lanes_defaulted",
            format!(
                "way {} ({}): no lanes tag, {default} per direction",
                way.id, way.tags.highway
            ),
        );
        (default, default)
    })
}

/// Speed limits (forward, backward) in m/s.
pub(super) fn speeds(way: &OsmWay, warnings: &mut Warnings) -> (f64, f64) {
    let (_, default, _) = class_defaults(&way.tags.highway);
    let t = &way.tags;
    let mut read = |key: &str, v: &Option<String>| -> Option<f64> {
        let text = v.as_deref()?;
        if text.trim() == "none" {
            return Some(SPEED_LIMIT_NONE_MPS);
        }
        match parse_maxspeed(text) {
            None => {
                warnings.add(
                    "maxspeed_unparsed",
                    format!("way {}: {key}={text}, class default used", way.id),
                );
                None
            }
            // a typo (`650`, `0.001`) or a unit mix-up: the class default is closer to the truth than 650 km/h,
            // as netconvert falls back on its type's speed
            Some(s) if !(MIN_PLAUSIBLE_SPEED_MPS..=MAX_PLAUSIBLE_SPEED_MPS).contains(&s) => {
                warnings.add(
                    "maxspeed_implausible",
                    format!(
                        "way {}: {key}={text}, outside {:.0} to {:.0} km/h: class default used",
                        way.id,
                        MIN_PLAUSIBLE_SPEED_MPS * 3.6,
                        MAX_PLAUSIBLE_SPEED_MPS * 3.6
                    ),
                );
                None
            }
            s => s,
        }
    };
    let both = read("maxspeed", &t.maxspeed);
    let fwd = read("maxspeed:forward", &t.maxspeed_forward).or(both);
    let bwd = read("maxspeed:backward", &t.maxspeed_backward).or(both);
    if fwd.is_none() && bwd.is_none() && t.maxspeed.is_none() {
        warnings.add(
            "maxspeed_defaulted",
            format!("way {} ({}): no maxspeed tag", way.id, way.tags.highway),
        );
    }
    (fwd.unwrap_or(default), bwd.unwrap_or(default))
}
