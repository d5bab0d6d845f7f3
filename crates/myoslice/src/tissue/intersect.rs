//! Exact(-enough) self-intersection test of a triangle surface: does any triangle cross
//! another one it shares no vertex with?

use glam::{DVec3, Vec3};

/// Number of pairs of triangles (sharing no vertex) whose interiors cross.
pub fn self_intersections(vertices: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    if triangles.is_empty() {
        return 0;
    }
    let tri: Vec<[DVec3; 3]> = triangles
        .iter()
        .map(|t| t.map(|i| vertices[i as usize].as_dvec3()))
        .collect();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut mean_edge = 0.0;
    for t in &tri {
        for p in t {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        mean_edge += (t[1] - t[0]).length();
    }
    let cell = (2.0 * mean_edge / tri.len() as f64).max(1e-6);
    let dims = ((hi - lo) / cell).floor().as_uvec3() + 1;
    let key = |c: glam::UVec3| (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); (dims.x * dims.y * dims.z) as usize];
    let cell_of = |p: DVec3| (((p - lo) / cell).floor().as_uvec3()).min(dims - 1);
    for (i, t) in tri.iter().enumerate() {
        let a = cell_of(t[0].min(t[1]).min(t[2]));
        let b = cell_of(t[0].max(t[1]).max(t[2]));
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    cells[key(glam::UVec3::new(x, y, z))].push(i as u32);
                }
            }
        }
    }
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for c in &cells {
        for (ia, &a) in c.iter().enumerate() {
            for &b in &c[ia + 1..] {
                let (a, b) = if a < b { (a, b) } else { (b, a) };
                let ta = triangles[a as usize];
                let tb = triangles[b as usize];
                if ta.iter().any(|v| tb.contains(v)) {
                    continue;
                }
                if triangles_cross(&tri[a as usize], &tri[b as usize]) {
                    pairs.push((a, b));
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs.len()
}

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

fn triangles_cross(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    (0..3).any(|i| segment_hits_triangle(a[i], a[(i + 1) % 3], b))
        || (0..3).any(|i| segment_hits_triangle(b[i], b[(i + 1) % 3], a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_triangles_are_found_and_separate_ones_are_not() {
        let v = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.2, 0.2, -0.5),
            Vec3::new(0.2, 0.2, 0.5),
            Vec3::new(0.8, 0.9, 0.0),
            Vec3::new(5.0, 5.0, 5.0),
            Vec3::new(6.0, 5.0, 5.0),
            Vec3::new(5.0, 6.0, 5.0),
        ];
        assert_eq!(self_intersections(&v, &[[0, 1, 2], [3, 4, 5]]), 1);
        assert_eq!(self_intersections(&v, &[[0, 1, 2], [6, 7, 8]]), 0);
        // Neighbours sharing a vertex are not counted.
        assert_eq!(self_intersections(&v, &[[0, 1, 2], [0, 3, 4]]), 0);
    }
}
