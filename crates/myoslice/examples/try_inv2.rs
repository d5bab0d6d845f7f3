use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    sim.set_knee(90f64.to_radians(), 0.0)?;
    let lat = sim.lattice().clone();
    let m = sim.tissue_metrics().unwrap();
    let k = sim.skeleton().knee().point;
    let mut hist = std::collections::BTreeMap::new();
    for (e, r) in m.volume_ratio.iter().enumerate() {
        if *r > 0.0 {
            continue;
        }
        let h = lat.fat.hexes[e];
        let c = h
            .iter()
            .map(|&i| lat.fat.vertices[i as usize])
            .sum::<glam::Vec3>()
            / 8.0
            - k;
        let layer = e % lat.fat.layers;
        let key = (
            (c.z * 50.0).round() as i32,
            if c.y < 0.0 { "post" } else { "ant" },
            layer,
        );
        *hist.entry(key).or_insert(0) += 1;
    }
    for (k, v) in hist {
        println!("dz {:+.2} m {} layer {}: {v}", k.0 as f32 / 50.0, k.1, k.2);
    }
    for (i, mu) in sim.muscles().iter().enumerate() {
        if (m.muscle_volume_ratio[i] - 1.0).abs() > 0.005 {
            println!("{} {:.4}", mu.name, m.muscle_volume_ratio[i]);
        }
    }
    Ok(())
}
