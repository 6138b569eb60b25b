//! Isosurface core for view-dependent ("implicit occluder") extraction.
//!
//! After Pesco, Lindstrom, Pascucci, Silva, "Implicit Occluders": a min/max
//! octree over the cells of a scalar volume tells which blocks can contain the
//! isosurface `f = w`; the renderer tests those blocks against a GPU occlusion
//! map and asks this module to triangulate only the visible ones.
//!
//! * [`Volume`]: a regular scalar grid (x fastest, then y, then z), optionally rotated about
//!   the vertical through its origin; [`layout`]: how a user's array (zyx or xyz order, z
//!   positive up or down) maps onto it.
//! * [`octree::MinMaxOctree`]: per-node min/max over cells, built with rayon.
//! * [`march`]: crack-free marching cubes (generated table, face-centre decider), per box of
//!   cells, plus a patch cache keyed by isovalue and node.
//! * [`mesh`]: the whole isosurface as one welded world-space mesh (the renderer's triangles).
//!
//! **Rotation.** Everything inside this module (octree boxes, occluders, patches) lives in the
//! volume's own *grid frame*: sample `(i,j,k)` at `origin + (i,j,k) * spacing`. A rotated volume
//! (`rotation` degrees counter-clockwise about the vertical through `origin`, as a rotated survey)
//! is turned only where it meets the world: the renderer folds the rotation into its
//! view-projection matrix (`render.rs`) and [`mesh`] turns the vertices it returns.
//!

use std::sync::Arc;

use rayon::prelude::*;

use crate::error::{ensure, input_err, Result};
use crate::scene::serial::{Reader, Writer};

const VOLUME_MAGIC: &[u8; 8] = b"GCVOLUM\0";

mod bricks;
pub mod enclosed;
pub mod layout;
#[cfg(test)]
mod lazy_tests;
pub mod march;
pub mod mesh;
pub mod octree;
mod oracle;
mod passes;
mod pool;
pub mod render;
pub mod scene_object;
mod seen;
pub mod store;
mod walk;

pub use octree::MinMaxOctree;
pub use store::{BrickCache, BrickSource, Window};

/// Identity of the volume a cache was filled from: its `values` allocation (the `Weak` keeps the
/// address from being reused), its value offset and its geometry.
pub(crate) struct VolumeId {
    values: std::sync::Weak<[f32]>,
    store: Option<std::sync::Weak<BrickCache>>,
    offset: u64,
    dims: [usize; 3],
    origin: [f64; 3],
    spacing: [f64; 3],
}

impl VolumeId {
    pub(crate) fn of(v: &Volume) -> Self {
        Self {
            values: Arc::downgrade(&v.values),
            store: v.store.as_ref().map(Arc::downgrade),
            offset: v.offset.to_bits(),
            dims: [v.nx, v.ny, v.nz],
            origin: v.origin,
            spacing: v.spacing,
        }
    }
    pub(crate) fn matches(&self, v: &Volume) -> bool {
        std::ptr::eq(self.values.as_ptr() as *const f32, Arc::as_ptr(&v.values) as *const f32)
            && self.store.as_ref().map(|w| w.as_ptr()) == v.store.as_ref().map(Arc::as_ptr)
            && self.offset == v.offset.to_bits()
            && self.dims == [v.nx, v.ny, v.nz]
            && self.origin == v.origin
            && self.spacing == v.spacing
    }
}

/// Samples in one z slice (`nx * ny`) of a volume of `dims` (nx, ny, nz), or an InputError naming
/// `values` when the whole volume's sample count overflows.
fn slice_len((nx, ny, nz): (usize, usize, usize)) -> Result<usize> {
    nx.checked_mul(ny)
        .filter(|s| s.checked_mul(nz).is_some())
        .ok_or_else(|| input_err("values", format!("volume dimensions {nx}x{ny}x{nz} overflow")))
}

/// The checks of [`Volume::new`] but the values' length: at least 2 samples per axis, cells per
/// axis within `u32`, finite origin, finite positive spacing. Returns the sample count.
fn check_grid(dims: (usize, usize, usize), origin: [f64; 3], spacing: [f64; 3]) -> Result<usize> {
    let (nx, ny, nz) = dims;
    ensure(nx >= 2 && ny >= 2 && nz >= 2, "values", || {
        format!("volume needs at least 2 samples per axis, got {nx}x{ny}x{nz}")
    })?;
    let max = u32::MAX as usize / 2;
    ensure(nx <= max && ny <= max && nz <= max, "values", || format!("volume dimensions {nx}x{ny}x{nz} too large"))?;
    let n = slice_len(dims)? * nz;
    for (i, o) in origin.iter().enumerate() {
        ensure(o.is_finite(), "origin", || format!("component {i} is {o}; expected a finite number"))?;
    }
    for (i, d) in spacing.iter().enumerate() {
        ensure(d.is_finite() && *d > 0.0, "spacing", || format!("component {i} is {d}; expected a finite number > 0"))?;
    }
    Ok(n)
}

/// A scalar field sampled on a regular grid.
///
/// `values` is indexed `values[(k*ny + j)*nx + i]`, where `k` is the z index,
/// `j` the y index and `i` the x index. Sample `(i,j,k)` sits at world
/// position `origin + (i,j,k) * spacing`. NaN samples mean "no data".
///
/// **Value offset.** The samples are stored as f32 *residuals* about an f64 `offset`: sample
/// value = `offset + values[..]`. For f64 input ([`Volume::from_f64`]) the offset is the midrange
/// of the finite samples, so values such as 1e8 ± 1 keep their differences (f32 alone cannot tell
/// 1e8 from 1e8 + 1); f32 input is stored as is (offset 0). Everything inside the iso module (the
/// octree's min/max, the extraction, the cache keys) works on residuals; isovalues enter through
/// [`Volume::residual`] and values leave through [`Volume::value`], so every value a user sees is
/// in the volume's own units.
#[derive(Clone, Debug)]
pub struct Volume {
    /// Residuals `value - offset` (NaN = no data). Fixed once the volume is in use: replacing
    /// them (tests do, before anything else) would leave [`Volume::finite_range`] stale.
    pub values: Arc<[f32]>,
    /// The f64 value every residual is relative to.
    pub offset: f64,
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub origin: [f64; 3],
    pub spacing: [f64; 3],
    /// Degrees counter-clockwise (seen from +z) about the vertical through `origin`; 0 = axis-aligned.
    pub rotation: f64,
    /// [`Volume::finite_range`], computed on first use (the samples never change).
    range: std::sync::OnceLock<Option<[f64; 2]>>,
    /// A lazy volume's samples ([`Volume::lazy`]; `values` is then empty): read on demand.
    store: Option<Arc<BrickCache>>,
}

impl Volume {
    /// Checks that `values.len() == nx*ny*nz`, that every dimension has at least 2 samples (one
    /// cell), that the cell count per axis fits in `u32`, and that origin and spacing are finite
    /// with positive spacing. Errors name the argument: `values`, `origin` or `spacing`.
    pub fn new(values: Arc<[f32]>, dims: (usize, usize, usize), origin: [f64; 3], spacing: [f64; 3]) -> Result<Self> {
        let (nx, ny, nz) = dims;
        let n = check_grid(dims, origin, spacing)?;
        ensure(values.len() == n, "values", || {
            format!("volume of {nx}x{ny}x{nz} needs {n} values, got {}", values.len())
        })?;
        Ok(Volume::assemble(values, 0.0, dims, origin, spacing, None))
    }

    /// A volume of these parts, unrotated, its range not computed yet (the constructors check
    /// the parts first).
    fn assemble(
        values: Arc<[f32]>,
        offset: f64,
        (nx, ny, nz): (usize, usize, usize),
        origin: [f64; 3],
        spacing: [f64; 3],
        store: Option<Arc<BrickCache>>,
    ) -> Self {
        Volume { values, offset, nx, ny, nz, origin, spacing, rotation: 0.0, range: Default::default(), store }
    }

    /// The same volume rotated by `rotation` degrees counter-clockwise about the vertical through
    /// its origin (a rotated survey). Errors name `rotation` when it is not finite.
    pub fn with_rotation(self, rotation: f64) -> Result<Self> {
        ensure(rotation.is_finite(), "rotation", || {
            format!("rotation is {rotation}; expected a finite angle in degrees (counter-clockwise)")
        })?;
        Ok(Volume { rotation, ..self })
    }

    /// (cos, sin) of the rotation, exact at multiples of 90°.
    pub fn cos_sin(&self) -> (f64, f64) {
        crate::lod::cos_sin_deg(self.rotation)
    }

    /// World position of a grid-frame point (rotation about the origin's vertical applied).
    #[inline]
    pub fn to_world(&self, p: [f64; 3]) -> [f64; 3] {
        self.rotated(self.cos_sin(), p)
    }

    /// [`Self::to_world`] with the rotation's (cos, sin) given ([`Self::cos_sin`], taken once
    /// for many points).
    #[inline]
    pub(crate) fn rotated(&self, (c, s): (f64, f64), p: [f64; 3]) -> [f64; 3] {
        if (c, s) == (1.0, 0.0) {
            return p;
        }
        let (u, v) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        [self.origin[0] + (c * u - s * v), self.origin[1] + (s * u + c * v), p[2]]
    }

    /// World-space bounding box `(min, max)` of the samples: [`Volume::bounds`] for an
    /// axis-aligned volume, else the box around the rotated grid's corners.
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let (lo, hi) = self.bounds();
        let mut a = [f64::INFINITY; 3];
        let mut b = [f64::NEG_INFINITY; 3];
        for c in 0..4 {
            let p =
                self.to_world([if c & 1 == 0 { lo[0] } else { hi[0] }, if c & 2 == 0 { lo[1] } else { hi[1] }, lo[2]]);
            for ax in 0..2 {
                a[ax] = a[ax].min(p[ax]);
                b[ax] = b[ax].max(p[ax]);
            }
        }
        a[2] = lo[2];
        b[2] = hi[2];
        (a, b)
    }

    /// A volume of f32 residuals about `offset` (checked as by [`Volume::new`]; `offset` finite).
    pub fn with_offset(
        values: Arc<[f32]>,
        offset: f64,
        dims: (usize, usize, usize),
        origin: [f64; 3],
        spacing: [f64; 3],
    ) -> Result<Self> {
        ensure(offset.is_finite(), "offset", || format!("offset is {offset}; expected a finite number"))?;
        Ok(Volume { offset, ..Volume::new(values, dims, origin, spacing)? })
    }

    /// A volume of f64 samples, stored as f32 residuals about the midrange of the finite samples
    /// (0 when there are none). Errors name `values[k, j, i]` when a sample is infinite or its
    /// residual exceeds the f32 range (a value range wider than about 6.8e38).
    pub fn from_f64(values: &[f64], dims: (usize, usize, usize), origin: [f64; 3], spacing: [f64; 3]) -> Result<Self> {
        let (nx, ny, nz) = dims;
        let n = nx.saturating_mul(ny).saturating_mul(nz);
        ensure(values.len() == n, "values", || {
            format!("volume of {nx}x{ny}x{nz} needs {n} values, got {}", values.len())
        })?;
        let slice = nx * ny;
        Self::from_f64_slices(dims, origin, spacing, |k, out| out.copy_from_slice(&values[k * slice..(k + 1) * slice]))
    }

    /// [`Volume::from_f64`] for samples that are not one contiguous slice (a strided, transposed or
    /// flipped array): `read(k, out)` writes z slice `k` (`ny * nx` samples, x fastest) into `out`.
    /// Slices are read in parallel, twice (the midrange, then the residuals) and never gathered
    /// into an f64 copy of the whole volume.
    pub fn from_f64_slices(
        dims: (usize, usize, usize),
        origin: [f64; 3],
        spacing: [f64; 3],
        read: impl Fn(usize, &mut [f64]) + Sync,
    ) -> Result<Self> {
        let (nx, ny, nz) = dims;
        let slice = slice_len(dims)?;
        let range = |(a, b): (f64, f64), v: &f64| if v.is_finite() { (a.min(*v), b.max(*v)) } else { (a, b) };
        let (lo, hi) = (0..nz)
            .into_par_iter()
            .map_init(
                || vec![0.0f64; slice],
                |buf, k| {
                    read(k, buf);
                    buf.iter().fold((f64::INFINITY, f64::NEG_INFINITY), range)
                },
            )
            .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |(a, b), (c, d)| (a.min(c), b.max(d)));
        let offset = if lo <= hi { lo * 0.5 + hi * 0.5 } else { 0.0 };
        let mut residuals = vec![0.0f32; slice * nz];
        if slice > 0 {
            residuals.par_chunks_mut(slice).enumerate().for_each_init(
                || vec![0.0f64; slice],
                |buf, (k, out)| {
                    read(k, buf);
                    for (r, &v) in out.iter_mut().zip(buf.iter()) {
                        *r = (v - offset) as f32;
                    }
                },
            );
        }
        if let Some(k) = residuals.par_iter().position_first(|r| r.is_infinite()) {
            let (i, j, kk) = (k % nx.max(1), (k / nx.max(1)) % ny.max(1), k / slice.max(1));
            let mut buf = vec![0.0f64; slice];
            read(kk, &mut buf);
            let v = buf[k % slice.max(1)];
            return Err(input_err(
                "values",
                format!(
                    "values[{kk}, {j}, {i}] is {}; {}",
                    crate::error::num(v),
                    if v.is_infinite() {
                        "use NaN for no data".to_string()
                    } else {
                        "the volume's value range does not fit float32 even about its midrange".to_string()
                    }
                ),
            ));
        }
        Self::with_offset(residuals.into(), offset, dims, origin, spacing)
    }

    /// [`Volume::new`] for f32 samples that are not one contiguous slice: `read(k, out)` writes z
    /// slice `k` (`ny * nx` samples, x fastest) into the volume's own buffer (in parallel): the one
    /// copy of the samples.
    pub fn from_f32_slices(
        dims: (usize, usize, usize),
        origin: [f64; 3],
        spacing: [f64; 3],
        read: impl Fn(usize, &mut [f32]) + Sync,
    ) -> Result<Self> {
        let nz = dims.2;
        let slice = slice_len(dims)?;
        let mut v = vec![0.0f32; slice * nz];
        if slice > 0 {
            v.par_chunks_mut(slice).enumerate().for_each(|(k, out)| read(k, out));
        }
        Self::new(v.into(), dims, origin, spacing)
    }

    /// The residual (f32, relative to [`Volume::offset`]) of a value in the volume's units, as the
    /// octree and the extraction use it. Errors name `arg` when the value is not finite or its
    /// residual is beyond the f32 range.
    pub fn residual(&self, value: f64, arg: &str) -> Result<f32> {
        let r = (value - self.offset) as f32;
        ensure(value.is_finite() && r.is_finite(), arg, || {
            if value.is_finite() {
                format!(
                    "{arg} is {}; it must lie within the float32 range of the volume's values, offset {}",
                    crate::error::num(value),
                    crate::error::num(self.offset)
                )
            } else {
                format!("{arg} is {value}; expected a finite number")
            }
        })?;
        Ok(r)
    }

    /// The volume as bytes: magic `b"GCVOLUM\0"`, version u32 (2), then little-endian
    /// nx, ny, nz (u64), origin, spacing (f64 x 3), offset (f64), rotation (f64, degrees; absent
    /// in version 1, read as 0) and the residuals (u64 count, f32 each); [`Volume::from_bytes`]
    /// reads them back.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(Vec::with_capacity(104 + 4 * self.values.len()));
        w.bytes(VOLUME_MAGIC);
        w.u32(2);
        for n in [self.nx, self.ny, self.nz] {
            w.u64(n as u64);
        }
        for v in self.origin.iter().chain(&self.spacing) {
            w.f64(*v);
        }
        w.f64(self.offset);
        w.f64(self.rotation);
        match &self.store {
            None => w.f32s(&self.values),
            // A lazy volume's samples, read slab by slab (NaN where a read failed: see `take_error`).
            Some(s) => {
                let n = self.nx * self.ny * self.nz;
                w.u64(n as u64);
                w.0.reserve(4 * n);
                s.for_each_slab(store::slab_layers(self.nx * self.ny, store::SLAB_BYTES), 0, |_, slab| {
                    w.0.extend(slab.iter().flat_map(|v| v.to_le_bytes()));
                });
            }
        }
        w.0
    }

    /// A volume from [`Volume::to_bytes`]'s bytes (checked as by [`Volume::with_offset`]; a
    /// damaged or foreign buffer is an InputError naming `data`).
    pub fn from_bytes(data: &[u8]) -> Result<Self> {
        let mut r = Reader::new(data, "data");
        let version = r.header(VOLUME_MAGIC, "volume", 2)?;
        let dims = (r.usize()?, r.usize()?, r.usize()?);
        let (origin, spacing, offset) = (r.f64x3()?, r.f64x3()?, r.f64()?);
        let rotation = if version >= 2 { r.f64()? } else { 0.0 };
        let values = r.f32s()?;
        r.finish()?;
        // Checked as the constructor checks its arguments, but the caller passed only `data`.
        Self::with_offset(values.into(), offset, dims, origin, spacing)
            .and_then(|v| v.with_rotation(rotation))
            .map_err(|e| input_err("data", format!("data: damaged volume bytes: {e}")))
    }

    /// A residual (an octree min/max, a stored sample) in the volume's units.
    #[inline]
    pub fn value(&self, residual: f32) -> f64 {
        residual as f64 + self.offset
    }

    /// Linear index of sample `(i,j,k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.ny + j) * self.nx + i
    }

    /// Sample value at `(i,j,k)` (a lazy volume's through its cache). Panics when out of range.
    #[inline]
    pub fn get(&self, i: usize, j: usize, k: usize) -> f32 {
        debug_assert!(i < self.nx && j < self.ny && k < self.nz);
        match &self.store {
            None => self.values[self.index(i, j, k)],
            Some(s) => s.read_box([i, j, k], [i + 1, j + 1, k + 1])[0],
        }
    }

    /// Number of cells per axis: `(nx-1, ny-1, nz-1)`.
    #[inline]
    pub fn cells(&self) -> [usize; 3] {
        [self.nx - 1, self.ny - 1, self.nz - 1]
    }

    /// World position of sample `(i,j,k)`.
    #[inline]
    pub fn sample_position(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        [
            self.origin[0] + i as f64 * self.spacing[0],
            self.origin[1] + j as f64 * self.spacing[1],
            self.origin[2] + k as f64 * self.spacing[2],
        ]
    }

    /// World-space bounding box `(min, max)` of the samples.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.origin, self.sample_position(self.nx - 1, self.ny - 1, self.nz - 1))
    }

    /// The samples of the plane `axis` = `index` (0: constant i, 1: constant j, 2: constant k)
    /// within the inclusive sample ranges `range` of the other two axes (`range[axis]` is not
    /// read), as a lattice along those axes in order (u the lower axis, v the higher): world
    /// positions (rotation applied) and values in the volume's units, row-major `v * nu + u`, and
    /// (nu, nv). Indices must be in range (the caller checks them).
    pub fn plane(
        &self,
        axis: usize,
        index: usize,
        range: [(usize, usize); 3],
    ) -> (Vec<[f64; 3]>, Vec<f64>, (usize, usize)) {
        let (ua, va) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let (nu, nv) = (range[ua].1 - range[ua].0 + 1, range[va].1 - range[va].0 + 1);
        // A lazy volume reads the plane's box through its cache's plane path (`read_plane`).
        let mut lo = [0; 3];
        let mut hi = [0; 3];
        for a in 0..3 {
            (lo[a], hi[a]) = if a == axis { (index, index) } else { range[a] };
        }
        let win = match &self.store {
            None => self.window(lo, hi),
            Some(s) => {
                let hx = hi.map(|v| v + 1);
                Window { data: s.read_plane(lo, hx).into(), lo, dims: [0, 1, 2].map(|a| hx[a] - lo[a]) }
            }
        };
        // Row by row in parallel, into the outputs (each sample computed as a serial pass
        // would): a plane across the volume's fastest axis reads one sample per cache line.
        let cs = self.cos_sin();
        let mut pos = vec![[0.0; 3]; nu * nv];
        let mut vals = vec![0.0; nu * nv];
        pos.par_chunks_mut(nu).zip(vals.par_chunks_mut(nu)).enumerate().for_each(|(v, (prow, vrow))| {
            for (u, (p, val)) in prow.iter_mut().zip(vrow).enumerate() {
                let mut ijk = [0; 3];
                (ijk[axis], ijk[ua], ijk[va]) = (index, range[ua].0 + u, range[va].0 + v);
                *p = self.rotated(cs, self.sample_position(ijk[0], ijk[1], ijk[2]));
                *val = self.value(win.get(ijk[0], ijk[1], ijk[2]));
            }
        });
        (pos, vals, (nu, nv))
    }

    /// The smallest and largest finite sample values, in the volume's units; None when no
    /// sample is finite. Computed once per volume (in parallel, on the f32 residuals: `value` is
    /// monotonic, so their extremes give the values' extremes exactly).
    pub fn finite_range(&self) -> Option<[f64; 2]> {
        *self.range.get_or_init(|| {
            let extremes = |(a, b): (f32, f32), (c, d): (f32, f32)| (a.min(c), b.max(d));
            let of = |values: &[f32]| {
                values
                    .par_chunks(1 << 16)
                    .map(|c| {
                        c.iter()
                            .filter(|v| v.is_finite())
                            .fold((f32::INFINITY, f32::NEG_INFINITY), |m, &v| extremes(m, (v, v)))
                    })
                    .reduce(|| (f32::INFINITY, f32::NEG_INFINITY), extremes)
            };
            let (lo, hi) = match &self.store {
                None => of(&self.values),
                // One streaming pass (the octree's build sets the range without it).
                Some(s) => {
                    let mut m = (f32::INFINITY, f32::NEG_INFINITY);
                    s.for_each_slab(store::slab_layers(self.nx * self.ny, store::SLAB_BYTES), 0, |_, slab| {
                        m = extremes(m, of(slab))
                    });
                    m
                }
            };
            (lo <= hi).then(|| [self.value(lo), self.value(hi)])
        })
    }

    /// Sets [`Volume::finite_range`] from residual extremes found elsewhere (the octree's root).
    pub(crate) fn set_range(&self, lo: f32, hi: f32) {
        let _ = self.range.set((lo <= hi).then(|| [self.value(lo), self.value(hi)]));
    }

    /// Samples `f(x,y,z)` at every grid point (in parallel over z slices).
    pub fn from_fn<F>(dims: (usize, usize, usize), origin: [f64; 3], spacing: [f64; 3], f: F) -> Result<Self>
    where
        F: Fn(f64, f64, f64) -> f32 + Sync,
    {
        let (nx, ny, nz) = dims;
        let slice = slice_len(dims)?;
        let total = slice * nz;
        let mut v = vec![0.0f32; total];
        if slice > 0 {
            v.par_chunks_mut(slice).enumerate().for_each(|(k, s)| {
                let z = origin[2] + k as f64 * spacing[2];
                for j in 0..ny {
                    let y = origin[1] + j as f64 * spacing[1];
                    for i in 0..nx {
                        let x = origin[0] + i as f64 * spacing[0];
                        s[j * nx + i] = f(x, y, z);
                    }
                }
            });
        }
        Volume::new(v.into(), dims, origin, spacing)
    }
}

/// The paper's synthetic field `f(x,y,z) = sin(x*y*z/8) + cos((x-2)(y-2)(z-2))`
/// on `[-5,5]^3`, sampled at `n^3` points (`n >= 2`). Extract it at isovalue 0.
#[cfg(test)]
pub fn pesco_synthetic(n: usize) -> Volume {
    let n = n.max(2);
    let h = 10.0 / (n - 1) as f64;
    Volume::from_fn((n, n, n), [-5.0; 3], [h; 3], |x, y, z| {
        ((x * y * z / 8.0).sin() + ((x - 2.0) * (y - 2.0) * (z - 2.0)).cos()) as f32
    })
    .expect("valid synthetic volume")
}

/// Signed distance to a sphere for tests: `value = |p - c| - radius`, with
/// `c = (0,0,0)`, sampled at `n^3` points (`n >= 2`) on the cube `[-1,1]^3`.
/// Use `radius < 1` for a closed surface; extract at isovalue 0.
#[cfg(test)]
pub fn sphere_field(n: usize, radius: f64) -> Volume {
    let n = n.max(2);
    let h = 2.0 / (n - 1) as f64;
    Volume::from_fn((n, n, n), [-1.0; 3], [h; 3], |x, y, z| ((x * x + y * y + z * z).sqrt() - radius) as f32)
        .expect("valid sphere volume")
}

/// Three cameras about `vol`'s box for the walk's tests, each with the direction of its eye from
/// the box centre (in box spans): two perspective views from opposite sides, below and above,
/// and an orthographic one from almost straight above.
#[cfg(test)]
pub(crate) fn test_views(vol: &Volume) -> Vec<([f64; 3], crate::camera::Camera)> {
    use crate::camera::{Camera, Projection};
    let size = [vol.nx, vol.ny, vol.nz].map(|n| n as f64 - 1.0);
    let c = [0, 1, 2].map(|a| vol.origin[a] + 0.5 * size[a] * vol.spacing[a]);
    let span = (0..3).map(|a| size[a] * vol.spacing[a]).fold(0.0, f64::max);
    [
        ([2.0, 1.3, 0.9], Projection::Perspective),
        ([-0.8, 2.1, -1.2], Projection::Perspective),
        ([0.3, -0.2, 3.0], Projection::Orthographic),
    ]
    .into_iter()
    .map(|(dir, proj)| {
        let eye = [0, 1, 2].map(|a| c[a] + dir[a] * span);
        (dir, Camera::look_at(eye, c, [0.0, 0.0, 1.0], 40.0, None, None, proj, Some(1.2 * span), 1.0).unwrap())
    })
    .collect()
}

/// A dense wavy field for the walk's tests (37 × 33 × 29 samples, z spacing 0.5): sheets of
/// surface across the whole volume at isovalue 0, most bricks straddling it.
#[cfg(test)]
pub(crate) fn wavy_field() -> Volume {
    Volume::from_fn((37, 33, 29), [0.0; 3], [1.0, 1.0, 0.5], |x, y, z| {
        ((0.41 * x).sin() + (0.33 * y + 0.13 * x).cos() + (0.67 * z).sin() * 0.8 - 0.2) as f32
    })
    .expect("valid wavy volume")
}

#[cfg(test)]
mod volume_tests;
