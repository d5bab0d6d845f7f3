use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    for n in [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
    ] {
        sim.set_excitation(n, 1.0)?;
    }
    let i = sim.muscle_index("gastrocnemius_lateral")?;
    for _ in 0..215 {
        let prev = sim.muscles()[i].chain.clone();
        if let Err(e) = sim.step(0.001) {
            println!("{e}");
            println!(
                "prev x {:?}\nv {:?}\nwrapped {} seg {} wrap {:?}",
                prev.x, prev.v, prev.wrapped, prev.wrap_segment, prev.wrap
            );
            for k in 0..prev.len() - 1 {
                println!("seg {k} {:?}", prev.segment(k));
            }
            break;
        }
    }
    Ok(())
}
