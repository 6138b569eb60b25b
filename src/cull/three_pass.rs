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
//! With `conservative: false` that is all (the paper's method): exact (the image equals `none`)
//! when the proxies are the fine tiles (`coarse_factor` 1), the threshold is 0 and the prepass has
//! the image's size; otherwise approximate: a proxy that bulges above its fine tile can hide a tile
//! that is visible, and a prepass at a lower resolution can miss tiles a few pixels wide.
//!
//! # Conservative mode (`conservative: true`, the default)
//!
//! First the tiles that a height field provably hides are left out of every pass (`hidden`, on
//! the CPU). Then steps 1–3 choose a first set A, whose fine tiles are drawn at once into the
//! final targets.
//! Then every other visible tile's bounding box is tested against the depth of that image, at
//! full resolution: a render pass rasterises the front faces of each box and counts,
//! per tile, the pixels where the box is at or in front of the stored depth (the comparison is
//! done in the fragment shader against the depth texture, so hidden fragments are never counted;
//! where the device has an exact early depth test, by the rasteriser against the depth bound
//! read-only, the same comparison at half the cost: `gpu::box_early`).
//! Tiles whose count exceeds the threshold are drawn too (into the same image, depth-tested), in a
//! second indirect draw built on the GPU. Why nothing visible is lost:
//!
//! * the depth D(p) after drawing A is that of a subset of the scene's fine triangles, so at every
//!   pixel it is at or behind the nearest fine surface F(p) of the whole scene;
//! * a tile T that has a visible fine fragment at p lies at F(p) there, inside T's box, so the
//!   box's entry point on p's ray is at or in front of F(p), hence of D(p): T's count is at least
//!   its number of visible pixels. It is culled only if that count is ≤ the threshold.
//!
//! So with threshold 0 the image equals `none` for any camera (above, below, between or inside
//! stacked horizons, perspective or orthographic, any z_scale), with holes, faults and UTM
//! coordinates, and whatever the coarse proxies and the prepass scale are: they only decide how
//! much is drawn in the first phase. With a threshold t > 0 the only tiles lost are those with at
//! most t visible pixels (the counts are upper bounds). Where the argument is given up:
//!
//! * a box that reaches the near plane (or contains the eye) is clipped, so its front faces may
//!   not cover the pixels of its tile: such tiles are drawn untested (counted as visible);
//! * f32 round-off of the GPU's transform: boxes are grown by 1e-6 of the coordinates' magnitude
//!   plus 1e-4 of their diagonal, far above that round-off, and ties count as visible.
//!
//! # Error predictor (`conservative: false, predict_errors: true`)
//!
//! The same box test, run after the approximate frame without drawing anything more, finds the
//! tiles that are culled but whose box shows in front of the image: the tiles at risk. Every tile
//! that the approximate mode really misses is among them (the argument above), and the sum of
//! their box counts bounds the missing pixels from above. Stats `tiles_at_risk`,
//! `predicted_max_missing_pixels`; per-tile counts `box_pixels`. Every frame also reports each
//! tile's proxy error (`TileMesh::proxy_error`, metres, from the build) projected to pixels at the
//! tile's nearest point (array `proxy_error_px`): how far the proxy the prepass drew may be off.

use super::phases::{draw_and_test_the_rest, prepass_first_set, FirstSet, Proxies};
use super::{CullStrategy, Draw, FrameInputs, FrameReport, Pixels, Stat, Visible};
use crate::error::Result;

#[derive(Default)]
pub struct ThreePass {
    /// This frame ran the box test (conservative or predictor).
    tested: bool,
    /// This frame only predicts (approximate mode).
    predicting: bool,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(ThreePass::default())
}

/// Each tile's proxy error (`TileMesh::proxy_error`, exaggerated by z_scale where that enlarges
/// it) projected to pixels at the tile's nearest point (`dist2`: squared eye distance to its box);
/// +inf for a box that contains the eye.
fn proxy_error_px(f: &FrameInputs<'_>, dist2: &[f64]) -> Vec<f32> {
    let proj = f.fc.view_proj * f.fc.view.inverse();
    let px_per_unit = proj.y_axis.y.abs() * f.height as f64 / 2.0; // at unit distance (perspective)
    let perspective = f.fc.projection == crate::camera::Projection::Perspective;
    let zs = f.camera.z_scale.max(1.0);
    let objects = f.scene.objects();
    let mut err = Vec::with_capacity(f.n_tiles());
    for o in objects {
        err.extend(o.tiles.iter().map(|t| t.proxy_error as f64 * zs));
    }
    err.iter()
        .zip(dist2)
        .map(|(&e, &d2)| {
            let d = if perspective { d2.sqrt().max(f.fc.near) } else { 1.0 };
            if e == 0.0 {
                0.0
            } else if perspective && d2 == 0.0 {
                f32::INFINITY
            } else {
                (e * px_per_unit / d) as f32
            }
        })
        .collect()
}

impl CullStrategy for ThreePass {
    fn name(&self) -> &'static str {
        "three_pass"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        // Conservative frames first leave out the tiles proven hidden by height fields (`hidden`),
        // and find what the first set misses: their prepass may use the cheapest proxy of each
        // tile. The paper's method (and its predictor) culls by the built proxies only.
        let (mask, proven_hidden) = if f.options.conservative {
            let (m, k) = super::hidden::visible_without_hidden(f, &|_| true);
            (Some(m), k)
        } else {
            (None, 0)
        };
        let narrowed;
        let f = match &mask {
            Some(m) => {
                narrowed = FrameInputs { object_visible: m, ..*f };
                &narrowed
            }
            None => f,
        };
        let proxies = if f.options.conservative { Proxies::Cheapest } else { Proxies::Built };
        let FirstSet { first, fine, counts, ratio, prepass_tris } = prepass_first_set(f, enc, proxies);
        let threshold = f.options.pixel_threshold;
        let dist = f.tile_dist2;
        let pixels = Pixels::Gpu { counts, scale: ratio };
        self.predicting = !f.options.conservative && f.options.predict_errors;
        self.tested = f.options.conservative || self.predicting;
        let error_px = ("proxy_error_px", proxy_error_px(f, dist));
        if !self.tested {
            let mut v = Visible::new(Draw::Gpu(first), pixels);
            v.stats.push(("triangles_prepass", Stat::Count(prepass_tris)));
            v.arrays.push(error_px);
            return Ok(v);
        }

        // Conservative second phase (or the predictor): draw the first set now, test every other
        // tile's box against its depth at full resolution, draw (or report) those that show.
        let rest = draw_and_test_the_rest(f, enc, &first, &fine, threshold as f32, !self.predicting, None);
        let rest_stats = rest.stats();
        let (draw, box_counts) = (rest.draw, rest.box_counts);
        let mut v = Visible::new(draw, pixels);
        v.arrays.push(error_px);
        v.predrawn = Some(first);
        v.tile_counts.push(("box_pixels", box_counts));
        v.stats.push(("triangles_prepass", Stat::Count(prepass_tris)));
        v.stats.extend(rest_stats);
        if !self.predicting {
            v.stats.push(("tiles_proven_hidden", Stat::Count(proven_hidden)));
        }
        Ok(v)
    }

    fn report(&mut self, r: &FrameReport<'_>) -> Vec<(&'static str, Stat)> {
        if !self.predicting {
            return Vec::new();
        }
        let Some(box_px) = r.counts("box_pixels") else { return Vec::new() };
        let image = r.width as u64 * r.height as u64;
        let (mut at_risk, mut pixels) = (0u64, 0u64);
        for (&drawn, &c) in r.tile_drawn.iter().zip(box_px) {
            if !drawn && c > 0 {
                at_risk += 1;
                pixels += (c as u64).min(image);
            }
        }
        vec![("tiles_at_risk", Stat::Count(at_risk)), ("predicted_max_missing_pixels", Stat::Count(pixels.min(image)))]
    }
}
