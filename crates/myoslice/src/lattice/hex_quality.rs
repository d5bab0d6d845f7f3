//! Whether a hexahedron is valid the way a user's tools judge it: all eight corner
//! Jacobians positive (ParaView's and VTK's test, `vtkMeshQuality`'s hexahedron
//! Jacobian). A hexahedron can keep a positive volume while one corner folds over; the
//! volume alone does not see it.

use glam::Vec3;

/// For each VTK hexahedron corner: the corner and its three edge neighbours in
/// right-handed order.
pub(crate) const HEX_CORNERS: [[usize; 4]; 8] = [
    [0, 1, 3, 4],
    [1, 2, 0, 5],
    [2, 3, 1, 6],
    [3, 0, 2, 7],
    [4, 7, 5, 0],
    [5, 4, 6, 1],
    [6, 5, 7, 2],
    [7, 6, 4, 3],
];

/// The Jacobian at corner `c` (one of [`HEX_CORNERS`]) of the hexahedron with corners `p`.
#[inline]
pub(crate) fn corner_jacobian(p: &[Vec3; 8], c: [usize; 4]) -> f32 {
    let o = p[c[0]];
    (p[c[1]] - o).dot((p[c[2]] - o).cross(p[c[3]] - o))
}

/// The eight corner Jacobians of hexahedron `h` of `x` (VTK corner order; m³: six times
/// each corner tetrahedron's volume).
#[inline]
pub fn corner_jacobians(x: &[Vec3], h: &[u32; 8]) -> [f32; 8] {
    let p = h.map(|i| x[i as usize]);
    HEX_CORNERS.map(|c| corner_jacobian(&p, c))
}

/// The smallest of a hexahedron's eight corner Jacobians.
///
/// ```
/// use glam::Vec3;
/// use myoslice::lattice::min_corner_jacobian;
/// // A unit cube in VTK order: bottom face counter-clockwise, then the top face.
/// let x = [
///     Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y,
///     Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::ONE, Vec3::new(0.0, 1.0, 1.0),
/// ];
/// let h = [0, 1, 2, 3, 4, 5, 6, 7];
/// assert!((min_corner_jacobian(&x, &h) - 1.0).abs() < 1e-6);
/// ```
#[inline]
pub fn min_corner_jacobian(x: &[Vec3], h: &[u32; 8]) -> f32 {
    corner_jacobians(x, h)
        .into_iter()
        .fold(f32::INFINITY, f32::min)
}

/// Whether every corner Jacobian of hexahedron `h` of `x` is positive.
#[inline]
pub fn hex_is_valid(x: &[Vec3], h: &[u32; 8]) -> bool {
    min_corner_jacobian(x, h) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::hex_volume_f32;

    fn cube() -> Vec<Vec3> {
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::ONE,
            Vec3::new(0.0, 1.0, 1.0),
        ]
    }

    const H: [u32; 8] = [0, 1, 2, 3, 4, 5, 6, 7];

    #[test]
    fn a_cube_is_valid_and_its_mirror_is_not() {
        let x = cube();
        assert!(hex_is_valid(&x, &H));
        let mirrored: Vec<Vec3> = x.iter().map(|p| Vec3::new(-p.x, p.y, p.z)).collect();
        assert!(!hex_is_valid(&mirrored, &H));
    }

    #[test]
    fn a_folded_corner_is_invalid_though_the_volume_stays_positive() {
        let mut x = cube();
        // Corner 6 pulled through the opposite face's diagonal plane: the element keeps
        // most of its volume, but corner 6's three edges turn left-handed.
        x[6] = Vec3::new(0.2, 0.2, 0.3);
        assert!(hex_volume_f32(&x, &H) > 0.0);
        assert!(!hex_is_valid(&x, &H));
    }
}
