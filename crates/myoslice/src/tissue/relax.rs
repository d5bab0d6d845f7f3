//! The fat's relaxation: shape-matching iterations with the constraints acting in them.
//!
//! With the fat's own constraints on ([`super::TissueConfig::fat_constraints`]), each
//! iteration runs, one after the other on the same positions: shape matching, the pull
//! of the inner fat toward its muscles and the contact behind the knee; in the last
//! iteration the sliding on bone; and in the last three the skin's keep-out from bone and
//! the fat's volume and corners ([`super::fat_volume`]). The update ends with the
//! unfolding swept until it gains nothing more, then the untangling of what it left
//! (vertex by vertex); then the skin's keep-out from bone and the stacking of its pleats
//! ([`super::skin_pleat`]), each followed by the untangling of what it folded with the
//! vertices it moved held, and a last untangling of what those left, the pleats still
//! held, so the last word is the fat's validity.
//! Without them, as before: shape matching with the pull and the contact, then the bone
//! passes and the contact once each after the iterations
//! (they folded hundreds of fat elements at deep flexion, docs/tissue-history.md).

use std::sync::Arc;

use glam::Vec3;

use super::fat_volume::VolumeBuffers;
use super::guard::Guard;
use super::phases::Lap;
use super::{Contact, FatSolver, Tissue, TissuePhases, fat_on_muscle};
use crate::body::BodyId;
use crate::muscle::BodyFrames;

/// No corner Jacobian of a fat element may fall below this share of its rest value.
/// A margin above ParaView's zero, so that the next update's first guess starts from
/// elements that are not on the edge of folding.
const CORNER_FLOOR: f32 = 0.2;

/// The last iterations of an update in which the fat's own constraints and the skin's
/// keep-out from bone act (in all six, the update took twice as long for the same
/// audit). The sliding on bone runs in the last one only: run in each of the three, it
/// let more bone out through the skin at deep flexion (docs/tissue-history.md).
const HELD_ITERATIONS: usize = 3;

/// Most sweeps of the unfolding that ends an update (it stops earlier once no element
/// is folded, or once four sweeps have unfolded none).
const FINAL_UNFOLD_SWEEPS: usize = 60;

/// What the fat is held to during an update, besides its own shape.
pub(super) struct Constraints<'a> {
    /// The contact behind the knee, its gap (m), and how far it has opened (0 to 1).
    pub contact: &'a Contact,
    pub gap: f32,
    pub opened: f32,
    /// Where inner vertices facing a muscle are pulled (see [`fat_on_muscle::targets`]).
    pub targets: &'a [(u32, Vec3, Vec3)],
    /// The skin's limits behind the knee (see [`super::crease::skin_limits`]).
    pub limits: &'a [(f32, f32)],
    /// Where the bones are.
    pub frames: &'a BodyFrames,
}

impl Tissue {
    /// Relaxes the fat from its first guess under `c`; times the iterations and what
    /// follows them into `phases`.
    pub(super) fn relax(
        &mut self,
        c: &Constraints<'_>,
        buffers: &mut VolumeBuffers,
        (phases, lap): (&mut TissuePhases, &mut Lap),
    ) {
        let fixed = Arc::clone(&self.fixed);
        let frames = c.frames;
        let pose = |b: BodyId| match b {
            BodyId::Thigh => frames.thigh,
            BodyId::Shank => frames.shank,
        };
        let k = self.config.stiffness as f32;
        let hold = self.config.fat_constraints;
        let slide = |fat: &mut FatSolver| {
            fixed
                .bone_slide
                .apply(&mut fat.x, &fat.free, &fixed.bone_sdfs, &fixed.bones, pose);
        };
        // The skin in front of the knee lifts over bone the fold brings under it (the
        // vertices it moved).
        let keep_out = |fat: &mut FatSolver| {
            fixed
                .fat_keep_out
                .apply(&mut fat.x, &fat.free, &fixed.bone_sdfs, &fixed.bones, pose)
        };
        for it in 0..self.config.iterations {
            self.fat.iterate(k);
            fat_on_muscle::pull(&mut self.fat.x, c.targets);
            self.apply_contact(c.contact, c.gap, c.limits, c.opened);
            if hold && it + 1 == self.config.iterations {
                slide(&mut self.fat);
            }
            if hold && it + HELD_ITERATIONS >= self.config.iterations {
                keep_out(&mut self.fat);
                fixed
                    .fat_volume
                    .hold(&mut self.fat, buffers, 1.0, CORNER_FLOOR);
            }
        }
        phases.shape_matching_s += lap.lap();
        if hold {
            let volume = &fixed.fat_volume;
            // What the element-by-element unfolding leaves (elements pulling against
            // their neighbours in the squeezed inner layer) each vertex untangles heeding
            // all its elements at once.
            if volume.unfold(&mut self.fat, buffers, CORNER_FLOOR, FINAL_UNFOLD_SWEEPS) > 0 {
                volume.untangle(&mut self.fat, buffers, FINAL_UNFOLD_SWEEPS);
            }
            // The skin's keep-out has the last word in front of the knee: the unfolding
            // drew it back down onto the patella by a millimetre or two. What that folds
            // is untangled with the vertices it moved held where it put them.
            let moved = keep_out(&mut self.fat);
            volume.untangle_holding(&mut self.fat, buffers, (&moved, &[]), FINAL_UNFOLD_SWEEPS);
            let mut left = buffers.take_folded();
            // Then the skin's pleats are stacked, and what that folds untangled likewise.
            let moved = self.stack_pleats(c.contact);
            volume.untangle_holding(&mut self.fat, buffers, (&moved, &[]), FINAL_UNFOLD_SWEEPS);
            // What either left folded is untangled once more, from a fresh start (the
            // sweeps stop after four that unfold nothing), the pleats still held and the
            // keep-out's vertices free again: moved by a fraction of a millimetre, they
            // let no more bone out, and half the folds left go.
            left.extend(buffers.take_folded());
            volume.untangle_holding(&mut self.fat, buffers, (&moved, &left), FINAL_UNFOLD_SWEEPS);
        } else {
            slide(&mut self.fat);
            keep_out(&mut self.fat);
            self.apply_contact(c.contact, c.gap, c.limits, c.opened);
        }
        phases.bone_sliding_s = lap.lap();
    }

    /// After the guard fell back toward the knee fold (which has elements folded behind a
    /// deeply bent knee), unfolds what that folded, holding the vertices the guard moved
    /// where it put them. The caller runs the guard again on the result.
    pub(super) fn unfold_after_guard(&mut self, guard: &Guard, buffers: &mut VolumeBuffers) {
        let free = self.fat.free.clone();
        for (v, f) in self.fat.free.iter_mut().enumerate() {
            *f = *f && !guard.moved(v);
        }
        // Not untangled here: even with the skin by the bones held where the guard left
        // it, untangling there let bone out through the skin at deep flexion
        // (docs/tissue-history.md).
        self.fixed
            .fat_volume
            .unfold(&mut self.fat, buffers, CORNER_FLOOR, FINAL_UNFOLD_SWEEPS);
        self.fat.free = free;
    }
}
