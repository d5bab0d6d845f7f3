//! The chain's motion (paper Eq. 1): segment tensions, the implicit step of its points
//! inside their cones, a chain carried rigidly by one bone, and the forces on the bones.

use glam::{Mat3, Vec3};

use super::Tether;
use super::chain::{BodyFrames, MuscleChain, SegmentGeom, clamp_depth, project_into_cone};
use crate::body::BodyId;

/// Work buffers of [`MuscleChain::advance`], kept to avoid allocating every step.
#[derive(Debug, Clone, Default)]
pub struct ChainScratch {
    f: Vec<Vec3>,
    kseg: Vec<f32>,
    c: Vec<f32>,
    d: Vec<Vec3>,
    dv: Vec<Vec3>,
    /// Tether stiffness of each point (N/m, 0 for none).
    kt: Vec<f32>,
}

impl ChainScratch {
    /// Every buffer at length `n` (contents are overwritten before use).
    fn fit(&mut self, n: usize) {
        if self.f.len() == n {
            return;
        }
        for v in [&mut self.kseg, &mut self.c, &mut self.kt] {
            v.resize(n, 0.0);
        }
        for v in [&mut self.f, &mut self.d, &mut self.dv] {
            v.resize(n, Vec3::ZERO);
        }
    }
}

/// Forces of one chain step on its end points (world force, world point).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndForces {
    /// Force on the origin body.
    pub origin: Vec3,
    /// Force on the insertion body.
    pub insertion: Vec3,
}

/// How the chain's segments pull.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainLoad {
    /// Contraction force C along every segment (N).
    pub contraction: f32,
    /// Spring constant per unit segment length: k_i = stiffness / rest_i (N).
    pub stiffness: f32,
    /// When true (Hill mode), belly springs only spread the points: their rest lengths
    /// follow the belly's current length, and tendons carry no spring.
    pub neutral_springs: bool,
    /// Gravity (m/s²).
    pub gravity: Vec3,
    /// The tether of an unloaded chain (beyond the paper): each cone-anchored point is
    /// pulled toward its rest place on its bone by `stiffness` (N/m) times the share of
    /// `release` (N) the contraction force falls short of; off from `release` up.
    pub tether: Tether,
}

impl MuscleChain {
    /// Tension of segment `i` (N, positive pulling its ends together) and its axial
    /// spring constant (N/m).
    #[inline(always)]
    fn tension(
        &self,
        i: usize,
        g: &SegmentGeom,
        load: &ChainLoad,
        belly_scale: f32,
        damping: f32,
    ) -> (f32, f32) {
        let rate = -(self.v[i].dot(g.dir_a) + self.v[i + 1].dot(g.dir_b));
        let rest = self.rest_len[i];
        let (k, neutral) = if load.neutral_springs {
            // Hill mode: tendons carry no spring; belly springs only spread the points.
            let k = if self.tendon[i] {
                0.0
            } else {
                load.stiffness / rest.max(5e-3)
            };
            (k, rest * belly_scale)
        } else {
            (load.stiffness / rest.max(5e-3), rest)
        };
        (
            k * (g.length - neutral) + damping * rate + load.contraction,
            k,
        )
    }

    /// Whether every point of the chain moves with one body (no knee crossing, no cone on
    /// the other body): then an unloaded chain is carried rigidly.
    pub fn single_body(&self) -> Option<BodyId> {
        let b = self.origin.body;
        let on_b = if self.bodies.len() == self.x.len() {
            self.bodies.iter().all(|&p| p == b)
        } else {
            (0..self.x.len()).all(|i| self.body_of_point(i) == b)
        };
        on_b.then_some(b)
    }

    /// Carries the whole chain rigidly with body `b` from `from` to `to`.
    pub fn carry(&mut self, b: BodyId, from: &BodyFrames, to: &BodyFrames, dt: f32) {
        let (q0, t0) = match b {
            BodyId::Thigh => from.thigh,
            BodyId::Shank => from.shank,
        };
        let (q1, t1) = match b {
            BodyId::Thigh => to.thigh,
            BodyId::Shank => to.shank,
        };
        if q0 == q1 && t0 == t1 {
            self.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
            return;
        }
        // The rigid motion from one pose to the other, composed once.
        let q = q1 * q0.inverse();
        let t = t1 - q * t0;
        let (m, inv_dt) = (Mat3::from_quat(q), 1.0 / dt);
        for i in 0..self.x.len() {
            let p = m * self.x[i] + t;
            self.v[i] = (p - self.x[i]) * inv_dt;
            self.x[i] = p;
        }
        self.refresh();
    }

    /// Advances the interior points by `dt` while the bodies move to `to`:
    /// Eq. 1 with gravity, integrated by linearly implicit (backward) Euler so that stiff
    /// springs and large contraction forces stay stable at the 1 kHz step, then the cone
    /// projection (one step: backward Euler is stable at any step).
    pub fn advance(&mut self, dt: f32, to: &BodyFrames, load: &ChainLoad) {
        let n = self.x.len();
        if n < 3 {
            self.attach_ends(to);
            return;
        }
        let (h, inv_h) = (dt, 1.0 / dt);
        let damping = self.critical_damping(load);
        let mut sc = std::mem::take(&mut self.scratch);
        sc.fit(n);
        // The bodies' rotations as matrices, built once: the pinned points, the tether's
        // rest places and the cones move with them.
        let thigh = (Mat3::from_quat(to.thigh.0), to.thigh.1);
        let shank = (Mat3::from_quat(to.shank.0), to.shank.1);
        let pose = |b: BodyId| match b {
            BodyId::Thigh => thigh,
            BodyId::Shank => shank,
        };
        let place = |b: BodyId, p: Vec3| {
            let (m, t) = pose(b);
            m * p + t
        };
        // The pinned points move with their bodies; their velocity is that motion.
        let old_ends = (self.x[0], self.x[n - 1]);
        self.x[0] = place(self.origin.body, self.origin.rest);
        self.x[n - 1] = place(self.insertion.body, self.insertion.rest);
        self.v[0] = (self.x[0] - old_ends.0) * inv_h;
        self.v[n - 1] = (self.x[n - 1] - old_ends.1) * inv_h;
        for (i, a) in &self.vias {
            let p = place(a.body, a.rest);
            self.v[*i] = (p - self.x[*i]) * inv_h;
            self.x[*i] = p;
        }
        self.refresh_pinned();
        let belly_scale = if load.neutral_springs {
            self.belly_length() / self.belly_rest.max(1e-6)
        } else {
            1.0
        };
        sc.f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for i in 0..n - 1 {
            let g = self.geom[i];
            let (t, k_ax) = self.tension(i, &g, load, belly_scale, damping);
            sc.f[i] += g.dir_a * t;
            sc.f[i + 1] += g.dir_b * t;
            // Isotropic bound of the segment stiffness: the axial spring or the transverse
            // stiffness of a string under tension (never negative), whichever is larger; a
            // scalar tridiagonal system, slightly over-damping the softer direction,
            // stable for any step.
            sc.kseg[i] = k_ax.max(t.max(0.0) / g.length.max(1e-4));
        }
        for i in 1..n - 1 {
            if self.mass[i] > 0.0 {
                sc.f[i] += load.gravity * self.mass[i];
            }
        }
        let tether = load.tether.at(load.contraction);
        sc.kt.fill(0.0);
        if tether > 0.0 {
            for i in 1..n - 1 {
                if let (true, Some(c)) = (self.mass[i] > 0.0, &self.cones[i]) {
                    sc.f[i] += (place(c.body, c.rest) - self.x[i]) * tether;
                    sc.kt[i] = tether;
                }
            }
        }
        self.solve_implicit(h, damping, &mut sc);
        for i in 1..n - 1 {
            if self.mass[i] <= 0.0 {
                continue; // pinned via point
            }
            let old = self.x[i];
            self.v[i] += sc.dv[i];
            self.x[i] += self.v[i] * h;
            if let Some(c) = self.cones[i] {
                let (apex, axis) = (place(c.body, c.apex), pose(c.body).0 * c.axis);
                let p = project_into_cone(self.x[i], apex, axis, self.cone_cos_tan);
                self.x[i] = clamp_depth(p, apex, c.depth);
                // Position-based correction: the velocity follows the projected motion.
                self.v[i] = (self.x[i] - old) * inv_h;
            }
        }
        self.update_wrap();
        self.scratch = sc;
    }

    /// Critical damping of the stiffest mode of the lightest point.
    fn critical_damping(&self, load: &ChainLoad) -> f32 {
        let n = self.x.len();
        let m_min = self.mass[1..n - 1]
            .iter()
            .copied()
            .filter(|&m| m > 0.0)
            .fold(f32::INFINITY, f32::min)
            .max(1e-6);
        let l_min = self
            .rest_len
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
            .max(5e-3);
        let k_max = load.stiffness / l_min + load.contraction.abs() / l_min;
        (k_max * m_min).sqrt()
    }

    /// Solves `(M + h·D + h²·K) Δv = h (f − h·K·v)` (K = −∂f/∂x, the stiffness) over the
    /// interior points, with the isotropic segment stiffness and the tether (scalar
    /// tridiagonal; pinned points have Δv = 0), into `sc.dv`.
    fn solve_implicit(&self, h: f32, damping: f32, sc: &mut ChainScratch) {
        let n = self.x.len();
        let pinned = |j: usize| j == 0 || j == n - 1 || self.mass[j] <= 0.0;
        let dmp = h * damping;
        let hh = h * h;
        // Forward elimination (Thomas) while the rows are built; row 0 and n − 1 are
        // pinned (Δv = 0).
        sc.c[0] = 0.0;
        sc.d[0] = Vec3::ZERO;
        for i in 1..n - 1 {
            let (kl, kr) = (sc.kseg[i - 1], sc.kseg[i]);
            let (diag, lower, upper, rhs) = if pinned(i) {
                (1.0, 0.0, 0.0, Vec3::ZERO)
            } else {
                // The tether pulls toward a place on a bone (at the step's end pose), not
                // toward a neighbour: its stiffness is on the diagonal only.
                let kt = sc.kt[i];
                let kv = (self.v[i - 1] - self.v[i]) * kl + (self.v[i + 1] - self.v[i]) * kr
                    - self.v[i] * kt;
                (
                    self.mass[i] + 2.0 * dmp + (kl + kr + kt) * hh,
                    if pinned(i - 1) { 0.0 } else { -dmp - kl * hh },
                    if pinned(i + 1) { 0.0 } else { -dmp - kr * hh },
                    (sc.f[i] + kv * h) * h,
                )
            };
            let inv = 1.0 / (diag - lower * sc.c[i - 1]);
            sc.c[i] = inv * upper;
            sc.d[i] = (rhs - sc.d[i - 1] * lower) * inv;
        }
        sc.dv[n - 1] = Vec3::ZERO;
        let mut sum = Vec3::ZERO;
        for i in (1..n - 1).rev() {
            let v = sc.d[i] - sc.dv[i + 1] * sc.c[i];
            sc.dv[i] = v;
            sum += v;
        }
        // A non-finite change (a degenerate row) is dropped and not passed on to the
        // points before it. Checked once per chain (a NaN or infinity anywhere makes the
        // sum non-finite); only then is the substitution redone point by point.
        if !sum.is_finite() {
            for i in (1..n - 1).rev() {
                let v = sc.d[i] - sc.dv[i + 1] * sc.c[i];
                sc.dv[i] = if v.is_finite() { v } else { Vec3::ZERO };
            }
        }
    }

    /// Lets the chain settle at rest under a steady contraction force `tension` (N),
    /// with the bones still, then takes the settled shape as its rest shape. A muscle's
    /// centre line from the slices is not in equilibrium under tension; settling first
    /// keeps that straightening out of the simulated fibre length.
    pub fn settle(&mut self, frames: &BodyFrames, tension: f32, stiffness: f32, gravity: Vec3) {
        let load = ChainLoad {
            contraction: tension,
            stiffness,
            neutral_springs: true,
            gravity,
            // The rest places are what settling finds.
            tether: Tether::default(),
        };
        for _ in 0..200 {
            self.advance(1e-3, frames, &load);
            for v in &mut self.v {
                *v *= 0.5;
            }
        }
        self.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
        let x = std::mem::take(&mut self.x);
        self.set_rest_places(&x, frames);
        self.x = x;
        for i in 0..self.x.len() - 1 {
            self.rest_len[i] = self.segment(i).length.max(1e-4);
        }
        self.belly_rest = (0..self.x.len() - 1)
            .filter(|&i| !self.tendon[i])
            .map(|i| self.rest_len[i])
            .sum();
    }

    /// Forces the paper's chain puts on its two bodies: the full Eq. 1 force of the end
    /// segments. (In Hill mode the tendon force acts through [`Self::pulls_on`] instead.)
    pub fn end_forces(&self, load: &ChainLoad) -> EndForces {
        let n = self.x.len();
        let (g0, g1) = (self.segment(0), self.segment(n - 2));
        let (t0, _) = self.tension(0, &g0, load, 1.0, 0.0);
        let (t1, _) = self.tension(n - 2, &g1, load, 1.0, 0.0);
        EndForces {
            origin: g0.dir_a * t0,
            insertion: g1.dir_b * t1,
        }
    }
}
