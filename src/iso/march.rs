//! Crack-free isosurface extraction by marching cubes, per box of cells.
//!
//! Each cell is looked up in a generated case table ([`cases`]): its corner signs plus, for every
//! ambiguous face (diagonal corners of equal sign, the two diagonals opposite), the *face-centre
//! decider*, the sign of the mean of the face's four samples. The decision depends on the face's
//! samples alone, so the two cells that share a face draw the same contour segments on it, and
//! every triangle edge lying in a face is a contour segment: patches of neighbouring cells, of
//! neighbouring octree nodes, and of parallel chunks meet edge to edge with no crack (a closed
//! field gives a closed surface; the tests check every edge is shared by exactly two triangles).
//! One loop of n crossing points gives n - 2 triangles, the classic marching-cubes count.
//!
//! Surface vertices lie on the 12 cube edges. Every such edge goes from a sample `p` to `p + e`
//! with `e` a unit axis step, so `p` is always the endpoint with the lower linear index. The
//! vertex is computed from the edge alone, always interpolating from `p` towards `p + e` in
//! `f64`, so two patches that share an edge produce bit-identical positions and normals. A vertex
//! is the linear interpolation of the isovalue along its edge, where the trilinear interpolant
//! of the cell equals the edge's linear interpolant: every vertex lies on the trilinear surface
//! `f = w` (up to rounding; tested).
//!
//! Conventions:
//! * a sample is *above* when `value >= w` (a sample exactly at `w` is above);
//! * cells touching a NaN sample produce nothing (NaN is outside the domain);
//! * normals are the normalized gradient (central differences, one-sided at the
//!   border or next to NaN), interpolated along the edge, so they point towards
//!   *increasing* values; triangles wind counter-clockwise seen from that side
//!   (the right-hand normal of `(p0,p1,p2)` points towards increasing values);
//! * a sample exactly at `w` may give zero-area triangles (several edges meet at
//!   that sample). They are kept: they draw nothing and keep patches consistent.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use rayon::prelude::*;

use super::octree::NodeInfo;
use cases::{cases, face_centre_above, face_corners, CENTRE, EDGES};

pub(crate) mod cases;
use super::{Volume, Window};

/// Triangles of one box of cells. Positions are grid-frame coordinates (world coordinates of an
/// unrotated volume; see `Volume::to_world`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfacePatch {
    pub positions: Vec<[f64; 3]>,
    /// Unit normals pointing towards increasing field values.
    pub normals: Vec<[f32; 3]>,
    /// Indices into `positions`/`normals`.
    pub triangles: Vec<[u32; 3]>,
    /// The triangles of the box's `c`-th cell (x fastest, then y, z) are
    /// `triangles[cell_starts[c]..cell_starts[c + 1]]` (cells in that order; one entry more than
    /// cells). Empty for a patch that is no box's (`concat`, `default`).
    pub cell_starts: Vec<u32>,
}

impl SurfacePatch {
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    #[cfg(test)]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    #[cfg(test)]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    #[cfg(test)]
    /// Concatenates patches (no welding; shared boundary vertices appear once
    /// per patch with bit-identical positions).
    pub fn concat<'a, I: IntoIterator<Item = &'a SurfacePatch>>(patches: I) -> SurfacePatch {
        let mut out = SurfacePatch::default();
        for p in patches {
            let base = out.positions.len() as u32;
            out.positions.extend_from_slice(&p.positions);
            out.normals.extend_from_slice(&p.normals);
            out.triangles.extend(p.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
        out
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
// ---------------------------------------------------------------------------
// Extraction

/// Central-difference gradient at a sample, in world units; one-sided at the
/// border or next to a NaN neighbour, 0 along an axis with no usable pair.
fn gradient(vol: &Volume, win: &Window<'_>, p: [usize; 3]) -> [f64; 3] {
    let n = [vol.nx, vol.ny, vol.nz];
    let v = &win.data[..];
    let c = win.index(p[0], p[1], p[2]);
    let vc = v[c] as f64;
    let stride = win.strides();
    let mut g = [0.0; 3];
    for a in 0..3 {
        let lo = if p[a] > 0 { Some(v[c - stride[a]] as f64) } else { None }.filter(|x| !x.is_nan());
        let hi = if p[a] + 1 < n[a] { Some(v[c + stride[a]] as f64) } else { None }.filter(|x| !x.is_nan());
        let h = vol.spacing[a];
        g[a] = match (lo, hi) {
            (Some(l), Some(u)) => (u - l) / (2.0 * h),
            (None, Some(u)) => (u - vc) / h,
            (Some(l), None) => (vc - l) / h,
            (None, None) => 0.0,
        };
    }
    g
}

/// Vertex on the edge from sample `p` to `q = p + d` (canonical direction:
/// always interpolated from `p` towards `q`), given both samples' gradients.
#[inline]
#[allow(clippy::too_many_arguments)]
fn edge_vertex(
    vol: &Volume,
    win: &Window<'_>,
    w: f32,
    p: [usize; 3],
    q: [usize; 3],
    ga: [f64; 3],
    gb: [f64; 3],
) -> ([f64; 3], [f32; 3]) {
    let va = win.get(p[0], p[1], p[2]) as f64;
    let vb = win.get(q[0], q[1], q[2]) as f64;
    let t = (w as f64 - va) / (vb - va);
    let pa = vol.sample_position(p[0], p[1], p[2]);
    let pb = vol.sample_position(q[0], q[1], q[2]);
    let pos = [0, 1, 2].map(|a| pa[a] + t * (pb[a] - pa[a]));

    let mut g = [0, 1, 2].map(|a| ga[a] + t * (gb[a] - ga[a]));
    let mut len = dot(g, g).sqrt();
    if len.is_nan() || len <= 0.0 || len.is_infinite() {
        // Degenerate gradient: fall back to the edge direction, oriented
        // towards the higher endpoint value.
        let s = if vb > va { 1.0 } else { -1.0 };
        g = sub(pb, pa).map(|x| x * s);
        len = dot(g, g).sqrt();
    }
    (pos, g.map(|x| (x / len) as f32))
}

const NONE: u32 = u32::MAX;

/// Appends the centroid of the vertices `ids` (normal: their normals' normalized mean) and returns
/// its id.
fn centroid_vertex(patch: &mut SurfacePatch, ids: &[u32]) -> u32 {
    let n = ids.len() as f64;
    let pos = [0, 1, 2].map(|a| ids.iter().map(|&i| patch.positions[i as usize][a]).sum::<f64>() / n);
    let g = [0, 1, 2].map(|a| ids.iter().map(|&i| patch.normals[i as usize][a] as f64).sum::<f64>());
    let len = dot(g, g).sqrt();
    let nrm = if len > 0.0 && len.is_finite() { g.map(|x| (x / len) as f32) } else { patch.normals[ids[0] as usize] };
    patch.positions.push(pos);
    patch.normals.push(nrm);
    (patch.positions.len() - 1) as u32
}

/// Lazily computed sample gradients of two consecutive sample layers.
struct GradLayers {
    sx: usize,
    g: [Vec<[f64; 3]>; 2],
    ok: [Vec<bool>; 2],
}

impl GradLayers {
    fn new(sx: usize, sy: usize) -> Self {
        let n = sx * sy;
        GradLayers { sx, g: [vec![[0.0; 3]; n], vec![[0.0; 3]; n]], ok: [vec![false; n], vec![false; n]] }
    }
    /// Gradient of local sample `(lx, ly)` in layer `layer` (0 = k, 1 = k+1);
    /// `p` is its global index.
    #[inline]
    fn get(&mut self, vol: &Volume, win: &Window<'_>, lx: usize, ly: usize, layer: usize, p: [usize; 3]) -> [f64; 3] {
        let i = ly * self.sx + lx;
        if !self.ok[layer][i] {
            self.g[layer][i] = gradient(vol, win, p);
            self.ok[layer][i] = true;
        }
        self.g[layer][i]
    }
    /// Moves layer k+1 down to layer k.
    fn advance(&mut self) {
        self.g.swap(0, 1);
        self.ok.swap(0, 1);
        self.ok[1].fill(false);
    }
}

struct SerialOut {
    patch: SurfacePatch,
    /// Vertex ids of the in-plane edges of the bottom / top sample layer
    /// (slot `3*(y*sx + x) + dir-1`), for welding z-chunks.
    bottom: Vec<u32>,
    top: Vec<u32>,
}

/// Single-threaded extraction of cells `lo..hi` (already clamped, non-empty), of the cells
/// `(i, j, k)` that `keep` takes (the others are left empty).
fn extract_serial(
    vol: &Volume,
    win: &Window<'_>,
    w: f32,
    lo: [usize; 3],
    hi: [usize; 3],
    keep_planes: bool,
    keep: &(dyn Fn([usize; 3]) -> bool + Sync),
) -> SerialOut {
    let tb = cases();
    let sx = hi[0] - lo[0] + 1;
    let sy = hi[1] - lo[1] + 1;
    let plane_len = sx * sy;
    let mut plane_a = vec![NONE; 2 * plane_len]; // x and y edges of layer k
    let mut plane_b = vec![NONE; 2 * plane_len]; // x and y edges of layer k+1
    let mut zedges = vec![NONE; plane_len]; // z edges from layer k to k+1
    let mut grads = GradLayers::new(sx, sy);
    let mut bottom = Vec::new();
    let mut patch = SurfacePatch::default();

    let [_, nx, nxy] = win.strides();
    let offs = [0, 1, nx, nx + 1, nxy, nxy + 1, nxy + nx, nxy + nx + 1];
    let v = &win.data[..];

    for k in lo[2]..hi[2] {
        if k > lo[2] {
            plane_b.fill(NONE);
            zedges.fill(NONE);
            grads.advance();
        }
        for j in lo[1]..hi[1] {
            let row = win.index(lo[0], j, k);
            for i in lo[0]..hi[0] {
                patch.cell_starts.push(patch.triangles.len() as u32);
                if !keep([i, j, k]) {
                    continue;
                }
                let base = row + (i - lo[0]);
                let mut mask = 0usize;
                let mut nan = false;
                let c = offs.map(|o| v[base + o]);
                for (n, &x) in c.iter().enumerate() {
                    nan |= x.is_nan();
                    mask |= ((x >= w) as usize) << n;
                }
                if nan || mask == 0 || mask == 255 {
                    continue;
                }
                let mut case = mask;
                let amb = tb.ambiguous[mask];
                if amb != 0 {
                    for f in 0..6 {
                        if (amb >> f) & 1 == 1 && face_centre_above(face_corners(f).map(|q| c[q as usize]), w) {
                            case |= 1 << (8 + f);
                        }
                    }
                }
                let (li, lj) = (i - lo[0], j - lo[1]);
                let mut at = |e: u8, patch: &mut SurfacePatch| -> u32 {
                    let (lc, d) = EDGES[e as usize];
                    let px = li + (lc & 1) as usize;
                    let py = lj + ((lc >> 1) & 1) as usize;
                    let pz = (lc >> 2) as usize;
                    let cell = py * sx + px;
                    let slot = if pz != 0 {
                        &mut plane_b[2 * cell + (d >> 1) as usize]
                    } else if d == 4 {
                        &mut zedges[cell]
                    } else {
                        &mut plane_a[2 * cell + (d >> 1) as usize]
                    };
                    if *slot == NONE {
                        let (qx, qy, qz) =
                            (px + (d & 1) as usize, py + ((d >> 1) & 1) as usize, pz + ((d >> 2) & 1) as usize);
                        let p = [lo[0] + px, lo[1] + py, k + pz];
                        let q = [lo[0] + qx, lo[1] + qy, k + qz];
                        let ga = grads.get(vol, win, px, py, pz, p);
                        let gb = grads.get(vol, win, qx, qy, qz, q);
                        let (pos, nrm) = edge_vertex(vol, win, w, p, q, ga, gb);
                        *slot = patch.positions.len() as u32;
                        patch.positions.push(pos);
                        patch.normals.push(nrm);
                    }
                    *slot
                };
                // The rare loops fanned about their centroid: a vertex of this cell alone.
                let mut centre = [NONE; 4];
                if tb.has_centre[case] {
                    for (c, lp) in centre.iter_mut().zip(tb.centres(case)) {
                        let ids: Vec<u32> = lp.iter().map(|&e| at(e, &mut patch)).collect();
                        *c = centroid_vertex(&mut patch, &ids);
                    }
                }
                for tri in &tb.tris[tb.start[case] as usize..tb.start[case + 1] as usize] {
                    let out = tri.map(|e| if e < CENTRE { at(e, &mut patch) } else { centre[(e - CENTRE) as usize] });
                    patch.triangles.push(out);
                }
            }
        }
        if keep_planes && k == lo[2] {
            bottom = plane_a.clone();
        }
        std::mem::swap(&mut plane_a, &mut plane_b);
    }
    patch.cell_starts.push(patch.triangles.len() as u32);
    SerialOut { patch, bottom, top: if keep_planes { plane_a } else { Vec::new() } }
}

/// Clamps a cell box to the volume; `None` when empty.
fn clamp_box(vol: &Volume, cell_lo: [u32; 3], cell_hi: [u32; 3]) -> Option<([usize; 3], [usize; 3])> {
    let cells = vol.cells();
    let hi = [0, 1, 2].map(|a| (cell_hi[a] as usize).min(cells[a]));
    let lo = [0, 1, 2].map(|a| (cell_lo[a] as usize).min(hi[a]));
    if (0..3).any(|a| lo[a] >= hi[a]) {
        None
    } else {
        Some((lo, hi))
    }
}

/// Boxes with at least this many cells are split into z-chunks and extracted
/// in parallel by [`extract`].
const PARALLEL_MIN_CELLS: usize = 32 * 32 * 32;

/// Splits `v` into consecutive mutable pieces of the given lengths.
fn split_lengths<'a, T>(mut v: &'a mut [T], lens: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(lens.len());
    for &l in lens {
        let (a, b) = std::mem::take(&mut v).split_at_mut(l);
        out.push(a);
        v = b;
    }
    out
}

/// Extracts the isosurface `w` in the cell box `[cell_lo, cell_hi)` (clamped to
/// the volume). Positions are grid-frame coordinates; vertices are shared between
/// the triangles of the box. Large boxes are processed in parallel z-chunks
/// and welded; the result does not depend on the thread count.
pub fn extract(vol: &Volume, w: f32, cell_lo: [u32; 3], cell_hi: [u32; 3]) -> SurfacePatch {
    let Some((lo, hi)) = clamp_box(vol, cell_lo, cell_hi) else {
        return SurfacePatch::default();
    };
    let layers = hi[2] - lo[2];
    let cells = (hi[0] - lo[0]) * (hi[1] - lo[1]) * layers;
    let win = vol.cell_window(lo, hi);
    if cells < PARALLEL_MIN_CELLS || layers < 2 {
        return extract_serial(vol, &win, w, lo, hi, false, &|_| true).patch;
    }
    // Fixed chunking (independent of the thread count) for reproducible output.
    let nchunks = layers.min(64).min(cells / (PARALLEL_MIN_CELLS / 4)).max(2);
    let bounds: Vec<(usize, usize)> =
        (0..nchunks).map(|c| (lo[2] + layers * c / nchunks, lo[2] + layers * (c + 1) / nchunks)).collect();
    let parts: Vec<SerialOut> = bounds
        .par_iter()
        .map(|&(z0, z1)| extract_serial(vol, &win, w, [lo[0], lo[1], z0], [hi[0], hi[1], z1], true, &|_| true))
        .collect();

    // Weld: a chunk's bottom-plane vertices are the previous chunk's top-plane
    // vertices (same edges, bit-identical), and those are never themselves
    // shared (a chunk has >= 1 layer). Every other vertex is "own"; a chunk's
    // own vertices get consecutive global ids, in local order.
    struct Numbering {
        shared_from: Vec<u32>, // prev-chunk local id, or NONE
        own_local: Vec<u32>,   // index among own vertices, or NONE
        own: usize,
    }
    let numberings: Vec<Numbering> = (0..parts.len())
        .into_par_iter()
        .map(|c| {
            let n = parts[c].patch.positions.len();
            let mut shared_from = vec![NONE; n];
            if c > 0 {
                let prev_top = &parts[c - 1].top;
                for (s, &b) in parts[c].bottom.iter().enumerate() {
                    if b != NONE && prev_top[s] != NONE {
                        shared_from[b as usize] = prev_top[s];
                    }
                }
            }
            let mut own_local = vec![NONE; n];
            let mut own = 0usize;
            for (l, &sf) in shared_from.iter().enumerate() {
                if sf == NONE {
                    own_local[l] = own as u32;
                    own += 1;
                }
            }
            Numbering { shared_from, own_local, own }
        })
        .collect();
    let mut base = Vec::with_capacity(parts.len());
    let mut total = 0usize;
    for nb in &numberings {
        base.push(total as u32);
        total += nb.own;
    }
    let own_lens: Vec<usize> = numberings.iter().map(|nb| nb.own).collect();
    let tri_lens: Vec<usize> = parts.iter().map(|p| p.patch.triangles.len()).collect();

    // Cell order is chunk order: each chunk's starts, offset by the triangles before it.
    let mut cell_starts = Vec::with_capacity((hi[0] - lo[0]) * (hi[1] - lo[1]) * layers + 1);
    let mut tri_base = 0u32;
    for p in &parts {
        let s = &p.patch.cell_starts;
        cell_starts.extend(s[..s.len() - 1].iter().map(|&v| v + tri_base));
        tri_base += p.patch.triangles.len() as u32;
    }
    cell_starts.push(tri_base);
    let mut out = SurfacePatch {
        positions: vec![[0.0; 3]; total],
        normals: vec![[0.0; 3]; total],
        triangles: vec![[0; 3]; tri_lens.iter().sum()],
        cell_starts,
    };
    let pos_parts = split_lengths(&mut out.positions, &own_lens);
    let nrm_parts = split_lengths(&mut out.normals, &own_lens);
    let tri_parts = split_lengths(&mut out.triangles, &tri_lens);
    pos_parts.into_par_iter().zip(nrm_parts).zip(tri_parts).enumerate().for_each(|(c, ((pos, nrm), tri))| {
        let nb = &numberings[c];
        let part = &parts[c].patch;
        for (l, &o) in nb.own_local.iter().enumerate() {
            if o != NONE {
                pos[o as usize] = part.positions[l];
                nrm[o as usize] = part.normals[l];
            }
        }
        let global = |l: u32| -> u32 {
            let o = nb.own_local[l as usize];
            if o != NONE {
                base[c] + o
            } else {
                let prev = &numberings[c - 1];
                base[c - 1] + prev.own_local[nb.shared_from[l as usize] as usize]
            }
        };
        for (dst, src) in tri.iter_mut().zip(&part.triangles) {
            *dst = src.map(global);
        }
    });
    out
}

/// Extracts one patch per node (over the node's cell box), in parallel.
pub fn extract_nodes(vol: &Volume, w: f32, nodes: &[NodeInfo]) -> Vec<SurfacePatch> {
    nodes.par_iter().map(|n| extract(vol, w, n.cell_lo, n.cell_hi)).collect()
}

/// [`extract_nodes`] of the cells `(i, j, k)` that `keep` takes: each node's patch has the
/// triangles (and only the vertices) of those cells, the very ones [`extract`] gives them, in the
/// same order, and every cell of its box in `cell_starts` (the others empty). Nodes in parallel,
/// each on one thread.
pub fn extract_nodes_where(
    vol: &Volume,
    w: f32,
    nodes: &[NodeInfo],
    keep: &(dyn Fn([usize; 3]) -> bool + Sync),
) -> Vec<SurfacePatch> {
    nodes
        .par_iter()
        .map(|n| match clamp_box(vol, n.cell_lo, n.cell_hi) {
            Some((lo, hi)) => extract_serial(vol, &vol.cell_window(lo, hi), w, lo, hi, false, keep).patch,
            None => SurfacePatch::default(),
        })
        .collect()
}

// ---------------------------------------------------------------------------
// Cache

/// Cache key: `(isovalue bits, depth, ix, iy, iz)`.
pub type PatchKey = (u32, u32, u32, u32, u32);

/// Key for isovalue `w` and `node`; `-0.0` and `0.0` share a key.
pub fn patch_key(w: f32, node: &NodeInfo) -> PatchKey {
    let w = if w == 0.0 { 0.0f32 } else { w };
    (w.to_bits(), node.depth, node.ix, node.iy, node.iz)
}

/// Default memory budget of a [`PatchCache`]: 256 MiB.
pub const DEFAULT_CACHE_BUDGET: usize = 256 << 20;

/// Host bytes a cached patch holds: its arrays (by capacity), the patch and its map entry.
pub fn patch_bytes(p: &SurfacePatch) -> usize {
    std::mem::size_of::<SurfacePatch>()
        + std::mem::size_of::<(PatchKey, Entry)>()
        + p.positions.capacity() * std::mem::size_of::<[f64; 3]>()
        + p.normals.capacity() * std::mem::size_of::<[f32; 3]>()
        + p.triangles.capacity() * std::mem::size_of::<[u32; 3]>()
        + p.cell_starts.capacity() * 4
}

struct Entry {
    patch: Arc<SurfacePatch>,
    bytes: usize,
    /// The frame (`PatchCache::tick`) that last used it.
    used: u64,
}

/// Extracted patches keyed by `(isovalue bits, depth, ix, iy, iz)`, so later
/// frames reuse earlier extractions, within a memory budget: when the patches
/// held exceed it, the least recently used are dropped (LRU by bytes, see
/// [`patch_bytes`]) down to 7/8 of the budget, so eviction is rare. The
/// cache remembers which volume it was filled from (the `values` allocation
/// plus geometry) and clears itself when asked about a different one. Nodes
/// must come from a [`MinMaxOctree`] of that volume.
///
/// [`MinMaxOctree`]: super::octree::MinMaxOctree
pub struct PatchCache {
    map: HashMap<PatchKey, Entry>,
    source: Option<super::VolumeId>,
    bytes: usize,
    budget: usize,
    tick: u64,
}

impl Default for PatchCache {
    fn default() -> Self {
        Self::with_budget(DEFAULT_CACHE_BUDGET)
    }
}

impl PatchCache {
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty cache holding at most `budget` bytes of patches.
    pub fn with_budget(budget: usize) -> Self {
        Self { map: HashMap::new(), source: None, bytes: 0, budget, tick: 0 }
    }

    fn bind(&mut self, vol: &Volume) {
        if !self.source.as_ref().is_some_and(|s| s.matches(vol)) {
            self.map.clear();
            self.bytes = 0;
            self.source = Some(super::VolumeId::of(vol));
        }
    }

    /// One patch per node, in order: cached ones are shared, missing ones are
    /// extracted in parallel and inserted; then the budget is enforced (the
    /// returned patches stay valid whatever is evicted).
    pub fn get_or_extract_many(&mut self, vol: &Volume, w: f32, nodes: &[NodeInfo]) -> Vec<Arc<SurfacePatch>> {
        self.bind(vol);
        self.tick += 1;
        let tick = self.tick;
        let mut seen = HashSet::new();
        let missing: Vec<&NodeInfo> = nodes
            .iter()
            .filter(|n| {
                let k = patch_key(w, n);
                !self.map.contains_key(&k) && seen.insert(k)
            })
            .collect();
        let fresh: Vec<(PatchKey, Arc<SurfacePatch>)> = missing
            .par_iter()
            .map(|n| {
                let mut p = extract(vol, w, n.cell_lo, n.cell_hi);
                // Kept for later frames: no growth slack (up to half of a Vec's capacity).
                p.positions.shrink_to_fit();
                p.normals.shrink_to_fit();
                p.triangles.shrink_to_fit();
                p.cell_starts.shrink_to_fit();
                (patch_key(w, n), Arc::new(p))
            })
            .collect();
        for (k, patch) in fresh {
            let bytes = patch_bytes(&patch);
            self.bytes += bytes;
            self.map.insert(k, Entry { patch, bytes, used: tick });
        }
        let out = nodes
            .iter()
            .map(|n| {
                let e = self.map.get_mut(&patch_key(w, n)).expect("inserted above");
                e.used = tick;
                e.patch.clone()
            })
            .collect();
        self.evict();
        out
    }

    /// Drops least recently used patches while the cache holds more than its budget (down to 7/8
    /// of it).
    fn evict(&mut self) {
        if self.bytes <= self.budget {
            return;
        }
        let target = self.budget - self.budget / 8;
        let mut order: Vec<(u64, PatchKey, usize)> = self.map.iter().map(|(k, e)| (e.used, *k, e.bytes)).collect();
        order.sort_unstable();
        for (_, k, b) in order {
            if self.bytes <= target {
                break;
            }
            self.map.remove(&k);
            self.bytes -= b;
        }
    }

    /// Sets the budget (bytes) and evicts down to it.
    pub fn set_budget(&mut self, budget: usize) {
        self.budget = budget;
        self.evict();
    }

    #[cfg(test)]
    pub fn budget(&self) -> usize {
        self.budget
    }

    /// Bytes of patches held (see [`patch_bytes`]); at most the budget after every call.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    #[cfg(test)]
    /// The cached patch for `(w, node)`, if any.
    pub fn get(&self, w: f32, node: &NodeInfo) -> Option<Arc<SurfacePatch>> {
        self.map.get(&patch_key(w, node)).map(|e| e.patch.clone())
    }

    #[cfg(test)]
    /// Drops every patch not extracted at isovalue `w`.
    pub fn retain_isovalue(&mut self, w: f32) {
        let bits = if w == 0.0 { 0.0f32 } else { w }.to_bits();
        self.map.retain(|k, _| k.0 == bits);
        self.bytes = self.map.values().map(|e| e.bytes).sum();
    }

    pub fn len(&self) -> usize {
        self.map.len()
    }

    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    pub fn clear(&mut self) {
        self.map.clear();
        self.bytes = 0;
        self.source = None;
    }
}

// ---------------------------------------------------------------------------

#[cfg(test)]
mod tests;
