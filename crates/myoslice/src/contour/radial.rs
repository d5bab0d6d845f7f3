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
    /// The point rays start from (the region centroid).
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
            return RegionPolygon {
                polygon: traced,
                centre: c,
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
    }
}
