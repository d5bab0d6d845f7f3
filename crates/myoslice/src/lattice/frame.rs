//! Mapping from slice pixel coordinates to world coordinates (metres).

use glam::{DVec3, Vec3};

use crate::label_volume::LabelVolume;
use crate::slices::SliceStack;

/// World position of pixel `(u, v)` of kept slice `s`: `origin[s] + u·du + v·dv`.
#[derive(Debug, Clone)]
pub struct SliceFrame {
    /// World position (m) of pixel (0, 0) of each kept slice.
    pub origin: Vec<DVec3>,
    /// World step (m) per pixel along u.
    pub du: DVec3,
    /// World step (m) per pixel along v.
    pub dv: DVec3,
    /// World step (m) of one source slice (k + 1).
    pub dk: DVec3,
    /// Number of source slices.
    pub source_slices: usize,
    /// Source slice index of each kept slice.
    pub source_k: Vec<usize>,
    /// Kept-slice spacing in source slices.
    pub step: usize,
    /// Pixel size (m) along u and v.
    pub pixel_m: [f64; 2],
}

impl SliceFrame {
    /// The frame of a reduced stack of `volume`.
    pub fn new(volume: &LabelVolume, stack: &SliceStack) -> Self {
        let w = |v: [f64; 3]| DVec3::from(volume.voxel_to_world_m(v));
        let o0 = w([0.0; 3]);
        let du = w([stack.scale[0], 0.0, 0.0]) - o0;
        let dv = w([0.0, stack.scale[1], 0.0]) - o0;
        let dk = w([0.0, 0.0, 1.0]) - o0;
        let origin = (0..stack.len())
            .map(|s| {
                let p = stack.to_voxel(s, 0.0, 0.0);
                w(p)
            })
            .collect();
        Self {
            origin,
            du,
            dv,
            dk,
            source_slices: volume.dims()[2],
            source_k: stack.source_k.clone(),
            step: stack.step,
            pixel_m: [du.length(), dv.length()],
        }
    }

    /// World position (m) of a pixel position on kept slice `s`.
    pub fn world(&self, s: usize, p: [f64; 2]) -> Vec3 {
        (self.origin[s] + self.du * p[0] + self.dv * p[1]).as_vec3()
    }

    /// Offsets of the caps below and above a ring on kept slice `s`: half a kept-slice
    /// step, clipped at the ends of the volume, so a ring stands for the voxel slab
    /// around it.
    pub fn cap_offsets(&self, s: usize) -> (Vec3, Vec3) {
        let k = self.source_k[s] as f64;
        let half = self.step as f64 / 2.0;
        let down = half.min(k + 0.5);
        let up = half.min(self.source_slices as f64 - 0.5 - k);
        ((-self.dk * down).as_vec3(), (self.dk * up).as_vec3())
    }

    /// Unit normal of the slices (direction of increasing k).
    pub fn normal(&self) -> Vec3 {
        self.dk.normalize().as_vec3()
    }
}
