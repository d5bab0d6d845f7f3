//! How often the validity guard stepped in over a run.

use serde::Serialize;

/// The validity guard's interventions since the tissue was built: the last resort that
/// moves fat back toward the knee fold where the relaxed shape would break. A run the
/// solver handles on its own keeps both at zero. Part of the tissue's state: a
/// checkpoint carries the tally it was taken with.
///
/// ```
/// use myoslice::tissue::GuardTally;
/// let mut t = GuardTally::default();
/// t.add(0);
/// t.add(12);
/// assert_eq!((t.updates, t.vertices), (1, 12));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct GuardTally {
    /// Tissue updates in which the guard moved at least one fat vertex.
    pub updates: u64,
    /// Fat vertices it moved, summed over the updates.
    pub vertices: u64,
}

impl GuardTally {
    /// Counts one update in which the guard moved `vertices` fat vertices.
    pub fn add(&mut self, vertices: usize) {
        if vertices > 0 {
            self.updates += 1;
            self.vertices += vertices as u64;
        }
    }
}
