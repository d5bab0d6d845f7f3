//! Per-element and whole-body tissue metrics (paper, section 5.3 and Eq. 5).

use glam::{Mat3, Vec3};

use super::Tissue;
use super::polar::{covariance, polar_rotation_exact};
use crate::lattice::{Lattice, hex_volume_points, quad_area};

/// Metrics of the tissue at one moment; arrays are contiguous, one value per fat
/// hexahedron (lattice order) or per muscle (simulation order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TissueMetrics {
    /// Relative change of the body-surface area of each element's outer face
    /// (`A/A0 − 1`: positive grown, negative shrunk; 0 for elements without one).
    pub area_change: Vec<f32>,
    /// Deformation degree (Eq. 5): mean distance (m) of each corner from its rotated rest
    /// position about the element's centroid.
    pub deformation_degree: Vec<f32>,
    /// Volume of each element over its rest volume.
    pub volume_ratio: Vec<f32>,
    /// Volume of each muscle over its rest volume.
    pub muscle_volume_ratio: Vec<f32>,
    /// Smallest element volume ratio.
    pub min_volume_ratio: f32,
    /// Largest |area change|.
    pub max_abs_area_change: f32,
    /// Elements of zero or negative volume.
    pub inverted: usize,
}

impl TissueMetrics {
    /// Measures the tissue now.
    pub fn measure(lattice: &Lattice, t: &Tissue) -> Self {
        let fat = &t.fat;
        let n = fat.hexes.len();
        let mut volume_ratio = vec![1.0f32; n];
        let mut degree = vec![0.0f32; n];
        let mut inverted = 0;
        for e in 0..n {
            let h = fat.hexes[e];
            let p = h.map(|i| fat.x[i as usize]);
            let v = hex_volume_points(&p.map(Vec3::as_dvec3));
            let v0 = hex_volume_points(&h.map(|i| fat.rest[i as usize].as_dvec3()));
            volume_ratio[e] = (v / v0) as f32;
            if v <= 0.0 {
                inverted += 1;
            }
            let c = p.iter().copied().sum::<Vec3>() / 8.0;
            let d = p.map(|q| q - c);
            let r = fat.rest_relative(e);
            let q = polar_rotation_exact(&covariance(&d, r), fat.rot[e]);
            let m = Mat3::from_quat(q);
            degree[e] = (0..8).map(|k| (m * r[k] - d[k]).length()).sum::<f32>() / 8.0;
        }
        let mut area_change = vec![0.0f32; n];
        for (h, quad) in lattice.fat.outer_faces() {
            let a0 = quad_area(&fat.rest, &quad);
            let a = quad_area(&fat.x, &quad);
            if a0 > 0.0 {
                area_change[h as usize] = (a / a0 - 1.0) as f32;
            }
        }
        let muscle_volume_ratio: Vec<f32> = t
            .muscles
            .iter()
            .map(|m| (m.volume() / m.rest_volume.max(1e-12)) as f32)
            .collect();
        Self {
            min_volume_ratio: volume_ratio.iter().copied().fold(f32::INFINITY, f32::min),
            max_abs_area_change: area_change.iter().map(|a| a.abs()).fold(0.0, f32::max),
            area_change,
            deformation_degree: degree,
            volume_ratio,
            muscle_volume_ratio,
            inverted,
        }
    }
}
