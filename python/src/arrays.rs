//! Rust data as numpy arrays, and argument checks shared by the methods.

use std::path::Path;

use glam::Vec3;
use myoslice::prelude::*;
use myoslice::tissue::TissueMetrics;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Kind, py_err};

/// Vertices (float32, (N, 3)) and triangles (uint32, (M, 3)) of a surface.
pub(crate) type SurfaceArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);

/// A per-element or per-muscle tissue metric as a float32 array (empty without tissue).
pub(crate) fn metric_array<'py>(
    py: Python<'py>,
    sim: &Simulation,
    pick: impl Fn(&TissueMetrics) -> &Vec<f32>,
) -> Bound<'py, PyArray1<f32>> {
    PyArray1::from_vec(
        py,
        sim.tissue_metrics()
            .map_or_else(Vec::new, |m| pick(m).clone()),
    )
}

/// How far muscles reach where they should not, as a dict of per-muscle arrays:
/// `vertices_over_1mm` (int64) and one distance (float32, m) under its own name.
pub(crate) fn per_muscle_reach<'py>(
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
