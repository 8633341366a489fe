//! AVs in any scenario (`--av-share P`): a share of each flow's vehicles become AVs, as Flow's benchmarks give
//! the AVs their own inflow beside the humans'. Each chosen flow is split in two: the humans keep the flow's id
//! at `1 - P` of its rate, and a flow `ID_av` of the same route, departure rules and times carries `P` of it in
//! an AV copy of the flow's type (`TYPE_av`: the same driver with `controlled = true`; for a type mix, the mix of
//! the AV copies, `MIX_av`). A flow by probability splits its probability, one by number its number.

use crate::model::{Control, Flow, Scenario, VehicleType};

/// The AV name of a vehicle type or mix.
fn av_name(name: &str) -> String {
    format!("{name}_av")
}

/// AVs controlled at once in a scenario that gets its controlled region from [`with_av_share`] (the paper's N_AV).
pub const DEFAULT_N_AV: u32 = 5;

/// `scenario` with `share` of the vehicles of its flows (those named in `only` by flow id or vehicle type; all
/// when empty) driven as AVs. Flows of AV types are left as they are. A scenario without a `control` section
/// gets one: at most [`DEFAULT_N_AV`] AVs controlled at once, on the whole network (the resolved scenario's
/// `with_av_share` narrows it to the approach to the network's bottlenecks).
pub fn with_av_share(
    mut scenario: Scenario,
    share: f64,
    only: &[String],
) -> Result<Scenario, String> {
    if !(0.0..=1.0).contains(&share) {
        return Err(format!("AV share {share} is outside [0, 1]"));
    }
    let known = |name: &String| {
        scenario
            .flows
            .iter()
            .any(|f| f.id == *name || f.vehicle_type == *name)
    };
    if let Some(unknown) = only.iter().find(|n| !known(n)) {
        return Err(format!(
            "--av-flows `{unknown}`: no flow or vehicle type of a flow has that name (flows: {})",
            scenario
                .flows
                .iter()
                .map(|f| f.id.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if share == 0.0 {
        return Ok(scenario);
    }
    let is_av_type = |s: &Scenario, name: &str| match s.vehicle_types.get(name) {
        Some(t) => t.controlled,
        None => s.vehicle_type_mixes.get(name).is_some_and(|m| {
            m.keys()
                .all(|t| s.vehicle_types.get(t).is_some_and(|t| t.controlled))
        }),
    };
    let mut flows = Vec::with_capacity(scenario.flows.len() * 2);
    // flows by number share their rounding: a scenario of single vehicles (each its own flow of one) still gets
    // `share` of them as AVs, every 1 / share-th vehicle in file order
    let mut carry = 0.0;
    for f in std::mem::take(&mut scenario.flows) {
        let chosen = only.is_empty() || only.iter().any(|n| *n == f.id || *n == f.vehicle_type);
        if !chosen || is_av_type(&scenario, &f.vehicle_type) {
            flows.push(f);
            continue;
        }
        add_av_type(&mut scenario, &f.vehicle_type)?;
        let (humans, avs) = split(&f, share, &mut carry);
        flows.extend(humans);
        flows.extend(avs);
    }
    scenario.flows = flows;
    if scenario.control.is_none() {
        scenario.control = Some(Control {
            n_av: DEFAULT_N_AV,
            region: Vec::new(),
            window: None,
            windows: Vec::new(),
        });
    }
    Ok(scenario)
}

/// The AV copy of type (or mix) `name`, added once.
fn add_av_type(s: &mut Scenario, name: &str) -> Result<(), String> {
    let copy = |t: &VehicleType| VehicleType {
        controlled: true,
        ..t.clone()
    };
    if let Some(t) = s.vehicle_types.get(name) {
        let t = copy(t);
        s.vehicle_types.entry(av_name(name)).or_insert(t);
        return Ok(());
    }
    let mix = s
        .vehicle_type_mixes
        .get(name)
        .cloned()
        .ok_or_else(|| format!("flow type `{name}` is not defined"))?;
    let mut av_mix = std::collections::BTreeMap::new();
    for (t, w) in mix {
        let ty = s
            .vehicle_types
            .get(&t)
            .ok_or_else(|| format!("mix `{name}`: type `{t}` is not defined"))?;
        let ty = copy(ty);
        s.vehicle_types.entry(av_name(&t)).or_insert(ty);
        av_mix.insert(av_name(&t), w);
    }
    s.vehicle_type_mixes.entry(av_name(name)).or_insert(av_mix);
    Ok(())
}

/// The humans' part of `f` and the AVs' (none when nothing is left of either: a flow of a few vehicles by
/// number whose share rounds to none stays human). `carry`: the AVs owed by the flows by number before this one
/// (the rounding of each is carried to the next, so their total is `share` of theirs).
fn split(f: &Flow, share: f64, carry: &mut f64) -> (Option<Flow>, Option<Flow>) {
    let mut avs = f.clone();
    avs.id = av_name(&f.id);
    avs.vehicle_type = av_name(&f.vehicle_type);
    avs.vehs_per_hour = f.vehs_per_hour * share;
    avs.probability = f.probability.map(|p| p * share);
    let mut humans = f.clone();
    humans.vehs_per_hour = f.vehs_per_hour * (1.0 - share);
    humans.probability = f.probability.map(|p| p * (1.0 - share));
    if let Some(n) = f.number {
        let owed = n as f64 * share + *carry;
        let av_n = (owed.round().max(0.0) as u64).min(n);
        *carry = owed - av_n as f64;
        avs.number = Some(av_n);
        humans.number = Some(n - av_n);
    }
    let nothing_left = humans.vehs_per_hour <= 0.0 || humans.number == Some(0);
    let no_av = avs.number == Some(0);
    (
        if nothing_left { None } else { Some(humans) },
        if no_av { None } else { Some(avs) },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tenth_of_each_flow_becomes_avs_as_flow_splits_its_inflows() {
        let s = Scenario::builtin("simple_merge").unwrap();
        let total: f64 = s.flows.iter().map(|f| f.vehs_per_hour).sum();
        let humans_only: Scenario = {
            let mut h = s.clone();
            h.flows
                .retain(|f| !h.vehicle_types[&f.vehicle_type].controlled);
            h.control = None;
            h
        };
        let n = humans_only.flows.len();
        let out = with_av_share(humans_only.clone(), 0.1, &[]).unwrap();
        assert_eq!(out.flows.len(), 2 * n);
        let av: f64 = out
            .flows
            .iter()
            .filter(|f| out.vehicle_types[&f.vehicle_type].controlled)
            .map(|f| f.vehs_per_hour)
            .sum();
        let all: f64 = out.flows.iter().map(|f| f.vehs_per_hour).sum();
        let human_total: f64 = humans_only.flows.iter().map(|f| f.vehs_per_hour).sum();
        assert!((all - human_total).abs() < 1e-9 && (av - 0.1 * human_total).abs() < 1e-9);
        assert!(total >= human_total);
        assert_eq!(out.control.as_ref().unwrap().n_av, 5);
        // only one flow, by its id
        let first = humans_only.flows[0].id.clone();
        let one = with_av_share(humans_only.clone(), 0.5, std::slice::from_ref(&first)).unwrap();
        assert_eq!(one.flows.len(), n + 1);
        assert!(one.flows.iter().any(|f| f.id == format!("{first}_av")));
    }

    #[test]
    fn flows_by_number_share_their_rounding_so_single_vehicles_get_their_share() {
        let mut f = Scenario::builtin("simple_merge").unwrap().flows[0].clone();
        f.number = Some(3);
        let (humans, avs) = split(&f, 0.1, &mut 0.0);
        assert_eq!(humans.unwrap().number, Some(3));
        assert!(avs.is_none());
        let (humans, avs) = split(&f, 0.5, &mut 0.0);
        assert_eq!(
            (humans.unwrap().number, avs.unwrap().number),
            (Some(1), Some(2))
        );
        // single vehicles, each a flow of one: every tenth becomes an AV
        f.number = Some(1);
        let mut carry = 0.0;
        let avs = (0..100)
            .filter(|_| split(&f, 0.1, &mut carry).1.is_some())
            .count();
        assert_eq!(avs, 10);
    }

    #[test]
    fn a_share_outside_0_1_or_an_unknown_flow_is_refused() {
        let s = Scenario::builtin("simple_merge").unwrap();
        assert!(
            with_av_share(s.clone(), 1.5, &[])
                .unwrap_err()
                .contains("outside [0, 1]")
        );
        assert!(with_av_share(s.clone(), -0.1, &[]).is_err());
        let e = with_av_share(s, 0.1, &["nope".into()]).unwrap_err();
        assert!(e.contains("`nope`"), "{e}");
    }

    #[test]
    fn all_avs_leave_no_human_flow_and_numbers_split() {
        let mut s = Scenario::builtin("simple_merge").unwrap();
        s.flows
            .retain(|f| !s.vehicle_types[&f.vehicle_type].controlled);
        s.flows[0].number = Some(7);
        let out = with_av_share(s.clone(), 1.0, &[]).unwrap();
        assert!(
            out.flows
                .iter()
                .all(|f| out.vehicle_types[&f.vehicle_type].controlled)
        );
        let out = with_av_share(s, 0.3, &[]).unwrap();
        let n: Vec<u64> = out.flows.iter().filter_map(|f| f.number).collect();
        assert_eq!(n, [5, 2]);
    }
}
