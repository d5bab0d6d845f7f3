//! Stepping: one call of `step` split into muscle and skeleton steps with the tissue
//! updated at its own rate, rolled back whole if anything fails.

use std::panic::AssertUnwindSafe;
use web_time::Instant;

use glam::Vec3;

use super::{MuscleModel, Simulation, TendonModel};
use crate::body::BodyId;
use crate::error::{Error, Result, check_positive};
use crate::muscle::hill::activation_rate;
use crate::muscle::{Axis, ChainLoad, MuscleSnapshot, Tether};
use crate::tissue::TissueBackup;

/// Largest force (N) one muscle may apply to the shank: a hundred times the strongest
/// human muscle's; beyond it the step has blown up.
const MAX_BODY_FORCE_N: f32 = 1e6;

/// The muscles as a `step` call found them, in buffers reused from call to call. A clone
/// of the simulation starts with empty ones: they hold nothing between calls.
#[derive(Debug, Default)]
pub(super) struct Rollback {
    muscles: MuscleSnapshot,
}

impl Clone for Rollback {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl Simulation {
    /// Advances the simulation by `dt` seconds (split into steps of at most
    /// `max_step_s`). If anything becomes non-finite, the whole simulation (muscles,
    /// skeleton, tissue and clocks) goes back to its state before the call and an error
    /// says what failed.
    ///
    /// While a tissue update runs its validity guard, the muscles and the skeleton take
    /// their steps to the next update on another thread, and the next update's muscle
    /// shapes are placed there: the guard reads none of them, and placing the shapes
    /// reads no fat, so the results are those of running one after the other, bit for
    /// bit.
    pub fn step(&mut self, dt: f64) -> Result<()> {
        check_positive("dt", dt)?;
        if dt > 10.0 {
            return Err(Error::invalid("dt", dt, "expected at most 10 s per call"));
        }
        let n = (dt / self.config.max_step_s).ceil().max(1.0) as usize;
        let h = dt / n as f64;
        let start = Instant::now();
        // The muscles save what a step changes into buffers kept from call to call, the
        // skeleton its joint state (a clone of the rapier world would cost a seventh of a
        // 1 ms step), the tissue a copy of itself (its model shared) before its first
        // update in the call.
        let mut rollback = std::mem::take(&mut self.rollback);
        rollback.muscles.save(&self.muscles);
        let skeleton = self.skeleton.snapshot();
        let saved = (self.time, self.steps, self.frames, self.knee_torque);
        // The tissue's clock at the start, so that its updates fall where a twin that
        // never failed has them.
        let clock = self.tissue.as_ref().map(|t| (t.pending, t.period()));
        let mut pending = clock.map(|(p, _)| p);
        let period = clock.map_or(f64::INFINITY, |(_, p)| p);
        let mut tissue_backup: Option<TissueBackup> = None;
        let mut taken = 0;
        // (when, what) of the first failure.
        let mut failure: Option<(f64, String)> = None;
        let mut due = match self.segment(n, h, &mut taken, pending.as_mut(), period) {
            Ok(due) => due,
            Err(f) => {
                failure = Some(f);
                false
            }
        };
        while due {
            let Some(mut t) = self.tissue.take() else {
                break;
            };
            let when = self.time;
            // The guard never reads the skeleton, the muscles or their shapes: they step
            // on to the next update beside it, and that update's shapes are placed
            // (their steps are serial and the guard mostly so, so each fills the other's
            // idle core). Same results as one after the other.
            let joined = std::panic::catch_unwind(AssertUnwindSafe(|| {
                let t0 = Instant::now();
                tissue_backup.get_or_insert_with(|| t.backup());
                let front = t.update_front(self.knee_angle(), &self.frames, &self.muscles);
                let front_s = t0.elapsed();
                let (back, next) = t.update_back_beside(front, |placing| {
                    let next = self.segment(n, h, &mut taken, pending.as_mut(), period);
                    // The next update is due: its muscle shapes are placed now, while
                    // the guard still runs.
                    if let Ok(true) = next {
                        placing.place(self.knee_angle(), &self.frames, &self.muscles);
                    }
                    next
                });
                (front_s, back, next)
            }));
            let (front_s, (updated, back_s), next) = match joined {
                Ok(r) => r,
                Err(panic) => {
                    // The tissue goes back in place before the panic goes on.
                    self.tissue = Some(t);
                    std::panic::resume_unwind(panic)
                }
            };
            self.timers.add_tissue(front_s + back_s, &t.last_phases);
            self.tissue = Some(t);
            if !updated {
                failure = Some((when, "fat or muscle shape".into()));
                break;
            }
            match next {
                Ok(d) => due = d,
                Err(f) => {
                    failure = Some(f);
                    break;
                }
            }
        }
        if let (Some(t), Some(p)) = (&mut self.tissue, pending) {
            t.pending = p;
        }
        let result = match failure {
            None => Ok(()),
            Some((time, what)) => {
                (self.time, self.steps, self.frames, self.knee_torque) = saved;
                self.skeleton.restore(&skeleton);
                if let Some(t) = &mut self.tissue {
                    if let Some(b) = tissue_backup.take() {
                        t.restore(b);
                    }
                    if let Some((pending, _)) = clock {
                        t.pending = pending;
                    }
                }
                let what = if rollback.muscles.restore(&mut self.muscles) {
                    what
                } else {
                    format!("{what} (and the muscles could not be put back)")
                };
                Err(Error::NonFinite { time, what })
            }
        };
        self.rollback = rollback;
        let advanced = self.time - saved.0;
        self.timers
            .add_call(start.elapsed(), taken as u64, advanced);
        result
    }

    /// Muscle and skeleton steps of `h` from step `*taken` of `n` on, until the tissue
    /// (its clock at `pending`, `period` apart; none without tissue) has an update due
    /// (true: the caller runs it) or all `n` are taken (false). Err((when, what)) if a
    /// step failed.
    fn segment(
        &mut self,
        n: usize,
        h: f64,
        taken: &mut usize,
        mut pending: Option<&mut f64>,
        period: f64,
    ) -> std::result::Result<bool, (f64, String)> {
        while *taken < n {
            *taken += 1;
            if let Some(what) = self.substep(h).or_else(|| self.non_finite()) {
                return Err((self.time, what));
            }
            if let Some(p) = pending.as_deref_mut()
                && crate::tissue::clock_due(p, period, h)
            {
                return Ok(true);
            }
        }
        Ok(false)
    }

    pub(super) fn non_finite(&self) -> Option<String> {
        if !self.knee_angle().is_finite() || !self.knee_velocity().is_finite() {
            return Some("knee angle".into());
        }
        for m in &self.muscles {
            // A NaN or infinity anywhere makes the sum non-finite (positions are metres:
            // no finite sum overflows); one branch per muscle instead of one per point.
            let sum: Vec3 = m.chain.x.iter().copied().sum();
            if !m.force.is_finite() || !sum.is_finite() {
                return Some(format!("muscle {}", m.name));
            }
        }
        None
    }

    /// One step of the muscles and the skeleton; says what failed if it could not run.
    pub(super) fn substep(&mut self, h: f64) -> Option<String> {
        let gravity = self.skeleton.gravity();
        let knee = *self.skeleton.knee();
        let hill = self.config.muscle_model == MuscleModel::Hill;
        let (mut forces, mut loads) = std::mem::take(&mut self.scratch);
        forces.clear();
        loads.clear();
        let mut torque = 0.0;
        let frames = self.frames;
        let knee_point = frames.point(BodyId::Thigh, knee.point);
        let knee_dir = frames.vector(BodyId::Thigh, knee.axis);
        let tether = Tether {
            stiffness: self.config.chain_tether as f32,
            release: self.config.chain_tether_release_n as f32,
        };
        for (m, sched) in self.muscles.iter_mut().zip(&self.schedules) {
            if let Some(s) = sched {
                m.excitation = s.value(self.time);
            }
            let load = ChainLoad {
                contraction: 0.0,
                stiffness: (self.config.chain_stiffness * m.hill.max_isometric_force) as f32,
                neutral_springs: hill,
                gravity,
                tether,
            };
            let quiet = !m.crosses_knee
                && m.excitation == 0.0
                && m.activation < 1e-4
                && m.force < 1e-3 * m.hill.max_isometric_force;
            if quiet && m.chain.single_body().is_some() {
                // At rest on one body: no force to compute or apply.
                m.force = 0.0;
                m.moment_arm = 0.0;
                loads.push(load);
                continue;
            }
            let (tension, ends) = if hill {
                m.fibre = if m.tendon == TendonModel::Compliant {
                    m.hill.compliant_tendon_step(
                        m.activation,
                        m.path_length,
                        m.fibre.length,
                        Some(h),
                    )
                } else {
                    m.hill
                        .rigid_tendon_kinematics(m.path_length, m.path_velocity)
                };
                let f = m.hill.force(m.activation, &m.fibre);
                m.force = f.tendon;
                (f.tendon as f32, None)
            } else {
                m.activation = m.excitation;
                let c = (m.excitation * m.hill.max_isometric_force) as f32;
                let load = ChainLoad {
                    contraction: c,
                    ..load
                };
                let e = m.chain.end_forces(&load);
                m.force = f64::from(e.insertion.length());
                m.fibre = m
                    .hill
                    .rigid_tendon_kinematics(m.path_length, m.path_velocity);
                (c, Some(e))
            };
            loads.push(ChainLoad {
                contraction: tension,
                ..load
            });
            let mut tau = 0.0;
            if let Some(ends) = ends {
                // The paper's model: only the end points pull the bones.
                let n = m.chain.len();
                let ends_on_shank = [
                    (m.chain.origin.body, ends.origin, m.chain.x[0]),
                    (m.chain.insertion.body, ends.insertion, m.chain.x[n - 1]),
                ];
                for (body, f, at) in ends_on_shank {
                    if body == BodyId::Shank {
                        forces.push((f, at));
                        tau += f64::from((at - knee_point).cross(f).dot(knee_dir));
                    }
                }
            } else if m.crosses_knee {
                // The tendon force pulls the shank where the path first reaches it (the
                // patella for the quadriceps), so the torque is exactly force × moment arm.
                // (A muscle that does not cross the knee pulls only within its bone.)
                for p in m.chain.pulls_on(BodyId::Shank) {
                    let f = p.dir * tension;
                    forces.push((f, p.at));
                    tau += f64::from((p.at - knee_point).cross(f).dot(knee_dir));
                }
            }
            m.moment_arm = if m.crosses_knee {
                m.current_moment_arm
            } else {
                0.0
            };
            torque += tau;
        }
        self.knee_torque = torque;
        // Rapier quarantines (disables) a body whose pose turns non-finite, which only a
        // full copy of its world could undo; no muscle pulls with a meganewton, so such
        // a force is refused before rapier sees it and the step fails cleanly.
        let unbounded = forces
            .iter()
            .find(|(f, at)| !(f.length() <= MAX_BODY_FORCE_N && at.is_finite()));
        if let Some(&(f, _)) = unbounded {
            let what = format!("an unbounded muscle force of {} N on the shank", f.length());
            self.scratch = (forces, loads);
            return Some(what);
        }
        if !self.skeleton.step(h, &forces) {
            self.scratch = (forces, loads);
            return Some("the shank's pose (rapier stopped it)".into());
        }
        let next = self.current_frames();
        // The thigh is fixed: the shank turns about the knee axis, so the path lengthens at
        // −(moment arm) × knee velocity (virtual work).
        let knee_velocity = self.skeleton.knee_velocity();
        let axis = Axis {
            point: next.point(BodyId::Thigh, knee.point),
            dir: next.vector(BodyId::Thigh, knee.axis),
        };
        let mut moving = std::mem::take(&mut self.moving);
        moving.clear();
        for (m, load) in self.muscles.iter_mut().zip(&loads) {
            // A muscle at rest on one body is carried with it; only loaded or
            // knee-crossing chains need their dynamics.
            let quiet = m.excitation == 0.0
                && m.activation < 1e-4
                && m.force < 1e-3 * m.hill.max_isometric_force;
            match m.chain.single_body() {
                Some(b) if quiet => {
                    m.chain.carry(b, &frames, &next, h as f32);
                    moving.push(false);
                }
                _ => {
                    m.chain.advance(h as f32, &next, load);
                    moving.push(true);
                }
            }
            if hill {
                let rate = activation_rate(
                    m.excitation,
                    m.activation,
                    m.hill.tau_activation,
                    m.hill.tau_deactivation,
                    10.0,
                );
                m.activation = (m.activation + h * rate).clamp(0.0, 1.0);
            }
        }
        if self.contact.project(&mut self.muscles, &moving) {
            for (m, _) in self.muscles.iter_mut().zip(&moving).filter(|(_, mv)| **mv) {
                m.chain.update_wrap();
            }
        }
        self.moving = moving;
        for m in &mut self.muscles {
            m.path_length = m.chain.path_length();
            if m.crosses_knee {
                // Computed once per step on the new geometry; the next step's torque
                // report and the fibre velocity both use it.
                m.current_moment_arm = m.chain.moment_arm(&axis, BodyId::Shank);
                m.path_velocity = -m.current_moment_arm * knee_velocity;
            } else {
                // Both ends and every cone on one rigid body: no excursion.
                m.path_velocity = 0.0;
            }
        }
        self.frames = next;
        self.time += h;
        self.steps += 1;
        self.scratch = (forces, loads);
        None
    }
}
