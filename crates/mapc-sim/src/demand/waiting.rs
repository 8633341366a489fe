//! Vehicles waiting to enter at one entry lane, in departure order.
//!
//! SUMO builds a flow's vehicle when it is due (its speed factor drawn then) and keeps it in the insertion queue
//! until there is room; the first [`BUILT_WAITING_CAP`] waiting vehicles of a lane are kept that way, so every run
//! whose queues stay shorter draws the same numbers in the same order: every recorded result does (the paper's
//! scenarios cannot even reach it: all their main-road demand over the 1000 s horizon is 556 vehicles; 100 human
//! seeds of the Simple Merge queue at most 144, of the I-696 window 3). Beyond that the
//! queue only counts vehicles per flow and builds each one when it is first tried (at the front, or, with lanes
//! chosen at insertion, behind vehicles refused on their lanes in that step), so a demand the road cannot take
//! costs a counter, not a vehicle record per departure.

use crate::demand::vehicle_table::VehicleId;
use std::collections::VecDeque;

/// Waiting vehicles per entry lane that are built when due; later ones are counted.
pub(crate) const BUILT_WAITING_CAP: usize = 1024;

#[derive(Clone, Debug, Default)]
pub(crate) struct EntryQueue {
    /// Built vehicles, front first.
    built: VecDeque<VehicleId>,
    /// Then runs of (flow index, how many) not built yet, in departure order.
    counted: VecDeque<(usize, u64)>,
}

impl EntryQueue {
    /// Vehicles waiting (built and counted).
    pub(crate) fn len(&self) -> u64 {
        self.built.len() as u64 + self.counted.iter().map(|&(_, n)| n).sum::<u64>()
    }

    /// No vehicle waits.
    pub(crate) fn is_empty(&self) -> bool {
        self.built.is_empty() && self.counted.is_empty()
    }

    /// Whether the next due vehicle is built now (the queue's built part has room and nothing is counted).
    pub(crate) fn builds_next(&self) -> bool {
        self.counted.is_empty() && self.built.len() < BUILT_WAITING_CAP
    }

    pub(crate) fn push_built(&mut self, id: VehicleId) {
        debug_assert!(self.counted.is_empty());
        self.built.push_back(id);
    }

    /// One more due vehicle of `flow`, counted.
    pub(crate) fn push_counted(&mut self, flow: usize) {
        match self.counted.back_mut() {
            Some((f, n)) if *f == flow => *n += 1,
            _ => self.counted.push_back((flow, 1)),
        }
    }

    /// The built vehicle at the front.
    pub(crate) fn front_built(&self) -> Option<VehicleId> {
        self.built.front().copied()
    }

    pub(crate) fn pop_built(&mut self) {
        self.built.pop_front();
    }

    /// The `i`-th built vehicle from the front.
    pub(crate) fn built_at(&self, i: usize) -> Option<VehicleId> {
        self.built.get(i).copied()
    }

    /// Takes out the `i`-th built vehicle (it entered ahead of those before it, on another lane).
    pub(crate) fn remove_built(&mut self, i: usize) {
        self.built.remove(i);
    }

    /// The vehicle built for what [`EntryQueue::take_counted`] gave: now the last built one, ahead of every
    /// counted one.
    pub(crate) fn push_taken(&mut self, id: VehicleId) {
        self.built.push_back(id);
    }

    /// Takes the front counted vehicle's flow (to be built now): when no built vehicle is waiting, or (lanes
    /// chosen at insertion) when every built one was refused in this step and the next may try another lane.
    pub(crate) fn take_counted(&mut self) -> Option<usize> {
        debug_assert!(self.built.len() < BUILT_WAITING_CAP);
        let (flow, n) = self.counted.front_mut()?;
        let flow = *flow;
        *n -= 1;
        if *n == 0 {
            self.counted.pop_front();
        }
        Some(flow)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counted_vehicles_keep_their_order_and_merge_runs() {
        let mut q = EntryQueue::default();
        for id in 0..BUILT_WAITING_CAP as u32 {
            assert!(q.builds_next());
            q.push_built(id);
        }
        assert!(!q.builds_next());
        q.push_counted(0);
        q.push_counted(0);
        q.push_counted(1);
        q.push_counted(0);
        assert_eq!(q.len(), BUILT_WAITING_CAP as u64 + 4);
        assert_eq!(q.counted.len(), 3);
        while q.front_built().is_some() {
            q.pop_built();
        }
        let order: Vec<usize> = std::iter::from_fn(|| q.take_counted()).collect();
        assert_eq!(order, vec![0, 0, 1, 0]);
        assert_eq!(q.len(), 0);
        assert!(q.builds_next());
    }
}
