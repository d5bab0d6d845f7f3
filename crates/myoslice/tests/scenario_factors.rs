//! A scenario's factors on muscle parameters and excitations act on the built model.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use std::path::Path;

use myoslice::muscle::MuscleScale;
use myoslice::prelude::*;

const BASE: &str = "[simulation]\nduration_s = 0.3\n[tissue]\nenabled = false\n\
                    [excitation]\nhamstrings = [[0.0, 0.5]]\n";

fn knee_after(text: &str) -> f64 {
    let sc = Scenario::from_str_at(text, Path::new("factors.toml")).unwrap();
    let mut sim = sc.build().unwrap();
    sim.step(sc.simulation.duration_s).unwrap();
    sim.knee_angle()
}

#[test]
fn stronger_hamstrings_flex_the_knee_further_and_weaker_excitation_less() {
    let base = knee_after(BASE);
    let strong = knee_after(&format!(
        "{BASE}[muscle.hamstrings]\nmax_force_scale = 2.0\n"
    ));
    let gentle = knee_after(&BASE.replace(
        "duration_s = 0.3\n",
        "duration_s = 0.3\nexcitation_scale = 0.5\n",
    ));
    assert!(base > 0.05, "base flexion {base}");
    assert!(strong > base + 0.02, "strong {strong} vs {base}");
    assert!(gentle < base - 0.02, "gentle {gentle} vs {base}");
}

#[test]
fn scaling_a_muscle_twice_does_not_compound_and_unknown_names_are_refused() {
    let sc = Scenario::from_str_at(BASE, Path::new("factors.toml")).unwrap();
    let mut sim = sc.build().unwrap();
    let i = sim.muscle_index("semitendinosus").unwrap();
    let built = sim.muscles()[i].hill.max_isometric_force;
    let s = MuscleScale {
        max_force_scale: 1.5,
        ..MuscleScale::default()
    };
    sim.scale_muscle("semitendinosus", &s).unwrap();
    sim.scale_muscle("semitendinosus", &s).unwrap();
    let scaled = sim.muscles()[i].hill.max_isometric_force;
    assert!((scaled / built - 1.5).abs() < 1e-12, "{scaled} / {built}");
    let e = sim
        .scale_muscle("semitendinosis", &s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("semitendinosus"), "{e}");
    let text = format!("{BASE}[muscle.hamstring]\ntendon_slack_length_scale = 1.1\n");
    let e = Scenario::from_str_at(&text, Path::new("factors.toml"))
        .unwrap()
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("muscle.hamstring") && e.contains("hamstrings"),
        "{e}"
    );
}

#[test]
fn a_muscle_named_alone_overrides_its_group_whatever_the_order() {
    let text = format!(
        "{BASE}[muscle.semitendinosus]\nmax_force_scale = 2.0\n\
         [muscle.hamstrings]\nmax_force_scale = 1.5\n"
    );
    let sc = Scenario::from_str_at(&text, Path::new("factors.toml")).unwrap();
    let sim = sc.build().unwrap();
    let ratio = |name: &str| {
        let m = &sim.muscles()[sim.muscle_index(name).unwrap()];
        m.hill.max_isometric_force / m.built_hill.max_isometric_force
    };
    assert_eq!(ratio("semitendinosus"), 2.0);
    assert_eq!(ratio("semimembranosus"), 1.5);
    assert_eq!(ratio("vastus_lateralis"), 1.0);
    // The same model, its lattice reused: the same simulation.
    let again = sc.build_on(sc.lattice().unwrap()).unwrap();
    assert_eq!(sc.lattice_key(), sc.lattice_key());
    assert_eq!(again.muscles().len(), sim.muscles().len());
}
