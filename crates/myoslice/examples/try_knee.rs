use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    println!("before {:.3}", sim.knee_angle().to_degrees());
    sim.set_knee(1.0, 0.0)?;
    println!(
        "after set {:.3} pose {:?}",
        sim.knee_angle().to_degrees(),
        sim.skeleton().pose(myoslice::body::BodyId::Shank)
    );
    sim.step(0.001)?;
    println!("after step {:.3}", sim.knee_angle().to_degrees());
    Ok(())
}
