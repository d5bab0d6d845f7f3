//! Off-screen rendering of a simulation into a numpy image.

use myoslice::Simulation;
use myoslice_viewer::capture::{CaptureOptions, Offscreen};
use myoslice_viewer::{CameraPreset, ColorMode, Gpu};
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use std::sync::OnceLock;

use crate::errors::{Kind, py_err};

/// The renderer a simulation's off-screen target was made on, and its size.
pub(crate) type Target = Option<(u32, u32, Offscreen)>;

fn gpu(py: Python<'_>) -> PyResult<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    GPU.get_or_init(|| Gpu::headless().map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| {
            py_err(
                py,
                Kind::Renderer,
                format!("the off-screen renderer is not available: {e}"),
            )
        })
}

/// Renders `sim` off-screen into `target` (made anew when the size changes): uint8
/// (height, width, 3).
pub(crate) fn render<'py>(
    py: Python<'py>,
    sim: &Simulation,
    offscreen: &mut Target,
    width: u32,
    height: u32,
    color: &str,
    camera: &str,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let color_mode = ColorMode::parse(color).ok_or_else(|| {
        py_err(
            py,
            Kind::Invalid,
            format!("color = '{color}': expected 'area', 'degree' or 'none'"),
        )
    })?;
    let cam = CameraPreset::parse(camera).ok_or_else(|| {
        py_err(
            py,
            Kind::Invalid,
            format!("camera = '{camera}': expected front, side, back, medial or oblique"),
        )
    })?;
    if !(16..=8192).contains(&width) || !(16..=8192).contains(&height) {
        return Err(py_err(
            py,
            Kind::Invalid,
            format!("render size {width}x{height}: expected 16 to 8192 pixels each way"),
        ));
    }
    let gpu = gpu(py)?;
    let mut opts = CaptureOptions {
        width,
        height,
        camera: cam,
        legend: false,
        ..CaptureOptions::default()
    };
    opts.scene.color_mode = color_mode;
    if offscreen
        .as_ref()
        .is_none_or(|(w, h, _)| (*w, *h) != (width, height))
    {
        *offscreen = Some((width, height, Offscreen::new(gpu, width, height)));
    }
    let Some((_, _, off)) = offscreen.as_mut() else {
        unreachable!()
    };
    let rgba = crate::pool::detach(py, || {
        off.render(gpu, sim, &opts).map_err(|e| e.to_string())
    })
    .map_err(|e| py_err(py, Kind::Renderer, e))?;
    let rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let arr = numpy::ndarray::Array3::from_shape_vec((height as usize, width as usize, 3), rgb)
        .map_err(|e| py_err(py, Kind::Renderer, e.to_string()))?;
    Ok(arr.into_pyarray(py))
}
