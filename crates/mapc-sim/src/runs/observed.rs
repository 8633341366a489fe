//! What the regime report ([`super::regime`]) observes of one run, apart from it so that the runs kept for a
//! job's later steps ([`super::kept`]) can hold it without importing the report.

/// Per approach, sums over measured steps.
#[derive(Clone, Default)]
pub(crate) struct Acc {
    pub(crate) speed_sum: f64,
    pub(crate) speed_n: u64,
    pub(crate) queue_sum: f64,
    pub(crate) queue_max: f64,
    pub(crate) steps: u64,
}

/// What the regime report observed of one run: per measure point and approach, the sums; the vehicles still
/// waiting to enter at the end.
#[derive(Clone)]
pub(crate) struct Observation {
    pub(crate) acc: Vec<Vec<Acc>>,
    pub(crate) waiting: usize,
}
