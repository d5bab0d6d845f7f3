//! Exact(-enough) self-intersection test of a triangle surface: does any triangle cross
//! another one it shares no vertex with?

use crate::par::*;
use glam::{UVec3, Vec3, Vec3A};

use crate::geometry::triangles_cross;

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
    let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of(vertices, t)).collect();
    let Some(grid) = TriangleGrid::new(&boxes, triangles, vertices) else {
        return Vec::new();
    };
    let is_active = |i: usize| active.is_none_or(|a| a[i]);
    let query: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&i| is_active(i as usize))
        .collect();
    grid.crossing_pairs(vertices, triangles, &boxes, &query, |i| {
        is_active(i as usize)
    })
}

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub lo: Vec3,
    /// Upper corner.
    pub hi: Vec3,
}

impl Aabb {
    /// The box of triangle `t`.
    pub fn of(vertices: &[Vec3], t: &[u32; 3]) -> Self {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        Self {
            lo: a.min(b).min(c),
            hi: a.max(b).max(c),
        }
    }

    /// The smallest box holding both.
    pub fn union(&self, o: &Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// Whether the boxes meet.
    pub fn overlaps(&self, o: &Self) -> bool {
        !(self.lo.cmpgt(o.hi).any() || o.lo.cmpgt(self.hi).any())
    }
}

/// A uniform grid over triangle boxes (counting-sorted cell lists): which triangles may
/// meet a given box. Built once, queried many times while the triangles stay within
/// the boxes it was built with.
#[derive(Debug, Clone)]
pub struct TriangleGrid {
    lo: Vec3,
    inv_cell: f32,
    dims: UVec3,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    /// A grid of `boxes` (one per triangle of `triangles` at `vertices`, which set the
    /// cell size: about the mean edge). None when there is nothing finite to hold.
    pub fn new(boxes: &[Aabb], triangles: &[[u32; 3]], vertices: &[Vec3]) -> Option<Self> {
        if boxes.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for b in boxes {
            lo = lo.min(b.lo);
            hi = hi.max(b.hi);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let mean_edge: f64 = triangles
            .iter()
            .map(|t| f64::from(vertices[t[0] as usize].distance(vertices[t[1] as usize])))
            .sum::<f64>()
            / triangles.len().max(1) as f64;
        let cell = (mean_edge as f32).max(1e-6);
        // At most ~64 cells per triangle on average: keeps the grid small for any input.
        let cell = cell.max(((hi - lo).element_product() / (64.0 * boxes.len() as f32)).cbrt());
        // At most 1024 cells a side and 2^24 in all, whatever the input (a flat or huge
        // set of boxes would otherwise overflow the count).
        let mut cell = cell;
        while ((hi - lo) / cell).max_element() >= 1024.0
            || ((hi - lo) / cell + 1.0).element_product() >= (1u32 << 24) as f32
        {
            cell *= 2.0;
        }
        let dims = ((hi - lo) / cell).as_uvec3() + 1;
        let n_cells = dims.x as usize * dims.y as usize * dims.z as usize;
        let mut g = Self {
            lo,
            inv_cell: 1.0 / cell,
            dims,
            start: vec![0u32; n_cells + 1],
            items: Vec::new(),
        };
        let mut start = std::mem::take(&mut g.start);
        for b in boxes {
            g.for_cells(b, |k| start[k + 1] += 1);
        }
        for k in 0..n_cells {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[n_cells] as usize];
        for (i, b) in boxes.iter().enumerate() {
            g.for_cells(b, |k| {
                items[fill[k] as usize] = i as u32;
                fill[k] += 1;
            });
        }
        (g.start, g.items) = (start, items);
        Some(g)
    }

    fn cell_of(&self, p: Vec3) -> UVec3 {
        // Truncation is the floor here (non-negative), and needs no libm call.
        ((p - self.lo) * self.inv_cell)
            .max(Vec3::ZERO)
            .as_uvec3()
            .min(self.dims - 1)
    }

    fn key(&self, c: UVec3) -> usize {
        (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize
    }

    fn for_cells(&self, b: &Aabb, mut f: impl FnMut(usize)) {
        let (a, c) = (self.cell_of(b.lo), self.cell_of(b.hi));
        for z in a.z..=c.z {
            for y in a.y..=c.y {
                for x in a.x..=c.x {
                    f(self.key(UVec3::new(x, y, z)));
                }
            }
        }
    }

    /// The pairs `(a, b)`, `a < b`, sharing no vertex, that cross at `vertices`, among
    /// those with at least one triangle in `query` (`queried` tells membership); `boxes`
    /// are the triangles' current boxes, which the grid must have been built with.
    /// Sorted.
    pub fn crossing_pairs(
        &self,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
        boxes: &[Aabb],
        query: &[u32],
        queried: impl Fn(u32) -> bool + Sync,
    ) -> Vec<(u32, u32)> {
        // The cells the queried triangles cover, in order.
        let mut touched = vec![false; self.start.len() - 1];
        for &a in query {
            self.for_cells(&boxes[a as usize], |k| touched[k] = true);
        }
        let cells: Vec<usize> = (0..touched.len()).filter(|&k| touched[k]).collect();
        // The cell of each box's low corner: that of a pair's overlap is their
        // componentwise max (`cell_of` is monotone), with no float work per pair.
        let low: Vec<UVec3> = boxes.iter().map(|b| self.cell_of(b.lo)).collect();
        let (nx, nxy) = (
            self.dims.x as usize,
            self.dims.x as usize * self.dims.y as usize,
        );
        // Cells in parallel; the sort below makes the order independent of the split.
        let mut pairs: Vec<(u32, u32)> = cells
            .par_chunks(256)
            .flat_map_iter(|chunk| {
                let mut found = Vec::new();
                // A cell's boxes side by side as SIMD vectors: its pair loop reads only
                // these, and tests a pair's overlap with two compares, no branch per axis.
                let mut cell: Vec<(Vec3A, Vec3A, UVec3, bool, u32)> = Vec::new();
                for &k in chunk {
                    let here = UVec3::new((k % nx) as u32, (k % nxy / nx) as u32, (k / nxy) as u32);
                    let items = &self.items[self.start[k] as usize..self.start[k + 1] as usize];
                    cell.clear();
                    cell.extend(items.iter().map(|&a| {
                        let b = &boxes[a as usize];
                        (b.lo.into(), b.hi.into(), low[a as usize], queried(a), a)
                    }));
                    for (ia, &(alo, ahi, la, qa, a)) in cell.iter().enumerate() {
                        for &(blo, bhi, lb, qb, b) in &cell[ia + 1..] {
                            // As `Aabb::overlaps` (a NaN box meets every box).
                            if !(qa || qb) || (alo.cmpgt(bhi) | blo.cmpgt(ahi)).any() {
                                continue;
                            }
                            // Each pair once: in the cell holding the overlap's low corner.
                            if la.max(lb) != here {
                                continue;
                            }
                            if let Some(p) = crossing(vertices, triangles, a, b) {
                                found.push(p);
                            }
                        }
                    }
                }
                found
            })
            .collect();
        pairs.sort_unstable();
        pairs
    }
}

/// The pairs, as [`TriangleGrid::crossing_pairs`], for a few queried triangles: each
/// against every triangle whose box meets its own, without a grid.
pub fn crossing_pairs_of_few(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    boxes: &[Aabb],
    query: &[u32],
    queried: impl Fn(u32) -> bool,
) -> Vec<(u32, u32)> {
    let near = near_query(boxes, query);
    let mut pairs = Vec::new();
    for &a in query {
        for &b in &near {
            // Each pair once: from its smaller index when both are queried.
            if b == a || (b < a && queried(b)) || !boxes[a as usize].overlaps(&boxes[b as usize]) {
                continue;
            }
            if let Some(p) = crossing(vertices, triangles, a, b) {
                pairs.push(p);
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// The pairs, as [`TriangleGrid::crossing_pairs`], from a grid over only the triangles
/// whose boxes meet the box around the queried ones: after a local change that grid is
/// a small part of the whole.
pub fn crossing_pairs_near(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    boxes: &[Aabb],
    query: &[u32],
    queried: impl Fn(u32) -> bool + Sync,
) -> Vec<(u32, u32)> {
    // In index order, so pairs keep their order when mapped back.
    let near = near_query(boxes, query);
    let sub_boxes: Vec<Aabb> = near.iter().map(|&i| boxes[i as usize]).collect();
    let sub_triangles: Vec<[u32; 3]> = near.iter().map(|&i| triangles[i as usize]).collect();
    // Every queried triangle is near (its box is inside the union).
    let local: Vec<u32> = query
        .iter()
        .filter_map(|a| near.binary_search(a).ok().map(|l| l as u32))
        .collect();
    let Some(grid) = TriangleGrid::new(&sub_boxes, &sub_triangles, vertices) else {
        return Vec::new();
    };
    grid.crossing_pairs(vertices, &sub_triangles, &sub_boxes, &local, |l| {
        queried(near[l as usize])
    })
    .into_iter()
    .map(|(a, b)| (near[a as usize], near[b as usize]))
    .collect()
}

/// The triangles, in index order, whose boxes meet the box around the queried ones
/// (none without a query).
fn near_query(boxes: &[Aabb], query: &[u32]) -> Vec<u32> {
    let Some(all) = query
        .iter()
        .map(|&a| boxes[a as usize])
        .reduce(|u, b| u.union(&b))
    else {
        return Vec::new();
    };
    (0..boxes.len() as u32)
        .filter(|&b| boxes[b as usize].overlaps(&all))
        .collect()
}

/// `(min, max)` if triangles `a` and `b` share no vertex and cross.
fn crossing(vertices: &[Vec3], triangles: &[[u32; 3]], a: u32, b: u32) -> Option<(u32, u32)> {
    let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
    if ta.iter().any(|v| tb.contains(v)) {
        return None;
    }
    let (pa, pb) = (
        ta.map(|v| vertices[v as usize]),
        tb.map(|v| vertices[v as usize]),
    );
    // Most candidates lie clearly on one side of the other's plane: told apart in single
    // precision with a margin well above its rounding; the rest get the exact test.
    if clearly_one_side(&pa, &pb) || clearly_one_side(&pb, &pa) {
        return None;
    }
    let exact = |p: [Vec3; 3]| p.map(Vec3::as_dvec3);
    triangles_cross(&exact(pa), &exact(pb)).then_some((a.min(b), a.max(b)))
}

/// Whether all corners of `a` lie on one side of the plane of `b` by more than a margin
/// far above single-precision rounding (about `b`'s first corner, so coordinates are
/// small).
fn clearly_one_side(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    let (e1, e2) = (b[1] - b[0], b[2] - b[0]);
    let n = e1.cross(e2);
    let d = a.map(|p| n.dot(p - b[0]));
    // |n| ~ b's edge², the distances ~ that times how far a's corners lie from b's:
    // rounding is ~1e-6 of their product at worst.
    let scale = e1.length_squared().max(e2.length_squared());
    let reach = a
        .iter()
        .map(|p| p.distance_squared(b[0]))
        .fold(scale, f32::max);
    let margin = 1e-4 * scale * reach.sqrt();
    (d[0] > margin && d[1] > margin && d[2] > margin)
        || (d[0] < -margin && d[1] < -margin && d[2] < -margin)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crumpled 12 × 12 sheet folded over itself: many crossing pairs.
    fn crumpled() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut seed = 12345u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let n = 13;
        let mut v = Vec::new();
        for j in 0..n {
            for i in 0..n {
                // Folded in two along x, with noise: the halves pass through each other.
                let (x, y) = (i as f32 * 0.1, j as f32 * 0.1);
                let fx = if x > 0.6 { 1.2 - x } else { x };
                v.push(Vec3::new(
                    fx + 0.03 * rnd(),
                    y,
                    0.02 * (x * 9.0).sin() + 0.04 * rnd(),
                ));
            }
        }
        let mut t = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let k = (j * n + i) as u32;
                t.push([k, k + 1, k + n as u32 + 1]);
                t.push([k, k + n as u32 + 1, k + n as u32]);
            }
        }
        (v, t)
    }

    #[test]
    fn the_grid_and_the_local_searches_find_exactly_the_crossing_pairs() {
        let (v, t) = crumpled();
        let boxes: Vec<Aabb> = t.iter().map(|tri| Aabb::of(&v, tri)).collect();
        let grid = TriangleGrid::new(&boxes, &t, &v).unwrap_or_else(|| panic!("a grid"));
        // Spread over the sheet, and a patch across the fold (rows 3–5, columns 4–8).
        type Query = Box<dyn Fn(u32) -> bool + Sync>;
        let mut cases: Vec<(String, Query)> = [1, 3, 7, 50]
            .map(|stride| {
                let q: Query = Box::new(move |i| i % stride == 0);
                (format!("every {stride}th triangle"), q)
            })
            .into_iter()
            .collect();
        cases.push((
            "a patch".into(),
            Box::new(|i| (4..9).contains(&(i / 2 % 12)) && (3..6).contains(&(i / 24))),
        ));
        for (name, queried) in &cases {
            let query: Vec<u32> = (0..t.len() as u32).filter(|&i| queried(i)).collect();
            // Every pair, by brute force.
            let mut want = Vec::new();
            for a in 0..t.len() as u32 {
                for b in a + 1..t.len() as u32 {
                    if (queried(a) || queried(b))
                        && let Some(p) = crossing(&v, &t, a, b)
                    {
                        want.push(p);
                    }
                }
            }
            let by_grid = grid.crossing_pairs(&v, &t, &boxes, &query, queried);
            let by_few = crossing_pairs_of_few(&v, &t, &boxes, &query, queried);
            let by_near = crossing_pairs_near(&v, &t, &boxes, &query, queried);
            assert!(!want.is_empty(), "the sheet crosses itself at {name}");
            assert_eq!(by_grid, want, "grid, {name} queried");
            assert_eq!(by_few, want, "few, {name} queried");
            assert_eq!(by_near, want, "near, {name} queried");
        }
        // The patch's grid is a part of the sheet's.
        let patch: Vec<u32> = (0..t.len() as u32).filter(|&i| cases[4].1(i)).collect();
        assert!(near_query(&boxes, &patch).len() < t.len());
    }

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
