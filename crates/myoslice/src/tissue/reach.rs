//! How far muscles and bones reach where they should not: muscles into bone and into one
//! another, muscles and bones out through the skin. Exact, for checks and tests, not for every update.

use crate::par::*;
use glam::Vec3;

use super::bone_keep_out::Bones;
use super::muscle_overlap::{MuscleOverlap, muscle_overlaps};
use super::{BoneOverlap, SkinBreach, Tissue, bone_overlap};
use crate::muscle::BodyFrames;

impl Tissue {
    /// How far each muscle's surface reaches into bone with the bodies at `frames`, in
    /// muscle order (a distance-field query per muscle vertex near a bone, and the
    /// winding number of what it calls inside by more than 1 mm: for checks, not for
    /// every update).
    pub fn muscles_in_bone(&self, frames: &BodyFrames) -> Vec<BoneOverlap> {
        let bones = Bones {
            sdfs: &self.fixed.bone_sdfs,
            surfaces: &self.fixed.bones,
            frames,
            fade: 1.0,
            contact: None,
            cover: None,
        };
        self.muscles
            .par_iter()
            .map(|m| bone_overlap::overlap(&m.current, &bones))
            .collect()
    }

    /// How far each muscle's surface reaches out through the skin now, in muscle order
    /// (exact: the skin closed at both ends of the lattice, a tree query per muscle
    /// vertex; for checks, not for every update). None when the skin is degenerate.
    pub fn muscles_outside_skin(&self) -> Option<Vec<SkinBreach>> {
        self.fixed.skin.breaches(&self.fat.x, &self.muscle_points())
    }

    /// How far each bone's surface reaches out through the skin with the bodies at
    /// `frames`, in the lattice's bone order (exact, as
    /// [`Tissue::muscles_outside_skin`]; for checks, not for every update). None when the
    /// skin is degenerate.
    pub fn bones_outside_skin(&self, frames: &BodyFrames) -> Option<Vec<SkinBreach>> {
        let bones = self.bone_points(frames);
        let bones: Vec<&[Vec3]> = bones.iter().map(Vec::as_slice).collect();
        self.fixed.skin.breaches(&self.fat.x, &bones)
    }

    /// Each muscle's vertices now, in muscle order.
    pub(super) fn muscle_points(&self) -> Vec<&[Vec3]> {
        self.muscles.iter().map(|m| m.current.as_slice()).collect()
    }

    /// Each bone's vertices with the bodies at `frames`, in the lattice's bone order.
    pub(super) fn bone_points(&self, frames: &BodyFrames) -> Vec<Vec<Vec3>> {
        self.fixed
            .bones
            .iter()
            .map(|(body, m)| {
                m.vertices()
                    .iter()
                    .map(|&p| frames.point(*body, p))
                    .collect()
            })
            .collect()
    }
}

impl Tissue {
    /// How far each muscle's surface reaches into the other muscles now, in muscle order
    /// (exact: a tree query per muscle vertex within another muscle's box, the winding
    /// number to confirm; for checks, not for every update).
    pub fn muscles_in_muscles(&self) -> Vec<MuscleOverlap> {
        let surfaces: Vec<(&[Vec3], &[[u32; 3]])> = self
            .muscles
            .iter()
            .map(|m| (m.current.as_slice(), m.triangles.as_ref()))
            .collect();
        muscle_overlaps(&surfaces)
    }
}
