//! GPU side of implicit occluders (Pesco, Lindstrom, Pascucci, Silva, "Implicit Occluders").
//!
//! [`IsoRenderer::render`] (through `Renderer::render_isosurface`) draws the isosurface `f = w` of a [`Volume`], extracting surface
//! only inside octree nodes that can be seen:
//!
//! 1. **Classes** (view independent, cached per isovalue and occluder depth, kept where the walk
//!    runs):
//!    every node at `occluder_depth` is *Below* (`max < w`, no NaN), *Above* (`min > w`, no NaN),
//!    *NaN* (some sample is NaN), or passable (it may hold surface); a byte per node with its
//!    skip bricks' flags (step 3; [`super::bricks::pack_nodes`]) and, for single cells, its low
//!    faces' classes ([`super::bricks::leaf_nodes`], one pass over the samples for both).
//! 2. **Occlusion map** (one compute pass, one invocation per pixel, or the same walk on the
//!    host's cores, [`IsoWalk`], below; reverse-Z; the pixel rays
//!    are built in f64, as an origin and a direction affine in the pixel's NDC): the pixel's ray
//!    walks the class grid near to far (3-D DDA) and stops at the first node of one class met
//!    after a node of the other class with no NaN node in between; `M(p)` is the depth of that
//!    node's entry point (pushed a thousandth of a cell farther), 0 (= nothing proven) where no
//!    such pair lies on the ray. This is the paper's set (Below nodes, then Above nodes behind
//!    them, or the other way round) without drawing a box: the earlier version rasterised
//!    every Below / Above box three times (~500k boxes, 6 M triangles for the Pesco field 128³)
//!    where a pixel's walk visits a few dozen nodes and usually stops at the second class change.
//!    The classes come with their skip bricks (step 3), built on the CPU ([`super::bricks`]).
//!
//!    **Why it is conservative.** The rendered surface is the marching-cubes surface
//!    ([`super::march`]): crack free, it is closed except where NaN cells stop it, and inside every
//!    cell it separates the cell's above corners from its below corners. A Below box holds no
//!    triangle and no triangle touches it (its cells are not cut, its faces have no crossing edge),
//!    so it lies on the below side; an Above box on the above side (Below and Above nodes never
//!    touch because touching nodes share samples). A ray segment that goes from a Below node to an
//!    Above node (or back) through NaN-free nodes only stays where the surface is closed, so it
//!    crosses the surface strictly before `M(p)`: any surface point behind `M(p)` is hidden.
//!
//!    **Faces.** With single-cell occluders the walk also reads the faces it crosses: a cell
//!    face whose 4 corners are all below (above) has no crossing edge, so no triangle touches it
//!    and the whole face lies on the below (above) side, as a Below (Above) cell does
//!    ([`super::bricks::leaf_nodes`]). A face of the other class than the last class seen proves
//!    the crossing before it, so the walk stops there and leaves the cell behind it unmarked.
//!    Thin sheets and aliased regions hold few uniform cells but many uniform faces: on the Pesco
//!    field 128³ this draws 21-28 % fewer triangles (frog 12 %, channels 3 %).
//!
//!    **Contours** (`IsoOptions::face_contours`; by default always for the host's walk, and for
//!    the compute walk where at least half the bricks of 4³ cells hold surface,
//!    [`CONTOUR_MIN_DENSITY`]): the surface meets a face only along the
//!    face's contour, segments between its edges' crossing points placed as the extraction places
//!    its vertices, so any point of a face has a side, not only the points of uniform faces. The
//!    walk finds the side of each point where it crosses a face (iso.wgsl `contour_side`: the
//!    triangle a corner cuts off lies on that corner's side, the rest of a face with one such
//!    corner on the other; the two parts of a face split by one segment; the middle of an
//!    ambiguous face, whose joining depends on the extraction's choice, is not known) and stops
//!    at the first point of the other side than the last seen: right behind the surface it
//!    crossed, usually in the next cell, where it used to walk on to a uniform face. It reads the
//!    5³ samples of each brick that holds surface, kept with the classes
//!    (`IsoStats::gpu_contour_bytes`; [`super::bricks::contour_bricks`]). A point is known only
//!    when its *ray* passes farther than the marking margin (a hundredth of a cell) from the
//!    segment's line: a ray that grazes the face meets it far from a segment it passes very near,
//!    and the rasteriser's rounding may put its pixel on the other side (found by
//!    `face_contours_change_nothing_drawn`). Faces with a corner at the isovalue are not known
//!    (its vertices may sit on the corner). Pesco field 128³: 0.28 → 0.18 of the triangles, the
//!    walk's steps per ray ~25 → ~18, frames 4-10 % faster.
//!
//!    **The domain.** The paper assumes a convex domain where the field is defined everywhere.
//!    Here the domain is the NaN-free cells, which need not be convex (NaN borders, slabs, holes):
//!    a segment from Below to Above may leave it through NaN cells, where the surface has a
//!    boundary and can be passed by, so a NaN node breaks every pair across it (the walk forgets
//!    the class it saw), and NaN nodes are never Below or Above themselves. What stays
//!    conservative: the proof only uses segments inside NaN-free nodes at `occluder_depth` (the
//!    volume's box is convex, so the segment never leaves it); a coarse occluder depth with a few
//!    NaN samples loses occluders (whole nodes count as NaN), never correctness. The segment must
//!    also stay clear of the surface's boundary, where the rasteriser's rounding may draw a ray
//!    past the last triangle (found by the random-volume test: a ray 0.0003 cells inside a face
//!    bordering NaN cells): nodes that touch a NaN node count as NaN for the walk
//!    ([`super::bricks::dilate_nan`]), and no proof ends within the margin of the box's faces or
//!    starts before a cell that may hold surface entered there (iso.wgsl `at_box`).
//! 3. **Cells and nodes seen**, in the same walk: every march cell (cells of the finer of the
//!    occluder and cull depths) that may hold surface (passable or NaN class) and that the pixel's
//!    ray enters before it stops (the stopping cell included) is seen. So is a cell the ray passes
//!    within a hundredth of a cell of, so rounding never skips one: where the ray enters a cell
//!    that close to a grid plane, the walk marks a *near event* along that axis, and the CPU
//!    marks the cells across it on both sides ([`super::seen::seen_cells`]; the walk used to mark
//!    only the near side's cells itself, with up to seven class reads and atomics per step, which
//!    a CPU rasteriser runs for every lane at every step: 40 % of the walk on the Pesco field,
//!    for 1 % fewer triangles). The walk's box is widened by the same margin, but a cell met only
//!    in that band outside the box breaks every pair as a NaN cell does: a proof needs its segment
//!    inside the volume. Below / Above cells hold no triangle and are never seen. The surface lies
//!    in those cells, so on every pixel where a cell's surface is the first hit, the ray enters the
//!    cell before `M(p)`: drawing only the seen cells' triangles gives the unculled image. A
//!    node at `cull_depth` is visible (extracted) when one of its cells is marked, counted on the
//!    CPU from the bits (`node_pixels` = its marked cells): no atomic counter per node in the walk
//!    (they cost ~40 % of the walk on the Pesco field on lavapipe), and a node whose only cells
//!    entered could hold no surface is not extracted. Nodes in front of the near plane are walked
//!    from the near plane, as drawn.
//!
//!    **Space skipping** ([`super::bricks`]): the walk steps cell by cell, but where the cell it
//!    enters has class `k` (Below or Above) and lies in a *skip brick* of class `k` (4³ or 16³
//!    occluder nodes that, *with the one-node ring around them*, are all of class `k`), it jumps
//!    to where the ray leaves the brick. Nothing is lost: inside the brick every cell the ray would
//!    enter is of class `k`, so it would mark none, and its state (last class `k`) would not change
//!    (no class change, no NaN reset) — the map's stop is at the first cell of the *other* class,
//!    outside the brick, at the entry point the cell-by-cell walk computes; the ring covers the
//!    neighbours a near event in the brick would mark (they are of class `k`: never seen). The
//!    jump lands in the very state the cell-by-cell walk reaches: the DDA's crossings are a
//!    function of the cell alone (`exits` in iso.wgsl), the exit axis is the first crossing out of
//!    the brick (ties to the lower axis, as the steps), and each other axis advances while its
//!    crossing comes first (counted in closed form: the crossings grow with the cell index, so an
//!    estimate corrected by one either way is exact). So the map and the seen cells are bit for
//!    bit those of the walk without skipping (`bricks::walk_tests`). A step is a brick of one
//!    cell, so both run the same straight-line code: a CPU rasteriser runs every branch for every
//!    lane. On the frog tissues (500×470×136) skipping takes the walk from ~110 to ~13 steps per
//!    pixel.
//! 4. **Surface**: marching cubes ([`super::march`]) in the visible nodes at `cull_depth`,
//!    cached per (volume, isovalue, node) in a [`PatchCache`]; drawn lit (two-sided Lambert).
//!    Of each patch only the triangles of the marked cells are drawn (patches index their
//!    triangles by cell, `SurfacePatch::cell_starts`), so the patches stay per node (cacheable)
//!    and the drawn triangles are per cell. On the Pesco field 128³ this takes the face ratio from
//!    0.43-0.49 (nodes of 2³-4³ cells) to 0.39. A frame without the cache keeps nothing for later
//!    frames, so it extracts the marked cells alone ([`super::march::extract_nodes_where`]): the
//!    same triangles, a quarter fewer vertices to extract, pack and upload.
//!
//! Depths count from the root (0) as in the octree; the leaves (single cells) are at
//! `tree.max_depth()`. A volume of 256³ samples has 255 cells per axis and max depth 8, matching
//! the paper's numbering for its 256³ volume; for a 128³ volume subtract 1 to compare node sizes.
//!
//! **Where the walk runs** ([`IsoWalk`]). On a GPU the walk is a compute pass. On an adapter
//! that is a CPU itself (lavapipe, llvmpipe) `IsoWalk::Auto` runs the same walk on the host's
//! cores instead ([`super::walk`], a task per image row): lavapipe runs the shader 8 lanes at a
//! time with every branch of the loop taken for every lane and reads storage buffers lane by lane,
//! where the host steps each ray by itself, takes only its own branches and reads node bytes with
//! plain loads, and a table of the skippable bricks' bytes ([`super::bricks::skip_byte`],
//! 1/64 of the nodes) keeps a brick jump's read in the caches; it also jumps a third level of
//! skip bricks and places contours on every surface (`IsoOptions::face_contours`). With the same
//! contour choice the two walks see the same cells and prove the same map (to the shader's
//! rounding, `walk.rs` tests); the host's needs no submission or read-back before the draw.
//!
//! **The oracle** (`IsoCulling::Oracle`, for benchmarks; [`super::oracle`]): the unculled frame
//! first, then only the cells that hold each pixel's surface point (read back from its depth, a
//! cell across a face within [`ORACLE_TOLERANCE`] too) are extracted and drawn as step 4 draws
//! the marked cells. Where its image differs from the unculled one (the rasteriser's snapping
//! moves the depth of a triangle seen edge-on a long way along the ray), the cells along those
//! pixels' rays about the point are added and the frame drawn again, at most [`ORACLE_TRIES`]
//! times; only the last frame's own extraction and draw are timed. What `Implicit` costs beyond
//! it is its walk and the cells it marks that no pixel shows: on the Pesco field 128³ at 512²
//! (warm, this machine's lavapipe) the oracle drew 0.09 of the triangles in 0.18-0.19 of the
//! unculled frame's time, the implicit walk 0.18 in 0.53-0.54.

use std::sync::Arc;
use std::time::Instant;

use glam::{DMat4, DVec3, DVec4, Mat4};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::bricks::{contour_grid, dilate_nan, CONTOUR_SHIFT};
pub use super::bricks::{node_classes, occluder_nodes};
use super::march::{PatchCache, SurfacePatch, DEFAULT_CACHE_BUDGET};
use super::octree::{MinMaxOctree, NodeInfo};
use super::oracle::{visible_cells, widen_where_wrong, OracleCells, ORACLE_TRIES};
use super::passes::{
    draw_pooled, draw_surface, march, pixel_rays, ClassGrid, Globals, IsoPasses, MapParams, Space, Targets, WalkData,
};
use super::pool::SurfacePool;
use super::seen::{cells_seen, seen_cells, visible_ranges};
use super::walk::{walk, WalkGrid};
use super::Volume;
use crate::camera::Camera;
use crate::error::{ensure, input_err, Interrupt, Result};
use crate::gpu::{GpuContext, ReadbackTexture};

/// The share of the nodes of 4³ cells that must straddle the isovalue for the compute walk to
/// place the faces' contours by default (`IsoOptions::face_contours`; the host's walk always
/// does: it evaluates a contour only where its ray crosses a mixed face, and with them the frog
/// drew 0.36 × the triangles in warm frames ~20 % faster, the channels 0.72 × within noise).
/// On lavapipe placing them makes each
/// step of the walk dearer (on the Pesco field ~30 % fewer steps gave a walk only a few % faster)
/// and pays where rays cross long stretches of cells that may hold surface before a uniform
/// cell or face stops them: the Pesco field 128³ (86 % of its bricks straddle) walks and draws
/// faster with them; the channels (28 %) and the frog (7 %) reach uniform cells within a cell or
/// two of their surface anyway, and their frames took up to 10 % longer.
pub const CONTOUR_MIN_DENSITY: f64 = 0.5;

/// How near a cell face (grid units) the oracle's surface point of a pixel marks the cell across
/// it too (`iso::oracle::visible_cells`): the depth buffer's rounding and sub-pixel snapping move
/// the point along the ray, most on triangles seen nearly edge-on.
pub const ORACLE_TOLERANCE: f64 = 0.05;

/// How the isosurface is culled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsoCulling {
    /// Extract and draw the whole isosurface (the reference).
    None,
    /// Implicit occluders: extract only inside nodes that pass the occlusion-map test.
    Implicit,
    /// For benchmarks: the cells that hold a visible point of the unculled image (rendered
    /// first, untimed, as is reading the cells from its depth), drawn as `Implicit` draws its
    /// marked cells; the same image (see the module docs). About the least any culling that
    /// draws whole cells can draw.
    Oracle,
}

impl IsoCulling {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Self::None),
            "implicit" => Ok(Self::Implicit),
            "oracle" => Ok(Self::Oracle),
            _ => Err(input_err(
                "culling",
                format!("unknown culling {s:?}; expected \"implicit\", \"none\" or \"oracle\""),
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Implicit => "implicit",
            Self::Oracle => "oracle",
        }
    }
}

/// Where the implicit walk (the occlusion map and the cells seen) runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsoWalk {
    /// On the host when the adapter is a CPU itself (lavapipe, llvmpipe), else on the GPU.
    Auto,
    /// A compute pass (iso.wgsl `cs_map`), one invocation per pixel.
    Gpu,
    /// On the host's cores (`iso::walk`), one task per image row: the same walk step for step.
    Cpu,
}

impl IsoWalk {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Self::Auto),
            "gpu" => Ok(Self::Gpu),
            "cpu" => Ok(Self::Cpu),
            _ => Err(input_err("walk", format!("unknown walk {s:?}; expected \"auto\", \"gpu\" or \"cpu\""))),
        }
    }

    /// Whether the walk runs on the host with adapter `info`.
    pub fn on_host(self, info: &wgpu::AdapterInfo) -> bool {
        match self {
            Self::Auto => info.device_type == wgpu::DeviceType::Cpu,
            Self::Gpu => false,
            Self::Cpu => true,
        }
    }
}

/// Options of one isosurface frame.
#[derive(Clone, Debug)]
pub struct IsoOptions {
    pub culling: IsoCulling,
    /// Depth of the occluder nodes (root = 0); `None` = `max_depth` (single cells: the class grid
    /// costs 4 bits per cell and the walk little more than at coarser depths).
    pub occluder_depth: Option<u32>,
    /// Depth of the nodes tested and extracted (root = 0); `None` = `max_depth - 2`.
    pub cull_depth: Option<u32>,
    /// Surface colour, RGB in [0, 1].
    pub color: [f32; 3],
    /// Reuse (and fill) the per-node patch cache. `false` extracts every visible node afresh.
    pub use_cache: bool,
    /// Also read back the occlusion map (as linear depth).
    pub return_map: bool,
    /// Memory budget of the renderer's isosurface caches in bytes (patches, and at most a quarter
    /// of it for the straddling-node lists); least recently used entries are dropped beyond it.
    pub cache_budget: usize,
    /// Let the walk jump whole skip bricks of one class (see the module docs); `false` walks cell
    /// by cell. Both give the same map, counts of drawn cells and image.
    pub space_skipping: bool,
    /// With single-cell occluders, let the walk place the contour of every face it crosses and stop
    /// right behind the surface (module docs, "Contours"): `Some(true)` always, `Some(false)` never
    /// (it knows only uniform faces), `None` (default) always for the host's walk ([`IsoWalk`]),
    /// and for the compute walk where the surface is dense: where the nodes of 4³ cells that
    /// straddle the isovalue are at least [`CONTOUR_MIN_DENSITY`] of them. All give the unculled
    /// image; contours draw fewer triangles.
    pub face_contours: Option<bool>,
    /// Where the walk runs (`IsoWalk::Auto`: on the host when the adapter is a CPU). Both walks
    /// give the unculled image, and the same map and cells seen with the same `face_contours`
    /// choice (by default the host's also places contours on sparse surfaces: fewer cells).
    pub walk: IsoWalk,
    /// Polled between the stages of the frame (map, each level of node tests, extraction); when
    /// it fires, `render` returns `Error::Interrupted` and the caches stay valid.
    pub interrupt: Interrupt,
}

impl Default for IsoOptions {
    fn default() -> Self {
        Self {
            culling: IsoCulling::Implicit,
            occluder_depth: None,
            cull_depth: None,
            color: [0.85, 0.72, 0.45],
            use_cache: true,
            return_map: false,
            cache_budget: DEFAULT_CACHE_BUDGET,
            space_skipping: true,
            face_contours: None,
            walk: IsoWalk::Auto,
            interrupt: Interrupt::default(),
        }
    }
}

/// Counts and wall-clock times (milliseconds) of one isosurface frame.
#[derive(Clone, Debug, Default)]
pub struct IsoStats {
    pub surface_triangles: u64,
    pub surface_vertices: u64,
    /// Nodes tested against the occlusion map, all levels together.
    pub nodes_tested: u32,
    /// Nodes tested at the cull depth itself.
    pub nodes_tested_cull_depth: u32,
    /// Visible nodes at the cull depth (all straddling nodes for culling = none).
    pub nodes_visible: u32,
    /// Straddling nodes at the cull depth (what culling = none extracts).
    pub nodes_straddling: u32,
    /// Below / Above nodes at the occluder depth (the map's class grid).
    pub occluder_boxes_below: u32,
    pub occluder_boxes_above: u32,
    pub occluder_depth: u32,
    pub cull_depth: u32,
    pub max_depth: u32,
    /// Patches found in the cache / extracted this frame.
    pub patches_cached: u32,
    pub patches_extracted: u32,
    /// Nodes at the occluder depth with a NaN sample or touching one (never occluders; they stop
    /// the map's walk, `bricks::dilate_nan`).
    pub occluder_nodes_nan: u32,
    /// The class grid (first frame of an isovalue and occluder depth, else 0) and the recording of
    /// the map pass, on the CPU; the pass itself runs on the GPU with the first node test and is
    /// part of `cull_ms` (one submission).
    pub occluder_ms: f64,
    /// Occlusion map and node test (one GPU walk per pixel), read-back included.
    pub cull_ms: f64,
    /// Marching cubes (cache look-ups included).
    pub extract_ms: f64,
    /// Upload of what is not on the GPU yet (the pool's new patches; implicit culling: the kept
    /// cells' indices) and the lit draw (GPU finished).
    pub draw_ms: f64,
    /// extract_ms + draw_ms.
    pub surface_ms: f64,
    /// Whole frame, from the call to the GPU finishing the image (no read-back, no setup).
    pub total_ms: f64,
    /// One-time work this frame paid for before its clock started (not in `total_ms`): pipeline
    /// creation and the case table (the renderer's first isosurface frame), targets (first frame
    /// at a size). 0 on other frames.
    pub setup_ms: f64,
    /// Queue submissions and GPU-to-host read-backs inside the frame (the walk's marked cells; the
    /// image read-back after the frame is not counted).
    pub submissions: u32,
    pub readbacks: u32,
    pub readback_ms: f64,
    /// Bytes held by the renderer's isosurface caches after the frame (patches and straddling-node
    /// lists), at most `IsoOptions::cache_budget`.
    pub cache_bytes: u64,
    /// Bytes of the cached patches' copy kept on the GPU between frames (vertices and triangles;
    /// at most about twice those the cache holds).
    pub gpu_cache_bytes: u64,
    /// Bytes of the walk's contour bricks kept with the class grid, on the GPU or on the host
    /// where the walk runs (single-cell occluders: one word per brick of 4³ cells, 125 samples per
    /// brick that holds surface; 0 without them: no implicit frame yet, coarser occluders, or, on
    /// the GPU, more than one storage binding).
    pub contour_bytes: u64,
    /// Where this frame's walk ran: `Some(true)` on the host, `Some(false)` on the GPU, `None`
    /// without one (culling = none).
    pub walk_on_host: Option<bool>,
    /// The host's walk: the pixel rays that entered the volume's box and the steps they took (a
    /// cell entered or a jump across skippable bricks: `walk::WalkCounts`). 0 where the walk ran on
    /// the GPU (not counted there) or there was none.
    pub walk_rays: u64,
    pub walk_steps: u64,
}

/// One rendered isosurface frame as host arrays.
#[derive(Clone, Debug)]
pub struct IsoOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, row 0 = top; background opaque black.
    pub image: Vec<u8>,
    /// Distance along the view axis (render-space units), +inf where empty.
    pub depth: Vec<f32>,
    /// The straddling nodes at the cull depth, `[depth, ix, iy, iz]`, in octree order.
    pub nodes: Vec<[u32; 4]>,
    /// Per node of `nodes`: its march cells that may hold surface and that some pixel's ray
    /// entered before the occlusion map (0 when hidden, and for culling = none).
    pub node_pixels: Vec<u32>,
    /// Per node of `nodes`: extracted and drawn.
    pub node_drawn: Vec<bool>,
    /// The occlusion map as linear depth (+inf where nothing is proven), when asked for.
    pub map: Option<Vec<f32>>,
    pub stats: IsoStats,
    pub near: f64,
    pub far: f64,
}

/// Straddling nodes of one (isovalue bits, depth).
type StraddlingEntry = ((u32, u32), Arc<Vec<NodeInfo>>);

/// Pipelines and caches of the isosurface passes (the scene renderer holds one, made on first use).
pub struct IsoRenderer {
    /// The pipelines, shared by the renderers on one device.
    passes: Arc<IsoPasses>,
    targets: Option<Targets>,
    source: Option<super::VolumeId>,
    classes: Option<ClassGrid>,
    /// Setup time not yet reported (pipelines made in `new`).
    setup_ms: f64,
    /// Straddling nodes per (isovalue bits, depth).
    straddling: Vec<StraddlingEntry>,
    patches: PatchCache,
    /// The cached patches' vertices and triangles on the GPU.
    pool: SurfacePool,
}

impl IsoRenderer {
    /// Creates the pipelines, or takes those of `ctx`'s device if another renderer on it made
    /// them (and the marching-cubes case table); their time is reported as the first frame's
    /// `setup_ms`.
    pub fn new(ctx: &GpuContext) -> Self {
        let t = Instant::now();
        let passes = ctx.per_device(IsoPasses::new);
        super::march::cases::cases();
        Self {
            passes,
            targets: None,
            source: None,
            classes: None,
            setup_ms: t.elapsed().as_secs_f64() * 1e3,
            straddling: Vec::new(),
            patches: PatchCache::new(),
            pool: SurfacePool::default(),
        }
    }

    /// Drops every cache when the volume changed.
    fn bind_volume(&mut self, vol: &Volume) {
        if !self.source.as_ref().is_some_and(|s| s.matches(vol)) {
            self.classes = None;
            self.straddling.clear();
            self.patches.clear();
            self.source = Some(super::VolumeId::of(vol));
        }
    }

    /// The straddling nodes of `(w, depth)`, cached most recently used last: at most 32 lists
    /// and `budget` bytes (the oldest go first; the caller keeps its own reference).
    fn straddling(&mut self, tree: &MinMaxOctree, w: f32, depth: u32, budget: usize) -> Arc<Vec<NodeInfo>> {
        let key = (norm_bits(w), depth);
        let v = match self.straddling.iter().position(|(k, _)| *k == key) {
            Some(i) => self.straddling.remove(i).1,
            None => Arc::new(tree.straddling_at_depth(w, depth)),
        };
        self.straddling.push((key, v.clone()));
        while !self.straddling.is_empty() && (self.straddling.len() > 32 || self.straddling_bytes() > budget) {
            self.straddling.remove(0);
        }
        v
    }

    fn straddling_bytes(&self) -> usize {
        self.straddling.iter().map(|(_, v)| v.capacity() * std::mem::size_of::<NodeInfo>()).sum()
    }

    /// Bytes held by the caches whose size grows with use: patches and straddling-node lists.
    pub fn cache_bytes(&self) -> usize {
        self.patches.bytes() + self.straddling_bytes()
    }

    /// Drops the cached patches, occluders and node lists (the pipelines stay).
    pub fn clear_cache(&mut self) {
        self.classes = None;
        self.straddling.clear();
        self.patches.clear();
        self.pool.clear();
        self.source = None;
    }
}

fn norm_bits(w: f32) -> u32 {
    if w == 0.0 { 0.0f32 } else { w }.to_bits()
}

impl IsoRenderer {
    /// Renders the isosurface `vol = isovalue` (in the volume's units, f64) seen by `camera` into
    /// `width` × `height` targets of its own; `tree` must be the octree of `vol`. See the module docs for what `culling = Implicit`
    /// does.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
        vol: &Volume,
        tree: &MinMaxOctree,
        isovalue: f64,
        camera: &Camera,
        opts: &IsoOptions,
    ) -> Result<IsoOutput> {
        if opts.culling != IsoCulling::Oracle {
            return self.frame(ctx, width, height, vol, tree, isovalue, camera, opts, None);
        }
        // The oracle: the unculled frame first, outside the clock; then frames of the cells of its
        // pixels' surface points until one draws its image (`iso::oracle`).
        let none = IsoOptions { culling: IsoCulling::None, return_map: false, ..opts.clone() };
        let reference = self.frame(ctx, width, height, vol, tree, isovalue, camera, &none, None)?;
        let mut cells = OracleCells { depth: reference.depth, reach: vec![0.0; (width * height) as usize] };
        let mut tries = 0;
        loop {
            let out = self.frame(ctx, width, height, vol, tree, isovalue, camera, opts, Some(&cells))?;
            tries += 1;
            if widen_where_wrong(&mut cells, &out.image, &reference.image) == 0 || tries == ORACLE_TRIES {
                return Ok(out);
            }
        }
    }

    /// [`Self::render`]'s frame; with `oracle`, the oracle's (`opts.culling` is then Oracle).
    #[allow(clippy::too_many_arguments)]
    fn frame(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
        vol: &Volume,
        tree: &MinMaxOctree,
        isovalue: f64,
        camera: &Camera,
        opts: &IsoOptions,
        oracle: Option<&OracleCells>,
    ) -> Result<IsoOutput> {
        // In the volume's units; from here on everything is a residual about `vol.offset`.
        let w = vol.residual(isovalue, "isovalue")?;
        ensure(opts.color.iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c)), "color", || {
            format!("color is {:?}; expected (r, g, b) in [0, 1]", opts.color)
        })?;
        ensure(tree.cells() == [vol.nx as u32 - 1, vol.ny as u32 - 1, vol.nz as u32 - 1], "volume", || {
            "the octree was built from another volume".into()
        })?;
        let maxd = tree.max_depth();
        let occ_depth = opts.occluder_depth.unwrap_or(maxd);
        let cull_depth = opts.cull_depth.unwrap_or(maxd.saturating_sub(2));
        ensure(occ_depth <= maxd, "occluder_depth", || {
            format!("occluder_depth is {occ_depth}; this volume's octree has depths 0..={maxd}")
        })?;
        ensure(cull_depth <= maxd, "cull_depth", || {
            format!("cull_depth is {cull_depth}; this volume's octree has depths 0..={maxd}")
        })?;

        // One-time work first, outside the frame's clock: targets at a new size.
        let t_setup = Instant::now();
        let made = Targets::ensure(&mut self.targets, &ctx.device, width, height);
        let targets_ms = if made { t_setup.elapsed().as_secs_f64() * 1e3 } else { 0.0 };
        let setup_ms = std::mem::take(&mut self.setup_ms) + targets_ms;

        let t0 = Instant::now();
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

        let d = &ctx.device;
        let iso: &mut IsoRenderer = self;
        iso.bind_volume(vol);
        // A quarter of the budget for node lists, the rest for patches.
        let (list_budget, patch_budget) = (opts.cache_budget / 4, opts.cache_budget - opts.cache_budget / 4);
        iso.patches.set_budget(patch_budget);
        let candidates = iso.straddling(tree, w, cull_depth, list_budget);
        let implicit = opts.culling == IsoCulling::Implicit;
        let t_occ = Instant::now();
        let host = opts.walk.on_host(&ctx.info);
        if implicit {
            // View independent: the node classes at the occluder depth (kept where the walk runs).
            let key = (norm_bits(w), occ_depth);
            let policy = opts.face_contours;
            if iso
                .classes
                .as_ref()
                .is_none_or(|g| g.key != key || g.contour_policy != policy || g.data.on_host() != host)
            {
                iso.classes = None;
                let dims = tree.dims_at_depth(occ_depth).expect("occ_depth <= max depth");
                // Single cells carry their faces' classes too (finer occluders for the walk), and
                // the samples of the bricks that hold surface, for the contours of mixed faces.
                let leaves = if occ_depth == tree.max_depth() { tree.leaf_nodes(w) } else { None };
                let faces = leaves.is_some();
                let contour = if faces && policy != Some(false) {
                    // (At the default cull depth the cache hands back the candidate nodes.)
                    let brick_depth = maxd.saturating_sub(CONTOUR_SHIFT);
                    let bricks = iso.straddling(tree, w, brick_depth, list_budget);
                    let n = tree.dims_at_depth(brick_depth).expect("brick depth <= max depth");
                    let dense =
                        bricks.len() as f64 >= CONTOUR_MIN_DENSITY * n.iter().map(|&v| v as f64).product::<f64>();
                    // (The host's walk places them wherever the surface is: it pays only for the
                    // faces its rays cross.)
                    (policy == Some(true) || dense || host).then(|| tree.contour_bricks(&bricks))
                } else {
                    None
                };
                let mut nodes = leaves.unwrap_or_else(|| node_classes(tree, w, occ_depth));
                dilate_nan(&mut nodes, dims);
                iso.classes = Some(ClassGrid::new(d, key, dims, nodes, faces, contour, policy, host));
            }
        }
        let iso: &IsoRenderer = &*iso;
        let globals_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("iso_globals"),
            contents: bytemuck::bytes_of(&globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let globals_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("iso_globals"),
            layout: &iso.passes.globals_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: globals_buf.as_entire_binding() }],
        });
        let mut stats = IsoStats {
            occluder_depth: occ_depth,
            cull_depth,
            max_depth: maxd,
            nodes_straddling: candidates.len() as u32,
            ..Default::default()
        };
        let mut node_pixels = vec![0u32; candidates.len()];
        let mut map_out = None;
        let tg = iso.targets.as_ref().unwrap();
        // ---- Occlusion map and node test: one walk per pixel, one submission, one read-back.
        // `seen`: the march cells some ray entered before the map (bits), their grid, and the shift
        // from volume cells to march cells.
        let mut seen: Option<(Vec<u32>, [u32; 3], u32)> = None;
        // The host walk's map (reverse-Z depth per pixel).
        let mut host_map: Option<Vec<f32>> = None;
        // The oracle's own work (its cells, read from the reference's depth) is not the frame's.
        let mut untimed = std::time::Duration::ZERO;
        let visible: Vec<NodeInfo> = if let Some(cells) = oracle {
            let t_or = Instant::now();
            let dims = tree.dims_at_depth(maxd).expect("max depth");
            let size = DVec3::new(vol.spacing[0], vol.spacing[1], vol.spacing[2] * space.z_scale);
            let rays = pixel_rays(&view_proj, &fc, plo, phi);
            let bits = visible_cells(cells, width, height, &rays, plo, size, dims, ORACLE_TOLERANCE);
            let counts: Vec<u32> = candidates.par_iter().map(|n| cells_seen(n, &bits, dims, 0)).collect();
            seen = Some((bits, dims, 0));
            let visible = candidates.iter().zip(&counts).filter(|(_, &c)| c > 0).map(|(n, _)| *n).collect();
            node_pixels = counts;
            untimed = t_or.elapsed();
            visible
        } else if !implicit {
            candidates.to_vec()
        } else {
            let grid = iso.classes.as_ref().unwrap();
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
            let rays = pixel_rays(&view_proj, &fc, plo, phi);
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
                    let view_proj = Mat4::from_cols_array_2d(&globals.view_proj);
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
                    march(ctx, &iso.passes, tg, &globals_bg, grid, &params, n_cells)?
                }
            };
            stats.walk_on_host = Some(host);
            let bits = seen_cells(&marks, march_dims, &grid.classes, grid.dims, md_march - occ_depth);
            let shift = maxd - md_march;
            let counts: Vec<u32> = candidates.par_iter().map(|n| cells_seen(n, &bits, march_dims, shift)).collect();
            seen = Some((bits, march_dims, shift));
            opts.interrupt.check()?;
            stats.nodes_tested = candidates.len() as u32;
            stats.nodes_tested_cull_depth = candidates.len() as u32;
            stats.cull_ms = t_cull.elapsed().as_secs_f64() * 1e3;
            let visible = candidates.iter().zip(&counts).filter(|(_, &c)| c > 0).map(|(n, _)| *n).collect();
            node_pixels = counts;
            visible
        };
        stats.nodes_visible = visible.len() as u32;
        // (A culled frame's visible nodes are the candidates with a cell seen, in their order.)
        let node_drawn: Vec<bool> = match opts.culling {
            IsoCulling::None => vec![true; candidates.len()],
            _ => node_pixels.iter().map(|&c| c > 0).collect(),
        };

        // ---- Marching cubes in the visible nodes (cached per node).
        let t_ex = Instant::now();
        let patches: Vec<Arc<SurfacePatch>> = if opts.use_cache {
            let iso = &mut *self;
            let before = iso.patches.len();
            let p = iso.patches.get_or_extract_many(vol, w, &visible);
            stats.patches_extracted = (iso.patches.len() - before) as u32;
            stats.patches_cached = visible.len() as u32 - stats.patches_extracted;
            p
        } else {
            stats.patches_extracted = visible.len() as u32;
            let patches = match &seen {
                // Nothing kept for later frames: only the cells some ray entered.
                Some((bits, mdims, shift)) => {
                    let seen_cell = |[i, j, k]: [usize; 3]| {
                        let m = ((k >> shift) * mdims[1] as usize + (j >> shift)) * mdims[0] as usize + (i >> shift);
                        bits[m / 32] >> (m % 32) & 1 == 1
                    };
                    super::march::extract_nodes_where(vol, w, &visible, &seen_cell)
                }
                None => super::march::extract_nodes(vol, w, &visible),
            };
            patches.into_iter().map(Arc::new).collect()
        };
        stats.extract_ms = t_ex.elapsed().as_secs_f64() * 1e3;
        opts.interrupt.check()?;

        // ---- Draw.
        let t_draw = Instant::now();
        let d = &ctx.device;
        // Of the visible nodes' patches, only the cells some ray entered before the map.
        // (Patches extracted for this frame alone hold only those cells already.)
        let ranges: Option<Vec<Vec<[u32; 2]>>> =
            seen.as_ref().filter(|_| opts.use_cache).map(|(bits, mdims, shift)| {
                visible.par_iter().zip(&patches).map(|(n, p)| visible_ranges(p, n, bits, *mdims, *shift)).collect()
            });
        let Self { passes, targets, pool, .. } = &mut *self;
        let tg = targets.as_ref().unwrap();
        // Cached patches stay on the GPU between frames (the pool); patches extracted for this
        // frame only are uploaded with it.
        let (tris, verts) = if opts.use_cache {
            draw_pooled(ctx, passes, pool, &globals_bg, tg, &patches, ranges.as_deref(), &space)?
        } else {
            draw_surface(ctx, passes, &globals_bg, tg, &patches, ranges.as_deref(), &space)?
        };
        let iso: &IsoRenderer = &*self;
        let tg = iso.targets.as_ref().unwrap();
        stats.submissions += 1;
        stats.surface_triangles = tris;
        stats.surface_vertices = verts;
        stats.draw_ms = t_draw.elapsed().as_secs_f64() * 1e3;
        stats.surface_ms = stats.extract_ms + stats.draw_ms;
        stats.total_ms = (t0.elapsed() - untimed).as_secs_f64() * 1e3;

        // ---- Read-back (not part of the frame time).
        let t_rb = Instant::now();
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_readback") });
        let color_rb = ReadbackTexture::new(d, &mut enc, &tg.color_tex, width, height, 4, wgpu::TextureAspect::All);
        let depth_rb = ctx.read_depth(&mut enc, &tg.depth_tex);
        let map_rb = (opts.return_map && implicit && host_map.is_none()).then(|| {
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
        let lin = |raw: Vec<f32>| -> Vec<f32> { raw.par_iter().map(|&v| fc.linear_depth(v)).collect() };
        let depth = lin(depth_rb.read()?);
        if let Some(m) = &map_rb {
            let raw: Vec<f32> =
                bytemuck::cast_slice(&m.slice(..).get_mapped_range().map_err(crate::gpu::map_err)?).to_vec();
            map_out = Some(lin(raw));
        } else if let Some(m) = host_map.filter(|_| opts.return_map) {
            map_out = Some(lin(m));
        } else if opts.return_map {
            map_out = Some(vec![f32::INFINITY; (width * height) as usize]);
        }
        stats.readback_ms = t_rb.elapsed().as_secs_f64() * 1e3;
        stats.setup_ms = setup_ms;
        // This frame's patches that the cache did not keep leave the pool.
        drop(patches);
        self.pool.trim();
        stats.cache_bytes = self.cache_bytes() as u64;
        stats.gpu_cache_bytes = self.pool.bytes();
        stats.contour_bytes = self.classes.as_ref().map_or(0, |g| g.data.contour_bytes());
        Ok(IsoOutput {
            width,
            height,
            image,
            depth,
            nodes: candidates.iter().map(|n| [n.depth, n.ix, n.iy, n.iz]).collect(),
            node_pixels,
            node_drawn,
            map: map_out,
            stats,
            near: fc.near,
            far: fc.far,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Projection;

    fn device() -> Option<GpuContext> {
        GpuContext::new("auto", wgpu::Features::empty()).ok()
    }

    #[test]
    fn sphere_implicit_equals_none() {
        let Some(ctx) = device() else { return };
        let mut r = IsoRenderer::new(&ctx);
        let vol = super::super::sphere_field(24, 0.6);
        let tree = MinMaxOctree::build(&vol);
        let cam = Camera::look_at(
            [3.0, 1.0, 1.0],
            [0.0; 3],
            [0.0, 0.0, 1.0],
            40.0,
            None,
            None,
            Projection::Perspective,
            None,
            1.0,
        )
        .unwrap();
        let none = r
            .render(
                &ctx,
                64,
                64,
                &vol,
                &tree,
                0.0,
                &cam,
                &IsoOptions { culling: IsoCulling::None, ..Default::default() },
            )
            .unwrap();
        let md = tree.max_depth();
        let imp = r
            .render(
                &ctx,
                64,
                64,
                &vol,
                &tree,
                0.0,
                &cam,
                &IsoOptions { occluder_depth: Some(md), cull_depth: Some(md - 1), ..Default::default() },
            )
            .unwrap();
        assert_eq!(none.image, imp.image);
        assert!(imp.stats.surface_triangles < none.stats.surface_triangles);
        assert!(imp.stats.nodes_visible < imp.stats.nodes_straddling);
    }
}
