//! The reduced slice stack: every k-th slice of a volume, optionally resampled in-plane.

use crate::par::*;

use crate::error::{Error, Result};
use crate::label_volume::LabelVolume;

/// How to reduce a volume into slices (paper, section 2.2 and Table 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliceReduction {
    /// Keep every `slice_step`-th slice (the paper keeps every 5th 1 mm slice).
    pub slice_step: usize,
    /// Optional in-plane pixel size (mm) to resample to, nearest neighbour.
    pub pixel_mm: Option<f64>,
}

impl Default for SliceReduction {
    fn default() -> Self {
        Self {
            slice_step: 5,
            pixel_mm: None,
        }
    }
}

impl SliceReduction {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        if self.slice_step == 0 {
            return Err(Error::invalid("slice_step", 0, "expected an integer >= 1"));
        }
        if let Some(p) = self.pixel_mm
            && !(p.is_finite() && p > 0.0)
        {
            return Err(Error::invalid(
                "pixel_mm",
                p,
                "expected a finite pixel size > 0 mm",
            ));
        }
        Ok(())
    }
}

/// The kept slices of a volume. Pixel `(u, v)` of slice `s` is voxel
/// `(u·scale_u + off_u, v·scale_v + off_v, k_s)` of the source volume.
#[derive(Debug, Clone)]
pub struct SliceStack {
    /// Pixels per row.
    pub width: usize,
    /// Rows per slice.
    pub height: usize,
    /// Source slice index of each kept slice.
    pub source_k: Vec<usize>,
    /// Labels of each kept slice, `u + width·v`.
    pub labels: Vec<Vec<u16>>,
    /// Voxel index step per pixel along u and v.
    pub scale: [f64; 2],
    /// Voxel index of pixel 0 along u and v.
    pub offset: [f64; 2],
    /// Kept-slice spacing in source slices.
    pub step: usize,
}

impl SliceStack {
    /// Reduces `volume` as `opts` says. The kept slices are centred in the stack so that
    /// both ends lose the same amount.
    pub fn reduce(volume: &LabelVolume, opts: &SliceReduction) -> Result<Self> {
        opts.validate()?;
        let [nx, ny, nz] = volume.dims();
        let step = opts.slice_step;
        let first = ((nz - 1) % step) / 2;
        let source_k: Vec<usize> = (first..nz).step_by(step).collect();
        let sp = volume.spacing_mm();
        let (fu, fv) = match opts.pixel_mm {
            Some(p) => (p / sp[0], p / sp[1]),
            None => (1.0, 1.0),
        };
        let width = ((nx as f64 / fu).floor() as usize).max(1);
        let height = ((ny as f64 / fv).floor() as usize).max(1);
        let off_u = 0.5 * fu - 0.5;
        let off_v = 0.5 * fv - 0.5;
        let labels = source_k
            .par_iter()
            .map(|&k| {
                resample(
                    volume.slice(k),
                    nx,
                    ny,
                    width,
                    height,
                    [fu, fv],
                    [off_u, off_v],
                    opts.pixel_mm.is_some(),
                )
            })
            .collect();
        Ok(Self {
            width,
            height,
            source_k,
            labels,
            scale: [fu, fv],
            offset: [off_u, off_v],
            step,
        })
    }

    /// The given source slices of `volume` (sorted, inside the volume) with the in-plane
    /// sampling of `opts`, for structures that need every slice.
    pub fn at_slices(
        volume: &LabelVolume,
        opts: &SliceReduction,
        source_k: Vec<usize>,
    ) -> Result<Self> {
        let full = SliceReduction {
            slice_step: 1,
            pixel_mm: opts.pixel_mm,
        };
        let [nx, ny, _] = volume.dims();
        let sp = volume.spacing_mm();
        let (fu, fv) = match opts.pixel_mm {
            Some(p) => (p / sp[0], p / sp[1]),
            None => (1.0, 1.0),
        };
        full.validate()?;
        let width = ((nx as f64 / fu).floor() as usize).max(1);
        let height = ((ny as f64 / fv).floor() as usize).max(1);
        let (off_u, off_v) = (0.5 * fu - 0.5, 0.5 * fv - 0.5);
        let labels = source_k
            .iter()
            .map(|&k| {
                resample(
                    volume.slice(k),
                    nx,
                    ny,
                    width,
                    height,
                    [fu, fv],
                    [off_u, off_v],
                    opts.pixel_mm.is_some(),
                )
            })
            .collect();
        Ok(Self {
            width,
            height,
            source_k,
            labels,
            scale: [fu, fv],
            offset: [off_u, off_v],
            step: 1,
        })
    }

    /// Number of kept slices.
    pub fn len(&self) -> usize {
        self.source_k.len()
    }

    /// True when no slice was kept.
    pub fn is_empty(&self) -> bool {
        self.source_k.is_empty()
    }

    /// Continuous voxel coordinate of a continuous pixel position on slice `s`.
    pub fn to_voxel(&self, s: usize, u: f64, v: f64) -> [f64; 3] {
        [
            u * self.scale[0] + self.offset[0],
            v * self.scale[1] + self.offset[1],
            self.source_k[s] as f64,
        ]
    }
}

/// Nearest-neighbour in-plane resampling of one slice (a copy when `active` is false).
#[allow(clippy::too_many_arguments)]
fn resample(
    src: &[u16],
    nx: usize,
    ny: usize,
    width: usize,
    height: usize,
    f: [f64; 2],
    off: [f64; 2],
    active: bool,
) -> Vec<u16> {
    if !active {
        return src.to_vec();
    }
    let mut out = Vec::with_capacity(width * height);
    for v in 0..height {
        let j = ((v as f64 * f[1] + off[1]).round() as usize).min(ny - 1);
        for u in 0..width {
            let i = ((u as f64 * f[0] + off[0]).round() as usize).min(nx - 1);
            out.push(src[i + nx * j]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kth_slice_is_kept_centred_and_resampling_halves_the_grid() {
        let data: Vec<u16> = (0..4 * 4 * 11).map(|i| (i / 16) as u16).collect();
        let v = LabelVolume::axis_aligned([4, 4, 11], [1.0; 3], [0.0; 3], data).unwrap();
        let s = SliceStack::reduce(
            &v,
            &SliceReduction {
                slice_step: 5,
                pixel_mm: None,
            },
        )
        .unwrap();
        assert_eq!(s.source_k, vec![0, 5, 10]);
        assert_eq!(s.labels[1][0], 5);
        let s = SliceStack::reduce(
            &v,
            &SliceReduction {
                slice_step: 3,
                pixel_mm: Some(2.0),
            },
        )
        .unwrap();
        assert_eq!(s.source_k, vec![0, 3, 6, 9]);
        assert_eq!((s.width, s.height), (2, 2));
        assert!(
            SliceStack::reduce(
                &v,
                &SliceReduction {
                    slice_step: 0,
                    pixel_mm: None
                }
            )
            .is_err()
        );
        assert!(
            SliceStack::reduce(
                &v,
                &SliceReduction {
                    slice_step: 1,
                    pixel_mm: Some(f64::NAN)
                }
            )
            .is_err()
        );
    }
}
