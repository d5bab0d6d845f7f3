//! The build report: voxel against lattice volumes and polygon fit, per structure.

use std::f64::consts::TAU;

use crate::par::*;
use serde::Serialize;

use crate::contour::{LabelSetMask, Mask, outermost_crossing};
use crate::label_table::TissueKind;
use crate::label_volume::LabelVolume;
use crate::lattice::Lattice;

/// One structure's line of the report.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct StructureReport {
    /// Structure name.
    pub name: String,
    /// `bone`, `muscle` or `fat`.
    pub kind: TissueKind,
    /// Label id (the fat record uses the fat label's id).
    pub label: u16,
    /// Volume of its voxels (cm³). For the fat: the fat voxels outside the bone/muscle
    /// envelope, i.e. what the fat lattice models (intermuscular fat lies inside).
    pub voxel_volume_cm3: f64,
    /// Volume enclosed by its lattice (cm³).
    pub lattice_volume_cm3: f64,
    /// Relative difference lattice − voxel.
    pub volume_error: f64,
    /// Area-weighted mean per-slice IoU of polygons and regions (bones and muscles).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_iou: Option<f64>,
    /// Smallest per-slice IoU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_iou: Option<f64>,
    /// Number of polygons on kept slices.
    pub polygons: usize,
    /// How many of them were traced because a radial polygon fitted poorly.
    pub traced_polygons: usize,
    /// Muscles: surface vertices drawn out of bone at build (where the polygons or the
    /// tube between slices reached into one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertices_drawn_out_of_bone: Option<usize>,
    /// Muscles: surface vertices left inside a bone (no short way out along their ray).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertices_left_in_bone: Option<usize>,
}

/// Totals of the lattice.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Totals {
    /// All vertices.
    pub vertices: usize,
    /// Bone surface vertices.
    pub bone_vertices: usize,
    /// Muscle lattice vertices.
    pub muscle_vertices: usize,
    /// Fat lattice vertices.
    pub fat_vertices: usize,
    /// Bone surface triangles.
    pub bone_triangles: usize,
    /// Muscle volume elements (slabs between rings).
    pub muscle_elements: usize,
    /// Fat hexahedra.
    pub fat_elements: usize,
    /// Kept slices.
    pub slices: usize,
    /// Rays per polygon.
    pub rays: usize,
    /// Kept-slice step.
    pub slice_step: usize,
    /// Every fat voxel including intermuscular fat (cm³), for reference.
    pub fat_all_voxel_volume_cm3: f64,
}

/// The whole report (`myoslice build --report`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BuildReport {
    /// Where the volume came from.
    pub source: String,
    /// One record per bone, muscle and the fat.
    pub structures: Vec<StructureReport>,
    /// Counts.
    pub totals: Totals,
    /// Seconds to read the input.
    pub read_time_s: f64,
    /// Seconds to build the lattice.
    pub build_time_s: f64,
}

impl BuildReport {
    /// Measures `lattice` against the voxels of `volume`.
    pub fn measure(volume: &LabelVolume, lattice: &Lattice, source: &str) -> Self {
        let hist = volume.histogram();
        let vox_cm3 = volume.voxel_volume_mm3().abs() * 1e-3;
        let mut structures = Vec::new();
        for st in &lattice.stats {
            let voxel = hist.get(st.label as usize).copied().unwrap_or(0) as f64 * vox_cm3;
            let lat = st.lattice_volume_m3 * 1e6;
            structures.push(StructureReport {
                name: st.name.clone(),
                kind: st.kind,
                label: st.label,
                voxel_volume_cm3: voxel,
                lattice_volume_cm3: lat,
                volume_error: rel(lat, voxel),
                mean_iou: Some(st.mean_iou),
                min_iou: Some(st.min_iou),
                polygons: st.polygons,
                traced_polygons: st.traced_polygons,
                vertices_drawn_out_of_bone: (st.kind == TissueKind::Muscle)
                    .then_some(st.bone_clearance.drawn_in),
                vertices_left_in_bone: (st.kind == TissueKind::Muscle)
                    .then_some(st.bone_clearance.left_inside),
            });
        }
        let kind_of = lattice.table.kind_lut();
        let fat_ids: Vec<u16> = lattice
            .table
            .of_kind(TissueKind::Fat)
            .map(|l| l.id)
            .collect();
        let fat_all: f64 = fat_ids
            .iter()
            .map(|&id| hist.get(id as usize).copied().unwrap_or(0) as f64)
            .sum::<f64>()
            * vox_cm3;
        let fat_sub = subcutaneous_fat_voxels(volume, lattice, &kind_of) as f64 * vox_cm3;
        let fat_lat = lattice.fat_volume_m3() * 1e6;
        structures.push(StructureReport {
            name: "fat".into(),
            kind: TissueKind::Fat,
            label: fat_ids.first().copied().unwrap_or(0),
            voxel_volume_cm3: fat_sub,
            lattice_volume_cm3: fat_lat,
            volume_error: rel(fat_lat, fat_sub),
            mean_iou: None,
            min_iou: None,
            polygons: lattice.fat.slices,
            traced_polygons: 0,
            vertices_drawn_out_of_bone: None,
            vertices_left_in_bone: None,
        });
        let (bv, mv, fv) = lattice.vertex_counts();
        Self {
            source: source.to_string(),
            structures,
            totals: Totals {
                vertices: bv + mv + fv,
                bone_vertices: bv,
                muscle_vertices: mv,
                fat_vertices: fv,
                bone_triangles: lattice.bones.iter().map(|b| b.mesh.triangles.len()).sum(),
                muscle_elements: lattice.muscles.iter().map(|m| m.mesh.slabs.len()).sum(),
                fat_elements: lattice.fat.hexes.len(),
                slices: lattice.fat.slices,
                rays: lattice.options.rays,
                slice_step: lattice.options.reduction.slice_step,
                fat_all_voxel_volume_cm3: fat_all,
            },
            read_time_s: 0.0,
            build_time_s: 0.0,
        }
    }

    /// The report as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if b > 0.0 { (a - b) / b } else { 0.0 }
}

/// Counts fat voxels outside the bone/muscle envelope on every source slice: the voxel
/// version of the fat lattice's inner surface, at 720 rays from the same reference.
fn subcutaneous_fat_voxels(
    volume: &LabelVolume,
    lattice: &Lattice,
    kind_of: &[Option<TissueKind>],
) -> u64 {
    const M: usize = 360;
    let [nx, ny, nz] = volume.dims();
    let frame = &lattice.frame;
    let fat = &lattice.fat;
    let body: Vec<bool> = kind_of
        .iter()
        .map(|k| k.is_some_and(|k| k != TissueKind::Background))
        .collect();
    let env: Vec<bool> = kind_of
        .iter()
        .map(|k| matches!(k, Some(TissueKind::Bone | TissueKind::Muscle)))
        .collect();
    let is_fat: Vec<bool> = kind_of
        .iter()
        .map(|k| *k == Some(TissueKind::Fat))
        .collect();
    // Stack pixel → voxel index mapping (the stack may be resampled in-plane).
    let sp = volume.spacing_mm();
    let px_mm = [frame.pixel_m[0] * 1e3, frame.pixel_m[1] * 1e3];
    let (su, sv) = (px_mm[0] / sp[0], px_mm[1] / sp[1]);
    let (ou, ov) = (0.5 * su - 0.5, 0.5 * sv - 0.5);
    let dirs: Vec<[f64; 2]> = (0..M)
        .map(|j| {
            let a = TAU * j as f64 / M as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let r_max = ((nx * nx + ny * ny) as f64).sqrt() + 2.0;
    (0..nz)
        .into_par_iter()
        .map(|k| {
            // Reference of this slice: interpolated between kept slices.
            let ks = &frame.source_k;
            let pos = ks.partition_point(|&x| x <= k);
            let rp = if pos == 0 {
                fat.reference_px[0]
            } else if pos >= ks.len() {
                fat.reference_px[ks.len() - 1]
            } else {
                let (a, b) = (ks[pos - 1], ks[pos]);
                let t = (k - a) as f64 / (b - a) as f64;
                let (p, q) = (fat.reference_px[pos - 1], fat.reference_px[pos]);
                [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
            };
            let c = [rp[0] * su + ou, rp[1] * sv + ov];
            let labels = volume.slice(k);
            let body_m = LabelSetMask {
                labels,
                width: nx,
                height: ny,
                member: &body,
            };
            let env_m = LabelSetMask {
                labels,
                width: nx,
                height: ny,
                member: &env,
            };
            // Search only from the body's bounding box inward.
            let (mut bx0, mut by0, mut bx1, mut by1) = (nx, ny, 0, 0);
            for v in 0..ny {
                for u in 0..nx {
                    if body[labels[u + nx * v] as usize] {
                        bx0 = bx0.min(u);
                        by0 = by0.min(v);
                        bx1 = bx1.max(u);
                        by1 = by1.max(v);
                    }
                }
            }
            if bx1 < bx0 {
                return 0;
            }
            let corner =
                |x: usize, y: usize| ((x as f64 - c[0]).powi(2) + (y as f64 - c[1]).powi(2)).sqrt();
            let r_far = corner(bx0, by0)
                .max(corner(bx1, by0))
                .max(corner(bx0, by1))
                .max(corner(bx1, by1))
                + 2.0;
            let r_far = r_far.min(r_max);
            let mut r_env = [0.0f64; M];
            for (j, d) in dirs.iter().enumerate() {
                let r_out = outermost_crossing(&body_m, c, *d, r_far, 0.0).unwrap_or(0.0);
                r_env[j] = outermost_crossing(&env_m, c, *d, r_out, 0.0).unwrap_or(0.0);
            }
            let mut n = 0u64;
            for v in 0..ny {
                for u in 0..nx {
                    let lab = labels[u + nx * v] as usize;
                    if !is_fat.get(lab).copied().unwrap_or(false) {
                        continue;
                    }
                    let (dx, dy) = (u as f64 - c[0], v as f64 - c[1]);
                    let r = (dx * dx + dy * dy).sqrt();
                    let a = dy.atan2(dx).rem_euclid(TAU);
                    let j = ((a / TAU * M as f64).round() as usize) % M;
                    if r > r_env[j] && env_m.sample(u as f64, v as f64) < 1.0 {
                        n += 1;
                    }
                }
            }
            n
        })
        .sum()
}
