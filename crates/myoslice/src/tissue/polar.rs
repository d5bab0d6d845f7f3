//! Rotation extraction for shape matching: the rotation of the polar decomposition of a
//! 3×3 matrix, by Müller et al. (2016), "A robust method to extract the rotational part of
//! deformations", warm-started from the previous rotation. Branch-free in the inner loop.

use glam::{Mat3, Quat, Vec3};

/// Improves `q` toward the rotation of the polar decomposition of `a` (columns `a0..a2`)
/// with `iters` iterations; returns the new unit quaternion.
#[inline]
pub fn extract_rotation(a: &Mat3, mut q: Quat, iters: usize) -> Quat {
    for _ in 0..iters {
        let r = Mat3::from_quat(q);
        let num = r.x_axis.cross(a.x_axis) + r.y_axis.cross(a.y_axis) + r.z_axis.cross(a.z_axis);
        let den =
            (r.x_axis.dot(a.x_axis) + r.y_axis.dot(a.y_axis) + r.z_axis.dot(a.z_axis)).abs() + 1e-9;
        let omega = num / den;
        let w = omega.length();
        if w < 1e-7 {
            break;
        }
        q = (Quat::from_axis_angle(omega / w, w) * q).normalize();
    }
    q
}

/// One warm-started iteration without trigonometry: the quaternion takes the first-order
/// exponential of the rotation vector ω (exact to second order for the small corrections
/// of a warm start; large ω are clamped to 0.5 rad so the normalisation stays well posed).
/// Returns the new quaternion and its matrix.
#[inline(always)]
pub fn rotation_step(a: &Mat3, q: Quat) -> (Quat, Mat3) {
    let r = Mat3::from_quat(q);
    let num = r.x_axis.cross(a.x_axis) + r.y_axis.cross(a.y_axis) + r.z_axis.cross(a.z_axis);
    let den =
        (r.x_axis.dot(a.x_axis) + r.y_axis.dot(a.y_axis) + r.z_axis.dot(a.z_axis)).abs() + 1e-12;
    let mut w = num / den;
    let len2 = w.length_squared();
    if len2 > 0.25 {
        w *= 0.5 / len2.sqrt();
    }
    // q' = q + ½ (ω, 0) q
    let dq = Quat::from_xyzw(w.x, w.y, w.z, 0.0) * q;
    let q2 = Quat::from_xyzw(
        q.x + 0.5 * dq.x,
        q.y + 0.5 * dq.y,
        q.z + 0.5 * dq.z,
        q.w + 0.5 * dq.w,
    )
    .normalize();
    (q2, Mat3::from_quat(q2))
}

/// The rotation of `a` from scratch (identity start, enough iterations to converge).
pub fn polar_rotation(a: &Mat3) -> Quat {
    extract_rotation(a, Quat::IDENTITY, 64)
}

/// The rotation of the polar decomposition of `a`, exactly: warm-started iterations, and
/// where they have not converged (flat or badly deformed elements), an SVD in f64.
pub fn polar_rotation_exact(a: &Mat3, warm: Quat) -> Quat {
    let q = extract_rotation(a, warm, 20);
    let r = Mat3::from_quat(q);
    let num = r.x_axis.cross(a.x_axis) + r.y_axis.cross(a.y_axis) + r.z_axis.cross(a.z_axis);
    let den =
        (r.x_axis.dot(a.x_axis) + r.y_axis.dot(a.y_axis) + r.z_axis.dot(a.z_axis)).abs() + 1e-12;
    if (num / den).length() < 1e-5 {
        return q;
    }
    let m = nalgebra::Matrix3::from_fn(|i, j| f64::from(a.col(j)[i]));
    let svd = m.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return q;
    };
    let mut rot = u * vt;
    if rot.determinant() < 0.0 {
        let mut u2 = u;
        let k = (0..3)
            .min_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]))
            .unwrap_or(2);
        for i in 0..3 {
            u2[(i, k)] = -u2[(i, k)];
        }
        rot = u2 * vt;
    }
    let m3 = Mat3::from_cols_array(&[
        rot[(0, 0)] as f32,
        rot[(1, 0)] as f32,
        rot[(2, 0)] as f32,
        rot[(0, 1)] as f32,
        rot[(1, 1)] as f32,
        rot[(2, 1)] as f32,
        rot[(0, 2)] as f32,
        rot[(1, 2)] as f32,
        rot[(2, 2)] as f32,
    ]);
    Quat::from_mat3(&m3).normalize()
}

/// `Σ p_i r_iᵀ` for current relative positions `p` and rest relative positions `r`.
#[inline]
pub fn covariance(p: &[Vec3], r: &[Vec3]) -> Mat3 {
    let mut c0 = Vec3::ZERO;
    let mut c1 = Vec3::ZERO;
    let mut c2 = Vec3::ZERO;
    for (pi, ri) in p.iter().zip(r) {
        c0 += *pi * ri.x;
        c1 += *pi * ri.y;
        c2 += *pi * ri.z;
    }
    Mat3::from_cols(c0, c1, c2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotation_of_a_rotated_stretch_is_recovered() {
        let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 1.3);
        let stretch = Mat3::from_diagonal(Vec3::new(1.4, 0.7, 1.1));
        let a = Mat3::from_quat(rot) * stretch;
        let q = polar_rotation(&a);
        assert!(q.angle_between(rot) < 1e-4, "{}", q.angle_between(rot));
        // Warm start from nearby converges in a couple of iterations.
        let q2 = extract_rotation(&a, rot * Quat::from_rotation_z(0.1), 8);
        assert!(q2.angle_between(rot) < 1e-3);
    }

    #[test]
    fn trigonometry_free_steps_converge_from_a_warm_start_and_from_far() {
        let rot = Quat::from_axis_angle(Vec3::new(-0.3, 0.8, 0.5).normalize(), 2.1);
        let a = Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::new(0.6, 1.3, 0.9));
        // Distance between rotations as the largest move of a unit axis (f32-safe).
        let err = |q: Quat| {
            [Vec3::X, Vec3::Y, Vec3::Z]
                .iter()
                .map(|e| (q * *e - rot * *e).length())
                .fold(0.0f32, f32::max)
        };
        let mut q = rot * Quat::from_rotation_x(0.05);
        for _ in 0..8 {
            q = rotation_step(&a, q).0;
        }
        assert!(err(q) < 1e-4, "warm start: {}", err(q));
        // From the identity the 0.5 rad clamp keeps each step sane; it still gets there.
        let mut q = Quat::IDENTITY;
        for _ in 0..60 {
            q = rotation_step(&a, q).0;
        }
        assert!(err(q) < 1e-3, "from the identity: {}", err(q));
        assert!((q.length() - 1.0).abs() < 1e-5);
    }
}
