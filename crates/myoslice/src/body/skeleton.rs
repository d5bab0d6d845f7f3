//! The rapier skeleton: pelvis + femur fixed, tibia + fibula + patella (+ foot mass) one
//! dynamic body on a revolute knee with hard flexion limits.

use glam::{Quat, Vec3};
use rapier3d::prelude::*;

use super::knee::KneeAxis;
use super::segments::{SegmentInertia, shank_and_foot};
use crate::error::{Error, Result};
use crate::lattice::Lattice;

/// Which rigid body a bone belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum BodyId {
    /// Pelvis and femur: fixed (the paper moves only the knee).
    Thigh,
    /// Tibia, fibula, patella and the foot's mass.
    Shank,
}

/// The body a bone of the given name is carried by.
pub fn body_of_bone(name: &str) -> BodyId {
    match name {
        "tibia" | "fibula" | "patella" | "talus" | "calcaneus" | "foot" => BodyId::Shank,
        _ => BodyId::Thigh,
    }
}

/// Skeleton options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkeletonOptions {
    /// Body mass (kg) for Dempster's segment mass.
    pub body_mass: f64,
    /// Body height (m) for Dempster's segment length.
    pub height: f64,
    /// Flexion limits (rad): extension, deepest flexion.
    pub limits: [f64; 2],
    /// Viscous joint damping (N m s/rad).
    pub damping: f64,
    /// Gravity (m/s²).
    pub gravity: [f64; 3],
}

/// The rigid skeleton and its rapier world.
pub struct Skeleton {
    bodies: RigidBodySet,
    colliders: ColliderSet,
    multibody: MultibodyJointSet,
    impulse: ImpulseJointSet,
    islands: IslandManager,
    broad: DefaultBroadPhase,
    narrow: NarrowPhase,
    ccd: CCDSolver,
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    gravity: Vector,
    thigh: RigidBodyHandle,
    shank: RigidBodyHandle,
    knee: KneeAxis,
    limits: [f64; 2],
    inertia: SegmentInertia,
    com: Vec3,
    bone_colliders: Vec<(BodyId, ColliderHandle)>,
}

impl std::fmt::Debug for Skeleton {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Skeleton")
            .field("knee", &self.knee)
            .field("limits", &self.limits)
            .field("inertia", &self.inertia)
            .finish_non_exhaustive()
    }
}

impl Clone for Skeleton {
    fn clone(&self) -> Self {
        Self {
            bodies: self.bodies.clone(),
            colliders: self.colliders.clone(),
            multibody: self.multibody.clone(),
            impulse: self.impulse.clone(),
            islands: self.islands.clone(),
            broad: self.broad.clone(),
            narrow: self.narrow.clone(),
            ccd: self.ccd.clone(),
            // The pipeline only holds scratch buffers that every step refills.
            pipeline: PhysicsPipeline::new(),
            params: self.params,
            gravity: self.gravity,
            thigh: self.thigh,
            shank: self.shank,
            knee: self.knee,
            limits: self.limits,
            inertia: self.inertia,
            com: self.com,
            bone_colliders: self.bone_colliders.clone(),
        }
    }
}

/// The skeleton's moving state (knee joint coordinates and velocities), copied without
/// allocation: what a failed step puts back. A full clone of the rapier world costs
/// about 5 us, a seventh of a 1 ms muscle step.
#[derive(Debug, Clone, Copy)]
pub struct SkeletonSnapshot {
    joint: Option<MultibodyJoint>,
    velocities: [f32; 12],
    linvel: Vec3,
    angvel: Vec3,
}

impl Skeleton {
    /// Builds the skeleton of a lattice about its knee axis.
    pub fn new(lattice: &Lattice, knee: KneeAxis, opts: &SkeletonOptions) -> Result<Self> {
        let tibia = lattice.bone("tibia").ok_or_else(|| {
            Error::Build("the lattice has no 'tibia' bone: the knee needs one".into())
        })?;
        // The shank's long axis: from the knee axis point to the centre of the tibia's
        // lowest ring.
        let lowest = tibia
            .mesh
            .rings
            .iter()
            .filter(|r| !r.cap)
            .min_by_key(|r| r.k)
            .map(|r| tibia.mesh.vertices[r.centre as usize])
            .ok_or_else(|| Error::Build("the tibia has no rings".into()))?;
        let dir = (lowest - knee.point).normalize_or(Vec3::NEG_Z);
        let radius = shank_radius(lattice, knee.point, dir);
        let inertia = shank_and_foot(opts.body_mass, opts.height, radius);
        let com = knee.point + dir * inertia.com_from_proximal as f32;
        let it = inertia.inertia_transverse as f32;
        let props = MassProperties::with_principal_inertia_frame(
            com,
            inertia.mass as f32,
            Vec3::new(it, it, inertia.inertia_long as f32),
            Quat::from_rotation_arc(Vec3::Z, dir),
        );
        let mut bodies = RigidBodySet::new();
        let thigh = bodies.insert(RigidBodyBuilder::fixed().build());
        let shank = bodies.insert(
            RigidBodyBuilder::dynamic()
                .additional_mass_properties(props)
                .can_sleep(false)
                .build(),
        );
        // Bone surfaces as colliders (rest frame = body frame): for queries, no contacts.
        let mut colliders = ColliderSet::new();
        let mut bone_colliders = Vec::new();
        for b in &lattice.bones {
            let body = body_of_bone(&b.name);
            let builder =
                ColliderBuilder::trimesh(b.mesh.vertices.clone(), b.mesh.triangles.clone())
                    .map_err(|e| {
                        Error::Build(format!("bone '{}' is not a valid mesh: {e}", b.name))
                    })?
                    .density(0.0)
                    .collision_groups(InteractionGroups::none());
            let parent = if body == BodyId::Thigh { thigh } else { shank };
            let h = colliders.insert_with_parent(builder.build(), parent, &mut bodies);
            bone_colliders.push((body, h));
        }
        let joint = RevoluteJointBuilder::new(knee.axis)
            .local_anchor1(knee.point)
            .local_anchor2(knee.point)
            .limits([opts.limits[0] as f32, opts.limits[1] as f32])
            .contacts_enabled(false)
            .build();
        let mut multibody = MultibodyJointSet::new();
        multibody
            .insert(thigh, shank, joint, true)
            .ok_or_else(|| Error::Build("rapier refused the knee joint".into()))?;
        let params = IntegrationParameters {
            dt: 1e-3,
            // One solver pass per 1 ms step: a single joint limit is the only constraint,
            // and rapier's default of four substeps quadruples the multibody work for no
            // accuracy the motion tests can see (pendulum period, energy, limits).
            num_solver_iterations: 1,
            ..IntegrationParameters::default()
        };
        let mut sk = Self {
            bodies,
            colliders,
            multibody,
            impulse: ImpulseJointSet::new(),
            islands: IslandManager::new(),
            broad: DefaultBroadPhase::default(),
            narrow: NarrowPhase::new(),
            ccd: CCDSolver::new(),
            pipeline: PhysicsPipeline::new(),
            params,
            gravity: Vector::new(
                opts.gravity[0] as f32,
                opts.gravity[1] as f32,
                opts.gravity[2] as f32,
            ),
            thigh,
            shank,
            knee,
            limits: opts.limits,
            inertia,
            com,
            bone_colliders,
        };
        sk.set_damping(opts.damping);
        Ok(sk)
    }

    fn multibody_mut(&mut self) -> Option<&mut Multibody> {
        let link = *self.multibody.rigid_body_link(self.shank)?;
        self.multibody.get_multibody_mut(link.multibody)
    }

    /// Sets the viscous knee damping (N m s/rad).
    pub fn set_damping(&mut self, c: f64) {
        if let Some(mb) = self.multibody_mut() {
            for d in mb.damping_mut().iter_mut() {
                *d = c as f32;
            }
        }
    }

    /// The knee axis.
    pub fn knee(&self) -> &KneeAxis {
        &self.knee
    }

    /// Flexion limits (rad).
    pub fn limits(&self) -> [f64; 2] {
        self.limits
    }

    /// Dempster inertia of the shank + foot.
    pub fn inertia(&self) -> &SegmentInertia {
        &self.inertia
    }

    /// Centre of mass of the shank at rest (world, m).
    pub fn shank_com_rest(&self) -> Vec3 {
        self.com
    }

    /// Gravity (m/s²).
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Pose of a body (rest frame to world).
    pub fn pose(&self, body: BodyId) -> Pose {
        let h = if body == BodyId::Thigh {
            self.thigh
        } else {
            self.shank
        };
        self.bodies.get(h).map_or(Pose::IDENTITY, |b| *b.position())
    }

    /// Knee flexion angle (rad), from the relative rotation of the two bodies.
    pub fn knee_angle(&self) -> f64 {
        let q = self.pose(BodyId::Thigh).rotation.inverse() * self.pose(BodyId::Shank).rotation;
        let s = Vec3::new(q.x, q.y, q.z).dot(self.knee.axis);
        2.0 * f64::from(s).atan2(f64::from(q.w))
    }

    /// Knee flexion velocity (rad/s).
    pub fn knee_velocity(&self) -> f64 {
        let w = self
            .bodies
            .get(self.shank)
            .map_or(Vec3::ZERO, |b| b.angvel());
        f64::from(w.dot(self.knee.axis))
    }

    /// The moving state now (see [`SkeletonSnapshot`]).
    pub fn snapshot(&self) -> SkeletonSnapshot {
        let mut velocities = [0.0; 12];
        let mut joint = None;
        if let Some(link) = self.multibody.rigid_body_link(self.shank).copied()
            && let Some(mb) = self.multibody.get_multibody(link.multibody)
        {
            joint = mb.link(link.id).map(|l| l.joint);
            debug_assert!(
                mb.ndofs() <= velocities.len(),
                "a multibody of at most 12 dofs"
            );
            for (v, &g) in velocities.iter_mut().zip(mb.generalized_velocity().iter()) {
                *v = g;
            }
        }
        let (linvel, angvel) = self
            .bodies
            .get(self.shank)
            .map_or((Vec3::ZERO, Vec3::ZERO), |b| (b.linvel(), b.angvel()));
        SkeletonSnapshot {
            joint,
            velocities,
            linvel,
            angvel,
        }
    }

    /// Puts back a state taken by [`Self::snapshot`] of this skeleton: the joint
    /// coordinates exactly, the body poses by forward kinematics from them.
    pub fn restore(&mut self, s: &SkeletonSnapshot) {
        if let Some(link) = self.multibody.rigid_body_link(self.shank).copied()
            && let Some(mb) = self.multibody.get_multibody_mut(link.multibody)
        {
            if let (Some(l), Some(joint)) = (mb.link_mut(link.id), s.joint) {
                l.joint = joint;
            }
            for (g, &v) in mb.generalized_velocity_mut().iter_mut().zip(&s.velocities) {
                *g = v;
            }
            mb.forward_kinematics(&self.bodies, true);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
        if let Some(b) = self.bodies.get_mut(self.shank) {
            // Rapier disables a body whose pose went non-finite (the step reports it);
            // the snapshot's state is finite, so the body can move again.
            if !b.is_enabled() {
                b.set_enabled(true);
            }
            b.set_linvel(s.linvel, true);
            b.set_angvel(s.angvel, true);
        }
        for &(_, h) in &self.bone_colliders {
            if let Some(c) = self.colliders.get_mut(h)
                && !c.is_enabled()
            {
                c.set_enabled(true);
            }
        }
    }

    /// Puts the knee at `angle` (rad) with flexion velocity `velocity` (rad/s).
    pub fn set_knee(&mut self, angle: f64, velocity: f64) {
        let delta = (angle - self.knee_angle()) as f32;
        let shank = self.shank;
        let Some(link) = self.multibody.rigid_body_link(shank).copied() else {
            return;
        };
        if let Some(mb) = self.multibody.get_multibody_mut(link.multibody) {
            let n = mb.ndofs();
            let mut disp = vec![0.0; n];
            if let Some(d) = disp.last_mut() {
                *d = delta;
            }
            mb.apply_displacements(&disp);
            if let Some(v) = mb.generalized_velocity_mut().iter_mut().last() {
                *v = velocity as f32;
            }
            mb.forward_kinematics(&self.bodies, true);
            mb.update_rigid_bodies(&mut self.bodies, true);
        }
        if let Some(b) = self.bodies.get_mut(shank) {
            let w = self.knee.axis * velocity as f32;
            let p = b.position().transform_point(self.knee.point);
            let c = b.center_of_mass();
            b.set_angvel(w, true);
            b.set_linvel(w.cross(c - p), true);
        }
    }

    /// Advances by `dt` with `forces` (world force, world application point) acting on
    /// the shank. Returns false if rapier had to stop a body whose pose went non-finite
    /// (it puts the body back and freezes it: the step did not happen as asked).
    pub fn step(&mut self, dt: f64, forces: &[(Vec3, Vec3)]) -> bool {
        if let Some(b) = self.bodies.get_mut(self.shank) {
            b.reset_forces(true);
            b.reset_torques(true);
            for &(f, p) in forces {
                b.add_force_at_point(f, p, true);
            }
        }
        self.params.dt = dt as f32;
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad,
            &mut self.narrow,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse,
            &mut self.multibody,
            &mut SoftBodySet::default(),
            &mut self.ccd,
            &(),
            &(),
        );
        self.pipeline.quarantine().is_empty()
    }

    /// Velocity (world, m/s) of the shank material point now at world position `p`.
    pub fn shank_point_velocity(&self, p: Vec3) -> Vec3 {
        self.bodies
            .get(self.shank)
            .map_or(Vec3::ZERO, |b| b.velocity_at_point(p))
    }

    /// Kinetic + gravitational potential energy of the shank (J), zero potential at rest.
    /// On the hinge the kinetic energy is `½ I_knee θ̇²` with the inertia about the axis.
    pub fn shank_energy(&self) -> f64 {
        let pose = self.pose(BodyId::Shank);
        let com = pose.transform_point(self.com);
        let r = self.com - self.knee.point;
        let d2 = f64::from((r - self.knee.axis * r.dot(self.knee.axis)).length_squared());
        let m = self.inertia.mass;
        let i_knee = self.inertia.inertia_transverse + m * d2;
        let w = self.knee_velocity();
        let pe = -m * self.gravity.as_dvec3().dot((com - self.com).as_dvec3());
        0.5 * i_knee * w * w + pe
    }

    /// The collider of each lattice bone, with its body (lattice bone order).
    pub fn bone_colliders(&self) -> &[(BodyId, ColliderHandle)] {
        &self.bone_colliders
    }

    /// The triangle mesh of a lattice bone (rest coordinates = body frame).
    pub fn bone_trimesh(&self, bone: usize) -> Option<&TriMesh> {
        let (_, h) = self.bone_colliders.get(bone)?;
        self.colliders.get(*h)?.shape().as_trimesh()
    }
}

/// Mean radius of the body outline (skin) around the shank axis, for its long-axis inertia.
fn shank_radius(lattice: &Lattice, knee: Vec3, dir: Vec3) -> f64 {
    let fat = &lattice.fat;
    let mut sum = 0.0;
    let mut n = 0.0;
    for s in 0..fat.slices {
        let c = fat.reference[s];
        if (c - knee).dot(dir) <= 0.05 {
            continue;
        }
        for j in 0..fat.rays {
            let p = fat.vertices[fat.vertex_index(s, j, fat.layers) as usize];
            let r = (p - c) - dir * (p - c).dot(dir);
            sum += f64::from(r.length());
            n += 1.0;
        }
    }
    if n > 0.0 { sum / n } else { 0.05 }
}
