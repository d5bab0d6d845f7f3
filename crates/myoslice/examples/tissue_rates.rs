//! How the tissue's update rate and iterations trade against its quality: the tissue
//! tests' flexion to deep flexion and back on the phantom, checked at every update, for
//! each `RATE:ITERATIONS` given (default `30:6 20:6 15:6 10:6`). Speed is the CLI's:
//! `myoslice bench --only whole_leg --tissue-rate R --tissue-iterations N`.
//!
//! ```text
//! cargo run --release -p myoslice --example tissue_rates -- 30:6 30:4 20:6 15:6 10:6 10:4
//! ```

#[path = "../tests/common/mod.rs"]
mod common;

use std::error::Error;

use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;

/// The worst of each check over a flexion.
#[derive(Default)]
struct Worst {
    /// Elements with a folded corner (VTK's test), and of non-positive volume.
    folded: usize,
    inverted: usize,
    crossings: usize,
    finite: bool,
    volume: (f32, f32),
    out: usize,
    out_m: f32,
    /// Muscle vertices in bone beyond those at rest, and the deepest of muscles deeper
    /// than at rest (as the tests count them).
    in_bone: usize,
    in_bone_m: f32,
    bones_out: Vec<usize>,
}

fn measure(
    lattice: &Lattice,
    rate_hz: f64,
    iterations: usize,
) -> Result<(f64, Worst), Box<dyn Error>> {
    let mut cfg = SimulationConfig::default();
    cfg.tissue.rate_hz = rate_hz;
    cfg.tissue.iterations = iterations;
    let mut sim = Simulation::new(lattice.clone(), cfg, &MuscleCatalogue::default())?;
    let triangles = sim.lattice().fat.surface_triangles();
    let rest = sim.muscles_in_bone().ok_or("no tissue")?;
    let mut w = Worst {
        finite: true,
        volume: (1.0, 1.0),
        bones_out: vec![0; sim.lattice().bones.len()],
        ..Worst::default()
    };
    // The helpers fail loudly (a skin that cannot be closed is not zero vertices out).
    let top = common::flex_and_back(&mut sim, 1.0, |s| {
        let b = common::tissue_breaks(s, &triangles);
        w.folded = w.folded.max(b.folded);
        (w.inverted, w.crossings) = (w.inverted.max(b.inverted), w.crossings.max(b.crossings));
        w.finite &= b.finite;
        for r in &s.tissue_metrics().expect("tissue").muscle_volume_ratio {
            w.volume = (w.volume.0.min(*r), w.volume.1.max(*r));
        }
        let (out, out_m) = common::muscles_out(s);
        (w.out, w.out_m) = (w.out.max(out), w.out_m.max(out_m));
        let (in_bone, in_bone_m) = common::muscles_in_bone_beyond(s, &rest);
        (w.in_bone, w.in_bone_m) = (w.in_bone.max(in_bone), w.in_bone_m.max(in_bone_m));
        let bones = s.bones_outside_skin().expect("a closed skin");
        for (most, b) in w.bones_out.iter_mut().zip(bones) {
            *most = (*most).max(b.vertices_over_1mm);
        }
    });
    Ok((top, w))
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cases: Vec<String> = if args.is_empty() {
        ["30:6", "20:6", "15:6", "10:6"].map(String::from).to_vec()
    } else {
        args
    };
    let lattice = common::phantom_lattice();
    let bones: Vec<&str> = lattice.bones.iter().map(|b| b.name.as_str()).collect();
    println!(
        "rate Hz  iterations  deepest at an update  folded  inverted  crossing pairs  all finite  \
         muscle volume ratio  muscle vertices out (farthest)  in bone beyond rest (deepest)  \
         bone vertices out"
    );
    for case in &cases {
        let parsed = case
            .split_once(':')
            .and_then(|(r, i)| Some((r.parse::<f64>().ok()?, i.parse::<usize>().ok()?)));
        let Some((rate, iterations)) = parsed else {
            return Err(format!("expected RATE:ITERATIONS (e.g. 30:6), got '{case}'").into());
        };
        let (top, w) = measure(lattice, rate, iterations)?;
        let bones_out: Vec<String> = bones
            .iter()
            .zip(&w.bones_out)
            .filter(|(_, n)| **n > 0)
            .map(|(b, n)| format!("{b} {n}"))
            .collect();
        println!(
            "{rate:7} {iterations:11} {:20.1}° {:7} {:9} {:15} {:11} [{:.4}, {:.4}] {:17} ({:.1} mm) {:9} ({:.1} mm)  {}",
            top.to_degrees(),
            w.folded,
            w.inverted,
            w.crossings,
            w.finite,
            w.volume.0,
            w.volume.1,
            w.out,
            w.out_m * 1e3,
            w.in_bone,
            w.in_bone_m * 1e3,
            bones_out.join(", ")
        );
    }
    Ok(())
}
