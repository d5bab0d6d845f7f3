use myoslice::prelude::*;
use myoslice::tissue::intersect::self_intersections;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    let tri = sim.lattice().fat.surface_triangles();
    let kz = sim.skeleton().knee().point;
    for deg in [30.0, 60.0, 90.0, 130.0, 0.0] {
        sim.set_knee(f64::to_radians(deg), 0.0)?;
        for it in 0..30 {
            sim.update_tissue()?;
            if it == 29 || it == 0 {
                let m = sim.tissue_metrics().unwrap();
                let t = sim.tissue().unwrap();
                println!(
                    "{deg:5.0} deg upd {it}: inverted {} minvol {:.3} maxarea {:.2} muscleV [{:.4},{:.4}] self-x {}",
                    m.inverted,
                    m.min_volume_ratio,
                    m.max_abs_area_change,
                    m.muscle_volume_ratio.iter().copied().fold(9.0, f32::min),
                    m.muscle_volume_ratio.iter().copied().fold(0.0, f32::max),
                    self_intersections(t.fat_vertices(), &tri)
                );
                if it == 29 {
                    let lat = sim.lattice();
                    let mut shown = 0;
                    for (e, r) in m.volume_ratio.iter().enumerate() {
                        if *r <= 0.0 && shown < 6 {
                            let h = lat.fat.hexes[e];
                            let c = h
                                .iter()
                                .map(|&i| lat.fat.vertices[i as usize])
                                .sum::<glam::Vec3>()
                                / 8.0;
                            let (s, rest) = (
                                e / (lat.fat.rays * lat.fat.layers),
                                e % (lat.fat.rays * lat.fat.layers),
                            );
                            println!(
                                "   inverted e{e} slice {s} ray {} layer {} rest dz {:.3} dy {:.3} ratio {r:.2}",
                                rest / lat.fat.layers,
                                rest % lat.fat.layers,
                                c.z - kz.z,
                                c.y - kz.y
                            );
                            shown += 1;
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
