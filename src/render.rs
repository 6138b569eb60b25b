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

use crate::camera::{Camera, FrameCamera};
use crate::cull::{self, CullOptions, CullStrategy, Draw, FrameInputs, FrameReport, Pixels, Stat, Visible};
use crate::error::{Error, Interrupt, Result};
use crate::gpu::{
    passes, readback, DrawArgs, Globals, GpuContext, GpuObject, Passes, SceneGeometry, Targets, Timestamps,
};
use crate::iso::render::{IsoOptions, IsoOutput, IsoRenderer};
use crate::iso::{MinMaxOctree, Volume};
use crate::lod::cos_sin_deg;
use crate::scene::{ColorSource, ObjectKind, Scene};
use glam::{DVec3, Mat4};
use rayon::prelude::*;
use std::time::Instant;

/// Which level of detail each drawn tile uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lod {
    /// Level 0 (the fine triangles) everywhere: the reference.
    Full,
    /// The coarsest level whose geometric error projects to at most `max_pixel_error` pixels at
    /// the tile's nearest point (`crate::lod::levels`) and whose shading error changes the lit
    /// colour by at most [`MAX_SHADING_LEVELS`].
    ScreenError { max_pixel_error: f64 },
}

/// The most a level of detail may change a pixel's lit colour, in 8-bit levels per channel:
/// a level is taken only if its shading error (`crate::lod::shading`, a normal chord) times the
/// object's levels per chord (`lod::shading::shade_levels_per_chord`: its brightest colour, the
/// vertical exaggeration) stays within it. Height fields shade from their fine surface at every
/// level (shading error 0), so only meshes' levels are held back.
pub const MAX_SHADING_LEVELS: f64 = 0.5;

impl Lod {
    pub fn parse(name: &str, max_pixel_error: f64) -> Result<Self> {
        match name {
            "full" => Ok(Self::Full),
            "screen_error" => {
                crate::error::ensure(max_pixel_error.is_finite() && max_pixel_error > 0.0, "max_pixel_error", || {
                    format!("max_pixel_error is {max_pixel_error}; expected pixels > 0")
                })?;
                Ok(Self::ScreenError { max_pixel_error })
            }
            _ => Err(crate::error::input_err(
                "lod",
                format!("unknown lod {name:?}; expected \"full\" or \"screen_error\""),
            )),
        }
    }
}

/// Which level of detail each block of a reservoir grid uses (`crate::grid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridLod {
    /// Level 0 (every boundary face of the active cells).
    Full,
    /// The paper's view-distance ranges (`crate::grid::distance_level`), `alpha` in [8, 15],
    /// `lambda` in [2, 3], the distance taken from the eye to the block's centre.
    Distance { alpha: f64, lambda: f64 },
    /// As `Lod::ScreenError`: the coarsest level whose geometric error projects to at most
    /// `max_pixel_error` pixels at the block's nearest point.
    ScreenError { max_pixel_error: f64 },
}

impl GridLod {
    pub fn parse(name: &str, alpha: f64, lambda: f64, max_pixel_error: f64) -> Result<Self> {
        match name {
            "full" => Ok(Self::Full),
            "distance" => {
                crate::grid::validate_alpha_lambda(alpha, lambda)?;
                Ok(Self::Distance { alpha, lambda })
            }
            "screen_error" => match Lod::parse("screen_error", max_pixel_error)? {
                Lod::ScreenError { max_pixel_error } => Ok(Self::ScreenError { max_pixel_error }),
                Lod::Full => unreachable!("parsed as screen_error"),
            },
            _ => Err(crate::error::input_err(
                "grid_lod",
                format!("unknown grid_lod {name:?}; expected \"full\", \"distance\" or \"screen_error\""),
            )),
        }
    }
}

/// Scenes of at least this many fine triangles may take long to draw (~0.1 s on llvmpipe): on GL
/// their frames are submitted so that Ctrl-C can stop them (`GpuContext::submit_and_wait`).
const LONG_FRAME_TRIANGLES: u64 = 1 << 20;

/// How to render one frame.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// A registered strategy's name (`crate::cull::names()`).
    pub culling: String,
    pub cull: CullOptions,
    pub lod: Lod,
    /// The level of detail of reservoir grids' blocks (height fields and meshes follow `lod`).
    pub grid_lod: GridLod,
    /// Polled between the stages of the frame and while waiting for the GPU; when it fires,
    /// `render` returns `Error::Interrupted` and the renderer stays usable (`crate::error::Interrupt`).
    pub interrupt: Interrupt,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            culling: "none".into(),
            cull: CullOptions::default(),
            lod: Lod::Full,
            grid_lod: GridLod::Full,
            interrupt: Interrupt::default(),
        }
    }
}

/// Names of the per-level triangle counts in the stats (`triangles_level{l}`).
const LEVEL_STATS: [&str; 1 + crate::lod::levels::MAX_LEVELS] = [
    "triangles_level0",
    "triangles_level1",
    "triangles_level2",
    "triangles_level3",
    "triangles_level4",
    "triangles_level5",
];

impl RenderOptions {
    /// `culling` with the default options.
    pub fn culling(name: &str) -> Self {
        Self { culling: name.into(), ..Default::default() }
    }
}

/// Timings and counts of one frame.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub triangles_fine_total: u64,
    /// Fine triangles of the tiles drawn by the final pass.
    pub triangles_drawn: u64,
    pub tiles_total: u32,
    pub tiles_drawn: u32,
    /// CPU time of the strategy's `visible_set` (CPU culling, or recording its GPU passes), ms.
    pub cull_ms: f64,
    /// GPU time of the final pass (timestamps; 0 where the adapter has none), ms.
    pub draw_ms: f64,
    /// Wall time from the call to the GPU finishing the frame (no read-back, no untimed
    /// `prepare`), ms.
    pub total_ms: f64,
    /// Wall time to copy the image, depth and counts back and convert them, ms.
    pub readback_ms: f64,
    pub gpu_timestamps: bool,
    /// GPU times of the strategy's passes by name (e.g. "prepass_ms") and the strategy's own
    /// stats (e.g. "nodes_visited").
    pub extra: Vec<(&'static str, Stat)>,
}

impl RenderStats {
    /// A named extra stat, if the frame has it.
    pub fn get(&self, name: &str) -> Option<Stat> {
        self.extra.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
    }
}

/// The result of one frame, as plain host arrays.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, row 0 = top.
    pub image: Vec<u8>,
    /// Distance along the view axis (render-space units), +inf where empty.
    pub depth: Vec<f32>,
    /// Per tile: the pixel counts the strategy decided on, in full-image pixels (three_pass: the
    /// pass-2 counts of the coarse proxies; oracle: the unculled image's); for strategies that
    /// count no pixels (none, horizon), the final image's.
    pub tile_pixels: Vec<u32>,
    pub tile_drawn: Vec<bool>,
    pub stats: RenderStats,
    pub near: f64,
    pub far: f64,
    /// The strategy's per-frame arrays by name (horizon: "horizon", one value per column).
    pub arrays: Vec<(&'static str, Vec<f32>)>,
    /// The strategy's per-tile counts by name (three_pass: "box_pixels").
    pub tile_counts: Vec<(&'static str, Vec<u32>)>,
}

impl RenderOutput {
    pub fn array(&self, name: &str) -> Option<&[f32]> {
        self.arrays.iter().find(|(n, _)| *n == name).map(|(_, a)| a.as_slice())
    }
}

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
        let (scene_bg, object_visible) = frame_state(ctx, passes, scene, camera, &fc, origin, geometry);
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
        out.stats.extra.extend(extra);
        grid_stats(scene, &mut out, chosen.as_ref().map(|c| &c.0[..]), &interior);
        out.stats.extra.extend(lens_stats.unwrap_or_default());
        if let Some((level, err_px)) = chosen {
            self.lod_stats(&mut out, &level, &err_px);
            out.tile_counts.push(("tile_level", level.iter().map(|&l| l as u32).collect()));
            out.arrays.push(("tile_error_px", err_px));
        }
        Ok(out)
    }

    /// LOD stats of a frame: triangles drawn per level, the largest error used (pixels, metres).
    fn lod_stats(&self, out: &mut RenderOutput, level: &[u8], err_px: &[f32]) {
        let g = self.geometry.as_ref().expect("uploaded");
        let mut tris = [0u64; LEVEL_STATS.len()];
        let (mut max_px, mut max_m) = (0.0f64, 0.0f64);
        for (i, &drawn) in out.tile_drawn.iter().enumerate() {
            if !drawn {
                continue;
            }
            let l = level[i] as usize;
            let (args, err) =
                if l == 0 { (g.fine[i], 0.0) } else { (g.levels[i][l - 1].args, g.levels[i][l - 1].error) };
            tris[l] += args.index_count as u64 / 3;
            max_px = max_px.max(err_px[i] as f64);
            max_m = max_m.max(err as f64);
        }
        for (name, t) in LEVEL_STATS.iter().zip(tris) {
            out.stats.extra.push((name, Stat::Count(t)));
        }
        out.stats.extra.push(("lod_max_error_px", Stat::Float(max_px)));
        out.stats.extra.push(("lod_max_error_m", Stat::Float(max_m)));
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
        let image = color_rb.read_rows()?;
        let depth: Vec<f32> = depth_rb.read()?.par_iter().map(|&v| fc.linear_depth(v)).collect();
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
        iso.render(&self.ctx, self.width, self.height, vol, tree, w, camera, opts)
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
) -> (wgpu::BindGroup, Vec<bool>) {
    let objects = scene.objects();
    // Colour maps: 256 rows per coloured object, then its NaN colour.
    let mut lut: Vec<[f32; 4]> = Vec::new();
    let gpu_objects: Vec<GpuObject> = objects
        .iter()
        .enumerate()
        .map(|(oi, o)| {
            let p = o.placement(origin);
            let cmap = match &o.color_by {
                None => [0.0; 4],
                Some(c) => {
                    let base = lut.len() as f32;
                    lut.extend(c.lut.iter().chain(std::iter::once(&c.nan_color)).map(|r| [r[0], r[1], r[2], 1.0]));
                    let (lo, mode) = match c.source {
                        // z relative to the object's origin, as the vertices are.
                        ColorSource::Z => (c.clim[0] - o.origin.z, 2.0),
                        ColorSource::Values => (c.clim[0], 1.0),
                    };
                    [lo as f32, (1.0 / (c.clim[1] - c.clim[0])) as f32, mode, base]
                }
            };
            let (mut grid, mut grid_rows, mut normal_map) = ([0.0; 4], [0.0; 4], [0; 4]);
            if let (ObjectKind::Heightfield { nx, ny, x0, y0, dx, dy, rotation, .. }, Some(base)) =
                (&o.kind, geom.shading_base[oi])
            {
                let (c, s) = cos_sin_deg(*rotation);
                grid = [*x0 as f32, *y0 as f32, (c / dx) as f32, (s / dx) as f32];
                grid_rows = [(-s / dy) as f32, (c / dy) as f32, *nx as f32, *ny as f32];
                normal_map[0] = base + 1;
            }
            normal_map[1] = u32::from(o.tiles.iter().any(|t| !t.normals.is_empty()));
            // A grid coloured per cell by its values (`grid::cells`); by z it takes its vertices'.
            if geom.cell_colors[oi] && o.color_by.as_ref().is_some_and(|c| c.source == ColorSource::Values) {
                normal_map[1] = 3;
            }
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
        _pad: [0.0; 2],
    };
    // Translucent objects (lenses) are no occluders: strategies see them as hidden; draw_lenses
    // draws them after the opaque image.
    let visible = geom
        .tile_object_cpu
        .iter()
        .map(|&oi| objects[oi as usize].visible && objects[oi as usize].opacity >= 1.0)
        .collect();
    (passes.scene_bind_group(&ctx.device, &globals, &gpu_objects, &lut, geom), visible)
}

/// Per tile: the level chosen (0 = fine) and its error in pixels.
type ChosenLevels = (Vec<u8>, Vec<f32>);

/// Stage 2b: the level of detail of every tile for this frame, and with `Lod::ScreenError` each
/// tile's chosen level and its error in pixels. The error of a level (world units) is scaled by the
/// exaggeration where that enlarges it and projected at the tile box's nearest point (perspective)
/// or with the orthographic scale; a box that contains the eye gets level 0. Cheap on the CPU (one
/// pass over the tiles), so it runs there, before the strategy, with no read-back.
#[allow(clippy::too_many_arguments)]
fn choose_levels(
    g: &SceneGeometry,
    scene: &Scene,
    camera: &Camera,
    fc: &FrameCamera,
    dist2: &[f64],
    height: u32,
    (lod, grid_lod): (Lod, GridLod),
    origin: DVec3,
) -> (Vec<DrawArgs>, Option<ChosenLevels>) {
    // Per tile: the grid block's leaf cell size, None for tiles of other objects.
    let mut grid_cell: Vec<Option<(f64, f64)>> = Vec::with_capacity(g.n_tiles());
    for o in scene.objects() {
        match &o.kind {
            ObjectKind::Grid(info) => grid_cell.extend(info.cell_size.iter().map(|&c| Some(c))),
            _ => grid_cell.extend(std::iter::repeat_n(None, o.tiles.len())),
        }
    }
    let any_grid = grid_cell.iter().any(|c| c.is_some());
    if lod == Lod::Full && (grid_lod == GridLod::Full || !any_grid) {
        return (g.fine.clone(), None);
    }
    let proj = fc.view_proj * fc.view.inverse();
    let px_per_unit = proj.y_axis.y.abs() * height as f64 / 2.0;
    let perspective = fc.projection == crate::camera::Projection::Perspective;
    let zs = camera.z_scale.max(1.0);
    let zv = DVec3::new(1.0, 1.0, camera.z_scale);
    let objects = scene.objects();
    // Per object, 8-bit colour levels per unit of shading error.
    let shade_levels: Vec<f64> = objects
        .iter()
        .map(|o| crate::lod::shading::shade_levels_per_chord(o.max_color_channel() as f64, camera.z_scale))
        .collect();
    let mut args = Vec::with_capacity(g.n_tiles());
    let (mut level, mut err_px) = (Vec::with_capacity(g.n_tiles()), Vec::with_capacity(g.n_tiles()));
    for (i, &d2) in dist2.iter().enumerate() {
        let scale = if perspective {
            if d2 > 0.0 {
                zs * px_per_unit / d2.sqrt()
            } else {
                f64::INFINITY
            }
        } else {
            zs * px_per_unit
        };
        let px_of = |lerr: f32| if lerr == 0.0 { 0.0 } else { lerr as f64 * scale };
        let per_chord = shade_levels[g.tile_object_cpu[i] as usize];
        // The coarsest level within `max_px` pixels of error and MAX_SHADING_LEVELS of colour.
        let screen = |max_px: f64| {
            let mut l = 0usize;
            for (k, lv) in g.levels[i].iter().enumerate() {
                if px_of(lv.error) > max_px || lv.shading_error as f64 * per_chord > MAX_SHADING_LEVELS {
                    break;
                }
                l = k + 1;
            }
            l
        };
        let l = match (grid_cell.get(i).copied().flatten(), grid_lod, lod) {
            (Some(_), GridLod::Full, _) | (None, _, Lod::Full) => 0,
            (Some(cell), GridLod::Distance { alpha, lambda }, _) => {
                let (lo, hi) = g.bbox[i];
                let off = objects[g.tile_object_cpu[i] as usize].placement(origin);
                let centre = ((lo + hi) * 0.5 + off) * zv;
                let d = (centre - fc.eye).length();
                crate::grid::distance_level(d, cell, alpha, lambda, g.levels[i].len())
            }
            (Some(_), GridLod::ScreenError { max_pixel_error }, _) => screen(max_pixel_error),
            (None, _, Lod::ScreenError { max_pixel_error }) => screen(max_pixel_error),
        };
        let (a, e) =
            if l == 0 { (g.fine[i], 0.0) } else { (g.levels[i][l - 1].args, px_of(g.levels[i][l - 1].error) as f32) };
        args.push(a);
        level.push(l as u8);
        err_px.push(e);
    }
    (args, Some((level, err_px)))
}

/// What [`draw_lenses`] recorded: per lens slice tested, its count read back after the frame.
struct LensFrame {
    counts: wgpu::Buffer,
    /// Per tested slice, the lens (object index) it belongs to.
    lens_of: Vec<usize>,
}

impl LensFrame {
    /// `lens_slices_tested`, `lens_slices_drawn`, `lenses_hidden` (wholly behind the opaque image).
    fn stats(&self, ctx: &GpuContext) -> Result<Vec<(&'static str, Stat)>> {
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
fn draw_lenses(f: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Option<LensFrame> {
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
        let lens = o.kind_name() == "lens";
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

/// Names of the per-level cell and face counts of grids (`grid_cells_level{l}`, `grid_faces_level{l}`).
const GRID_STATS: [[&str; 2]; 1 + crate::lod::levels::MAX_LEVELS] = [
    ["grid_cells_level0", "grid_faces_level0"],
    ["grid_cells_level1", "grid_faces_level1"],
    ["grid_cells_level2", "grid_faces_level2"],
    ["grid_cells_level3", "grid_faces_level3"],
    ["grid_cells_level4", "grid_faces_level4"],
    ["grid_cells_level5", "grid_faces_level5"],
];

/// Grids' merged cells and faces drawn per level, over the drawn blocks (only when the scene has
/// a grid), and `grid_interior_triangles_skipped`: the interior triangles of drawn blocks left out
/// (`interior`: indices per tile). `level`: each tile's level (None = all 0).
fn grid_stats(scene: &Scene, out: &mut RenderOutput, level: Option<&[u8]>, interior: &[u32]) {
    let mut sums = [[0u64; 2]; GRID_STATS.len()];
    let skipped: u64 =
        (interior.iter().zip(&out.tile_drawn).filter(|(_, &d)| d).map(|(&n, _)| n as u64).sum::<u64>()) / 3;
    let (mut any, mut t) = (false, 0usize);
    for o in scene.objects() {
        let ObjectKind::Grid(info) = &o.kind else {
            t += o.tiles.len();
            continue;
        };
        any = true;
        for b in &info.block_levels {
            if out.tile_drawn.get(t).copied().unwrap_or(false) {
                let l = level.and_then(|l| l.get(t)).map_or(0, |&l| l as usize).min(GRID_STATS.len() - 1);
                if let Some(s) = b.get(l.min(b.len().saturating_sub(1))) {
                    sums[l][0] += s.cells;
                    sums[l][1] += s.faces;
                }
            }
            t += 1;
        }
    }
    if any {
        for (names, v) in GRID_STATS.iter().zip(sums) {
            out.stats.extra.push((names[0], Stat::Count(v[0])));
            out.stats.extra.push((names[1], Stat::Count(v[1])));
        }
        out.stats.extra.push(("grid_interior_triangles_skipped", Stat::Count(skipped)));
    }
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
        f.outside,
        f.pass_breaks,
        f.timestamps,
    );
    args
}

#[cfg(test)]
mod tests;
