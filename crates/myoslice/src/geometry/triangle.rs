//! Exact small-scale geometry on triangles: the closest point and the feature it lies on,
//! and whether two triangles cross.

use glam::{DVec3, Vec3};

/// Which part of a triangle a closest point lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// Corner `0..3`.
    Vertex(u8),
    /// Edge from corner `i` to corner `(i + 1) % 3`.
    Edge(u8),
    /// The interior.
    Face,
}

/// The closest point of triangle `abc` to `p`, its barycentric weights and its feature
/// (Ericson, *Real-Time Collision Detection*, 5.1.5).
#[inline]
pub fn closest_point(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f32; 3], Feature) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0], Feature::Vertex(0));
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0], Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0], Feature::Edge(0));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0], Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w], Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w], Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w], Feature::Face)
}

/// Whether triangles `a` and `b` cross: an edge of one meets the other (boundaries
/// included), in double precision so that the tests' verdicts do not flicker with
/// rounding. Triangles sharing a vertex should not be asked.
pub fn triangles_cross(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    // Most neighbours whose boxes overlap are told apart by a plane test alone.
    if one_side_of(a, b) || one_side_of(b, a) {
        return false;
    }
    (0..3).any(|i| segment_hits_triangle(a[i], a[(i + 1) % 3], b))
        || (0..3).any(|i| segment_hits_triangle(b[i], b[(i + 1) % 3], a))
}

/// Whether segment `pq` meets triangle `t` (Möller–Trumbore, boundaries included).
fn segment_hits_triangle(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    let d = q - p;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(e2);
    let a = e1.dot(h);
    if a.abs() < 1e-18 {
        return false;
    }
    let f = 1.0 / a;
    let s = p - t[0];
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(e1);
    let v = f * d.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let w = f * e2.dot(qv);
    (0.0..=1.0).contains(&w)
}

/// Whether all corners of `a` lie strictly on one side of the plane of `b`.
fn one_side_of(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let n = (b[1] - b[0]).cross(b[2] - b[0]);
    let d = a.map(|p| n.dot(p - b[0]));
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_names_the_feature_it_lies_on() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let (q, w, f) = closest_point(Vec3::new(0.2, 0.2, 1.0), a, b, c);
        assert_eq!(f, Feature::Face);
        assert!(q.distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert_eq!(
            closest_point(Vec3::new(-1.0, -1.0, 0.0), a, b, c).2,
            Feature::Vertex(0)
        );
        assert_eq!(
            closest_point(Vec3::new(0.5, -1.0, 0.3), a, b, c).2,
            Feature::Edge(0)
        );
        assert_eq!(
            closest_point(Vec3::new(1.0, 1.0, 0.0), a, b, c).2,
            Feature::Edge(1)
        );
        assert_eq!(
            closest_point(Vec3::new(-1.0, 0.5, 0.0), a, b, c).2,
            Feature::Edge(2)
        );
    }

    #[test]
    fn crossing_triangles_are_told_from_apart_ones() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let through = [
            Vec3::new(0.2, 0.2, -1.0),
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.3, 0.1, 1.0),
        ];
        let cross = |a: [Vec3; 3], b: [Vec3; 3]| {
            triangles_cross(&a.map(Vec3::as_dvec3), &b.map(Vec3::as_dvec3))
        };
        assert!(cross(t, through));
        let above = through.map(|p| p + Vec3::Z * 2.0);
        assert!(!cross(t, above));
        let beside = through.map(|p| p + Vec3::X * 3.0);
        assert!(!cross(t, beside));
    }

    #[test]
    fn the_closest_point_of_a_triangle_is_found_in_each_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let near = |p: Vec3| closest_point(p, a, b, c).0;
        assert!(near(Vec3::new(0.2, 0.2, 1.0)).distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6);
        assert_eq!(near(Vec3::new(-1.0, -1.0, 0.3)), a);
        assert_eq!(near(Vec3::new(2.0, -0.5, 0.0)), b);
        assert_eq!(near(Vec3::new(-0.5, 2.0, 0.0)), c);
        assert!(near(Vec3::new(0.5, -1.0, 0.0)).distance(Vec3::new(0.5, 0.0, 0.0)) < 1e-6);
        assert!(near(Vec3::new(1.0, 1.0, 0.0)).distance(Vec3::new(0.5, 0.5, 0.0)) < 1e-6);
    }
}
