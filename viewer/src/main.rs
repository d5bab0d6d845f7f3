//! `viewer`: the interactive leg, or an off-screen capture with `--capture`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use myoslice::prelude::*;
use myoslice_viewer::camera::CameraPreset;
use myoslice_viewer::capture::{CaptureMeta, CaptureOptions, advance, capture_frames, capture_png};
use myoslice_viewer::colormap::ColorMode;
use myoslice_viewer::model::{ModelSource, Preset};
use myoslice_viewer::scene::SceneOptions;
use myoslice_viewer::{Gpu, app};

#[derive(Parser, Debug)]
#[command(
    name = "viewer",
    version,
    about = "The myoslice leg: interactive, or captured off-screen"
)]
struct Args {
    /// Render off-screen to this PNG instead of opening a window.
    #[arg(long)]
    capture: Option<PathBuf>,
    /// Capture width (pixels).
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Capture height (pixels).
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Scenario file (model, excitations).
    #[arg(long, conflicts_with_all = ["volume", "labels"])]
    scenario: Option<PathBuf>,
    /// Label volume: NIfTI or NRRD; a 3D Slicer segmentation (.seg.nrrd) names its own
    /// labels.
    #[arg(long)]
    volume: Option<PathBuf>,
    /// Label table, ITK-SNAP label file or Slicer colour table for --volume.
    #[arg(long, requires = "volume")]
    labels: Option<PathBuf>,
    /// Your own label names (TOML: `[map]` name = structure) for --volume.
    #[arg(long, requires = "volume")]
    names: Option<PathBuf>,
    /// Label names no structure is known by: error, fat or ignore.
    #[arg(long, default_value = "error", requires = "volume")]
    unmapped: String,
    /// Simulated time before the capture (s).
    #[arg(long, default_value_t = 0.0)]
    time: f64,
    /// Motion during --time without a scenario: relax, flexion, extension, cocontraction.
    #[arg(long, default_value = "relax")]
    preset: String,
    /// Surface colours: area, degree, none.
    #[arg(long, default_value = "area")]
    color: String,
    /// Viewpoint: front, side, back, medial, oblique.
    #[arg(long, default_value = "oblique")]
    camera: String,
    /// Render an animation of this many frames over --time.
    #[arg(long)]
    frames: Option<usize>,
    /// Folder for the animation's PNG frames.
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// Animated GIF of the animation.
    #[arg(long)]
    gif: Option<PathBuf>,
    /// Layers to draw, comma separated: bone, muscle, skin.
    #[arg(long, value_delimiter = ',', default_value = "bone,muscle,skin")]
    layers: Vec<String>,
    /// Skin opacity (0..1).
    #[arg(long, default_value_t = 0.45)]
    skin_opacity: f32,
    /// No colour-bar legend in captures.
    #[arg(long)]
    no_legend: bool,
    /// Interactive window: close by itself after this many frames and print the frame
    /// timing (for smoke tests and frame-time measurements).
    #[arg(long, conflicts_with = "capture")]
    exit_after_frames: Option<u64>,
    /// Also write what the PNG shows (time, knee angle, the knee's pixel) as JSON here.
    #[arg(long, requires = "capture")]
    meta: Option<PathBuf>,
}

/// The model the command line names.
fn source(args: &Args) -> Result<ModelSource> {
    let Some(volume) = &args.volume else {
        return Ok(ModelSource::Phantom);
    };
    let Some(unmapped) = Unmapped::parse(&args.unmapped) else {
        bail!(
            "unknown --unmapped '{}': use error, fat or ignore",
            args.unmapped
        );
    };
    Ok(ModelSource::Volume {
        volume: volume.clone(),
        labels: args.labels.clone(),
        names: args.names.clone(),
        unmapped,
    })
}

fn build(args: &Args) -> Result<Simulation> {
    if let Some(s) = &args.scenario {
        let sc = Scenario::from_path(s)?;
        return sc.build().map_err(|e| anyhow!("{e}"));
    }
    let mut sim = source(args)?.load(SimulationConfig::default())?;
    let preset = Preset::parse(&args.preset).ok_or_else(|| {
        anyhow!(
            "unknown --preset '{}': use relax, flexion, extension or cocontraction",
            args.preset
        )
    })?;
    preset.apply(&mut sim)?;
    Ok(sim)
}

fn capture(args: &Args) -> Result<()> {
    let color = ColorMode::parse(&args.color)
        .ok_or_else(|| anyhow!("unknown --color '{}': use area, degree or none", args.color))?;
    let camera = CameraPreset::parse(&args.camera).ok_or_else(|| {
        anyhow!(
            "unknown --camera '{}': use front, side, back, medial or oblique",
            args.camera
        )
    })?;
    if !(16..=8192).contains(&args.width) || !(16..=8192).contains(&args.height) {
        return Err(anyhow!(
            "--width and --height must be between 16 and 8192 pixels"
        ));
    }
    if !(args.time.is_finite() && args.time >= 0.0) {
        return Err(anyhow!("--time must be a finite number of seconds >= 0"));
    }
    let mut visible = [false; 3];
    for l in &args.layers {
        match l.as_str() {
            "bone" => visible[0] = true,
            "muscle" => visible[1] = true,
            "skin" => visible[2] = true,
            other => {
                return Err(anyhow!(
                    "unknown layer '{other}' in --layers: use bone, muscle, skin"
                ));
            }
        }
    }
    if !(0.0..=1.0).contains(&args.skin_opacity) {
        return Err(anyhow!("--skin-opacity must be between 0 and 1"));
    }
    let animation = args.frames.is_some() || args.gif.is_some() || args.out_dir.is_some();
    if animation {
        if args.gif.is_none() && args.out_dir.is_none() {
            return Err(anyhow!(
                "--frames needs --out-dir (PNG frames) or --gif (an animated GIF)"
            ));
        }
        if args.frames == Some(0) {
            return Err(anyhow!("--frames must be at least 1"));
        }
        if args.frames.unwrap_or(24) > 1 && args.time <= 0.0 {
            return Err(anyhow!("an animation needs --time > 0 (the span it shows)"));
        }
    }
    // The model first: a bad file is reported as such, with or without a GPU.
    let mut sim = build(args)?;
    let gpu = Gpu::headless()?;
    let opts = CaptureOptions {
        width: args.width,
        height: args.height,
        camera,
        scene: SceneOptions {
            color_mode: color,
            visible,
            opacity: [1.0, 1.0, args.skin_opacity],
            ..SceneOptions::default()
        },
        legend: !args.no_legend,
        fixed_camera: None,
    };
    if animation {
        let frames = args.frames.unwrap_or(24);
        capture_frames(
            &gpu,
            &mut sim,
            &opts,
            args.time,
            frames,
            args.out_dir.as_deref(),
            args.gif.as_deref(),
        )?;
        if let Some(p) = &args.capture {
            capture_png(&gpu, &sim, &opts, p)?;
            write_meta(args, &sim, &opts)?;
        }
        return Ok(());
    }
    if args.time > 0.0 {
        advance(&mut sim, args.time)?;
    }
    let path = args
        .capture
        .as_ref()
        .context("--capture needs an output path")?;
    capture_png(&gpu, &sim, &opts, path)?;
    write_meta(args, &sim, &opts)
}

fn write_meta(args: &Args, sim: &Simulation, opts: &CaptureOptions) -> Result<()> {
    match &args.meta {
        Some(p) => CaptureMeta::of(sim, opts).write(p),
        None => Ok(()),
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    let offscreen = args.capture.is_some()
        || args.gif.is_some()
        || args.out_dir.is_some()
        || args.frames.is_some();
    let result = if offscreen {
        capture(&args)
    } else {
        let opts = app::RunOptions {
            exit_after_frames: args.exit_after_frames,
        };
        source(&args).and_then(|source| app::run(source, args.scenario.clone(), opts)).map(|stats| {
            if args.exit_after_frames.is_some() {
                println!(
                    "window: {} frames; first {:.0} ms; then mean {:.1} ms (simulating {:.1} ms), slowest {:.1} ms",
                    stats.frames,
                    stats.first_ms,
                    stats.mean_ms(),
                    stats.mean_sim_ms(),
                    stats.worst_ms
                );
            }
        })
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("viewer: {e:#}");
            ExitCode::FAILURE
        }
    }
}
