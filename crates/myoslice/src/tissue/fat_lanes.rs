//! The fat kernel on four elements at once: each SIMD lane holds one element (struct of
//! arrays across elements), so the covariance, the warm-started rotation step and the
//! goals run four-wide with no shuffles; only gathering corners and scattering goals
//! touch lanes one by one. Same arithmetic as [`super::polar::rotation_step`].

use glam::{Quat, Vec3, Vec3A, Vec4};

/// Elements per group.
pub const LANES: usize = 4;

/// Rest corners of a group: `[corner][axis]`, lanes = elements.
pub type RestLanes = [[Vec4; 3]; 8];

/// The rest-relative corners of up to four elements as lanes (missing lanes repeat the
/// first element).
pub fn rest_lanes(rel: &[[Vec3; 8]]) -> RestLanes {
    let lane = |l: usize| &rel[l.min(rel.len() - 1)];
    std::array::from_fn(|i| {
        std::array::from_fn(|a| Vec4::from_array(std::array::from_fn(|l| lane(l)[i][a])))
    })
}

/// A 3×3 matrix per lane, row-major: `m[row][col]`.
type Mat = [[Vec4; 3]; 3];

fn mat_of_quat([x, y, z, w]: [Vec4; 4]) -> Mat {
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, xy, xz) = (x * x2, x * y2, x * z2);
    let (yy, yz, zz) = (y * y2, y * z2, z * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let one = Vec4::ONE;
    [
        [one - (yy + zz), xy - wz, xz + wy],
        [xy + wz, one - (xx + zz), yz - wx],
        [xz - wy, yz + wx, one - (xx + yy)],
    ]
}

/// Per-lane `1 / sqrt(v)` (scalar square roots: glam's Vec4 has none lane-wise).
fn inv_sqrt(v: Vec4) -> Vec4 {
    Vec4::from_array(v.to_array().map(|s| 1.0 / s.sqrt()))
}

/// One pass over a group: reads the corners of `hexes` from `x`, steps the rotations
/// `rot` (warm start) and adds each active element's corner goals into `sum` at `local`.
#[allow(clippy::too_many_arguments)] // the kernel's arrays, passed apart on purpose
pub fn group_pass(
    x: &[Vec3],
    hexes: &[[u32; 8]],
    rest: &RestLanes,
    rot: &mut [Quat],
    active: &[bool],
    local: &[[u16; 8]],
    sum: &mut [Vec3A],
) {
    let n = rot.len();
    // Corners and centroid.
    let mut p = [[Vec4::ZERO; 3]; 8];
    let mut c = [Vec4::ZERO; 3];
    for i in 0..8 {
        let pt: [Vec3; LANES] = std::array::from_fn(|l| x[hexes[l.min(n - 1)][i] as usize]);
        for a in 0..3 {
            p[i][a] = Vec4::new(pt[0][a], pt[1][a], pt[2][a], pt[3][a]);
            c[a] += p[i][a];
        }
    }
    let c = c.map(|v| v * 0.125);
    // A = Σ (p − c) rᵀ.
    let mut am = [[Vec4::ZERO; 3]; 3];
    for i in 0..8 {
        let d = [p[i][0] - c[0], p[i][1] - c[1], p[i][2] - c[2]];
        for (row, dr) in am.iter_mut().zip(d) {
            for (a, r) in row.iter_mut().zip(rest[i]) {
                *a += dr * r;
            }
        }
    }
    // One warm-started rotation step per lane.
    let q: [Vec4; 4] = std::array::from_fn(|k| {
        Vec4::from_array(std::array::from_fn(|l| rot[l.min(n - 1)].to_array()[k]))
    });
    let r = mat_of_quat(q);
    let mut num = [Vec4::ZERO; 3];
    let mut den = Vec4::ZERO;
    for j in 0..3 {
        let (u, v) = ([r[0][j], r[1][j], r[2][j]], [am[0][j], am[1][j], am[2][j]]);
        num[0] += u[1] * v[2] - u[2] * v[1];
        num[1] += u[2] * v[0] - u[0] * v[2];
        num[2] += u[0] * v[1] - u[1] * v[0];
        den += u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    }
    let inv_den = Vec4::ONE / (den.abs() + Vec4::splat(1e-12));
    let mut w = num.map(|v| v * inv_den);
    let len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    // Corrections beyond 0.5 rad are clamped (as in the scalar step).
    let clamp = Vec4::from_array(
        len2.to_array()
            .map(|s| if s > 0.25 { 0.5 / s.sqrt() } else { 1.0 }),
    );
    w = w.map(|v| v * clamp);
    let [qx, qy, qz, qw] = q;
    let half = Vec4::splat(0.5);
    let q2 = [
        qx + half * (w[0] * qw + w[1] * qz - w[2] * qy),
        qy + half * (w[1] * qw + w[2] * qx - w[0] * qz),
        qz + half * (w[0] * qy - w[1] * qx + w[2] * qw),
        qw - half * (w[0] * qx + w[1] * qy + w[2] * qz),
    ];
    let inv = inv_sqrt(q2[0] * q2[0] + q2[1] * q2[1] + q2[2] * q2[2] + q2[3] * q2[3]);
    let q2 = q2.map(|v| v * inv);
    let m = mat_of_quat(q2);
    let qa = q2.map(|v| v.to_array());
    for (l, q) in rot.iter_mut().enumerate() {
        if active[l] {
            *q = Quat::from_xyzw(qa[0][l], qa[1][l], qa[2][l], qa[3][l]);
        }
    }
    // Goals c + M r, scattered lane by lane.
    for i in 0..8 {
        let r = rest[i];
        let g: [[f32; 4]; 3] = std::array::from_fn(|a| {
            (c[a] + m[a][0] * r[0] + m[a][1] * r[1] + m[a][2] * r[2]).to_array()
        });
        for l in 0..n {
            if active[l] {
                sum[local[l][i] as usize] += Vec3A::new(g[0][l], g[1][l], g[2][l]);
            }
        }
    }
}
