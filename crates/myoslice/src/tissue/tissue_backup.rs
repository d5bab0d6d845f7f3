//! A copy of a tissue, taken before an update and put back if it fails.

use super::Tissue;

/// A copy of a tissue, to put back after a failed update or `step` call. What a tissue
/// is built on and never changes (its lattice, rest shapes, elements and their layout,
/// bone fields, the muscles' watched pairs) sits behind shared pointers, so the copy
/// allocates only what updates change, and none of the update's work buffers.
#[derive(Debug)]
pub(crate) struct TissueBackup(Box<Tissue>);

impl Tissue {
    /// A copy of everything an update changes and the next one reads.
    pub(crate) fn backup(&self) -> TissueBackup {
        TissueBackup(Box::new(self.clone()))
    }

    /// Puts back what [`Self::backup`] took, but for the clock (`step` advances it and
    /// puts it back itself) and the phase timings (they describe the update that ran).
    /// The work buffers in use stay, and shapes placed ahead for an update that will not
    /// come now are dropped.
    pub(crate) fn restore(&mut self, b: TissueBackup) {
        let (pending, phases) = (self.pending, self.last_phases);
        let scratch = std::mem::take(&mut self.scratch);
        *self = *b.0;
        (self.pending, self.last_phases, self.scratch) = (pending, phases, scratch);
        self.placed = None;
    }
}
