//! The fat: Miyazaki's local-shape elastic model (paper, section 4.2, Eqs. 2–4) as shape
//! matching per hexahedron. Each element's goal is its rest shape turned by the rotation
//! of the polar decomposition of `Σ (x_i − c) R_iᵀ` and placed at its current centroid;
//! every free vertex moves toward the mean of its elements' goals by a stiffness `k`.
//! Data are struct-of-arrays in lattice order (slice-major), the rotation is warm-started
//! and extracted branch-free, and element chunks run in parallel.
//!
//! Goals are scattered, not stored: each chunk of consecutive elements adds its corner
//! goals into a buffer over the compact vertex range it touches, and the buffers are
//! summed in chunk order. Chunks are fixed, so results do not depend on the thread count.

use std::sync::Arc;

use crate::par::*;
use glam::{Quat, Vec3, Vec3A};

use super::fat_lanes::{LANES, RestLanes, group_pass, rest_lanes};

/// Vertices per parallel block of the vertex pass.
const BLOCK: usize = 2048;

/// Elements per chunk of the element pass (a multiple of [`LANES`]).
const CHUNK: usize = 512;

/// Consecutive elements and the vertices they touch.
#[derive(Debug)]
struct Chunk {
    /// Elements `first..first + len`.
    first: usize,
    len: usize,
    /// The vertices touched, ascending.
    verts: Vec<u32>,
    /// Each element's corners as indices into `verts`.
    local: Vec<[u16; 8]>,
}

impl Chunk {
    fn new(hexes: &[[u32; 8]], first: usize, len: usize) -> Self {
        let mut verts: Vec<u32> = hexes[first..first + len]
            .iter()
            .flatten()
            .copied()
            .collect();
        verts.sort_unstable();
        verts.dedup();
        let local = hexes[first..first + len]
            .iter()
            .map(|h| h.map(|v| verts.partition_point(|&u| u < v) as u16))
            .collect();
        Self {
            first,
            len,
            verts,
            local,
        }
    }
}

/// A chunk's goal sums in a pass.
#[derive(Debug)]
struct ChunkSum {
    /// Σ goals per vertex of the chunk's `verts`.
    sum: Vec<Vec3A>,
    /// Whether any element of the chunk was active in the last pass.
    used: bool,
}

/// The goal sums of every chunk: work buffers, refilled each pass. A copy of a solver
/// starts without them (they are allocated at its first pass).
#[derive(Debug, Default)]
struct ChunkSums(Vec<ChunkSum>);

impl Clone for ChunkSums {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// What a solver's lattice fixes for good: shared by its copies.
#[derive(Debug)]
struct FatMesh {
    /// Rest corners relative to each element's rest centroid, four elements per group
    /// as SIMD lanes (the kernel's layout).
    rest4: Vec<RestLanes>,
    /// Element chunks of the scatter.
    chunks: Vec<Chunk>,
    /// 1 / number of elements at each vertex (0 for none).
    inv_count: Vec<f32>,
    /// Vertex block → the chunks whose vertex range meets it (CSR, chunk order).
    block_start: Vec<u32>,
    block_chunks: Vec<u32>,
    /// Vertex → element corners (`hex * 8 + corner`), CSR.
    inc_start: Vec<u32>,
    inc: Vec<u32>,
}

/// The shape-matching state of a hexahedral lattice. A copy shares the lattice (rest
/// shape, elements, their layout) and owns the changing state (positions, rotations,
/// what is relaxed): a backup or checkpoint is a clone.
#[derive(Debug, Clone)]
pub struct FatSolver {
    /// Rest vertex positions.
    pub rest: Arc<[Vec3]>,
    /// Current vertex positions.
    pub x: Vec<Vec3>,
    /// Hexahedra (vertex indices).
    pub hexes: Arc<[[u32; 8]]>,
    /// Volume of each element at rest (m³).
    pub rest_volume: Arc<[f64]>,
    mesh: Arc<FatMesh>,
    /// Goal sums of each chunk of [`FatMesh::chunks`].
    sums: ChunkSums,
    /// Current rotation of each element (warm start).
    pub rot: Vec<Quat>,
    /// Whether a vertex is moved by the solver (false: set by a constraint, or outside
    /// the region being relaxed).
    pub free: Vec<bool>,
    /// Whether an element's goal is computed (every element touching a free vertex).
    pub active: Vec<bool>,
}

impl FatSolver {
    /// A solver at rest for a lattice.
    pub fn new(rest: &[Vec3], hexes: &[[u32; 8]]) -> Self {
        let rel: Vec<[Vec3; 8]> = hexes.iter().map(|h| relative_corners(rest, h)).collect();
        let (count, inc) = super::incidence::vertex_corners(rest.len(), hexes);
        let rest_volume = hexes
            .iter()
            .map(|h| crate::lattice::hex_volume_points(&h.map(|i| rest[i as usize].as_dvec3())))
            .collect();
        // At most 8 × CHUNK corners: local indices fit u16.
        let chunks: Vec<Chunk> = (0..hexes.len())
            .step_by(CHUNK)
            .map(|first| Chunk::new(hexes, first, CHUNK.min(hexes.len() - first)))
            .collect();
        let (block_start, block_chunks) = block_lists(&chunks, rest.len());
        let rest4 = rel.chunks(LANES).map(rest_lanes).collect();
        let inv_count = (0..rest.len())
            .map(|v| match count[v + 1] - count[v] {
                0 => 0.0,
                n => 1.0 / n as f32,
            })
            .collect();
        Self {
            rest_volume,
            rest: rest.into(),
            x: rest.to_vec(),
            hexes: hexes.into(),
            mesh: Arc::new(FatMesh {
                rest4,
                chunks,
                inv_count,
                block_start,
                block_chunks,
                inc_start: count,
                inc,
            }),
            sums: ChunkSums::default(),
            rot: vec![Quat::IDENTITY; hexes.len()],
            free: vec![true; rest.len()],
            active: vec![true; hexes.len()],
        }
    }

    /// A block of `nx × ny × nz` cubic cells of edge `cell` (m), for tests and benchmarks.
    ///
    /// ```
    /// use myoslice::tissue::FatSolver;
    /// let mut s = FatSolver::grid(20, 7, 6, 0.01);
    /// assert_eq!(s.len(), 840);
    /// s.iterate(0.5);
    /// ```
    pub fn grid(nx: usize, ny: usize, nz: usize, cell: f32) -> Self {
        let idx = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
        let mut v = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    v.push(Vec3::new(i as f32, j as f32, k as f32) * cell);
                }
            }
        }
        let mut h = Vec::with_capacity(nx * ny * nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    h.push([
                        idx(i, j, k),
                        idx(i + 1, j, k),
                        idx(i + 1, j + 1, k),
                        idx(i, j + 1, k),
                        idx(i, j, k + 1),
                        idx(i + 1, j, k + 1),
                        idx(i + 1, j + 1, k + 1),
                        idx(i, j + 1, k + 1),
                    ]);
                }
            }
        }
        Self::new(&v, &h)
    }

    /// One shape-matching iteration: element goals, then every free vertex moves a
    /// fraction `k` toward the mean of its goals.
    ///
    /// Each free vertex's goals come from all its elements, which must then be active
    /// (as [`Self::restrict_to`] and [`Self::release`] leave them).
    pub fn iterate(&mut self, k: f32) {
        debug_assert!(
            (0..self.x.len())
                .filter(|&v| self.free[v])
                .all(|v| self.elements_of(v).all(|e| self.active[e])),
            "a free vertex has an inactive element"
        );
        self.scatter_goals();
        let mesh = &*self.mesh;
        let (free, inv, sums) = (&self.free, &mesh.inv_count, &self.sums.0);
        let (chunks, start, list) = (&mesh.chunks, &mesh.block_start, &mesh.block_chunks);
        self.x
            .par_chunks_mut(BLOCK)
            .enumerate()
            .for_each(|(b, xs)| {
                let base = b * BLOCK;
                // Σ goals of this block's vertices, chunk by chunk in order (deterministic).
                let mut acc = [Vec3A::ZERO; BLOCK];
                for &ci in &list[start[b] as usize..start[b + 1] as usize] {
                    let (c, cs) = (&chunks[ci as usize], &sums[ci as usize]);
                    if !cs.used {
                        continue;
                    }
                    let from = c.verts.partition_point(|&v| (v as usize) < base);
                    let to = c.verts.partition_point(|&v| (v as usize) < base + xs.len());
                    for (v, g) in c.verts[from..to].iter().zip(&cs.sum[from..to]) {
                        acc[*v as usize - base] += *g;
                    }
                }
                for (o, (x, g)) in xs.iter_mut().zip(&acc).enumerate() {
                    let v = base + o;
                    if free[v] && inv[v] > 0.0 {
                        let g = Vec3::from(*g * inv[v]);
                        *x += (g - *x) * k;
                    }
                }
            });
    }

    /// Every active element's goals (rest shape turned by its warm-started rotation, one
    /// trigonometry-free step per pass, placed at its centroid), summed per vertex into
    /// its chunk's buffer.
    fn scatter_goals(&mut self) {
        let mesh = &*self.mesh;
        if self.sums.0.len() != mesh.chunks.len() {
            self.sums.0 = mesh
                .chunks
                .iter()
                .map(|c| ChunkSum {
                    sum: vec![Vec3A::ZERO; c.verts.len()],
                    used: false,
                })
                .collect();
        }
        let (x, hexes, rest4, active) = (&self.x, &self.hexes, &mesh.rest4, &self.active);
        let rot = &mut self.rot;
        // Each chunk owns its elements' rotations: split them alongside.
        let mut rots: Vec<&mut [Quat]> = Vec::with_capacity(mesh.chunks.len());
        let mut rest = rot.as_mut_slice();
        for c in &mesh.chunks {
            let (head, tail) = rest.split_at_mut(c.len);
            rots.push(head);
            rest = tail;
        }
        mesh.chunks
            .par_iter()
            .zip(self.sums.0.par_iter_mut())
            .zip(rots.into_par_iter())
            .for_each(|((c, cs), rots)| {
                cs.used = active[c.first..c.first + c.len].iter().any(|a| *a);
                if !cs.used {
                    return;
                }
                cs.sum.iter_mut().for_each(|s| *s = Vec3A::ZERO);
                for o in (0..c.len).step_by(LANES) {
                    let e = c.first + o;
                    let n = LANES.min(c.len - o);
                    let act = &active[e..e + n];
                    if act.iter().any(|a| *a) {
                        group_pass(
                            x,
                            &hexes[e..e + n],
                            &rest4[e / LANES],
                            &mut rots[o..o + n],
                            act,
                            &c.local[o..o + n],
                            &mut cs.sum,
                        );
                    }
                }
            });
    }

    /// Relaxes only where the shape can change: elements with a `moving` vertex and
    /// their corners (elsewhere the lattice moves rigidly and shape matching would
    /// leave it as it is). Marks the corners free and every element touching one active.
    pub fn restrict_to(&mut self, moving: &[bool]) {
        self.free.iter_mut().for_each(|f| *f = false);
        for h in self.hexes.iter() {
            if h.iter().any(|&v| moving[v as usize]) {
                for &v in h {
                    self.free[v as usize] = true;
                }
            }
        }
        for (a, h) in self.active.iter_mut().zip(self.hexes.iter()) {
            *a = h.iter().any(|&v| self.free[v as usize]);
        }
    }

    /// Relaxes everywhere again (see [`Self::restrict_to`]).
    pub fn release(&mut self) {
        self.free.iter_mut().for_each(|f| *f = true);
        self.active.iter_mut().for_each(|a| *a = true);
    }

    /// The elements with vertex `v` as a corner.
    pub fn elements_of(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        let m = &*self.mesh;
        let (s, e) = (m.inc_start[v] as usize, m.inc_start[v + 1] as usize);
        m.inc[s..e].iter().map(|&c| (c >> 3) as usize)
    }

    /// Rest-relative corner vectors of element `e`.
    pub fn rest_relative(&self, e: usize) -> [Vec3; 8] {
        relative_corners(&self.rest, &self.hexes[e])
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.hexes.len()
    }

    /// True without elements.
    pub fn is_empty(&self) -> bool {
        self.hexes.is_empty()
    }
}

/// The corners of hexahedron `h` relative to its centroid.
fn relative_corners(pos: &[Vec3], h: &[u32; 8]) -> [Vec3; 8] {
    let p = h.map(|i| pos[i as usize]);
    let c = p.iter().copied().sum::<Vec3>() / 8.0;
    p.map(|q| q - c)
}

/// For each block of [`BLOCK`] vertices, the chunks whose vertex range meets it.
fn block_lists(chunks: &[Chunk], n_vertices: usize) -> (Vec<u32>, Vec<u32>) {
    let n_blocks = n_vertices.div_ceil(BLOCK);
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_blocks];
    for (ci, c) in chunks.iter().enumerate() {
        let mut last = usize::MAX;
        for &v in &c.verts {
            let b = v as usize / BLOCK;
            if b != last && b < n_blocks {
                lists[b].push(ci as u32);
                last = b;
            }
        }
    }
    let mut start = vec![0u32];
    let mut all = Vec::new();
    for l in lists {
        all.extend(l);
        start.push(all.len() as u32);
    }
    (start, all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tissue::polar::rotation_step;
    use glam::Mat3;

    #[test]
    fn the_four_lane_kernel_matches_the_scalar_shape_matching_step() {
        // 27 elements: six full groups of four and a partial one; some inactive.
        let mut s = FatSolver::grid(3, 3, 3, 0.01);
        for (i, p) in s.x.iter_mut().enumerate() {
            *p += Vec3::new((i % 5) as f32, (i % 3) as f32, (i % 7) as f32) * 0.0007;
        }
        for (e, q) in s.rot.iter_mut().enumerate() {
            *q = Quat::from_axis_angle(Vec3::new(1.0, 0.5, 0.2).normalize(), 0.02 * e as f32);
        }
        // As `restrict_to` leaves it: a vertex of an idle element is not free.
        for e in [5, 25] {
            s.active[e] = false;
            for v in s.hexes[e] {
                s.free[v as usize] = false;
            }
        }
        let (x0, rot0) = (s.x.clone(), s.rot.clone());
        // The scalar reference: goals per element, the mean at each vertex.
        let mut sum = vec![Vec3::ZERO; x0.len()];
        let mut rot = rot0.clone();
        for (e, h) in s.hexes.iter().enumerate() {
            if !s.active[e] {
                continue;
            }
            let p = h.map(|v| x0[v as usize]);
            let c = p.iter().copied().sum::<Vec3>() / 8.0;
            let r = s.rest_relative(e);
            let a = Mat3::from_cols(
                (0..8).map(|i| (p[i] - c) * r[i].x).sum(),
                (0..8).map(|i| (p[i] - c) * r[i].y).sum(),
                (0..8).map(|i| (p[i] - c) * r[i].z).sum(),
            );
            let (q, m) = rotation_step(&a, rot0[e]);
            rot[e] = q;
            for i in 0..8 {
                sum[h[i] as usize] += c + m * r[i];
            }
        }
        s.iterate(0.5);
        assert!(s.free.iter().filter(|f| **f).count() > 20);
        for (e, (a, b)) in s.rot.iter().zip(&rot).enumerate() {
            assert!(a.dot(*b).abs() > 1.0 - 1e-6, "element {e}: {a} vs {b}");
        }
        for v in 0..x0.len() {
            let n = s.elements_of(v).count() as f32;
            let want = if s.free[v] {
                x0[v] + (sum[v] / n - x0[v]) * 0.5
            } else {
                x0[v]
            };
            assert!(
                s.x[v].distance(want) < 1e-6,
                "vertex {v}: {} vs {want}",
                s.x[v]
            );
        }
    }

    #[test]
    fn a_perturbed_block_returns_to_its_rest_shape_up_to_a_rigid_motion() {
        let mut s = FatSolver::grid(4, 3, 3, 0.01);
        let v = s.rest.clone();
        // Rotate everything, then perturb.
        let q = Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), 0.8);
        for (i, p) in s.x.iter_mut().enumerate() {
            let jitter = Vec3::new(
                ((i * 7) % 5) as f32,
                ((i * 3) % 7) as f32,
                ((i * 11) % 3) as f32,
            ) * 0.001;
            *p = q * *p + Vec3::new(0.1, -0.2, 0.05) + jitter;
        }
        for _ in 0..300 {
            s.iterate(0.5);
        }
        // Pairwise distances are back to rest.
        let mut worst = 0.0f32;
        for i in (0..v.len()).step_by(7) {
            for j in (0..v.len()).step_by(5) {
                let d0 = v[i].distance(v[j]);
                let d = s.x[i].distance(s.x[j]);
                worst = worst.max((d - d0).abs());
            }
        }
        assert!(worst < 1e-4, "largest distance error {worst} m");
    }
}
