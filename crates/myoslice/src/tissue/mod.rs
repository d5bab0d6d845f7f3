//! Tissue deformation: constant-volume muscles riding on their chains, shape-matching fat
//! that follows muscles and bones, a contact plane behind the knee, and the per-element
//! metrics of the paper (section 5.3).

pub mod fat_solver;
pub mod intersect;
pub mod metrics;
pub mod muscle_shape;
pub mod polar;

use std::sync::Arc;

use glam::{Quat, Vec3};
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;
use serde::{Deserialize, Serialize};

pub use fat_solver::FatSolver;
pub use metrics::TissueMetrics;
pub use muscle_shape::{Contact, KneeField, MuscleShape};

use crate::body::{BodyId, KneeAxis, body_of_bone};
use crate::error::{Result, check_range};
use crate::lattice::{InnerContact, Lattice, hex_volume_points};
use crate::muscle::{BodyFrames, MuscleUnit};

/// Tissue options (all with documented defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TissueConfig {
    /// Deform muscles and fat at all. Default true.
    pub enabled: bool,
    /// Tissue updates per simulated second (the muscles step at 1 kHz). Default 30.
    pub rate_hz: f64,
    /// Shape-matching iterations per update. Default 6.
    pub iterations: usize,
    /// Shape-matching stiffness k in (0, 1]: fraction of the way to the goal per
    /// iteration. Default 0.6.
    pub stiffness: f64,
    /// Fraction of the last update's own motion carried into the next (inertia; 0 is
    /// quasi-static). Default 0.3.
    pub momentum: f64,
    /// Half-gap (m) kept between the thigh and calf sides of the contact plane behind
    /// the knee. Default 0.001.
    pub contact_gap_m: f64,
    /// Half-width (m) of the band about the knee over which fat follows the shank's
    /// rotation as a first guess. Default 0.06.
    pub blend_m: f64,
}

impl Default for TissueConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 30.0,
            iterations: 6,
            stiffness: 0.6,
            momentum: 0.3,
            contact_gap_m: 0.001,
            blend_m: 0.06,
        }
    }
}

impl TissueConfig {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        check_range("tissue.rate_hz", self.rate_hz, 1.0, 1000.0)?;
        check_range("tissue.iterations", self.iterations as f64, 1.0, 200.0)?;
        check_range("tissue.stiffness", self.stiffness, 1e-3, 1.0)?;
        check_range("tissue.momentum", self.momentum, 0.0, 0.95)?;
        check_range("tissue.contact_gap_m", self.contact_gap_m, 0.0, 0.01)?;
        check_range("tissue.blend_m", self.blend_m, 0.005, 0.3)?;
        Ok(())
    }
}

/// Extra distance (m) from the contact plane per fat layer below the skin.
const LAYER_GAP: f32 = 0.001;

/// Bone surfaces for tissue queries: body and mesh (rest frame) of each lattice bone.
pub type BoneSurfaces = Arc<Vec<(BodyId, TriMesh)>>;

/// The deformable tissue of a simulation.
#[derive(Debug, Clone)]
pub struct Tissue {
    config: TissueConfig,
    /// Muscle shapes, in muscle order.
    pub muscles: Vec<MuscleShape>,
    /// The fat solver.
    pub fat: FatSolver,
    /// Fat vertex → (muscle, muscle vertex) it follows.
    muscle_ref: Vec<Option<(u32, u32)>>,
    /// Fat vertex → (bone, rest distance from its surface) it slides on.
    bone_ref: Vec<Option<(u32, f32)>>,
    /// Fat vertex side of the knee: +1 thigh, −1 shank.
    side: Vec<f32>,
    /// Fraction of the shank's rotation each fat vertex takes as a first guess.
    follow: Vec<f32>,
    /// Motion of the last update beyond the skinned guess (for momentum).
    drift: Vec<Vec3>,
    knee: KneeAxis,
    theta: f32,
    layers: usize,
    bones: BoneSurfaces,
    /// Metrics at the last update.
    pub metrics: TissueMetrics,
    /// Time accumulated since the last update (s).
    pub(crate) pending: f64,
}

impl Tissue {
    /// Binds the tissue of a lattice to its muscles at rest.
    pub fn new(
        lattice: &Lattice,
        muscles: &[MuscleUnit],
        knee: KneeAxis,
        bones: BoneSurfaces,
        config: TissueConfig,
    ) -> Result<Self> {
        config.validate()?;
        let shapes: Vec<MuscleShape> = muscles
            .iter()
            .map(|m| MuscleShape::new(&lattice.muscles[m.lattice_index], &m.chain))
            .collect();
        let fat = &lattice.fat;
        let solver = FatSolver::new(&fat.vertices, &fat.hexes);
        let nv = fat.vertices.len();
        let mut muscle_ref = vec![None; nv];
        let mut bone_ref = vec![None; nv];
        for (k, c) in fat.inner_contact.iter().enumerate() {
            let (s, j) = (k / fat.rays, k % fat.rays);
            let v = fat.vertex_index(s, j, 0) as usize;
            match *c {
                InnerContact::Muscle(_) => {
                    if let Some((mi, mv)) = lattice.fat_muscle_ref[k] {
                        // Lattice muscle index → simulation muscle index.
                        if let Some(si) =
                            muscles.iter().position(|m| m.lattice_index == mi as usize)
                        {
                            muscle_ref[v] = Some((si as u32, mv));
                        }
                    }
                }
                InnerContact::Bone(label) => {
                    if let Some(bi) = lattice.bones.iter().position(|b| b.label == label) {
                        let p = fat.vertices[v];
                        let d = bones[bi].1.project_local_point(p, false).point.distance(p);
                        bone_ref[v] = Some((bi as u32, d));
                    }
                }
                InnerContact::Free => {}
            }
        }
        let kz = knee.point.z;
        let side = fat
            .vertices
            .iter()
            .map(|p| if p.z >= kz { 1.0 } else { -1.0 })
            .collect();
        let b = config.blend_m as f32;
        let follow = fat
            .vertices
            .iter()
            .map(|p| {
                let t = ((kz + b - p.z) / (2.0 * b)).clamp(0.0, 1.0);
                t * t * (3.0 - 2.0 * t)
            })
            .collect();
        let mut tissue = Self {
            config,
            muscles: shapes,
            drift: vec![Vec3::ZERO; nv],
            fat: solver,
            muscle_ref,
            bone_ref,
            side,
            follow,
            knee,
            theta: 0.0,
            layers: fat.layers,
            bones,
            metrics: TissueMetrics::default(),
            pending: 0.0,
        };
        tissue.metrics = TissueMetrics::measure(lattice, &tissue);
        Ok(tissue)
    }

    /// The options.
    pub fn config(&self) -> &TissueConfig {
        &self.config
    }

    /// Seconds between updates.
    pub fn period(&self) -> f64 {
        1.0 / self.config.rate_hz
    }

    /// Deforms muscles and fat for the current skeleton and chains. Returns false (and
    /// keeps the previous shape) if anything became non-finite.
    pub fn update(
        &mut self,
        lattice: &Lattice,
        knee_angle: f64,
        frames: &BodyFrames,
        muscles: &[MuscleUnit],
    ) -> bool {
        let backup = self.fat.x.clone();
        let backup_theta = self.theta;
        self.deform(lattice, knee_angle, frames, muscles);
        let ok = self.fat.x.iter().all(|p| p.is_finite())
            && self
                .muscles
                .iter()
                .all(|m| m.current.iter().all(|p| p.is_finite()));
        if !ok {
            self.fat.x = backup;
            self.theta = backup_theta;
            for (shape, m) in self.muscles.iter_mut().zip(muscles) {
                shape.current.clone_from(&shape.rest);
                let _ = m;
            }
        }
        ok
    }

    fn deform(
        &mut self,
        lattice: &Lattice,
        knee_angle: f64,
        frames: &BodyFrames,
        muscles: &[MuscleUnit],
    ) {
        let field = KneeField {
            point: self.knee.point,
            axis: self.knee.axis,
            theta: knee_angle as f32,
            band: self.config.blend_m as f32,
        };
        let theta = knee_angle as f32;
        let knee_pt = frames.point(BodyId::Thigh, self.knee.point);
        let axis = frames.vector(BodyId::Thigh, self.knee.axis);
        let gap = self.config.contact_gap_m as f32;
        // Muscles keep further from the contact than the fat over them.
        let muscle_gap = gap + LAYER_GAP * (self.layers as f32 + 1.0);
        let contact = Contact::new(
            knee_pt,
            axis,
            frames.vector(BodyId::Thigh, Vec3::Z),
            theta,
            muscle_gap,
        );
        // Muscles are not pushed by the contact plane: their volume is the invariant
        // kept; the fat over them is.
        for (shape, m) in self.muscles.iter_mut().zip(muscles) {
            // A muscle resting on one body keeps its rest shape and moves with the body.
            let quiet = !m.crosses_knee && m.activation < 1e-4 && m.excitation == 0.0;
            match m.chain.single_body() {
                Some(b) if quiet => {
                    let (q, t) = match b {
                        BodyId::Thigh => frames.thigh,
                        BodyId::Shank => frames.shank,
                    };
                    shape.carry(q, t);
                }
                _ => shape.update(&m.chain, &field, None),
            }
        }
        // First guess, from the rest shape (so nothing accumulates): every vertex turns
        // about the knee by its share of the shank's rotation; each radial column of
        // vertices then moves with its inner vertex where that follows a muscle; part of
        // the last update's correction is carried over (inertia with damping).
        let momentum = self.config.momentum as f32;
        let lat = &lattice.fat;
        let mut guess = vec![Vec3::ZERO; self.fat.x.len()];
        for (i, g) in guess.iter_mut().enumerate() {
            let q = Quat::from_axis_angle(axis, theta * self.follow[i]);
            *g = knee_pt + q * (self.fat.rest[i] - self.knee.point);
        }
        let layers = lat.layers;
        for s in 0..lat.slices {
            for j in 0..lat.rays {
                let inner = lat.vertex_index(s, j, 0) as usize;
                let Some((m, mv)) = self.muscle_ref[inner] else {
                    continue;
                };
                let shape = &self.muscles[m as usize];
                let target =
                    self.fat.rest[inner] + (shape.current[mv as usize] - shape.rest[mv as usize]);
                let delta = target - guess[inner];
                for l in 0..=layers {
                    let v = lat.vertex_index(s, j, l) as usize;
                    guess[v] += delta * (1.0 - 0.5 * l as f32 / layers as f32);
                }
            }
        }
        for (i, p) in self.fat.x.iter_mut().enumerate() {
            *p = guess[i] + self.drift[i] * momentum;
        }
        self.apply_muscles();
        self.apply_contact(&contact, gap);
        let k = self.config.stiffness as f32;
        for _ in 0..self.config.iterations {
            self.fat.iterate(k);
            self.apply_muscles();
            self.apply_contact(&contact, gap);
        }
        self.apply_bones(frames);
        self.apply_contact(&contact, gap);
        self.guard_inversions(&contact, gap);
        for i in 0..self.drift.len() {
            self.drift[i] = self.fat.x[i] - guess[i];
        }
        self.theta = theta;
        self.metrics = TissueMetrics::measure(lattice, self);
    }

    /// Pulls inner vertices facing a muscle toward their reference muscle vertex's moving
    /// vector (the paper's rule), strongly but not rigidly, so that millimetre noise of
    /// the muscle surface cannot fold the thin fat elements; shape matching shares the
    /// rest.
    fn apply_muscles(&mut self) {
        const PULL: f32 = 0.7;
        let (x, rest, shapes) = (&mut self.fat.x, &self.fat.rest, &self.muscles);
        for (v, r) in self.muscle_ref.iter().enumerate() {
            if let Some((m, mv)) = *r {
                let s = &shapes[m as usize];
                let mv = mv as usize;
                let target = rest[v] + (s.current[mv] - s.rest[mv]);
                let cur = x[v];
                x[v] = cur + (target - cur) * PULL;
            }
        }
    }

    /// Keeps thigh-side and calf-side fat apart behind the knee ([`Contact`]).
    fn apply_contact(&mut self, c: &Contact, gap: f32) {
        let l1 = self.layers + 1;
        for (v, (p, &s)) in self.fat.x.iter_mut().zip(&self.side).enumerate() {
            // Deeper layers stop further from the contact, so squeezed elements stay
            // thin but never flat.
            let depth = (self.layers - v % l1) as f32;
            *p = c.apply(*p, s > 0.0, gap + LAYER_GAP * depth);
        }
    }

    fn apply_bones(&mut self, frames: &BodyFrames) {
        for (v, r) in self.bone_ref.iter().enumerate() {
            let Some((b, d0)) = *r else { continue };
            let (body, mesh) = &self.bones[b as usize];
            let (q, t) = match body {
                BodyId::Thigh => frames.thigh,
                BodyId::Shank => frames.shank,
            };
            let p_rest = q.inverse() * (self.fat.x[v] - t);
            let proj = mesh.project_local_point(p_rest, false);
            let out = if proj.is_inside {
                (proj.point - p_rest).normalize_or_zero()
            } else {
                (p_rest - proj.point).normalize_or_zero()
            };
            // Slide on the bone: pulled onto the surface (at its rest distance), softly.
            let target = q * (proj.point + out * d0) + t;
            let cur = self.fat.x[v];
            self.fat.x[v] = cur + (target - cur) * if proj.is_inside { 1.0 } else { 0.7 };
        }
    }

    /// Elements squeezed below a tenth of their rest volume are pulled onto their own
    /// goal shape (a rotated copy of the rest shape, never inverted).
    fn guard_inversions(&mut self, contact: &Contact, gap: f32) {
        for _ in 0..8 {
            let bad: Vec<usize> = (0..self.fat.hexes.len())
                .filter(|&e| {
                    let h = self.fat.hexes[e];
                    let p = h.map(|i| self.fat.x[i as usize].as_dvec3());
                    let r = h.map(|i| self.fat.rest[i as usize].as_dvec3());
                    hex_volume_points(&p) < 0.1 * hex_volume_points(&r)
                })
                .collect();
            if bad.is_empty() {
                return;
            }
            self.fat.compute_goals_for(&bad);
            for &e in &bad {
                let h = self.fat.hexes[e];
                for (k, &v) in h.iter().enumerate() {
                    if self.fat.free[v as usize] {
                        self.fat.x[v as usize] = self.fat.goal(e, k);
                    }
                }
            }
            self.apply_contact(contact, gap);
        }
    }

    /// Whether the tissue has an update due after `dt` more seconds.
    pub(crate) fn advance_clock(&mut self, dt: f64) -> bool {
        self.pending += dt;
        if self.pending + 1e-12 >= self.period() {
            self.pending -= self.period();
            self.pending = self.pending.max(0.0);
            true
        } else {
            false
        }
    }

    /// Fat vertices now.
    pub fn fat_vertices(&self) -> &[Vec3] {
        &self.fat.x
    }

    /// The knee axis the tissue uses.
    pub fn knee(&self) -> &KneeAxis {
        &self.knee
    }
}

/// Bone surfaces of a lattice for a skeleton.
pub fn bone_surfaces(lattice: &Lattice, meshes: &[&TriMesh]) -> BoneSurfaces {
    Arc::new(
        lattice
            .bones
            .iter()
            .zip(meshes)
            .map(|(b, m)| (body_of_bone(&b.name), (*m).clone()))
            .collect(),
    )
}
