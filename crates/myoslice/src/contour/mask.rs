//! Binary masks over a slice and their bilinear sampling at sub-pixel positions.

/// A binary pixel mask; pixel centres sit at integer coordinates.
pub trait Mask {
    /// Whether pixel `(u, v)` is inside; pixels outside the slice are never inside.
    fn at(&self, u: i64, v: i64) -> bool;

    /// Bilinear interpolation of the 0/1 mask at `(x, y)`; the border is the 0.5 level.
    fn sample(&self, x: f64, y: f64) -> f64 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (u, v) = (x0 as i64, y0 as i64);
        let f = |du: i64, dv: i64| if self.at(u + du, v + dv) { 1.0 } else { 0.0 };
        let a = f(0, 0) * (1.0 - fx) + f(1, 0) * fx;
        let b = f(0, 1) * (1.0 - fx) + f(1, 1) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// The pixels of one component of a component image.
#[derive(Debug, Clone, Copy)]
pub struct ComponentMask<'a> {
    /// Component image (see [`crate::slices::SliceComponents`]).
    pub image: &'a [u32],
    /// Slice width.
    pub width: usize,
    /// Slice height.
    pub height: usize,
    /// Component id.
    pub id: u32,
}

impl Mask for ComponentMask<'_> {
    #[inline]
    fn at(&self, u: i64, v: i64) -> bool {
        u >= 0
            && v >= 0
            && (u as usize) < self.width
            && (v as usize) < self.height
            && self.image[u as usize + self.width * v as usize] == self.id
    }
}

/// Pixels whose label passes a lookup table (e.g. "bone or muscle", "inside the body").
#[derive(Debug, Clone, Copy)]
pub struct LabelSetMask<'a> {
    /// Slice labels.
    pub labels: &'a [u16],
    /// Slice width.
    pub width: usize,
    /// Slice height.
    pub height: usize,
    /// Membership per label id (ids beyond the table are outside).
    pub member: &'a [bool],
}

impl Mask for LabelSetMask<'_> {
    #[inline]
    fn at(&self, u: i64, v: i64) -> bool {
        u >= 0
            && v >= 0
            && (u as usize) < self.width
            && (v as usize) < self.height
            && self
                .member
                .get(self.labels[u as usize + self.width * v as usize] as usize)
                .copied()
                .unwrap_or(false)
    }
}

/// The outermost radius along a ray where `mask` crosses 0.5, searching inward from
/// `r_max`; `None` when the ray never enters the mask before `r_min`.
pub fn outermost_crossing(
    mask: &impl Mask,
    centre: [f64; 2],
    dir: [f64; 2],
    r_max: f64,
    r_min: f64,
) -> Option<f64> {
    const STEP: f64 = 0.5;
    let at = |r: f64| mask.sample(centre[0] + dir[0] * r, centre[1] + dir[1] * r);
    let mut r = r_max;
    if at(r) >= 0.5 {
        return Some(r);
    }
    while r > r_min {
        let next = (r - STEP).max(r_min);
        if at(next) >= 0.5 {
            // Refine between `next` (inside) and `r` (outside).
            let (mut lo, mut hi) = (next, r);
            for _ in 0..8 {
                let mid = 0.5 * (lo + hi);
                if at(mid) >= 0.5 { lo = mid } else { hi = mid }
            }
            return Some(0.5 * (lo + hi));
        }
        r = next;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Disc(f64);
    impl Mask for Disc {
        fn at(&self, u: i64, v: i64) -> bool {
            ((u * u + v * v) as f64).sqrt() <= self.0
        }
    }

    #[test]
    fn the_crossing_of_a_disc_is_found_near_its_radius() {
        let d = Disc(10.0);
        for k in 0..16 {
            let a = k as f64 * std::f64::consts::TAU / 16.0;
            let r = outermost_crossing(&d, [0.0, 0.0], [a.cos(), a.sin()], 30.0, 0.0).unwrap();
            assert!((r - 10.5).abs() < 0.8, "angle {a}: r = {r}");
        }
        assert!(outermost_crossing(&d, [50.0, 0.0], [1.0, 0.0], 10.0, 0.0).is_none());
    }
}
