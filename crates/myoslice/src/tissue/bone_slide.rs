//! Fat vertices that touch bone slide on it (paper, section 4.2): each keeps its rest
//! distance from the bone surface, measured in the bone's distance field (no memory of
//! where it was: a walk from the last nearest triangle could settle on the wrong side of
//! a condyle and hold the fat there for good).

use crate::par::*;
use glam::{Quat, Vec3};
use parry3d::shape::TriMesh;

use crate::body::BodyId;
use crate::geometry::BoneSdf;

/// The fat vertices that slide on bone, with their bone and rest distance from it.
#[derive(Debug, Clone, Default)]
pub(crate) struct BoneSlide {
    /// (fat vertex, bone index, signed rest distance from the surface).
    vertices: Vec<(u32, u32, f32)>,
}

impl BoneSlide {
    /// Binds each `(fat vertex, bone)` at its rest position.
    pub(crate) fn new(
        pairs: &[(u32, u32)],
        rest: &[Vec3],
        sdfs: &[BoneSdf],
        bones: &[(BodyId, TriMesh)],
    ) -> Self {
        // Each vertex once: `apply` pulls them in parallel and writes each back once.
        debug_assert!({
            let mut v: Vec<u32> = pairs.iter().map(|p| p.0).collect();
            v.sort_unstable();
            v.windows(2).all(|w| w[0] != w[1])
        });
        let vertices = pairs
            .iter()
            .map(|&(v, b)| {
                let (d, _) =
                    surface_offset(&sdfs[b as usize], &bones[b as usize].1, rest[v as usize]);
                (v, b, d)
            })
            .collect();
        Self { vertices }
    }

    /// Pulls every free sliding vertex of `x` onto its bone at its rest distance (fully
    /// when it is inside the bone, most of the way otherwise); `pose` gives the bodies'
    /// poses (rotation, translation).
    pub(crate) fn apply(
        &self,
        x: &mut [Vec3],
        free: &[bool],
        sdfs: &[BoneSdf],
        bones: &[(BodyId, TriMesh)],
        pose: impl Fn(BodyId) -> (Quat, Vec3) + Sync,
    ) {
        // Each vertex is pulled by itself: in parallel, written back in order.
        let xs = &*x;
        let moved: Vec<(u32, Vec3)> = self
            .vertices
            .par_iter()
            // The rest moves rigidly with its bone (to within 0.1 mm).
            .filter(|(v, ..)| free[*v as usize])
            .map(|&(v, b, d0)| {
                let (body, mesh) = &bones[b as usize];
                let (q, t) = pose(*body);
                let p_rest = q.inverse() * (xs[v as usize] - t);
                let (d, n) = surface_offset(&sdfs[b as usize], mesh, p_rest);
                // Slide on the bone: pulled onto the surface (at its rest distance), softly.
                let target = q * (p_rest - n * (d - d0)) + t;
                let cur = xs[v as usize];
                (v, cur + (target - cur) * if d < 0.0 { 1.0 } else { 0.7 })
            })
            .collect();
        for (v, p) in moved {
            x[v as usize] = p;
        }
    }
}

/// Signed distance of `p` (rest frame) from a bone's surface and the outward direction
/// there ([`BoneSdf::nearest`]: exact at any depth).
fn surface_offset(sdf: &BoneSdf, mesh: &TriMesh, p: Vec3) -> (f32, Vec3) {
    sdf.nearest(mesh, p, f32::INFINITY)
        .map_or((f32::INFINITY, Vec3::ZERO), |s| (s.distance, s.normal))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sliding vertex goes to its bone's nearest point wherever it was before: 0.5 mm
    /// over the cube's top at rest, it is pulled back there from inside the cube (fully)
    /// and from above (most of the way), and pushed out through the nearer side face
    /// when it ends inside next to one.
    #[test]
    fn a_sliding_vertex_keeps_its_rest_distance_from_the_nearest_face() {
        let mesh = super::super::test_shapes::box_mesh(Vec3::ZERO, Vec3::splat(0.1));
        let sdfs = [BoneSdf::new(mesh.vertices(), mesh.indices(), 0.002, 0.006)];
        let bones = [(BodyId::Thigh, mesh)];
        let rest = [Vec3::new(0.05, 0.05, 0.1005)];
        let slide = BoneSlide::new(&[(0, 0)], &rest, &sdfs, &bones);
        let identity = |_| (Quat::IDENTITY, Vec3::ZERO);
        let run = |p: Vec3| {
            let mut x = [p];
            slide.apply(&mut x, &[true], &sdfs, &bones, identity);
            x[0]
        };
        // Inside under the top face: straight out to 0.5 mm over it.
        let p = run(Vec3::new(0.03, 0.06, 0.098));
        assert!(p.distance(Vec3::new(0.03, 0.06, 0.1005)) < 1e-5, "{p}");
        // 3 mm over the top: 70 % of the way back to 0.5 mm.
        let p = run(Vec3::new(0.04, 0.05, 0.103));
        assert!(p.distance(Vec3::new(0.04, 0.05, 0.10125)) < 1e-5, "{p}");
        // Inside, 1 mm from the side face x = 0.1 and 4 mm under the top: out the side.
        let p = run(Vec3::new(0.099, 0.05, 0.096));
        assert!(p.distance(Vec3::new(0.1005, 0.05, 0.096)) < 1e-5, "{p}");
        // Left alone when not free.
        let mut x = [Vec3::new(0.05, 0.05, 0.05)];
        slide.apply(&mut x, &[false], &sdfs, &bones, identity);
        assert_eq!(x[0], Vec3::new(0.05, 0.05, 0.05));
    }
}
