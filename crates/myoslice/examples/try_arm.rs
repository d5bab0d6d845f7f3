use myoslice::prelude::*;
fn main() -> Result<()> {
    let base = Simulation::phantom(SimulationConfig::default())?;
    for name in [
        "semimembranosus",
        "semitendinosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "rectus_femoris",
        "vastus_lateralis",
        "plantaris",
        "gastrocnemius_medial",
    ] {
        let i = base.muscle_index(name)?;
        let m = &base.muscles()[i];
        let w = m.chain.wrap.unwrap();
        println!(
            "{name}: wrap seg {} of {} r {:.3} side {} ins {:?} knee {:?}",
            m.chain.wrap_segment,
            m.chain.len() - 1,
            w.radius,
            w.side,
            m.chain.insertion.rest,
            base.skeleton().knee().point
        );
        for deg in [0.0, 30.0, 60.0, 90.0, 120.0] {
            let mut s = base.clone();
            s.set_knee(f64::to_radians(deg), 0.0)?;
            s.set_excitation(name, 0.5)?;
            s.step(0.002)?;
            let m = &s.muscles()[i];
            let k = m.chain.wrap_segment;
            let cl = w.clearance(m.chain.x[k], m.chain.x[k + 1]);
            println!(
                "  {deg:5.0} deg: arm {:5.2} cm wrapped {} clearance {:.3} path {:.4} l~ {:.2}",
                m.moment_arm * 100.0,
                m.chain.wrapped,
                cl,
                m.path_length,
                m.fibre.length / m.hill.optimal_fibre_length
            );
        }
    }
    Ok(())
}
