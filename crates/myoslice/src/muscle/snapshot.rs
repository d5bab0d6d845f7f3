//! What a step changes in the muscles, saved so that a failed `step` call can put it back.

use glam::Vec3;

use super::chain::{MuscleChain, SegmentGeom};
use super::hill::FibreState;
use super::unit::MuscleUnit;

/// The state of every muscle that stepping changes (chain points and velocities, cached
/// segment geometry, wrap side, activation dynamics and path), in flat buffers reused from
/// save to save. Stepping leaves the rest (attachments, rest lengths, cones, parameters)
/// alone, so this is all a rollback needs; a full copy of the muscles cost 3.8 µs on the
/// phantom, a sixth of a 1 ms step.
#[derive(Debug, Clone, Default)]
pub(crate) struct MuscleSnapshot {
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
    pub(crate) fn save(&mut self, muscles: &[MuscleUnit]) {
        self.x.clear();
        self.v.clear();
        self.geom.clear();
        self.units.clear();
        for m in muscles {
            // Every field named, so that a new one needs a decision here: saved, or left
            // alone by stepping.
            let MuscleUnit {
                name: _,
                lattice_index: _,
                group: _,
                hill: _,
                built_hill: _,
                chain: c,
                crosses_knee: _,
                mass: _,
                bones: _,
                from_catalogue: _,
                excitation,
                activation,
                path_length,
                path_velocity,
                force,
                fibre,
                tendon: _,
                moment_arm,
                current_moment_arm,
            } = m;
            let MuscleChain {
                origin: _,
                insertion: _,
                x,
                v,
                mass: _,
                rest_len: _,
                tendon: _,
                cones: _,
                vias: _,
                cone_cos_tan: _,
                wrap: _,
                wrap_segment: _,
                wrapped,
                belly_rest: _,
                scratch: _,
                geom,
                bodies: _,
            } = c;
            self.x.extend_from_slice(x);
            self.v.extend_from_slice(v);
            self.geom.extend_from_slice(geom);
            self.units.push(UnitState {
                points: x.len(),
                segments: geom.len(),
                wrapped: *wrapped,
                excitation: *excitation,
                activation: *activation,
                path_length: *path_length,
                path_velocity: *path_velocity,
                force: *force,
                fibre: *fibre,
                moment_arm: *moment_arm,
                current_moment_arm: *current_moment_arm,
            });
        }
    }

    /// Puts the saved state back into the muscles it was saved from; false (and nothing
    /// changed) if their number or chain lengths differ from what was saved.
    pub(crate) fn restore(&self, muscles: &mut [MuscleUnit]) -> bool {
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
