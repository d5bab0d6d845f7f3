//! `myoslice`: build reports, scenario runs and benchmarks from the command line.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use myoslice::BuildReport;

mod bench;
mod labels;
mod sweep;
use myoslice::prelude::*;

#[derive(Parser)]
#[command(
    name = "myoslice",
    version,
    about = "Deformable lower limb from labelled slices, moved by its muscles"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build the lattice body and report how well it matches the voxels.
    Build(BuildArgs),
    /// Run a scenario: VTU/PVD frames, an animated GLB, timeseries.csv and summary.json.
    Run(RunArgs),
    /// Time the standard cases (lattice build, muscle step, fat kernel, whole leg).
    Bench(BenchArgs),
    /// Step the phantom and print exact results as JSON (reference for the Python tests).
    Probe(ProbeArgs),
    /// Write axial slices of the model, coloured by label, side by side to a PNG.
    Slices(SlicesArgs),
    /// Measure a phantom definition (per-level outlines) from a labelled volume.
    PhantomMeasure(MeasureArgs),
    /// Show how a label table or a segmentation tool's label list (ITK-SNAP, 3D Slicer)
    /// reads: each label's name and the structure it maps to.
    Labels(labels::LabelsArgs),
    /// Run a sweep file's runs (a parameter study) on Ray or one after another, into one
    /// Parquet table; runs the Python package (`python3 -m myoslice sweep`, or the
    /// interpreter in MYOSLICE_PYTHON), which needs ray and pyarrow.
    Sweep(sweep::SweepArgs),
}

#[derive(Args)]
struct RunArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Override the scenario's duration (s), e.g. for a quick check.
    #[arg(long)]
    duration: Option<f64>,
    /// Audit the tissue after every update (`audit.csv`; about a second an update): folded
    /// and squashed fat, muscles and bones out through the skin, muscles in bone and in
    /// one another, skin crossings.
    #[arg(long)]
    audit: bool,
}

#[derive(Args)]
struct BenchArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Also time the Visible Human build from ../shared/data (path to the folder).
    #[arg(long)]
    visible_human: Option<PathBuf>,
    /// Run only the cases whose name contains this (e.g. `whole_leg` under a profiler).
    #[arg(long)]
    only: Option<String>,
    /// Runs of each case; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Tissue updates per simulated second for `whole_leg_step` (default: the library's).
    #[arg(long)]
    tissue_rate: Option<f64>,
    /// Shape-matching iterations per tissue update for `whole_leg_step` (default: the
    /// library's).
    #[arg(long)]
    tissue_iterations: Option<usize>,
}

#[derive(Args)]
struct ProbeArgs {
    /// Steps of --dt.
    #[arg(long, default_value_t = 1000)]
    steps: u64,
    /// Step (s).
    #[arg(long, default_value_t = 0.001)]
    dt: f64,
    /// Excitations NAME=VALUE.
    #[arg(long)]
    excite: Vec<String>,
    /// Deform the tissue too.
    #[arg(long)]
    tissue: bool,
}

#[derive(Args)]
struct SlicesArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Heights of the slices (mm, volume frame).
    #[arg(long, value_delimiter = ',', default_value = "700,500,330")]
    z_mm: Vec<f64>,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args)]
struct MeasureArgs {
    /// NIfTI label volume.
    #[arg(long)]
    volume: PathBuf,
    /// Label table.
    #[arg(long)]
    labels: PathBuf,
    /// Output definition (TOML).
    #[arg(long)]
    out: PathBuf,
    /// Distance between measured levels (mm).
    #[arg(long, default_value_t = 10.0)]
    level_mm: f64,
    /// Rays per outline.
    #[arg(long, default_value_t = 32)]
    angles: usize,
    /// Provenance written into the file.
    #[arg(long, default_value = "measured")]
    source: String,
}

#[derive(Args)]
struct ModelArgs {
    /// Use the built-in phantom (the default when no volume is given).
    #[arg(long, conflicts_with_all = ["volume", "labels"])]
    phantom: bool,
    /// Label volume: NIfTI-1/-2 (.nii, .nii.gz) or NRRD (.nrrd, .nhdr), or a PNG stack
    /// (folder or manifest), told apart by content; a 3D Slicer segmentation (.seg.nrrd)
    /// names its own labels.
    #[arg(long)]
    volume: Option<PathBuf>,
    /// Label table (.json, .toml), ITK-SNAP label description file or 3D Slicer colour
    /// table (see `myoslice labels`).
    #[arg(long, requires = "volume")]
    labels: Option<PathBuf>,
    /// Label names no structure is known by: an error, or fat, or background.
    #[arg(long, value_enum, default_value_t = labels::UnmappedArg::Error)]
    unmapped: labels::UnmappedArg,
    /// Your own label names (TOML, see `myoslice labels --help`).
    #[arg(long, requires = "volume")]
    names: Option<PathBuf>,
    /// Keep every K-th slice.
    #[arg(long, default_value_t = 5)]
    slice_step: usize,
    /// Rays per polygon.
    #[arg(long, default_value_t = 48)]
    rays: usize,
    /// Resample slices in-plane to this pixel size (mm).
    #[arg(long)]
    pixel_mm: Option<f64>,
}

#[derive(Args)]
struct BuildArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Write the JSON report here.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Write the lattice as a VTK unstructured grid here.
    #[arg(long)]
    vtu: Option<PathBuf>,
}

fn load(m: &ModelArgs) -> Result<(LabelVolume, LabelTable, String)> {
    match &m.volume {
        Some(v) => {
            let mapping = labels::mapping(m.unmapped, m.names.as_deref())?;
            let (vol, table) = myoslice::io::read_input(v, m.labels.as_deref(), mapping)?;
            Ok((vol, table, v.display().to_string()))
        }
        None => {
            let (vol, table) = myoslice::phantom::Phantom::default().generate()?;
            Ok((vol, table, "built-in phantom".into()))
        }
    }
}

/// A spinner on stderr naming the stage of a multi-second job (drawn only on a terminal).
fn stages() -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new_spinner();
    pb.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}

fn build(args: &BuildArgs) -> Result<()> {
    let pb = stages();
    pb.set_message("reading the label volume");
    let t0 = Instant::now();
    let (volume, table, source) = load(&args.model)?;
    let read = t0.elapsed().as_secs_f64();
    let opts = BuildOptions {
        reduction: SliceReduction {
            slice_step: args.model.slice_step,
            pixel_mm: args.model.pixel_mm,
        },
        rays: args.model.rays,
        ..BuildOptions::default()
    };
    pb.set_message("building the lattice");
    let t1 = Instant::now();
    let lattice = Lattice::build(&volume, &table, &opts)?;
    let build_time = t1.elapsed().as_secs_f64();
    let catalogue = myoslice::muscle::MuscleCatalogue::default();
    for m in lattice
        .muscles
        .iter()
        .filter(|m| !catalogue.muscles.contains_key(&m.name))
    {
        pb.suspend(|| {
            eprintln!(
                "warning: muscle '{}' has no entry in the muscle catalogue: its parameters \
                 will come from its volume and length",
                m.name
            )
        });
    }
    pb.set_message("measuring volumes and coverage");
    let mut report = BuildReport::measure(&volume, &lattice, &source);
    pb.set_message("checking invariants");
    let inv = lattice.check_invariants();
    pb.finish_and_clear();
    report.read_time_s = read;
    report.build_time_s = build_time;
    println!(
        "{:<28} {:>6} {:>10} {:>10} {:>7} {:>6} {:>6}",
        "structure", "kind", "voxel cm3", "lattice", "error", "IoU", "traced"
    );
    for s in &report.structures {
        println!(
            "{:<28} {:>6} {:>10.1} {:>10.1} {:>6.1}% {:>6} {:>6}",
            s.name,
            s.kind.as_str(),
            s.voxel_volume_cm3,
            s.lattice_volume_cm3,
            100.0 * s.volume_error,
            s.mean_iou.map_or("-".into(), |v| format!("{v:.3}")),
            s.traced_polygons
        );
    }
    let t = &report.totals;
    println!(
        "{} slices x {} rays: {} vertices, {} fat hexahedra, {} muscle elements; read {:.2} s, build {:.2} s",
        t.slices, t.rays, t.vertices, t.fat_elements, t.muscle_elements, read, build_time
    );
    println!(
        "invariants: open bones {:?}, fat elements <= 0: {}, muscle elements <= 0: {}/{}, fat vertices in bone: {}, duplicates {:?}",
        inv.open_bones,
        inv.nonpositive_fat,
        inv.nonpositive_muscle_elements,
        inv.muscle_elements,
        inv.fat_in_bone,
        inv.duplicate_vertices
    );
    let sum = |f: fn(&myoslice::StructureReport) -> Option<usize>| {
        report.structures.iter().filter_map(f).sum::<usize>()
    };
    println!(
        "muscle vertices drawn out of bone: {}, left inside: {}",
        sum(|s| s.vertices_drawn_out_of_bone),
        sum(|s| s.vertices_left_in_bone)
    );
    if let Some(p) = &args.vtu {
        myoslice::export::rest_vtu(&lattice).write(p)?;
    }
    if let Some(p) = &args.report {
        std::fs::write(p, report.to_json()).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

fn run_scenario(a: &RunArgs) -> Result<()> {
    let mut sc = Scenario::from_path(&a.scenario)?;
    if let Some(d) = a.duration {
        anyhow::ensure!(
            d.is_finite() && d > 0.0,
            "--duration {d}: expected a duration > 0 s"
        );
        sc.simulation.duration_s = d;
    }
    sc.output.audit |= a.audit;
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(0)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {msg}  eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut warned = false;
    let summary = myoslice::export::run_scenario(&sc, &a.out, &mut |p| {
        if !warned {
            for w in p.sim.warnings() {
                bar.suspend(|| eprintln!("warning: {w}"));
            }
            bar.set_length(p.steps);
            warned = true;
        }
        bar.set_position(p.step);
        if p.step % 50 == 0 {
            bar.set_message(format!("knee {:.1}°", p.sim.knee_angle().to_degrees()));
        }
    })?;
    bar.finish_and_clear();
    if !a.quiet {
        println!(
            "{:.2} s simulated in {:.2} s ({:.2}x real time; muscles {:.2} s, tissue {:.2} s): knee {:.1}..{:.1}°, {} frames -> {}",
            summary.duration_s,
            summary.wall_time_s,
            summary.realtime_factor,
            summary.muscles_wall_time_s,
            summary.tissue_wall_time_s,
            summary.knee_angle_range_deg[0],
            summary.knee_angle_range_deg[1],
            summary.frames,
            a.out.display()
        );
        println!(
            "fat elements folded (ParaView's test): at most {}, {} at the end; the validity guard stepped in at {} tissue updates ({} vertices)",
            summary.inverted_elements,
            summary.final_inverted_elements,
            summary.guard.updates,
            summary.guard.vertices
        );
        if let Some(r) = &summary.audit {
            print_audit(r);
        }
    }
    Ok(())
}

/// The worst of each tissue check over an audited run, and where it ended.
fn print_audit(r: &myoslice::export::RunAudit) {
    println!("audit of {} tissue updates, worst (last):", r.updates);
    for (w, l) in r.worst.lines().into_iter().zip(r.last.lines()) {
        let mark = if w.holds { " " } else { "!" };
        println!("{mark} {:24} {} ({})", w.check, w.found, l.found);
    }
}

fn probe(a: &ProbeArgs) -> Result<()> {
    let mut cfg = SimulationConfig::default();
    cfg.tissue.enabled = a.tissue;
    let mut sim = Simulation::phantom(cfg)?;
    for e in &a.excite {
        let (n, v) = e
            .split_once('=')
            .with_context(|| format!("--excite {e}: expected NAME=VALUE"))?;
        sim.set_excitation(
            n,
            v.parse()
                .with_context(|| format!("--excite {e}: bad number"))?,
        )?;
    }
    let t0 = Instant::now();
    for _ in 0..a.steps {
        sim.step(a.dt)?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let list = |v: Vec<f64>| {
        format!(
            "[{}]",
            v.iter()
                .map(|x| format!("{x:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    println!(
        "{{\"time\": {:?}, \"knee_angle\": {:?}, \"knee_velocity\": {:?}, \"forces\": {}, \"activations\": {}, \"wall_s\": {:?}}}",
        sim.time(),
        sim.knee_angle(),
        sim.knee_velocity(),
        list(sim.muscles().iter().map(|m| m.force).collect()),
        list(sim.muscles().iter().map(|m| m.activation).collect()),
        wall
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: &Cli) -> Result<()> {
    match &cli.command {
        Command::Build(a) => build(a),
        Command::Run(a) => run_scenario(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Bench(a) => bench::run(&bench::BenchOptions {
            json: a.json,
            visible_human: a.visible_human.as_deref(),
            only: a.only.as_deref(),
            runs: a.runs,
            tissue_rate_hz: a.tissue_rate,
            tissue_iterations: a.tissue_iterations,
        }),
        Command::Probe(a) => probe(a),
        Command::Labels(a) => labels::run(a),
        Command::Slices(a) => {
            let (vol, table, _) = load(&a.model)?;
            let ks = myoslice::export::write_axial_slices(&vol, &table, &a.z_mm, &a.out)?;
            println!("slices {ks:?} -> {}", a.out.display());
            Ok(())
        }
        Command::PhantomMeasure(a) => {
            let vol = read_nifti(&a.volume)?;
            let table = LabelTable::from_path(&a.labels)?;
            let def =
                myoslice::phantom::measure_phantom(&vol, &table, a.level_mm, a.angles, &a.source)?;
            std::fs::write(&a.out, def.to_toml())
                .with_context(|| format!("writing {}", a.out.display()))?;
            println!(
                "{} structures, {} skin levels -> {}",
                def.structure.len(),
                def.skin.len(),
                a.out.display()
            );
            Ok(())
        }
    }
}
