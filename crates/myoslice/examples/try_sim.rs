use myoslice::prelude::*;
fn main() -> Result<()> {
    let t0 = std::time::Instant::now();
    let base = Simulation::phantom(SimulationConfig::default())?;
    println!(
        "built in {:.2}s; knee {:?}",
        t0.elapsed().as_secs_f64(),
        base.skeleton().knee()
    );
    println!("shank inertia {:?}", base.skeleton().inertia());
    for m in base.muscles() {
        println!(
            "{:28} {:?} pts {} cross {} lopt {:.3} lts {:.3} F {:.0} path {:.3} wrap {:?} bones {:?}",
            m.name,
            m.group,
            m.chain.len(),
            m.crosses_knee,
            m.hill.optimal_fibre_length,
            m.hill.tendon_slack_length,
            m.hill.max_isometric_force,
            m.path_length,
            m.chain.wrap.map(|w| (w.radius, w.side)),
            m.bones
        );
    }
    for (label, names, start) in [
        (
            "hamstrings",
            vec![
                "semitendinosus",
                "semimembranosus",
                "biceps_femoris_long",
                "biceps_femoris_short",
            ],
            0.0,
        ),
        (
            "quads",
            vec![
                "rectus_femoris",
                "vastus_lateralis",
                "vastus_medialis",
                "vastus_intermedius",
            ],
            90.0,
        ),
    ] {
        let mut sim = base.clone();
        if start > 0.0 {
            sim.set_knee(f64::to_radians(start), 0.0)?;
        }
        for n in &names {
            sim.set_excitation(n, 1.0)?;
        }
        let t1 = std::time::Instant::now();
        for k in 0..20 {
            sim.step(0.05)?;
            let ms: Vec<String> = names
                .iter()
                .map(|n| {
                    let r = sim.muscle(n).unwrap();
                    format!(
                        "{:.0}N/{:.1}cm/l{:.2}",
                        r.force,
                        r.moment_arm * 100.0,
                        r.normalised_fibre_length
                    )
                })
                .collect();
            if k % 2 == 1 {
                println!(
                    "{label} t={:.2} knee {:6.1} deg vel {:6.1} torque {:6.1} {}",
                    sim.time(),
                    sim.knee_angle().to_degrees(),
                    sim.knee_velocity().to_degrees(),
                    sim.knee_torque(),
                    ms.join(" ")
                );
            }
        }
        println!("wall {:.3}s for 1 s", t1.elapsed().as_secs_f64());
    }
    Ok(())
}
