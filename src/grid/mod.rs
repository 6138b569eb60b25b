//! Reservoir grids (Jia et al., seed 003): corner-point grids cut into blocks of columns, each
//! block a tile with levels of detail by cell merging.
//!
//! A [`CornerGrid`] is nk x nj x ni hexahedral cells given by their 8 corners (faulted: the
//! columns on either side of a fault do not share corners; truncated: pinch-outs and erosion
//! collapse corners). [`build_grid`] draws the boundary of the active cells of each region
//! (level 0, [`faces`]: interior faces are never built, faces on faults are split so that every
//! region's surface is watertight) and merges cells over a quadtree of each block's columns into
//! coarser levels ([`merge`]); [`distance_level`] picks a block's level from the eye distance with
//! the paper's ranges.
//!
//! Conventions: corner c of a cell has i-bit `c & 1`, j-bit `(c >> 1) & 1`, k-bit `(c >> 2) & 1`
//! (k-bit 0 = the cell's top), k = 0 the top layer. Which way is up, and whether (i, j, up) is a
//! right- or left-handed frame, is read off the corners (the sums over the active cells), so z up
//! or z down and either handedness give outward normals.

pub mod cells;
pub(crate) mod faces;
pub(crate) mod merge;
pub(crate) mod poly;
#[cfg(test)]
mod tests;

use crate::error::{ensure, input_err, num, Progress, Result};
use crate::lod::{levels::Level, TileMesh};
use faces::{Block, Level0};
use glam::DVec3;
use rayon::prelude::*;
#[cfg(test)]
use std::sync::atomic::AtomicBool;
use std::sync::atomic::Ordering;

/// A corner-point grid: nk x nj x ni cells (k = 0 the top), 8 corners each.
pub struct CornerGrid<'a> {
    pub nk: usize,
    pub nj: usize,
    pub ni: usize,
    /// (nk, nj, ni, 8, 3) world coordinates, C order; corner c of a cell has i-bit c&1,
    /// j-bit (c>>1)&1, k-bit (c>>2)&1 (k-bit 0 = the top of the cell).
    pub corners: &'a [f64],
    /// (nk, nj, ni) or None = all active.
    pub active: Option<&'a [bool]>,
    /// (nk, nj, ni) region ids or None = one region.
    pub region: Option<&'a [i32]>,
    /// (nk, nj, ni) cell property or None; NaN allowed (no data).
    pub values: Option<&'a [f64]>,
}

/// The tiles of a grid and its levels' statistics.
pub struct GridBuild {
    /// One tile per block, row-major over blocks (index by * bx + bi), `ix`/`iy` the block's
    /// (i, j) index; positions f32 relative to `origin`; `values` one per position when the grid
    /// has values (each face's vertices carry their cell's value, a merged face the mean of its
    /// cells' values, so colour is flat per cell), else empty; `fine` = level 0 (every drawn face,
    /// triangulated); `levels` = merged levels 1.. with their geometric error in world units
    /// (index lists into the same `positions`); `coarse` = the block's coarsest merged level (the
    /// proxy for occlusion culling) with `proxy_error`; bbox of the positions.
    pub tiles: Vec<TileMesh>,
    /// Per level 0..=max: cells, faces (polygons before triangulation), triangles, vertices,
    /// volume (m^3, of the active cells' union as the level represents it) over the whole grid.
    /// A block with fewer levels counts with its coarsest one.
    pub levels: Vec<LevelStats>,
    /// Mean leaf cell size (L = mean edge length along i, W = along j, world units, over the
    /// block's drawn cells; (0, 0) for a block without any) of each block.
    pub cell_size: Vec<(f64, f64)>,
    /// Per block (tile order), per level 0..: the block's own counts (as `levels`; a block stops
    /// at its coarsest level).
    pub block_levels: Vec<Vec<LevelStats>>,
    /// Per level 0..=max over the whole grid (a block with fewer levels counts with its coarsest
    /// one): faces and triangles by what lies across them (diagnostics the tests read).
    #[cfg_attr(not(test), allow(dead_code))]
    pub kinds: Vec<KindCounts>,
}

/// One level's counts over the whole grid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LevelStats {
    /// Merged cells (node x layer) holding at least one drawn cell; level 0: the drawn cells
    /// (active, not collapsed).
    pub cells: u64,
    pub faces: u64,
    pub triangles: u64,
    /// Distinct vertices of the level's triangles (a vertex per cell value: flat colours).
    pub vertices: u64,
    /// The volume the level's surface encloses (divergence theorem over every region's closed
    /// surface, summed), m^3.
    pub volume: f64,
    /// The last triangles of the level's index list that cannot be seen from outside the grid's
    /// cells (`faces::kind::interior`): faces between regions and of cavities.
    pub interior_triangles: u64,
}

/// Faces and triangles of one level by what lies across them (`faces::kind`, index = kind).
pub type KindCounts = [[u64; faces::kind::NAMES.len()]; 2];

/// What the face builders need of the grid.
pub(crate) struct Ctx<'g> {
    pub g: &'g CornerGrid<'g>,
    /// +1 when the cells' tops have the larger z, else -1; heights along pillars are `up * z`.
    pub up: f64,
    /// (i, j, up) is left-handed: every outline is reversed.
    pub flip: bool,
    pub origin: DVec3,
    /// The grid is coloured by cell values: faces carry cell coordinates ([`cells`]) and merge
    /// only where those stay exact.
    pub cells: bool,
}

impl Ctx<'_> {
    #[inline]
    pub fn cell(&self, k: usize, j: usize, i: usize) -> usize {
        (k * self.g.nj + j) * self.g.ni + i
    }
    #[inline]
    pub fn corner(&self, cell: usize, c: usize) -> [f64; 3] {
        let o = cell * 24 + c * 3;
        let q = &self.g.corners[o..o + 3];
        [q[0], q[1], q[2]]
    }
    #[inline]
    pub fn s(&self, p: [f64; 3]) -> f64 {
        self.up * p[2]
    }
    #[inline]
    pub fn active(&self, cell: usize) -> bool {
        self.g.active.is_none_or(|a| a[cell])
    }
    #[inline]
    pub fn region(&self, cell: usize) -> i32 {
        self.g.region.map_or(0, |r| r[cell])
    }
    #[inline]
    pub fn value(&self, cell: usize) -> f64 {
        self.g.values.map_or(f64::NAN, |v| v[cell])
    }
    /// Zero volume: each top corner equals the bottom corner below it.
    #[inline]
    pub fn collapsed(&self, cell: usize) -> bool {
        (0..4).all(|c| self.corner(cell, c) == self.corner(cell, c + 4))
    }
    /// Drawn: active and not collapsed.
    #[inline]
    pub fn present(&self, cell: usize) -> bool {
        self.active(cell) && !self.collapsed(cell)
    }
    /// An inactive cell (not collapsed) enclosed by present cells: its four neighbours in the
    /// layer and the next cells above and below that are not collapsed are present (of any
    /// regions) and share its corners (`faces::kind::CAVITY`).
    pub fn enclosed(&self, cell: usize) -> bool {
        if self.present(cell) || self.collapsed(cell) {
            return false;
        }
        let g = self.g;
        let (i, j, k) = (cell % g.ni, (cell / g.ni) % g.nj, cell / (g.ni * g.nj));
        // (neighbour, its corners, this cell's corners that must equal them)
        let mut nbs: Vec<(usize, [usize; 4], [usize; 4])> = Vec::with_capacity(6);
        let lateral = [
            (i > 0, [1, 3, 5, 7], [0, 2, 4, 6], -1isize, 0isize),
            (i + 1 < g.ni, [0, 2, 4, 6], [1, 3, 5, 7], 1, 0),
            (j > 0, [2, 3, 6, 7], [0, 1, 4, 5], 0, -1),
            (j + 1 < g.nj, [0, 1, 4, 5], [2, 3, 6, 7], 0, 1),
        ];
        for (ok, theirs, mine, di, dj) in lateral {
            if !ok {
                return false;
            }
            let c = self.cell(k, (j as isize + dj) as usize, (i as isize + di) as usize);
            nbs.push((c, theirs, mine));
        }
        // The next cells above and below that are not collapsed.
        let above = (0..k).rev().map(|kk| self.cell(kk, j, i)).find(|&c| !self.collapsed(c));
        let below = (k + 1..g.nk).map(|kk| self.cell(kk, j, i)).find(|&c| !self.collapsed(c));
        match (above, below) {
            (Some(a), Some(b)) => {
                nbs.push((a, [4, 5, 6, 7], [0, 1, 2, 3]));
                nbs.push((b, [0, 1, 2, 3], [4, 5, 6, 7]));
            }
            _ => return false,
        }
        nbs.iter().all(|&(c, theirs, mine)| {
            self.present(c) && (0..4).all(|x| self.corner(c, theirs[x]) == self.corner(cell, mine[x]))
        })
    }

    /// Mean height of the cell along its four pillars.
    pub fn thickness(&self, cell: usize) -> f64 {
        (0..4).map(|c| self.s(self.corner(cell, c)) - self.s(self.corner(cell, c + 4))).sum::<f64>() / 4.0
    }
}

fn mean_edges(ctx: &Ctx, cell: usize, pairs: [(usize, usize); 4]) -> f64 {
    pairs
        .iter()
        .map(|&(a, b)| (DVec3::from_array(ctx.corner(cell, a)) - DVec3::from_array(ctx.corner(cell, b))).length())
        .sum::<f64>()
        / 4.0
}

/// Checks the arrays (lengths, finite corners of active cells, values finite or NaN).
fn validate(g: &CornerGrid, origin: DVec3, blocks: (usize, usize)) -> Result<usize> {
    let n = g.nk.checked_mul(g.nj).and_then(|v| v.checked_mul(g.ni));
    let n = n.ok_or_else(|| input_err("corners", "the grid's size overflows"))?;
    ensure(n > 0, "corners", || format!("the grid has no cells ({} x {} x {})", g.nk, g.nj, g.ni))?;
    ensure(n.checked_mul(24) == Some(g.corners.len()), "corners", || {
        format!("has {} values, expected nk * nj * ni * 8 * 3 = {} x {} x {} x 24", g.corners.len(), g.nk, g.nj, g.ni)
    })?;
    for (name, len) in [
        ("active", g.active.map(|a| a.len())),
        ("region", g.region.map(|a| a.len())),
        ("values", g.values.map(|a| a.len())),
    ] {
        if let Some(len) = len {
            ensure(len == n, name, || format!("has {len} values, expected nk * nj * ni = {n}"))?;
        }
    }
    ensure(blocks.0 >= 1 && blocks.1 >= 1, "blocks", || {
        format!("({}, {}): cells per block along i and j must be at least 1", blocks.0, blocks.1)
    })?;
    let o = origin.to_array();
    for cell in 0..n {
        if !g.active.is_none_or(|a| a[cell]) {
            continue;
        }
        let c = &g.corners[cell * 24..cell * 24 + 24];
        if let Some(x) = c.iter().enumerate().position(|(x, v)| !v.is_finite() || (v - o[x % 3]).abs() > 1e30) {
            let (i, j, k) = (cell % g.ni, (cell / g.ni) % g.nj, cell / (g.ni * g.nj));
            let v = c[x];
            let why = if v.is_finite() { "is too far from the scene origin" } else { "is not finite" };
            return Err(input_err(
                "corners",
                format!(
                    "corners[{k}, {j}, {i}, {}, {}] = {} {why} (cell ({k}, {j}, {i}) is active)",
                    x / 3,
                    x % 3,
                    num(v)
                ),
            ));
        }
    }
    if let Some(v) = g.values {
        if let Some(cell) = v.iter().position(|x| x.is_infinite()) {
            let (i, j, k) = (cell % g.ni, (cell / g.ni) % g.nj, cell / (g.ni * g.nj));
            return Err(input_err(
                "values",
                format!("values[{k}, {j}, {i}] = {}: must be finite or NaN", num(v[cell])),
            ));
        }
    }
    Ok(n)
}

/// Validates (Error::Input naming `corners` / `active` / `region` / `values` / `blocks` and the
/// first bad cell as corners[k, j, i, c, a]: non-finite corners of ACTIVE cells are errors;
/// inactive cells may hold anything, including NaN) and builds. `blocks = (bi, bj)` cells per
/// block along i and j (each >= 1). Works block by block in parallel (rayon); polls `stop`
/// between blocks (blocks not started once it is set are left empty; the caller discards the
/// result). Never panics on any input of the right length.
pub fn build_grid(g: &CornerGrid, origin: DVec3, blocks: (usize, usize), stop: &impl Progress) -> Result<GridBuild> {
    let n = validate(g, origin, blocks)?;
    // Up and handedness from the active cells' mean axes.
    let probe = Ctx { g, up: 1.0, flip: false, origin, cells: false };
    let (sum_up, sum_hand) = (0..n)
        .into_par_iter()
        .filter(|&c| probe.active(c))
        .map(|c| {
            let p = |x: usize| DVec3::from_array(probe.corner(c, x));
            let ei = (p(1) + p(3) + p(5) + p(7)) - (p(0) + p(2) + p(4) + p(6));
            let ej = (p(2) + p(3) + p(6) + p(7)) - (p(0) + p(1) + p(4) + p(5));
            let ek = (p(0) + p(1) + p(2) + p(3)) - (p(4) + p(5) + p(6) + p(7));
            (ek.z, ei.cross(ej).dot(ek))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let cells = g.values.is_some() && g.nk <= cells::MAX_LAYERS && blocks.0.max(blocks.1) <= cells::MAX_BLOCK;
    let ctx = Ctx { g, up: if sum_up < 0.0 { -1.0 } else { 1.0 }, flip: sum_hand < 0.0, origin, cells };
    let (bi, bj) = blocks;
    let (nbx, nby) = (g.ni.div_ceil(bi), g.nj.div_ceil(bj));
    let out: Vec<BlockOut> = (0..nbx * nby)
        .into_par_iter()
        .map(|t| {
            let (bx, by) = (t % nbx, t / nbx);
            if stop.stop_flag().load(Ordering::Relaxed) {
                return (
                    TileMesh { ix: bx as u32, iy: by as u32, ..Default::default() },
                    Vec::new(),
                    (0.0, 0.0),
                    Vec::new(),
                );
            }
            let b = Block { i0: bx * bi, i1: ((bx + 1) * bi).min(g.ni), j0: by * bj, j1: ((by + 1) * bj).min(g.nj) };
            let out = build_block(&ctx, b, (bx, by));
            stop.item_done();
            out
        })
        .collect();
    let nlev = out.iter().map(|o| o.1.len()).max().unwrap_or(0);
    let mut levels = vec![LevelStats::default(); nlev];
    let mut kinds = vec![KindCounts::default(); nlev];
    for (_, st, _, kc) in &out {
        if st.is_empty() {
            continue;
        }
        for (h, k) in kinds.iter_mut().enumerate() {
            let s = &kc[h.min(kc.len() - 1)];
            for (a, b) in k.iter_mut().flatten().zip(s.iter().flatten()) {
                *a += b;
            }
        }
        for (h, l) in levels.iter_mut().enumerate() {
            let s = &st[h.min(st.len() - 1)];
            l.cells += s.cells;
            l.faces += s.faces;
            l.triangles += s.triangles;
            l.vertices += s.vertices;
            l.volume += s.volume;
            l.interior_triangles += s.interior_triangles;
        }
    }
    let cell_size = out.iter().map(|o| o.2).collect();
    let block_levels = out.iter().map(|o| o.1.clone()).collect();
    let tiles = out.into_iter().map(|o| o.0).collect();
    Ok(GridBuild { tiles, levels, cell_size, block_levels, kinds })
}

/// Number of merged levels a block of w x h columns allows: until one node covers the block.
fn block_levels(w: usize, h: usize) -> u32 {
    let m = w.max(h).max(1);
    usize::BITS - (m - 1).leading_zeros()
}

type BlockOut = (TileMesh, Vec<LevelStats>, (f64, f64), Vec<KindCounts>);

fn kind_counts(lev: &merge::LevelFaces) -> KindCounts {
    let mut k = KindCounts::default();
    for f in &lev.faces {
        k[0][f.kind as usize] += 1;
        k[1][f.kind as usize] += f.tris.len() as u64;
    }
    k
}

fn build_block(ctx: &Ctx, b: Block, (bx, by): (usize, usize)) -> BlockOut {
    let g = ctx.g;
    let (bw, bh) = (b.i1 - b.i0, b.j1 - b.j0);
    // Drawn cells per column and layer, and the mean cell size.
    let mut present = vec![false; bw * bh * g.nk];
    let (mut sl, mut sw, mut nc) = (0.0, 0.0, 0usize);
    for j in b.j0..b.j1 {
        for i in b.i0..b.i1 {
            for k in 0..g.nk {
                let c = ctx.cell(k, j, i);
                if ctx.present(c) {
                    present[((j - b.j0) * bw + (i - b.i0)) * g.nk + k] = true;
                    sl += mean_edges(ctx, c, [(0, 1), (2, 3), (4, 5), (6, 7)]);
                    sw += mean_edges(ctx, c, [(0, 2), (1, 3), (4, 6), (5, 7)]);
                    nc += 1;
                }
            }
        }
    }
    let cell_size = if nc > 0 { (sl / nc as f64, sw / nc as f64) } else { (0.0, 0.0) };
    let mut l0 = Level0::new(ctx, b);
    l0.build();
    let Level0 { mut verts, mut faces, .. } = l0;
    if ctx.cells {
        // Each face's vertices' cell coordinates (`Face::lat`), for colouring per cell.
        for f in &mut faces {
            f.lat = cells::level0(f, &verts, (b.i0 as u32, b.j0 as u32), g.ni);
        }
    }
    let mut tile = TileMesh { ix: bx as u32, iy: by as u32, ..Default::default() };
    let has_values = g.values.is_some();
    // A vertex per position, value and cell coordinates.
    let mut out_map: poly::FastMap<(u32, u64, u32), u32> = poly::FastMap::default();
    let mut stats = Vec::new();
    let mut kinds = Vec::new();
    let mut seen: Vec<u32> = Vec::new();
    let mut emit =
        |lev: &merge::LevelFaces, verts: &Verts0, tile: &mut TileMesh, stamp: u32| -> (Vec<u32>, LevelStats) {
            let mut idx = Vec::new();
            let mut st = LevelStats { faces: lev.faces.len() as u64, ..Default::default() };
            let o = ctx.origin;
            // Faces seen from outside first, then the interior ones (`faces::kind::interior`).
            let inner: Vec<bool> = lev.faces.iter().map(|f| faces::kind::interior(f.kind)).collect();
            let order = (0..lev.faces.len()).filter(|&f| !inner[f]).chain((0..lev.faces.len()).filter(|&f| inner[f]));
            for f in order {
                let f = &lev.faces[f];
                let vb = if has_values { f.value.to_bits() } else { 0 };
                for t in &f.tris {
                    let p = t.map(|v| DVec3::from_array(verts.pos[v as usize]) - o);
                    st.volume += p[0].dot(p[1].cross(p[2])) / 6.0;
                    for &v in t {
                        let next = tile.positions.len() as u32;
                        let lat = if ctx.cells { cells::of(f, v).unwrap_or(0) } else { 0 };
                        let e = *out_map.entry((v, vb, lat)).or_insert(next);
                        if e == next {
                            tile.positions.push(verts.rel[v as usize]);
                            if has_values {
                                tile.values.push(f.value as f32);
                            }
                            if ctx.cells {
                                tile.grid_uv.push(lat);
                            }
                            seen.push(0);
                        }
                        if seen[e as usize] != stamp {
                            seen[e as usize] = stamp;
                            st.vertices += 1;
                        }
                        idx.push(e);
                    }
                }
            }
            st.triangles = (idx.len() / 3) as u64;
            st.interior_triangles =
                lev.faces.iter().zip(&inner).filter(|(_, &i)| i).map(|(f, _)| f.tris.len() as u64).sum();
            (idx, st)
        };
    type Verts0 = poly::Verts;
    let mut lev = merge::level0(faces, b);
    let (fine, mut st) = emit(&lev, &verts, &mut tile, 1);
    st.cells = present.iter().filter(|&&p| p).count() as u64;
    tile.fine = fine.into();
    stats.push(st);
    kinds.push(kind_counts(&lev));
    let mut levels = Vec::new();
    for h in 1..=block_levels(bw, bh) {
        lev = merge::next_level(&lev, h, b, (g.ni, g.nj), ctx.cells, &mut verts);
        let (idx, mut st) = emit(&lev, &verts, &mut tile, h + 1);
        let s = 1usize << h;
        let (nw, nh) = (bw.div_ceil(s), bh.div_ceil(s));
        for nj in 0..nh {
            for ni in 0..nw {
                for k in 0..g.nk {
                    let any = (nj * s..((nj + 1) * s).min(bh))
                        .any(|j| (ni * s..((ni + 1) * s).min(bw)).any(|i| present[(j * bw + i) * g.nk + k]));
                    st.cells += any as u64;
                }
            }
        }
        stats.push(st);
        kinds.push(kind_counts(&lev));
        let error = lev.error as f32;
        levels.push(Level {
            indices: idx.into(),
            error,
            error_z: error,
            shading_error: lev.shading as f32,
            grouped: Vec::new(),
            grouped_error: error,
        });
    }
    tile.levels = levels.into();
    match tile.levels.last() {
        Some(l) => {
            tile.coarse = l.indices.clone();
            tile.proxy_error = l.error;
        }
        None => tile.coarse = tile.fine.clone(),
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &tile.positions {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if tile.positions.is_empty() {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    (tile.bbox_min, tile.bbox_max) = (lo, hi);
    (tile, stats, cell_size, kinds)
}

/// `alpha` in [8, 15] and `lam` in [2, 3], the paper's ranges.
pub fn validate_alpha_lambda(alpha: f64, lambda: f64) -> Result<()> {
    ensure((8.0..=15.0).contains(&alpha), "alpha", || format!("{} is outside [8, 15]", num(alpha)))?;
    ensure((2.0..=3.0).contains(&lambda), "lam", || format!("{} is outside [2, 3]", num(lambda)))
}

/// The level of a block at distance `d` from the eye (to the block's centre), from the paper's
/// view-distance ranges (Jia et al.): with L, W = `cell` (the block's mean leaf cell size),
/// S(h) = alpha 2^h max(L, W) and r(h) = lambda 2^h sqrt(L^2 + W^2) / 2, the leaves are shown for
/// d in [0, S(0)] and a node of height h for d in [S(h) - r(h), S(h)].
///
/// Those ranges never overlap and leave gaps: for alpha >= 8 and lambda <= 3,
/// S(h) - r(h) - S(h - 1) = 2^(h-1) (alpha max(L, W) - lambda sqrt(L^2 + W^2)) > 0. The rule here
/// keeps every range exactly and fills each gap with the finer of its two neighbours (never less
/// detail than the paper asks for): the level is the largest h in 1..=max_level with
/// d >= S(h) - r(h), else 0. So height h is used for d in [S(h) - r(h), S(h+1) - r(h+1)), which
/// contains [S(h) - r(h), S(h)]; the result is monotone (non-decreasing) in d and capped at
/// `max_level`. A NaN distance gives 0.
pub fn distance_level(d: f64, cell: (f64, f64), alpha: f64, lambda: f64, max_level: usize) -> usize {
    let (l, w) = cell;
    let start = |h: usize| {
        let p = (1u64 << h.min(62)) as f64;
        alpha * p * l.max(w) - lambda * p * (l * l + w * w).sqrt() / 2.0
    };
    let mut level = 0;
    for h in 1..=max_level.min(62) {
        if d >= start(h) {
            level = h;
        } else {
            break;
        }
    }
    level
}
