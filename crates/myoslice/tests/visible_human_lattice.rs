//! The lattice built from the real Visible Human leg at the paper's reduction.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use myoslice::prelude::*;
use myoslice::{BuildReport, TissueKind};

#[test]
fn visible_human_lattice_matches_voxel_volumes_and_region_shapes() {
    let Some((volume, table)) = common::vh_leg() else {
        return;
    };
    assert_eq!(volume.dims(), [218, 300, 861]);
    assert_eq!(volume.spacing_mm(), [1.0, 1.0, 1.0]);
    let lattice = Lattice::build(&volume, &table, &BuildOptions::default()).unwrap();
    let report = BuildReport::measure(&volume, &lattice, "vh");
    let mut failures = Vec::new();
    for s in &report.structures {
        let tol = if s.voxel_volume_cm3 >= 50.0 && s.kind != TissueKind::Fat {
            0.05
        } else {
            0.10
        };
        if s.volume_error.abs() > tol {
            failures.push(format!(
                "{}: lattice {:.1} vs voxel {:.1} cm3 ({:+.1}%, limit {:.0}%)",
                s.name,
                s.lattice_volume_cm3,
                s.voxel_volume_cm3,
                100.0 * s.volume_error,
                100.0 * tol
            ));
        }
        if s.kind == TissueKind::Muscle {
            let iou = s.mean_iou.unwrap_or(0.0);
            if iou < 0.9 {
                failures.push(format!("{}: area-weighted mean IoU {iou:.3} < 0.9", s.name));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The fat lattice holds the subcutaneous fat; against all fat voxels (intermuscular
    // fat, tendons and ligaments included, which lie inside the envelope) it must still
    // be within 10 %.
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    let all_fat = json["totals"]["fat_all_voxel_volume_cm3"].as_f64().unwrap();
    let fat = report
        .structures
        .iter()
        .find(|s| s.kind == TissueKind::Fat)
        .unwrap();
    let off = fat.lattice_volume_cm3 / all_fat - 1.0;
    assert!(
        off.abs() < 0.10,
        "fat lattice {:.0} cm³ against {all_fat:.0} cm³ of fat voxels ({:+.1} %)",
        fat.lattice_volume_cm3,
        100.0 * off
    );
    // Every muscle and bone of the table made it into the lattice.
    for l in table.labels() {
        if matches!(l.kind, TissueKind::Bone | TissueKind::Muscle) {
            assert!(
                report.structures.iter().any(|s| s.name == l.name),
                "{} missing",
                l.name
            );
        }
    }
    // The JSON report carries the documented keys.
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    let first = &json["structures"][0];
    for key in [
        "name",
        "kind",
        "voxel_volume_cm3",
        "lattice_volume_cm3",
        "mean_iou",
    ] {
        assert!(first.get(key).is_some(), "report lacks {key}");
    }
}

#[test]
fn visible_human_lattice_is_closed_positive_and_keeps_fat_out_of_bone() {
    let Some((volume, table)) = common::vh_leg() else {
        return;
    };
    let lattice = Lattice::build(&volume, &table, &BuildOptions::default()).unwrap();
    let inv = lattice.check_invariants();
    assert!(inv.is_sound(), "{inv:?}");
    assert!(lattice.fat.hexes.len() > 10_000);
    // The vastus intermedius wraps the femur: its polygons must not fill the bone.
    let vi = lattice.muscle("vastus_intermedius").unwrap();
    let femur = lattice.bone("femur").unwrap();
    let inside = femur
        .mesh
        .rings
        .iter()
        .filter(|r| !r.cap)
        .map(|r| femur.mesh.vertices[r.centre as usize])
        .filter(|c| {
            let w = myoslice::lattice::winding_number(&vi.mesh.vertices, &vi.mesh.triangles, *c);
            w.abs() > 0.5
        })
        .count();
    assert_eq!(
        inside, 0,
        "femur centres lie inside the vastus intermedius lattice"
    );
}

#[test]
fn visible_human_moment_arms_lie_in_published_human_ranges() {
    // As the phantom's test, on the real leg's own geometry.
    let Some((volume, table)) = common::vh_leg() else {
        return;
    };
    let lattice = Lattice::build(&volume, &table, &BuildOptions::default()).unwrap();
    let mut cfg = SimulationConfig::default();
    cfg.tissue.enabled = false;
    let base =
        Simulation::new(lattice, cfg, &myoslice::muscle::MuscleCatalogue::default()).unwrap();
    println!("{}", common::assert_moment_arms_in_published_ranges(&base));
}

#[test]
fn visible_human_muscles_are_built_clear_of_bone() {
    let Some(lattice) = common::vh_lattice() else {
        return;
    };
    // Before the build drew them out: 52 vertices in five muscles, up to 2.2 mm deep.
    assert_eq!(common::muscles_in_bone_at_build(lattice), vec![]);
    let drawn: usize = lattice
        .stats
        .iter()
        .map(|s| s.bone_clearance.drawn_in)
        .sum();
    assert!(drawn > 0);
}

#[test]
fn phantom_muscles_are_built_clear_of_bone_but_where_the_hip_bone_surface_covers_them() {
    // Two small tubes of the iliacus (one slice each) lie wholly inside the hip bone's
    // surface, their centres too: no ray of theirs leads out. Everything else is
    // clear (before the build drew them out: 203 vertices in seven muscles, 164 of them
    // the iliacus's).
    let found = common::muscles_in_bone_at_build(common::phantom_lattice());
    assert!(
        found.len() == 1 && found[0].0 == "iliacus" && found[0].1 < 150,
        "{found:?}"
    );
}
