//! How far muscle surfaces reach into bone: an exact measure for checks, not for every
//! update (the updates keep them out with [`super::bone_keep_out`]).

use glam::Vec3;

use super::bone_keep_out::Bones;
use crate::lattice::winding_number;

/// How far muscle surfaces reach into something they should not: a bone
/// ([`BoneOverlap`], see [`super::Tissue::muscles_in_bone`]) or another muscle
/// ([`super::MuscleOverlap`], see [`super::Tissue::muscles_in_muscles`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Overlap {
    /// Muscle vertices more than 1 mm inside.
    pub vertices_over_1mm: usize,
    /// Deepest muscle vertex inside (m), 0 when none is.
    pub deepest_m: f32,
}

/// How far muscle surfaces reach into bone.
pub type BoneOverlap = Overlap;

impl Overlap {
    /// The worse of two, count and depth each (a run's worst moment).
    pub fn worse(&self, o: &Self) -> Self {
        Self {
            vertices_over_1mm: self.vertices_over_1mm.max(o.vertices_over_1mm),
            deepest_m: self.deepest_m.max(o.deepest_m),
        }
    }

    /// Of several muscles together: their counts summed, the deepest of them.
    pub fn total(parts: &[Self]) -> Self {
        Self {
            vertices_over_1mm: parts.iter().map(|o| o.vertices_over_1mm).sum(),
            deepest_m: parts.iter().map(|o| o.deepest_m).fold(0.0, f32::max),
        }
    }
}

/// Measures `vertices` against every bone: a point its distance field calls more than
/// 1 mm inside (or deeper than the deepest so far) is confirmed by the surface's winding
/// number, as a user's tools decide inside, and its depth is the distance to the nearest
/// surface point (exact at any depth).
pub(crate) fn overlap(vertices: &[Vec3], bones: &Bones) -> BoneOverlap {
    let mut o = BoneOverlap::default();
    for (b, (body, mesh)) in bones.surfaces.iter().enumerate() {
        let (q, t) = bones.pose(*body);
        let aabb = mesh.local_aabb();
        for &p in vertices {
            let p_rest = q.inverse() * (p - t);
            if !aabb.contains_local_point(p_rest) {
                continue;
            }
            // Inside by the bone's distance field, depth to the nearest surface point.
            let Some(s) = bones.sdfs[b].nearest(mesh, p_rest, 0.0) else {
                continue;
            };
            let d = -s.distance;
            // Only what would change the result is confirmed (a winding number visits
            // every triangle).
            if d <= 0.0 || (d <= 1e-3 && d <= o.deepest_m) {
                continue;
            }
            if winding_number(mesh.vertices(), mesh.indices(), p_rest).abs() < 0.5 {
                continue;
            }
            o.deepest_m = o.deepest_m.max(d);
            o.vertices_over_1mm += usize::from(d > 1e-3);
        }
    }
    o
}
