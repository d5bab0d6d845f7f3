//! Exact small-scale geometry on triangles: the closest point and the feature it lies on,
//! and whether two triangles cross.

use glam::Vec3;

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

/// Whether triangles `t` and `u` cross: a segment of one passes through the other's
/// interior (triangles sharing a vertex should not be asked). Touching within `1e-9`
/// of the plane does not count.
pub fn triangles_cross(t: [Vec3; 3], u: [Vec3; 3]) -> bool {
    (0..3).any(|i| segment_crosses(t[i], t[(i + 1) % 3], u))
        || (0..3).any(|i| segment_crosses(u[i], u[(i + 1) % 3], t))
}

/// Whether segment `pq` passes through the interior of triangle `t` (in f64: the test
/// decides the tests' verdicts, so it must not flicker with rounding).
fn segment_crosses(p: Vec3, q: Vec3, t: [Vec3; 3]) -> bool {
    let [a, b, c] = t.map(Vec3::as_dvec3);
    let (p, q) = (p.as_dvec3(), q.as_dvec3());
    let n = (b - a).cross(c - a);
    let dp = n.dot(p - a);
    let dq = n.dot(q - a);
    let scale = n.length() * (q - p).length();
    if scale == 0.0 || dp * dq > 0.0 || (dp - dq).abs() <= 1e-9 * scale {
        return false;
    }
    let s = dp / (dp - dq);
    let x = p + (q - p) * s;
    let e0 = (b - a).cross(x - a).dot(n);
    let e1 = (c - b).cross(x - b).dot(n);
    let e2 = (a - c).cross(x - c).dot(n);
    (e0 > 0.0 && e1 > 0.0 && e2 > 0.0) || (e0 < 0.0 && e1 < 0.0 && e2 < 0.0)
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
    fn crossing_triangles_are_told_from_touching_and_apart_ones() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let through = [
            Vec3::new(0.2, 0.2, -1.0),
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.3, 0.1, 1.0),
        ];
        assert!(triangles_cross(t, through));
        let above = through.map(|p| p + Vec3::Z * 2.0);
        assert!(!triangles_cross(t, above));
        let beside = through.map(|p| p + Vec3::X * 3.0);
        assert!(!triangles_cross(t, beside));
    }
}
