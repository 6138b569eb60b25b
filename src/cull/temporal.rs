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
//! renderer and reset when the scene's geometry changes (`Scene::geometry_key`).
//!
//! A repeated frame (with `pixel_threshold` 0, everything that decides a pixel's winner equal to
//! the last frame's: geometry, image size, camera, exaggeration, origin, each object's placement
//! and priority, each tile's draw and visibility, which objects are seen from outside; compared
//! exactly, [`fingerprint`]) draws the last frame's visible tiles and nothing else, untested: the
//! last image was `none`'s, every pixel of it won by one of those tiles, and drawing a subset
//! that holds every winner, in the same order, leaves every winner and so every pixel as it was
//! (the oracle's argument). A re-render of one view (a new colour map, a notebook
//! cell run again) then costs what the oracle costs. Stats: `tiles_reused` (the first set when it
//! came from the history), `frame_repeated` (1 for such a frame), `tiles_box_tested`,
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
    /// The last frame's [`fingerprint`] when it was exact (pixel_threshold 0), and the frame's.
    last_print: Option<Vec<u64>>,
    print: Option<Vec<u64>>,
}

/// Everything that decides which tile wins each pixel of an exact frame, as words compared
/// exactly between frames (see the module docs): the geometry key, image size, threshold, the
/// frame camera's matrix and near/far, the exaggeration and origin, per object its placement and
/// priority, per tile its draw (level, range) and visibility, per object whether it is seen from
/// outside (back faces culled).
fn fingerprint(f: &FrameInputs<'_>) -> Vec<u64> {
    let mut w = vec![f.geometry.key.0, f.geometry.key.1, f.width as u64, f.height as u64];
    w.push(f.options.pixel_threshold.to_bits());
    w.extend(f.fc.view_proj.to_cols_array().map(f64::to_bits));
    w.extend([f.fc.near, f.fc.far, f.camera.z_scale, f.origin.x, f.origin.y, f.origin.z].map(f64::to_bits));
    for o in f.scene.objects() {
        let p = o.placement(f.origin);
        w.extend([p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), o.priority() as u64]);
    }
    for (a, &v) in f.draw_args.iter().zip(f.object_visible) {
        w.push(a.index_count as u64 | (a.instance_count as u64) << 32);
        w.push(a.first_index as u64 | (a.base_vertex as u32 as u64) << 32);
        w.push(a.first_instance as u64 | (v as u64) << 32);
    }
    w.extend(f.outside.iter().map(|&o| o as u64));
    w
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
        // A repeated exact frame: the last frame's visible tiles, untested (module docs).
        let print = (f.options.pixel_threshold == 0.0).then(|| fingerprint(f));
        let repeated = print.is_some() && print == self.last_print;
        self.print = print;
        if let (true, Some(seen)) = (repeated, seen) {
            self.current = Some(key);
            let mut v = Visible::new(super::Draw::Mask(seen.to_vec()), Pixels::FinalImage);
            let reused = seen.iter().filter(|&&s| s).count() as u64;
            v.stats.extend([("tiles_reused", Stat::Count(reused)), ("frame_repeated", Stat::Count(1))]);
            for name in super::phases::Rest::STATS.into_iter().chain(["tiles_proven_hidden"]) {
                v.stats.push((name, Stat::Count(0)));
            }
            return Ok(v);
        }
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
        let rest_stats = rest.stats();
        let mut v = Visible::new(rest.draw, Pixels::FinalImage);
        v.predrawn = Some(first);
        v.tile_counts.push(("box_pixels", rest.box_counts));
        v.stats.extend(stats);
        v.stats.push(("frame_repeated", Stat::Count(0)));
        v.stats.extend(rest_stats);
        v.stats.push(("tiles_proven_hidden", Stat::Count(proven_hidden)));
        Ok(v)
    }

    fn report(&mut self, r: &FrameReport<'_>) -> Vec<(&'static str, Stat)> {
        if let Some(key) = self.current.take() {
            self.last = Some((key, r.tile_pixels.iter().map(|&p| p > 0).collect()));
            self.last_print = self.print.take();
        }
        Vec::new()
    }
}
