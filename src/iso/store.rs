//! Where a [`super::Volume`]'s samples come from: resident in memory, or read on demand from a
//! [`BrickSource`] (a zarr / dask array, a memory map, a SEG-Y file; the Python-backed source lives
//! in `crate::python`) through a bounded LRU cache of bricks ([`BrickCache`]).
//!
//! **Lazy volumes.** A volume over a source holds no samples: the octree is built in one streaming
//! pass over slabs of sample layers (about [`OCTREE_SLAB_BYTES`]; [`BrickCache::read_direct`],
//! never cached); a slice reads the bricks its plane crosses, in a few large reads, and keeps
//! them while they take at most a quarter of the budget, else its plane alone
//! ([`BrickCache::read_plane`]); the extraction reads, per node, the box of samples it needs (the
//! node's cells and a one-sample ring for the gradients) as a [`Window`] assembled from cached
//! bricks of [`BRICK`]³ samples. The cache holds at most its budget of brick bytes (least recently
//! used dropped first; a budget below one brick keeps none) and counts every byte read from the
//! source ([`BrickCache::bytes_read`]).
//!
//! **Errors.** The readers of samples (the octree, the extraction) return no `Result`: a failed
//! read fills its box with NaN and is kept ([`BrickCache::take_error`]); the entry points that
//! read a lazy volume (`MinMaxOctree::try_build`, the renderer's frame, `isosurface_mesh`, planes)
//! return it as an error naming `values`. A brick that failed to read is not cached.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use super::{check_grid, Volume};
use crate::error::{ensure, input_err, Result};

/// Samples per axis of a cached brick.
pub const BRICK: usize = 32;

/// Sample layers per slab of a streaming pass over a grid of `layer` samples per z layer: about
/// `bytes` per slab, at least 2 layers.
pub fn slab_layers(layer: usize, bytes: usize) -> usize {
    (bytes / (4 * layer.max(1))).max(2)
}

/// Bytes per slab of the passes that only reduce (the finite range, the bytes): 32 MiB.
pub const SLAB_BYTES: usize = 32 << 20;

/// Bytes per slab of the octree's pass: 128 MiB, so that a slab spans whole chunks of a chunked
/// source (1024² layers: 33 layers, about two 32-layer chunk rows per read).
pub const OCTREE_SLAB_BYTES: usize = 128 << 20;

/// Bytes per read when a plane's missing bricks are read ([`BrickCache::read_plane`]).
pub const PLANE_BATCH_BYTES: usize = 32 << 20;

/// Bytes of a box from which [`BrickCache::read_box`] fills it in parallel.
pub const PARALLEL_BOX_BYTES: usize = 1 << 20;

/// A store of f32 samples (residuals, see [`super::Volume`]) on a grid of `dims` (x, y, z).
pub trait BrickSource: Send + Sync {
    /// Writes the samples of the box `lo..hi` (exclusive per axis, x y z; inside the grid,
    /// non-empty) into `out` (x fastest, then y, z; `out.len()` is the box's sample count).
    fn read(&self, lo: [usize; 3], hi: [usize; 3], out: &mut [f32]) -> Result<()>;
}

#[cfg(test)]
/// Samples in memory, as a source (for tests and for comparing the lazy path with the resident one).
pub struct Resident {
    pub values: Arc<[f32]>,
    pub dims: [usize; 3],
}

#[cfg(test)]
impl BrickSource for Resident {
    fn read(&self, lo: [usize; 3], hi: [usize; 3], out: &mut [f32]) -> Result<()> {
        copy_box(&self.values, self.dims, lo, hi, out);
        Ok(())
    }
}

/// Copies the box `lo..hi` of `src` (a grid of `dims`) into `out` (the box, x fastest).
fn copy_box(src: &[f32], dims: [usize; 3], lo: [usize; 3], hi: [usize; 3], out: &mut [f32]) {
    let w = hi[0] - lo[0];
    let mut o = 0;
    for k in lo[2]..hi[2] {
        for j in lo[1]..hi[1] {
            let row = (k * dims[1] + j) * dims[0];
            out[o..o + w].copy_from_slice(&src[row + lo[0]..row + hi[0]]);
            o += w;
        }
    }
}

/// Samples in `parts` (the pieces of a box being filled).
fn out_len(parts: &[(usize, usize, &mut [f32])]) -> usize {
    parts.iter().map(|p| p.2.len()).sum()
}

/// `dst` = `src` (equal lengths): a plain loop for the short rows of a thin box (a plane across
/// x copies one sample per row, where `copy_from_slice` calls `memmove` for each).
#[inline]
fn copy_row(dst: &mut [f32], src: &[f32]) {
    if dst.len() < 16 {
        for (d, s) in dst.iter_mut().zip(src) {
            *d = *s;
        }
    } else {
        dst.copy_from_slice(src);
    }
}

/// The number of samples of the box `lo..hi`.
fn box_len(lo: [usize; 3], hi: [usize; 3]) -> usize {
    (0..3).map(|a| hi[a] - lo[a]).product()
}

/// A box of samples: `lo ..= lo + dims - 1` of the volume (x fastest), borrowed (a resident
/// volume's whole array) or read for the box.
pub struct Window<'a> {
    pub data: Cow<'a, [f32]>,
    pub lo: [usize; 3],
    pub dims: [usize; 3],
}

impl Window<'_> {
    /// Index in `data` of the volume's sample `(i, j, k)` (inside the window).
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        ((k - self.lo[2]) * self.dims[1] + (j - self.lo[1])) * self.dims[0] + (i - self.lo[0])
    }

    /// The volume's sample `(i, j, k)` (inside the window).
    #[inline]
    pub fn get(&self, i: usize, j: usize, k: usize) -> f32 {
        self.data[self.index(i, j, k)]
    }

    /// Index steps along x, y, z.
    #[inline]
    pub fn strides(&self) -> [usize; 3] {
        [1, self.dims[0], self.dims[0] * self.dims[1]]
    }
}

#[derive(Default)]
struct Lru {
    bricks: HashMap<[usize; 3], (Arc<[f32]>, u64)>,
    order: BTreeMap<u64, [usize; 3]>,
    bytes: usize,
    tick: u64,
}

/// A bounded LRU cache of bricks in front of a [`BrickSource`]; see the module docs.
pub struct BrickCache {
    source: Box<dyn BrickSource>,
    dims: [usize; 3],
    budget: usize,
    lru: Mutex<Lru>,
    /// Held while a brick is read from the source.
    reading: Mutex<()>,
    bytes_read: AtomicU64,
    peak: AtomicU64,
    error: Mutex<Option<String>>,
}

impl std::fmt::Debug for BrickCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BrickCache")
            .field("dims", &self.dims)
            .field("budget", &self.budget)
            .field("bytes_read", &self.bytes_read())
            .finish()
    }
}

impl BrickCache {
    /// A cache of at most `budget` bytes of bricks over `source`, a grid of `dims` (x, y, z).
    pub fn new(source: Box<dyn BrickSource>, dims: [usize; 3], budget: usize) -> Self {
        BrickCache {
            source,
            dims,
            budget,
            lru: Mutex::default(),
            reading: Mutex::new(()),
            bytes_read: AtomicU64::new(0),
            peak: AtomicU64::new(0),
            error: Mutex::new(None),
        }
    }

    /// Samples per axis (x, y, z).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The byte budget.
    pub fn budget(&self) -> usize {
        self.budget
    }

    /// Bytes read from the source so far (4 per sample; cache hits read nothing).
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read.load(Ordering::Relaxed)
    }

    /// Bytes of bricks held now.
    pub fn held_bytes(&self) -> usize {
        self.lock().bytes
    }

    /// The most bytes of bricks ever held at once (never above the budget).
    pub fn peak_bytes(&self) -> u64 {
        self.peak.load(Ordering::Relaxed)
    }

    /// Drops every cached brick.
    pub fn clear(&self) {
        *self.lock() = Lru::default();
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Lru> {
        self.lock_of(&self.lru)
    }

    fn lock_of<'a, T>(&self, m: &'a Mutex<T>) -> std::sync::MutexGuard<'a, T> {
        m.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The first read error since the last call, as an error naming `values`.
    pub fn take_error(&self) -> Result<()> {
        match self.lock_of(&self.error).take() {
            Some(msg) => Err(input_err("values", format!("values: reading the volume's samples failed: {msg}"))),
            None => Ok(()),
        }
    }

    /// Keeps `e` as the store's error (the first one kept wins).
    pub(crate) fn fail(&self, e: crate::Error) {
        let mut slot = self.lock_of(&self.error);
        if slot.is_none() {
            *slot = Some(e.to_string());
        }
    }

    /// Reads the box `lo..hi` from the source into `out` (not cached), counting its bytes; on an
    /// error, `out` is NaN and the error is kept ([`Self::take_error`]).
    pub fn read_direct(&self, lo: [usize; 3], hi: [usize; 3], out: &mut [f32]) -> bool {
        self.bytes_read.fetch_add(4 * out.len() as u64, Ordering::Relaxed);
        match self.source.read(lo, hi, out) {
            Ok(()) => true,
            Err(e) => {
                out.fill(f32::NAN);
                self.fail(e);
                false
            }
        }
    }

    /// Brick `b` from the cache (marked used), if there.
    fn cached(&self, b: [usize; 3]) -> Option<Arc<[f32]>> {
        let mut l = self.lock();
        l.tick += 1;
        let tick = l.tick;
        let (data, used) = l.bricks.get_mut(&b)?;
        let (data, old) = (data.clone(), std::mem::replace(used, tick));
        l.order.remove(&old);
        l.order.insert(tick, b);
        Some(data)
    }

    /// Brick `b` (brick indices), from the cache or read (and cached when it fits the budget).
    fn brick(&self, b: [usize; 3]) -> Arc<[f32]> {
        if let Some(d) = self.cached(b) {
            return d;
        }
        // Misses read one at a time (a Python source holds the GIL anyway), so that two threads
        // never read the same brick twice.
        let _reading = self.lock_of(&self.reading);
        if let Some(d) = self.cached(b) {
            return d;
        }
        let (lo, hi) = self.bricks_box(b, b);
        let mut data = vec![0.0f32; box_len(lo, hi)];
        let ok = self.read_direct(lo, hi, &mut data);
        let data: Arc<[f32]> = data.into();
        if ok {
            self.insert(b, data.clone());
        }
        data
    }

    /// The samples `lo..hi` of the bricks `b0 ..= b1` (brick indices; the grid's last bricks
    /// are cut at its sides).
    fn bricks_box(&self, b0: [usize; 3], b1: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        (b0.map(|v| v * BRICK), [0, 1, 2].map(|a| ((b1[a] + 1) * BRICK).min(self.dims[a])))
    }

    /// Caches brick `b` (over the budget: not at all), dropping the least recently used bricks to
    /// make room; a brick held already is only marked used, so that bricks inserted after it (the
    /// rest of a plane's) never drop it.
    fn insert(&self, b: [usize; 3], data: Arc<[f32]>) {
        let bytes = 4 * data.len();
        if bytes > self.budget {
            return;
        }
        let mut l = self.lock();
        l.tick += 1;
        let tick = l.tick;
        if let Some((_, used)) = l.bricks.get_mut(&b) {
            let old = std::mem::replace(used, tick);
            l.order.remove(&old);
            l.order.insert(tick, b);
            return;
        }
        while l.bytes + bytes > self.budget {
            let Some((_, key)) = l.order.pop_first() else { break };
            if let Some((old, _)) = l.bricks.remove(&key) {
                l.bytes -= 4 * old.len();
            }
        }
        l.bricks.insert(b, (data, tick));
        l.order.insert(tick, b);
        l.bytes += bytes;
        self.peak.fetch_max(l.bytes as u64, Ordering::Relaxed);
    }

    /// The samples of a plane's box `lo..hi` (one sample thick along some axis; inside the
    /// grid). When the bricks it crosses take at most a quarter of the budget, it is read through
    /// the cache: the missing bricks in a few large reads (rows of bricks, at most
    /// `PLANE_BATCH_BYTES` each: a chunked source decodes whole chunks however thin the box),
    /// so that the next planes within the same bricks (a slice moved by a few samples) read
    /// nothing. Otherwise straight from the source, not cached. A failed read is NaN and kept.
    pub fn read_plane(&self, lo: [usize; 3], hi: [usize; 3]) -> Vec<f32> {
        let (b0, b1) = (lo.map(|v| v / BRICK), hi.map(|v| (v - 1) / BRICK));
        let (blo, bhi) = self.bricks_box(b0, b1);
        if 4 * box_len(blo, bhi) > self.budget / 4 {
            let mut out = vec![0.0f32; box_len(lo, hi)];
            self.read_direct(lo, hi, &mut out);
            return out;
        }
        // Batches: runs of brick rows, cut along the slowest axis that spans more than one brick.
        let cut = (0..3).rev().find(|&a| b1[a] > b0[a]).unwrap_or(2);
        let row = 4 * box_len(blo, bhi) / (b1[cut] - b0[cut] + 1);
        let per = (PLANE_BATCH_BYTES / row.max(1)).max(1);
        let mut c = b0[cut];
        while c <= b1[cut] {
            let e = (c + per - 1).min(b1[cut]);
            let (mut q0, mut q1) = (b0, b1);
            (q0[cut], q1[cut]) = (c, e);
            if !self.fill_bricks(q0, q1) {
                // The error is kept; the plane is NaN (no brick-by-brick retry of a failing source).
                return vec![f32::NAN; box_len(lo, hi)];
            }
            c = e + 1;
        }
        self.read_box(lo, hi)
    }

    /// Reads the bricks `b0 ..= b1` (brick indices) in one read of their box when any is
    /// missing from the cache, and caches them; false when that read failed (kept).
    fn fill_bricks(&self, b0: [usize; 3], b1: [usize; 3]) -> bool {
        let all = |b0: [usize; 3], b1: [usize; 3]| {
            (b0[2]..=b1[2])
                .flat_map(move |z| (b0[1]..=b1[1]).flat_map(move |y| (b0[0]..=b1[0]).map(move |x| [x, y, z])))
        };
        let missing = || all(b0, b1).any(|b| !self.lock().bricks.contains_key(&b));
        if !missing() {
            return true;
        }
        let _reading = self.lock_of(&self.reading);
        if !missing() {
            return true;
        }
        let (lo, hi) = self.bricks_box(b0, b1);
        let dims = [0, 1, 2].map(|a| hi[a] - lo[a]);
        let mut data = vec![0.0f32; box_len(lo, hi)];
        if !self.read_direct(lo, hi, &mut data) {
            return false;
        }
        for b in all(b0, b1) {
            let s = [0, 1, 2].map(|a| b[a] * BRICK - lo[a]);
            let e = [0, 1, 2].map(|a| (s[a] + BRICK).min(dims[a]));
            let mut brick = vec![0.0f32; box_len(s, e)];
            copy_box(&data, dims, s, e, &mut brick);
            self.insert(b, brick.into());
        }
        true
    }

    /// The samples of the box `lo..hi` (inside the grid), assembled from cached bricks; a large
    /// box (a plane) one layer of bricks per task, in parallel.
    pub fn read_box(&self, lo: [usize; 3], hi: [usize; 3]) -> Vec<f32> {
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let mut out = vec![0.0f32; box_len(lo, hi)];
        let (b0, b1) = (lo.map(|v| v / BRICK), hi.map(|v| (v - 1) / BRICK));
        // `out` cut at the bricks' z boundaries: part `bz` holds layers k0..k1.
        let mut parts = Vec::with_capacity(b1[2] - b0[2] + 1);
        let mut rest = &mut out[..];
        for bz in b0[2]..=b1[2] {
            let (k0, k1) = (lo[2].max(bz * BRICK), hi[2].min((bz + 1) * BRICK));
            let (part, r) = std::mem::take(&mut rest).split_at_mut((k1 - k0) * w * h);
            rest = r;
            parts.push((bz, k0, part));
        }
        let fill = |(bz, k0, part): (usize, usize, &mut [f32])| {
            for by in b0[1]..=b1[1] {
                for bx in b0[0]..=b1[0] {
                    let data = self.brick([bx, by, bz]);
                    let blo = [bx * BRICK, by * BRICK, bz * BRICK];
                    let bd = [0, 1, 2].map(|a| (blo[a] + BRICK).min(self.dims[a]) - blo[a]);
                    let (s, e) = ([0, 1, 2].map(|a| lo[a].max(blo[a])), [0, 1, 2].map(|a| hi[a].min(blo[a] + bd[a])));
                    for k in s[2]..e[2] {
                        for j in s[1]..e[1] {
                            let src = ((k - blo[2]) * bd[1] + (j - blo[1])) * bd[0] - blo[0];
                            let dst = ((k - k0) * h + (j - lo[1])) * w - lo[0];
                            copy_row(&mut part[dst + s[0]..dst + e[0]], &data[src + s[0]..src + e[0]]);
                        }
                    }
                }
            }
        };
        if parts.len() > 1 && 4 * out_len(&parts) >= PARALLEL_BOX_BYTES {
            use rayon::prelude::*;
            parts.into_par_iter().for_each(fill);
        } else {
            parts.into_iter().for_each(fill);
        }
        out
    }

    /// The box `lo ..= hi_incl` (inside the grid) as a `Window`.
    pub fn window(&self, lo: [usize; 3], hi_incl: [usize; 3]) -> Window<'static> {
        let hi = hi_incl.map(|v| v + 1);
        Window { data: Cow::Owned(self.read_box(lo, hi)), lo, dims: [0, 1, 2].map(|a| hi[a] - lo[a]) }
    }

    /// Calls `f(k0, slab)` for consecutive slabs of `layers` sample layers (z), sharing
    /// `overlap` layers with the previous slab (`overlap < layers`), read straight from the source
    /// (not cached): `slab` holds layers `k0 .. k0 + slab.len() / (nx ny)`. Stops at the first
    /// read error (kept, see [`Self::take_error`]); returns false then.
    pub fn for_each_slab(&self, layers: usize, overlap: usize, mut f: impl FnMut(usize, &[f32])) -> bool {
        let [nx, ny, nz] = self.dims;
        let mut buf = Vec::new();
        let mut k0 = 0;
        loop {
            let k1 = (k0 + layers).min(nz);
            buf.resize(nx * ny * (k1 - k0), 0.0);
            if !self.read_direct([0, 0, k0], [nx, ny, k1], &mut buf) {
                return false;
            }
            f(k0, &buf);
            if k1 == nz {
                return true;
            }
            k0 = k1 - overlap;
        }
    }
}

/// A volume's access to its samples, resident or in a store.
impl Volume {
    /// A volume whose samples (f32 residuals about `offset`) stay in `store` and are read on
    /// demand (see `store`): its `values` are empty. Checked as by `Volume::with_offset`;
    /// `store`'s grid must be `dims`.
    pub fn lazy(
        store: Arc<BrickCache>,
        offset: f64,
        dims: (usize, usize, usize),
        origin: [f64; 3],
        spacing: [f64; 3],
    ) -> Result<Self> {
        let (nx, ny, nz) = dims;
        ensure(store.dims() == [nx, ny, nz], "values", || {
            format!("the sample store holds {:?} samples; expected {nx}x{ny}x{nz}", store.dims())
        })?;
        check_grid(dims, origin, spacing)?;
        ensure(offset.is_finite(), "offset", || format!("offset is {offset}; expected a finite number"))?;
        Ok(Volume::assemble(Arc::from(Vec::new()), offset, dims, origin, spacing, Some(store)))
    }

    /// The sample store of a lazy volume ([`Volume::lazy`]); None for a resident one.
    pub fn store(&self) -> Option<&Arc<BrickCache>> {
        self.store.as_ref()
    }

    /// True for a volume over a sample store ([`Volume::lazy`]).
    pub fn is_lazy(&self) -> bool {
        self.store.is_some()
    }

    /// Bytes read from a lazy volume's store so far (0 for a resident volume).
    pub fn bytes_read(&self) -> u64 {
        self.store.as_ref().map_or(0, |s| s.bytes_read())
    }

    /// The first read error of a lazy volume's store since the last call (see `store`).
    pub fn take_error(&self) -> Result<()> {
        self.store.as_ref().map_or(Ok(()), |s| s.take_error())
    }

    /// The samples `lo ..= hi_incl` (inside the grid): a resident volume's whole array (borrowed),
    /// or a lazy volume's box read through its cache.
    pub fn window(&self, lo: [usize; 3], hi_incl: [usize; 3]) -> Window<'_> {
        match &self.store {
            None => Window {
                data: std::borrow::Cow::Borrowed(&self.values[..]),
                lo: [0; 3],
                dims: [self.nx, self.ny, self.nz],
            },
            Some(s) => s.window(lo, hi_incl),
        }
    }

    /// The samples a box of cells `lo..hi` (clamped, non-empty) and the gradients at its samples
    /// need: its samples and a one-sample ring (clamped to the grid).
    pub fn cell_window(&self, lo: [usize; 3], hi: [usize; 3]) -> Window<'_> {
        let n = [self.nx, self.ny, self.nz];
        self.window(lo.map(|v| v.saturating_sub(1)), [0, 1, 2].map(|a| (hi[a] + 1).min(n[a] - 1)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(dims: [usize; 3]) -> Arc<[f32]> {
        (0..dims.iter().product::<usize>()).map(|i| (i as f32 * 0.37).sin()).collect::<Vec<_>>().into()
    }

    #[test]
    fn boxes_equal_the_resident_samples_and_the_budget_holds() {
        let dims = [70, 45, 38];
        let values = grid(dims);
        let brick = 4 * BRICK * BRICK * BRICK;
        for budget in [0, brick - 1, brick, 3 * brick + 5, 1 << 30] {
            let c = BrickCache::new(Box::new(Resident { values: values.clone(), dims }), dims, budget);
            let mut rng = crate::TestRng(7);
            for _ in 0..60 {
                let lo = dims.map(|n| (rng.next_u64() % n as u64) as usize);
                let hi = [0, 1, 2].map(|a| lo[a] + 1 + (rng.next_u64() % (dims[a] - lo[a]) as u64) as usize);
                let got = c.read_box(lo, hi);
                let mut want = vec![0.0; got.len()];
                copy_box(&values, dims, lo, hi, &mut want);
                assert_eq!(got, want);
                assert!(c.held_bytes() <= budget && c.peak_bytes() as usize <= budget);
            }
            c.take_error().unwrap();
        }
        // A box over PARALLEL_BOX_BYTES (filled a brick layer per task) and one over several
        // brick layers just under it (serially).
        let big = [128, 64, 40];
        let values_big = grid(big);
        let c = BrickCache::new(Box::new(Resident { values: values_big.clone(), dims: big }), big, 1 << 30);
        for (lo, hi) in [([0, 0, 0], big), ([3, 1, 2], [127, 63, 39]), ([1, 2, 3], [100, 60, 37])] {
            let mut want = vec![0.0; box_len(lo, hi)];
            copy_box(&values_big, big, lo, hi, &mut want);
            assert_eq!(c.read_box(lo, hi), want);
        }
        assert!(
            4 * box_len([0; 3], big) >= PARALLEL_BOX_BYTES
                && 4 * box_len([1, 2, 3], [100, 60, 37]) < PARALLEL_BOX_BYTES
        );
        // Hits read nothing.
        let c = BrickCache::new(Box::new(Resident { values, dims }), dims, 1 << 30);
        let w = c.window([1, 2, 3], [40, 40, 36]);
        let read = c.bytes_read();
        assert_eq!(read as usize, 4 * 64 * dims[1] * dims[2], "every brick of the box (x < 64), once");
        assert_eq!(w.get(5, 6, 7), c.window([5, 6, 7], [5, 6, 7]).data[0]);
        assert_eq!(c.bytes_read(), read);
    }

    #[test]
    fn planes_read_their_bricks_once_when_they_fit_and_alone_when_not() {
        let dims = [70, 45, 38];
        let values = grid(dims);
        let plane = |c: &BrickCache, axis: usize, index: usize| {
            let (mut lo, mut hi) = ([0; 3], dims);
            (lo[axis], hi[axis]) = (index, index + 1);
            let mut want = vec![0.0; box_len(lo, hi)];
            copy_box(&values, dims, lo, hi, &mut want);
            assert_eq!(c.read_plane(lo, hi), want, "axis {axis}, index {index}");
        };
        // The x = 40 plane crosses 2 x 2 bricks of x 32..64 (64 x 45 x 38 samples).
        let slab = 4 * 32 * dims[1] * dims[2];
        let c = BrickCache::new(Box::new(Resident { values: values.clone(), dims }), dims, 4 * slab);
        plane(&c, 0, 40);
        assert_eq!(c.bytes_read() as usize, slab, "the plane's bricks, once");
        plane(&c, 0, 63);
        plane(&c, 0, 33);
        assert_eq!(c.bytes_read() as usize, slab, "planes within the same bricks read nothing");
        plane(&c, 0, 64);
        assert_eq!(c.bytes_read() as usize, slab + 4 * 6 * dims[1] * dims[2], "the next bricks (x 64..70)");
        for (axis, index) in [(1, 0), (1, 44), (2, 37), (2, 5)] {
            plane(&c, axis, index);
        }
        assert!(c.peak_bytes() as usize <= 4 * slab);
        // A budget the bricks do not fit in a quarter of: the plane alone, nothing kept.
        let c = BrickCache::new(Box::new(Resident { values: values.clone(), dims }), dims, 4 * slab - 4);
        plane(&c, 0, 40);
        plane(&c, 0, 41);
        assert_eq!(c.bytes_read() as usize, 2 * 4 * dims[1] * dims[2]);
        assert_eq!(c.held_bytes(), 0);
        // Errors: NaN, kept, nothing cached, the source asked once (through the cache or not).
        for budget in [1 << 20, 0] {
            let c = BrickCache::new(Box::new(Failing), [4, 4, 4], budget);
            assert!(c.read_plane([0, 0, 1], [4, 4, 2]).iter().all(|v| v.is_nan()));
            assert_eq!(c.held_bytes(), 0);
            assert_eq!(c.bytes_read(), if budget > 0 { 4 * 4 * 4 * 4 } else { 4 * 4 * 4 });
            assert!(c.take_error().is_err());
        }
    }

    #[test]
    fn a_plane_whose_bricks_are_partly_cached_reads_each_once() {
        // Bricks of x 0..32 are 32 KiB here, of x 32..40 8 KiB; the cache holds 160 KiB.
        let dims = [40, 8, 200];
        let values = grid(dims);
        let c = BrickCache::new(Box::new(Resident { values: values.clone(), dims }), dims, 160 << 10);
        c.read_box([0, 0, 0], [1, 1, 1]); // brick (0, 0, 0), the least recently used
        for k in 1..5 {
            c.read_box([0, 0, 32 * k], [1, 1, 32 * k + 1]);
        }
        assert_eq!(c.held_bytes(), 160 << 10, "full");
        // The plane z = 3 crosses (0, 0, 0), held, and (1, 0, 0), missing: both are read in one
        // read, and keeping (1, 0, 0) must drop another brick than (0, 0, 0).
        let before = c.bytes_read();
        let (lo, hi) = ([0, 0, 3], [40, 8, 4]);
        let mut want = vec![0.0; box_len(lo, hi)];
        copy_box(&values, dims, lo, hi, &mut want);
        assert_eq!(c.read_plane(lo, hi), want);
        assert_eq!(c.bytes_read() - before, 4 * 40 * 8 * 32, "the plane's bricks once, none read again");
    }

    struct Failing;
    impl BrickSource for Failing {
        fn read(&self, _: [usize; 3], _: [usize; 3], _: &mut [f32]) -> Result<()> {
            Err(input_err("values", "disk on fire"))
        }
    }

    #[test]
    fn read_errors_are_nan_and_kept() {
        let c = BrickCache::new(Box::new(Failing), [4, 4, 4], 1 << 20);
        assert!(c.read_box([0; 3], [2; 3]).iter().all(|v| v.is_nan()));
        assert_eq!(c.held_bytes(), 0);
        let e = c.take_error().unwrap_err().to_string();
        assert!(e.starts_with("values: reading the volume's samples failed") && e.contains("disk on fire"), "{e}");
        c.take_error().unwrap();
        assert!(!c.for_each_slab(2, 1, |_, _| panic!("no slab")));
    }

    #[test]
    fn slabs_cover_the_grid_with_their_overlap() {
        let dims = [5, 4, 11];
        let values = grid(dims);
        let c = BrickCache::new(Box::new(Resident { values: values.clone(), dims }), dims, 0);
        let mut seen = Vec::new();
        assert!(c.for_each_slab(4, 1, |k0, s| {
            assert_eq!(s, &values[k0 * 20..k0 * 20 + s.len()]);
            seen.push((k0, s.len() / 20));
        }));
        assert_eq!(seen, [(0, 4), (3, 4), (6, 4), (9, 2)]);
    }
}
