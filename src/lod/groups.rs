//! Neighbouring lattice tiles at one level share their sides at that level's stride: the border
//! of a coarse level without its full-resolution cost.
//!
//! Every level keeps its tile's border at full resolution ([`super::levels`]), so that neighbours at
//! any levels meet without cracks. At the coarse levels that border is most of the triangles (a
//! tile of 42 × 42 samples at stride 8: 18 triangles inside, about 230 on the border), and a scene
//! of finer samples in tiles of the same size draws ever more of them: the border, not the
//! surface, is what a distant frame pays for.
//!
//! Where two neighbouring tiles of one height field are drawn at the same level, the side they
//! share can be drawn at that level's stride by both: the same samples, so still no crack. Each
//! level from 3 on of a hole-free tile therefore has, besides its full-border triangles, one
//! variant per side mask (`Level::grouped`, entry mask - 1, [`masks`], [`variants`]): the sides of
//! the mask at the level's stride, the others at full resolution. Sides on the object's outline
//! stay at full resolution in every variant ([`open_sides`]; its silhouette then does not move
//! with the level). Each frame, [`stitch`] gives every drawn tile the mask of its sides shared
//! with a neighbour at the same level where both may draw it so (`render::groups`): a side is
//! coarse on both of its tiles or on neither, and [`super::lattice::cell_triangles`] draws each
//! side as its bit says along its whole length, so the two tiles draw the same edges there
//! whatever their other sides are.
//!
//! Error: a variant's triangles are, cell by cell, the level's own (inner cells; border cells with
//! their border sides at full resolution, fanned as the level fans them), a border cell's two
//! diagonal triangles where all its border sides are coarse, or, in a cell on two or more of the
//! tile's sides with one of them coarse, the fan triangle from its centre to that side's corners.
//! So every variant lies within the larger of the level's error and [`BorderErrors::coarse`]
//! (those diagonal pairs and corner triangles) of the fine surface: `Level::grouped_error`, for
//! every mask.

use super::lattice::{cell_triangles, lattice_error, square_cell_error};
use super::Indices;

/// Variants per level: one per non-empty side mask (`Level::grouped`, entry mask - 1).
pub const VARIANTS: usize = 15;

/// Bits of a tile's sides in a side mask (local sample space: row 0 is the bottom, column 0 the left).
pub const BOTTOM: u8 = 1;
pub const RIGHT: u8 = 2;
pub const TOP: u8 = 4;
pub const LEFT: u8 = 8;

/// The sides of tile (`ix`, `iy`) of a height field of `tx` × `ty` tiles that it shares with a
/// neighbouring tile: the others lie on the object's outline.
pub fn open_sides(ix: usize, iy: usize, tx: usize, ty: usize) -> u8 {
    [(BOTTOM, iy > 0), (RIGHT, ix + 1 < tx), (TOP, iy + 1 < ty), (LEFT, ix > 0)]
        .into_iter()
        .filter(|&(_, open)| open)
        .fold(0, |m, (side, _)| m | side)
}

/// The tile across `side` (one bit) of tile (`ix`, `iy`), which must be open ([`open_sides`]).
fn across(ix: usize, iy: usize, side: u8) -> (usize, usize) {
    match side {
        BOTTOM => (ix, iy - 1),
        RIGHT => (ix + 1, iy),
        TOP => (ix, iy + 1),
        _ => (ix - 1, iy),
    }
}

/// The side masks of a level's variants (`Level::grouped`) for a tile whose `open` sides
/// ([`open_sides`]) have neighbours: entry mask - 1 for mask 1..=[`VARIANTS`], with the outline's
/// sides taken out (those entries then repeat one of the others or the level's own, and share its
/// list). Empty for a tile without neighbours (it has no variants).
pub fn masks(open: u8) -> Vec<u8> {
    if open == 0 {
        return Vec::new();
    }
    (1..=VARIANTS as u8).map(|m| m & open).collect()
}

/// This frame's side masks of the tiles of one height field of `tx` × `ty` tiles: `level[iy * tx +
/// ix]` is tile (ix, iy)'s level where it may draw a variant of it (a lattice tile drawn at a level
/// that has variants, within the frame's error budget with its group error), None otherwise. A
/// side is in a tile's mask where the tile across it has the same level: so a side is in the masks
/// of both of its tiles or of neither (no crack), and the outline never is.
pub fn stitch(tx: usize, ty: usize, level: &[Option<u8>]) -> Vec<u8> {
    assert_eq!(level.len(), tx * ty, "one entry per tile");
    let at = |ix: usize, iy: usize| level[iy * tx + ix];
    let mut out = vec![0u8; tx * ty];
    for iy in 0..ty {
        for ix in 0..tx {
            let Some(l) = at(ix, iy) else { continue };
            let open = open_sides(ix, iy, tx, ty);
            out[iy * tx + ix] = [BOTTOM, RIGHT, TOP, LEFT]
                .into_iter()
                .filter(|&side| {
                    open & side != 0 && {
                        let (x, y) = across(ix, iy, side);
                        at(x, y) == Some(l)
                    }
                })
                .fold(0, |m, side| m | side);
        }
    }
    out
}

/// The triangle lists (into `vid`'s vertices) of the lattice `xs` × `ys` (local sample positions
/// of a tile of `size` samples) with the sides of each mask of `masks` at the lattice's stride
/// ([`cell_triangles`]), one per mask; equal masks share one list.
pub fn variants(
    xs: &[usize],
    ys: &[usize],
    size: (usize, usize),
    masks: &[u8],
    vid: &impl Fn(usize, usize) -> u32,
) -> Vec<Indices> {
    let mut made: Vec<(u8, Indices)> = Vec::new();
    let mut tris = Vec::new();
    masks
        .iter()
        .map(|&m| {
            if let Some((_, l)) = made.iter().find(|(k, _)| *k == m) {
                return l.clone();
            }
            tris.clear();
            for jj in ys.windows(2) {
                for ii in xs.windows(2) {
                    cell_triangles((ii[0], jj[0]), (ii[1], jj[1]), size, m, &mut tris);
                }
            }
            let l: Indices = tris.iter().flat_map(|t| t.iter().map(|&(i, j)| vid(i, j))).collect();
            made.push((m, l.clone()));
            l
        })
        .collect()
}

/// What [`border_errors`] measures of a level's cells on the tile's border.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BorderErrors {
    /// The largest vertical distance between the fine surface and the triangles that a variant
    /// may put in a cell beyond the level's own: the two diagonal triangles of each cell touching
    /// the tile's border (a border cell whose border sides are all coarse), and in a cell on two
    /// or more of the tile's sides (a corner, or across the whole tile), the triangles from its
    /// centre sample to the corners of each of its border sides (a coarse one beside a full one);
    /// any other cell draws the level's own triangles ([`cell_triangles`]).
    pub coarse: f64,
    /// With `fans`: an upper bound on the vertical distance between the fine surface and the
    /// level's own triangles in those cells (fans to the border samples): per cell, the distance
    /// between the fine surface and the cell's two diagonal triangles plus the largest between
    /// those and the fan. Both are linear on each piece of their overlay, whose corners are the
    /// fan's vertices and the points where its edges cross the diagonal; so that part is largest
    /// at one of them, a few dozen points a cell instead of every fine sample and crossing.
    pub fans: Option<f64>,
}

/// [`BorderErrors`] of the cells of the lattice `xs` × `ys` (of a tile of `size` samples, heights
/// `z`) that touch the tile's border, the bound on their fans only with `fans`.
pub fn border_errors(
    xs: &[usize],
    ys: &[usize],
    size: (usize, usize),
    z: &impl Fn(usize, usize) -> f64,
    fans: bool,
) -> BorderErrors {
    let (mut across, mut split, mut fan) = (Vec::new(), Vec::new(), Vec::new());
    let (mut coarse, mut bound) = (0.0f64, 0.0f64);
    for jj in ys.windows(2) {
        for ii in xs.windows(2) {
            let ((a, b), (a1, b1)) = ((ii[0], jj[0]), (ii[1], jj[1]));
            let on = [b == 0, a1 == size.0 - 1, b1 == size.1 - 1, a == 0];
            if !on.iter().any(|&o| o) {
                continue;
            }
            if on.iter().filter(|&&o| o).count() >= 2 {
                // A cell on two sides of the tile, one coarse and one full, fans from its centre
                // to the coarse side's two corners (the centre's edges to them are the level's
                // own, its fan's).
                let c = (a + (a1 - a) / 2, b + (b1 - b) / 2);
                let ring = [(a, b), (a1, b), (a1, b1), (a, b1)];
                across.extend((0..4).filter(|&s| on[s]).map(|s| [c, ring[s], ring[(s + 1) % 4]]));
            }
            let e_split = if a1 - a == b1 - b {
                square_cell_error((a, b), a1 - a, z)
            } else {
                split.clear();
                cell_triangles((a, b), (a1, b1), size, BOTTOM | RIGHT | TOP | LEFT, &mut split);
                lattice_error(&split, z)
            };
            coarse = coarse.max(e_split);
            if fans {
                fan.clear();
                cell_triangles((a, b), (a1, b1), size, 0, &mut fan);
                bound = bound.max(e_split + fan_to_split((a, b), (a1, b1), &fan, z));
            }
        }
    }
    if !across.is_empty() {
        coarse = coarse.max(lattice_error(&across, z));
    }
    BorderErrors { coarse, fans: fans.then_some(bound) }
}

/// The largest vertical distance between the triangles `fan` of the lattice cell `lo..hi` and the
/// cell's two diagonal triangles (split from `lo` to `hi`), at the fan's vertices and where its
/// edges cross the diagonal ([`BorderErrors::fans`]).
fn fan_to_split(
    (a, b): (usize, usize),
    (a1, b1): (usize, usize),
    fan: &[[(usize, usize); 3]],
    z: &impl Fn(usize, usize) -> f64,
) -> f64 {
    // The two diagonal triangles at (u, v) in 0..=1 across the cell.
    let (z00, z10, z11, z01) = (z(a, b), z(a1, b), z(a1, b1), z(a, b1));
    let at = |u: f64, v: f64| {
        if u >= v {
            z00 + u * (z10 - z00) + v * (z11 - z10)
        } else {
            z00 + u * (z11 - z01) + v * (z01 - z00)
        }
    };
    let uv = |p: (usize, usize)| ((p.0 - a) as f64 / (a1 - a) as f64, (p.1 - b) as f64 / (b1 - b) as f64);
    let mut d = 0.0f64;
    for t in fan {
        for e in 0..3 {
            let (p, q) = (t[e], t[(e + 1) % 3]);
            let ((up, vp), (uq, vq)) = (uv(p), uv(q));
            let (zp, zq) = (z(p.0, p.1), z(q.0, q.1));
            d = d.max((zp - at(up, vp)).abs());
            let (fp, fq) = (up - vp, uq - vq);
            if fp * fq < 0.0 {
                let s = fp / (fp - fq);
                let (u, v) = (up + s * (uq - up), vp + s * (vq - vp));
                d = d.max((zp + s * (zq - zp) - at(u, v)).abs());
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::levels::tests::distance_sampled;
    use crate::lod::levels::{lattice_levels, Level};
    use crate::lod::tile_bounds;
    use std::collections::HashMap;

    /// A height field of `n` × `n` samples cut into `t` × `t` tiles, its levels with their
    /// variants, the vertices being the samples' global indices.
    fn tiled(n: usize, t: usize, z: &[f64]) -> Vec<((usize, usize), Vec<Level>)> {
        let b = tile_bounds(n, t);
        let mut out = Vec::new();
        for iy in 0..t {
            for ix in 0..t {
                let (i0, j0) = (b[ix], b[iy]);
                let (w, h) = (b[ix + 1] - i0 + 1, b[iy + 1] - j0 + 1);
                let masks = masks(open_sides(ix, iy, t, t));
                let levels = lattice_levels(
                    w,
                    h,
                    |i, j| ((j0 + j) * n + i0 + i) as u32,
                    |i, j| z[(j0 + j) * n + i0 + i],
                    &masks,
                );
                out.push(((ix, iy), levels));
            }
        }
        out
    }

    #[test]
    fn open_sides_and_masks_leave_the_outline_full() {
        assert_eq!(open_sides(1, 1, 5, 3), 15);
        assert_eq!(open_sides(0, 0, 5, 3), TOP | RIGHT);
        assert_eq!(open_sides(4, 2, 5, 3), BOTTOM | LEFT);
        assert_eq!(open_sides(0, 0, 1, 1), 0);
        let m = masks(TOP | RIGHT);
        assert_eq!(m.len(), VARIANTS);
        assert_eq!((m[(TOP | LEFT) as usize - 1], m[14], m[(BOTTOM | LEFT) as usize - 1]), (TOP, TOP | RIGHT, 0));
        assert!(masks(0).is_empty());
    }

    #[test]
    fn stitch_opens_the_sides_between_equal_levels_on_both_tiles() {
        // 3 x 2 tiles: levels 3 3 4 / 3 None 4 (row 0 first).
        let l = [Some(3), Some(3), Some(4), Some(3), None, Some(4)];
        let m = stitch(3, 2, &l);
        assert_eq!(m, vec![RIGHT | TOP, LEFT, TOP, BOTTOM, 0, BOTTOM]);
        // On random levels, a side is in both of its tiles' masks or in neither.
        let mut rng = crate::TestRng(17);
        for _ in 0..50 {
            let (tx, ty) = (1 + (rng.f() * 6.0) as usize, 1 + (rng.f() * 6.0) as usize);
            let l: Vec<Option<u8>> = (0..tx * ty).map(|_| (rng.f() < 0.8).then(|| 3 + (rng.f() * 2.0) as u8)).collect();
            let m = stitch(tx, ty, &l);
            for iy in 0..ty {
                for ix in 0..tx {
                    let k = iy * tx + ix;
                    assert_eq!(m[k] & !open_sides(ix, iy, tx, ty), 0);
                    if ix + 1 < tx {
                        assert_eq!(m[k] & RIGHT != 0, m[k + 1] & LEFT != 0);
                        assert_eq!(m[k] & RIGHT != 0, l[k].is_some() && l[k] == l[k + 1]);
                    }
                    if iy + 1 < ty {
                        assert_eq!(m[k] & TOP != 0, m[k + tx] & BOTTOM != 0);
                        assert_eq!(m[k] & TOP != 0, l[k].is_some() && l[k] == l[k + tx]);
                    }
                }
            }
        }
    }

    #[test]
    fn stitched_tiles_at_random_levels_have_no_crack_and_a_full_outline() {
        // Tiles at random levels (fine included), those that may stitch at random: the union of
        // their triangles is watertight (every edge in two triangles) but for the field's
        // outline, where every edge is one sample long.
        let (n, t) = (61, 5);
        let mut rng = crate::TestRng(5);
        let z: Vec<f64> = (0..n * n).map(|_| 10.0 * rng.f()).collect();
        let tiles = tiled(n, t, &z);
        let n_levels = tiles.iter().map(|(_, l)| l.len()).min().unwrap();
        assert!(n_levels >= 4, "{n_levels}");
        let mut stitched = 0;
        for round in 0..40 {
            let level: Vec<usize> = (0..t * t).map(|_| (rng.f() * (n_levels + 1) as f64) as usize).collect();
            let may: Vec<Option<u8>> = level
                .iter()
                .enumerate()
                .map(|(k, &l)| (l >= 3 && !tiles[k].1[l - 1].grouped.is_empty() && rng.f() < 0.9).then_some(l as u8))
                .collect();
            let masks = stitch(t, t, &may);
            let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
            for (k, (_, levels)) in tiles.iter().enumerate() {
                let fine: Vec<u32>;
                let tris: &[u32] = match (level[k], masks[k]) {
                    (0, _) => {
                        fine = fine_of(&tiles[k].0, n, t);
                        &fine
                    }
                    (l, 0) => &levels[l - 1].indices,
                    (l, m) => {
                        stitched += 1;
                        &levels[l - 1].grouped[m as usize - 1]
                    }
                };
                for tri in tris.chunks_exact(3) {
                    for e in 0..3 {
                        let (p, q) = (tri[e], tri[(e + 1) % 3]);
                        *edges.entry((p.min(q), p.max(q))).or_default() += 1;
                    }
                }
            }
            for (&(p, q), &count) in &edges {
                if count == 2 {
                    continue;
                }
                assert_eq!(count, 1, "round {round}: edge {p}-{q} in {count} triangles");
                let (pi, pj, qi, qj) = (p as usize % n, p as usize / n, q as usize % n, q as usize / n);
                let on = |a: usize, c: usize| a == c && (a == 0 || a == n - 1);
                assert!(on(pi, qi) || on(pj, qj), "round {round}: open edge {p}-{q} inside");
                assert_eq!(pi.abs_diff(qi) + pj.abs_diff(qj), 1, "round {round}: coarse edge {p}-{q} on the outline");
            }
        }
        assert!(stitched > 100, "{stitched}");
    }

    /// The fine triangles of tile `(ix, iy)` of [`tiled`]'s field.
    fn fine_of(&(ix, iy): &(usize, usize), n: usize, t: usize) -> Vec<u32> {
        let b = tile_bounds(n, t);
        let id = |i: usize, j: usize| (j * n + i) as u32;
        (b[iy]..b[iy + 1])
            .flat_map(|j| (b[ix]..b[ix + 1]).map(move |i| (i, j)))
            .flat_map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)])
            .collect()
    }

    #[test]
    fn every_variant_lies_within_the_grouped_error() {
        // Sampled densely (eighths of a cell) over every variant's triangles on rough heights, on
        // tiles of 16 samples (lattices of one cell across) and of 42 (whose levels at strides
        // 16 and 32 lie past the chain of full borders, their border errors bounded).
        for (n, t) in [(47, 3), (83, 2)] {
            let mut rng = crate::TestRng(91);
            let z: Vec<f64> = (0..n * n).map(|_| 30.0 * rng.f()).collect();
            within_errors(n, t, &z);
        }
    }

    fn within_errors(n: usize, t: usize, z: &[f64]) {
        let zf = |i: usize, j: usize| z[j * n + i];
        let tiles = tiled(n, t, z);
        assert_eq!(tiles.iter().map(|(_, l)| l.len()).max(), Some(if n == 83 { 5 } else { 4 }));
        for (_, levels) in tiles {
            for l in &levels {
                assert!(l.grouped_error >= l.error);
                // The level's own triangles against its error (bounded past the chain), then the
                // variants against the group error.
                let own = distance_sampled(&l.indices, (n, n), &zf);
                assert!(l.error as f64 >= own * (1.0 - 1e-6), "{} below {own}", l.error);
                let seen = l.grouped.iter().map(|v| distance_sampled(v, (n, n), &zf)).fold(0.0, f64::max);
                assert!(l.grouped_error as f64 >= seen * (1.0 - 1e-6), "{} below {seen}", l.grouped_error);
            }
        }
    }

    #[test]
    fn wholly_coarse_variants_go_further_than_full_borders() {
        // A 42 x 42 tile with neighbours on every side: the full-border chain stops at stride 8,
        // where the border is most of the level; the chain with variants goes on, and its
        // coarsest variant with every side shared has a cell's two triangles per lattice cell.
        let w = 42;
        let z = |i: usize, j: usize| ((i * 7 + j * 3) % 5) as f64;
        let plain = lattice_levels(w, w, |i, j| (j * w + i) as u32, z, &[]);
        let grouped = lattice_levels(w, w, |i, j| (j * w + i) as u32, z, &masks(15));
        assert!(grouped.len() > plain.len(), "{} vs {}", grouped.len(), plain.len());
        let last = grouped.last().unwrap();
        assert_eq!(last.grouped[14].len() / 3, 8); // stride 32: lattice 0, 32, 41 a side
        assert!(last.indices.len() / 3 > 160); // its full border: 4 x 41 samples fanned
    }
}
