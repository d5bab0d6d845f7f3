//! The interactive window: winit event loop, wgpu surface, egui panel, orbit camera.

use std::path::PathBuf;
use std::sync::Arc;
use web_time::Instant;

use anyhow::{Result, anyhow};
use myoslice::prelude::*;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, TouchPhase, WindowEvent};
use winit::event_loop::ActiveEventLoop;
#[cfg(not(target_arch = "wasm32"))]
use winit::event_loop::{ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use crate::camera::{CameraPreset, OrbitCamera};
pub use crate::frame_stats::FrameStats;
use crate::gpu::Gpu;
use crate::model::ModelSource;
use crate::pick::{Ray, pick_muscle};
use crate::render::{RenderSettings, Renderer};
use crate::scene::{SceneMesh, SceneOptions};
use crate::touch::{Gesture, Touches};
use crate::ui::{UiAction, UiState};
use crate::window_gfx::{Gfx, targets, view_format};

/// How far (px) the pointer may move between press and release and still be a click.
const CLICK_SLOP_PX: f64 = 4.0;

/// How an interactive session ends.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// Close by itself after this many frames and print their timing (smoke tests,
    /// frame-time measurements); `None` runs until the window is closed.
    pub exit_after_frames: Option<u64>,
}

/// Opens the window on a model (or a scenario) and runs until it is closed (or for
/// `opts.exit_after_frames`); returns the frame timing.
#[cfg(not(target_arch = "wasm32"))]
pub fn run(source: ModelSource, scenario: Option<PathBuf>, opts: RunOptions) -> Result<FrameStats> {
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("cannot open a window ({e}); without a display, use `viewer --capture out.png`")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
        Box::new(event_loop.owned_display_handle()),
    ));
    let mut ui = UiState {
        source: source.clone(),
        ..UiState::default()
    };
    let sim = match load(&source, scenario.as_ref()) {
        Ok(s) => s,
        Err(e) => {
            ui.error = Some(format!("{e:#}\n\nShowing the built-in phantom instead."));
            ui.source = ModelSource::Phantom;
            load(&ModelSource::Phantom, None)?
        }
    };
    let mut app = App::new(sim, ui, scenario, opts);
    app.instance = Some(instance);
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("event loop: {e}"))?;
    match app.fatal {
        Some(e) => Err(e),
        None => Ok(app.stats),
    }
}

fn load(source: &ModelSource, scenario: Option<&PathBuf>) -> Result<Simulation> {
    if let Some(s) = scenario {
        let sc = Scenario::from_path(s)?;
        return sc.build().map_err(|e| anyhow!("{e}"));
    }
    source.load(SimulationConfig::default())
}

struct App {
    /// The instance the window's surface comes from (a page makes its own once the
    /// browser says whether it has WebGPU).
    #[cfg(not(target_arch = "wasm32"))]
    instance: Option<wgpu::Instance>,
    gfx: Option<Gfx>,
    /// A page's graphics, arriving from the browser's promises.
    #[cfg(target_arch = "wasm32")]
    arriving: web::Arriving,
    sim: Simulation,
    ui: UiState,
    scenario: Option<PathBuf>,
    camera: Option<OrbitCamera>,
    drag: Option<(MouseButton, (f64, f64))>,
    /// Last cursor position in the window (px).
    cursor: Option<(f64, f64)>,
    /// Where the left button went down, and the muscle under it then.
    press: Option<((f64, f64), Option<usize>)>,
    /// Fingers on the view.
    touches: Touches,
    last: Instant,
    fatal: Option<anyhow::Error>,
    opts: RunOptions,
    stats: FrameStats,
}

impl App {
    fn new(sim: Simulation, ui: UiState, scenario: Option<PathBuf>, opts: RunOptions) -> Self {
        let mut app = Self {
            #[cfg(not(target_arch = "wasm32"))]
            instance: None,
            gfx: None,
            #[cfg(target_arch = "wasm32")]
            arriving: web::Arriving::default(),
            sim,
            ui,
            scenario,
            camera: None,
            drag: None,
            cursor: None,
            press: None,
            touches: Touches::default(),
            last: Instant::now(),
            fatal: None,
            opts,
            stats: FrameStats::default(),
        };
        app.ui.default_plot(&app.sim);
        app
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn init(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let attrs = Window::default_attributes()
            .with_title("myoslice")
            .with_inner_size(winit::dpi::LogicalSize::new(1400.0, 860.0));
        let window = Arc::new(el.create_window(attrs)?);
        let instance = self
            .instance
            .clone()
            .ok_or_else(|| anyhow!("no graphics instance"))?;
        let surface = instance.create_surface(window.clone())?;
        let gpu = Gpu::with_instance(instance, Some(&surface))?;
        self.attach(window, surface, gpu)
    }

    /// Sets up drawing into `window` once its surface and device exist.
    fn attach(
        &mut self,
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        gpu: Gpu,
    ) -> Result<()> {
        let size = window.inner_size();
        let caps = surface.get_capabilities(&gpu.adapter);
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| anyhow!("the window surface is not supported by {}", gpu.describe()))?;
        // The renderer writes linear colour for an sRGB target to encode. A browser's
        // WebGPU canvas has no sRGB format: it is drawn through an sRGB view of it.
        match caps.formats.iter().copied().find(|f| f.is_srgb()) {
            Some(f) => config.format = f,
            // Only where the device may view the surface in another format (not on GL,
            // nor on Vulkan without mutable swapchain formats): elsewhere the colours
            // come out darker, but the window opens.
            None if config.format.add_srgb_suffix() != config.format
                && gpu
                    .adapter
                    .get_downlevel_capabilities()
                    .flags
                    .contains(wgpu::DownlevelFlags::SURFACE_VIEW_FORMATS) =>
            {
                config.view_formats = vec![config.format.add_srgb_suffix()];
            }
            None => {}
        }
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(&gpu.device, &config);
        let format = view_format(&config);
        let samples = gpu.msaa_samples(format);
        let renderer = Renderer::new(&gpu, format, samples);
        let (msaa, depth) = targets(&gpu, &config, samples);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &*window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        self.gfx = Some(Gfx {
            window,
            surface,
            gpu,
            config,
            renderer,
            msaa,
            depth,
            egui_ctx,
            egui_state,
            egui_renderer,
        });
        Ok(())
    }

    fn advance(&mut self) {
        let now = Instant::now();
        let elapsed = now.duration_since(self.last).as_secs_f64();
        self.last = now;
        self.ui.frame_ms = (elapsed * 1e3) as f32;
        // A stall (window dragged, slow frame) does not make the simulation jump.
        let real = elapsed.min(0.1);
        if self.ui.playing {
            let t0 = Instant::now();
            let dt = (real * self.ui.speed).clamp(1e-4, 0.05);
            if let Err(e) = self.sim.step(dt) {
                self.ui.playing = false;
                self.ui.error = Some(format!("{e}"));
            }
            self.ui.sim_ms = (t0.elapsed().as_secs_f64() * 1e3) as f32;
            self.ui.record(&self.sim);
        } else {
            self.ui.sim_ms = 0.0;
        }
    }

    fn act(&mut self, actions: Vec<UiAction>) {
        for a in actions {
            let r: Result<()> = match a {
                UiAction::Reset => load(&self.ui.source, self.scenario.as_ref()).map(|s| {
                    self.sim = with_models_of(s, &self.sim);
                    self.ui.default_plot(&self.sim);
                }),
                UiAction::Step => self
                    .sim
                    .step(0.01)
                    .map_err(Into::into)
                    .map(|_| self.ui.record(&self.sim)),
                UiAction::Preset(p) => p.apply(&mut self.sim),
                UiAction::Camera(p) => {
                    self.camera = Some(self.frame_camera(p));
                    Ok(())
                }
                UiAction::Load(src) => load(&src, None).map(|s| self.switch_to(src, s)),
            };
            if let Err(e) = r {
                self.ui.error = Some(format!("{e:#}"));
            }
        }
    }

    /// A finger's event on the view (`panel`: the panel has it).
    fn touch(&mut self, id: u64, phase: TouchPhase, at: (f64, f64), panel: bool, height: f32) {
        let gesture = self.touches.event(id, phase, at, panel);
        let (Some(cam), Some(g)) = (self.camera.as_mut(), gesture) else {
            return;
        };
        match g {
            Gesture::Orbit(dx, dy) => cam.orbit(dx, dy, 0.006),
            Gesture::PinchPan { zoom, pan } => {
                cam.zoom(zoom);
                cam.pan(pan.0, pan.1, height);
            }
        }
    }

    /// Runs `sim`, built from `src`, instead of the model before, with the muscle and
    /// tendon models chosen in the panel (a scenario's own stay).
    fn switch_to(&mut self, src: ModelSource, sim: Simulation) {
        self.sim = match src {
            ModelSource::ScenarioText { .. } => sim,
            _ => with_models_of(sim, &self.sim),
        };
        self.ui.selected = None;
        self.ui.hovered = None;
        self.ui.source = src;
        self.scenario = None;
        self.ui.default_plot(&self.sim);
        self.camera = None;
    }

    fn frame_camera(&self, preset: CameraPreset) -> OrbitCamera {
        let s = SceneMesh::build(
            &self.sim,
            &SceneOptions {
                visible: [true, false, true],
                ..SceneOptions::default()
            },
        );
        OrbitCamera::framing(s.bounds.0, s.bounds.1, preset, self.aspect())
    }

    /// Width over height of the window (16:9 before it exists).
    fn aspect(&self) -> f32 {
        self.gfx.as_ref().map_or(16.0 / 9.0, |g| {
            g.config.width as f32 / g.config.height.max(1) as f32
        })
    }

    fn redraw(&mut self) {
        self.advance();
        let Some(g) = self.gfx.as_mut() else { return };
        let raw = g.egui_state.take_egui_input(&g.window);
        let ui_state = &mut self.ui;
        let sim = &mut self.sim;
        let mut actions = Vec::new();
        let mut out = g.egui_ctx.run_ui(raw, |ui| {
            actions = ui_state.show(ui, sim);
        });
        g.egui_state
            .handle_platform_output(&g.window, std::mem::take(&mut out.platform_output));
        let ppp = out.pixels_per_point;
        let paint = g.egui_ctx.tessellate(std::mem::take(&mut out.shapes), ppp);
        for (id, deltas) in out.textures_delta.set.drain() {
            for d in deltas {
                g.egui_renderer
                    .update_texture(&g.gpu.device, &g.gpu.queue, id, &d);
            }
        }
        let frame = match g.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                g.surface.configure(&g.gpu.device, &g.config);
                for id in out.textures_delta.free.drain() {
                    g.egui_renderer.free_texture(&id);
                }
                return;
            }
            _ => {
                for id in out.textures_delta.free.drain() {
                    g.egui_renderer.free_texture(&id);
                }
                return;
            }
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(view_format(&g.config)),
            ..Default::default()
        });
        let scene = SceneMesh::build(&self.sim, &self.ui.scene_options());
        self.ui.color_range = scene.color_range;
        let aspect = g.config.width as f32 / g.config.height.max(1) as f32;
        let camera = *self.camera.get_or_insert_with(|| {
            OrbitCamera::framing(
                scene.bounds.0,
                scene.bounds.1,
                CameraPreset::Oblique,
                aspect,
            )
        });
        // What the cursor is over, for the next frame's tint and tooltip (not while the
        // camera is dragged or the pointer is on the panel).
        let over_egui = g.egui_ctx.is_pointer_over_egui();
        let moving_camera = self.drag.is_some_and(|(_, last)| last.0.is_finite());
        self.ui.hovered = match self.cursor {
            Some((x, y)) if self.ui.visible[1] && !over_egui && !moving_camera => {
                let size = glam::Vec2::new(g.config.width as f32, g.config.height as f32);
                let ray = Ray::through_pixel(&camera, glam::Vec2::new(x as f32, y as f32), size);
                pick_muscle(&scene, &ray)
            }
            _ => None,
        };
        let mut enc = g
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        let (target, resolve) = match &g.msaa {
            Some(m) => (m, Some(&view)),
            None => (&view, None),
        };
        let size = (g.config.width, g.config.height);
        g.renderer.draw(
            &g.gpu,
            &mut enc,
            target,
            resolve,
            &g.depth,
            size,
            &scene,
            &camera,
            &RenderSettings { legend: None },
        );
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [g.config.width, g.config.height],
            pixels_per_point: ppp,
        };
        let extra =
            g.egui_renderer
                .update_buffers(&g.gpu.device, &g.gpu.queue, &mut enc, &paint, &screen);
        {
            let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            g.egui_renderer
                .render(&mut pass.forget_lifetime(), &paint, &screen);
        }
        g.gpu.queue.submit(extra.into_iter().chain([enc.finish()]));
        for id in out.textures_delta.free.drain() {
            g.egui_renderer.free_texture(&id);
        }
        g.window.pre_present_notify();
        g.gpu.queue.present(frame);
        self.stats.add(
            f64::from(self.ui.frame_ms) * 1e-3,
            f64::from(self.ui.sim_ms) * 1e-3,
        );
        self.act(actions);
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.init(el)
        {
            self.fatal = Some(e);
            el.exit();
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(g) = self.gfx.as_mut() else { return };
        let resp = g.egui_state.on_window_event(&g.window, &event);
        let egui_wants = g.egui_ctx.egui_wants_pointer_input();
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(s) => {
                g.config.width = s.width.max(1);
                g.config.height = s.height.max(1);
                g.surface.configure(&g.gpu.device, &g.config);
                let (msaa, depth) = targets(&g.gpu, &g.config, g.renderer.samples);
                g.msaa = msaa;
                g.depth = depth;
            }
            WindowEvent::RedrawRequested => self.redraw(),
            // A release the panel takes still ends a press begun in the view.
            WindowEvent::MouseInput {
                state: ElementState::Released,
                button: MouseButton::Left,
                ..
            } if resp.consumed => {
                self.press = None;
                self.drag = None;
            }
            WindowEvent::MouseInput { state, button, .. } if !resp.consumed => {
                // A left click that barely moved picks a muscle; a drag moves the camera.
                match (state, button) {
                    (ElementState::Pressed, MouseButton::Left) if !egui_wants => {
                        self.press = self.cursor.map(|c| (c, self.ui.hovered));
                    }
                    (ElementState::Released, MouseButton::Left) => {
                        if let (Some((p, picked)), Some(c)) = (self.press.take(), self.cursor)
                            && (p.0 - c.0).hypot(p.1 - c.1) < CLICK_SLOP_PX
                        {
                            self.ui.click(picked);
                        }
                    }
                    _ => {}
                }
                self.drag = match state {
                    ElementState::Pressed if !egui_wants => Some((button, (f64::NAN, f64::NAN))),
                    _ => None,
                };
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = Some((position.x, position.y));
                // A system that makes mouse moves of a finger's would turn the view twice.
                if let (Some((button, last)), Some(cam), true) = (
                    self.drag.as_mut(),
                    self.camera.as_mut(),
                    self.touches.is_empty(),
                ) {
                    if last.0.is_finite() {
                        let (dx, dy) = ((position.x - last.0) as f32, (position.y - last.1) as f32);
                        match button {
                            MouseButton::Left => cam.orbit(dx, dy, 0.006),
                            _ => cam.pan(dx, dy, g.config.height as f32),
                        }
                    }
                    *last = (position.x, position.y);
                }
            }
            WindowEvent::Touch(t) => {
                let at = (t.location.x, t.location.y);
                let height = g.config.height as f32;
                // Whose the finger is, by where it comes down (egui's own notion of the
                // pointer is the last frame's, and gone once a finger lifts).
                let ppp = f64::from(g.egui_ctx.pixels_per_point());
                let point = egui::pos2((at.0 / ppp) as f32, (at.1 / ppp) as f32);
                let panel = resp.consumed
                    || self.ui.panel_rect.is_some_and(|r| r.contains(point))
                    || g.egui_ctx
                        .layer_id_at(point)
                        .is_some_and(|l| l.order != egui::Order::Background);
                self.touch(t.id, t.phase, at, panel, height);
            }
            WindowEvent::MouseWheel { delta, .. } if !egui_wants => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(cam) = self.camera.as_mut() {
                    cam.zoom((-lines * 0.1).exp());
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        #[cfg(target_arch = "wasm32")]
        self.page_tick();
        if self
            .opts
            .exit_after_frames
            .is_some_and(|n| self.stats.frames >= n)
        {
            el.exit();
            return;
        }
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }
}

#[cfg(target_arch = "wasm32")]
#[path = "web.rs"]
pub mod web;

/// `new` with the muscle and tendon models `old` runs now: the panel's choice outlives a
/// reset or a load (the source's own models are only where a session starts), a muscle's
/// own tendon included.
fn with_models_of(mut new: Simulation, old: &Simulation) -> Simulation {
    new.set_muscle_model(old.muscle_model());
    // Only a changed default: the global switch would override tendons the catalogue
    // gives single muscles.
    if new.tendon_model() != old.tendon_model() {
        new.set_tendon_model(old.tendon_model());
    }
    // Muscles with a tendon of their own now keep it, where the new one has the muscle.
    for m in old.muscles() {
        if m.tendon != old.tendon_model() {
            let _ = new.set_muscle_tendon(&m.name, m.tendon);
        }
    }
    new
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reset_or_a_load_keeps_the_models_chosen_in_the_panel() {
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let mut old = Simulation::phantom(config.clone()).expect("phantom");
        old.set_muscle_model(MuscleModel::Spring);
        old.set_tendon_model(TendonModel::Compliant);
        let new = with_models_of(Simulation::phantom(config).expect("phantom"), &old);
        assert_eq!(new.muscle_model(), MuscleModel::Spring);
        assert_eq!(new.tendon_model(), TendonModel::Compliant);
    }

    #[test]
    fn a_reset_keeps_a_muscle_s_own_tendon() {
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let mut old = Simulation::phantom(config.clone()).expect("phantom");
        old.set_muscle_tendon("semitendinosus", TendonModel::Compliant)
            .expect("a catalogued muscle");
        let new = with_models_of(Simulation::phantom(config).expect("phantom"), &old);
        assert_eq!(new.tendon_model(), TendonModel::Rigid);
        for m in new.muscles() {
            let want = if m.name == "semitendinosus" {
                TendonModel::Compliant
            } else {
                TendonModel::Rigid
            };
            assert_eq!(m.tendon, want, "{}", m.name);
        }
    }
}
