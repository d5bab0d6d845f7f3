//! Bad input gets a clear error naming the problem, never a panic.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use myoslice::prelude::*;
use myoslice::{Label, TissueKind};

fn table() -> LabelTable {
    let l = |id, name: &str, kind| Label {
        id,
        name: name.into(),
        kind,
        origin: None,
        insertion: None,
    };
    LabelTable::new(vec![
        l(0, "background", TissueKind::Background),
        l(1, "fat", TissueKind::Fat),
        l(2, "femur", TissueKind::Bone),
        l(10, "m", TissueKind::Muscle),
    ])
    .unwrap()
}

fn vol(f: impl Fn(usize, usize, usize) -> u16) -> LabelVolume {
    let (nx, ny, nz) = (20, 20, 12);
    let mut d = vec![0; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                d[i + nx * (j + ny * k)] = f(i, j, k);
            }
        }
    }
    LabelVolume::axis_aligned([nx, ny, nz], [1.0; 3], [0.0; 3], d).unwrap()
}

fn leg(i: usize, j: usize, _k: usize) -> u16 {
    let r2 = (i as i64 - 10).pow(2) + (j as i64 - 10).pow(2);
    if r2 <= 4 {
        2
    } else if r2 <= 20 {
        10
    } else if r2 <= 64 {
        1
    } else {
        0
    }
}

fn err(v: &LabelVolume, t: &LabelTable, o: BuildOptions) -> String {
    Lattice::build(v, t, &o).unwrap_err().to_string()
}

#[test]
fn a_good_small_leg_builds() {
    assert!(
        Lattice::build(
            &vol(leg),
            &table(),
            &BuildOptions {
                reduction: SliceReduction {
                    slice_step: 2,
                    pixel_mm: None
                },
                ..BuildOptions::default()
            }
        )
        .is_ok()
    );
}

#[test]
fn an_empty_volume_is_refused() {
    let e = err(&vol(|_, _, _| 0), &table(), BuildOptions::default());
    assert!(e.contains("empty"), "{e}");
}

#[test]
fn a_stack_without_bone_is_refused() {
    let e = err(
        &vol(|i, j, k| if leg(i, j, k) == 2 { 10 } else { leg(i, j, k) }),
        &table(),
        BuildOptions::default(),
    );
    assert!(e.contains("no bone"), "{e}");
}

#[test]
fn a_label_missing_from_the_table_is_named() {
    let e = err(
        &vol(|i, j, k| {
            if i == 0 && j == 0 && k == 0 {
                7
            } else {
                leg(i, j, k)
            }
        }),
        &table(),
        BuildOptions::default(),
    );
    assert!(
        e.contains("label 7") && e.contains("missing from the label table"),
        "{e}"
    );
}

#[test]
fn too_few_rays_and_a_zero_slice_step_are_refused() {
    let e = err(
        &vol(leg),
        &table(),
        BuildOptions {
            rays: 2,
            ..BuildOptions::default()
        },
    );
    assert!(e.contains("rays"), "{e}");
    let o = BuildOptions {
        reduction: SliceReduction {
            slice_step: 0,
            pixel_mm: None,
        },
        ..BuildOptions::default()
    };
    let e = err(&vol(leg), &table(), o);
    assert!(e.contains("slice_step"), "{e}");
}

#[test]
fn missing_and_corrupt_files_are_named() {
    let e = read_nifti("/nonexistent/leg.nii.gz")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/leg.nii.gz"), "{e}");
    let dir = std::env::temp_dir().join(format!("myoslice-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gz = dir.join("garbage.nii.gz");
    std::fs::write(&gz, [0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3, 1, 2, 3]).unwrap();
    let e = read_nifti(&gz).unwrap_err().to_string();
    assert!(e.contains("gzip"), "{e}");
    let labels = dir.join("labels.json");
    std::fs::write(&labels, "{\"labels\": {\"1\": {\"name\": \"fat\"}}}").unwrap();
    let e = LabelTable::from_path(&labels).unwrap_err().to_string();
    assert!(e.contains("labels.json") && e.contains("kind"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
