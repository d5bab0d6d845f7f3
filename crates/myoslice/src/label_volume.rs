//! A labelled voxel volume: every voxel carries a label id of a [`LabelTable`].

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

    /// The same voxels stored the way the lattice builder slices them: index i along the
    /// world axis x (right), j along y (anterior), k along z (superior, the leg's long
    /// axis), each increasing. A scan saved in another order (sagittal or coronal
    /// slices, a left-posterior-superior frame, axes flipped) is permuted and flipped,
    /// voxel for voxel: no resampling, the world position of every voxel unchanged. Each
    /// voxel axis goes to the world axis it runs most along (an oblique scan keeps its
    /// tilt in the affine).
    ///
    /// ```
    /// use myoslice::LabelVolume;
    /// // Two voxels along k, which runs toward the subject's left (−x).
    /// let a = [[0.0, 0.0, -2.0, 10.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]];
    /// let v = LabelVolume::new([1, 1, 2], a, vec![7, 9]).unwrap();
    /// let c = v.canonical();
    /// assert_eq!(c.dims(), [2, 1, 1]);
    /// assert_eq!(c.data(), &[9, 7]); // now increasing x
    /// assert_eq!(c.affine()[0], [2.0, 0.0, 0.0, 8.0]);
    /// ```
    pub fn canonical(self) -> Self {
        let a = &self.affine;
        let sp = self.spacing_mm();
        // Voxel axis of each world axis: the most aligned pairs first (direction cosines,
        // whatever the voxel sizes), each axis once.
        let mut pairs: Vec<(f64, usize, usize)> = (0..3)
            .flat_map(|r| (0..3).map(move |c| (a[r][c].abs() / sp[c], r, c)))
            .collect();
        pairs.sort_by(|p, q| q.0.total_cmp(&p.0).then((p.1, p.2).cmp(&(q.1, q.2))));
        let mut axis_of = [usize::MAX; 3];
        let mut used = [false; 3];
        for (_, r, c) in pairs {
            if axis_of[r] == usize::MAX && !used[c] {
                axis_of[r] = c;
                used[c] = true;
            }
        }
        let flip: [bool; 3] = std::array::from_fn(|r| a[r][axis_of[r]] < 0.0);
        if axis_of == [0, 1, 2] && flip == [false; 3] {
            return self;
        }
        let dims: [usize; 3] = std::array::from_fn(|r| self.dims[axis_of[r]]);
        // New voxel (i, j, k) is old voxel `src`, whose index along old axis axis_of[r]
        // is the new index along r (or its mirror).
        let mut data = Vec::with_capacity(self.data.len());
        let mut src = [0usize; 3];
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    for (r, n) in [i, j, k].into_iter().enumerate() {
                        src[axis_of[r]] = if flip[r] { dims[r] - 1 - n } else { n };
                    }
                    data.push(self.get(src[0], src[1], src[2]));
                }
            }
        }
        let mut affine = [[0.0f64; 4]; 3];
        for (row, old) in affine.iter_mut().zip(a) {
            let mut origin = old[3];
            for r in 0..3 {
                let c = axis_of[r];
                let step = if flip[r] { -old[c] } else { old[c] };
                row[r] = step;
                if flip[r] {
                    origin += old[c] * (self.dims[c] - 1) as f64;
                }
            }
            row[3] = origin;
        }
        Self { dims, affine, data }
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

    /// Any order and direction of the axes comes back to the same canonical volume,
    /// every voxel at the same world position.
    #[test]
    fn canonical_order_undoes_any_permutation_and_flip_of_the_axes() {
        let dims = [3, 4, 5];
        let data: Vec<u16> = (0..60).collect();
        let v = LabelVolume::axis_aligned(dims, [1.0, 2.0, 3.0], [10.0, 20.0, 30.0], data).unwrap();
        let world = |v: &LabelVolume| {
            let mut out: Vec<(u16, [i64; 3])> = Vec::new();
            let [nx, ny, nz] = v.dims();
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let w = v.voxel_to_world_m([i as f64, j as f64, k as f64]);
                        out.push((v.get(i, j, k), w.map(|x| (x * 1e6).round() as i64)));
                    }
                }
            }
            out.sort();
            out
        };
        for perm in [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ] {
            for flips in 0..8 {
                // Store `v` with its axes permuted and flipped.
                let nd: [usize; 3] = std::array::from_fn(|c| dims[perm[c]]);
                let mut data = Vec::new();
                for k in 0..nd[2] {
                    for j in 0..nd[1] {
                        for i in 0..nd[0] {
                            let mut o = [0; 3];
                            for (c, n) in [i, j, k].into_iter().enumerate() {
                                let f = flips >> c & 1 == 1;
                                o[perm[c]] = if f { nd[c] - 1 - n } else { n };
                            }
                            data.push(v.get(o[0], o[1], o[2]));
                        }
                    }
                }
                let mut a = [[0.0; 4]; 3];
                for r in 0..3 {
                    a[r][3] = v.affine()[r][3];
                }
                for c in 0..3 {
                    let r = perm[c];
                    let step = v.affine()[r][r];
                    if flips >> c & 1 == 1 {
                        a[r][c] = -step;
                        a[r][3] += step * (nd[c] - 1) as f64;
                    } else {
                        a[r][c] = step;
                    }
                }
                let stored = LabelVolume::new(nd, a, data).unwrap();
                assert_eq!(world(&stored), world(&v), "{perm:?} {flips}");
                assert_eq!(stored.canonical(), v, "{perm:?} {flips}");
            }
        }
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
