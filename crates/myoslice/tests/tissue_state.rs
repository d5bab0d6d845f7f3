//! The tissue's state: a checkpoint continues bit for bit, the thread count changes no
//! bit, and the validity guard's interventions are counted.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use glam::Vec3;
use myoslice::prelude::*;

/// Every fat and muscle vertex's bits, the knee angle's and the guard's tally.
fn tissue_bits(sim: &Simulation) -> (Vec<[u32; 3]>, u64, (u64, u64)) {
    let t = sim.tissue().unwrap();
    let bits = |p: &Vec3| p.to_array().map(f32::to_bits);
    let mut v: Vec<[u32; 3]> = t.fat_vertices().iter().map(bits).collect();
    for m in &t.muscles {
        v.extend(m.current.iter().map(bits));
    }
    let g = t.guard_tally();
    (v, sim.knee_angle().to_bits(), (g.updates, g.vertices))
}

/// The hamstrings at full excitation for `seconds` from rest, in steps of 10 ms.
fn flex(sim: &mut Simulation, seconds: f64) {
    for m in common::HAMSTRINGS {
        sim.set_excitation(m, 1.0).unwrap();
    }
    for _ in 0..(seconds / 0.01).round() as usize {
        sim.step(0.01).unwrap();
    }
}

/// The guard's tally is the sum of what each update's metrics report.
#[test]
fn the_guard_tally_counts_every_update_it_stepped_in() {
    let mut sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    let (mut updates, mut vertices) = (0u64, 0u64);
    common::flex_and_back(&mut sim, 3.0, |s| {
        let g = s.tissue_metrics().unwrap().guarded_vertices as u64;
        updates += u64::from(g > 0);
        vertices += g;
    });
    let tally = sim.tissue().unwrap().guard_tally();
    eprintln!(
        "the guard stepped in at {} updates, {} vertices",
        tally.updates, tally.vertices
    );
    assert_eq!((tally.updates, tally.vertices), (updates, vertices));
    assert!(
        tally.updates > 0,
        "the guard never stepped in: the test says nothing"
    );
}

/// A checkpoint taken past 30° of a flexion and restored goes on exactly as the run it was
/// taken from, the tissue's warm starts, carried motion and guard tally included.
#[test]
fn a_checkpoint_taken_mid_flexion_continues_bit_identically() {
    let mut sim = Simulation::phantom(SimulationConfig::default()).unwrap();
    flex(&mut sim, 0.25);
    assert!(sim.knee_angle().to_degrees() > 30.0);
    let checkpoint = sim.state();
    flex(&mut sim, 0.2);
    let first = tissue_bits(&sim);
    sim.set_state(&checkpoint).unwrap();
    flex(&mut sim, 0.2);
    assert!(
        first == tissue_bits(&sim),
        "the restored run went another way"
    );
}

/// The tissue's parallel loops split their work by thread, but what they compute does
/// not depend on how many threads there are.
#[test]
fn the_tissue_gives_the_same_bits_on_one_and_two_threads() {
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut sim = common::phantom();
            flex(&mut sim, 0.4);
            tissue_bits(&sim)
        })
    };
    let one = on(1);
    assert!(
        f64::from_bits(one.1).to_degrees() > 30.0,
        "the knee hardly bent"
    );
    assert!(one == on(2), "one and two threads differ");
}
