//! The vehicle records of a run, indexed by vehicle id, that forget the vehicles which left long ago: a run's
//! memory then follows the vehicles on the road (and those waiting to enter), not the horizon.
//!
//! Ids stay the creation numbers. Records are dropped only as a prefix: once the oldest
//! [`FORGET_AT_LEAST`] or more vehicles have all arrived before the last step, and they are at least half the
//! table. The paper's runs never reach that (they create at most about 620 vehicles), so nothing there changes;
//! after it, `get` answers `None` for a forgotten vehicle.

pub use crate::ids::VehicleId;

/// Fewest leading arrived vehicles worth dropping (a drop moves the rest of the table).
const FORGET_AT_LEAST: usize = 1024;

#[derive(Debug)]
pub(crate) struct VehicleTable<T> {
    /// Id of `items[0]`.
    base: usize,
    items: Vec<T>,
    /// `items[..forgettable]` may be dropped.
    forgettable: usize,
    /// `items`' start moved back by `base` records (wrapping): vehicle `id`'s record is `origin + id`. The step
    /// indexes the table some fifty times per vehicle, and the subtraction with its load of `base`, after every
    /// store to a record, was about 2 % of its instructions. Set again whenever `items` moves or `base` changes.
    origin: *mut T,
}

// SAFETY: `origin` only points into `items`, which the table owns: it is sent and shared as `items` is
unsafe impl<T: Send> Send for VehicleTable<T> {}
unsafe impl<T: Sync> Sync for VehicleTable<T> {}

impl<T> Default for VehicleTable<T> {
    fn default() -> Self {
        let mut t = VehicleTable {
            base: 0,
            items: Vec::new(),
            forgettable: 0,
            origin: std::ptr::null_mut(),
        };
        t.set_origin();
        t
    }
}

impl<T: Clone> Clone for VehicleTable<T> {
    fn clone(&self) -> Self {
        let mut t = VehicleTable {
            base: self.base,
            items: self.items.clone(),
            forgettable: self.forgettable,
            origin: std::ptr::null_mut(),
        };
        t.set_origin();
        t
    }
}

impl<T> VehicleTable<T> {
    /// Vehicles ever created (the next id).
    pub(crate) fn len(&self) -> usize {
        self.base + self.items.len()
    }

    /// Records held now.
    pub(crate) fn held(&self) -> usize {
        self.items.len()
    }

    pub(crate) fn push(&mut self, x: T) {
        self.items.push(x);
        self.set_origin();
    }

    fn set_origin(&mut self) {
        self.origin = self.items.as_mut_ptr().wrapping_sub(self.base);
    }

    /// The record of `id`, `None` for an id not created yet or forgotten.
    pub(crate) fn get(&self, id: usize) -> Option<&T> {
        id.checked_sub(self.base).and_then(|i| self.items.get(i))
    }

    pub(crate) fn get_mut(&mut self, id: usize) -> Option<&mut T> {
        id.checked_sub(self.base)
            .and_then(|i| self.items.get_mut(i))
    }

    /// Extends the forgettable prefix over the records `done` says are finished with, and drops the prefix once
    /// it is long enough (amortised: each record is looked at once and moved at most once per halving).
    pub(crate) fn forget_finished(&mut self, done: impl Fn(&T) -> bool) {
        while self.forgettable < self.items.len() && done(&self.items[self.forgettable]) {
            self.forgettable += 1;
        }
        if self.forgettable >= FORGET_AT_LEAST && 2 * self.forgettable >= self.items.len() {
            self.items.drain(..self.forgettable);
            self.base += self.forgettable;
            self.forgettable = 0;
            self.set_origin();
        }
    }
}

impl<T> std::ops::Index<usize> for VehicleTable<T> {
    type Output = T;
    #[inline(always)]
    fn index(&self, id: usize) -> &T {
        debug_assert!(
            id >= self.base && id - self.base < self.items.len(),
            "vehicle {id} of {}..{}",
            self.base,
            self.len()
        );
        // SAFETY: only the simulation's own ids of vehicles still in the network or waiting reach this (see
        // `Table`); those are never forgotten, so `origin + id` lies in `items`. Checked in debug builds.
        unsafe { &*self.origin.wrapping_add(id) }
    }
}

impl<T> std::ops::IndexMut<usize> for VehicleTable<T> {
    #[inline(always)]
    fn index_mut(&mut self, id: usize) -> &mut T {
        debug_assert!(
            id >= self.base && id - self.base < self.items.len(),
            "vehicle {id} of {}..{}",
            self.base,
            self.len()
        );
        // SAFETY: as for `index`
        unsafe { &mut *self.origin.wrapping_add(id) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_long_finished_prefix_is_forgotten() {
        let mut t = VehicleTable::default();
        for i in 0..3 * FORGET_AT_LEAST {
            t.push(i);
        }
        // vehicle 10 still running: nothing before it may go, and 10 records are too few to move
        t.forget_finished(|&x| x != 10);
        assert_eq!((t.held(), t.get(0)), (3 * FORGET_AT_LEAST, Some(&0)));
        // all but the last third finished: the first two thirds go, ids stay
        let mut t2 = VehicleTable::default();
        for i in 0..3 * FORGET_AT_LEAST {
            t2.push(i);
        }
        t2.forget_finished(|&x| x < 2 * FORGET_AT_LEAST);
        assert_eq!(t2.held(), FORGET_AT_LEAST);
        assert_eq!(t2.len(), 3 * FORGET_AT_LEAST);
        assert_eq!(t2.get(0), None);
        assert_eq!(t2[2 * FORGET_AT_LEAST], 2 * FORGET_AT_LEAST);
        assert_eq!(
            t2.get(3 * FORGET_AT_LEAST - 1),
            Some(&(3 * FORGET_AT_LEAST - 1))
        );
        // a copy indexes its own records, after the original grew (and moved) and went
        let copy = t2.clone();
        for i in 0..10 * FORGET_AT_LEAST {
            t2.push(i);
        }
        t2[2 * FORGET_AT_LEAST] = 7;
        drop(t2);
        assert_eq!(copy[2 * FORGET_AT_LEAST], 2 * FORGET_AT_LEAST);
        assert_eq!(copy[3 * FORGET_AT_LEAST - 1], 3 * FORGET_AT_LEAST - 1);
    }
}
