//! The simulation's own record vectors, indexed without bounds checks in release builds.

/// A vector of the simulation's own records (vehicles, lanes' vehicle lists, routes, plans, per-type and per-link
/// values) whose indexing skips the bounds check in release builds: the checks, with the code around them, were
/// 17 % of the hot loop's instructions. Only indices the simulation made itself reach it (vehicle ids from
/// `create_vehicle`, lane, link and route indices from the network and `add_route`, positions within the lists
/// they index); ids that come from callers (`vehicle`, `leader`, `set_acceleration`, ...) go through `get` first.
/// Debug builds, and so every test, check each index.
#[derive(Clone, Debug, Default)]
pub(super) struct Table<T>(pub(super) Vec<T>);

impl<T> std::ops::Deref for Table<T> {
    type Target = Vec<T>;
    fn deref(&self) -> &Vec<T> {
        &self.0
    }
}

impl<T> std::ops::DerefMut for Table<T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        &mut self.0
    }
}

impl<T> std::ops::Index<usize> for Table<T> {
    type Output = T;
    #[inline(always)]
    fn index(&self, i: usize) -> &T {
        debug_assert!(i < self.0.len(), "index {i} of {}", self.0.len());
        // SAFETY: indices are the simulation's own (see the type's documentation), checked in debug builds
        unsafe { self.0.get_unchecked(i) }
    }
}

impl<T> std::ops::IndexMut<usize> for Table<T> {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut T {
        debug_assert!(i < self.0.len(), "index {i} of {}", self.0.len());
        // SAFETY: as for `index`
        unsafe { self.0.get_unchecked_mut(i) }
    }
}

impl<T> FromIterator<T> for Table<T> {
    fn from_iter<I: IntoIterator<Item = T>>(it: I) -> Self {
        Table(it.into_iter().collect())
    }
}

impl<'a, T> IntoIterator for &'a Table<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl<'a, T> IntoIterator for &'a mut Table<T> {
    type Item = &'a mut T;
    type IntoIter = std::slice::IterMut<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter_mut()
    }
}

impl<T: PartialEq> PartialEq<Vec<T>> for Table<T> {
    fn eq(&self, other: &Vec<T>) -> bool {
        self.0 == *other
    }
}
