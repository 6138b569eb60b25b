//! The passes of a scene frame as pipelines plus functions that record them into an encoder.
//! Each knows what it draws or counts, never why: the culling strategies decide that.
//!
//! - [`Passes::record_prepass`]: depth + tile id of a set of draws (prepass.wgsl);
//! - [`Passes::record_histogram`]: exact pixels per tile id of an id image (histogram.wgsl);
//! - [`Passes::record_select`]: draw args switched off where a count is at or under a threshold
//!   (select.wgsl), so the next draw needs no read-back;
//! - [`Passes::record_draw`]: the lit draw of a set of draws, colour + tile id (draw.wgsl).
//!
//! Sets of draws are indirect buffers of [`DrawArgs`], one per tile, drawn with one
//! `multi_draw_indexed_indirect`.

use super::geometry::SceneGeometry;
use super::layout::{DrawArgs, SelectParams};
use super::targets::{Targets, COLOR_FORMAT, DEPTH_FORMAT, ID_FORMAT};
use super::timing::Timestamps;
use super::GpuContext;
use wgpu::util::DeviceExt;

const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");

/// Usage of every indirect-args buffer: drawn from, written by compute, copied for read-back.
pub const ARGS_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDIRECT
    .union(wgpu::BufferUsages::STORAGE)
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// Pipelines and bind-group layouts of the scene passes.
pub struct Passes {
    pub scene_layout: wgpu::BindGroupLayout,
    hist_layout: wgpu::BindGroupLayout,
    select_layout: wgpu::BindGroupLayout,
    draw: wgpu::RenderPipeline,
    prepass: wgpu::RenderPipeline,
    histogram: wgpu::ComputePipeline,
    select: wgpu::ComputePipeline,
}

pub fn storage_entry(binding: u32, read_only: bool, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

pub fn uniform_entry(binding: u32, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn shader(d: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

fn compute(
    d: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&pl),
        module,
        entry_point: Some(entry),
        // Every shader here writes its workgroup memory before reading it (histogram.wgsl: each
        // lane its own slot, then a barrier), so the zero-initialisation naga adds by default is
        // dead work; naga writes it out for GLSL, where it made the histogram 11x slower (120 ms
        // vs 11 ms at 1280 x 1024 on llvmpipe; Vulkan: 11 ms either way).
        compilation_options: wgpu::PipelineCompilationOptions {
            zero_initialize_workgroup_memory: false,
            ..Default::default()
        },
        cache: None,
    })
}

/// A render pass over `targets`, cleared: colour to the background, ids to 0, depth to far (0).
fn begin<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    targets: &'e Targets,
    with_color: bool,
    keep_depth: bool,
    ts: Option<wgpu::RenderPassTimestampWrites<'e>>,
) -> wgpu::RenderPass<'e> {
    let clear = |c: wgpu::Color| wgpu::Operations { load: wgpu::LoadOp::Clear(c), store: wgpu::StoreOp::Store };
    let view = |v: &'e wgpu::TextureView, c: wgpu::Color| {
        Some(wgpu::RenderPassColorAttachment { view: v, depth_slice: None, resolve_target: None, ops: clear(c) })
    };
    let black = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 };
    let color = with_color.then(|| view(targets.color.as_ref().expect("targets without colour"), black)).flatten();
    let id = view(&targets.id, wgpu::Color::TRANSPARENT);
    let attachments = [color, id];
    let store = if keep_depth { wgpu::StoreOp::Store } else { wgpu::StoreOp::Discard };
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: if with_color { &attachments[..] } else { &attachments[1..] },
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store }),
            stencil_ops: None,
        }),
        timestamp_writes: ts,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

impl Passes {
    pub fn new(d: &wgpu::Device) -> Self {
        let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let scene_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &[uniform_entry(0, vf), storage_entry(1, true, vf), storage_entry(2, true, vf)],
        });
        let cs = wgpu::ShaderStages::COMPUTE;
        let hist_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("histogram"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: cs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                storage_entry(1, false, cs),
            ],
        });
        let select_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("select"),
            entries: &[
                uniform_entry(0, cs),
                storage_entry(1, true, cs),
                storage_entry(2, true, cs),
                storage_entry(3, false, cs),
            ],
        });
        let scene_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&scene_layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            }],
        };
        let depth_state = wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            // Reverse-Z: larger is nearer.
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        };
        // GL writes frag_depth from `*_gl` entry points, for reverse-Z precision (common.wgsl).
        let gl = d.adapter_info().backend == wgpu::Backend::Gl;
        let scene_pipeline = |label: &str, file: &str, fs: &str, targets: &[Option<wgpu::ColorTargetState>]| {
            let module = shader(d, label, format!("{COMMON_WGSL}\n{file}"));
            let (vs, fs) = if gl { ("vs_gl", format!("{fs}_gl")) } else { ("vs_main", fs.to_string()) };
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&scene_pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(vertex_layout.clone())],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(depth_state.clone()),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(&fs),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let draw = scene_pipeline(
            "draw.wgsl",
            include_str!("shaders/draw.wgsl"),
            "fs_main",
            &[
                Some(wgpu::ColorTargetState { format: COLOR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL }),
                Some(ID_FORMAT.into()),
            ],
        );
        let prepass =
            scene_pipeline("prepass.wgsl", include_str!("shaders/prepass.wgsl"), "fs_id", &[Some(ID_FORMAT.into())]);
        let hist_shader = shader(d, "histogram.wgsl", include_str!("shaders/histogram.wgsl").into());
        let select_shader = shader(d, "select.wgsl", include_str!("shaders/select.wgsl").into());
        let histogram = compute(d, "histogram", &hist_layout, &hist_shader, "histogram");
        let select = compute(d, "select", &select_layout, &select_shader, "select_draws");
        Self { scene_layout, hist_layout, select_layout, draw, prepass, histogram, select }
    }

    /// Pass: depth + tile id of `args` (one draw per tile) into `targets` (no colour). Depth is
    /// discarded; the ids are what later passes count.
    pub fn record_prepass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        ts: Option<&Timestamps>,
    ) {
        let mut pass = begin(enc, "prepass", targets, false, false, ts.and_then(|t| t.render("prepass_ms")));
        self.draw_into(&mut pass, &self.prepass, scene_bg, geom, args);
    }

    /// Pass: the lit draw of `args` into `targets` (colour, tile id, depth kept for read-back).
    pub fn record_draw(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        ts: Option<&Timestamps>,
    ) {
        let mut pass = begin(enc, "draw", targets, true, true, ts.and_then(|t| t.render("draw_ms")));
        self.draw_into(&mut pass, &self.draw, scene_bg, geom, args);
    }

    fn draw_into(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
    ) {
        if let (Some(vb), Some(ib)) = (&geom.vertices, &geom.indices) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, scene_bg, &[]);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            pass.multi_draw_indexed_indirect(args, 0, geom.n_tiles() as u32);
        }
    }

    /// Pass: adds, per tile, the pixels of `ids` (width × height) holding that tile's id + 1 to
    /// `counts` (one u32 per tile; clear it first for a fresh count).
    pub fn record_histogram(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        ids: &wgpu::TextureView,
        size: (u32, u32),
        counts: &wgpu::Buffer,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("histogram"),
            layout: &self.hist_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(ids) },
                wgpu::BindGroupEntry { binding: 1, resource: counts.as_entire_binding() },
            ],
        });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("histogram"), timestamp_writes: ts });
        pass.set_pipeline(&self.histogram);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(size.0.div_ceil(16), size.1.div_ceil(16), 1);
    }

    /// Pass: `out[i] = src[i]`, switched off where `counts[i] <= threshold`, for `n` tiles.
    #[allow(clippy::too_many_arguments)]
    pub fn record_select(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        counts: &wgpu::Buffer,
        src: &wgpu::Buffer,
        out: &wgpu::Buffer,
        n: usize,
        threshold: f32,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let params = SelectParams { n_tiles: n as u32, threshold, _pad: [0; 2] };
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("select_params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("select"),
            layout: &self.select_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: counts.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: src.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: out.as_entire_binding() },
            ],
        });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("select"), timestamp_writes: ts });
        pass.set_pipeline(&self.select);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups((n as u32).div_ceil(64).max(1), 1, 1);
    }
}

/// An indirect-args buffer holding `args` (one zeroed draw when empty: buffers may not be empty).
pub fn args_buffer(d: &wgpu::Device, label: &str, args: &[DrawArgs]) -> wgpu::Buffer {
    let one = [DrawArgs::default()];
    let a = if args.is_empty() { &one[..] } else { args };
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(a),
        usage: ARGS_USAGE,
    })
}

/// An uninitialised indirect-args buffer for `n` draws (a compute pass fills it).
pub fn empty_args_buffer(d: &wgpu::Device, label: &str, n: usize) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (n.max(1) * std::mem::size_of::<DrawArgs>()) as u64,
        usage: ARGS_USAGE,
        mapped_at_creation: false,
    })
}

/// A zeroed u32 per tile for histogram counts.
pub fn counts_buffer(d: &wgpu::Device, n: usize) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("counts"),
        size: 4 * n.max(1) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl GpuContext {
    /// A new command encoder.
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }
}

impl Passes {
    /// The scene bind group of one frame: uniforms, per-object state, the tile → object table.
    pub fn scene_bind_group(
        &self,
        d: &wgpu::Device,
        globals: &super::layout::Globals,
        objects: &[super::layout::GpuObject],
        geom: &SceneGeometry,
    ) -> wgpu::BindGroup {
        let zero = [bytemuck::Zeroable::zeroed()];
        let objects = if objects.is_empty() { &zero[..] } else { objects };
        let globals_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::bytes_of(globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let objects_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("objects"),
            contents: bytemuck::cast_slice(objects),
            usage: wgpu::BufferUsages::STORAGE,
        });
        d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.scene_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: globals_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: objects_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: geom.tile_object.as_entire_binding() },
            ],
        })
    }
}
