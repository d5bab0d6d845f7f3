//! Per-element and whole-body tissue metrics (paper, section 5.3 and Eq. 5).

use std::sync::OnceLock;

use glam::{Mat3, Vec3};

use super::{MuscleShape, Tissue};
use crate::par::*;

use super::polar::{covariance, polar_rotation_exact, rotation_step};
use crate::lattice::{hex_is_valid, hex_volume_f32, quad_area};

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
    /// Elements with a folded corner: a corner Jacobian at or below zero (ParaView's and
    /// VTK's test of a valid hexahedron; an element can fold at a corner and keep a
    /// positive volume). Every element is tested, whichever were measured.
    pub inverted: usize,
    /// Measured elements of zero or negative volume (turned inside out as a whole; each
    /// is also counted in [`Self::inverted`]). After an update only the elements it
    /// relaxed are measured; the others moved with a bone and keep their rest volume.
    pub negative_volume: usize,
    /// Fat vertices the validity guard moved off the relaxed shape toward the knee fold
    /// in the last update (0: the elastic relaxation stood everywhere).
    pub guarded_vertices: usize,
}

impl TissueMetrics {
    /// Measures the tissue now, every element.
    pub fn measure(t: &Tissue) -> Self {
        Self::measure_where(t, None)
    }

    /// Measures the elements the last update relaxed ([`super::FatSolver::active`]); the
    /// others moved rigidly with a bone (to within 0.1 mm, `RIGID_TOLERANCE_M2`), so they
    /// count as having no deformation, no area change and their rest volume.
    pub fn measure_active(t: &Tissue) -> Self {
        Self::measure_where(t, Some(&t.fat.active))
    }

    fn measure_where(t: &Tissue, only: Option<&[bool]>) -> Self {
        let fat = &t.fat;
        let n = fat.hexes.len();
        let measured = |e: usize| only.is_none_or(|a| a[e]);
        // Volume ratio and deformation degree per element, in parallel.
        let per: Vec<(f32, f32)> = (0..n)
            .into_par_iter()
            .map(|e| {
                if !measured(e) {
                    return (1.0, 0.0);
                }
                let h = fat.hexes[e];
                let p = h.map(|i| fat.x[i as usize]);
                let v = f64::from(hex_volume_f32(&fat.x, &h));
                let c = p.iter().copied().sum::<Vec3>() / 8.0;
                let d = p.map(|q| q - c);
                let r = fat.rest_relative(e);
                let a = covariance(&d, &r);
                // After an update the solver's rotation is warm: two trigonometry-free
                // steps reach float precision. A hand-made state may be far from it.
                let q = if only.is_some() {
                    let (q, _) = rotation_step(&a, fat.rot[e]);
                    rotation_step(&a, q).0
                } else {
                    polar_rotation_exact(&a, fat.rot[e])
                };
                let m = Mat3::from_quat(q);
                let degree = (0..8).map(|k| (m * r[k] - d[k]).length()).sum::<f32>() / 8.0;
                ((v / fat.rest_volume[e]) as f32, degree)
            })
            .collect();
        let volume_ratio: Vec<f32> = per.iter().map(|p| p.0).collect();
        let degree: Vec<f32> = per.iter().map(|p| p.1).collect();
        // Every element, also those that moved with a bone: a fold may leave one folded.
        let inverted = fat
            .hexes
            .par_iter()
            .filter(|h| !hex_is_valid(&fat.x, h))
            .count();
        let negative_volume = volume_ratio.iter().filter(|&&r| r <= 0.0).count();
        let mut area_change = vec![0.0f32; n];
        for &(h, quad, a0) in t.outer_faces() {
            if measured(h as usize) && a0 > 0.0 {
                area_change[h as usize] = (quad_area(&fat.x, &quad) / a0 - 1.0) as f32;
            }
        }
        let muscle_volume_ratio: Vec<f32> =
            t.muscles.iter().map(MuscleShape::volume_ratio).collect();
        Self {
            min_volume_ratio: volume_ratio.iter().copied().fold(f32::INFINITY, f32::min),
            max_abs_area_change: area_change.iter().map(|a| a.abs()).fold(0.0, f32::max),
            area_change,
            deformation_degree: degree,
            volume_ratio,
            muscle_volume_ratio,
            inverted,
            negative_volume,
            guarded_vertices: 0,
        }
    }
}

/// The metrics of a tissue's last update, measured when first asked for: a run that never
/// reads them (a benchmark, a controller's training) does not pay for them, and one that
/// does gets the same values as if they had been measured at the update.
#[derive(Debug, Clone, Default)]
pub(crate) struct LazyMetrics {
    measured: OnceLock<TissueMetrics>,
    /// Whether every element is measured (the built tissue), or only those the last
    /// update relaxed.
    every_element: bool,
    /// Fat vertices the guard moved in the last update.
    guarded: usize,
}

impl LazyMetrics {
    /// Of a tissue as built.
    pub(crate) fn built() -> Self {
        Self {
            every_element: true,
            ..Self::default()
        }
    }

    /// Of an update whose guard moved `guarded` vertices.
    pub(crate) fn updated(guarded: usize) -> Self {
        Self {
            guarded,
            ..Self::default()
        }
    }

    /// The metrics of `t`, the tissue these belong to (measured on the first call).
    pub(crate) fn of<'a>(&'a self, t: &Tissue) -> &'a TissueMetrics {
        self.measured.get_or_init(|| {
            let mut m = if self.every_element {
                TissueMetrics::measure(t)
            } else {
                TissueMetrics::measure_active(t)
            };
            m.guarded_vertices = self.guarded;
            m
        })
    }
}
