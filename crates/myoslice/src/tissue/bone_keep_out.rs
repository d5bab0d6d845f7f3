//! Muscle surfaces kept out of bone. A cross-section ring that a bone reaches into is
//! shifted out whole, across its muscle until clear of the bone (a ring the bone reaches
//! into from opposite sides only as far as evens the two out), rather than squashed:
//! a shifted ring keeps its area, so the muscle keeps its volume (squashing the vertices
//! onto the bone took up to 61 % of a small muscle pressed between two bones). The shift
//! stays with the ring from update to update and fades once the bone has gone.
//!
//! Behind the knee the same shifts keep each muscle's rings on their own side of the
//! contact plane (thigh or calf, as each vertex lay at rest), where the calf's muscles
//! would otherwise rise with the shank past the plane that holds the fat apart and come
//! out through the skin of the crease; a bone wins over the plane.

use std::sync::Arc;

use glam::{Quat, Vec3};
use parry3d::bounding_volume::BoundingVolume;
use parry3d::shape::TriMesh;

use super::knee_fold::Contact;
use super::skin_cover::SkinCover;
use crate::body::BodyId;
use crate::muscle::BodyFrames;

/// Muscle vertices closer than this (m) to a bone at rest are watched against it...
const NEAR_M: f32 = 0.02;
/// ...and within [`KNEE_M`] of the knee, where the bones turn past each other, this.
const NEAR_KNEE_M: f32 = 0.06;
/// Distance (m) from the knee point within which [`NEAR_KNEE_M`] holds.
const KNEE_M: f32 = 0.12;
/// Distance (m) from the knee point at rest within which vertices are kept on their side
/// of the contact plane (measured from the point, not the axis: it reaches less far from
/// the axis at the sides of the knee). At 12 cm the gastrocnemii's bellies, 12–19 cm
/// below the knee, came up to 36 mm past the plane at 134° and out through the skin; 25
/// and 30 cm give the same bits as 20.
const PLANE_REACH_M: f32 = 0.20;
/// How far (m) in front of the knee axis at rest a vertex may lie and still be kept on
/// its side of the contact plane.
const PLANE_FRONT_M: f32 = 0.01;
/// How far (m) beyond the bone surface a pushed ring ends up.
const MARGIN_M: f32 = 0.001;
/// Share of a ring's shift given to its neighbours 1, 2, 3... rings away (the surface
/// bends over several rings rather than stepping: a step creased the skin over it).
const SPREAD: [f32; 3] = [0.75, 0.5, 0.25];
/// Most rounds of shifting rings out of bone per update (8 left the phantom's long
/// biceps femoris 8.4 mm in bone at 132°, against 5.7 mm; most updates stop far sooner).
const PUSH_ROUNDS: usize = 16;
/// Share of a ring's shift kept over a thirtieth of a second (one update at the default
/// rate).
const FADE: f32 = 0.9;
/// How far (m) a ring's vertex may reach into a bone or past its place by the contact
/// plane, placed without the ring's shift, for the shift to go (the rounds push it out of
/// what is left): placements are not exact to the bit, and a plane that asked a
/// micrometre held the plantaris's rings 11 mm off rest for good.
const RELEASE_TOLERANCE_M: f32 = 0.0005;
/// Most the contact plane asks of a vertex (m) in one round (its ring moves across the
/// muscle up to twice that): asked as far as it wanted at once, at deep flexion the
/// rings were driven up to 19 mm into bone.
const PLANE_STEP_M: f32 = 0.002;

/// The bones a tissue update sees: their distance fields and surfaces (rest frames) and
/// the bodies' poses.
#[derive(Clone, Copy)]
pub(crate) struct Bones<'a> {
    /// Each bone's distance field (rest frame), for exact measures.
    pub(crate) sdfs: &'a [crate::geometry::BoneSdf],
    /// Each bone's body and surface as a parry mesh (its tree answers what lies deeper
    /// than the field is exact).
    pub(crate) surfaces: &'a [(BodyId, TriMesh)],
    pub(crate) frames: &'a BodyFrames,
    /// Share of a ring's shift kept into this update (see [`fade_per_update`]).
    pub(crate) fade: f32,
    /// The contact plane behind the knee (world), which muscles keep their side of.
    pub(crate) contact: Option<Contact>,
    /// How near the plane the skin over it lies, which muscles keep under.
    pub(crate) cover: Option<&'a SkinCover>,
}

/// Share of a ring's shift kept from one update to the next at `rate_hz` updates a second:
/// [`FADE`] per thirtieth of a second whatever the rate.
pub(crate) fn fade_per_update(rate_hz: f64) -> f32 {
    FADE.powf((30.0 / rate_hz.max(1e-3)) as f32)
}

impl Bones<'_> {
    pub(crate) fn pose(&self, body: BodyId) -> (Quat, Vec3) {
        self.frames.pose(body)
    }

    /// `p` (world) in the rest frame of bone `b`.
    pub(crate) fn rest_point(&self, b: usize, p: Vec3) -> Vec3 {
        let (q, t) = self.pose(self.surfaces[b].0);
        q.inverse() * (p - t)
    }

    /// How far `p` (world) lies inside bone `b`, as the world vector that takes it to the
    /// surface; None when outside. Exact at any depth, from the bone's distance field
    /// (one lookup for most points) and its tree. `ball` (rest frame) is known to lie
    /// outside the bone: a point in it needs no lookup, and the check leaves there the
    /// ball it finds clear about `p`.
    fn depth(&self, b: usize, p: Vec3, ball: &mut (Vec3, f32)) -> Option<Vec3> {
        let (body, tree) = &self.surfaces[b];
        let q = self.pose(*body).0;
        let p_rest = self.rest_point(b, p);
        if p_rest.distance_squared(ball.0) < ball.1 * ball.1 {
            return None;
        }
        let sdf = &self.sdfs[b];
        // Off the field's grid is further than its band from the bone.
        let clear = sdf.clearance(p_rest).unwrap_or(sdf.band());
        if clear > 0.0 {
            *ball = (p_rest, clear);
            return None;
        }
        let s = sdf.nearest(tree, p_rest, f32::INFINITY)?;
        *ball = (p_rest, s.distance.max(0.0));
        (s.distance < 0.0).then(|| q * (s.point - p_rest))
    }

    /// Whether `p` (world) lies more than `depth` (m) inside bone `b` by the distance
    /// interpolated in its field (one lookup; see [`crate::geometry::BoneSdf::interpolated`]),
    /// or not at all if it lies in `ball` (see [`Self::depth`]).
    fn deeper_than(&self, b: usize, p: Vec3, depth: f32, ball: (Vec3, f32)) -> bool {
        let p_rest = self.rest_point(b, p);
        p_rest.distance_squared(ball.0) >= ball.1 * ball.1
            && self.sdfs[b]
                .interpolated(p_rest)
                .is_some_and(|d| d < -depth)
    }
}

/// Which muscle vertices are watched against which bone and against the contact plane,
/// and each ring's shift.
#[derive(Debug, Clone, Default)]
pub(crate) struct BoneKeepOut {
    /// (muscle vertex, bone index, how far the vertex lay from the bone at rest, m)
    /// for pairs near enough at rest to meet (fixed: shared by copies).
    pairs: Arc<[(u32, u32, f32)]>,
    /// Vertices near the knee kept on their side of the contact plane: (vertex, how far
    /// on its side it was at rest (m, negative past it), whether the side is the
    /// thigh's). None need keep further from the plane than at rest, unless the skin over
    /// it is further ([`Bones::cover`]). Fixed: shared by copies.
    plane: Arc<[(u32, f32, bool)]>,
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
    /// Work buffer: the last shift bones alone asked of each ring this update (zero if
    /// none; the contact plane may not push against it).
    bone_push: Vec<Vec3>,
    /// Per pair, a ball in the bone's rest frame (centre, radius) that lay outside the
    /// bone at the last check (by the distance field's bound, or the exact distance): a
    /// vertex still in it is taken as outside with no lookup. Part of the state: it
    /// spares most lookups (without it, placing the muscles took half as long again),
    /// and where the field's sign and the nearest triangle's disagree near the surface
    /// an empty one can decide differently.
    balls: Vec<(Vec3, f32)>,
    /// Checks [`Self::clear_carried_rings`] skipped (tests only).
    #[cfg(test)]
    skipped: usize,
}

impl BoneKeepOut {
    /// Pairs every vertex of `rest` with each bone within [`NEAR_M`] of it
    /// ([`NEAR_KNEE_M`] near the knee point, the point of `rest_contact`). A vertex
    /// already inside a bone at rest (where the slices let muscle and bone overlap) is
    /// left alone: no shift of a ring wrapped round a bone frees it. Lists the vertices
    /// kept on their side of the contact plane, with how far from `rest_contact` (the
    /// plane at rest, rest frame; its margin is not used) each lay.
    pub(crate) fn new(
        rest: &[Vec3],
        rings: usize,
        bones: &[(BodyId, TriMesh)],
        sdfs: &[crate::geometry::BoneSdf],
        rest_contact: &Contact,
    ) -> Self {
        let knee = rest_contact.point;
        let plane = rest
            .iter()
            .enumerate()
            // Only what lies behind the knee or near the axis at rest can come past the
            // plane: in front, the plane turns away as the knee bends.
            .filter(|(_, p)| {
                p.distance(knee) < PLANE_REACH_M
                    && rest_contact.locate(**p, true).0 > -PLANE_FRONT_M
            })
            .map(|(v, &p)| {
                let thigh = p.z >= knee.z;
                (v as u32, rest_contact.locate(p, thigh).1, thigh)
            })
            .collect();
        let mut pairs = Vec::new();
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
                // Most vertices are far: the field says so in one lookup.
                if let Some(s) = sdfs[b].nearest(mesh, p, near)
                    && s.distance > 0.0
                    && s.distance < near
                {
                    pairs.push((v as u32, b as u32, s.distance));
                }
            }
        }
        Self {
            balls: vec![(Vec3::ZERO, 0.0); pairs.len()],
            pairs: pairs.into(),
            plane,
            shift: vec![Vec3::ZERO; rings],
            need: vec![Vec3::ZERO; rings],
            spread: vec![Vec3::ZERO; rings],
            pushes: Vec::new(),
            against: vec![0.0; rings],
            moved: vec![Vec3::ZERO; rings],
            bone_push: vec![Vec3::ZERO; rings],
            #[cfg(test)]
            skipped: 0,
        }
    }

    /// Lets the shifts fade by `keep` (a bone that has left no longer holds the rings off).
    pub(crate) fn fade(&mut self, keep: f32) {
        for s in &mut self.shift {
            *s *= keep;
            // Below a tenth of a micrometre a shift is gone: multiplied on, it would stay
            // a few subnormal units for half a minute, and its ring count as shifted.
            if s.length_squared() < 1e-14 {
                *s = Vec3::ZERO;
            }
        }
    }

    /// Whether any vertex is kept on its side of the contact plane.
    pub(crate) fn near_plane(&self) -> bool {
        !self.plane.is_empty()
    }

    /// Forgets every shift (the shape is carried at rest on one body, away from the
    /// contact plane).
    pub(crate) fn clear(&mut self) {
        self.shift.iter_mut().for_each(|s| *s = Vec3::ZERO);
    }

    /// Shifts the rings out of the bones and back toward their side of the contact plane
    /// in up to [`PUSH_ROUNDS`] rounds of [`Self::push_out`] (a shift can move a ring's
    /// other vertices in) and returns how far each ring moved in all.
    pub(crate) fn clear_rings(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
    ) -> &[Vec3] {
        self.clear_rings_of(current, ring_of, axis, bones, None)
    }

    /// [`Self::clear_rings`] for a shape carried rigidly by `body`: the caller has placed
    /// every ring where `body` carries its rest place, plus (across the ring) its shift.
    /// A ring without a shift then sits on that body's bones where it sat at rest, clear
    /// of them (pairs are only formed for vertices clear at rest), so only the other
    /// body's bones, the contact plane and the shifted rings are looked at.
    pub(crate) fn clear_carried_rings(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
        body: BodyId,
    ) -> &[Vec3] {
        self.clear_rings_of(current, ring_of, axis, bones, Some(body))
    }

    fn clear_rings_of(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
        carried: Option<BodyId>,
    ) -> &[Vec3] {
        self.moved.clear();
        self.moved.resize(self.shift.len(), Vec3::ZERO);
        self.bone_push.iter_mut().for_each(|b| *b = Vec3::ZERO);
        self.release(current, ring_of, &axis, bones);
        let mut last = f32::INFINITY;
        for round in 0..PUSH_ROUNDS {
            let again = round > 0;
            let Some(deep) = self.push_out(current, ring_of, &axis, bones, again, carried) else {
                break;
            };
            for (m, s) in self.moved.iter_mut().zip(&self.spread) {
                *m += *s;
            }
            // A round that finds its vertices over 1 mm deep no shallower in all than the
            // last is the last: rings pushing each other back in (as one wrapped round a
            // bone does) would use every round for nothing. (Counting those vertices
            // instead stopped rings that were still coming out: the phantom's sartorius
            // stayed 9.5 mm in bone on the way back from the flexion, against 6.2 mm.)
            if deep >= last {
                break;
            }
            last = deep;
        }
        &self.moved
    }

    /// Drops the shift of every shifted ring that would be clear without it, as would
    /// the rings near it that share their shifts ([`SPREAD`]): each of their watched
    /// vertices outside its bone and on its side of the contact plane, placed where the
    /// ring's chain puts it. A shift is kept only while something asks for it: fading
    /// alone, a ring that the bone had pushed over to its far side (the plantaris over
    /// the femur's condyle at deep flexion) was pushed back out there update after
    /// update and never came back to rest.
    fn release(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
    ) {
        let shift = &self.shift;
        if shift.iter().all(|s| *s == Vec3::ZERO) {
            return;
        }
        let across = |r: usize| {
            let (s, a) = (shift[r], axis(r));
            s - a * s.dot(a)
        };
        // `need` is free until the rounds: here, per ring, whether a shifted ring still
        // needs its shift (non-zero).
        let held = &mut self.need;
        held.iter_mut().for_each(|n| *n = Vec3::ZERO);
        for (&(v, b, _), &ball) in self.pairs.iter().zip(&self.balls) {
            let r = ring_of[v as usize] as usize;
            if shift[r] != Vec3::ZERO
                && held[r] == Vec3::ZERO
                && bones.deeper_than(
                    b as usize,
                    current[v as usize] - across(r),
                    RELEASE_TOLERANCE_M,
                    ball,
                )
            {
                held[r] = Vec3::ONE;
            }
        }
        if let Some(c) = &bones.contact {
            for &(v, rest_d, thigh) in self.plane.iter() {
                let r = ring_of[v as usize] as usize;
                if shift[r] != Vec3::ZERO && held[r] == Vec3::ZERO {
                    // As the rounds would: a push along the muscle is none.
                    let d = plane_push(
                        c,
                        bones.cover,
                        current[v as usize] - across(r),
                        rest_d,
                        thigh,
                    );
                    if d.length() > RELEASE_TOLERANCE_M
                        && ring_push((d, 0.0), axis(r), true).is_some()
                    {
                        held[r] = Vec3::ONE;
                    }
                }
            }
        }
        let rings = shift.len();
        let reach = SPREAD.len();
        for r in 0..rings {
            let near = r.saturating_sub(reach)..(r + reach + 1).min(rings);
            if shift[r] != Vec3::ZERO && held[near].iter().all(|h| *h == Vec3::ZERO) {
                self.moved[r] = -across(r);
            }
        }
        for (p, &r) in current.iter_mut().zip(ring_of) {
            *p += self.moved[r as usize];
        }
        for (s, m) in self.shift.iter_mut().zip(&self.moved) {
            if *m != Vec3::ZERO {
                *s = Vec3::ZERO;
            }
        }
    }

    /// Records in `pushes` and `need` the push of ring `r` ([`ring_push`]) for `d` and
    /// `margin`, if any, and adds the length of `d` to `deep` if over 1 mm.
    fn add_push(
        pushes: &mut Vec<(u32, Vec3)>,
        need: &mut [Vec3],
        r: usize,
        d_margin: (Vec3, f32),
        a: Vec3,
        deep: &mut Option<f32>,
        plane: bool,
    ) {
        let Some(push) = ring_push(d_margin, a, plane) else {
            return;
        };
        pushes.push((r as u32, push));
        let need = &mut need[r];
        if push.length_squared() > need.length_squared() {
            *need = push;
        }
        let depth = d_margin.0.length();
        *deep = Some(deep.unwrap_or(0.0) + if depth > 1e-3 { depth } else { 0.0 });
    }

    /// Finds the rings a bone reaches into or that lie nearer the contact plane than they
    /// keep (its margin, or the floor of the skin over them, [`Bones::cover`]), shifts
    /// them out (a neighbour as far as the largest of [`SPREAD`]'s shares of the rings
    /// near it, so the surface bends rather than steps) and moves their vertices in
    /// `current` with them. Returns how far (m) the vertices found more than 1 mm in
    /// bone or nearer the plane than they keep were in, summed (zero when none was that
    /// far), None when none was found at all.
    ///
    /// A ring moves across its muscle only (`axis` gives each ring's direction): moved
    /// along, it would slide into its neighbours and crease the surface.
    ///
    /// `again` says the last call was this update's previous round: then only the
    /// vertices that call moved are looked at (the others would be found as they were).
    /// `carried` names the body that carries the shape rigidly, if one does: then its
    /// bones are not looked at for rings without a shift (see
    /// [`Self::clear_carried_rings`]).
    fn push_out(
        &mut self,
        current: &mut [Vec3],
        ring_of: &[u32],
        axis: impl Fn(usize) -> Vec3,
        bones: &Bones,
        again: bool,
        carried: Option<BodyId>,
    ) -> Option<f32> {
        self.need.iter_mut().for_each(|n| *n = Vec3::ZERO);
        self.pushes.clear();
        let mut deep: Option<f32> = None;
        for (&(v, b, clear), ball) in self.pairs.iter().zip(&mut self.balls) {
            let r = ring_of[v as usize] as usize;
            if again && self.spread[r] == Vec3::ZERO {
                continue;
            }
            if carried == Some(bones.surfaces[b as usize].0) && self.shift[r] == Vec3::ZERO {
                #[cfg(test)]
                {
                    self.skipped += 1;
                }
                continue;
            }
            let Some(d) = bones.depth(b as usize, current[v as usize], ball) else {
                continue;
            };
            // Out to its rest distance from the bone, if that is less than the margin: a
            // vertex pushed further than it lay at rest moves its ring, wrapped round the
            // bone, into it on the other side, update after update.
            let (pushes, need) = (&mut self.pushes, &mut self.need);
            let margin = MARGIN_M.min(clear);
            Self::add_push(pushes, need, r, (d, margin), axis(r), &mut deep, false);
        }
        // Then the contact plane, which may not push a ring against the way a bone
        // pushed it this update (a bone wins).
        for (b, n) in self.bone_push.iter_mut().zip(&self.need) {
            if *n != Vec3::ZERO {
                *b = *n;
            }
        }
        if let Some(c) = &bones.contact {
            for &(v, rest_d, thigh) in self.plane.iter() {
                let r = ring_of[v as usize] as usize;
                if again && self.spread[r] == Vec3::ZERO {
                    continue;
                }
                let d = plane_push(c, bones.cover, current[v as usize], rest_d, thigh);
                if d != Vec3::ZERO && d.dot(self.bone_push[r]) >= 0.0 {
                    let (pushes, need) = (&mut self.pushes, &mut self.need);
                    // The plane's allowance already holds the muscles' margin from it.
                    Self::add_push(pushes, need, r, (d, 0.0), axis(r), &mut deep, true);
                }
            }
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

/// The shift of a ring (axis `a`) that takes one of its vertices `d` out of what it
/// reaches into, and `margin` (m) further: across the axis, as far as clears along `d`,
/// at most twice as far as `d`. None if the push runs along the muscle, or for the
/// contact plane (`plane`) within 30° of it.
fn ring_push((d, margin): (Vec3, f32), a: Vec3, plane: bool) -> Option<Vec3> {
    let push = d + d.normalize_or_zero() * margin;
    let across = push - a * push.dot(a);
    let clears = across.dot(push);
    let push = if clears > 0.25 * push.length_squared() {
        across * (push.length_squared() / clears)
    } else if plane {
        // Twice the push sideways would not clear the plane, only throw the ring aside
        // (as at small angles, the plane nearly across the muscle).
        return None;
    } else {
        across.normalize_or_zero() * (2.0 * push.length())
    };
    (push != Vec3::ZERO).then_some(push)
}

/// How far the contact plane `c` moves vertex `p` (at most [`PLANE_STEP_M`] a round),
/// which lay `rest_d` on its side of it at rest (`thigh`: the thigh's side), under the
/// skin `cover`.
fn plane_push(c: &Contact, cover: Option<&SkinCover>, p: Vec3, rest_d: f32, thigh: bool) -> Vec3 {
    let mut margin = c.muscle_margin.min(rest_d);
    if let Some(cover) = cover {
        margin = margin.max(cover.floor(p, thigh));
    }
    (c.apply(p, thigh, margin) - p).clamp_length_max(PLANE_STEP_M)
}

#[cfg(test)]
#[path = "bone_keep_out_tests.rs"]
mod tests;
