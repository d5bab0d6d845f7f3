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

/// The lattice of the last model built with `reuse_model`, by its scenario's lattice key.
static LAST_LATTICE: Mutex<Option<(String, Lattice)>> = Mutex::new(None);

/// Builds the scenario's simulation on the kept lattice when the model is the same (the
/// lattice build is most of a short run's time; a kept lattice gives the same bits).
fn build_reusing(sc: &Scenario) -> myoslice::Result<Simulation> {
    sc.check()?;
    let key = sc.lattice_key();
    let kept = {
        let slot = LAST_LATTICE.lock().unwrap_or_else(|e| e.into_inner());
        slot.as_ref()
            .filter(|(k, _)| *k == key)
            .map(|(_, l)| l.clone())
    };
    let lattice = match kept {
        Some(l) => l,
        None => {
            let l = sc.lattice()?;
            *LAST_LATTICE.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, l.clone()));
            l
        }
    };
    sc.build_on(lattice)
}

/// Runs a scenario to its end into the folder `out` (`timeseries.csv`, `summary.json`,
/// and the VTU series and GLB its `[output]` asks for), as `myoslice run` does, and
/// returns the summary as a dict. With `text`, the scenario is that TOML text and `path`
/// only places its relative files and names it in errors. With `reuse_model`, the
/// lattice of the last model built so in this process is reused when the scenario's
/// model (source, files, slicing) is the same: the same bits, without the build's cost
/// (sweeps and fits run many scenarios of one model). The GIL is released while it runs.
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
/// build. With `build`, also builds its model (reusing the lattice as `reuse_model` does)
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
