//! The tether of an unloaded chain: through a flexion by the hamstrings and back, the
//! relaxed calf muscles' chain points stay near where they were built on their bones.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;

use common::{HAMSTRINGS, QUADRICEPS, phantom_lattice};

const CALF: [&str; 2] = ["gastrocnemius_medial", "gastrocnemius_lateral"];

/// Mean distance (m) of the cone-anchored points of the calf's two-joint muscles from
/// their rest places on their bones.
fn calf_from_rest(s: &Simulation) -> f32 {
    let (mut sum, mut n) = (0.0f32, 0);
    for name in CALF {
        let chain = &s.muscles()[s.muscle_index(name).unwrap()].chain;
        for (x, c) in chain.x.iter().zip(&chain.cones) {
            if let Some(c) = c {
                sum += x.distance(s.frames().point(c.body, c.rest));
                n += 1;
            }
        }
    }
    sum / n.max(1) as f32
}

/// Lets the chains settle for 2 s, flexes the knee with the hamstrings for 0.8 s, then
/// extends it with the quadriceps for 0.8 s, the calf at rest throughout; returns the
/// deepest knee angle (degrees), the calf's mean distance from its rest places after
/// settling, and its largest on the way back between 60° and 20°.
fn flex_and_return(tether: f64) -> (f64, f32, f32) {
    let mut c = SimulationConfig::default();
    c.tissue.enabled = false;
    c.chain_tether = tether;
    let mut s = Simulation::new(phantom_lattice().clone(), c, &MuscleCatalogue::default()).unwrap();
    s.step(2.0).unwrap();
    let at_rest = calf_from_rest(&s);
    let (mut deepest, mut back) = (0.0f64, 0.0f32);
    for k in 0..160 {
        let flexing = k < 80;
        for m in HAMSTRINGS {
            s.set_excitation(m, if flexing { 1.0 } else { 0.0 })
                .unwrap();
        }
        for m in QUADRICEPS {
            s.set_excitation(m, if flexing { 0.0 } else { 0.6 })
                .unwrap();
        }
        s.step(0.01).unwrap();
        let knee = s.knee_angle().to_degrees();
        deepest = deepest.max(knee);
        if !flexing && (20.0..60.0).contains(&knee) {
            back = back.max(calf_from_rest(&s));
        }
    }
    (deepest, at_rest, back)
}

#[test]
fn relaxed_calf_muscles_stay_near_their_rest_places_through_a_flexion_and_back() {
    let (deep, rest, back) = flex_and_return(SimulationConfig::default().chain_tether);
    let (deep0, rest0, back0) = flex_and_return(0.0);
    let mm = |m: f32| m * 1e3;
    let summary = format!(
        "calf chain points from their rest places (mean, mm), at rest and the most from 60° to \
         20° on the way back: tether {:.2} and {:.1} (knee to {deep:.0}°); without {:.2} and \
         {:.1} (knee to {deep0:.0}°)",
        mm(rest),
        mm(back),
        mm(rest0),
        mm(back0)
    );
    eprintln!("{summary}");
    assert!(deep > 90.0 && deep0 > 90.0, "{summary}");
    // The rest places are where the chains were built: at rest the tether holds them
    // there (within a millimetre), while without it they sag and straighten away.
    assert!(rest < 1e-3 && rest < 0.5 * rest0, "{summary}");
    assert!(back < 0.5 * back0, "{summary}");
}
