//! Off-screen capture: render the simulation into a texture without any window, read it
//! back, write PNG or GIF.

use std::path::Path;

use anyhow::{Context, Result};
use myoslice::Simulation;

use crate::camera::{CameraPreset, OrbitCamera};

use crate::gpu::Gpu;
use crate::render::{DEPTH, RenderSettings, Renderer};
use crate::scene::{SceneMesh, SceneOptions};

/// Colour format of captures.
pub const CAPTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// What a capture looks like.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureOptions {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Viewpoint.
    pub camera: CameraPreset,
    /// Scene options (colour mode, layers).
    pub scene: SceneOptions,
    /// Draw the colour-bar legend.
    pub legend: bool,
    /// Keep this camera instead of framing each picture on its own (animations).
    pub fixed_camera: Option<OrbitCamera>,
}

impl Default for CaptureOptions {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            camera: CameraPreset::Oblique,
            scene: SceneOptions::default(),
            legend: true,
            fixed_camera: None,
        }
    }
}

/// Render targets of one size, reusable across frames.
#[derive(Debug)]
pub struct Offscreen {
    renderer: Renderer,
    msaa: Option<wgpu::TextureView>,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth: wgpu::TextureView,
    size: (u32, u32),
}

impl Offscreen {
    /// Targets of `width` × `height`.
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Self {
        let samples = gpu.msaa_samples(CAPTURE_FORMAT);
        let tex = |format, samples, usage, label| {
            gpu.target((width, height), format, samples, usage, label)
        };
        let color = tex(
            CAPTURE_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            "color",
        );
        let color_view = color.create_view(&wgpu::TextureViewDescriptor::default());
        let msaa = (samples > 1).then(|| {
            tex(
                CAPTURE_FORMAT,
                samples,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
                "msaa",
            )
            .create_view(&wgpu::TextureViewDescriptor::default())
        });
        let depth = tex(
            DEPTH,
            samples,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
            "depth",
        )
        .create_view(&wgpu::TextureViewDescriptor::default());
        Self {
            renderer: Renderer::new(gpu, CAPTURE_FORMAT, samples),
            msaa,
            color,
            color_view,
            depth,
            size: (width, height),
        }
    }

    /// Renders the simulation now and returns RGBA8 pixels, rows top to bottom.
    pub fn render(
        &mut self,
        gpu: &Gpu,
        sim: &Simulation,
        opts: &CaptureOptions,
    ) -> Result<Vec<u8>> {
        let scene = SceneMesh::build(sim, &opts.scene);
        let camera = camera_for(&scene, opts);
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("capture"),
            });
        let settings = RenderSettings {
            legend: opts.legend.then_some(opts.scene.color_mode),
        };
        let (view, resolve) = match &self.msaa {
            Some(m) => (m, Some(&self.color_view)),
            None => (&self.color_view, None),
        };
        self.renderer.draw(
            gpu,
            &mut enc,
            view,
            resolve,
            &self.depth,
            self.size,
            &scene,
            &camera,
            &settings,
        );
        read_rgba(gpu, enc, &self.color)
    }
}

/// The camera a capture of `scene` uses: the fixed one, or one framing the scene.
fn camera_for(scene: &SceneMesh, opts: &CaptureOptions) -> OrbitCamera {
    let aspect = opts.width as f32 / opts.height.max(1) as f32;
    opts.fixed_camera.unwrap_or_else(|| {
        OrbitCamera::framing(scene.bounds.0, scene.bounds.1, opts.camera, aspect)
    })
}

/// What a capture shows, for annotating or checking it: where the knee lies in the
/// picture and at what angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureMeta {
    /// Picture size (pixels).
    pub size: [u32; 2],
    /// Simulated time (s).
    pub time: f64,
    /// Knee flexion (degrees).
    pub knee_angle_deg: f64,
    /// The knee axis's centre in the picture (pixels from the top-left corner).
    pub knee_px: [f32; 2],
    /// Pixels per metre at the knee's depth (to size regions around it).
    pub px_per_m: f32,
}

impl CaptureMeta {
    /// The metadata of a capture of `sim` now with `opts`.
    pub fn of(sim: &Simulation, opts: &CaptureOptions) -> Self {
        let scene = SceneMesh::build(sim, &opts.scene);
        let camera = camera_for(&scene, opts);
        let (w, h) = (opts.width as f32, opts.height.max(1) as f32);
        let vp = camera.projection(w / h) * camera.view();
        let knee = sim.knee_axis().point;
        let to_px = |p: glam::Vec3| {
            let clip = vp * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            [(ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h]
        };
        let k = to_px(knee);
        // A 10 cm step across the view at the knee's depth.
        let view = camera.view();
        let right = glam::Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let r = to_px(knee + right * 0.1);
        Self {
            size: [opts.width, opts.height],
            time: sim.time(),
            knee_angle_deg: sim.knee_angle().to_degrees(),
            knee_px: k,
            px_per_m: (r[0] - k[0]).hypot(r[1] - k[1]) / 0.1,
        }
    }

    /// As a JSON object (non-finite numbers as `null`).
    pub fn to_json(&self) -> String {
        let num = |v: f64| {
            if v.is_finite() {
                format!("{v:?}")
            } else {
                "null".into()
            }
        };
        format!(
            "{{\"width\": {}, \"height\": {}, \"time_s\": {}, \"knee_angle_deg\": {}, \"knee_px\": [{}, {}], \"px_per_m\": {}}}\n",
            self.size[0],
            self.size[1],
            num(self.time),
            num(self.knee_angle_deg),
            num(f64::from(self.knee_px[0])),
            num(f64::from(self.knee_px[1])),
            num(f64::from(self.px_per_m))
        )
    }

    /// Writes the JSON to `path`.
    pub fn write(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.to_json()).with_context(|| format!("writing {}", path.display()))
    }
}

fn read_rgba(gpu: &Gpu, mut enc: wgpu::CommandEncoder, tex: &wgpu::Texture) -> Result<Vec<u8>> {
    let (w, h) = (tex.width(), tex.height());
    let unpadded = w * 4;
    let padded = wgpu::util::align_to(unpadded, wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    enc.copy_texture_to_buffer(
        tex.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: None,
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    let idx = gpu.queue.submit([enc.finish()]);
    let slice = buf.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(idx),
            timeout: None,
        })
        .map_err(|e| anyhow::anyhow!("waiting for the GPU: {e}"))?;
    rx.recv()?
        .map_err(|e| anyhow::anyhow!("reading the frame back: {e}"))?;
    let mut out = Vec::with_capacity((unpadded * h) as usize);
    {
        let data = slice
            .get_mapped_range()
            .map_err(|e| anyhow::anyhow!("mapping: {e}"))?;
        for row in data.chunks(padded as usize) {
            out.extend_from_slice(&row[..unpadded as usize]);
        }
    }
    buf.unmap();
    Ok(out)
}

/// Writes RGBA8 pixels as an RGB PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    enc.write_header()?.write_image_data(&rgb)?;
    Ok(())
}

/// Renders one PNG of the simulation as it is now.
pub fn capture_png(gpu: &Gpu, sim: &Simulation, opts: &CaptureOptions, path: &Path) -> Result<()> {
    let mut off = Offscreen::new(gpu, opts.width, opts.height);
    let rgba = off.render(gpu, sim, opts)?;
    write_png(path, opts.width, opts.height, &rgba)
}

/// Steps `sim` by `seconds` (in calls of at most a second) and updates its tissue for
/// the picture.
pub fn advance(sim: &mut Simulation, seconds: f64) -> Result<()> {
    anyhow::ensure!(
        seconds.is_finite() && seconds >= 0.0,
        "cannot advance by {seconds} s: expected a finite time >= 0"
    );
    let mut left = seconds;
    while left > 1e-12 {
        let h = left.min(1.0);
        sim.step(h)?;
        left -= h;
    }
    sim.update_tissue()?;
    Ok(())
}

/// Renders `frames` pictures from now to `duration` seconds later, both ends included
/// (a single frame shows the end):
/// PNGs into `out_dir` (`frame_0000.png`, ...) and/or one animated GIF. The camera
/// frames the whole motion (found by a dry run on a copy) and stays put.
pub fn capture_frames(
    gpu: &Gpu,
    sim: &mut Simulation,
    opts: &CaptureOptions,
    duration: f64,
    frames: usize,
    out_dir: Option<&Path>,
    gif_path: Option<&Path>,
) -> Result<()> {
    // One frame shows the end of the span.
    if frames == 1 && duration > 0.0 {
        advance(sim, duration)?;
    }
    let dt = if frames > 1 {
        duration / (frames - 1) as f64
    } else {
        0.0
    };
    let mut opts = opts.clone();
    if opts.fixed_camera.is_none() {
        let mut dry = sim.clone();
        let (mut lo, mut hi) = SceneMesh::build(&dry, &opts.scene).bounds;
        for _ in 1..frames {
            advance(&mut dry, dt)?;
            let b = SceneMesh::build(&dry, &opts.scene).bounds;
            (lo, hi) = (lo.min(b.0), hi.max(b.1));
        }
        let aspect = opts.width as f32 / opts.height.max(1) as f32;
        opts.fixed_camera = Some(OrbitCamera::framing(lo, hi, opts.camera, aspect));
    }
    let opts = &opts;
    let mut off = Offscreen::new(gpu, opts.width, opts.height);
    if let Some(d) = out_dir {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let mut gif_enc = match gif_path {
        Some(p) => {
            let f =
                std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?;
            let w = u16::try_from(opts.width).context("GIF width must be below 65536")?;
            let h = u16::try_from(opts.height).context("GIF height must be below 65536")?;
            let mut e = gif::Encoder::new(std::io::BufWriter::new(f), w, h, &[])?;
            e.set_repeat(gif::Repeat::Infinite)?;
            Some(e)
        }
        None => None,
    };
    let delay = ((dt * 100.0).round() as u16).max(2);
    for k in 0..frames {
        if k > 0 {
            advance(sim, dt)?;
        }
        let mut rgba = off.render(gpu, sim, opts)?;
        if let Some(d) = out_dir {
            write_png(
                &d.join(format!("frame_{k:04}.png")),
                opts.width,
                opts.height,
                &rgba,
            )?;
        }
        if let Some(e) = gif_enc.as_mut() {
            let mut frame =
                gif::Frame::from_rgba_speed(opts.width as u16, opts.height as u16, &mut rgba, 10);
            frame.delay = delay;
            e.write_frame(&frame)?;
        }
    }
    Ok(())
}
