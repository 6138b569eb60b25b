//! Culling strategies: each decides which fine tiles the final pass of a frame draws.
//!
//! A strategy is one file implementing [`CullStrategy`] plus one line in [`REGISTRY`]; the
//! renderer (`crate::render`) owns one instance of each (so a strategy may keep caches between
//! frames), and Python's list of modes is [`names`]. A strategy sees the frame through
//! [`FrameInputs`] and answers with a [`Visible`]: a CPU tile mask or an indirect-args buffer it
//! recorded on the GPU, the per-tile pixel counts its decision rests on, and its own named stats.
//! It builds on `crate::gpu`'s passes and never on the renderer.
//!
//! Each strategy's file documents what it draws and when that is exact; [`REGISTRY`] lists them.

pub mod frustum;
pub mod hidden;
pub mod horizon;
pub mod implicit;
pub mod none;
pub mod oracle;
pub mod phases;
pub mod temporal;
pub mod three_pass;

#[cfg(test)]
pub(crate) mod reference;

use crate::camera::{Camera, FrameCamera};
use crate::error::{ensure, input_err, Result};
use crate::gpu::{DrawArgs, GpuContext, Passes, SceneGeometry, Targets, Timestamps};
use crate::scene::Scene;

/// Every strategy, in the order Python lists them. Adding a strategy: its file, one line here.
pub const REGISTRY: &[fn() -> Box<dyn CullStrategy>] =
    &[none::make, three_pass::make, oracle::make, horizon::make, frustum::make, temporal::make, implicit::make];

/// Names of the registered strategies (what `culling=` accepts).
pub fn names() -> Vec<&'static str> {
    REGISTRY.iter().map(|make| make().name()).collect()
}

/// The error for an unknown `culling=` name, listing the registered ones.
pub fn unknown(name: &str) -> crate::error::Error {
    let list: Vec<String> = names().iter().map(|n| format!("{n:?}")).collect();
    input_err("culling", format!("unknown culling {name:?}; expected one of {}", list.join(", ")))
}

/// Options every strategy may read (validated once per frame, for every strategy).
#[derive(Clone, Debug)]
pub struct CullOptions {
    /// Tiles with at most this many visible pixels (full-image units) are not drawn (three_pass).
    pub pixel_threshold: f64,
    /// Prepass resolution relative to the image, in (0, 1] (three_pass; temporal's first frame).
    /// Callers that give none take [`CullOptions::default_prepass_scale`].
    pub prepass_scale: f64,
    /// three_pass: never cull a tile with a visible pixel (beyond what the threshold allows);
    /// false: the paper's approximate method.
    pub conservative: bool,
    /// three_pass with `conservative: false`: also find the tiles at risk of being wrongly culled
    /// (stats `tiles_at_risk`, `predicted_max_missing_pixels`; costs the box-test pass).
    pub predict_errors: bool,
}

impl Default for CullOptions {
    fn default() -> Self {
        Self {
            pixel_threshold: 10.0,
            prepass_scale: Self::default_prepass_scale(true),
            conservative: true,
            predict_errors: false,
        }
    }
}

impl CullOptions {
    /// The prepass scale when the caller gives none: 1/2 for conservative frames, whose image does
    /// not depend on it (it only chooses the first set; a quarter of the pixels to draw and count:
    /// 1.50 -> 1.38 x the oracle on the seven Gullfaks-like views at coarse_factor 25, the same
    /// tiles drawn), 1 for the paper's approximate method, whose culling does.
    pub fn default_prepass_scale(conservative: bool) -> f64 {
        if conservative {
            0.5
        } else {
            1.0
        }
    }

    pub fn validate(&self) -> Result<()> {
        let t = self.pixel_threshold;
        ensure(t.is_finite() && t >= 0.0, "pixel_threshold", || {
            format!("pixel_threshold is {t}; expected a number >= 0")
        })?;
        let s = self.prepass_scale;
        ensure(s.is_finite() && s > 0.0 && s <= 1.0, "prepass_scale", || {
            format!("prepass_scale is {s}; expected a number in (0, 1]")
        })
    }
}

/// What a strategy sees of the frame being rendered.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub ctx: &'a GpuContext,
    pub passes: &'a Passes,
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// The frame's camera in render space (relative to `origin`, exaggerated), near/far included.
    pub fc: &'a FrameCamera,
    /// The frame's render origin (world, f64); an object's tiles lie at
    /// `Object::placement(origin)` + their positions, before exaggeration.
    pub origin: glam::DVec3,
    pub geometry: &'a SceneGeometry,
    /// Per tile, the draw of the level of detail chosen for this frame (`geometry.fine` with
    /// lod = full): what every strategy draws in place of the fine tiles.
    pub draw_args: &'a [DrawArgs],
    /// Per tile, the squared distance from the eye to its box in render space (exaggerated): the
    /// key of front-to-back orders and of the LOD choice, computed once per frame.
    pub tile_dist2: &'a [f64],
    /// Bind group of the scene passes for this frame.
    pub scene_bg: &'a wgpu::BindGroup,
    /// Per tile: its object is visible (`Scene::set_visible`). Hidden objects are never drawn.
    pub object_visible: &'a [bool],
    /// Per object: this frame sees it from outside (`Scene::seen_from_outside`): its interior
    /// faces are left out of `draw_args` and the lit pass culls its back faces.
    pub outside: &'a [bool],
    /// The runs of tiles of this frame's lit draws (`SceneGeometry::frame_runs` over
    /// `draw_args`): pass it to every `record_draw`.
    pub draw_runs: &'a [crate::gpu::geometry::DrawRun],
    /// Where the lit draws of this frame break into render passes (`gpu::passes::pass_breaks`
    /// over `draw_args`, `Renderer::set_pass_triangles`): pass it to every `record_draw`.
    pub pass_breaks: &'a [usize],
    pub width: u32,
    pub height: u32,
    /// The final image's targets; a strategy may draw into them in `prepare` (the final pass
    /// clears them).
    pub main_targets: &'a Targets,
    /// The renderer's id + depth targets for a prepass (`phases::prepass_first_set`), shared by
    /// the strategies that run one; made or resized on use.
    pub prepass_targets: &'a std::sync::Mutex<Option<Targets>>,
    pub options: &'a CullOptions,
    pub timestamps: Option<&'a Timestamps>,
}

impl FrameInputs<'_> {
    /// `args` with the draws of hidden objects, and of tiles where `keep` is false, switched off.
    pub fn pick(&self, args: &[DrawArgs], keep: impl Fn(usize) -> bool) -> Vec<DrawArgs> {
        args.iter().enumerate().map(|(i, a)| if self.object_visible[i] && keep(i) { *a } else { a.off() }).collect()
    }
    pub fn n_tiles(&self) -> usize {
        self.geometry.n_tiles()
    }
    /// Where object `oi` (position in `scene.objects()`) lies in this frame's render space
    /// (before exaggeration).
    pub fn placement(&self, oi: usize) -> glam::DVec3 {
        self.scene.objects()[oi].placement(self.origin)
    }

    /// The bound (world units, not exaggerated) on the vertical distance between what tile `i`
    /// draws this frame and its fine surface, everywhere: 0 at level 0, a level's error where its
    /// levels' errors are such bounds (`SceneGeometry::slab_draws`' flag, `lod::slab::Slab::
    /// levels_exact`: lattice levels, measured levels of tiles with holes); None for other levels,
    /// whose error is not a bound everywhere.
    pub fn exact_level_error(&self, i: usize) -> Option<f64> {
        let g = self.geometry;
        let d = self.draw_args[i];
        if d == g.fine[i] {
            return Some(0.0);
        }
        let exact = g.slab_draws[i].is_some_and(|s| s.exact);
        g.drawn_errors(i, &d).filter(|_| exact).map(|e| e.0 as f64)
    }

    /// Tile `i`'s box in render space (its object's placement and z_scale applied), grown against
    /// f32 round-off, as the box passes draw it, and whether it reaches the near plane (then its
    /// front faces may be clipped and a box test cannot be trusted to see it).
    pub fn tile_box(&self, i: usize) -> (glam::DVec3, glam::DVec3, bool) {
        let (lo, hi) = self.geometry.bbox[i];
        self.render_box(i, lo, hi)
    }

    /// The box `lo..hi` of tile `i` (origin-relative, as `SceneGeometry::bbox`) in render space:
    /// its object's placement and z_scale applied, not grown.
    pub fn render_space_box(&self, i: usize, lo: glam::DVec3, hi: glam::DVec3) -> (glam::DVec3, glam::DVec3) {
        let zs = glam::DVec3::new(1.0, 1.0, self.camera.z_scale);
        let off = self.placement(self.geometry.tile_object_cpu[i] as usize);
        let (a, b) = ((lo + off) * zs, (hi + off) * zs);
        (a.min(b), a.max(b))
    }

    /// The box `lo..hi` of tile `i` (origin-relative, as `SceneGeometry::bbox`) as [`Self::tile_box`]
    /// makes the tile's.
    pub fn render_box(&self, i: usize, lo: glam::DVec3, hi: glam::DVec3) -> (glam::DVec3, glam::DVec3, bool) {
        use glam::DVec3;
        let (lo, hi) = self.render_space_box(i, lo, hi);
        let grow = 1e-6 * lo.abs().max(hi.abs()).max_element() + 1e-4 * (hi - lo).length() + 1e-9;
        let (lo, hi) = (lo - DVec3::splat(grow), hi + DVec3::splat(grow));
        let nearest =
            box_corners(lo, hi).iter().map(|&p| (p - self.fc.eye).dot(self.fc.forward)).fold(f64::INFINITY, f64::min);
        (lo, hi, nearest <= self.fc.near * 1.001 + 1e-9)
    }
}

/// The 8 corners of box `lo..hi`; corner c takes x from bit 0, y from bit 1, z from bit 2
/// (0 = lo), as box.wgsl numbers them.
pub fn box_corners(lo: glam::DVec3, hi: glam::DVec3) -> [glam::DVec3; 8] {
    std::array::from_fn(|c| glam::DVec3::select(glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0), hi, lo))
}

/// Which fine tiles the final pass draws.
pub enum Draw {
    /// Every tile of a visible object.
    All,
    /// Per tile, decided on the CPU (hidden objects are switched off as well).
    Mask(Vec<bool>),
    /// Indirect args (one per tile) that the strategy's GPU passes write in this frame.
    Gpu(wgpu::Buffer),
}

/// The per-tile pixel counts reported as `tile_pixels`: those the strategy's decision rests on,
/// in full-image pixels; for strategies that count no pixels, those of the final image.
pub enum Pixels {
    /// Count the final image (after the frame time is taken).
    FinalImage,
    /// Counted on the host (e.g. oracle: the reference image's counts).
    Host(Vec<u32>),
    /// A u32 per tile that this frame's GPU passes write; multiplied by `scale` (to full-image
    /// pixels) when read back.
    Gpu { counts: wgpu::Buffer, scale: f64 },
}

/// A named statistic's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stat {
    /// A count (triangles, nodes, tiles).
    Count(u64),
    /// A duration in milliseconds.
    Ms(f64),
    /// Any other real number (its name says the unit, e.g. `_px`, `_m`).
    Float(f64),
}

/// A strategy's answer for one frame.
pub struct Visible {
    pub draw: Draw,
    /// Draw args the strategy itself already drew into the main targets in this frame (clearing
    /// them); the final pass then adds `draw` to that image instead of clearing it.
    pub predrawn: Option<wgpu::Buffer>,
    pub pixels: Pixels,
    /// Per-tile u32 counts the strategy's GPU passes write, read back by name (e.g. "box_pixels").
    pub tile_counts: Vec<(&'static str, wgpu::Buffer)>,
    /// The strategy's own stats (e.g. "nodes_visited"), added to the frame's stats by name.
    pub stats: Vec<(&'static str, Stat)>,
    /// The strategy's own per-frame arrays (e.g. "horizon": one value per image column).
    pub arrays: Vec<(&'static str, Vec<f32>)>,
}

impl Visible {
    pub fn new(draw: Draw, pixels: Pixels) -> Self {
        Self { draw, predrawn: None, pixels, tile_counts: Vec::new(), stats: Vec::new(), arrays: Vec::new() }
    }
}

/// Bytes a strategy's cache may keep between frames unless the renderer says otherwise
/// (`CullStrategy::set_cache_budget`).
pub const DEFAULT_CACHE_BUDGET: u64 = 256 << 20;

/// A culling strategy. One instance lives in each renderer, so it may cache between frames
/// (keyed by what it depends on, e.g. `Scene::geometry_key` and the camera's z_scale), within a
/// byte budget ([`DEFAULT_CACHE_BUDGET`], [`CullStrategy::set_cache_budget`]).
pub trait CullStrategy: Send + Sync {
    /// The `culling=` name.
    fn name(&self) -> &'static str;
    /// Device features this strategy needs beyond the renderer's own; the renderer asks for
    /// them when the adapter has them and refuses the strategy, naming them, when it has not.
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::empty()
    }
    /// Bounds what the strategy caches between frames to `bytes` (evicting at once if needed).
    /// Strategies without a cache ignore it.
    fn set_cache_budget(&mut self, _bytes: u64) {}
    /// Work that is not part of the frame time (e.g. the oracle's reference render). May submit.
    fn prepare(&mut self, _frame: &FrameInputs<'_>) -> Result<()> {
        Ok(())
    }
    /// Decides the visible set. GPU work is recorded into `enc`, the frame's one encoder, which
    /// the renderer submits after recording the final draw.
    fn visible_set(&mut self, frame: &FrameInputs<'_>, enc: &mut wgpu::CommandEncoder) -> Result<Visible>;
    /// Stats computed from what was read back after the frame (e.g. from `tile_counts`).
    fn report(&mut self, _frame: &FrameReport<'_>) -> Vec<(&'static str, Stat)> {
        Vec::new()
    }
}

/// What was read back after a frame, for [`CullStrategy::report`].
pub struct FrameReport<'a> {
    pub tile_drawn: &'a [bool],
    pub tile_pixels: &'a [u32],
    /// The strategy's `tile_counts`, read back, by name.
    pub tile_counts: &'a [(&'static str, Vec<u32>)],
    pub width: u32,
    pub height: u32,
}

impl FrameReport<'_> {
    pub fn counts(&self, name: &str) -> Option<&[u32]> {
        self.tile_counts.iter().find(|(n, _)| *n == name).map(|(_, c)| c.as_slice())
    }
}
