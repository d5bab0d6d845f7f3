//! Simple polygons in slice pixel coordinates.

/// A closed polygon, counter-clockwise in the (u, v) plane, as a list of vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    /// Vertices in order; the last joins the first.
    pub points: Vec<[f64; 2]>,
}

impl Polygon {
    /// Signed area (positive for counter-clockwise).
    pub fn signed_area(&self) -> f64 {
        signed_area(&self.points)
    }

    /// Area centroid (falls back to the vertex mean for degenerate polygons).
    pub fn centroid(&self) -> [f64; 2] {
        let p = &self.points;
        let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
        for i in 0..p.len() {
            let (x0, y0) = (p[i][0], p[i][1]);
            let (x1, y1) = (p[(i + 1) % p.len()][0], p[(i + 1) % p.len()][1]);
            let c = x0 * y1 - x1 * y0;
            a += c;
            cx += (x0 + x1) * c;
            cy += (y0 + y1) * c;
        }
        if a.abs() < 1e-12 {
            let n = p.len().max(1) as f64;
            return [
                p.iter().map(|q| q[0]).sum::<f64>() / n,
                p.iter().map(|q| q[1]).sum::<f64>() / n,
            ];
        }
        [cx / (3.0 * a), cy / (3.0 * a)]
    }

    /// Even-odd point-in-polygon test.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let p = &self.points;
        let mut inside = false;
        let mut j = p.len() - 1;
        for i in 0..p.len() {
            let (xi, yi) = (p[i][0], p[i][1]);
            let (xj, yj) = (p[j][0], p[j][1]);
            if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
                inside = !inside;
            }
            j = i;
        }
        inside
    }

    /// Calls `f(u0, u1, v)` for each run of pixel centres `u0..=u1` on row `v` inside the
    /// polygon (even-odd rule), for rows `v0..=v1`.
    pub fn scan_rows(&self, v0: i64, v1: i64, mut f: impl FnMut(i64, i64, i64)) {
        let p = &self.points;
        let mut xs: Vec<f64> = Vec::with_capacity(16);
        for v in v0..=v1 {
            let y = v as f64;
            xs.clear();
            let mut j = p.len() - 1;
            for i in 0..p.len() {
                let (yi, yj) = (p[i][1], p[j][1]);
                if (yi > y) != (yj > y) {
                    xs.push(p[i][0] + (y - yi) * (p[j][0] - p[i][0]) / (yj - yi));
                }
                j = i;
            }
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks_exact(2) {
                let (a, b) = (pair[0].ceil() as i64, pair[1].ceil() as i64 - 1);
                if b >= a {
                    f(a, b, v);
                }
            }
        }
    }

    /// Inclusive bounding box of the vertices `[xmin, ymin, xmax, ymax]`.
    pub fn bounds(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for q in &self.points {
            b = [
                b[0].min(q[0]),
                b[1].min(q[1]),
                b[2].max(q[0]),
                b[3].max(q[1]),
            ];
        }
        b
    }
}

/// Signed area of a closed vertex loop.
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let mut a = 0.0;
    for i in 0..p.len() {
        let q = p[(i + 1) % p.len()];
        a += p[i][0] * q[1] - q[0] * p[i][1];
    }
    0.5 * a
}

/// Intersection-over-union of a polygon with the pixels of a mask, counted at pixel
/// centres over the polygon's and the mask's bounding boxes.
pub fn iou(poly: &Polygon, mask: &impl super::Mask, mask_bbox: [u32; 4], mask_area: u32) -> f64 {
    let b = poly.bounds();
    let v0 = (b[1].floor() as i64).min(i64::from(mask_bbox[1]));
    let v1 = (b[3].ceil() as i64).max(i64::from(mask_bbox[3]));
    let (mut inter, mut pin) = (0u64, 0u64);
    poly.scan_rows(v0, v1, |a, c, v| {
        for u in a..=c {
            pin += 1;
            if mask.at(u, v) {
                inter += 1;
            }
        }
    });
    let union = pin + u64::from(mask_area) - inter;
    if union == 0 {
        0.0
    } else {
        inter as f64 / union as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_area_centroid_and_scan() {
        let sq = Polygon {
            points: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]],
        };
        assert_eq!(sq.signed_area(), 8.0);
        assert_eq!(sq.centroid(), [2.0, 1.0]);
        assert!(sq.contains(1.0, 1.0) && !sq.contains(5.0, 1.0));
        let mut n = 0;
        sq.scan_rows(-1, 3, |a, b, _| n += b - a + 1);
        assert_eq!(n, 8); // centres (0..=3) x (0..=1)
    }
}
