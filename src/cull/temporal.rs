//! `culling="temporal"`: frame-to-frame coherence with the conservative guarantee.
//!
//! The tiles that were visible in the last frame rendered of the same scene geometry (those with
//! at least one pixel in its final image) are drawn first, at once, into the final targets: no
//! prepass, no count. Then every other visible tile's box is tested against that image's depth
//! at full resolution and the tiles that show are drawn too ([`super::phases`], as conservative
//! `three_pass`). Whatever the last frame was (another view, another z_scale, objects hidden or
//! moved since), the first set is only a guess: the box test finds every tile it missed, so the
//! image equals `none` with `pixel_threshold` 0 (a threshold t drops only tiles outside the first
//! set with at most t visible pixels; tiles of the first set are always drawn). The tiles that a
//! height field provably hides are left out of both phases first (`hidden`, on the CPU).
//!
//! Cost: the last frame's visible set (some of which may be hidden now) plus the box pass. With a
//! coherent camera (an orbit, a Jupyter viewer, repeated renders of one view) the first set is
//! nearly the visible set and the frame costs about as much as the oracle; after a jump it costs
//! as much as `none` plus the box pass at worst, and on a scene's first frame it
//! costs about as much as conservative `three_pass`: without a history (a scene's first frame, new
//! geometry) the first set is three_pass's (the coarse proxies' prepass, counted and selected on
//! the GPU, [`super::phases::prepass_first_set`]). The history is one bit per tile, kept per
//! renderer and reset when the scene's geometry changes (`Scene::geometry_key`). Stats:
//! `tiles_reused` (the first set when it came from the history), `tiles_box_tested`,
//! `triangles_prepass` (frames without history); per-tile counts `box_pixels`.

use super::phases::{draw_and_test_the_rest, prepass_first_set, Proxies};
use super::{CullStrategy, FrameInputs, FrameReport, Pixels, Stat, Visible};
use crate::error::Result;
use crate::gpu::passes;

#[derive(Default)]
pub struct Temporal {
    /// The geometry key and, per tile, whether it had pixels in the last frame rendered with it.
    last: Option<((u64, u64), Vec<bool>)>,
    /// The geometry key of the frame being rendered (for `report`).
    current: Option<(u64, u64)>,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Temporal::default())
}

impl CullStrategy for Temporal {
    fn name(&self) -> &'static str {
        "temporal"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let n = f.n_tiles();
        let key = f.geometry.key;
        let seen = match &self.last {
            Some((k, m)) if *k == key && m.len() == n => Some(m.as_slice()),
            _ => None,
        };
        // The tiles proven hidden by height fields (`hidden`) are left out of every pass; those
        // seen in the last frame are drawn first whatever the proof says, so it skips them.
        let (mask, proven_hidden) = super::hidden::visible_without_hidden(f, &|i| seen.is_none_or(|s| !s[i]));
        let f = &FrameInputs { object_visible: &mask, ..*f };
        let d = &f.ctx.device;
        let threshold = f.options.pixel_threshold as f32;
        let mut stats = Vec::new();
        let (first, fine) = match seen {
            Some(seen) => {
                let first_args = f.pick(f.draw_args, |i| seen[i]);
                let n_reused = first_args.iter().filter(|a| a.instance_count > 0).count();
                stats.push(("tiles_reused", Stat::Count(n_reused as u64)));
                let fine = passes::args_buffer(d, "fine_args", &f.pick(f.draw_args, |_| true));
                (passes::args_buffer(d, "first_args", &first_args), fine)
            }
            // No history (a scene's first frame, new geometry): three_pass's prepass chooses.
            None => {
                let set = prepass_first_set(f, enc, Proxies::Cheapest);
                stats.push(("tiles_reused", Stat::Count(0)));
                stats.push(("triangles_prepass", Stat::Count(set.prepass_tris)));
                (set.first, set.fine)
            }
        };
        let rest = draw_and_test_the_rest(f, enc, &first, &fine, threshold, true, seen);
        self.current = Some(key);
        let mut v = Visible::new(rest.draw, Pixels::FinalImage);
        v.predrawn = Some(first);
        v.tile_counts.push(("box_pixels", rest.box_counts));
        v.stats.extend(stats);
        v.stats.push(("tiles_box_tested", Stat::Count(rest.tested as u64)));
        v.stats.push(("tiles_slab_tested", Stat::Count(rest.slab_tiles as u64)));
        v.stats.push(("triangles_slab_test", Stat::Count(rest.slab_triangles)));
        v.stats.push(("tiles_proven_hidden", Stat::Count(proven_hidden)));
        Ok(v)
    }

    fn report(&mut self, r: &FrameReport<'_>) -> Vec<(&'static str, Stat)> {
        if let Some(key) = self.current.take() {
            self.last = Some((key, r.tile_pixels.iter().map(|&p| p > 0).collect()));
        }
        Vec::new()
    }
}
