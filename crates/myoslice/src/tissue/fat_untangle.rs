//! Where one fat vertex goes to untangle the elements about it: simultaneous untangling
//! and smoothing (Escobar, Rodríguez, Montenegro, Montero, González-Yuste, 2003), on the
//! corner tetrahedra of the hexahedra.
//!
//! Each corner tetrahedron a vertex takes part in is measured against its rest shape,
//! `S = A W⁻¹` (its edges now, times the inverse of its edges at rest), by
//! `|S|² / (3 h(σ)^⅔)`, with `σ = det S` (the corner's Jacobian over its rest
//! value) and `h(s) = ½ (s + √(s² + 4δ²))`. For δ = 0 this is a barrier at the fold that is
//! smallest for the rest shape (turned); for δ > 0 it is finite on folded corners too
//! and still falls as they unfold, so a vertex whose corners pull against one another
//! finds the place that is best for all of them at once, where projecting it onto one
//! corner's bound after the other stalled. The vertex minimises the sum by damped Newton
//! steps (the Hessian from differences of the exact gradient), in double precision about
//! its starting place.

use glam::{DMat3, DVec3, Vec3};

use crate::lattice::HEX_CORNERS;

/// Newton steps per vertex and visit: the sweeps visit it again while an element about
/// it is folded. One unfolded as many elements as six at a fifth of the cost.
const NEWTON_STEPS: usize = 1;

/// Farthest (m) a vertex moves in one visit: under half an element's size.
const MAX_STEP_M: f64 = 0.002;

/// Step (m) of the differences that give the Hessian: a thousandth of an element.
const DIFF_M: f64 = 5e-6;

/// The regularisation's scale: δ² = ε (ε − σ_min) while the worst corner's σ is below ε
/// (Escobar et al.'s choice).
const EPSILON: f64 = 0.01;

/// One corner tetrahedron about the vertex: its four points (about the vertex's start),
/// which of them is the vertex, and the inverse of its rest edges.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CornerTerm {
    points: [DVec3; 4],
    slot: usize,
    rest_inverse: DMat3,
    /// d S / d (vertex) = e_k ⊗ `lever` (see the module's notes).
    lever: DVec3,
}

/// The δ² that makes every term finite when the worst corner's σ is `sigma_min`.
pub(crate) fn delta_squared(sigma_min: f64) -> f64 {
    if sigma_min < EPSILON {
        EPSILON * (EPSILON - sigma_min)
    } else {
        0.0
    }
}

/// The smallest σ (Jacobian over its rest value) among the corner tetrahedra of an
/// element (its corners `now` and at `rest`) that contain its corner `k`: what sets δ
/// (see [`delta_squared`]) before [`push_terms`] builds them.
pub(crate) fn sigma_min(now: &[Vec3; 8], rest: &[Vec3; 8], k: usize) -> f64 {
    let det = |p: [DVec3; 4]| DMat3::from_cols(p[1] - p[0], p[2] - p[0], p[3] - p[0]).determinant();
    HEX_CORNERS
        .iter()
        .filter(|corner| corner.contains(&k))
        .map(|corner| {
            det(corner.map(|i| now[i].as_dvec3())) / det(corner.map(|i| rest[i].as_dvec3()))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The corner tetrahedra of an element (its corners `now` and at `rest`) that contain
/// its corner `k`, appended to `out`, relative to `origin`.
pub(crate) fn push_terms(
    now: &[Vec3; 8],
    rest: &[Vec3; 8],
    k: usize,
    origin: Vec3,
    out: &mut Vec<CornerTerm>,
) {
    for corner in HEX_CORNERS {
        let Some(slot) = corner.iter().position(|&i| i == k) else {
            continue;
        };
        let points = corner.map(|i| (now[i] - origin).as_dvec3());
        let r = corner.map(|i| rest[i].as_dvec3());
        let w = DMat3::from_cols(r[1] - r[0], r[2] - r[0], r[3] - r[0]);
        let rest_inverse = w.inverse();
        let lever = if slot == 0 {
            -(rest_inverse.row(0) + rest_inverse.row(1) + rest_inverse.row(2))
        } else {
            rest_inverse.row(slot - 1)
        };
        out.push(CornerTerm {
            points,
            slot,
            rest_inverse,
            lever,
        });
    }
}

impl CornerTerm {
    fn shape(&self, p: DVec3) -> DMat3 {
        let mut q = self.points;
        q[self.slot] = p;
        DMat3::from_cols(q[1] - q[0], q[2] - q[0], q[3] - q[0]) * self.rest_inverse
    }

    #[cfg(test)]
    fn sigma(&self, p: DVec3) -> f64 {
        self.shape(p).determinant()
    }

    /// The term's value and gradient with the vertex at `p`.
    fn value_gradient(&self, p: DVec3, delta2: f64) -> (f64, DVec3) {
        let s = self.shape(p);
        let (s0, s1, s2) = (s.x_axis, s.y_axis, s.z_axis);
        let sigma = s.determinant();
        let root = (sigma * sigma + 4.0 * delta2).sqrt();
        let h = 0.5 * (sigma + root);
        if h <= 0.0 || !h.is_finite() {
            return (f64::INFINITY, DVec3::ZERO);
        }
        let n2 = s0.length_squared() + s1.length_squared() + s2.length_squared();
        let c = self.lever;
        let d_n2 = 2.0 * (s * c);
        let d_sigma = c.x * s1.cross(s2) + c.y * s2.cross(s0) + c.z * s0.cross(s1);
        let d_h = 0.5 * (1.0 + sigma / root.max(1e-300)) * d_sigma;
        let h23 = h.powf(2.0 / 3.0);
        let value = n2 / (3.0 * h23);
        let grad = d_n2 / (3.0 * h23) - (2.0 / 9.0) * n2 / (h23 * h) * d_h;
        (value, grad)
    }
}

/// The sum of the terms' values and gradients with the vertex at `p`.
fn total(terms: &[CornerTerm], p: DVec3, delta2: f64) -> (f64, DVec3) {
    terms.iter().fold((0.0, DVec3::ZERO), |(f, g), t| {
        let (tf, tg) = t.value_gradient(p, delta2);
        (f + tf, g + tg)
    })
}

/// How far the vertex whose corner tetrahedra are `terms` (relative to its start) moves
/// to lower their sum; None if it cannot.
pub(crate) fn untangle_move(terms: &[CornerTerm], delta2: f64) -> Option<Vec3> {
    let mut p = DVec3::ZERO;
    let (mut f, mut g) = total(terms, p, delta2);
    if !f.is_finite() {
        return None;
    }
    for _ in 0..NEWTON_STEPS {
        let cols = [DVec3::X, DVec3::Y, DVec3::Z]
            .map(|e| (total(terms, p + e * DIFF_M, delta2).1 - g) / DIFF_M);
        let h = DMat3::from_cols(cols[0], cols[1], cols[2]);
        let h = 0.5 * (h + h.transpose());
        // Damped until the step goes downhill (Levenberg).
        let scale = (h.x_axis.x.abs() + h.y_axis.y.abs() + h.z_axis.z.abs()) / 3.0;
        let mut lambda = 0.0;
        let mut step = None;
        for _ in 0..8 {
            let m = h + DMat3::from_diagonal(DVec3::splat(lambda));
            if m.determinant().abs() > 1e-300 {
                let d = -(m.inverse() * g);
                if d.is_finite() && d.dot(g) < 0.0 {
                    step = Some(d);
                    break;
                }
            }
            lambda = if lambda == 0.0 {
                1e-3 * scale.max(1e-12)
            } else {
                lambda * 10.0
            };
        }
        let room = MAX_STEP_M - p.length();
        if room <= 1e-9 {
            break;
        }
        let mut d = step.unwrap_or(-g);
        let len = d.length();
        if len > room {
            d *= room / len;
        }
        let mut moved = false;
        for _ in 0..12 {
            let (nf, ng) = total(terms, p + d, delta2);
            if nf < f {
                (p, f, g) = (p + d, nf, ng);
                moved = true;
                break;
            }
            d *= 0.5;
        }
        if !moved || d.length() < 1e-9 {
            break;
        }
    }
    (p != DVec3::ZERO && p.is_finite()).then(|| p.as_vec3())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> [Vec3; 8] {
        [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::ONE,
            Vec3::new(0.0, 1.0, 1.0),
        ]
        .map(|p| p * 0.005)
    }

    #[test]
    fn the_gradient_is_the_energy_s_slope() {
        let rest = cube();
        let mut now = rest;
        now[6] += Vec3::new(-0.004, -0.003, -0.0045);
        now[2] += Vec3::new(0.001, -0.002, 0.0005);
        for k in [0, 2, 6] {
            let mut terms = Vec::new();
            push_terms(&now, &rest, k, now[k], &mut terms);
            // σ of the terms at the vertex's start is what `sigma_min` gives (to the
            // rounding of the terms' points, taken about the vertex in single precision).
            let s_min = terms
                .iter()
                .map(|t| t.sigma(t.points[t.slot]))
                .fold(f64::MAX, f64::min);
            let direct = sigma_min(&now, &rest, k);
            assert!(
                (s_min - direct).abs() <= 1e-5 * s_min.abs().max(1.0),
                "{s_min} {direct}"
            );
            let least = delta_squared(s_min - 0.1);
            for delta2 in [least, least + 1e-3] {
                let p = DVec3::new(1e-4, -2e-4, 5e-5);
                let (_, g) = total(&terms, p, delta2);
                for e in [DVec3::X, DVec3::Y, DVec3::Z] {
                    let h = 1e-8;
                    let fd = (total(&terms, p + e * h, delta2).0
                        - total(&terms, p - e * h, delta2).0)
                        / (2.0 * h);
                    let a = g.dot(e);
                    assert!((fd - a).abs() <= 1e-4 * a.abs().max(1.0), "{k} {fd} {a}");
                }
            }
        }
    }

    #[test]
    fn a_corner_pushed_through_its_element_unfolds_it() {
        let rest = cube();
        let mut now = rest;
        // Corner 6 pushed through the opposite corner: folded.
        now[6] = Vec3::splat(-0.001);
        let mut p = now[6];
        for _ in 0..20 {
            let mut terms = Vec::new();
            let mut q = now;
            q[6] = p;
            push_terms(&q, &rest, 6, p, &mut terms);
            let Some(d) = untangle_move(&terms, delta_squared(sigma_min(&q, &rest, 6))) else {
                break;
            };
            p += d;
        }
        now[6] = p;
        let j = crate::lattice::corner_jacobians(&now, &[0, 1, 2, 3, 4, 5, 6, 7]);
        let r = crate::lattice::corner_jacobians(&rest, &[0, 1, 2, 3, 4, 5, 6, 7]);
        assert!(j.iter().zip(&r).all(|(j, r)| *j > 0.1 * r), "{j:?}");
    }
}
