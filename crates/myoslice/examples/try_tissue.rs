use myoslice::prelude::*;
use myoslice::tissue::intersect::self_intersections;
fn main() -> Result<()> {
    let t0 = std::time::Instant::now();
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    println!("built {:.2}s", t0.elapsed().as_secs_f64());
    let flex = [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "gracilis",
        "sartorius",
    ];
    let ext = [
        "rectus_femoris",
        "vastus_lateralis",
        "vastus_medialis",
        "vastus_intermedius",
    ];
    let tri = sim.lattice().fat.surface_triangles();
    let t1 = std::time::Instant::now();
    let mut max_angle: f64 = 0.0;
    let (mut vmin, mut vmax, mut inv, mut minvr) = (f32::INFINITY, 0.0f32, 0usize, f32::INFINITY);
    for k in 0..40 {
        let t = k as f64 * 0.05;
        for n in flex {
            sim.set_excitation(n, if t < 1.0 { 0.6 } else { 0.0 })?;
        }
        for n in ext {
            sim.set_excitation(n, if t < 1.0 { 0.0 } else { 0.5 })?;
        }
        sim.step(0.05)?;
        let m = sim.tissue_metrics().unwrap();
        max_angle = max_angle.max(sim.knee_angle());
        for r in &m.muscle_volume_ratio {
            vmin = vmin.min(*r);
            vmax = vmax.max(*r);
        }
        inv = inv.max(m.inverted);
        minvr = minvr.min(m.min_volume_ratio);
        if k % 4 == 3 {
            let x = sim.tissue().unwrap().fat_vertices();
            println!(
                "t {:.2} knee {:6.1} inverted {} minvol {:.3} maxarea {:.2} muscleV [{:.4},{:.4}] self-x {}",
                sim.time(),
                sim.knee_angle().to_degrees(),
                m.inverted,
                m.min_volume_ratio,
                m.max_abs_area_change,
                m.muscle_volume_ratio
                    .iter()
                    .copied()
                    .fold(f32::INFINITY, f32::min),
                m.muscle_volume_ratio.iter().copied().fold(0.0, f32::max),
                self_intersections(x, &tri)
            );
        }
    }
    println!(
        "wall {:.2}s for 2 s; max angle {:.1}; muscle V range [{vmin:.4},{vmax:.4}] inverted {inv} min vol ratio {minvr:.3}",
        t1.elapsed().as_secs_f64(),
        max_angle.to_degrees()
    );
    Ok(())
}
