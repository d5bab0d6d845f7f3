//! Exact(-enough) self-intersection test of a triangle surface: does any triangle cross
//! another one it shares no vertex with?

use glam::{DVec3, UVec3, Vec3};

/// Number of pairs of triangles (sharing no vertex) whose interiors cross.
pub fn self_intersections(vertices: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    crossing_pairs(vertices, triangles).len()
}

/// The pairs `(a, b)`, `a < b`, of triangles (indices into `triangles`, sharing no
/// vertex) that cross, sorted.
pub fn crossing_pairs(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    crossing_pairs_among(vertices, triangles, None)
}

/// As [`crossing_pairs`], but only pairs in which at least one triangle is `active`
/// (all when `None`): after a local change, only the triangles it touched need looking
/// at again.
pub fn crossing_pairs_among(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    active: Option<&[bool]>,
) -> Vec<(u32, u32)> {
    if triangles.is_empty() {
        return Vec::new();
    }
    let corners = |t: &[u32; 3]| t.map(|i| vertices[i as usize].as_dvec3());
    let bbox = |t: &[DVec3; 3]| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    // With an active set, only triangles overlapping the active ones' box can matter.
    let (ids, tri): (Vec<u32>, Vec<[DVec3; 3]>) = match active {
        None => (0..triangles.len() as u32)
            .zip(triangles.iter().map(corners))
            .unzip(),
        Some(a) => {
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for (t, _) in triangles.iter().zip(a).filter(|(_, on)| **on) {
                let b = bbox(&corners(t));
                lo = lo.min(b.0);
                hi = hi.max(b.1);
            }
            (0..triangles.len() as u32)
                .zip(triangles.iter().map(corners))
                .filter(|(_, t)| {
                    let b = bbox(t);
                    !(b.0.cmpgt(hi).any() || lo.cmpgt(b.1).any())
                })
                .unzip()
        }
    };
    if tri.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<(DVec3, DVec3)> = tri.iter().map(bbox).collect();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut mean_edge = 0.0;
    for (t, b) in tri.iter().zip(&boxes) {
        lo = lo.min(b.0);
        hi = hi.max(b.1);
        mean_edge += (t[1] - t[0]).length();
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let cell = (0.6 * mean_edge / tri.len() as f64).max(1e-6);
    // At most ~64 cells per triangle on average: keeps the grid small for any input.
    let cell = cell.max(((hi - lo).element_product() / (64.0 * tri.len() as f64)).cbrt());
    let dims = ((hi - lo) / cell).as_uvec3() + 1;
    let key = |c: UVec3| (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
    // Truncation is the floor here (non-negative), and needs no libm call.
    let inv = 1.0 / cell;
    let cell_of = |p: DVec3| ((p - lo) * inv).max(DVec3::ZERO).as_uvec3().min(dims - 1);
    let n_cells = (dims.x * dims.y * dims.z) as usize;
    // Cell lists in one array (counting sort).
    let mut start = vec![0u32; n_cells + 1];
    let for_cells = |b: &(DVec3, DVec3), f: &mut dyn FnMut(usize)| {
        let (a, c) = (cell_of(b.0), cell_of(b.1));
        for z in a.z..=c.z {
            for y in a.y..=c.y {
                for x in a.x..=c.x {
                    f(key(UVec3::new(x, y, z)));
                }
            }
        }
    };
    for b in &boxes {
        for_cells(b, &mut |k| start[k + 1] += 1);
    }
    for k in 0..n_cells {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut items = vec![0u32; start[n_cells] as usize];
    for (i, b) in boxes.iter().enumerate() {
        for_cells(b, &mut |k| {
            items[fill[k] as usize] = i as u32;
            fill[k] += 1;
        });
    }
    let is_active = |i: u32| active.is_none_or(|a| a[ids[i as usize] as usize]);
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for k in 0..n_cells {
        let c = &items[start[k] as usize..start[k + 1] as usize];
        for (ia, &a) in c.iter().enumerate() {
            for &b in &c[ia + 1..] {
                if !(is_active(a) || is_active(b)) {
                    continue;
                }
                let (ba, bb) = (&boxes[a as usize], &boxes[b as usize]);
                if ba.0.cmpgt(bb.1).any() || bb.0.cmpgt(ba.1).any() {
                    continue;
                }
                // Each pair once: in the cell holding the low corner of the boxes' overlap.
                if key(cell_of(ba.0.max(bb.0))) != k {
                    continue;
                }
                let (ga, gb) = (ids[a as usize], ids[b as usize]);
                let (ta, tb) = (triangles[ga as usize], triangles[gb as usize]);
                if ta.iter().any(|v| tb.contains(v)) {
                    continue;
                }
                if triangles_cross(&tri[a as usize], &tri[b as usize]) {
                    pairs.push(if ga < gb { (ga, gb) } else { (gb, ga) });
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs
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

/// Whether all corners of `a` lie strictly on one side of the plane of `b`.
fn one_side_of(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let n = (b[1] - b[0]).cross(b[2] - b[0]);
    let d = a.map(|p| n.dot(p - b[0]));
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

fn triangles_cross(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    // Most neighbours whose boxes overlap are told apart by a plane test alone.
    if one_side_of(a, b) || one_side_of(b, a) {
        return false;
    }
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
