//! Every check of the tissue's soundness at one moment, measured the way a user's tools
//! do: a hexahedron is valid when all eight corner Jacobians are positive (ParaView's
//! test), a point is inside a closed surface by its winding number. Exact, about a second
//! on a whole leg: for checks after an update, not inside one.

use serde::Serialize;

use glam::Vec3;

use super::skin_breach::breaches_of;
use super::{BoneOverlap, MuscleOverlap, MuscleShape, Overlap, SkinBreach, Tissue};
use crate::body::BodyId;
use crate::lattice::{hex_is_valid, hex_volume_f32};
use crate::muscle::BodyFrames;
use crate::par::*;

/// The tissue's soundness now (see [`Tissue::audit`]). Counts are summed over muscles
/// and bones, depths are the largest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TissueAudit {
    /// Fat hexahedra with a corner Jacobian at or below zero.
    pub folded_fat: usize,
    /// Fat hexahedra below half their rest volume (fat is nearly incompressible: it should
    /// bulge, not vanish).
    pub fat_under_half_volume: usize,
    /// Smallest fat element volume over its rest volume.
    pub min_fat_volume_ratio: f32,
    /// Muscle vertices outside the skin (None when the skin cannot be closed into a mesh).
    pub muscles_out_of_skin: Option<SkinBreach>,
    /// Bone vertices outside the skin (None when the skin cannot be closed into a mesh).
    pub bones_out_of_skin: Option<SkinBreach>,
    /// Muscle vertices inside bone.
    pub muscles_in_bone: BoneOverlap,
    /// Muscle vertices inside another muscle.
    pub muscles_in_muscles: MuscleOverlap,
    /// Pairs of skin triangles that cross.
    pub skin_crossings: usize,
    /// Area of skin touching other skin (m²): triangles with the skin across from them
    /// within the contact gap and 1 mm, or passed into the body across from them; each
    /// side of a contact counts its own. Over a run, [`Self::worse`] keeps the most (None
    /// when the skin cannot be closed into a mesh).
    pub skin_in_contact_m2: Option<f32>,
    /// Smallest and largest muscle volume over its rest volume.
    pub muscle_volume_ratio: [f32; 2],
    /// Farthest fat vertex from its rest place carried by its bone (m): with the knee
    /// straight again, how far the fat is from coming back.
    pub fat_off_rest_m: f32,
    /// Whether every fat and muscle vertex is finite.
    pub finite: bool,
}

/// One line of the audit: what was checked, what was found, and whether it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct AuditLine {
    /// What was checked.
    pub check: &'static str,
    /// What was found.
    pub found: String,
    /// Whether it holds (the tissue issue's bound).
    pub holds: bool,
}

fn worse_breach(a: Option<SkinBreach>, b: Option<SkinBreach>) -> Option<SkinBreach> {
    match (a, b) {
        (Some(a), Some(b)) => Some(SkinBreach {
            vertices_over_1mm: a.vertices_over_1mm.max(b.vertices_over_1mm),
            farthest_m: a.farthest_m.max(b.farthest_m),
        }),
        _ => None,
    }
}

fn sum_breach(v: &[SkinBreach]) -> SkinBreach {
    SkinBreach {
        vertices_over_1mm: v.iter().map(|b| b.vertices_over_1mm).sum(),
        farthest_m: v.iter().map(|b| b.farthest_m).fold(0.0, f32::max),
    }
}

impl TissueAudit {
    /// The audit line by line: each of the tissue issue's must-holds, what was found and
    /// whether it holds (the fat's distance from rest is shown, not judged).
    pub fn lines(&self) -> Vec<AuditLine> {
        let a = self;
        let breach = |b: Option<SkinBreach>| match b {
            Some(b) => (
                format!("{} ({:.1} mm)", b.vertices_over_1mm, b.farthest_m * 1e3),
                b.vertices_over_1mm == 0,
            ),
            None => ("skin not closed".to_string(), false),
        };
        let line = |check, (found, holds)| AuditLine {
            check,
            found,
            holds,
        };
        let overlap = |o: Overlap| {
            (
                format!("{} ({:.1} mm)", o.vertices_over_1mm, o.deepest_m * 1e3),
                o.vertices_over_1mm == 0,
            )
        };
        let [lo, hi] = a.muscle_volume_ratio;
        vec![
            line("folded fat", (a.folded_fat.to_string(), a.folded_fat == 0)),
            line(
                "fat under half volume",
                (
                    format!(
                        "{} (least {:.2})",
                        a.fat_under_half_volume, a.min_fat_volume_ratio
                    ),
                    a.fat_under_half_volume == 0,
                ),
            ),
            line("muscle out of skin", breach(a.muscles_out_of_skin)),
            line("bone out of skin", breach(a.bones_out_of_skin)),
            line("muscle in bone", overlap(a.muscles_in_bone)),
            line("muscle in muscle", overlap(a.muscles_in_muscles)),
            line(
                "skin crossings",
                (a.skin_crossings.to_string(), a.skin_crossings == 0),
            ),
            line(
                "skin in contact",
                match a.skin_in_contact_m2 {
                    Some(m2) => (format!("{:.1} cm²", m2 * 1e4), true),
                    None => ("skin not closed".to_string(), false),
                },
            ),
            line(
                "muscle volumes",
                (
                    format!("{lo:.3}..{hi:.3}"),
                    (0.99..=1.01).contains(&lo) && (0.99..=1.01).contains(&hi),
                ),
            ),
            line(
                "fat off rest",
                (format!("{:.1} mm", a.fat_off_rest_m * 1e3), true),
            ),
        ]
    }

    /// The worse of two audits, field by field: over a run, its worst moment for each
    /// check (a skin that could not be closed once stays unmeasured).
    ///
    /// ```
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// let rest = sim.audit().expect("the phantom has tissue");
    /// sim.set_excitation("semitendinosus", 1.0)?;
    /// sim.step(0.1)?;
    /// let worst = rest.worse(&sim.audit().expect("tissue"));
    /// assert!(worst.folded_fat >= rest.folded_fat);
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn worse(&self, o: &Self) -> Self {
        Self {
            folded_fat: self.folded_fat.max(o.folded_fat),
            fat_under_half_volume: self.fat_under_half_volume.max(o.fat_under_half_volume),
            min_fat_volume_ratio: self.min_fat_volume_ratio.min(o.min_fat_volume_ratio),
            muscles_out_of_skin: worse_breach(self.muscles_out_of_skin, o.muscles_out_of_skin),
            bones_out_of_skin: worse_breach(self.bones_out_of_skin, o.bones_out_of_skin),
            muscles_in_bone: self.muscles_in_bone.worse(&o.muscles_in_bone),
            muscles_in_muscles: self.muscles_in_muscles.worse(&o.muscles_in_muscles),
            skin_crossings: self.skin_crossings.max(o.skin_crossings),
            skin_in_contact_m2: match (self.skin_in_contact_m2, o.skin_in_contact_m2) {
                (Some(a), Some(b)) => Some(a.max(b)),
                _ => None,
            },
            muscle_volume_ratio: [
                self.muscle_volume_ratio[0].min(o.muscle_volume_ratio[0]),
                self.muscle_volume_ratio[1].max(o.muscle_volume_ratio[1]),
            ],
            fat_off_rest_m: self.fat_off_rest_m.max(o.fat_off_rest_m),
            finite: self.finite && o.finite,
        }
    }

    /// The column names of [`Self::csv_row`] (lengths in mm).
    pub const CSV_HEADER: &'static str = "folded_fat,fat_under_half_volume,min_fat_volume_ratio,\
muscle_vertices_out_of_skin,muscle_out_of_skin_mm,bone_vertices_out_of_skin,bone_out_of_skin_mm,\
muscle_vertices_in_bone,muscle_in_bone_mm,muscle_vertices_in_muscle,muscle_in_muscle_mm,\
skin_crossings,min_muscle_volume_ratio,max_muscle_volume_ratio,fat_off_rest_mm,\
skin_in_contact_cm2,finite";

    /// The audit as one CSV row (an empty cell where the skin could not be closed).
    pub fn csv_row(&self) -> String {
        let breach = |b: Option<SkinBreach>| {
            b.map_or_else(
                || ",".to_string(),
                |b| format!("{},{:.3}", b.vertices_over_1mm, b.farthest_m * 1e3),
            )
        };
        format!(
            "{},{},{:.5},{},{},{},{:.3},{},{:.3},{},{:.5},{:.5},{:.3},{},{}",
            self.folded_fat,
            self.fat_under_half_volume,
            self.min_fat_volume_ratio,
            breach(self.muscles_out_of_skin),
            breach(self.bones_out_of_skin),
            self.muscles_in_bone.vertices_over_1mm,
            self.muscles_in_bone.deepest_m * 1e3,
            self.muscles_in_muscles.vertices_over_1mm,
            self.muscles_in_muscles.deepest_m * 1e3,
            self.skin_crossings,
            self.muscle_volume_ratio[0],
            self.muscle_volume_ratio[1],
            self.fat_off_rest_m * 1e3,
            self.skin_in_contact_m2
                .map_or_else(String::new, |m2| format!("{:.3}", m2 * 1e4)),
            self.finite,
        )
    }
}

impl Tissue {
    /// Every soundness check of the tissue now, with the bones at `frames`: folded and
    /// squashed fat, muscles and bones out through the skin, muscles in bone and in one
    /// another, the skin crossing itself and touching itself, muscle volumes, and how far
    /// the fat is from its rest place. Exact (see the module); a second or so on a whole leg.
    pub fn audit(&self, frames: &BodyFrames) -> TissueAudit {
        let fat = &self.fat;
        // Per element in parallel, then summed in order (the same on one thread: a web
        // page has no pool).
        let per: Vec<(bool, f32)> = fat
            .hexes
            .par_iter()
            .zip(&fat.rest_volume[..])
            .map(|(h, &v0)| {
                let r = (f64::from(hex_volume_f32(&fat.x, h)) / v0) as f32;
                (!hex_is_valid(&fat.x, h), r)
            })
            .collect();
        let folded_fat = per.iter().filter(|p| p.0).count();
        let under_half = per.iter().filter(|p| p.1 < 0.5).count();
        let min_ratio = per.iter().map(|p| p.1).fold(f32::INFINITY, f32::min);
        let off_rest: Vec<f32> = fat
            .x
            .par_iter()
            .zip(&fat.rest[..])
            .zip(&self.fixed.thigh_side)
            .map(|((x, r), &thigh)| {
                let body = if thigh { BodyId::Thigh } else { BodyId::Shank };
                x.distance(frames.point(body, *r))
            })
            .collect();
        let fat_off_rest_m = off_rest.into_iter().fold(0.0, f32::max);
        let muscle_volume_ratio = self
            .muscles
            .iter()
            .map(MuscleShape::volume_ratio)
            .fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], r| {
                [lo.min(r), hi.max(r)]
            });
        // One closed skin for every check against it.
        let skin = self.fixed.skin.vertices(&fat.x);
        let mesh = self.fixed.skin.mesh(&skin);
        let bones = self.bone_points(frames);
        let bones: Vec<&[Vec3]> = bones.iter().map(Vec::as_slice).collect();
        let out_of_skin =
            |sets: &[&[Vec3]]| mesh.as_ref().map(|m| sum_breach(&breaches_of(m, sets)));
        TissueAudit {
            folded_fat,
            fat_under_half_volume: under_half,
            min_fat_volume_ratio: min_ratio,
            muscles_out_of_skin: out_of_skin(&self.muscle_points()),
            bones_out_of_skin: out_of_skin(&bones),
            muscles_in_bone: Overlap::total(&self.muscles_in_bone(frames)),
            muscles_in_muscles: Overlap::total(&self.muscles_in_muscles()),
            skin_crossings: self.fixed.skin.crossings(&skin),
            skin_in_contact_m2: mesh.as_ref().and_then(|m| {
                let reach = self.config.contact_gap_m as f32 + 1e-3;
                Some(self.fixed.skin.contact_area(&skin, m, reach)? as f32)
            }),
            muscle_volume_ratio,
            fat_off_rest_m,
            finite: fat.x.iter().all(|p| p.is_finite())
                && self
                    .muscles
                    .iter()
                    .all(|m| m.current.iter().all(|p| p.is_finite())),
        }
    }
}
