//! The one `Simulation` API every front uses: build from a lattice, step, excite muscles,
//! read the knee and the muscles.

mod config;
mod from_files;
mod models;
mod schedule;
mod stepping;
mod surface;
mod timers;

use std::sync::Arc;

use glam::Vec3;

pub use config::{MuscleModel, SimulationConfig, TendonModel};
pub use schedule::Schedule;
pub use surface::{Layer, Surface};
pub use timers::StepTimers;

use stepping::Rollback;

use crate::body::{BodyId, Skeleton, SkeletonOptions, knee_axis};
use crate::error::{Error, Result, check_range};
use crate::lattice::Lattice;
use crate::muscle::{
    Axis, BodyFrames, ChainContact, ChainLoad, ChainOptions, MuscleCatalogue, MuscleGroup,
    MuscleUnit,
};
use crate::tissue::{BoneOverlap, SkinBreach, Tissue, TissueAudit, TissueMetrics, bone_surfaces};

/// Simulated time (s) the muscle chains settle at rest before time 0 (see `settle`).
const SETTLE_S: f64 = 2.0;

/// What a muscle reports.
#[derive(Debug, Clone, PartialEq)]
pub struct MuscleReadout {
    /// Name.
    pub name: String,
    /// Control group.
    pub group: MuscleGroup,
    /// Excitation in [0, 1].
    pub excitation: f64,
    /// Activation in [0, 1].
    pub activation: f64,
    /// Tendon force (N).
    pub force: f64,
    /// Fibre length (m).
    pub fibre_length: f64,
    /// Fibre length over optimal fibre length.
    pub normalised_fibre_length: f64,
    /// Moment arm about the knee (m), positive for flexion; 0 when it does not cross it.
    /// Geometric (virtual work, −dL/dθ): in Hill mode the knee torque is exactly tendon
    /// force × moment arm; in the paper's spring mode the bones feel the end segments'
    /// Eq. 1 forces instead, so the torque need not equal it.
    pub moment_arm: f64,
    /// Path length origin to insertion (m).
    pub path_length: f64,
    /// Its tendon model (used in Hill mode).
    pub tendon: TendonModel,
}

/// The dynamic state of a simulation, for checkpoints (`state` / `set_state`).
#[derive(Debug, Clone)]
pub struct SimulationState {
    time: f64,
    steps: u64,
    skeleton: Skeleton,
    muscles: Vec<MuscleUnit>,
    frames: BodyFrames,
    knee_torque: f64,
    tissue: Option<Tissue>,
    /// The models may be switched mid-run: a checkpoint replays with the ones it had.
    models: (MuscleModel, TendonModel),
}

impl SimulationState {
    /// Simulated time of the checkpoint (s).
    pub fn time(&self) -> f64 {
        self.time
    }
}

/// A muscle-driven lower limb.
#[derive(Debug, Clone)]
pub struct Simulation {
    lattice: Arc<Lattice>,
    config: SimulationConfig,
    skeleton: Skeleton,
    muscles: Vec<MuscleUnit>,
    schedules: Vec<Option<Schedule>>,
    time: f64,
    steps: u64,
    frames: BodyFrames,
    knee_torque: f64,
    tissue: Option<Tissue>,
    /// The muscles' contacts with one another (found at rest, never changed).
    contact: Arc<ChainContact>,
    /// Which chains moved by their own dynamics in a substep (the others were carried).
    moving: Vec<bool>,
    /// Per-substep buffers, kept to avoid allocating every step.
    scratch: (Vec<(Vec3, Vec3)>, Vec<ChainLoad>),
    /// Buffers for the state a `step` call started from.
    rollback: Rollback,
    /// Wall-clock time of the `step` calls.
    timers: StepTimers,
    /// What the build could not take from the catalogue (see `warnings`).
    warnings: Vec<String>,
}

impl Simulation {
    /// Builds a simulation of a lattice body.
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// sim.set_excitation("semitendinosus", 1.0)?;
    /// sim.step(0.5)?;
    /// println!("knee at {:.1} deg", sim.knee_angle().to_degrees());
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn new(
        lattice: Lattice,
        config: SimulationConfig,
        catalogue: &MuscleCatalogue,
    ) -> Result<Self> {
        config.validate()?;
        let femur = lattice.bone("femur").ok_or_else(|| {
            Error::Build("the lattice has no 'femur' bone: the knee needs one".into())
        })?;
        let knee = knee_axis(femur)?;
        let skeleton = Skeleton::new(
            &lattice,
            knee,
            &SkeletonOptions {
                body_mass: config.body_mass_kg,
                height: config.height_m,
                limits: config.knee_limits_deg.map(f64::to_radians),
                damping: config.knee_damping,
                gravity: config.gravity,
            },
        )?;
        let meshes: Vec<_> = (0..lattice.bones.len())
            .map(|i| {
                skeleton
                    .bone_trimesh(i)
                    .ok_or_else(|| Error::Build("bone collider missing".into()))
            })
            .collect::<Result<_>>()?;
        let opts = ChainOptions {
            spacing: config.chain_spacing_m,
            cone_half_angle: config.cone_half_angle_deg.to_radians(),
            stiffness: config.chain_stiffness as f32,
            gravity: Vec3::from_array(config.gravity.map(|g| g as f32)),
        };
        let muscles = (0..lattice.muscles.len())
            .map(|i| {
                MuscleUnit::build(&lattice, i, &meshes, &knee, catalogue, &opts, config.tendon)
            })
            .collect::<Result<Vec<_>>>()?;
        let bones = config
            .tissue
            .enabled
            .then(|| bone_surfaces(&lattice, &meshes));
        let warnings = muscles
            .iter()
            .filter(|m| !catalogue.muscles.contains_key(&m.name))
            .map(|m| {
                format!(
                    "muscle '{}' has no entry in the muscle catalogue: its parameters come \
                     from its volume and length (max force {:.0} N, optimal fibre length \
                     {:.3} m, tendon slack length {:.3} m)",
                    m.name,
                    m.hill.max_isometric_force,
                    m.hill.optimal_fibre_length,
                    m.hill.tendon_slack_length
                )
            })
            .collect();
        let n = muscles.len();
        let mut sim = Self {
            lattice: Arc::new(lattice),
            config,
            skeleton,
            muscles,
            schedules: vec![None; n],
            time: 0.0,
            steps: 0,
            frames: BodyFrames::REST,
            knee_torque: 0.0,
            tissue: None,
            contact: Arc::default(),
            moving: Vec::new(),
            scratch: Default::default(),
            rollback: Rollback::default(),
            timers: StepTimers::default(),
            warnings,
        };
        // Moment arms (each step's torque report uses the last step's) and wrap state of
        // the chains as built.
        sim.reattach_muscles();
        // The tether holds an unloaded chain where it was built (along the muscle's
        // centroids, under its build tension). The chains settle against it before the
        // simulation starts, and the tissue rests on the settled chains, so a simulation
        // that starts idle stays at rest. (A tissue resting on the chains' tether-free
        // equilibrium, centimetres away near the knee, began every run by moving there:
        // folded fat, muscles pressed into their neighbours.)
        sim.settle();
        if sim.config.chain_contact {
            sim.contact = Arc::new(ChainContact::new(&sim.muscles, &sim.lattice.muscles));
        }
        if let Some(bones) = bones {
            sim.tissue = Some(Tissue::new(
                &sim.lattice,
                &sim.muscles,
                knee,
                bones,
                sim.config.tissue.clone(),
            )?);
        }
        if sim.config.initial_knee_deg != 0.0 {
            sim.set_knee(sim.config.initial_knee_deg.to_radians(), 0.0)?;
        }
        Ok(sim)
    }

    /// Lets the muscle chains settle at rest against their tether: a chain drawn along a
    /// curved muscle straightens a little under its passive tension and sags under
    /// gravity, and the tissue takes that equilibrium as its rest shape rather than
    /// showing the settling as deformation. The skeleton is put back where it was; the
    /// clock stays at 0.
    fn settle(&mut self) {
        let skeleton = self.skeleton.clone();
        let muscles = self.muscles.clone();
        let h = self.config.max_step_s;
        let n = (SETTLE_S / h).ceil() as usize;
        for _ in 0..n {
            if self.substep(h).or_else(|| self.non_finite()).is_some() {
                // A model that cannot rest (absurd muscle parameters) starts unsettled;
                // stepping will report it.
                self.muscles = muscles;
                break;
            }
        }
        self.skeleton = skeleton;
        self.frames = self.current_frames();
        for m in &mut self.muscles {
            m.chain.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
        }
        self.reattach_muscles();
        (self.time, self.steps, self.knee_torque) = (0.0, 0, 0.0);
    }

    /// After the bones moved by a jump: every chain back on its attachments, its wrap,
    /// path length and moment arm brought up to date, no excursion velocity.
    fn reattach_muscles(&mut self) {
        let axis = self.knee_axis();
        for m in &mut self.muscles {
            m.chain.attach_ends(&self.frames);
            m.chain.update_wrap();
            m.path_length = m.chain.path_length();
            m.path_velocity = 0.0;
            if m.crosses_knee {
                m.moment_arm = m.chain.moment_arm(&axis, BodyId::Shank);
                m.current_moment_arm = m.moment_arm;
            }
        }
        // After a jump a compliant fibre starts in static equilibrium with its tendon at
        // the new length (a step across the jump would read it as a huge velocity).
        self.start_fibres();
    }

    /// The lattice body.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// The lattice, shared.
    pub fn lattice_arc(&self) -> Arc<Lattice> {
        Arc::clone(&self.lattice)
    }

    /// The options.
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    /// The rigid skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Body poses now.
    pub fn frames(&self) -> &BodyFrames {
        &self.frames
    }

    /// The deformable tissue (None when disabled).
    pub fn tissue(&self) -> Option<&Tissue> {
        self.tissue.as_ref()
    }

    /// The fat and muscles of the last tissue update carried with the bones to now (see
    /// [`Tissue::carried`]): what to draw between updates. None when tissue is disabled.
    pub fn carried_tissue(&self) -> Option<crate::tissue::CarriedTissue> {
        self.tissue()
            .map(|t| t.carried(self.knee_angle(), self.frames()))
    }

    /// Tissue metrics of the last tissue update (None when tissue is disabled).
    pub fn tissue_metrics(&self) -> Option<&TissueMetrics> {
        self.tissue.as_ref().map(Tissue::metrics)
    }

    /// How far each muscle's surface reaches into bone now, in muscle order (exact: a
    /// tree query per muscle vertex near a bone, tens of milliseconds; for checks, not
    /// every frame). None when tissue is disabled.
    pub fn muscles_in_bone(&self) -> Option<Vec<BoneOverlap>> {
        self.tissue
            .as_ref()
            .map(|t| t.muscles_in_bone(&self.frames))
    }

    /// How far each muscle's surface reaches out through the skin now, in muscle order
    /// (exact: a tree query per muscle vertex, tens of milliseconds; for checks, not every
    /// frame). None when tissue is disabled (or its skin cannot be closed into a mesh).
    pub fn muscles_outside_skin(&self) -> Option<Vec<SkinBreach>> {
        self.tissue.as_ref().and_then(|t| t.muscles_outside_skin())
    }

    /// How far each bone's surface reaches out through the skin now, in the lattice's bone
    /// order (exact, as [`Simulation::muscles_outside_skin`]). None when tissue is disabled
    /// (or its skin cannot be closed into a mesh).
    pub fn bones_outside_skin(&self) -> Option<Vec<SkinBreach>> {
        self.tissue
            .as_ref()
            .and_then(|t| t.bones_outside_skin(&self.frames))
    }

    /// Every soundness check of the tissue now ([`Tissue::audit`]): folded and squashed
    /// fat, muscles and bones out through the skin, muscles in bone and in one another,
    /// skin crossings. Exact, about a second on a whole leg: for checks, not every frame.
    /// None when tissue is disabled.
    pub fn audit(&self) -> Option<TissueAudit> {
        self.tissue.as_ref().map(|t| t.audit(&self.frames))
    }

    /// Wall-clock time spent in `step` since the build or `reset_timers`.
    pub fn timers(&self) -> &StepTimers {
        &self.timers
    }

    /// Starts the step timers from zero.
    pub fn reset_timers(&mut self) {
        self.timers = StepTimers::default();
    }

    /// Updates the tissue now for the current pose (also done automatically at
    /// `tissue.rate_hz` while stepping).
    pub fn update_tissue(&mut self) -> Result<()> {
        let angle = self.knee_angle();
        if let Some(t) = &mut self.tissue
            && !t.update(angle, &self.frames, &self.muscles)
        {
            return Err(Error::NonFinite {
                time: self.time,
                what: "tissue".into(),
            });
        }
        Ok(())
    }

    /// The muscle-tendon units, in lattice order.
    pub fn muscles(&self) -> &[MuscleUnit] {
        &self.muscles
    }

    /// Muscle names, in order.
    pub fn muscle_names(&self) -> Vec<&str> {
        self.muscles.iter().map(|m| m.name.as_str()).collect()
    }

    /// Index of a muscle by name.
    pub fn muscle_index(&self, name: &str) -> Result<usize> {
        self.muscles
            .iter()
            .position(|m| m.name == name)
            .ok_or_else(|| {
                Error::unknown_name("muscle", name, self.muscles.iter().map(|m| m.name.as_str()))
            })
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Muscle steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Knee flexion angle (rad).
    pub fn knee_angle(&self) -> f64 {
        self.skeleton.knee_angle()
    }

    /// The knee's flexion axis in the world now (it turns with the thigh).
    pub fn knee_axis(&self) -> Axis {
        let knee = self.skeleton.knee();
        Axis {
            point: self.frames.point(BodyId::Thigh, knee.point),
            dir: self.frames.vector(BodyId::Thigh, knee.axis),
        }
    }

    /// Knee flexion velocity (rad/s).
    pub fn knee_velocity(&self) -> f64 {
        self.skeleton.knee_velocity()
    }

    /// Net muscle torque about the knee in the last step (N m), positive flexing.
    pub fn knee_torque(&self) -> f64 {
        self.knee_torque
    }

    /// Sets one muscle's excitation (and drops its schedule).
    pub fn set_excitation(&mut self, name: &str, value: f64) -> Result<()> {
        let i = self.muscle_index(name)?;
        check_range(&format!("excitation of {name}"), value, 0.0, 1.0)?;
        self.muscles[i].excitation = value;
        self.schedules[i] = None;
        Ok(())
    }

    /// Sets every muscle's excitation, in muscle order.
    pub fn set_excitations(&mut self, values: &[f64]) -> Result<()> {
        if values.len() != self.muscles.len() {
            return Err(Error::invalid(
                "excitations",
                format!("{} values", values.len()),
                format!("expected one per muscle ({})", self.muscles.len()),
            ));
        }
        for (i, v) in values.iter().enumerate() {
            check_range(
                &format!("excitation of {}", self.muscles[i].name),
                *v,
                0.0,
                1.0,
            )?;
        }
        for (i, v) in values.iter().enumerate() {
            self.muscles[i].excitation = *v;
            self.schedules[i] = None;
        }
        Ok(())
    }

    /// Excitations in muscle order.
    pub fn excitations(&self) -> Vec<f64> {
        self.muscles.iter().map(|m| m.excitation).collect()
    }

    /// Drives a muscle's excitation by a schedule of absolute simulation time.
    pub fn set_schedule(&mut self, name: &str, schedule: Schedule) -> Result<()> {
        let i = self.muscle_index(name)?;
        self.muscles[i].excitation = schedule.value(self.time);
        self.schedules[i] = Some(schedule);
        Ok(())
    }

    /// What one muscle reports.
    pub fn muscle(&self, name: &str) -> Result<MuscleReadout> {
        Ok(self.readout(self.muscle_index(name)?))
    }

    /// What muscle `i` reports.
    pub fn readout(&self, i: usize) -> MuscleReadout {
        let m = &self.muscles[i];
        MuscleReadout {
            name: m.name.clone(),
            group: m.group,
            excitation: m.excitation,
            activation: m.activation,
            force: m.force,
            fibre_length: m.fibre.length,
            normalised_fibre_length: m.fibre.length / m.hill.optimal_fibre_length,
            moment_arm: m.moment_arm,
            path_length: m.path_length,
            tendon: m.tendon,
        }
    }

    /// Puts the knee at `angle` (rad) and `velocity` (rad/s), moving the muscle chains
    /// with the shank.
    pub fn set_knee(&mut self, angle: f64, velocity: f64) -> Result<()> {
        let [lo, hi] = self.skeleton.limits();
        check_range("knee angle (rad)", angle, lo, hi)?;
        check_range("knee velocity (rad/s)", velocity, -100.0, 100.0)?;
        let before = self.frames;
        // Sweep the wrapped tendons through the intermediate angles so each ends up on
        // the side continuous motion would have put it.
        let start = self.knee_angle();
        let steps = ((angle - start).abs() / 1f64.to_radians()).ceil().max(1.0) as usize;
        let knee = *self.skeleton.knee();
        for k in 1..=steps {
            let a = start + (angle - start) * k as f64 / steps as f64;
            let q = glam::Quat::from_axis_angle(knee.axis, a as f32);
            let shank = (q, knee.point - q * knee.point);
            let frames = BodyFrames {
                thigh: before.thigh,
                shank,
            };
            for m in &mut self.muscles {
                let Some(w) = m.chain.wrap else { continue };
                let i = m.chain.wrap_segment;
                let place = |j: usize, chain: &crate::muscle::MuscleChain| -> Vec3 {
                    let b = chain.point_body(j);
                    let rest = match b {
                        BodyId::Shank => before.shank.0.inverse() * (chain.x[j] - before.shank.1),
                        BodyId::Thigh => before.thigh.0.inverse() * (chain.x[j] - before.thigh.1),
                    };
                    frames.point(b, rest)
                };
                let (p, q) = (place(i, &m.chain), place(i + 1, &m.chain));
                m.chain.wrapped = w.path(p, q, m.chain.wrapped).wrapped;
            }
        }
        self.skeleton.set_knee(angle, velocity);
        self.frames = self.current_frames();
        for m in &mut self.muscles {
            // Points anchored on the shank follow it; the rest stay.
            let n = m.chain.len();
            for i in 0..n {
                if let Some(c) = m.chain.cones[i]
                    && c.body == BodyId::Shank
                {
                    let rest = before.shank.0.inverse() * (m.chain.x[i] - before.shank.1);
                    m.chain.x[i] = self.frames.point(BodyId::Shank, rest);
                }
                m.chain.v[i] = Vec3::ZERO;
            }
        }
        self.reattach_muscles();
        if self.tissue.is_some() {
            // The fat follows a jump in a few relaxation passes.
            for _ in 0..4 {
                self.update_tissue()?;
            }
        }
        Ok(())
    }

    fn current_frames(&self) -> BodyFrames {
        let t = self.skeleton.pose(BodyId::Thigh);
        let s = self.skeleton.pose(BodyId::Shank);
        BodyFrames {
            thigh: (t.rotation, t.translation),
            shank: (s.rotation, s.translation),
        }
    }

    /// A checkpoint of everything that changes while stepping, the muscle and tendon models
    /// included (they may be switched mid-run).
    pub fn state(&self) -> SimulationState {
        SimulationState {
            time: self.time,
            steps: self.steps,
            skeleton: self.skeleton.clone(),
            muscles: self.muscles.clone(),
            frames: self.frames,
            knee_torque: self.knee_torque,
            tissue: self.tissue.clone(),
            models: (self.config.muscle_model, self.config.tendon),
        }
    }

    /// Restores a checkpoint taken from this simulation.
    pub fn set_state(&mut self, s: &SimulationState) -> Result<()> {
        if s.muscles.len() != self.muscles.len()
            || s.muscles
                .iter()
                .zip(&self.muscles)
                .any(|(a, b)| a.name != b.name || a.chain.len() != b.chain.len())
        {
            return Err(Error::StateMismatch(
                "the checkpoint has other muscles".into(),
            ));
        }
        self.time = s.time;
        self.steps = s.steps;
        self.skeleton = s.skeleton.clone();
        self.muscles = s.muscles.clone();
        self.frames = s.frames;
        self.knee_torque = s.knee_torque;
        self.tissue.clone_from(&s.tissue);
        (self.config.muscle_model, self.config.tendon) = s.models;
        Ok(())
    }
}
