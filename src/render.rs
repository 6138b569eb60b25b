//! The frame pipeline: a [`Renderer`] draws a scene as named stages,
//! upload → strategy → draw → read-back, in one submission per frame:
//!
//! 1. `Renderer::upload`: the scene's geometry, when it changed since the last frame;
//! 2. the frame's camera and per-object state (offsets, colours, visibility: no re-upload);
//! 3. the culling strategy (`crate::cull`, chosen by name): untimed `prepare`, then
//!    `visible_set`, which may record GPU passes into the frame's encoder;
//! 4. `draw`: the lit fine pass of the visible set (one `multi_draw_indexed_indirect`);
//!    submit and wait: the frame time ends here;
//! 5. `Renderer::read_back`: image, linear depth, per-tile pixels, the draws made, stats.
//!
//! Isosurfaces ([`Renderer::render_isosurface`]) have their own passes in `crate::iso`, on the
//! same device.

mod background;
mod groups;
mod lenses;
mod levels;
mod options;

pub use background::Background;
pub use options::{
    GridLod, Lod, RenderOptions, RenderOutput, RenderStats, MAX_SHADING_LEVELS, MAX_TUBE_SHADING_LEVELS,
};

use lenses::draw_lenses;
use levels::{choose_levels, grid_stats};

use crate::camera::{Camera, FrameCamera};
use crate::cull::{self, CullStrategy, Draw, FrameInputs, FrameReport, Pixels, Stat, Visible};
use crate::error::{Error, Result};
use crate::gpu::{
    passes, readback, DrawArgs, Globals, GpuContext, GpuObject, Passes, SceneGeometry, Targets, Timestamps,
};
use crate::iso::render::{IsoOptions, IsoOutput, IsoRenderer};
use crate::iso::{MinMaxOctree, Volume};
use crate::lod::cos_sin_deg;
use crate::scene::{ColorSource, Scene};
use glam::{DVec3, Mat4};
use rayon::prelude::*;
use std::time::Instant;

/// Scenes of at least this many fine triangles may take long to draw (~0.1 s on llvmpipe): on GL
/// their frames are submitted so that Ctrl-C can stop them (`GpuContext::submit_and_wait`).
const LONG_FRAME_TRIANGLES: u64 = 1 << 20;

pub struct Renderer {
    ctx: GpuContext,
    width: u32,
    height: u32,
    /// The scene passes' pipelines, shared by the renderers on one device.
    passes: std::sync::Arc<Passes>,
    main_targets: Targets,
    /// Prepass targets, shared by the strategies that run a prepass (three_pass, temporal).
    prepass_targets: std::sync::Mutex<Option<Targets>>,
    geometry: Option<SceneGeometry>,
    timestamps: Option<Timestamps>,
    /// One instance of every registered strategy (they may cache between frames).
    strategies: Vec<Box<dyn CullStrategy>>,
    /// Isosurface pipelines and caches, created on first use.
    iso: Option<Box<IsoRenderer>>,
    /// Bytes each strategy's cache may keep between frames.
    cache_budget: u64,
    /// At most this many triangles per lit render pass (`None`: one pass), [`Self::set_pass_triangles`].
    pass_triangles: Option<u64>,
    /// Put into every image read back where nothing was drawn (`None`: the passes' black).
    background: Option<Background>,
}

impl Renderer {
    /// Opens the device and builds the pipelines for `width` × `height` images.
    pub fn new(width: u32, height: u32, backend: &str) -> Result<Self> {
        // Validate the cheap things before touching the driver.
        crate::error::ensure(width >= 1, "width", || format!("width is {width}; expected >= 1"))?;
        crate::error::ensure(height >= 1, "height", || format!("height is {height}; expected >= 1"))?;
        let strategies: Vec<Box<dyn CullStrategy>> = cull::REGISTRY.iter().map(|make| make()).collect();
        // SHADER_EARLY_DEPTH_TEST: the box test's cheaper variant (gpu::box_early), where available.
        let wanted = strategies.iter().fold(wgpu::Features::SHADER_EARLY_DEPTH_TEST, |f, s| f | s.required_features());
        let ctx = GpuContext::new(backend, wanted)?;
        ctx.check_image_size(width, height)?;
        let passes = ctx.per_device(Passes::new);
        let timestamps = ctx.timestamps.then(|| Timestamps::new(&ctx.device));
        let main_targets = Targets::new(&ctx.device, width, height, true);
        ctx.take_error()?;
        let cache_budget = cull::DEFAULT_CACHE_BUDGET;
        Ok(Self {
            ctx,
            width,
            height,
            passes,
            main_targets,
            prepass_targets: std::sync::Mutex::new(None),
            geometry: None,
            timestamps,
            strategies,
            iso: None,
            cache_budget,
            pass_triangles: None,
            background: None,
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }
    pub fn adapter_info(&self) -> String {
        self.ctx.adapter_description()
    }
    pub fn max_texture_size(&self) -> u32 {
        self.ctx.limits.max_texture_dimension_2d
    }
    /// Bytes each culling strategy may keep cached between frames (horizon: its trees).
    pub fn cache_budget(&self) -> u64 {
        self.cache_budget
    }
    /// Sets [`cache_budget`](Self::cache_budget); caches over it shrink at once.
    pub fn set_cache_budget(&mut self, bytes: u64) {
        self.cache_budget = bytes;
        self.strategies.iter_mut().for_each(|s| s.set_cache_budget(bytes));
    }
    /// At most this many triangles (an upper bound: the chosen levels' triangles of the tiles a
    /// pass may draw) per render pass of a frame's lit draws; `None` (the default) draws each in
    /// one pass. The image is the same. On a CPU driver (lavapipe, llvmpipe) the triangles binned
    /// for a pass stay in memory until its end, as many of the driver's 36 MB bins as its
    /// rasteriser threads lag behind: a bound caps that memory (the 3.9 M-triangle benchmark
    /// frame: 420 -> 280 MiB at 300,000) for 20-40 % more frame time there (each pass waits for
    /// its rasterisation). On a GPU it costs a little and saves nothing.
    pub fn pass_triangles(&self) -> Option<u64> {
        self.pass_triangles
    }
    /// Sets [`pass_triangles`](Self::pass_triangles) (`Some(0)` is refused: `None` is unbounded).
    pub fn set_pass_triangles(&mut self, max: Option<u64>) -> Result<()> {
        crate::error::ensure(max != Some(0), "pass_triangles", || {
            "pass_triangles is 0; expected >= 1, or None for one pass per draw".into()
        })?;
        self.pass_triangles = max;
        Ok(())
    }
    /// Sets the background put into every image where nothing was drawn: `rgb` one RGB8 colour
    /// per image row, top row first ([`Background`]); `None`: the passes' own black. Input error
    /// naming `background` when `rgb` is not 3 bytes per row of this renderer's images.
    pub fn set_background(&mut self, rgb: Option<&[u8]>) -> Result<()> {
        self.background = rgb.map(|c| Background::from_rows(c, self.height)).transpose()?;
        Ok(())
    }
    /// Bytes of scene geometry currently held on the GPU.
    pub fn gpu_bytes(&self) -> u64 {
        self.geometry.as_ref().map_or(0, |g| g.bytes)
    }

    /// Stage 1: uploads the scene's geometry if it changed since the last frame: only the objects
    /// replaced since then where nothing else changed and they keep their layout (a moved slice,
    /// [`SceneGeometry::patch`]), else all of it. Returns the objects rewritten in place (0 when
    /// nothing changed or all was uploaded).
    fn upload(&mut self, scene: &Scene) -> Result<u64> {
        let key = scene.geometry_key();
        if let Some(g) = self.geometry.as_mut() {
            if g.key == key {
                return Ok(0);
            }
            if let Some(mut ids) = (g.key.0 == key.0).then(|| scene.replaced_since(g.key.1)).flatten() {
                ids.sort_unstable();
                ids.dedup();
                if g.patch(&self.ctx, scene, &ids)? {
                    return Ok(ids.len() as u64);
                }
            }
        }
        self.geometry = None; // free the old buffers first
        self.geometry = Some(SceneGeometry::upload(&self.ctx, scene)?);
        Ok(0)
    }

    /// The frame's camera, relative to `origin`: near/far from the visible objects' world bounds.
    fn frame_camera(&self, camera: &Camera, origin: DVec3, world: Option<(DVec3, DVec3)>) -> FrameCamera {
        let zs = DVec3::new(1.0, 1.0, camera.z_scale);
        let bounds = world.map(|(lo, hi)| ((lo - origin) * zs, (hi - origin) * zs));
        camera.frame(origin, bounds, self.width as f64 / self.height as f64)
    }

    /// Renders `scene` from `camera` with the strategy `opts.culling`.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, opts: &RenderOptions) -> Result<RenderOutput> {
        opts.cull.validate()?;
        let si = self
            .strategies
            .iter()
            .position(|s| s.name() == opts.culling)
            .ok_or_else(|| cull::unknown(&opts.culling))?;
        let missing = self.strategies[si].required_features() - self.ctx.features;
        if !missing.is_empty() {
            return Err(Error::Device(format!(
                "culling={:?} needs the device features {missing:?}, which {} lacks",
                opts.culling,
                self.ctx.adapter_description()
            )));
        }
        // Work an interrupted frame left on the GPU finishes before this frame's clock starts.
        self.ctx.finish_pending(&opts.interrupt)?;
        let t0 = Instant::now();
        let patched = self.upload(scene)?;
        let upload_ms = t0.elapsed().as_secs_f64() * 1e3;
        opts.interrupt.check()?;
        let world = scene.visible_bounds(DVec3::ZERO);
        let origin = render_origin(world, camera);
        let fc = self.frame_camera(camera, origin, world);
        if let Some(ts) = self.timestamps.as_mut() {
            ts.begin_frame();
        }
        let Self {
            ctx,
            passes,
            main_targets,
            prepass_targets,
            geometry,
            timestamps,
            strategies,
            width,
            height,
            pass_triangles,
            ..
        } = self;
        let geometry = geometry.as_ref().expect("uploaded above");
        let (scene_bg, object_visible) =
            frame_state(ctx, passes, scene, camera, &fc, origin, geometry, (*width, *height));
        let tile_dist2 = geometry.eye_distances(scene, origin, fc.eye, camera.z_scale);
        let (mut draw_args, chosen) =
            choose_levels(geometry, scene, camera, &fc, &tile_dist2, *height, (opts.lod, opts.grid_lod), origin);
        // Grid blocks' interior faces (drawn last in each level) are left out when the grid lies
        // wholly beyond the near plane.
        let outside = scene.seen_from_outside(origin, (fc.eye, fc.forward, fc.near), camera.z_scale);
        let interior = scene
            .grid_interior_indices(&outside, |t| chosen.as_ref().and_then(|c| c.0.get(t)).map_or(0, |&l| l as usize));
        for (a, &n) in draw_args.iter_mut().zip(&interior) {
            a.index_count -= n.min(a.index_count);
        }
        let pass_breaks = passes::pass_breaks(draw_args.iter().map(|a| a.index_count), *pass_triangles);
        let draw_runs = geometry.frame_runs(scene, &draw_args);
        let fine_depth_tiles: usize = draw_runs.iter().filter(|r| r.fine_depth).map(|r| r.tiles.len()).sum();
        let inputs = FrameInputs {
            ctx,
            passes,
            scene,
            camera,
            fc: &fc,
            origin,
            geometry,
            draw_args: &draw_args,
            tile_dist2: &tile_dist2,
            scene_bg: &scene_bg,
            object_visible: &object_visible,
            outside: &outside,
            draw_runs: &draw_runs,
            pass_breaks: &pass_breaks,
            width: *width,
            height: *height,
            main_targets,
            prepass_targets,
            options: &opts.cull,
            timestamps: timestamps.as_ref(),
        };
        let strategy = &mut strategies[si];
        let tp = Instant::now();
        strategy.prepare(&inputs)?;
        let untimed = tp.elapsed();
        let mut enc = ctx.encoder("frame");
        let tc = Instant::now();
        let visible = strategy.visible_set(&inputs, &mut enc)?;
        let cull_ms = tc.elapsed().as_secs_f64() * 1e3;
        opts.interrupt.check()?;
        let final_args = draw(&inputs, &mut enc, &visible);
        let lenses = draw_lenses(&inputs, &mut enc);
        let ts_rb = timestamps.as_ref().and_then(|t| t.resolve(&ctx.device, &mut enc));
        ctx.submit_and_wait(enc.finish(), &opts.interrupt, geometry.fine_triangles() >= LONG_FRAME_TRIANGLES)?;
        let lens_stats = lenses.map(|l| l.stats(ctx)).transpose()?;
        let total_ms = (t0.elapsed() - untimed).as_secs_f64() * 1e3;
        ctx.take_error()?;
        let mut out = self.read_back(&fc, visible, &final_args, ts_rb)?;
        out.stats.cull_ms = cull_ms;
        out.stats.total_ms = total_ms;
        let report = FrameReport {
            tile_drawn: &out.tile_drawn,
            tile_pixels: &out.tile_pixels,
            tile_counts: &out.tile_counts,
            width: out.width,
            height: out.height,
        };
        let extra = self.strategies[si].report(&report);
        out.stats.extra.push(("upload_ms", Stat::Float(upload_ms)));
        out.stats.extra.push(("objects_patched", Stat::Count(patched)));
        out.stats.extra.push(("draw_passes", Stat::Count(pass_breaks.len() as u64 + 1)));
        if chosen.is_some() {
            out.stats.extra.push(("tiles_fine_depth", Stat::Count(fine_depth_tiles as u64)));
        }
        out.stats.extra.extend(extra);
        grid_stats(scene, &mut out, chosen.as_ref().map(|c| &c.0[..]), &interior);
        out.stats.extra.extend(lens_stats.unwrap_or_default());
        if let Some((level, err_px)) = chosen {
            self.lod_stats(&mut out, &level, &err_px, &draw_args);
            out.tile_counts.push(("tile_level", level.iter().map(|&l| l as u32).collect()));
            out.arrays.push(("tile_error_px", err_px));
        }
        Ok(out)
    }

    /// Stage 5: image, depth, per-tile counts and the draws made, copied back and converted
    /// (not part of the frame time). Counts the final image's tiles when the strategy asks for it.
    fn read_back(
        &self,
        fc: &FrameCamera,
        visible: Visible,
        final_args: &wgpu::Buffer,
        ts_rb: Option<wgpu::Buffer>,
    ) -> Result<RenderOutput> {
        let t1 = Instant::now();
        let (ctx, mt) = (&self.ctx, &self.main_targets);
        let d = &ctx.device;
        let geom = self.geometry.as_ref().expect("uploaded");
        let n = geom.n_tiles();
        let (w, h) = (self.width, self.height);
        let mut enc = ctx.encoder("readback");
        let counted = match &visible.pixels {
            Pixels::FinalImage => {
                let c = passes::counts_buffer(d, n);
                enc.clear_buffer(&c, 0, None);
                self.passes.record_histogram(d, &mut enc, &mt.id, (w, h), &c, None);
                Some((readback::copy_buffer(d, &mut enc, &c, 4 * n.max(1) as u64), 1.0))
            }
            Pixels::Gpu { counts, scale } => {
                Some((readback::copy_buffer(d, &mut enc, counts, 4 * n.max(1) as u64), *scale))
            }
            Pixels::Host(_) => None,
        };
        let color_rb = readback::ReadbackTexture::new(
            d,
            &mut enc,
            mt.color_tex.as_ref().unwrap(),
            w,
            h,
            4,
            wgpu::TextureAspect::All,
        );
        let depth_rb = ctx.read_depth(&mut enc, &mt.depth_tex);
        let args_bytes = (n.max(1) * std::mem::size_of::<DrawArgs>()) as u64;
        let args_rb = readback::copy_buffer(d, &mut enc, final_args, args_bytes);
        let pre_rb = visible.predrawn.as_ref().map(|b| readback::copy_buffer(d, &mut enc, b, args_bytes));
        let counts_rb: Vec<(&'static str, wgpu::Buffer)> = visible
            .tile_counts
            .iter()
            .map(|(name, b)| (*name, readback::copy_buffer(d, &mut enc, b, 4 * n.max(1) as u64)))
            .collect();
        ctx.queue.submit([enc.finish()]);
        readback::map_all(
            [&color_rb.buffer, depth_rb.buffer(), &args_rb]
                .into_iter()
                .chain(counted.as_ref().map(|c| &c.0))
                .chain(ts_rb.as_ref())
                .chain(pre_rb.as_ref())
                .chain(counts_rb.iter().map(|(_, b)| b)),
        );
        ctx.wait()?;
        ctx.take_error()?;
        let mut image = color_rb.read_rows()?;
        let depth: Vec<f32> = depth_rb.read()?.par_iter().map(|&v| fc.linear_depth(v)).collect();
        if let Some(bg) = &self.background {
            bg.fill(&mut image, &depth);
        }
        let tile_pixels: Vec<u32> = match (visible.pixels, counted) {
            (Pixels::Host(c), _) => c,
            (_, Some((buf, scale))) => {
                let mut c: Vec<u32> = readback::read_mapped(&buf)?;
                c.truncate(n);
                if scale == 1.0 {
                    c
                } else {
                    c.iter().map(|&v| (v as f64 * scale).round() as u32).collect()
                }
            }
            _ => unreachable!("counts are read back for every other kind"),
        };
        let on = |a: &DrawArgs| a.instance_count > 0 && a.index_count > 0;
        let mut drawn: Vec<DrawArgs> = readback::read_mapped(&args_rb)?;
        drawn.truncate(n);
        let mut extra = Vec::new();
        if let Some(pre) = &pre_rb {
            // Tiles drawn by the strategy's own first phase, then by the final pass.
            let pre: Vec<DrawArgs> = readback::read_mapped(pre)?;
            extra.push(("tiles_drawn_first", Stat::Count(pre[..n].iter().filter(|a| on(a)).count() as u64)));
            extra.push(("tiles_drawn_second", Stat::Count(drawn.iter().filter(|a| on(a)).count() as u64)));
            for (a, p) in drawn.iter_mut().zip(&pre[..n]) {
                if on(p) {
                    *a = *p;
                }
            }
        }
        let tile_counts = counts_rb
            .iter()
            .map(|(name, b)| {
                let mut c: Vec<u32> = readback::read_mapped(b)?;
                c.truncate(n);
                Ok((*name, c))
            })
            .collect::<Result<Vec<_>>>()?;
        let tile_drawn: Vec<bool> = drawn.iter().map(on).collect();
        let mut stats = RenderStats {
            triangles_fine_total: geom.fine_triangles(),
            triangles_drawn: drawn.iter().map(|a| a.triangles()).sum(),
            extra,
            tiles_total: n as u32,
            tiles_drawn: tile_drawn.iter().filter(|&&b| b).count() as u32,
            gpu_timestamps: ts_rb.is_some(),
            ..Default::default()
        };
        if let (Some(b), Some(ts)) = (&ts_rb, &self.timestamps) {
            for (name, ms) in ts.read(b, ctx.queue.get_timestamp_period())? {
                if name == "draw_ms" {
                    stats.draw_ms = ms;
                } else {
                    stats.extra.push((name, Stat::Ms(ms)));
                }
            }
        }
        stats.extra.extend(visible.stats);
        stats.readback_ms = t1.elapsed().as_secs_f64() * 1e3;
        Ok(RenderOutput {
            width: w,
            height: h,
            image,
            depth,
            tile_pixels,
            tile_drawn,
            stats,
            near: fc.near,
            far: fc.far,
            arrays: visible.arrays,
            tile_counts,
        })
    }

    /// Drops cached isosurface patches and occluders.
    pub fn clear_isosurface_cache(&mut self) {
        if let Some(g) = self.iso.as_mut() {
            g.clear_cache();
        }
    }

    /// Renders the isosurface `vol = w` (in the volume's units: converted to the volume's f32
    /// residuals about its f64 offset by `crate::iso`) seen by `camera`; `tree` must be the octree
    /// of `vol`. See `crate::iso::render` for what `culling = Implicit` does.
    pub fn render_isosurface(
        &mut self,
        vol: &Volume,
        tree: &MinMaxOctree,
        w: f64,
        camera: &Camera,
        opts: &IsoOptions,
    ) -> Result<IsoOutput> {
        let iso = self.iso.get_or_insert_with(|| Box::new(IsoRenderer::new(&self.ctx)));
        let mut out = iso.render(&self.ctx, self.width, self.height, vol, tree, w, camera, opts)?;
        if let Some(bg) = &self.background {
            let t = Instant::now();
            bg.fill(&mut out.image, &out.depth);
            out.stats.readback_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        Ok(out)
    }
}

/// The origin of a frame's render space (world, f64): the point of the visible objects' bounds
/// nearest to the camera's eye (the eye itself when it is inside them), rounded to a metre. What
/// is nearest the camera then has the full precision of f32 positions relative to it, whatever the
/// objects' coordinates, offsets and insertion order (each object's offset from it is computed in
/// f64, [`crate::scene::Object::placement`]).
fn render_origin(visible: Option<(DVec3, DVec3)>, camera: &Camera) -> DVec3 {
    match visible {
        Some((lo, hi)) => camera.eye.clamp(lo, hi).round(),
        None => camera.eye.round(),
    }
}

/// The world size of one of a `width` × `height` image's pixels at clip w = 1 under `view_proj`
/// (render space to clip space), the larger of a column's and a row's: NDC per world unit along
/// the view's x (y) axis is the length of the matrix's row 0 (1) over w, and a pixel spans 2 /
/// width (2 / height) of NDC.
fn pixel_world(view_proj: &glam::DMat4, (width, height): (u32, u32)) -> f64 {
    let row = |r: usize| view_proj.row(r).truncate().length();
    (2.0 / width as f64 / row(0)).max(2.0 / height as f64 / row(1))
}

/// Stage 2: the scene bind group of this frame (uniforms, per-object offsets and colours) and
/// the per-tile object visibility.
#[allow(clippy::too_many_arguments)]
fn frame_state(
    ctx: &GpuContext,
    passes: &Passes,
    scene: &Scene,
    camera: &Camera,
    fc: &FrameCamera,
    origin: DVec3,
    geom: &SceneGeometry,
    (width, height): (u32, u32),
) -> (wgpu::BindGroup, Vec<bool>) {
    let objects = scene.objects();
    // Colour maps: tables of 256 rows, then the NaN colour, one per distinct map.
    let mut lut = crate::gpu::ColorTables::default();
    let gpu_objects: Vec<GpuObject> = objects
        .iter()
        .enumerate()
        .map(|(oi, o)| {
            let p = o.placement(origin);
            let cmap = match &o.color_by {
                None => [0.0; 4],
                Some(c) => {
                    let table = lut.table(&c.lut, c.nan_color) as f32;
                    let (lo, mode) = match c.source {
                        // z relative to the object's origin, as the vertices are.
                        ColorSource::Z => (c.clim[0] - o.origin.z, 2.0),
                        ColorSource::Values => (c.clim[0], 1.0),
                    };
                    [lo as f32, (1.0 / (c.clim[1] - c.clim[0])) as f32, mode, table]
                }
            };
            let (mut grid, mut grid_rows, mut normal_map) = ([0.0; 4], [0.0; 4], [0; 4]);
            if let (Some(hf), Some(base)) = (o.heightfield(), geom.shading_base[oi]) {
                let (c, s) = cos_sin_deg(hf.rotation);
                grid = [hf.x0 as f32, hf.y0 as f32, (c / hf.dx) as f32, (s / hf.dx) as f32];
                grid_rows = [(-s / hf.dy) as f32, (c / hf.dy) as f32, hf.nx as f32, hf.ny as f32];
                normal_map[0] = base + 1;
            }
            normal_map[1] = u32::from(o.tiles.iter().any(|t| !t.normals.is_empty()));
            // A grid coloured per cell by its values (`grid::cells`); by z it takes its vertices'.
            let by_values = o.color_by.as_ref().is_some_and(|c| c.source == ColorSource::Values);
            if geom.table_colors[oi] && by_values && !geom.log_colors[oi] {
                normal_map[1] = 3;
            }
            // A well whose vertices carry their stations, its log a table (`gpu::cell_values`).
            normal_map[3] = u32::from(geom.log_colors[oi] && by_values);
            if let (Some((nu, nv)), Some(base)) = (geom.grid_dims[oi], geom.shading_base[oi]) {
                grid_rows = [0.0, 0.0, nu as f32, nv as f32];
                normal_map = [base + 1, 2, 0, 0];
            }
            normal_map[2] = o.priority() as u32;
            GpuObject {
                offset: [p.x as f32, p.y as f32, p.z as f32, 0.0],
                color: [o.color[0], o.color[1], o.color[2], o.opacity],
                cmap,
                grid,
                grid_rows,
                normal_map,
            }
        })
        .collect();
    let light = fc.light_dir();
    let globals = Globals {
        view_proj: Mat4::from_cols_array(&fc.view_proj.to_cols_array().map(|v| v as f32)).to_cols_array_2d(),
        light_dir: [light.x as f32, light.y as f32, light.z as f32, 0.0],
        z_scale: camera.z_scale as f32,
        ortho_near: match fc.projection {
            crate::camera::Projection::Orthographic => (fc.near / (fc.far - fc.near)) as f32,
            crate::camera::Projection::Perspective => -1.0,
        },
        pixel_world: [pixel_world(&fc.view_proj, (width, height)) as f32, 0.0],
        eye: match fc.projection {
            crate::camera::Projection::Orthographic => {
                [fc.forward.x as f32, fc.forward.y as f32, fc.forward.z as f32, 0.0]
            }
            crate::camera::Projection::Perspective => [fc.eye.x as f32, fc.eye.y as f32, fc.eye.z as f32, 1.0],
        },
    };
    // Translucent objects (lenses) are no occluders: strategies see them as hidden; draw_lenses
    // draws them after the opaque image.
    let visible = geom
        .tile_object_cpu
        .iter()
        .map(|&oi| objects[oi as usize].visible && objects[oi as usize].opacity >= 1.0)
        .collect();
    (passes.scene_bind_group(ctx, &globals, &gpu_objects, &lut, geom), visible)
}

/// Stage 4: records the lit fine pass of the visible set; returns the args it draws.
fn draw(f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder, visible: &Visible) -> wgpu::Buffer {
    let d = &f.ctx.device;
    let args = match &visible.draw {
        Draw::All => passes::args_buffer(d, "draw_args", &f.pick(f.draw_args, |_| true)),
        Draw::Mask(m) => passes::args_buffer(d, "draw_args", &f.pick(f.draw_args, |i| m[i])),
        Draw::Gpu(b) => b.clone(),
    };
    let load = visible.predrawn.is_some();
    f.passes.record_draw(
        enc,
        f.main_targets,
        f.scene_bg,
        f.geometry,
        &args,
        load,
        f.draw_runs,
        f.outside,
        f.pass_breaks,
        f.timestamps,
    );
    args
}

#[cfg(test)]
mod tests;
