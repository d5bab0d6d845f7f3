//! Moment arms by virtual work, and where a chain's tension acts on a moving body.
//!
//! With every chain point carried by its body (origin, insertion, via points, cones) and
//! the wrap cylinder fixed to the thigh, turning the shank by dθ about the knee axis
//! changes the path length by dL; the moment arm is r = −dL/dθ (An et al. 1984, the
//! tendon-excursion method). The same geometry tells where a tension T pulls the
//! shank: at the shank end of every segment that crosses from one body to the other,
//! along that segment. Segments lying wholly on the shank pull it at both ends and
//! cancel, so the torque those pulls make is exactly T·r (virtual work).

use glam::Vec3;

use super::chain::MuscleChain;
use crate::body::BodyId;

/// A rotation axis in the world: the knee's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    /// A point on the axis (world, m).
    pub point: Vec3,
    /// Unit direction; turning the moving body about it is positive.
    pub dir: Vec3,
}

/// One pull of the chain on a body: unit direction (world) and where it acts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pull {
    /// Unit direction of the force.
    pub dir: Vec3,
    /// Point of application (world, m).
    pub at: Vec3,
}

impl MuscleChain {
    /// Moment arm (m) about `axis` of the path when `moving` turns about it:
    /// −dL/dθ, positive when the path shortens as the body turns positively.
    pub fn moment_arm(&self, axis: &Axis, moving: BodyId) -> f64 {
        // Σ over segments of the rate its ends separate when `moving` turns at unit rate.
        let mut rate = 0.0f32;
        for i in 0..self.x.len().saturating_sub(1) {
            let g = self.segment(i);
            if self.point_body(i) == moving {
                rate -= axis.dir.cross(self.x[i] - axis.point).dot(g.dir_a);
            }
            if self.point_body(i + 1) == moving {
                rate -= axis.dir.cross(self.x[i + 1] - axis.point).dot(g.dir_b);
            }
        }
        -f64::from(rate)
    }

    /// The chain's pulls on `body` per unit tension: one at the `body` end of each segment
    /// with exactly one end on it.
    pub fn pulls_on(&self, body: BodyId) -> impl Iterator<Item = Pull> + '_ {
        (0..self.x.len().saturating_sub(1)).filter_map(move |i| {
            let (a, b) = (self.point_body(i) == body, self.point_body(i + 1) == body);
            let g = self.segment(i);
            match (a, b) {
                (true, false) => Some(Pull {
                    dir: g.dir_a,
                    at: self.x[i],
                }),
                (false, true) => Some(Pull {
                    dir: g.dir_b,
                    at: self.x[i + 1],
                }),
                _ => None,
            }
        })
    }
}
