//! Fixed-time traffic lights as SUMO 1.8 runs a static `tlLogic`: the phases follow each other for their
//! durations from the run's begin (shifted by the program's offset), and each controlled link reads its letter
//! of the current phase's state.

use mapc_graph::TrafficLight;

/// What a link's signal says now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignalState {
    /// `G` (and the signal off, `o`/`O`): drive on with priority.
    Green,
    /// `g`: drive on, yielding to the foes with priority.
    GreenYield,
    /// `y`/`Y`: stop if one can still brake in time.
    Yellow,
    /// `s`: stop, then drive on yielding to the foes with priority (a right turn on red; SUMO's
    /// `LINKSTATE_STOP`).
    Stop,
    /// `r`, `u` (red-yellow) and anything else: stop.
    Red,
}

impl SignalState {
    fn of(letter: u8) -> SignalState {
        match letter {
            b'G' | b'o' | b'O' => SignalState::Green,
            b'g' => SignalState::GreenYield,
            b'y' | b'Y' => SignalState::Yellow,
            b's' => SignalState::Stop,
            _ => SignalState::Red,
        }
    }
}

/// The state of link `index` of `light` at `t` seconds after the run's begin.
pub fn state_at(light: &TrafficLight, index: u32, t: f64) -> SignalState {
    state_in_phase(light, phase_at(light, t), index)
}

/// The phase of `light` at `t` seconds after the run's begin; `None` where the light shows green to all (no
/// cycle). The simulator asks this once a step per light ([`state_in_phase`] then reads each link's letter).
pub fn phase_at(light: &TrafficLight, t: f64) -> Option<usize> {
    let cycle: f64 = light.phases.iter().map(|p| p.duration_s).sum();
    if !(cycle > 0.0) {
        return None;
    }
    let mut into = (t - light.offset_s).rem_euclid(cycle);
    for (i, p) in light.phases.iter().enumerate() {
        if into < p.duration_s {
            return Some(i);
        }
        into -= p.duration_s;
    }
    None
}

/// The state of link `index` of `light` in its phase `phase` ([`phase_at`]).
pub fn state_in_phase(light: &TrafficLight, phase: Option<usize>, index: u32) -> SignalState {
    phase
        .and_then(|i| light.phases[i].state.as_bytes().get(index as usize))
        .map_or(SignalState::Green, |&c| SignalState::of(c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mapc_graph::SignalPhase;

    #[test]
    fn phases_follow_each_other_from_the_offset() {
        let meter = TrafficLight {
            id: "m".into(),
            program: "0".into(),
            offset_s: 0.0,
            phases: vec![
                SignalPhase {
                    duration_s: 5.0,
                    state: "Gr".into(),
                },
                SignalPhase {
                    duration_s: 2.0,
                    state: "yr".into(),
                },
                SignalPhase {
                    duration_s: 3.0,
                    state: "rg".into(),
                },
            ],
        };
        assert_eq!(state_at(&meter, 0, 0.0), SignalState::Green);
        assert_eq!(state_at(&meter, 0, 4.99), SignalState::Green);
        assert_eq!(state_at(&meter, 0, 5.0), SignalState::Yellow);
        assert_eq!(state_at(&meter, 0, 7.5), SignalState::Red);
        assert_eq!(state_at(&meter, 1, 7.5), SignalState::GreenYield);
        // the cycle repeats every 10 s
        assert_eq!(state_at(&meter, 0, 1234.0), SignalState::Green);
        let late = TrafficLight {
            offset_s: 5.0,
            ..meter
        };
        assert_eq!(state_at(&late, 0, 0.0), SignalState::Yellow);
    }
}
