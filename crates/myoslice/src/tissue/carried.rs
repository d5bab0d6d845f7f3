//! The tissue between its updates: what the last update left, carried with the bones to
//! where they are now. The tissue updates at its own rate (30 Hz by default) while the
//! skeleton steps every millisecond; a viewer drawing every frame would otherwise show
//! the bones moving under skin and muscles that jump at each update.

use glam::{Quat, Vec3};

use super::{KneeFold, Tissue};
use crate::muscle::BodyFrames;
use crate::par::*;

/// Fat and muscle vertices of the last tissue update carried to the skeleton's pose now
/// (see [`Tissue::carried`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CarriedTissue {
    /// Fat vertices, lattice order.
    pub fat: Vec<Vec3>,
    /// Each muscle shape's vertices, muscle order.
    pub muscles: Vec<Vec<Vec3>>,
}

impl Tissue {
    /// The fat and muscles of the last update, carried to the knee at `knee_angle` (rad)
    /// and the bodies at `frames`: each vertex turns about the knee axis by the share of
    /// the change in knee angle that the knee fold gives it (0 on the thigh, 1 on the
    /// shank, in between around the knee), then moves with the thigh; a muscle that the
    /// update carried whole with one body moves with that body. Right after an update it
    /// is that update's shape, bit for bit.
    ///
    /// ```
    /// use myoslice::prelude::*;
    /// let mut sim = Simulation::phantom(SimulationConfig::default())?;
    /// sim.set_excitation("biceps_femoris_short", 1.0)?;
    /// sim.step(0.2)?;
    /// sim.step(0.01)?; // the tissue is now behind the skeleton
    /// let tissue = sim.tissue().unwrap();
    /// let now = tissue.carried(sim.knee_angle(), sim.frames());
    /// assert_eq!(now.fat.len(), tissue.fat_vertices().len());
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn carried(&self, knee_angle: f64, frames: &BodyFrames) -> CarriedTissue {
        let muscles = || self.muscles.iter().map(|m| m.current.clone()).collect();
        let turn = knee_angle as f32 - self.theta;
        let then = &self.frames_at_update;
        if turn == 0.0 && frames == then {
            return CarriedTissue {
                fat: self.fat.x.clone(),
                muscles: muscles(),
            };
        }
        let fold = KneeFold::new(&self.knee, self.theta);
        let (tq, tt) = then.thigh;
        let (nq, nt) = frames.thigh;
        let back = tq.inverse();
        // World at the update → thigh's rest frame → turned about the axis → world now.
        let carry = |p: Vec3, w: f32| {
            let rest = back * (p - tt);
            let turned =
                fold.point + Quat::from_axis_angle(fold.axis, turn * w) * (rest - fold.point);
            nq * turned + nt
        };
        let zone = &self.fixed.zone;
        let fat = self
            .fat
            .x
            .par_iter()
            .enumerate()
            .map(|(v, &p)| carry(p, zone.weight(&fold, v)))
            .collect();
        let muscles = self
            .muscles
            .par_iter()
            .map(|m| match m.carried {
                Some(body) => {
                    let ((q0, t0), (q, t)) = (then.pose(body), frames.pose(body));
                    let back = q0.inverse();
                    m.current
                        .iter()
                        .map(|&p| q * (back * (p - t0)) + t)
                        .collect()
                }
                None => m
                    .current
                    .iter()
                    .zip(m.rest.iter())
                    .map(|(&p, &r)| carry(p, fold.weight(r)))
                    .collect(),
            })
            .collect();
        CarriedTissue { fat, muscles }
    }
}
