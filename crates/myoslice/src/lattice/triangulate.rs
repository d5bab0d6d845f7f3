//! Ear-clipping triangulation of simple polygons (end caps, muscle cross-sections).

/// Triangulates a simple polygon given counter-clockwise; returns index triples, each
/// counter-clockwise. Falls back to a fan where ear clipping finds no ear (a polygon
/// that is not quite simple).
pub fn ear_clip(points: &[[f64; 2]]) -> Vec<[u32; 3]> {
    let n = points.len();
    let mut out = Vec::with_capacity(n.saturating_sub(2));
    if n < 3 {
        return out;
    }
    let mut idx: Vec<usize> = (0..n).collect();
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let mut guard = 0;
    while idx.len() > 3 && guard < 4 * n * n {
        guard += 1;
        let m = idx.len();
        let mut clipped = false;
        for k in 0..m {
            let (ia, ib, ic) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (a, b, c) = (points[ia], points[ib], points[ic]);
            if cross(a, b, c) <= 1e-12 {
                continue;
            }
            let blocked = idx.iter().any(|&ip| {
                if ip == ia || ip == ib || ip == ic {
                    return false;
                }
                let p = points[ip];
                cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
            });
            if !blocked {
                out.push([ia as u32, ib as u32, ic as u32]);
                idx.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break;
        }
    }
    // Whatever is left (a triangle, or a non-simple remainder) is fanned.
    for k in 1..idx.len().saturating_sub(1) {
        out.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::signed_area;

    #[test]
    fn an_l_shape_is_covered_exactly_by_positive_triangles() {
        let p = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        let t = ear_clip(&p);
        assert_eq!(t.len(), 4);
        let mut total = 0.0;
        for tri in &t {
            let a = signed_area(&tri.map(|i| p[i as usize]));
            assert!(a > 0.0);
            total += a;
        }
        assert!((total - 3.0).abs() < 1e-12);
    }
}
