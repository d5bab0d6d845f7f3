//! Radial polygons (paper, Fig. 1) with a traced fallback where they fit poorly.

use std::f64::consts::TAU;

use super::mask::{Mask, outermost_crossing};
use super::polygon::{Polygon, iou};
use super::trace::{resample_loop, trace_outer_loops};
use crate::slices::Region;

/// How a region's polygon was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolygonMethod {
    /// Outermost border crossings on equal-angle rays from the centroid (the paper's).
    Radial,
    /// Traced border resampled at equal arc length: used where the region is not
    /// star-shaped from its centroid (a C-shaped muscle around a bone).
    Traced,
}

/// A region's polygon and how well it covers the region.
#[derive(Debug, Clone)]
pub struct RegionPolygon {
    /// The polygon, `rays` vertices, counter-clockwise.
    pub polygon: Polygon,
    /// The ring's centre: the region centroid for radial polygons (where the rays start);
    /// for traced ones a point well inside the polygon (a C-shape's centroid lies in its
    /// hole, and a tiny region's may sit on its own border).
    pub centre: [f64; 2],
    /// Intersection over union with the region's pixels.
    pub iou: f64,
    /// Which method made it.
    pub method: PolygonMethod,
}

/// Unit direction of ray `j` of `n` (counter-clockwise from +u).
pub fn ray_dir(j: usize, n: usize) -> [f64; 2] {
    let a = TAU * j as f64 / n as f64;
    [a.cos(), a.sin()]
}

/// Polygonises one region with `rays` rays; falls back to a traced polygon when the radial
/// one covers the region with an IoU below `min_iou` and the traced one does better.
pub fn polygonise(mask: &impl Mask, region: &Region, rays: usize, min_iou: f64) -> RegionPolygon {
    let c = region.centroid;
    let b = region.bbox;
    let far = [
        [f64::from(b[0]) - 1.0, f64::from(b[1]) - 1.0],
        [f64::from(b[2]) + 1.0, f64::from(b[1]) - 1.0],
        [f64::from(b[0]) - 1.0, f64::from(b[3]) + 1.0],
        [f64::from(b[2]) + 1.0, f64::from(b[3]) + 1.0],
    ]
    .iter()
    .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt())
    .fold(0.0, f64::max);
    let mut pts = Vec::with_capacity(rays);
    let mut degenerate = false;
    for j in 0..rays {
        let d = ray_dir(j, rays);
        let r = match outermost_crossing(mask, c, d, far, 0.0) {
            Some(r) if r > 0.05 => r,
            _ => {
                degenerate = true;
                0.05
            }
        };
        pts.push([c[0] + d[0] * r, c[1] + d[1] * r]);
    }
    let radial = Polygon { points: pts };
    let radial_iou = iou(&radial, mask, b, region.area);
    if radial_iou >= min_iou && !degenerate {
        return RegionPolygon {
            polygon: radial,
            centre: c,
            iou: radial_iou,
            method: PolygonMethod::Radial,
        };
    }
    let loops = trace_outer_loops(mask, b);
    if let Some(lp) = loops.first() {
        let traced = resample_loop(lp, rays, c);
        let traced_iou = iou(&traced, mask, b, region.area);
        if traced_iou > radial_iou || degenerate {
            let centre = interior_centre(&traced, b, c);
            return RegionPolygon {
                polygon: traced,
                centre,
                iou: traced_iou,
                method: PolygonMethod::Traced,
            };
        }
    }
    RegionPolygon {
        polygon: radial,
        centre: c,
        iou: radial_iou,
        method: PolygonMethod::Radial,
    }
}

/// A point well inside the polygon: the centroid where it lies at least a pixel inside,
/// else the point farthest from the border, searched on the pixel grid over `bbox` and
/// refined on a quarter-pixel grid about the best pixel.
fn interior_centre(poly: &Polygon, bbox: [u32; 4], centroid: [f64; 2]) -> [f64; 2] {
    let p = &poly.points;
    let clearance = |x: f64, y: f64| -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = (dx * dx + dy * dy).max(1e-18);
            let t = (((x - a[0]) * dx + (y - a[1]) * dy) / len2).clamp(0.0, 1.0);
            let (ex, ey) = (a[0] + t * dx - x, a[1] + t * dy - y);
            best = best.min(ex * ex + ey * ey);
        }
        best
    };
    let inside = |x: f64, y: f64| poly.contains(x, y);
    let mut best = (0.0, centroid);
    if inside(centroid[0], centroid[1]) {
        let d = clearance(centroid[0], centroid[1]);
        if d >= 1.0 {
            return centroid;
        }
        best = (d, centroid);
    }
    let search = |x0: f64, y0: f64, nx: usize, ny: usize, h: f64, best: &mut (f64, [f64; 2])| {
        for iy in 0..=ny {
            for ix in 0..=nx {
                let (x, y) = (x0 + h * ix as f64, y0 + h * iy as f64);
                if inside(x, y) {
                    let d = clearance(x, y);
                    if d > best.0 {
                        *best = (d, [x, y]);
                    }
                }
            }
        }
    };
    let (u0, v0) = (f64::from(bbox[0]), f64::from(bbox[1]));
    let (nu, nv) = ((bbox[2] - bbox[0]) as usize, (bbox[3] - bbox[1]) as usize);
    search(u0, v0, nu, nv, 1.0, &mut best);
    let c = best.1;
    search(c[0] - 1.0, c[1] - 1.0, 8, 8, 0.25, &mut best);
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::ComponentMask;
    use crate::slices::label_components;

    fn slice_of(w: usize, h: usize, f: impl Fn(i64, i64) -> bool) -> Vec<u16> {
        (0..w * h)
            .map(|p| u16::from(f((p % w) as i64, (p / w) as i64)))
            .collect()
    }

    #[test]
    fn a_disc_gets_a_radial_polygon_with_high_iou() {
        let lab = slice_of(64, 64, |u, v| {
            ((u - 30).pow(2) + (v - 32).pow(2)) as f64 <= 400.0
        });
        let c = label_components(&lab, 64, 64, |l| l == 1);
        let m = ComponentMask {
            image: &c.image,
            width: 64,
            height: 64,
            id: 0,
        };
        let p = polygonise(&m, &c.regions[0], 48, 0.92);
        assert_eq!(p.method, PolygonMethod::Radial);
        assert!(p.iou > 0.95, "iou {}", p.iou);
        let area = p.polygon.signed_area();
        assert!((area - f64::from(c.regions[0].area)).abs() / area < 0.03);
    }

    #[test]
    fn a_c_shape_around_a_hole_is_traced_and_does_not_fill_the_hole() {
        let lab = slice_of(80, 80, |u, v| {
            let (x, y) = (u - 40, v - 40);
            let r = ((x * x + y * y) as f64).sqrt();
            (12.0..=24.0).contains(&r) && !(x < 0 && y.abs() <= 5)
        });
        let c = label_components(&lab, 80, 80, |l| l == 1);
        let m = ComponentMask {
            image: &c.image,
            width: 80,
            height: 80,
            id: 0,
        };
        let p = polygonise(&m, &c.regions[0], 48, 0.92);
        assert_eq!(p.method, PolygonMethod::Traced);
        assert!(p.iou > 0.85, "iou {}", p.iou);
        assert!(
            !p.polygon.contains(40.0, 40.0),
            "the hole (bone) must stay outside"
        );
        assert!(
            p.polygon.contains(p.centre[0], p.centre[1]),
            "the ring centre {:?} lies inside the C, not in its hole",
            p.centre
        );
    }
}
