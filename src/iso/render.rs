//! GPU side of implicit occluders (Pesco, Lindstrom, Pascucci, Silva, "Implicit Occluders").
//!
//! [`IsoRenderer::render`] (through `Renderer::render_isosurface`) draws the isosurface `f = w` of a [`Volume`], extracting surface
//! only inside octree nodes that can be seen:
//!
//! 1. **Occluders** (view independent, cached per isovalue and build depth): descending the
//!    min/max octree from the root, every node of depth <= `occluder_depth` that lies wholly
//!    below `w` (`max < w`) becomes a *Below* box and every node wholly above (`min > w`) an
//!    *Above* box; straddling nodes are refined down to `occluder_depth` and never occlude.
//!    The union of these boxes equals the union of the Below/Above nodes *at* `occluder_depth`
//!    (the paper's set), with far fewer boxes. Boxes are shrunk by a small epsilon.
//! 2. **Occlusion map** (three depth-only passes, reverse-Z, at image resolution):
//!    * pass 1: all faces of the Below boxes, depth test Greater → `B(p)`, the nearest point of a
//!      Below box on pixel `p`'s ray (0 = none);
//!    * pass 2: the same for the Above boxes → `A(p)`;
//!    * pass 3 into the map `M` (cleared to 0 = far): all faces of the Above boxes, discarding
//!      fragments not strictly farther than `B(p)`, then all faces of the Below boxes discarding
//!      fragments not strictly farther than `A(p)`; depth test Greater keeps the nearest survivor.
//!
//!    So `M(p)` is the nearest point on the ray that lies in a box of one class *behind* a point
//!    of a box of the other class (0 where no such pair exists). This is the paper's stencil
//!    formulation (Below boxes mark the stencil, Above boxes drawn front to back where it is set,
//!    unmarked pixels reset to far) done with a depth-texture read instead of stencil + sorting,
//!    and for both orders (below→above and above→below).
//!
//!    **Why it is conservative.** The rendered surface is the marching-cubes surface
//!    ([`super::march`]): crack free, it is closed except where NaN cells stop it, and inside every
//!    cell it separates the cell's above corners from its below corners, so it splits the volume
//!    into an above and a below side. A Below box holds no triangle (all its samples are below,
//!    none of its cells is cut, and no neighbour's triangle reaches its faces: those have no
//!    crossing edge), so it lies on the below side; an Above box on the above side (Below and Above
//!    nodes never touch because touching nodes share samples). The ray segment between the Below
//!    point and the Above point (inside the convex volume) goes from one side to the other, so it
//!    crosses the surface strictly before `M(p)`. Any surface point behind `M(p)` is hidden.
//! 3. **Node test**, coarse to fine from `cull_depth - 2` to `cull_depth`: the front faces of the
//!    boxes of the straddling nodes (expanded by a small epsilon) are rasterised without a depth
//!    attachment; the fragment shader compares each fragment's depth with `M` and counts, per node,
//!    the pixels where the box is nearer than or as near as the map (`atomicAdd` into a storage
//!    buffer; exact counts, one front-face fragment per pixel of a convex box). A node is visible
//!    when its count is > 0; only the children of visible nodes are tested at the next depth.
//!    The surface inside a node lies inside its box, so on every pixel where the node's surface is
//!    the first hit, the box's entry point is nearer than `M(p)`: the culled image equals the
//!    unculled one. Boxes that reach the near plane (or contain the eye) are visible untested.
//! 4. **Surface**: marching cubes ([`super::march`]) in the visible nodes at `cull_depth`,
//!    cached per (volume, isovalue, node) in a [`PatchCache`]; drawn lit (two-sided Lambert).
//!
//! Depths count from the root (0) as in the octree; the leaves (single cells) are at
//! `tree.max_depth()`. A volume of 256³ samples has 255 cells per axis and max depth 8, matching
//! the paper's numbering for its 256³ volume; for a 128³ volume subtract 1 to compare node sizes.

use std::sync::Arc;
use std::time::Instant;

use glam::{DMat4, DVec3, DVec4, Mat4};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::march::{PatchCache, SurfacePatch, DEFAULT_CACHE_BUDGET};
use super::octree::{Class, MinMaxOctree, NodeInfo};
use super::passes::{draw_map, draw_surface, test_nodes, BoxInstance, Globals, IsoPasses, Occluders, Space, Targets};
use super::Volume;
use crate::camera::{Camera, FrameCamera};
use crate::error::{ensure, input_err, Interrupt, Result};
use crate::gpu::{GpuContext, ReadbackTexture};

/// How the isosurface is culled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsoCulling {
    /// Extract and draw the whole isosurface (the reference).
    None,
    /// Implicit occluders: extract only inside nodes that pass the occlusion-map test.
    Implicit,
}

impl IsoCulling {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Self::None),
            "implicit" => Ok(Self::Implicit),
            _ => Err(input_err("culling", format!("unknown culling {s:?}; expected \"implicit\" or \"none\""))),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Implicit => "implicit",
        }
    }
}

/// Options of one isosurface frame.
#[derive(Clone, Debug)]
pub struct IsoOptions {
    pub culling: IsoCulling,
    /// Depth of the occluder nodes (root = 0); `None` = `max_depth - 1`.
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
    /// Below / Above occluder boxes drawn into the map.
    pub occluder_boxes_below: u32,
    pub occluder_boxes_above: u32,
    pub occluder_depth: u32,
    pub cull_depth: u32,
    pub max_depth: u32,
    /// Patches found in the cache / extracted this frame.
    pub patches_cached: u32,
    pub patches_extracted: u32,
    /// Occluder selection + occlusion map (GPU finished).
    pub occluder_ms: f64,
    /// Coarse-to-fine node tests, read-backs included.
    pub cull_ms: f64,
    /// Marching cubes (cache look-ups included).
    pub extract_ms: f64,
    /// Vertex assembly, upload and the lit draw (GPU finished).
    pub draw_ms: f64,
    /// extract_ms + draw_ms.
    pub surface_ms: f64,
    /// Whole frame, from the call to the GPU finishing the image (no read-back).
    pub total_ms: f64,
    pub readback_ms: f64,
    /// Bytes held by the renderer's isosurface caches after the frame (patches and straddling-node
    /// lists), at most `IsoOptions::cache_budget`.
    pub cache_bytes: u64,
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
    /// Per node of `nodes`: pixels where its box is in front of the occlusion map (0 when a coarser
    /// ancestor was already hidden, or for culling = none).
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
    passes: IsoPasses,
    targets: Option<Targets>,
    source: Option<super::VolumeId>,
    occluders: Option<Occluders>,
    /// Straddling nodes per (isovalue bits, depth).
    straddling: Vec<StraddlingEntry>,
    patches: PatchCache,
}

impl IsoRenderer {
    pub fn new(d: &wgpu::Device) -> Self {
        Self {
            passes: IsoPasses::new(d),
            targets: None,
            source: None,
            occluders: None,
            straddling: Vec::new(),
            patches: PatchCache::new(),
        }
    }

    /// Drops every cache when the volume changed.
    fn bind_volume(&mut self, vol: &Volume) {
        if !self.source.as_ref().is_some_and(|s| s.matches(vol)) {
            self.occluders = None;
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
        self.occluders = None;
        self.straddling.clear();
        self.patches.clear();
        self.source = None;
    }
}

fn norm_bits(w: f32) -> u32 {
    if w == 0.0 { 0.0f32 } else { w }.to_bits()
}

/// The occluders of depth `depth`: maximal Below and Above nodes of depth <= `depth` (see the
/// module docs). Returned in octree order (deterministic).
pub fn occluder_nodes(tree: &MinMaxOctree, w: f32, depth: u32) -> (Vec<NodeInfo>, Vec<NodeInfo>) {
    let depth = depth.min(tree.max_depth());
    let (mut below, mut above) = (Vec::new(), Vec::new());
    let mut frontier = vec![tree.root()];
    for d in 0..=depth {
        let (b, a, next): (Vec<NodeInfo>, Vec<NodeInfo>, Vec<NodeInfo>) = frontier
            .par_iter()
            .fold(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut b, mut a, mut nx), n| {
                    match n.classify(w) {
                        Class::Below => b.push(*n),
                        Class::Above => a.push(*n),
                        Class::Straddles if d < depth => nx.extend(tree.children(n)),
                        _ => {}
                    }
                    (b, a, nx)
                },
            )
            .reduce(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut b0, mut a0, mut n0), (b1, a1, n1)| {
                    b0.extend(b1);
                    a0.extend(a1);
                    n0.extend(n1);
                    (b0, a0, n0)
                },
            );
        below.extend(b);
        above.extend(a);
        frontier = next;
    }
    (below, above)
}

/// True when some part of the box (grid frame, turned into render space by `model`) is not in
/// front of the near plane (so the test pass could miss it): such nodes are treated as visible.
fn reaches_near_plane(fc: &FrameCamera, model: &DMat4, b: &BoxInstance) -> bool {
    let mut dmin = f64::INFINITY;
    for i in 0..8 {
        let c = model.transform_point3(DVec3::new(
            if i & 1 == 0 { b.lo[0] } else { b.hi[0] } as f64,
            if i & 2 == 0 { b.lo[1] } else { b.hi[1] } as f64,
            if i & 4 == 0 { b.lo[2] } else { b.hi[2] } as f64,
        ));
        dmin = dmin.min((c - fc.eye).dot(fc.forward));
    }
    dmin <= fc.near * 1.001 + 1e-9
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
        // In the volume's units; from here on everything is a residual about `vol.offset`.
        let w = vol.residual(isovalue, "isovalue")?;
        ensure(opts.color.iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c)), "color", || {
            format!("color is {:?}; expected (r, g, b) in [0, 1]", opts.color)
        })?;
        ensure(tree.cells() == [vol.nx as u32 - 1, vol.ny as u32 - 1, vol.nz as u32 - 1], "volume", || {
            "the octree was built from another volume".into()
        })?;
        let maxd = tree.max_depth();
        let occ_depth = opts.occluder_depth.unwrap_or(maxd.saturating_sub(1));
        let cull_depth = opts.cull_depth.unwrap_or(maxd.saturating_sub(2));
        ensure(occ_depth <= maxd, "occluder_depth", || {
            format!("occluder_depth is {occ_depth}; this volume's octree has depths 0..={maxd}")
        })?;
        ensure(cull_depth <= maxd, "cull_depth", || {
            format!("cull_depth is {cull_depth}; this volume's octree has depths 0..={maxd}")
        })?;

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
        // Occluders shrink, tested boxes grow, by a thousandth of a cell: rasterisation ties never
        // cull a visible node.
        let eps = 1e-3 * min_spacing;

        let d = &ctx.device;
        let iso: &mut IsoRenderer = self;
        iso.bind_volume(vol);
        Targets::ensure(&mut iso.targets, d, width, height);
        // A quarter of the budget for node lists, the rest for patches.
        let (list_budget, patch_budget) = (opts.cache_budget / 4, opts.cache_budget - opts.cache_budget / 4);
        iso.patches.set_budget(patch_budget);
        let candidates = iso.straddling(tree, w, cull_depth, list_budget);
        let implicit = opts.culling == IsoCulling::Implicit;
        let t_occ = Instant::now();
        if implicit {
            let okey = (
                norm_bits(w),
                occ_depth,
                [
                    space.origin.x.to_bits(),
                    space.origin.y.to_bits(),
                    space.origin.z.to_bits(),
                    camera.z_scale.to_bits(),
                ],
            );
            if iso.occluders.as_ref().is_none_or(|o| o.key != okey) {
                iso.occluders = None;
                let (below, above) = occluder_nodes(tree, w, occ_depth);
                let make = |nodes: &[NodeInfo], label: &str| {
                    (!nodes.is_empty()).then(|| {
                        let inst: Vec<BoxInstance> = nodes.par_iter().map(|n| space.instance(n, 0, -eps)).collect();
                        d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some(label),
                            contents: bytemuck::cast_slice(&inst),
                            usage: wgpu::BufferUsages::VERTEX,
                        })
                    })
                };
                iso.occluders = Some(Occluders {
                    key: okey,
                    below: make(&below, "iso_below"),
                    above: make(&above, "iso_above"),
                    n_below: below.len() as u32,
                    n_above: above.len() as u32,
                });
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

        // ---- Occlusion map, then coarse-to-fine node tests.
        let visible: Vec<NodeInfo> = if !implicit {
            candidates.to_vec()
        } else {
            let occ = iso.occluders.as_ref().unwrap();
            stats.occluder_boxes_below = occ.n_below;
            stats.occluder_boxes_above = occ.n_above;
            draw_map(ctx, &iso.passes, iso.targets.as_ref().unwrap(), &globals_bg, occ)?;
            opts.interrupt.check()?;
            stats.occluder_ms = t_occ.elapsed().as_secs_f64() * 1e3;
            let t_cull = Instant::now();
            let start = cull_depth.saturating_sub(2);
            let mut level: Vec<NodeInfo> =
                if start == cull_depth { candidates.to_vec() } else { tree.straddling_at_depth(w, start) };
            let mut d_level = start;
            let vis_final: Vec<NodeInfo> = loop {
                let boxes: Vec<BoxInstance> =
                    level.par_iter().enumerate().map(|(i, n)| space.instance(n, i as u32, eps)).collect();
                let forced: Vec<bool> = boxes.par_iter().map(|b| reaches_near_plane(&fc, &model, b)).collect();
                let counts = test_nodes(ctx, &iso.passes, iso.targets.as_ref().unwrap(), &globals_bg, &boxes)?;
                opts.interrupt.check()?;
                stats.nodes_tested += level.len() as u32;
                let vis: Vec<NodeInfo> = level
                    .iter()
                    .zip(&counts)
                    .zip(&forced)
                    .filter(|((_, &c), &f)| c > 0 || f)
                    .map(|((n, _), _)| *n)
                    .collect();
                if d_level == cull_depth {
                    stats.nodes_tested_cull_depth = level.len() as u32;
                    let index: std::collections::HashMap<(u32, u32, u32), usize> =
                        candidates.iter().enumerate().map(|(i, n)| ((n.ix, n.iy, n.iz), i)).collect();
                    for (n, &c) in level.iter().zip(&counts) {
                        if let Some(&i) = index.get(&(n.ix, n.iy, n.iz)) {
                            node_pixels[i] = c;
                        }
                    }
                    // Keep octree order (the order of `candidates`), like culling = none.
                    let mut keep = vec![false; candidates.len()];
                    for n in &vis {
                        if let Some(&i) = index.get(&(n.ix, n.iy, n.iz)) {
                            keep[i] = true;
                        }
                    }
                    break candidates.iter().zip(&keep).filter(|(_, &k)| k).map(|(n, _)| *n).collect();
                }
                level = vis
                    .par_iter()
                    .flat_map_iter(|n| {
                        let mut c = tree.children(n);
                        c.retain(|c| c.straddles(w));
                        c
                    })
                    .collect();
                d_level += 1;
            };
            stats.cull_ms = t_cull.elapsed().as_secs_f64() * 1e3;
            vis_final
        };
        stats.nodes_visible = visible.len() as u32;
        let node_drawn: Vec<bool> = if implicit {
            let set: std::collections::HashSet<(u32, u32, u32)> = visible.iter().map(|n| (n.ix, n.iy, n.iz)).collect();
            candidates.iter().map(|n| set.contains(&(n.ix, n.iy, n.iz))).collect()
        } else {
            vec![true; candidates.len()]
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
            super::march::extract_nodes(vol, w, &visible).into_iter().map(Arc::new).collect()
        };
        stats.extract_ms = t_ex.elapsed().as_secs_f64() * 1e3;
        opts.interrupt.check()?;

        // ---- Draw.
        let t_draw = Instant::now();
        let d = &ctx.device;
        let iso: &IsoRenderer = &*self;
        let tg = iso.targets.as_ref().unwrap();
        let (tris, verts) = draw_surface(ctx, &iso.passes, &globals_bg, tg, &patches, &space)?;
        stats.surface_triangles = tris;
        stats.surface_vertices = verts;
        stats.draw_ms = t_draw.elapsed().as_secs_f64() * 1e3;
        stats.surface_ms = stats.extract_ms + stats.draw_ms;
        stats.total_ms = t0.elapsed().as_secs_f64() * 1e3;

        // ---- Read-back (not part of the frame time).
        let t_rb = Instant::now();
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_readback") });
        let color_rb = ReadbackTexture::new(d, &mut enc, &tg.color_tex, width, height, 4, wgpu::TextureAspect::All);
        let depth_rb = ctx.read_depth(&mut enc, &tg.depth_tex);
        let map_rb = (opts.return_map && implicit).then(|| ctx.read_depth(&mut enc, &tg.map_tex));
        ctx.queue.submit([enc.finish()]);
        for b in [&color_rb.buffer, depth_rb.buffer()].into_iter().chain(map_rb.as_ref().map(|m| m.buffer())) {
            b.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        }
        ctx.wait()?;
        ctx.take_error()?;
        let image = color_rb.read_rows()?;
        let lin = |raw: Vec<f32>| -> Vec<f32> { raw.par_iter().map(|&v| fc.linear_depth(v)).collect() };
        let depth = lin(depth_rb.read()?);
        if let Some(m) = &map_rb {
            map_out = Some(lin(m.read()?));
        } else if opts.return_map {
            map_out = Some(vec![f32::INFINITY; (width * height) as usize]);
        }
        stats.readback_ms = t_rb.elapsed().as_secs_f64() * 1e3;
        stats.cache_bytes = self.cache_bytes() as u64;
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
    fn occluders_partition_the_classified_volume() {
        let vol = super::super::sphere_field(17, 0.5);
        let tree = MinMaxOctree::build(&vol);
        let (b, a) = occluder_nodes(&tree, 0.0, tree.max_depth());
        assert!(b.iter().all(|n| n.max < 0.0) && a.iter().all(|n| n.min > 0.0));
        let cells = |v: &[NodeInfo]| v.iter().map(|n| n.cell_count()).sum::<u64>();
        let leaves = tree.nodes_at_depth(tree.max_depth());
        let nb = leaves.iter().filter(|n| n.max < 0.0).count() as u64;
        let na = leaves.iter().filter(|n| n.min > 0.0).count() as u64;
        assert_eq!((cells(&b), cells(&a)), (nb, na));
    }

    #[test]
    fn sphere_implicit_equals_none() {
        let Some(ctx) = device() else { return };
        let mut r = IsoRenderer::new(&ctx.device);
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
