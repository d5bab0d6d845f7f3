//! Muscle-driven knee motion: the rapier skeleton, the muscle chains and the Hill units.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

mod common;

use glam::Quat;
use myoslice::body::{Skeleton, SkeletonOptions, knee_axis};
use myoslice::muscle::hill::{
    activation_rate, active_force_length, force_velocity, passive_force_length, tendon_force_length,
};
use myoslice::muscle::{MuscleCatalogue, MuscleGroup};
use myoslice::prelude::*;

use common::{HAMSTRINGS, QUADRICEPS, assert_moment_arms_in_published_ranges, phantom_lattice};

fn config() -> SimulationConfig {
    let mut c = SimulationConfig::default();
    c.tissue.enabled = false;
    c
}

fn sim(c: SimulationConfig) -> Simulation {
    Simulation::new(phantom_lattice().clone(), c, &MuscleCatalogue::default()).unwrap()
}

#[test]
fn passive_shank_swings_with_the_compound_pendulum_period_and_keeps_its_energy() {
    let lat = phantom_lattice();
    let knee = knee_axis(lat.bone("femur").unwrap()).unwrap();
    // Gravity along the shank at 60° of flexion: the shank hangs there, clear of limits.
    let probe = Skeleton::new(
        lat,
        knee,
        &SkeletonOptions {
            body_mass: 60.0,
            height: 1.65,
            limits: [0.0, 2.4],
            damping: 0.0,
            gravity: [0.0, 0.0, -9.81],
        },
    )
    .unwrap();
    let down = (probe.shank_com_rest() - knee.point).normalize();
    let g = Quat::from_axis_angle(knee.axis, 60f32.to_radians()) * down * 9.81;
    let opts = SkeletonOptions {
        body_mass: 60.0,
        height: 1.65,
        limits: [0.0, 2.4],
        damping: 0.0,
        gravity: [f64::from(g.x), f64::from(g.y), f64::from(g.z)],
    };
    let mut sk = Skeleton::new(lat, knee, &opts).unwrap();
    let eq = 60f64.to_radians();
    sk.set_knee(eq + 3f64.to_radians(), 0.0);
    // Expected period from the segment's own mass, centre of mass and inertia.
    let inertia = *sk.inertia();
    let com = sk.shank_com_rest() - knee.point;
    let d = f64::from((com - knee.axis * com.dot(knee.axis)).length());
    let i_knee = inertia.inertia_transverse + inertia.mass * d * d;
    let expected = 2.0 * std::f64::consts::PI * (i_knee / (inertia.mass * 9.81 * d)).sqrt();
    let e0 = sk.shank_energy();
    let (mut crossings, mut prev, mut t, mut max_drift) =
        (Vec::new(), sk.knee_angle() - eq, 0.0, 0.0f64);
    let dt = 1e-3;
    while crossings.len() < 21 && t < 30.0 {
        sk.step(dt, &[]);
        t += dt;
        let x = sk.knee_angle() - eq;
        if prev > 0.0 && x <= 0.0 {
            crossings.push(t - dt * x / (x - prev));
        }
        prev = x;
        max_drift = max_drift.max((sk.shank_energy() - e0).abs());
    }
    assert!(
        crossings.len() >= 11,
        "only {} downward crossings",
        crossings.len()
    );
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let err = (period - expected).abs() / expected;
    assert!(
        err < 0.02,
        "period {period:.4} s vs compound pendulum {expected:.4} s ({:.2}%)",
        100.0 * err
    );
    // Energy of the swing: m g d (1 - cos 3°).
    let swing = inertia.mass * 9.81 * d * (1.0 - 3f64.to_radians().cos());
    // Measured against the swing's own energy, not the (much larger) potential energy
    // from the rest pose.
    assert!(
        max_drift < 0.01 * swing,
        "energy drift {max_drift:.2e} J is {:.2} % of the swing energy {swing:.2e} J",
        100.0 * max_drift / swing
    );
}

#[test]
fn knee_flexes_past_60_degrees_within_a_second_when_the_hamstrings_contract() {
    let mut s = sim(config());
    for m in HAMSTRINGS {
        s.set_excitation(m, 1.0).unwrap();
    }
    let mut reached = None;
    for k in 0..100 {
        s.step(0.01).unwrap();
        if reached.is_none() && s.knee_angle() > 60f64.to_radians() {
            reached = Some(0.01 * (k + 1) as f64);
        }
    }
    assert!(
        reached.is_some_and(|t| t <= 1.0),
        "knee at {:.1}° after 1 s",
        s.knee_angle().to_degrees()
    );
}

#[test]
fn the_quadriceps_extend_the_knee_from_90_degrees() {
    let mut s = sim(SimulationConfig {
        initial_knee_deg: 90.0,
        ..config()
    });
    assert!((s.knee_angle().to_degrees() - 90.0).abs() < 0.5);
    for m in QUADRICEPS {
        s.set_excitation(m, 0.6).unwrap();
    }
    s.step(1.0).unwrap();
    assert!(
        s.knee_angle().to_degrees() < 20.0,
        "knee at {:.1}°",
        s.knee_angle().to_degrees()
    );
}

#[test]
fn the_joint_never_passes_its_limits() {
    let mut s = sim(config());
    for m in HAMSTRINGS.iter().chain(["gracilis", "sartorius"].iter()) {
        s.set_excitation(m, 1.0).unwrap();
    }
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for _ in 0..150 {
        s.step(0.01).unwrap();
        lo = lo.min(s.knee_angle());
        hi = hi.max(s.knee_angle());
    }
    for m in HAMSTRINGS {
        s.set_excitation(m, 0.0).unwrap();
    }
    for m in QUADRICEPS {
        s.set_excitation(m, 1.0).unwrap();
    }
    for _ in 0..150 {
        s.step(0.01).unwrap();
        lo = lo.min(s.knee_angle());
        hi = hi.max(s.knee_angle());
    }
    let tol = 0.5f64.to_radians();
    assert!(
        lo >= -tol && hi <= 140f64.to_radians() + tol,
        "range [{:.2}, {:.2}] deg",
        lo.to_degrees(),
        hi.to_degrees()
    );
}

/// Muscle torque about the knee at an angle, all still (N m, + flexing).
fn torque_at(base: &Simulation, deg: f64, exc: &[(&str, f64)]) -> f64 {
    let mut s = base.clone();
    s.set_knee(deg.to_radians(), 0.0).unwrap();
    for (m, e) in exc {
        s.set_excitation(m, *e).unwrap();
    }
    // Let activation reach its steady state with the knee held: step and put it back.
    for _ in 0..40 {
        s.step(0.005).unwrap();
        s.set_knee(deg.to_radians(), 0.0).unwrap();
    }
    s.step(0.001).unwrap();
    s.knee_torque()
}

#[test]
fn co_contraction_holds_the_knee_and_stiffens_it() {
    let base = sim(SimulationConfig {
        initial_knee_deg: 45.0,
        ..config()
    });
    // Equal drive to both groups, scaled so their torques balance at 45°.
    let flex: Vec<(&str, f64)> = HAMSTRINGS.iter().map(|m| (*m, 0.3)).collect();
    let ext: Vec<(&str, f64)> = QUADRICEPS.iter().map(|m| (*m, 0.3)).collect();
    let tf = torque_at(&base, 45.0, &flex);
    let te = torque_at(&base, 45.0, &ext);
    assert!(
        tf > 0.0 && te < 0.0,
        "flexors {tf:.1} N m, extensors {te:.1} N m"
    );
    let k = (-te / tf).clamp(0.2, 5.0);
    let mut both: Vec<(&str, f64)> = HAMSTRINGS
        .iter()
        .map(|m| (*m, (0.3 * k).min(1.0)))
        .collect();
    both.extend(ext.iter().copied());
    let mut s = base.clone();
    for (m, e) in &both {
        s.set_excitation(m, *e).unwrap();
    }
    let mut worst = 0.0f64;
    for _ in 0..100 {
        s.step(0.01).unwrap();
        worst = worst.max((s.knee_angle().to_degrees() - 45.0).abs());
    }
    assert!(
        worst < 8.0,
        "co-contraction let the knee drift by {worst:.1}°"
    );
    // Stiffness: restoring torque per degree about 45°, relaxed and co-contracted.
    let stiff =
        |exc: &[(&str, f64)]| (torque_at(&base, 40.0, exc) - torque_at(&base, 50.0, exc)) / 10.0;
    let relaxed = stiff(&[]);
    let co = stiff(&both);
    assert!(
        co > relaxed + 0.05,
        "stiffness co-contracted {co:.3} vs relaxed {relaxed:.3} N m/deg"
    );
}

#[test]
fn hill_curves_match_the_published_de_groote_formulas() {
    // Values of De Groote et al. (2016) evaluated independently (Python, double precision).
    const FL: [(f64, f64); 7] = [
        (0.5, 0.054102394),
        (0.7, 0.684099775),
        (0.9, 0.936668197),
        (1.0, 0.999433461),
        (1.1, 0.952586641),
        (1.3, 0.580835322),
        (1.5, 0.226017735),
    ];
    const FPE: [(f64, f64); 4] = [
        (1.0, 0.0),
        (1.2, 0.052122469),
        (1.4, 0.249857805),
        (1.6, 1.0),
    ];
    const FV: [(f64, f64); 7] = [
        (-1.0, 0.010835476),
        (-0.5, 0.242828155),
        (-0.2, 0.551036828),
        (0.0, 1.002119219),
        (0.2, 1.345749325),
        (0.5, 1.585369331),
        (1.0, 1.789482663),
    ];
    const FT: [(f64, f64); 3] = [
        (1.0, -0.011750757),
        (1.02, 0.229775059),
        (1.04, 0.716148324),
    ];
    let check = |name: &str, f: &dyn Fn(f64) -> f64, table: &[(f64, f64)]| {
        for &(x, y) in table {
            let got = f(x);
            let tol = 0.01 * y.abs().max(0.01);
            assert!((got - y).abs() <= tol, "{name}({x}) = {got}, published {y}");
        }
    };
    check("f_L", &active_force_length, &FL);
    check("f_PE", &passive_force_length, &FPE);
    check("f_V", &force_velocity, &FV);
    check("f_T", &tendon_force_length, &FT);
}

#[test]
fn activation_rises_and_falls_with_the_published_time_constants() {
    let (ta, td) = (0.015, 0.060);
    // De Groote 2016: da/dt = (e - a)/(τa (0.5 + 1.5a)) when rising, (e - a)(0.5 + 1.5a)/τd
    // when falling.
    assert!((activation_rate(1.0, 0.0, ta, td, 10.0) - 1.0 / (0.5 * ta)).abs() < 1e-6 / ta);
    assert!((activation_rate(0.0, 1.0, ta, td, 10.0) + 2.0 / td).abs() < 1e-6 / td);
    let a = 0.4;
    let rise = activation_rate(0.8, a, ta, td, 10.0);
    assert!((rise - 0.4 / (ta * (0.5 + 1.5 * a))).abs() / rise < 0.01);
    let fall = activation_rate(0.1, a, ta, td, 10.0);
    assert!((fall + 0.3 * (0.5 + 1.5 * a) / td).abs() / fall.abs() < 0.01);
    // In a simulation, a step of excitation reaches 63% in about τa(0.5+1.5·0.3).
    let mut s = sim(config());
    s.set_excitation("semitendinosus", 1.0).unwrap();
    let mut t63 = 0.0;
    while s.muscle("semitendinosus").unwrap().activation < 0.632 {
        s.step(0.001).unwrap();
        t63 = s.time();
    }
    assert!((0.005..0.03).contains(&t63), "63% activation after {t63} s");
}

#[test]
fn moment_arms_lie_in_published_human_ranges() {
    println!("{}", assert_moment_arms_in_published_ranges(&sim(config())));
}

#[test]
fn pes_anserinus_tendons_keep_their_flexor_lever_at_deep_flexion() {
    // Semitendinosus, gracilis and sartorius insert on the tibia's anteromedial face and
    // come round the medial condyle from behind: their lever cannot turn through the
    // axis as the knee closes (semitendinosus about 4-5.5 cm, e.g. Spoor & van Leeuwen
    // 1992), unlike a straight line to a posterior insertion.
    let base = sim(config());
    for deg in [0.0, 60.0, 120.0, 140.0] {
        let mut s = base.clone();
        s.set_knee(f64::to_radians(deg), 0.0).unwrap();
        for m in ["semitendinosus", "gracilis", "sartorius"] {
            let r = s.muscle(m).unwrap().moment_arm * 100.0;
            assert!(
                (2.0..=5.5).contains(&r),
                "{m} at {deg}°: moment arm {r:.2} cm"
            );
        }
    }
}

#[test]
fn every_knee_flexor_flexes_and_every_extensor_extends_over_the_range() {
    let base = sim(config());
    for deg in [0.0, 30.0, 60.0, 90.0, 120.0] {
        let mut s = base.clone();
        s.set_knee(f64::to_radians(deg), 0.0).unwrap();
        for m in s.muscles().iter().filter(|m| m.crosses_knee) {
            let r = m.moment_arm;
            match m.group {
                MuscleGroup::Flexor => {
                    assert!(r > 0.005, "{} at {deg}°: moment arm {r:.4} m", m.name)
                }
                MuscleGroup::Extensor => {
                    assert!(r < -0.005, "{} at {deg}°: moment arm {r:.4} m", m.name)
                }
                MuscleGroup::Other => {}
            }
        }
    }
}

#[test]
fn moment_arms_equal_the_tendon_excursion() {
    // Virtual work (the reported moment arm) against tendon excursion: turn the knee by
    // ±0.5° with every chain point carried by its bone and difference the path lengths.
    let base = sim(config());
    let d = 0.5f64.to_radians();
    for deg in [5.0, 30.0, 60.0, 90.0, 120.0] {
        let mut at = base.clone();
        at.set_knee(f64::to_radians(deg), 0.0).unwrap();
        let (mut up, mut down) = (at.clone(), at.clone());
        up.set_knee(f64::to_radians(deg) + d, 0.0).unwrap();
        down.set_knee(f64::to_radians(deg) - d, 0.0).unwrap();
        for (i, m) in at
            .muscles()
            .iter()
            .enumerate()
            .filter(|(_, m)| m.crosses_knee)
        {
            let excursion = -(up.readout(i).path_length - down.readout(i).path_length) / (2.0 * d);
            let arm = at.readout(i).moment_arm;
            assert!(
                (arm - excursion).abs() <= 0.02 * excursion.abs() + 5e-4,
                "{} at {deg}°: moment arm {arm:.4} m, excursion {excursion:.4} m",
                m.name
            );
        }
    }
}

#[test]
fn moment_arms_are_reported_from_the_start() {
    let mut s = sim(config());
    for when in ["before the first step", "after the first step"] {
        for m in HAMSTRINGS {
            let r = s.muscle(m).unwrap().moment_arm;
            assert!(r > 0.01, "{m} {when}: moment arm {r} m");
        }
        for m in QUADRICEPS {
            let r = s.muscle(m).unwrap().moment_arm;
            assert!(r < -0.01, "{m} {when}: moment arm {r} m");
        }
        s.step(0.001).unwrap();
    }
}

#[test]
fn knee_torque_is_tendon_force_times_moment_arm() {
    let mut s = sim(config());
    s.set_knee(40f64.to_radians(), 0.0).unwrap();
    for m in HAMSTRINGS.iter().chain(&QUADRICEPS) {
        s.set_excitation(m, 0.3).unwrap();
    }
    for _ in 0..50 {
        s.step(0.001).unwrap();
        let sum: f64 = (0..s.muscles().len())
            .map(|i| {
                let r = s.readout(i);
                r.force * r.moment_arm
            })
            .sum();
        let tau = s.knee_torque();
        assert!(
            (tau - sum).abs() <= 1e-3 * sum.abs().max(1.0),
            "knee torque {tau} N m, sum of force × moment arm {sum} N m"
        );
    }
}

#[test]
fn bad_input_gets_clear_errors() {
    let mut s = sim(config());
    let e = s
        .set_excitation("semitendinosis", 0.5)
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean 'semitendinosus'"), "{e}");
    assert!(s.set_excitation("semitendinosus", 1.5).is_err());
    assert!(s.set_excitation("semitendinosus", f64::NAN).is_err());
    assert!(s.step(0.0).is_err());
    assert!(s.step(-0.01).is_err());
    assert!(s.step(f64::NAN).is_err());
    assert!(s.set_excitations(&[0.1, 0.2]).is_err());
    let e = Simulation::new(
        phantom_lattice().clone(),
        SimulationConfig {
            body_mass_kg: -3.0,
            ..config()
        },
        &MuscleCatalogue::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("body_mass_kg"), "{e}");
}

#[test]
fn a_simulation_that_blows_up_stops_with_an_error_and_keeps_the_last_good_state() {
    let mut cat = MuscleCatalogue::default();
    cat.muscles
        .get_mut("vastus_intermedius")
        .unwrap()
        .max_isometric_force_n = Some(1e30);
    let mut s = Simulation::new(phantom_lattice().clone(), config(), &cat).unwrap();
    s.step(0.01).unwrap();
    let (t, a) = (s.time(), s.knee_angle());
    s.set_excitation("vastus_intermedius", 1.0).unwrap();
    let e = s.step(0.2).unwrap_err().to_string();
    assert!(e.contains("non-finite"), "{e}");
    assert_eq!(
        (s.time(), s.knee_angle()),
        (t, a),
        "the state before the failing call is kept"
    );
}

#[test]
fn a_failed_call_leaves_no_trace_in_what_follows() {
    let mut cat = MuscleCatalogue::default();
    cat.muscles
        .get_mut("vastus_intermedius")
        .unwrap()
        .max_isometric_force_n = Some(3e6);
    let start = || {
        let mut s = Simulation::new(phantom_lattice().clone(), config(), &cat).unwrap();
        // A short extensor: no passive force from its huge strength until it is excited.
        s.set_excitation("semimembranosus", 0.8).unwrap();
        s.step(0.05).unwrap();
        s
    };
    let bits = |s: &Simulation| {
        let mut b = vec![s.time().to_bits(), s.knee_angle().to_bits()];
        b.push(s.knee_velocity().to_bits());
        b.extend(s.muscles().iter().map(|m| m.force.to_bits()));
        b.extend(s.muscles().iter().map(|m| m.path_length.to_bits()));
        b.extend(
            s.muscles()
                .iter()
                .flat_map(|m| m.chain.x.iter().map(|p| p.x.to_bits() as u64)),
        );
        b
    };
    // Every field of every muscle but its work buffers: a step that changed a field the
    // rollback does not save would show here.
    let muscles = |s: &Simulation| {
        let mut m = s.muscles().to_vec();
        m.iter_mut()
            .for_each(|m| m.chain.scratch = Default::default());
        format!("{m:?}")
    };
    let mut never = start();
    never.step(0.1).unwrap();
    let mut failed = start();
    let before = bits(&failed);
    let timed = *failed.timers();
    failed.set_excitation("vastus_intermedius", 1.0).unwrap();
    let before_muscles = muscles(&failed);
    // Strong enough to blow up only after its activation has risen for a few steps, so
    // that the skeleton has moved on before the call fails.
    match failed.step(0.2) {
        Err(Error::NonFinite { time, .. }) => assert!(time > 0.05 + 0.002, "failed at {time}"),
        other => panic!("expected a blow-up, got {other:?}"),
    }
    assert_eq!(bits(&failed), before, "the state before the call is back");
    assert!(
        muscles(&failed) == before_muscles,
        "every muscle field is back"
    );
    // The failed call's work is timed, but it advanced no simulated time.
    let t = failed.timers();
    assert_eq!(t.calls, timed.calls + 1);
    assert!(t.steps > timed.steps + 2 && t.wall_s > timed.wall_s);
    assert_eq!(t.simulated_s, timed.simulated_s);
    failed.set_excitation("vastus_intermedius", 0.0).unwrap();
    failed.step(0.1).unwrap();
    assert!(never.knee_velocity().abs() > 0.1, "the knee was moving");
    assert_eq!(bits(&failed), bits(&never));
}

#[test]
fn the_same_inputs_give_the_same_bits() {
    let run = || {
        let mut s = sim(config());
        s.set_excitation("semimembranosus", 0.7).unwrap();
        s.step(0.3).unwrap();
        (
            s.knee_angle().to_bits(),
            s.muscle("semimembranosus").unwrap().force.to_bits(),
        )
    };
    assert_eq!(run(), run());
}

#[test]
fn step_timers_count_every_call_and_stay_out_of_checkpoints() {
    let mut s = sim(config());
    let checkpoint = s.state();
    assert_eq!(s.timers().calls, 0, "building is not stepping");
    for _ in 0..3 {
        s.step(0.01).unwrap();
    }
    let t = *s.timers();
    assert_eq!((t.calls, t.steps, t.tissue_updates), (3, 30, 0));
    assert!((t.simulated_s - s.time()).abs() < 1e-12);
    assert!(t.wall_s > 0.0 && t.tissue_wall_s == 0.0 && t.muscles_wall_s() == t.wall_s);
    assert!(t.realtime_factor().is_some_and(|f| f > 0.0));
    // Timers measure the machine: restoring a checkpoint leaves them, a reset clears them.
    s.set_state(&checkpoint).unwrap();
    assert_eq!(*s.timers(), t);
    s.reset_timers();
    assert_eq!(s.timers().calls, 0);
    assert_eq!(s.timers().realtime_factor(), None);
}
