//! Bring your own anatomy: the Visible Human leg saved as 3D Slicer and ITK-SNAP would
//! save someone's segmentation (their names, their label numbers, their axis order, an
//! oblique scan) builds the same lattice as the original.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use common::tool_files::{human, itk_snap};
use myoslice::io::{encode_nifti, read_segmentation};
use myoslice::prelude::*;
use myoslice::{BuildReport, Label};

/// The folder the files are written to: `MYOSLICE_ANATOMY_OUT` keeps them (to time the
/// readers with `myoslice build`), else a scratch folder removed at the end.
fn out_dir() -> (PathBuf, bool) {
    match std::env::var_os("MYOSLICE_ANATOMY_OUT") {
        Some(d) => {
            let d = PathBuf::from(d);
            std::fs::create_dir_all(&d).unwrap();
            (d, true)
        }
        None => {
            let d = std::env::temp_dir().join(format!("myoslice-anatomy-{}", std::process::id()));
            std::fs::create_dir_all(&d).unwrap();
            (d, false)
        }
    }
}

fn gzip(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

/// Lattice volume (cm³) of each structure, by name.
fn structure_volumes(volume: &LabelVolume, table: &LabelTable) -> BTreeMap<String, f64> {
    let lattice = Lattice::build(volume, table, &BuildOptions::default()).unwrap();
    BuildReport::measure(volume, &lattice, "test")
        .structures
        .iter()
        .map(|s| (s.name.clone(), s.lattice_volume_cm3))
        .collect()
}

/// Largest relative difference of a structure's volume from the reference, and which.
fn worst(reference: &BTreeMap<String, f64>, got: &BTreeMap<String, f64>, what: &str) -> f64 {
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        reference.keys().collect::<Vec<_>>(),
        "{what}: not the same structures"
    );
    let mut report = String::new();
    let mut most: (f64, &str) = (0.0, "");
    for (name, &v) in reference {
        let off = got[name] / v - 1.0;
        report += &format!(
            "{name:<28} {v:>9.2} {:>9.2} {:>+7.3}%\n",
            got[name],
            100.0 * off
        );
        if off.abs() > most.0 {
            most = (off.abs(), name);
        }
    }
    eprintln!(
        "{what}: largest structure volume difference {:.3}% ({})\n{report}",
        100.0 * most.0,
        most.1
    );
    assert!(
        most.0 <= 0.01,
        "{what}: {} differs by {:.2}% (> 1%)\n{report}",
        most.1,
        100.0 * most.0
    );
    most.0
}

/// New label value of each structure (its position in the table, from 1) and the
/// segment header lines a 3D Slicer segmentation names them with.
fn slicer_segments(table: &LabelTable) -> (BTreeMap<u16, u8>, String) {
    let mut value = BTreeMap::new();
    let mut header = String::new();
    let structures: Vec<&Label> = table
        .labels()
        .iter()
        .filter(|l| l.kind != TissueKind::Background)
        .collect();
    for (s, l) in structures.iter().enumerate() {
        let v = u8::try_from(s + 1).unwrap();
        value.insert(l.id, v);
        header += &format!(
            "Segment{s}_ID:=Segment_{}\nSegment{s}_Name:={}\nSegment{s}_LabelValue:={v}\n\
             Segment{s}_Layer:=0\nSegment{s}_Color:=0.5 0.5 0.5\n",
            s + 1,
            human(&l.name, s)
        );
    }
    (value, header)
}

/// A 3-D Slicer segmentation (one layer, gzip) of `labels` (x fastest) with the given
/// voxel axes and origin, in Slicer's left-posterior-superior space.
fn write_seg_nrrd(
    path: &Path,
    sizes: [usize; 3],
    directions_lps: [[f64; 3]; 3],
    origin_lps: [f64; 3],
    segments: &str,
    labels: &[u8],
) {
    let dir = |d: [f64; 3]| format!("({},{},{})", d[0], d[1], d[2]);
    let mut out = format!(
        "NRRD0004\n# Complete NRRD file format specification at:\n\
         # http://teem.sourceforge.net/nrrd/format.html\ntype: unsigned char\ndimension: 3\n\
         space: left-posterior-superior\nsizes: {} {} {}\nspace directions: {} {} {}\n\
         kinds: domain domain domain\nencoding: gzip\nspace origin: {}\n{segments}\n",
        sizes[0],
        sizes[1],
        sizes[2],
        dir(directions_lps[0]),
        dir(directions_lps[1]),
        dir(directions_lps[2]),
        dir(origin_lps),
    )
    .into_bytes();
    out.extend(gzip(labels));
    std::fs::write(path, out).unwrap();
}

/// The Visible Human leg as a Slicer segmentation: segments named as people name them,
/// renumbered 1, 2, ..., every voxel axis reversed (i toward the subject's left, j
/// posterior, k inferior), in LPS space.
fn reversed_segmentation(volume: &LabelVolume, table: &LabelTable, path: &Path) {
    let (value, segments) = slicer_segments(table);
    let [nx, ny, nz] = volume.dims();
    let mut labels = Vec::with_capacity(nx * ny * nz);
    for k in (0..nz).rev() {
        for j in (0..ny).rev() {
            for i in (0..nx).rev() {
                labels.push(value.get(&volume.get(i, j, k)).copied().unwrap_or(0));
            }
        }
    }
    let a = volume.affine();
    let far: [f64; 3] =
        std::array::from_fn(|r| a[r][3] + a[r][r] * [nx - 1, ny - 1, nz - 1][r] as f64);
    // RAS → LPS negates x and y; each stored axis runs against ours.
    write_seg_nrrd(
        path,
        [nx, ny, nz],
        [
            [a[0][0], 0.0, 0.0],
            [0.0, a[1][1], 0.0],
            [0.0, 0.0, -a[2][2]],
        ],
        [-far[0], -far[1], far[2]],
        &segments,
        &labels,
    );
}

/// The leg as ITK-SNAP's NIfTI and label file: label values moved (3·id + 5), stored in
/// sagittal slices (i along y, j along z, k along x), gzip.
fn sagittal_itk_snap(volume: &LabelVolume, table: &LabelTable, nii: &Path, txt: &Path) {
    let moved = |id: u16| if id == 0 { 0 } else { 3 * id + 5 };
    let relabelled = LabelTable::new(
        table
            .labels()
            .iter()
            .map(|l| Label {
                id: moved(l.id),
                ..l.clone()
            })
            .collect(),
    )
    .unwrap();
    std::fs::write(txt, itk_snap(&relabelled)).unwrap();
    let [nx, ny, nz] = volume.dims();
    let a = volume.affine();
    let mut data = Vec::with_capacity(nx * ny * nz);
    for i in 0..nx {
        for k in 0..nz {
            for j in 0..ny {
                data.push(moved(volume.get(i, j, k)));
            }
        }
    }
    let affine = [
        [0.0, 0.0, a[0][0], a[0][3]],
        [a[1][1], 0.0, 0.0, a[1][3]],
        [0.0, a[2][2], 0.0, a[2][3]],
    ];
    let stored = LabelVolume::new([ny, nz, nx], affine, data).unwrap();
    std::fs::write(nii, gzip(&encode_nifti(&stored))).unwrap();
}

/// The leg as an oblique scan saved by Slicer: the voxel grid turned 8° about x (a
/// gantry tilt) and 5° about y, 1 mm voxels, each grid voxel taking the label at its
/// centre in the original (nearest neighbour).
fn oblique_segmentation(volume: &LabelVolume, table: &LabelTable, path: &Path) {
    let (value, segments) = slicer_segments(table);
    let (sa, ca) = 8f64.to_radians().sin_cos();
    let (sb, cb) = 5f64.to_radians().sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]];
    let ry = [[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]];
    // Columns: the grid's axes in our (RAS) frame.
    let rot: [[f64; 3]; 3] =
        std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| ry[r][k] * rx[k][c]).sum()));
    let [nx, ny, nz] = volume.dims();
    let a = volume.affine();
    let world = |i: f64, j: f64, k: f64| -> [f64; 3] {
        std::array::from_fn(|r| a[r][0] * i + a[r][1] * j + a[r][2] * k + a[r][3])
    };
    // The grid covers the original's corners, in grid coordinates (rotᵀ · p).
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in 0..8 {
        let p = world(
            ((c & 1) * (nx - 1)) as f64,
            ((c >> 1 & 1) * (ny - 1)) as f64,
            ((c >> 2) * (nz - 1)) as f64,
        );
        for g in 0..3 {
            let q: f64 = (0..3).map(|r| rot[r][g] * p[r]).sum();
            lo[g] = lo[g].min(q.floor());
            hi[g] = hi[g].max(q.ceil());
        }
    }
    let sizes: [usize; 3] = std::array::from_fn(|g| (hi[g] - lo[g]) as usize + 1);
    let origin: [f64; 3] = std::array::from_fn(|r| (0..3).map(|g| rot[r][g] * lo[g]).sum());
    let mut labels = Vec::with_capacity(sizes.iter().product());
    for k in 0..sizes[2] {
        for j in 0..sizes[1] {
            for i in 0..sizes[0] {
                let q = [i as f64, j as f64, k as f64];
                // Original voxel index: the affine is the identity plus an origin
                // (checked by the caller).
                let idx: [f64; 3] = std::array::from_fn(|r| {
                    origin[r] + (0..3).map(|g| rot[r][g] * q[g]).sum::<f64>() - a[r][3]
                });
                let inside = idx
                    .iter()
                    .zip([nx, ny, nz])
                    .all(|(&x, n)| x.round() >= 0.0 && x.round() < n as f64);
                labels.push(if inside {
                    let [x, y, z] = idx.map(|x| x.round() as usize);
                    value.get(&volume.get(x, y, z)).copied().unwrap_or(0)
                } else {
                    0
                });
            }
        }
    }
    // RAS → LPS negates the x and y components.
    let lps = |v: [f64; 3]| [-v[0], -v[1], v[2]];
    write_seg_nrrd(
        path,
        sizes,
        std::array::from_fn(|g| lps([rot[0][g], rot[1][g], rot[2][g]])),
        lps(origin),
        &segments,
        &labels,
    );
}

#[test]
fn the_visible_human_saved_by_slicer_and_itk_snap_builds_the_same_lattice() {
    let Some((volume, table)) = common::vh_leg() else {
        return;
    };
    // The oblique writer above relies on this.
    assert_eq!(volume.spacing_mm(), [1.0; 3]);
    assert!(volume.is_in_frame());
    let reference = structure_volumes(&volume, &table);
    let (dir, keep) = out_dir();

    // Reversed axes, Slicer's names and numbers: the very same voxels come back.
    let seg = dir.join("vh-reversed.seg.nrrd");
    reversed_segmentation(&volume, &table, &seg);
    let (v, t) = read_segmentation(&seg, None, Unmapped::Error).unwrap();
    assert_eq!((v.dims(), v.affine()), (volume.dims(), volume.affine()));
    let off = worst(&reference, &structure_volumes(&v, &t), "reversed .seg.nrrd");
    assert!(off < 1e-9, "a reordering changed a volume by {off}");

    // Sagittal NIfTI with ITK-SNAP's label file.
    let (nii, txt) = (
        dir.join("vh-sagittal.nii.gz"),
        dir.join("vh-sagittal-labels.txt"),
    );
    sagittal_itk_snap(&volume, &table, &nii, &txt);
    let (v, t) = read_segmentation(&nii, Some(&txt), Unmapped::Error).unwrap();
    assert_eq!(v.dims(), volume.dims());
    let off = worst(
        &reference,
        &structure_volumes(&v, &t),
        "sagittal ITK-SNAP NIfTI",
    );
    assert!(off < 1e-9, "a reordering changed a volume by {off}");

    // An oblique scan: resampled into the body frame, within 1 % per structure.
    let oblique = dir.join("vh-oblique.seg.nrrd");
    oblique_segmentation(&volume, &table, &oblique);
    let (v, t) = read_segmentation(&oblique, None, Unmapped::Error).unwrap();
    assert!(v.is_in_frame());
    worst(&reference, &structure_volumes(&v, &t), "oblique .seg.nrrd");

    if !keep {
        std::fs::remove_dir_all(dir).unwrap();
    }
}
