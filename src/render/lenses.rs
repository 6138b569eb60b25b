//! Stage 4b of a frame: volume lenses, drawn after the opaque image ([`draw_lenses`]).

use crate::cull::{FrameInputs, Stat};
use crate::error::Result;
use crate::gpu::{passes, readback, DrawArgs, GpuContext};
use glam::DVec3;

/// What [`draw_lenses`] recorded: per lens slice tested, its count read back after the frame.
pub(super) struct LensFrame {
    counts: wgpu::Buffer,
    /// Per tested slice, the lens (object index) it belongs to.
    lens_of: Vec<usize>,
}

impl LensFrame {
    /// `lens_slices_tested`, `lens_slices_drawn`, `lenses_hidden` (wholly behind the opaque image).
    pub(super) fn stats(&self, ctx: &GpuContext) -> Result<Vec<(&'static str, Stat)>> {
        readback::map_all([&self.counts]);
        ctx.wait()?;
        let c: Vec<u32> = readback::read_mapped(&self.counts)?;
        let drawn = c.iter().take(self.lens_of.len()).filter(|&&k| k > 0).count();
        let mut shown: std::collections::BTreeMap<usize, bool> = Default::default();
        for (k, &l) in self.lens_of.iter().enumerate() {
            *shown.entry(l).or_default() |= c[k] > 0;
        }
        Ok(vec![
            ("lens_slices_tested", Stat::Count(self.lens_of.len() as u64)),
            ("lens_slices_drawn", Stat::Count(drawn as u64)),
            ("lenses_hidden", Stat::Count(shown.values().filter(|s| !**s).count() as u64)),
        ])
    }
}

/// Stage 4b: volume lenses (`scene::lens`), after the opaque image in the same encoder: per lens
/// the stack of slices whose normal is closest to the view direction, farthest first, each
/// slice's box tested against the opaque depth (a box reaching the near plane is always drawn),
/// the visible ones selected on the GPU and blended in that order. None without a visible lens.
pub(super) fn draw_lenses(f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Option<LensFrame> {
    let g = f.geometry;
    let objects = f.scene.objects();
    let zs = DVec3::new(1.0, 1.0, f.camera.z_scale);
    // (distance, tile, lens) of the slices to draw.
    let mut chosen: Vec<(f64, usize, usize)> = Vec::new();
    let mut first = 0usize;
    for (oi, o) in objects.iter().enumerate() {
        let range = first..first + o.tiles.len();
        first = range.end;
        if !o.visible || o.opacity >= 1.0 || o.tiles.is_empty() {
            continue;
        }
        // A lens's stack (tile ix = axis) whose slices face the eye most squarely.
        let normal = |t: &crate::lod::TileMesh| -> DVec3 {
            let p = |k: usize| DVec3::from_array(t.positions[t.fine[k] as usize].map(f64::from)) * zs;
            (p(1) - p(0)).cross(p(2) - p(0)).normalize_or_zero()
        };
        let mut best = [0.0f64; 3];
        for t in o.tiles.iter().filter(|t| t.fine.len() >= 3) {
            let a = (t.ix as usize).min(2);
            best[a] = best[a].max(normal(t).dot(f.fc.forward).abs());
        }
        let axis = (0..3).max_by(|&a, &b| best[a].total_cmp(&best[b])).unwrap_or(2) as u32;
        // A lens draws one of its three stacks; any other translucent object (a slice) all its tiles.
        let lens = o.kind().one_stack;
        let off = o.placement(f.origin);
        for (ti, t) in range.zip(&o.tiles) {
            if (!lens || t.ix == axis) && !t.fine.is_empty() {
                let (lo, hi) = g.bbox[ti];
                let c = ((lo + hi) * 0.5 + off) * zs;
                chosen.push(((c - f.fc.eye).length(), ti, oi));
            }
        }
    }
    if chosen.is_empty() {
        return None;
    }
    chosen.sort_by(|a, b| b.0.total_cmp(&a.0));
    let d = &f.ctx.device;
    let m = chosen.len();
    let mut boxes = Vec::with_capacity(m);
    let mut init = vec![0u32; m];
    for (p, &(_, ti, _)) in chosen.iter().enumerate() {
        let (lo, hi, near) = f.tile_box(ti);
        if near {
            init[p] = 1;
        }
        boxes.push(crate::gpu::layout::BoxInstance {
            lo: lo.as_vec3().to_array(),
            id: p as u32,
            hi: hi.as_vec3().to_array(),
            _pad: 0,
        });
    }
    let counts = passes::counts_buffer_init(d, &init);
    let boxes_buf = passes::boxes_buffer(d, &boxes);
    let skip = passes::empty_args_buffer(d, "lens_skip", m);
    enc.clear_buffer(&skip, 0, None);
    let open = passes::counts_buffer_init(d, &vec![1; m]);
    f.passes.record_box_test(d, enc, f.scene_bg, f.main_targets, &boxes_buf, m, &skip, &open, &counts, None);
    let src: Vec<DrawArgs> = chosen.iter().map(|&(_, ti, _)| g.fine[ti]).collect();
    let src = passes::args_buffer(d, "lens_args", &src);
    let out = passes::empty_args_buffer(d, "lens_draws", m);
    f.passes.record_select(d, enc, &counts, &src, &out, m, 0.0, None);
    f.passes.record_draw_blend(enc, f.main_targets, f.scene_bg, g, &out, m);
    let rb = readback::copy_buffer(d, enc, &counts, 4 * m as u64);
    Some(LensFrame { counts: rb, lens_of: chosen.iter().map(|c| c.2).collect() })
}
