//! How far muscle surfaces reach into bone: an exact measure for checks, not for every
//! update (the updates keep them out with [`super::bone_keep_out`]).

use glam::Vec3;

use super::bone_keep_out::Bones;
use crate::lattice::winding_number;

/// How far muscle surfaces reach into bone (see [`super::Tissue::muscles_in_bone`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BoneOverlap {
    /// Muscle vertices more than 1 mm inside a bone.
    pub vertices_over_1mm: usize,
    /// Deepest muscle vertex inside a bone (m), 0 when none is.
    pub deepest_m: f32,
}

/// Measures `vertices` against every bone (a tree query per vertex near a bone; exact
/// for a surface that does not cross itself). `crossed[b]` says bone `b`'s surface
/// crosses itself (tubes of one bone overlapping, or a tube folding): there the
/// pseudo-normal can call a point outside inside, so the winding number confirms it;
/// it can still miss a point inside one tube whose nearest surface is another tube's
/// wall running inside it, and measures depth to that wall (a lower bound).
pub(crate) fn overlap(vertices: &[Vec3], bones: &Bones, crossed: &[bool]) -> BoneOverlap {
    let mut o = BoneOverlap::default();
    for (b, (body, mesh)) in bones.surfaces.iter().enumerate() {
        let (q, t) = bones.pose(*body);
        let aabb = mesh.local_aabb();
        for &p in vertices {
            let p_rest = q.inverse() * (p - t);
            if !aabb.contains_local_point(p_rest) {
                continue;
            }
            let w = bones.meshes[b].walk_from_tree(mesh, p_rest);
            let d = w.point.distance(p_rest);
            // Only what would change the result is confirmed (a winding number visits
            // every triangle).
            if !w.inside || (d <= 1e-3 && d <= o.deepest_m) {
                continue;
            }
            if crossed[b] && winding_number(mesh.vertices(), mesh.indices(), p_rest).abs() < 0.5 {
                continue;
            }
            o.deepest_m = o.deepest_m.max(d);
            o.vertices_over_1mm += usize::from(d > 1e-3);
        }
    }
    o
}
