//! The fat: Miyazaki's local-shape elastic model (paper, section 4.2, Eqs. 2–4) as shape
//! matching per hexahedron. Each element's goal is its rest shape turned by the rotation
//! of the polar decomposition of `Σ (x_i − c) R_iᵀ` and placed at its current centroid;
//! every free vertex moves toward the mean of its elements' goals by a stiffness `k`.
//! Data are struct-of-arrays in lattice order (slice-major), the rotation is warm-started
//! and extracted branch-free, and element blocks run in parallel.

use glam::{Mat3, Quat, Vec3};
use rayon::prelude::*;

use super::polar::{covariance, extract_rotation};

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
    /// Whether a vertex is moved by the solver (false: set by a constraint).
    pub free: Vec<bool>,
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
        Self {
            rest: rest.to_vec(),
            x: rest.to_vec(),
            hexes: hexes.to_vec(),
            rel,
            rot: vec![Quat::IDENTITY; hexes.len()],
            goals: vec![[Vec3::ZERO; 8]; hexes.len()],
            inc_start: count,
            inc,
            free: vec![true; rest.len()],
        }
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

    /// Goals of every element from the current positions (rotation warm-started).
    pub fn compute_goals(&mut self) {
        let x = &self.x;
        let hexes = &self.hexes;
        let rel = &self.rel;
        self.goals
            .par_chunks_mut(BLOCK)
            .zip(self.rot.par_chunks_mut(BLOCK))
            .enumerate()
            .for_each(|(b, (goals, rots))| {
                for (o, (g, q)) in goals.iter_mut().zip(rots.iter_mut()).enumerate() {
                    let e = b * BLOCK + o;
                    let h = &hexes[e];
                    let r = &rel[e];
                    let p = h.map(|i| x[i as usize]);
                    let c = (p[0] + p[1] + p[2] + p[3] + p[4] + p[5] + p[6] + p[7]) * 0.125;
                    let d = p.map(|pi| pi - c);
                    let a = covariance(&d, r);
                    *q = extract_rotation(&a, *q, 1);
                    let m = Mat3::from_quat(*q);
                    for k in 0..8 {
                        g[k] = c + m * r[k];
                    }
                }
            });
    }

    /// Goals of the listed elements only.
    pub fn compute_goals_for(&mut self, elements: &[usize]) {
        for &e in elements {
            let h = self.hexes[e];
            let r = &self.rel[e];
            let p = h.map(|i| self.x[i as usize]);
            let c = p.iter().copied().sum::<Vec3>() / 8.0;
            let d = p.map(|pi| pi - c);
            let a = covariance(&d, r);
            let q = extract_rotation(&a, self.rot[e], 8);
            self.rot[e] = q;
            let m = Mat3::from_quat(q);
            for k in 0..8 {
                self.goals[e][k] = c + m * r[k];
            }
        }
    }

    /// Goal of corner `k` of element `e` (after a goals pass).
    pub fn goal(&self, e: usize, k: usize) -> Vec3 {
        self.goals[e][k]
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

    fn block(nx: usize, ny: usize, nz: usize) -> (Vec<Vec3>, Vec<[u32; 8]>) {
        let idx = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
        let mut v = Vec::new();
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    v.push(Vec3::new(i as f32, j as f32, k as f32) * 0.01);
                }
            }
        }
        let mut h = Vec::new();
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
        (v, h)
    }

    #[test]
    fn a_perturbed_block_returns_to_its_rest_shape_up_to_a_rigid_motion() {
        let (v, h) = block(4, 3, 3);
        let mut s = FatSolver::new(&v, &h);
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
