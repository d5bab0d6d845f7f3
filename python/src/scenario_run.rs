//! Scenario runs from Python: the CLI's `run`, and what each run of a sweep does.

use std::path::PathBuf;
use std::sync::Mutex;

use myoslice::prelude::*;
use pyo3::prelude::*;

use crate::arrays::check_path;
use crate::errors::{Kind, OrPy, py_err};

fn scenario(py: Python<'_>, path: PathBuf, text: Option<String>) -> PyResult<Scenario> {
    match text {
        Some(t) => crate::pool::detach(py, move || Scenario::from_str_at(&t, &path)).or_py(py),
        None => {
            check_path(py, &path, "scenario")?;
            crate::pool::detach(py, move || Scenario::from_path(&path)).or_py(py)
        }
    }
}

/// The last model built with `reuse_model`: its lattice, or the simulation built on it
/// for one configuration, before any schedule or muscle factor (which holds the lattice).
struct Kept {
    lattice_key: String,
    model: Model,
}

enum Model {
    Lattice(Box<Lattice>),
    Built {
        config_key: String,
        sim: Box<Simulation>,
    },
}

static KEPT: Mutex<Option<Kept>> = Mutex::new(None);

fn kept() -> std::sync::MutexGuard<'static, Option<Kept>> {
    KEPT.lock().unwrap_or_else(|e| e.into_inner())
}

/// Keeps `sim` (built for `config_key`) as the model of `lattice_key`, if that model is
/// still the one kept.
fn keep_built(lattice_key: &str, config_key: String, sim: &Simulation) {
    if let Some(k) = kept().as_mut().filter(|k| k.lattice_key == lattice_key) {
        k.model = Model::Built {
            config_key,
            sim: Box::new(sim.clone()),
        };
    }
}

/// Builds the scenario's simulation from what was kept of the last one when the model
/// is the same: a clone of the simulation when the configuration is the same too (only
/// schedules and muscle factors differ: the common case of sweeps and fits), else a new
/// simulation on the kept lattice. Both give the same bits as a build from scratch; the
/// lock is not held while building.
fn build_reusing(sc: &Scenario) -> myoslice::Result<Simulation> {
    sc.check()?;
    let lattice_key = sc.lattice_key();
    let config_key = format!("{:?}", sc.config());
    let found = kept()
        .as_ref()
        .filter(|k| k.lattice_key == lattice_key)
        .map(|k| match &k.model {
            Model::Built { config_key: c, sim } if *c == config_key => Ok(sim.clone()),
            Model::Built { sim, .. } => Err(Box::new(sim.lattice().clone())),
            Model::Lattice(l) => Err(l.clone()),
        });
    let mut sim = match found {
        Some(Ok(sim)) => *sim,
        Some(Err(lattice)) => {
            let sim = sc.simulation_on(*lattice)?;
            keep_built(&lattice_key, config_key, &sim);
            sim
        }
        None => {
            let lattice = sc.lattice()?;
            // Kept before the simulation's build, which may fail for this configuration
            // and not for the next.
            *kept() = Some(Kept {
                lattice_key: lattice_key.clone(),
                model: Model::Lattice(Box::new(lattice.clone())),
            });
            let sim = sc.simulation_on(lattice)?;
            keep_built(&lattice_key, config_key, &sim);
            sim
        }
    };
    sc.apply_schedules(&mut sim)?;
    Ok(sim)
}

/// Runs a scenario to its end into the folder `out` (`timeseries.csv`, `summary.json`,
/// and the VTU series and GLB its `[output]` asks for), as `myoslice run` does, and
/// returns the summary as a dict. With `text`, the scenario is that TOML text and `path`
/// only places its relative files and names it in errors. With `reuse_model`, what was
/// built for the last scenario run so in this process is reused when the model (source,
/// files, slicing) is the same: its lattice, and the whole simulation when the settings
/// are the same too (only schedules and muscle factors differ). The same bits, without
/// the build's cost (sweeps and fits run many scenarios of one model). The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (path, out, *, text = None, reuse_model = false))]
pub(crate) fn run_scenario<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: PathBuf,
    text: Option<String>,
    reuse_model: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let sc = scenario(py, path, text)?;
    let summary = crate::pool::detach(py, move || {
        let build: &mut dyn FnMut(&Scenario) -> myoslice::Result<Simulation> = if reuse_model {
            &mut build_reusing
        } else {
            &mut Scenario::build
        };
        myoslice::export::run_scenario_with(&sc, build, &out, &mut |_| {})
    })
    .or_py(py)?;
    let json = serde_json::to_string(&summary)
        .map_err(|e| py_err(py, Kind::Simulation, format!("summary: {e}")))?;
    py.import("json")?.call_method1("loads", (json,))
}

/// Reads and checks a scenario (every field, range and file, and the simulation's
/// settings) without building it: raises what `run_scenario` would raise before its
/// build. With `build`, also builds its model (reusing what was built as `reuse_model` does)
/// so that the muscle and group names of `[excitation]` and `[muscle.NAME]` are checked
/// too. `text` as in `run_scenario`.
#[pyfunction]
#[pyo3(signature = (path, *, text = None, build = false))]
pub(crate) fn check_scenario(
    py: Python<'_>,
    path: PathBuf,
    text: Option<String>,
    build: bool,
) -> PyResult<()> {
    let sc = scenario(py, path, text)?;
    crate::pool::detach(py, move || {
        if build {
            build_reusing(&sc).map(|_| ())
        } else {
            sc.check()
        }
    })
    .or_py(py)
}
