//! Height fields (horizons, terrain): a (ny, nx) grid of heights cut into tiles of the grid, with
//! lattice or QEM coarse proxies (`crate::lod::tile_heightfield`).
//!
//! Rotated grids (xtgeo's `rotation`, `yflip`): the GPU vertices are world positions, rotated in
//! f64 before they are stored origin-relative in f32 (`lod::GridSpec::pos`), so every strategy that
//! works on tiles and their boxes (three_pass, oracle, frustum) sees an ordinary mesh. Tiles, tile
//! order and the triangulation stay those of the grid's own (i, j) frame, and the object keeps that
//! frame ([`ObjectKind::Heightfield`]): a strategy that needs the grid (horizon culling's axis-aligned
//! quadtree) works in the grid's frame and folds the rotation into its view-projection matrix, as it
//! already did with the object's translation (see `cull::horizon::strategy`).

use super::{check_coarse_factor, check_color, AddOptions, ColorByArg, ColorSource, Object, ObjectKind, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use crate::lod::slab::{Slab, TileSlabs};
use crate::lod::{self, cos_sin_deg, GridSpec, TileMesh};
use glam::DVec3;
use rayon::prelude::*;

/// What a height-field object keeps besides its tiles (`ObjectKind::Heightfield`): its grid
/// layout in the grid's own frame, and its tiles' slabs. Sample (i, j) lies at `(x0, y0) +
/// R(rotation) (i dx, j dy)` (x0, y0 relative to the object's origin; `dy < 0` for a yflipped
/// grid; R counter-clockwise by `rotation` degrees, see `lod::cos_sin_deg`). The heights live only
/// in the tiles' vertices; [`Object::height_grid`] rebuilds the grid when a CPU culler needs it.
#[derive(Clone, Debug)]
pub struct HeightfieldInfo {
    pub nx: usize,
    pub ny: usize,
    pub x0: f64,
    pub y0: f64,
    pub dx: f64,
    pub dy: f64,
    pub rotation: f64,
    /// Tiles (columns, rows) the grid is cut into (`lod::tile_bounds` of each axis).
    pub tiles: (usize, usize),
    /// Per tile, its slab ([`Object::slabs`]): built with the tiles, or on first use.
    pub slabs: TileSlabs,
}

/// Where a height field's grid lies: sample (i, j) at `origin + R(rotation) (i dx, ±j dy)` (world
/// units), rows towards -y in the grid's frame when `yflip`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFrame {
    /// World (x, y) of sample (0, 0), the centre of rotation.
    pub origin: [f64; 2],
    /// (dx, dy) > 0: the distance between columns and between rows.
    pub spacing: [f64; 2],
    /// Degrees counter-clockwise (seen from +z) about `origin`, xtgeo's convention.
    pub rotation: f64,
    /// xtgeo's yflip = -1: row j lies at -j dy along the grid's y axis (a left-handed grid).
    pub yflip: bool,
}

impl GridFrame {
    /// An axis-aligned grid: sample (i, j) at `(x0 + i dx, y0 + j dy)`.
    pub fn new(origin: [f64; 2], spacing: [f64; 2]) -> Self {
        Self { origin, spacing, rotation: 0.0, yflip: false }
    }
    /// The same grid rotated by `rotation` degrees and with rows flipped when `yflip`.
    pub fn rotated(self, rotation: f64, yflip: bool) -> Self {
        Self { rotation, yflip, ..self }
    }

    /// Checks the frame of a grid of `nx` x `ny` samples cut into `tiles` (columns, rows), as
    /// [`Scene::add_heightfield`] does and as `Scene::from_bytes` does on reading one: origin and
    /// rotation finite, spacings finite, > 0 and normal (a denormal spacing puts every sample at
    /// the origin), every corner within +-[`MAX_COORD`], each axis cut into 1..n - 1 tiles.
    /// Errors name `origin`, `spacing`, `rotation` or `tiles`. Returns the grid's four corners
    /// (x, y): the extremes of the rotated rectangle.
    pub(crate) fn check(&self, nx: usize, ny: usize, tiles: (usize, usize)) -> Result<[(f64, f64); 4]> {
        let GridFrame { origin, spacing, rotation, yflip } = *self;
        ensure(nx >= 2 && ny >= 2, "z", || {
            format!("z has shape ({ny}, {nx}); a height field needs at least 2 x 2 samples")
        })?;
        for (i, v) in origin.iter().enumerate() {
            ensure(v.is_finite(), "origin", || format!("component {i} is {v}; expected a finite number"))?;
        }
        for (i, v) in spacing.iter().enumerate() {
            ensure(v.is_normal() && *v > 0.0, "spacing", || {
                let tiny = if v.is_finite() && *v > 0.0 {
                    format!(" (at least {:e})", f64::MIN_POSITIVE)
                } else {
                    String::new()
                };
                format!("component {i} is {}; expected a finite number > 0{tiny}", num(*v))
            })?;
        }
        ensure(rotation.is_finite(), "rotation", || {
            format!("rotation is {rotation}; expected a finite angle in degrees (counter-clockwise)")
        })?;
        let probe = GridSpec {
            z: &[],
            nx,
            ny,
            x0: origin[0],
            y0: origin[1],
            dx: spacing[0],
            dy: spacing[1],
            rot: cos_sin_deg(rotation),
            yflip,
            values: None,
        };
        let corners = [probe.pos(0, 0), probe.pos(nx - 1, 0), probe.pos(0, ny - 1), probe.pos(nx - 1, ny - 1)];
        for (i, o) in origin.iter().enumerate() {
            ensure(o.abs() <= MAX_COORD, "origin", || {
                format!("component {i} is {}; coordinates must be within +-{MAX_COORD:e}", num(*o))
            })?;
        }
        for (i, (c, ax)) in corners.iter().flat_map(|c| [(c.0, 0), (c.1, 1)]).enumerate() {
            ensure(c.abs() <= MAX_COORD, "spacing", || {
                format!(
                    "component {ax}: the grid reaches {} at corner {}; coordinates must be within +-{MAX_COORD:e}",
                    num(c),
                    i / 2
                )
            })?;
        }
        let (tx, ty) = tiles;
        ensure(tx >= 1 && tx < nx, "tiles", || {
            format!("tiles[0] is {tx}; expected 1..={} for {nx} columns (each tile needs one cell)", nx - 1)
        })?;
        ensure(ty >= 1 && ty < ny, "tiles", || {
            format!("tiles[1] is {ty}; expected 1..={} for {ny} rows (each tile needs one cell)", ny - 1)
        })?;
        Ok(corners)
    }
}

impl Scene {
    /// Adds a height field. `z` is row-major (ny, nx): x along columns, y along rows of the grid's
    /// frame (`frame`). NaN samples (and samples equal to `null_value`) are holes; triangles touching
    /// a hole are dropped.
    #[allow(clippy::too_many_arguments)]
    pub fn add_heightfield(
        &mut self,
        z: &[f64],
        ny: usize,
        nx: usize,
        frame: GridFrame,
        tiles: (usize, usize),
        null_value: Option<f64>,
        mut opts: AddOptions,
    ) -> Result<u32> {
        let GridFrame { origin, spacing, rotation, yflip } = frame;
        ensure(nx >= 2 && ny >= 2, "z", || {
            format!("z has shape ({ny}, {nx}); a height field needs at least 2 x 2 samples")
        })?;
        ensure(z.len() == nx * ny, "z", || format!("z has {} values, expected {ny} x {nx}", z.len()))?;
        let corners = frame.check(nx, ny, tiles)?;
        let rot = cos_sin_deg(rotation);
        let (tx, ty) = tiles;
        if let Some(nv) = null_value {
            ensure(!nv.is_infinite(), "null_value", || format!("null_value is {nv}; expected a finite number or NaN"))?;
        }
        let cf = check_coarse_factor(opts.coarse_factor)?;
        let color = check_color(opts.color, self.next_id)?;
        // Height fields given no colour are coloured by z.
        let color_by = super::color_by_arg(&opts.color, opts.color_by.take(), || Some(ColorByArg::z()))?;
        if let Some(c) = &color_by {
            c.check(Some((nx * ny, &format!("one per sample of z, ({ny}, {nx})"))))?;
        }
        // Holes: NaN and null_value become NaN; infinities are an error.
        let mut zz: Vec<f64> = Vec::with_capacity(z.len());
        let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, &v) in z.iter().enumerate() {
            let v = if null_value.is_some_and(|nv| v == nv) { f64::NAN } else { v };
            ensure(!v.is_infinite(), "z", || {
                format!("z[{}, {}] is {v}; use NaN or null_value for holes", k / nx, k % nx)
            })?;
            ensure(v.is_nan() || v.abs() <= MAX_COORD, "z", || {
                format!(
                    "z[{}, {}] is {}; coordinates must be within +-{MAX_COORD:e}{}",
                    k / nx,
                    k % nx,
                    num(v),
                    undefined_hint(v)
                )
            })?;
            if v.is_finite() {
                zmin = zmin.min(v);
                zmax = zmax.max(v);
            }
            zz.push(v);
        }
        let (x0, y0) = (origin[0], origin[1]);
        let (dx, dy) = (spacing[0], spacing[1]);
        if zmin > zmax {
            (zmin, zmax) = (0.0, 0.0);
        }
        let (lo, hi) = corners.iter().fold(
            (DVec3::new(f64::INFINITY, f64::INFINITY, zmin), DVec3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, zmax)),
            |(lo, hi), c| (lo.min(DVec3::new(c.0, c.1, zmin)), hi.max(DVec3::new(c.0, c.1, zmax))),
        );
        let o = self.origin_for(lo, hi);
        let values = color_by.as_ref().and_then(|c| c.values.as_deref());
        let color_by = match &color_by {
            None => None,
            Some(c) if c.source == ColorSource::Z => Some(c.resolve(zz.iter().copied())?),
            // The range of the values where z is defined (holes draw nothing).
            Some(c) => {
                Some(c.resolve(values.unwrap_or(&[]).iter().zip(&zz).filter(|(_, z)| z.is_finite()).map(|(v, _)| *v))?)
            }
        };
        let grid = GridSpec { z: &zz, nx, ny, x0, y0, dx, dy, rot, yflip, values };
        // Interruptible between tiles; on Err the scene is unchanged (the origin is set by push).
        let (tile_meshes, slabs) =
            opts.interrupt.run_parallel(|stop| lod::tile_heightfield(&grid, o, (tx, ty), cf, stop))?;
        let kind = ObjectKind::Heightfield(Box::new(HeightfieldInfo {
            nx,
            ny,
            x0: x0 - o.x,
            y0: y0 - o.y,
            dx,
            dy: if yflip { -dy } else { dy },
            rotation,
            tiles: (tx, ty),
            slabs: TileSlabs::built(slabs),
        }));
        Ok(self.push(o, opts.name, kind, color, color_by, tile_meshes))
    }
}

/// Magnitude from which a height is taken for a no-data marker rather than a height: xtgeo's
/// `UNDEF` is 1e33 (`10e32`, masked in `surf.values`, written out by `surf.get_values1d()` and
/// friends) and Irap binary maps mark undefined nodes with 1e30.
const UNDEFINED_MIN: f64 = 1e30;

/// A hint for the out-of-range message of a height that looks like an undefined-value marker.
fn undefined_hint(v: f64) -> String {
    if v.abs() >= UNDEFINED_MIN {
        format!(
            " ({} looks like an undefined-value marker: 1e33 is xtgeo's UNDEF and 1e30 that of Irap binary \
             maps; pass surf.values (a masked array) or null_value={})",
            num(v),
            num(v)
        )
    } else {
        String::new()
    }
}

/// A height field's grid in its object's frame: sample (i, j) at `o + i u + j v`, relative to the
/// object's origin (`u = dx (cos, sin)`, `v = dy (-sin, cos)` with `dy < 0` when rows are flipped).
#[derive(Clone, Copy, Debug)]
pub struct GridAxes {
    pub o: [f64; 2],
    pub u: [f64; 2],
    pub v: [f64; 2],
    pub nx: usize,
    pub ny: usize,
    /// (cos, sin) of the rotation.
    rot: (f64, f64),
    dx: f64,
    dy: f64,
}

impl GridAxes {
    /// The grid of a height field's kind; None for other kinds.
    pub(crate) fn of(kind: &ObjectKind) -> Option<Self> {
        let ObjectKind::Heightfield(hf) = kind else { return None };
        let HeightfieldInfo { nx, ny, x0, y0, dx, dy, rotation, .. } = **hf;
        let (c, s) = cos_sin_deg(rotation);
        Some(GridAxes { o: [x0, y0], u: [c * dx, s * dx], v: [-s * dy, c * dy], nx, ny, rot: (c, s), dx, dy })
    }

    /// Object-relative (x, y) of sample (i, j), rounded as `lod::GridSpec::pos` rounds it (so that
    /// it is the f64 value the tiles' f32 vertices were made from).
    pub fn pos(&self, i: usize, j: usize) -> [f64; 2] {
        let (a, b) = (i as f64 * self.dx, j as f64 * self.dy);
        let (c, s) = self.rot;
        if (c, s) == (1.0, 0.0) {
            [self.o[0] + a, self.o[1] + b]
        } else {
            [self.o[0] + (c * a - s * b), self.o[1] + (s * a + c * b)]
        }
    }

    /// The sample (column, row) nearest to object-relative (x, y): the grid frame's inverse,
    /// rounded; None outside the grid.
    pub fn sample_at(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let (c, s) = self.rot;
        let (qx, qy) = (x - self.o[0], y - self.o[1]);
        let (a, b) = if (c, s) == (1.0, 0.0) { (qx, qy) } else { (c * qx + s * qy, c * qy - s * qx) };
        Some((nearest_index(a / self.dx, self.nx)?, nearest_index(b / self.dy, self.ny)?))
    }
}

/// `v` rounded half away from zero, as `f64::round` rounds it, when that lies in `0..n`; None
/// otherwise (NaN included). Without `round`, a libm call on baseline x86-64 that took most of
/// [`GridAxes::sample_at`]'s time over every vertex of an upload: `round(v)` is in `0..n`
/// exactly when -0.5 < v < n - 0.5 (both bounds exact in f64 for the grid sizes a scene
/// holds); there the cast truncates to t = floor(v) (0 for v in (-0.5, 0)), and `v - t`,
/// exact (v and t lie within 1 of each other), says whether to round up.
pub(super) fn nearest_index(v: f64, n: usize) -> Option<usize> {
    if !(v > -0.5 && v < n as f64 - 0.5) {
        return None;
    }
    let t = v as usize;
    Some(if v - t as f64 >= 0.5 { t + 1 } else { t })
}

/// A height-field tile's vertices as samples of its grid (`Object::tile_lattice`).
#[derive(Clone, Debug, PartialEq)]
pub struct TileLattice {
    /// The smallest column and row of the tile's vertices.
    pub i0: usize,
    pub j0: usize,
    /// Per vertex of the tile (in `TileMesh::positions` order), its column and row relative to
    /// `(i0, j0)`.
    pub local: Vec<[u32; 2]>,
}

impl Object {
    /// The grid of a height field in its object's frame; None for other kinds.
    pub fn grid_axes(&self) -> Option<GridAxes> {
        GridAxes::of(&self.kind)
    }

    /// The heights of a height field as a row-major (ny, nx) grid relative to the origin's z
    /// (NaN where no triangle uses the sample), rebuilt from the tiles' vertices: every vertex is
    /// a grid sample, and its origin-relative x, y, turned back into the grid's frame, give back its
    /// integer column and row.
    pub fn height_grid(&self) -> Option<Vec<f32>> {
        self.sample_grid(|t, k| t.positions[k][2])
    }

    /// The per-vertex values (colour by data) of a height field as a row-major (ny, nx) grid, as
    /// [`Self::height_grid`] rebuilds the heights (NaN where no triangle uses the sample or where
    /// the value is no data); None for other kinds and for height fields without values.
    pub fn value_grid(&self) -> Option<Vec<f32>> {
        if self.tiles.iter().all(|t| t.values.is_empty()) {
            return None;
        }
        self.sample_grid(|t, k| t.values.get(k).copied().unwrap_or(f32::NAN))
    }

    /// `f(tile, vertex)` of every tile vertex, put at the grid sample the vertex is.
    fn sample_grid(&self, f: impl Fn(&TileMesh, usize) -> f32) -> Option<Vec<f32>> {
        let g = self.grid_axes()?;
        let mut out = vec![f32::NAN; g.nx * g.ny];
        for t in &self.tiles {
            for (k, p) in t.positions.iter().enumerate() {
                if let Some((i, j)) = g.sample_at(p[0] as f64, p[1] as f64) {
                    out[j * g.nx + i] = f(t, k);
                }
            }
        }
        Some(out)
    }

    /// Tile `t` of this height field as grid samples (the same inverse as [`Self::height_grid`]),
    /// so that the GPU can rebuild its vertices from the normal map's heights
    /// (`gpu::geometry`); None for other kinds, for empty tiles, and for a tile with a vertex that
    /// is not within a thousandth of a sample spacing of its sample (never, for tiles made by
    /// `lod::tile_heightfield`).
    pub fn tile_lattice(&self, t: &TileMesh) -> Option<TileLattice> {
        let g = self.grid_axes()?;
        let tol = 1e-3 * g.dx.abs().min(g.dy.abs());
        let samples = t
            .positions
            .iter()
            .map(|p| {
                let (i, j) = g.sample_at(p[0] as f64, p[1] as f64)?;
                let q = g.pos(i, j);
                ((q[0] - p[0] as f64).abs() <= tol && (q[1] - p[1] as f64).abs() <= tol).then_some((i, j))
            })
            .collect::<Option<Vec<_>>>()?;
        let i0 = samples.iter().map(|s| s.0).min()?;
        let j0 = samples.iter().map(|s| s.1).min()?;
        let local = samples.iter().map(|&(i, j)| [(i - i0) as u32, (j - j0) as u32]).collect();
        Some(TileLattice { i0, j0, local })
    }
}

impl Object {
    /// Per tile of a height field, its slab (`lod::slab`: the shell the box test uses as its
    /// occludee; None: the tile is box-tested); empty for other kinds. Built with the tiles by
    /// [`Scene::add_heightfield`]; for a height field read from bytes (which do not store slabs:
    /// loading allocates none) built on the first call, from the tiles' vertices as
    /// `lod::tile_heightfield` builds them, and kept. A tile gets none unless its vertices are
    /// distinct samples of its grid within its tile's range and its triangles are the lattice's
    /// (as every tile built by this crate), so a damaged scene never gets a slab that does not
    /// hold what it draws.
    pub fn slabs(&self) -> &[Option<Slab>] {
        let Some(hf) = self.heightfield() else { return &[] };
        hf.slabs.get_or_build(|| self.build_slabs())
    }

    /// Tile `t`'s slab ([`Self::slabs`]); None for tiles without one and for other kinds.
    pub fn slab(&self, t: usize) -> Option<&Slab> {
        self.slabs().get(t)?.as_ref()
    }

    /// [`Self::slabs`] built from the tiles' vertices (in parallel).
    fn build_slabs(&self) -> Vec<Option<Slab>> {
        let (Some(g), Some(bounds)) = (self.grid_axes(), self.tile_sample_bounds()) else {
            return vec![None; self.tiles.len()];
        };
        self.tiles
            .par_iter()
            .map(|tile| {
                let ((i0, j0), (w, h), map) = lattice_map(&g, &bounds, tile)?;
                let holes = tile.fine_triangles() != 2 * (w - 1) * (h - 1);
                let grid_xy = |li: usize, lj: usize| {
                    let q = g.pos(i0 + li, j0 + lj);
                    (q[0], q[1])
                };
                let slab = lod::slab::tile_slab(tile, (w, h), |li, lj| map[lj * w + li], grid_xy)?;
                // A tile with holes: its levels' errors (as built, measured) must bound them still.
                let exact = !holes
                    || lod::hole_level_bounds(tile, (w, h), &map).is_some_and(|b| {
                        !tile.levels.is_empty() && tile.levels.iter().zip(b).all(|(l, e)| l.error as f64 >= e)
                    });
                Some(Slab { levels_exact: exact, ..slab })
            })
            .collect()
    }

    /// Per tile of a height field, its height blocks (`lod::blocks`, built with its slab: see
    /// [`Self::slabs`]), for tiles with a slab; None for other tiles and kinds.
    pub fn height_blocks(&self) -> Vec<Option<std::sync::Arc<lod::blocks::HeightBlocks>>> {
        match self.heightfield() {
            Some(_) => self.slabs().iter().map(|s| s.as_ref().map(|s| s.blocks.clone())).collect(),
            None => vec![None; self.tiles.len()],
        }
    }

    /// A height field's tile boundaries in samples (`lod::tile_bounds` of each axis), when its
    /// tile counts fit its grid and its tiles; None otherwise and for other kinds.
    pub fn tile_sample_bounds(&self) -> Option<(Vec<usize>, Vec<usize>)> {
        let g = self.grid_axes()?;
        let (tx, ty) = self.heightfield()?.tiles;
        let fits = |n: usize, t: usize| t >= 1 && t < n && n <= 1 << 31;
        (fits(g.nx, tx) && fits(g.ny, ty) && self.tiles.len() == tx * ty)
            .then(|| (lod::tile_bounds(g.nx, tx), lod::tile_bounds(g.ny, ty)))
    }

    /// The fine surface of a height field as the lit pass samples it: at every sample the
    /// gradient `(dz/dx, dz/dy)` in the world's (unexaggerated, unrotated) x and y, and the height
    /// relative to the object's origin; a row-major (ny, nx) grid, None for other kinds.
    ///
    /// The lit pass shades a height field with the normal `(-dz/dx z_scale, -dz/dy z_scale, 1)`
    /// and colours it by z (when it is coloured by z) from these samples, interpolated bilinearly
    /// at the pixel's (x, y), whatever level of detail its tile is drawn at: coarser levels then
    /// shade and colour as the fine surface does, and differ from it only where the pixel's
    /// surface point moves (issue 13). Gradients are central differences where both neighbours are
    /// defined, one-sided where one is, 0 where neither is; a sample no triangle uses (a hole)
    /// takes the mean of its defined 4-neighbours, so that interpolation next to a hole stays
    /// smooth (its own triangles are never drawn).
    pub fn shading_samples(&self) -> Option<Vec<[f32; 3]>> {
        let mut out = Vec::new();
        self.for_each_shading_sample(|v| out.push(v))?;
        Some(out)
    }

    /// [`Self::shading_samples`] without the vector: `out` gets every sample in row-major order.
    /// Holds only the (ny, nx) f32 height grid meanwhile (the upload writes straight into the
    /// GPU buffer). None, without a call, for other kinds.
    pub fn for_each_shading_sample(&self, mut out: impl FnMut([f32; 3])) -> Option<()> {
        let HeightfieldInfo { nx, ny, dx, dy, rotation, .. } = *self.heightfield()?;
        let z = self.height_grid()?;
        let at = |i: usize, j: usize| z[j * nx + i];
        // One axis' derivative per sample step, from the neighbours before and after.
        let diff = |prev: Option<f32>, here: f32, next: Option<f32>| -> f64 {
            match (prev.filter(|v| v.is_finite()), next.filter(|v| v.is_finite())) {
                (Some(a), Some(b)) => (b as f64 - a as f64) / 2.0,
                (Some(a), None) => here as f64 - a as f64,
                (None, Some(b)) => b as f64 - here as f64,
                (None, None) => 0.0,
            }
        };
        let (c, s) = cos_sin_deg(rotation);
        // The sample's (gradient, height) where it is defined.
        let defined = |i: usize, j: usize| -> Option<[f32; 3]> {
            let h = at(i, j);
            if !h.is_finite() {
                return None;
            }
            let gi = diff((i > 0).then(|| at(i - 1, j)), h, (i + 1 < nx).then(|| at(i + 1, j))) / dx;
            let gj = diff((j > 0).then(|| at(i, j - 1)), h, (j + 1 < ny).then(|| at(i, j + 1))) / dy;
            // Grid frame -> world: the gradient turns with the grid (dy < 0 flips rows).
            Some([(c * gi - s * gj) as f32, (s * gi + c * gj) as f32, h])
        };
        for j in 0..ny {
            for i in 0..nx {
                out(defined(i, j).unwrap_or_else(|| {
                    // A hole: the mean of its defined 4-neighbours (not of holes filled before).
                    let near = [(i.wrapping_sub(1), j), (i + 1, j), (i, j.wrapping_sub(1)), (i, j + 1)];
                    let (mut sum, mut n) = ([0.0f32; 3], 0.0f32);
                    for v in near.into_iter().filter(|&(a, b)| a < nx && b < ny).filter_map(|(a, b)| defined(a, b)) {
                        sum = [sum[0] + v[0], sum[1] + v[1], sum[2] + v[2]];
                        n += 1.0;
                    }
                    if n > 0.0 {
                        sum.map(|x| x / n)
                    } else {
                        [0.0; 3]
                    }
                }));
            }
        }
        Some(())
    }
}

/// A tile of a height field on its grid (`bounds`: the tile boundaries in samples): its first
/// sample (i0, j0), its size (w, h) in samples and per local sample (row-major) its vertex
/// (u32::MAX: none), when its vertices are distinct samples within its range (within a thousandth
/// of a spacing) and its triangles are the lattice's (each over a fine cell, as
/// `lod::tile_heightfield` makes them); None otherwise.
#[allow(clippy::type_complexity)]
fn lattice_map(
    g: &GridAxes,
    (bx, by): &(Vec<usize>, Vec<usize>),
    tile: &TileMesh,
) -> Option<((usize, usize), (usize, usize), Vec<u32>)> {
    let (ix, iy) = (tile.ix as usize, tile.iy as usize);
    if ix + 1 >= bx.len() || iy + 1 >= by.len() {
        return None;
    }
    let (i0, j0) = (bx[ix], by[iy]);
    let (w, h) = (bx[ix + 1] - i0 + 1, by[iy + 1] - j0 + 1);
    if w * h > 4 * tile.positions.len() + 64 {
        return None;
    }
    let tol = 1e-3 * g.dx.abs().min(g.dy.abs());
    // Each vertex's local sample, and each sample's vertex.
    let mut map = vec![u32::MAX; w * h];
    let mut local = Vec::with_capacity(tile.positions.len());
    let on_grid = tile.positions.iter().enumerate().all(|(k, p)| {
        let Some((i, j)) = g.sample_at(p[0] as f64, p[1] as f64) else { return false };
        let q = g.pos(i, j);
        let near = (q[0] - p[0] as f64).abs() <= tol && (q[1] - p[1] as f64).abs() <= tol;
        if !near || !(i0..i0 + w).contains(&i) || !(j0..j0 + h).contains(&j) {
            return false;
        }
        let slot = &mut map[(j - j0) * w + i - i0];
        local.push((i - i0, j - j0));
        std::mem::replace(slot, k as u32) == u32::MAX
    });
    let lattice = on_grid
        && tile.fine.chunks_exact(3).all(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|k| local.get(k as usize).copied());
            let (Some(a), Some(b), Some(c)) = (a, b, c) else { return false };
            (b == (a.0 + 1, a.1) && c == (a.0 + 1, a.1 + 1)) || (b == (a.0 + 1, a.1 + 1) && c == (a.0, a.1 + 1))
        });
    lattice.then_some(((i0, j0), (w, h), map))
}
