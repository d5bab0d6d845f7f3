//! Muscle surfaces kept out of bone. A cross-section ring that a bone reaches into is
//! shifted out whole, across its muscle until clear of the bone (a ring the bone reaches
//! into from opposite sides only as far as evens the two out), rather than squashed:
//! a shifted ring keeps its area, so the muscle keeps its volume (squashing the vertices
//! onto the bone took up to 61 % of a small muscle pressed between two bones). The shift
//! stays with the ring from update to update and fades once the bone has gone.

use glam::{Quat, Vec3};
use parry3d::bounding_volume::BoundingVolume;
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TriMesh;

use super::bone_slide::BoneMesh;
use crate::body::BodyId;
use crate::lattice::winding_number;
use crate::muscle::BodyFrames;

/// Muscle vertices closer than this (m) to a bone at rest are watched against it...
const NEAR_M: f32 = 0.02;
/// ...and within [`KNEE_M`] of the knee, where the bones turn past each other, this.
const NEAR_KNEE_M: f32 = 0.06;
/// Distance (m) from the knee point within which [`NEAR_KNEE_M`] holds.
const KNEE_M: f32 = 0.12;
/// Beyond this distance (m) from the bone a vertex's clear ball is renewed from the tree.
const TREE_REFRESH_M: f32 = 0.004;
/// How far (m) beyond the bone surface a pushed ring ends up.
const MARGIN_M: f32 = 0.001;
/// Share of a ring's shift given to its neighbours 1, 2, 3... rings away (the surface
/// bends over several rings rather than stepping: a step creased the skin over it).
const SPREAD: [f32; 3] = [0.75, 0.5, 0.25];
/// Most rounds of shifting rings out of bone per update.
const PUSH_ROUNDS: usize = 8;
/// Share of a ring's shift kept over a thirtieth of a second (one update at the default
/// rate).
const FADE: f32 = 0.9;

/// The bones a tissue update sees: surfaces with adjacency, the same as parry meshes (for
/// the rare global query) and the bodies' poses.
#[derive(Clone, Copy)]
pub(crate) struct Bones<'a> {
    pub(crate) meshes: &'a [BoneMesh],
    pub(crate) surfaces: &'a [(BodyId, TriMesh)],
    pub(crate) frames: &'a BodyFrames,
    /// Share of a ring's shift kept into this update (see [`fade_per_update`]).
    pub(crate) fade: f32,
}

/// Share of a ring's shift kept from one update to the next at `rate_hz` updates a second:
/// [`FADE`] per thirtieth of a second whatever the rate.
pub(crate) fn fade_per_update(rate_hz: f64) -> f32 {
    FADE.powf((30.0 / rate_hz.max(1e-3)) as f32)
}

impl Bones<'_> {
    fn pose(&self, body: BodyId) -> (Quat, Vec3) {
        match body {
            BodyId::Thigh => self.frames.thigh,
            BodyId::Shank => self.frames.shank,
        }
    }

    /// How far `p` (world) lies inside bone `b`, as the world vector that takes it to the
    /// surface; None when outside. `w` is what the pair knew at its last check.
    fn depth(&self, b: usize, p: Vec3, w: &mut Watch) -> Option<Vec3> {
        let mesh = &self.meshes[b];
        let (q, t) = self.pose(mesh.body());
        let p_rest = q.inverse() * (p - t);
        // Still within the ball that was clear of the bone at the last check: outside.
        if p_rest.distance_squared(w.from) < w.clear * w.clear {
            return None;
        }
        let walk = mesh.walk_checked(w.nearest, p_rest, &self.surfaces[b].1);
        w.nearest = walk.triangle;
        if walk.inside {
            w.clear = 0.0;
            return Some(q * (walk.point - p_rest));
        }
        // The walk's nearest point may be only local, so it cannot vouch for a ball. Close
        // to the bone the ball known before shrinks by how far the vertex has gone (a
        // walk an update costs little there); further out the tree, searched no further
        // than the walk's distance, gives a ball that lasts many updates.
        let d = walk.point.distance(p_rest);
        let shrunk = (w.clear - p_rest.distance(w.from)).max(0.0);
        w.clear = shrunk;
        if d > TREE_REFRESH_M {
            match self.surfaces[b]
                .1
                .project_local_point_and_get_location_with_max_dist(p_rest, false, d)
            {
                Some((proj, (tri, _))) => {
                    let exact = mesh.walk(tri, p_rest);
                    w.nearest = exact.triangle;
                    if exact.inside {
                        w.clear = 0.0;
                        return Some(q * (exact.point - p_rest));
                    }
                    w.clear = exact
                        .point
                        .distance(p_rest)
                        .min(proj.point.distance(p_rest));
                }
                // Nothing nearer than the walk's point: it is the nearest.
                None => w.clear = d,
            }
        }
        w.from = p_rest;
        None
    }
}

/// What a watched pair knew at its last check.
#[derive(Debug, Clone, Copy)]
struct Watch {
    /// The triangle the vertex was nearest (where the next walk starts).
    nearest: u32,
    /// Where the vertex was (bone rest frame)...
    from: Vec3,
    /// ...and how far from the bone (m): until it has moved that far it cannot be in.
    clear: f32,
}

/// Which muscle vertices are watched against which bone, and each ring's shift.
#[derive(Debug, Clone, Default)]
pub(crate) struct BoneKeepOut {
    /// (muscle vertex, bone index) pairs near enough at rest to meet.
    pairs: Vec<(u32, u32)>,
    /// What each pair knew at its last check.
    watch: Vec<Watch>,
    /// Shift of each ring (world, m).
    pub(crate) shift: Vec<Vec3>,
    /// Work buffers: the shift each ring needs this update, and that spread to its
    /// neighbours (what the last [`Self::push_out`] moved each ring by: zero when it
    /// moved nothing).
    need: Vec<Vec3>,
    pub(crate) spread: Vec<Vec3>,
    /// Work buffers: every push of the round (ring, push), and per ring the largest push
    /// against its largest (see [`Self::push_out`]).
    pushes: Vec<(u32, Vec3)>,
    against: Vec<f32>,
    /// What [`Self::clear_rings`] moved each ring by.
    moved: Vec<Vec3>,
}

/// What a [`BoneKeepOut`] carries from one update to the next: the rings' shifts and what
/// each watched pair knew (a walk starts where the last one ended and may stop at a local
/// nearest point, so a failed update must give this back too for the run to replay).
#[derive(Debug, Clone)]
pub(crate) struct KeepOutMemory {
    shift: Vec<Vec3>,
    watch: Vec<Watch>,
}

impl BoneKeepOut {
    /// What the next update starts from.
    pub(crate) fn memory(&self) -> KeepOutMemory {
        KeepOutMemory {
            shift: self.shift.clone(),
            watch: self.watch.clone(),
        }
    }

    /// Puts back what [`Self::memory`] took.
    pub(crate) fn recall(&mut self, m: KeepOutMemory) {
        (self.shift, self.watch) = (m.shift, m.watch);
    }

    /// Pairs every vertex of `rest` with each bone within [`NEAR_M`] of it
    /// ([`NEAR_KNEE_M`] near the knee point `knee`). A vertex already inside a bone at
    /// rest (where the slices let muscle and bone overlap) is left alone: no shift of a
    /// ring wrapped round a bone frees it.
    pub(crate) fn new(
        rest: &[Vec3],
        rings: usize,
        bones: &[(BodyId, TriMesh)],
        meshes: &[BoneMesh],
        knee: Vec3,
    ) -> Self {
        let mut pairs = Vec::new();
        let mut watch = Vec::new();
        for (b, (_, mesh)) in bones.iter().enumerate() {
            let (aabb, aabb_knee) = (
                mesh.local_aabb().loosened(NEAR_M),
                mesh.local_aabb().loosened(NEAR_KNEE_M),
            );
            for (v, &p) in rest.iter().enumerate() {
                let (near, bounds) = if p.distance(knee) < KNEE_M {
                    (NEAR_KNEE_M, &aabb_knee)
                } else {
                    (NEAR_M, &aabb)
                };
                if !bounds.contains_local_point(p) {
                    continue;
                }
                // The tree search gives up beyond `near`: most vertices are far.
                let Some((proj, (tri, _))) =
                    mesh.project_local_point_and_get_location_with_max_dist(p, false, near)
                else {
                    continue;
                };
                let clear = proj.point.distance(p);
                if clear < near && !meshes[b].walk(tri, p).inside {
                    pairs.push((v as u32, b as u32));
                    watch.push(Watch {
                        nearest: tri,
                        from: p,
                        clear,
                    });
                }
            }
        }
        Self {
            pairs,
            watch,
            shift: vec![Vec3::ZERO; rings],
            need: vec![Vec3::ZERO; rings],
            spread: vec![Vec3::ZERO; rings],
            pushes: Vec::new(),
            against: vec![0.0; rings],
            moved: vec![Vec3::ZERO; rings],
        }
    }

    /// Lets the shifts fade by `keep` (a bone that has left no longer holds the rings off).
    pub(crate) fn fade(&mut self, keep: f32) {
        self.shift.iter_mut().for_each(|s| *s *= keep);
    }

    /// Forgets every shift (the shape is back at rest on one body).
    pub(crate) fn clear(&mut self) {
        self.shift.iter_mut().for_each(|s| *s = Vec3::ZERO);
    }

    /// Shifts the rings out of the bones in up to [`PUSH_ROUNDS`] rounds of
    /// [`Self::push_out`] (a shift can move a ring's other vertices in) and returns how far
    /// each ring moved in all.
    pub(crate) fn clear_rings(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
    ) -> &[Vec3] {
        self.moved.clear();
        self.moved.resize(self.shift.len(), Vec3::ZERO);
        let mut last = usize::MAX;
        for round in 0..PUSH_ROUNDS {
            let Some(deep) = self.push_out(current, ring_of, &axis, bones, round > 0) else {
                break;
            };
            for (m, s) in self.moved.iter_mut().zip(&self.spread) {
                *m += *s;
            }
            // A round that finds no fewer vertices over 1 mm deep than the last is the
            // last: rings pushing each other back in (as one wrapped round a bone does)
            // would use every round for nothing.
            if deep >= last {
                break;
            }
            last = deep;
        }
        &self.moved
    }

    /// Finds the rings a bone reaches into, shifts them out (a neighbour as far as the
    /// largest of [`SPREAD`]'s shares of the rings near it, so the surface bends rather
    /// than steps) and moves their vertices in `current` with them. Returns how many of
    /// the vertices found in bone were more than 1 mm deep, None when none was in bone.
    ///
    /// A ring moves across its muscle only (`axis` gives each ring's direction): moved
    /// along, it would slide into its neighbours and crease the surface.
    ///
    /// `again` says the last call was this update's previous round: then only the
    /// vertices that call moved are looked at (the others would be found as they were).
    fn push_out(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
        again: bool,
    ) -> Option<usize> {
        self.need.iter_mut().for_each(|n| *n = Vec3::ZERO);
        self.pushes.clear();
        let mut deep: Option<usize> = None;
        for (&(v, b), w) in self.pairs.iter().zip(&mut self.watch) {
            if again && self.spread[ring_of[v as usize] as usize] == Vec3::ZERO {
                continue;
            }
            let Some(d) = bones.depth(b as usize, current[v as usize], w) else {
                continue;
            };
            let r = ring_of[v as usize] as usize;
            let push = d + d.normalize_or_zero() * MARGIN_M;
            // Across the ring, as far as clears the bone along its normal (at most twice
            // the depth where the normal runs nearly along the muscle).
            let a = axis(r);
            let across = push - a * push.dot(a);
            let clears = across.dot(push);
            let push = if clears > 0.25 * push.length_squared() {
                across * (push.length_squared() / clears)
            } else {
                across.normalize_or_zero() * (2.0 * push.length())
            };
            if push == Vec3::ZERO {
                continue; // the bone's normal runs along the muscle: nothing across
            }
            self.pushes.push((r as u32, push));
            let need = &mut self.need[r];
            if push.length_squared() > need.length_squared() {
                *need = push;
            }
            deep = Some(deep.unwrap_or(0) + usize::from(d.length_squared() > 1e-6));
        }
        if deep.is_none() {
            // Nothing moved: a call `again` after this one must find every ring still.
            self.spread.iter_mut().for_each(|s| *s = Vec3::ZERO);
            return None;
        }
        // A ring that bone reaches into from opposite sides straddles it: no shift clears
        // it, and shifting it by its largest push ran away update after update (7 cm for
        // the phantom's vastus medialis by the femur, out through the skin). It moves half
        // the difference between its largest push and the largest against it, which
        // evens the two depths out (the whole difference would swap them).
        self.against.iter_mut().for_each(|a| *a = 0.0);
        for &(r, push) in &self.pushes {
            let r = r as usize;
            let against = -push.dot(self.need[r].normalize_or_zero());
            self.against[r] = self.against[r].max(against);
        }
        for (n, &a) in self.need.iter_mut().zip(&self.against) {
            if a > 0.0 {
                let len = n.length();
                *n *= (0.5 * (len - a) / len).max(0.0);
            }
        }
        let rings = self.need.len();
        for r in 0..rings {
            let mut total = self.need[r];
            for (k, w) in SPREAD.iter().enumerate() {
                for nb in [r.wrapping_sub(k + 1), r + k + 1] {
                    if let Some(&m) = self.need.get(nb) {
                        let part = m * *w;
                        if part.length_squared() > total.length_squared() {
                            total = part;
                        }
                    }
                }
            }
            self.spread[r] = total;
            self.shift[r] += total;
        }
        for (p, &r) in current.iter_mut().zip(ring_of) {
            *p += self.spread[r as usize];
        }
        deep
    }
}

/// How far muscle surfaces reach into bone (see [`super::Tissue::muscles_in_bone`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BoneOverlap {
    /// Muscle vertices more than 1 mm inside a bone.
    pub vertices_over_1mm: usize,
    /// Deepest muscle vertex inside a bone (m), 0 when none is.
    pub deepest_m: f32,
}

/// Measures `vertices` against every bone (a tree query per vertex near a bone; exact
/// for a surface that does not cross itself). `crossed[b]` says bone `b`'s surface
/// crosses itself (tubes of one bone overlapping, or a tube folding): there the
/// pseudo-normal can call a point outside inside, so the winding number confirms it;
/// it can still miss a point inside one tube whose nearest surface is another tube's
/// wall running inside it, and measures depth to that wall (a lower bound).
pub(crate) fn overlap(vertices: &[Vec3], bones: &Bones, crossed: &[bool]) -> BoneOverlap {
    let mut o = BoneOverlap::default();
    for (b, (body, mesh)) in bones.surfaces.iter().enumerate() {
        let (q, t) = bones.pose(*body);
        let aabb = mesh.local_aabb();
        for &p in vertices {
            let p_rest = q.inverse() * (p - t);
            if !aabb.contains_local_point(p_rest) {
                continue;
            }
            let w = bones.meshes[b].walk_from_tree(mesh, p_rest);
            let d = w.point.distance(p_rest);
            // Only what would change the result is confirmed (a winding number visits
            // every triangle).
            if !w.inside || (d <= 1e-3 && d <= o.deepest_m) {
                continue;
            }
            if crossed[b] && winding_number(mesh.vertices(), mesh.indices(), p_rest).abs() < 0.5 {
                continue;
            }
            o.deepest_m = o.deepest_m.max(d);
            o.vertices_over_1mm += usize::from(d > 1e-3);
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box bone `lo..hi` (m), outward triangles.
    fn box_bone(lo: Vec3, hi: Vec3) -> (BodyId, TriMesh) {
        let v: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t: Vec<[u32; 3]> = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let mesh = TriMesh::new(v, t).unwrap_or_else(|e| panic!("{e}"));
        (BodyId::Thigh, mesh)
    }

    /// Rings of 32 vertices round the z axis, `RINGS` of them 2 mm apart from z = 0, with
    /// semi-axes `a` (x) and `b` (y), shifted along z by `dz`.
    const RINGS: usize = 5;
    fn rings(a: f32, b: f32, dz: f32) -> (Vec<Vec3>, Vec<u32>) {
        let mut p = Vec::new();
        let mut ring_of = Vec::new();
        for r in 0..RINGS {
            for k in 0..32 {
                let t = k as f32 / 32.0 * std::f32::consts::TAU;
                p.push(Vec3::new(a * t.cos(), b * t.sin(), dz + 0.002 * r as f32));
                ring_of.push(r as u32);
            }
        }
        (p, ring_of)
    }

    /// Runs `updates` updates as a muscle shape does: the rings placed at `base` plus
    /// their faded shifts, then pushed out round after round. Returns the largest shift.
    fn run(
        keep: &mut BoneKeepOut,
        base: &[Vec3],
        ring_of: &[u32],
        bones: &Bones,
        updates: usize,
    ) -> f32 {
        for _ in 0..updates {
            keep.fade(bones.fade);
            let mut current: Vec<Vec3> = base
                .iter()
                .zip(ring_of)
                .map(|(p, &r)| *p + keep.shift[r as usize])
                .collect();
            keep.clear_rings(&mut current, ring_of, |_| Vec3::Z, bones);
        }
        keep.shift.iter().map(|s| s.length()).fold(0.0, f32::max)
    }

    #[test]
    fn a_ring_a_bone_reaches_into_from_opposite_sides_is_not_pushed_away() {
        // A bone 20 mm wide from z = 5 mm on, clear of the rings at rest (their inradius,
        // 14.9 mm, is more than its half-diagonal); the rings then move 12 mm along and
        // flatten to a semi-axis of 8 mm in y, so the bone reaches 2 mm into each ring
        // from both sides in y at once (and about as far in x).
        let bones = [box_bone(
            Vec3::new(-0.01, -0.01, 0.005),
            Vec3::new(0.01, 0.01, 0.05),
        )];
        let meshes = [BoneMesh::new(bones[0].0, &bones[0].1)];
        let frames = BodyFrames::REST;
        let b = Bones {
            meshes: &meshes,
            surfaces: &bones,
            frames: &frames,
            fade: fade_per_update(30.0),
        };
        let (rest, ring_of) = rings(0.015, 0.015, 0.0);
        let mut keep = BoneKeepOut::new(&rest, RINGS, &bones, &meshes, Vec3::splat(10.0));
        assert!(!keep.pairs.is_empty(), "no vertex watched");
        let (flat, _) = rings(0.015, 0.008, 0.012);
        let far = run(&mut keep, &flat, &ring_of, &b, 30);
        assert!(far < 1e-4, "a straddling ring moved {:.1} mm", far * 1e3);
        // Reached from one side only (the flat rings 15 mm up in y, their lowest vertices
        // 3 mm into the bone), they are pushed clear on that side.
        let one_sided: Vec<Vec3> = flat
            .iter()
            .map(|p| *p + Vec3::new(0.0, 0.015, 0.0))
            .collect();
        let mut keep = BoneKeepOut::new(&rest, RINGS, &bones, &meshes, Vec3::splat(10.0));
        let moved = run(&mut keep, &one_sided, &ring_of, &b, 1);
        assert!(
            moved > 0.003,
            "a ring reached from one side moved {:.1} mm",
            moved * 1e3
        );
        for r in 0..RINGS {
            assert!(keep.shift[r].y > 0.0, "ring {r}: {:?}", keep.shift[r]);
        }
    }
}
