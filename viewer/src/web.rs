//! The viewer in a web page: the window's app, renderer and panel drawing into the page's
//! canvas (`#myoslice-canvas`), the simulation single-threaded in the page. The page
//! (`web/index.html`, built by `scripts/web.sh`) hands files over and reads the state
//! through the functions exported here, which are also the hooks the browser test uses:
//! `status()`, `add_file(name, bytes)` + `open_files()`, `preset(name)`, `run_to(s)`.

// wasm-bindgen's exports and imports expand to `unsafe` glue.
#![allow(unsafe_code)]

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use anyhow::{Result, anyhow};
use myoslice::prelude::*;
use wasm_bindgen::prelude::*;
use web_time::Instant;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::platform::web::{EventLoopExtWebSys, WindowAttributesExtWebSys};
use winit::window::Window;

use super::{App, RunOptions, load};
use crate::gpu::Gpu;
use crate::model::{ModelSource, Preset};
use crate::ui::UiState;

/// The page's canvas.
const CANVAS_ID: &str = "myoslice-canvas";

/// Simulated time (s) a frame advances by on the way to a [`run_to`] target: the page
/// stays responsive and shows the motion.
const RUN_TO_CHUNK_S: f64 = 0.1;

/// A window's surface and device, once the browser's promises resolve.
type Ready = Result<(Arc<Window>, wgpu::Surface<'static>, Gpu)>;

/// Where the graphics arrive (see [`App::page_tick`]), and how their arrival wakes the
/// event loop.
#[derive(Default)]
pub(super) struct Arriving {
    slot: Rc<RefCell<Option<Ready>>>,
    wake: Option<EventLoopProxy<()>>,
}

/// What the page asked for, waiting for the next frame.
enum Command {
    Preset(Preset),
    Open(Vec<(String, Vec<u8>)>),
    Playing(bool),
}

/// What the page and the app share.
#[derive(Default)]
struct Page {
    /// Files added since the last [`open_files`].
    files: Vec<(String, Vec<u8>)>,
    commands: Vec<Command>,
    /// Simulated time a [`run_to`] is stepping to.
    running_to: Option<f64>,
    /// The state as [`status`] reports it.
    ready: bool,
    backend: String,
    build_ms: f64,
    time_s: f64,
    knee_deg: f64,
    model: String,
    error: Option<String>,
    frames: u64,
    /// Milliseconds from the page's start to its first frame drawn.
    first_frame_ms: Option<f64>,
    /// Mean time (ms) of the frames after the first, and of the simulation in them.
    frame_ms: f64,
    sim_ms: f64,
    /// Wall time (s) spent stepping toward [`run_to`] targets (frames apart).
    run_wall_s: f64,
    /// Where the 3D view starts on the canvas (pixels): the panel's right edge.
    view_left_px: f32,
    /// The knee axis's centre on the canvas (pixels from its top-left corner) and pixels
    /// per metre at its depth.
    knee_px: Option<([f32; 2], f32)>,
}

thread_local! {
    static PAGE: RefCell<Page> = RefCell::new(Page::default());
}

fn page<R>(f: impl FnOnce(&mut Page) -> R) -> R {
    PAGE.with(|p| f(&mut p.borrow_mut()))
}

/// Builds the phantom and starts the viewer on the page's canvas (run when the module
/// loads).
#[wasm_bindgen(start)]
pub fn start() {
    std::panic::set_hook(Box::new(|info| {
        let msg = format!("the viewer stopped: {info}");
        web_sys::console::error_1(&msg.clone().into());
        page(|p| p.error = Some(msg));
    }));
    if let Err(e) = launch() {
        let msg = format!("{e:#}");
        web_sys::console::error_1(&msg.clone().into());
        page(|p| p.error = Some(msg));
    }
}

fn launch() -> Result<()> {
    let event_loop =
        EventLoop::new().map_err(|e| anyhow!("cannot start the page's event loop: {e}"))?;
    // Frames come from the browser's animation frames (each asks for the next): between
    // them the page's thread is free.
    event_loop.set_control_flow(ControlFlow::Wait);
    let t0 = Instant::now();
    let sim = load(&ModelSource::Phantom, None)?;
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;
    page(|p| {
        p.build_ms = build_ms;
        p.model = ModelSource::Phantom.describe();
    });
    // `?paused` opens the page with the simulation stopped (a test, or a link to the rest
    // pose).
    let paused = web_sys::window()
        .and_then(|w| w.location().search().ok())
        .is_some_and(|q| q.contains("paused"));
    let ui = UiState {
        playing: !paused,
        ..UiState::default()
    };
    let mut app = App::new(sim, ui, None, RunOptions::default());
    app.arriving.wake = Some(event_loop.create_proxy());
    event_loop.spawn_app(app);
    Ok(())
}

/// The page's state as JSON: `ready` (drawing), `backend` (WebGPU or WebGL2),
/// `build_ms` (the phantom's build), `time_s`, `knee_deg`, `model`, `error` (the last
/// error, or null), `frames`, `running` (a [`run_to`] under way), `knee_px` (the knee
/// axis's centre on the canvas, in pixels), `px_per_m` (pixels per metre there),
/// `first_frame_ms` (from the page's start to its first frame), `frame_ms` and `sim_ms`
/// (mean time of a frame after the first, and of the simulation in it), `view_left_px`
/// (where the 3D view starts, right of the panel), `run_wall_s` (wall time spent stepping
/// toward [`run_to`] targets, the frames apart).
#[wasm_bindgen]
pub fn status() -> String {
    page(|p| {
        serde_json::json!({
            "ready": p.ready,
            "backend": p.backend,
            "build_ms": p.build_ms,
            "time_s": p.time_s,
            "knee_deg": p.knee_deg,
            "model": p.model,
            "error": p.error,
            "frames": p.frames,
            "running": p.running_to.is_some(),
            "first_frame_ms": p.first_frame_ms,
            "frame_ms": p.frame_ms,
            "sim_ms": p.sim_ms,
            "view_left_px": p.view_left_px,
            "run_wall_s": p.run_wall_s,
            "knee_px": p.knee_px.map(|k| k.0),
            "px_per_m": p.knee_px.map(|k| k.1),
        })
        .to_string()
    })
}

/// Adds a file (its name and bytes) to those [`open_files`] opens next.
#[wasm_bindgen]
pub fn add_file(name: String, bytes: Vec<u8>) {
    page(|p| p.files.push((name, bytes)));
}

/// Opens the files added since the last call, at the next frame: a label volume (NIfTI,
/// NRRD, a Slicer segmentation) with its label table or label list, or a scenario. A
/// file that does not build leaves the running leg as it is and sets `error`.
#[wasm_bindgen]
pub fn open_files() {
    page(|p| {
        let files = std::mem::take(&mut p.files);
        p.commands.push(Command::Open(files));
        p.error = None;
    });
}

/// Sets a preset's excitations: relax, flexion, extension or cocontraction.
#[wasm_bindgen]
pub fn preset(name: &str) -> Result<(), JsValue> {
    let p = Preset::parse(name).ok_or_else(|| {
        JsValue::from_str(&format!(
            "unknown preset '{name}': use relax, flexion, extension or cocontraction"
        ))
    })?;
    page(|page| page.commands.push(Command::Preset(p)));
    Ok(())
}

/// Pauses playback and steps the simulation to `seconds` of simulated time, a tenth of a
/// second a frame (`status().running` is true until it is there).
#[wasm_bindgen]
pub fn run_to(seconds: f64) -> Result<(), JsValue> {
    if !(seconds.is_finite() && seconds >= 0.0) {
        return Err(JsValue::from_str(&format!(
            "run_to({seconds}): expected a finite time >= 0"
        )));
    }
    // Set at once, so that `status().running` says so from this call on.
    page(|p| p.running_to = Some(seconds));
    Ok(())
}

/// Plays or pauses the simulation.
#[wasm_bindgen]
pub fn set_playing(playing: bool) {
    page(|p| p.commands.push(Command::Playing(playing)));
}

impl App {
    /// Creates the window on the page's canvas and asks the browser for a device (WebGPU
    /// where it has it, WebGL2 otherwise); [`Self::page_tick`] attaches it when it comes.
    pub(super) fn init(&mut self, el: &ActiveEventLoop) -> Result<()> {
        use wasm_bindgen::JsCast;
        let canvas = web_sys::window()
            .and_then(|w| w.document())
            .and_then(|d| d.get_element_by_id(CANVAS_ID))
            .and_then(|e| e.dyn_into::<web_sys::HtmlCanvasElement>().ok())
            .ok_or_else(|| anyhow!("the page has no <canvas id=\"{CANVAS_ID}\">"))?;
        let attrs = Window::default_attributes()
            .with_title("myoslice")
            .with_canvas(Some(canvas))
            .with_prevent_default(true);
        let window = Arc::new(el.create_window(attrs)?);
        let slot = Rc::clone(&self.arriving.slot);
        let wake = self.arriving.wake.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let ready = async {
                let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
                desc.backends = wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL;
                let instance = wgpu::util::new_instance_with_webgpu_detection(desc).await;
                let surface = instance.create_surface(window.clone())?;
                let gpu = Gpu::request(instance, Some(&surface)).await?;
                Ok((window, surface, gpu))
            };
            *slot.borrow_mut() = Some(ready.await);
            // The loop may be gone (the page closing): nothing to wake then.
            if let Some(w) = wake {
                let _ = w.send_event(());
            }
        });
        Ok(())
    }

    /// After each round of events (a frame, the device arriving): attaches the graphics
    /// when they arrive, runs what the page asked for and publishes the state.
    pub(super) fn page_tick(&mut self) {
        if self.gfx.is_none() {
            let arrived = self.arriving.slot.borrow_mut().take();
            match arrived.map(|r| {
                r.and_then(|(w, s, g)| {
                    let backend = match g.adapter.get_info().backend {
                        wgpu::Backend::BrowserWebGpu => "WebGPU",
                        wgpu::Backend::Gl => "WebGL2",
                        _ => "other",
                    };
                    page(|p| p.backend = backend.into());
                    self.attach(w, s, g)
                })
            }) {
                Some(Ok(())) => page(|p| p.ready = true),
                Some(Err(e)) => {
                    page(|p| p.error = Some(format!("no graphics in this page: {e:#}")))
                }
                None => {}
            }
        }
        let commands = page(|p| std::mem::take(&mut p.commands));
        for c in commands {
            let r = match c {
                Command::Preset(p) => p.apply(&mut self.sim),
                Command::Playing(on) => {
                    self.ui.playing = on;
                    Ok(())
                }
                Command::Open(files) => {
                    // A model opened meanwhile stops a run toward a time of the one before.
                    page(|p| p.running_to = None);
                    self.open(files)
                }
            };
            if let Err(e) = r {
                self.ui.error = Some(format!("{e:#}"));
                page(|p| p.error = Some(format!("{e:#}")));
            }
        }
        if let Some(target) = page(|p| p.running_to) {
            self.ui.playing = false;
            let left = target - self.sim.time();
            let r = if left > 1e-9 {
                let t0 = Instant::now();
                let r = self.sim.step(left.min(RUN_TO_CHUNK_S));
                let wall = t0.elapsed().as_secs_f64();
                page(|p| p.run_wall_s += wall);
                r
            } else {
                page(|p| p.running_to = None);
                self.sim.update_tissue().map(|_| ())
            };
            match r {
                Ok(_) => self.ui.record(&self.sim),
                Err(e) => {
                    page(|p| {
                        p.running_to = None;
                        p.error = Some(e.to_string());
                    });
                    self.ui.error = Some(e.to_string());
                }
            }
        }
        let (time, knee) = (self.sim.time(), self.sim.knee_angle().to_degrees());
        let frames = self.stats.frames;
        let model = self.ui.source.describe();
        let knee_px = self.knee_on_canvas();
        let view_left = match (&self.gfx, self.ui.panel_rect) {
            (Some(g), Some(r)) => r.max.x * g.egui_ctx.pixels_per_point(),
            _ => 0.0,
        };
        // performance.now() counts from the page's start.
        let now_ms = web_sys::window()
            .and_then(|w| w.performance())
            .map(|p| p.now());
        let (frame_ms, sim_ms) = (self.stats.mean_ms(), self.stats.mean_sim_ms());
        page(|p| {
            if frames > 0 && p.first_frame_ms.is_none() {
                p.first_frame_ms = now_ms;
            }
            p.frame_ms = frame_ms;
            p.sim_ms = sim_ms;
            p.time_s = time;
            p.knee_deg = knee;
            p.frames = frames;
            p.model = model;
            p.knee_px = knee_px;
            p.view_left_px = view_left;
        });
    }

    /// Where the knee axis's centre is on the canvas, and pixels per metre there.
    fn knee_on_canvas(&self) -> Option<([f32; 2], f32)> {
        let (g, camera) = (self.gfx.as_ref()?, self.camera?);
        let (w, h) = (g.config.width as f32, g.config.height.max(1) as f32);
        let view = camera.view();
        let vp = camera.projection(w / h) * view;
        let to_px = |p: glam::Vec3| {
            let clip = vp * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            glam::Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h)
        };
        let knee = self.sim.knee_axis().point;
        let right = glam::Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let k = to_px(knee);
        let per_m = to_px(knee + right * 0.1).distance(k) / 0.1;
        Some(([k.x, k.y], per_m))
    }

    /// Builds the model of `files`; on failure the running leg stays.
    fn open(&mut self, files: Vec<(String, Vec<u8>)>) -> Result<()> {
        let src = ModelSource::from_files(files, self.ui.open_unmapped)?;
        let sim = src.load(SimulationConfig::default())?;
        self.switch_to(src, sim);
        self.ui.error = None;
        page(|p| p.error = None);
        Ok(())
    }
}
