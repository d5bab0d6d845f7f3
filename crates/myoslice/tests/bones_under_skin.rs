//! Bones stay under the skin through a deep flexion (`Simulation::bones_outside_skin`).

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use myoslice::prelude::*;

/// Bones reach out through the skin over the deep flexion no further than recorded. The
/// patella, carried by the shank under skin the fold turns by less, came out from about
/// 70° (108 vertices on the phantom, 6.9 mm; 111 on the Visible Human, 7.6 mm) until the
/// fat the fold can bring near a bone was kept off it (`tissue/fat_keep_out.rs`): now
/// 0 and 2 vertices, at most 2.0 mm, where the skin's flat triangles span the bone's
/// edges. Behind the knee the fibula's head reaches the contact plane from about 95° and
/// comes out between the two skins where they meet on it: 314 and 247 vertices, 8.9 and
/// 7.1 mm with the tissue passes run one after another, 67 and 65, 4.7 and 4.5 mm since
/// they act inside the fat's iterations with its volume held. No other bone comes out beyond what stands out at rest (the sacrum, past the
/// lattice's top end).
fn bones_reach_out_no_further_than_recorded(mut sim: Simulation) {
    let names: Vec<String> = sim.lattice().bones.iter().map(|b| b.name.clone()).collect();
    let rest = sim.bones_outside_skin().unwrap();
    // Per bone: most vertices out beyond those at rest, and the farthest then (m).
    let mut worst = vec![(0usize, 0.0f32); names.len()];
    let max = common::flex_and_back(&mut sim, 1.0, |s| {
        let now = s.bones_outside_skin().unwrap();
        for ((w, n), r) in worst.iter_mut().zip(&now).zip(&rest) {
            if n.vertices_over_1mm > r.vertices_over_1mm {
                w.0 = w.0.max(n.vertices_over_1mm - r.vertices_over_1mm);
                w.1 = w.1.max(n.farthest_m);
            }
        }
    });
    let summary: Vec<String> = names
        .iter()
        .zip(&worst)
        .filter(|(_, w)| w.0 > 0)
        .map(|(n, w)| format!("{n}: {} vertices, {:.1} mm", w.0, w.1 * 1e3))
        .collect();
    eprintln!("bone vertices > 1 mm outside the skin beyond rest, at most: {summary:?}");
    assert!(
        max.to_degrees() > 125.0,
        "the flexion reached only {:.1}°",
        max.to_degrees()
    );
    for (name, &(count, far)) in names.iter().zip(&worst) {
        let (most, farthest) = match name.as_str() {
            "patella" => (5, 0.0025),
            "fibula" => (80, 0.0065),
            _ => (0, 0.0),
        };
        assert!(
            count <= most && far <= farthest,
            "{name}: {count} vertices > 1 mm outside the skin, {:.1} mm: {summary:?}",
            far * 1e3
        );
    }
}

#[test]
fn bones_reach_out_through_the_skin_no_further_than_recorded_in_a_deep_flexion() {
    bones_reach_out_no_further_than_recorded(
        Simulation::phantom(SimulationConfig::default()).unwrap(),
    );
}

#[test]
fn visible_human_bones_reach_out_through_the_skin_no_further_than_recorded() {
    if let Some(sim) = common::visible_human() {
        bones_reach_out_no_further_than_recorded(sim);
    }
}
