//! A tissue's changing state, taken before an update and put back if it fails.

use super::Tissue;

/// A copy of a tissue, to put back after a failed update or `step` call. The model a
/// tissue is built on (its lattice, rest shapes, bone fields, element layout) sits
/// behind shared pointers, so the copy holds only what changes.
#[derive(Debug)]
pub(crate) struct TissueBackup(Box<Tissue>);

impl Tissue {
    /// Everything an update changes and the next one reads. The clock and the phase
    /// timings are left out: `step` advances the clock and puts it back itself, and the
    /// timings describe the update that ran.
    pub(crate) fn backup(&self) -> TissueBackup {
        TissueBackup(Box::new(self.clone()))
    }

    /// Puts back what [`Self::backup`] took.
    pub(crate) fn restore(&mut self, b: TissueBackup) {
        let (pending, phases) = (self.pending, self.last_phases);
        *self = *b.0;
        (self.pending, self.last_phases) = (pending, phases);
        // Shapes placed ahead for an update that will not come now.
        self.placed = None;
    }
}
