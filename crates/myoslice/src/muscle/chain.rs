//! The paper's muscle (section 3.2, Eq. 1): mass points in series on the muscle's centre
//! line, joined by damped springs, pulled together by a contraction force, with end points
//! fixed to the bones. Interior points are kept in cones anchored on the bone surface
//! (section 4.1, Fig. 6).

use glam::{Quat, Vec3};

use super::dynamics::ChainScratch;
use super::wrap::{WrapCylinder, WrapPath};
use crate::body::BodyId;

/// A point fixed to a body, given in the body's rest frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attachment {
    /// The body.
    pub body: BodyId,
    /// Position at rest (body frame = world at rest).
    pub rest: Vec3,
}

/// A cone restricting an interior chain point: apex on the bone surface (the centre of
/// the nearest bone triangle at rest), axis through the point at rest. Beyond the paper,
/// the point also keeps near its rest depth from the apex (`depth`): the tissue around a
/// muscle holds it there, and a chain under tension would otherwise bowstring through
/// its neighbours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeAnchor {
    /// Body carrying the apex.
    pub body: BodyId,
    /// Apex at rest.
    pub apex: Vec3,
    /// Unit axis at rest.
    pub axis: Vec3,
    /// Smallest and largest distance (m) from the apex.
    pub depth: [f32; 2],
    /// The point's place at rest (body rest frame), where an unloaded chain's tether pulls
    /// it back to (see [`super::ChainLoad::tether`]): where [`MuscleChain::settle`] left it
    /// when the chain was built (under its settling tension), which is also where the
    /// tissue rests on it.
    pub rest: Vec3,
}

/// How far (share of the rest depth, at least [`DEPTH_SLACK_MIN`]) a cone-anchored point
/// may move away from its apex beyond its rest depth.
pub const DEPTH_SLACK: f32 = 0.25;

/// Least depth slack (m).
pub const DEPTH_SLACK_MIN: f32 = 0.005;

impl ConeAnchor {
    /// A cone at `apex` through `point` (rest), on `body`.
    pub fn new(body: BodyId, apex: Vec3, axis: Vec3, point: Vec3) -> Self {
        let d = point.distance(apex);
        let slack = (DEPTH_SLACK * d).max(DEPTH_SLACK_MIN);
        Self {
            body,
            apex,
            axis,
            depth: [0.0, d + slack],
            rest: point,
        }
    }
}

/// Body poses as seen by the chains: rotation and translation of each body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyFrames {
    /// Thigh pose.
    pub thigh: (Quat, Vec3),
    /// Shank pose.
    pub shank: (Quat, Vec3),
}

impl BodyFrames {
    /// Rest poses.
    pub const REST: Self = Self {
        thigh: (Quat::IDENTITY, Vec3::ZERO),
        shank: (Quat::IDENTITY, Vec3::ZERO),
    };

    /// The pose (rotation, translation) of body `b`.
    pub fn pose(&self, b: BodyId) -> (Quat, Vec3) {
        match b {
            BodyId::Thigh => self.thigh,
            BodyId::Shank => self.shank,
        }
    }

    /// A rest point of body `b` in the world now.
    pub fn point(&self, b: BodyId, p: Vec3) -> Vec3 {
        let (q, t) = self.pose(b);
        q * p + t
    }

    /// A rest direction of body `b` in the world now.
    pub fn vector(&self, b: BodyId, v: Vec3) -> Vec3 {
        self.pose(b).0 * v
    }
}

/// Per-segment geometry of the current chain.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SegmentGeom {
    /// Length along the path (m).
    pub length: f32,
    /// Unit direction from its first point toward the second.
    pub dir_a: Vec3,
    /// Unit direction from its second point toward the first.
    pub dir_b: Vec3,
}

/// A muscle's chain of mass points, origin (index 0) to insertion (last).
#[derive(Debug)]
pub struct MuscleChain {
    /// Origin attachment.
    pub origin: Attachment,
    /// Insertion attachment.
    pub insertion: Attachment,
    /// Positions (world, m).
    pub x: Vec<Vec3>,
    /// Velocities (m/s).
    pub v: Vec<Vec3>,
    /// Mass of each interior point (kg); 0 for the end points.
    pub mass: Vec<f32>,
    /// Rest length of each segment (m).
    pub rest_len: Vec<f32>,
    /// Whether each segment is tendon (outside the muscle belly).
    pub tendon: Vec<bool>,
    /// Cone of each point (end points have none).
    pub cones: Vec<Option<ConeAnchor>>,
    /// Interior points pinned to a body (via points the tendon runs through).
    pub vias: Vec<(usize, Attachment)>,
    /// Cosine and tangent of the cone half-angle.
    pub cone_cos_tan: (f32, f32),
    /// Wrap cylinder of the segment crossing the knee, for muscles crossing it.
    pub wrap: Option<WrapCylinder>,
    /// Index of the segment that crosses the knee (the one that may wrap).
    pub wrap_segment: usize,
    /// Whether that segment is wrapped now.
    pub wrapped: bool,
    /// Rest length of the belly (sum of belly segments).
    pub belly_rest: f32,
    /// Reused buffers of the implicit step.
    pub scratch: ChainScratch,
    /// Geometry of every segment at the current positions (see [`Self::refresh`]).
    pub geom: Vec<SegmentGeom>,
    /// The body each point moves with (see [`Self::index_bodies`]): fixed once the chain
    /// is built, looked up every step.
    pub bodies: Vec<BodyId>,
}

impl Clone for MuscleChain {
    fn clone(&self) -> Self {
        let mut c = Self {
            origin: self.origin,
            insertion: self.insertion,
            x: Vec::new(),
            v: Vec::new(),
            mass: Vec::new(),
            rest_len: Vec::new(),
            tendon: Vec::new(),
            cones: Vec::new(),
            vias: Vec::new(),
            cone_cos_tan: self.cone_cos_tan,
            wrap: self.wrap,
            wrap_segment: self.wrap_segment,
            wrapped: self.wrapped,
            belly_rest: self.belly_rest,
            scratch: ChainScratch::default(),
            geom: Vec::new(),
            bodies: Vec::new(),
        };
        c.clone_from(self);
        c
    }

    /// Copies into the buffers already here (a step's rollback copy is taken every
    /// call: this keeps it free of allocations). Work buffers are not copied.
    fn clone_from(&mut self, o: &Self) {
        // Every field named, so that a new one cannot be forgotten here.
        let Self {
            origin,
            insertion,
            x,
            v,
            mass,
            rest_len,
            tendon,
            cones,
            vias,
            cone_cos_tan,
            wrap,
            wrap_segment,
            wrapped,
            belly_rest,
            scratch: _,
            geom,
            bodies,
        } = o;
        (self.origin, self.insertion) = (*origin, *insertion);
        self.x.clone_from(x);
        self.v.clone_from(v);
        self.mass.clone_from(mass);
        self.rest_len.clone_from(rest_len);
        self.tendon.clone_from(tendon);
        self.cones.clone_from(cones);
        self.vias.clone_from(vias);
        (self.cone_cos_tan, self.wrap, self.wrap_segment) = (*cone_cos_tan, *wrap, *wrap_segment);
        (self.wrapped, self.belly_rest) = (*wrapped, *belly_rest);
        self.geom.clone_from(geom);
        self.bodies.clone_from(bodies);
    }
}

impl MuscleChain {
    /// Takes `x` (world, at `frames`) as where each cone-anchored point rests on its
    /// bone ([`ConeAnchor::rest`], where the tether pulls it back to).
    pub fn set_rest_places(&mut self, x: &[Vec3], frames: &BodyFrames) {
        debug_assert_eq!(x.len(), self.cones.len(), "one place per chain point");
        for (p, c) in x.iter().zip(&mut self.cones) {
            if let Some(c) = c {
                let (q, t) = frames.pose(c.body);
                c.rest = q.inverse() * (*p - t);
            }
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True for an empty chain.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Geometry of segment `i` at the positions of the last [`Self::refresh`].
    #[inline]
    pub fn segment(&self, i: usize) -> SegmentGeom {
        self.geom
            .get(i)
            .copied()
            .unwrap_or_else(|| self.compute_segment(i))
    }

    /// Recomputes the cached segment geometry (after moving points).
    pub fn refresh(&mut self) {
        self.refresh_geometry(false);
    }

    /// The segment geometry; with `update_wrap`, the wrapped state of the knee-crossing
    /// segment follows the new positions too. One wrap evaluation serves both: the
    /// geometry of `path(a, b, was)` equals that of `path(a, b, path(a, b, was).wrapped)`.
    fn refresh_geometry(&mut self, update_wrap: bool) {
        let n = self.x.len().saturating_sub(1);
        self.geom.resize(n, SegmentGeom::default());
        // Straight segments in one tight loop (the hot part of every step), then the one
        // segment that may wrap.
        for (g, p) in self.geom.iter_mut().zip(self.x.windows(2)) {
            *g = straight_segment(p[0], p[1]);
        }
        if self.wrap.is_some() && self.wrap_segment < n {
            self.refresh_segment(self.wrap_segment, update_wrap);
        }
    }

    #[inline]
    fn refresh_segment(&mut self, i: usize, update_wrap: bool) {
        let (g, wrapped) = self.segment_now(i);
        self.geom[i] = g;
        if update_wrap && let Some(w) = wrapped {
            self.wrapped = w;
        }
    }

    /// The geometry after only the pinned points (ends, via points) moved: the segments
    /// next to them. The rest is as the last refresh left it (every method that moves
    /// interior points refreshes).
    pub(super) fn refresh_pinned(&mut self) {
        let n = self.x.len();
        if self.geom.len() + 1 != n {
            self.refresh();
            return;
        }
        // Ends and via points are the massless points.
        for i in 0..n - 1 {
            if self.mass[i] > 0.0 && self.mass[i + 1] > 0.0 {
                continue;
            }
            if self.wrap.is_some() && i == self.wrap_segment {
                self.refresh_segment(i, false);
            } else {
                self.geom[i] = straight_segment(self.x[i], self.x[i + 1]);
            }
        }
        debug_assert!(
            !self.x.iter().all(|p| p.is_finite())
                || (0..n - 1).all(|i| self.compute_segment(i) == self.geom[i]),
            "interior chain points moved without a refresh"
        );
    }

    /// Geometry of segment `i` (between points i and i+1); the knee-crossing one may wrap.
    fn compute_segment(&self, i: usize) -> SegmentGeom {
        self.segment_now(i).0
    }

    /// Geometry of segment `i` now, and for the knee-crossing segment whether it wraps.
    fn segment_now(&self, i: usize) -> (SegmentGeom, Option<bool>) {
        let (a, b) = (self.x[i], self.x[i + 1]);
        match &self.wrap {
            Some(w) if i == self.wrap_segment => {
                let WrapPath {
                    length,
                    dir_p,
                    dir_q,
                    wrapped,
                } = w.path(a, b, self.wrapped);
                let g = SegmentGeom {
                    length,
                    dir_a: dir_p,
                    dir_b: dir_q,
                };
                (g, Some(wrapped))
            }
            _ => (straight_segment(a, b), None),
        }
    }

    /// Path length origin to insertion (m), wrapping included.
    pub fn path_length(&self) -> f64 {
        (0..self.x.len() - 1)
            .map(|i| f64::from(self.segment(i).length))
            .sum()
    }

    /// The body each point moves with: the attachment bodies at the ends, the cone's body
    /// for interior points.
    pub fn point_body(&self, i: usize) -> BodyId {
        match self.bodies.get(i) {
            Some(b) if self.bodies.len() == self.x.len() => *b,
            _ => self.body_of_point(i),
        }
    }

    pub(super) fn body_of_point(&self, i: usize) -> BodyId {
        if i == 0 {
            self.origin.body
        } else if i + 1 == self.x.len() {
            self.insertion.body
        } else if let Some((_, a)) = self.vias.iter().find(|(k, _)| *k == i) {
            a.body
        } else {
            self.cones[i].map_or(self.origin.body, |c| c.body)
        }
    }

    /// Fills [`Self::bodies`] from the attachments, via points and cones (call after
    /// changing any of them).
    pub fn index_bodies(&mut self) {
        self.bodies = (0..self.x.len()).map(|i| self.body_of_point(i)).collect();
    }

    /// Current belly length (m).
    pub fn belly_length(&self) -> f32 {
        (0..self.x.len() - 1)
            .filter(|&i| !self.tendon[i])
            .map(|i| self.segment(i).length)
            .sum()
    }

    /// Updates whether the knee-crossing segment is wrapped, and the segment geometry
    /// (call after points move).
    pub fn update_wrap(&mut self) {
        self.refresh_geometry(true);
    }

    /// Moves the end points onto their attachments.
    pub fn attach_ends(&mut self, frames: &BodyFrames) {
        let n = self.x.len();
        self.x[0] = frames.point(self.origin.body, self.origin.rest);
        self.x[n - 1] = frames.point(self.insertion.body, self.insertion.rest);
        for (i, a) in &self.vias {
            self.x[*i] = frames.point(a.body, a.rest);
        }
    }
}

/// The straight segment from `a` to `b`.
#[inline]
fn straight_segment(a: Vec3, b: Vec3) -> SegmentGeom {
    let d = b - a;
    let l = d.length().max(1e-9);
    let dir = d * (1.0 / l);
    SegmentGeom {
        length: l,
        dir_a: dir,
        dir_b: -dir,
    }
}

/// `p` moved along the line from `apex` so that its distance from it lies in `depth`.
pub fn clamp_depth(p: Vec3, apex: Vec3, depth: [f32; 2]) -> Vec3 {
    let w = p - apex;
    // Inside the shell (the usual case) without a square root.
    let d2 = w.length_squared();
    if d2 >= depth[0] * depth[0] && d2 <= depth[1] * depth[1] {
        return p;
    }
    let d = d2.sqrt();
    if d < 1e-9 {
        return p;
    }
    let c = d.clamp(depth[0], depth[1]);
    if c == d { p } else { apex + w * (c / d) }
}

/// Closest point of the cone (apex, unit axis, half-angle given by its cosine and
/// tangent) to `p`.
pub fn project_into_cone(p: Vec3, apex: Vec3, axis: Vec3, (cos_a, tan_a): (f32, f32)) -> Vec3 {
    let w = p - apex;
    let t = w.dot(axis);
    let radial = w - axis * t;
    // Inside (the usual case) without a square root.
    let r2 = radial.length_squared();
    if t > 0.0 && r2 <= (t * tan_a) * (t * tan_a) {
        return p;
    }
    let r = r2.sqrt();
    let sin_a = cos_a * tan_a;
    let s = t * cos_a + r * sin_a;
    if s <= 0.0 {
        return apex;
    }
    let rhat = if r > 1e-12 {
        radial / r
    } else {
        axis.any_orthonormal_vector()
    };
    apex + (axis * cos_a + rhat * sin_a) * s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cone_point_cannot_bowstring_past_its_depth_bound_but_may_sink_toward_the_bone() {
        let c = ConeAnchor::new(
            BodyId::Thigh,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(0.0, 0.0, 0.04),
        );
        assert!(
            c.depth[0] == 0.0 && (c.depth[1] - 0.05).abs() < 1e-6,
            "{:?}",
            c.depth
        );
        let out = clamp_depth(Vec3::new(0.0, 0.03, 0.09), Vec3::ZERO, c.depth);
        assert!((out.length() - 0.05).abs() < 1e-6, "{out}");
        assert!(out.normalize().dot(Vec3::new(0.0, 0.03, 0.09).normalize()) > 0.9999);
        let near = Vec3::new(0.0, 0.0, 0.01);
        assert_eq!(clamp_depth(near, Vec3::ZERO, c.depth), near);
    }

    #[test]
    fn cone_projection_keeps_inside_points_and_lands_outside_ones_on_the_surface() {
        let cs = (30f32.to_radians().cos(), 30f32.to_radians().tan());
        let inside = Vec3::new(0.1, 0.0, 1.0);
        assert_eq!(project_into_cone(inside, Vec3::ZERO, Vec3::Z, cs), inside);
        let q = project_into_cone(Vec3::new(2.0, 0.0, 1.0), Vec3::ZERO, Vec3::Z, cs);
        let ang = (q.x / q.z).atan().to_degrees();
        assert!((ang - 30.0).abs() < 1e-3, "{ang}");
        assert_eq!(
            project_into_cone(Vec3::new(0.0, 0.0, -1.0), Vec3::ZERO, Vec3::Z, cs),
            Vec3::ZERO
        );
    }
}
