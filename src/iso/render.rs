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

mod frame;
mod options;

pub use options::{IsoCulling, IsoOptions, IsoOutput, IsoStats, IsoWalk};

use std::sync::Arc;
use std::time::Instant;

pub use super::bricks::node_classes;
use super::march::PatchCache;
use super::octree::{MinMaxOctree, NodeInfo};
use super::oracle::{widen_where_wrong, OracleCells, ORACLE_TRIES};
use super::passes::{ClassGrid, IsoPasses, Targets};
use super::pool::SurfacePool;
use super::Volume;
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::GpuContext;
use frame::FrameArgs;

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
        let args = FrameArgs { ctx, width, height, vol, tree, isovalue, camera, opts };
        if opts.culling != IsoCulling::Oracle {
            return self.frame(&args, None);
        }
        // The oracle: the unculled frame first, outside the clock; then frames of the cells of its
        // pixels' surface points until one draws its image (`iso::oracle`).
        let none = IsoOptions { culling: IsoCulling::None, return_map: false, ..opts.clone() };
        let reference = self.frame(&FrameArgs { opts: &none, ..args }, None)?;
        let mut cells = OracleCells { depth: reference.depth, reach: vec![0.0; (width * height) as usize] };
        let mut tries = 0;
        loop {
            let out = self.frame(&args, Some(&cells))?;
            tries += 1;
            if widen_where_wrong(&mut cells, &out.image, &reference.image) == 0 || tries == ORACLE_TRIES {
                return Ok(out);
            }
        }
    }
}

#[cfg(test)]
mod tests;
