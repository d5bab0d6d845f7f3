//! Tissue deformation: constant-volume muscles, shape-matching fat and the metrics.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use glam::{Quat, Vec3};
use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;
use myoslice::tissue::TissueMetrics;

#[test]
fn rigid_motions_leave_no_deformation_and_no_area_change() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let mut t = common::tissue_of(&sim);
    let q = Quat::from_axis_angle(Vec3::new(0.2, 1.0, 0.4).normalize(), 0.9);
    let shift = Vec3::new(0.3, -0.1, 0.25);
    for (x, r) in t.fat.x.iter_mut().zip(t.fat.rest.iter()) {
        *x = q * *r + shift;
    }
    let m = TissueMetrics::measure(&t);
    let worst_degree = m.deformation_degree.iter().copied().fold(0.0f32, f32::max);
    let worst_area = m.area_change.iter().map(|a| a.abs()).fold(0.0f32, f32::max);
    assert!(
        worst_degree < 1e-5,
        "deformation degree {worst_degree} m after a rigid motion"
    );
    assert!(
        worst_area < 1e-4,
        "area change {worst_area} after a rigid motion"
    );
    assert!((m.min_volume_ratio - 1.0).abs() < 1e-3);
}

#[test]
fn stretched_skin_shows_positive_area_change_and_compressed_skin_negative() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let lat = sim.lattice();
    let fat = &lat.fat;
    let mut t = common::tissue_of(&sim);
    // Around slice 40 the skin is pushed out (stretched); around slice 120, drawn in.
    for (band, factor) in [(38..43, 1.25f32), (118..123, 0.8f32)] {
        for s in band {
            let c = fat.reference[s];
            for j in 0..fat.rays {
                for l in 1..=fat.layers {
                    let v = fat.vertex_index(s, j, l) as usize;
                    let d = t.fat.rest[v] - c;
                    let radial = Vec3::new(d.x, d.y, 0.0);
                    t.fat.x[v] =
                        t.fat.rest[v] + radial * (factor - 1.0) * (l as f32 / fat.layers as f32);
                }
            }
        }
    }
    let m = TissueMetrics::measure(&t);
    let outer = |s: usize, j: usize| m.area_change[fat.hex_index(s, j, fat.layers - 1) as usize];
    let grown = (0..fat.rays).filter(|&j| outer(40, j) > 0.05).count();
    let shrunk = (0..fat.rays).filter(|&j| outer(120, j) < -0.05).count();
    assert!(
        grown > fat.rays * 9 / 10,
        "{grown} of {} stretched faces grew",
        fat.rays
    );
    assert!(
        shrunk > fat.rays * 9 / 10,
        "{shrunk} of {} compressed faces shrank",
        fat.rays
    );
    assert!(outer(80, 0).abs() < 1e-5, "untouched skin keeps its area");
}

fn muscle_volumes_stay_within_one_percent(lattice: Lattice) {
    let mut sim = Simulation::new(
        lattice,
        SimulationConfig::default(),
        &MuscleCatalogue::default(),
    )
    .unwrap();
    let names: Vec<String> = sim.muscles().iter().map(|m| m.name.clone()).collect();
    let mut range = vec![(1.0f32, 1.0f32); names.len()];
    let max = common::flex_and_back(&mut sim, 1.0, |s| {
        let ratios = &s.tissue_metrics().unwrap().muscle_volume_ratio;
        for (r, v) in range.iter_mut().zip(ratios) {
            *r = (r.0.min(*v), r.1.max(*v));
        }
    });
    let timers = sim.timers();
    assert!(timers.tissue_updates > 0 && timers.tissue_updates <= timers.steps);
    assert!(timers.tissue_wall_s > 0.0 && timers.tissue_wall_s < timers.wall_s);
    // Every phase takes time, and together all of the tissue's but a call's backup and
    // the finiteness checks.
    let phases = timers.tissue_phases;
    assert!(phases.named().iter().all(|(_, s)| *s > 0.0), "{phases:?}");
    let share = phases.total_s() / timers.tissue_wall_s;
    assert!(
        share > 0.9 && share <= 1.0 + 1e-9,
        "{phases:?}: {share} of the tissue's time"
    );
    let lo = range.iter().map(|r| r.0).fold(1.0, f32::min);
    let hi = range.iter().map(|r| r.1).fold(1.0, f32::max);
    let outside: Vec<String> = names
        .iter()
        .zip(&range)
        .filter(|(_, r)| r.0 <= 0.99 || r.1 >= 1.01)
        .map(|(n, r)| format!("{n} [{:.4}, {:.4}]", r.0, r.1))
        .collect();
    assert!(
        max.to_degrees() > 125.0,
        "the flexion reached only {:.1}°",
        max.to_degrees()
    );
    assert!(
        lo > 0.99 && hi < 1.01,
        "muscle volume ratio range [{lo:.4}, {hi:.4}]; outside ±1 %: {outside:?}"
    );
}

#[test]
fn muscle_volume_is_conserved_through_a_deep_flexion_of_the_phantom() {
    muscle_volumes_stay_within_one_percent(common::phantom_lattice().clone());
}

#[test]
fn muscle_volume_is_conserved_through_a_deep_flexion_of_the_visible_human_leg() {
    let Some(lattice) = common::vh_lattice() else {
        return;
    };
    muscle_volumes_stay_within_one_percent(lattice.clone());
}

/// Flexes `sim` to deep flexion and back at `speed` × the tests' excitation speed,
/// asserting after every update that no fat element turns inside out, the skin never
/// crosses itself and every fat vertex stays finite; and that no more fat elements have a
/// folded corner (ParaView's test of a valid hexahedron) than `folded.0` at any update
/// and `folded.1` once the knee is straight again. Returns the largest knee angle after
/// an update.
///
/// The folds are a regression bound, not a goal: the fat's own constraints, its
/// untangling and the stacking of the skin's pleats leave 3–9 at the worst update (22 at
/// a third of the tissue rate; 17–37 before the last two, 420–590 before the
/// constraints, see docs/tissue-history.md), and none with the knee straight again.
fn tissue_never_breaks(mut sim: Simulation, speed: f64, folded: (usize, usize)) -> f64 {
    let tri = sim.lattice().fat.surface_triangles();
    let mut worst = common::Breaks {
        finite: true,
        ..Default::default()
    };
    let mut last = worst;
    let max = common::flex_and_back(&mut sim, speed, |s| {
        let b = common::tissue_breaks(s, &tri);
        worst = common::Breaks {
            folded: worst.folded.max(b.folded),
            inverted: worst.inverted.max(b.inverted),
            crossings: worst.crossings.max(b.crossings),
            finite: worst.finite && b.finite,
        };
        last = b;
    });
    eprintln!(
        "at most {} fat elements with a folded corner ({} at the end, knee at {:.1}°)",
        worst.folded,
        last.folded,
        sim.knee_angle().to_degrees()
    );
    assert!(worst.finite, "a fat vertex became non-finite");
    assert_eq!(
        (worst.inverted, worst.crossings),
        (0, 0),
        "inverted elements, self-intersecting skin triangle pairs"
    );
    assert!(
        worst.folded <= folded.0 && last.folded <= folded.1,
        "{} fat elements with a folded corner, {} at the end: more than the {folded:?} recorded",
        worst.folded,
        last.folded
    );
    max.to_degrees()
}

/// [`tissue_never_breaks`] with the default options on `lattice`, reaching past 125°.
fn tissue_never_breaks_on(lattice: Lattice, speed: f64, folded: (usize, usize)) {
    let sim = Simulation::new(
        lattice,
        SimulationConfig::default(),
        &MuscleCatalogue::default(),
    )
    .unwrap();
    let max = tissue_never_breaks(sim, speed, folded);
    assert!(max > 125.0, "the flexion reached only {max:.1}°");
}

#[test]
fn fat_never_inverts_nor_self_intersects_through_a_deep_flexion() {
    tissue_never_breaks_on(common::phantom_lattice().clone(), 1.0, (15, 0));
}

#[test]
fn fat_never_inverts_nor_self_intersects_at_three_times_the_speed() {
    tissue_never_breaks_on(common::phantom_lattice().clone(), 3.0, (15, 0));
}

/// The README's table of tissue rates offers a third of the default rate as a trade of
/// smoothness for speed: the knee turns up to three times as far between updates.
#[test]
fn fat_never_inverts_nor_self_intersects_at_a_third_of_the_tissue_rate() {
    let mut cfg = SimulationConfig::default();
    cfg.tissue.rate_hz /= 3.0;
    let sim = Simulation::phantom(cfg).unwrap();
    let max = tissue_never_breaks(sim, 1.0, (30, 0));
    // Updates 0.1 s apart fall at most at 123° of the flexion's 134°.
    assert!(
        max > 120.0,
        "the flexion reached only {max:.1}° at an update"
    );
}

#[test]
fn visible_human_fat_never_inverts_nor_self_intersects_through_a_deep_flexion() {
    let Some(lattice) = common::vh_lattice() else {
        return;
    };
    tissue_never_breaks_on(lattice.clone(), 1.0, (15, 0));
}

#[test]
fn visible_human_fat_never_inverts_nor_self_intersects_at_three_times_the_speed() {
    let Some(lattice) = common::vh_lattice() else {
        return;
    };
    tissue_never_breaks_on(lattice.clone(), 3.0, (15, 0));
}

/// After a deep flexion and back, with every muscle relaxed, 1 s after the knee is
/// straight again (within 1°): how far (m) the fat lies from its rest place at most,
/// riding bone and anywhere, and how far the muscles do; and how many fat elements stay
/// folded.
fn fat_after_flexion_and_rest(mut sim: Simulation, speed: f64) -> (f32, f32, f32, usize) {
    common::flex_and_back(&mut sim, speed, |_| {});
    for m in sim
        .muscle_names()
        .iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
    {
        sim.set_excitation(&m, 0.0).unwrap();
    }
    let period = sim.tissue().unwrap().period();
    let mut waited = 0.0;
    while sim.knee_angle().to_degrees().abs() >= 1.0 {
        assert!(
            waited < 2.0,
            "the knee did not come back straight: {:.1}°",
            sim.knee_angle().to_degrees()
        );
        sim.step(period).unwrap();
        waited += period;
    }
    sim.step(1.0).unwrap();
    let fat = &sim.lattice().fat;
    let t = sim.tissue().unwrap();
    let off = |v: usize| t.fat_vertices()[v].distance(t.fat.rest[v]);
    let anywhere = (0..fat.vertices.len()).map(off).fold(0.0f32, f32::max);
    let on_bone = fat
        .inner_contact
        .iter()
        .enumerate()
        .filter(|(_, c)| matches!(c, myoslice::lattice::InnerContact::Bone(_)))
        .map(|(k, _)| off(fat.vertex_index(k / fat.rays, k % fat.rays, 0) as usize))
        .fold(0.0f32, f32::max);
    let muscles = t
        .muscles
        .iter()
        .flat_map(|m| {
            m.current
                .iter()
                .zip(m.rest.iter())
                .map(|(p, r)| p.distance(*r))
        })
        .fold(0.0f32, f32::max);
    let folded = sim.tissue_metrics().unwrap().inverted;
    eprintln!(
        "after the flexion and 1 s straight: fat up to {:.2} mm from rest ({:.2} mm riding \
         bone), muscles up to {:.2} mm; {folded} fat elements folded",
        anywhere * 1e3,
        on_bone * 1e3,
        muscles * 1e3
    );
    (anywhere, on_bone, muscles, folded)
}

/// The bounds of [`fat_after_flexion_and_rest`]: every fat and muscle vertex within 2 mm
/// of its rest place (issue 27's "no lasting damage"), fat riding bone within 0.5 mm, and
/// no element still folded.
fn fat_comes_back_to_rest(sim: Simulation, speed: f64) {
    let (anywhere, on_bone, muscles, folded) = fat_after_flexion_and_rest(sim, speed);
    assert!(
        on_bone < 0.5e-3,
        "fat riding bone {:.2} mm from rest",
        on_bone * 1e3
    );
    assert!(
        anywhere < 2e-3 && muscles < 2e-3,
        "fat {:.2} mm from rest, muscles {:.2} mm",
        anywhere * 1e3,
        muscles * 1e3
    );
    assert_eq!(folded, 0, "fat elements stay folded");
}

/// Fat sliding on bone comes back to its rest place once the knee is straight: it
/// once settled on the far side of a condyle and stayed there.
#[test]
fn the_tissue_is_back_at_rest_a_second_after_a_deep_flexion() {
    fat_comes_back_to_rest(common::phantom(), 1.0);
}

#[test]
fn visible_human_tissue_is_back_at_rest_a_second_after_a_deep_flexion() {
    if let Some(sim) = common::visible_human() {
        fat_comes_back_to_rest(sim, 1.0);
    }
}

#[test]
fn the_tissue_is_back_at_rest_a_second_after_a_fast_deep_flexion() {
    fat_comes_back_to_rest(common::phantom(), 3.0);
}

#[test]
fn visible_human_tissue_is_back_at_rest_a_second_after_a_fast_deep_flexion() {
    if let Some(sim) = common::visible_human() {
        fat_comes_back_to_rest(sim, 3.0);
    }
}

/// Flexes `sim` to about 130° and back; returns how many muscle vertices lay more than
/// 1 mm inside bone at rest, how many more at the worst update, and the deepest of any
/// muscle deeper than at rest (m).
fn muscles_in_bone_through_a_deep_flexion(mut sim: Simulation) -> (usize, usize, f32) {
    let rest = sim.muscles_in_bone().unwrap();
    let at_rest: usize = rest.iter().map(|o| o.vertices_over_1mm).sum();
    let (mut added, mut deepest) = (0usize, 0.0f32);
    common::flex_and_back(&mut sim, 1.0, |s| {
        let (n, d) = common::muscles_in_bone_beyond(s, &rest);
        (added, deepest) = (added.max(n), deepest.max(d));
    });
    eprintln!(
        "at most {added} more muscle vertices than at rest > 1 mm inside bone ({at_rest} at \
         rest), the deepest {:.1} mm",
        deepest * 1e3
    );
    (at_rest, added, deepest)
}

#[test]
fn muscles_are_kept_out_of_bone_through_a_deep_flexion() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let (_, added, deepest) = muscles_in_bone_through_a_deep_flexion(sim);
    // Without the rings' shifts: about 2 700 more vertices, 19 mm deep; with rings that
    // straddle a bone shifted by their largest push, 14.7 mm deep; with the contact plane
    // pushing rings as far as it wanted at once, 595 vertices, 19 mm; with the rounds
    // stopped by the count of vertices over 1 mm in, not by their depth, and at most 8 of
    // them, 215 vertices, 9.5 mm. Depths from the walk over the bone's triangles that
    // remembered where it last ended: 185, 7.5 mm; from the distance field: 201, 7.6 mm
    // (the deepest behind the knee at 137°, squeezed between femur and tibia).
    assert!(
        added < 230 && deepest < 0.009,
        "{added} more muscle vertices than at rest > 1 mm inside bone, the deepest {:.1} mm",
        deepest * 1e3
    );
}

#[test]
fn visible_human_muscles_are_kept_out_of_bone_through_a_deep_flexion() {
    let Some(sim) = common::visible_human() else {
        return;
    };
    let (at_rest, added, deepest) = muscles_in_bone_through_a_deep_flexion(sim);
    assert!(
        // 273, 12.3 mm (the plantaris behind the knee at 137°; the walk: 307, 11.2 mm).
        at_rest == 0 && added < 320 && deepest < 0.013,
        "{at_rest} muscle vertices > 1 mm inside bone at rest, at most {added} more, the \
         deepest {:.1} mm",
        deepest * 1e3
    );
}

#[test]
fn every_tissue_vertex_stays_finite_at_three_times_the_speed() {
    let mut sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let mut finite = true;
    common::flex_and_back(&mut sim, 3.0, |s| {
        let t = s.tissue().unwrap();
        finite &= t.fat_vertices().iter().all(|p| p.is_finite());
        finite &= t
            .muscles
            .iter()
            .all(|m| m.current.iter().all(|p| p.is_finite()));
    });
    assert!(finite);
}

/// The phantom with tissue and a vastus intermedius a thousand times too strong: excited,
/// it blows the step up a few milliseconds later (no passive force until then).
fn blowing_up_phantom() -> Simulation {
    let mut cat = MuscleCatalogue::default();
    cat.muscles
        .get_mut("vastus_intermedius")
        .unwrap()
        .max_isometric_force_n = Some(3e6);
    Simulation::new(
        common::phantom_lattice().clone(),
        SimulationConfig::default(),
        &cat,
    )
    .unwrap()
}

#[test]
fn a_failed_call_leaves_the_tissue_clock_where_it_was() {
    let mut sim = blowing_up_phantom();
    let period = sim.tissue().unwrap().period();
    // Just past an update: the failing call below ends before the next one is due.
    sim.step(period).unwrap();
    let mut twin = sim.clone();
    sim.set_excitation("vastus_intermedius", 1.0).unwrap();
    let failed_at = match sim.step(0.5 * period) {
        Err(Error::NonFinite { time, .. }) => time,
        other => panic!("expected a blow-up, got {other:?}"),
    };
    // The failed call stepped long enough for a clock left advanced to bring the next
    // update into the 0.9 period stepped below.
    assert!(
        failed_at - period > 0.1 * period + 1e-3,
        "the call failed too soon, at {failed_at} s"
    );
    sim.set_excitation("vastus_intermedius", 0.0).unwrap();
    // Both now step a little less than a period: a clock left advanced by the failed call
    // would update the tissue within it.
    let before = (sim.timers().tissue_updates, twin.timers().tissue_updates);
    sim.step(0.9 * period).unwrap();
    twin.step(0.9 * period).unwrap();
    assert_eq!(
        sim.timers().tissue_updates - before.0,
        twin.timers().tissue_updates - before.1
    );
    assert_eq!(sim.time().to_bits(), twin.time().to_bits());
}

#[test]
fn a_failed_call_leaves_no_trace_in_the_tissue() {
    let mut sim = blowing_up_phantom();
    let period = sim.tissue().unwrap().period();
    sim.set_excitation("semimembranosus", 0.8).unwrap();
    sim.step(period).unwrap();
    // The next update falls a tenth of a period into the failing call, before it fails.
    sim.step(0.9 * period).unwrap();
    let bits = |s: &Simulation| {
        let t = s.tissue().unwrap();
        let mut b = vec![s.time().to_bits(), s.knee_angle().to_bits()];
        let points = t
            .fat_vertices()
            .iter()
            .chain(t.muscles.iter().flat_map(|m| &m.current));
        b.extend(
            points
                .flat_map(|p| p.to_array())
                .map(|c| u64::from(c.to_bits())),
        );
        b.extend(
            t.metrics()
                .area_change
                .iter()
                .map(|c| u64::from(c.to_bits())),
        );
        b
    };
    let mut twin = sim.clone();
    let before = bits(&sim);
    let updates = sim.timers().tissue_updates;
    sim.set_excitation("vastus_intermedius", 1.0).unwrap();
    assert!(matches!(
        sim.step(0.5 * period),
        Err(Error::NonFinite { .. })
    ));
    assert!(
        sim.timers().tissue_updates > updates,
        "the failed call updated the tissue"
    );
    assert!(bits(&sim) == before, "the tissue before the call is back");
    sim.set_excitation("vastus_intermedius", 0.0).unwrap();
    sim.step(period).unwrap();
    twin.step(period).unwrap();
    assert!(
        bits(&sim) == bits(&twin),
        "what follows is what a twin that never failed does"
    );
}

#[test]
fn a_copy_of_the_tissue_shares_its_model_and_owns_its_state() {
    // A checkpoint or a step's backup is a clone: what never changes (rest shapes,
    // elements, surfaces) is shared, what an update changes is the copy's own.
    let mut sim = common::phantom();
    let copy = sim.clone();
    for m in common::HAMSTRINGS {
        sim.set_excitation(m, 1.0).unwrap();
    }
    let period = sim.tissue().unwrap().period();
    sim.step(3.0 * period).unwrap();
    let (t, c) = (sim.tissue().unwrap(), copy.tissue().unwrap());
    assert!(std::sync::Arc::ptr_eq(&t.fat.rest, &c.fat.rest));
    assert!(std::sync::Arc::ptr_eq(&t.fat.hexes, &c.fat.hexes));
    for (m, n) in t.muscles.iter().zip(&c.muscles) {
        assert!(std::sync::Arc::ptr_eq(&m.rest, &n.rest));
        assert!(std::sync::Arc::ptr_eq(&m.triangles, &n.triangles));
    }
    assert!(
        t.fat_vertices() != c.fat_vertices(),
        "the fat moved in one only"
    );
    assert_eq!(
        c.fat_vertices(),
        &c.fat.rest[..],
        "the copy's fat is at rest"
    );
    assert!(
        c.muscles.iter().all(|m| m.current[..] == m.rest[..]),
        "the copy's muscles are at rest"
    );
}

#[test]
fn metrics_read_late_are_those_of_their_update() {
    // Measured when first asked for: a run that reads them after every update and one
    // that reads them only at the end see the same values, bit for bit.
    let mut eager = common::phantom();
    let built = eager.tissue_metrics().unwrap().clone();
    assert_eq!(built.inverted, 0);
    assert!(built.volume_ratio.iter().all(|r| (r - 1.0).abs() < 1e-5));
    for m in common::HAMSTRINGS {
        eager.set_excitation(m, 0.8).unwrap();
    }
    let mut late = eager.clone();
    let period = eager.tissue().unwrap().period();
    for _ in 0..4 {
        eager.step(period).unwrap();
        let t = eager.tissue().unwrap();
        let mut now = TissueMetrics::measure_active(t);
        now.guarded_vertices = t.metrics().guarded_vertices;
        assert!(&now == t.metrics(), "the metrics are those of the update");
        // The same calls, the metrics not read.
        late.step(period).unwrap();
    }
    assert!(eager.knee_angle() > 0.05, "the knee moved");
    assert!(late.tissue_metrics() == eager.tissue_metrics());
    assert!(late.tissue_metrics() != Some(&built));
}

#[test]
fn every_muscle_lies_under_the_skin_at_rest() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let out = sim.muscles_outside_skin().unwrap();
    assert_eq!(out.len(), sim.muscles().len());
    let names: Vec<String> = sim
        .muscles()
        .iter()
        .zip(&out)
        .filter(|(_, b)| b.vertices_over_1mm > 0)
        .map(|(m, b)| format!("{} {:.1} mm", m.name, b.farthest_m * 1e3))
        .collect();
    // Muscles end on the lattice's end slices, where the closed skin's end fans bulge a
    // fraction of a millimetre off their plane: hence the 1 mm tolerance.
    assert!(
        names.is_empty(),
        "over 1 mm outside the skin at rest: {names:?}"
    );
}

#[test]
fn a_muscle_moved_out_of_the_body_is_found_outside_the_skin() {
    let sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let mut t = common::tissue_of(&sim);
    // Half a metre in front of the body: every vertex out, by at least 30 cm.
    let n = t.muscles[0].current.len();
    t.muscles[0]
        .current
        .iter_mut()
        .for_each(|p| *p += Vec3::new(0.0, 0.5, 0.0));
    let out = t.muscles_outside_skin().unwrap();
    assert_eq!(out[0].vertices_over_1mm, n);
    assert!(out[0].farthest_m > 0.3, "{:?}", out[0]);
    assert!(out[1..].iter().all(|b| b.vertices_over_1mm == 0));
}

/// `step` moves the muscles and the skeleton on while a tissue update runs its guard,
/// and places the next update's muscle shapes there; stepped one update per call,
/// nothing runs beside it. Both give the same bits.
#[test]
fn muscles_stepping_beside_the_guard_give_the_same_bits_as_one_after_the_other() {
    // Steps and updates of exact binary fractions of a second: both runs add up the same
    // clock.
    let mut cfg = SimulationConfig {
        max_step_s: 1.0 / 1024.0,
        ..Default::default()
    };
    cfg.tissue.rate_hz = 32.0;
    let mut beside = Simulation::phantom(cfg).unwrap();
    for m in [
        "semitendinosus",
        "biceps_femoris_long",
        "gastrocnemius_medial",
    ] {
        beside.set_excitation(m, 1.0).unwrap();
    }
    let mut after = beside.clone();
    beside.step(0.5).unwrap();
    for _ in 0..16 {
        after.step(1.0 / 32.0).unwrap();
    }
    assert_eq!(beside.timers().tissue_updates, 16);
    assert_eq!(after.timers().tissue_updates, 16);
    assert!(beside.knee_angle() > 0.2, "{}", beside.knee_angle());
    let bits = |s: &Simulation| -> Vec<u32> {
        let muscles = (0..s.muscles().len()).flat_map(|i| s.muscle_vertices(i));
        s.fat_vertices()
            .iter()
            .copied()
            .chain(muscles)
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(beside.knee_angle().to_bits(), after.knee_angle().to_bits());
    assert!(bits(&beside) == bits(&after), "the tissue differs");
}

/// Checks how far muscles reach out through the skin over the tissue tests' flexion
/// against the bound recorded: the most vertices more than 1 mm out at one update (and
/// below 70°), the farthest, and the farthest while the knee first bends to 45°.
///
/// A regression bound, not a goal: muscles still overlap across the contact plane behind
/// the knee (see the README), and the bound records how far. While the knee first bends
/// to 45° it is tighter: rings pushed off a bone from both sides ran away (the phantom's
/// vastus medialis came 21 mm out). Below 70° it holds the chains' tether, which brings
/// the relaxed calf back on the way back (without: 1 361 vertices on the phantom, 1 452
/// on the Visible Human; without the contact plane on muscles either, 2 237 and 2 207).
/// The most at one update and the farthest hold the skin kept from drawing back from the
/// plane (without: 9 022 and 8 815 vertices, 39.7 and 39.6 mm; with the plane's reach
/// for muscles at 12 cm too, 44.9 and 45.2 mm), and the muscles kept under the skin that
/// faces the plane (without: 1 821 and 2 004 vertices at 117°, 19.2 and 22.3 mm).
fn muscles_reach_out_no_further_than_recorded(mut sim: Simulation) {
    let (mut most, mut below_70, mut farthest, mut rising_45) = (0usize, 0usize, 0.0f32, 0.0f32);
    let mut top = 0.0f64;
    common::flex_and_back(&mut sim, 1.0, |s| {
        let (count, far) = common::muscles_out(s);
        let angle = s.knee_angle().to_degrees();
        eprintln!(
            "{angle:6.1}°: {count} muscle vertices > 1 mm outside the skin, the farthest {:.1} mm",
            far * 1e3
        );
        top = top.max(angle);
        if angle < 45.0 && angle > top - 1.0 {
            rising_45 = rising_45.max(far);
        }
        most = most.max(count);
        farthest = farthest.max(far);
        if angle < 70.0 {
            below_70 = below_70.max(count);
        }
    });
    let summary = format!(
        "at most {most} muscle vertices > 1 mm outside the skin ({below_70} below 70°), the \
         farthest {:.1} mm ({:.1} mm while first bending to 45°)",
        farthest * 1e3,
        rising_45 * 1e3
    );
    eprintln!("{summary}");
    assert!(
        rising_45 < 0.006 && most < 1_000 && below_70 < 600 && farthest < 0.020,
        "{summary}"
    );
}

#[test]
fn muscles_reach_out_through_the_skin_no_further_than_recorded_in_a_deep_flexion() {
    muscles_reach_out_no_further_than_recorded(
        Simulation::phantom(SimulationConfig::default()).unwrap(),
    );
}

#[test]
fn visible_human_muscles_reach_out_through_the_skin_no_further_than_recorded() {
    if let Some(sim) = common::visible_human() {
        muscles_reach_out_no_further_than_recorded(sim);
    }
}
