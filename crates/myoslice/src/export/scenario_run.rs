//! A scenario run from start to end into a folder: what the CLI's `run`, Python's
//! `run_scenario` and the sweeps all do, so that they give the same bits.

use std::path::Path;
use web_time::Instant;

use super::run::{RunOutputs, RunSummary, RunWriter};
use crate::error::Result;
use crate::scenario::Scenario;
use crate::simulation::Simulation;

/// Where a run is, for progress displays.
#[derive(Debug, Clone, Copy)]
pub struct RunProgress<'a> {
    /// Steps done.
    pub step: u64,
    /// Steps in the run.
    pub steps: u64,
    /// The simulation after that step.
    pub sim: &'a Simulation,
}

/// Builds `scenario`'s model and runs it for its duration, writing its outputs
/// (`timeseries.csv`, `summary.json`, and the VTU series and GLB the scenario asks for)
/// into `out`. `progress` is told after every step. The wall time counts the build.
///
/// ```no_run
/// use myoslice::export::run_scenario;
/// use myoslice::prelude::*;
/// let sc = Scenario::from_path("assets/scenarios/knee_flexion.toml")?;
/// let summary = run_scenario(&sc, "runs/flexion".as_ref(), &mut |_| {})?;
/// println!("knee up to {:.1} deg", summary.knee_angle_range_deg[1]);
/// # Ok::<(), myoslice::Error>(())
/// ```
pub fn run_scenario(
    scenario: &Scenario,
    out: &Path,
    progress: &mut dyn FnMut(RunProgress<'_>),
) -> Result<RunSummary> {
    run_scenario_with(scenario, &mut Scenario::build, out, progress)
}

/// [`run_scenario`] with the simulation made by `build` (which may, say, reuse a lattice
/// kept from an earlier run: [`Scenario::build_on`]); its time is in the run's wall time.
pub fn run_scenario_with(
    scenario: &Scenario,
    build: &mut dyn FnMut(&Scenario) -> Result<Simulation>,
    out: &Path,
    progress: &mut dyn FnMut(RunProgress<'_>),
) -> Result<RunSummary> {
    let t0 = Instant::now();
    let mut sim = build(scenario)?;
    let outputs = RunOutputs {
        vtu: scenario.output.vtu,
        glb: scenario.output.glb,
        audit: scenario.output.audit,
    };
    let mut w = RunWriter::create(out, &sim, outputs)?;
    let dt = scenario.simulation.step_s;
    let steps = (scenario.simulation.duration_s / dt).round().max(1.0) as u64;
    let frames = scenario.output.frames.max(1) as u64;
    // A time series row every 10 ms of simulated time.
    let row_every = ((0.01 / dt).round() as u64).max(1);
    let mut next_frame = 1;
    for k in 1..=steps {
        sim.step(dt)?;
        w.audit(&sim)?;
        if k % row_every == 0 || k == steps {
            w.row(&sim)?;
        }
        if k * frames >= next_frame * steps {
            sim.update_tissue()?;
            w.audit(&sim)?;
            w.frame(&sim)?;
            next_frame += 1;
        }
        progress(RunProgress {
            step: k,
            steps,
            sim: &sim,
        });
    }
    w.finish(&sim, t0.elapsed().as_secs_f64())
}
