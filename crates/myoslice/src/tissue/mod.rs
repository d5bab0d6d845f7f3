//! Tissue deformation: constant-volume muscles riding on their chains, shape-matching fat
//! that follows muscles and bones while holding its volume and unfolding (`relax`,
//! `fat_volume`), the knee fold and contact plane behind the knee, a validity guard, and
//! the per-element metrics of the paper (section 5.3).

mod audit;
mod bone_keep_out;
mod bone_overlap;
mod bone_slide;
mod carried;
mod crease;
mod fat_keep_out;
mod fat_lanes;
mod fat_on_muscle;
pub mod fat_solver;
mod fat_untangle;
mod fat_volume;
mod guard;
mod guard_tally;
mod incidence;
pub mod intersect;
pub mod knee_fold;
pub mod metrics;
mod muscle_contact;
mod muscle_overlap;
mod muscle_placing;
pub mod muscle_shape;
mod phases;
pub mod polar;
mod reach;
mod relax;
mod skin_breach;
mod skin_cover;
mod skin_pleat;
#[cfg(test)]
mod test_shapes;
mod tissue_backup;
mod tissue_config;
mod update_back;

use std::sync::Arc;

use crate::par::*;
use glam::{Quat, Vec3};
use parry3d::shape::TriMesh;

pub use audit::{AuditLine, TissueAudit};
pub use carried::CarriedTissue;
pub use fat_solver::FatSolver;
pub use guard_tally::GuardTally;
pub use knee_fold::{Contact, FoldZone, KneeFold};
use metrics::LazyMetrics;
pub use metrics::TissueMetrics;
pub use muscle_overlap::MuscleOverlap;
use muscle_placing::Placing;
pub use muscle_shape::MuscleShape;
use phases::Lap;
pub use phases::TissuePhases;
use skin_breach::ClosedSkin;
pub use skin_breach::SkinBreach;
pub(crate) use tissue_backup::TissueBackup;
pub use tissue_config::TissueConfig;

use crate::body::{BodyId, KneeAxis, body_of_bone};
use crate::error::Result;
use crate::geometry::BoneSdf;
use crate::lattice::{InnerContact, Lattice};
use crate::muscle::{BodyFrames, MuscleUnit};
pub use bone_overlap::{BoneOverlap, Overlap};
use bone_slide::BoneSlide;
use fat_keep_out::FatKeepOut;
use guard::Guard;

/// Extra distance (m) from the contact plane per fat layer below the skin.
const LAYER_GAP: f32 = 0.001;

/// Knee angle (rad) by which the contact behind the knee keeps its full gap; at rest it
/// keeps each vertex at no more than its rest distance from the plane.
const CONTACT_OPENS_RAD: f32 = std::f32::consts::PI / 6.0;

/// Body-surface triangles behind the knee and within this distance (m) of it at rest are
/// guarded against crossing; farther out the tissue moves nearly rigidly with its bone.
const GUARD_RADIUS: f32 = 0.25;

/// Squared distance (m²) from the fold below which a fat vertex's first guess counts as
/// moving rigidly with its bone, and is not relaxed: 0.1 mm, about 2 % of the slice
/// spacing and a tenth of the contact gap, invisible. At 1 µm the damped carry-over of
/// earlier corrections kept most elements relaxing long after they had stopped moving
/// (docs/speed-history.md, 2026-12-04 night).
const RIGID_TOLERANCE_M2: f32 = 1e-8;

/// Node spacing (m) of the bones' distance fields: exact within
/// [`SDF_BAND_M`] − 2 cells of the surface, interpolated beyond.
const SDF_CELL_M: f32 = 0.002;

/// How far (m) from each bone's surface its distance field holds exact distances: the
/// field answers exactly within 6 mm, past the skin's clearance over bone in front of the
/// knee (5 mm), so the keep-outs seldom need the mesh's tree.
const SDF_BAND_M: f32 = 0.010;

/// Bone surfaces for tissue queries: body and mesh (rest frame) of each lattice bone.
pub type BoneSurfaces = Arc<Vec<(BodyId, TriMesh)>>;

/// What a tissue update needs that never changes: built once from the lattice.
#[derive(Debug)]
struct TissueStatic {
    /// Fat vertex → (muscle, muscle vertex) it follows, and its rest offset from the
    /// muscle's surface under it ([`MuscleShape::surface_under`] at rest).
    muscle_ref: Vec<Option<(u32, u32, Vec3)>>,
    /// Whether a fat vertex belongs to the thigh side of the knee.
    thigh_side: Vec<bool>,
    /// Fat vertices behind the knee axis at rest (the contact acts there).
    posterior: Vec<u32>,
    /// How far each of [`Self::posterior`] lies from the contact plane at rest, on its
    /// own side (m): the contact keeps no vertex further off than that at rest.
    posterior_rest_side: Vec<f32>,
    /// The skin's among them, the whole length of the lattice: drawn back toward the
    /// contact plane wherever it lies further from it than its bone alone would carry it
    /// (see [`crease`]), which happens mostly near the knee, where the fold moves it.
    posterior_skin: Vec<u32>,
    /// Rest position, radial column (from its inner vertex: it points outward) and side
    /// (thigh or not) of each of [`Self::posterior_skin`].
    /// Skin vertices are the last of their column (`FatLattice::vertex_index`).
    posterior_skin_rest: Vec<(Vec3, Vec3, bool)>,
    /// Body-surface triangles near the knee, checked for crossings after each update.
    guard_triangles: Vec<[u32; 3]>,
    /// Where the knee fold can bend the fat.
    zone: FoldZone,
    /// Bone surfaces as parry meshes with the body each rides, lattice bone order.
    bones: BoneSurfaces,
    /// Signed distance field of each bone, lattice bone order (rest frame).
    bone_sdfs: Vec<BoneSdf>,
    /// Fat vertices that slide on bone.
    bone_slide: BoneSlide,
    /// Fat vertices the fold can bring near a bone, kept out of it.
    fat_keep_out: FatKeepOut,
    /// Outer (skin) face of each outer-layer element and its rest area (m²).
    outer_faces: Vec<(u32, [u32; 4], f64)>,
    /// The skin closed at both ends (for [`Tissue::muscles_outside_skin`]).
    skin: ClosedSkin,
    /// The fat's volume and validity constraints.
    fat_volume: fat_volume::FatVolume,
}

/// What the front half of an update hands its back half (see [`Tissue::update_front`]).
#[derive(Debug)]
pub(crate) struct Front {
    phases: TissuePhases,
    /// Whether every muscle vertex came out finite.
    shapes_finite: bool,
}

/// Buffers an update fills anew each time, kept to avoid allocating them. A copy of the
/// tissue (a checkpoint) starts with empty ones: they hold nothing between updates.
#[derive(Debug, Default)]
struct Scratch {
    /// The knee fold of the rest shape (world): valid, the guard's fallback.
    safe: Vec<Vec3>,
    /// Fold weight of each vertex.
    weights: Vec<f32>,
    /// The first guess of the update.
    guess: Vec<Vec3>,
    moving: Vec<bool>,
    /// Where each inner vertex facing a muscle is pulled this update, and the direction
    /// across its fat layer.
    muscle_targets: Vec<(u32, Vec3, Vec3)>,
    /// How far from the contact plane each skin vertex behind the knee may lie this
    /// update before it is pulled, and the share of the excess a pass removes
    /// ([`crease::skin_limits`]).
    skin_limits: Vec<(f32, f32)>,
    guard: Guard,
    volume: fat_volume::VolumeBuffers,
}

impl Clone for Scratch {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// The deformable tissue of a simulation.
#[derive(Debug, Clone)]
pub struct Tissue {
    config: TissueConfig,
    /// Muscle shapes, in muscle order.
    pub muscles: Vec<MuscleShape>,
    /// The fat solver.
    pub fat: FatSolver,
    fixed: Arc<TissueStatic>,
    /// Motion of the last update beyond the skinned guess (for momentum).
    drift: Vec<Vec3>,
    scratch: Scratch,
    knee: KneeAxis,
    /// The knee angle (rad) and the bodies' poses at the last update.
    theta: f32,
    frames_at_update: BodyFrames,
    layers: usize,
    /// Metrics of the last update (see [`Self::metrics`]).
    metrics: LazyMetrics,
    /// The guard's interventions so far.
    guard_tally: GuardTally,
    /// Updates done since the tissue was built.
    updates: u64,
    /// Time accumulated since the last update (s).
    pub(crate) pending: f64,
    /// How long each phase of the last update took.
    pub(crate) last_phases: TissuePhases,
    /// The muscle shapes are placed already for the coming update (placed beside the last
    /// one's guard, see [`Self::update_back_beside`]): the time it took and whether all
    /// were finite.
    placed: Option<(f64, bool)>,
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
        let bone_sdfs: Vec<BoneSdf> = bones
            .par_iter()
            .map(|(_, m)| BoneSdf::new(m.vertices(), m.indices(), SDF_CELL_M, SDF_BAND_M))
            .collect();
        let rest_contact = KneeFold::new(&knee, 0.0).contact(0.0);
        let mut shapes: Vec<MuscleShape> = muscles
            .par_iter()
            .map(|m| {
                let mut s = MuscleShape::new(&lattice.muscles[m.lattice_index], &m.chain);
                s.watch_bones(&bones, &bone_sdfs, &rest_contact);
                s
            })
            .collect();
        if config.muscle_contact {
            let free = muscle_contact::free_to_bulge(&shapes, &bone_sdfs);
            for (s, f) in shapes.iter_mut().zip(free) {
                s.bulges = Arc::new(f);
            }
        }
        let fat = &lattice.fat;
        let solver = FatSolver::new(&fat.vertices, &fat.hexes);
        let nv = fat.vertices.len();
        let mut muscle_ref = vec![None; nv];
        let mut on_bone = Vec::new();
        for (k, c) in fat.inner_contact.iter().enumerate() {
            let (s, j) = (k / fat.rays, k % fat.rays);
            let v = fat.vertex_index(s, j, 0);
            match *c {
                InnerContact::Muscle(_) => {
                    if let Some((mi, mv)) = lattice.fat_muscle_ref[k] {
                        // Lattice muscle index → simulation muscle index.
                        if let Some(si) =
                            muscles.iter().position(|m| m.lattice_index == mi as usize)
                        {
                            let shape = &shapes[si];
                            let p = fat.vertices[v as usize];
                            let under = shape
                                .surface_under(mv, p)
                                .unwrap_or(shape.rest[mv as usize]);
                            muscle_ref[v as usize] = Some((si as u32, mv, p - under));
                        }
                    }
                }
                InnerContact::Bone(label) => {
                    if let Some(bi) = lattice.bones.iter().position(|b| b.label == label) {
                        on_bone.push((v, bi as u32));
                    }
                }
                InnerContact::Free => {}
            }
        }
        let kz = knee.point.z;
        let fold = KneeFold::new(&knee, 0.0);
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
        let outer_faces = fat
            .outer_faces()
            .into_iter()
            .map(|(h, q)| (h, q, crate::lattice::quad_area(&fat.vertices, &q)))
            .collect();
        let posterior: Vec<u32> = (0..nv as u32)
            .filter(|&v| fold.is_posterior(fat.vertices[v as usize]))
            .collect();
        let posterior_skin: Vec<u32> = posterior
            .iter()
            .copied()
            .filter(|&v| v as usize % (fat.layers + 1) == fat.layers)
            .collect();
        let zone = FoldZone::new(&knee, &fat.vertices, &fat.hexes);
        let fat_keep_out = FatKeepOut::new(
            &knee,
            &fat.vertices,
            &zone,
            |v| v % (fat.layers + 1),
            &bone_sdfs,
            &bones,
        );
        let posterior_rest_side = posterior
            .iter()
            .map(|&v| {
                let p = fat.vertices[v as usize];
                rest_contact.locate(p, p.z >= kz).1.max(0.0)
            })
            .collect();
        let fixed = TissueStatic {
            posterior_rest_side,
            muscle_ref,
            posterior_skin_rest: posterior_skin
                .iter()
                .map(|&v| {
                    let p = fat.vertices[v as usize];
                    (p, p - fat.vertices[v as usize - fat.layers], p.z >= kz)
                })
                .collect(),
            thigh_side: fat.vertices.iter().map(|p| p.z >= kz).collect(),
            posterior_skin,
            posterior,
            guard_triangles,
            zone,
            bone_slide: BoneSlide::new(&on_bone, &fat.vertices, &bone_sdfs, &bones),
            fat_keep_out,
            bones: Arc::clone(&bones),
            bone_sdfs,
            outer_faces,
            skin: ClosedSkin::new(fat),
            fat_volume: fat_volume::FatVolume::new(&fat.vertices, &fat.hexes),
        };
        let tissue = Self {
            config,
            muscles: shapes,
            drift: vec![Vec3::ZERO; nv],
            fat: solver,
            fixed: Arc::new(fixed),
            scratch: Scratch::default(),
            knee,
            theta: 0.0,
            frames_at_update: BodyFrames::REST,
            layers: fat.layers,
            metrics: LazyMetrics::built(),
            guard_tally: GuardTally::default(),
            updates: 0,
            pending: 0.0,
            last_phases: TissuePhases::default(),
            placed: None,
        };
        Ok(tissue)
    }

    /// Metrics of the last update (of the rest shape before any), measured when first
    /// asked for, from the shape that update left (moving `fat` or `muscles` by hand in
    /// between changes what they describe).
    pub fn metrics(&self) -> &TissueMetrics {
        self.metrics.of(self)
    }

    /// How often the validity guard stepped in since the tissue was built.
    pub fn guard_tally(&self) -> GuardTally {
        self.guard_tally
    }

    /// Updates done since the tissue was built (a checkpoint carries its count): a run
    /// that checks the tissue after every update watches it change.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// The options.
    pub fn config(&self) -> &TissueConfig {
        &self.config
    }

    /// Seconds between updates.
    pub fn period(&self) -> f64 {
        1.0 / self.config.rate_hz
    }

    /// Outer (skin) face of each outer-layer element, with its rest area (m²).
    pub fn outer_faces(&self) -> &[(u32, [u32; 4], f64)] {
        &self.fixed.outer_faces
    }

    /// Deforms muscles and fat for the current skeleton and chains. Returns false (and
    /// keeps the previous shape) if anything became non-finite.
    pub fn update(&mut self, knee_angle: f64, frames: &BodyFrames, muscles: &[MuscleUnit]) -> bool {
        let backup = self.backup();
        let ok = self.update_unguarded(knee_angle, frames, muscles);
        if !ok {
            self.restore(backup);
        }
        ok
    }

    /// [`Self::update`] without its own backup: the caller puts back a [`TissueBackup`]
    /// if this returns false. (`step` runs [`Self::update_front`] and
    /// [`Self::update_back`] itself, backing up once before its first update.)
    pub(crate) fn update_unguarded(
        &mut self,
        knee_angle: f64,
        frames: &BodyFrames,
        muscles: &[MuscleUnit],
    ) -> bool {
        let front = self.update_front(knee_angle, frames, muscles);
        self.update_back(front)
    }

    /// The part of an update that reads the skeleton and the muscles: everything up to
    /// the validity guard, starting with the muscle shapes unless they were placed for
    /// this update already (beside the last one's guard, see
    /// [`Self::update_back_beside`]). [`Self::update_back`] finishes it; in between, the
    /// caller may move the skeleton and the muscles on (the back half never reads them).
    pub(crate) fn update_front(
        &mut self,
        knee_angle: f64,
        frames: &BodyFrames,
        muscles: &[MuscleUnit],
    ) -> Front {
        let (shapes_s, shapes_finite) = match self.placed.take() {
            Some(placed) => placed,
            None => {
                let mut placing = Placing {
                    shapes: &mut self.muscles,
                    fixed: &self.fixed,
                    knee: self.knee,
                    config: &self.config,
                    layers: self.layers,
                    placed: None,
                };
                placing.place(knee_angle, frames, muscles);
                placing.placed.unwrap_or((0.0, false))
            }
        };
        let mut lap = Lap::start();
        let mut phases = TissuePhases {
            muscle_shapes_s: shapes_s,
            ..TissuePhases::default()
        };
        let theta = knee_angle as f32;
        let fold = KneeFold::new(&self.knee, theta);
        let (tq, tt) = frames.thigh;
        let gap = self.config.contact_gap_m as f32;
        let contact =
            muscle_placing::muscle_contact(&fold, &self.config, self.layers, frames.thigh);
        let fixed = Arc::clone(&self.fixed);

        let mut sc = std::mem::take(&mut self.scratch);
        crease::skin_limits(
            self,
            &fold,
            &contact,
            frames.thigh,
            gap,
            &mut sc.skin_limits,
        );
        // The fold of the rest shape is valid: the fallback of the guard below.
        knee_fold::fold_hexes(
            &fold,
            &fixed.zone,
            &self.fat.rest,
            &self.fat.hexes,
            (tq, tt),
            &mut sc.safe,
            &mut sc.weights,
        );
        phases.knee_fold_s = lap.lap();
        let (safe, weights) = (&sc.safe, &sc.weights);
        fat_on_muscle::targets(
            &fixed.muscle_ref,
            &self.muscles,
            &self.fat.rest,
            (safe, weights),
            self.layers,
            (tq, fold.axis, theta),
            &mut sc.muscle_targets,
        );
        // First guess, from the fold (so nothing accumulates): each radial column of
        // vertices moves with its inner vertex where that follows a muscle (across the
        // layer as a whole, along it the skin by half as much); part of the last
        // update's correction is carried over (inertia with damping).
        let momentum = self.config.momentum as f32;
        let layers = self.layers;
        sc.guess.clone_from(safe);
        for &(inner, target, _) in &sc.muscle_targets {
            // Inner vertices are layer 0 of their column (see `FatLattice::vertex_index`).
            let inner = inner as usize;
            let delta = target - sc.guess[inner];
            let n = (sc.guess[inner + layers] - sc.guess[inner]).normalize_or_zero();
            let normal = n * delta.dot(n);
            let along = delta - normal;
            for (l, g) in sc.guess[inner..=inner + layers].iter_mut().enumerate() {
                *g += normal + along * (1.0 - 0.5 * l as f32 / layers as f32);
            }
        }
        phases.first_guess_s = lap.lap();
        let guess = &sc.guess;
        self.fat
            .x
            .par_iter_mut()
            .zip(guess.par_iter().zip(&self.drift))
            .for_each(|(x, (g, d))| *x = *g + *d * momentum);
        // Relax only where the fat does not simply move with a bone.
        sc.moving.clear();
        sc.moving.extend((0..safe.len()).map(|i| {
            (weights[i] > 0.0 && weights[i] < 1.0)
                || self.fat.x[i].distance_squared(safe[i]) > RIGID_TOLERANCE_M2
        }));
        for &e in fixed.zone.elements() {
            let h = &self.fat.hexes[e as usize];
            let w0 = weights[h[0] as usize];
            if h.iter().any(|&v| weights[v as usize] != w0) {
                for &v in h {
                    sc.moving[v as usize] = true;
                }
            }
        }
        self.fat.restrict_to(&sc.moving);
        // Elements left out turn with their bone: keep their warm start on that rotation,
        // so that one becoming active later starts from its true orientation.
        let shank_turn = tq * Quat::from_axis_angle(fold.axis, theta);
        for (e, h) in self.fat.hexes.iter().enumerate() {
            if !self.fat.active[e] {
                let w = weights[h[0] as usize];
                self.fat.rot[e] = match w {
                    0.0 => tq,
                    1.0 => shank_turn,
                    _ => tq * Quat::from_axis_angle(fold.axis, theta * w),
                };
            }
        }
        let (targets, limits) = (&sc.muscle_targets, &sc.skin_limits);
        fat_on_muscle::pull(&mut self.fat.x, targets);
        // The contact's gap opens as the knee bends: at rest the fat across the plane
        // is whole.
        let opened = (theta / CONTACT_OPENS_RAD).clamp(0.0, 1.0);
        self.apply_contact(&contact, gap, limits, opened);
        let constraints = relax::Constraints {
            contact: &contact,
            gap,
            targets,
            limits,
            opened,
            frames,
        };
        self.relax(&constraints, &mut sc.volume, (&mut phases, &mut lap));
        self.theta = theta;
        self.frames_at_update = *frames;
        self.scratch = sc;
        Front {
            phases,
            shapes_finite,
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

/// Whether a tissue clock at `pending` (s since its last update) has an update due after
/// `dt` more seconds, updates `period` apart; moves the clock on.
pub(crate) fn clock_due(pending: &mut f64, period: f64, dt: f64) -> bool {
    *pending += dt;
    if *pending + 1e-12 >= period {
        *pending = (*pending - period).max(0.0);
        true
    } else {
        false
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
