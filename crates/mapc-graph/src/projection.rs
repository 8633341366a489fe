//! From WGS84 longitude/latitude to the graph's local metric frame and back.
//!
//! mapc uses the same frame as SUMO's netconvert: UTM (WGS84) plus an offset that puts the map near the origin, so a
//! graph imported from OSM and a SUMO net of the same area share coordinates. The UTM series are the USGS ones
//! (Snyder, "Map Projections: A Working Manual", 1987), accurate to well under a millimetre within a zone.

use serde::{Deserialize, Serialize};

const WGS84_A: f64 = 6_378_137.0;
const WGS84_F: f64 = 1.0 / 298.257_223_563;
const UTM_K0: f64 = 0.9996;
const UTM_FALSE_EASTING: f64 = 500_000.0;
const UTM_FALSE_NORTHING_SOUTH: f64 = 10_000_000.0;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Projection {
    /// local = UTM(zone) + offset.
    Utm {
        zone: u8,
        north: bool,
        offset: [f64; 2],
    },
    /// A frame with no geographic reference (a generated or abstract SUMO net): local = plane + offset.
    Plane { offset: [f64; 2] },
}

impl Projection {
    /// The UTM zone whose central meridian is nearest `lon`, with an offset that puts `(lon, lat)` at the origin.
    pub fn utm_around(lon: f64, lat: f64) -> Projection {
        let zone = (((lon + 180.0) / 6.0).floor() as i64).clamp(0, 59) as u8 + 1;
        let north = lat >= 0.0;
        let [e, n] = utm_forward(zone, north, lon, lat);
        Projection::Utm {
            zone,
            north,
            offset: [-e.round(), -n.round()],
        }
    }

    /// Parse SUMO's `<location netOffset=".." projParameter="..">`.
    pub fn from_sumo_location(
        net_offset: [f64; 2],
        proj_parameter: &str,
    ) -> Result<Projection, String> {
        let p = proj_parameter.trim();
        if p == "!" || p.is_empty() {
            return Ok(Projection::Plane { offset: net_offset });
        }
        let mut zone = None;
        let mut is_utm = false;
        let mut north = true;
        for part in p.split_whitespace() {
            match part {
                "+proj=utm" => is_utm = true,
                "+south" => north = false,
                _ => {
                    if let Some(z) = part.strip_prefix("+zone=") {
                        zone = z.parse::<u8>().ok().filter(|z| (1..=60).contains(z));
                    }
                }
            }
        }
        match (is_utm, zone) {
            (true, Some(zone)) => Ok(Projection::Utm {
                zone,
                north,
                offset: net_offset,
            }),
            _ => Err(format!(
                "unsupported projection `{p}` (mapc reads UTM projections and `!`)"
            )),
        }
    }

    pub fn is_geographic(&self) -> bool {
        matches!(self, Projection::Utm { .. })
    }

    /// Local metric position of a WGS84 point; `None` for a frame with no geographic reference.
    pub fn to_local(&self, lon: f64, lat: f64) -> Option<[f64; 2]> {
        match *self {
            Projection::Utm {
                zone,
                north,
                offset,
            } => {
                let [e, n] = utm_forward(zone, north, lon, lat);
                Some([e + offset[0], n + offset[1]])
            }
            Projection::Plane { .. } => None,
        }
    }

    /// WGS84 `[lon, lat]` of a local position; `None` for a frame with no geographic reference.
    pub fn to_lonlat(&self, pos: [f64; 2]) -> Option<[f64; 2]> {
        match *self {
            Projection::Utm {
                zone,
                north,
                offset,
            } => Some(utm_inverse(
                zone,
                north,
                pos[0] - offset[0],
                pos[1] - offset[1],
            )),
            Projection::Plane { .. } => None,
        }
    }
}

fn central_meridian_rad(zone: u8) -> f64 {
    ((zone as f64 - 1.0) * 6.0 - 180.0 + 3.0).to_radians()
}

fn meridian_arc(e2: f64, phi: f64) -> f64 {
    let e4 = e2 * e2;
    let e6 = e4 * e2;
    WGS84_A
        * ((1.0 - e2 / 4.0 - 3.0 * e4 / 64.0 - 5.0 * e6 / 256.0) * phi
            - (3.0 * e2 / 8.0 + 3.0 * e4 / 32.0 + 45.0 * e6 / 1024.0) * (2.0 * phi).sin()
            + (15.0 * e4 / 256.0 + 45.0 * e6 / 1024.0) * (4.0 * phi).sin()
            - (35.0 * e6 / 3072.0) * (6.0 * phi).sin())
}

/// `[easting, northing]` in metres.
pub fn utm_forward(zone: u8, north: bool, lon: f64, lat: f64) -> [f64; 2] {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let ep2 = e2 / (1.0 - e2);
    let phi = lat.to_radians();
    let (s, c) = phi.sin_cos();
    let n = WGS84_A / (1.0 - e2 * s * s).sqrt();
    let t = (s / c).powi(2);
    let cc = ep2 * c * c;
    let a = c * (lon.to_radians() - central_meridian_rad(zone));
    let m = meridian_arc(e2, phi);
    let x = UTM_K0
        * n
        * (a + (1.0 - t + cc) * a.powi(3) / 6.0
            + (5.0 - 18.0 * t + t * t + 72.0 * cc - 58.0 * ep2) * a.powi(5) / 120.0)
        + UTM_FALSE_EASTING;
    let mut y = UTM_K0
        * (m + n
            * (s / c)
            * (a * a / 2.0
                + (5.0 - t + 9.0 * cc + 4.0 * cc * cc) * a.powi(4) / 24.0
                + (61.0 - 58.0 * t + t * t + 600.0 * cc - 330.0 * ep2) * a.powi(6) / 720.0));
    if !north {
        y += UTM_FALSE_NORTHING_SOUTH;
    }
    [x, y]
}

/// `[lon, lat]` in degrees.
pub fn utm_inverse(zone: u8, north: bool, easting: f64, northing: f64) -> [f64; 2] {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let ep2 = e2 / (1.0 - e2);
    let e4 = e2 * e2;
    let e6 = e4 * e2;
    let y = if north {
        northing
    } else {
        northing - UTM_FALSE_NORTHING_SOUTH
    };
    let m = y / UTM_K0;
    let mu = m / (WGS84_A * (1.0 - e2 / 4.0 - 3.0 * e4 / 64.0 - 5.0 * e6 / 256.0));
    let e1 = (1.0 - (1.0 - e2).sqrt()) / (1.0 + (1.0 - e2).sqrt());
    let phi1 = mu
        + (3.0 * e1 / 2.0 - 27.0 * e1.powi(3) / 32.0) * (2.0 * mu).sin()
        + (21.0 * e1 * e1 / 16.0 - 55.0 * e1.powi(4) / 32.0) * (4.0 * mu).sin()
        + (151.0 * e1.powi(3) / 96.0) * (6.0 * mu).sin()
        + (1097.0 * e1.powi(4) / 512.0) * (8.0 * mu).sin();
    let (s1, c1) = phi1.sin_cos();
    let cc1 = ep2 * c1 * c1;
    let t1 = (s1 / c1).powi(2);
    let n1 = WGS84_A / (1.0 - e2 * s1 * s1).sqrt();
    let r1 = WGS84_A * (1.0 - e2) / (1.0 - e2 * s1 * s1).powf(1.5);
    let d = (easting - UTM_FALSE_EASTING) / (n1 * UTM_K0);
    let phi = phi1
        - (n1 * s1 / c1 / r1)
            * (d * d / 2.0
                - (5.0 + 3.0 * t1 + 10.0 * cc1 - 4.0 * cc1 * cc1 - 9.0 * ep2) * d.powi(4) / 24.0
                + (61.0 + 90.0 * t1 + 298.0 * cc1 + 45.0 * t1 * t1
                    - 252.0 * ep2
                    - 3.0 * cc1 * cc1)
                    * d.powi(6)
                    / 720.0);
    let lambda = central_meridian_rad(zone)
        + (d - (1.0 + 2.0 * t1 + cc1) * d.powi(3) / 6.0
            + (5.0 - 2.0 * cc1 + 28.0 * t1 - 3.0 * cc1 * cc1 + 8.0 * ep2 + 24.0 * t1 * t1)
                * d.powi(5)
                / 120.0)
            / c1;
    [lambda.to_degrees(), phi.to_degrees()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_matches_a_published_point() {
        // The Statue of Liberty, zone 18N: 40.689247 N, 74.044502 W -> 580 741 E, 4 504 692 N (NGS/NOAA tools).
        let [e, n] = utm_forward(18, true, -74.044502, 40.689247);
        assert!((e - 580_741.0).abs() < 10.0, "easting {e}");
        assert!((n - 4_504_692.0).abs() < 10.0, "northing {n}");
    }

    #[test]
    fn utm_round_trips_to_a_millimetre() {
        for &(lon, lat) in &[
            (-83.4877071, 42.4878973),
            (-83.3429, 42.5261),
            (-80.9, 43.0),
            (-84.0, 41.9),
        ] {
            let [e, n] = utm_forward(17, true, lon, lat);
            let [lon2, lat2] = utm_inverse(17, true, e, n);
            let err_m = ((lon2 - lon) * 82_000.0).hypot((lat2 - lat) * 111_000.0);
            assert!(err_m < 1e-3, "({lon}, {lat}) came back {err_m} m away");
        }
    }

    #[test]
    fn sumo_location_is_parsed() {
        let p = Projection::from_sumo_location(
            [-291727.60, -4702987.13],
            "+proj=utm +zone=17 +ellps=WGS84 +datum=WGS84 +units=m +no_defs",
        )
        .unwrap();
        assert_eq!(
            p,
            Projection::Utm {
                zone: 17,
                north: true,
                offset: [-291727.60, -4702987.13]
            }
        );
        assert_eq!(
            Projection::from_sumo_location([1.0, 2.0], "!").unwrap(),
            Projection::Plane { offset: [1.0, 2.0] }
        );
        assert!(Projection::from_sumo_location([0.0, 0.0], "+proj=merc").is_err());
    }
}
