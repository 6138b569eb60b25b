//! Tiling and levels of detail.
//!
//! Every object is cut into tiles. A tile owns a compact local vertex array (f32, relative to the
//! scene origin) and two triangle lists into it: level 0 (`fine`, the original triangles) and the
//! coarse proxy (`coarse`, about 1/coarse_factor of them, by quadric-error simplification with the
//! tile's border locked, see [`simplify`]). The coarse level reuses the fine vertices, so it costs
//! only its indices.
//!
//! Height fields: a (ny, nx) grid, x along columns, y along rows, two triangles per cell (diagonal
//! from sample (i, j) to (i+1, j+1)); a triangle touching a NaN sample is dropped. Tile boundaries
//! along x are `round(t * (nx-1) / tx)` for t = 0..=tx (likewise y), and neighbouring tiles share
//! their border samples so the fine level has no cracks. A grid may be rotated about its origin
//! and its rows may run towards -y ([`GridSpec::pos`]); tiles, tile order and triangles are those
//! of the grid's own (i, j) frame either way, only the vertex positions are turned.

pub mod blocks;
pub mod clearance;
pub mod groups;
mod lattice;
pub mod levels;
pub mod normals;
pub mod per_vertex;
pub mod plane;
pub mod shading;
pub mod simplify;
pub mod slab;
pub mod tube;

use crate::error::Work;
use glam::DVec3;
pub use per_vertex::PerVertex;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// A triangle list into a tile's vertices, shared between tiles whose lists are equal (hole-free
/// tiles of one height field's shape: [`share_indices`]).
pub type Indices = std::sync::Arc<[u32]>;

/// Makes equal triangle lists of `tiles` (fine, coarse and levels, across tiles) one shared
/// allocation: the tiles of a height field without holes all have the same few, so their host
/// copy costs the vertices only.
pub fn share_indices(tiles: &mut [TileMesh]) {
    let mut seen: std::collections::HashSet<Indices> = std::collections::HashSet::new();
    // Allocations already shared (lattice shapes' lists): by address, without hashing their content.
    let mut kept: std::collections::HashSet<(usize, usize)> = std::collections::HashSet::new();
    let mut share = |l: &mut Indices| {
        if l.is_empty() || kept.contains(&(l.as_ptr() as usize, l.len())) {
            return;
        }
        match seen.get(l) {
            Some(s) => *l = s.clone(),
            None => {
                seen.insert(l.clone());
            }
        }
        kept.insert((l.as_ptr() as usize, l.len()));
    };
    for t in tiles {
        share(&mut t.fine);
        share(&mut t.coarse);
        for l in &mut t.levels {
            share(&mut l.indices);
            l.grouped.iter_mut().for_each(&mut share);
        }
    }
}

/// One tile of one object.
#[derive(Clone, Debug, Default)]
pub struct TileMesh {
    pub ix: u32,
    pub iy: u32,
    /// Local vertices, relative to the scene origin (world units, not exaggerated).
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex scalar for colour by data (`values=` of the add functions; a grid's cell
    /// property): empty when the object has none, else one per entry of `positions`. NaN = no
    /// data (drawn in the colour map's NaN colour).
    pub values: PerVertex<f32>,
    /// Per-vertex smooth normals for the lit pass ([`normals`]: packed, `normals::NONE` for none):
    /// empty when the object shades by its facets (height fields take theirs from the fine
    /// surface instead, grids are flat), else one per entry of `positions`.
    pub normals: PerVertex<u32>,
    /// Per-vertex grid coordinates of a mesh that is a structured grid with smooth normals
    /// ([`structured_grid`]): `i | j << 16` for column i and row j (packed as two u16). The lit
    /// pass then shades every level from the fine grid's normals at the interpolated (i, j), as
    /// height fields do from their fine surface. Empty otherwise, else one per entry of
    /// `positions`.
    pub grid_uv: PerVertex<u32>,
    /// Per-vertex height of a well tube's vertex above the centre of its ring (world units,
    /// [`tube`]): vertical exaggeration stretches the well's path, not its rings (the lit pass
    /// lowers the vertex by `(1 - 1 / z_scale)` times this), so that a tube keeps its radius on
    /// screen however much z is exaggerated. Each vertex minus this lies within the tile's box
    /// in z. Empty for other tiles (and for tubes read from bytes older than version 9, drawn
    /// exaggerated whole), else one per entry of `positions`.
    pub ring_z: PerVertex<f32>,
    /// Per-vertex station of a well tube coloured by a log, counted from the tile's first station
    /// (a small exact integer; [`tube`]): the lit pass interpolates it and looks the log up per
    /// fragment from the tile's table (`values` by station, `gpu::cell_values`), so that a level
    /// keeping fewer stations shows level 0's colours. Empty for other tiles (and for tubes read
    /// from bytes older than version 11, coloured by their vertices' values), else one per entry
    /// of `positions`.
    pub stations: PerVertex<f32>,
    /// Fine (level 0) triangle list into `positions` (shared with the tiles of the same shape,
    /// [`share_indices`]).
    pub fine: Indices,
    /// Coarse proxy triangle list into `positions`.
    pub coarse: Indices,
    pub bbox_min: [f32; 3],
    pub bbox_max: [f32; 3],
    /// How far the coarse proxy may lie from the fine triangles, world units (not exaggerated):
    /// lattice proxies of height fields, the exact largest vertical distance at any fine sample;
    /// quadric simplification, meshoptimizer's own error estimate scaled by the tile's extent;
    /// 0 when the proxy is the fine level itself.
    pub proxy_error: f32,
    /// Levels 1.. for screen-space-error LOD ([`levels`]): each about a quarter of the triangles
    /// of the one before, the tile's border at full resolution; level 0 is `fine`.
    pub levels: Box<[levels::Level]>,
}

impl TileMesh {
    /// Each level's triangle list followed by its group variants (`Level::grouped`), level by
    /// level: the draws the upload gives a lattice tile after its fine and coarse ones.
    pub fn level_lists(&self) -> impl Iterator<Item = &Indices> {
        self.levels.iter().flat_map(|l| std::iter::once(&l.indices).chain(&l.grouped))
    }
    pub fn is_empty(&self) -> bool {
        self.fine.is_empty()
    }
    pub fn fine_triangles(&self) -> usize {
        self.fine.len() / 3
    }
    pub fn coarse_triangles(&self) -> usize {
        self.coarse.len() / 3
    }

    /// Sets `bbox_min` / `bbox_max` from the positions ([`Self::tight_bbox`]).
    pub fn compute_bbox(&mut self) {
        (self.bbox_min, self.bbox_max) = self.tight_bbox();
    }

    /// The bounds of the positions (zeros when there are none): the box every builder gives a
    /// tile, and the one `Scene::from_bytes` requires.
    pub fn tight_bbox(&self) -> ([f32; 3], [f32; 3]) {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if self.positions.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        (lo, hi)
    }

    /// Boxes whose union holds every fine triangle, as the box test uses them in place of the
    /// tile's box at level 0: of [`Self::sub_boxes`] (2 × 2 cells of the (x, y) box: a sloping
    /// surface) and [`Self::slice_boxes`] (8 slices along the box's longest side: a tube, a steep
    /// or long piece), the set of the smaller total volume. Both in one pass over the triangles.
    pub fn occludee_boxes(&self) -> Vec<([f32; 3], [f32; 3])> {
        self.finer_boxes(2, 8)
    }

    /// Of [`Self::sub_boxes`]`(s)` and [`Self::slice_boxes`]`(k)`, the set of the smaller total
    /// volume (one pass over the triangles).
    pub fn finer_boxes(&self, s: usize, k: usize) -> Vec<([f32; 3], [f32; 3])> {
        let (grid, slices) = self.cell_and_slice_boxes(s, k);
        if boxes_volume(&slices) < boxes_volume(&grid) {
            slices
        } else {
            grid
        }
    }

    /// Boxes whose union holds every fine triangle: the tile's box cut across its longest side
    /// into `k` equal slices, each the bounding box of the triangles whose centroid lies in it
    /// (their whole extent, so slices overlap where triangles straddle); empty slices left out.
    pub fn slice_boxes(&self, k: usize) -> Vec<([f32; 3], [f32; 3])> {
        self.cell_and_slice_boxes(1, k).1
    }

    /// Boxes whose union holds every fine triangle: the tile's (x, y) box cut into `s` × `s` cells,
    /// each the bounding box of the triangles whose own box overlaps it (so the boxes overlap
    /// where triangles straddle cells); cells without triangles are left out. Tighter than the
    /// tile's box for a sloping or curved tile: each cell spans only its part of the heights.
    pub fn sub_boxes(&self, s: usize) -> Vec<([f32; 3], [f32; 3])> {
        self.cell_and_slice_boxes(s, 1).0
    }

    /// [`Self::sub_boxes`]`(s)` and [`Self::slice_boxes`]`(k)` in one pass over the triangles.
    #[allow(clippy::type_complexity)]
    fn cell_and_slice_boxes(&self, s: usize, k: usize) -> (Vec<([f32; 3], [f32; 3])>, Vec<([f32; 3], [f32; 3])>) {
        let (s, k) = (s.max(1), k.max(1));
        let (lo, hi) = (self.bbox_min, self.bbox_max);
        let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
        let width = (hi[axis] - lo[axis]) / k as f32;
        let cell = [(hi[0] - lo[0]) / s as f32, (hi[1] - lo[1]) / s as f32];
        // The slot of `v` among `n` of size `size` from `from`: floor, clamped to 0..n (a cast
        // truncates, which is the floor of what max(0) leaves; NaN goes to 0 either way).
        let slot = |v: f32, from: f32, size: f32, n: usize| {
            if size > 0.0 {
                (((v - from) / size).max(0.0) as usize).min(n - 1)
            } else {
                0
            }
        };
        let empty = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut cells, mut slices) = (vec![empty; s * s], vec![empty; k]);
        let grow = |(l, h): &mut ([f32; 3], [f32; 3]), a: [f32; 3], b: [f32; 3]| {
            for d in 0..3 {
                l[d] = l[d].min(a[d]);
                h[d] = h[d].max(b[d]);
            }
        };
        for t in self.fine.chunks_exact(3) {
            let p = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
            let (mut a, mut b) = (p[0], p[0]);
            for q in &p[1..] {
                for d in 0..3 {
                    a[d] = a[d].min(q[d]);
                    b[d] = b[d].max(q[d]);
                }
            }
            let c = (p[0][axis] + p[1][axis] + p[2][axis]) / 3.0;
            grow(&mut slices[slot(c, lo[axis], width, k)], a, b);
            let (x0, x1) = (slot(a[0], lo[0], cell[0], s), slot(b[0], lo[0], cell[0], s));
            for cy in slot(a[1], lo[1], cell[1], s)..=slot(b[1], lo[1], cell[1], s) {
                for cx in x0..=x1 {
                    grow(&mut cells[cy * s + cx], a, b);
                }
            }
        }
        cells.retain(|(l, h)| l[0] <= h[0]);
        slices.retain(|(l, h)| l[0] <= h[0]);
        (cells, slices)
    }

    /// Bounding box, and the coarse proxy (with its error) by quadric simplification unless
    /// `coarse` is given; levels by simplification unless set, with their shading error measured
    /// unless the tile is `fine_shaded` (a height field's: the lit pass shades it from its fine
    /// surface at every level). A tile coloured by data (`values`) gets no levels: its object
    /// keeps its full resolution (`Scene::push`), so none would be drawn.
    fn finish(mut self, coarse_factor: f32, coarse: Option<(Vec<u32>, f32)>, fine_shaded: bool) -> Self {
        self.compute_bbox();
        let (c, e) = coarse.unwrap_or_else(|| simplify::coarse_indices(&self.positions, &self.fine, coarse_factor));
        (self.coarse, self.proxy_error) = (c.into(), e);
        if self.levels.is_empty() && !self.fine.is_empty() && self.values.is_empty() {
            let shading = (!fine_shaded).then_some(levels::Shading { normals: &self.normals, grid_uv: &self.grid_uv });
            self.levels = levels::simplified_levels(&self.positions, &self.fine, shading).into();
        }
        self
    }
}

/// Tile boundaries: `n_samples` samples cut into `n_tiles` runs sharing their end samples,
/// `b[t] = round(t (n_samples - 1) / n_tiles) for t = 0..=n_tiles`, in exact integer arithmetic
/// (halves round up). The renderer's tiles and the horizon culler's quadtree both use it.
pub fn tile_bounds(n_samples: usize, n_tiles: usize) -> Vec<usize> {
    (0..=n_tiles).map(|t| (2 * t * (n_samples - 1) + n_tiles) / (2 * n_tiles)).collect()
}

/// Cosine and sine of an angle in degrees, exact (0, +-1) at multiples of 90° so that grids
/// rotated by a quarter turn keep exact, axis-aligned positions (`90f64.to_radians().cos()` is
/// 6e-17, not 0). `deg` must be finite.
pub fn cos_sin_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r == 0.0 {
        (1.0, 0.0)
    } else if r == 90.0 {
        (0.0, 1.0)
    } else if r == 180.0 {
        (-1.0, 0.0)
    } else if r == 270.0 {
        (0.0, -1.0)
    } else {
        let (s, c) = deg.to_radians().sin_cos();
        (c, s)
    }
}

/// A height field grid in world coordinates. `z` is row-major (ny, nx); NaN = hole.
///
/// Sample (i, j) lies at `(x0, y0) + R(rotation) (i dx, j dy')` with `dy' = -dy` when `yflip`
/// (xtgeo's yflip = -1: rows run towards -y in the grid's frame) and R the counter-clockwise
/// rotation by `rotation` degrees about the origin (xtgeo's convention), see [`GridSpec::pos`].
pub struct GridSpec<'a> {
    pub z: &'a [f64],
    pub nx: usize,
    pub ny: usize,
    pub x0: f64,
    pub y0: f64,
    pub dx: f64,
    pub dy: f64,
    /// (cos, sin) of the rotation ([`cos_sin_deg`]); (1, 0) for an axis-aligned grid.
    pub rot: (f64, f64),
    pub yflip: bool,
    /// Per-sample scalars for colour by data, row-major (ny, nx) like `z`; None = none.
    pub values: Option<&'a [f64]>,
}

impl GridSpec<'_> {
    /// World (x, y) of sample (i, j), in f64. For rot = (1, 0) and no yflip this is exactly
    /// `(x0 + i dx, y0 + j dy)`.
    #[inline]
    pub fn pos(&self, i: usize, j: usize) -> (f64, f64) {
        let u = i as f64 * self.dx;
        let v = j as f64 * if self.yflip { -self.dy } else { self.dy };
        let (c, s) = self.rot;
        if (c, s) == (1.0, 0.0) {
            (self.x0 + u, self.y0 + v)
        } else {
            (self.x0 + (c * u - s * v), self.y0 + (s * u + c * v))
        }
    }
}

/// The summed volume of boxes `lo..hi` (overlaps counted twice; an empty box counts 0).
pub fn boxes_volume(boxes: &[([f32; 3], [f32; 3])]) -> f64 {
    boxes.iter().map(|(l, h)| (0..3).map(|a| (h[a] as f64 - l[a] as f64).max(0.0)).product::<f64>()).sum()
}

/// Cuts a height field into `tiles = (tx, ty)` tiles (in parallel). Returns `tx * ty` tiles in
/// row-major order (index `iy * tx + ix`; tiles wholly inside holes are empty) and their slabs
/// ([`slab::tile_slab`]: the shells the box test uses as their occludees), in the same order. Once
/// `stop` is set, tiles not yet started are left empty (the caller discards the result; see
/// `crate::error::Interrupt::run_parallel`).
pub fn tile_heightfield(
    g: &GridSpec,
    origin: DVec3,
    tiles: (usize, usize),
    coarse_factor: f32,
    stop: &Work,
) -> (Vec<TileMesh>, Vec<Option<slab::Slab>>) {
    let (tx, ty) = tiles;
    let bx = tile_bounds(g.nx, tx);
    let by = tile_bounds(g.ny, ty);
    let shapes = levels::ShapeCache::default();
    (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (ix, iy) = (t % tx, t / tx);
            if stop.load(Ordering::Relaxed) {
                return (TileMesh::default(), None);
            }
            let (i0, i1, j0, j1) = (bx[ix], bx[ix + 1], by[iy], by[iy + 1]);
            let w = i1 - i0 + 1;
            let h = j1 - j0 + 1;
            let at = |i: usize, j: usize| g.z[j * g.nx + i];
            // Local sample -> vertex index (u32::MAX = not used by any triangle).
            let mut map = vec![u32::MAX; w * h];
            let mut tile = TileMesh { ix: ix as u32, iy: iy as u32, ..Default::default() };
            let mut vertex = |li: usize, lj: usize, tile: &mut TileMesh| -> u32 {
                let slot = &mut map[lj * w + li];
                if *slot == u32::MAX {
                    *slot = tile.positions.len() as u32;
                    let (i, j) = (i0 + li, j0 + lj);
                    // World position in f64 (rotation included), then origin-relative f32.
                    let (x, y) = g.pos(i, j);
                    tile.positions.push([(x - origin.x) as f32, (y - origin.y) as f32, (at(i, j) - origin.z) as f32]);
                    if let Some(v) = g.values {
                        tile.values.push(v[j * g.nx + i] as f32);
                    }
                }
                *slot
            };
            let mut fine = Vec::with_capacity(6 * (w - 1) * (h - 1));
            for lj in 0..h - 1 {
                for li in 0..w - 1 {
                    let (i, j) = (i0 + li, j0 + lj);
                    let z00 = at(i, j).is_finite();
                    let z10 = at(i + 1, j).is_finite();
                    let z11 = at(i + 1, j + 1).is_finite();
                    let z01 = at(i, j + 1).is_finite();
                    if z00 && z10 && z11 {
                        let a = vertex(li, lj, &mut tile);
                        let b = vertex(li + 1, lj, &mut tile);
                        let c = vertex(li + 1, lj + 1, &mut tile);
                        fine.extend_from_slice(&[a, b, c]);
                    }
                    if z00 && z11 && z01 {
                        let a = vertex(li, lj, &mut tile);
                        let c = vertex(li + 1, lj + 1, &mut tile);
                        let d = vertex(li, lj + 1, &mut tile);
                        fine.extend_from_slice(&[a, c, d]);
                    }
                }
            }
            tile.fine = fine.into();
            // Hole-free tiles: the proxy is the sample lattice at stride k = round(sqrt(coarse_factor)),
            // always keeping the tile's last row and column. Neighbours then keep the same border
            // samples, so proxies meet without cracks at any factor. (Quadric simplification with a
            // locked border cannot go below the border's own edges: about 1/20 for 40 x 40 cells.)
            let k = (coarse_factor as f64).sqrt().round() as usize;
            let holes = tile.fine_triangles() != 2 * (w - 1) * (h - 1);
            let lattice = (k > 1 && !holes).then(|| {
                let steps = |n: usize| -> Vec<usize> { (0..n - 1).step_by(k).chain(std::iter::once(n - 1)).collect() };
                let (xs, ys) = (steps(w), steps(h));
                let mut idx = Vec::with_capacity(6 * xs.len() * ys.len());
                let mut err = 0.0f64;
                let zl = |li: usize, lj: usize| at(i0 + li, j0 + lj);
                for jj in ys.windows(2) {
                    for ii in xs.windows(2) {
                        let m = |li: usize, lj: usize| map[lj * w + li];
                        let (a, b, c, d) = (m(ii[0], jj[0]), m(ii[1], jj[0]), m(ii[1], jj[1]), m(ii[0], jj[1]));
                        idx.extend_from_slice(&[a, b, c, a, c, d]);
                        // Vertical distance of every fine sample of the quad to the two proxy
                        // triangles (a, b, c) below the diagonal a-c and (a, c, d) above it.
                        let (za, zb, zc, zd) = (zl(ii[0], jj[0]), zl(ii[1], jj[0]), zl(ii[1], jj[1]), zl(ii[0], jj[1]));
                        let (sx, sy) = ((ii[1] - ii[0]) as f64, (jj[1] - jj[0]) as f64);
                        for lj in jj[0]..=jj[1] {
                            for li in ii[0]..=ii[1] {
                                let (u, v) = ((li - ii[0]) as f64 / sx, (lj - jj[0]) as f64 / sy);
                                let p = if u >= v {
                                    za + u * (zb - za) + v * (zc - zb)
                                } else {
                                    za + u * (zc - zd) + v * (zd - za)
                                };
                                err = err.max((zl(li, lj) - p).abs());
                            }
                        }
                    }
                }
                (idx, err as f32)
            });
            if !holes {
                let zl = |li: usize, lj: usize| at(i0 + li, j0 + lj);
                // Hole-free tiles of one size number their vertices alike (the loop above), so
                // tiles of one size and masks share a shape.
                let masks = groups::masks(groups::open_sides(ix, iy, tx, ty));
                let shape = levels::LatticeShape::shared(&shapes, w, h, &|li, lj| map[lj * w + li], &masks);
                tile.levels = shape.levels(&zl).into();
                debug_assert_eq!(tile.fine, shape.fine);
                tile.fine = shape.fine.clone(); // one allocation for all such tiles
            }
            let grid_xy = |li: usize, lj: usize| {
                let (x, y) = g.pos(i0 + li, j0 + lj);
                (x - origin.x, y - origin.y)
            };
            let slab = slab::tile_slab(&tile, (w, h), |li, lj| map[lj * w + li], grid_xy)
                .map(|s| slab::Slab { levels_exact: !holes, ..s });
            let mut tile = tile.finish(coarse_factor, lattice, true);
            let slab = match slab {
                Some(s) if holes && !tile.levels.is_empty() => {
                    Some(slab::Slab { levels_exact: exact_hole_levels(&mut tile, (w, h), &map), ..s })
                }
                s => s,
            };
            (tile, slab)
        })
        .inspect(|_| stop.item_done())
        .unzip()
}

/// A height-field tile with holes: its simplified levels' errors measured exactly as vertical
/// distances to its fine triangles ([`hole_level_bounds`]), in place of the simplifier's
/// estimates; true when they then bound every level (its slab's `Slab::levels_exact`, so that
/// the culling tests grow the slab by them as for lattice levels), false with the levels left as
/// they were when a level is no such bound (a triangle over a hole).
fn exact_hole_levels(tile: &mut TileMesh, size: (usize, usize), map: &[u32]) -> bool {
    let Some(bounds) = hole_level_bounds(tile, size, map) else { return false };
    for (l, e) in tile.levels.iter_mut().zip(bounds) {
        l.error = f32_at_least(e);
        // A vertical bound: all of it is vertical.
        l.error_z = l.error;
        l.grouped_error = l.error;
    }
    true
}

/// Per level of a height-field tile of `w` x `h` samples (`map`: local sample -> vertex,
/// u32::MAX: none), the largest vertical distance between it and the tile's fine triangles
/// ([`levels::grid_level_error`]); None where some level has no such bound.
pub fn hole_level_bounds(tile: &TileMesh, (w, h): (usize, usize), map: &[u32]) -> Option<Vec<f64>> {
    let mut at = vec![[0u32; 2]; tile.positions.len()];
    for (k, &v) in map.iter().enumerate() {
        if let Some(a) = at.get_mut(v as usize) {
            *a = [(k % w) as u32, (k / w) as u32];
        }
    }
    let zk: Vec<f64> = tile.positions.iter().map(|p| p[2] as f64).collect();
    let z = |i: usize, j: usize| match map[j * w + i] {
        u32::MAX => f64::NAN,
        v => zk[v as usize],
    };
    tile.levels.iter().map(|l| levels::grid_level_error((w, h), z, (&at, &zk), &l.indices)).collect()
}

/// The least f32 at or above `x` (finite): where a bound computed in f64 is stored as f32.
pub(crate) fn f32_at_least(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// The greatest f32 at or below `x` (finite).
pub(crate) fn f32_at_most(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}

/// Optional per-vertex attributes of a mesh, one per vertex each.
#[derive(Clone, Copy, Default)]
pub struct VertexAttributes<'a> {
    /// Scalars for colour by data.
    pub values: Option<&'a [f64]>,
    /// Packed smooth normals ([`normals::smooth_normals`]).
    pub normals: Option<&'a [u32]>,
    /// Packed grid coordinates (`TileMesh::grid_uv`).
    pub grid_uv: Option<&'a [u32]>,
}

/// The largest side (columns or rows) of a structured grid mesh that shades from its grid.
pub const MAX_GRID_SIDE: usize = 1 << 16;

/// The columns `nu` and rows `nv` of a mesh that is a structured grid of vertices numbered
/// row-major (vertex `j nu + i`), triangulated as `geocull.data.grid_faces` and height fields
/// are: every cell, with a = (j, i), b = (j, i + 1), c = (j + 1, i), d = (j + 1, i + 1), split into
/// the triangles (a, b, d) and (a, d, c), each once, in any order and either winding. None for any
/// other mesh, or a grid with a side over [`MAX_GRID_SIDE`].
pub fn structured_grid(n_vertices: usize, faces: &[[u32; 3]]) -> Option<(usize, usize)> {
    let sorted = |f: &[u32; 3]| {
        let mut s = f.map(|k| k as usize);
        s.sort_unstable();
        s
    };
    let s = sorted(faces.first()?);
    let nu = if s[1] == s[0] + 1 { (s[2] - s[0]).checked_sub(1)? } else { s[1] - s[0] };
    if nu < 2 || !n_vertices.is_multiple_of(nu) {
        return None;
    }
    let nv = n_vertices / nu;
    if nv < 2 || nu > MAX_GRID_SIDE || nv > MAX_GRID_SIDE || faces.len() != 2 * (nu - 1) * (nv - 1) {
        return None;
    }
    // Per cell and half (0: (a, b, d), 1: (a, d, c)), whether a face is it.
    let mut seen = vec![false; 2 * (nu - 1) * (nv - 1)];
    for f in faces {
        let [a, x, y] = sorted(f);
        let (i, j) = (a % nu, a / nu);
        let half = if (x, y) == (a + 1, a + nu + 1) {
            0
        } else if (x, y) == (a + nu, a + nu + 1) {
            1
        } else {
            return None;
        };
        if i + 1 >= nu || j + 1 >= nv || std::mem::replace(&mut seen[2 * (j * (nu - 1) + i) + half], true) {
            return None;
        }
    }
    Some((nu, nv))
}

/// Cuts a triangle mesh into about `clusters` spatially coherent tiles (1 = one tile).
/// `vertices` are world coordinates, `attrs` optional per-vertex scalars (colour by data) and
/// normals; `faces` index into them (validated by the caller). Once
/// `stop` is set, tiles not yet started are left empty (as in [`tile_heightfield`]).
pub fn tile_mesh(
    vertices: &[[f64; 3]],
    attrs: VertexAttributes<'_>,
    faces: &[[u32; 3]],
    origin: DVec3,
    clusters: usize,
    coarse_factor: f32,
    stop: &Work,
) -> Vec<TileMesh> {
    let (ids, n) = if clusters <= 1 || faces.len() <= 1 {
        (vec![0u32; faces.len()], 1)
    } else {
        simplify::cluster_triangles(vertices, faces, clusters)
    };
    if stop.load(Ordering::Relaxed) {
        return Vec::new();
    }
    stop.set_total(n);
    // Faces of each cluster, in input order.
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, &c) in ids.iter().enumerate() {
        members[c as usize].push(f as u32);
    }
    members
        .into_par_iter()
        .enumerate()
        .map(|(c, fs)| {
            if stop.load(Ordering::Relaxed) {
                return TileMesh::default();
            }
            let mut map = std::collections::HashMap::<u32, u32>::with_capacity(fs.len());
            let mut tile = TileMesh { ix: c as u32, iy: 0, ..Default::default() };
            let mut fine = Vec::with_capacity(3 * fs.len());
            for &f in &fs {
                for &v in &faces[f as usize] {
                    let next = tile.positions.len() as u32;
                    let slot = *map.entry(v).or_insert(next);
                    if slot == next {
                        let p = vertices[v as usize];
                        tile.positions.push([
                            (p[0] - origin.x) as f32,
                            (p[1] - origin.y) as f32,
                            (p[2] - origin.z) as f32,
                        ]);
                        if let Some(vals) = attrs.values {
                            tile.values.push(vals[v as usize] as f32);
                        }
                        if let Some(ns) = attrs.normals {
                            tile.normals.push(ns[v as usize]);
                        }
                        if let Some(uv) = attrs.grid_uv {
                            tile.grid_uv.push(uv[v as usize]);
                        }
                    }
                    fine.push(slot);
                }
            }
            tile.fine = fine.into();
            tile.finish(coarse_factor, None, false)
        })
        .inspect(|_| stop.item_done())
        .collect()
}

#[cfg(test)]
mod tests;
