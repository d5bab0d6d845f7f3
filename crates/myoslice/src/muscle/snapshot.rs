//! What a step changes in the muscles, saved so that a failed `step` call can put it back.

use glam::Vec3;

use super::chain::SegmentGeom;
use super::hill::FibreState;
use super::unit::MuscleUnit;

/// The state of every muscle that stepping changes (chain points and velocities, cached
/// segment geometry, wrap side, activation dynamics and path), in flat buffers reused from
/// save to save. Stepping leaves the rest (attachments, rest lengths, cones, parameters)
/// alone, so this is all a rollback needs; a full copy of the muscles cost 3.8 µs on the
/// phantom, a sixth of a 1 ms step.
#[derive(Debug, Clone, Default)]
pub struct MuscleSnapshot {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    geom: Vec<SegmentGeom>,
    units: Vec<UnitState>,
}

#[derive(Debug, Clone, Copy)]
struct UnitState {
    points: usize,
    segments: usize,
    wrapped: bool,
    excitation: f64,
    activation: f64,
    path_length: f64,
    path_velocity: f64,
    force: f64,
    fibre: FibreState,
    moment_arm: f64,
    current_moment_arm: f64,
}

impl MuscleSnapshot {
    /// Saves the muscles' changing state (replacing what was saved).
    pub fn save(&mut self, muscles: &[MuscleUnit]) {
        self.x.clear();
        self.v.clear();
        self.geom.clear();
        self.units.clear();
        for m in muscles {
            let c = &m.chain;
            self.x.extend_from_slice(&c.x);
            self.v.extend_from_slice(&c.v);
            self.geom.extend_from_slice(&c.geom);
            self.units.push(UnitState {
                points: c.x.len(),
                segments: c.geom.len(),
                wrapped: c.wrapped,
                excitation: m.excitation,
                activation: m.activation,
                path_length: m.path_length,
                path_velocity: m.path_velocity,
                force: m.force,
                fibre: m.fibre,
                moment_arm: m.moment_arm,
                current_moment_arm: m.current_moment_arm,
            });
        }
    }

    /// Puts the saved state back into the same muscles; false (and nothing changed) if
    /// they are not the ones saved.
    pub fn restore(&self, muscles: &mut [MuscleUnit]) -> bool {
        let same = muscles.len() == self.units.len()
            && muscles
                .iter()
                .zip(&self.units)
                .all(|(m, u)| m.chain.x.len() == u.points && m.chain.v.len() == u.points);
        if !same {
            return false;
        }
        let (mut p, mut s) = (0, 0);
        for (m, u) in muscles.iter_mut().zip(&self.units) {
            let c = &mut m.chain;
            c.x.copy_from_slice(&self.x[p..p + u.points]);
            c.v.copy_from_slice(&self.v[p..p + u.points]);
            c.geom.clear();
            c.geom.extend_from_slice(&self.geom[s..s + u.segments]);
            c.wrapped = u.wrapped;
            (m.excitation, m.activation, m.force) = (u.excitation, u.activation, u.force);
            (m.path_length, m.path_velocity, m.fibre) = (u.path_length, u.path_velocity, u.fibre);
            (m.moment_arm, m.current_moment_arm) = (u.moment_arm, u.current_moment_arm);
            p += u.points;
            s += u.segments;
        }
        true
    }
}
