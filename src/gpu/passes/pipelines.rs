//! The scene passes' pipelines and bind-group layouts, built once per device ([`Passes::new`]):
//! the layouts, the scene pipelines (lit passes, blended, prepass), the compute pipelines
//! (histogram, select, select_rest, slab_gate), the box test's.

use super::Passes;
use crate::gpu::shader::{
    box_pipeline, float_texture_entry, shader, storage_entry, uint_texture_entry, uniform_entry, with_box_wgsl,
    BOX_TEST_WGSL, COMMON_WGSL, GLOBALS_WGSL, PRIORITY_WGSL, SELECT_WGSL,
};
use crate::gpu::targets::{COLOR_FORMAT, DEPTH_FORMAT, ID_FORMAT};
use wgpu::util::DeviceExt;

/// The bind-group layouts of the scene passes, the histogram and the selection.
struct Layouts {
    scene: wgpu::BindGroupLayout,
    hist: wgpu::BindGroupLayout,
    select: wgpu::BindGroupLayout,
}

/// The render pipelines over the scene's geometry (see the fields of [`Passes`]).
struct ScenePipelines {
    draw: wgpu::RenderPipeline,
    draw_grid: wgpu::RenderPipeline,
    draw_field: wgpu::RenderPipeline,
    draw_field_fine: wgpu::RenderPipeline,
    draw_closed: wgpu::RenderPipeline,
    draw_cells: wgpu::RenderPipeline,
    draw_cells_closed: wgpu::RenderPipeline,
    draw_blend: wgpu::RenderPipeline,
    prepass: wgpu::RenderPipeline,
}

/// The compute pipelines (and select_rest's layout).
struct ComputePipelines {
    histogram: wgpu::ComputePipeline,
    select: wgpu::ComputePipeline,
    rest_layout: wgpu::BindGroupLayout,
    select_rest: wgpu::ComputePipeline,
    slab_gate: wgpu::ComputePipeline,
}

/// The box test's layout and pipelines, the slab test, and the box's corner indices.
struct BoxPipelines {
    box_layout: wgpu::BindGroupLayout,
    box_test: wgpu::RenderPipeline,
    box_early: Option<wgpu::RenderPipeline>,
    slab_test: crate::gpu::slab_test::SlabTest,
    box_indices: wgpu::Buffer,
}

impl Passes {
    pub fn new(d: &wgpu::Device) -> Self {
        let layouts = layouts(d);
        // GL writes frag_depth from `*_gl` entry points, for reverse-Z precision (common.wgsl).
        let gl = d.adapter_info().backend == wgpu::Backend::Gl;
        let ScenePipelines {
            draw,
            draw_grid,
            draw_field,
            draw_field_fine,
            draw_closed,
            draw_cells,
            draw_cells_closed,
            draw_blend,
            prepass,
        } = scene_pipelines(d, &layouts.scene, gl);
        let ComputePipelines { histogram, select, rest_layout, select_rest, slab_gate } =
            compute_pipelines(d, &layouts);
        let BoxPipelines { box_layout, box_test, box_early, slab_test, box_indices } =
            box_pipelines(d, &layouts.scene, gl);
        let Layouts { scene: scene_layout, hist: hist_layout, select: select_layout } = layouts;
        Self {
            box_indices,
            scene_layout,
            hist_layout,
            select_layout,
            draw,
            draw_grid,
            draw_field,
            draw_field_fine,
            draw_closed,
            draw_cells,
            draw_cells_closed,
            draw_blend,
            prepass,
            histogram,
            select,
            rest_layout,
            select_rest,
            slab_gate,
            box_early,
            box_layout,
            box_test,
            slab_test,
        }
    }
}

/// The bind-group layouts of the scene passes, the histogram and the selection.
fn layouts(d: &wgpu::Device) -> Layouts {
    let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
    let scene_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &[
            uniform_entry(0, vf),
            uint_texture_entry(1, vf),
            uint_texture_entry(2, vf),
            float_texture_entry(3, wgpu::ShaderStages::FRAGMENT),
            uint_texture_entry(4, vf),
            uint_texture_entry(6, vf),
        ],
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
    Layouts { scene: scene_layout, hist: hist_layout, select: select_layout }
}

/// The lit passes (per kind of tile, opaque and blended) and the prepass, over `scene_layout`.
fn scene_pipelines(d: &wgpu::Device, scene_layout: &wgpu::BindGroupLayout, gl: bool) -> ScenePipelines {
    let scene_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("scene"),
        bind_group_layouts: &[Some(scene_layout)],
        immediate_size: 0,
    });
    let vertex_layout = wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }],
    };
    let depth_state = wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        // Reverse-Z: larger is nearer.
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    };
    // The lit pass's second vertex stream: per vertex an f32 scalar (colour by data) and a
    // packed smooth normal (`lod::normals`).
    // Per vertex: its scalar, packed normal and ring height (`gpu::geometry::vertex_words`).
    let value_layout = wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32, offset: 0, shader_location: 1 },
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Uint32, offset: 4, shader_location: 2 },
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32, offset: 8, shader_location: 3 },
        ],
    };
    // The prepass reads the ring height only.
    let ring_layout = wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32, offset: 8, shader_location: 3 }],
    };
    let scene_pipeline = |label: &str,
                          file: &str,
                          vs: (&str, &str),
                          fs: &str,
                          buffers: &[Option<wgpu::VertexBufferLayout>],
                          targets: &[Option<wgpu::ColorTargetState>],
                          depth: &wgpu::DepthStencilState,
                          cull_mode: Option<wgpu::Face>| {
        let module = shader(d, label, format!("{GLOBALS_WGSL}\n{COMMON_WGSL}\n{PRIORITY_WGSL}\n{file}"));
        // (entry point, its GL variant)
        let (vs, fs) = if gl { (vs.1, format!("{fs}_gl")) } else { (vs.0, fs.to_string()) };
        d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&scene_pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(vs),
                compilation_options: Default::default(),
                buffers,
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode,
                ..Default::default()
            },
            depth_stencil: Some(depth.clone()),
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
    let lit_vs = |vs: (&str, &str), fs: &str, cull: Option<wgpu::Face>| {
        scene_pipeline(
            "draw.wgsl",
            include_str!("../shaders/draw.wgsl"),
            vs,
            fs,
            &[Some(vertex_layout.clone()), Some(value_layout.clone())],
            &[
                Some(wgpu::ColorTargetState { format: COLOR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL }),
                Some(ID_FORMAT.into()),
            ],
            &depth_state,
            cull,
        )
    };
    let lit = |fs: &str, cull: Option<wgpu::Face>| lit_vs(("vs_draw", "vs_draw_gl"), fs, cull);
    // Opaque tiles that are no height field with a normal map (the field branch of fs_main
    // only serves blended ones).
    let (draw, draw_grid) = (lit("fs_mesh", None), lit("fs_grid", None));
    let draw_field = lit_vs(("vs_field", "vs_field_gl"), "fs_field", None);
    // Their tiles drawn at a coarser level: the fine surface's depth (draw.wgsl `fine_depth`), the
    // object carried flat (`vs_field_fine`).
    let draw_field_fine = lit_vs(("vs_field_fine", "vs_field_gl"), "fs_field_fine", None);
    let draw_closed = lit("fs_mesh", Some(wgpu::Face::Back));
    let (draw_cells, draw_cells_closed) = (lit("fs_cells", None), lit("fs_cells", Some(wgpu::Face::Back)));
    // Translucent objects: the lit pass's shaders, alpha-blended over the image, depth tested
    // but not written, the tile ids left as the opaque pass wrote them.
    let draw_blend = scene_pipeline(
        "draw.wgsl (blended)",
        include_str!("../shaders/draw.wgsl"),
        ("vs_draw", "vs_draw_gl"),
        "fs_main",
        &[Some(vertex_layout.clone()), Some(value_layout.clone())],
        &[
            Some(wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            }),
            Some(wgpu::ColorTargetState { format: ID_FORMAT, blend: None, write_mask: wgpu::ColorWrites::empty() }),
        ],
        &wgpu::DepthStencilState { depth_write_enabled: Some(false), ..depth_state.clone() },
        None,
    );
    let prepass = scene_pipeline(
        "prepass.wgsl",
        include_str!("../shaders/prepass.wgsl"),
        ("vs_main", "vs_gl"),
        "fs_id",
        &[Some(vertex_layout.clone()), Some(ring_layout)],
        &[Some(ID_FORMAT.into())],
        &depth_state,
        None,
    );
    ScenePipelines {
        draw,
        draw_grid,
        draw_field,
        draw_field_fine,
        draw_closed,
        draw_cells,
        draw_cells_closed,
        draw_blend,
        prepass,
    }
}

/// The histogram, select, select_rest and slab_gate compute pipelines.
fn compute_pipelines(d: &wgpu::Device, layouts: &Layouts) -> ComputePipelines {
    let cs = wgpu::ShaderStages::COMPUTE;
    let hist_shader = shader(d, "histogram.wgsl", include_str!("../shaders/histogram.wgsl").into());
    let select_shader = shader(d, "select.wgsl", format!("{SELECT_WGSL}\n{}", include_str!("../shaders/select.wgsl")));
    let histogram = compute(d, "histogram", &layouts.hist, &hist_shader, "histogram");
    let select = compute(d, "select", &layouts.select, &select_shader, "select_draws");
    let rest_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("select_rest"),
        entries: &[
            uniform_entry(0, cs),
            storage_entry(1, true, cs),
            storage_entry(2, true, cs),
            storage_entry(3, true, cs),
            storage_entry(4, false, cs),
        ],
    });
    let rest_shader =
        shader(d, "select_rest.wgsl", format!("{SELECT_WGSL}\n{}", include_str!("../shaders/select_rest.wgsl")));
    let select_rest = compute(d, "select_rest", &rest_layout, &rest_shader, "select_rest");
    let gate_shader =
        shader(d, "slab_gate.wgsl", format!("{SELECT_WGSL}\n{}", include_str!("../shaders/slab_gate.wgsl")));
    let slab_gate = compute(d, "slab_gate", &rest_layout, &gate_shader, "slab_gate");
    ComputePipelines { histogram, select, rest_layout, select_rest, slab_gate }
}

/// The box test's layout and pipelines (over the scene's layout and its own), the slab test and
/// the box's 36 corner indices.
fn box_pipelines(d: &wgpu::Device, scene_layout: &wgpu::BindGroupLayout, gl: bool) -> BoxPipelines {
    let fs = wgpu::ShaderStages::FRAGMENT;
    let box_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("box_test"),
        entries: &[
            float_texture_entry(0, fs),
            storage_entry(1, false, fs),
            storage_entry(2, true, wgpu::ShaderStages::VERTEX),
            storage_entry(3, true, wgpu::ShaderStages::VERTEX),
        ],
    });
    let box_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("box_test"),
        bind_group_layouts: &[Some(scene_layout), Some(&box_layout)],
        immediate_size: 0,
    });
    let box_shader = shader(d, "box_test.wgsl", with_box_wgsl(BOX_TEST_WGSL));
    let box_test = box_pipeline(d, &box_pl, &box_shader, if gl { "fs_box_gl" } else { "fs_box" }, None);
    let box_early = crate::gpu::box_early::early_box_pipeline(d, &box_pl);
    let slab_test = crate::gpu::slab_test::SlabTest::new(d, scene_layout, gl, box_early.is_some());
    let cube: [u32; 36] =
        [0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6];
    let box_indices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("box_indices"),
        contents: bytemuck::cast_slice(&cube),
        usage: wgpu::BufferUsages::INDEX,
    });
    BoxPipelines { box_layout, box_test, box_early, slab_test, box_indices }
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
