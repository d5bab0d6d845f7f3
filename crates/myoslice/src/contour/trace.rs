//! Border tracing by marching squares, for regions a radial polygon cannot follow.

use super::mask::Mask;
use super::polygon::{Polygon, signed_area};

/// Traces the 0.5 level of `mask` inside the inclusive pixel box `bbox` (padded by one
/// pixel) and returns its outer loops, counter-clockwise, largest first.
pub fn trace_outer_loops(mask: &impl Mask, bbox: [u32; 4]) -> Vec<Vec<[f64; 2]>> {
    let u0 = i64::from(bbox[0]) - 1;
    let v0 = i64::from(bbox[1]) - 1;
    let nu = (i64::from(bbox[2]) - u0 + 2) as usize; // corners u0..=u1+1
    let nv = (i64::from(bbox[3]) - v0 + 2) as usize;
    // Edge ids: horizontal edge (u,v)-(u+1,v) -> h(u,v); vertical (u,v)-(u,v+1) -> vt(u,v).
    let h = |u: usize, v: usize| u + nu * v;
    let vt = |u: usize, v: usize| nu * nv + u + nu * v;
    let n_edges = 2 * nu * nv;
    const NONE: u32 = u32::MAX;
    let mut next = vec![NONE; n_edges];
    let inside = |u: usize, v: usize| mask.at(u0 + u as i64, v0 + v as i64);
    for v in 0..nv - 1 {
        for u in 0..nu - 1 {
            let c = usize::from(inside(u, v))
                | usize::from(inside(u + 1, v)) << 1
                | usize::from(inside(u + 1, v + 1)) << 2
                | usize::from(inside(u, v + 1)) << 3;
            let (bottom, top, left, right) = (h(u, v), h(u, v + 1), vt(u, v), vt(u + 1, v));
            let segs: &[(usize, usize)] = match c {
                1 => &[(bottom, left)],
                2 => &[(right, bottom)],
                3 => &[(right, left)],
                4 => &[(top, right)],
                5 => &[(bottom, right), (top, left)],
                6 => &[(top, bottom)],
                7 => &[(top, left)],
                8 => &[(left, top)],
                9 => &[(bottom, top)],
                10 => &[(left, bottom), (right, top)],
                11 => &[(right, top)],
                12 => &[(left, right)],
                13 => &[(bottom, right)],
                14 => &[(left, bottom)],
                _ => &[],
            };
            for &(a, b) in segs {
                next[a] = b as u32;
            }
        }
    }
    let point = |e: usize| -> [f64; 2] {
        if e < nu * nv {
            let (u, v) = (e % nu, e / nu);
            [(u0 + u as i64) as f64 + 0.5, (v0 + v as i64) as f64]
        } else {
            let e = e - nu * nv;
            let (u, v) = (e % nu, e / nu);
            [(u0 + u as i64) as f64, (v0 + v as i64) as f64 + 0.5]
        }
    };
    let mut loops = Vec::new();
    let mut seen = vec![false; n_edges];
    for start in 0..n_edges {
        if next[start] == NONE || seen[start] {
            continue;
        }
        let mut pts = Vec::new();
        let mut e = start;
        while !seen[e] && next[e] != NONE {
            seen[e] = true;
            pts.push(point(e));
            e = next[e] as usize;
        }
        if pts.len() >= 3 && signed_area(&pts) > 0.0 {
            loops.push(pts);
        }
    }
    loops.sort_by(|a, b| signed_area(b).total_cmp(&signed_area(a)));
    loops
}

/// Resamples a closed loop to `n` points at equal arc length, starting where the ray from
/// `centre` along +u leaves the loop for the last time (or at the loop's right-most point).
pub fn resample_loop(lp: &[[f64; 2]], n: usize, centre: [f64; 2]) -> Polygon {
    let m = lp.len();
    // Start: the outermost crossing of the +u ray from the centre, else the right-most point.
    let mut start: Option<(f64, usize, f64)> = None; // (x, segment, t)
    for i in 0..m {
        let (a, b) = (lp[i], lp[(i + 1) % m]);
        if (a[1] > centre[1]) != (b[1] > centre[1]) {
            let t = (centre[1] - a[1]) / (b[1] - a[1]);
            let x = a[0] + t * (b[0] - a[0]);
            if x >= centre[0] && start.is_none_or(|s| x > s.0) {
                start = Some((x, i, t));
            }
        }
    }
    let (seg, t0) = match start {
        Some((_, i, t)) => (i, t),
        None => {
            let i = (0..m)
                .max_by(|&a, &b| lp[a][0].total_cmp(&lp[b][0]))
                .unwrap_or(0);
            (i, 0.0)
        }
    };
    // Walk the loop from the start point, collecting a polyline with cumulative length.
    let first = lerp(lp[seg], lp[(seg + 1) % m], t0);
    let mut pts = vec![first];
    for k in 1..=m {
        pts.push(lp[(seg + k) % m]);
    }
    pts.push(first);
    let mut cum = vec![0.0];
    for w in pts.windows(2) {
        let d = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        cum.push(cum[cum.len() - 1] + d);
    }
    let total = cum[cum.len() - 1];
    let mut out = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let s = total * k as f64 / n as f64;
        while j + 2 < cum.len() && cum[j + 1] < s {
            j += 1;
        }
        let len = cum[j + 1] - cum[j];
        let t = if len > 0.0 { (s - cum[j]) / len } else { 0.0 };
        out.push(lerp(pts[j], pts[j + 1], t));
    }
    Polygon { points: out }
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampled_loops_keep_area_and_orientation() {
        struct Big;
        impl Mask for Big {
            fn at(&self, u: i64, v: i64) -> bool {
                let r = (((u - 20) * (u - 20) + (v - 20) * (v - 20)) as f64).sqrt();
                (6.0..=12.0).contains(&r) && !(u < 20 && (v - 20).abs() <= 3)
            }
        }
        let loops = trace_outer_loops(&Big, [5, 5, 35, 35]);
        assert_eq!(loops.len(), 1);
        let px = (0..41)
            .flat_map(|u| (0..41).map(move |v| (u, v)))
            .filter(|&(u, v)| Big.at(u, v))
            .count() as f64;
        let a = signed_area(&loops[0]);
        assert!((a - px).abs() / px < 0.08, "area {a} vs {px}");
        let p = resample_loop(&loops[0], 64, [20.0, 20.0]);
        assert_eq!(p.points.len(), 64);
        assert!(p.signed_area() > 0.9 * a);
        assert!(p.points[0][0] > 30.0 && (p.points[0][1] - 20.0).abs() < 1.0);
    }
}
