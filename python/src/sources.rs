//! Where a model comes from: the user's files, read by content.

use std::path::{Path, PathBuf};

use myoslice::io::InputKind;
use myoslice::label_mapping::LabelMapping;
use myoslice::label_names::Unmapped;
use myoslice::prelude::*;
use pyo3::prelude::*;

use crate::arrays::check_path;
use crate::errors::OrPy;

/// `unmapped="error" | "fat" | "ignore"` and `names=` as a label mapping.
pub(crate) fn mapping(
    py: Python<'_>,
    unmapped: &str,
    names: Option<&Path>,
) -> PyResult<LabelMapping> {
    let Some(rule) = Unmapped::parse(unmapped) else {
        return Err(myoslice::Error::InvalidValue {
            name: "unmapped".into(),
            value: format!("'{unmapped}'"),
            expected: "\"error\", \"fat\" or \"ignore\"".into(),
        })
        .or_py(py);
    };
    let m = LabelMapping::new(rule);
    match names {
        Some(p) => {
            check_path(py, p, "names file")?;
            m.with_names_file(p).or_py(py)
        }
        None => Ok(m),
    }
}

/// A simulation of a label volume or PNG stack (told apart by content), built with the
/// GIL released.
pub(crate) fn simulation_from_file(
    py: Python<'_>,
    path: PathBuf,
    labels: Option<PathBuf>,
    mapping: LabelMapping,
    build: BuildOptions,
    config: SimulationConfig,
) -> PyResult<Simulation> {
    check_path(py, &path, "volume")?;
    if let Some(labels) = &labels {
        check_path(py, labels, "label table")?;
    }
    crate::pool::detach(py, move || {
        Simulation::from_file(&path, labels.as_deref(), mapping, &build, config)
    })
    .or_py(py)
}

/// Whether `path` holds a scenario rather than a volume or PNG stack.
pub(crate) fn is_scenario(py: Python<'_>, path: &Path) -> PyResult<bool> {
    check_path(py, path, "file")?;
    Ok(InputKind::sniff(path).or_py(py)? == InputKind::Scenario)
}

/// Issues each build warning as a Python `UserWarning`.
pub(crate) fn warn(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    if warnings.is_empty() {
        return Ok(());
    }
    let warn = py.import("warnings")?.getattr("warn")?;
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    for w in warnings {
        // Called from Rust, the innermost Python frame is the caller's line.
        warn.call1((w, &category, 1))?;
    }
    Ok(())
}
