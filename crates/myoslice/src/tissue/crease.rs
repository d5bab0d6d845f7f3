//! The crease behind the knee: thigh-side and calf-side fat kept apart by the contact
//! plane, and the skin there drawn back toward it.
//!
//! The knee fold spreads the posterior compression of a deep flexion over a wide sector,
//! so it carries the skin of the back of the thigh and calf toward the front, away from
//! the plane (at 134°, 10–13 cm above the axis, 40–50 mm), while the muscles under that
//! skin stay with their bones: they came out through it. Each contact pass now pulls the
//! skin behind the knee that lies further from the plane, on its own side, than its bone
//! alone would carry it back toward that (toward the plane itself where its bone would
//! carry it past it: the thigh and calf press on each other there), by a share of the
//! excess: the share of its outward direction that faces the plane, nothing at the
//! crease's apex. Over an update's passes the two sides come to meet on the plane, over
//! the muscles between.

use glam::{Quat, Vec3};

use super::knee_fold::{Contact, KneeFold};
use super::{LAYER_GAP, Tissue};

/// Within this distance (m) behind the knee axis the skin is not pulled, and over the
/// next [`APEX_RAMP_M`] the pull grows to its full share: at the crease's apex the skin
/// turns round the axis, and pulled there it folded over itself (116 crossing triangle
/// pairs and 83 elements below their volume floor in the guard's first round of an
/// update, against 59 and 58 with the apex spared). Sparing it costs a little cover:
/// the most muscle vertices out went 1 769 → 1 842 (phantom) and 1 995 → 2 024 (Visible
/// Human), for a cheaper guard.
const APEX_M: f32 = 0.05;
/// See [`APEX_M`].
const APEX_RAMP_M: f32 = 0.03;

/// Skin vertices behind the knee axis (rest), each with how far (m) from the contact
/// plane, on its side, it may lie now before it is pulled (where its bone alone carries
/// it, but no nearer than `gap`, the skin's own margin), and the share of the excess
/// each contact pass removes: the share of its outward direction (its rest column,
/// turned with its bone) that faces the plane. Skin at the sides of the knee, which runs across the plane, is not pulled
/// along itself: pulled whole, it folded over (379 crossing triangle pairs in the
/// guard's first round of an update, against 116).
///
/// `fold` is the knee at this update, `contact` its plane (world) and `thigh` the thigh's
/// pose.
pub(super) fn skin_limits(
    tissue: &Tissue,
    fold: &KneeFold,
    contact: &Contact,
    (tq, tt): (Quat, Vec3),
    gap: f32,
    out: &mut Vec<(f32, f32)>,
) {
    let rigid = Rigid::new(fold, (tq, tt));
    out.clear();
    out.extend(
        tissue
            .fixed
            .posterior_skin_rest
            .iter()
            .map(|&(r, col, thigh)| {
                let (_, d) = contact.locate(rigid.place(r, thigh), thigh);
                let col = rigid.turn(col, thigh);
                let w = (-contact.off_side(col.normalize_or_zero(), thigh)).max(0.0);
                (d.max(gap), w)
            }),
    );
}

/// How the bones alone carry the tissue at a knee fold: the thigh at its pose, the shank
/// turned about the knee point by the knee angle as well. Where the skin would be, and
/// which way it would face, if nothing but its bone moved it.
pub(super) struct Rigid {
    point: Vec3,
    shank: Quat,
    thigh: (Quat, Vec3),
}

impl Rigid {
    /// The bones' carry at `fold`, with the thigh at pose `thigh`.
    pub(super) fn new(fold: &KneeFold, thigh: (Quat, Vec3)) -> Self {
        Self {
            point: fold.point,
            shank: Quat::from_axis_angle(fold.axis, fold.theta),
            thigh,
        }
    }

    /// Where rest point `r` of the thigh's side (`thigh`) or the shank's goes (world).
    pub(super) fn place(&self, r: Vec3, thigh: bool) -> Vec3 {
        let (tq, tt) = self.thigh;
        if thigh {
            tq * r + tt
        } else {
            tq * (self.point + self.shank * (r - self.point)) + tt
        }
    }

    /// Where rest direction `v` of the thigh's side (`thigh`) or the shank's turns.
    pub(super) fn turn(&self, v: Vec3, thigh: bool) -> Vec3 {
        let tq = self.thigh.0;
        if thigh { tq * v } else { tq * (self.shank * v) }
    }
}

impl Tissue {
    /// Keeps thigh-side and calf-side fat apart behind the knee ([`Contact`]) by a gap
    /// that opens as the knee bends (`opened`, 0 straight to 1), and pulls
    /// the skin there back toward the plane by the shares `limits` give (see
    /// [`skin_limits`]; spared at the crease's apex, see [`APEX_M`]).
    pub(super) fn apply_contact(
        &mut self,
        c: &Contact,
        gap: f32,
        limits: &[(f32, f32)],
        opened: f32,
    ) {
        let l1 = self.layers + 1;
        let fixed = &self.fixed;
        let x = &mut self.fat.x;
        for (&v, &rest_side) in fixed.posterior.iter().zip(&fixed.posterior_rest_side) {
            let v = v as usize;
            // Vertices outside the relaxed region sit on the fold (to within 0.1 mm), which
            // keeps its side.
            if !self.fat.free[v] {
                continue;
            }
            // Deeper layers stop further from the contact, so squeezed elements stay
            // thin but never flat. The gap opens as the knee bends (`opened` from 0 to 1):
            // straight, no vertex is pushed further off than it lies at rest, where the
            // pushes had folded the thin elements across the plane.
            let depth = (self.layers - v % l1) as f32;
            let margin = gap + LAYER_GAP * depth;
            x[v] = c.apply(
                x[v],
                fixed.thigh_side[v],
                margin.min(rest_side + margin * opened),
            );
        }
        // Only pulls toward the plane, to no less than `gap` from it: the push above
        // holds the other bound.
        debug_assert_eq!(fixed.posterior_skin.len(), limits.len());
        for (&v, &(limit, w)) in fixed.posterior_skin.iter().zip(limits) {
            let v = v as usize;
            if !self.fat.free[v] {
                continue;
            }
            let thigh = fixed.thigh_side[v];
            let (behind, d) = c.locate(x[v], thigh);
            if behind <= 0.0 {
                continue;
            }
            let f = ((behind - APEX_M) / APEX_RAMP_M).clamp(0.0, 1.0);
            if d > limit {
                x[v] = c.toward_side(x[v], thigh, -((d - limit) * w * f));
            }
        }
    }
}
