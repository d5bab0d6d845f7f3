//! Rust data as numpy arrays, and argument checks shared by the methods.

use std::path::Path;

use glam::Vec3;
use myoslice::prelude::*;
use myoslice::tissue::{SkinBreach, TissueMetrics};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Kind, OrPy, py_err};

/// Vertices (float32, (N, 3)) and triangles (uint32, (M, 3)) of a surface.
pub(crate) type SurfaceArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);

/// A per-element or per-muscle tissue metric as a float32 array (empty without tissue).
pub(crate) fn metric_array<'py>(
    py: Python<'py>,
    sim: &Simulation,
    pick: impl Fn(&TissueMetrics) -> &Vec<f32> + Send + Sync,
) -> Bound<'py, PyArray1<f32>> {
    // Measured on first use, in parallel: on threads of this process (crate::pool).
    let values = crate::pool::detach(py, || {
        sim.tissue_metrics()
            .map_or_else(Vec::new, |m| pick(m).clone())
    });
    PyArray1::from_vec(py, values)
}

/// How far muscles reach where they should not, as a dict of per-muscle arrays:
/// `vertices_over_1mm` (int64) and one distance (float32, m) under its own name.
pub(crate) fn reach_dict<'py>(
    py: Python<'py>,
    count: Vec<usize>,
    (name, distance): (&str, Vec<f32>),
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let count: Vec<i64> = count.into_iter().map(|c| c as i64).collect();
    d.set_item("vertices_over_1mm", PyArray1::from_vec(py, count))?;
    d.set_item(name, PyArray1::from_vec(py, distance))?;
    Ok(d)
}

/// How far muscles or bones reach out through the skin (see [`reach_dict`]; empty
/// arrays for None).
pub(crate) fn breach_dict<'py>(
    py: Python<'py>,
    breaches: Option<Vec<SkinBreach>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (count, farthest) = breaches
        .unwrap_or_default()
        .iter()
        .map(|b| (b.vertices_over_1mm, b.farthest_m))
        .unzip();
    reach_dict(py, count, ("farthest_m", farthest))
}

/// The pairs of an excitations dict {name: value}, every name known and every value in
/// [0, 1] (checked before any is set, so a bad entry sets none).
pub(crate) fn excitation_pairs(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
    sim: &Simulation,
) -> PyResult<Vec<(String, f64)>> {
    let mut pairs = Vec::with_capacity(d.len());
    for (k, v) in d.iter() {
        let name: String = k.extract().map_err(|_| {
            py_err(
                py,
                Kind::Invalid,
                "excitation keys must be muscle names (str)".into(),
            )
        })?;
        let value: f64 = v.extract().map_err(|_| {
            py_err(
                py,
                Kind::Invalid,
                format!("excitation of {name} must be a number"),
            )
        })?;
        sim.muscle_index(&name).or_py(py)?;
        pairs.push((name, value));
    }
    for (name, value) in &pairs {
        if !(value.is_finite() && (0.0..=1.0).contains(value)) {
            return Err(py_err(
                py,
                Kind::Invalid,
                format!("excitation of {name} = {value}: expected a value in [0, 1]"),
            ));
        }
    }
    Ok(pairs)
}

pub(crate) fn check_path(py: Python<'_>, p: &Path, what: &str) -> PyResult<()> {
    if p.exists() {
        Ok(())
    } else {
        Err(py_err(
            py,
            Kind::File,
            format!("{what} {} does not exist", p.display()),
        ))
    }
}

pub(crate) fn vec3_array<'py>(py: Python<'py>, v: &[Vec3]) -> Bound<'py, PyArray2<f32>> {
    let flat: Vec<f32> = v.iter().flat_map(|p| p.to_array()).collect();
    Array2::from_shape_vec((v.len(), 3), flat).map_or_else(
        |_| PyArray2::zeros(py, (0, 3), false),
        |a| a.into_pyarray(py),
    )
}

pub(crate) fn tri_array<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyArray2<u32>> {
    let flat: Vec<u32> = t.iter().flatten().copied().collect();
    Array2::from_shape_vec((t.len(), 3), flat).map_or_else(
        |_| PyArray2::zeros(py, (0, 3), false),
        |a| a.into_pyarray(py),
    )
}
