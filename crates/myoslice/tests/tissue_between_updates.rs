//! The tissue between its updates: carried with the bones to where they are now, what a
//! viewer draws every frame while the tissue updates at its own rate.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use glam::{Quat, Vec3};
use myoslice::prelude::*;

/// Steps of 1 ms until the tissue has just updated.
fn to_next_update(sim: &mut Simulation) {
    let before = sim.tissue().unwrap().updates();
    while sim.tissue().unwrap().updates() == before {
        sim.step(0.001).unwrap();
    }
}

#[test]
fn the_tissue_between_updates_moves_with_the_bones_and_is_the_update_right_after_one() {
    let mut sim = common::phantom();
    for m in common::HAMSTRINGS {
        sim.set_excitation(m, 1.0).unwrap();
    }
    sim.step(0.15).unwrap();
    to_next_update(&mut sim);
    // Right after an update: that update's shape, bit for bit.
    let t = sim.tissue().unwrap();
    let now = sim.carried_tissue().unwrap();
    assert_eq!(now.fat, t.fat_vertices());
    for (c, m) in now.muscles.iter().zip(&t.muscles) {
        assert_eq!(c, &m.current);
    }
    let (at_update, angle) = (*sim.frames(), sim.knee_angle());
    let fat = t.fat_vertices().to_vec();
    let muscles: Vec<Vec<Vec3>> = t.muscles.iter().map(|m| m.current.clone()).collect();
    // Most of a period later, the knee has turned on and no update has come.
    let period = sim.tissue().unwrap().period();
    let updates = sim.tissue().unwrap().updates();
    for _ in 0..((0.8 * period) / 0.001) as usize {
        sim.step(0.001).unwrap();
    }
    assert_eq!(sim.tissue().unwrap().updates(), updates);
    let turned = (sim.knee_angle() - angle).to_degrees();
    assert!(turned > 1.0, "the knee turned {turned:.2}° between updates");
    let now = sim.carried_tissue().unwrap();
    // Beyond the reach of the knee's fold (28 cm from its axis) the tissue moves rigidly
    // with the shank below the knee and with the thigh above it.
    let knee = sim.skeleton().knee().point;
    let (sq0, st0) = at_update.shank;
    let (sq, st) = sim.frames().shank;
    let with_shank = |p: Vec3| sq * (sq0.inverse() * (p - st0)) + st;
    let (tq0, tt0) = at_update.thigh;
    let (tq, tt) = sim.frames().thigh;
    let with_thigh = |p: Vec3| tq * (tq0.inverse() * (p - tt0)) + tt;
    let (mut below, mut above) = (0, 0);
    let rest = &sim.lattice().fat.vertices;
    for ((p, c), r) in fat.iter().zip(&now.fat).zip(rest) {
        if r.z < knee.z - 0.3 {
            assert!(c.distance(with_shank(*p)) < 2e-5, "{p} → {c}");
            below += 1;
        } else if r.z > knee.z + 0.3 {
            assert!(c.distance(with_thigh(*p)) < 2e-5, "{p} → {c}");
            above += 1;
        }
    }
    assert!(below > 1000 && above > 1000, "{below} below, {above} above");
    // The calf's muscles go with the shank too, and nothing is left where it was.
    let soleus = sim.muscle_index("soleus").unwrap();
    for (p, c) in muscles[soleus].iter().zip(&now.muscles[soleus]) {
        assert!(c.distance(with_shank(*p)) < 2e-5, "{p} → {c}");
    }
    let moved = fat
        .iter()
        .zip(&now.fat)
        .map(|(p, c)| p.distance(*c))
        .fold(0.0f32, f32::max);
    assert!(
        moved > 0.005,
        "the skin moved at most {:.1} mm",
        moved * 1e3
    );
    // The shank turned relative to the thigh by the knee's turn.
    let relative = (tq.inverse() * sq) * (tq0.inverse() * sq0).inverse();
    let shank_turn = relative.angle_between(Quat::IDENTITY).to_degrees();
    assert!(
        (f64::from(shank_turn) - turned.abs()).abs() < 0.1,
        "{shank_turn} vs {turned}"
    );
}
