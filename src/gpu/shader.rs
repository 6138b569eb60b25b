//! What the GPU passes' pipelines are made of: the WGSL sources they share (the scene's
//! uniforms, the box geometry, the depth-tie priorities, the box test), shader modules, bind-group
//! layout entries, and the box-test pipeline every box or slab pass builds on. No pass lives here;
//! `passes`, `slab_test`, `box_early`, `occluder_depth` and `depth_read` build theirs from it.

use super::targets::{DEPTH_FORMAT, ID_FORMAT};

/// The scene passes' uniforms (`Globals`, `g`): prepended to common.wgsl and to the box passes.
pub(super) const GLOBALS_WGSL: &str = include_str!("shaders/globals.wgsl");
/// What the scene passes share, after their uniforms.
pub(super) const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");
pub(super) const BOX_WGSL: &str = include_str!("shaders/box.wgsl");
pub(super) const SELECT_WGSL: &str = include_str!("shaders/select_common.wgsl");
/// Depth-tie priorities: appended to the scene passes' and the box tests' sources.
pub(super) const PRIORITY_WGSL: &str = include_str!("shaders/priority.wgsl");

/// `source` with the scene's uniforms (globals.wgsl: `Globals`, `g`), the shared box geometry
/// (box.wgsl: `CUBE`, `box_corner`) and the depth-tie priorities prepended.
pub fn with_box_wgsl(source: &str) -> String {
    format!("{GLOBALS_WGSL}\n{BOX_WGSL}\n{PRIORITY_WGSL}\n{source}")
}

/// The box test's shader (box.wgsl is prepended): vertex stage and the hand-compared fragment.
pub const BOX_TEST_WGSL: &str = include_str!("shaders/box_test.wgsl");

/// A box-test pipeline of `layout` (scene bind group, then the box test's: depth texture, counts,
/// skip): front faces of the box instances, fragment entry `fs` of `module` writing nothing to the
/// id target it needs as an attachment; `depth`: the depth attachment's state, if any.
pub fn box_pipeline(
    d: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    depth: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    test_pipeline(d, layout, module, ("vs_box", box_vertex_layout()), fs, depth)
}

/// The depth attachment of a test on the hardware's early depth test: the image's depth, read
/// only, at or in front of it (reverse-Z) passing, the comparison box_test.wgsl makes by hand.
pub fn early_test_depth() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// A pipeline that counts occludee fragments (boxes, slabs): vertex entry `vs` of `module` over
/// `buffer`, front faces only (a convex box, or a slab's outward-wound prisms: a ray enters each
/// through one of them, one fragment per pixel), fragment entry `fs` writing nothing to the id
/// target it needs as an attachment; `depth`: the depth attachment's state, if any.
pub fn test_pipeline(
    d: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vs, buffer): (&str, wgpu::VertexBufferLayout<'_>),
    fs: &str,
    depth: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[Some(buffer)],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: Some(wgpu::Face::Back),
            front_face: wgpu::FrontFace::Ccw,
            ..Default::default()
        },
        depth_stencil: depth,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: ID_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Vertex layout of [`BoxInstance`](super::layout::BoxInstance) instances (two vec4s).
pub fn box_vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRS: [wgpu::VertexAttribute; 2] = [
        wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 0, shader_location: 0 },
        wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 16, shader_location: 1 },
    ];
    wgpu::VertexBufferLayout { array_stride: 32, step_mode: wgpu::VertexStepMode::Instance, attributes: &ATTRS }
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

/// A 2D float texture bound unfilterable, read with `textureLoad`: a depth image (naga's GLSL
/// cannot load a `texture_depth_2d`), as the box and slab tests and the depth read-back read
/// it, or a table (the lit pass's colour maps, `layout::ColorTables`).
pub fn float_texture_entry(binding: u32, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A 2D unsigned-integer texture, read with `textureLoad` (the lit pass's objects,
/// `layout::object_texels`).
pub fn uint_texture_entry(binding: u32, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        ..float_texture_entry(binding, vis)
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

pub fn shader(d: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
