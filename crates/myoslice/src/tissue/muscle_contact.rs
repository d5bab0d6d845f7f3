//! Muscles pressing on one another: after every shape is placed on its chain, each
//! muscle's surface vertices that lie inside a neighbour move out toward that neighbour's
//! surface, half the depth each (the neighbour's vertices inside this muscle do the same),
//! so two muscles pressed together meet between their surfaces; the volume they lost comes
//! back on the sides that press on nothing. Nothing here is tied to a joint or a muscle:
//! any two shapes that come to overlap are pulled apart.
//!
//! Inside-ness is read from a shape's own structure, not a mesh query: a muscle is a
//! stack of cross-section rings placed on its chain by a known pose (centre, turn, scale),
//! so a point between two rings is mapped back into each ring's rest plane, where the
//! ring's outline is a table of radius by angle around its centre, built once.

use std::f32::consts::TAU;

use crate::par::*;
use glam::{Mat3, Vec3};

use super::MuscleShape;
use super::muscle_shape::{VOLUME_PASSES, volume_about, volume_fix};
use crate::geometry::BoneSdf;

/// Angular bins of a ring's outline table.
pub(crate) const BINS: usize = 64;

/// Rounds of pushing apart (each Jacobi: every muscle reads the others as the round
/// began), with the volume given back after each.
const ROUNDS: usize = 2;

/// Share of its depth a vertex found inside a neighbour moves out per round: half, the
/// neighbour's vertices inside it moving the other half.
const SHARE: f32 = 0.5;

/// Depth (m) below which a vertex counts as touching, not inside: the audit's tolerance is
/// 1 mm.
const TOUCH_M: f32 = 2e-4;

/// How a ring sits on its chain now: its chain point (with any shift out of bone), turn,
/// scale across and axis (see [`MuscleShape`]'s placement).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RingPose {
    pub(crate) c: Vec3,
    pub(crate) m: Mat3,
    pub(crate) across: f32,
    pub(crate) axis: Vec3,
}

/// A ring's outline in its rest plane: the plane's axes, the offset of the ring's centre
/// from its chain point, and the outline's radius (m) in each angular bin around it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RingOutline {
    pub(crate) e1: Vec3,
    pub(crate) e2: Vec3,
    pub(crate) centre: Vec3,
    pub(crate) radius: [f32; BINS],
    /// The outline itself, in the plane's axes, for a ring that is not star-shaped about
    /// its centre (traced around a hole, or bent): its radius table would claim the
    /// hole, where a neighbour may lie. Empty for star-shaped rings.
    pub(crate) polygon: Vec<(f32, f32)>,
    /// The largest radius (m): no point further from the centre is inside.
    pub(crate) reach: f32,
}

/// Whether the closed polygon `pts` winds once around the origin with every vertex
/// further round than the last (either way round): star-shaped about it, so the radius
/// by angle is the outline.
fn star_shaped(pts: &[(f32, f32)]) -> bool {
    let turns: Vec<f32> = pts
        .iter()
        .zip(pts.iter().cycle().skip(1))
        .map(|(p, q)| (p.0 * q.1 - p.1 * q.0).atan2(p.0 * q.0 + p.1 * q.1))
        .collect();
    let one_way = turns.iter().all(|d| *d > 0.0) || turns.iter().all(|d| *d < 0.0);
    one_way && (turns.iter().sum::<f32>().abs() - TAU).abs() < 1e-2
}

/// Signed distance (negative inside) from `p` to closed polygon `poly`, and the unit
/// direction that leads out of it (or further away, outside).
fn polygon_gap(poly: &[(f32, f32)], p: (f32, f32)) -> (f32, (f32, f32)) {
    let mut inside = false;
    let mut best = (f32::INFINITY, (0.0f32, 0.0f32));
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        if (a.1 > p.1) != (b.1 > p.1) && p.0 < a.0 + (p.1 - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            inside = !inside;
        }
        let e = (b.0 - a.0, b.1 - a.1);
        let l2 = (e.0 * e.0 + e.1 * e.1).max(1e-18);
        let t = (((p.0 - a.0) * e.0 + (p.1 - a.1) * e.1) / l2).clamp(0.0, 1.0);
        let q = (a.0 + e.0 * t, a.1 + e.1 * t);
        let d2 = (p.0 - q.0).powi(2) + (p.1 - q.1).powi(2);
        if d2 < best.0 {
            best = (d2, q);
        }
    }
    let d = best.0.sqrt();
    let q = best.1;
    let away = ((p.0 - q.0) / d.max(1e-9), (p.1 - q.1) / d.max(1e-9));
    if inside {
        (-d, (-away.0, -away.1))
    } else {
        (d, away)
    }
}

impl RingOutline {
    /// The outline of a ring whose vertices lie at `perp` from their chain point at rest
    /// (perpendicular to `axis`), centred on `centre` (also from the chain point): for
    /// each bin, the farthest crossing of its ray with the polygon (a star-shaped hull of
    /// rings traced around a hole).
    pub(crate) fn new(axis: Vec3, centre: Vec3, perp: &[Vec3]) -> Self {
        let e1 = axis.any_orthonormal_vector();
        let e2 = axis.cross(e1);
        let pts: Vec<(f32, f32)> = perp
            .iter()
            .map(|p| ((*p - centre).dot(e1), (*p - centre).dot(e2)))
            .collect();
        let mut radius = [0.0f32; BINS];
        for (k, r) in radius.iter_mut().enumerate() {
            let a = TAU * k as f32 / BINS as f32;
            let d = (a.cos(), a.sin());
            for (i, &p) in pts.iter().enumerate() {
                let q = pts[(i + 1) % pts.len()];
                // Ray t·d against segment p + s (q − p): t = cross(p, e)/cross(d, e).
                let e = (q.0 - p.0, q.1 - p.1);
                let den = d.0 * e.1 - d.1 * e.0;
                if den.abs() < 1e-12 {
                    continue;
                }
                let t = (p.0 * e.1 - p.1 * e.0) / den;
                let s = (p.0 * d.1 - p.1 * d.0) / den;
                if t > 0.0 && (0.0..=1.0).contains(&s) {
                    *r = r.max(t);
                }
            }
        }
        let polygon = if star_shaped(&pts) { Vec::new() } else { pts };
        Self {
            reach: radius.iter().copied().fold(0.0, f32::max),
            e1,
            e2,
            centre,
            radius,
            polygon,
        }
    }

    /// Radius at angle `a` (rad), interpolated between bins.
    fn at(&self, a: f32) -> f32 {
        let f = a.rem_euclid(TAU) / TAU * BINS as f32;
        let k = (f as usize).min(BINS - 1);
        let w = f - k as f32;
        self.radius[k] * (1.0 - w) + self.radius[(k + 1) % BINS] * w
    }
}

/// Axis-aligned box.
#[derive(Debug, Clone, Copy)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Self = Self {
        lo: Vec3::splat(f32::INFINITY),
        hi: Vec3::splat(f32::NEG_INFINITY),
    };

    fn add(&mut self, p: Vec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }
}

/// A shape's boxes for one round: the whole and each slab between consecutive rings of a
/// tube (first ring, box).
struct Boxes {
    all: Aabb,
    slabs: Vec<(u32, Aabb)>,
}

fn boxes_of(s: &MuscleShape) -> Boxes {
    let mut all = Aabb::EMPTY;
    let mut slabs = Vec::new();
    let n = s.ring_len as usize;
    let ring_box = |r: usize| {
        let mut b = Aabb::EMPTY;
        let f = s.ring_first[r] as usize;
        s.current[f..f + n].iter().for_each(|p| b.add(*p));
        b
    };
    for r in 0..s.ring_first.len() {
        let b = ring_box(r);
        all.add(b.lo);
        all.add(b.hi);
        if s.tube_of_ring[r].1 as usize > r {
            let mut slab = b;
            let next = ring_box(r + 1);
            slab.add(next.lo);
            slab.add(next.hi);
            slabs.push((r as u32, slab));
        }
    }
    Boxes { all, slabs }
}

/// Offset of `p` from ring `r`'s centre along the ring's axis (m).
fn ring_axial(s: &MuscleShape, r: usize, p: Vec3) -> f32 {
    (p - s.current[s.ring_centre[r] as usize]).dot(s.pose[r].axis)
}

/// Signed gap (m, negative inside) of `p` from ring `r`'s outline, seen in the ring's
/// plane, and the way out at that point (beyond the ring's reach, the gap to the reach).
fn ring_gap(s: &MuscleShape, r: usize, p: Vec3) -> (f32, Vec3) {
    let (pose, out) = (&s.pose[r], &s.outline[r]);
    let local = pose.m.transpose() * (p - pose.c);
    let u0 = out.e1.cross(out.e2);
    let flat = (local - u0 * local.dot(u0)) / pose.across.max(1e-6) - out.centre;
    let (x, y) = (flat.dot(out.e1), flat.dot(out.e2));
    let rho = (x * x + y * y).sqrt();
    if rho >= out.reach || out.polygon.is_empty() {
        let a = y.atan2(x);
        let edge = if rho >= out.reach {
            out.reach
        } else {
            out.at(a)
        };
        let dir = pose.m * (out.e1 * a.cos() + out.e2 * a.sin());
        return ((rho - edge) * pose.across, dir);
    }
    let (gap, (dx, dy)) = polygon_gap(&out.polygon, (x, y));
    (gap * pose.across, pose.m * (out.e1 * dx + out.e2 * dy))
}

/// Cell size (m) of the grid that finds the slabs near a vertex.
const CELL_M: f32 = 0.01;

/// Every shape's slabs binned in a uniform grid: the slabs a point may lie in are those
/// of its cell (each slab is listed in every cell its box touches).
struct SlabGrid {
    lo: Vec3,
    dims: [usize; 3],
    /// Start of each cell's entries in `entries` (one more than cells).
    start: Vec<u32>,
    /// (shape, slab index in its [`Boxes::slabs`]), in shape then slab order per cell.
    entries: Vec<(u32, u32)>,
}

impl SlabGrid {
    fn new(boxes: &[Boxes]) -> Self {
        let mut all = Aabb::EMPTY;
        for b in boxes {
            if b.all.lo.x <= b.all.hi.x {
                all.add(b.all.lo);
                all.add(b.all.hi);
            }
        }
        if all.lo.x > all.hi.x {
            return Self {
                lo: Vec3::ZERO,
                dims: [0; 3],
                start: vec![0],
                entries: Vec::new(),
            };
        }
        let size = ((all.hi - all.lo) / CELL_M).floor();
        let dims = [
            size.x as usize + 1,
            size.y as usize + 1,
            size.z as usize + 1,
        ];
        let mut grid = Self {
            lo: all.lo,
            dims,
            start: Vec::new(),
            entries: Vec::new(),
        };
        let cells = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; cells + 1];
        grid.for_each_cell(boxes, |c, _| count[c + 1] += 1);
        for c in 0..cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut entries = vec![(0u32, 0u32); count[cells] as usize];
        grid.for_each_cell(boxes, |c, e| {
            entries[fill[c] as usize] = e;
            fill[c] += 1;
        });
        grid.start = count;
        grid.entries = entries;
        grid
    }

    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        let c = ((p - self.lo) / CELL_M).floor().max(Vec3::ZERO);
        [
            (c.x as usize).min(self.dims[0] - 1),
            (c.y as usize).min(self.dims[1] - 1),
            (c.z as usize).min(self.dims[2] - 1),
        ]
    }

    fn for_each_cell(&self, boxes: &[Boxes], mut f: impl FnMut(usize, (u32, u32))) {
        for (b, bx) in boxes.iter().enumerate() {
            for (k, (_, slab)) in bx.slabs.iter().enumerate() {
                let (lo, hi) = (self.cell_of(slab.lo), self.cell_of(slab.hi));
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            f(
                                x + self.dims[0] * (y + self.dims[1] * z),
                                (b as u32, k as u32),
                            );
                        }
                    }
                }
            }
        }
    }

    /// The slabs listed where `p` lies (none outside the grid).
    fn near(&self, p: Vec3) -> &[(u32, u32)] {
        if self.dims[0] == 0 {
            return &[];
        }
        let c = (p - self.lo) / CELL_M;
        if c.min_element() < 0.0 {
            return &[];
        }
        let [x, y, z] = [c.x as usize, c.y as usize, c.z as usize];
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return &[];
        }
        let cell = x + self.dims[0] * (y + self.dims[1] * z);
        &self.entries[self.start[cell] as usize..self.start[cell + 1] as usize]
    }
}

/// How deep `p` lies in slab `k` of shape `s` (its boxes `bx`), and the way out.
fn depth_in_slab(s: &MuscleShape, bx: &Boxes, k: usize, p: Vec3) -> Option<(f32, Vec3)> {
    let (r, b) = bx.slabs[k];
    if !b.contains(p) {
        return None;
    }

    let r = r as usize;
    let (s0, s1) = (ring_axial(s, r, p), ring_axial(s, r + 1, p));
    if s0 * s1 > 0.0 {
        return None; // not between the two rings
    }
    let w = if s0 == s1 { 0.5 } else { s0 / (s0 - s1) };
    let (g0, d0) = ring_gap(s, r, p);
    let (g1, d1) = ring_gap(s, r + 1, p);
    let g = g0 * (1.0 - w) + g1 * w;
    (g < -TOUCH_M).then(|| (-g, (d0 * (1.0 - w) + d1 * w).normalize_or_zero()))
}

/// How far (m) out from a muscle's surface [`free_to_bulge`] looks for other tissue.
const BULGE_PROBE_M: f32 = 0.003;

/// Which surface vertices of each of `shapes` (at rest) may bulge to give back the
/// volume a contact took: those with neither another muscle nor a bone (`bones`, rest
/// frame) within [`BULGE_PROBE_M`] outside them, i.e. facing fat. A muscle bulging
/// where it faces a neighbour would press into it again.
pub(crate) fn free_to_bulge(shapes: &[MuscleShape], bones: &[BoneSdf]) -> Vec<Vec<bool>> {
    let boxes: Vec<Boxes> = shapes.iter().map(boxes_of).collect();
    let grid = SlabGrid::new(&boxes);
    shapes
        .par_iter()
        .enumerate()
        .map(|(a, sa)| {
            (0..sa.current.len())
                .map(|v| {
                    if sa.is_centre(v) {
                        return false;
                    }
                    let r = sa.ring_of_vertex(v);
                    let p = sa.current[v];
                    let axis = sa.pose[r].axis;
                    let o = p - sa.current[sa.ring_centre[r] as usize];
                    let out = (o - axis * o.dot(axis)).normalize_or_zero();
                    let q = p + out * BULGE_PROBE_M;
                    let in_muscle = grid.near(q).iter().any(|&(b, k)| {
                        let b = b as usize;
                        b != a && depth_in_slab(&shapes[b], &boxes[b], k as usize, q).is_some()
                    });
                    let in_bone = bones
                        .iter()
                        .any(|s| s.sample(q).is_some_and(|x| x.distance < 0.0));
                    !(in_muscle || in_bone)
                })
                .collect()
        })
        .collect()
}

/// Pushes apart every pair of `shapes` that overlap, keeping each one's volume.
pub(crate) fn separate(shapes: &mut [MuscleShape]) {
    for _ in 0..ROUNDS {
        let boxes: Vec<Boxes> = shapes.par_iter().map(boxes_of).collect();
        let grid = SlabGrid::new(&boxes);
        let moves: Vec<Vec<(u32, Vec3)>> = shapes
            .par_iter()
            .enumerate()
            .map(|(a, sa)| {
                let mut moves = Vec::new();
                for (v, &p) in sa.current.iter().enumerate() {
                    let near = grid.near(p);
                    if near.iter().all(|&(b, _)| b as usize == a) || sa.is_centre(v) {
                        continue;
                    }
                    // The deepest slab of each other shape (entries come shape by shape).
                    let mut push = Vec3::ZERO;
                    let mut deepest: Option<(u32, f32, Vec3)> = None;
                    for &(b, k) in near {
                        let rigid =
                            sa.carried.is_some() && sa.carried == shapes[b as usize].carried;
                        if b as usize == a || rigid {
                            continue;
                        }
                        if let Some((bb, d, dir)) = deepest
                            && bb != b
                        {
                            push += dir * (d * SHARE);
                            deepest = None;
                        }
                        let bi = b as usize;
                        if let Some((d, dir)) =
                            depth_in_slab(&shapes[bi], &boxes[bi], k as usize, p)
                            && deepest.is_none_or(|(_, dd, _)| d > dd)
                        {
                            deepest = Some((b, d, dir));
                        }
                    }
                    if let Some((_, d, dir)) = deepest {
                        push += dir * (d * SHARE);
                    }
                    if push != Vec3::ZERO {
                        moves.push((v as u32, push));
                    }
                }
                moves
            })
            .collect();
        if moves.iter().all(Vec::is_empty) {
            break;
        }
        shapes
            .par_iter_mut()
            .zip(&moves)
            .filter(|(_, m)| !m.is_empty())
            .for_each(|(s, m)| s.press(m));
    }
}

impl MuscleShape {
    /// Moves vertices by `moves` (vertex, displacement: out of a neighbour, see
    /// [`super::muscle_contact`]), then gives back the volume that cost on the vertices
    /// that did not move, spreading their cross-sections about their rings' centres.
    pub(super) fn press(&mut self, moves: &[(u32, Vec3)]) {
        let mut free: Vec<bool> = if self.bulges.len() == self.current.len() {
            self.bulges.to_vec()
        } else {
            vec![true; self.current.len()]
        };
        for &(v, d) in moves {
            self.current[v as usize] += d;
            free[v as usize] = false;
        }
        let surface = (0..self.current.len()).filter(|&v| !self.is_centre(v));
        let (n_free, n_all) = surface.fold((0usize, 0usize), |(f, a), v| {
            (f + usize::from(free[v]), a + 1)
        });
        let share = n_free as f32 / n_all.max(1) as f32;
        let origin = self.current[self.current.len() / 2];
        let centres: Vec<Vec3> = (0..self.pose.len())
            .map(|r| self.current_centre(r))
            .collect();
        let mut v = volume_about(&self.current, &self.triangles, origin);
        for pass in 0..VOLUME_PASSES {
            let Some(fix) = volume_fix(self.rest_volume, v, pass) else {
                break;
            };
            // Too much volume (pushed out several ways at once): every cross-section
            // shrinks, which also eases the contacts. Too little: only the free share
            // of the surface moves, and it makes up the whole.
            let all = fix < 1.0 || share < 0.05;
            let k = if all {
                fix.clamp(0.8, 1.25)
            } else {
                (1.0 + (fix - 1.0) / share).clamp(0.8, 1.25)
            };
            for (vi, p) in self.current.iter_mut().enumerate() {
                let ring = self.ring_of[vi] as usize;
                if !(all || free[vi]) {
                    continue;
                }
                let (c, a) = (centres[ring], self.pose[ring].axis);
                let o = *p - c;
                let along = a * o.dot(a);
                *p = c + along + (o - along) * k;
            }
            v = volume_about(&self.current, &self.triangles, origin);
        }
        self.volume_now = v;
    }

    /// Where ring `r`'s centre lies now (in its plane), from its pose.
    fn current_centre(&self, r: usize) -> Vec3 {
        let p = &self.pose[r];
        let o = &self.outline[r];
        p.c + p.m * (o.centre * p.across)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square 2 cm across about the origin, in the plane z = 0, counter-clockwise.
    fn square() -> Vec<Vec3> {
        (0..16)
            .map(|k| {
                let t = k as f32 / 4.0;
                let (side, f) = ((t as usize) % 4, t.fract() * 2.0 - 1.0);
                let p = match side {
                    0 => Vec3::new(1.0, f, 0.0),
                    1 => Vec3::new(-f, 1.0, 0.0),
                    2 => Vec3::new(-1.0, -f, 0.0),
                    _ => Vec3::new(f, -1.0, 0.0),
                };
                p * 0.01
            })
            .collect()
    }

    #[test]
    fn a_square_ring_is_star_shaped_and_its_outline_runs_from_its_sides_to_its_corners() {
        let o = RingOutline::new(Vec3::Z, Vec3::ZERO, &square());
        assert!(o.polygon.is_empty(), "star-shaped about its centre");
        assert!((o.reach - 0.01 * 2f32.sqrt()).abs() < 2e-4, "{}", o.reach);
        let least = o.radius.iter().copied().fold(f32::MAX, f32::min);
        assert!((least - 0.01).abs() < 2e-4, "{least}");
    }

    #[test]
    fn a_ring_traced_around_a_hole_keeps_its_polygon_and_the_hole_is_outside() {
        // A C: the square's outline with a slot cut in to the centre along +x.
        let mut c: Vec<(f32, f32)> = vec![(0.01, 0.001), (0.002, 0.001), (0.002, -0.001)];
        c.extend([
            (0.01, -0.001),
            (0.01, -0.01),
            (-0.01, -0.01),
            (-0.01, 0.01),
            (0.01, 0.01),
        ]);
        assert!(!star_shaped(&c));
        let (hole, _) = polygon_gap(&c, (0.005, 0.0));
        assert!(
            (hole - 0.001).abs() < 1e-6,
            "outside, 1 mm from the slot's sides: {hole}"
        );
        let (inside, out) = polygon_gap(&c, (-0.008, 0.0));
        assert!(
            (inside + 0.002).abs() < 1e-6,
            "2 mm inside the far side: {inside}"
        );
        assert!(
            (out.0 + 1.0).abs() < 1e-6,
            "the way out is toward the far side: {out:?}"
        );
    }
}
