//! A labelled voxel volume: every voxel carries a label id of a [`LabelTable`].

mod frame;

use crate::error::{Error, Result};
use crate::label_table::LabelTable;

/// A 3-D label volume with its voxel-to-world mapping.
///
/// Voxel `(i, j, k)` has its centre at `affine · (i, j, k, 1)` in millimetres, in the body
/// frame (+x toward the subject's right, +y anterior, +z superior). The third index `k` is
/// the slice index.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelVolume {
    dims: [usize; 3],
    affine: [[f64; 4]; 3],
    data: Vec<u16>,
}

impl LabelVolume {
    /// Wraps label data stored x-fastest (`i + nx·(j + ny·k)`).
    pub fn new(dims: [usize; 3], affine: [[f64; 4]; 3], data: Vec<u16>) -> Result<Self> {
        if dims.contains(&0) {
            return Err(Error::Build(format!(
                "volume has an empty dimension {dims:?}"
            )));
        }
        let n = dims[0]
            .checked_mul(dims[1])
            .and_then(|v| v.checked_mul(dims[2]))
            .ok_or_else(|| Error::Build(format!("volume dimensions {dims:?} overflow")))?;
        if data.len() != n {
            return Err(Error::Build(format!(
                "volume {dims:?} needs {n} voxels, got {}",
                data.len()
            )));
        }
        if affine.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::Build("volume affine is not finite".into()));
        }
        let vol = Self { dims, affine, data };
        if vol.voxel_volume_mm3().abs() < 1e-12 {
            return Err(Error::Build("volume affine is singular".into()));
        }
        Ok(vol)
    }

    /// An axis-aligned volume with the given voxel size and origin (both mm).
    pub fn axis_aligned(
        dims: [usize; 3],
        spacing_mm: [f64; 3],
        origin_mm: [f64; 3],
        data: Vec<u16>,
    ) -> Result<Self> {
        let mut a = [[0.0; 4]; 3];
        for r in 0..3 {
            a[r][r] = spacing_mm[r];
            a[r][3] = origin_mm[r];
        }
        Self::new(dims, a, data)
    }

    /// Number of voxels along i, j, k.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Voxel-to-world affine (mm), rows x, y, z.
    pub fn affine(&self) -> &[[f64; 4]; 3] {
        &self.affine
    }

    /// Voxel edge lengths (mm) along i, j, k.
    pub fn spacing_mm(&self) -> [f64; 3] {
        let a = &self.affine;
        let col = |c: usize| (a[0][c].powi(2) + a[1][c].powi(2) + a[2][c].powi(2)).sqrt();
        [col(0), col(1), col(2)]
    }

    /// Signed volume of one voxel (mm³); negative when the affine flips handedness.
    pub fn voxel_volume_mm3(&self) -> f64 {
        let a = &self.affine;
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    }

    /// All labels, x fastest.
    pub fn data(&self) -> &[u16] {
        &self.data
    }

    /// Label at voxel (i, j, k), which must be inside.
    pub fn get(&self, i: usize, j: usize, k: usize) -> u16 {
        self.data[i + self.dims[0] * (j + self.dims[1] * k)]
    }

    /// One slice (fixed k), x fastest.
    pub fn slice(&self, k: usize) -> &[u16] {
        let n = self.dims[0] * self.dims[1];
        &self.data[k * n..(k + 1) * n]
    }

    /// World position (metres) of a continuous voxel coordinate.
    pub fn voxel_to_world_m(&self, v: [f64; 3]) -> [f64; 3] {
        let a = &self.affine;
        let mut out = [0.0; 3];
        for (r, o) in out.iter_mut().enumerate() {
            *o = (a[r][0] * v[0] + a[r][1] * v[1] + a[r][2] * v[2] + a[r][3]) * 1e-3;
        }
        out
    }

    /// Voxel count per label id (index = id).
    pub fn histogram(&self) -> Vec<u64> {
        let mut h = vec![0u64; 1 << 16];
        for &v in &self.data {
            h[v as usize] += 1;
        }
        let last = h.iter().rposition(|&c| c > 0).map_or(0, |p| p + 1);
        h.truncate(last);
        h
    }

    /// Checks that every label present is defined in `table`.
    pub fn check_labels(&self, table: &LabelTable) -> Result<()> {
        for (id, &count) in self.histogram().iter().enumerate() {
            if count > 0 && table.get(id as u16).is_none() {
                return Err(Error::UnknownLabel {
                    id: id as u32,
                    voxels: count,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_shapes_are_rejected() {
        assert!(LabelVolume::axis_aligned([0, 1, 1], [1.0; 3], [0.0; 3], vec![]).is_err());
        assert!(LabelVolume::axis_aligned([2, 2, 2], [1.0; 3], [0.0; 3], vec![0; 7]).is_err());
        assert!(LabelVolume::axis_aligned([1, 1, 1], [0.0, 1.0, 1.0], [0.0; 3], vec![0]).is_err());
    }

    #[test]
    fn world_mapping_uses_the_affine_in_metres() {
        let v =
            LabelVolume::axis_aligned([2, 2, 2], [1.0, 2.0, 5.0], [10.0, 0.0, -5.0], vec![0; 8])
                .unwrap();
        let w = v.voxel_to_world_m([1.0, 1.0, 1.0]);
        assert!((w[0] - 0.011).abs() < 1e-12 && (w[1] - 0.002).abs() < 1e-12 && w[2].abs() < 1e-12);
        assert_eq!(v.spacing_mm(), [1.0, 2.0, 5.0]);
    }
}
