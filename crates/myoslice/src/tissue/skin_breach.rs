//! Muscles that reach out through the skin: the body surface closed at both ends of the
//! lattice, and each muscle vertex measured against it (exact: a tree query per vertex;
//! for checks, not for every update).

use crate::par::*;
use glam::Vec3;
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;

use crate::lattice::{FatLattice, oriented_trimesh};

/// How far a muscle's surface reaches out through the skin (see
/// [`super::Tissue::muscles_outside_skin`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SkinBreach {
    /// Muscle vertices more than 1 mm outside the skin.
    pub vertices_over_1mm: usize,
    /// Farthest muscle vertex outside the skin (m), 0 when none is.
    pub farthest_m: f32,
}

/// The skin as a closed surface: the outer faces of the fat and a fan over each end.
#[derive(Debug, Clone)]
pub(crate) struct ClosedSkin {
    /// Fat vertices on the skin, in the closed surface's vertex order (the two end
    /// centres follow them).
    used: Vec<u32>,
    /// Triangles over `used` and the two end centres, oriented outward (the end fans as
    /// the rest shape faces them).
    triangles: Vec<[u32; 3]>,
    /// Positions in `used` of the outer ring of the first and last slice.
    ends: [Vec<u32>; 2],
    /// How many of `triangles` are the skin's (the end fans follow them).
    sides: usize,
}

impl ClosedSkin {
    /// The closed skin of a fat lattice.
    pub(crate) fn new(fat: &FatLattice) -> Self {
        let skin = fat.surface_triangles();
        let mut slot = vec![u32::MAX; fat.vertices.len()];
        let mut used = Vec::new();
        let mut index = |v: u32| {
            let s = &mut slot[v as usize];
            if *s == u32::MAX {
                *s = used.len() as u32;
                used.push(v);
            }
            *s
        };
        let mut triangles: Vec<[u32; 3]> = skin.iter().map(|t| t.map(&mut index)).collect();
        let ring = |s: usize| -> Vec<u32> {
            (0..fat.rays)
                .map(|j| fat.vertex_index(s, j, fat.layers))
                .collect()
        };
        let ends: [Vec<u32>; 2] =
            [ring(0), ring(fat.slices - 1)].map(|r| r.into_iter().map(&mut index).collect());
        let n = used.len() as u32;
        let sides = triangles.len();
        // Each end fan faces away from the other end (the ends never swap places, so the
        // rest shape settles it for good).
        let centres = ends.each_ref().map(|r| {
            r.iter()
                .map(|&i| fat.vertices[used[i as usize] as usize])
                .sum::<Vec3>()
                / r.len().max(1) as f32
        });
        for (e, end) in ends.iter().enumerate() {
            let centre = n + e as u32;
            let out = centres[e] - centres[1 - e];
            let at = |i: u32| fat.vertices[used[i as usize] as usize];
            let normal: Vec3 = (0..end.len())
                .map(|j| (at(end[j]) - centres[e]).cross(at(end[(j + 1) % end.len()]) - centres[e]))
                .sum();
            let flip = normal.dot(out) < 0.0;
            triangles.extend((0..end.len()).map(|j| {
                let (a, b) = (end[j], end[(j + 1) % end.len()]);
                if flip { [centre, b, a] } else { [centre, a, b] }
            }));
        }
        Self {
            used,
            triangles,
            ends,
            sides,
        }
    }

    /// The closed skin's vertices with the fat vertices at `fat_x`: the skin's, then the
    /// centres of the two end fans.
    pub(crate) fn vertices(&self, fat_x: &[Vec3]) -> Vec<Vec3> {
        let mut v: Vec<Vec3> = self.used.iter().map(|&i| fat_x[i as usize]).collect();
        let centres = self
            .ends
            .each_ref()
            .map(|r| r.iter().map(|&i| v[i as usize]).sum::<Vec3>() / r.len().max(1) as f32);
        v.extend(centres);
        v
    }

    /// The closed skin as a mesh at `vertices` ([`Self::vertices`]); None when degenerate.
    pub(crate) fn mesh(&self, vertices: &[Vec3]) -> Option<TriMesh> {
        oriented_trimesh(vertices, &self.triangles)
    }

    /// Pairs of skin triangles (sharing no vertex) that cross at `vertices`
    /// ([`Self::vertices`]): the skin passing through itself.
    pub(crate) fn crossings(&self, vertices: &[Vec3]) -> usize {
        crate::tissue::intersect::self_intersections(vertices, &self.triangles[..self.sides])
    }

    /// The area (m²) of skin that touches other skin, at `vertices` ([`Self::vertices`];
    /// `closed` is [`Self::mesh`] there): a skin triangle touches when its centre, lifted
    /// [`CONTACT_OFFSET_M`] along its normal, lies inside the closed skin (it has passed
    /// into the body across from it) or sees the skin (not the end fans) within `reach`
    /// along the normal. Each side of a contact counts its own triangles. Nothing in it
    /// knows where a joint is: any two parts of the skin that meet are found. None when
    /// the skin alone is degenerate.
    pub(crate) fn contact_area(
        &self,
        vertices: &[Vec3],
        closed: &TriMesh,
        reach: f32,
    ) -> Option<f64> {
        use parry3d::query::{Ray, RayCast};
        let skin = &self.triangles[..self.sides];
        let open = TriMesh::new(vertices.to_vec(), skin.to_vec()).ok()?;
        let touching = |t: &[u32; 3]| {
            let t = t.map(|i| vertices[i as usize]);
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let area = 0.5 * f64::from(n.length());
            let n = n.normalize_or_zero();
            if n == Vec3::ZERO {
                return 0.0;
            }
            let from = (t[0] + t[1] + t[2]) / 3.0 + n * CONTACT_OFFSET_M;
            let max = (reach - CONTACT_OFFSET_M).max(0.0);
            let touches = closed.project_local_point(from, false).is_inside
                || open
                    .cast_local_ray(&Ray::new(from, n), max, false)
                    .is_some();
            if touches { area } else { 0.0 }
        };
        // Per triangle in parallel, summed in order (the same bits on any thread count).
        let areas: Vec<f64> = skin.par_iter().map(touching).collect();
        Some(areas.iter().sum())
    }

    /// How far each of `muscles` (vertex lists) reaches out through the skin with the fat
    /// vertices at `fat_x`. None when the skin is degenerate.
    pub(crate) fn breaches(&self, fat_x: &[Vec3], muscles: &[&[Vec3]]) -> Option<Vec<SkinBreach>> {
        let mesh = self.mesh(&self.vertices(fat_x))?;
        Some(breaches_of(&mesh, muscles))
    }
}

/// How far each of `sets` (vertex lists) reaches out through the closed skin `mesh`.
pub(crate) fn breaches_of(mesh: &TriMesh, sets: &[&[Vec3]]) -> Vec<SkinBreach> {
    sets.par_iter()
        .map(|m| {
            let mut b = SkinBreach::default();
            for &p in *m {
                let proj = mesh.project_local_point(p, false);
                if !proj.is_inside {
                    let d = proj.point.distance(p);
                    b.farthest_m = b.farthest_m.max(d);
                    b.vertices_over_1mm += usize::from(d > 1e-3);
                }
            }
            b
        })
        .collect()
}

/// How far out from its own triangle (m) a skin triangle looks for other skin: past
/// the neighbouring triangles of a gently curved skin, well under the audit's 1 mm.
const CONTACT_OFFSET_M: f32 = 2e-4;
