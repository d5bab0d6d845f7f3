//! The myoslice viewer: an interactive wgpu window over the core `Simulation`, and an
//! off-screen capture that needs no window or display.

pub mod camera;
pub mod capture;
pub mod colormap;
pub mod gpu;
pub mod model;
#[cfg(feature = "window")]
pub mod model_switch;
pub mod pick;
pub mod render;
pub mod scene;

#[cfg(feature = "window")]
pub mod app;
#[cfg(feature = "window")]
pub mod frame_stats;
#[cfg(feature = "window")]
pub mod readouts;
#[cfg(feature = "window")]
pub mod touch;
#[cfg(feature = "window")]
pub mod ui;
#[cfg(feature = "window")]
mod window_gfx;

pub use camera::{CameraPreset, OrbitCamera};
pub use capture::{CaptureOptions, capture_frames, capture_png};
pub use colormap::ColorMode;
pub use gpu::{Gpu, GpuError};
pub use pick::{Ray, pick_muscle};
pub use render::{RenderSettings, Renderer};
pub use scene::{Layer, SceneMesh};
