//! The body frame the lattice builder slices in: voxel axes along x, y, z, each
//! increasing. A scan stored in another order is reordered voxel for voxel; an oblique
//! one is resampled.

use crate::par::*;

use super::LabelVolume;
use crate::error::{Error, Result};

/// The drift (in voxels) across the whole volume below which a tilt of the voxel axes is
/// read as none: the rounding noise of direction cosines stored as 32-bit floats.
const ALIGNED_DRIFT_VOXELS: f64 = 0.1;

/// Most voxels a resampled volume may have, against the scan's own: a tilt of 45° about
/// two axes at once needs about 3.
const MAX_GROWTH: usize = 8;

impl LabelVolume {
    /// The same voxels stored the way the lattice builder slices them: index i along the
    /// world axis x (right), j along y (anterior), k along z (superior, the leg's long
    /// axis), each increasing. A scan saved in another order (sagittal or coronal
    /// slices, a left-posterior-superior frame, axes flipped) is permuted and flipped,
    /// voxel for voxel: no resampling, the world position of every voxel unchanged. Each
    /// voxel axis goes to the world axis it runs most along (an oblique scan keeps its
    /// tilt in the affine: [`Self::in_frame`] resamples it).
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

    /// How far (in voxels of the axis it drifts along) the most tilted voxel axis drifts
    /// across the volume: 0 for a volume in the body frame's order with no tilt.
    fn tilt_drift_voxels(&self) -> f64 {
        let a = &self.affine;
        let mut worst: f64 = 0.0;
        for r in 0..3 {
            let along = a[r][r].abs().max(f64::MIN_POSITIVE);
            for c in (0..3).filter(|&c| c != r) {
                worst = worst.max(a[r][c].abs() * (self.dims[c] - 1) as f64 / along);
            }
        }
        worst
    }

    /// True when the voxels are stored as the lattice builder slices them: i along x,
    /// j along y, k along z, each increasing, and no tilt beyond a tenth of a voxel
    /// across the volume.
    pub fn is_in_frame(&self) -> bool {
        (0..3).all(|r| self.affine[r][r] > 0.0) && self.tilt_drift_voxels() < ALIGNED_DRIFT_VOXELS
    }

    /// The volume in the body frame: [`Self::canonical`] order, and an oblique scan
    /// (voxel axes tilted against x, y, z) resampled onto an axis-aligned grid of the
    /// scan's own voxel size by nearest neighbour (labels cannot be interpolated). The
    /// new grid covers the labelled voxels with half a voxel to spare; voxels outside
    /// the scan are label 0. A tilt that drifts less than a tenth of a voxel across the
    /// volume is rounding noise and is dropped without resampling.
    ///
    /// ```
    /// use myoslice::LabelVolume;
    /// // A 4 x 4 x 8 block of label 3, its k axis tilted 10° toward +y.
    /// let (s, c) = 10f64.to_radians().sin_cos();
    /// let a = [[1.0, 0.0, 0.0, 0.0], [0.0, c, s, 0.0], [0.0, -s, c, 0.0]];
    /// let v = LabelVolume::new([4, 4, 8], a, vec![3; 128]).unwrap();
    /// let f = v.in_frame().unwrap();
    /// assert!(f.is_in_frame());
    /// let n = f.data().iter().filter(|&&l| l == 3).count();
    /// assert!((n as f64 - 128.0).abs() < 13.0, "{n}");
    /// ```
    pub fn in_frame(self) -> Result<Self> {
        let v = self.canonical();
        if v.is_in_frame() {
            return Ok(v);
        }
        if v.tilt_drift_voxels() < ALIGNED_DRIFT_VOXELS {
            // Only a flip is left, which canonical() handles: cannot happen, but keep the
            // volume as it is rather than resample.
            return Ok(v);
        }
        v.resampled()
    }

    /// Nearest-neighbour resampling onto the axis-aligned grid of [`Self::in_frame`].
    fn resampled(&self) -> Result<Self> {
        let a = &self.affine;
        let m = nalgebra::Matrix3::from_fn(|r, c| a[r][c]);
        let inv = m.try_inverse().ok_or_else(|| {
            Error::Build("the volume's voxel-to-world transform cannot be inverted".into())
        })?;
        let t = nalgebra::Vector3::new(a[0][3], a[1][3], a[2][3]);
        let spacing = self.spacing_mm();
        let [nx, ny, nz] = self.dims;
        // World bounds of the labelled voxels' centres: along a row the world position
        // is linear in i, so its first and last labelled voxels bound it.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let take = |lo: &mut [f64; 3], hi: &mut [f64; 3], i: usize, j: usize, k: usize| {
            let p = m * nalgebra::Vector3::new(i as f64, j as f64, k as f64) + t;
            for r in 0..3 {
                lo[r] = lo[r].min(p[r]);
                hi[r] = hi[r].max(p[r]);
            }
        };
        for (row, labels) in self.data.chunks_exact(nx).enumerate() {
            let (j, k) = (row % ny, row / ny);
            if let (Some(first), Some(last)) = (
                labels.iter().position(|&l| l != 0),
                labels.iter().rposition(|&l| l != 0),
            ) {
                take(&mut lo, &mut hi, first, j, k);
                take(&mut lo, &mut hi, last, j, k);
            }
        }
        if !lo[0].is_finite() {
            // Nothing labelled: the whole scan's box.
            for c in 0..8 {
                let corner = [c & 1, c >> 1 & 1, c >> 2];
                take(
                    &mut lo,
                    &mut hi,
                    corner[0] * (nx - 1),
                    corner[1] * (ny - 1),
                    corner[2] * (nz - 1),
                );
            }
        }
        let mut dims = [0usize; 3];
        let mut origin = [0.0; 3];
        for r in 0..3 {
            let pad = 0.5 * (0..3).map(|c| a[r][c].abs()).sum::<f64>();
            origin[r] = lo[r] - pad;
            let n = ((hi[r] + pad - origin[r]) / spacing[r]).ceil() + 1.0;
            dims[r] = if n.is_finite() && n >= 1.0 {
                n as usize
            } else {
                0
            };
        }
        let total = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .filter(|&n| {
                n > 0
                    && n <= MAX_GROWTH.saturating_mul(self.data.len()).max(1 << 20)
                    && (n as u64).saturating_mul(2) <= crate::io::MAX_VOLUME_BYTES
            })
            .ok_or_else(|| {
                Error::Build(format!(
                    "resampling the oblique volume {:?} into the body frame would take \
                     {dims:?} voxels, more than {MAX_GROWTH} times its own or the \
                     {}-byte cap on a label volume",
                    self.dims,
                    crate::io::MAX_VOLUME_BYTES
                ))
            })?;
        let step: [nalgebra::Vector3<f64>; 3] = std::array::from_fn(|r| {
            let mut e = nalgebra::Vector3::zeros();
            e[r] = spacing[r];
            inv * e
        });
        let start = inv * (nalgebra::Vector3::from(origin) - t);
        let inside = |q: f64, n: usize| {
            let f = (q + 0.5).floor();
            (f >= 0.0 && f < n as f64).then_some(f as usize)
        };
        let mut data = vec![0u16; total];
        data.par_chunks_mut(dims[0] * dims[1])
            .enumerate()
            .for_each(|(k, slab)| {
                for (j, row) in slab.chunks_exact_mut(dims[0]).enumerate() {
                    let q0 = start + step[1] * j as f64 + step[2] * k as f64;
                    for (i, out) in row.iter_mut().enumerate() {
                        let q = q0 + step[0] * i as f64;
                        if let (Some(x), Some(y), Some(z)) =
                            (inside(q[0], nx), inside(q[1], ny), inside(q[2], nz))
                        {
                            *out = self.get(x, y, z);
                        }
                    }
                }
            });
        Self::axis_aligned(dims, spacing, origin, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A labelled block written on a grid tilted about two axes comes back, in the body
    /// frame, at the same place with the same volume.
    #[test]
    fn an_oblique_volume_is_resampled_in_place_keeping_its_volume() {
        // A 20 x 16 x 30 mm block of label 5, at 1 mm, inside an empty margin.
        let [nx, ny, nz] = [40usize, 36, 50];
        let inside = |p: [f64; 3]| {
            (-10.0..10.0).contains(&p[0])
                && (-8.0..8.0).contains(&p[1])
                && (-15.0..15.0).contains(&p[2])
        };
        let (sa, ca) = 12f64.to_radians().sin_cos();
        let (sb, cb) = 7f64.to_radians().sin_cos();
        // Rotation about x by 12°, then about y by 7°, columns scaled by the voxel size.
        let rx = [[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]];
        let ry = [[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]];
        let mut rot = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                rot[r][c] = (0..3).map(|k| ry[r][k] * rx[k][c]).sum();
            }
        }
        let centre = [nx as f64 / 2.0, ny as f64 / 2.0, nz as f64 / 2.0];
        let mut a = [[0.0; 4]; 3];
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] = rot[r][c];
            }
            a[r][3] = -(0..3).map(|c| rot[r][c] * centre[c]).sum::<f64>();
        }
        let mut data = Vec::with_capacity(nx * ny * nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let q = [i, j, k].map(|x| x as f64);
                    let p: [f64; 3] = std::array::from_fn(|r| {
                        (0..3).map(|c| a[r][c] * q[c]).sum::<f64>() + a[r][3]
                    });
                    data.push(if inside(p) { 5 } else { 0 });
                }
            }
        }
        let tilted = LabelVolume::new([nx, ny, nz], a, data).unwrap();
        assert!(!tilted.is_in_frame());
        let f = tilted.clone().in_frame().unwrap();
        assert!(f.is_in_frame() && f.affine()[0][1] == 0.0);
        let n = |v: &LabelVolume| v.data().iter().filter(|&&l| l == 5).count() as f64;
        assert!(
            (n(&f) / n(&tilted) - 1.0).abs() < 0.02,
            "{} vs {}",
            n(&f),
            n(&tilted)
        );
        // Every resampled voxel of the block lies within a voxel of the block.
        let [fx, fy, fz] = f.dims();
        for k in 0..fz {
            for j in 0..fy {
                for i in 0..fx {
                    if f.get(i, j, k) == 5 {
                        let p = f
                            .voxel_to_world_m([i as f64, j as f64, k as f64])
                            .map(|x| x * 1e3);
                        let near = (0..27).any(|d| {
                            let o = [d % 3, d / 3 % 3, d / 9].map(|x| x as f64 - 1.0);
                            inside([p[0] + o[0], p[1] + o[1], p[2] + o[2]])
                        });
                        assert!(near, "{p:?}");
                    }
                }
            }
        }
        // Noise in the direction cosines is no tilt.
        let mut b = [[0.0; 4]; 3];
        for r in 0..3 {
            b[r][r] = 1.0;
        }
        b[0][2] = 1e-6;
        let v = LabelVolume::new([4, 4, 100], b, vec![1; 1600]).unwrap();
        assert!(v.is_in_frame());
        // A header claiming a wild tilt of a long thin volume is refused, not allocated.
        let mut c = [[0.0; 4]; 3];
        c[0][0] = 1e-3;
        c[1][1] = 1.0;
        c[2][2] = 1.0;
        c[0][2] = 1.0;
        let w = LabelVolume::new([2, 2, 1_000], c, vec![1; 4_000]).unwrap();
        let e = w.in_frame().unwrap_err().to_string();
        assert!(e.contains("more than 8 times"), "{e}");
    }
}
