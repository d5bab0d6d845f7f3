//! A cheap lower bound on how far a point lies outside a bone: a coarse grid over the
//! bone's rest frame holds the exact signed distance from each cell's centre, filled in the
//! first time a point falls in the cell. The signed distance changes no faster than the
//! point moves, so a point `r` from a centre that lies `D` outside is at least `D - r`
//! outside: most muscle vertices watched against a bone are vouched for by one lookup,
//! without a walk over the surface or a tree search (those took a quarter of a tissue
//! update on the phantom's flexion).

use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;

/// Cell edge (m). Finer cells vouch for points nearer the bone but take more exact
/// distances to fill.
const CELL_M: f32 = 0.004;
/// How far (m) beyond the bone's bounds the grid reaches (muscles watched near the knee
/// start up to 6 cm from a bone and move further with the chains).
const REACH_M: f32 = 0.08;
/// Most cells of one grid; a larger bone gets coarser cells.
const MAX_CELLS: usize = 1 << 22;
/// A cell not yet filled (a NaN no distance can be).
const UNKNOWN: u32 = u32::MAX;

/// Signed distances (negative inside) from cell centres to one bone, filled lazily. The
/// value of a cell does not depend on which thread fills it or when, so lookups from
/// parallel muscle updates give the same bits as serial ones.
#[derive(Debug)]
pub(crate) struct DistanceGrid {
    /// Corner of cell (0, 0, 0), rest frame.
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    cells: Vec<AtomicU32>,
}

impl Clone for DistanceGrid {
    fn clone(&self) -> Self {
        Self {
            origin: self.origin,
            cell: self.cell,
            dims: self.dims,
            cells: self
                .cells
                .iter()
                .map(|c| AtomicU32::new(c.load(Ordering::Relaxed)))
                .collect(),
        }
    }
}

impl DistanceGrid {
    /// A grid over the box `lo..hi` (rest frame), [`REACH_M`] wider on every side.
    pub(crate) fn new(lo: Vec3, hi: Vec3) -> Self {
        let (lo, hi) = (lo - Vec3::splat(REACH_M), hi + Vec3::splat(REACH_M));
        let size = (hi - lo).max(Vec3::splat(CELL_M));
        let mut cell = CELL_M;
        let dims = loop {
            let d = (size / cell).ceil();
            let dims = [d.x as usize, d.y as usize, d.z as usize];
            if dims.iter().product::<usize>() <= MAX_CELLS {
                break dims;
            }
            cell *= 1.25;
        };
        let cells = (0..dims.iter().product())
            .map(|_| AtomicU32::new(UNKNOWN))
            .collect();
        Self {
            origin: lo,
            cell,
            dims,
            cells,
        }
    }

    /// How far (m) `p` (rest frame) is at least outside the bone: positive only when it
    /// surely is outside, else zero (inside, too near to tell, or beyond the grid).
    /// `exact` gives the signed distance of a point, for a cell met the first time.
    pub(crate) fn clear_of(&self, p: Vec3, exact: impl FnOnce(Vec3) -> f32) -> f32 {
        let rel = (p - self.origin) / self.cell;
        // NaN and points off the grid give no bound.
        if !(rel.cmpge(Vec3::ZERO).all()) {
            return 0.0;
        }
        let [i, j, k] = [rel.x as usize, rel.y as usize, rel.z as usize];
        let [nx, ny, nz] = self.dims;
        if i >= nx || j >= ny || k >= nz {
            return 0.0;
        }
        let centre = self.origin + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * self.cell;
        let slot = &self.cells[(k * ny + j) * nx + i];
        let bits = slot.load(Ordering::Relaxed);
        let d = if bits == UNKNOWN {
            let d = exact(centre);
            slot.store(d.to_bits(), Ordering::Relaxed);
            d
        } else {
            f32::from_bits(bits)
        };
        (d - p.distance(centre)).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed distance to the unit-radius ball about the origin.
    fn ball(p: Vec3) -> f32 {
        p.length() - 1.0
    }

    #[test]
    fn the_bound_never_exceeds_the_true_distance_and_vouches_for_points_well_clear() {
        let g = DistanceGrid::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut vouched = 0;
        for n in 0..2000u32 {
            // A spread of points in and about the ball (a fixed, low-discrepancy walk).
            let f = |k: u32| ((n * k) % 997) as f32 / 997.0;
            let p = Vec3::new(f(389), f(557), f(733)) * 2.3 - 1.15;
            let b = g.clear_of(p, ball);
            assert!(b >= 0.0 && b <= ball(p).max(0.0) + 1e-6, "{p} {b}");
            if ball(p) > 0.01 && b > 0.0 {
                vouched += 1;
            }
        }
        assert!(vouched > 100, "{vouched}");
    }

    #[test]
    fn points_off_the_grid_or_not_numbers_get_no_bound() {
        let g = DistanceGrid::new(Vec3::ZERO, Vec3::splat(0.01));
        assert_eq!(g.clear_of(Vec3::splat(5.0), ball), 0.0);
        assert_eq!(g.clear_of(Vec3::splat(-5.0), ball), 0.0);
        assert_eq!(g.clear_of(Vec3::NAN, ball), 0.0);
    }

    #[test]
    fn a_cell_is_measured_once_and_its_clone_keeps_it() {
        let g = DistanceGrid::new(Vec3::ZERO, Vec3::splat(0.01));
        let p = Vec3::splat(0.005);
        let mut calls = 0;
        let first = g.clear_of(p, |c| {
            calls += 1;
            c.length() + 1.0
        });
        let again = g.clone().clear_of(p, |_| panic!("measured twice"));
        assert_eq!((calls, first.to_bits()), (1, again.to_bits()));
    }
}
