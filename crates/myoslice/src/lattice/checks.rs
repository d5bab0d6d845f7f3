//! Structural invariants of a lattice, checked by tests and reported by tools.

use glam::Vec3;
use parry3d::query::PointQuery;
use parry3d::shape::{TriMesh, TriMeshFlags};

use super::tube::check_closed;
use super::{Lattice, hex_volume};

/// Counts of invariant violations (all zero for a sound lattice).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InvariantReport {
    /// Bones whose surface has an edge not shared by exactly two opposite triangles.
    pub open_bones: Vec<String>,
    /// Bones whose enclosed volume is not positive (normals pointing inward).
    pub inward_bones: Vec<String>,
    /// Fat hexahedra of zero or negative volume.
    pub nonpositive_fat: usize,
    /// Muscle volume elements (slabs) of zero or negative volume.
    pub nonpositive_muscle_elements: usize,
    /// Muscle volume elements in all.
    pub muscle_elements: usize,
    /// Fat vertices strictly inside a bone surface.
    pub fat_in_bone: usize,
    /// Structures with two vertices at the same position.
    pub duplicate_vertices: Vec<String>,
}

impl InvariantReport {
    /// True when nothing is violated.
    pub fn is_sound(&self) -> bool {
        self.open_bones.is_empty()
            && self.inward_bones.is_empty()
            && self.nonpositive_fat == 0
            && self.nonpositive_muscle_elements == 0
            && self.fat_in_bone == 0
            && self.duplicate_vertices.is_empty()
    }
}

/// A parry triangle mesh of a closed, outward surface (for containment and projection).
pub fn oriented_trimesh(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Option<TriMesh> {
    TriMesh::with_flags(
        vertices.to_vec(),
        triangles.to_vec(),
        TriMeshFlags::ORIENTED,
    )
    .ok()
}

/// Generalised winding number of a closed triangle surface about `p` (1 inside, 0
/// outside, well defined even where the surface folds through itself).
pub fn winding_number(vertices: &[Vec3], triangles: &[[u32; 3]], p: Vec3) -> f64 {
    let mut w = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|i| (vertices[i as usize] - p).as_dvec3());
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c));
        let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        w += 2.0 * num.atan2(den);
    }
    w / (4.0 * std::f64::consts::PI)
}

/// Whether `p` is strictly inside a closed surface: parry's pseudo-normal test, confirmed
/// by the winding number (robust where tubes of one bone overlap or fold).
pub fn strictly_inside(mesh: &TriMesh, vertices: &[Vec3], triangles: &[[u32; 3]], p: Vec3) -> bool {
    if !mesh.contains_local_point(p) {
        return false;
    }
    let depth = (mesh.project_local_point(p, false).point - p).length();
    depth > 1e-6 && winding_number(vertices, triangles, p).abs() > 0.5
}

fn has_duplicates(v: &[Vec3]) -> bool {
    let mut keys: Vec<[u32; 3]> = v.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    keys.sort_unstable();
    keys.windows(2).any(|w| w[0] == w[1])
}

impl Lattice {
    /// Checks closed, outward bone surfaces, positive elements, no fat vertex inside a
    /// bone and no duplicate vertices.
    pub fn check_invariants(&self) -> InvariantReport {
        let mut r = InvariantReport::default();
        let mut bone_meshes = Vec::new();
        for b in &self.bones {
            if check_closed(&b.mesh.triangles).is_err() {
                r.open_bones.push(b.name.clone());
            }
            if b.mesh.volume() <= 0.0 {
                r.inward_bones.push(b.name.clone());
            }
            if has_duplicates(&b.mesh.vertices) {
                r.duplicate_vertices.push(b.name.clone());
            }
            if let Some(t) = oriented_trimesh(&b.mesh.vertices, &b.mesh.triangles) {
                bone_meshes.push((t, b));
            }
        }
        for m in &self.muscles {
            r.muscle_elements += m.mesh.slabs.len();
            r.nonpositive_muscle_elements +=
                m.mesh.slabs.iter().filter(|s| s.volume <= 0.0).count();
            if has_duplicates(&m.mesh.vertices) {
                r.duplicate_vertices.push(m.name.clone());
            }
        }
        r.nonpositive_fat = self
            .fat
            .hexes
            .iter()
            .filter(|h| hex_volume(&self.fat.vertices, h) <= 0.0)
            .count();
        if has_duplicates(&self.fat.vertices) {
            r.duplicate_vertices.push("fat".into());
        }
        r.fat_in_bone = self
            .fat
            .vertices
            .iter()
            .filter(|p| {
                bone_meshes
                    .iter()
                    .any(|(t, b)| strictly_inside(t, &b.mesh.vertices, &b.mesh.triangles, **p))
            })
            .count();
        r
    }
}
