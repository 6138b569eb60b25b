//! The box test of [`Passes::record_box_test`](super::Passes::record_box_test) on the hardware's
//! early depth test (box_test_early.wgsl): the same counts, with hidden fragments rejected by the
//! rasteriser instead of each running a texture load and a comparison. Built only where the device
//! has `SHADER_EARLY_DEPTH_TEST` and is not GL (whose fixed depth-range mapping loses reverse-Z
//! precision, so its scene passes write `frag_depth` and its box test compares by hand).

use super::layout::BoxInstance;
use super::passes::{box_vertex_layout, storage_entry, with_box_wgsl};
use super::targets::{Targets, DEPTH_FORMAT, ID_FORMAT};

pub struct EarlyBoxTest {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

const _: () = assert!(std::mem::size_of::<BoxInstance>() == 32);

impl EarlyBoxTest {
    /// The pipeline, or None where the device cannot run it exactly.
    pub fn new(d: &wgpu::Device, scene_layout: &wgpu::BindGroupLayout) -> Option<Self> {
        if !d.features().contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST)
            || d.adapter_info().backend == wgpu::Backend::Gl
        {
            return None;
        }
        let fs = wgpu::ShaderStages::FRAGMENT;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("box_test_early"),
            entries: &[storage_entry(0, false, fs), storage_entry(1, true, wgpu::ShaderStages::VERTEX)],
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("box_test_early"),
            bind_group_layouts: &[Some(scene_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("box_test_early.wgsl"),
            source: wgpu::ShaderSource::Wgsl(with_box_wgsl(include_str!("shaders/box_test_early.wgsl")).into()),
        });
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("box_test_early"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_box"),
                compilation_options: Default::default(),
                buffers: &[Some(box_vertex_layout())],
            },
            // Front faces only: one fragment per pixel of a convex box.
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: Some(wgpu::Face::Back),
                front_face: wgpu::FrontFace::Ccw,
                ..Default::default()
            },
            // The image's depth, read only: at or in front of it (reverse-Z) passes, as the
            // comparison box_test.wgsl makes by hand.
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_box"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: ID_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::empty(),
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        Some(Self { layout, pipeline })
    }

    /// Records the test of `n` boxes against `targets`' depth (see `Passes::record_box_test`).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        scene_bg: &wgpu::BindGroup,
        targets: &Targets,
        boxes: &wgpu::Buffer,
        n: usize,
        skip: &wgpu::Buffer,
        counts: &wgpu::Buffer,
        ts: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("box_test_early"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: counts.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: skip.as_entire_binding() },
            ],
        });
        let keep = wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("box_test_early"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.id,
                depth_slice: None,
                resolve_target: None,
                ops: keep,
            })],
            // Read-only depth: no depth_ops.
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: ts,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if n > 0 {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, scene_bg, &[]);
            pass.set_bind_group(1, &bg, &[]);
            pass.set_vertex_buffer(0, boxes.slice(..));
            pass.draw(0..36, 0..n as u32);
        }
    }
}
