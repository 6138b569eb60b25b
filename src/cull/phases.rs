//! The phases `three_pass` and `temporal` share.
//!
//! [`prepass_first_set`] is three_pass's passes 1–3 (Plate et al.): a depth + tile-id prepass of
//! the coarse proxies, front to back, at `prepass_scale`; the exact pixels per tile of its id
//! image; the tiles above the threshold selected on the GPU as the first set A.
//!
//! When the second phase follows (conservative three_pass, temporal), nothing drawn rests on the
//! proxies: they only choose A. Each tile's prepass then draws the cheapest of its coarse proxy,
//! its coarsest level of detail and its occluder ([`Proxies::Cheapest`]), so a scene built
//! without coarse proxies (`coarse_factor` 1, the default: the proxy is the fine tile) does not
//! pay a prepass of every fine triangle; tiles drawing one pattern go as one instanced draw
//! ([`instanced_runs`]).
//!
//! [`draw_and_test_the_rest`] is the conservative second phase: after A has been drawn into the
//! final targets, every other visible tile's box (its sub-boxes when drawn at level 0) is tested
//! against that image's depth at full resolution (`Passes::record_box_test`), and the tiles whose
//! count exceeds the threshold are drawn too, selected on the GPU (`record_select_rest`).
//!
//! Why nothing visible is lost, whatever A is: the depth D(p) after drawing A is that of a subset
//! of the scene's fine triangles, so at every pixel it is at or behind the nearest fine surface
//! F(p); a tile T with a visible fragment at p lies at F(p) there, inside T's box, so the box's
//! entry point on p's ray is at or in front of D(p): T's count is at least its number of visible
//! pixels. The same holds for any set of boxes whose union holds what is drawn of T (the ray enters
//! one of them in front of the fragment): T's sub-boxes (`SceneGeometry::sub_boxes`: a height-field
//! tile's quarters of its height blocks; another tile's `TileMesh::occludee_boxes`, each cell of
//! its (x, y) box spanning only its own triangles' heights, or each slice along its longest side
//! only its own triangles, whichever is smaller: a tube's slices follow it) when T is drawn at
//! level 0, which cuts the tiles whose box pokes through an occluder while their surface stays
//! behind it; the whole box
//! at coarser levels, whose triangles may leave the sub-boxes but not the convex box of the
//! vertices they share with level 0. A pixel counted in several overlapping sub-boxes only raises
//! the count. Sub-boxes are rasterised only where the tile's whole box, tested first, counts a
//! pixel ([`tile_boxes`]): that changes no count, only the work. A height-field tile with a slab
//! (`lod::slab`: closed prisms, wound outwards, whose union holds its fine triangles and, grown by
//! a lattice level's error, that level's) is tested with its slab instead: the ray's entry into
//! the prisms is a front face at or in front of the fragment, the same argument, with an
//! occludee as thin as the surface's departure from its coarse lattice rather than as tall as the
//! tile's height range. Its gate is its slab's gate (`lod::slab::Slab::gate`: a coarser slab, a
//! few dozen triangles against the slab's hundreds; the whole box where it has none), drawn
//! first: the gate holds every fine triangle (and, grown by the same error, the drawn level), so
//! a tile with a visible pixel opens its gate, and a tile whose gate stays shut has none: its
//! count 0 still bounds its visible pixels (the slab alone might have counted pixels where it
//! pokes out of the gate; only the work and such counts of hidden tiles differ). On the Reek
//! field's views the tiles' boxes let 180-200 of ~290 hidden height-field tiles through to their
//! slabs, of which 7-17 counted a pixel. Boxes reaching the near plane
//! are drawn untested ([`FORCED`]); boxes are grown against f32 round-off and ties count as
//! visible (`FrameInputs::tile_box`).

use super::{Draw, FrameInputs};
use crate::gpu::geometry::SlabDraw;
use crate::gpu::layout::BoxInstance;
use crate::gpu::slab_test::SlabDraws;
use crate::gpu::DrawArgs;
use crate::gpu::{passes, Targets};

/// What the prepass phase recorded.
pub struct FirstSet {
    /// The first set's draws (one per tile, switched off where not selected), written on the GPU.
    pub first: wgpu::Buffer,
    /// The frame's draws of every visible tile (`FrameInputs::draw_args`), one per tile.
    pub fine: wgpu::Buffer,
    /// Pixels per tile in the prepass image.
    pub counts: wgpu::Buffer,
    /// Full-image pixels per prepass pixel: the real size ratio (rounding and the 1-pixel floor
    /// make it differ from 1 / scale² for small images).
    pub ratio: f64,
    /// Coarse-proxy triangles drawn by the prepass.
    pub prepass_tris: u64,
}

/// Which draw of each tile the prepass makes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Proxies {
    /// The coarse proxy built with the scene (`coarse_factor`): the paper's method, whose
    /// culling rests on it.
    Built,
    /// Whichever of the coarse proxy, the coarsest level of detail and the occluder
    /// (`SceneGeometry::occluder`: a coarse lattice of a height-field tile's samples, 8 to 32
    /// triangles) has the fewest triangles: for frames whose second phase finds whatever the
    /// first set misses.
    Cheapest,
}

/// Each visible tile's prepass draw (`proxies`), switched off for the others.
pub fn prepass_draws(f: &FrameInputs<'_>, proxies: Proxies) -> Vec<DrawArgs> {
    let g = f.geometry;
    let args: Vec<DrawArgs> = match proxies {
        Proxies::Built => g.coarse.clone(),
        Proxies::Cheapest => (0..g.n_tiles())
            .map(|i| {
                // The coarse proxy first: it wins ties.
                let others = [Some(g.occluder[i]), g.levels[i].last().map(|l| l.args)];
                let drawable = others.into_iter().flatten().filter(|a| a.index_count > 0);
                std::iter::once(g.coarse[i]).chain(drawable).min_by_key(|a| a.index_count).unwrap_or(g.coarse[i])
            })
            .collect(),
    };
    f.pick(&args, |_| true)
}

/// `draws` (one per tile, in tile order, each one instance of its tile) as instanced runs: the
/// switched-off draws left out, and consecutive tiles that draw the same indices (tiles of one
/// shape sharing a lattice pattern) merged into one draw of consecutive instances. The vertex
/// stage reads the tile from the instance index either way, so the pixels drawn are the same;
/// a software rasteriser pays its per-draw cost (~1 µs on lavapipe) once per run.
pub fn instanced_runs(draws: &[DrawArgs]) -> Vec<DrawArgs> {
    let mut runs: Vec<DrawArgs> = Vec::new();
    for a in draws.iter().filter(|a| a.instance_count > 0 && a.index_count > 0) {
        match runs.last_mut() {
            Some(r)
                if (r.index_count, r.first_index, r.base_vertex) == (a.index_count, a.first_index, a.base_vertex)
                    && r.first_instance + r.instance_count == a.first_instance =>
            {
                r.instance_count += a.instance_count
            }
            _ => runs.push(*a),
        }
    }
    runs
}

/// Passes 1–3 of three_pass into `enc`: the prepass of each tile's `proxies` draw into the
/// renderer's prepass targets (`FrameInputs::prepass_targets`, made or resized for
/// `prepass_scale`), its histogram and the GPU selection of the tiles with more than
/// `pixel_threshold` pixels (compared in prepass pixels).
pub fn prepass_first_set(f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder, proxies: Proxies) -> FirstSet {
    let d = &f.ctx.device;
    let n = f.n_tiles();
    let scale = f.options.prepass_scale;
    let pw = ((f.width as f64 * scale).round() as u32).max(1);
    let ph = ((f.height as f64 * scale).round() as u32).max(1);
    let mut targets = f.prepass_targets.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let pt = Targets::ensure(&mut targets, d, pw, ph);

    // Pass 1: coarse proxies, front to back.
    let coarse = prepass_draws(f, proxies);
    let prepass_tris: u64 = coarse.iter().map(|a| a.triangles()).sum();
    let mut runs = instanced_runs(&coarse);
    let dist = f.tile_dist2;
    let near = |a: &DrawArgs| {
        let tiles = a.first_instance as usize..(a.first_instance + a.instance_count) as usize;
        dist[tiles].iter().copied().fold(f64::INFINITY, f64::min)
    };
    runs.sort_by(|a, b| near(a).total_cmp(&near(b)));
    let coarse_buf = passes::args_buffer(d, "coarse_args", &runs);
    f.passes.record_prepass(enc, pt, f.scene_bg, f.geometry, &coarse_buf, runs.len(), f.timestamps);

    // Pass 2: exact visible pixels per tile.
    let counts = passes::counts_buffer(d, n);
    enc.clear_buffer(&counts, 0, None);
    let ts = |name| f.timestamps.and_then(|t| t.compute(name));
    f.passes.record_histogram(d, enc, &pt.id, (pw, ph), &counts, ts("count_ms"));

    // Pass 3: the first set of fine draws, selected on the GPU.
    let fine = passes::args_buffer(d, "fine_args", &f.pick(f.draw_args, |_| true));
    let first = passes::empty_args_buffer(d, "draw_args", n);
    let threshold = f.options.pixel_threshold;
    let scaled = (threshold * (pw as f64 * ph as f64) / (f.width as f64 * f.height as f64)) as f32;
    f.passes.record_select(d, enc, &counts, &fine, &first, n, scaled, ts("count_ms"));
    let ratio = (f.width as f64 * f.height as f64) / (pw as f64 * ph as f64);
    FirstSet { first, fine, counts, ratio, prepass_tris }
}

/// Initial box count of tiles drawn untested (their box reaches the near plane).
pub const FORCED: u32 = 1 << 30;

/// The boxes of the box test (render space, grown against f32 round-off; instance id = tile).
pub struct TileBoxes {
    /// Every visible, non-empty tile's box, or its sub-boxes when it is drawn at level 0.
    pub boxes: Vec<BoxInstance>,
    /// Per tile, the initial count (FORCED when its box reaches the near plane, else 0).
    pub init: Vec<u32>,
    /// The whole box of each tile tested with sub-boxes: the gate of its sub-boxes.
    pub gates: Vec<BoxInstance>,
    /// Per tile, the initial gate count: 0 for a tile whose sub-boxes (or slab) wait for its
    /// whole box, 1 (open) for the others.
    pub gate_init: Vec<u32>,
    /// The slab draws (`SceneGeometry::slab_draws`) of the tiles tested with their slabs.
    pub slabs: Vec<DrawArgs>,
    /// The draws of those slabs' gates (`lod::slab::Slab::gate`), for the tiles that have one:
    /// the gate of their slab in place of their whole box.
    pub slab_gates: Vec<DrawArgs>,
    /// Per tile, for the slab test: its object's placement (render space, before exaggeration)
    /// and how far its slab grows along z (the drawn level's error and a margin), world units.
    pub place: Vec<[f32; 4]>,
}

/// The boxes of the visible, non-empty tiles. A tile drawn at level 0 is tested with its
/// sub-boxes (their union holds its triangles), behind the gate of its whole box: its sub-boxes
/// are rasterised only when the whole box counts a pixel. The gate changes no count: each sub-box
/// lies in the whole box (grown by no more), so where a sub-box's front face is at or in front of
/// the image, the whole box's (the ray's entry into the larger convex box) is too. Most hidden
/// tiles are then rasterised once, as one box, instead of as four.
pub fn tile_boxes(f: &FrameInputs<'_>, drawn: Option<&[bool]>) -> TileBoxes {
    let g = f.geometry;
    let n = g.n_tiles();
    let mut t = TileBoxes {
        boxes: Vec::new(),
        init: vec![0; n],
        gates: Vec::new(),
        gate_init: vec![1; n],
        slabs: Vec::new(),
        slab_gates: Vec::new(),
        place: vec![[0.0; 4]; n],
    };
    let instance = |i: usize, (lo, hi, _): (glam::DVec3, glam::DVec3, bool)| BoxInstance {
        lo: lo.as_vec3().to_array(),
        id: i as u32,
        hi: hi.as_vec3().to_array(),
        _pad: 0,
    };
    for i in 0..n {
        // Tiles the first set is known (on the CPU) to draw need no test: their draw is on.
        if !f.object_visible[i] || g.fine[i].index_count == 0 || drawn.is_some_and(|d| d[i]) {
            continue;
        }
        // A tile drawn at a coarser level is tested with its whole box, which holds every level
        // (levels use the tile's own vertices, and a box is convex).
        let subs = &g.sub_boxes[i];
        let whole = f.render_box(i, g.bbox[i].0, g.bbox[i].1);
        if let Some((slab, grow)) = slab_test(f, i) {
            match slab.gate {
                Some(gate) => t.slab_gates.push(gate),
                None => t.gates.push(instance(i, whole)),
            }
            t.gate_init[i] = 0;
            let off = f.placement(g.tile_object_cpu[i] as usize);
            t.place[i] = [off.x as f32, off.y as f32, off.z as f32, grow as f32];
            t.slabs.push(slab.args);
        } else if f.draw_args[i] == g.fine[i] && !subs.is_empty() {
            // A whole box reaching the near plane is clipped, so it cannot gate: its sub-boxes
            // are then tested straight away.
            if !whole.2 {
                t.gates.push(instance(i, whole));
                t.gate_init[i] = 0;
            }
            for &(lo, hi) in subs {
                let b = f.render_box(i, lo, hi);
                if b.2 {
                    t.init[i] = FORCED;
                }
                t.boxes.push(instance(i, b));
            }
        } else {
            if whole.2 {
                t.init[i] = FORCED;
            }
            t.boxes.push(instance(i, whole));
        }
    }
    t
}

/// Tile `i`'s slab draw and how far its slab grows along z when the box test uses its slab: a
/// height-field tile with a slab, drawn at level 0 or at a lattice level (whose error bounds its
/// vertical distance to the fine surface, so the slab grown by it holds the level), where the
/// box of the tile, its slab and its gate so grown (`SlabDraw::bounds`) does not reach the near
/// plane (nor then does the tile's own box, which it holds). The growth adds a margin against f32
/// round-off as `FrameInputs::render_box` grows boxes.
fn slab_test(f: &FrameInputs<'_>, i: usize) -> Option<(SlabDraw, f64)> {
    let g = f.geometry;
    let slab = g.slab_draws[i]?;
    let error = f.exact_level_error(i)?;
    let (lo, hi) = g.bbox[i];
    let off = f.placement(g.tile_object_cpu[i] as usize);
    let margin = 1e-6 * (lo + off).abs().max((hi + off).abs()).max_element() + 1e-4 * (hi - lo).length() + 1e-9;
    // The slab and its gate, grown, may reach out of the tile's box (by their thickness): one
    // that reaches the near plane is clipped there, and the tile is box-tested instead.
    let grow = glam::DVec3::new(0.0, 0.0, error + margin);
    let (slo, shi) = slab.bounds;
    if f.render_box(i, lo.min(slo) - grow, hi.max(shi) + grow).2 {
        return None;
    }
    Some((slab, error + margin))
}

/// What the second phase recorded.
pub struct Rest {
    /// The draws it adds (Gpu), or nothing (a Mask of false) when it only tests.
    pub draw: Draw,
    /// Per tile, the box pixels counted (FORCED + count for untested tiles).
    pub box_counts: wgpu::Buffer,
    /// Tiles tested (each with one box, its sub-boxes or its slab).
    pub tested: usize,
    /// Tiles tested with their slabs, the slabs' triangles and their gates' triangles.
    pub slab_tiles: usize,
    pub slab_triangles: u64,
    pub gate_triangles: u64,
}

impl Rest {
    /// The names of [`Self::stats`].
    pub const STATS: [&'static str; 4] =
        ["tiles_box_tested", "tiles_slab_tested", "triangles_slab_test", "triangles_slab_gates"];

    /// The test's stats ([`Self::STATS`]: tiles tested, tiles tested with slabs, the slabs'
    /// triangles, their gates').
    pub fn stats(&self) -> [(&'static str, super::Stat); 4] {
        let n = [self.tested as u64, self.slab_tiles as u64, self.slab_triangles, self.gate_triangles];
        std::array::from_fn(|k| (Self::STATS[k], super::Stat::Count(n[k])))
    }
}

/// Draws `first` (the set A, as indirect args, one per tile) into the final targets, tests every
/// other visible tile's box against the result, and selects from `fine` (the frame's draws, one per
/// tile) those whose count exceeds `threshold` (full-image pixels) when `add` is true. `drawn`, when
/// the caller knows the first set on the CPU, lists its tiles: they are not tested at all (on the
/// GPU their boxes would collapse, but only after their vertex work).
pub fn draw_and_test_the_rest(
    f: &FrameInputs<'_>,
    enc: &mut wgpu::CommandEncoder,
    first: &wgpu::Buffer,
    fine: &wgpu::Buffer,
    threshold: f32,
    add: bool,
    drawn: Option<&[bool]>,
) -> Rest {
    draw_first(f, enc, first);
    test_the_rest(f, enc, first, fine, threshold, add, drawn, f.main_targets)
}

/// Draws `first` (the set A, as indirect args, one per tile) into the final targets, clearing
/// them: the first half of [`draw_and_test_the_rest`].
pub fn draw_first(f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder, first: &wgpu::Buffer) {
    f.passes.record_draw(
        enc,
        f.main_targets,
        f.scene_bg,
        f.geometry,
        first,
        false,
        f.draw_runs,
        f.outside,
        f.pass_breaks,
        f.timestamps,
    );
}

/// The second half of [`draw_and_test_the_rest`], once `first` is drawn: every other visible
/// tile's boxes (or slab) tested against the depth of `test` (the final targets, or targets of
/// their size whose depth is at or in front of theirs everywhere and still at or behind the
/// nearest fine surface of the scene: `cull::implicit`), and the selection from `fine`.
#[allow(clippy::too_many_arguments)]
pub fn test_the_rest(
    f: &FrameInputs<'_>,
    enc: &mut wgpu::CommandEncoder,
    first: &wgpu::Buffer,
    fine: &wgpu::Buffer,
    threshold: f32,
    add: bool,
    drawn: Option<&[bool]>,
    test: &Targets,
) -> Rest {
    let d = &f.ctx.device;
    let n = f.n_tiles();
    let t = tile_boxes(f, drawn);
    // Two test passes: the gates (whole boxes, and slabs' gates, every gate open for them), then
    // the sub-boxes and slabs behind open gates. Each pass rasterises its tests together.
    let gate = passes::counts_buffer_init(d, &t.gate_init);
    let open = passes::counts_buffer_init(d, &vec![1; n]);
    let box_counts = passes::counts_buffer_init(d, &t.init);
    let gates_buf = passes::boxes_buffer(d, &t.gates);
    let boxes_buf = passes::boxes_buffer(d, &t.boxes);
    let ts = |name| f.timestamps.and_then(|t| t.render(name));
    let (main, bg) = (test, f.scene_bg);
    let slabs = f.geometry.slabs.as_ref().filter(|_| !t.slabs.is_empty()).map(|(vertices, indices)| {
        let (extent, place) = crate::gpu::layout::rows(&t.place, crate::gpu::slab_test::PLACE_ROW);
        let place =
            crate::gpu::layout::table_texture(f.ctx, "slab_place", wgpu::TextureFormat::Rgba32Float, extent, &place)
                .create_view(&Default::default());
        (vertices, indices, place)
    });
    // Each slab's draw switched on where its gate is open (the first set's draws off).
    let slab_draws = |enc: &mut wgpu::CommandEncoder, draws: &[DrawArgs], gate: &wgpu::Buffer| {
        let all = passes::args_buffer(d, "slab_args", draws);
        let on = passes::empty_args_buffer(d, "slab_open", draws.len());
        let gate_ts = f.timestamps.and_then(|t| t.compute("count_ms"));
        f.passes.record_slab_gate(d, enc, gate, &all, first, &on, draws.len(), gate_ts);
        on
    };
    // One test pass: `boxes` behind the open gates of `gate`, and the slab draws `slab_draws`
    // (switched on by their own gates already), all counting into `counts`.
    let test_pass = |enc: &mut wgpu::CommandEncoder,
                     boxes: (&wgpu::Buffer, usize),
                     gate: &wgpu::Buffer,
                     counts: &wgpu::Buffer,
                     slab_draws: Option<(&wgpu::Buffer, usize)>| {
        let mut pass = f.passes.begin_test_pass(enc, main, ts("test_ms"));
        f.passes.draw_boxes(d, &mut pass, bg, main, boxes, first, gate, counts);
        if let (Some((vertices, indices, place)), Some((draws, n))) = (&slabs, slab_draws) {
            let s = SlabDraws { vertices, indices, draws, n: n as u32, place };
            f.passes.slab_test.draw(d, &mut pass, bg, main, &s, counts);
        }
    };
    let gate_slabs = slabs.as_ref().filter(|_| !t.slab_gates.is_empty()).map(|_| slab_draws(enc, &t.slab_gates, &open));
    let gate_slabs = gate_slabs.as_ref().map(|b| (b, t.slab_gates.len()));
    test_pass(enc, (&gates_buf, t.gates.len()), &open, &gate, gate_slabs);
    let fine_slabs = slabs.as_ref().map(|_| slab_draws(enc, &t.slabs, &gate));
    test_pass(enc, (&boxes_buf, t.boxes.len()), &gate, &box_counts, fine_slabs.as_ref().map(|b| (b, t.slabs.len())));
    let draw = if add {
        let rest = passes::empty_args_buffer(d, "rest_args", n);
        let ts = f.timestamps.and_then(|t| t.compute("count_ms"));
        f.passes.record_select_rest(d, enc, &box_counts, fine, first, &rest, n, threshold, ts);
        Draw::Gpu(rest)
    } else {
        Draw::Mask(vec![false; n])
    };
    let tested = (0..n).filter(|&i| f.object_visible[i] && f.geometry.fine[i].index_count > 0).count();
    let slab_triangles = t.slabs.iter().map(|a| a.triangles()).sum();
    let gate_triangles = t.slab_gates.iter().map(|a| a.triangles()).sum();
    Rest { draw, box_counts, tested, slab_tiles: t.slabs.len(), slab_triangles, gate_triangles }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(index_count: u32, first_index: u32, tile: u32) -> DrawArgs {
        DrawArgs { index_count, instance_count: 1, first_index, base_vertex: 0, first_instance: tile }
    }

    #[test]
    fn instanced_runs_merge_consecutive_tiles_of_one_pattern_only() {
        let mut draws = vec![draw(24, 0, 0), draw(24, 0, 1), draw(24, 0, 2), draw(6, 24, 3), draw(24, 0, 4)];
        draws.push(draw(24, 0, 5).off());
        draws.push(draw(24, 0, 6));
        draws.push(draw(0, 0, 7));
        let runs = instanced_runs(&draws);
        let want = [(24, 0, 0, 3), (6, 24, 3, 1), (24, 0, 4, 1), (24, 0, 6, 1)];
        let got: Vec<_> =
            runs.iter().map(|r| (r.index_count, r.first_index, r.first_instance, r.instance_count)).collect();
        assert_eq!(got, want);
        // Every drawn tile is drawn once, with its own indices.
        let tris: u64 = runs.iter().map(|r| r.index_count as u64 / 3 * r.instance_count as u64).sum();
        assert_eq!(tris, draws.iter().map(|d| d.triangles()).sum::<u64>());
    }
}
