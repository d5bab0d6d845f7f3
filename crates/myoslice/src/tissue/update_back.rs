//! The back half of a tissue update: the validity guard and the momentum carried to the
//! next update. It reads no muscle shape, skeleton or muscle, so `Simulation::step` runs
//! the muscles' steps and the next update's muscle shapes beside it.

use std::sync::Arc;

use super::phases::Lap;
use super::{Front, LazyMetrics, Placing, Tissue};

impl Tissue {
    /// Finishes an update [`Self::update_front`] began. Returns false if anything became
    /// non-finite (the caller puts back a [`super::TissueBackup`]).
    pub(crate) fn update_back(&mut self, front: Front) -> bool {
        let shapes_finite = front.shapes_finite;
        self.deform_back(front);
        shapes_finite
            && self.fat.x.iter().all(|p| p.is_finite())
            && self.drift.iter().all(|p| p.is_finite())
    }

    /// [`Self::update_back`] and, beside it on another thread, `beside`, which may place
    /// the muscle shapes for the next update ([`Placing::place`]) once it has moved the
    /// skeleton and the muscles on: the back half reads no muscle shape, and placing
    /// them reads no fat, so the results are those of running one after the other.
    /// Returns what [`Self::update_back`] did and how long it took, and what `beside`
    /// returned.
    pub(crate) fn update_back_beside<R: Send>(
        &mut self,
        front: Front,
        beside: impl FnOnce(&mut Placing<'_>) -> R + Send,
    ) -> ((bool, std::time::Duration), R) {
        let mut shapes = std::mem::take(&mut self.muscles);
        let fixed = Arc::clone(&self.fixed);
        let config = self.config.clone();
        let (knee, layers) = (self.knee, self.layers);
        let joined = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut placing = Placing {
                shapes: &mut shapes,
                fixed: &fixed,
                knee,
                config: &config,
                layers,
                placed: None,
            };
            let (back, r) = crate::par::join(
                || {
                    let start = web_time::Instant::now();
                    (self.update_back(front), start.elapsed())
                },
                || beside(&mut placing),
            );
            (back, r, placing.placed)
        }));
        // The shapes go back in place whatever happened (before a panic goes on).
        self.muscles = shapes;
        match joined {
            Ok((back, r, placed)) => {
                self.placed = placed;
                (back, r)
            }
            Err(panic) => std::panic::resume_unwind(panic),
        }
    }

    /// The validity guard and the momentum carried to the next update (see
    /// [`Self::update_back`]).
    fn deform_back(&mut self, front: Front) {
        // Timed from here: the back half may start a little after the front ended.
        let mut lap = Lap::start();
        let Front { mut phases, .. } = front;
        let fixed = Arc::clone(&self.fixed);
        let mut sc = std::mem::take(&mut self.scratch);
        let (safe, guess) = (&sc.safe, &sc.guess);
        let (eps, surface) = (
            self.config.min_volume_ratio as f32,
            self.config.surface_guard,
        );
        let mut guarded = sc
            .guard
            .run(&mut self.fat, safe, &fixed.guard_triangles, eps, surface);
        if guarded > 0 && self.config.fat_constraints {
            self.unfold_after_guard(&sc.guard, &mut sc.volume);
            guarded += sc
                .guard
                .run(&mut self.fat, safe, &fixed.guard_triangles, eps, surface);
        }
        for i in 0..self.drift.len() {
            self.drift[i] = self.fat.x[i] - guess[i];
        }
        self.scratch = sc;
        self.metrics = LazyMetrics::updated(guarded);
        self.guard_tally.add(guarded);
        self.updates += 1;
        phases.guard_s = lap.lap();
        self.last_phases = phases;
    }
}
