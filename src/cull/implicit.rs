//! `culling="implicit"`: conservative three_pass (`three_pass`'s module docs, [`super::phases`])
//! whose box test also sees the isosurfaces' *implicit occluders* (after Pesco et al., "Implicit
//! Occluders"): boxes of volume cells wholly on one side of the isovalue that no ray from outside
//! the volume reaches without crossing the drawn isosurface (`Object::occluders`, computed when the
//! isosurface is added: `crate::iso::enclosed`). The salt's back half, the horizons and the slice
//! behind it are then culled by the salt itself, which three_pass can only do where the salt's
//! front triangles were drawn by the first set and happen to cover the boxes tested.
//!
//! The frame: the tiles proven hidden by height fields are left out (`hidden`), the prepass chooses
//! the first set A, A is drawn into the final targets ([`super::phases::draw_first`]); then a
//! separate depth image is made, A's depth with the front faces of the usable occluder boxes drawn
//! over it where nearer (`gpu::occluder_depth`, the boxes pushed 16 priority steps, 2^-17 of their
//! distance, farther), and every other visible tile's boxes (or slab) are tested against *that*
//! depth ([`super::phases::test_the_rest`]); the tiles that show are drawn into the final targets,
//! whose depth never holds a box: the image is made of scene triangles only.
//!
//! **Why nothing visible is lost** (pixel_threshold 0: the image equals `none`). Let D(p) be the
//! test's depth at pixel p: the larger (nearer) of A's depth and the occluder boxes' there. A's
//! depth is at or behind the nearest fine surface F(p) (three_pass's argument). Where an occluder
//! box of object O is drawn at p, the pixel's ray reaches a point P of the box, and by
//! `iso::enclosed`'s argument it has crossed O's surface at least a quarter cell before P (the
//! boxes are inset by that much from cells the surface does not touch, and the ray's start lies
//! outside the surface's bounding box). O's surface is drawn in full at p by `none` (the conditions below),
//! so F(p) lies at or in front of that crossing, hence in front of the box's depth at p: D(p) is
//! still at or behind F(p), and the box test's argument holds unchanged (a tile with a visible
//! fragment at p has its box entry at or in front of F(p), so it counts p). The quarter cell and
//! the 16 priority steps are the margin for f32 rounding of both depths and for O's own priority
//! (3: drawn one step farther than a horizon).
//!
//! An object's occluders are used in a frame only where that argument's premises hold:
//! * the object is visible and opaque, and every one of its tiles is visible and drawn at level 0
//!   (a coarser level of detail is not the surface the boxes were proven against);
//! * the bounding box of the object's surface (`Occluders::bounds`, `iso::enclosed::mesh_bounds`,
//!   render space, grown against round-off), which holds every enclosed region, lies wholly
//!   beyond the near plane: every pixel's ray then starts outside every region (perspective or
//!   orthographic), and the crossing lies on the ray after its start, so it is not clipped. (The
//!   automatic near plane lies in front of the scene's bounds, so only a camera given a near plane,
//!   or one among or inside the salt, switches them off.)
//!
//! The rest is three_pass's: a box reaching the near plane is drawn untested; threshold t > 0 loses
//! only tiles with at most t visible pixels. `conservative` and `predict_errors` are ignored (this
//! mode is always conservative). Stats: three_pass's, plus `implicit_occluder_boxes` (boxes drawn
//! into the test's depth this frame) and `implicit_objects` (objects whose occluders were used).

use super::phases::{draw_first, prepass_first_set, test_the_rest, FirstSet, Proxies};
use super::{box_corners, CullStrategy, FrameInputs, Pixels, Stat, Visible};
use crate::error::Result;
use crate::gpu::layout::BoxInstance;
use crate::gpu::occluder_depth::OccluderDepth;
use crate::gpu::Targets;
use glam::DVec3;

/// The strategy: the occluder pass's pipelines and the test's depth targets, made on first use.
#[derive(Default)]
pub struct Implicit {
    depth: Option<OccluderDepth>,
    targets: Option<Targets>,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Implicit::default())
}

/// The occluder boxes usable this frame (render space), and how many objects they come from
/// (module docs: the conditions). `visible`: per tile, its object is visible.
pub fn frame_occluders(f: &FrameInputs<'_>, visible: &[bool]) -> (Vec<BoxInstance>, u64) {
    let g = f.geometry;
    let objects = f.scene.objects();
    // Per object: all of its tiles visible and drawn at level 0.
    let mut whole = vec![true; objects.len()];
    for (i, (&v, args)) in visible.iter().zip(f.draw_args).enumerate().take(f.n_tiles()) {
        if !v || *args != g.fine[i] {
            whole[g.tile_object_cpu[i] as usize] = false;
        }
    }
    let zs = DVec3::new(1.0, 1.0, f.camera.z_scale);
    let (mut out, mut used) = (Vec::new(), 0);
    for (oi, o) in objects.iter().enumerate() {
        let Some(occ) = o.occluders.as_deref().filter(|_| o.visible && o.opacity >= 1.0 && whole[oi]) else {
            continue;
        };
        let off = f.placement(oi);
        let to_render = |lo: DVec3, hi: DVec3| {
            let (a, b) = ((lo + off) * zs, (hi + off) * zs);
            (a.min(b), a.max(b))
        };
        let [blo, bhi] = occ.bounds;
        let (lo, hi) = to_render(DVec3::from_array(blo), DVec3::from_array(bhi));
        let grow = 1e-6 * lo.abs().max(hi.abs()).max_element() + 1e-4 * (hi - lo).length() + 1e-9;
        let (lo, hi) = (lo - DVec3::splat(grow), hi + DVec3::splat(grow));
        let nearest =
            box_corners(lo, hi).iter().map(|&p| (p - f.fc.eye).dot(f.fc.forward)).fold(f64::INFINITY, f64::min);
        if nearest <= f.fc.near * 1.001 + 1e-9 {
            continue;
        }
        used += 1;
        for [blo, bhi] in &occ.boxes {
            let (lo, hi) = to_render(glam::Vec3::from_array(*blo).as_dvec3(), glam::Vec3::from_array(*bhi).as_dvec3());
            // Rounded inwards to f32 again: the box only shrinks.
            let lo = lo.to_array().map(crate::lod::f32_at_least);
            let hi = hi.to_array().map(crate::lod::f32_at_most);
            if (0..3).all(|a| lo[a] < hi[a]) {
                out.push(BoxInstance { lo, id: 0, hi, _pad: 0 });
            }
        }
    }
    (out, used)
}

impl CullStrategy for Implicit {
    fn name(&self) -> &'static str {
        "implicit"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let (boxes, objects) = frame_occluders(f, f.object_visible);
        let (mask, proven_hidden) = super::hidden::visible_without_hidden(f, &|_| true);
        let f = &FrameInputs { object_visible: &mask, ..*f };
        let FirstSet { first, fine, counts, ratio, prepass_tris } = prepass_first_set(f, enc, Proxies::Cheapest);
        let threshold = f.options.pixel_threshold as f32;
        draw_first(f, enc, &first);
        let rest = if boxes.is_empty() {
            test_the_rest(f, enc, &first, &fine, threshold, true, None, f.main_targets)
        } else {
            let d = &f.ctx.device;
            let test = Targets::ensure(&mut self.targets, d, f.width, f.height);
            let pass = self.depth.get_or_insert_with(|| OccluderDepth::new(d, &f.passes.scene_layout));
            pass.record(d, enc, f.scene_bg, &f.main_targets.depth, &test.depth, &boxes);
            test_the_rest(f, enc, &first, &fine, threshold, true, None, test)
        };
        let rest_stats = rest.stats();
        let mut v = Visible::new(rest.draw, Pixels::Gpu { counts, scale: ratio });
        v.predrawn = Some(first);
        v.tile_counts.push(("box_pixels", rest.box_counts));
        v.stats.push(("triangles_prepass", Stat::Count(prepass_tris)));
        v.stats.extend(rest_stats);
        v.stats.push(("tiles_proven_hidden", Stat::Count(proven_hidden)));
        v.stats.push(("implicit_occluder_boxes", Stat::Count(boxes.len() as u64)));
        v.stats.push(("implicit_objects", Stat::Count(objects)));
        Ok(v)
    }
}
