//! The box test of [`Passes::record_box_test`](super::Passes::record_box_test) on the hardware's
//! early depth test (box_test_early.wgsl's `fs_box_early`): the same counts, with hidden fragments
//! rejected by the rasteriser instead of each running a texture load and a comparison. Built only
//! where the device has `SHADER_EARLY_DEPTH_TEST` and is not GL (whose fixed depth-range mapping
//! loses reverse-Z precision, so its scene passes write `frag_depth` and its box test compares by
//! hand). Same layout, vertex stage and bind group as the regular box test; `record_box_test`
//! binds the image's depth read-only as the depth attachment when it uses this pipeline.

use super::shader::{box_pipeline, early_test_depth, shader, with_box_wgsl, BOX_TEST_WGSL};

/// The early-depth box-test pipeline (`layout`: the regular box test's), or None where the device
/// cannot run it exactly.
pub fn early_box_pipeline(d: &wgpu::Device, layout: &wgpu::PipelineLayout) -> Option<wgpu::RenderPipeline> {
    if !d.features().contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST) || d.adapter_info().backend == wgpu::Backend::Gl
    {
        return None;
    }
    let source = format!("{}\n{}", with_box_wgsl(BOX_TEST_WGSL), include_str!("shaders/box_test_early.wgsl"));
    let module = shader(d, "box_test_early.wgsl", source);
    Some(box_pipeline(d, layout, &module, "fs_box_early", Some(early_test_depth())))
}
