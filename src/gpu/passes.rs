//! The passes of a scene frame as pipelines plus functions that record them into an encoder.
//! Each knows what it draws or counts, never why: the culling strategies decide that.
//!
//! - [`Passes::record_prepass`]: depth + tile id of a set of draws (prepass.wgsl);
//! - [`Passes::record_histogram`]: exact pixels per tile id of an id image (histogram.wgsl);
//! - [`Passes::record_select`]: draw args switched off where a count is at or under a threshold
//!   (select.wgsl), so the next draw needs no read-back;
//! - [`Passes::record_draw`]: the lit draw of a set of draws, colour + tile id (draw.wgsl);
//! - [`Passes::record_box_test`]: per tile, the pixels where its box is at or in front of a
//!   depth image (box_test.wgsl, with box.wgsl; box_test_early.wgsl on the hardware's early depth
//!   test where the device allows it exactly, `box_early.rs`);
//! - [`Passes::record_select_rest`]: the draws not yet made whose count is above a threshold;
//! - [`Passes::record_slab_gate`]: the slab test's draws of the tiles whose gate is open.
//!
//! Sets of draws are indirect buffers of [`DrawArgs`], one per tile, drawn with one
//! `multi_draw_indexed_indirect`.

mod pipelines;

use super::geometry::SceneGeometry;
use super::layout::{DrawArgs, SelectParams};
use super::targets::Targets;
use super::timing::Timestamps;
use super::GpuContext;
use wgpu::util::DeviceExt;

/// Usage of every indirect-args buffer: drawn from, written by compute, copied for read-back.
pub const ARGS_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDIRECT
    .union(wgpu::BufferUsages::STORAGE)
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// Pipelines and bind-group layouts of the scene passes.
pub struct Passes {
    pub scene_layout: wgpu::BindGroupLayout,
    hist_layout: wgpu::BindGroupLayout,
    select_layout: wgpu::BindGroupLayout,
    draw: wgpu::RenderPipeline,
    /// The lit pass for the tiles of grid meshes (`SceneGeometry::draw_runs`).
    draw_grid: wgpu::RenderPipeline,
    /// The lit pass for the tiles of height fields with a normal map (`geometry::DrawRun::field`).
    draw_field: wgpu::RenderPipeline,
    /// `draw_field` for such tiles drawn at a coarser level: the fine surface's depth
    /// (`geometry::DrawRun::fine_depth`).
    draw_field_fine: wgpu::RenderPipeline,
    /// The lit pass with back faces culled, for closed surfaces seen from outside
    /// (`geometry::DrawRun::closed`).
    draw_closed: wgpu::RenderPipeline,
    /// `draw` and `draw_closed` for grids coloured per cell (`geometry::DrawRun::cells`).
    draw_cells: wgpu::RenderPipeline,
    draw_cells_closed: wgpu::RenderPipeline,
    draw_blend: wgpu::RenderPipeline,
    prepass: wgpu::RenderPipeline,
    histogram: wgpu::ComputePipeline,
    select: wgpu::ComputePipeline,
    rest_layout: wgpu::BindGroupLayout,
    select_rest: wgpu::ComputePipeline,
    /// The slab test's draws switched off behind closed gates (slab_gate.wgsl).
    slab_gate: wgpu::ComputePipeline,
    box_layout: wgpu::BindGroupLayout,
    box_test: wgpu::RenderPipeline,
    /// The 36 corner indices of a box's 12 triangles (box.wgsl `CUBE`): one indexed instance per
    /// box shades its 8 corners instead of 36 vertices.
    box_indices: wgpu::Buffer,
    /// The box test on the hardware's early depth test, where the device allows it exactly.
    box_early: Option<wgpu::RenderPipeline>,
    /// The box test's count with height-field tiles' slabs as occludees.
    pub slab_test: super::slab_test::SlabTest,
}

/// A render pass over `targets`, cleared (colour to the background, ids to 0, depth to far = 0)
/// unless `load`, which keeps what an earlier pass of the frame drew.
fn begin<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    targets: &'e Targets,
    with_color: bool,
    keep_depth: bool,
    load: bool,
    ts: Option<wgpu::RenderPassTimestampWrites<'e>>,
) -> wgpu::RenderPass<'e> {
    let clear = |c: wgpu::Color| wgpu::Operations {
        load: if load { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(c) },
        store: wgpu::StoreOp::Store,
    };
    let view = |v: &'e wgpu::TextureView, c: wgpu::Color| {
        Some(wgpu::RenderPassColorAttachment { view: v, depth_slice: None, resolve_target: None, ops: clear(c) })
    };
    let black = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 };
    let color = with_color.then(|| view(targets.color.as_ref().expect("targets without colour"), black)).flatten();
    let id = view(&targets.id, wgpu::Color::TRANSPARENT);
    let attachments = [color, id];
    let store = if keep_depth { wgpu::StoreOp::Store } else { wgpu::StoreOp::Discard };
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: if with_color { &attachments[..] } else { &attachments[1..] },
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth,
            depth_ops: Some(wgpu::Operations {
                load: if load { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(0.0) },
                store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: ts,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

impl Passes {
    /// Pass: depth + tile id of the first `count` draws of `args` (each draws instances of tile
    /// ids, usually one) into `targets` (no colour). Depth is discarded; the ids are what later
    /// passes count.
    #[allow(clippy::too_many_arguments)]
    pub fn record_prepass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        count: usize,
        ts: Option<&Timestamps>,
    ) {
        let mut pass = begin(enc, "prepass", targets, false, false, false, ts.and_then(|t| t.render("prepass_ms")));
        self.draw_range(&mut pass, &self.prepass, scene_bg, geom, args, 0..count);
    }

    /// Pass: the lit draw of `args` into `targets` (colour, tile id, depth kept for read-back),
    /// clearing them first unless `load` (then it adds to what an earlier pass drew).
    /// `runs`: the frame's runs of tiles (`SceneGeometry::frame_runs`). `outside`: per object,
    /// whether this frame sees it from outside (`Scene::seen_from_outside`), so that the back
    /// faces of its closed runs are culled.
    /// `breaks`: ascending tile indices where one render pass ends and the next begins (loading
    /// what the earlier drew): the same image as one pass, drawn in several (see
    /// [`pass_breaks`]). Timed as one pass (`draw_ms`: first pass's start to last pass's end).
    #[allow(clippy::too_many_arguments)]
    pub fn record_draw(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        load: bool,
        runs: &[super::geometry::DrawRun],
        outside: &[bool],
        breaks: &[usize],
        ts: Option<&Timestamps>,
    ) {
        let times = ts.and_then(|t| t.render("draw_ms"));
        let n_passes = breaks.len() + 1;
        for p in 0..n_passes {
            let lo = if p == 0 { 0 } else { breaks[p - 1] };
            let hi = breaks.get(p).copied().unwrap_or(usize::MAX);
            let (first, last) = (p == 0, p + 1 == n_passes);
            let times = times.as_ref().filter(|_| first || last).map(|t| wgpu::RenderPassTimestampWrites {
                query_set: t.query_set,
                beginning_of_pass_write_index: t.beginning_of_pass_write_index.filter(|_| first),
                end_of_pass_write_index: t.end_of_pass_write_index.filter(|_| last),
            });
            let mut pass = begin(enc, "draw", targets, true, true, load || p > 0, times);
            // Runs of tiles: grid meshes' with their own fragment entry point (fs_grid), height fields
            // with a normal map with entry points of their own that carry one varying fewer and run
            // no mesh branch (vs_field / fs_field: the 418² bench scene's frames 5-8 % faster on
            // lavapipe, the same images), the rest with fs_main. One fs_main with the lookup behind a pipeline-overridable constant was slower
            // on lavapipe: the reservoir grid's near frame took 40.4-40.9 ms against 37.6-39.5.
            // Closed surfaces seen from outside skip their back faces: the reservoir grid bench's
            // frames took about a quarter less (level 0, near 38.8 -> 28.4 ms, distant 25.1 -> 18.4).
            for run in runs {
                let pipeline = match run.closed {
                    _ if run.grid_mesh => &self.draw_grid,
                    _ if run.field && run.fine_depth => &self.draw_field_fine,
                    _ if run.field => &self.draw_field,
                    Some(o) if outside.get(o).copied().unwrap_or(false) && run.cells => &self.draw_cells_closed,
                    _ if run.cells => &self.draw_cells,
                    Some(o) if outside.get(o).copied().unwrap_or(false) => &self.draw_closed,
                    _ => &self.draw,
                };
                let tiles = run.tiles.start.max(lo)..run.tiles.end.min(hi);
                self.draw_range(&mut pass, pipeline, scene_bg, geom, args, tiles);
            }
        }
    }

    /// Pass: `args` (`n` draws, in their order) blended over `targets`' colour with their objects'
    /// opacity, depth tested against what is there, nothing else written (volume lenses).
    #[allow(clippy::too_many_arguments)]
    pub fn record_draw_blend(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        n: usize,
    ) {
        let mut pass = begin(enc, "draw_blend", targets, true, true, true, None);
        self.draw_range(&mut pass, &self.draw_blend, scene_bg, geom, args, 0..n);
    }

    /// Draws `range` of `args` with `pipeline`, the vertex and value streams bound.
    #[allow(clippy::too_many_arguments)]
    fn draw_range(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        scene_bg: &wgpu::BindGroup,
        geom: &SceneGeometry,
        args: &wgpu::Buffer,
        range: std::ops::Range<usize>,
    ) {
        if let (Some(vb), Some(sb), Some(ib)) = (&geom.vertices, &geom.values, &geom.indices) {
            if range.is_empty() {
                return;
            }
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, scene_bg, &[]);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.set_vertex_buffer(1, sb.slice(..));
            pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            let stride = std::mem::size_of::<super::layout::DrawArgs>() as u64;
            pass.multi_draw_indexed_indirect(args, range.start as u64 * stride, range.len() as u32);
        }
    }

    /// Pass: adds, per tile, the pixels of `ids` (width × height) holding that tile's id + 1 to
    /// `counts` (one u32 per tile; clear it first for a fresh count).
    pub fn record_histogram(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        ids: &wgpu::TextureView,
        size: (u32, u32),
        counts: &wgpu::Buffer,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("histogram"),
            layout: &self.hist_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(ids) },
                wgpu::BindGroupEntry { binding: 1, resource: counts.as_entire_binding() },
            ],
        });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("histogram"), timestamp_writes: ts });
        pass.set_pipeline(&self.histogram);
        pass.set_bind_group(0, &bg, &[]);
        // (histogram.wgsl: one invocation per 16 pixels of a row, in workgroups of 8 x 8.)
        pass.dispatch_workgroups(size.0.div_ceil(16 * 8), size.1.div_ceil(8), 1);
    }

    /// Pass: `out[i] = src[i]`, switched off where `counts[i] <= threshold`, for `n` tiles.
    #[allow(clippy::too_many_arguments)]
    pub fn record_select(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        counts: &wgpu::Buffer,
        src: &wgpu::Buffer,
        out: &wgpu::Buffer,
        n: usize,
        threshold: f32,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let buffers = [counts, src, out];
        self.run_selection(d, enc, "select", &self.select_layout, &self.select, &buffers, n, threshold, ts);
    }
}

impl Passes {
    /// Pass: for every box of `boxes` (render space; its `id` is a tile index) whose tile's draw in
    /// `skip` is off and whose `gate` count is above 0, adds to `counts[id]` the pixels where the
    /// front faces of the box are at or in front of the depth of `targets` (drawn by an earlier
    /// pass, reverse-Z). Writes nothing to `targets`. ([`Self::begin_test_pass`] with
    /// [`Self::draw_boxes`].)
    #[allow(clippy::too_many_arguments)]
    pub fn record_box_test(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        scene_bg: &wgpu::BindGroup,
        targets: &Targets,
        boxes: &wgpu::Buffer,
        n: usize,
        skip: &wgpu::Buffer,
        gate: &wgpu::Buffer,
        counts: &wgpu::Buffer,
        ts: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = self.begin_test_pass(enc, targets, ts);
        self.draw_boxes(d, &mut pass, scene_bg, targets, (boxes, n), skip, gate, counts);
    }

    /// A render pass for box and slab tests ([`Self::draw_boxes`], `SlabTest::draw`) against
    /// the depth of `targets`: its id image as the attachment (writes masked off) and, where the
    /// tests run on the early depth test (`box_early.rs`; the slab test runs there exactly when
    /// the box test does), its depth bound read-only. Tests drawn into one pass are rasterised
    /// together: a CPU rasteriser then waits once for their counts, not once per test.
    pub fn begin_test_pass<'e>(
        &self,
        enc: &'e mut wgpu::CommandEncoder,
        targets: &'e Targets,
        ts: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        // Without the early-depth pipeline there is no depth attachment: the fragment shader reads
        // the depth texture and counts by hand. With it, the same depth is also bound read-only
        // as the attachment the rasteriser tests against (both uses are reads).
        let depth_stencil_attachment = self.box_early.as_ref().map(|_| wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth,
            depth_ops: None,
            stencil_ops: None,
        });
        let keep = wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store };
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("box_test"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.id,
                depth_slice: None,
                resolve_target: None,
                ops: keep,
            })],
            depth_stencil_attachment,
            timestamp_writes: ts,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// Into `pass` ([`Self::begin_test_pass`] of `targets`): the box test of [`Self::record_box_test`]
    /// for the `n` boxes of `boxes`.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_boxes(
        &self,
        d: &wgpu::Device,
        pass: &mut wgpu::RenderPass<'_>,
        scene_bg: &wgpu::BindGroup,
        targets: &Targets,
        (boxes, n): (&wgpu::Buffer, usize),
        skip: &wgpu::Buffer,
        gate: &wgpu::Buffer,
        counts: &wgpu::Buffer,
    ) {
        if n == 0 {
            return;
        }
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("box_test"),
            layout: &self.box_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&targets.depth) },
                wgpu::BindGroupEntry { binding: 1, resource: counts.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: skip.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: gate.as_entire_binding() },
            ],
        });
        pass.set_pipeline(self.box_early.as_ref().unwrap_or(&self.box_test));
        pass.set_bind_group(0, scene_bg, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_vertex_buffer(0, boxes.slice(..));
        pass.set_index_buffer(self.box_indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..36, 0, 0..n as u32);
    }

    /// Pass: `out[i] = src[i]` where `done[i]` is off and `counts[i] > threshold`, else switched
    /// off: the draws a second phase adds to those an earlier one made.
    #[allow(clippy::too_many_arguments)]
    pub fn record_select_rest(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        counts: &wgpu::Buffer,
        src: &wgpu::Buffer,
        done: &wgpu::Buffer,
        out: &wgpu::Buffer,
        n: usize,
        threshold: f32,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let buffers = [counts, src, done, out];
        self.run_selection(d, enc, "select_rest", &self.rest_layout, &self.select_rest, &buffers, n, threshold, ts);
    }

    /// Pass: `out[k] = slabs[k]` (`n` draws, one per slab, its tile in `first_instance`) where the
    /// tile's draw in `done` is off and its `gate` count is above 0, else switched off: the slab
    /// test then runs no vertex work for the slabs of tiles whose gate (their slab's gate or whole
    /// box) counted nothing.
    #[allow(clippy::too_many_arguments)]
    pub fn record_slab_gate(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        gate: &wgpu::Buffer,
        slabs: &wgpu::Buffer,
        done: &wgpu::Buffer,
        out: &wgpu::Buffer,
        n: usize,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let buffers = [gate, slabs, done, out];
        self.run_selection(d, enc, "slab_gate", &self.rest_layout, &self.slab_gate, &buffers, n, 0.0, ts);
    }

    /// One selection dispatch: `SelectParams { n, threshold }` at binding 0, then `buffers` at
    /// bindings 1.., over `n` tiles in a 2-D dispatch.
    #[allow(clippy::too_many_arguments)]
    fn run_selection(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
        n: usize,
        threshold: f32,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let params = SelectParams { n_tiles: n as u32, threshold, _pad: [0; 2] };
        let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: params_buf.as_entire_binding() }];
        for (k, b) in buffers.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry { binding: k as u32 + 1, resource: b.as_entire_binding() });
        }
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes: ts });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bg, &[]);
        let (x, y) = tile_groups(n);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// Workgroups `(x, y)` covering `n` tiles with 64 per group: a 2-D dispatch, since one dimension
/// holds at most 65,535 groups (4,194,240 tiles); the shaders index `gid.x + gid.y * 65535 * 64`.
pub fn tile_groups(n: usize) -> (u32, u32) {
    const MAX: usize = 65_535;
    let groups = n.div_ceil(64).max(1);
    (groups.min(MAX) as u32, groups.div_ceil(MAX) as u32)
}

/// A vertex buffer of box instances (one zeroed box when empty).
pub fn boxes_buffer(d: &wgpu::Device, boxes: &[super::layout::BoxInstance]) -> wgpu::Buffer {
    let one = [super::layout::BoxInstance::default()];
    let b = if boxes.is_empty() { &one[..] } else { boxes };
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("boxes"),
        contents: bytemuck::cast_slice(b),
        usage: wgpu::BufferUsages::VERTEX,
    })
}

/// A u32 per tile initialised from `values` (e.g. counts that start above zero).
pub fn counts_buffer_init(d: &wgpu::Device, values: &[u32]) -> wgpu::Buffer {
    let one = [0u32];
    let v = if values.is_empty() { &one[..] } else { values };
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("counts"),
        contents: bytemuck::cast_slice(v),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
    })
}

/// An indirect-args buffer holding `args` (one zeroed draw when empty: buffers may not be empty).
pub fn args_buffer(d: &wgpu::Device, label: &str, args: &[DrawArgs]) -> wgpu::Buffer {
    let one = [DrawArgs::default()];
    let a = if args.is_empty() { &one[..] } else { args };
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(a),
        usage: ARGS_USAGE,
    })
}

/// An uninitialised indirect-args buffer for `n` draws (a compute pass fills it).
pub fn empty_args_buffer(d: &wgpu::Device, label: &str, n: usize) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (n.max(1) * std::mem::size_of::<DrawArgs>()) as u64,
        usage: ARGS_USAGE,
        mapped_at_creation: false,
    })
}

/// A zeroed u32 per tile for histogram counts.
pub fn counts_buffer(d: &wgpu::Device, n: usize) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("counts"),
        size: 4 * n.max(1) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl GpuContext {
    /// A new command encoder.
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }
}

impl Passes {
    /// The scene bind group of one frame: uniforms, the objects (`layout::object_texels`), the
    /// tiles' grids and objects (`SceneGeometry::tiles`), the colour-map tables the objects'
    /// `cmap.w` name (`layout::ColorTables`), the height fields' normal map
    /// (`SceneGeometry::shading`) and the sample values and tables (`SceneGeometry::sample_values`).
    pub fn scene_bind_group(
        &self,
        ctx: &GpuContext,
        globals: &super::layout::Globals,
        objects: &[super::layout::GpuObject],
        lut: &super::layout::ColorTables,
        geom: &SceneGeometry,
    ) -> wgpu::BindGroup {
        let d = &ctx.device;
        let shading_view = geom.shading.create_view(&Default::default());
        let tiles_view = geom.tiles.create_view(&Default::default());
        let values_view = geom.sample_values.create_view(&Default::default());
        let lut_view = super::layout::table_texture(
            ctx,
            "colour maps",
            wgpu::TextureFormat::Rgba32Float,
            lut.extent(),
            &lut.image(),
        )
        .create_view(&Default::default());
        let (extent, texels) = super::layout::object_texels(objects);
        let object_view =
            super::layout::table_texture(ctx, "objects", wgpu::TextureFormat::Rgba32Uint, extent, &texels)
                .create_view(&Default::default());
        let globals_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::bytes_of(globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.scene_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: globals_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&object_view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&tiles_view) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&lut_view) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&shading_view) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(&values_view) },
            ],
        })
    }
}

/// Where to break a lit draw into render passes of at most `max_triangles` triangles each
/// (`per_tile`: each tile's index count, an upper bound of what it draws): ascending tile indices,
/// each the first tile of a new pass; empty when `max_triangles` is `None` or everything fits.
/// A tile larger than the bound gets a pass of its own.
///
/// Why: a CPU driver (lavapipe, llvmpipe) bins a pass's triangles into memory it holds until
/// the pass is rasterised; at the end of a pass it rasterises what it binned, so a bound on one
/// pass's triangles bounds that memory (see `Renderer::set_pass_triangles`).
pub fn pass_breaks(per_tile: impl IntoIterator<Item = u32>, max_triangles: Option<u64>) -> Vec<usize> {
    let Some(max) = max_triangles else { return Vec::new() };
    let mut breaks = Vec::new();
    let mut acc = 0u64;
    for (i, indices) in per_tile.into_iter().enumerate() {
        let t = indices as u64 / 3;
        if acc > 0 && t > 0 && acc + t > max {
            breaks.push(i);
            acc = 0;
        }
        acc += t;
    }
    breaks
}
