//! `culling="three_pass"` (Plate et al., seeds 000/001), all on the GPU in the frame's one
//! submission, with no read-back between passes:
//!
//! 1. depth + tile-id prepass of every visible tile's coarse proxy, front to back (so hidden
//!    fragments fail the depth test early), at `prepass_scale` × the image size;
//! 2. histogram of the id image: the exact number of pixels where each tile's proxy is the
//!    front-most surface (no occlusion queries: those are boolean on several backends);
//! 3. selection: each tile keeps its fine draw when its count is above `pixel_threshold`
//!    (compared in prepass pixels, threshold × scale²); the final pass draws the result with
//!    one `multi_draw_indexed_indirect`.
//!
//! Exact (the image equals `none`) when the proxies are the fine tiles (`coarse_factor` 1), the
//! threshold is 0 and the prepass has the image's size; otherwise approximate, as in the paper:
//! a proxy that bulges above its fine tile can hide a tile that is visible.

use super::{CullStrategy, Draw, FrameInputs, Pixels, Stat, Visible};
use crate::error::Result;
use crate::gpu::{passes, Targets};

#[derive(Default)]
pub struct ThreePass {
    /// Id + depth targets of the prepass, re-created when its size changes.
    targets: Option<Targets>,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(ThreePass::default())
}

impl CullStrategy for ThreePass {
    fn name(&self) -> &'static str {
        "three_pass"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let d = &f.ctx.device;
        let n = f.n_tiles();
        let scale = f.options.prepass_scale;
        let pw = ((f.width as f64 * scale).round() as u32).max(1);
        let ph = ((f.height as f64 * scale).round() as u32).max(1);
        let pt = Targets::ensure(&mut self.targets, d, pw, ph);

        // Pass 1: coarse proxies, front to back.
        let mut coarse = f.pick(&f.geometry.coarse, |_| true);
        let dist = f.geometry.eye_distances(f.scene, f.fc.eye, f.camera.z_scale);
        coarse.sort_by(|a, b| dist[a.first_instance as usize].total_cmp(&dist[b.first_instance as usize]));
        let prepass_tris: u64 = coarse.iter().map(|a| a.triangles()).sum();
        let coarse_buf = passes::args_buffer(d, "coarse_args", &coarse);
        f.passes.record_prepass(enc, pt, f.scene_bg, f.geometry, &coarse_buf, f.timestamps);

        // Pass 2: exact visible pixels per tile.
        let counts = passes::counts_buffer(d, n);
        enc.clear_buffer(&counts, 0, None);
        let ts = |name| f.timestamps.and_then(|t| t.compute(name));
        f.passes.record_histogram(d, enc, &pt.id, (pw, ph), &counts, ts("count_ms"));

        // Pass 3a: the final draws, selected on the GPU.
        let fine = passes::args_buffer(d, "fine_args", &f.pick(&f.geometry.fine, |_| true));
        let out = passes::empty_args_buffer(d, "draw_args", n);
        let threshold = (f.options.pixel_threshold * scale * scale) as f32;
        f.passes.record_select(d, enc, &counts, &fine, &out, n, threshold, ts("count_ms"));

        let mut v = Visible::new(Draw::Gpu(out), Pixels::Gpu { counts, scale: 1.0 / (scale * scale) });
        v.stats.push(("triangles_prepass", Stat::Count(prepass_tris)));
        Ok(v)
    }
}
