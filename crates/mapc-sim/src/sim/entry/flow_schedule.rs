//! Which flows a step visits for departures: each flow by period waits in a queue by its next departure time and
//! is visited only once that time is due; flows drawn by probability are visited every step. A SUMO user's file of
//! thousands of `<vehicle>`s is thousands of one-vehicle flows: visiting them all every step cost more than the
//! simulation itself (sumo-rl's 3x3 grid: 7 000 flows, a quarter of the run).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A departure time ordered by `total_cmp` (times of flows by period are finite).
#[derive(Clone, Copy, Debug, PartialEq)]
struct At(f64);

impl Eq for At {}

impl PartialOrd for At {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for At {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct FlowSchedule {
    /// Flows by period with a departure left, by that departure's time (then index).
    by_time: BinaryHeap<Reverse<(At, usize)>>,
    /// Flows by probability with vehicles left to draw, by index.
    by_probability: Vec<usize>,
    /// The flows of this step's visit, by index (kept to reuse its allocation).
    visit: Vec<usize>,
    started: bool,
}

impl FlowSchedule {
    /// Starts the schedule: per flow in index order, whether it draws by probability, else its first departure
    /// time by period if it has one left.
    pub(in crate::sim) fn start(&mut self, flows: impl Iterator<Item = (bool, Option<f64>)>) {
        self.started = true;
        for (f, (by_probability, first_due)) in flows.enumerate() {
            if by_probability {
                self.by_probability.push(f);
            } else if let Some(t) = first_due {
                self.by_time.push(Reverse((At(t), f)));
            }
        }
    }

    pub(in crate::sim) fn started(&self) -> bool {
        self.started
    }

    /// The flows to visit at `now` (those by period due by then, every one by probability), by index: the order in
    /// which the departures of one step join their queues. Flows by period leave the schedule until [`Self::wait`]
    /// puts them back.
    pub(in crate::sim) fn take_visit(&mut self, now: f64) -> Vec<usize> {
        let mut visit = std::mem::take(&mut self.visit);
        visit.clear();
        while let Some(&Reverse((At(t), f))) = self.by_time.peek() {
            if !(t <= now + 1e-9) {
                break;
            }
            self.by_time.pop();
            visit.push(f);
        }
        visit.extend_from_slice(&self.by_probability);
        visit.sort_unstable();
        visit
    }

    /// Flow `f` by period waits for its next departure at `t`.
    pub(in crate::sim) fn wait(&mut self, f: usize, t: f64) {
        self.by_time.push(Reverse((At(t), f)));
    }

    /// Flow `f` by probability has drawn its last vehicle.
    pub(in crate::sim) fn drop_probability(&mut self, f: usize) {
        self.by_probability.retain(|&g| g != f);
    }

    /// Hands the visit's allocation back.
    pub(in crate::sim) fn give_back(&mut self, visit: Vec<usize>) {
        self.visit = visit;
    }

    /// The earliest next departure of any flow by period; NaN while a flow draws by probability (every step is
    /// visited then); infinity when no departure is left.
    pub(in crate::sim) fn quiet_until(&self) -> f64 {
        if !self.by_probability.is_empty() {
            return f64::NAN;
        }
        self.by_time
            .peek()
            .map_or(f64::INFINITY, |&Reverse((At(t), _))| t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_visits_the_due_flows_and_every_probability_flow_in_index_order() {
        let mut s = FlowSchedule::default();
        // flows 0 and 3 by period (due at 4 s and 2 s), 1 by probability, 2 by period with nothing left
        s.start(
            [
                (false, Some(4.0)),
                (true, None),
                (false, None),
                (false, Some(2.0)),
            ]
            .into_iter(),
        );
        assert!(
            s.quiet_until().is_nan(),
            "a probability flow is visited every step"
        );
        let v = s.take_visit(1.0);
        assert_eq!(v, [1]);
        s.give_back(v);
        let v = s.take_visit(4.0 - 1e-10);
        assert_eq!(v, [0, 1, 3], "by index, whatever their times");
        s.give_back(v);
        s.wait(3, 6.0);
        s.drop_probability(1);
        assert_eq!(s.quiet_until(), 6.0);
        assert_eq!(s.take_visit(5.0), Vec::<usize>::new());
        s.wait(0, 8.0);
        assert_eq!(s.quiet_until(), 6.0);
    }
}
