//! A segmentation's label list (ITK-SNAP, 3D Slicer) with the names people give
//! structures reads as the same label table as our own format.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use common::scratch;
use common::tool_files::{itk_snap, slicer};

use std::path::Path;

use myoslice::label_names::Unmapped;
use myoslice::{LabelTable, TissueKind};

/// `table` written by each tool, read back: the same ids, names and kinds, and the
/// same attachments where `table` has them.
fn reads_back(table: &LabelTable, dir: &Path) {
    for (file, text) in [
        ("seg-labels.txt", itk_snap(table)),
        ("seg.ctbl", slicer(table)),
    ] {
        let path = dir.join(file);
        std::fs::write(&path, &text).unwrap();
        let read = LabelTable::from_path(&path).unwrap_or_else(|e| panic!("{file}: {e}\n{text}"));
        assert_eq!(read.labels().len(), table.labels().len(), "{file}");
        for (a, b) in read.labels().iter().zip(table.labels()) {
            assert_eq!((a.id, &a.name, a.kind), (b.id, &b.name, b.kind), "{file}");
            if b.origin.is_some() || b.insertion.is_some() {
                assert_eq!(
                    (&a.origin, &a.insertion),
                    (&b.origin, &b.insertion),
                    "{file}: {}",
                    b.name
                );
            }
        }
    }
}

#[test]
fn the_phantoms_labels_written_by_itk_snap_and_slicer_read_back_as_its_table() {
    let (_, table) = myoslice::phantom::Phantom::default().generate().unwrap();
    let dir = scratch("labels-phantom");
    reads_back(&table, &dir);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn the_visible_human_labels_written_by_itk_snap_and_slicer_read_back_as_its_table() {
    let Some((_, table)) = common::vh_leg() else {
        return;
    };
    let dir = scratch("labels-vh");
    reads_back(&table, &dir);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn unknown_names_are_refused_by_default_and_taken_as_asked_otherwise() {
    let dir = scratch("labels-unknown");
    let path = dir.join("seg.txt");
    std::fs::write(
        &path,
        "0 0 0 0 0 0 0 \"Clear Label\"\n1 1 1 1 1 1 1 \"fat\"\n2 1 1 1 1 1 1 \"Femur\"\n\
         3 1 1 1 1 1 1 \"Popliteal artery\"\n4 1 1 1 1 1 1 \"Sciatic nerve\"\n",
    )
    .unwrap();
    let e = LabelTable::from_path(&path).unwrap_err().to_string();
    assert!(
        e.contains("seg.txt") && e.contains("label 3 'Popliteal artery', label 4 'Sciatic nerve'"),
        "{e}"
    );
    let fat = LabelTable::from_path_with(&path, Unmapped::Fat).unwrap();
    assert_eq!(
        (fat.kind(3), fat.kind(4)),
        (Some(TissueKind::Fat), Some(TissueKind::Fat))
    );
    let bg = LabelTable::from_path_with(&path, Unmapped::Ignore).unwrap();
    assert_eq!(bg.kind(4), Some(TissueKind::Background));
    // Our own formats are read as before, whatever the option.
    let json = dir.join("t.json");
    std::fs::write(&json, fat.to_json()).unwrap();
    assert_eq!(LabelTable::from_path(&json).unwrap(), fat);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn files_already_read_give_the_same_volume_and_table_as_their_paths() {
    // As a web page hands them over: bytes and names, no file system.
    let (volume, table) = myoslice::phantom::Phantom::default().generate().unwrap();
    let dir = scratch("labels-bytes");
    let nii = myoslice::io::encode_nifti(&volume);
    std::fs::write(dir.join("leg.nii"), &nii).unwrap();
    let texts: [(&str, String); 2] = [
        ("leg.json", table.to_json()),
        ("leg-labels.txt", itk_snap(&table)),
    ];
    for (file, text) in texts {
        std::fs::write(dir.join(file), &text).unwrap();
        let (v0, t0) = myoslice::io::read_segmentation(
            dir.join("leg.nii"),
            Some(&dir.join(file)),
            Unmapped::Error,
        )
        .unwrap();
        let (v1, t1) =
            myoslice::io::parse_segmentation(&nii, "leg.nii", Some((&text, file)), Unmapped::Error)
                .unwrap();
        assert!(v0.data() == v1.data() && v0.dims() == v1.dims(), "{file}");
        assert_eq!(t0.to_json(), t1.to_json(), "{file}");
    }
    // A corrupt volume names the file it was given as.
    let err = myoslice::io::parse_segmentation(
        &nii[..100],
        "broken.nii",
        Some((&table.to_json(), "leg.json")),
        Unmapped::Error,
    )
    .unwrap_err();
    assert!(err.to_string().contains("broken.nii"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
