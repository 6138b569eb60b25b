//! The box test of [`Passes::record_box_test`](super::Passes::record_box_test) on the hardware's
//! early depth test (box_test_early.wgsl's `fs_box_early`): the same counts, with hidden fragments
//! rejected by the rasteriser instead of each running a texture load and a comparison. Built only
//! where the device has `SHADER_EARLY_DEPTH_TEST` and is not GL (whose fixed depth-range mapping
//! loses reverse-Z precision, so its scene passes write `frag_depth` and its box test compares by
//! hand). Same layout, vertex stage and bind group as the regular box test.

use super::passes::{box_pipeline, with_box_wgsl, BOX_TEST_WGSL};
use super::targets::{Targets, DEPTH_FORMAT};

pub struct EarlyBoxTest {
    pipeline: wgpu::RenderPipeline,
}

impl EarlyBoxTest {
    /// The pipeline (`layout`: the regular box test's), or None where the device cannot run it
    /// exactly.
    pub fn new(d: &wgpu::Device, layout: &wgpu::PipelineLayout) -> Option<Self> {
        if !d.features().contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST)
            || d.adapter_info().backend == wgpu::Backend::Gl
        {
            return None;
        }
        let source = format!("{}\n{}", with_box_wgsl(BOX_TEST_WGSL), include_str!("shaders/box_test_early.wgsl"));
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("box_test_early.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        // The image's depth, read only: at or in front of it (reverse-Z) passes, the comparison
        // box_test.wgsl makes by hand.
        let depth = wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        };
        Some(Self { pipeline: box_pipeline(d, layout, &module, "fs_box_early", Some(depth)) })
    }

    /// Records the test of `n` boxes against `targets`' depth, bound read-only as the depth
    /// attachment (and, unused here, as the bind group's texture: both are reads).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene_bg: &wgpu::BindGroup,
        box_bg: &wgpu::BindGroup,
        targets: &Targets,
        boxes: &wgpu::Buffer,
        n: usize,
        ts: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let keep = wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("box_test_early"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.id,
                depth_slice: None,
                resolve_target: None,
                ops: keep,
            })],
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
            pass.set_bind_group(1, box_bg, &[]);
            pass.set_vertex_buffer(0, boxes.slice(..));
            pass.draw(0..36, 0..n as u32);
        }
    }
}
