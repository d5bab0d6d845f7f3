//! How far muscles reach into one another: an exact measure for checks, not for every
//! update. Each muscle's surface is closed (its rings end in caps), so a point is inside it
//! by the surface's winding number, as a user's tools decide.

use crate::par::*;
use glam::Vec3;
use parry3d::bounding_volume::Aabb;
use parry3d::query::PointQuery;

use crate::lattice::{oriented_trimesh, winding_number};

/// How far one muscle's surface reaches into the others (see
/// [`super::Tissue::muscles_in_muscles`]): its vertices more than 1 mm inside another
/// muscle (each counted once) and the deepest.
pub type MuscleOverlap = super::bone_overlap::Overlap;

/// Measures each muscle's vertices against every other muscle's closed surface
/// (`surfaces`: vertices and triangles per muscle). A point parry's pseudo-normals call
/// inside is confirmed by the winding number where it would change the result; its depth
/// is the distance to the nearest surface point.
pub(crate) fn muscle_overlaps(surfaces: &[(&[Vec3], &[[u32; 3]])]) -> Vec<MuscleOverlap> {
    let meshes: Vec<_> = surfaces
        .par_iter()
        .map(|(v, t)| {
            let mesh = oriented_trimesh(v, t)?;
            let aabb = Aabb::from_points(v.iter().copied());
            Some((mesh, aabb))
        })
        .collect();
    surfaces
        .par_iter()
        .enumerate()
        .map(|(a, (points, _))| {
            let mut o = MuscleOverlap::default();
            for &p in *points {
                let mut deepest = 0.0f32;
                for (b, m) in meshes.iter().enumerate() {
                    let Some((mesh, aabb)) = m else { continue };
                    if b == a || !aabb.contains_local_point(p) {
                        continue;
                    }
                    let proj = mesh.project_local_point(p, false);
                    let d = proj.point.distance(p);
                    if !proj.is_inside || d <= deepest || (d <= 1e-3 && d <= o.deepest_m) {
                        continue;
                    }
                    let (v, t) = surfaces[b];
                    if winding_number(v, t, p).abs() >= 0.5 {
                        deepest = d;
                    }
                }
                o.deepest_m = o.deepest_m.max(deepest);
                o.vertices_over_1mm += usize::from(deepest > 1e-3);
            }
            o
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box from `lo` to `hi`, triangles facing out.
    fn cube(lo: Vec3, hi: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let m = crate::tissue::test_shapes::box_mesh(lo, hi);
        (m.vertices().to_vec(), m.indices().to_vec())
    }

    #[test]
    fn a_corner_pushed_into_another_muscle_is_found_at_its_depth() {
        let (a, ta) = cube(Vec3::ZERO, Vec3::splat(0.02));
        // The second box's corner 3 mm into the first across its +x face.
        let (mut b, tb) = cube(Vec3::new(0.021, 0.0, 0.0), Vec3::new(0.04, 0.02, 0.02));
        b[0] = Vec3::new(0.017, 0.01, 0.01);
        let o = muscle_overlaps(&[(&a, &ta), (&b, &tb)]);
        assert_eq!(o[0], MuscleOverlap::default());
        assert_eq!(o[1].vertices_over_1mm, 1);
        assert!((o[1].deepest_m - 0.003).abs() < 1e-6, "{:?}", o[1]);
    }

    #[test]
    fn muscles_side_by_side_do_not_overlap() {
        let (a, ta) = cube(Vec3::ZERO, Vec3::splat(0.02));
        let (b, tb) = cube(Vec3::new(0.02, 0.0, 0.0), Vec3::new(0.04, 0.02, 0.02));
        let o = muscle_overlaps(&[(&a, &ta), (&b, &tb)]);
        assert_eq!(o, vec![MuscleOverlap::default(); 2]);
    }

    #[test]
    fn a_vertex_just_inside_counts_its_depth_but_not_as_over_1mm() {
        let (a, ta) = cube(Vec3::ZERO, Vec3::splat(0.02));
        let (mut b, tb) = cube(Vec3::new(0.021, 0.0, 0.0), Vec3::new(0.04, 0.02, 0.02));
        b[0] = Vec3::new(0.0195, 0.01, 0.01);
        let o = muscle_overlaps(&[(&a, &ta), (&b, &tb)]);
        assert_eq!(o[1].vertices_over_1mm, 0);
        assert!((o[1].deepest_m - 0.0005).abs() < 1e-6, "{:?}", o[1]);
    }
}
