//! A bone's signed distance field in its rest frame: a narrow band of grid nodes around
//! the surface, each holding its exact signed distance and nearest triangle. A query
//! near the surface is answered exactly from the nearest triangles of the eight nodes
//! around it; further out, by trilinear interpolation. Built once per bone; queries are
//! lock-free reads, so any number of threads may share one field.
//!
//! The sign comes from the surface's winding number along grid columns (a union of
//! closed tubes, even overlapping ones, is inside where any tube is), so it is right
//! where pseudo-normals are not: where one tube's wall runs inside another.

use crate::par::*;
use glam::{IVec3, Vec3};
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;

use super::triangle::{Feature, closest_point};

/// √3: a grid cell's diagonal over its side.
const SQRT_3: f32 = 1.732_050_8;

/// What a distance query found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SdfSample {
    /// Signed distance (m): negative inside the bone.
    pub distance: f32,
    /// Unit direction of increasing distance (outward), rest frame.
    pub normal: Vec3,
    /// The nearest surface point, where the sample is exact (within
    /// [`BoneSdf::exact_within`] of the surface); None where it is interpolated.
    pub nearest: Option<Vec3>,
}

/// The nearest point of a bone's surface to a query point, exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Signed distance (m): negative inside the bone.
    pub distance: f32,
    /// Unit outward direction at the query point (rest frame).
    pub normal: Vec3,
    /// The nearest surface point (rest frame).
    pub point: Vec3,
}

/// Narrow-band signed distance field of a closed triangle surface.
///
/// ```
/// use glam::Vec3;
/// use myoslice::geometry::BoneSdf;
/// // A unit cube (1 dm) as twelve outward triangles.
/// let v: Vec<Vec3> = (0..8)
///     .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) * 0.1)
///     .collect();
/// let t = vec![
///     [0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
///     [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5],
/// ];
/// let sdf = BoneSdf::new(&v, &t, 0.005, 0.02);
/// let inside = sdf.sample(Vec3::new(0.05, 0.05, 0.003)).unwrap();
/// assert!((inside.distance + 0.003).abs() < 1e-5);
/// assert!(inside.normal.distance(Vec3::NEG_Z) < 1e-4);
/// assert!(sdf.sample(Vec3::new(0.5, 0.5, 0.5)).is_none());
/// ```
#[derive(Debug, Clone)]
pub struct BoneSdf {
    origin: Vec3,
    cell: f32,
    inv_cell: f32,
    dims: IVec3,
    band: f32,
    /// Signed distance of each node, clamped to ±`band`.
    dist: Vec<f32>,
    /// Nearest triangle of each node within the band (`u32::MAX` beyond it).
    nearest: Vec<u32>,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per triangle: face normal, then the pseudo-normals of its three edges.
    face_normals: Vec<[Vec3; 4]>,
    /// Angle-weighted pseudo-normal of each vertex.
    vertex_normals: Vec<Vec3>,
}

/// Within this share of a cell of the surface a sample's normal is its closest feature's
/// pseudo-normal, beyond it the direction from the closest point.
const NORMAL_FROM_OFFSET: f32 = 0.25;

impl BoneSdf {
    /// The field of a closed, outward surface, on nodes `cell` apart (m), exact within
    /// `band` (m) of it.
    pub fn new(vertices: &[Vec3], triangles: &[[u32; 3]], cell: f32, band: f32) -> Self {
        let lo = vertices
            .iter()
            .copied()
            .fold(Vec3::splat(f32::MAX), Vec3::min);
        let hi = vertices
            .iter()
            .copied()
            .fold(Vec3::splat(f32::MIN), Vec3::max);
        let pad = Vec3::splat(band + 2.0 * cell);
        let origin = lo - pad;
        let size = (hi + pad) - origin;
        let dims = (size / cell).ceil().as_ivec3() + IVec3::ONE;
        let (face_normals, vertex_normals) = pseudo_normals(vertices, triangles);
        let mut sdf = Self {
            origin,
            cell,
            inv_cell: 1.0 / cell,
            dims,
            band,
            dist: Vec::new(),
            nearest: Vec::new(),
            vertices: vertices.to_vec(),
            triangles: triangles.to_vec(),
            face_normals,
            vertex_normals,
        };
        sdf.fill();
        sdf
    }

    /// Grid node count along each axis.
    pub fn dims(&self) -> [usize; 3] {
        [self.dims.x, self.dims.y, self.dims.z].map(|d| d as usize)
    }

    /// A lower bound on the distance (m) from `p` (rest frame) to the surface, outside
    /// it: positive only where `p` lies surely outside, by at least that much (the
    /// interpolated distance less a cell's diagonal). `None` outside the grid.
    #[inline]
    pub fn clearance(&self, p: Vec3) -> Option<f32> {
        self.interpolated(p).map(|d| d - SQRT_3 * self.cell)
    }

    /// How far from the surface (m) the field's nodes hold exact distances.
    pub fn band(&self) -> f32 {
        self.band
    }

    /// How far from the surface (m) a [`Self::sample`] is exact (from the nearest
    /// triangles); beyond, it is interpolated between nodes.
    pub fn exact_within(&self) -> f32 {
        self.band - 2.0 * self.cell
    }

    #[inline]
    fn node(&self, i: i32, j: i32, k: i32) -> usize {
        (i + self.dims.x * (j + self.dims.y * k)) as usize
    }

    fn node_point(&self, i: i32, j: i32, k: i32) -> Vec3 {
        self.origin + Vec3::new(i as f32, j as f32, k as f32) * self.cell
    }

    /// Exact unsigned distance and nearest triangle within the band (splatting each
    /// triangle over the nodes near it, a slab of z per task), then the sign of every
    /// node from the winding number along its z column.
    fn fill(&mut self) {
        let (nx, ny, nz) = (self.dims.x, self.dims.y, self.dims.z);
        let reach = self.band + self.cell;
        let boxes: Vec<(IVec3, IVec3)> = self
            .triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| self.vertices[i as usize]);
                let lo = p[0].min(p[1]).min(p[2]) - Vec3::splat(reach);
                let hi = p[0].max(p[1]).max(p[2]) + Vec3::splat(reach);
                let a = ((lo - self.origin) * self.inv_cell)
                    .floor()
                    .as_ivec3()
                    .max(IVec3::ZERO);
                let b = ((hi - self.origin) * self.inv_cell)
                    .ceil()
                    .as_ivec3()
                    .min(self.dims - IVec3::ONE);
                (a, b)
            })
            .collect();
        let layer = (nx * ny) as usize;
        let mut unsigned = vec![f32::INFINITY; layer * nz as usize];
        let mut nearest = vec![u32::MAX; layer * nz as usize];
        let this = &*self;
        unsigned
            .par_chunks_mut(layer)
            .zip(nearest.par_chunks_mut(layer))
            .enumerate()
            .for_each(|(k, (ud, nd))| {
                let k = k as i32;
                for (ti, (a, b)) in boxes.iter().enumerate() {
                    if k < a.z || k > b.z {
                        continue;
                    }
                    let t = this.triangles[ti];
                    let [p0, p1, p2] = t.map(|i| this.vertices[i as usize]);
                    for j in a.y..=b.y {
                        for i in a.x..=b.x {
                            let q = this.node_point(i, j, k);
                            let d = closest_point(q, p0, p1, p2).0.distance(q);
                            let n = (i + nx * j) as usize;
                            if d < ud[n] {
                                ud[n] = d;
                                nd[n] = ti as u32;
                            }
                        }
                    }
                }
            });
        let winding = self.column_winding();
        let band = self.band;
        self.dist = unsigned
            .iter()
            .zip(&winding)
            .map(|(&d, &inside)| {
                let d = d.min(band);
                if inside { -d } else { d }
            })
            .collect();
        for (n, d) in nearest.iter_mut().zip(&unsigned) {
            if *d > band {
                *n = u32::MAX;
            }
        }
        self.nearest = nearest;
    }

    /// Whether each node lies inside: the signed crossings of the surface below it along
    /// its z column sum to a non-zero winding number.
    fn column_winding(&self) -> Vec<bool> {
        let (nx, ny, nz) = (
            self.dims.x as usize,
            self.dims.y as usize,
            self.dims.z as usize,
        );
        // Crossings (z, ±1) of each column. Columns sit a hair off the node lattice so
        // that none runs exactly through a mesh vertex or edge (both are on it only by
        // coincidence of the data's own grid).
        let off = Vec3::new(1.37e-6, 2.71e-6, 0.0);
        let mut hits: Vec<Vec<(f32, i8)>> = vec![Vec::new(); nx * ny];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i as usize] - self.origin - off);
            let lo = a.min(b).min(c) * self.inv_cell;
            let hi = a.max(b).max(c) * self.inv_cell;
            let (i0, i1) = (lo.x.ceil().max(0.0) as usize, hi.x.floor() as isize);
            let (j0, j1) = (lo.y.ceil().max(0.0) as usize, hi.y.floor() as isize);
            let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            if area == 0.0 || i1 < 0 || j1 < 0 {
                continue;
            }
            for j in j0..=(j1 as usize).min(ny - 1) {
                for i in i0..=(i1 as usize).min(nx - 1) {
                    let (x, y) = (i as f32 * self.cell, j as f32 * self.cell);
                    let e0 = (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
                    let e1 = (c.x - b.x) * (y - b.y) - (c.y - b.y) * (x - b.x);
                    let e2 = (a.x - c.x) * (y - c.y) - (a.y - c.y) * (x - c.x);
                    let inside = if area > 0.0 {
                        e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0
                    } else {
                        e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0
                    };
                    if inside {
                        let (w1, w2) = (e1 / area, e2 / area);
                        let z = w1 * a.z + w2 * b.z + (1.0 - w1 - w2) * c.z;
                        // Outward normal pointing up: the column leaves the solid.
                        hits[i + nx * j].push((z, if area > 0.0 { -1 } else { 1 }));
                    }
                }
            }
        }
        let mut inside = vec![false; nx * ny * nz];
        for (col, h) in hits.iter_mut().enumerate() {
            if h.is_empty() {
                continue;
            }
            h.sort_by(|p, q| p.0.total_cmp(&q.0));
            let mut w = 0i32;
            let mut next = 0;
            for k in 0..nz {
                let z = k as f32 * self.cell;
                while next < h.len() && h[next].0 < z {
                    w += i32::from(h[next].1);
                    next += 1;
                }
                inside[col + nx * ny * k] = w != 0;
            }
        }
        inside
    }

    /// The cell of the grid holding `p`: its eight nodes (x fastest), their distances,
    /// where `p` lies in it (0 to 1 per axis) and the distance interpolated there. `None`
    /// outside the grid.
    #[inline]
    fn cell_of(&self, p: Vec3) -> Option<([usize; 8], [f32; 8], Vec3, f32)> {
        let g = (p - self.origin) * self.inv_cell;
        let base = g.floor();
        let i = base.as_ivec3();
        if i.cmplt(IVec3::ZERO).any() || i.cmpge(self.dims - IVec3::ONE).any() {
            return None;
        }
        let f = g - base;
        let n000 = self.node(i.x, i.y, i.z);
        let sx = 1usize;
        let sy = self.dims.x as usize;
        let sz = (self.dims.x * self.dims.y) as usize;
        let idx = [
            n000,
            n000 + sx,
            n000 + sy,
            n000 + sx + sy,
            n000 + sz,
            n000 + sx + sz,
            n000 + sy + sz,
            n000 + sx + sy + sz,
        ];
        let d = idx.map(|n| self.dist[n]);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let y0 = lerp(lerp(d[0], d[1], f.x), lerp(d[2], d[3], f.x), f.y);
        let y1 = lerp(lerp(d[4], d[5], f.x), lerp(d[6], d[7], f.x), f.y);
        Some((idx, d, f, lerp(y0, y1, f.z)))
    }

    /// The signed distance at `p` (rest frame) interpolated between the grid's nodes
    /// (exact at them, within a fraction of a cell between them on a smooth surface):
    /// the cheap query, for decisions that tolerate that; `None` outside the grid.
    #[inline]
    pub fn interpolated(&self, p: Vec3) -> Option<f32> {
        self.cell_of(p).map(|c| c.3)
    }

    /// The signed distance and outward normal at `p` (rest frame); `None` outside the
    /// grid, which reaches `band` beyond the surface everywhere.
    #[inline]
    pub fn sample(&self, p: Vec3) -> Option<SdfSample> {
        let (idx, d, f, trilinear) = self.cell_of(p)?;
        let (fx, fy, fz) = (f.x, f.y, f.z);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        if trilinear.abs() > self.exact_within() {
            let gx = lerp(
                lerp(d[1] - d[0], d[3] - d[2], fy),
                lerp(d[5] - d[4], d[7] - d[6], fy),
                fz,
            );
            let gy = lerp(
                lerp(d[2] - d[0], d[3] - d[1], fx),
                lerp(d[6] - d[4], d[7] - d[5], fx),
                fz,
            );
            let gz = lerp(
                lerp(d[4] - d[0], d[5] - d[1], fx),
                lerp(d[6] - d[2], d[7] - d[3], fx),
                fy,
            );
            return Some(SdfSample {
                distance: trilinear,
                normal: Vec3::new(gx, gy, gz).normalize_or_zero(),
                nearest: None,
            });
        }
        // Near the surface: exact, from the nodes' nearest triangles.
        let mut best = (f32::INFINITY, Vec3::ZERO, u32::MAX, Feature::Face);
        let mut seen = [u32::MAX; 8];
        for (s, &n) in idx.iter().enumerate() {
            let t = self.nearest[n];
            if t == u32::MAX || seen[..s].contains(&t) {
                continue;
            }
            seen[s] = t;
            let [a, b, c] = self.triangles[t as usize].map(|v| self.vertices[v as usize]);
            let (q, _, feature) = closest_point(p, a, b, c);
            let d2 = q.distance_squared(p);
            if d2 < best.0 || (d2 == best.0 && t < best.2) {
                best = (d2, q, t, feature);
            }
        }
        if best.2 == u32::MAX {
            return Some(SdfSample {
                distance: trilinear,
                normal: Vec3::ZERO,
                nearest: None,
            });
        }
        let (d2, q, t, feature) = best;
        let pseudo = match feature {
            Feature::Face => self.face_normals[t as usize][0],
            Feature::Edge(e) => self.face_normals[t as usize][1 + e as usize],
            Feature::Vertex(v) => {
                self.vertex_normals[self.triangles[t as usize][v as usize] as usize]
            }
        };
        let dist = d2.sqrt();
        let off = p - q;
        // The winding sign where the eight nodes agree on a side (or lie clearly on
        // one), the closest feature's pseudo-normal where the surface passes between.
        let inside = if d.iter().all(|&x| x < 0.0) || trilinear < -self.cell {
            true
        } else if d.iter().all(|&x| x > 0.0) || trilinear > self.cell {
            false
        } else {
            off.dot(pseudo) < 0.0
        };
        // Very near the surface the offset's direction says little (next to an edge it
        // may lie almost along the surface): the feature's pseudo-normal does.
        let normal = if dist > NORMAL_FROM_OFFSET * self.cell {
            if inside { -off / dist } else { off / dist }
        } else {
            pseudo
        };
        Some(SdfSample {
            distance: if inside { -dist } else { dist },
            normal,
            nearest: Some(q),
        })
    }

    /// The nearest point of the surface to `p` (rest frame) with its signed distance,
    /// exact at any depth: from the field within [`Self::exact_within`] of the surface,
    /// from `tree` (the same surface as a parry mesh) further, the field's sign saying
    /// which side. None when `p` lies more than `within` outside the surface, known
    /// from the field alone where it can tell (the interpolated distance a cell or more
    /// beyond `within`, or outside the grid), so most far points cost one lookup.
    pub fn nearest(&self, tree: &TriMesh, p: Vec3, within: f32) -> Option<SurfacePoint> {
        // The nodes hold exact distances and a distance changes no faster than the
        // point moves, so the interpolated one is within a cell's diagonal of the true:
        // beyond that, farther than `within` for sure, with no triangle looked at.
        if self.clearance(p).is_some_and(|d| d > within) {
            return None;
        }
        let sample = self.sample(p);
        if let Some(s) = sample {
            if let Some(point) = s.nearest
                && s.normal != Vec3::ZERO
            {
                return (s.distance <= within).then_some(SurfacePoint {
                    distance: s.distance,
                    normal: s.normal,
                    point,
                });
            }
            if s.distance - self.cell > within {
                return None;
            }
        } else if within < self.band {
            // The grid reaches `band` beyond the surface everywhere.
            return None;
        }
        let proj = tree.project_local_point(p, false);
        // Outside the field's grid is outside the bone.
        let inside = sample.is_some_and(|s| s.distance < 0.0);
        let off = p - proj.point;
        let d = off.length();
        let n = if d > 0.0 { off / d } else { Vec3::ZERO };
        let (distance, normal) = if inside { (-d, -n) } else { (d, n) };
        (distance <= within).then_some(SurfacePoint {
            distance,
            normal,
            point: proj.point,
        })
    }
}

/// Face normals with the edge pseudo-normals of each triangle (the sum of its two faces'
/// normals), and the angle-weighted pseudo-normal of each vertex.
pub(crate) fn pseudo_normals(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
) -> (Vec<[Vec3; 4]>, Vec<Vec3>) {
    let faces: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    let mut vn = vec![Vec3::ZERO; vertices.len()];
    let mut edges: Vec<((u32, u32), u32)> = Vec::with_capacity(triangles.len() * 3);
    for (ti, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (pa, pb, pc) = (
                vertices[a as usize],
                vertices[b as usize],
                vertices[c as usize],
            );
            let angle = (pb - pa).angle_between(pc - pa);
            if angle.is_finite() {
                vn[a as usize] += faces[ti] * angle;
            }
            edges.push(((a.min(b), a.max(b)), ti as u32));
        }
    }
    edges.sort_unstable();
    let mut out: Vec<[Vec3; 4]> = faces.iter().map(|&f| [f, f, f, f]).collect();
    for w in edges.chunk_by(|x, y| x.0 == y.0) {
        let sum: Vec3 = w.iter().map(|(_, t)| faces[*t as usize]).sum();
        let n = sum.normalize_or_zero();
        for (e, t) in w {
            let tri = triangles[*t as usize];
            let k = (0..3)
                .find(|&k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (a.min(b), a.max(b)) == *e
                })
                .unwrap_or(0);
            out[*t as usize][1 + k] = n;
        }
    }
    (out, vn.into_iter().map(|n| n.normalize_or_zero()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed UV sphere of radius `r`.
    fn sphere(r: f32, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut v = vec![Vec3::new(0.0, 0.0, -r)];
        for i in 1..n {
            let th = std::f32::consts::PI * i as f32 / n as f32;
            for j in 0..2 * n {
                let ph = std::f32::consts::PI * j as f32 / n as f32;
                v.push(Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos()) * r);
            }
        }
        v.push(Vec3::new(0.0, 0.0, r));
        let ring = |i: usize, j: usize| (1 + (i - 1) * 2 * n + j % (2 * n)) as u32;
        let top = v.len() as u32 - 1;
        let mut t = Vec::new();
        for j in 0..2 * n {
            t.push([0, ring(1, j + 1), ring(1, j)]);
            t.push([top, ring(n - 1, j), ring(n - 1, j + 1)]);
        }
        for i in 1..n - 1 {
            for j in 0..2 * n {
                t.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
                t.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
            }
        }
        (v, t)
    }

    #[test]
    fn distances_match_a_sphere_inside_and_out() {
        let (v, t) = sphere(0.03, 24);
        let sdf = BoneSdf::new(&v, &t, 0.002, 0.01);
        for (i, dir) in [
            Vec3::X,
            Vec3::new(0.3, 0.5, -0.8),
            Vec3::new(-0.6, 0.1, 0.4),
        ]
        .iter()
        .enumerate()
        {
            let dir = dir.normalize();
            for r in [0.022f32, 0.028, 0.0299, 0.031, 0.036] {
                let s = sdf.sample(dir * r).unwrap();
                // The mesh is a polyhedron inside the sphere: within its chord sag.
                assert!(
                    (s.distance - (r - 0.03)).abs() < 4e-4,
                    "{i} {r}: {}",
                    s.distance
                );
                assert!(s.normal.dot(dir) > 0.9, "{i} {r}: {}", s.normal);
            }
        }
        assert!(sdf.sample(Vec3::ZERO).unwrap().distance <= -0.01 + 1e-6);
    }

    #[test]
    fn overlapping_tubes_are_inside_where_either_is() {
        let (a, ta) = sphere(0.03, 16);
        let (b, tb) = sphere(0.03, 16);
        let shift = Vec3::X * 0.03;
        let mut v = a.clone();
        v.extend(b.iter().map(|p| *p + shift));
        let mut t = ta.clone();
        let n = a.len() as u32;
        t.extend(tb.iter().map(|x| x.map(|i| i + n)));
        let sdf = BoneSdf::new(&v, &t, 0.002, 0.01);
        // Inside sphere A and outside sphere B, a hair from B's wall (which runs inside
        // A, where a pseudo-normal would call the point outside).
        let p = Vec3::new(-0.0007, 0.0, 0.0);
        assert!(sdf.sample(p).unwrap().distance < 0.0);
        assert!(sdf.sample(Vec3::new(0.07, 0.0, 0.0)).unwrap().distance > 0.0);
    }
}
