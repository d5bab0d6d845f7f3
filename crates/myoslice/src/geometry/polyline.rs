//! The point of a polyline nearest a query point.

use std::ops::Range;

use glam::Vec3;

/// The point nearest `q` on the segments `segments` of polyline `p` (segment `i` runs from
/// `p[i]` to `p[i + 1]`) that `use_segment` admits: (segment, fraction along it, point).
/// None if it admits none. The first of equally near segments wins.
///
/// ```
/// use glam::Vec3;
/// use myoslice::geometry::closest_on_polyline;
/// let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
/// let (s, t, at) = closest_on_polyline(&p, 0..2, |_| true, Vec3::new(2.0, 0.5, 0.0)).unwrap();
/// assert_eq!((s, t, at), (1, 0.5, Vec3::new(1.0, 0.5, 0.0)));
/// assert!(closest_on_polyline(&p, 0..2, |_| false, Vec3::ZERO).is_none());
/// ```
pub fn closest_on_polyline(
    p: &[Vec3],
    segments: Range<usize>,
    use_segment: impl Fn(usize) -> bool,
    q: Vec3,
) -> Option<(usize, f32, Vec3)> {
    let mut best: Option<(usize, f32, Vec3, f32)> = None;
    for i in segments {
        if !use_segment(i) {
            continue;
        }
        let (a, b) = (p[i], p[i + 1]);
        let ab = b - a;
        let t = ((q - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
        let at = a + ab * t;
        let d = at.distance_squared(q);
        if best.is_none_or(|(.., bd)| d < bd) {
            best = Some((i, t, at, d));
        }
    }
    best.map(|(i, t, at, _)| (i, t, at))
}
