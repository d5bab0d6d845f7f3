//! Picking: which muscle lies under the cursor. A ray from the eye through the pixel is
//! tested against the drawn bones and muscles (the skin is see-through and never blocks);
//! the nearest hit wins, so a muscle behind a bone is not picked.

use glam::{Mat4, Vec2, Vec3};

use crate::camera::OrbitCamera;
use crate::scene::{Layer, SceneMesh};

/// A ray in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start (on the near plane).
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

impl Ray {
    /// The ray through pixel `px` (origin top-left) of a `size` viewport.
    pub fn through_pixel(camera: &OrbitCamera, px: Vec2, size: Vec2) -> Self {
        let size = size.max(Vec2::ONE);
        let ndc = Vec2::new(2.0 * px.x / size.x - 1.0, 1.0 - 2.0 * px.y / size.y);
        let inv: Mat4 = (camera.projection(size.x / size.y) * camera.view()).inverse();
        // Depth 0..1 (wgpu): the near and far planes.
        let near = inv.project_point3(ndc.extend(0.0));
        let far = inv.project_point3(ndc.extend(1.0));
        Self {
            origin: near,
            dir: (far - near).normalize_or(Vec3::NEG_Z),
        }
    }

    /// Distance along the ray to triangle `abc`, if it hits it (either side).
    pub fn hit_triangle(&self, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
        // Möller–Trumbore.
        let (e1, e2) = (b - a, c - a);
        let p = self.dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = self.origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = self.dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t > 0.0).then_some(t)
    }
}

/// The muscle (index in the simulation's order) the ray meets first, if a muscle and not
/// a bone is the nearest thing drawn along it.
pub fn pick_muscle(scene: &SceneMesh, ray: &Ray) -> Option<usize> {
    let nearest = |range: std::ops::Range<u32>| -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for (k, t) in scene.indices[range.start as usize..range.end as usize]
            .chunks_exact(3)
            .enumerate()
        {
            let [a, b, c] =
                [t[0], t[1], t[2]].map(|i| Vec3::from_array(scene.vertices[i as usize].pos));
            if let Some(d) = ray.hit_triangle(a, b, c)
                && best.is_none_or(|(bd, _)| d < bd)
            {
                best = Some((d, range.start + 3 * k as u32));
            }
        }
        best
    };
    let (d_muscle, at) = nearest(scene.ranges[Layer::Muscle as usize].clone())?;
    if let Some((d_bone, _)) = nearest(scene.ranges[Layer::Bone as usize].clone())
        && d_bone < d_muscle
    {
        return None;
    }
    scene.muscle_of_index(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraPreset;
    use crate::scene::SceneOptions;
    use myoslice::{Simulation, SimulationConfig};

    #[test]
    fn a_ray_through_a_projected_point_passes_through_it() {
        let cam = OrbitCamera::framing(Vec3::ZERO, Vec3::ONE, CameraPreset::Oblique, 1.5);
        let size = Vec2::new(900.0, 600.0);
        let p = Vec3::new(0.3, 0.6, 0.2);
        let clip = cam.projection(1.5) * cam.view() * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let px = Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y);
        let ray = Ray::through_pixel(&cam, px, size);
        let off = (p - ray.origin) - ray.dir * (p - ray.origin).dot(ray.dir);
        assert!(
            off.length() < 1e-4,
            "ray misses the point by {}",
            off.length()
        );
        assert!((ray.dir.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn triangle_hits_report_the_distance_and_misses_none() {
        let ray = Ray {
            origin: Vec3::new(0.2, 0.2, 5.0),
            dir: Vec3::NEG_Z,
        };
        let t = ray.hit_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert!((t.unwrap_or(0.0) - 5.0).abs() < 1e-5);
        let away = Ray {
            dir: Vec3::Z,
            ..ray
        };
        assert_eq!(away.hit_triangle(Vec3::ZERO, Vec3::X, Vec3::Y), None);
        let beside = Ray {
            origin: Vec3::new(0.8, 0.8, 5.0),
            ..ray
        };
        assert_eq!(beside.hit_triangle(Vec3::ZERO, Vec3::X, Vec3::Y), None);
    }

    #[test]
    fn the_cursor_over_a_muscle_picks_that_muscle_and_empty_space_picks_none() {
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let sim = Simulation::phantom(config).expect("phantom");
        let scene = SceneMesh::build(&sim, &SceneOptions::default());
        let size = Vec2::new(800.0, 800.0);
        let cam = OrbitCamera::framing(scene.bounds.0, scene.bounds.1, CameraPreset::Front, 1.0);
        // Aim at the front of the rectus femoris (the most anterior thigh muscle): the
        // most anterior of its vertices at mid-thigh height.
        let rf = sim.muscle_index("rectus_femoris").expect("rectus femoris");
        let v = sim.muscle_vertices(rf);
        let zmid = 0.5
            * (v.iter().map(|p| p.z).fold(f32::INFINITY, f32::min)
                + v.iter().map(|p| p.z).fold(f32::NEG_INFINITY, f32::max));
        let front = v
            .iter()
            .filter(|p| (p.z - zmid).abs() < 0.02)
            .copied()
            .max_by(|a, b| a.y.total_cmp(&b.y))
            .expect("vertices at mid-height");
        let clip = cam.projection(1.0) * cam.view() * front.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        // A hair inside the muscle's outline.
        let px = Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y);
        let ray = Ray::through_pixel(&cam, px, size);
        assert_eq!(pick_muscle(&scene, &ray), Some(rf));
        // The top-left corner of the frame shows no leg.
        let corner = Ray::through_pixel(&cam, Vec2::new(2.0, 2.0), size);
        assert_eq!(pick_muscle(&scene, &corner), None);
    }
}
