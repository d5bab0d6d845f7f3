//! A tissue's changing state, taken before an update and put back if it fails.

use glam::{Quat, Vec3};

use super::bone_keep_out::KeepOutMemory;
use super::metrics::LazyMetrics;
use super::{GuardTally, Tissue};

/// A tissue's changing state, to put back after a failed update or `step` call.
#[derive(Debug)]
pub(crate) struct TissueBackup {
    fat_x: Vec<Vec3>,
    fat_rot: Vec<Quat>,
    fat_free: Vec<bool>,
    fat_active: Vec<bool>,
    drift: Vec<Vec3>,
    theta: f32,
    metrics: LazyMetrics,
    guard_tally: GuardTally,
    updates: u64,
    /// Each muscle's vertices, volume and keep-out memory.
    muscles: Vec<(Vec<Vec3>, f64, KeepOutMemory)>,
}

impl Tissue {
    /// Everything an update changes and the next one reads. Not the clock: `step`
    /// advances it and puts it back itself.
    pub(crate) fn backup(&self) -> TissueBackup {
        TissueBackup {
            fat_x: self.fat.x.clone(),
            fat_rot: self.fat.rot.clone(),
            fat_free: self.fat.free.clone(),
            fat_active: self.fat.active.clone(),
            drift: self.drift.clone(),
            theta: self.theta,
            metrics: self.metrics.clone(),
            guard_tally: self.guard_tally,
            updates: self.updates,
            muscles: self
                .muscles
                .iter()
                .map(|m| (m.current.clone(), m.volume_now, m.keep.memory()))
                .collect(),
        }
    }

    /// Puts back what [`Self::backup`] took.
    pub(crate) fn restore(&mut self, b: TissueBackup) {
        (self.fat.x, self.fat.rot) = (b.fat_x, b.fat_rot);
        (self.fat.free, self.fat.active) = (b.fat_free, b.fat_active);
        (self.drift, self.theta, self.metrics) = (b.drift, b.theta, b.metrics);
        (self.guard_tally, self.updates) = (b.guard_tally, b.updates);
        // Shapes placed ahead for an update that will not come now.
        self.placed = None;
        for (shape, (c, v, keep)) in self.muscles.iter_mut().zip(b.muscles) {
            (shape.current, shape.volume_now) = (c, v);
            shape.keep.recall(keep);
        }
    }
}
