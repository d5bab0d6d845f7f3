//! Where a tissue update's wall-clock time goes, phase by phase.

use web_time::Instant;

/// Wall-clock time (s) of tissue updates, phase by phase, in the order an update runs
/// them (see [`crate::StepTimers::tissue_phases`]).
///
/// ```
/// use myoslice::tissue::TissuePhases;
/// let p = TissuePhases { guard_s: 0.002, shape_matching_s: 0.003, ..Default::default() };
/// assert!((p.total_s() - 0.005).abs() < 1e-12);
/// assert_eq!(p.named()[3], ("shape_matching", 0.003));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TissuePhases {
    /// Muscle shapes placed on their chains, with their keep-out from bone (when
    /// `Simulation::step` runs several updates in one call, beside the last update's
    /// guard).
    pub muscle_shapes_s: f64,
    /// The knee fold of the rest shape (the first guess's base and the guard's fallback).
    pub knee_fold_s: f64,
    /// Where the fat facing a muscle goes, and the first guess.
    pub first_guess_s: f64,
    /// The momentum carried into the guess, the restriction to the region that moves,
    /// and the shape-matching iterations with their muscle and contact constraints.
    pub shape_matching_s: f64,
    /// Fat sliding on bone, and the fat in front of the knee kept off bone; with the
    /// fat's own constraints (`TissueConfig::fat_constraints`), which move those into the
    /// iterations, the unfolding that ends the update.
    pub bone_sliding_s: f64,
    /// The validity guard (element volumes, body-surface crossings) and the momentum
    /// carried to the next update.
    pub guard_s: f64,
}

impl TissuePhases {
    /// All phases together (s).
    pub fn total_s(&self) -> f64 {
        self.named().iter().map(|(_, s)| s).sum()
    }

    /// The phases as (name, seconds), in update order.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("muscle_shapes", self.muscle_shapes_s),
            ("knee_fold", self.knee_fold_s),
            ("first_guess", self.first_guess_s),
            ("shape_matching", self.shape_matching_s),
            ("bone_sliding", self.bone_sliding_s),
            ("guard", self.guard_s),
        ]
    }

    /// Adds `other`'s times to these.
    pub(crate) fn add(&mut self, other: &Self) {
        self.muscle_shapes_s += other.muscle_shapes_s;
        self.knee_fold_s += other.knee_fold_s;
        self.first_guess_s += other.first_guess_s;
        self.shape_matching_s += other.shape_matching_s;
        self.bone_sliding_s += other.bone_sliding_s;
        self.guard_s += other.guard_s;
    }
}

/// Times consecutive phases: each [`Self::lap`] gives the time since the last.
pub(crate) struct Lap(Instant);

impl Lap {
    pub(crate) fn start() -> Self {
        Self(Instant::now())
    }

    /// Seconds since the start or the last lap.
    pub(crate) fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let s = (now - self.0).as_secs_f64();
        self.0 = now;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn added_phases_sum_to_the_added_totals() {
        let a = TissuePhases {
            muscle_shapes_s: 1.0,
            knee_fold_s: 2.0,
            first_guess_s: 3.0,
            shape_matching_s: 4.0,
            bone_sliding_s: 5.0,
            guard_s: 6.0,
        };
        let mut b = a;
        b.add(&a);
        assert_eq!(b.total_s(), 2.0 * a.total_s());
        assert_eq!(b.named()[5], ("guard", 12.0));
    }
}
