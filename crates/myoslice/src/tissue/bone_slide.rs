//! Fat vertices that touch bone slide on it (paper, section 4.2): each keeps its rest
//! distance from the bone surface, found from the triangle it was nearest last time by a
//! walk over neighbouring triangles (a vertex slides a little between updates, so the
//! walk is short; a tree search per vertex would cost far more).

use glam::{Quat, Vec3};
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TriMesh;

use crate::body::BodyId;

/// Most triangles a walk visits before it settles for the best seen.
const MAX_WALK: usize = 24;

/// A bone surface in its rest frame, with triangle adjacency.
#[derive(Debug, Clone)]
pub(crate) struct BoneMesh {
    body: BodyId,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Outward unit normal of each triangle.
    normals: Vec<Vec3>,
    /// The triangles sharing an edge with each triangle (u32::MAX: none).
    neighbours: Vec<[u32; 3]>,
}

impl BoneMesh {
    pub(crate) fn new(body: BodyId, mesh: &TriMesh) -> Self {
        let vertices = mesh.vertices().to_vec();
        let triangles = mesh.indices().to_vec();
        let normals = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let mut edges: Vec<((u32, u32), u32, u8)> = triangles
            .iter()
            .enumerate()
            .flat_map(|(ti, t)| {
                (0..3u8).map(move |k| {
                    let (a, b) = (t[k as usize], t[(k as usize + 1) % 3]);
                    ((a.min(b), a.max(b)), ti as u32, k)
                })
            })
            .collect();
        edges.sort_unstable();
        let mut neighbours = vec![[u32::MAX; 3]; triangles.len()];
        for w in edges.windows(2) {
            if w[0].0 == w[1].0 {
                neighbours[w[0].1 as usize][w[0].2 as usize] = w[1].1;
                neighbours[w[1].1 as usize][w[1].2 as usize] = w[0].1;
            }
        }
        Self {
            body,
            vertices,
            triangles,
            normals,
            neighbours,
        }
    }

    fn closest_on(&self, t: u32, p: Vec3) -> Vec3 {
        let [a, b, c] = self.triangles[t as usize].map(|i| self.vertices[i as usize]);
        closest_on_triangle(p, a, b, c)
    }

    /// The nearest surface point to `p` (rest frame) found by walking from triangle
    /// `start`, the triangle it lies on, and whether `p` is inside the bone.
    fn walk(&self, start: u32, p: Vec3) -> (Vec3, u32, bool) {
        let mut cur = start.min(self.triangles.len() as u32 - 1);
        let mut best = self.closest_on(cur, p);
        let mut d2 = best.distance_squared(p);
        for _ in 0..MAX_WALK {
            let mut next = None;
            for &nb in &self.neighbours[cur as usize] {
                if nb == u32::MAX {
                    continue;
                }
                let q = self.closest_on(nb, p);
                let d = q.distance_squared(p);
                if d < d2 {
                    (best, d2, next) = (q, d, Some(nb));
                }
            }
            match next {
                Some(nb) => cur = nb,
                None => break,
            }
        }
        let inside = (p - best).dot(self.normals[cur as usize]) < 0.0;
        (best, cur, inside)
    }
}

/// Closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The fat vertices that slide on bone, with their bone, rest distance and the triangle
/// each was last nearest.
#[derive(Debug, Clone, Default)]
pub(crate) struct BoneSlide {
    /// (fat vertex, bone index, rest distance from the surface).
    vertices: Vec<(u32, u32, f32)>,
    /// Triangle each vertex was nearest at the last update.
    nearest: Vec<u32>,
}

impl BoneSlide {
    /// Binds each `(fat vertex, bone)` at its rest position.
    pub(crate) fn new(pairs: &[(u32, u32)], rest: &[Vec3], bones: &[(BodyId, TriMesh)]) -> Self {
        let mut vertices = Vec::with_capacity(pairs.len());
        let mut nearest = Vec::with_capacity(pairs.len());
        for &(v, b) in pairs {
            let p = rest[v as usize];
            let mesh = &bones[b as usize].1;
            let (proj, (tri, _)) = mesh.project_local_point_and_get_location(p, false);
            vertices.push((v, b, proj.point.distance(p)));
            nearest.push(tri.min(mesh.num_triangles().saturating_sub(1) as u32));
        }
        Self { vertices, nearest }
    }

    /// Pulls every free sliding vertex of `x` onto its bone at its rest distance (fully
    /// when it is inside the bone, most of the way otherwise); `frames` gives the bodies'
    /// poses (rotation, translation).
    pub(crate) fn apply(
        &mut self,
        x: &mut [Vec3],
        free: &[bool],
        meshes: &[BoneMesh],
        pose: impl Fn(BodyId) -> (Quat, Vec3),
    ) {
        for (k, &(v, b, d0)) in self.vertices.iter().enumerate() {
            if !free[v as usize] {
                continue; // moves rigidly with its bone already
            }
            let mesh = &meshes[b as usize];
            let (q, t) = pose(mesh.body);
            let p_rest = q.inverse() * (x[v as usize] - t);
            let (on, tri, inside) = mesh.walk(self.nearest[k], p_rest);
            self.nearest[k] = tri;
            let out = if inside {
                (on - p_rest).normalize_or_zero()
            } else {
                (p_rest - on).normalize_or_zero()
            };
            // Slide on the bone: pulled onto the surface (at its rest distance), softly.
            let target = q * (on + out * d0) + t;
            let cur = x[v as usize];
            x[v as usize] = cur + (target - cur) * if inside { 1.0 } else { 0.7 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closest_point_of_a_triangle_is_found_in_each_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let near = |p: Vec3| closest_on_triangle(p, a, b, c);
        assert!(near(Vec3::new(0.2, 0.2, 1.0)).distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6);
        assert_eq!(near(Vec3::new(-1.0, -1.0, 0.3)), a);
        assert_eq!(near(Vec3::new(2.0, -0.5, 0.0)), b);
        assert_eq!(near(Vec3::new(-0.5, 2.0, 0.0)), c);
        assert!(near(Vec3::new(0.5, -1.0, 0.0)).distance(Vec3::new(0.5, 0.0, 0.0)) < 1e-6);
        assert!(near(Vec3::new(1.0, 1.0, 0.0)).distance(Vec3::new(0.5, 0.5, 0.0)) < 1e-6);
    }
}
