use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    let m0 = sim.tissue_metrics().unwrap().muscle_volume_ratio.clone();
    println!(
        "at rest: min {:.4} max {:.4}",
        m0.iter().copied().fold(9.0, f32::min),
        m0.iter().copied().fold(0.0, f32::max)
    );
    sim.set_knee(90f64.to_radians(), 0.0)?;
    let m = sim.tissue_metrics().unwrap();
    for (i, mu) in sim.muscles().iter().enumerate() {
        let r = m.muscle_volume_ratio[i];
        if (r - 1.0).abs() > 0.01 {
            println!(
                "{:28} {:.4} cross {} pts {}",
                mu.name,
                r,
                mu.crosses_knee,
                mu.chain.len()
            );
        }
    }
    Ok(())
}
