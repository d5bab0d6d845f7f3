//! The window's graphics: surface, device, renderer and their targets, egui.

use std::sync::Arc;

use winit::window::Window;

use crate::gpu::Gpu;
use crate::render::{DEPTH, Renderer};

/// The window's graphics: its surface on the device, the renderer and its targets,
/// and egui's state and renderer.
pub(crate) struct Gfx {
    pub window: Arc<Window>,
    pub surface: wgpu::Surface<'static>,
    pub gpu: Gpu,
    pub config: wgpu::SurfaceConfiguration,
    pub renderer: Renderer,
    pub msaa: Option<wgpu::TextureView>,
    pub depth: wgpu::TextureView,
    pub egui_ctx: egui::Context,
    pub egui_state: egui_winit::State,
    pub egui_renderer: egui_wgpu::Renderer,
}

/// The format the frame is drawn in: the surface's, or its sRGB view's.
pub(crate) fn view_format(config: &wgpu::SurfaceConfiguration) -> wgpu::TextureFormat {
    config
        .view_formats
        .first()
        .copied()
        .unwrap_or(config.format)
}

/// The multisampled colour target (when `samples` > 1) and the depth target for a
/// surface of `config`'s size.
pub(crate) fn targets(
    gpu: &Gpu,
    config: &wgpu::SurfaceConfiguration,
    samples: u32,
) -> (Option<wgpu::TextureView>, wgpu::TextureView) {
    let tex = |format, usage, label| {
        gpu.target((config.width, config.height), format, samples, usage, label)
            .create_view(&wgpu::TextureViewDescriptor::default())
    };
    let msaa = (samples > 1).then(|| {
        tex(
            view_format(config),
            wgpu::TextureUsages::RENDER_ATTACHMENT,
            "msaa",
        )
    });
    (
        msaa,
        tex(DEPTH, wgpu::TextureUsages::RENDER_ATTACHMENT, "depth"),
    )
}
