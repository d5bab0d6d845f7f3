//! A tendon wrapping over a cylinder about the knee axis (the condyles or the trochlea),
//! so that the line of action keeps a moment arm when the knee bends deeply.

use glam::{DVec2, Vec3};

/// A wrap cylinder about the knee axis, and the side the tendon passes on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WrapCylinder {
    /// A point on the axis (world).
    pub point: Vec3,
    /// Unit axis.
    pub axis: Vec3,
    /// Radius (m).
    pub radius: f32,
    /// +1 when the path goes counter-clockwise about `axis` from its first to its last
    /// point, −1 otherwise (fixed at rest).
    pub side: f32,
}

/// The path between two points, wrapped or straight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WrapPath {
    /// Path length (m).
    pub length: f32,
    /// Unit direction the path leaves `p` in.
    pub dir_p: Vec3,
    /// Unit direction the path leaves `q` in (toward `p`).
    pub dir_q: Vec3,
    /// Whether the path touches the cylinder.
    pub wrapped: bool,
}

impl WrapCylinder {
    fn basis(&self) -> (Vec3, Vec3) {
        let a = self.axis;
        let e1 = a.any_orthonormal_vector();
        (e1, a.cross(e1))
    }

    fn planar(&self, p: Vec3) -> (DVec2, f32) {
        self.planar_in(self.basis(), p)
    }

    /// `p` in the plane across the axis (basis `e`) and its height along it.
    fn planar_in(&self, (e1, e2): (Vec3, Vec3), p: Vec3) -> (DVec2, f32) {
        let d = p - self.point;
        (
            DVec2::new(f64::from(d.dot(e1)), f64::from(d.dot(e2))),
            d.dot(self.axis),
        )
    }

    fn spatial_in(&self, (e1, e2): (Vec3, Vec3), q: DVec2, h: f32) -> Vec3 {
        self.point + e1 * q.x as f32 + e2 * q.y as f32 + self.axis * h
    }

    /// Where `ps` lie in the plane across the axis through `point` along `axis`.
    fn across<const N: usize>(point: Vec3, axis: Vec3, ps: [Vec3; N]) -> [DVec2; N] {
        let c = WrapCylinder {
            point,
            axis,
            radius: 0.0,
            side: 1.0,
        };
        ps.map(|p| c.planar(p).0)
    }

    /// The side (+1/−1) a path from `p` to `q` passes the axis on.
    pub fn side_of(point: Vec3, axis: Vec3, p: Vec3, q: Vec3) -> f32 {
        let [a, b] = Self::across(point, axis, [p, q]);
        if a.perp_dot(b) >= 0.0 { 1.0 } else { -1.0 }
    }

    /// The side (+1/−1) a path from `p` to `q` round the axis takes so as not to pass
    /// over the direction `avoid` (a flexor's tendon never crosses the front of the knee
    /// nor an extensor's its back, whichever way the straight line would go).
    pub fn side_avoiding(point: Vec3, axis: Vec3, p: Vec3, q: Vec3, avoid: Vec3) -> f32 {
        let [a, b, t] = Self::across(point, axis, [p, q, point + avoid]);
        let ccw = |u: DVec2, v: DVec2| {
            u.perp_dot(v)
                .atan2(u.dot(v))
                .rem_euclid(std::f64::consts::TAU)
        };
        if ccw(a, t) < ccw(a, b) { -1.0 } else { 1.0 }
    }

    /// Signed distance (m) of the straight line p→q from the axis, positive on `side`.
    pub fn clearance(&self, p: Vec3, q: Vec3) -> f32 {
        let (a, _) = self.planar(p);
        let (b, _) = self.planar(q);
        let len = (b - a).length().max(1e-12);
        (f64::from(self.side) * a.perp_dot(b) / len) as f32
    }

    /// The shortest path from `p` to `q` that stays outside the cylinder on its side.
    /// Wrapping starts where the straight line would cut the cylinder and, once started
    /// (`was_wrapped`), holds until the line clears the cylinder on its side again, so the
    /// path never jumps.
    pub fn path(&self, p: Vec3, q: Vec3, was_wrapped: bool) -> WrapPath {
        let straight = |p: Vec3, q: Vec3| {
            let d = q - p;
            let l = d.length().max(1e-9);
            WrapPath {
                length: l,
                dir_p: d / l,
                dir_q: -d / l,
                wrapped: false,
            }
        };
        let e = self.basis();
        let (a, ha) = self.planar_in(e, p);
        let (b, hb) = self.planar_in(e, q);
        let r = f64::from(self.radius);
        let (da, db) = (a.length(), b.length());
        if r <= 0.0 || da <= r * 1.0001 || db <= r * 1.0001 {
            return straight(p, q);
        }
        let ab = b - a;
        let s = f64::from(self.side) * a.perp_dot(b) / ab.length().max(1e-12);
        let t = (-a).dot(ab) / ab.length_squared().max(1e-18);
        let starts = s.abs() < r && t > 0.0 && t < 1.0;
        if !(starts || (was_wrapped && s < r)) {
            return straight(p, q);
        }
        let sg = f64::from(self.side);
        // Tangent points: each end's direction turned by ±acos(r/d) (toward the side the
        // path goes round), without trigonometry; one atan2 for the arc between them.
        let tangent = |u: DVec2, d: f64, turn: f64| {
            let (c, sn) = (r / d, turn * (1.0 - (r / d).powi(2)).max(0.0).sqrt());
            DVec2::new(u.x * c - u.y * sn, u.x * sn + u.y * c) * r
        };
        let t1 = tangent(a / da, da, sg);
        let t2 = tangent(b / db, db, -sg);
        let arc = (sg * t1.perp_dot(t2))
            .atan2(t1.dot(t2))
            .rem_euclid(std::f64::consts::TAU);
        if arc > 1.75 * std::f64::consts::PI {
            // Nearly a full turn: the points sit where no tendon could; go straight.
            return straight(p, q);
        }
        let (l1, l2, l3) = ((t1 - a).length(), arc * r, (b - t2).length());
        let total = (l1 + l2 + l3).max(1e-12);
        // Along the axis the path climbs linearly with its length.
        let h1 = ha + (hb - ha) * (l1 / total) as f32;
        let h2 = ha + (hb - ha) * ((l1 + l2) / total) as f32;
        let (p1, p2) = (self.spatial_in(e, t1, h1), self.spatial_in(e, t2, h2));
        let planar = l1 + l2 + l3;
        let length = (planar * planar + f64::from(hb - ha).powi(2)).sqrt() as f32;
        WrapPath {
            length,
            dir_p: (p1 - p).normalize_or_zero(),
            dir_q: (p2 - q).normalize_or_zero(),
            wrapped: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flexor_passes_behind_the_axis_even_where_the_straight_line_is_in_front() {
        // Axis along x; p above and slightly behind, q below and in front (+y anterior).
        let (o, x) = (Vec3::ZERO, Vec3::X);
        let p = Vec3::new(0.0, -0.01, 0.10);
        let q = Vec3::new(0.0, 0.02, -0.04);
        let front = WrapCylinder::side_of(o, x, p, q);
        let behind = WrapCylinder::side_avoiding(o, x, p, q, Vec3::Y);
        assert_eq!(behind, -front);
        assert_eq!(WrapCylinder::side_avoiding(o, x, p, q, Vec3::NEG_Y), front);
        let c = WrapCylinder {
            point: o,
            axis: x,
            radius: 0.03,
            side: behind,
        };
        let w = c.path(p, q, false);
        assert!(w.wrapped);
        // The path leaves p going backward (−y) and reaches q from behind.
        assert!(w.dir_p.y < 0.0 && w.dir_q.y < 0.0, "{w:?}");
    }

    #[test]
    fn a_path_clear_of_the_cylinder_is_straight_and_a_blocked_one_wraps() {
        let c = WrapCylinder {
            point: Vec3::ZERO,
            axis: Vec3::Z,
            radius: 1.0,
            side: 1.0,
        };
        let clear = c.path(Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0), false);
        assert!(!clear.wrapped);
        // Half way round: 2 tangents of sqrt(3) and a third of a circle... by symmetry.
        let p = Vec3::new(2.0, 0.0, 0.0);
        let q = Vec3::new(-2.0, 0.0, 0.0);
        let w = c.path(p, q, false);
        assert!(w.wrapped);
        let expect = 2.0 * 3f32.sqrt() + (std::f32::consts::PI - 2.0 * (0.5f32).acos());
        assert!((w.length - expect).abs() < 1e-4, "{} vs {expect}", w.length);
        // Goes counter-clockwise: leaves p toward +y.
        assert!(w.dir_p.y > 0.0 && w.dir_q.y > 0.0);
        // The line of action at q is tangent: its distance from the axis is the radius.
        let arm = (q.cross(-w.dir_q)).z.abs();
        assert!((arm - 1.0).abs() < 1e-4);
    }
}
