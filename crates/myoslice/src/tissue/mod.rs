//! Tissue deformation: constant-volume muscles riding on their chains, shape-matching fat
//! that follows muscles and bones, the knee fold and contact plane behind the knee, a
//! validity guard, and the per-element metrics of the paper (section 5.3).

mod fat_lanes;
pub mod fat_solver;
pub mod intersect;
pub mod knee_fold;
pub mod metrics;
pub mod muscle_shape;
pub mod polar;

use std::sync::Arc;

use glam::Vec3;
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;
use serde::{Deserialize, Serialize};

pub use fat_solver::FatSolver;
pub use knee_fold::{Contact, KneeFold};
pub use metrics::TissueMetrics;
pub use muscle_shape::MuscleShape;

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
    /// No fat element may shrink below half of this share of its rest volume (or half of
    /// its volume in the knee fold, if that is smaller): where relaxation would, the
    /// tissue falls back toward the fold locally (see [`Tissue`]). Default 0.05, i.e. a
    /// floor at 2.5 % of rest volume.
    pub min_volume_ratio: f64,
    /// Keep the body surface from passing through itself near the knee (checked exactly,
    /// triangle against triangle, after every update). Default true.
    pub surface_guard: bool,
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
            min_volume_ratio: 0.05,
            surface_guard: true,
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
        check_range("tissue.min_volume_ratio", self.min_volume_ratio, 0.0, 0.9)?;
        Ok(())
    }
}

/// Extra distance (m) from the contact plane per fat layer below the skin.
const LAYER_GAP: f32 = 0.001;

/// Body-surface triangles behind the knee and within this distance (m) of it at rest are
/// guarded against crossing; farther out the tissue moves nearly rigidly with its bone.
const GUARD_RADIUS: f32 = 0.25;

/// Times the validity guard halves an offending vertex's relaxation before it puts the
/// vertex on the fold outright.
const GUARD_HALVINGS: u8 = 2;

/// Squared distance (m²) from the fold below which a fat vertex counts as moving
/// rigidly with its bone.
const RIGID_TOLERANCE_M2: f32 = 1e-12;

/// Most rounds of the validity guard (each settles at least one more vertex).
const GUARD_MAX_ROUNDS: usize = 64;

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
    /// Whether a fat vertex lies behind the knee axis at rest (the contact acts there).
    posterior: Vec<bool>,
    /// Body-surface triangles near the knee, checked for crossings after each update.
    guard_triangles: Vec<[u32; 3]>,
    /// Where each inner vertex facing a muscle is pulled this update (scratch).
    muscle_targets: Vec<(u32, Vec3)>,
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
        let fold = KneeFold::new(&knee, 0.0);
        let posterior = fat.vertices.iter().map(|&p| fold.is_posterior(p)).collect();
        // Behind the knee, where the thigh and calf press on each other; in front the
        // skin only stretches.
        let guard_triangles = fat
            .surface_triangles()
            .into_iter()
            .filter(|t| {
                t.iter().any(|&v| {
                    let p = fat.vertices[v as usize];
                    p.distance(knee.point) < GUARD_RADIUS && fold.is_posterior(p)
                })
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
            posterior,
            guard_triangles,
            muscle_targets: Vec::new(),
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
        // Everything an update changes, to put back if it fails.
        let backup = (
            self.fat.x.clone(),
            self.fat.rot.clone(),
            self.fat.free.clone(),
            self.fat.active.clone(),
            self.drift.clone(),
            self.theta,
            self.metrics.clone(),
            self.muscles
                .iter()
                .map(|m| m.current.clone())
                .collect::<Vec<_>>(),
        );
        self.deform(lattice, knee_angle, frames, muscles);
        let ok = self.fat.x.iter().all(|p| p.is_finite())
            && self.drift.iter().all(|p| p.is_finite())
            && self
                .muscles
                .iter()
                .all(|m| m.current.iter().all(|p| p.is_finite()));
        if !ok {
            let (x, rot, free, active, drift, theta, metrics, current) = backup;
            (self.fat.x, self.fat.rot, self.fat.free, self.fat.active) = (x, rot, free, active);
            (self.drift, self.theta, self.metrics) = (drift, theta, metrics);
            for (shape, c) in self.muscles.iter_mut().zip(current) {
                shape.current = c;
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
        let theta = knee_angle as f32;
        let fold = KneeFold::new(&self.knee, theta);
        let (tq, tt) = frames.thigh;
        let gap = self.config.contact_gap_m as f32;
        // Muscles keep further from the contact than the fat over them.
        let muscle_gap = gap + LAYER_GAP * (self.layers as f32 + 1.0);
        let contact = fold.contact(muscle_gap);
        let contact = Contact {
            point: tq * contact.point + tt,
            normal: tq * contact.normal,
            behind: tq * contact.behind,
            ..contact
        };
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
                _ => shape.update(&m.chain, &fold, None),
            }
        }
        // The fold of the rest shape is valid: the fallback of the guard below.
        let (folded, weights) = knee_fold::fold_hexes(&fold, &self.fat.rest, &self.fat.hexes);
        let safe: Vec<Vec3> = folded.into_iter().map(|p| tq * p + tt).collect();
        // Where each inner vertex facing a muscle goes: with its reference muscle vertex,
        // keeping its rest offset from it turned as the tissue about it turns (the
        // paper's moving vector alone would shear thin fat at large angles).
        self.muscle_targets.clear();
        for (v, r) in self.muscle_ref.iter().enumerate() {
            let Some((m, mv)) = *r else { continue };
            let shape = &self.muscles[m as usize];
            let turn = tq * glam::Quat::from_axis_angle(fold.axis, theta * weights[v]);
            let offset = self.fat.rest[v] - shape.rest[mv as usize];
            self.muscle_targets
                .push((v as u32, shape.current[mv as usize] + turn * offset));
        }
        // First guess, from the fold (so nothing accumulates): each radial column of
        // vertices moves with its inner vertex where that follows a muscle, the skin by
        // half as much; part of the last update's correction is carried over (inertia
        // with damping).
        let momentum = self.config.momentum as f32;
        let lat = &lattice.fat;
        let mut guess = safe.clone();
        let l1 = lat.layers + 1;
        for &(inner, target) in &self.muscle_targets {
            // Inner vertices are layer 0 of their column (see `FatLattice::vertex_index`).
            let inner = inner as usize;
            let delta = target - guess[inner];
            for (l, g) in guess[inner..inner + l1].iter_mut().enumerate() {
                *g += delta * (1.0 - 0.5 * l as f32 / lat.layers as f32);
            }
        }
        for (i, p) in self.fat.x.iter_mut().enumerate() {
            *p = guess[i] + self.drift[i] * momentum;
        }
        // Relax only where the fat does not simply move with a bone.
        let mut moving: Vec<bool> = (0..safe.len())
            .map(|i| {
                (weights[i] > 0.0 && weights[i] < 1.0)
                    || self.fat.x[i].distance_squared(safe[i]) > RIGID_TOLERANCE_M2
            })
            .collect();
        for h in &self.fat.hexes {
            let w0 = weights[h[0] as usize];
            if h.iter().any(|&v| weights[v as usize] != w0) {
                for &v in h {
                    moving[v as usize] = true;
                }
            }
        }
        self.fat.restrict_to(&moving);
        // Elements left out turn with their bone: keep their warm start on that rotation,
        // so that one becoming active later starts from its true orientation.
        for (e, h) in self.fat.hexes.iter().enumerate() {
            if !self.fat.active[e] {
                let w = weights[h[0] as usize];
                self.fat.rot[e] = tq * glam::Quat::from_axis_angle(fold.axis, theta * w);
            }
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
        let guarded = self.guard(&safe);
        for i in 0..self.drift.len() {
            self.drift[i] = self.fat.x[i] - guess[i];
        }
        self.theta = theta;
        self.metrics = TissueMetrics::measure_active(lattice, self);
        self.metrics.guarded_vertices = guarded;
    }

    /// Pulls inner vertices facing a muscle toward their reference muscle vertex's moving
    /// vector (the paper's rule), strongly but not rigidly, so that millimetre noise of
    /// the muscle surface cannot fold the thin fat elements; shape matching shares the
    /// rest.
    fn apply_muscles(&mut self) {
        const PULL: f32 = 0.7;
        for &(v, target) in &self.muscle_targets {
            let cur = self.fat.x[v as usize];
            self.fat.x[v as usize] = cur + (target - cur) * PULL;
        }
    }

    /// Keeps thigh-side and calf-side fat apart behind the knee ([`Contact`]).
    fn apply_contact(&mut self, c: &Contact, gap: f32) {
        let l1 = self.layers + 1;
        for (v, (p, &s)) in self.fat.x.iter_mut().zip(&self.side).enumerate() {
            // Vertices outside the relaxed region sit on the fold, which keeps its side.
            if !self.posterior[v] || !self.fat.free[v] {
                continue;
            }
            // Deeper layers stop further from the contact, so squeezed elements stay
            // thin but never flat.
            let depth = (self.layers - v % l1) as f32;
            *p = c.apply(*p, s > 0.0, gap + LAYER_GAP * depth);
        }
    }

    fn apply_bones(&mut self, frames: &BodyFrames) {
        for (v, r) in self.bone_ref.iter().enumerate() {
            let Some((b, d0)) = *r else { continue };
            if !self.fat.free[v] {
                continue; // moves rigidly with its bone already
            }
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

    /// The validity guard (beyond the paper, which reports fat that breaks): where the
    /// relaxed shape has an element below its allowed volume or body-surface triangles
    /// behind the knee that cross, the vertices involved give back half of their way from
    /// the fold (`safe`) to the relaxed shape, round after round, and after
    /// [`GUARD_HALVINGS`] halvings take the fold outright; the vertices around them give
    /// back part of the way too. Elsewhere the relaxed shape stands. After the first round only what the last round moved is looked at again.
    /// Returns how many vertices it moved off the relaxed shape.
    fn guard(&mut self, safe: &[Vec3]) -> usize {
        let eps = self.config.min_volume_ratio;
        let n_el = self.fat.hexes.len();
        let volume = |x: &[Vec3], e: usize, hexes: &[[u32; 8]]| {
            hex_volume_points(&hexes[e].map(|i| x[i as usize].as_dvec3()))
        };
        let floor = |e: usize, hexes: &[[u32; 8]], v0: &[f64]| {
            0.5 * (eps * v0[e]).min(volume(safe, e, hexes)).max(0.0)
        };
        // Elements outside the relaxed region are rigid copies of the fold's (valid).
        let mut bad_el: Vec<usize> = (0..n_el)
            .filter(|&e| {
                self.fat.active[e]
                    && volume(&self.fat.x, e, &self.fat.hexes)
                        <= floor(e, &self.fat.hexes, &self.fat.rest_volume)
            })
            .collect();
        let relaxed = self.fat.x.clone();
        let mut share = vec![1.0f32; relaxed.len()];
        let mut halvings = vec![0u8; relaxed.len()];
        let mut bad = vec![false; relaxed.len()];
        let mut moved_now = vec![false; relaxed.len()];
        let mut moved_list: Vec<usize> = Vec::new();
        for round in 0..GUARD_MAX_ROUNDS {
            if round > 0 {
                // Only elements touching a vertex just moved can have changed.
                bad_el.clear();
                for &v in &moved_list {
                    bad_el.extend(self.fat.elements_of(v));
                }
                bad_el.sort_unstable();
                bad_el.dedup();
                bad_el.retain(|&e| {
                    volume(&self.fat.x, e, &self.fat.hexes)
                        <= floor(e, &self.fat.hexes, &self.fat.rest_volume)
                });
            }
            for &e in &bad_el {
                for &i in &self.fat.hexes[e] {
                    bad[i as usize] = true;
                }
            }
            if self.config.surface_guard {
                // Triangles outside the relaxed region are where the fold put them (the
                // tests check the fold's skin for crossings); after the first round only
                // those with a vertex just moved can have changed.
                let live = if round == 0 {
                    &self.fat.free
                } else {
                    &moved_now
                };
                let active: Vec<bool> = self
                    .guard_triangles
                    .iter()
                    .map(|t| t.iter().any(|&i| live[i as usize]))
                    .collect();
                let pairs = intersect::crossing_pairs_among(
                    &self.fat.x,
                    &self.guard_triangles,
                    Some(&active),
                );
                for (a, b) in pairs {
                    let (ta, tb) = (
                        self.guard_triangles[a as usize],
                        self.guard_triangles[b as usize],
                    );
                    for i in ta.iter().chain(&tb) {
                        bad[*i as usize] = true;
                    }
                }
            }
            // Stop when nothing is wrong, or nothing is left to give back.
            for &v in &moved_list {
                moved_now[v] = false;
            }
            moved_list.clear();
            for (i, b) in bad.iter_mut().enumerate() {
                if std::mem::take(b) && share[i] > 0.0 {
                    moved_now[i] = true;
                    moved_list.push(i);
                    halvings[i] += 1;
                    share[i] = if halvings[i] >= GUARD_HALVINGS {
                        0.0
                    } else {
                        0.5 * share[i]
                    };
                }
            }
            if moved_list.is_empty() {
                break;
            }
            // The vertices around give back part of it too: a soft edge, not a step from
            // one vertex to the next.
            let n_bad = moved_list.len();
            for k in 0..n_bad {
                let v = moved_list[k];
                let cap = 0.5 * (1.0 + share[v]);
                for e in self.fat.elements_of(v) {
                    for &u in &self.fat.hexes[e] {
                        let u = u as usize;
                        if share[u] > cap {
                            share[u] = cap;
                            if !moved_now[u] {
                                moved_now[u] = true;
                                moved_list.push(u);
                            }
                        }
                    }
                }
            }
            for &i in &moved_list {
                self.fat.x[i] = safe[i] + (relaxed[i] - safe[i]) * share[i];
            }
            if round + 1 == GUARD_MAX_ROUNDS {
                // Out of rounds (not seen in practice): whatever was touched takes the fold.
                for (i, sh) in share.iter_mut().enumerate() {
                    if *sh < 1.0 {
                        *sh = 0.0;
                        self.fat.x[i] = safe[i];
                    }
                }
            }
        }
        share.iter().filter(|&&s| s < 1.0).count()
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
