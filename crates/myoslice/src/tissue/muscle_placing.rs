//! The first phase of a tissue update: every muscle shape placed on its chain, kept out
//! of bone and on its side of the contact plane behind the knee. It reads the skeleton
//! and the muscles but no fat, and the rest of an update reads no chain, so
//! `Simulation::step` places the next update's shapes beside the last update's guard
//! (see [`super::Tissue::update_back_beside`]).

use web_time::Instant;

use crate::par::*;
use glam::Quat;

use super::bone_keep_out::{self, Bones};
use super::knee_fold::{Contact, KneeFold};
use super::skin_cover::SkinCover;
use super::{LAYER_GAP, MuscleShape, TissueConfig, TissueStatic};
use crate::body::{BodyId, KneeAxis};
use crate::muscle::{BodyFrames, MuscleUnit};

/// What placing the muscle shapes needs of a tissue, apart from its fat.
pub(crate) struct Placing<'a> {
    pub(super) shapes: &'a mut [MuscleShape],
    pub(super) fixed: &'a TissueStatic,
    pub(super) knee: KneeAxis,
    pub(super) config: &'a TissueConfig,
    pub(super) layers: usize,
    /// What the last [`Self::place`] left: its time (s) and whether every vertex was
    /// finite. None before one.
    pub(super) placed: Option<(f64, bool)>,
}

impl Placing<'_> {
    /// Places every shape for the skeleton at `knee_angle` and `frames` and the chains of
    /// `muscles` (muscle order), and records the time and whether all came out finite.
    pub(crate) fn place(&mut self, knee_angle: f64, frames: &BodyFrames, muscles: &[MuscleUnit]) {
        let start = Instant::now();
        let fold = KneeFold::new(&self.knee, knee_angle as f32);
        let contact = muscle_contact(&fold, self.config, self.layers, frames.thigh);
        // Muscles are not squashed onto the contact plane (their volume is the invariant
        // kept; the fat over them is): bones push them aside ring by ring, and the plane
        // pushes whole rings back to their side of it, a little each round.
        let cover = SkinCover::new(
            &self.fixed.posterior_skin_rest,
            &fold,
            &contact,
            frames.thigh,
            LAYER_GAP * (self.layers as f32 + 1.0),
        );
        let bones = Bones {
            sdfs: &self.fixed.bone_sdfs,
            surfaces: &self.fixed.bones,
            frames,
            fade: bone_keep_out::fade_per_update(self.config.rate_hz),
            contact: Some(contact),
            cover: Some(&cover),
        };
        self.shapes
            .par_iter_mut()
            .zip(muscles)
            .for_each(|(shape, m)| {
                // A muscle resting on one body keeps its rest shape and moves with it
                // (placed from its chain, such muscles came out more, 9 850 → 10 233);
                // one the contact plane watches is still shifted ring by ring back to
                // its side of it and out of bone, as a placed one is (the phantom's
                // peroneus longus: 158 → 25 vertices out through the skin at 134°).
                // One it does not watch is carried alone, even where it could meet the
                // other body's bones (none has been seen to).
                let quiet = !m.crosses_knee && m.activation < 1e-4 && m.excitation == 0.0;
                match m.chain.single_body() {
                    Some(b) if quiet => {
                        let (q, t) = match b {
                            BodyId::Thigh => frames.thigh,
                            BodyId::Shank => frames.shank,
                        };
                        if shape.near_plane() {
                            shape.carry_clear_of(q, t, &bones, b);
                        } else {
                            shape.carry(q, t);
                        }
                        shape.carried = Some(b);
                    }
                    _ => shape.update_clear_of(&m.chain, &fold, &bones),
                }
            });
        if self.config.muscle_contact {
            super::muscle_contact::separate(self.shapes);
        }
        let finite = self
            .shapes
            .iter()
            .all(|m| m.current.iter().all(|p| p.is_finite()));
        self.placed = Some((start.elapsed().as_secs_f64(), finite));
    }
}

/// The contact plane behind the knee of `fold` (world; the thigh at pose `thigh`), with
/// the margin muscles keep from it: further than the fat over them.
pub(super) fn muscle_contact(
    fold: &KneeFold,
    config: &TissueConfig,
    layers: usize,
    (tq, tt): (Quat, glam::Vec3),
) -> Contact {
    let gap = config.contact_gap_m as f32;
    let contact = fold.contact(gap + LAYER_GAP * (layers as f32 + 1.0));
    Contact {
        point: tq * contact.point + tt,
        normal: tq * contact.normal,
        behind: tq * contact.behind,
        ..contact
    }
}
