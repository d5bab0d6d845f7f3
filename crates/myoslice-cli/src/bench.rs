//! `myoslice bench`: times the standard cases on this machine.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use myoslice::prelude::*;
use myoslice::tissue::FatSolver;
use serde_json::json;

struct Case {
    name: &'static str,
    seconds: f64,
    per_unit_ns: Option<f64>,
    unit: &'static str,
    realtime_factor: Option<f64>,
    note: String,
}

fn best_of<T>(n: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..n {
        let t = Instant::now();
        let r = f()?;
        let s = t.elapsed().as_secs_f64();
        // The fastest run's output (its timers, where a case reports them).
        if s < best || out.is_none() {
            (best, out) = (s, Some(r));
        }
    }
    Ok((best, out.ok_or_else(|| anyhow::anyhow!("no run"))?))
}

fn fat_case(
    name: &'static str,
    dims: (usize, usize, usize),
    iters: usize,
    runs: usize,
) -> Result<Case> {
    let mut s = FatSolver::grid(dims.0, dims.1, dims.2, 0.01);
    // Bend it a little so the rotations are not trivial.
    for p in &mut s.x {
        p.z += 0.02 * (p.x * 10.0).sin();
    }
    let n = s.len();
    let (t, _) = best_of(runs, || {
        for _ in 0..iters {
            s.iterate(0.5);
        }
        Ok(())
    })?;
    Ok(Case {
        name,
        seconds: t,
        per_unit_ns: Some(t * 1e9 / (iters * n) as f64),
        unit: "ns per element-iteration",
        realtime_factor: None,
        note: format!(
            "{n} hexahedra, {iters} iterations, {} threads",
            rayon::current_num_threads()
        ),
    })
}

fn knee_case(
    name: &'static str,
    cfg: SimulationConfig,
    muscles: &[&str],
    note: &str,
    runs: usize,
) -> Result<Case> {
    let base = Simulation::phantom(cfg)?;
    let (t, (angle, timers)) = best_of(runs, || {
        let mut s = base.clone();
        s.reset_timers();
        for m in muscles {
            s.set_excitation(m, 0.6)?;
        }
        s.step(1.0)?;
        Ok((s.knee_angle().to_degrees(), *s.timers()))
    })?;
    let mut note = format!("{note}; knee reached {angle:.1}°");
    // Where a tissue update's time goes (ms per update, the fastest run's).
    if timers.tissue_updates > 0 {
        let per = 1e3 / timers.tissue_updates as f64;
        let phases: Vec<String> = timers
            .tissue_phases
            .named()
            .iter()
            .map(|(name, s)| format!("{name} {:.2}", s * per))
            .collect();
        note += &format!(
            "; per tissue update (ms): {}, all {:.2}",
            phases.join(", "),
            timers.tissue_wall_s * per
        );
    }
    Ok(Case {
        name,
        seconds: t,
        per_unit_ns: Some(t * 1e9 / 1000.0),
        unit: "ns per 1 ms step",
        realtime_factor: Some(1.0 / t),
        note,
    })
}

/// What `myoslice bench` runs and how it prints.
#[derive(Debug, Clone)]
pub struct BenchOptions<'a> {
    /// JSON instead of a table.
    pub json: bool,
    /// The Visible Human folder, to time its build too.
    pub visible_human: Option<&'a Path>,
    /// Only the cases whose name contains this.
    pub only: Option<&'a str>,
    /// Runs per case (the best is reported).
    pub runs: usize,
    /// The whole leg's tissue updates per simulated second (default: the library's).
    pub tissue_rate_hz: Option<f64>,
    /// The whole leg's shape-matching iterations per update (default: the library's).
    pub tissue_iterations: Option<usize>,
}

/// Runs every case (or those `only` names) and prints the table (or JSON).
pub fn run(o: &BenchOptions) -> Result<()> {
    let wanted = |name: &str| o.only.is_none_or(|w| name.contains(w));
    let runs = o.runs.max(1);
    // The whole leg's tissue options, checked before any case runs. Slower updates or
    // fewer iterations trade the tissue's smoothness for speed (the README's table).
    let mut leg = SimulationConfig::default();
    leg.tissue.rate_hz = o.tissue_rate_hz.unwrap_or(leg.tissue.rate_hz);
    leg.tissue.iterations = o.tissue_iterations.unwrap_or(leg.tissue.iterations);
    leg.validate()?;
    if (o.tissue_rate_hz.is_some() || o.tissue_iterations.is_some()) && !wanted("whole_leg_step") {
        anyhow::bail!(
            "--tissue-rate and --tissue-iterations apply to whole_leg_step, which --only '{}' \
             leaves out",
            o.only.unwrap_or_default()
        );
    }
    let mut cases = Vec::new();
    if wanted("build_phantom") {
        let (t, lat) = best_of(runs, || {
            let (v, tb) = Phantom::default().generate()?;
            Ok(Lattice::build(&v, &tb, &BuildOptions::default())?)
        })?;
        cases.push(Case {
            name: "build_phantom",
            seconds: t,
            per_unit_ns: None,
            unit: "s",
            realtime_factor: None,
            note: format!("generate + build, {} fat hexahedra", lat.fat.hexes.len()),
        });
    }
    if let Some(dir) = o.visible_human.filter(|_| wanted("build_visible_human")) {
        let (t, lat) = best_of(runs, || {
            let v = read_nifti(dir.join("vhf_left_leg_labels.nii.gz"))?;
            let tb = LabelTable::from_path(dir.join("vhf_left_leg_labels.json"))?;
            Ok(Lattice::build(&v, &tb, &BuildOptions::default())?)
        })?;
        cases.push(Case {
            name: "build_visible_human",
            seconds: t,
            per_unit_ns: None,
            unit: "s",
            realtime_factor: None,
            note: format!("read + build, {} fat hexahedra", lat.fat.hexes.len()),
        });
    }
    const FLEXORS: [&str; 10] = [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "gracilis",
        "sartorius",
        "gastrocnemius_medial",
        "gastrocnemius_lateral",
        "popliteus",
        "plantaris",
    ];
    let mut muscles_only = SimulationConfig::default();
    muscles_only.tissue.enabled = false;
    if wanted("knee_hinge_16") {
        cases.push(knee_case(
            "knee_hinge_16",
            muscles_only.clone(),
            &FLEXORS,
            "all muscles, the 10 flexors excited at 0.6, Hill, 1 ms, no tissue",
            runs,
        )?);
    }
    if wanted("knee_hinge_16_compliant") {
        cases.push(knee_case(
            "knee_hinge_16_compliant",
            SimulationConfig {
                tendon: TendonModel::Compliant,
                ..muscles_only
            },
            &FLEXORS,
            "as knee_hinge_16 with compliant tendons",
            runs,
        )?);
    }
    for (name, dims, iters) in [
        ("fat_kernel_840", (20, 7, 6), 2000),
        ("fat_kernel_20k", (40, 25, 20), 100),
        ("fat_kernel_200k", (100, 50, 40), 10),
    ] {
        if wanted(name) {
            cases.push(fat_case(name, dims, iters, runs)?);
        }
    }
    if wanted("whole_leg_step") {
        let note = format!(
            "all muscles, tissue at {} Hz x {} iterations, 1 ms",
            leg.tissue.rate_hz, leg.tissue.iterations
        );
        cases.push(knee_case("whole_leg_step", leg, &FLEXORS, &note, runs)?);
    }
    if cases.is_empty() {
        anyhow::bail!(
            "no benchmark case matches '{}' (cases: build_phantom, build_visible_human, \
             knee_hinge_16, knee_hinge_16_compliant, fat_kernel_840, fat_kernel_20k, fat_kernel_200k, whole_leg_step)",
            o.only.unwrap_or_default()
        );
    }
    let machine = machine();
    let date = std::process::Command::new("date")
        .arg("-u")
        .arg("+%Y-%m-%d")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    if o.json {
        let v = json!({
            "machine": machine,
            "date": date,
            "threads": rayon::current_num_threads(),
            "cases": cases.iter().map(|c| json!({
                "name": c.name, "seconds": c.seconds, "per_unit_ns": c.per_unit_ns, "unit": c.unit,
                "realtime_factor": c.realtime_factor, "note": c.note,
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{machine}, {} threads, {date}",
            rayon::current_num_threads()
        );
        println!(
            "{:<20} {:>10} {:>14} {:>10}  note",
            "case", "seconds", "per unit", "x realtime"
        );
        for c in &cases {
            println!(
                "{:<20} {:>10.4} {:>14} {:>10}  {}",
                c.name,
                c.seconds,
                c.per_unit_ns.map_or("-".into(), |v| format!("{v:.1} ns")),
                c.realtime_factor.map_or("-".into(), |v| format!("{v:.1}")),
                c.note
            );
        }
    }
    Ok(())
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    format!(
        "{cpu}, {} logical cores",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    )
}
