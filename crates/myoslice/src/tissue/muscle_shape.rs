//! Muscle shape at constant volume (paper, section 4.1, Fig. 7): every cross-section ring
//! rides on its muscle's chain at a fixed place, turns with the chain, and is scaled by
//! `sqrt(L0/L)` across and `L/L0` along when its chain segment goes from `L0` to `L`, so
//! the local volume (and the muscle's) is kept.

use glam::{Mat3, Quat, Vec3, Vec3A};

use std::sync::Arc;

use super::bone_keep_out::{BoneKeepOut, Bones};
use super::knee_fold::{Contact, KneeFold};
use super::muscle_contact::{RingOutline, RingPose};
use crate::body::BodyId;
use crate::geometry::closest_on_polyline;
use crate::lattice::{MuscleLattice, signed_volume};
use crate::muscle::MuscleChain;

/// Most placement passes per update: each after the first corrects the cross-sections by
/// the volume the previous one missed. Most updates need two; a small muscle whose rings
/// were shifted far out of bone (plantaris by the condyle) needed more than five.
pub(super) const VOLUME_PASSES: usize = 12;

/// How many rings either way [`MuscleShape::surface_under`] looks, within the ring's
/// tube (5 mm slices: 6 cm).
const MERIDIAN_RINGS: usize = 12;

/// Where a ring rides on the chain and how its vertices sit around it. A copy shares
/// what never changes (rest shape, triangles, ring layout) and owns what an update
/// changes (current vertices, ring poses, keep-out memory).
#[derive(Debug, Clone)]
pub struct MuscleShape {
    /// Chain positions at rest.
    rest_chain: Arc<[Vec3]>,
    /// Whether each chain segment is belly (not tendon).
    belly: Arc<[bool]>,
    /// Segment and fraction along it of each ring's centre.
    ring_param: Arc<[(u32, f32)]>,
    /// Ring index of each vertex.
    pub(super) ring_of: Arc<[u32]>,
    /// First surface vertex of each ring; a ring's vertices are consecutive.
    pub(super) ring_first: Arc<[u32]>,
    /// Surface vertices per ring.
    pub(super) ring_len: u32,
    /// Centre vertex of each ring.
    pub(super) ring_centre: Arc<[u32]>,
    /// First and last ring of each ring's tube (a muscle may be several tubes).
    pub(super) tube_of_ring: Arc<[(u32, u32)]>,
    /// Each ring's outline in its rest plane (for [`super::muscle_contact`]).
    pub(super) outline: Arc<Vec<RingOutline>>,
    /// How each ring sits now, as the last placement left it.
    pub(super) pose: Vec<RingPose>,
    /// The body this shape was carried by rigidly in the last update, if it was (not
    /// placed on its chain): two shapes carried by one body keep their rest contact.
    pub(crate) carried: Option<BodyId>,
    /// Which vertices face fat at rest, and may bulge to keep the volume a contact
    /// took (see [`super::muscle_contact::free_to_bulge`]); empty: all.
    pub(super) bulges: Arc<Vec<bool>>,
    /// Axial offset and perpendicular offset of each vertex in its segment's rest frame.
    axial: Arc<[f32]>,
    perp: Arc<[Vec3]>,
    /// Current vertex positions (world, m).
    pub current: Vec<Vec3>,
    /// Rest vertex positions.
    pub rest: Arc<[Vec3]>,
    /// Enclosed volume at rest (m³).
    pub rest_volume: f64,
    /// Enclosed volume of the current shape (m³), as its last placement measured it.
    pub volume_now: f64,
    /// Surface triangles (from the lattice).
    pub triangles: Arc<[[u32; 3]]>,
    /// The rings' shifts out of bone and back to their side of the contact plane.
    pub(crate) keep: BoneKeepOut,
}

/// First and last ring of the tube each ring of `mesh` belongs to (a ring in no tube is
/// a tube of its own).
fn tube_of_ring(mesh: &crate::lattice::TubeMesh) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = (0..mesh.rings.len() as u32).map(|r| (r, r)).collect();
    for t in &mesh.tubes {
        if t.is_empty() || t.end as usize > out.len() {
            continue;
        }
        for r in t.clone() {
            out[r as usize] = (t.start, t.end - 1);
        }
    }
    out
}

impl MuscleShape {
    /// Binds a muscle lattice to its chain at rest.
    pub fn new(lattice: &MuscleLattice, chain: &MuscleChain) -> Self {
        let rest_chain = chain.x.clone();
        // Rings ride on the belly: a ring past its end hangs on the last belly segment
        // rather than on a tendon that turns with the other bone.
        let mut belly: Vec<bool> = chain.tendon.iter().map(|t| !t).collect();
        if !belly.iter().any(|b| *b) {
            belly.iter_mut().for_each(|b| *b = true);
        }
        let mesh = &lattice.mesh;
        let n = mesh.ring_len() as u32;
        let mut ring_of = vec![0u32; mesh.vertices.len()];
        let mut ring_param = Vec::with_capacity(mesh.rings.len());
        for (ri, r) in mesh.rings.iter().enumerate() {
            for v in r.first..r.first + n {
                ring_of[v as usize] = ri as u32;
            }
            ring_of[r.centre as usize] = ri as u32;
            let centre = mesh.vertices[r.centre as usize];
            let segments = 0..rest_chain.len().saturating_sub(1);
            ring_param.push(
                closest_on_polyline(&rest_chain, segments, |s| belly[s], centre)
                    .map_or((0, 0.0), |(s, t, _)| (s as u32, t)),
            );
        }
        let mut axial = Vec::with_capacity(mesh.vertices.len());
        let mut perp = Vec::with_capacity(mesh.vertices.len());
        for (vi, &v) in mesh.vertices.iter().enumerate() {
            let (s, t) = ring_param[ring_of[vi] as usize];
            let (a, b) = (rest_chain[s as usize], rest_chain[s as usize + 1]);
            let u0 = (b - a).normalize_or(Vec3::Z);
            let o = v - a.lerp(b, t);
            let ax = o.dot(u0);
            axial.push(ax);
            perp.push(o - u0 * ax);
        }
        let outline = mesh
            .rings
            .iter()
            .zip(&ring_param)
            .map(|(r, &(seg, _))| {
                let seg = seg as usize;
                let u0 = (rest_chain[seg + 1] - rest_chain[seg]).normalize_or(Vec3::Z);
                let f = r.first as usize;
                RingOutline::new(u0, perp[r.centre as usize], &perp[f..f + n as usize])
            })
            .collect();
        let mut shape = Self {
            ring_centre: mesh.rings.iter().map(|r| r.centre).collect(),
            outline: Arc::new(outline),
            pose: Vec::new(),
            bulges: Arc::default(),
            carried: None,
            rest_chain: rest_chain.into(),
            belly: belly.into(),
            ring_param: ring_param.into(),
            ring_of: ring_of.into(),
            ring_first: mesh.rings.iter().map(|r| r.first).collect(),
            ring_len: n,
            tube_of_ring: tube_of_ring(mesh).into(),
            axial: axial.into(),
            perp: perp.into(),
            current: mesh.vertices.clone(),
            rest: mesh.vertices.as_slice().into(),
            rest_volume: mesh.volume().abs(),
            volume_now: mesh.volume().abs(),
            triangles: mesh.triangles.as_slice().into(),
            keep: BoneKeepOut::default(),
        };
        shape.carry(Quat::IDENTITY, Vec3::ZERO);
        shape
    }

    /// The rings' poses of a shape carried rigidly by `(q, t)`, each ring's chain point
    /// shifted by `shift` across its axis (none if empty).
    fn carry_poses(&mut self, q: Quat, t: Vec3, shift: &[Vec3]) {
        let m = Mat3::from_quat(q);
        let mut pose = std::mem::take(&mut self.pose);
        pose.clear();
        pose.extend(self.rest_points().enumerate().map(|(r, (c, u0))| {
            let axis = q * u0;
            let sh = shift.get(r).copied().unwrap_or_default();
            RingPose {
                c: m * c + t + (sh - axis * sh.dot(axis)),
                m,
                across: 1.0,
                axis,
            }
        }));
        self.pose = pose;
    }

    /// The ring vertex `v` belongs to.
    pub(super) fn ring_of_vertex(&self, v: usize) -> usize {
        self.ring_of[v] as usize
    }

    /// Whether vertex `v` is a ring's centre (inside the muscle, not on its surface).
    pub(super) fn is_centre(&self, v: usize) -> bool {
        let f = self.ring_first[self.ring_of[v] as usize] as usize;
        v < f || v >= f + self.ring_len as usize
    }

    /// Each ring's chain point at rest.
    fn rest_points(&self) -> impl Iterator<Item = (Vec3, Vec3)> + '_ {
        self.ring_param.iter().map(|&(s, t)| {
            let s = s as usize;
            let (a, b) = (self.rest_chain[s], self.rest_chain[s + 1]);
            (a.lerp(b, t), (b - a).normalize_or(Vec3::Z))
        })
    }

    /// The point nearest `p` on the line of surface vertices through `v` from ring to
    /// ring (a meridian), within [`MERIDIAN_RINGS`] rings of `v`'s: the muscle's surface
    /// under `p` when the muscle has slid under it along its length. None when `v` is no
    /// ring's surface vertex. (A walk from `v`'s ring toward `p` stops at the first
    /// local minimum, on a bulge's far side: it left more muscle out through the skin.)
    pub(crate) fn surface_under(&self, v: u32, p: Vec3) -> Option<Vec3> {
        let r0 = *self.ring_of.get(v as usize)? as usize;
        let slot = v
            .checked_sub(self.ring_first[r0])
            .filter(|s| *s < self.ring_len)?;
        let at = |r: usize| self.current[(self.ring_first[r] + slot) as usize];
        let (first, last) = self.tube_of_ring[r0];
        let lo = r0.saturating_sub(MERIDIAN_RINGS).max(first as usize);
        let hi = (r0 + MERIDIAN_RINGS).min(last as usize);
        let mut best = (at(r0), at(r0).distance_squared(p));
        let mut a = at(lo);
        for r in lo..hi {
            let b = at(r + 1);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
            let q = a + ab * t;
            let d = q.distance_squared(p);
            if d < best.1 {
                best = (q, d);
            }
            a = b;
        }
        Some(best.0)
    }

    /// Watches the vertices near `bones` at rest (more of them near the knee, the point
    /// of `rest_contact`), to keep them out of those bones, and those behind the knee, to
    /// keep them on their side of the contact plane (`rest_contact`: the plane at rest).
    pub(crate) fn watch_bones(
        &mut self,
        bones: &[(crate::body::BodyId, parry3d::shape::TriMesh)],
        sdfs: &[crate::geometry::BoneSdf],
        rest_contact: &Contact,
    ) {
        self.keep = BoneKeepOut::new(&self.rest, self.ring_param.len(), bones, sdfs, rest_contact);
    }

    /// Places every vertex on the chain's current shape. Where the knee fold rules (see
    /// [`KneeFold::nearness`]) the rings turn with the same field as the fat, instead of
    /// with the chain's bend: rings on two sides of a sharp bend would otherwise cross.
    ///
    /// `contact` keeps thigh-side and calf-side vertices apart behind the knee (see
    /// [`Contact`]); the cross-sections then make up the volume it squeezed out.
    pub fn update(&mut self, chain: &MuscleChain, knee: &KneeFold, contact: Option<&Contact>) {
        self.place(chain, knee, contact, None);
    }

    /// [`Self::update`], with the rings shifted out of the bones where they reach in, and
    /// back toward their side of `bones`' contact plane.
    pub(crate) fn update_clear_of(&mut self, chain: &MuscleChain, knee: &KneeFold, bones: &Bones) {
        self.place(chain, knee, None, Some(bones));
    }

    fn place(
        &mut self,
        chain: &MuscleChain,
        knee: &KneeFold,
        contact: Option<&Contact>,
        bones: Option<&Bones>,
    ) {
        let segs = self.rest_chain.len() - 1;
        let mut seg_rot = Vec::with_capacity(segs);
        let mut seg_len = Vec::with_capacity(segs);
        for s in 0..segs {
            let (a0, b0) = (self.rest_chain[s], self.rest_chain[s + 1]);
            let (a, b) = (chain.x[s], chain.x[s + 1]);
            let (d0, d) = (b0 - a0, b - a);
            let (l0, l) = (d0.length().max(1e-6), d.length().max(1e-6));
            seg_rot.push(Quat::from_rotation_arc(d0 / l0, d / l));
            seg_len.push((l / l0, d0 / l0));
        }
        // Rotation and stretch at each chain point: the mean of its two segments (of
        // its belly segment alone where the other is tendon).
        let point = |i: usize| -> (Quat, f32) {
            let mut a = i.saturating_sub(1).min(segs - 1);
            let mut b = i.min(segs - 1);
            if self.belly[a] != self.belly[b] {
                (a, b) = if self.belly[a] { (a, a) } else { (b, b) };
            }
            (
                seg_rot[a].slerp(seg_rot[b], 0.5),
                0.5 * (seg_len[a].0 + seg_len[b].0),
            )
        };
        // Per ring: centre, turn (as a matrix: one per ring, not per vertex) and stretch
        // (all its vertices share them).
        // Shifts (out of bone, off the contact plane) only where bones are watched; kept
        // across the muscle (the rings turn with it while a shift is world-fixed).
        let shift: &[Vec3] = match bones {
            Some(b) => {
                self.keep.fade(b.fade);
                &self.keep.shift
            }
            None => &[],
        };
        let mut rings: Vec<(Vec3, Mat3, Vec3, f32)> = self
            .ring_param
            .iter()
            .enumerate()
            .map(|(r, &(s, t))| {
                let s = s as usize;
                let ((q0, l0), (q1, l1)) = (point(s), point(s + 1));
                let mut q = q0.slerp(q1, t);
                let lambda = l0 + (l1 - l0) * t;
                let centre_rest = self.rest_chain[s].lerp(self.rest_chain[s + 1], t);
                let near = knee.nearness(centre_rest);
                if near > 0.0 {
                    q = q.slerp(knee.rotation(centre_rest), near);
                }
                let axis = q * seg_len[s].1;
                let sh = shift.get(r).copied().unwrap_or_default();
                let c = chain.x[s].lerp(chain.x[s + 1], t) + (sh - axis * sh.dot(axis));
                (c, Mat3::from_quat(q), axis, lambda)
            })
            .collect();
        // Volumes are taken about a point inside the muscle: small coordinates keep the
        // single-precision sum accurate.
        let origin = chain.x[chain.x.len() / 2];
        let mut across_fix = 1.0f32;
        // Each ring's √λ, and its cross-section's scale this pass (once per ring, not per
        // vertex: the same operations on the same values, so the same bits).
        let root: Vec<f32> = rings.iter().map(|r| r.3.sqrt()).collect();
        let mut across = vec![0.0f32; rings.len()];
        // The closest volume found, and the cross-section scale that gave it: where the
        // contact plane flattens a muscle its volume need not grow with the scale, and
        // the passes can swing ever wider (the plantaris by the condyle went to ×20).
        let mut best = (f64::INFINITY, across_fix);
        // The nearest scales found below and above the rest volume: where the volume
        // grows faster than the square of the scale (rings crossing at a sharp bend),
        // the square-root step overshoots back and forth, and the passes search between
        // them instead.
        let mut bracket: [Option<(f32, f64)>; 2] = [None, None];
        let mut pass = 0;
        loop {
            for (a, r) in across.iter_mut().zip(&root) {
                *a = across_fix / r;
            }
            for (vi, p) in self.current.iter_mut().enumerate() {
                let ring = self.ring_of[vi] as usize;
                let (c, m, axis_now, lambda) = rings[ring];
                *p = c + axis_now * (self.axial[vi] * lambda) + m * (self.perp[vi] * across[ring]);
            }
            if let Some(c) = contact {
                for (p, r) in self.current.iter_mut().zip(self.rest.iter()) {
                    *p = c.apply(*p, r.z >= knee.point.z, c.muscle_margin);
                }
            }
            // In the first pass only: the volume passes change the cross-sections by far
            // less than the margin the shifted rings keep. A shift can move a ring's
            // other vertices in, so a few rounds.
            if pass == 0
                && let Some(b) = bones
            {
                let moved =
                    self.keep
                        .clear_rings(&mut self.current, &self.ring_of, |r| rings[r].2, b);
                for (ring, m) in rings.iter_mut().zip(moved) {
                    ring.0 += *m;
                }
            }
            // What the piecewise map still gains or loses, the cross-sections give back:
            // one factor per muscle, the square root of the volume ratio, at most a
            // quarter either way a pass.
            let v = volume_about(&self.current, &self.triangles, origin);
            self.volume_now = v;
            let miss = (v / self.rest_volume - 1.0).abs();
            if miss < best.0 {
                best = (miss, across_fix);
            }
            bracket[usize::from(v > self.rest_volume)] = Some((across_fix, v));
            if pass == VOLUME_PASSES {
                break;
            }
            match volume_fix(self.rest_volume, v, pass) {
                Some(fix) => {
                    across_fix = match bracket {
                        [Some(lo), Some(hi)] => between(lo, hi, self.rest_volume),
                        _ => across_fix * fix.clamp(0.8, 1.25),
                    }
                }
                // Done; or out of passes, or no volume at all: then the best scale again
                // (one more placement), unless this was it.
                None if best.1 == across_fix => break,
                None => {
                    across_fix = best.1;
                    pass = VOLUME_PASSES;
                    continue;
                }
            }
            pass += 1;
        }
        self.carried = None;
        self.pose.clear();
        self.pose.extend(
            rings
                .iter()
                .zip(&across)
                .map(|(&(c, m, axis, _), &across)| RingPose { c, m, across, axis }),
        );
    }

    /// Moves the whole shape rigidly with a body (rest → now).
    pub fn carry(&mut self, q: Quat, t: Vec3) {
        let m = Mat3::from_quat(q);
        for (p, r) in self.current.iter_mut().zip(self.rest.iter()) {
            *p = m * *r + t;
        }
        self.carry_poses(q, t, &[]);
        self.keep.clear();
        self.volume_now = self.rest_volume;
    }

    /// [`Self::carry`], with the rings shifted out of `bones` and back to their side of
    /// its contact plane, as a placed shape's are: a muscle at rest on the shank is still
    /// overtaken by the plane as the knee bends deeply.
    pub(crate) fn carry_clear_of(&mut self, q: Quat, t: Vec3, bones: &Bones, body: BodyId) {
        let m = Mat3::from_quat(q);
        self.keep.fade(bones.fade);
        let axes: Vec<Vec3> = self
            .ring_param
            .iter()
            .map(|&(s, _)| {
                let s = s as usize;
                q * (self.rest_chain[s + 1] - self.rest_chain[s]).normalize_or(Vec3::Z)
            })
            .collect();
        let shift = &self.keep.shift;
        for ((p, r), &ring) in self
            .current
            .iter_mut()
            .zip(self.rest.iter())
            .zip(self.ring_of.iter())
        {
            let (sh, a) = (shift[ring as usize], axes[ring as usize]);
            *p = m * *r + t + (sh - a * sh.dot(a));
        }
        self.keep
            .clear_carried_rings(&mut self.current, &self.ring_of, |r| axes[r], bones, body);
        let shift = std::mem::take(&mut self.keep.shift);
        self.carry_poses(q, t, &shift);
        self.keep.shift = shift;
        if self.keep.shift.iter().all(|s| *s == Vec3::ZERO) {
            self.volume_now = self.rest_volume;
            return;
        }
        // Shifted rings shear the surface between them, which changes its volume a
        // little (1.6 % for the phantom's peroneus longus at 134°): the cross-sections
        // give it back, one factor per muscle, as in `place` (which likewise scales them
        // after the keep-out: a fraction of a millimetre, unchecked).
        let centres: Vec<Vec3> = self
            .ring_param
            .iter()
            .zip(&self.keep.shift)
            .zip(&axes)
            .map(|((&(s, f), sh), a)| {
                let s = s as usize;
                m * self.rest_chain[s].lerp(self.rest_chain[s + 1], f) + t + (*sh - *a * sh.dot(*a))
            })
            .collect();
        let origin = self.current[self.current.len() / 2];
        for pass in 0..VOLUME_PASSES {
            let v = volume_about(&self.current, &self.triangles, origin);
            self.volume_now = v;
            let Some(fix) = volume_fix(self.rest_volume, v, pass) else {
                break;
            };
            for (p, &ring) in self.current.iter_mut().zip(self.ring_of.iter()) {
                let (c, a) = (centres[ring as usize], axes[ring as usize]);
                let o = *p - c;
                let along = a * o.dot(a);
                *p = c + along + (o - along) * fix;
            }
        }
    }

    /// Whether the contact plane watches any vertex of this shape.
    pub(crate) fn near_plane(&self) -> bool {
        self.keep.near_plane()
    }

    /// Volume over rest volume, as the last placement measured it.
    pub fn volume_ratio(&self) -> f32 {
        (self.volume_now / self.rest_volume.max(1e-12)) as f32
    }

    /// Enclosed volume now (m³), measured anew.
    pub fn volume(&self) -> f64 {
        signed_volume(&self.current, &self.triangles).abs()
    }
}

/// The factor by which volume pass `pass` scales the cross-sections of a shape that
/// encloses `v` (m³) against `rest`: the square root of the volume ratio. None when the
/// shape is close enough (within 2 × 10⁻⁴ of that factor), out of passes, or not a
/// volume at all.
pub(super) fn volume_fix(rest: f64, v: f64, pass: usize) -> Option<f32> {
    let fix = ((rest / v.max(1e-15)) as f32).sqrt();
    let done = (fix - 1.0).abs() < 2e-4 || pass + 1 == VOLUME_PASSES || v <= 0.0;
    (!done).then_some(fix)
}

/// The scale between `lo` and `hi` (scale, volume: one below `rest`, one above) where
/// the volume, a power of the scale between them, meets `rest`; the middle of the two
/// (geometric) if that falls outside.
fn between(lo: (f32, f64), hi: (f32, f64), rest: f64) -> f32 {
    let (l0, l1) = (f64::from(lo.0).ln(), f64::from(hi.0).ln());
    let (v0, v1) = (lo.1.max(1e-18).ln(), hi.1.max(1e-18).ln());
    let t = if v1 > v0 {
        (rest.ln() - v0) / (v1 - v0)
    } else {
        0.5
    };
    let t = if (0.02..=0.98).contains(&t) { t } else { 0.5 };
    (l0 + (l1 - l0) * t).exp() as f32
}

/// Enclosed volume (m³) of a closed triangle surface, summed about `origin` in single
/// precision per triangle (double across them).
pub(super) fn volume_about(vertices: &[Vec3], triangles: &[[u32; 3]], origin: Vec3) -> f64 {
    let mut v = 0.0f64;
    for chunk in triangles.chunks(64) {
        let mut part = 0.0f32;
        for t in chunk {
            let [a, b, c] = t.map(|i| Vec3A::from(vertices[i as usize] - origin));
            part += a.dot(b.cross(c));
        }
        v += f64::from(part);
    }
    (v / 6.0).abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tubes of square rings (4 vertices, 1 cm across), 5 mm apart along z: rings
    /// 0–5 about x = 0, rings 6–8 about x = 5 cm. Vertex `4 r + k` is corner k of ring r.
    fn two_tubes() -> MuscleShape {
        let corner = [Vec3::X, Vec3::Y, -Vec3::X, -Vec3::Y];
        let mut current = Vec::new();
        let mut ring_of = Vec::new();
        for r in 0..9u32 {
            let centre = if r < 6 {
                Vec3::new(0.0, 0.0, 0.005 * r as f32)
            } else {
                Vec3::new(0.05, 0.0, 0.005 * (r - 6) as f32)
            };
            current.extend(corner.iter().map(|c| centre + *c * 0.005));
            ring_of.extend([r; 4]);
        }
        MuscleShape {
            rest_chain: Arc::default(),
            belly: Arc::default(),
            ring_param: Arc::default(),
            ring_of: ring_of.into(),
            ring_first: (0..9).map(|r| 4 * r).collect(),
            ring_len: 4,
            tube_of_ring: (0..9)
                .map(|r| if r < 6 { (0, 5) } else { (6, 8) })
                .collect(),
            axial: Arc::default(),
            perp: Arc::default(),
            rest: current.as_slice().into(),
            current,
            rest_volume: 0.0,
            volume_now: 0.0,
            triangles: Arc::default(),
            keep: BoneKeepOut::default(),
            ring_centre: Arc::default(),
            outline: Arc::default(),
            pose: Vec::new(),
            bulges: Arc::default(),
            carried: None,
        }
    }

    #[test]
    fn the_surface_under_a_point_is_found_along_its_vertex_meridian_within_its_tube() {
        let s = two_tubes();
        // Corner 0 of ring 1 (x = 5 mm, z = 5 mm); a point 3 mm out from that meridian at
        // z = 17 mm lies over the segment between rings 3 and 4.
        let q = s.surface_under(4, Vec3::new(0.008, 0.0, 0.017)).unwrap();
        assert!(q.distance(Vec3::new(0.005, 0.0, 0.017)) < 1e-6, "{q}");
        // Past the tube's end the meridian's last vertex.
        let q = s.surface_under(4, Vec3::new(0.008, 0.0, 0.1)).unwrap();
        assert!(q.distance(Vec3::new(0.005, 0.0, 0.025)) < 1e-6, "{q}");
        // Never on another tube, however near it lies.
        let q = s.surface_under(4, Vec3::new(0.056, 0.0, 0.005)).unwrap();
        assert!(q.x < 0.01, "{q}");
        // The moved surface, not the rest one.
        let mut moved = s.clone();
        moved.current.iter_mut().for_each(|p| p.x += 0.002);
        let q = moved.surface_under(4, Vec3::new(0.01, 0.0, 0.01)).unwrap();
        assert!(q.distance(Vec3::new(0.007, 0.0, 0.01)) < 1e-6, "{q}");
        // No such vertex.
        assert!(s.surface_under(99, Vec3::ZERO).is_none());
    }
}
