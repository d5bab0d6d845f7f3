//! Inner fat on its muscle: where each inner fat vertex over a muscle is pulled, and the
//! pull (the paper's rule, with the fat gliding on the muscle's fascia).

use crate::par::*;
use glam::{Quat, Vec3};

use super::MuscleShape;

/// Share of a muscle surface's sliding (along the fat layer) that drags the fat over it.
const FASCIA_DRAG: f32 = 0.2;

/// Share of the way to its target across the fat layer an inner vertex facing a muscle
/// is pulled each iteration, and along the muscle (see [`pull`]). Pulled along as hard
/// as across, the fat was held where it folded and muscles came out through it; much
/// weaker, more muscle came out (docs/tissue-history.md).
const PULL_ACROSS: f32 = 0.7;
const PULL_ALONG: f32 = 0.15;

/// Where each inner fat vertex facing a muscle (`muscle_ref`: fat vertex → muscle, its
/// vertex and the rest offset from the surface under it) goes this update, with the
/// direction across its fat layer, into `out`.
/// `safe` is the knee fold of the rest shape and `weights` the fold's weight of each
/// vertex; `thigh_turn`, `axis` and `theta` the thigh's rotation, the knee axis and angle.
/// The vertex keeps its rest offset from its muscle vertex turned as the tissue about it
/// turns (the paper's moving vector alone would shear thin fat at large angles).
pub(super) fn targets(
    muscle_ref: &[Option<(u32, u32, Vec3)>],
    muscles: &[MuscleShape],
    fat_rest: &[Vec3],
    (safe, weights): (&[Vec3], &[f32]),
    layers: usize,
    (thigh_turn, axis, theta): (Quat, Vec3, f32),
    out: &mut Vec<(u32, Vec3, Vec3)>,
) {
    out.clear();
    out.par_extend(muscle_ref.par_iter().enumerate().filter_map(|(v, r)| {
        let (m, mv, under_offset) = (*r)?;
        let shape = &muscles[m as usize];
        let turn = thigh_turn * Quat::from_axis_angle(axis, theta * weights[v]);
        let offset = fat_rest[v] - shape.rest[mv as usize];
        let follow = shape.current[mv as usize] + turn * offset;
        // Across the layer the fat follows the muscle fully (a bulge pushes the skin out);
        // along it the muscle glides under its fascia and drags the fat only partly
        // (following its sliding fully shears the elements inside out).
        let (base, outer) = (safe[v], safe[v + layers]);
        let n = (outer - base).normalize_or_zero();
        let d = follow - base;
        let across = n * d.dot(n);
        let along = (d - across) * FASCIA_DRAG;
        // Across it, the fat keeps its rest offset from the muscle's surface where the fat
        // now lies over it, not from the vertex it lay over at rest: a muscle that slides
        // far under the fat (a gastrocnemius as the knee bends) would otherwise carry the
        // fat over its own tapering ends, and through neighbouring tissue. The offset is
        // from the surface under the fat at rest (not from that vertex), so that a tissue
        // at rest stays there.
        let across = shape
            .surface_under(mv, base + along)
            .map_or(across, |q| n * (q + turn * under_offset - base).dot(n));
        Some((v as u32, base + across + along, n))
    }));
}

/// Pulls inner vertices facing a muscle toward their `targets`: across the layer (along
/// the third field) strongly but not rigidly, so that millimetre noise of the muscle
/// surface cannot fold the thin fat elements; along the muscle weakly, so that the fat
/// glides on its fascia where the elements about it pull. Shape matching shares the rest.
pub(super) fn pull(x: &mut [Vec3], targets: &[(u32, Vec3, Vec3)]) {
    for &(v, target, n) in targets {
        let cur = x[v as usize];
        let d = target - cur;
        let across = n * d.dot(n);
        x[v as usize] = cur + across * PULL_ACROSS + (d - across) * PULL_ALONG;
    }
}
