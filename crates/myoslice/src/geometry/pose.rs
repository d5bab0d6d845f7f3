//! A rigid pose (rotation, then translation) and the interpolation the tissue uses
//! between two bodies' poses.

use glam::{Quat, Vec3};

/// A rigid transform `p ↦ rot · p + pos`: where a body's rest frame is now.
///
/// ```
/// use glam::{Quat, Vec3};
/// use myoslice::geometry::Pose;
/// let p = Pose::new(Quat::from_rotation_z(1.0), Vec3::new(1.0, 2.0, 3.0));
/// let x = Vec3::new(0.3, -0.2, 0.5);
/// assert!(p.inverse().apply(p.apply(x)).distance(x) < 1e-6);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation.
    pub rot: Quat,
    /// Translation (m).
    pub pos: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No motion.
    pub const IDENTITY: Self = Self {
        rot: Quat::IDENTITY,
        pos: Vec3::ZERO,
    };

    /// A pose from its rotation and translation.
    pub fn new(rot: Quat, pos: Vec3) -> Self {
        Self { rot, pos }
    }

    /// A rest point carried by this pose.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.rot * p + self.pos
    }

    /// A rest direction carried by this pose.
    #[inline]
    pub fn rotate(&self, v: Vec3) -> Vec3 {
        self.rot * v
    }

    /// The inverse transform (world → rest frame).
    pub fn inverse(&self) -> Self {
        let r = self.rot.inverse();
        Self {
            rot: r,
            pos: -(r * self.pos),
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Self) -> Self {
        Self {
            rot: self.rot * other.rot,
            pos: self.rot * other.pos + self.pos,
        }
    }

    /// The pose a fraction `t` of the way from `self` to `other` along the screw motion
    /// between them: a rotation about the relative motion's own axis, so that a revolute
    /// or ball joint's centre stays put at every `t`.
    pub fn screw_lerp(&self, other: &Self, t: f32) -> Self {
        // Relative motion in self's frame: x ↦ R x + d.
        let rel = self.inverse().compose(other);
        let (axis, angle) = rel.rot.to_axis_angle();
        if angle.abs() < 1e-6 {
            return Self {
                rot: self.rot,
                pos: self.pos + self.rot * (rel.pos * t),
            };
        }
        // Screw decomposition: translation along the axis, rotation about a line through
        // the point c that the rotation leaves fixed in the plane normal to the axis.
        let along = axis * rel.pos.dot(axis);
        let perp = rel.pos - along;
        // c solves (I − R) c = perp in the plane ⊥ axis.
        let half = 0.5 * angle;
        let c = 0.5 * (perp + axis.cross(perp) / half.tan());
        let r_t = Quat::from_axis_angle(axis, angle * t);
        let d_t = c - r_t * c + along * t;
        self.compose(&Self { rot: r_t, pos: d_t })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screw_lerp_keeps_the_joint_centre_fixed_and_ends_at_the_other_pose() {
        let c = Vec3::new(0.1, 0.4, 0.5);
        let a = Pose::new(Quat::from_rotation_y(0.2), Vec3::new(0.02, 0.0, 0.01));
        let turn = Quat::from_axis_angle(Vec3::new(1.0, 0.2, 0.1).normalize(), 2.3);
        // b = a then a rotation about the world point a(c).
        let ca = a.apply(c);
        let b = Pose::new(turn, ca - turn * ca).compose(&a);
        for t in [0.0f32, 0.25, 0.5, 0.9, 1.0] {
            let p = a.screw_lerp(&b, t);
            assert!(p.apply(c).distance(ca) < 1e-5, "t = {t}");
        }
        let end = a.screw_lerp(&b, 1.0);
        let x = Vec3::new(0.3, -0.1, 0.2);
        assert!(end.apply(x).distance(b.apply(x)) < 1e-5);
        assert!(a.screw_lerp(&b, 0.0).apply(x).distance(a.apply(x)) < 1e-6);
    }
}
