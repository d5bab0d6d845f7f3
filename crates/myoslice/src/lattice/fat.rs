//! The fat lattice (paper, Fig. 2): hexahedra between the bone/muscle envelope and the
//! skin, on rays from the centre of the largest bone region of each slice.

use crate::par::*;
use glam::{DVec3, Vec3};

use super::frame::SliceFrame;
use crate::contour::{LabelSetMask, Mask, Polygon, outermost_crossing, ray_dir};
use crate::error::{Error, Result};
use crate::label_table::TissueKind;
use crate::slices::SliceStack;

/// What an inner fat vertex rests against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InnerContact {
    /// Nothing: fat on both sides (the envelope was not reached on this ray).
    Free,
    /// A bone: the vertex slides on its surface.
    Bone(u16),
    /// A muscle: the vertex follows its reference muscle vertex.
    Muscle(u16),
}

/// The fat lattice: `slices × rays × (layers + 1)` vertices and `(slices − 1) × rays ×
/// layers` hexahedra, indexed slice-major so neighbours are close in memory.
#[derive(Debug, Clone)]
pub struct FatLattice {
    /// Number of rays per slice.
    pub rays: usize,
    /// Radial element layers.
    pub layers: usize,
    /// Number of slices.
    pub slices: usize,
    /// Vertices (world, m).
    pub vertices: Vec<Vec3>,
    /// Hexahedra, VTK vertex order, positive volume at rest.
    pub hexes: Vec<[u32; 8]>,
    /// Face neighbours of each hexahedron (`u32::MAX` where none): −slice, +slice,
    /// −ray, +ray, inner, outer.
    pub neighbours: Vec<[u32; 6]>,
    /// What each inner vertex (layer 0) touches, per slice and ray.
    pub inner_contact: Vec<InnerContact>,
    /// Reference point (world, m) of each slice's rays.
    pub reference: Vec<Vec3>,
    /// The same reference points in slice pixel coordinates.
    pub reference_px: Vec<[f64; 2]>,
}

impl FatLattice {
    /// Index of vertex (slice, ray, layer).
    #[inline]
    pub fn vertex_index(&self, s: usize, j: usize, l: usize) -> u32 {
        ((s * self.rays + j % self.rays) * (self.layers + 1) + l) as u32
    }

    /// Index of hexahedron (slice, ray, layer).
    #[inline]
    pub fn hex_index(&self, s: usize, j: usize, l: usize) -> u32 {
        ((s * self.rays + j) * self.layers + l) as u32
    }

    /// Outer (skin) face of each outer-layer hexahedron: `(hex index, quad)`, the quad
    /// counter-clockwise seen from outside.
    pub fn outer_faces(&self) -> Vec<(u32, [u32; 4])> {
        let mut out = Vec::with_capacity((self.slices - 1) * self.rays);
        let l = self.layers;
        for s in 0..self.slices - 1 {
            for j in 0..self.rays {
                let h = self.hex_index(s, j, l - 1);
                let q = self.hexes[h as usize];
                // Outer quad of a hex: vertices 2, 3 (bottom, outer) and 6, 7 (top, outer).
                out.push((h, [q[3], q[2], q[6], q[7]]));
            }
        }
        // Face the quads outward: away from the slice's reference point.
        if let Some((_, q)) = out.first() {
            let p = q.map(|i| self.vertices[i as usize]);
            let normal = (p[1] - p[0]).cross(p[2] - p[0]);
            let centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
            let axis = (self.reference[0] - self.reference[self.slices - 1]).normalize_or_zero();
            let radial = centre - self.reference[0];
            let radial = radial - axis * radial.dot(axis);
            if normal.dot(radial) < 0.0 {
                for (_, q) in &mut out {
                    q.reverse();
                }
            }
        }
        out
    }

    /// Body-surface triangles (two per outer face), oriented outward.
    pub fn surface_triangles(&self) -> Vec<[u32; 3]> {
        self.outer_faces()
            .iter()
            .flat_map(|(_, q)| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    /// Vertex indices of the inner (layer 0) vertex of every (slice, ray).
    pub fn inner_vertices(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.slices).flat_map(move |s| (0..self.rays).map(move |j| self.vertex_index(s, j, 0)))
    }
}

/// Signed volume of a hexahedron in VTK order (six tetrahedra about the 0–6 diagonal).
pub fn hex_volume(v: &[Vec3], h: &[u32; 8]) -> f64 {
    let p = h.map(|i| v[i as usize].as_dvec3());
    hex_volume_points(&p)
}

/// The six tetrahedra of a hexahedron (VTK corner order) about its 0–6 diagonal, as the
/// corners each makes with corner 0.
const HEX_TETS: [[usize; 3]; 6] = [
    [1, 2, 6],
    [2, 3, 6],
    [3, 7, 6],
    [7, 4, 6],
    [4, 5, 6],
    [5, 1, 6],
];

/// Signed volume of eight hexahedron corners in VTK order.
pub fn hex_volume_points(p: &[DVec3; 8]) -> f64 {
    let mut vol = 0.0;
    for t in HEX_TETS {
        let (a, b, c) = (p[t[0]] - p[0], p[t[1]] - p[0], p[t[2]] - p[0]);
        vol += a.dot(b.cross(c));
    }
    vol / 6.0
}

/// Signed volume of hexahedron `h` of `x` (VTK corner order), about its first corner in
/// single precision: for the per-update checks, whose thresholds are percents of the
/// rest volume.
pub fn hex_volume_f32(x: &[Vec3], h: &[u32; 8]) -> f32 {
    let p0 = x[h[0] as usize];
    let p = h.map(|i| glam::Vec3A::from(x[i as usize] - p0));
    HEX_TETS
        .iter()
        .map(|t| p[t[0]].dot(p[t[1]].cross(p[t[2]])))
        .sum::<f32>()
        / 6.0
}

/// Inputs of the fat build that come from the bone and muscle passes.
pub(crate) struct FatInputs<'a> {
    pub stack: &'a SliceStack,
    pub frame: &'a SliceFrame,
    pub kind_of: &'a [Option<TissueKind>],
    /// Centroid (pixels) of the largest bone region of each slice, if any.
    pub bone_centre: &'a [Option<[f64; 2]>],
    /// Bone polygons (pixels) of each slice.
    pub bone_polygons: &'a [Vec<Polygon>],
    pub rays: usize,
    pub layers: usize,
    pub min_thickness_px: f64,
}

pub(crate) fn build_fat(inp: &FatInputs<'_>) -> Result<FatLattice> {
    let n_slices = inp.stack.len();
    if n_slices < 2 {
        return Err(Error::Build(format!(
            "the fat lattice needs at least 2 kept slices, got {n_slices}"
        )));
    }
    let reference = smoothed_reference(inp.bone_centre)?;
    let lut_len = inp.kind_of.len();
    let body: Vec<bool> = (0..lut_len)
        .map(|i| inp.kind_of[i].is_some_and(|k| k != TissueKind::Background))
        .collect();
    let env: Vec<bool> = (0..lut_len)
        .map(|i| matches!(inp.kind_of[i], Some(TissueKind::Bone | TissueKind::Muscle)))
        .collect();
    let (w, h) = (inp.stack.width, inp.stack.height);
    let r_max = ((w * w + h * h) as f64).sqrt() + 2.0;
    let layers = inp.layers;
    let per_slice: Vec<(Vec<Vec3>, Vec<InnerContact>)> = (0..n_slices)
        .into_par_iter()
        .map(|s| {
            let labels = &inp.stack.labels[s];
            let body_m = LabelSetMask {
                labels,
                width: w,
                height: h,
                member: &body,
            };
            let env_m = LabelSetMask {
                labels,
                width: w,
                height: h,
                member: &env,
            };
            let c = reference[s];
            let mut verts = Vec::with_capacity(inp.rays * (layers + 1));
            let mut contact = Vec::with_capacity(inp.rays);
            for j in 0..inp.rays {
                let d = ray_dir(j, inp.rays);
                let mut r_out = outermost_crossing(&body_m, c, d, r_max, 0.0)
                    .unwrap_or(inp.min_thickness_px + 2.0)
                    .max(inp.min_thickness_px + 2.0);
                let found = outermost_crossing(&env_m, c, d, r_out, 0.0);
                let mut r_in = found.unwrap_or(0.3 * r_out);
                r_in = r_in.clamp(1.0, r_out - inp.min_thickness_px);
                // Never start inside a bone: step out along the ray past the bone polygons
                // of this slice (the exact section of the bone surfaces by the slice plane),
                // and where a bone reaches the skin, move the skin out to keep fat on it.
                let at = |r: f64| [c[0] + d[0] * r, c[1] + d[1] * r];
                let in_bone = |r: f64| {
                    let q = at(r);
                    inp.bone_polygons[s].iter().any(|p| p.contains(q[0], q[1]))
                };
                let mut r = r_out + 1.0;
                while r > r_in - 0.25 {
                    if in_bone(r) {
                        r_in = r + 0.5;
                        r_out = r_out.max(r_in + inp.min_thickness_px);
                        break;
                    }
                    r -= 0.25;
                }
                let kind = if found.is_some() {
                    let q = at((r_in - 0.75).max(0.0));
                    let (u, v) = (q[0].round() as i64, q[1].round() as i64);
                    if u >= 0 && v >= 0 && (u as usize) < w && (v as usize) < h {
                        let lab = labels[u as usize + w * v as usize];
                        match inp.kind_of.get(lab as usize).copied().flatten() {
                            Some(TissueKind::Bone) => InnerContact::Bone(lab),
                            Some(TissueKind::Muscle) => InnerContact::Muscle(lab),
                            _ => nearest_envelope_label(&env_m, labels, w, inp.kind_of, at(r_in)),
                        }
                    } else {
                        InnerContact::Free
                    }
                } else {
                    InnerContact::Free
                };
                contact.push(kind);
                for l in 0..=layers {
                    let r = r_in + (r_out - r_in) * l as f64 / layers as f64;
                    verts.push(inp.frame.world(s, at(r)));
                }
            }
            (verts, contact)
        })
        .collect();
    let mut vertices = Vec::with_capacity(n_slices * inp.rays * (layers + 1));
    let mut inner_contact = Vec::with_capacity(n_slices * inp.rays);
    for (v, c) in per_slice {
        vertices.extend(v);
        inner_contact.extend(c);
    }
    let mut lat = FatLattice {
        rays: inp.rays,
        layers,
        slices: n_slices,
        vertices,
        hexes: Vec::new(),
        neighbours: Vec::new(),
        inner_contact,
        reference: reference
            .iter()
            .enumerate()
            .map(|(s, c)| inp.frame.world(s, *c))
            .collect(),
        reference_px: reference.clone(),
    };
    let n = inp.rays;
    let mut hexes = Vec::with_capacity((n_slices - 1) * n * layers);
    for s in 0..n_slices - 1 {
        for j in 0..n {
            for l in 0..layers {
                let vi = |ss, jj, ll| lat.vertex_index(ss, jj, ll);
                hexes.push([
                    vi(s, j, l),
                    vi(s, j + 1, l),
                    vi(s, j + 1, l + 1),
                    vi(s, j, l + 1),
                    vi(s + 1, j, l),
                    vi(s + 1, j + 1, l),
                    vi(s + 1, j + 1, l + 1),
                    vi(s + 1, j, l + 1),
                ]);
            }
        }
    }
    // Orientation depends on the handedness of the volume's axes: fix it once for all.
    let total: f64 = hexes.iter().map(|hx| hex_volume(&lat.vertices, hx)).sum();
    if total < 0.0 {
        for hx in &mut hexes {
            *hx = [hx[4], hx[5], hx[6], hx[7], hx[0], hx[1], hx[2], hx[3]];
        }
    }
    let mut neighbours = Vec::with_capacity(hexes.len());
    for s in 0..n_slices - 1 {
        for j in 0..n {
            for l in 0..layers {
                let none = u32::MAX;
                neighbours.push([
                    if s > 0 {
                        lat.hex_index(s - 1, j, l)
                    } else {
                        none
                    },
                    if s + 2 < n_slices {
                        lat.hex_index(s + 1, j, l)
                    } else {
                        none
                    },
                    lat.hex_index(s, (j + n - 1) % n, l),
                    lat.hex_index(s, (j + 1) % n, l),
                    if l > 0 {
                        lat.hex_index(s, j, l - 1)
                    } else {
                        none
                    },
                    if l + 1 < layers {
                        lat.hex_index(s, j, l + 1)
                    } else {
                        none
                    },
                ]);
            }
        }
    }
    lat.hexes = hexes;
    lat.neighbours = neighbours;
    Ok(lat)
}

fn nearest_envelope_label(
    env: &LabelSetMask<'_>,
    labels: &[u16],
    w: usize,
    kind_of: &[Option<TissueKind>],
    p: [f64; 2],
) -> InnerContact {
    let (u0, v0) = (p[0].round() as i64, p[1].round() as i64);
    for rad in 1..=2i64 {
        for dv in -rad..=rad {
            for du in -rad..=rad {
                if env.at(u0 + du, v0 + dv) {
                    let lab = labels[(u0 + du) as usize + w * (v0 + dv) as usize];
                    return match kind_of.get(lab as usize).copied().flatten() {
                        Some(TissueKind::Bone) => InnerContact::Bone(lab),
                        _ => InnerContact::Muscle(lab),
                    };
                }
            }
        }
    }
    InnerContact::Free
}

/// Reference points per slice: the largest bone centre, gaps filled from the nearest
/// slices and smoothed over ±2 slices so rays do not jump between bones.
fn smoothed_reference(centres: &[Option<[f64; 2]>]) -> Result<Vec<[f64; 2]>> {
    let known: Vec<(usize, [f64; 2])> = centres
        .iter()
        .enumerate()
        .filter_map(|(s, c)| c.map(|c| (s, c)))
        .collect();
    if known.is_empty() {
        return Err(Error::Build(
            "no kept slice contains bone: the fat lattice needs a bone in the slices".into(),
        ));
    }
    let filled: Vec<[f64; 2]> = (0..centres.len())
        .map(|s| {
            if let Some(c) = centres[s] {
                return c;
            }
            let after = known.iter().find(|(k, _)| *k > s);
            let before = known.iter().rev().find(|(k, _)| *k < s);
            match (before, after) {
                (Some((a, ca)), Some((b, cb))) => {
                    let t = (s - a) as f64 / (b - a) as f64;
                    [ca[0] + t * (cb[0] - ca[0]), ca[1] + t * (cb[1] - ca[1])]
                }
                (Some((_, c)), None) | (None, Some((_, c))) => *c,
                (None, None) => [0.0, 0.0],
            }
        })
        .collect();
    let n = filled.len() as i64;
    Ok((0..n)
        .map(|s| {
            let (mut x, mut y, mut k) = (0.0, 0.0, 0.0);
            for t in (s - 2).max(0)..=(s + 2).min(n - 1) {
                x += filled[t as usize][0];
                y += filled[t as usize][1];
                k += 1.0;
            }
            [x / k, y / k]
        })
        .collect())
}

/// Area (m²) of a quad as two triangles.
pub fn quad_area(v: &[Vec3], q: &[u32; 4]) -> f64 {
    let p = q.map(|i| v[i as usize].as_dvec3());
    0.5 * ((p[1] - p[0]).cross(p[2] - p[0]).length() + (p[2] - p[0]).cross(p[3] - p[0]).length())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_cube_hex_has_unit_volume() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ]
        .map(DVec3::from);
        assert!((hex_volume_points(&p) - 1.0).abs() < 1e-12);
    }
}
