use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    for n in [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
    ] {
        sim.set_excitation(n, 0.3)?;
    }
    let t = std::time::Instant::now();
    let snap = sim.clone();
    let _ = snap;
    for _ in 0..10 {
        sim.step(3.0)?;
    }
    println!("30 s in {:.3}s", t.elapsed().as_secs_f64());
    Ok(())
}
