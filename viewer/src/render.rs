//! The renderer: opaque layers with depth, translucent layers sorted back to front,
//! multisampled, and a colour-bar legend overlay.

use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::camera::OrbitCamera;
use crate::colormap::{self, ColorMode};
use crate::gpu::Gpu;
use crate::scene::{SceneMesh, Vertex};

/// Depth format.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Background colour (linear).
pub const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.018,
    g: 0.021,
    b: 0.027,
    a: 1.0,
};

/// Per-frame drawing options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Draw the colour-bar legend for this mode (None: no legend).
    pub legend: Option<ColorMode>,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
}

/// GPU pipelines and buffers for drawing [`SceneMesh`]es.
#[derive(Debug)]
pub struct Renderer {
    opaque: wgpu::RenderPipeline,
    transparent: wgpu::RenderPipeline,
    overlay: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vbuf: Option<(wgpu::Buffer, u64)>,
    ibuf: Option<(wgpu::Buffer, u64)>,
    /// Samples per pixel of the colour target.
    pub samples: u32,
}

fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRS: [wgpu::VertexAttribute; 3] =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRS,
    }
}

impl Renderer {
    /// Pipelines for colour targets of `format` with `samples` samples per pixel.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, samples: u32) -> Self {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("mesh.wgsl").into()),
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("uniforms"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let make = |label: &str,
                    vs: &str,
                    fs: &str,
                    depth_write: bool,
                    depth_test: bool,
                    blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers: &[Some(vertex_layout())],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(if depth_test {
                        wgpu::CompareFunction::Less
                    } else {
                        wgpu::CompareFunction::Always
                    }),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let opaque = make(
            "opaque",
            "vs_main",
            "fs_main",
            true,
            true,
            Some(wgpu::BlendState::REPLACE),
        );
        let transparent = make(
            "transparent",
            "vs_main",
            "fs_main",
            false,
            true,
            Some(wgpu::BlendState::ALPHA_BLENDING),
        );
        let overlay = make(
            "overlay",
            "vs_overlay",
            "fs_overlay",
            false,
            false,
            Some(wgpu::BlendState::ALPHA_BLENDING),
        );
        Self {
            opaque,
            transparent,
            overlay,
            uniforms,
            bind_group,
            vbuf: None,
            ibuf: None,
            samples,
        }
    }

    fn upload(
        buf: &mut Option<(wgpu::Buffer, u64)>,
        gpu: &Gpu,
        data: &[u8],
        usage: wgpu::BufferUsages,
        label: &str,
    ) {
        let need = data.len() as u64;
        match buf {
            Some((b, cap)) if *cap >= need && need > 0 => gpu.queue.write_buffer(b, 0, data),
            _ => {
                let b = gpu
                    .device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: if data.is_empty() { &[0u8; 16] } else { data },
                        usage: usage | wgpu::BufferUsages::COPY_DST,
                    });
                *buf = Some((b, need.max(16)));
            }
        }
    }

    /// Records the drawing of `scene` into `view` (resolving into `resolve` when
    /// multisampled) with depth buffer `depth`.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        resolve: Option<&wgpu::TextureView>,
        depth: &wgpu::TextureView,
        size: (u32, u32),
        scene: &SceneMesh,
        camera: &OrbitCamera,
        settings: &RenderSettings,
    ) {
        let aspect = size.0 as f32 / size.1.max(1) as f32;
        let vp: Mat4 = camera.projection(aspect) * camera.view();
        let eye = camera.eye();
        let u = Uniforms {
            view_proj: vp.to_cols_array_2d(),
            eye: [eye.x, eye.y, eye.z, 1.0],
        };
        gpu.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        // Opaque triangles first, then translucent ones sorted far to near.
        let mut opaque: Vec<u32> = Vec::with_capacity(scene.indices.len());
        let mut translucent: Vec<(f32, [u32; 3])> = Vec::new();
        for range in &scene.ranges {
            let tris = scene.indices[range.start as usize..range.end as usize].chunks_exact(3);
            for t in tris {
                let a = scene.vertices[t[0] as usize].color[3];
                if a >= 0.999 {
                    opaque.extend_from_slice(t);
                } else if a > 0.0 {
                    let c = (Vec3::from(scene.vertices[t[0] as usize].pos)
                        + Vec3::from(scene.vertices[t[1] as usize].pos)
                        + Vec3::from(scene.vertices[t[2] as usize].pos))
                        / 3.0;
                    translucent.push((c.distance_squared(eye), [t[0], t[1], t[2]]));
                }
            }
        }
        translucent.sort_by(|a, b| b.0.total_cmp(&a.0));
        let n_opaque = opaque.len() as u32;
        opaque.extend(translucent.iter().flat_map(|(_, t)| *t));
        let n_all = opaque.len() as u32;
        // Legend quads (in NDC) go after the scene vertices.
        let mut vertices = scene.vertices.clone();
        let legend_start = n_all;
        if let Some(mode) = settings.legend
            && mode != ColorMode::None
        {
            legend(&mut vertices, &mut opaque, mode, aspect);
        }
        let n_total = opaque.len() as u32;
        Self::upload(
            &mut self.vbuf,
            gpu,
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
            "vertices",
        );
        Self::upload(
            &mut self.ibuf,
            gpu,
            bytemuck::cast_slice(&opaque),
            wgpu::BufferUsages::INDEX,
            "indices",
        );
        let (Some((vb, _)), Some((ib, _))) = (&self.vbuf, &self.ibuf) else {
            return;
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(BACKGROUND),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, vb.slice(..));
        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
        if n_opaque > 0 {
            pass.set_pipeline(&self.opaque);
            pass.draw_indexed(0..n_opaque, 0, 0..1);
        }
        if n_all > n_opaque {
            pass.set_pipeline(&self.transparent);
            pass.draw_indexed(n_opaque..n_all, 0, 0..1);
        }
        if n_total > legend_start {
            pass.set_pipeline(&self.overlay);
            pass.draw_indexed(legend_start..n_total, 0, 0..1);
        }
    }
}

/// A vertical colour bar at the right edge, in NDC, with a dark frame.
fn legend(vertices: &mut Vec<Vertex>, indices: &mut Vec<u32>, mode: ColorMode, aspect: f32) {
    let w = 0.04 / aspect.max(0.2);
    let (x0, x1, y0, y1) = (0.92 - w, 0.92, -0.6, 0.6);
    let mut quad = |xa: f32, xb: f32, ya: f32, yb: f32, ca: [f32; 3], cb: [f32; 3]| {
        let base = vertices.len() as u32;
        for (x, y, c) in [(xa, ya, ca), (xb, ya, ca), (xb, yb, cb), (xa, yb, cb)] {
            vertices.push(Vertex {
                pos: [x, y, 0.0],
                normal: [0.0, 0.0, 1.0],
                color: [c[0], c[1], c[2], 1.0],
            });
        }
        indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    };
    let pad = 0.008;
    quad(
        x0 - pad,
        x1 + pad,
        y0 - pad * aspect,
        y1 + pad * aspect,
        [0.05; 3],
        [0.05; 3],
    );
    let n = 32;
    for k in 0..n {
        let (t0, t1) = (k as f32 / n as f32, (k + 1) as f32 / n as f32);
        let col = |t: f32| match mode {
            ColorMode::Area => colormap::area_color(2.0 * t - 1.0, 1.0),
            _ => colormap::degree_color(t, 1.0),
        };
        quad(
            x0,
            x1,
            y0 + (y1 - y0) * t0,
            y0 + (y1 - y0) * t1,
            col(t0),
            col(t1),
        );
    }
}
