//! `myoslice`: build reports, scenario runs and benchmarks from the command line.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use myoslice::BuildReport;
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
    /// Write axial slices of the model, coloured by label, side by side to a PNG.
    Slices(SlicesArgs),
    /// Measure a phantom definition (per-level outlines) from a labelled volume.
    PhantomMeasure(MeasureArgs),
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
    /// NIfTI label volume (.nii or .nii.gz).
    #[arg(long, requires = "labels")]
    volume: Option<PathBuf>,
    /// Label table (.json or .toml).
    #[arg(long, requires = "volume")]
    labels: Option<PathBuf>,
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
    match (&m.volume, &m.labels) {
        (Some(v), Some(l)) => {
            let vol = read_nifti(v)?;
            let table = LabelTable::from_path(l)?;
            Ok((vol, table, v.display().to_string()))
        }
        _ => {
            let (vol, table) = myoslice::phantom::Phantom::default().generate()?;
            Ok((vol, table, "built-in phantom".into()))
        }
    }
}

fn build(args: &BuildArgs) -> Result<()> {
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
    let t1 = Instant::now();
    let lattice = Lattice::build(&volume, &table, &opts)?;
    let build_time = t1.elapsed().as_secs_f64();
    let mut report = BuildReport::measure(&volume, &lattice, &source);
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
    let inv = lattice.check_invariants();
    println!(
        "invariants: open bones {:?}, fat elements <= 0: {}, muscle elements <= 0: {}/{}, fat vertices in bone: {}, duplicates {:?}",
        inv.open_bones,
        inv.nonpositive_fat,
        inv.nonpositive_muscle_elements,
        inv.muscle_elements,
        inv.fat_in_bone,
        inv.duplicate_vertices
    );
    if let Some(p) = &args.vtu {
        myoslice::export::rest_vtu(&lattice).write(p)?;
    }
    if let Some(p) = &args.report {
        std::fs::write(p, report.to_json()).with_context(|| format!("writing {}", p.display()))?;
    }
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
