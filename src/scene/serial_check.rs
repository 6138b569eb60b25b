//! What [`Scene::from_bytes`](super::Scene::from_bytes) checks of each object once its bytes are
//! read, beyond the layout: the rules its constructor applies (a height field's frame through
//! [`GridFrame::check`], colours through [`check_rgb`], coordinates within +-[`MAX_COORD`]) and
//! the consistency of its tiles with the object (a height field's samples and tile table, tile
//! boxes, packed grid coordinates, a grid's block tables), with every size that a later stage
//! allocates from bounded by the bytes first. Each check returns the message of an InputError
//! that the reader reports naming `data`.

use super::super::color::check_rgb;
use super::super::grid::GridInfo;
use super::super::heightfield::{GridAxes, GridFrame};
use super::super::{HeightfieldInfo, ObjectKind};
use crate::camera::MAX_COORD;
use crate::error::num;
use crate::lod::{tile_bounds, TileMesh};
use glam::DVec3;

/// The largest station a tube's vertex may carry: a tile spans at most this many segments.
const MAX_STATION: f32 = crate::lod::tube::SEGMENTS_PER_TILE as f32;

/// Ok, or what is wrong (the reader prefixes `data` and where).
pub(super) type Check = std::result::Result<(), String>;

/// Samples a height field may have whatever its size in bytes: horizon culling and the normal
/// map take one f32 height and one gradient per sample (64 MiB at this size).
pub(super) const MIN_SAMPLE_BOUND: usize = 1 << 22;

/// Above [`MIN_SAMPLE_BOUND`], samples per byte of the height field's object: a defined sample
/// stores 12 bytes of position and some 30 of triangles, so a grid built by `add_heightfield`
/// has more only when fewer than about 1 sample in 300 is defined.
pub(super) const SAMPLES_PER_BYTE: usize = 8;

/// A point (an origin, an offset): finite, within +-[`MAX_COORD`] as every constructor keeps them.
pub(super) fn point(p: DVec3, what: &str) -> Check {
    for (a, v) in p.to_array().into_iter().enumerate() {
        if v.is_nan() || v.abs() > MAX_COORD {
            return Err(format!("{what}[{a}] is {}; coordinates are finite, within +-{MAX_COORD:e}", num(v)));
        }
    }
    Ok(())
}

/// A colour as [`check_rgb`] takes one: (r, g, b) in [0, 1].
pub(super) fn rgb(c: [f32; 3], what: &str) -> Check {
    check_rgb(c.map(f64::from), what).map(|_| ()).map_err(|e| e.to_string())
}

/// A tile as read, placed at its object's `origin`: positions within +-[`MAX_COORD`] (beyond
/// the f32 rounding of a position made within it), its box the bounds of its positions (as every
/// builder makes it, [`TileMesh::tight_bbox`]: the box test culls by it, so a box that does not
/// hold the tile hides what it draws), its LOD errors not NaN nor negative.
pub(super) fn tile(t: &TileMesh, origin: DVec3) -> Check {
    for (k, p) in t.positions.iter().enumerate() {
        for a in 0..3 {
            let w = origin[a] + p[a] as f64;
            if w.is_nan() || w.abs() > MAX_COORD + p[a].abs() as f64 * 1e-6 {
                return Err(format!(
                    "vertex {k} lies at {} along axis {a}; coordinates must be within +-{MAX_COORD:e}",
                    num(w)
                ));
            }
        }
    }
    let (lo, hi) = t.tight_bbox();
    if t.bbox_min != lo || t.bbox_max != hi {
        return Err(format!(
            "its box {:?}..{:?} is not the bounds of its vertices {lo:?}..{hi:?}",
            t.bbox_min, t.bbox_max
        ));
    }
    let errors =
        std::iter::once(t.proxy_error).chain(t.levels.iter().flat_map(|l| [l.error, l.error_z, l.shading_error]));
    if let Some(e) = errors.into_iter().find(|e| e.is_nan() || *e < 0.0) {
        return Err(format!("an LOD error is {e}; errors are >= 0"));
    }
    if let Some(l) = t.levels.iter().find(|l| l.error_z > l.error) {
        return Err(format!("a level's vertical error {} exceeds its error {}", l.error_z, l.error));
    }
    // The lit pass draws a tube's vertex between its position and its ring's centre (`z -
    // ring_z`, TileMesh::ring_z): within the box as long as that centre is.
    if let Some((k, r)) = t
        .ring_z
        .iter()
        .zip(&t.positions)
        .enumerate()
        .find_map(|(k, (&r, p))| (!(lo[2]..=hi[2]).contains(&(p[2] - r))).then_some((k, r)))
    {
        return Err(format!("vertex {k}'s ring height {r} puts its ring's centre outside the tile's box"));
    }
    // A tube's stations index its log table (`gpu::cell_values`), built from its values.
    if !t.stations.is_empty() && t.values.is_empty() {
        return Err("its vertices carry stations but no values".into());
    }
    if let Some((k, s)) =
        t.stations.iter().enumerate().find(|(_, &s)| !(0.0..=MAX_STATION).contains(&s) || s.fract() != 0.0)
    {
        return Err(format!("vertex {k}'s station is {s}; stations are whole numbers in 0..={MAX_STATION}"));
    }
    Ok(())
}

/// An object's tiles against its kind, before anything is sized from them: [`heightfield`] and
/// [`grid`], and for every kind the packed grid coordinates ([`grid_uv`]). `bytes`: the
/// object's size in the buffer.
pub(super) fn object(kind: &ObjectKind, tiles: &[TileMesh], origin: DVec3, bytes: usize) -> Check {
    match kind {
        ObjectKind::Heightfield(_) => heightfield(kind, tiles, origin, bytes)?,
        ObjectKind::Grid(g) => return grid(g, tiles).and_then(|_| cells(g, tiles)),
        ObjectKind::Mesh { .. } => {}
    }
    grid_uv(tiles)
}

/// A grid's cell coordinates (`grid::cells`, the lit pass sizes each tile's table of cell values
/// by the largest): within its blocks and layers (or `cells::FLAT`).
fn cells(g: &GridInfo, tiles: &[TileMesh]) -> Check {
    let (nk, _, _) = g.dims;
    let (bi, bj) = g.blocks;
    for &c in tiles.iter().flat_map(|t| &t.grid_uv) {
        let [i2, j2, k2] = crate::grid::cells::unpack(c);
        if c != crate::grid::cells::FLAT && (i2 as usize > 2 * bi || j2 as usize > 2 * bj || k2 as usize >= 2 * nk) {
            return Err(format!("a grid vertex's cell coordinates {:?} lie outside its block", [i2, j2, k2]));
        }
    }
    Ok(())
}

/// A height field's grid against its tiles: its frame as `add_heightfield` checks it
/// ([`GridFrame::check`]; `x0`, `y0` are stored relative to the object's `origin`), `nx * ny`
/// samples bounded by the object's `bytes` ([`MIN_SAMPLE_BOUND`], [`SAMPLES_PER_BYTE`]: horizon
/// culling allocates per sample), `tx * ty` tiles in grid order, and every vertex a distinct
/// sample of its own tile's part of the grid (within rounding), a sample on a border between
/// tiles at one height in each tile that has it: horizon culling rebuilds the grid from the
/// frame and the vertices, so they must be the grid the tiles draw.
fn heightfield(kind: &ObjectKind, tiles: &[TileMesh], origin: DVec3, bytes: usize) -> Check {
    let ObjectKind::Heightfield(hf) = kind else { return Ok(()) };
    let HeightfieldInfo { nx, ny, x0, y0, dx, dy, rotation, tiles: (tx, ty), .. } = **hf;
    let frame =
        GridFrame { origin: [x0 + origin.x, y0 + origin.y], spacing: [dx, dy.abs()], rotation, yflip: dy < 0.0 };
    frame.check(nx, ny, (tx, ty)).map_err(|e| e.to_string())?;
    let bound = MIN_SAMPLE_BOUND.max(bytes.saturating_mul(SAMPLES_PER_BYTE));
    if nx.checked_mul(ny).is_none_or(|n| n > bound) {
        return Err(format!(
            "a height field of {ny} x {nx} samples in {bytes} bytes; at most {bound} samples \
             ({MIN_SAMPLE_BOUND}, or {SAMPLES_PER_BYTE} per byte)"
        ));
    }
    if tx.checked_mul(ty) != Some(tiles.len()) {
        return Err(format!("a height field of {tx} x {ty} tiles has {}", tiles.len()));
    }
    let (bx, by) = (tile_bounds(nx, tx), tile_bounds(ny, ty));
    let g = GridAxes::of(kind).expect("a height field");
    // Rounding: the f32 position (relative to the object's origin) and the f64 grid arithmetic.
    let world = x0.abs().max(y0.abs()) + origin.x.abs().max(origin.y.abs()) + nx as f64 * dx + ny as f64 * dy.abs();
    let slack = 1e-3 * dx.min(dy.abs()) + world * f64::EPSILON * 16.0;
    // Per vertex on its tile's border: its sample (as two u32) and its height's bits, sorted
    // afterwards so that the tiles' copies of a sample meet. Reserved whole: per tile at most its
    // vertices and its border's samples, 2 (w - 1 + h - 1) for w x h (12 bytes each, against a
    // vertex's 12 of position); a map grown sample by sample held twice that and more at its
    // peak, beyond twice the bytes of a height field of small tiles (issue 39).
    let perimeter = |t: usize| 2 * (bx[t % tx + 1] - bx[t % tx] + by[t / tx + 1] - by[t / tx]);
    let most = tiles.iter().enumerate().map(|(t, tile)| tile.positions.len().min(perimeter(t))).sum();
    let mut border: Vec<[u32; 3]> = Vec::with_capacity(most);
    for (t, tile) in tiles.iter().enumerate() {
        let (ix, iy) = (t % tx, t / tx);
        if (tile.ix as usize, tile.iy as usize) != (ix, iy) {
            return Err(format!("tile {t} is tile ({}, {}), not ({ix}, {iy}) of the grid", tile.ix, tile.iy));
        }
        let (cols, rows) = (bx[ix]..=bx[ix + 1], by[iy]..=by[iy + 1]);
        let mut samples = Vec::with_capacity(tile.positions.len());
        let on_borders = border.len() + perimeter(t);
        for (k, p) in tile.positions.iter().enumerate() {
            let (x, y) = (p[0] as f64, p[1] as f64);
            let tol = slack + x.abs().max(y.abs()) * (f32::EPSILON as f64);
            let at = g.sample_at(x, y).filter(|(i, j)| cols.contains(i) && rows.contains(j)).filter(|&(i, j)| {
                let q = g.pos(i, j);
                (q[0] - x).abs() <= tol && (q[1] - y).abs() <= tol
            });
            let Some((i, j)) = at else {
                return Err(format!(
                    "vertex {k} of tile {t} is not a sample of its part of the {ny} x {nx} grid \
                     (columns {cols:?}, rows {rows:?})"
                ));
            };
            samples.push(j * nx + i);
            let on_border = i == *cols.start() || i == *cols.end() || j == *rows.start() || j == *rows.end();
            if on_border {
                // More than its border's samples: two at one (and `border` would outgrow its
                // reservation).
                if border.len() == on_borders {
                    return Err(format!("tile {t} has two vertices at one sample of the grid"));
                }
                let s = (j * nx + i) as u64;
                border.push([(s >> 32) as u32, s as u32, p[2].to_bits()]);
            }
        }
        samples.sort_unstable();
        if samples.windows(2).any(|w| w[0] == w[1]) {
            return Err(format!("tile {t} has two vertices at one sample of the grid"));
        }
    }
    border.sort_unstable();
    if let Some(w) = border.windows(2).find(|w| w[0][..2] == w[1][..2] && w[0][2] != w[1][2]) {
        let s = ((w[0][0] as u64) << 32 | w[0][1] as u64) as usize;
        return Err(format!("tiles give sample ({}, {}) of the grid two heights", s % nx, s / nx));
    }
    Ok(())
}

/// A grid's tables against its tiles (one block each): a leaf cell size per block, finite and
/// not negative; per block the statistics of every level a tile draws (level 0 and its `levels`;
/// a block may list more, beyond `MAX_LEVELS`) counting that level's triangles, interior
/// triangles among them (a frame leaves them out of the draw); finite volumes.
fn grid(g: &GridInfo, tiles: &[TileMesh]) -> Check {
    if g.cell_size.len() != tiles.len() || g.block_levels.len() != tiles.len() {
        return Err(format!("a grid's block tables do not match its {} tiles", tiles.len()));
    }
    if let Some(c) = g.cell_size.iter().find(|c| !(c.0 >= 0.0 && c.1 >= 0.0 && c.0.is_finite() && c.1.is_finite())) {
        return Err(format!("a grid block's cell size is {c:?}; sizes are finite, >= 0"));
    }
    if g.levels.iter().chain(g.block_levels.iter().flatten()).any(|l| !l.volume.is_finite()) {
        return Err("a grid level's volume is not finite".into());
    }
    for (t, (levels, tile)) in g.block_levels.iter().zip(tiles).enumerate() {
        let drawn = std::iter::once(&tile.fine).chain(tile.levels.iter().map(|l| &l.indices));
        if levels.len() < 1 + tile.levels.len() {
            return Err(format!(
                "grid block {t} has {} levels of statistics for {} levels",
                levels.len(),
                1 + tile.levels.len()
            ));
        }
        for (h, (l, idx)) in levels.iter().zip(drawn).enumerate() {
            if l.triangles != (idx.len() / 3) as u64 || l.interior_triangles > l.triangles {
                return Err(format!(
                    "grid block {t} level {h}: {} triangles ({} interior) for {} drawn",
                    l.triangles,
                    l.interior_triangles,
                    idx.len() / 3
                ));
            }
        }
    }
    Ok(())
}

/// Packed grid coordinates (`TileMesh::grid_uv`: column | row << 16) of a structured mesh: the
/// lit pass's normal grid (`Object::grid_normals`) is sized by the largest column and row, so
/// that grid must not be much larger than the vertices that fill it (every sample of a
/// structured grid is a vertex of some tile).
fn grid_uv(tiles: &[TileMesh]) -> Check {
    let n: u64 = tiles.iter().map(|t| t.grid_uv.len() as u64).sum();
    let (mut nu, mut nv) = (0u64, 0u64);
    for &k in tiles.iter().flat_map(|t| &t.grid_uv) {
        nu = nu.max((k & 0xffff) as u64 + 1);
        nv = nv.max((k >> 16) as u64 + 1);
    }
    if nu * nv > 2 * n + 64 {
        return Err(format!("grid coordinates reach column {} and row {} for only {n} vertices", nu - 1, nv - 1));
    }
    Ok(())
}

#[cfg(test)]
#[path = "serial_check_tests.rs"]
mod tests;
