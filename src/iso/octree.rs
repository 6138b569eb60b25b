//! Min/max octree over the cells of a [`Volume`].
//!
//! Cell `(i,j,k)` spans samples `i..=i+1`, `j..=j+1`, `k..=k+1`. With
//! `D = ceil(log2(max cells per axis))`, depth 0 is the root covering the
//! padded cube of `2^D` cells per side and a node at depth `d` covers a block of
//! `2^(D-d)` cells per side (depth `D` = single cells). Only nodes that
//! intersect the real volume exist; their cell ranges are clamped to it.
//!
//! **Compact storage.** Min/max are stored for depths `0..=B` only, where `B = D - 3`
//! ([`BRICK_LEVELS`]): the finest stored nodes are bricks of 8³ cells, so the pyramid has
//! about (n/8)³ · 8/7 entries of 8 bytes (about 0.02 bytes per sample; single-cell leaves cost
//! 9 bytes per sample, twice a float32 volume). The nodes of the three finer depths (4³, 2³ and
//! single cells, at most 125 samples each) are answered by scanning the volume's samples, which
//! the tree shares (`Arc`). The public numbering is unchanged: depth `D` = single cells.
//!
//! **NaN samples** are outside the domain and carry no surface: they are skipped in min/max (a
//! node whose samples are all NaN gets `min = +inf, max = -inf`), and every node records whether
//! any of its samples is NaN (`has_nan`). A node with a NaN is never wholly below or wholly above
//! ([`Class::Below`] / [`Class::Above`] are NaN-free by definition), so it never acts as an
//! implicit occluder: it is [`Class::Straddles`] when its finite samples straddle the isovalue (some
//! of its NaN-free cells may hold surface), else [`Class::Empty`].

use std::sync::Arc;

use rayon::prelude::*;

use super::store::BrickCache;
use super::Volume;
use build::{brick_rows, build_streaming};

mod build;

/// Depths below the finest stored level, answered by scanning samples: bricks of 2^3 = 8 cells.
pub const BRICK_LEVELS: u32 = 3;

/// Position of an isovalue relative to a node's value range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// `max < w` and no NaN: the node lies wholly below the isovalue.
    Below,
    /// `min > w` and no NaN: the node lies wholly above the isovalue.
    Above,
    /// `min <= w <= max` over the finite samples: the node may contain surface.
    Straddles,
    /// No surface, and not an occluder: all samples NaN, or some NaN and the finite ones all on
    /// one side.
    Empty,
}

/// One octree node, with its cell range and world-space box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeInfo {
    pub depth: u32,
    pub ix: u32,
    pub iy: u32,
    pub iz: u32,
    /// Minimum of the non-NaN samples of the node's cells (`+inf` if none).
    pub min: f32,
    /// Maximum of the non-NaN samples of the node's cells (`-inf` if none).
    pub max: f32,
    /// Some sample of the node's cells is NaN (outside the domain).
    pub has_nan: bool,
    /// First cell (inclusive) per axis.
    pub cell_lo: [u32; 3],
    /// Last cell (exclusive) per axis, clamped to the volume's cells.
    pub cell_hi: [u32; 3],
    /// World position of sample `cell_lo`.
    pub bbox_min: [f64; 3],
    /// World position of sample `cell_hi` (the far corner of the last cell).
    pub bbox_max: [f64; 3],
}

impl NodeInfo {
    /// Classifies the node against isovalue `w` (see [`Class`]).
    #[inline]
    pub fn classify(&self, w: f32) -> Class {
        match classify_range(self.min, self.max, w) {
            Class::Below | Class::Above if self.has_nan => Class::Empty,
            c => c,
        }
    }

    /// True when the node may contain the isosurface `w`.
    #[inline]
    pub fn straddles(&self, w: f32) -> bool {
        self.classify(w) == Class::Straddles
    }

    /// Node key `(depth, ix, iy, iz)`.
    #[inline]
    pub fn key(&self) -> (u32, u32, u32, u32) {
        (self.depth, self.ix, self.iy, self.iz)
    }

    /// Number of cells covered (after clamping).
    pub fn cell_count(&self) -> u64 {
        (0..3).map(|a| (self.cell_hi[a] - self.cell_lo[a]) as u64).product()
    }
}

/// Classification of a value range `[min, max]` against `w`.
#[inline]
pub fn classify_range(min: f32, max: f32, w: f32) -> Class {
    if min.is_nan() || max.is_nan() || min > max {
        Class::Empty
    } else if max < w {
        Class::Below
    } else if min > w {
        Class::Above
    } else {
        Class::Straddles
    }
}

#[derive(Clone, Debug)]
struct Level {
    /// Nodes per axis at this depth (only those intersecting the volume).
    dims: [u32; 3],
    min: Vec<f32>,
    max: Vec<f32>,
    /// Some sample is NaN.
    nan: Vec<bool>,
}

impl Level {
    #[inline]
    fn idx(&self, x: u32, y: u32, z: u32) -> usize {
        ((z as usize * self.dims[1] as usize) + y as usize) * self.dims[0] as usize + x as usize
    }
}

/// Min/max octree over cells; see the module docs.
#[derive(Clone)]
pub struct MinMaxOctree {
    depth: u32,
    cells: [u32; 3],
    origin: [f64; 3],
    spacing: [f64; 3],
    /// `levels[d]` holds depth `d`, for `d <= depth - BRICK_LEVELS` (at least the root).
    levels: Vec<Level>,
    /// The volume's samples (shared), for the depths finer than the stored ones.
    values: Arc<[f32]>,
    /// A lazy volume's store (`values` is then empty), read through its cache for those depths.
    store: Option<Arc<BrickCache>>,
    /// Samples per axis.
    samples: [usize; 3],
}

impl std::fmt::Debug for MinMaxOctree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MinMaxOctree")
            .field("depth", &self.depth)
            .field("cells", &self.cells)
            .field("stored_depths", &self.levels.len())
            .field("heap_bytes", &self.heap_bytes())
            .finish()
    }
}

#[inline]
fn nan_min(a: f32, b: f32) -> f32 {
    // `b` may be NaN; NaN comparisons are false so it is skipped.
    if b < a {
        b
    } else {
        a
    }
}

#[inline]
fn nan_max(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

/// Min/max of the non-NaN samples `lo..=hi` (per axis, sample indices) of a volume with `samples`
/// samples per axis (`(+inf, -inf)` when all are NaN), and whether any is NaN.
fn scan(v: &[f32], samples: [usize; 3], lo: [usize; 3], hi: [usize; 3]) -> (f32, f32, bool) {
    let (nx, ny) = (samples[0], samples[1]);
    let (mut mn, mut mx, mut nan) = (f32::INFINITY, f32::NEG_INFINITY, false);
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            let row = (k * ny + j) * nx;
            for &x in &v[row + lo[0]..=row + hi[0]] {
                mn = nan_min(mn, x);
                mx = nan_max(mx, x);
                nan |= x.is_nan();
            }
        }
    }
    (mn, mx, nan)
}

impl MinMaxOctree {
    /// Builds the octree in parallel (rayon): the finest stored level (bricks of 8³ cells) by
    /// scanning the samples, the coarser ones by 2×2×2 reduction.
    pub fn build(vol: &Volume) -> Self {
        let cells = [(vol.nx - 1) as u32, (vol.ny - 1) as u32, (vol.nz - 1) as u32];
        let m = *cells.iter().max().unwrap();
        let depth = if m <= 1 { 0 } else { 32 - (m - 1).leading_zeros() };
        let finest = depth.saturating_sub(BRICK_LEVELS);
        let samples = [vol.nx, vol.ny, vol.nz];

        // Finest stored level: min/max over the samples of each brick of s³ cells.
        let bricks = {
            let s = 1usize << (depth - finest);
            let dims = [0, 1, 2].map(|a| (cells[a] as usize).div_ceil(s).max(1) as u32);
            let n = dims.iter().map(|&d| d as usize).product();
            let mut level =
                Level { dims, min: vec![f32::INFINITY; n], max: vec![f32::NEG_INFINITY; n], nan: vec![false; n] };
            match vol.store() {
                None => brick_rows(&mut level, &vol.values, 0, 0, samples, s),
                Some(store) => build_streaming(&mut level, store, samples, s),
            }
            level
        };

        let mut levels = vec![bricks];
        for d in (0..finest).rev() {
            let child = levels.last().unwrap();
            let s = 1u64 << (depth - d);
            let dims = [0, 1, 2].map(|a| (cells[a] as u64).div_ceil(s).max(1) as u32);
            let (px, py, pz) = (dims[0] as usize, dims[1] as usize, dims[2] as usize);
            let n = px * py * pz;
            let mut min = vec![f32::INFINITY; n];
            let mut max = vec![f32::NEG_INFINITY; n];
            let mut nan = vec![false; n];
            min.par_chunks_mut(px * py)
                .zip(max.par_chunks_mut(px * py))
                .zip(nan.par_chunks_mut(px * py))
                .enumerate()
                .for_each(|(z, ((mn, mx), na))| {
                    let z = z as u32;
                    for y in 0..py as u32 {
                        for x in 0..px as u32 {
                            let (mut lo, mut hi, mut any) = (f32::INFINITY, f32::NEG_INFINITY, false);
                            for cz in 2 * z..(2 * z + 2).min(child.dims[2]) {
                                for cy in 2 * y..(2 * y + 2).min(child.dims[1]) {
                                    for cx in 2 * x..(2 * x + 2).min(child.dims[0]) {
                                        let ci = child.idx(cx, cy, cz);
                                        lo = lo.min(child.min[ci]);
                                        hi = hi.max(child.max[ci]);
                                        any |= child.nan[ci];
                                    }
                                }
                            }
                            let o = y as usize * px + x as usize;
                            (mn[o], mx[o], na[o]) = (lo, hi, any);
                        }
                    }
                });
            levels.push(Level { dims, min, max, nan });
        }
        levels.reverse();

        let tree = MinMaxOctree {
            depth,
            cells,
            origin: vol.origin,
            spacing: vol.spacing,
            levels,
            values: vol.values.clone(),
            store: vol.store().cloned(),
            samples,
        };
        if vol.is_lazy() {
            let r = tree.root();
            vol.set_range(r.min, r.max);
        }
        tree
    }

    /// [`Self::build`], with a lazy volume's read errors (and infinite samples) as an error naming
    /// `values`.
    pub fn try_build(vol: &Volume) -> crate::Result<Self> {
        let t = Self::build(vol);
        vol.take_error()?;
        Ok(t)
    }

    /// Min/max and NaN of the samples `lo..=hi`: the shared samples, or a lazy volume's cache.
    fn scan(&self, lo: [usize; 3], hi: [usize; 3]) -> (f32, f32, bool) {
        match &self.store {
            None => scan(&self.values, self.samples, lo, hi),
            Some(s) => {
                let w = s.window(lo, hi);
                scan(&w.data, w.dims, [0; 3], [0, 1, 2].map(|a| hi[a] - lo[a]))
            }
        }
    }

    /// Host bytes of the stored min/max pyramid (the shared samples not counted).
    pub fn heap_bytes(&self) -> usize {
        self.levels.iter().map(|l| (l.min.capacity() + l.max.capacity()) * 4 + l.nan.capacity()).sum()
    }

    /// The finest depth whose min/max are stored (finer ones are scanned from the samples).
    pub fn stored_depth(&self) -> u32 {
        self.levels.len() as u32 - 1
    }

    /// `D`: the depth of the single-cell leaves (root is depth 0).
    pub fn max_depth(&self) -> u32 {
        self.depth
    }

    /// Cells per axis of the volume the tree was built from.
    pub fn cells(&self) -> [u32; 3] {
        self.cells
    }

    /// Nodes per axis at `depth` (only those intersecting the volume).
    pub fn dims_at_depth(&self, depth: u32) -> Option<[u32; 3]> {
        (depth <= self.depth).then(|| {
            let s = 1u64 << (self.depth - depth);
            [0, 1, 2].map(|a| (self.cells[a] as u64).div_ceil(s).max(1) as u32)
        })
    }

    /// The root node (depth 0).
    pub fn root(&self) -> NodeInfo {
        self.make(0, 0, 0, 0)
    }

    fn make(&self, depth: u32, ix: u32, iy: u32, iz: u32) -> NodeInfo {
        let s = 1u64 << (self.depth - depth);
        let c = [ix, iy, iz];
        let cell_lo = [0, 1, 2].map(|a| (c[a] as u64 * s) as u32);
        let cell_hi = [0, 1, 2].map(|a| ((c[a] as u64 + 1) * s).min(self.cells[a] as u64) as u32);
        let (min, max, has_nan) = match self.levels.get(depth as usize) {
            Some(l) => {
                let i = l.idx(ix, iy, iz);
                (l.min[i], l.max[i], l.nan[i])
            }
            // Finer than the stored bricks: at most 5³ samples (cells lo..hi span samples lo..=hi).
            None => self.scan(cell_lo.map(|v| v as usize), cell_hi.map(|v| v as usize)),
        };
        let pos = |p: [u32; 3]| [0, 1, 2].map(|a| self.origin[a] + p[a] as f64 * self.spacing[a]);
        NodeInfo {
            depth,
            ix,
            iy,
            iz,
            min,
            max,
            has_nan,
            cell_lo,
            cell_hi,
            bbox_min: pos(cell_lo),
            bbox_max: pos(cell_hi),
        }
    }

    /// The node at `depth` with index `(ix,iy,iz)`, if it intersects the volume.
    pub fn node(&self, depth: u32, (ix, iy, iz): (u32, u32, u32)) -> Option<NodeInfo> {
        let dims = self.dims_at_depth(depth)?;
        if ix < dims[0] && iy < dims[1] && iz < dims[2] {
            Some(self.make(depth, ix, iy, iz))
        } else {
            None
        }
    }

    /// All nodes at `depth` that intersect the volume (x fastest, then y, z).
    /// Empty when `depth > max_depth()`.
    pub fn nodes_at_depth(&self, depth: u32) -> Vec<NodeInfo> {
        let Some(dims) = self.dims_at_depth(depth) else {
            return Vec::new();
        };
        (0..dims[2])
            .into_par_iter()
            .flat_map_iter(|z| (0..dims[1]).flat_map(move |y| (0..dims[0]).map(move |x| self.make(depth, x, y, z))))
            .collect()
    }

    /// The samples the tree was built from, all of them (x fastest), and their count per axis: the
    /// resident volume's, or read whole through a lazy volume's cache (`super::bricks`' scans of
    /// every cell; a lazy volume only reaches them where nothing else answers).
    pub(super) fn all_samples(&self) -> (std::borrow::Cow<'_, [f32]>, [usize; 3]) {
        let values = match &self.store {
            None => std::borrow::Cow::Borrowed(&self.values[..]),
            Some(s) => s.window([0; 3], self.samples.map(|n| n - 1)).data,
        };
        (values, self.samples)
    }

    /// Whether single cells are answered straight from resident samples: the finest depth is
    /// not a stored level and the volume is not lazy.
    pub(super) fn leaves_from_samples(&self) -> bool {
        self.levels.len() as u32 <= self.depth && self.store.is_none()
    }

    /// `f(min, max, has_nan)` of every node at `depth` (x fastest, then y, z), in parallel, without
    /// materialising the nodes (single-cell depths of a 128³ volume have 2 M of them).
    pub fn map_at_depth<T: Send>(&self, depth: u32, f: impl Fn(f32, f32, bool) -> T + Sync) -> Vec<T> {
        let Some(dims) = self.dims_at_depth(depth) else {
            return Vec::new();
        };
        let (dx, dy) = (dims[0] as usize, dims[1] as usize);
        let s = 1u64 << (self.depth - depth);
        let level = self.levels.get(depth as usize);
        (0..dims[2])
            .into_par_iter()
            .flat_map_iter(|z| {
                let f = &f;
                (0..dy * dx).map(move |k| {
                    let (x, y) = ((k % dx) as u32, (k / dx) as u32);
                    match level {
                        Some(l) => {
                            let i = l.idx(x, y, z);
                            f(l.min[i], l.max[i], l.nan[i])
                        }
                        None => {
                            let c = [x, y, z];
                            let lo = [0, 1, 2].map(|a| (c[a] as u64 * s) as usize);
                            let hi = [0, 1, 2].map(|a| ((c[a] as u64 + 1) * s).min(self.cells[a] as u64) as usize);
                            let (mn, mx, nan) = self.scan(lo, hi);
                            f(mn, mx, nan)
                        }
                    }
                })
            })
            .collect()
    }

    /// Children of `n` (up to 8, only those intersecting the volume);
    /// empty for leaves.
    pub fn children(&self, n: &NodeInfo) -> Vec<NodeInfo> {
        if n.depth >= self.depth {
            return Vec::new();
        }
        let d = n.depth + 1;
        let dims = self.dims_at_depth(d).expect("d <= depth");
        let mut out = Vec::with_capacity(8);
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let (x, y, z) = (2 * n.ix + dx, 2 * n.iy + dy, 2 * n.iz + dz);
                    if x < dims[0] && y < dims[1] && z < dims[2] {
                        out.push(self.make(d, x, y, z));
                    }
                }
            }
        }
        out
    }

    /// All nodes at `depth` (clamped to `max_depth()`) that straddle `w`,
    /// found by descending from the root through straddling nodes only.
    pub fn straddling_at_depth(&self, w: f32, depth: u32) -> Vec<NodeInfo> {
        let depth = depth.min(self.depth);
        let mut frontier = vec![self.root()];
        frontier.retain(|n| n.straddles(w));
        for _ in 0..depth {
            frontier = frontier
                .par_iter()
                .flat_map_iter(|n| {
                    let mut c = self.children(n);
                    c.retain(|c| c.straddles(w));
                    c
                })
                .collect();
        }
        frontier
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::TestRng as Lcg;

    /// Uniform f32 in [0, 1) from bits 33..64.
    fn unit(rng: &mut Lcg) -> f32 {
        (rng.next_u64() >> 33) as f32 / (1u64 << 31) as f32
    }

    fn random_volume(rng: &mut Lcg, dims: (usize, usize, usize), nan_frac: f32) -> Volume {
        let n = dims.0 * dims.1 * dims.2;
        let v: Vec<f32> =
            (0..n).map(|_| if unit(rng) < nan_frac { f32::NAN } else { unit(rng) * 200.0 - 100.0 }).collect();
        Volume::new(Arc::from(v), dims, [0.5, -1.0, 2.0], [1.0, 0.5, 2.0]).unwrap()
    }

    fn brute(vol: &Volume, lo: [u32; 3], hi: [u32; 3]) -> (f32, f32) {
        let (mn, mx, _) = brute_nan(vol, lo, hi);
        (mn, mx)
    }

    fn brute_nan(vol: &Volume, lo: [u32; 3], hi: [u32; 3]) -> (f32, f32, bool) {
        let mut nan = false;
        let mut mn = f32::INFINITY;
        let mut mx = f32::NEG_INFINITY;
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    let v = vol.get(i as usize, j as usize, k as usize);
                    nan |= v.is_nan();
                    if !v.is_nan() {
                        mn = mn.min(v);
                        mx = mx.max(v);
                    }
                }
            }
        }
        (mn, mx, nan)
    }

    #[test]
    fn minmax_matches_brute_force() {
        let mut rng = Lcg(12345);
        for (t, dims) in
            [(2, 2, 2), (3, 2, 2), (5, 7, 3), (9, 9, 9), (17, 4, 11), (12, 30, 6), (2, 2, 40)].into_iter().enumerate()
        {
            let nan_frac = [0.0, 0.05, 0.3][t % 3];
            let vol = random_volume(&mut rng, dims, nan_frac);
            let tree = MinMaxOctree::build(&vol);
            let m = (dims.0.max(dims.1).max(dims.2) - 1) as u32;
            assert!(1u32 << tree.max_depth() >= m);
            assert!(tree.max_depth() == 0 || 1u32 << (tree.max_depth() - 1) < m);
            let mut total_leaf_cells = 0;
            for d in 0..=tree.max_depth() {
                let nodes = tree.nodes_at_depth(d);
                let mut cells = 0u64;
                for n in &nodes {
                    assert_eq!(n.depth, d);
                    let (mn, mx, nan) = brute_nan(&vol, n.cell_lo, n.cell_hi);
                    assert_eq!((n.min, n.max, n.has_nan), (mn, mx, nan), "dims {dims:?} node {n:?}");
                    if nan {
                        assert!(!matches!(n.classify(0.0), Class::Below | Class::Above));
                    }
                    assert_eq!(tree.node(d, (n.ix, n.iy, n.iz)), Some(*n));
                    for a in 0..3 {
                        assert!(n.cell_lo[a] < n.cell_hi[a]);
                        assert!((n.cell_hi[a] as usize) < [dims.0, dims.1, dims.2][a]);
                    }
                    cells += n.cell_count();
                    // children partition the parent
                    let ch = tree.children(n);
                    if d < tree.max_depth() {
                        assert!(!ch.is_empty() && ch.len() <= 8);
                        assert_eq!(ch.iter().map(|c| c.cell_count()).sum::<u64>(), n.cell_count());
                        let cmin = ch.iter().map(|c| c.min).fold(f32::INFINITY, f32::min);
                        let cmax = ch.iter().map(|c| c.max).fold(f32::NEG_INFINITY, f32::max);
                        assert_eq!((cmin, cmax), (n.min, n.max));
                    } else {
                        assert!(ch.is_empty());
                        assert_eq!(n.cell_count(), 1);
                    }
                }
                // every depth covers exactly all cells
                let all = ((dims.0 - 1) * (dims.1 - 1) * (dims.2 - 1)) as u64;
                assert_eq!(cells, all);
                total_leaf_cells = cells;
            }
            assert!(total_leaf_cells > 0);
            for d in 0..=tree.max_depth() {
                let a = tree.map_at_depth(d, |mn, mx, nan| (mn, mx, nan));
                let b: Vec<_> = tree.nodes_at_depth(d).iter().map(|n| (n.min, n.max, n.has_nan)).collect();
                assert_eq!(a, b);
            }
            let root = tree.root();
            assert_eq!(root.bbox_min, vol.origin);
            assert_eq!(root.bbox_max, vol.bounds().1);
            assert!(tree.node(tree.max_depth() + 1, (0, 0, 0)).is_none());
            assert!(tree.nodes_at_depth(tree.max_depth() + 1).is_empty());
        }
    }

    #[test]
    fn pyramid_is_compact_and_finer_depths_match_the_samples() {
        let vol = super::super::pesco_synthetic(129);
        let t = MinMaxOctree::build(&vol);
        assert_eq!((t.max_depth(), t.stored_depth()), (7, 4));
        // 16³ bricks and their ancestors, 2 floats each: about 0.02 bytes per sample
        let per_sample = t.heap_bytes() as f64 / vol.values.len() as f64;
        assert!(per_sample < 0.025, "{per_sample}");
        for d in t.stored_depth() + 1..=t.max_depth() {
            for n in t.nodes_at_depth(d).iter().step_by(97) {
                assert_eq!((n.min, n.max), brute(&vol, n.cell_lo, n.cell_hi), "{n:?}");
            }
        }
    }

    #[test]
    fn classify_rules() {
        let mk = |min: f32, max: f32| NodeInfo {
            depth: 0,
            ix: 0,
            iy: 0,
            iz: 0,
            min,
            max,
            has_nan: false,
            cell_lo: [0; 3],
            cell_hi: [1; 3],
            bbox_min: [0.0; 3],
            bbox_max: [1.0; 3],
        };
        assert_eq!(mk(0.0, 1.0).classify(2.0), Class::Below);
        assert_eq!(mk(0.0, 1.0).classify(-0.5), Class::Above);
        assert_eq!(mk(0.0, 1.0).classify(0.5), Class::Straddles);
        assert_eq!(mk(0.0, 1.0).classify(0.0), Class::Straddles);
        assert_eq!(mk(0.0, 1.0).classify(1.0), Class::Straddles);
        assert_eq!(mk(f32::INFINITY, f32::NEG_INFINITY).classify(0.0), Class::Empty);
        assert_eq!(mk(2.0, 2.0).classify(2.0), Class::Straddles);
        // a node with a NaN is never an occluder, but may hold surface
        let nan = |min: f32, max: f32| NodeInfo { has_nan: true, ..mk(min, max) };
        assert_eq!(nan(0.0, 1.0).classify(2.0), Class::Empty);
        assert_eq!(nan(0.0, 1.0).classify(-0.5), Class::Empty);
        assert_eq!(nan(0.0, 1.0).classify(0.5), Class::Straddles);
    }

    #[test]
    fn all_nan_nodes_are_empty() {
        let mut v = vec![f32::NAN; 5 * 5 * 5];
        v[0] = 1.0; // only cell (0,0,0) has data
        let vol = Volume::new(v.into(), (5, 5, 5), [0.0; 3], [1.0; 3]).unwrap();
        let t = MinMaxOctree::build(&vol);
        assert_eq!(t.root().min, 1.0);
        assert_eq!(t.root().classify(1.0), Class::Straddles);
        let leaf = t.node(t.max_depth(), (3, 3, 3)).unwrap();
        assert_eq!(leaf.classify(0.0), Class::Empty);
        assert_eq!(t.straddling_at_depth(1.0, 99).len(), 1);
    }

    #[test]
    fn straddling_descent_matches_filter() {
        let vol = super::super::pesco_synthetic(40);
        let t = MinMaxOctree::build(&vol);
        for d in 0..=t.max_depth() {
            let a = t.straddling_at_depth(0.0, d);
            let b: Vec<_> = t.nodes_at_depth(d).into_iter().filter(|n| n.straddles(0.0)).collect();
            let mut ka: Vec<_> = a.iter().map(|n| n.key()).collect();
            let mut kb: Vec<_> = b.iter().map(|n| n.key()).collect();
            ka.sort();
            kb.sort();
            assert_eq!(ka, kb);
        }
    }
}
