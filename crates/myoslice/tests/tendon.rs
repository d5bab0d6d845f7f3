//! The compliant tendon: its backward-Euler solve, its stretch under load, and a
//! simulation driven by units with elastic tendons.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use myoslice::muscle::hill::tendon_force_length;
use myoslice::muscle::{HillParams, MuscleCatalogue};
use myoslice::prelude::*;

use common::{HAMSTRINGS, phantom_lattice};

fn sim(tendon: TendonModel) -> Simulation {
    let mut c = SimulationConfig {
        tendon,
        ..SimulationConfig::default()
    };
    c.tissue.enabled = false;
    Simulation::new(phantom_lattice().clone(), c, &MuscleCatalogue::default()).unwrap()
}

/// A pennate unit with a long tendon (semitendinosus-like proportions).
fn unit() -> HillParams {
    HillParams::new(1000.0, 0.1, 0.25, 0.2, 10.0)
}

#[test]
fn a_compliant_tendon_pulls_exactly_as_hard_as_its_fibre_after_every_step() {
    let p = unit();
    let fmax = p.max_isometric_force;
    // Activation, muscle-tendon length, previous fibre length, step: shortening,
    // lengthening, isometric, inactive, slack and stretched units, small and large steps.
    let cases = [
        (1.0, 0.36, 0.10, 1e-3),
        (1.0, 0.36, 0.12, 1e-3),
        (0.5, 0.34, 0.09, 1e-3),
        (0.0, 0.36, 0.10, 1e-3),
        (0.0, 0.30, 0.10, 1e-3),
        (0.2, 0.40, 0.14, 1e-4),
        (1.0, 0.33, 0.05, 1e-2),
        (0.8, 0.50, 0.10, 1e-3),
    ];
    for (a, l_mt, prev, h) in cases {
        let f = p.compliant_tendon_step(a, l_mt, prev, Some(h));
        assert!(f.length.is_finite() && f.length > 0.0, "{f:?}");
        let tendon = p.tendon_force(l_mt - f.length * f.cos_pennation);
        let fibre = p.force(a, &f).tendon;
        assert!(
            (tendon - fibre).abs() <= 1e-6 * fmax,
            "a {a}, l_mt {l_mt}, prev {prev}: tendon {tendon} N, fibre {fibre} N"
        );
        assert!(((f.length - prev) / h - f.velocity).abs() <= 1e-9 * f.velocity.abs().max(1.0));
    }
}

#[test]
fn a_held_active_unit_settles_at_optimal_fibre_length_with_its_tendon_stretched() {
    // Held at the length where a fully active fibre at optimal length balances its tendon;
    // started with the fibre 20 % short, it lengthens (stretching the tendon less) until
    // it settles there, pulling F_max along the fibre.
    let p = unit();
    let cos_a = p.pennation.cos();
    // De Groote's tendon curve reaches F_max·cos α at this normalised length.
    let l_t = 0.995 + ((cos_a + 0.25) / 0.2).ln() / 35.0;
    assert!((tendon_force_length(l_t) - cos_a).abs() < 1e-12);
    let l_mt = p.optimal_fibre_length * cos_a + p.tendon_slack_length * l_t;
    let mut fibre = 0.08;
    let mut state = None;
    for _ in 0..2000 {
        let f = p.compliant_tendon_step(1.0, l_mt, fibre, Some(1e-3));
        fibre = f.length;
        state = Some(f);
    }
    let f = state.unwrap();
    let force = p.force(1.0, &f).tendon;
    let strain = (l_mt - f.length * f.cos_pennation) / p.tendon_slack_length - 1.0;
    assert!(
        (f.length / p.optimal_fibre_length - 1.0).abs() < 0.01,
        "fibre at {:.4} of optimal",
        f.length / p.optimal_fibre_length
    );
    assert!(
        (force / (p.max_isometric_force * cos_a) - 1.0).abs() < 0.01,
        "{force} N"
    );
    // About 4.7 % at F_max (De Groote 2016's curve; Zajac 1989 gives 3.3 %).
    assert!((0.04..0.05).contains(&strain), "tendon strain {strain}");
    assert!(
        f.velocity.abs() < 1e-6,
        "still moving at {} m/s",
        f.velocity
    );
}

#[test]
fn the_static_equilibrium_needs_no_fibre_velocity() {
    let p = unit();
    for (a, l_mt) in [(1.0, 0.36), (0.3, 0.35), (0.0, 0.37), (0.0, 0.30)] {
        let f = p.compliant_tendon_step(a, l_mt, 0.1, None);
        assert_eq!(f.velocity, 0.0);
        let tendon = p.tendon_force(l_mt - f.length * f.cos_pennation);
        assert!((tendon - p.force(a, &f).tendon).abs() <= 1e-6 * p.max_isometric_force);
    }
}

#[test]
fn knee_flexes_past_60_degrees_within_a_second_with_compliant_tendons() {
    let mut s = sim(TendonModel::Compliant);
    let rigid = sim(TendonModel::Rigid);
    // Built at rest: tendons at their zero-force length, fibres where the rigid model
    // puts them.
    for (m, r) in s.muscles().iter().zip(rigid.muscles()) {
        let rel = (m.fibre.length - r.fibre.length).abs() / r.fibre.length;
        assert!(
            rel < 0.02,
            "{}: fibre {} vs {}",
            m.name,
            m.fibre.length,
            r.fibre.length
        );
    }
    for m in HAMSTRINGS {
        s.set_excitation(m, 1.0).unwrap();
    }
    let mut reached = None;
    let mut stretched = false;
    let mut max_strain: f64 = 0.0;
    let [lo, hi] = [0.0, 140f64.to_radians()];
    for k in 0..100 {
        s.step(0.01).unwrap();
        let a = s.knee_angle();
        assert!((lo - 1e-3..=hi + 1e-3).contains(&a), "knee at {a} rad");
        if reached.is_none() && a > 60f64.to_radians() {
            reached = Some(0.01 * (k + 1) as f64);
        }
        let m = s.muscle("semitendinosus").unwrap();
        let i = s.muscle_index("semitendinosus").unwrap();
        let u = &s.muscles()[i];
        let tendon = m.path_length - u.fibre.length * u.fibre.cos_pennation;
        if m.force > 100.0 && tendon > u.hill.tendon_slack_length * 1.002 {
            stretched = true;
        }
        max_strain = max_strain.max(tendon / u.hill.tendon_slack_length - 1.0);
    }
    println!(
        "compliant: knee {:.1}° at 1 s, semitendinosus tendon strain up to {:.2} %",
        s.knee_angle().to_degrees(),
        100.0 * max_strain
    );
    assert!(
        reached.is_some_and(|t| t <= 1.0),
        "knee at {:.1}° after 1 s",
        s.knee_angle().to_degrees()
    );
    assert!(
        stretched,
        "the loaded semitendinosus tendon never stretched"
    );
}

#[test]
fn compliant_stepping_is_deterministic() {
    let run = || {
        let mut s = sim(TendonModel::Compliant);
        for m in HAMSTRINGS {
            s.set_excitation(m, 0.7).unwrap();
        }
        s.step(0.3).unwrap();
        (
            s.knee_angle().to_bits(),
            s.muscles()
                .iter()
                .map(|m| m.fibre.length.to_bits())
                .collect::<Vec<_>>(),
        )
    };
    assert_eq!(run(), run());
}

#[test]
fn switching_tendons_mid_run_starts_each_fibre_where_the_new_model_puts_it() {
    let mut s = sim(TendonModel::Rigid);
    for m in HAMSTRINGS {
        s.set_excitation(m, 0.8).unwrap();
    }
    s.step(0.3).unwrap();
    assert_eq!(s.tendon_model(), TendonModel::Rigid);
    let mut unswitched = s.clone();
    let (checkpoint, mut reference) = (s.state(), s.clone());
    s.set_tendon_model(TendonModel::Compliant);
    assert_eq!(s.tendon_model(), TendonModel::Compliant);
    // In static equilibrium at once: tendon force equals fibre force along it.
    for u in s.muscles() {
        let f = u.hill.force(u.activation, &u.fibre);
        let tendon = u
            .hill
            .tendon_force(u.path_length - u.fibre.length * u.fibre.cos_pennation);
        assert!(
            (tendon - f.tendon).abs() <= 1e-6 * u.hill.max_isometric_force,
            "{}: tendon {tendon} N vs fibre {} N",
            u.name,
            f.tendon
        );
    }
    // The stretched tendons of the loaded hamstrings leave their fibres shorter.
    let i = s.muscle_index("semitendinosus").unwrap();
    let rigid_fibre = s.muscles()[i]
        .hill
        .rigid_tendon_kinematics(s.muscles()[i].path_length, 0.0)
        .length;
    assert!(s.muscles()[i].fibre.length < rigid_fibre);
    // The motion goes on from the same pose: over the next 50 ms the knee stays within
    // a few degrees of a run that kept its rigid tendons (the stretching tendons make it
    // flex about a degree slower).
    unswitched.step(0.05).unwrap();
    s.step(0.05).unwrap();
    let gap = (s.knee_angle() - unswitched.knee_angle()).to_degrees();
    assert!(gap.abs() < 3.0, "the switched knee is {gap:.2}° off");
    // And back: the fibre takes the whole path again.
    s.set_tendon_model(TendonModel::Rigid);
    let u = &s.muscles()[i];
    assert_eq!(
        u.fibre.length,
        u.hill
            .rigid_tendon_kinematics(u.path_length, u.path_velocity)
            .length
    );
    // Switching the muscle model keeps the pose and steps on.
    let angle = s.knee_angle();
    s.set_muscle_model(MuscleModel::Spring);
    assert_eq!(s.muscle_model(), MuscleModel::Spring);
    assert_eq!(s.knee_angle(), angle);
    s.step(0.1).unwrap();
    assert!(s.knee_angle().is_finite());
    // A checkpoint carries its models: restored, it replays the unswitched run exactly.
    s.set_state(&checkpoint).unwrap();
    assert_eq!(
        (s.muscle_model(), s.tendon_model()),
        (MuscleModel::Hill, TendonModel::Rigid)
    );
    s.step(0.05).unwrap();
    reference.step(0.05).unwrap();
    assert_eq!(s.knee_angle().to_bits(), reference.knee_angle().to_bits());
}

#[test]
fn model_names_parse_back_and_unknown_ones_are_named_in_the_error() {
    for m in MuscleModel::ALL {
        assert_eq!(m.name().parse::<MuscleModel>().unwrap(), m);
    }
    for t in TendonModel::ALL {
        assert_eq!(t.name().parse::<TendonModel>().unwrap(), t);
    }
    let e = "springy".parse::<MuscleModel>().unwrap_err().to_string();
    assert!(
        e.contains("muscle_model") && e.contains("'springy'") && e.contains("'hill'"),
        "{e}"
    );
    let e = "elastic".parse::<TendonModel>().unwrap_err().to_string();
    assert!(e.contains("tendon") && e.contains("'compliant'"), "{e}");
}

#[test]
fn an_active_fibre_on_a_slack_tendon_shortens_at_its_maximum_speed() {
    // The unit is shorter than its tendon's slack length: nothing resists the fibre, so
    // backward Euler lets it shorten at about v_max per step, where its force vanishes
    // (not to the bottom of the bracket in one step).
    let p = unit();
    let (lopt, h) = (p.optimal_fibre_length, 1e-3);
    let f = p.compliant_tendon_step(1.0, 0.8 * p.tendon_slack_length, lopt, Some(h));
    let shortening = (lopt - f.length) / (p.max_contraction_velocity * lopt * h);
    assert!(
        (0.95..=1.0).contains(&shortening),
        "shortened by {shortening} of v_max·h"
    );
    assert!(p.force(1.0, &f).tendon <= 1e-6 * p.max_isometric_force);
}

/// Whether muscle `i`'s fibre is where a rigid tendon puts it (bit for bit).
fn fibre_is_rigid(s: &Simulation, i: usize) -> bool {
    let u = &s.muscles()[i];
    u.fibre.length
        == u.hill
            .rigid_tendon_kinematics(u.path_length, u.path_velocity)
            .length
}

/// How far (m) muscle `i`'s tendon is stretched past its slack length.
fn tendon_stretch(s: &Simulation, i: usize) -> f64 {
    let u = &s.muscles()[i];
    u.path_length - u.fibre.length * u.fibre.cos_pennation - u.hill.tendon_slack_length
}

#[test]
fn one_muscle_can_have_its_own_tendon_while_the_others_keep_theirs() {
    let mut s = sim(TendonModel::Rigid);
    for m in HAMSTRINGS {
        s.set_excitation(m, 0.8).unwrap();
    }
    s.step(0.1).unwrap();
    let before = s.clone();
    s.set_muscle_tendon("semitendinosus", TendonModel::Compliant)
        .unwrap();
    // The default is unchanged, and so is every other muscle (bit for bit).
    assert_eq!(s.tendon_model(), TendonModel::Rigid);
    let st = s.muscle_index("semitendinosus").unwrap();
    for (i, (a, b)) in s.muscles().iter().zip(before.muscles()).enumerate() {
        let expect = if i == st {
            TendonModel::Compliant
        } else {
            TendonModel::Rigid
        };
        assert_eq!(s.readout(i).tendon, expect, "{}", a.name);
        if i != st {
            assert_eq!(a.fibre, b.fibre, "{}", a.name);
        }
    }
    s.step(0.2).unwrap();
    // Only the semitendinosus's loaded tendon stretches; every other fibre takes the
    // whole path (but for the last step's path change: the fibre went with the path at
    // the step's start).
    for i in 0..s.muscles().len() {
        let (stretch, name) = (tendon_stretch(&s, i), &s.muscles()[i].name);
        if i == st {
            assert!(stretch > 2e-3, "{name}: tendon stretched {stretch} m");
        } else {
            assert!(stretch.abs() < 1e-3, "{name}: tendon stretched {stretch} m");
        }
    }
    // Bad input changes nothing.
    let e = s
        .set_muscle_tendon("semitendinosis", TendonModel::Rigid)
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean 'semitendinosus'"), "{e}");
    assert_eq!(s.muscles()[st].tendon, TendonModel::Compliant);
    // A checkpoint carries each muscle's tendon; the global switch overrides them all.
    let checkpoint = s.state();
    s.set_tendon_model(TendonModel::Rigid);
    assert!(s.muscles().iter().all(|m| m.tendon == TendonModel::Rigid));
    assert!(fibre_is_rigid(&s, st));
    s.set_state(&checkpoint).unwrap();
    assert_eq!(s.muscles()[st].tendon, TendonModel::Compliant);
    assert_eq!(s.tendon_model(), TendonModel::Rigid);
}

#[test]
fn the_catalogue_gives_a_muscle_its_own_tendon() {
    let mut cat = MuscleCatalogue::default();
    let gm = cat.muscles.get_mut("gastrocnemius_medial").unwrap();
    gm.tendon = Some(TendonModel::Compliant);
    let mut c = SimulationConfig::default();
    c.tissue.enabled = false;
    let s = Simulation::new(phantom_lattice().clone(), c.clone(), &cat).unwrap();
    for (i, m) in s.muscles().iter().enumerate() {
        let own = m.name == "gastrocnemius_medial";
        assert_eq!(m.tendon == TendonModel::Compliant, own, "{}", m.name);
        assert_eq!(s.readout(i).tendon, m.tendon);
    }
    // A compliant default does not override a catalogued rigid tendon.
    cat.muscles.get_mut("semitendinosus").unwrap().tendon = Some(TendonModel::Rigid);
    c.tendon = TendonModel::Compliant;
    let s = Simulation::new(phantom_lattice().clone(), c, &cat).unwrap();
    assert_eq!(
        s.muscle("semitendinosus").unwrap().tendon,
        TendonModel::Rigid
    );
    assert_eq!(
        s.muscle("semimembranosus").unwrap().tendon,
        TendonModel::Compliant
    );
    // In the catalogue's text, with a bad value named.
    let head = "[default]\nspecific_tension_pa = 1\nfibre_fraction = 0.5\npennation_deg = 0\nmax_contraction_velocity = 10\nrest_fibre_length = 1\n[muscle.x]\n";
    let ok = MuscleCatalogue::from_toml_str(&format!("{head}tendon = \"compliant\"\n"), "c.toml")
        .unwrap();
    assert_eq!(ok.muscles["x"].tendon, Some(TendonModel::Compliant));
    let e = MuscleCatalogue::from_toml_str(&format!("{head}tendon = \"elastic\"\n"), "c.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("elastic") && e.contains("c.toml"), "{e}");
}
