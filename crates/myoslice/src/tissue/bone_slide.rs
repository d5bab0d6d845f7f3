//! Fat vertices that touch bone slide on it (paper, section 4.2): each keeps its rest
//! distance from the bone surface, measured in the bone's distance field (no memory of
//! where it was: a walk from the last nearest triangle could settle on the wrong side of
//! a condyle and hold the fat there for good). [`BoneMesh`] holds a bone's surface with
//! its adjacency for the muscles' keep-out walks.

use crate::par::*;
use glam::{Quat, Vec3};
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TriMesh;

use super::distance_grid::DistanceGrid;
use crate::body::BodyId;
use crate::geometry::sdf::pseudo_normals;
use crate::geometry::{BoneSdf, Feature, closest_point};

/// Most triangles a walk visits before it settles for the best seen.
const MAX_WALK: usize = 24;

/// A bone surface in its rest frame, with triangle adjacency.
#[derive(Debug, Clone)]
pub(crate) struct BoneMesh {
    body: BodyId,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per triangle: outward unit normal, then the pseudo-normals of its edges (ab, bc,
    /// ca), the mean of the two faces' (the distance field's own).
    face_normals: Vec<[Vec3; 4]>,
    /// Angle-weighted pseudo-normal of each vertex (Bærentzen and Aanæs 2005): which side
    /// of the surface a point lies on, whatever feature is nearest it.
    vertex_normals: Vec<Vec3>,
    /// The triangles sharing an edge with each triangle (u32::MAX: none).
    neighbours: Vec<[u32; 3]>,
    /// The triangles around each vertex (CSR: `fan[fan_start[v]..fan_start[v + 1]]`).
    fan_start: Vec<u32>,
    fan: Vec<u32>,
    /// Exact distances from a coarse grid of points, for a quick bound.
    grid: DistanceGrid,
}

/// Where a walk over a bone surface ended.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Walk {
    /// The nearest surface point it found.
    pub(crate) point: Vec3,
    /// The triangle that point lies on.
    pub(crate) triangle: u32,
    /// Whether the query point lies inside the bone (by the pseudo-normal there).
    pub(crate) inside: bool,
    /// Whether it stopped at a local minimum of the distance (else it ran out of steps).
    pub(crate) settled: bool,
}

impl BoneMesh {
    /// The surface of a bone on `body` (closed, outward triangles).
    pub(crate) fn new(body: BodyId, mesh: &TriMesh) -> Self {
        let vertices = mesh.vertices().to_vec();
        let triangles = mesh.indices().to_vec();
        let (face_normals, vertex_normals) = pseudo_normals(&vertices, &triangles);
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
                let (t0, k0, t1, k1) = (
                    w[0].1 as usize,
                    w[0].2 as usize,
                    w[1].1 as usize,
                    w[1].2 as usize,
                );
                neighbours[t0][k0] = t1 as u32;
                neighbours[t1][k1] = t0 as u32;
            }
        }
        let (fan_start, corners) = super::incidence::vertex_corners(vertices.len(), &triangles);
        let fan = corners.into_iter().map(|c| c / 3).collect();
        let (lo, hi) = vertices.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        let grid = if vertices.is_empty() {
            DistanceGrid::new(Vec3::ZERO, Vec3::ZERO)
        } else {
            DistanceGrid::new(lo, hi)
        };
        Self {
            body,
            vertices,
            triangles,
            face_normals,
            vertex_normals,
            neighbours,
            fan_start,
            fan,
            grid,
        }
    }

    fn closest_on(&self, t: u32, p: Vec3) -> (Vec3, Feature) {
        let [a, b, c] = self.triangles[t as usize].map(|i| self.vertices[i as usize]);
        let (q, _, feature) = closest_point(p, a, b, c);
        (q, feature)
    }

    /// The outward pseudo-normal at `feature` of triangle `t`.
    fn pseudo_normal(&self, t: u32, feature: Feature) -> Vec3 {
        match feature {
            Feature::Face => self.face_normals[t as usize][0],
            Feature::Edge(k) => self.face_normals[t as usize][1 + usize::from(k)],
            Feature::Vertex(k) => {
                self.vertex_normals[self.triangles[t as usize][usize::from(k)] as usize]
            }
        }
    }

    /// The body the bone moves with.
    pub(crate) fn body(&self) -> BodyId {
        self.body
    }

    /// The nearest surface point to `p` (rest frame) found by walking from triangle
    /// `start` (see [`Walk`]).
    pub(crate) fn walk(&self, start: u32, p: Vec3) -> Walk {
        let mut cur = start.min(self.triangles.len().saturating_sub(1) as u32);
        let mut best = self.closest_on(cur, p);
        let mut d2 = best.0.distance_squared(p);
        let mut settled = false;
        for _ in 0..MAX_WALK {
            let mut next = None;
            // Across the edges, and all round a corner when the nearest point is one (a
            // walk over edges alone can stall at a corner shared by many triangles).
            let corner = match best.1 {
                Feature::Vertex(k) => {
                    let v = self.triangles[cur as usize][usize::from(k)] as usize;
                    &self.fan[self.fan_start[v] as usize..self.fan_start[v + 1] as usize]
                }
                _ => &[],
            };
            for &nb in self.neighbours[cur as usize].iter().chain(corner) {
                if nb == u32::MAX || nb == cur {
                    continue;
                }
                let q = self.closest_on(nb, p);
                let d = q.0.distance_squared(p);
                if d < d2 {
                    (best, d2, next) = (q, d, Some(nb));
                }
            }
            match next {
                Some(nb) => cur = nb,
                None => {
                    settled = true;
                    break;
                }
            }
        }
        Walk {
            point: best.0,
            triangle: cur,
            inside: (p - best.0).dot(self.pseudo_normal(cur, best.1)) < 0.0,
            settled,
        }
    }

    /// How far (m) `p` (rest frame) surely lies outside the bone, zero when that is not
    /// sure (see [`DistanceGrid`]; `tree` is this bone's parry mesh, for a cell's first
    /// distance).
    pub(crate) fn clear_bound(&self, p: Vec3, tree: &TriMesh) -> f32 {
        self.grid.clear_of(p, |c| {
            let w = self.walk_from_tree(tree, c);
            let d = w.point.distance(c);
            if w.inside { -d } else { d }
        })
    }

    /// The nearest surface point to `p` (rest frame) from the tree's nearest triangle
    /// (exact, a tree search).
    pub(crate) fn walk_from_tree(&self, tree: &TriMesh, p: Vec3) -> Walk {
        let (_, (tri, _)) = tree.project_local_point_and_get_location(p, false);
        self.walk(tri, p)
    }

    /// [`Self::walk`] from `start`; but a walk can stop at a nearest point that is only
    /// local (across a concave part of the bone): when it says inside, or runs out of
    /// steps, the tree (`tree`, this bone's parry mesh) decides before anything moves.
    pub(crate) fn walk_checked(&self, start: u32, p: Vec3, tree: &TriMesh) -> Walk {
        let w = self.walk(start, p);
        if w.settled && !w.inside {
            return w;
        }
        // The walk's point lies on the surface, so the nearest is no further: the tree
        // searches only that far (with the walk after it, 0.8 µs against 1.3 µs for an
        // unbounded search during the phantom's flexion).
        match tree.project_local_point_and_get_location_with_max_dist(p, false, w.point.distance(p))
        {
            Some((_, (tri, _))) => self.walk(tri, p),
            // Nothing nearer: the walk's point is the nearest, and its pseudo-normal
            // tells inside from outside.
            None => w,
        }
    }
}

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

    /// A unit cube, outward triangles.
    fn cube() -> BoneMesh {
        let v: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = 0, normal −z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let t: Vec<[u32; 3]> = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        BoneMesh::new(
            BodyId::Thigh,
            &TriMesh::new(v, t).unwrap_or_else(|e| panic!("{e}")),
        )
    }

    #[test]
    fn a_walk_finds_the_nearest_point_and_the_side_from_any_start() {
        let m = cube();
        for start in 0..12 {
            // Just inside the top face, near its middle.
            let w = m.walk(start, Vec3::new(0.5, 0.4, 0.98));
            assert!(w.settled && w.inside, "start {start}: {w:?}");
            assert!(w.point.distance(Vec3::new(0.5, 0.4, 1.0)) < 1e-5, "{w:?}");
            // Outside beyond a corner (the nearest feature is a vertex of six triangles).
            let w = m.walk(start, Vec3::new(1.2, 1.3, 1.1));
            assert!(w.settled && !w.inside, "start {start}: {w:?}");
            assert!(w.point.distance(Vec3::ONE) < 1e-5, "{w:?}");
            // Outside beyond an edge.
            let w = m.walk(start, Vec3::new(-0.1, 0.5, -0.2));
            assert!(!w.inside && w.point.distance(Vec3::new(0.0, 0.5, 0.0)) < 1e-5);
        }
    }

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

    #[test]
    fn the_closest_point_of_a_triangle_is_found_in_each_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let near = |p: Vec3| closest_point(p, a, b, c).0;
        assert!(near(Vec3::new(0.2, 0.2, 1.0)).distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6);
        assert_eq!(near(Vec3::new(-1.0, -1.0, 0.3)), a);
        assert_eq!(near(Vec3::new(2.0, -0.5, 0.0)), b);
        assert_eq!(near(Vec3::new(-0.5, 2.0, 0.0)), c);
        assert!(near(Vec3::new(0.5, -1.0, 0.0)).distance(Vec3::new(0.5, 0.0, 0.0)) < 1e-6);
        assert!(near(Vec3::new(1.0, 1.0, 0.0)).distance(Vec3::new(0.5, 0.5, 0.0)) < 1e-6);
    }
}
