//! A uniform grid over points for nearest-point queries.

use glam::Vec3;

/// Points bucketed in a uniform grid (cell lists sorted, so queries are deterministic).
#[derive(Debug, Clone)]
pub struct PointGrid {
    min: Vec3,
    cell: f32,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
    points: Vec<Vec3>,
}

impl PointGrid {
    /// Buckets `points` in cells of edge `cell` (m).
    pub fn new(points: Vec<Vec3>, cell: f32) -> Self {
        let cell = cell.max(1e-6);
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &points {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if points.is_empty() {
            lo = Vec3::ZERO;
            hi = Vec3::ZERO;
        }
        let d = ((hi - lo) / cell).floor();
        let dims = [d.x as usize + 1, d.y as usize + 1, d.z as usize + 1];
        let ncell = dims[0] * dims[1] * dims[2];
        let key = |p: Vec3| {
            let c = ((p - lo) / cell).floor();
            let (x, y, z) = (
                (c.x as usize).min(dims[0] - 1),
                (c.y as usize).min(dims[1] - 1),
                (c.z as usize).min(dims[2] - 1),
            );
            x + dims[0] * (y + dims[1] * z)
        };
        let mut count = vec![0u32; ncell + 1];
        for p in &points {
            count[key(*p) + 1] += 1;
        }
        for i in 0..ncell {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; points.len()];
        for (i, p) in points.iter().enumerate() {
            let k = key(*p);
            items[fill[k] as usize] = i as u32;
            fill[k] += 1;
        }
        Self {
            min: lo,
            cell,
            dims,
            start: count,
            items,
            points,
        }
    }

    /// The stored points.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Index of the point nearest to `q` (ties → smallest index), `None` if empty.
    pub fn nearest(&self, q: Vec3) -> Option<u32> {
        if self.points.is_empty() {
            return None;
        }
        // Start from the cell of q's projection onto the grid box: distances from q are
        // no smaller than from that projection, so the ring bound below still holds.
        let c = ((q - self.min) / self.cell).floor();
        let ci = [
            (c.x as i64).clamp(0, self.dims[0] as i64 - 1),
            (c.y as i64).clamp(0, self.dims[1] as i64 - 1),
            (c.z as i64).clamp(0, self.dims[2] as i64 - 1),
        ];
        let mut best: Option<(f32, u32)> = None;
        let max_ring = self.dims.iter().copied().max().unwrap_or(1) as i64 + 1;
        for ring in 0..=max_ring {
            // Once a point is found, one more ring settles it (cells are cubes).
            if let Some((d2, _)) = best {
                let reach = (ring - 1) as f32 * self.cell;
                if reach > 0.0 && reach * reach > d2 {
                    break;
                }
            }
            for z in ci[2] - ring..=ci[2] + ring {
                for y in ci[1] - ring..=ci[1] + ring {
                    for x in ci[0] - ring..=ci[0] + ring {
                        let on_shell = (x - ci[0]).abs() == ring
                            || (y - ci[1]).abs() == ring
                            || (z - ci[2]).abs() == ring;
                        if !on_shell
                            || x < 0
                            || y < 0
                            || z < 0
                            || x as usize >= self.dims[0]
                            || y as usize >= self.dims[1]
                            || z as usize >= self.dims[2]
                        {
                            continue;
                        }
                        let k =
                            x as usize + self.dims[0] * (y as usize + self.dims[1] * z as usize);
                        for &i in &self.items[self.start[k] as usize..self.start[k + 1] as usize] {
                            let d2 = self.points[i as usize].distance_squared(q);
                            if best.is_none_or(|(b, bi)| d2 < b || (d2 == b && i < bi)) {
                                best = Some((d2, i));
                            }
                        }
                    }
                }
            }
        }
        best.map(|(_, i)| i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn nearest_matches_brute_force(
            pts in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 1..60),
            q in (-1.5f32..1.5, -1.5f32..1.5, -1.5f32..1.5),
            cell in 0.05f32..0.7,
        ) {
            let pts: Vec<Vec3> = pts.into_iter().map(|(x, y, z)| Vec3::new(x, y, z)).collect();
            let q = Vec3::new(q.0, q.1, q.2);
            let g = PointGrid::new(pts.clone(), cell);
            let got = g.nearest(q).unwrap() as usize;
            let best = pts.iter().map(|p| p.distance_squared(q)).fold(f32::INFINITY, f32::min);
            prop_assert!((pts[got].distance_squared(q) - best).abs() <= 1e-6);
        }
    }
}
