//! From a label volume to the lattice body.

use std::collections::BTreeMap;

use crate::par::*;
use glam::{DVec3, Vec3};

use super::bone_clearance::{Clearance, clear_muscles_of_bone};
use super::fat::{FatInputs, InnerContact, build_fat};
use super::frame::SliceFrame;
use super::tube::{RingInput, TubeMesh};
use super::{BoneMesh, Lattice, MuscleLattice, StructureStats};
use crate::contour::{ComponentMask, Polygon, PolygonMethod, RegionPolygon, polygonise};
use crate::error::{Error, Result};
use crate::label_table::{LabelTable, TissueKind};
use crate::label_volume::LabelVolume;
use crate::slices::{SliceComponents, SliceReduction, SliceStack, label_components};
use crate::spatial::PointGrid;
use crate::tracking::track_regions;

/// Options of the lattice build.
///
/// ```
/// use myoslice::prelude::*;
/// let opts = BuildOptions { rays: 32, ..BuildOptions::default() };
/// assert!(opts.validate().is_ok());
/// assert!(BuildOptions { rays: 2, ..opts }.validate().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuildOptions {
    /// Slice reduction (every k-th slice, optional in-plane resampling).
    pub reduction: SliceReduction,
    /// Rays per polygon, for bones, muscles and the fat (default 48: a 7.5° step keeps
    /// the chord error of a 2 cm muscle under 0.1 mm and the whole leg near 20k fat
    /// hexahedra at 5 mm slices).
    pub rays: usize,
    /// Radial layers of fat elements between envelope and skin (default 2).
    pub fat_layers: usize,
    /// Below this IoU a radial polygon is replaced by a traced one if that fits better.
    pub min_iou: f64,
    /// Regions with fewer pixels are not polygonised (default 4).
    pub min_region_px: u32,
    /// Minimum fat thickness (mm) between envelope and skin, so no element is flat.
    pub min_fat_thickness_mm: f64,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            reduction: SliceReduction::default(),
            rays: 48,
            fat_layers: 2,
            min_iou: 0.92,
            min_region_px: 4,
            min_fat_thickness_mm: 1.0,
        }
    }
}

impl BuildOptions {
    /// Checks every option.
    pub fn validate(&self) -> Result<()> {
        self.reduction.validate()?;
        if !(3..=4096).contains(&self.rays) {
            return Err(Error::invalid("rays", self.rays, "expected 3 to 4096 rays"));
        }
        if !(1..=16).contains(&self.fat_layers) {
            return Err(Error::invalid(
                "fat_layers",
                self.fat_layers,
                "expected 1 to 16 layers",
            ));
        }
        if !(self.min_iou.is_finite() && (0.0..=1.0).contains(&self.min_iou)) {
            return Err(Error::invalid(
                "min_iou",
                self.min_iou,
                "expected a value in [0, 1]",
            ));
        }
        if !(self.min_fat_thickness_mm.is_finite() && self.min_fat_thickness_mm > 0.0) {
            return Err(Error::invalid(
                "min_fat_thickness_mm",
                self.min_fat_thickness_mm,
                "expected a finite thickness > 0",
            ));
        }
        Ok(())
    }
}

struct SliceData {
    comps: SliceComponents,
    polys: Vec<Option<RegionPolygon>>,
}

impl Lattice {
    /// Builds the lattice body of a label volume, brought into the body frame first
    /// ([`LabelVolume::in_frame`]) when it is stored in another order or tilted.
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let (volume, table) = Phantom::default().generate()?;
    /// let lattice = Lattice::build(&volume, &table, &BuildOptions::default())?;
    /// println!("{} fat hexahedra", lattice.fat.hexes.len());
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn build(volume: &LabelVolume, table: &LabelTable, opts: &BuildOptions) -> Result<Self> {
        opts.validate()?;
        volume.check_labels(table)?;
        // Slices run across the body's long axis: a scan stored in another order or
        // tilted is brought into the body frame first.
        let in_frame;
        let volume = if volume.is_in_frame() {
            volume
        } else {
            in_frame = volume.clone().in_frame()?;
            &in_frame
        };
        let kind_of = table.kind_lut();
        let hist = volume.histogram();
        let count_kind = |k: TissueKind| -> u64 {
            hist.iter()
                .enumerate()
                .filter(|(id, _)| kind_of.get(*id).copied().flatten() == Some(k))
                .map(|(_, c)| *c)
                .sum()
        };
        let body = count_kind(TissueKind::Fat)
            + count_kind(TissueKind::Bone)
            + count_kind(TissueKind::Muscle);
        if body == 0 {
            return Err(Error::Build(
                "the volume is empty: no fat, bone or muscle voxel".into(),
            ));
        }
        if count_kind(TissueKind::Bone) == 0 {
            return Err(Error::Build(
                "the slice stack has no bone: the skeleton and the fat rays need one".into(),
            ));
        }
        let stack = SliceStack::reduce(volume, &opts.reduction)?;
        let frame = SliceFrame::new(volume, &stack);
        let is_solid = |l: u16| {
            matches!(
                kind_of.get(l as usize).copied().flatten(),
                Some(TissueKind::Bone | TissueKind::Muscle)
            )
        };
        let mut pass = MeshPass::run(volume, &stack, &frame, opts, &is_solid);
        // Structures only a few kept slices tall (the gemelli run across the slices) are
        // resampled on every source slice so their shape and volume survive the reduction.
        let short: Vec<(u16, usize, usize)> = pass
            .extent
            .iter()
            .filter(|(_, e)| e.2 < SHORT_STRUCTURE_SLICES && stack.step > 1)
            .map(|(&l, e)| (l, e.0, e.1))
            .collect();
        for (label, s0, s1) in short {
            let k0 = stack.source_k[s0].saturating_sub(stack.step - 1);
            let k1 = (stack.source_k[s1] + stack.step - 1).min(volume.dims()[2] - 1);
            let fine = SliceStack::at_slices(volume, &opts.reduction, (k0..=k1).collect())?;
            let fine_frame = SliceFrame::new(volume, &fine);
            let sub = MeshPass::run(volume, &fine, &fine_frame, opts, &|l| l == label);
            pass.replace(label, sub);
        }
        let MeshPass {
            per,
            meshes,
            mut fit,
            centre_acc,
            ..
        } = pass;

        let mut bones = Vec::new();
        let mut muscles = Vec::new();
        let mut stats = Vec::new();
        for (label, mesh) in meshes {
            let Some(info) = table.get(label) else {
                continue;
            };
            let acc = fit.remove(&label).unwrap_or_default();
            stats.push(StructureStats {
                label,
                name: info.name.clone(),
                kind: info.kind,
                polygons: acc.n,
                traced_polygons: acc.traced,
                dropped_regions: acc.dropped,
                mean_iou: if acc.area > 0.0 {
                    acc.iou_area / acc.area
                } else {
                    0.0
                },
                min_iou: acc.min_iou,
                lattice_volume_m3: mesh.volume(),
                bone_clearance: Clearance::default(),
            });
            match info.kind {
                TissueKind::Bone => bones.push(BoneMesh {
                    label,
                    name: info.name.clone(),
                    mesh,
                }),
                TissueKind::Muscle => {
                    let centre_line = centre_acc
                        .range((label, i64::MIN)..=(label, i64::MAX))
                        .map(|(_, (sum, a))| (*sum / *a).as_vec3())
                        .collect();
                    muscles.push(MuscleLattice {
                        label,
                        name: info.name.clone(),
                        origin: info.origin.clone(),
                        insertion: info.insertion.clone(),
                        mesh,
                        centre_line,
                    });
                }
                _ => {}
            }
        }

        let cleared = clear_muscles_of_bone(&mut muscles, &bones);
        for (m, c) in muscles.iter().zip(cleared) {
            if let Some(st) = stats.iter_mut().find(|s| s.label == m.label) {
                st.bone_clearance = c;
                st.lattice_volume_m3 = m.mesh.volume();
            }
        }

        // Fat: rays from the largest bone region of each slice.
        let bone_centre: Vec<Option<[f64; 2]>> = per
            .iter()
            .map(|d| {
                d.comps
                    .regions
                    .iter()
                    .filter(|r| {
                        kind_of.get(r.label as usize).copied().flatten() == Some(TissueKind::Bone)
                    })
                    .max_by_key(|r| (r.area, std::cmp::Reverse(r.id)))
                    .map(|r| r.centroid)
            })
            .collect();
        let bone_polygons: Vec<Vec<Polygon>> = per
            .iter()
            .map(|d| {
                d.comps
                    .regions
                    .iter()
                    .zip(&d.polys)
                    .filter(|(r, _)| {
                        kind_of.get(r.label as usize).copied().flatten() == Some(TissueKind::Bone)
                    })
                    .filter_map(|(_, p)| p.as_ref().map(|p| p.polygon.clone()))
                    .collect()
            })
            .collect();
        let px_mm = frame.pixel_m[0].min(frame.pixel_m[1]) * 1e3;
        let fat = build_fat(&FatInputs {
            stack: &stack,
            frame: &frame,
            kind_of: &kind_of,
            bone_centre: &bone_centre,
            bone_polygons: &bone_polygons,
            rays: opts.rays,
            layers: opts.fat_layers,
            min_thickness_px: opts.min_fat_thickness_mm / px_mm,
        })?;
        let fat_muscle_ref = muscle_references(&fat, &muscles);
        Ok(Lattice {
            bones,
            muscles,
            fat,
            fat_muscle_ref,
            stats,
            frame,
            table: table.clone(),
            options: *opts,
        })
    }
}

/// Structures spanning fewer kept slices than this are resampled on every slice.
const SHORT_STRUCTURE_SLICES: usize = 4;

/// Polygons, tracks and tube meshes of the solid labels of one slice stack.
struct MeshPass {
    per: Vec<SliceData>,
    meshes: BTreeMap<u16, TubeMesh>,
    fit: BTreeMap<u16, FitAcc>,
    centre_acc: BTreeMap<(u16, i64), (DVec3, f64)>,
    /// Per label: first and last slice with a ring, and the most rings of one track.
    extent: BTreeMap<u16, (usize, usize, usize)>,
}

impl MeshPass {
    fn run(
        volume: &LabelVolume,
        stack: &SliceStack,
        frame: &SliceFrame,
        opts: &BuildOptions,
        keep: &(dyn Fn(u16) -> bool + Sync),
    ) -> Self {
        let (w, h) = (stack.width, stack.height);
        let per: Vec<SliceData> = (0..stack.len())
            .into_par_iter()
            .map(|s| {
                let comps = label_components(&stack.labels[s], w, h, keep);
                let polys = comps
                    .regions
                    .iter()
                    .map(|r| {
                        (r.area >= opts.min_region_px).then(|| {
                            let m = ComponentMask {
                                image: &comps.image,
                                width: w,
                                height: h,
                                id: r.id,
                            };
                            polygonise(&m, r, opts.rays, opts.min_iou)
                        })
                    })
                    .collect();
                SliceData { comps, polys }
            })
            .collect();
        let active: Vec<Vec<bool>> = per
            .iter()
            .map(|d| d.polys.iter().map(Option::is_some).collect())
            .collect();
        let comps: Vec<&SliceComponents> = per.iter().map(|d| &d.comps).collect();
        let tracks = track_regions(&comps, &active);
        let mut meshes: BTreeMap<u16, TubeMesh> = BTreeMap::new();
        let mut fit: BTreeMap<u16, FitAcc> = BTreeMap::new();
        let mut centre_acc: BTreeMap<(u16, i64), (DVec3, f64)> = BTreeMap::new();
        let mut extent: BTreeMap<u16, (usize, usize, usize)> = BTreeMap::new();
        for t in &tracks {
            let rings: Vec<RingInput> = t
                .regions
                .iter()
                .enumerate()
                .filter_map(|(i, &id)| {
                    let s = t.first_slice + i;
                    let rp = per[s].polys[id as usize].as_ref()?;
                    let region = &per[s].comps.regions[id as usize];
                    Some(RingInput {
                        slice: s,
                        points: rp
                            .polygon
                            .points
                            .iter()
                            .map(|p| frame.world(s, *p))
                            .collect(),
                        points_2d: rp.polygon.points.clone(),
                        centre: frame.world(s, rp.centre),
                        method: rp.method,
                        area_px: region.area,
                        iou: rp.iou,
                    })
                })
                .collect();
            let mut rings = rings;
            align_traced_rings(&mut rings);
            let (Some(first), Some(last)) = (rings.first(), rings.last()) else {
                continue;
            };
            let end_cap = |r: &RingInput, dir: i64| {
                let d = cap_depth(volume, stack, &per, t.label, r, dir);
                (frame.dk * d * dir as f64).as_vec3()
            };
            let below = end_cap(first, -1);
            let above = end_cap(last, 1);
            meshes
                .entry(t.label)
                .or_default()
                .add_tube(&rings, below, above, &stack.source_k);
            let e = extent
                .entry(t.label)
                .or_insert((first.slice, last.slice, 0));
            *e = (
                e.0.min(first.slice),
                e.1.max(last.slice),
                e.2.max(rings.len()),
            );
            let acc = fit.entry(t.label).or_default();
            for r in &rings {
                acc.add(r);
                let poly_centre = Polygon {
                    points: r.points_2d.clone(),
                }
                .centroid();
                let c = frame.world(r.slice, poly_centre).as_dvec3();
                let k = stack.source_k[r.slice] as i64;
                let e = centre_acc.entry((t.label, k)).or_insert((DVec3::ZERO, 0.0));
                e.0 += c * f64::from(r.area_px);
                e.1 += f64::from(r.area_px);
            }
        }
        for d in &per {
            for (r, p) in d.comps.regions.iter().zip(&d.polys) {
                if p.is_none() {
                    fit.entry(r.label).or_default().dropped += 1;
                }
            }
        }
        Self {
            per,
            meshes,
            fit,
            centre_acc,
            extent,
        }
    }

    /// Takes `label`'s meshes and statistics from a finer pass.
    fn replace(&mut self, label: u16, mut sub: MeshPass) {
        if let Some(m) = sub.meshes.remove(&label) {
            self.meshes.insert(label, m);
        }
        if let Some(f) = sub.fit.remove(&label) {
            self.fit.insert(label, f);
        }
        self.centre_acc.retain(|(l, _), _| *l != label);
        self.centre_acc.extend(sub.centre_acc);
    }
}

#[derive(Default)]
struct FitAcc {
    n: usize,
    traced: usize,
    dropped: usize,
    iou_area: f64,
    area: f64,
    min_iou: f64,
}

impl FitAcc {
    fn add(&mut self, r: &RingInput) {
        if self.n == 0 {
            self.min_iou = r.iou;
        }
        self.n += 1;
        self.traced += usize::from(r.method == PolygonMethod::Traced);
        self.iou_area += r.iou * f64::from(r.area_px);
        self.area += f64::from(r.area_px);
        self.min_iou = self.min_iou.min(r.iou);
    }
}

/// Nearest surface vertex of the touched muscle (any muscle if that one has no lattice)
/// for every inner fat vertex that rests on muscle.
fn muscle_references(
    fat: &super::FatLattice,
    muscles: &[MuscleLattice],
) -> Vec<Option<(u32, u32)>> {
    let surface_vertices = |m: &MuscleLattice| -> Vec<(u32, Vec3)> {
        let n = ring_len(m) as u32;
        m.mesh
            .rings
            .iter()
            .flat_map(|r| (r.first..r.first + n).map(|i| (i, m.mesh.vertices[i as usize])))
            .collect()
    };
    let per_muscle: Vec<(Vec<u32>, PointGrid)> = muscles
        .iter()
        .map(|m| {
            let sv = surface_vertices(m);
            let idx = sv.iter().map(|(i, _)| *i).collect();
            (
                idx,
                PointGrid::new(sv.iter().map(|(_, p)| *p).collect(), 0.01),
            )
        })
        .collect();
    let all: Vec<(u32, u32)> = per_muscle
        .iter()
        .enumerate()
        .flat_map(|(mi, (idx, _))| idx.iter().map(move |&v| (mi as u32, v)))
        .collect();
    let all_grid = PointGrid::new(
        all.iter()
            .map(|&(mi, v)| muscles[mi as usize].mesh.vertices[v as usize])
            .collect(),
        0.01,
    );
    fat.inner_contact
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let InnerContact::Muscle(label) = *c else {
                return None;
            };
            let (s, j) = (k / fat.rays, k % fat.rays);
            let p = fat.vertices[fat.vertex_index(s, j, 0) as usize];
            match muscles.iter().position(|m| m.label == label) {
                Some(mi) => {
                    let (idx, grid) = &per_muscle[mi];
                    grid.nearest(p).map(|n| (mi as u32, idx[n as usize]))
                }
                None => all_grid.nearest(p).map(|n| all[n as usize]),
            }
        })
        .collect()
}

fn ring_len(m: &MuscleLattice) -> usize {
    m.mesh.ring_len()
}

/// Depth (in source slices) of the cap beyond an end ring, from the unreduced slices: the
/// voxels of the label near the ring on the skipped slices beyond it, divided by the ring's
/// area, plus half a slice. Skipped slices nearer another kept slice that still holds the
/// label nearby count for that slice instead. This puts caps where the structure ends
/// rather than blindly half a step out, which matters for muscles a few slices long.
fn cap_depth(
    volume: &LabelVolume,
    stack: &SliceStack,
    per: &[SliceData],
    label: u16,
    ring: &RingInput,
    dir: i64,
) -> f64 {
    let [nx, ny, nz] = volume.dims();
    let s = ring.slice;
    let k0 = stack.source_k[s] as i64;
    let step = stack.step as i64;
    let b = Polygon {
        points: ring.points_2d.clone(),
    }
    .bounds();
    let to_vox = |p: f64, a: usize| p * stack.scale[a] + stack.offset[a];
    let pad = 2.0;
    let u0 = (to_vox(b[0], 0) - pad).floor().max(0.0) as usize;
    let v0 = (to_vox(b[1], 1) - pad).floor().max(0.0) as usize;
    let u1 = ((to_vox(b[2], 0) + pad).ceil() as usize).min(nx - 1);
    let v1 = ((to_vox(b[3], 1) + pad).ceil() as usize).min(ny - 1);
    let area_vox = f64::from(ring.area_px) * stack.scale[0] * stack.scale[1];
    // Does the next kept slice beyond hold this label near the ring?
    let next = s as i64 + dir;
    let shared = next >= 0
        && (next as usize) < stack.len()
        && per[next as usize].comps.regions.iter().any(|r| {
            r.label == label
                && f64::from(r.bbox[2]) >= b[0] - pad
                && f64::from(r.bbox[0]) <= b[2] + pad
                && f64::from(r.bbox[3]) >= b[1] - pad
                && f64::from(r.bbox[1]) <= b[3] + pad
        });
    let reach = if shared { (step - 1) / 2 } else { step - 1 };
    let mut voxels = 0u64;
    for i in 1..=reach {
        let k = k0 + dir * i;
        if k < 0 || k >= nz as i64 {
            break;
        }
        let sl = volume.slice(k as usize);
        for v in v0..=v1 {
            voxels += sl[u0 + nx * v..=u1 + nx * v]
                .iter()
                .filter(|&&l| l == label)
                .count() as u64;
        }
    }
    let depth = 0.5 + voxels as f64 / area_vox.max(1.0);
    depth.min(step as f64 - 0.5)
}

/// Where a ring was traced (its vertices follow the border, not fixed angles), shifts its
/// vertex order cyclically to best match the previous ring, so vertex j joins vertex j
/// without a twist.
fn align_traced_rings(rings: &mut [RingInput]) {
    for i in 1..rings.len() {
        if rings[i].method != PolygonMethod::Traced && rings[i - 1].method != PolygonMethod::Traced
        {
            continue;
        }
        let n = rings[i].points_2d.len();
        let (prev, cur) = (&rings[i - 1].points_2d, &rings[i].points_2d);
        let cost = |shift: usize| -> f64 {
            (0..n)
                .map(|j| {
                    let (a, b) = (prev[j], cur[(j + shift) % n]);
                    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
                })
                .sum()
        };
        let best = (0..n)
            .min_by(|&a, &b| cost(a).total_cmp(&cost(b)))
            .unwrap_or(0);
        if best != 0 {
            rings[i].points_2d.rotate_left(best);
            rings[i].points.rotate_left(best);
        }
    }
}
