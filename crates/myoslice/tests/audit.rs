//! The tissue audit: every soundness check of the tissue issue at one moment, and a run
//! audited after every tissue update.
#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use glam::Vec3;
use myoslice::export::run_scenario;
use myoslice::lattice::winding_number;
use myoslice::prelude::*;

#[test]
fn the_audit_of_the_built_phantom_agrees_with_each_separate_measure() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let a = sim.audit().unwrap();
    let m = sim.tissue_metrics().unwrap();
    assert_eq!(a.folded_fat, m.inverted);
    assert_eq!(a.min_fat_volume_ratio, m.min_volume_ratio);
    let out = sim.muscles_outside_skin().unwrap();
    let b = a.muscles_out_of_skin.unwrap();
    assert_eq!(
        b.vertices_over_1mm,
        out.iter().map(|o| o.vertices_over_1mm).sum::<usize>()
    );
    let bones = sim.bones_outside_skin().unwrap();
    let b = a.bones_out_of_skin.unwrap();
    assert_eq!(
        b.vertices_over_1mm,
        bones.iter().map(|o| o.vertices_over_1mm).sum::<usize>()
    );
    let in_bone = sim.muscles_in_bone().unwrap();
    let deepest = in_bone.iter().map(|o| o.deepest_m).fold(0.0, f32::max);
    assert_eq!(a.muscles_in_bone.deepest_m, deepest);
    assert_eq!((a.skin_crossings, a.fat_under_half_volume), (0, 0));
    assert_eq!(a.fat_off_rest_m, 0.0, "the built fat is at rest");
    assert!(a.finite);
}

#[test]
fn the_audit_finds_a_muscle_out_through_the_skin_inside_another_and_a_skin_fold() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let frames = sim.frames();
    let mut t = common::tissue_of(&sim);
    let rest = t.audit(frames);

    // A muscle whose vertices' centroid lies well inside it; another muscle's vertex put
    // there is inside the first by as much.
    let (host, centre) = t
        .muscles
        .iter()
        .enumerate()
        .map(|(i, m)| (i, m.current.iter().sum::<Vec3>() / m.current.len() as f32))
        .find(|(i, c)| {
            let m = &t.muscles[*i];
            winding_number(&m.current, &m.triangles, *c) > 0.5
                && m.current.iter().all(|p| p.distance(*c) > 0.003)
        })
        .unwrap();
    let guest = usize::from(host == 0);
    t.muscles[guest].current[0] = centre;
    let a = t.audit(frames);
    assert!(
        a.muscles_in_muscles.vertices_over_1mm > rest.muscles_in_muscles.vertices_over_1mm,
        "{:?} at rest, {:?} now",
        rest.muscles_in_muscles,
        a.muscles_in_muscles
    );
    assert!(a.muscles_in_muscles.deepest_m >= rest.muscles_in_muscles.deepest_m);

    // Half a metre in front of the body: every vertex of the muscle out, by 30 cm or more.
    let third = 2 + usize::from(host == 2);
    let n = t.muscles[third].current.len();
    for p in &mut t.muscles[third].current {
        *p += Vec3::new(0.0, 0.5, 0.0);
    }
    let a = t.audit(frames);
    let out = a.muscles_out_of_skin.unwrap();
    assert!(out.vertices_over_1mm >= n, "{out:?}");
    assert!(out.farthest_m > 0.3);

    // One skin vertex pushed through the body and out the other side: the skin crosses
    // itself, the elements under it fold, and the fat is far from its rest place.
    let fat = &sim.lattice().fat;
    let (s, j) = (fat.slices / 2, 0);
    let v = fat.vertex_index(s, j, fat.layers) as usize;
    let across = fat.vertex_index(s, fat.rays / 2, fat.layers) as usize;
    let through = t.fat.x[across] + (t.fat.x[across] - t.fat.x[v]).normalize() * 0.01;
    let moved = through.distance(t.fat.x[v]);
    t.fat.x[v] = through;
    let a = t.audit(frames);
    assert!(a.skin_crossings > 0);
    assert!(a.folded_fat > rest.folded_fat);
    assert!(
        (a.fat_off_rest_m - moved).abs() < 1e-6,
        "{} {moved}",
        a.fat_off_rest_m
    );

    // A vertex that is not a number.
    t.fat.x[v] = Vec3::NAN;
    assert!(!t.audit(frames).finite);
}

/// The skin that touches skin, measured from the skin alone: a few triangles where the
/// phantom's skin faces itself at the top of the thigh as built, and far more once the
/// knee is bent deep and the calf lies against the thigh.
#[test]
fn skin_touches_skin_behind_a_deeply_bent_knee_and_hardly_anywhere_at_rest() {
    let mut sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let rest = sim.audit().unwrap().skin_in_contact_m2.unwrap();
    assert!(rest < 5e-4, "{:.1} cm² at rest", rest * 1e4);
    sim.set_knee(130f64.to_radians(), 0.0).unwrap();
    sim.update_tissue().unwrap();
    let a = sim.audit().unwrap();
    let bent = a.skin_in_contact_m2.unwrap();
    assert!(
        bent > rest + 5e-4,
        "{:.1} cm² at rest, {:.1} cm² at 130°",
        rest * 1e4,
        bent * 1e4
    );
    let line = a.lines().into_iter().find(|l| l.check == "skin in contact");
    assert_eq!(
        line.map(|l| l.found),
        Some(format!("{:.1} cm²", bent * 1e4))
    );
}

/// A short flexion with the audit on and off (every other output off).
fn audited_run(audit: bool) -> (std::path::PathBuf, myoslice::export::RunSummary) {
    let dir = common::scratch(&format!("audit-run-{audit}"));
    let text = format!(
        "[model]\nsource = \"phantom\"\n[simulation]\nduration_s = 0.1\n\
         [tissue]\nrate_hz = 30.0\n[excitation]\nhamstrings = [[0.0, 1.0]]\n\
         [output]\nframes = 2\nvtu = false\nglb = false\naudit = {audit}\n"
    );
    let sc = Scenario::from_str_at(&text, &dir.join("scenario.toml")).unwrap();
    let summary = run_scenario(&sc, &dir.join("out"), &mut |_| {}).unwrap();
    (dir.join("out"), summary)
}

#[test]
fn an_audited_run_writes_a_row_for_each_tissue_update() {
    let (out, summary) = audited_run(true);
    let audit = summary.audit.unwrap();
    let text = std::fs::read_to_string(out.join("audit.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // The tissue as built, then every update: 30 a second for 0.1 s, and one for each
    // output frame.
    assert_eq!(rows.len() as u64, audit.updates);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    let updates: Vec<usize> = rows.iter().map(|r| r[2].parse().unwrap()).collect();
    assert_eq!(updates, (0..=5).collect::<Vec<_>>(), "{text}");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let folded: Vec<usize> = rows
        .iter()
        .map(|r| r[col("folded_fat")].parse().unwrap())
        .collect();
    assert_eq!(folded.iter().max(), Some(&audit.worst.folded_fat));
    assert_eq!(folded.last(), Some(&audit.last.folded_fat));
    let contact: f32 = rows.last().unwrap()[col("skin_in_contact_cm2")]
        .parse()
        .unwrap();
    let last = audit.last.skin_in_contact_m2.unwrap() * 1e4;
    assert!((contact - last).abs() < 1e-3, "{contact} {last}");
    let json = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(json.contains("\"muscles_in_muscles\""), "{json}");

    let (out, summary) = audited_run(false);
    assert!(summary.audit.is_none());
    assert!(!out.join("audit.csv").exists());
}

/// A tissue updated with everything where it was built stays there: no pass may move
/// fat at rest (a fold at rest would show in every frame of every run).
#[test]
fn a_tissue_updated_at_rest_stays_at_rest() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let mut t = common::tissue_of(&sim);
    let rest = myoslice::muscle::BodyFrames::REST;
    for _ in 0..3 {
        assert!(t.update(0.0, &rest, sim.muscles()));
    }
    let a = t.audit(&rest);
    assert_eq!(a.folded_fat, 0);
    assert!(
        a.fat_off_rest_m < 1e-4,
        "fat {:.3} mm off rest",
        a.fat_off_rest_m * 1e3
    );
}

/// Total muscle vertices more than 1 mm inside other muscles, and the deepest (m).
fn overlap(t: &myoslice::tissue::Tissue) -> (usize, f32) {
    let o = t.muscles_in_muscles();
    (
        o.iter().map(|o| o.vertices_over_1mm).sum(),
        o.iter().map(|o| o.deepest_m).fold(0.0, f32::max),
    )
}

#[test]
fn muscle_contact_pushes_overlapping_muscles_apart_and_keeps_their_volumes() {
    let mut sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    for m in [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "sartorius",
    ] {
        sim.set_excitation(m, 1.0).unwrap();
    }
    while sim.knee_angle() < 90f64.to_radians() && sim.time() < 1.0 {
        sim.step(0.02).unwrap();
    }
    let (knee, frames) = (sim.knee_angle(), *sim.frames());
    let apart = myoslice::tissue::TissueConfig {
        muscle_contact: true,
        ..Default::default()
    };
    let mut found = Vec::new();
    for config in [myoslice::tissue::TissueConfig::default(), apart] {
        let mut t = common::tissue_with(&sim, config);
        assert!(t.update(knee, &frames, sim.muscles()));
        let volumes = t.muscles.iter().map(|m| m.volume_ratio());
        let (lo, hi) = volumes.fold((f32::MAX, 0.0f32), |(lo, hi), v| (lo.min(v), hi.max(v)));
        found.push((overlap(&t), lo, hi));
    }
    let [((off, off_deep), ..), ((on, on_deep), lo, hi)] = found[..] else {
        unreachable!()
    };
    let summary = format!(
        "at {:.0}°: muscle vertices > 1 mm in another muscle {off} ({:.1} mm) without \
         contact, {on} ({:.1} mm) with it; volumes {lo:.4}..{hi:.4}",
        knee.to_degrees(),
        off_deep * 1e3,
        on_deep * 1e3
    );
    eprintln!("{summary}");
    assert!(knee > 80f64.to_radians(), "{summary}");
    assert!(
        off > 1000,
        "the flexion presses muscles together: {summary}"
    );
    // A quarter fewer as measured: the rings' outlines miss some of what the winding
    // number finds inside (see the tissue history).
    assert!(5 * on < 4 * off && on_deep < off_deep, "{summary}");
    assert!(lo > 0.99 && hi < 1.01, "{summary}");
}
