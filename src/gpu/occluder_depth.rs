//! The occluder depth pass (occluder_depth.wgsl): into a depth target, the depth of another image
//! (copied texel for texel by a full-screen triangle, which every backend can run, where a
//! depth-to-depth copy is not) with the front faces of a set of boxes drawn over it wherever they
//! are nearer (reverse-Z, ties keep the box), pushed 16 priority steps (2^-17 of their distance)
//! farther. No colour, no ids. What the boxes mean is the caller's business (`cull::implicit`).

use super::layout::BoxInstance;
use super::passes::boxes_buffer;
use super::shader::{box_vertex_layout, float_texture_entry, shader, with_box_wgsl};
use super::targets::DEPTH_FORMAT;

/// The pipelines and bind-group layout of the pass.
pub struct OccluderDepth {
    layout: wgpu::BindGroupLayout,
    copy: wgpu::RenderPipeline,
    boxes: wgpu::RenderPipeline,
}

fn pipeline(
    d: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vs, fs): (&str, &str),
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    cull: Option<wgpu::Face>,
    compare: wgpu::CompareFunction,
) -> wgpu::RenderPipeline {
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(layout),
        vertex: wgpu::VertexState { module, entry_point: Some(vs), compilation_options: Default::default(), buffers },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: cull,
            front_face: wgpu::FrontFace::Ccw,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl OccluderDepth {
    /// The pass's pipelines; `scene_layout` is `Passes::scene_layout` (the boxes' transform).
    pub fn new(d: &wgpu::Device, scene_layout: &wgpu::BindGroupLayout) -> Self {
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("occluder_depth"),
            entries: &[float_texture_entry(0, wgpu::ShaderStages::FRAGMENT)],
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("occluder_depth"),
            bind_group_layouts: &[Some(scene_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = shader(d, "occluder_depth.wgsl", with_box_wgsl(include_str!("shaders/occluder_depth.wgsl")));
        let always = wgpu::CompareFunction::Always;
        let copy = pipeline(d, &pl, &module, ("vs_full", "fs_copy"), &[], None, always);
        let boxes = pipeline(
            d,
            &pl,
            &module,
            ("vs_box_depth", "fs_box_depth"),
            &[Some(box_vertex_layout())],
            Some(wgpu::Face::Back),
            wgpu::CompareFunction::GreaterEqual,
        );
        Self { layout, copy, boxes }
    }

    /// Records the pass: `target` (a depth view of `source`'s size) gets `source`'s depth, then
    /// the front faces of `boxes` (render space; `id` unused) where they are at or in front of it.
    pub fn record(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        scene_bg: &wgpu::BindGroup,
        source: &wgpu::TextureView,
        target: &wgpu::TextureView,
        boxes: &[BoxInstance],
    ) {
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("occluder_depth"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) }],
        });
        let buf = boxes_buffer(d, boxes);
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("occluder_depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: target,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, scene_bg, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_pipeline(&self.copy);
        pass.draw(0..3, 0..1);
        if !boxes.is_empty() {
            pass.set_pipeline(&self.boxes);
            pass.set_vertex_buffer(0, buf.slice(..));
            pass.draw(0..36, 0..boxes.len() as u32);
        }
    }
}
