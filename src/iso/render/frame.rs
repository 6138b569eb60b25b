//! [`IsoRenderer::render`]'s frame as named stages, in this order: the arguments checked, targets
//! (untimed), the view, the candidate nodes, the occluder classes, the visible nodes (the
//! oracle's cells, the walk, or every candidate), marching cubes, the draw, the read-back.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DMat4, DVec3, DVec4, Mat4};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::{
    node_classes, norm_bits, IsoCulling, IsoOptions, IsoOutput, IsoRenderer, IsoStats, CONTOUR_MIN_DENSITY,
    ORACLE_TOLERANCE,
};
use crate::camera::{Camera, FrameCamera};
use crate::error::{ensure, Result};
use crate::gpu::{GpuContext, ReadbackTexture};
use crate::iso::bricks::{contour_grid, dilate_nan, CONTOUR_SHIFT};
use crate::iso::march::SurfacePatch;
use crate::iso::octree::{MinMaxOctree, NodeInfo};
use crate::iso::oracle::{visible_cells, OracleCells};
use crate::iso::passes::{draw_surface, march, pixel_rays, ClassGrid, Globals, MapParams, Space, Targets, WalkData};
use crate::iso::pool::draw_pooled;
use crate::iso::seen::{cells_seen, seen_cells, visible_ranges};
use crate::iso::walk::{walk, WalkGrid};
use crate::iso::Volume;

/// One frame's arguments, as [`IsoRenderer::render`] takes them.
#[derive(Clone, Copy)]
pub(super) struct FrameArgs<'a> {
    pub(super) ctx: &'a GpuContext,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) vol: &'a Volume,
    pub(super) tree: &'a MinMaxOctree,
    pub(super) isovalue: f64,
    pub(super) camera: &'a Camera,
    pub(super) opts: &'a IsoOptions,
}

/// What every stage of a frame reads: its arguments, the isovalue and depths checked ([`check`]),
/// and the view ([`Frame::view`]).
struct Frame<'a> {
    args: FrameArgs<'a>,
    /// The isovalue as a residual about `vol.offset`.
    w: f32,
    maxd: u32,
    occ_depth: u32,
    cull_depth: u32,
    /// The volume's render space (see [`Frame::view`]) and its box there.
    space: Space,
    plo: DVec3,
    phi: DVec3,
    fc: FrameCamera,
    /// `fc.view_proj` with the volume's rotation folded in.
    view_proj: DMat4,
    globals: Globals,
    /// How far the map is pushed back: a thousandth of a cell.
    eps: f64,
    implicit: bool,
}

/// What the culling stage found: the nodes to extract, per candidate its march cells seen, the
/// march cells some ray entered before the map (bits, their grid, the shift from volume cells to
/// march cells), the host walk's map, and the oracle's own time (not the frame's).
struct Culled {
    visible: Vec<NodeInfo>,
    node_pixels: Vec<u32>,
    seen: Option<(Vec<u32>, [u32; 3], u32)>,
    host_map: Option<Vec<f32>>,
    untimed: Duration,
}

/// The read-back's host arrays: image, linear depth, the map when asked for.
type ReadBack = (Vec<u8>, Vec<f32>, Option<Vec<f32>>);

/// The isovalue as a residual and the depths (max, occluder, cull) of a frame, checked.
type Checked = (f32, u32, u32, u32);

/// Checks a frame's arguments: the isovalue in the volume's units (from here on everything is a
/// residual about `vol.offset`), the colour, the octree, the depths.
fn check(args: &FrameArgs<'_>) -> Result<Checked> {
    let FrameArgs { vol, tree, opts, .. } = *args;
    let w = vol.residual(args.isovalue, "isovalue")?;
    ensure(opts.color.iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c)), "color", || {
        format!("color is {:?}; expected (r, g, b) in [0, 1]", opts.color)
    })?;
    ensure(tree.cells() == [vol.nx as u32 - 1, vol.ny as u32 - 1, vol.nz as u32 - 1], "volume", || {
        "the octree was built from another volume".into()
    })?;
    let maxd = tree.max_depth();
    // A lazy volume's defaults are the finest stored depth: its classes and candidates come from
    // the octree alone, and only the visible nodes' samples are read.
    let lazy = vol.is_lazy().then(|| tree.stored_depth());
    let occ_depth = opts.occluder_depth.or(lazy).unwrap_or(maxd);
    let cull_depth = opts.cull_depth.or(lazy).unwrap_or(maxd.saturating_sub(2));
    ensure(occ_depth <= maxd, "occluder_depth", || {
        format!("occluder_depth is {occ_depth}; this volume's octree has depths 0..={maxd}")
    })?;
    ensure(cull_depth <= maxd, "cull_depth", || {
        format!("cull_depth is {cull_depth}; this volume's octree has depths 0..={maxd}")
    })?;
    Ok((w, maxd, occ_depth, cull_depth))
}

impl<'a> Frame<'a> {
    /// The frame of checked arguments, with its view.
    fn new(args: FrameArgs<'a>, (w, maxd, occ_depth, cull_depth): Checked) -> Self {
        let opts = args.opts;
        let (space, plo, phi, fc, view_proj, globals, eps) = Self::view(&args);
        let implicit = opts.culling == IsoCulling::Implicit;
        Frame { args, w, maxd, occ_depth, cull_depth, space, plo, phi, fc, view_proj, globals, eps, implicit }
    }

    /// The view: the render space, the volume's box in it, the frame camera, the matrix every
    /// pass draws with, the passes' globals and the map's push.
    #[allow(clippy::type_complexity)]
    fn view(args: &FrameArgs<'_>) -> (Space, DVec3, DVec3, FrameCamera, DMat4, Globals, f64) {
        let FrameArgs { vol, camera, opts, width, height, .. } = *args;
        let (lo, hi) = vol.bounds();
        // Boxes and patches live in the volume's grid frame, relative to its centre (`space`). A
        // rotated volume's render space is that turned about z (`model`; z exaggeration commutes
        // with it): the frame is centred on the world position of the centre, bounded by the turned
        // box, and the rotation is folded into the matrix every pass draws with.
        let space = Space { origin: (DVec3::from_array(lo) + DVec3::from_array(hi)) * 0.5, z_scale: camera.z_scale };
        let (c, s) = vol.cos_sin();
        let model = DMat4::from_cols(DVec4::new(c, s, 0.0, 0.0), DVec4::new(-s, c, 0.0, 0.0), DVec4::Z, DVec4::W);
        let (plo, phi) = (space.point(lo).min(space.point(hi)), space.point(lo).max(space.point(hi)));
        let mut rb = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for k in 0..8 {
            let p = DVec3::new(
                if k & 1 == 0 { plo.x } else { phi.x },
                if k & 2 == 0 { plo.y } else { phi.y },
                if k & 4 == 0 { plo.z } else { phi.z },
            );
            let q = model.transform_point3(p);
            rb = (rb.0.min(q), rb.1.max(q));
        }
        let centre = DVec3::from_array(vol.to_world(space.origin.to_array()));
        let fc = camera.frame(centre, Some(rb), width as f64 / height as f64);
        let rotated = (c, s) != (1.0, 0.0);
        let view_proj = if rotated { fc.view_proj * model } else { fc.view_proj };
        // Normals are in the grid frame too: light them with the light turned back.
        let light = if rotated { model.transpose().transform_vector3(fc.light_dir()) } else { fc.light_dir() };
        let globals = Globals {
            view_proj: Mat4::from_cols_array(&view_proj.to_cols_array().map(|v| v as f32)).to_cols_array_2d(),
            light_dir: [light.x as f32, light.y as f32, light.z as f32, 0.0],
            color: [opts.color[0], opts.color[1], opts.color[2], 1.0],
        };
        let min_spacing = vol.spacing.iter().cloned().fold(f64::INFINITY, f64::min);
        // The map is pushed farther by a thousandth of a cell: rounding never culls a visible node.
        let eps = 1e-3 * min_spacing;
        (space, plo, phi, fc, view_proj, globals, eps)
    }
}

impl IsoRenderer {
    /// [`Self::render`]'s frame; with `oracle`, the oracle's (`opts.culling` is then Oracle).
    pub(super) fn frame(&mut self, args: &FrameArgs<'_>, oracle: Option<&OracleCells>) -> Result<IsoOutput> {
        let FrameArgs { ctx, width, height, opts, .. } = *args;
        let checked = check(args)?;

        // One-time work first, outside the frame's clock: targets at a new size.
        let t_setup = Instant::now();
        let made = Targets::ensure(&mut self.targets, &ctx.device, width, height);
        let targets_ms = if made { t_setup.elapsed().as_secs_f64() * 1e3 } else { 0.0 };
        let setup_ms = std::mem::take(&mut self.setup_ms) + targets_ms;

        let t0 = Instant::now();
        let read0 = args.vol.bytes_read();
        let f = Frame::new(*args, checked);
        self.bind_volume(args.vol);
        // A quarter of the budget for node lists, the rest for patches.
        let (list_budget, patch_budget) = (opts.cache_budget / 4, opts.cache_budget - opts.cache_budget / 4);
        self.patches.set_budget(patch_budget);
        let candidates = self.straddling(args.tree, f.w, f.cull_depth, list_budget);
        let t_occ = Instant::now();
        let host = opts.walk.on_host(&ctx.info);
        if f.implicit {
            self.ensure_classes(&f, list_budget, host);
        }
        let globals_bg = self.globals_bind_group(ctx, &f.globals);
        let mut stats = IsoStats {
            occluder_depth: f.occ_depth,
            cull_depth: f.cull_depth,
            max_depth: f.maxd,
            nodes_straddling: candidates.len() as u32,
            ..Default::default()
        };
        // ---- Occlusion map and node test: one walk per pixel, one submission, one read-back.
        let culled = if let Some(cells) = oracle {
            oracle_nodes(&f, &candidates, cells)
        } else if !f.implicit {
            Culled {
                visible: candidates.to_vec(),
                node_pixels: vec![0u32; candidates.len()],
                seen: None,
                host_map: None,
                untimed: Duration::ZERO,
            }
        } else {
            self.walk_nodes(&f, &candidates, &globals_bg, (host, t_occ), &mut stats)?
        };
        stats.nodes_visible = culled.visible.len() as u32;
        // (A culled frame's visible nodes are the candidates with a cell seen, in their order.)
        let node_drawn: Vec<bool> = match opts.culling {
            IsoCulling::None => vec![true; candidates.len()],
            _ => culled.node_pixels.iter().map(|&c| c > 0).collect(),
        };

        // ---- Marching cubes in the visible nodes (cached per node).
        let t_ex = Instant::now();
        let patches = self.extract(&f, &culled, &mut stats);
        stats.extract_ms = t_ex.elapsed().as_secs_f64() * 1e3;
        if let Err(e) = args.vol.take_error() {
            // (Patches and node lists of samples that failed to read are NaN-holed: none is kept.)
            self.clear_cache();
            return Err(e);
        }
        opts.interrupt.check()?;

        // ---- Draw.
        let t_draw = Instant::now();
        let (tris, verts) = self.draw(&f, &culled, &patches, &globals_bg)?;
        stats.submissions += 1;
        stats.surface_triangles = tris;
        stats.surface_vertices = verts;
        stats.draw_ms = t_draw.elapsed().as_secs_f64() * 1e3;
        stats.surface_ms = stats.extract_ms + stats.draw_ms;
        stats.total_ms = (t0.elapsed() - culled.untimed).as_secs_f64() * 1e3;

        // ---- Read-back (not part of the frame time).
        let t_rb = Instant::now();
        let (image, depth, map_out) = self.read_back(&f, culled.host_map)?;
        stats.readback_ms = t_rb.elapsed().as_secs_f64() * 1e3;
        stats.setup_ms = setup_ms;
        // This frame's patches that the cache did not keep leave the pool.
        drop(patches);
        self.pool.trim();
        stats.cache_bytes = self.cache_bytes() as u64;
        stats.gpu_cache_bytes = self.pool.bytes();
        stats.contour_bytes = self.classes.as_ref().map_or(0, |g| g.data.contour_bytes());
        stats.bytes_read = args.vol.bytes_read() - read0;
        stats.brick_cache_bytes = args.vol.store().map_or(0, |s| s.held_bytes() as u64);
        Ok(IsoOutput {
            width,
            height,
            image,
            depth,
            nodes: candidates.iter().map(|n| [n.depth, n.ix, n.iy, n.iz]).collect(),
            node_pixels: culled.node_pixels,
            node_drawn,
            map: map_out,
            stats,
            near: f.fc.near,
            far: f.fc.far,
        })
    }

    /// View independent: the node classes at the occluder depth (kept where the walk runs, `host`),
    /// built unless those of this isovalue, depth, contour policy and place are kept.
    fn ensure_classes(&mut self, f: &Frame<'_>, list_budget: usize, host: bool) {
        let (tree, w, occ_depth, maxd) = (f.args.tree, f.w, f.occ_depth, f.maxd);
        let key = (norm_bits(w), occ_depth);
        let policy = f.args.opts.face_contours;
        if self.classes.as_ref().is_none_or(|g| g.key != key || g.contour_policy != policy || g.data.on_host() != host)
        {
            self.classes = None;
            let dims = tree.dims_at_depth(occ_depth).expect("occ_depth <= max depth");
            // Single cells carry their faces' classes too (finer occluders for the walk), and
            // the samples of the bricks that hold surface, for the contours of mixed faces.
            let leaves = if occ_depth == tree.max_depth() { tree.leaf_nodes(w) } else { None };
            let faces = leaves.is_some();
            let contour = if faces && policy != Some(false) {
                // (At the default cull depth the cache hands back the candidate nodes.)
                let brick_depth = maxd.saturating_sub(CONTOUR_SHIFT);
                let bricks = self.straddling(tree, w, brick_depth, list_budget);
                let n = tree.dims_at_depth(brick_depth).expect("brick depth <= max depth");
                let dense = bricks.len() as f64 >= CONTOUR_MIN_DENSITY * n.iter().map(|&v| v as f64).product::<f64>();
                // (The host's walk places them wherever the surface is: it pays only for the
                // faces its rays cross.)
                (policy == Some(true) || dense || host).then(|| tree.contour_bricks(&bricks))
            } else {
                None
            };
            let mut nodes = leaves.unwrap_or_else(|| node_classes(tree, w, occ_depth));
            dilate_nan(&mut nodes, dims);
            self.classes = Some(ClassGrid::new(&f.args.ctx.device, key, dims, nodes, faces, contour, policy, host));
        }
    }

    /// The frame's globals (uniform buffer and bind group).
    fn globals_bind_group(&self, ctx: &GpuContext, globals: &Globals) -> wgpu::BindGroup {
        let d = &ctx.device;
        let globals_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("iso_globals"),
            contents: bytemuck::bytes_of(globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("iso_globals"),
            layout: &self.passes.globals_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: globals_buf.as_entire_binding() }],
        })
    }

    /// Implicit culling: the walk (on the host or in one compute pass; `host`, and `t_occ` the
    /// start of the occluder stage) marks the cells seen before the occlusion map; the visible
    /// nodes are the candidates with a cell seen.
    fn walk_nodes(
        &self,
        f: &Frame<'_>,
        candidates: &[NodeInfo],
        globals_bg: &wgpu::BindGroup,
        (host, t_occ): (bool, Instant),
        stats: &mut IsoStats,
    ) -> Result<Culled> {
        let FrameArgs { ctx, width, height, vol, tree, opts, .. } = f.args;
        let (maxd, occ_depth, cull_depth, w) = (f.maxd, f.occ_depth, f.cull_depth, f.w);
        let (plo, phi, eps, space) = (f.plo, f.phi, f.eps, &f.space);
        let d = &ctx.device;
        let tg = self.targets.as_ref().unwrap();
        let mut host_map = None;
        let grid = self.classes.as_ref().unwrap();
        stats.occluder_boxes_below = grid.n_below;
        stats.occluder_boxes_above = grid.n_above;
        stats.occluder_nodes_nan = grid.n_nan;
        // The walk steps through cells of the finer of the two depths.
        let md_march = occ_depth.max(cull_depth);
        // The walk places the contour of the faces it crosses (`passes::march` picks its
        // pipeline by the same test): a grid has contour bricks only with single-cell
        // occluders, whose cells the walk then steps through.
        let contour = grid.data.contour_at();
        debug_assert!(contour.is_none() || md_march == occ_depth);
        let cell = (1u64 << (maxd - md_march)) as f64;
        let size = DVec3::new(vol.spacing[0] * cell, vol.spacing[1] * cell, vol.spacing[2] * cell * space.z_scale);
        let march_dims = tree.dims_at_depth(md_march).expect("depth checked");
        let f4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let rays = pixel_rays(&f.view_proj, &f.fc, plo, phi);
        let (near_pl, far_pl) = (rays.near, rays.far);
        let p = MapParams {
            ray_o: f4(near_pl[0], 0.0),
            ray_ox: f4(near_pl[1], 0.0),
            ray_oy: f4(near_pl[2], 0.0),
            ray_d: f4(far_pl[0] - near_pl[0], 0.0),
            ray_dx: f4(far_pl[1] - near_pl[1], 0.0),
            ray_dy: f4(far_pl[2] - near_pl[2], 0.0),
            lo: f4(plo, eps.min(eps * space.z_scale)),
            hi: f4(phi, 1e-2),
            node: f4(size, 0.0),
            dims: [march_dims[0], march_dims[1], march_dims[2], width],
            // z: the walk reads the faces of the cells it crosses (march cells are the nodes).
            size: [height, md_march - occ_depth, u32::from(grid.faces && md_march == occ_depth), 1],
            occ_dims: [grid.dims[0], grid.dims[1], grid.dims[2], 0],
            contour: match contour {
                Some(at) => {
                    let [bx, by, _] = contour_grid([vol.nx, vol.ny, vol.nz]);
                    [at, bx as u32, by as u32, w.to_bits()]
                }
                None => [0; 4],
            },
            bricks: if opts.space_skipping { grid.bricks } else { [0; 4] },
        };
        stats.occluder_ms = t_occ.elapsed().as_secs_f64() * 1e3;
        let t_cull = Instant::now();
        let n_cells = march_dims.iter().map(|&v| v as usize).product();
        let marks = match &grid.data {
            WalkData::Host { nodes, skip, reach, huge, contour } => {
                let view_proj = Mat4::from_cols_array_2d(&f.globals.view_proj);
                let contour = contour.as_ref().map(|c| c.0.as_slice());
                let data = WalkGrid { nodes, skip, reach, huge: (&huge.0, huge.1), contour };
                let (marks, map, counts) = walk(&p, &view_proj, &data, width, height, n_cells);
                stats.walk_rays = counts.rays;
                stats.walk_steps = counts.steps;
                host_map = Some(map);
                marks
            }
            WalkData::Gpu { .. } => {
                let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("iso_map_params"),
                    contents: bytemuck::bytes_of(&p),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                stats.submissions += 1;
                stats.readbacks += 1;
                march(ctx, &self.passes, tg, globals_bg, grid, &params, n_cells)?
            }
        };
        stats.walk_on_host = Some(host);
        let bits = seen_cells(&marks, march_dims, &grid.classes, grid.dims, md_march - occ_depth);
        let shift = maxd - md_march;
        let counts: Vec<u32> = candidates.par_iter().map(|n| cells_seen(n, &bits, march_dims, shift)).collect();
        let seen = Some((bits, march_dims, shift));
        opts.interrupt.check()?;
        stats.nodes_tested = candidates.len() as u32;
        stats.nodes_tested_cull_depth = candidates.len() as u32;
        stats.cull_ms = t_cull.elapsed().as_secs_f64() * 1e3;
        let visible = candidates.iter().zip(&counts).filter(|(_, &c)| c > 0).map(|(n, _)| *n).collect();
        Ok(Culled { visible, node_pixels: counts, seen, host_map, untimed: Duration::ZERO })
    }

    /// Marching cubes in the visible nodes: through the patch cache, or (without it) only the
    /// cells some ray entered.
    fn extract(&mut self, f: &Frame<'_>, culled: &Culled, stats: &mut IsoStats) -> Vec<Arc<SurfacePatch>> {
        let (vol, w, visible) = (f.args.vol, f.w, &culled.visible);
        if f.args.opts.use_cache {
            let before = self.patches.len();
            let p = self.patches.get_or_extract_many(vol, w, visible);
            stats.patches_extracted = (self.patches.len() - before) as u32;
            stats.patches_cached = visible.len() as u32 - stats.patches_extracted;
            p
        } else {
            stats.patches_extracted = visible.len() as u32;
            let patches = match &culled.seen {
                // Nothing kept for later frames: only the cells some ray entered.
                Some((bits, mdims, shift)) => {
                    let seen_cell = |[i, j, k]: [usize; 3]| {
                        let m = ((k >> shift) * mdims[1] as usize + (j >> shift)) * mdims[0] as usize + (i >> shift);
                        bits[m / 32] >> (m % 32) & 1 == 1
                    };
                    crate::iso::march::extract_nodes_where(vol, w, visible, &seen_cell)
                }
                None => crate::iso::march::extract_nodes(vol, w, visible),
            };
            patches.into_iter().map(Arc::new).collect()
        }
    }

    /// The lit draw of the visible nodes' patches; returns the triangles and vertices drawn.
    fn draw(
        &mut self,
        f: &Frame<'_>,
        culled: &Culled,
        patches: &[Arc<SurfacePatch>],
        globals_bg: &wgpu::BindGroup,
    ) -> Result<(u64, u64)> {
        let (ctx, opts) = (f.args.ctx, f.args.opts);
        // Of the visible nodes' patches, only the cells some ray entered before the map.
        // (Patches extracted for this frame alone hold only those cells already.)
        let ranges: Option<Vec<Vec<[u32; 2]>>> =
            culled.seen.as_ref().filter(|_| opts.use_cache).map(|(bits, mdims, shift)| {
                culled
                    .visible
                    .par_iter()
                    .zip(patches)
                    .map(|(n, p)| visible_ranges(p, n, bits, *mdims, *shift))
                    .collect()
            });
        let Self { passes, targets, pool, .. } = &mut *self;
        let tg = targets.as_ref().unwrap();
        // Cached patches stay on the GPU between frames (the pool); patches extracted for this
        // frame only are uploaded with it.
        if opts.use_cache {
            draw_pooled(ctx, passes, pool, globals_bg, tg, patches, ranges.as_deref(), &f.space)
        } else {
            draw_surface(ctx, passes, globals_bg, tg, patches, ranges.as_deref(), &f.space)
        }
    }

    /// Copies the image, the depth and (implicit culling, when asked for) the map back and
    /// converts them to linear depth; `host_map` is the host walk's map.
    fn read_back(&self, f: &Frame<'_>, host_map: Option<Vec<f32>>) -> Result<ReadBack> {
        let FrameArgs { ctx, width, height, opts, .. } = f.args;
        let d = &ctx.device;
        let tg = self.targets.as_ref().unwrap();
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_readback") });
        let color_rb = ReadbackTexture::new(d, &mut enc, &tg.color_tex, width, height, 4, wgpu::TextureAspect::All);
        let depth_rb = ctx.read_depth(&mut enc, &tg.depth_tex);
        let map_rb = (opts.return_map && f.implicit && host_map.is_none()).then(|| {
            let b = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("iso_map_rb"),
                size: tg.map.size(),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.copy_buffer_to_buffer(&tg.map, 0, &b, 0, tg.map.size());
            b
        });
        ctx.queue.submit([enc.finish()]);
        for b in [&color_rb.buffer, depth_rb.buffer()].into_iter().chain(map_rb.as_ref()) {
            b.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        }
        ctx.wait()?;
        ctx.take_error()?;
        let image = color_rb.read_rows()?;
        let fc = &f.fc;
        let lin = |raw: Vec<f32>| -> Vec<f32> { raw.par_iter().map(|&v| fc.linear_depth(v)).collect() };
        let depth = lin(depth_rb.read()?);
        let mut map_out = None;
        if let Some(m) = &map_rb {
            let raw: Vec<f32> =
                bytemuck::cast_slice(&m.slice(..).get_mapped_range().map_err(crate::gpu::map_err)?).to_vec();
            map_out = Some(lin(raw));
        } else if let Some(m) = host_map.filter(|_| opts.return_map) {
            map_out = Some(lin(m));
        } else if opts.return_map {
            map_out = Some(vec![f32::INFINITY; (width * height) as usize]);
        }
        Ok((image, depth, map_out))
    }
}

/// The oracle's cells (read from the reference frame's depth; its own work is not the frame's):
/// the visible nodes are the candidates with one of its cells.
fn oracle_nodes(f: &Frame<'_>, candidates: &[NodeInfo], cells: &OracleCells) -> Culled {
    let FrameArgs { width, height, vol, tree, .. } = f.args;
    let t_or = Instant::now();
    let dims = tree.dims_at_depth(f.maxd).expect("max depth");
    let size = DVec3::new(vol.spacing[0], vol.spacing[1], vol.spacing[2] * f.space.z_scale);
    let rays = pixel_rays(&f.view_proj, &f.fc, f.plo, f.phi);
    let bits = visible_cells(cells, width, height, &rays, f.plo, size, dims, ORACLE_TOLERANCE);
    let counts: Vec<u32> = candidates.par_iter().map(|n| cells_seen(n, &bits, dims, 0)).collect();
    let seen = Some((bits, dims, 0));
    let visible = candidates.iter().zip(&counts).filter(|(_, &c)| c > 0).map(|(n, _)| *n).collect();
    let untimed = t_or.elapsed();
    Culled { visible, node_pixels: counts, seen, host_map: None, untimed }
}
