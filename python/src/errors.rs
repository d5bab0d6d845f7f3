//! Errors: the core's error kinds as the exception classes of `myoslice.errors`.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

/// The Python exception classes of `myoslice.errors`.
#[derive(Clone, Copy)]
pub(crate) enum Kind {
    Invalid,
    UnknownName,
    File,
    Simulation,
    Renderer,
}

pub(crate) fn py_err(py: Python<'_>, kind: Kind, msg: String) -> PyErr {
    static CLASSES: [PyOnceLock<Py<PyType>>; 5] = [
        PyOnceLock::new(),
        PyOnceLock::new(),
        PyOnceLock::new(),
        PyOnceLock::new(),
        PyOnceLock::new(),
    ];
    let (i, name) = match kind {
        Kind::Invalid => (0, "InvalidInputError"),
        Kind::UnknownName => (1, "UnknownNameError"),
        Kind::File => (2, "ModelFileError"),
        Kind::Simulation => (3, "SimulationError"),
        Kind::Renderer => (4, "RendererUnavailableError"),
    };
    match CLASSES[i].import(py, "myoslice.errors", name) {
        Ok(ty) => PyErr::from_type(ty.clone(), msg),
        Err(e) => e,
    }
}

pub(crate) fn core_err(py: Python<'_>, e: myoslice::Error) -> PyErr {
    use myoslice::Error as E;
    let kind = match &e {
        E::Io { .. }
        | E::Write { .. }
        | E::Nifti { .. }
        | E::Png { .. }
        | E::Parse { .. }
        | E::UnknownLabel { .. } => Kind::File,
        E::UnknownName { .. } => Kind::UnknownName,
        E::NonFinite { .. } => Kind::Simulation,
        _ => Kind::Invalid,
    };
    py_err(py, kind, e.to_string())
}

pub(crate) trait OrPy<T> {
    fn or_py(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> OrPy<T> for Result<T, myoslice::Error> {
    fn or_py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| core_err(py, e))
    }
}
