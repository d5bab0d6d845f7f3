//! The fat keeps its volume and never folds: constraints that act inside the shape-matching
//! iterations, beside the muscles' pull, the contact and the bones, so that the last word
//! of an update is not a pass that folds what the others left.
//!
//! Per element, the mean of its eight corner Jacobians (its volume, exactly for a
//! parallelepiped) is held at its rest value, and no corner Jacobian may fall below a
//! share of its own rest value (ParaView's validity test, with a margin). Position-based
//! projections: [`FatVolume::hold`] on many elements at once, each vertex moved by the
//! mean of its elements' corrections (Jacobi, summed in element order), and
//! [`FatVolume::unfold`] on the few elements left folded, one after the other in index
//! order (Gauss–Seidel), and [`FatVolume::untangle`] on the vertices of what that left,
//! one after the other. None depends on the thread count.

use glam::Vec3;

use super::fat_solver::FatSolver;
use super::fat_untangle;
use crate::lattice::{HEX_CORNERS, corner_jacobian, corner_jacobians};
use crate::par::*;

/// An element's volume is held only when it is further than this share off its rest
/// volume: most of the relaxed region moves nearly rigidly.
const VOLUME_SLACK: f32 = 0.05;

/// Sweeps over which the unfolding must have unfolded an element to go on.
const STALLED_AFTER: usize = 4;

/// Elements from which a projection round runs on several threads.
const PARALLEL_FROM: usize = 512;

/// What the constraints need of the rest fat: each element's rest corner Jacobians, and
/// which element corners meet at each vertex.
#[derive(Debug)]
pub(crate) struct FatVolume {
    rest: Vec<[f32; 8]>,
    inc_start: Vec<u32>,
    inc: Vec<u32>,
}

/// Buffers the projections fill anew each time.
#[derive(Debug, Default)]
pub(crate) struct VolumeBuffers {
    /// Correction of each element's corners, and whether it has one.
    corr: Vec<[Vec3; 8]>,
    moved: Vec<bool>,
    /// Elements projected this round, and their corrections.
    elements: Vec<u32>,
    out: Vec<([Vec3; 8], bool)>,
    /// Vertices they touch, and where those go.
    vertices: Vec<u32>,
    seen: Vec<bool>,
    new_x: Vec<Vec3>,
}

impl VolumeBuffers {
    /// The elements the last [`FatVolume::untangle`] left folded (ascending), taken out.
    pub(crate) fn take_folded(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.elements)
    }
}

/// The gradient of corner `c`'s Jacobian with respect to the four points it involves.
#[inline]
fn gradient(p: &[Vec3; 8], c: [usize; 4]) -> [(usize, Vec3); 4] {
    let o = p[c[0]];
    let (a, b, d) = (p[c[1]] - o, p[c[2]] - o, p[c[3]] - o);
    let (ga, gb, gd) = (b.cross(d), d.cross(a), a.cross(b));
    [(c[0], -(ga + gb + gd)), (c[1], ga), (c[2], gb), (c[3], gd)]
}

/// Moves `p` along `g` (per point, weighted by `w`) so that a function with gradient `g`
/// changes by `change` to first order.
#[inline]
fn step_along(p: &mut [Vec3; 8], w: &[f32; 8], g: &[(usize, Vec3)], change: f32) {
    let den: f32 = g.iter().map(|(i, gi)| w[*i] * gi.length_squared()).sum();
    if den > 1e-30 {
        let l = change / den;
        for &(i, gi) in g {
            p[i] += gi * (l * w[i]);
        }
    }
}

/// Raises each corner Jacobian of `p` below `floor` × its `rest` value to that bound, one
/// corner after the other.
#[inline]
fn raise_corners(p: &mut [Vec3; 8], w: &[f32; 8], rest: &[f32; 8], floor: f32) {
    for (c, r) in HEX_CORNERS.iter().zip(rest) {
        let (min, j) = (floor * r, corner_jacobian(p, *c));
        if j < min {
            let g = gradient(p, *c);
            step_along(p, w, &g, min - j);
        }
    }
}

impl FatVolume {
    /// The constraints of a fat lattice at rest.
    pub(crate) fn new(rest: &[Vec3], hexes: &[[u32; 8]]) -> Self {
        let (inc_start, inc) = super::incidence::vertex_corners(rest.len(), hexes);
        Self {
            rest: hexes.iter().map(|h| corner_jacobians(rest, h)).collect(),
            inc_start,
            inc,
        }
    }

    /// Whether element `e` has a corner below `floor` × its rest Jacobian, and whether it
    /// has one below zero (folded).
    fn below_at(&self, x: &[Vec3], hexes: &[[u32; 8]], e: usize, floor: f32) -> (bool, bool) {
        let c = corner_jacobians(x, &hexes[e]);
        let below = |f: f32| c.iter().zip(&self.rest[e]).any(|(j, r)| *j < f * r);
        (below(floor), below(0.0))
    }

    /// One projection of every active element more than [`VOLUME_SLACK`] off its rest
    /// volume or with a corner below `floor` × its rest Jacobian: its volume a share
    /// `stiffness` of the way back to rest, then each low corner up to the floor; free
    /// vertices only, each moved by the mean of its elements' corrections.
    pub(crate) fn hold(
        &self,
        fat: &mut FatSolver,
        b: &mut VolumeBuffers,
        stiffness: f32,
        floor: f32,
    ) {
        let rest = &self.rest;
        let sum0 = |e: usize| rest[e].iter().sum::<f32>();
        b.elements.clear();
        b.elements
            .par_extend((0..fat.hexes.len() as u32).into_par_iter().filter(|&e| {
                let e = e as usize;
                fat.active[e] && {
                    let c = corner_jacobians(&fat.x, &fat.hexes[e]);
                    let sum: f32 = c.iter().sum();
                    (sum - sum0(e)).abs() > VOLUME_SLACK * sum0(e)
                        || c.iter().zip(&rest[e]).any(|(j, r)| *j < floor * r)
                }
            }));
        let FatSolver { x, hexes, free, .. } = fat;
        self.correct(x, hexes, free, b, |p, w, e| {
            // Σ corner Jacobians is 8 × the volume; its gradient is the sum of theirs.
            let mut g = [(0, Vec3::ZERO); 8];
            for (i, gi) in g.iter_mut().enumerate() {
                gi.0 = i;
            }
            let mut change = sum0(e);
            for c in HEX_CORNERS {
                change -= corner_jacobian(p, c);
                for (i, gi) in gradient(p, c) {
                    g[i].1 += gi;
                }
            }
            step_along(p, w, &g, change * stiffness);
            raise_corners(p, w, &rest[e], floor);
            true
        });
    }

    /// Unfolds: each active element with a corner below `floor` × its rest Jacobian moves
    /// its free corners back over that bound, element after element in index order
    /// (Gauss–Seidel: a fold shared by neighbours is undone in a few sweeps, where
    /// averaged steps took tens), for at most `rounds` sweeps, each looking again only at
    /// the elements about what the last one moved.
    pub(crate) fn unfold(
        &self,
        fat: &mut FatSolver,
        b: &mut VolumeBuffers,
        floor: f32,
        rounds: usize,
    ) -> usize {
        b.elements.clear();
        b.elements
            .par_extend((0..fat.hexes.len() as u32).into_par_iter().filter(|&e| {
                fat.active[e as usize] && self.below_at(&fat.x, &fat.hexes, e as usize, floor).0
            }));
        let mut folded = b
            .elements
            .iter()
            .filter(|&&e| self.below_at(&fat.x, &fat.hexes, e as usize, floor).1)
            .count();
        if b.seen.len() != fat.x.len() {
            b.seen = vec![false; fat.x.len()];
        }
        let rest = &self.rest;
        let mut history = [usize::MAX; STALLED_AFTER];
        for r in 0..rounds {
            // Stop when no element is left folded, or when the sweeps have stopped
            // unfolding any (tissue squeezed with no room left: the guard's business).
            let before = std::mem::replace(&mut history[r % STALLED_AFTER], folded);
            if folded == 0 || folded >= before {
                return folded;
            }
            b.vertices.clear();
            for &e in &b.elements {
                let h = &fat.hexes[e as usize];
                let mut p = h.map(|i| fat.x[i as usize]);
                let w = h.map(|i| if fat.free[i as usize] { 1.0 } else { 0.0 });
                let start = p;
                raise_corners(&mut p, &w, &rest[e as usize], floor);
                for i in 0..8 {
                    let v = h[i] as usize;
                    if p[i] != start[i] {
                        fat.x[v] = p[i];
                        if !b.seen[v] {
                            b.seen[v] = true;
                            b.vertices.push(v as u32);
                        }
                    }
                }
            }
            // Next sweep: the elements about the vertices just moved.
            for &v in &b.vertices {
                b.seen[v as usize] = false;
            }
            let moved = std::mem::take(&mut b.vertices);
            self.elements_about(b, &moved);
            b.vertices = moved;
            let (x, hexes, active) = (&fat.x, &fat.hexes, &fat.active);
            folded = 0;
            b.elements.retain(|&e| {
                let (below, flat) = self.below_at(x, hexes, e as usize, floor);
                folded += usize::from(active[e as usize] && flat);
                active[e as usize] && below
            });
        }
        folded
    }

    /// Untangles what [`Self::unfold`] left: each free vertex of a folded active element
    /// (a corner Jacobian at or below zero) moves to where the corners of all its
    /// elements are best at once ([`fat_untangle`], a barrier at zero: where an
    /// element's own corners pull against its neighbours', the unfolding's stall, a
    /// vertex that heeds all its elements finds the room between them). One vertex
    /// after the other in index order; sweeps over the folded elements about what moved
    /// until none is, or [`STALLED_AFTER`] sweeps unfold none, at most `sweeps`. Starts
    /// from the folded ones among `b`'s elements: what [`Self::unfold`] left there, or
    /// those about some vertices ([`Self::elements_about`]); leaves there the folded
    /// ones it could not unfold.
    ///
    /// The barrier sits at zero, not at the unfolding's floor: one at the floor weighed a
    /// folded corner no more than one merely under it, and traded the one for the other
    /// (more elements left folded at deep flexion, docs/tissue-history.md).
    pub(crate) fn untangle(&self, fat: &mut FatSolver, b: &mut VolumeBuffers, sweeps: usize) {
        let (x, hexes, active) = (&fat.x, &fat.hexes, &fat.active);
        b.elements
            .retain(|&e| active[e as usize] && self.below_at(x, hexes, e as usize, 0.0).1);
        if b.seen.len() != fat.x.len() {
            b.seen = vec![false; fat.x.len()];
        }
        let mut folded = b.elements.len();
        let mut history = [usize::MAX; STALLED_AFTER];
        let mut terms = Vec::new();
        for r in 0..sweeps {
            let before = std::mem::replace(&mut history[r % STALLED_AFTER], folded);
            if folded == 0 || folded >= before {
                return;
            }
            b.vertices.clear();
            for &e in &b.elements {
                for &v in &fat.hexes[e as usize] {
                    if fat.free[v as usize] && !b.seen[v as usize] {
                        b.seen[v as usize] = true;
                        b.vertices.push(v);
                    }
                }
            }
            b.vertices.sort_unstable();
            // One regularisation per sweep, from the worst corner about what moves.
            let s_min = b
                .vertices
                .iter()
                .map(|&v| self.vertex_sigma_min(fat, v as usize))
                .fold(f64::INFINITY, f64::min);
            let delta2 = fat_untangle::delta_squared(s_min);
            for &v in &b.vertices {
                b.seen[v as usize] = false;
                self.vertex_terms(fat, v as usize, &mut terms);
                if let Some(d) = fat_untangle::untangle_move(&terms, delta2) {
                    fat.x[v as usize] += d;
                }
            }
            let moved = std::mem::take(&mut b.vertices);
            self.elements_about(b, &moved);
            b.vertices = moved;
            let (x, hexes, active) = (&fat.x, &fat.hexes, &fat.active);
            b.elements
                .retain(|&e| active[e as usize] && self.below_at(x, hexes, e as usize, 0.0).1);
            folded = b.elements.len();
        }
    }

    /// Untangles the elements about `moved` and the elements `also` with the `moved`
    /// vertices held where they were put (by a pass with the last word on them), then
    /// frees them again. Leaves in `b` what it left folded ([`VolumeBuffers::take_folded`]).
    pub(crate) fn untangle_holding(
        &self,
        fat: &mut FatSolver,
        b: &mut VolumeBuffers,
        (moved, also): (&[u32], &[u32]),
        sweeps: usize,
    ) {
        for &v in moved {
            fat.free[v as usize] = false;
        }
        self.elements_about(b, moved);
        b.elements.extend_from_slice(also);
        b.elements.sort_unstable();
        b.elements.dedup();
        self.untangle(fat, b, sweeps);
        for &v in moved {
            fat.free[v as usize] = true;
        }
    }

    /// The corner tetrahedra vertex `v` takes part in (of all its elements), into
    /// `terms`.
    fn vertex_terms(&self, fat: &FatSolver, v: usize, terms: &mut Vec<fat_untangle::CornerTerm>) {
        terms.clear();
        let origin = fat.x[v];
        for (now, rest, k) in self.corners_of(fat, v) {
            fat_untangle::push_terms(&now, &rest, k, origin, terms);
        }
    }

    /// The smallest corner Jacobian relative to its rest one among the corner
    /// tetrahedra vertex `v` takes part in.
    fn vertex_sigma_min(&self, fat: &FatSolver, v: usize) -> f64 {
        self.corners_of(fat, v)
            .map(|(now, rest, k)| fat_untangle::sigma_min(&now, &rest, k))
            .fold(f64::INFINITY, f64::min)
    }

    /// Each element about vertex `v`: its corners now and at rest, and which is `v`.
    fn corners_of<'a>(
        &'a self,
        fat: &'a FatSolver,
        v: usize,
    ) -> impl Iterator<Item = ([Vec3; 8], [Vec3; 8], usize)> + 'a {
        let (s, t) = (self.inc_start[v] as usize, self.inc_start[v + 1] as usize);
        self.inc[s..t].iter().map(move |&c| {
            let (e, k) = ((c >> 3) as usize, (c & 7) as usize);
            let h = &fat.hexes[e];
            (
                h.map(|i| fat.x[i as usize]),
                h.map(|i| fat.rest[i as usize]),
                k,
            )
        })
    }

    /// Puts the elements about `vertices` in `b` (ascending, each once), where
    /// [`Self::untangle`] starts.
    pub(crate) fn elements_about(&self, b: &mut VolumeBuffers, vertices: &[u32]) {
        b.elements.clear();
        for &v in vertices {
            let (s, t) = (self.inc_start[v as usize], self.inc_start[v as usize + 1]);
            b.elements
                .extend(self.inc[s as usize..t as usize].iter().map(|c| c >> 3));
        }
        b.elements.sort_unstable();
        b.elements.dedup();
    }

    /// Runs `project` (corners, their inverse masses, element → whether it moved them) on
    /// each of `b.elements`, then moves each free vertex they touch by the mean of the
    /// corrections of the elements that moved it.
    fn correct(
        &self,
        x_mut: &mut [Vec3],
        hexes: &[[u32; 8]],
        free: &[bool],
        b: &mut VolumeBuffers,
        project: impl Fn(&mut [Vec3; 8], &[f32; 8], usize) -> bool + Sync,
    ) {
        let ne = hexes.len();
        if b.corr.len() != ne {
            b.corr = vec![[Vec3::ZERO; 8]; ne];
            b.moved = vec![false; ne];
        }
        if b.seen.len() != x_mut.len() {
            b.seen = vec![false; x_mut.len()];
        }
        let x: &[Vec3] = x_mut;
        let one = |&e: &u32| {
            let h = &hexes[e as usize];
            let start = h.map(|i| x[i as usize]);
            let w = h.map(|i| if free[i as usize] { 1.0 } else { 0.0 });
            let mut p = start;
            let moved = w.iter().any(|&w| w > 0.0) && project(&mut p, &w, e as usize);
            let mut d = [Vec3::ZERO; 8];
            for i in 0..8 {
                d[i] = p[i] - start[i];
            }
            (d, moved)
        };
        b.out.clear();
        // A thread pays for itself only on many elements (the later rounds see a few).
        if b.elements.len() < PARALLEL_FROM {
            b.out.extend(b.elements.iter().map(one));
        } else {
            b.out.par_extend(b.elements.par_iter().map(one));
        }
        b.vertices.clear();
        for (&e, &(d, moved)) in b.elements.iter().zip(&b.out) {
            b.corr[e as usize] = d;
            b.moved[e as usize] = moved;
            if moved {
                for &v in &hexes[e as usize] {
                    if free[v as usize] && !b.seen[v as usize] {
                        b.seen[v as usize] = true;
                        b.vertices.push(v);
                    }
                }
            }
        }
        // In index order: by a scan of the marks when many, else by sorting the few.
        if b.vertices.len() > b.seen.len() / 16 {
            b.vertices.clear();
            let seen = &b.seen;
            b.vertices
                .extend((0..seen.len() as u32).filter(|&v| seen[v as usize]));
        } else {
            b.vertices.sort_unstable();
        }
        let (corr, moved) = (&b.corr, &b.moved);
        let (start, inc) = (&self.inc_start, &self.inc);
        b.new_x.clear();
        let moved_to = |&v: &u32| {
            let (s, t) = (start[v as usize] as usize, start[v as usize + 1] as usize);
            let (mut sum, mut n) = (Vec3::ZERO, 0.0f32);
            for &c in &inc[s..t] {
                let (e, k) = ((c >> 3) as usize, (c & 7) as usize);
                if moved[e] {
                    sum += corr[e][k];
                    n += 1.0;
                }
            }
            x[v as usize] + sum / n.max(1.0)
        };
        if b.vertices.len() < PARALLEL_FROM {
            b.new_x.extend(b.vertices.iter().map(moved_to));
        } else {
            b.new_x.par_extend(b.vertices.par_iter().map(moved_to));
        }
        for (&v, p) in b.vertices.iter().zip(&b.new_x) {
            x_mut[v as usize] = *p;
            b.seen[v as usize] = false;
        }
        for &e in &b.elements {
            b.moved[e as usize] = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::{hex_volume_f32, min_corner_jacobian};

    fn folded(fat: &FatSolver) -> usize {
        fat.hexes
            .iter()
            .filter(|h| min_corner_jacobian(&fat.x, h) <= 0.0)
            .count()
    }

    #[test]
    fn a_vertex_pushed_through_its_neighbours_is_unfolded_and_held_vertices_stay() {
        let mut fat = FatSolver::grid(4, 3, 3, 0.01);
        let c = FatVolume::new(&fat.rest, &fat.hexes);
        // An inner vertex pushed past the next one along x folds the elements about it.
        let v = 1 + 5 * (1 + 4);
        fat.x[v].x += 0.015;
        assert!(folded(&fat) > 0);
        // The grid's bottom face is held.
        for (f, p) in fat.free.iter_mut().zip(fat.rest.iter()) {
            *f = p.z > 0.0;
        }
        let held = |fat: &FatSolver| -> Vec<Vec3> {
            fat.x
                .iter()
                .zip(&fat.free)
                .filter(|(_, f)| !**f)
                .map(|(p, _)| *p)
                .collect()
        };
        let before = held(&fat);
        let mut b = VolumeBuffers::default();
        c.unfold(&mut fat, &mut b, 0.2, 60);
        assert_eq!(folded(&fat), 0);
        assert_eq!(held(&fat), before);
    }

    #[test]
    fn a_vertex_pushed_through_its_neighbours_is_untangled_and_held_vertices_stay() {
        let mut fat = FatSolver::grid(4, 3, 3, 0.01);
        let c = FatVolume::new(&fat.rest, &fat.hexes);
        let v = 1 + 5 * (1 + 4);
        fat.x[v] += Vec3::new(0.015, 0.004, -0.003);
        assert!(folded(&fat) > 0);
        for (f, p) in fat.free.iter_mut().zip(fat.rest.iter()) {
            *f = p.z > 0.0;
        }
        let held: Vec<Vec3> = (0..fat.x.len())
            .filter(|&u| !fat.free[u])
            .map(|u| fat.x[u])
            .collect();
        let mut b = VolumeBuffers::default();
        // Alone, without the element-by-element unfolding first: it stops once nothing is
        // folded, the barrier having kept every corner well clear of zero.
        let all: Vec<u32> = (0..fat.x.len() as u32).collect();
        c.elements_about(&mut b, &all);
        c.untangle(&mut fat, &mut b, 60);
        assert_eq!(folded(&fat), 0);
        for h in fat.hexes.iter() {
            let (j, r) = (corner_jacobians(&fat.x, h), corner_jacobians(&fat.rest, h));
            assert!(j.iter().zip(&r).all(|(j, r)| *j >= 0.1 * r), "{j:?}");
        }
        let now: Vec<Vec3> = (0..fat.x.len())
            .filter(|&u| !fat.free[u])
            .map(|u| fat.x[u])
            .collect();
        assert_eq!(now, held);
    }

    #[test]
    fn squashed_elements_get_their_volume_back() {
        let mut fat = FatSolver::grid(3, 3, 3, 0.01);
        let c = FatVolume::new(&fat.rest, &fat.hexes);
        for p in &mut fat.x {
            p.z *= 0.6;
        }
        let mut b = VolumeBuffers::default();
        for _ in 0..30 {
            c.hold(&mut fat, &mut b, 1.0, 0.2);
        }
        for (e, h) in fat.hexes.iter().enumerate() {
            let ratio = hex_volume_f32(&fat.x, h) / fat.rest_volume[e] as f32;
            assert!(
                (ratio - 1.0).abs() < 2.0 * VOLUME_SLACK,
                "element {e} at {ratio} of its rest volume"
            );
        }
    }

    #[test]
    fn the_projections_give_the_same_bits_on_one_thread_as_on_several() {
        let run = || {
            let mut fat = FatSolver::grid(12, 8, 8, 0.01);
            let c = FatVolume::new(&fat.rest, &fat.hexes);
            for (i, p) in fat.x.iter_mut().enumerate() {
                let s = (i as f32 * 0.37).sin();
                *p += Vec3::new(s, s * 0.5, -s) * 0.006;
            }
            let mut b = VolumeBuffers::default();
            c.hold(&mut fat, &mut b, 1.0, 0.2);
            c.unfold(&mut fat, &mut b, 0.2, 10);
            c.untangle(&mut fat, &mut b, 10);
            fat.x
        };
        let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build();
        let (Ok(one), Ok(three)) = (pool(1), pool(3)) else {
            panic!("no thread pool");
        };
        assert_eq!(one.install(run), three.install(run));
    }
}
