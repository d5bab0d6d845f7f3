//! The fat: Miyazaki's local-shape elastic model (paper, section 4.2, Eqs. 2–4) as shape
//! matching per hexahedron. Each element's goal is its rest shape turned by the rotation
//! of the polar decomposition of `Σ (x_i − c) R_iᵀ` and placed at its current centroid;
//! every free vertex moves toward the mean of its elements' goals by a stiffness `k`.
//! Data are struct-of-arrays in lattice order (slice-major), the rotation is warm-started
//! and extracted branch-free, and element blocks run in parallel.

use glam::{Mat3, Quat, Vec3};
use rayon::prelude::*;

use super::polar::rotation_step;

/// Elements per parallel block.
const BLOCK: usize = 2048;

/// The shape-matching state of a hexahedral lattice.
#[derive(Debug, Clone)]
pub struct FatSolver {
    /// Rest vertex positions.
    pub rest: Vec<Vec3>,
    /// Current vertex positions.
    pub x: Vec<Vec3>,
    /// Hexahedra (vertex indices).
    pub hexes: Vec<[u32; 8]>,
    /// Rest positions relative to each element's rest centroid.
    rel: Vec<[Vec3; 8]>,
    /// Current rotation of each element (warm start).
    pub rot: Vec<Quat>,
    /// Goal position of each element corner (scratch).
    goals: Vec<[Vec3; 8]>,
    /// Vertex → element corners (`hex * 8 + corner`), CSR.
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Whether a vertex is moved by the solver (false: set by a constraint, or outside
    /// the region being relaxed).
    pub free: Vec<bool>,
    /// Whether an element's goal is computed (every element touching a free vertex).
    pub active: Vec<bool>,
    /// Volume of each element at rest (m³).
    pub rest_volume: Vec<f64>,
}

impl FatSolver {
    /// A solver at rest for a lattice.
    pub fn new(rest: &[Vec3], hexes: &[[u32; 8]]) -> Self {
        let rel = hexes
            .iter()
            .map(|h| {
                let p = h.map(|i| rest[i as usize]);
                let c = p.iter().copied().sum::<Vec3>() / 8.0;
                p.map(|q| q - c)
            })
            .collect();
        let mut count = vec![0u32; rest.len() + 1];
        for h in hexes {
            for &v in h {
                count[v as usize + 1] += 1;
            }
        }
        for i in 0..rest.len() {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut inc = vec![0u32; hexes.len() * 8];
        for (e, h) in hexes.iter().enumerate() {
            for (k, &v) in h.iter().enumerate() {
                inc[fill[v as usize] as usize] = (e * 8 + k) as u32;
                fill[v as usize] += 1;
            }
        }
        let rest_volume = hexes
            .iter()
            .map(|h| crate::lattice::hex_volume_points(&h.map(|i| rest[i as usize].as_dvec3())))
            .collect();
        Self {
            rest_volume,
            rest: rest.to_vec(),
            x: rest.to_vec(),
            hexes: hexes.to_vec(),
            rel,
            rot: vec![Quat::IDENTITY; hexes.len()],
            goals: vec![[Vec3::ZERO; 8]; hexes.len()],
            inc_start: count,
            inc,
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
    pub fn iterate(&mut self, k: f32) {
        self.compute_goals();
        let goals = &self.goals;
        let (inc_start, inc) = (&self.inc_start, &self.inc);
        let free = &self.free;
        self.x
            .par_chunks_mut(BLOCK)
            .enumerate()
            .for_each(|(b, chunk)| {
                for (o, x) in chunk.iter_mut().enumerate() {
                    let v = b * BLOCK + o;
                    if !free[v] {
                        continue;
                    }
                    let (s, e) = (inc_start[v] as usize, inc_start[v + 1] as usize);
                    if s == e {
                        continue;
                    }
                    let mut g = Vec3::ZERO;
                    for &c in &inc[s..e] {
                        g += goals[(c >> 3) as usize][(c & 7) as usize];
                    }
                    let g = g / (e - s) as f32;
                    *x += (g - *x) * k;
                }
            });
    }

    /// Goals of every element from the current positions (rotation warm-started, one
    /// trigonometry-free iteration per pass).
    pub fn compute_goals(&mut self) {
        let x = &self.x;
        let hexes = &self.hexes;
        let rel = &self.rel;
        let active = &self.active;
        self.goals
            .par_chunks_mut(BLOCK)
            .zip(self.rot.par_chunks_mut(BLOCK))
            .enumerate()
            .for_each(|(b, (goals, rots))| {
                let base = b * BLOCK;
                for (o, (g, q)) in goals.iter_mut().zip(rots.iter_mut()).enumerate() {
                    let e = base + o;
                    if !active[e] {
                        continue;
                    }
                    let h = &hexes[e];
                    let r = &rel[e];
                    let mut p = [Vec3::ZERO; 8];
                    let mut c = Vec3::ZERO;
                    for k in 0..8 {
                        p[k] = x[h[k] as usize];
                        c += p[k];
                    }
                    c *= 0.125;
                    let (mut a0, mut a1, mut a2) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                    for k in 0..8 {
                        let d = p[k] - c;
                        a0 += d * r[k].x;
                        a1 += d * r[k].y;
                        a2 += d * r[k].z;
                    }
                    let (q2, m) = rotation_step(&Mat3::from_cols(a0, a1, a2), *q);
                    *q = q2;
                    for k in 0..8 {
                        g[k] = c + m * r[k];
                    }
                }
            });
    }

    /// Relaxes only where the shape can change: elements with a `moving` vertex and
    /// their corners (elsewhere the lattice moves rigidly and shape matching would
    /// leave it as it is). Marks the corners free and every element touching one active.
    pub fn restrict_to(&mut self, moving: &[bool]) {
        self.free.iter_mut().for_each(|f| *f = false);
        for h in &self.hexes {
            if h.iter().any(|&v| moving[v as usize]) {
                for &v in h {
                    self.free[v as usize] = true;
                }
            }
        }
        for (a, h) in self.active.iter_mut().zip(&self.hexes) {
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
        let (s, e) = (self.inc_start[v] as usize, self.inc_start[v + 1] as usize);
        self.inc[s..e].iter().map(|&c| (c >> 3) as usize)
    }

    /// Rest-relative corner vectors of element `e`.
    pub fn rest_relative(&self, e: usize) -> &[Vec3; 8] {
        &self.rel[e]
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

#[cfg(test)]
mod tests {
    use super::*;

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
