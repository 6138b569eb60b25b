//! Groups of lattice tiles drawn as one: the border of a coarse level without its full-resolution
//! cost.
//!
//! Every level keeps its tile's border at full resolution ([`super::levels`]), so that neighbours at
//! any levels meet without cracks. At the coarse levels that border is most of the triangles (a
//! tile of 42 × 42 samples at stride 8: 18 triangles inside, about 230 on the border), and a scene
//! of finer samples in tiles of the same size draws ever more of them: the border, not the
//! surface, is what a distant frame pays for.
//!
//! A *group* of depth d is an aligned block of 2^d × 2^d tiles of one height field (fewer at the
//! object's far sides). When every tile of a group is drawn at the same level, the sides they share
//! can be drawn at that level's stride on both sides: the same samples, so still no crack. Each
//! level from 3 on of a hole-free tile therefore has, besides its full-border triangles, one variant per
//! depth d = 1..=[`MAX_GROUP_DEPTH`] (`Level::grouped`) whose sides inside the group are coarse
//! ([`side_masks`], [`variants`]); the group's own outline stays at full resolution, so it meets
//! whatever lies beyond at any level (and the object's outline, its silhouette, does not move).
//! The renderer picks per frame, bottom-up, the groups whose tiles all draw a level and whose
//! merged draw has fewer triangles, away from other objects (`render::groups`).
//!
//! A cell at a corner of the tile whose sides there are one coarse, one at full resolution draws
//! both at full resolution: the tile across the coarse side lies in the same group, so its cell
//! there lies on the same full side (groups are aligned blocks) and draws the shared piece at full
//! resolution too.
//!
//! Error: a variant's triangles are, cell by cell, the level's own (inner cells; border cells with
//! their border sides at full resolution, fanned as the level fans them), a border cell's two
//! diagonal triangles where all its border sides are coarse, or, in a cell across the whole tile
//! (on two opposite sides) with one of them coarse, the fan triangle from its centre to that
//! side's corners. So every variant lies within the larger of the level's error and
//! [`BorderErrors::coarse`] (those diagonal pairs and corner triangles) of the fine surface:
//! `Level::grouped_error`, for every depth.

use super::lattice::{cell_triangles, lattice_error, square_cell_error};
use super::Indices;

/// The deepest group: 2^6 = 64 tiles a side.
pub const MAX_GROUP_DEPTH: usize = 6;

/// Bits of a tile's sides in a side mask (local sample space: row 0 is the bottom, column 0 the left).
pub const BOTTOM: u8 = 1;
pub const RIGHT: u8 = 2;
pub const TOP: u8 = 4;
pub const LEFT: u8 = 8;

/// Per group depth d = 1..=[`MAX_GROUP_DEPTH`] (entry d - 1), the sides of tile (`ix`, `iy`) of a
/// height field of `tx` × `ty` tiles drawn at the level's stride in its group of depth d: those
/// whose neighbour lies in the same group. (The object's outline stays at full resolution: its
/// silhouette then does not move with the level.)
pub fn side_masks(ix: usize, iy: usize, tx: usize, ty: usize) -> Vec<u8> {
    (1..=MAX_GROUP_DEPTH)
        .map(|d| {
            let same = |a: usize, b: usize| a >> d == b >> d;
            let mut m = 0;
            if iy > 0 && same(iy, iy - 1) {
                m |= BOTTOM;
            }
            if ix + 1 < tx && same(ix, ix + 1) {
                m |= RIGHT;
            }
            if iy + 1 < ty && same(iy, iy + 1) {
                m |= TOP;
            }
            if ix > 0 && same(ix, ix - 1) {
                m |= LEFT;
            }
            m
        })
        .collect()
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
    /// the tile's border (a border cell whose border sides are all coarse), and in a cell across
    /// the whole tile, the triangles from its centre sample to the corners of each of its border
    /// sides (a coarse one beside a full one opposite); any other cell draws the level's own
    /// triangles ([`cell_triangles`]).
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
            if (on[0] && on[2]) || (on[1] && on[3]) {
                // Its centre's edges to the corners are the level's own (its fan's).
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

    /// A height field of `n` × `n` samples cut into `t` × `t` tiles, its levels with groups, the
    /// vertices being the samples' global indices.
    fn tiled(n: usize, t: usize, z: &[f64]) -> Vec<((usize, usize), Vec<Level>)> {
        let b = tile_bounds(n, t);
        let mut out = Vec::new();
        for iy in 0..t {
            for ix in 0..t {
                let (i0, j0) = (b[ix], b[iy]);
                let (w, h) = (b[ix + 1] - i0 + 1, b[iy + 1] - j0 + 1);
                let masks = side_masks(ix, iy, t, t);
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
    fn side_masks_open_the_sides_inside_a_group_and_on_the_outline() {
        // 5 x 3 tiles: in groups of 2 x 2, tile (1, 1) shares its left and bottom sides with its
        // group (above it lies the next group); tile (4, 0) shares only its top (its group has no
        // column 5).
        let m = side_masks(1, 1, 5, 3);
        assert_eq!(m[0], BOTTOM | LEFT);
        assert_eq!(side_masks(4, 0, 5, 3)[0], TOP);
        assert_eq!(side_masks(2, 1, 5, 3)[0], BOTTOM | RIGHT);
        // Depth 2 (4 x 4): tile (1, 1) shares every side.
        assert_eq!(m[1], 15);
        assert_eq!(side_masks(3, 1, 5, 3)[1], BOTTOM | LEFT | TOP);
        // Deep enough, every side but the outline's is open.
        let deep = |ix: usize, iy: usize| side_masks(ix, iy, 5, 3)[MAX_GROUP_DEPTH - 1];
        assert_eq!(deep(2, 1), 15);
        assert_eq!(deep(0, 0), TOP | RIGHT);
        assert_eq!(deep(4, 2), BOTTOM | LEFT);
    }

    #[test]
    fn a_group_at_one_level_has_no_crack_and_a_full_outline() {
        // Every group of every depth, its tiles at one level (each variant of that depth): an
        // edge of the union that only one triangle has lies on the group's outline, and there
        // it is a full-resolution edge (one sample long). So the group meets itself without
        // cracks and anything beyond at any level.
        let (n, t) = (61, 5);
        let mut rng = crate::TestRng(5);
        let z: Vec<f64> = (0..n * n).map(|_| 10.0 * rng.f()).collect();
        let tiles = tiled(n, t, &z);
        let b = tile_bounds(n, t);
        let n_levels = tiles.iter().map(|(_, l)| l.len()).min().unwrap();
        assert!(n_levels >= 3, "{n_levels}");
        let mut groups_seen = 0;
        for d in 1..=3 {
            let side = 1usize << d;
            for (gx, gy) in (0..t.div_ceil(side)).flat_map(|gy| (0..t.div_ceil(side)).map(move |gx| (gx, gy))) {
                let members: Vec<_> = tiles.iter().filter(|((ix, iy), _)| ix >> d == gx && iy >> d == gy).collect();
                let (x0, x1) = (b[gx * side], b[((gx + 1) * side).min(t)]);
                let (y0, y1) = (b[gy * side], b[((gy + 1) * side).min(t)]);
                // Levels 1 and 2 have no group variants (`LatticeShape::new`).
                for l in 2..n_levels {
                    assert_eq!(members[0].1[l].grouped.len(), MAX_GROUP_DEPTH);
                    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
                    for (_, levels) in &members {
                        for tri in levels[l].grouped[d - 1].chunks_exact(3) {
                            for e in 0..3 {
                                let (p, q) = (tri[e], tri[(e + 1) % 3]);
                                *edges.entry((p.min(q), p.max(q))).or_default() += 1;
                            }
                        }
                    }
                    for (&(p, q), &count) in &edges {
                        let (pi, pj, qi, qj) = (p as usize % n, p as usize / n, q as usize % n, q as usize / n);
                        if count == 2 {
                            continue;
                        }
                        assert_eq!(count, 1, "edge {p}-{q} in {count} triangles");
                        let on = |a: usize, c: usize, lo: usize, hi: usize| a == c && (a == lo || a == hi);
                        let outline = on(pi, qi, x0, x1) || on(pj, qj, y0, y1);
                        assert!(outline, "depth {d} group ({gx}, {gy}) level {}: open edge {p}-{q} inside", l + 1);
                        let object = on(pi, qi, 0, n - 1) || on(pj, qj, 0, n - 1);
                        assert!(
                            object || pi.abs_diff(qi) + pj.abs_diff(qj) == 1,
                            "coarse edge {p}-{q} on the group's side"
                        );
                    }
                    groups_seen += 1;
                }
            }
        }
        assert!(groups_seen > 20);
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
        // A 42 x 42 tile inside a group of 4 x 4 (every side shared): the full-border chain
        // stops at stride 8, where the border is most of the level; the grouped chain goes on,
        // and its coarsest variant at that depth has a cell's two triangles per lattice cell.
        let w = 42;
        let z = |i: usize, j: usize| ((i * 7 + j * 3) % 5) as f64;
        let plain = lattice_levels(w, w, |i, j| (j * w + i) as u32, z, &[]);
        let masks = side_masks(1, 1, 4, 4);
        assert_eq!(masks[1], 15);
        let grouped = lattice_levels(w, w, |i, j| (j * w + i) as u32, z, &masks);
        assert!(grouped.len() > plain.len(), "{} vs {}", grouped.len(), plain.len());
        let last = grouped.last().unwrap();
        assert_eq!(last.grouped[1].len() / 3, 8); // stride 32: lattice 0, 32, 41 a side
        assert!(last.indices.len() / 3 > 160); // its full border: 4 x 41 samples fanned
    }
}
