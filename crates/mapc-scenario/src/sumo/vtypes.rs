//! SUMO 1.8's vehicle types: a `vType` element with the defaults of its vehicle class, as a mapc
//! [`VehicleType`]. Attributes that only draw the vehicle (colour, shape, size in the GUI) are read and left
//! aside; those that change the driving and are not simulated are refused.

use super::SumoError;
use crate::model::{CarFollowModel, VehicleType};
use mapc_import::SumoElement;

/// SUMO 1.8's defaults of a vehicle class: length, max speed, accel, decel, emergency decel and the speed
/// factor's deviation (`SUMOVTypeParameter::VClassDefaultValues`).
struct ClassDefaults {
    length: f64,
    max_speed: f64,
    accel: f64,
    decel: f64,
    emergency_decel: f64,
    speed_dev: f64,
}

fn class_defaults(vclass: &str) -> Option<ClassDefaults> {
    let d = |length, max_speed, accel, decel, emergency_decel, speed_dev| ClassDefaults {
        length,
        max_speed,
        accel,
        decel,
        emergency_decel,
        speed_dev,
    };
    let car = 200.0 / 3.6;
    Some(match vclass {
        "passenger" | "private" | "vip" | "hov" | "custom1" | "custom2" | "evehicle" => {
            d(5.0, car, 2.6, 4.5, 9.0, 0.1)
        }
        "taxi" => d(5.0, car, 2.6, 4.5, 9.0, 0.05),
        "truck" => d(7.1, 130.0 / 3.6, 1.3, 4.0, 7.0, 0.05),
        "trailer" => d(16.5, 130.0 / 3.6, 1.1, 4.0, 7.0, 0.05),
        "bus" => d(12.0, 100.0 / 3.6, 1.2, 4.0, 7.0, 0.0),
        "coach" => d(14.0, 100.0 / 3.6, 2.0, 4.0, 7.0, 0.05),
        "delivery" => d(6.5, car, 2.6, 4.5, 9.0, 0.05),
        "emergency" => d(6.5, car, 2.6, 4.5, 9.0, 0.0),
        "motorcycle" => d(2.2, car, 6.0, 10.0, 10.0, 0.1),
        _ => return None,
    })
}

/// Attributes that change nothing mapc simulates (drawing, emissions, persons, the sublane model's lateral
/// behaviour, which only acts with a lateral resolution).
const WITHOUT_EFFECT: &[&str] = &[
    "id",
    "color",
    "guiShape",
    "width",
    "height",
    "imgFile",
    "osgFile",
    "emissionClass",
    "personCapacity",
    "containerCapacity",
    "boardingDuration",
    "loadingDuration",
    "latAlignment",
    "minGapLat",
    "maxSpeedLat",
    "probability",
    "laneChangeModel",
    "apparentDecel",
    "actionStepLength",
];

/// The mean and deviation of SUMO's `speedFactor` (`1.1`, `norm(1,0.1)`, `normc(1,0.1,0.2,2)`), over the class's
/// (`mean`, `dev`) where only the mean is given.
fn speed_factor(text: &str, dev: f64, place: &str) -> Result<(f64, f64), SumoError> {
    let bad = || {
        SumoError::at(
            place,
            format!("speedFactor `{text}`: a number, norm(mean,dev) or normc(mean,dev,min,max)"),
        )
    };
    let t = text.trim();
    if let Ok(mean) = t.parse::<f64>() {
        return Ok((mean, dev));
    }
    let inner = t
        .strip_prefix("normc(")
        .or_else(|| t.strip_prefix("norm("))
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(bad)?;
    let xs: Vec<f64> = inner
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let bound = |k: usize, sumo: f64, what: &str| -> Result<(), SumoError> {
        match xs.get(k) {
            Some(x) if (x - sumo).abs() > 1e-12 => Err(SumoError::at(
                place,
                format!(
                    "speedFactor `{text}`: mapc bounds the speed factor by [0.2, 2] (SUMO's default), not {what} {x}"
                ),
            )),
            _ => Ok(()),
        }
    };
    if !(2..=4).contains(&xs.len()) {
        return Err(bad());
    }
    bound(2, 0.2, "from")?;
    bound(3, 2.0, "up to")?;
    Ok((xs[0], xs[1]))
}

/// A number attribute of `e`, if given.
pub(super) fn num(e: &SumoElement, key: &str) -> Result<Option<f64>, SumoError> {
    e.number(key).map_err(|m| SumoError::at(&e.place, m))
}

/// SUMO's default vehicle type (`DEFAULT_VEHTYPE`): a passenger car.
pub fn default_vtype(default_speed_dev: f64, model: CarFollowModel) -> VehicleType {
    let c = class_defaults("passenger").expect("passenger is a class");
    VehicleType {
        accel: c.accel,
        decel: c.decel,
        tau: 1.0,
        min_gap: 2.5,
        max_speed: c.max_speed,
        speed_factor: 1.0,
        speed_dev: if default_speed_dev >= 0.0 {
            default_speed_dev
        } else {
            c.speed_dev
        },
        impatience: 0.0,
        length: c.length,
        car_follow_model: model,
        sigma: Some(0.5),
        emergency_decel: Some(c.emergency_decel),
        ..VehicleType::default()
    }
}

/// A `vType` element as a mapc vehicle type (`skipped`: the kinds of attribute dropped where
/// `skip_unsupported`).
pub fn vtype(
    e: &SumoElement,
    default_speed_dev: f64,
    default_model: CarFollowModel,
    skip_unsupported: bool,
    skipped: &mut Vec<String>,
) -> Result<VehicleType, SumoError> {
    let vclass = e.get("vClass").unwrap_or("passenger");
    let c = class_defaults(vclass).ok_or_else(|| {
        SumoError::at(&e.place, format!("vClass `{vclass}`: mapc simulates road vehicles (passenger, taxi, truck, trailer, bus, coach, delivery, emergency, motorcycle)"))
    })?;
    let model = match e.get("carFollowModel") {
        None => default_model,
        Some("Krauss") => CarFollowModel::Krauss,
        Some("IDM") => CarFollowModel::Idm,
        Some(m) => {
            return Err(SumoError::at(
                &e.place,
                format!("carFollowModel `{m}`: mapc has Krauss and IDM"),
            ));
        }
    };
    if let Some(m) = e.get("laneChangeModel")
        && m != "LC2013"
        && m != "default"
    {
        return Err(SumoError::at(
            &e.place,
            format!("laneChangeModel `{m}`: mapc has LC2013"),
        ));
    }
    let decel = num(e, "decel")?.unwrap_or(c.decel);
    let dev0 = if default_speed_dev >= 0.0 {
        default_speed_dev
    } else {
        c.speed_dev
    };
    let (speed_factor, mut speed_dev) = match e.get("speedFactor") {
        Some(t) => speed_factor(t, dev0, &e.place)?,
        None => (1.0, dev0),
    };
    if let Some(d) = num(e, "speedDev")? {
        speed_dev = d;
    }
    let mut t = VehicleType {
        accel: num(e, "accel")?.unwrap_or(c.accel),
        decel,
        tau: num(e, "tau")?.unwrap_or(1.0),
        min_gap: num(e, "minGap")?.unwrap_or(2.5),
        max_speed: num(e, "maxSpeed")?.unwrap_or(c.max_speed),
        speed_factor,
        speed_dev,
        impatience: num(e, "impatience")?.unwrap_or(0.0),
        length: num(e, "length")?.unwrap_or(c.length),
        car_follow_model: model,
        sigma: Some(num(e, "sigma")?.unwrap_or(0.5)),
        emergency_decel: Some(num(e, "emergencyDecel")?.unwrap_or(c.emergency_decel.max(decel))),
        ..VehicleType::default()
    };
    if let Some(delta) = num(e, "delta")? {
        t.delta = delta;
    }
    if let Some(stepping) = num(e, "stepping")? {
        t.idm_stepping_s = stepping;
    }
    t.lane_change = crate::model::LaneChangeParams::from_sumo(|attr| num(e, attr))?;
    for (name, _, v) in t.lane_change.given() {
        crate::ranges::check(name, v, crate::ranges::lane_change_range(name)).map_err(|r| {
            SumoError::at(&e.place, format!("lane-change {}: {}", r.key, r.message))
        })?;
    }
    for (k, v) in &e.attrs {
        let known = matches!(
            k.as_str(),
            "vClass"
                | "carFollowModel"
                | "accel"
                | "decel"
                | "emergencyDecel"
                | "tau"
                | "minGap"
                | "maxSpeed"
                | "speedFactor"
                | "speedDev"
                | "impatience"
                | "length"
                | "sigma"
                | "delta"
                | "stepping"
        ) || WITHOUT_EFFECT.contains(&k.as_str())
            || crate::model::LANE_CHANGE_NAMES
                .iter()
                .any(|(_, attr)| attr == k);
        if known {
            continue;
        }
        // lane-change and junction-model parameters other than SUMO's defaults change the driving
        let what = if k.starts_with("lc") {
            "a lane-change parameter mapc does not simulate (it reads lcStrategic, lcCooperative, lcSpeedGain, \
             lcKeepRight, lcLookaheadLeft, lcSpeedGainRight and lcAssertive)"
        } else if k.starts_with("jm") {
            "junction-model parameters are not simulated"
        } else {
            "an attribute mapc does not read"
        };
        if skip_unsupported {
            skipped.push(format!("vType attribute `{k}` ({what})"));
        } else {
            return Err(SumoError::at(
                &e.place,
                format!("`{k}=\"{v}\"`: {what}; `--skip-unsupported` drops it"),
            ));
        }
    }
    for child in &e.children {
        if child.name != "param" {
            if skip_unsupported {
                skipped.push(format!("<{}> inside a vType", child.name));
            } else {
                return Err(SumoError::at(
                    &child.place,
                    format!(
                        "<{}> inside a vType is not read; `--skip-unsupported` drops it",
                        child.name
                    ),
                ));
            }
        }
    }
    Ok(t)
}
