//! The hiders of a frame: each height field drawn, as the render-space heights of its tiles'
//! height blocks (`lod::blocks`) on its grid, in index space, and the queries the proof makes of
//! them (`super`).

use super::super::FrameInputs;
use super::flat::{FlatTable, Found};
use crate::lod::blocks;
use glam::{DMat2, DVec2, DVec3};
use rayon::prelude::*;

/// The most blocks of a hider one query reads (the proof's work per test stays bounded).
const MAX_BLOCKS: usize = 4096;

/// Flat queries of at most this many blocks read them one by one; larger ones read the min/max
/// tables ([`FlatTable`]), which a hider makes only when a query needs them.
const SMALL: usize = 256;

/// A usable block's heights in render space: its box's z range, its plane's heights at its
/// corners (p, q), (p + 1, q), (p, q + 1), and how far its surface may lie from that plane
/// (residual and level error).
#[derive(Clone, Copy, Debug)]
pub(super) struct BlockZ {
    lo: f64,
    hi: f64,
    plane: [f64; 3],
    r: f64,
}

/// A height field drawn this frame: its tiles' height blocks on its grid, in index space.
pub(super) struct Hider {
    pub object: u32,
    /// Render-space (x, y) -> (column, row) of the grid: `inv * (xy - at0)`; `fwd` its inverse.
    at0: DVec2,
    inv: DMat2,
    fwd: DMat2,
    /// Block column and row boundaries in samples: block (p, q) spans columns xb[p]..xb[p + 1]
    /// and rows yb[q]..yb[q + 1].
    xb: Vec<f64>,
    yb: Vec<f64>,
    /// Per block (row-major by q, then p) its heights; None where what its tile draws is not
    /// known to cover the block (a hole in it, its tile not drawn, or drawn at a level whose
    /// error is not a bound everywhere).
    z: Vec<Option<BlockZ>>,
    /// Tile column and row boundaries in samples, and per tile (row-major) the z range of its
    /// usable blocks (empty: none): a coarse bound for quick rejections.
    txb: Vec<f64>,
    tyb: Vec<f64>,
    tile_z: Vec<(f64, f64)>,
    /// The blocks' min/max tables with heights as they are, made by the first query that needs
    /// them (one over more than [`SMALL`] blocks).
    flat: std::sync::OnceLock<FlatTable>,
}

/// A plane `z = a (x - centre.x) + b (y - centre.y)` in render space, which the proof subtracts
/// from every height (a shear: vertical lines, vertical order and vertical distances stay, rays
/// stay straight, convex hulls stay hulls).
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    a: f64,
    b: f64,
    centre: DVec2,
}

impl Plane {
    pub const FLAT: Plane = Plane { a: 0.0, b: 0.0, centre: DVec2::ZERO };

    fn at(&self, xy: DVec2) -> f64 {
        self.a * (xy.x - self.centre.x) + self.b * (xy.y - self.centre.y)
    }
    /// Height over the plane of point `p`.
    pub fn over(&self, p: DVec3) -> f64 {
        p.z - self.at(p.truncate())
    }
    /// The rate of change of [`Self::over`] along direction `d`.
    pub fn slope(&self, d: DVec3) -> f64 {
        d.z - self.a * d.x - self.b * d.y
    }
}

impl Hider {
    /// Column and row of render-space (x, y).
    pub fn index(&self, p: DVec2) -> DVec2 {
        self.inv * (p - self.at0)
    }

    /// Render-space (x, y) of column and row `c`.
    fn xy(&self, c: DVec2) -> DVec2 {
        self.at0 + self.fwd * c
    }

    /// The margin, in samples, that keeps the proof's rectangles off the grid's rim against the
    /// f32 rounding of its vertices: in world units, then through the inverse map (which
    /// stretches no length by more than its Frobenius norm).
    pub fn margin(&self) -> f64 {
        let diagonal = self.fwd * DVec2::new(self.xb[self.xb.len() - 1], self.yb[self.yb.len() - 1]);
        let world = 1e-4 * diagonal.length() + 1e-6 * self.at0.abs().max_element().max(diagonal.abs().max_element());
        world * (self.inv.x_axis.length_squared() + self.inv.y_axis.length_squared()).sqrt()
    }

    /// The range of heights over `plane` of the blocks meeting index rectangle `lo..hi`, or None
    /// when it leaves the grid shrunk by `m` samples, meets a block that is not usable, or needs
    /// more than [`MAX_BLOCKS`] reads. With heights as they are (the flat plane) the range comes
    /// from the min/max tables ([`FlatTable`]: it holds the exact one).
    pub fn range(&self, lo: DVec2, hi: DVec2, m: f64, plane: &Plane) -> Option<(f64, f64)> {
        let (xb, yb) = (&self.xb, &self.yb);
        let (tx, ty) = (xb.len() - 1, yb.len() - 1);
        if !(lo.x >= xb[0] + m && hi.x <= xb[tx] - m && lo.y >= yb[0] + m && hi.y <= yb[ty] - m) {
            return None;
        }
        let Some(ip) = self.index_plane(plane) else {
            let found = self.flat_query(lo, hi)?;
            return found.usable.filter(|_| found.all);
        };
        self.blocks_meeting(lo, hi)?.try_fold((f64::INFINITY, f64::NEG_INFINITY), |r, (p, q, z)| {
            let (a, b) = self.over(p, q, &z?, ip);
            Some((r.0.min(a), r.1.max(b)))
        })
    }

    /// The range of heights over `plane` of the usable blocks meeting `lo..hi` (clamped to the
    /// grid), None without any or when it needs more than [`MAX_BLOCKS`] reads
    /// ([`Self::too_many`]): where the proof starts from, not what it rests on.
    pub fn first_guess(&self, lo: DVec2, hi: DVec2, plane: &Plane) -> Option<(f64, f64)> {
        let Some(ip) = self.index_plane(plane) else { return self.flat_query(lo, hi)?.usable };
        let r = self
            .blocks_meeting(lo, hi)?
            .filter_map(|(p, q, z)| Some(self.over(p, q, &z?, ip)))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, (a, b)| (r.0.min(a), r.1.max(b)));
        (r.0 <= r.1).then_some(r)
    }

    /// Whether a query of index rectangle `lo..hi` over `plane` needs more than [`MAX_BLOCKS`]
    /// reads (blocks, or table entries with heights as they are).
    pub fn too_many(&self, lo: DVec2, hi: DVec2, plane: &Plane) -> bool {
        let cells = (cells_meeting(&self.xb, lo.x, hi.x), cells_meeting(&self.yb, lo.y, hi.y));
        let reads = match self.index_plane(plane) {
            None => self.flat_reads(cells),
            Some(_) => area(cells),
        };
        reads > MAX_BLOCKS
    }

    /// The grid's size in blocks.
    fn blocks(&self) -> (usize, usize) {
        (self.xb.len() - 1, self.yb.len() - 1)
    }

    /// How many reads a flat query of `cells` makes: its blocks, or the tables' entries.
    fn flat_reads(&self, cells: ((usize, usize), (usize, usize))) -> usize {
        match area(cells) {
            a if a <= SMALL => a,
            _ => FlatTable::reads(self.blocks(), cells.0, cells.1),
        }
    }

    /// The usable blocks' range with heights as they are, and whether all are usable, for the
    /// blocks meeting `lo..hi` (clamped to the grid): read block by block when they are few,
    /// from the tables otherwise (made now if no query made them yet). None when it needs more
    /// than [`MAX_BLOCKS`] reads.
    fn flat_query(&self, lo: DVec2, hi: DVec2) -> Option<Found> {
        let cells = (cells_meeting(&self.xb, lo.x, hi.x), cells_meeting(&self.yb, lo.y, hi.y));
        if self.flat_reads(cells) > MAX_BLOCKS {
            return None;
        }
        if area(cells) > SMALL {
            let (w, h) = self.blocks();
            let table = self.flat.get_or_init(|| {
                let z: Vec<_> = self.z.iter().map(|b| b.as_ref().map(flat_over)).collect();
                FlatTable::new(w, h, &z)
            });
            return Some(table.query(cells.0, cells.1));
        }
        let (mut r, mut all) = ((f64::INFINITY, f64::NEG_INFINITY), true);
        for (_, _, z) in self.blocks_meeting(lo, hi)? {
            match z {
                Some(z) => {
                    let (a, b) = flat_over(&z);
                    r = (r.0.min(a), r.1.max(b));
                }
                None => all = false,
            }
        }
        Some(Found { usable: (r.0 <= r.1).then_some(r), all })
    }

    /// The z range of the usable blocks of the tiles meeting index rectangle `lo..hi` (clamped
    /// to the grid): it holds [`Self::first_guess`]'s range with heights as they are. None
    /// without any.
    pub fn coarse(&self, lo: DVec2, hi: DVec2) -> Option<(f64, f64)> {
        let tx = self.txb.len() - 1;
        let ((i0, i1), (j0, j1)) = (cells_meeting(&self.txb, lo.x, hi.x), cells_meeting(&self.tyb, lo.y, hi.y));
        let r = (j0..=j1)
            .flat_map(|j| self.tile_z[j * tx + i0..=j * tx + i1].iter())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, t| (r.0.min(t.0), r.1.max(t.1)));
        (r.0 <= r.1).then_some(r)
    }

    /// `plane` as a function of the sample indices: its value at column c, row r is
    /// `k[0] + k[1] c + k[2] r` (the map to render space is affine); None for the flat plane.
    fn index_plane(&self, plane: &Plane) -> Option<[f64; 3]> {
        let g = DVec2::new(plane.a, plane.b);
        (g != DVec2::ZERO).then(|| [g.dot(self.at0 - plane.centre), g.dot(self.fwd.x_axis), g.dot(self.fwd.y_axis)])
    }

    /// Block (p, q)'s heights over a plane (`ip`: [`Self::index_plane`]): both of its bounds (the
    /// box's z range less the plane's extremes, its own plane less the plane at its corners,
    /// where the difference of two planes over a parallelogram peaks, widened by its residual),
    /// intersected.
    fn over(&self, p: usize, q: usize, z: &BlockZ, [k0, kc, kr]: [f64; 3]) -> (f64, f64) {
        let [z00, z10, z01] = z.plane;
        let own = [z00, z10, z01, z10 + z01 - z00];
        let (c0, c1, r0, r1) = (self.xb[p], self.xb[p + 1], self.yb[q], self.yb[q + 1]);
        let v00 = k0 + kc * c0 + kr * r0;
        let v = [v00, v00 + kc * (c1 - c0), v00 + kr * (r1 - r0), k0 + kc * c1 + kr * r1];
        let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
        for k in 0..4 {
            (lo.0, hi.0) = (lo.0.min(own[k] - v[k]), hi.0.max(own[k] - v[k]));
            (lo.1, hi.1) = (lo.1.min(v[k]), hi.1.max(v[k]));
        }
        ((lo.0 - z.r).max(z.lo - hi.1), (hi.0 + z.r).min(z.hi - lo.1))
    }

    /// The plane of the usable block under the middle of index rectangle `lo..hi` (the
    /// field's local dip, which the proof shears away), through the block's middle; None where
    /// that block is not usable or the rectangle's middle is off the grid.
    pub fn dip(&self, lo: DVec2, hi: DVec2) -> Option<Plane> {
        let (tx, ty) = (self.xb.len() - 1, self.yb.len() - 1);
        let c = (lo + hi) / 2.0;
        if !(c.x >= self.xb[0] && c.x <= self.xb[tx] && c.y >= self.yb[0] && c.y <= self.yb[ty]) {
            return None;
        }
        let (p, q) = (cells_meeting(&self.xb, c.x, c.x).0, cells_meeting(&self.yb, c.y, c.y).0);
        let z = self.z[q * tx + p]?;
        // The block's plane is linear in (column, row): its gradient there, then in (x, y).
        let (w, h) = (self.xb[p + 1] - self.xb[p], self.yb[q + 1] - self.yb[q]);
        let grad = DVec2::new((z.plane[1] - z.plane[0]) / w, (z.plane[2] - z.plane[0]) / h);
        let g = self.inv.transpose() * grad;
        let centre = self.xy(DVec2::new(self.xb[p] + w / 2.0, self.yb[q] + h / 2.0));
        g.is_finite().then_some(Plane { a: g.x, b: g.y, centre })
    }

    /// The blocks meeting index rectangle `lo..hi`, the grid's border blocks for parts beyond
    /// it, as (column, row, heights); None when they are more than [`MAX_BLOCKS`].
    #[allow(clippy::type_complexity)]
    fn blocks_meeting(
        &self,
        lo: DVec2,
        hi: DVec2,
    ) -> Option<impl Iterator<Item = (usize, usize, Option<BlockZ>)> + '_> {
        let tx = self.xb.len() - 1;
        let ((i0, i1), (j0, j1)) = (cells_meeting(&self.xb, lo.x, hi.x), cells_meeting(&self.yb, lo.y, hi.y));
        ((i1 - i0 + 1) * (j1 - j0 + 1) <= MAX_BLOCKS)
            .then(|| (j0..=j1).flat_map(move |q| (i0..=i1).map(move |p| (p, q, self.z[q * tx + p]))))
    }
}

/// A block's heights as they are: both of its bounds (its box's z range, its plane at its corners
/// widened by its residual), intersected.
fn flat_over(z: &BlockZ) -> (f64, f64) {
    let [z00, z10, z01] = z.plane;
    let own = [z00, z10, z01, z10 + z01 - z00];
    let (lo, hi) = own.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, &v| (r.0.min(v), r.1.max(v)));
    ((lo - z.r).max(z.lo), (hi + z.r).min(z.hi))
}

/// How many blocks `cells` ((i0, i1), (j0, j1), inclusive) holds.
fn area(((i0, i1), (j0, j1)): ((usize, usize), (usize, usize))) -> usize {
    (i1 - i0 + 1) * (j1 - j0 + 1)
}

/// The first and last of the cells between boundaries `b` (sorted) that meet `lo..=hi`, the
/// first (last) cell for parts before (beyond) them.
fn cells_meeting(b: &[f64], lo: f64, hi: f64) -> (usize, usize) {
    let n = b.len() - 1;
    (b[1..n].partition_point(|&v| v < lo), b[1..n].partition_point(|&v| v <= hi))
}

/// The frame's hiders: every visible height field with a usable block. `drawn(i)`: tile i is
/// drawn this frame.
pub(super) fn hiders(f: &FrameInputs<'_>, drawn: &(dyn Fn(usize) -> bool + Sync)) -> Vec<Hider> {
    let objects = f.scene.objects();
    let mut first = Vec::with_capacity(objects.len());
    objects.iter().fold(0usize, |k, o| {
        first.push(k);
        k + o.tiles.len()
    });
    // Objects in parallel, in object order.
    (0..objects.len()).into_par_iter().filter_map(|oi| hider(f, drawn, oi, first[oi])).collect()
}

/// Object `oi`'s hider (its first tile is the frame's tile `first`), None when it is no height
/// field on a tile grid or has no usable block.
fn hider(f: &FrameInputs<'_>, drawn: &(dyn Fn(usize) -> bool + Sync), oi: usize, first: usize) -> Option<Hider> {
    let g = f.geometry;
    let o = &f.scene.objects()[oi];
    let range = first..first + o.tiles.len();
    let (Some(axes), Some((tbx, tby))) = (o.grid_axes(), o.tile_sample_bounds()) else { return None };
    let (tx, ty) = (tbx.len() - 1, tby.len() - 1);
    let m = DMat2::from_cols(DVec2::from(axes.u), DVec2::from(axes.v));
    if m.determinant() == 0.0 {
        return None;
    }
    // Every tile column (row) cut into its blocks, numbered across the grid.
    let cut = |tb: &[usize]| -> (Vec<f64>, Vec<usize>) {
        let mut b = vec![0.0];
        let mut first = Vec::with_capacity(tb.len());
        for w in tb.windows(2) {
            first.push(b.len() - 1);
            b.extend(blocks::bounds(w[1] - w[0]).into_iter().skip(1).map(|c| (w[0] + c) as f64));
        }
        (b, first)
    };
    let ((xb, fx), (yb, fy)) = (cut(&tbx), cut(&tby));
    let bw = xb.len() - 1;
    let mut z = vec![None; bw * (yb.len() - 1)];
    let mut tile_z = vec![(f64::INFINITY, f64::NEG_INFINITY); tx * ty];
    let (pz, zs) = (f.placement(oi).z, f.camera.z_scale);
    let render = |v: f32| (v as f64 + pz) * zs;
    for (t, i) in o.tiles.iter().zip(range) {
        let (ix, iy) = (t.ix as usize, t.iy as usize);
        let (Some(hb), true, Some(e)) = (&g.height_blocks[i], drawn(i), f.exact_level_error(i)) else { continue };
        if (&hb.cols, &hb.rows) != (&blocks::bounds(tbx[ix + 1] - tbx[ix]), &blocks::bounds(tby[iy + 1] - tby[iy])) {
            continue;
        }
        for q in 0..hb.rows.len() - 1 {
            for p in 0..hb.columns() {
                let b = hb.block(p, q);
                let (lo, hi) = (render(b.lo[2]) - e * zs.abs(), render(b.hi[2]) + e * zs.abs());
                let usable = BlockZ {
                    lo: lo.min(hi),
                    hi: lo.max(hi),
                    plane: b.plane.map(render),
                    r: (b.residual as f64 + e) * zs.abs(),
                };
                z[(fy[iy] + q) * bw + fx[ix] + p] = b.complete.then_some(usable);
                if b.complete {
                    let t = &mut tile_z[iy * tx + ix];
                    *t = (t.0.min(usable.lo), t.1.max(usable.hi));
                }
            }
        }
    }
    if !z.iter().any(Option::is_some) {
        return None;
    }
    let at0 = DVec2::from(axes.o) + f.placement(oi).truncate();
    let as_f64 = |b: &[usize]| b.iter().map(|&v| v as f64).collect();
    let (txb, tyb) = (as_f64(&tbx), as_f64(&tby));
    let flat = std::sync::OnceLock::new();
    Some(Hider { object: oi as u32, at0, inv: m.inverse(), fwd: m, xb, yb, z, txb, tyb, tile_z, flat })
}
