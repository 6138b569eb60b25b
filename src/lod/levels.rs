//! Levels of detail for screen-space-error LOD: every tile gets a chain of levels 1, 2, ... each
//! with about a quarter of the triangles of the one before and its geometric error in world
//! units (level 0 is the tile's fine triangles, error 0).
//!
//! Every level of every tile keeps the tile's border at full resolution (its variants with sides
//! shared coarse with a neighbour at the same level aside, [`super::groups`]), so neighbouring
//! tiles drawn at different levels share the same border vertices and meet without cracks, by
//! construction (no skirts: skirts hide cracks with extra geometry that the full-resolution image
//! does not have, visible from below and at grazing angles; a locked border costs triangles on
//! the border instead, about 4 × the tile's side, which bounds the reduction of small tiles).
//!
//! * Hole-free height-field tiles ([`lattice_levels`]): the sample lattice at strides 2, 4, 8, ...;
//!   lattice cells that touch the tile border are fanned from their centre sample to every border
//!   sample. Error: the largest vertical distance between the level and the fine surface, at the
//!   fine samples and where the level's edges cross the fine edges (grid lines and diagonals).
//! * Every other tile ([`simplified_levels`]): meshoptimizer's quadric simplification of the
//!   previous level to a quarter of its triangles with the border (and hole outlines) locked.
//!   Error: the sum of meshoptimizer's estimates of each step (relative to the tile's extent, times
//!   that extent), which bounds the distance to level 0 as far as those estimates are right. A
//!   height-field tile with holes then has each level's error measured exactly, as the largest
//!   vertical distance to its fine triangles ([`grid_level_error`], `lod::tile_heightfield`),
//!   where every level triangle lies over fine triangles and the level covers their area: its
//!   levels then bound their distance everywhere as lattice levels do (`Slab::levels_exact`).
//!
//! Every level also records its shading error ([`super::shading`]): how far the lit pass's normals
//! on it may turn from the fine level's (a normal chord, unitless). Height-field levels record 0,
//! as the lit pass shades every level of a height field from its fine surface; simplified levels
//! measure it against the tile's smooth normals (or facet normals without them). The renderer
//! takes a level only if both errors hold (`crate::render`).
//!
//! The chain stops when a level would not reach 0.6 × the triangles of the one before (the border
//! then dominates), or after [`MAX_LEVELS`] levels; a hole-free height-field tile's goes on while
//! the level with its shared sides coarse ([`super::groups`]) would.

use super::lattice::{cell_triangles, lattice_error, square_cell_error};
use super::{shading, simplify};
pub use shading::Shading;

/// The most levels beyond level 0.
pub const MAX_LEVELS: usize = 5;

/// One level of a tile: a triangle list into the tile's vertices and its errors.
#[derive(Clone, Debug, Default)]
pub struct Level {
    pub indices: super::Indices,
    /// Geometric error, world units (not exaggerated): every point of the level lies within this
    /// distance of level 0's surface, and every point of level 0's within it of the level's.
    pub error: f32,
    /// The vertical part of that error (at most `error`): the displacement that `error` bounds
    /// has a z component of at most this. Vertical exaggeration stretches only that part, so a
    /// level whose error is horizontal (a vertical well's thinner polygon, a path's sideways
    /// wiggle) keeps its size on screen under exaggeration (`render::levels`). Height-field levels
    /// (vertical error) and isotropic ones (simplified meshes, grids) have `error_z == error`.
    pub error_z: f32,
    /// Shading error: the largest chord between the lit pass's unit normals on this level and on
    /// level 0 ([`super::shading::shading_error`]; unitless, 0..=sqrt 2). 0 for height-field
    /// levels (shaded from the fine surface); reservoir-grid levels bound it by summing each
    /// level's chord to the triangles of the faces it merges (`grid::merge`).
    pub shading_error: f32,
    /// Hole-free height-field tiles, levels 3..: this level with the sides of side mask m at the
    /// level's stride instead of full resolution, for m = 1..=[`super::groups::VARIANTS`] (entry
    /// m - 1; sides on the object's outline stay full), drawn where the neighbours across those
    /// sides are at the same level ([`super::groups`]). Empty for other tiles and levels.
    pub grouped: Vec<super::Indices>,
    /// The geometric error of every entry of `grouped`, vertical, world units: at least `error`.
    pub grouped_error: f32,
}

/// Lattice positions 0, k, 2k, ..., n - 1 along a side of n samples, with every gap at least 2
/// (so that a cell has a centre sample), or None when the side is too short (n < 3).
fn lattice_steps(n: usize, k: usize) -> Option<Vec<usize>> {
    if n < 3 {
        return None;
    }
    let mut s: Vec<usize> = (0..n - 1).step_by(k).collect();
    s.push(n - 1);
    if s.len() >= 3 && s[s.len() - 1] - s[s.len() - 2] < 2 {
        s.remove(s.len() - 2);
    }
    Some(s)
}

/// Levels of a hole-free height-field tile of `w` × `h` samples: `vid(li, lj)` is the vertex of
/// local sample (li, lj), `z(li, lj)` its height; `masks`: the side masks of each level's variants
/// ([`super::groups::masks`]; empty: none). Empty when the tile is too small to coarsen. [`LatticeShape::new`] then
/// [`LatticeShape::levels`]; tiles of one size and masks share the shape.
/// The length, after exaggerating z by `z_scale`, of a displacement of length at most `error`
/// whose z part is at most `error_z` (world units): `sqrt(error² + (z_scale² - 1) error_z²)`, as
/// `z_scale` stretches only the z part; `error` where `z_scale` <= 1 (nothing grows).
pub fn exaggerated(error: f32, error_z: f32, z_scale: f64) -> f64 {
    let (e, ez) = (error as f64, (error_z.min(error)) as f64);
    if z_scale <= 1.0 {
        return e;
    }
    (e * e + (z_scale * z_scale - 1.0) * ez * ez).sqrt()
}

#[cfg(test)]
pub fn lattice_levels(
    w: usize,
    h: usize,
    vid: impl Fn(usize, usize) -> u32,
    z: impl Fn(usize, usize) -> f64,
    masks: &[u8],
) -> Vec<Level> {
    LatticeShape::new(w, h, &vid, masks).levels(&z)
}

/// Lattice shapes by tile size and masks ([`LatticeShape::shared`]), for the tiles of one build.
pub type ShapeCache =
    std::sync::Mutex<std::collections::HashMap<(usize, usize, Vec<u8>), std::sync::Arc<LatticeShape>>>;

/// What the lattice levels of a hole-free tile are, apart from its heights: per level the lattice,
/// its cells (square inner cells; the other cells' triangles) and triangle lists. The same for
/// every tile of one size whose vertices are numbered alike, and one set of masks, so a height
/// field builds it once per such tile shape (`lod::tile_heightfield`).
///
/// The chain of levels stops when a level would not reach 0.6 × the triangles of the one before,
/// or, with groups, when neither it nor its wholly coarse variant would (a level past the first
/// that did not is a level for groups, whose border part of the error is bounded by
/// [`super::groups::BorderErrors::fans`] rather than measured: its fans cover most of the tile, and
/// measuring them doubled the time of a tile's levels).
#[derive(Debug)]
pub struct LatticeShape {
    size: (usize, usize),
    /// The fine triangles: two a cell, split from (i, j) to (i + 1, j + 1), cells row by row.
    pub fine: super::Indices,
    levels: Vec<ShapeLevel>,
}

#[derive(Debug)]
struct ShapeLevel {
    xs: Vec<usize>,
    ys: Vec<usize>,
    /// Square inner cells (corner, side), measured by `square_cell_error`.
    squares: Vec<(usize, usize, usize)>,
    /// The other cells' triangles (fans on the tile's border, the shorter last cells).
    others: Vec<[(usize, usize); 3]>,
    indices: super::Indices,
    grouped: Vec<super::Indices>,
    /// Within the chain of full borders (its error measured exactly).
    chain: bool,
}

impl LatticeShape {
    /// The shape of a tile of `w` × `h` samples, its vertices numbered by `vid`, with `masks` as
    /// [`lattice_levels`] takes them.
    pub fn new(w: usize, h: usize, vid: &impl Fn(usize, usize) -> u32, masks: &[u8]) -> Self {
        let mut levels = Vec::new();
        let mut prev = 2 * (w - 1) * (h - 1);
        let mut prev_coarse = prev;
        let mut chain = true;
        for l in 1..=MAX_LEVELS {
            let k = 1 << l;
            let (Some(xs), Some(ys)) = (lattice_steps(w, k), lattice_steps(h, k)) else { break };
            let mut tris: Vec<[(usize, usize); 3]> = Vec::new();
            let (mut squares, mut others) = (Vec::new(), Vec::new());
            for jj in ys.windows(2) {
                for ii in xs.windows(2) {
                    let start = tris.len();
                    cell_triangles((ii[0], jj[0]), (ii[1], jj[1]), (w, h), 0, &mut tris);
                    if tris.len() - start == 2 && ii[1] - ii[0] == jj[1] - jj[0] {
                        squares.push((ii[0], jj[0], ii[1] - ii[0]));
                    } else {
                        others.extend_from_slice(&tris[start..]);
                    }
                }
            }
            // The wholly coarse variant: two triangles a cell.
            let coarse = 2 * (xs.len() - 1) * (ys.len() - 1);
            let fewer = |n: usize, before: usize| n as f64 <= 0.6 * before as f64;
            chain &= fewer(tris.len(), prev);
            let for_groups = !masks.is_empty() && fewer(coarse, prev_coarse);
            if !chain && !for_groups {
                break;
            }
            (prev, prev_coarse) = (tris.len(), coarse);
            let indices = tris.iter().flat_map(|t| t.iter().map(|&(i, j)| vid(i, j))).collect();
            // Variants from level 3 on (below, the border is a smaller part of the tile's triangles,
            // and the variants, uploaded once per tile size and masks, would cost more than they save).
            let grouped = if masks.is_empty() || l < 3 {
                Vec::new()
            } else {
                super::groups::variants(&xs, &ys, (w, h), masks, vid)
            };
            levels.push(ShapeLevel { xs, ys, squares, others, indices, grouped, chain });
        }
        let fine = (0..h - 1)
            .flat_map(|j| (0..w - 1).map(move |i| (i, j)))
            .flat_map(|(i, j)| {
                let (a, b, c, d) = (vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1));
                [a, b, c, a, c, d]
            })
            .collect();
        LatticeShape { size: (w, h), fine, levels }
    }

    /// [`Self::new`], remembered in `cache` and shared with every caller that asks it for the same
    /// size and masks: for tiles whose vertices `vid` numbers as every such tile's are
    /// (`lod::tile_heightfield`'s hole-free tiles), so that their lists are one allocation (the
    /// upload then compacts each once).
    pub fn shared(
        cache: &ShapeCache,
        w: usize,
        h: usize,
        vid: &impl Fn(usize, usize) -> u32,
        masks: &[u8],
    ) -> std::sync::Arc<Self> {
        let key = (w, h, masks.to_vec());
        let lock = || cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(shape) = lock().get(&key) {
            return shape.clone();
        }
        let shape = std::sync::Arc::new(Self::new(w, h, vid, masks));
        lock().entry(key).or_insert(shape).clone()
    }

    /// The levels of a tile of this shape with heights `z(li, lj)`: the shape's triangle lists
    /// (shared) with their errors measured.
    pub fn levels(&self, z: &impl Fn(usize, usize) -> f64) -> Vec<Level> {
        self.levels
            .iter()
            .map(|s| {
                let inner =
                    s.squares.iter().map(|&(a, b, side)| square_cell_error((a, b), side, z)).fold(0.0, f64::max);
                let border = (!s.grouped.is_empty() || !s.chain)
                    .then(|| super::groups::border_errors(&s.xs, &s.ys, self.size, z, !s.chain));
                let error = match border.and_then(|b| b.fans) {
                    None => inner.max(lattice_error(&s.others, z)) as f32,
                    Some(fans) => super::f32_at_least(inner.max(fans)),
                };
                let grouped_error = match border {
                    Some(b) if !s.grouped.is_empty() => super::f32_at_least((error as f64).max(b.coarse)),
                    _ => error,
                };
                Level {
                    indices: s.indices.clone(),
                    error,
                    error_z: error,
                    shading_error: 0.0,
                    grouped: s.grouped.clone(),
                    grouped_error,
                }
            })
            .collect()
    }
}

/// The largest vertical distance between the triangles `level` and the fine surface of a
/// height-field tile with holes, or None where that is no bound everywhere: a level triangle
/// turned over or flat, a level triangle over a cell's fine triangle that is missing (a hole), or
/// levels' triangles that do not cover the fine ones' area. `at[k]`, `zk[k]`: vertex k's local
/// sample (column, row) and height; `z(i, j)`: the height of local sample (i, j), NaN where no
/// triangle uses it; the fine surface is two triangles per cell of `w` x `h` samples, split from
/// (i, j) to (i + 1, j + 1), where their corners are defined. Both surfaces are linear over each
/// piece where a level triangle meets a fine one (a convex polygon), so the distance is largest at
/// a corner of such a piece.
pub fn grid_level_error(
    (w, h): (usize, usize),
    z: impl Fn(usize, usize) -> f64,
    (at, zk): (&[[u32; 2]], &[f64]),
    level: &[u32],
) -> Option<f64> {
    type P = (f64, f64);
    let cross = |a: P, b: P, c: P| (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
    let area = |poly: &[P]| {
        (0..poly.len())
            .map(|i| poly[i].0 * poly[(i + 1) % poly.len()].1 - poly[(i + 1) % poly.len()].0 * poly[i].1)
            .sum::<f64>()
            / 2.0
    };
    // The plane through three (x, y, z) points, as z(x, y).
    let plane = |p: [(f64, f64, f64); 3]| {
        let d = cross((p[0].0, p[0].1), (p[1].0, p[1].1), (p[2].0, p[2].1));
        move |x: f64, y: f64| {
            let l1 = cross((p[0].0, p[0].1), (x, y), (p[2].0, p[2].1)) / d;
            let l2 = cross((p[0].0, p[0].1), (p[1].0, p[1].1), (x, y)) / d;
            (1.0 - l1 - l2) * p[0].2 + l1 * p[1].2 + l2 * p[2].2
        }
    };
    let mut fine_area = 0.0;
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            let (z00, z10, z11, z01) = (z(i, j), z(i + 1, j), z(i + 1, j + 1), z(i, j + 1));
            fine_area += 0.5
                * (f64::from(u8::from(z00.is_finite() && z10.is_finite() && z11.is_finite()))
                    + f64::from(u8::from(z00.is_finite() && z11.is_finite() && z01.is_finite())));
        }
    }
    let (mut err, mut level_area) = (0.0f64, 0.0f64);
    for t in level.chunks_exact(3) {
        let v = |k: u32| (at[k as usize][0] as f64, at[k as usize][1] as f64, zk[k as usize]);
        let c = [v(t[0]), v(t[1]), v(t[2])];
        let tri = [(c[0].0, c[0].1), (c[1].0, c[1].1), (c[2].0, c[2].1)];
        let a2 = cross(tri[0], tri[1], tri[2]);
        if a2 == 0.0 {
            // Flat in (x, y): a vertical sliver (or nothing) over a segment, checked along it.
            err = err.max(sliver_error((w, h), &z, c)?);
            continue;
        }
        if a2 < 0.0 {
            return None;
        }
        level_area += a2 / 2.0;
        let coarse = plane(c);
        let (x0, x1) =
            (tri.iter().map(|p| p.0).fold(f64::MAX, f64::min), tri.iter().map(|p| p.0).fold(f64::MIN, f64::max));
        let (y0, y1) =
            (tri.iter().map(|p| p.1).fold(f64::MAX, f64::min), tri.iter().map(|p| p.1).fold(f64::MIN, f64::max));
        for j in (y0 as usize)..(y1 as usize).min(h - 1) {
            for i in (x0 as usize)..(x1 as usize).min(w - 1) {
                let s = |a: usize, b: usize| (a as f64, b as f64, z(a, b));
                for f in [[s(i, j), s(i + 1, j), s(i + 1, j + 1)], [s(i, j), s(i + 1, j + 1), s(i, j + 1)]] {
                    // The fine triangle clipped by the level triangle's three sides.
                    let mut poly: Vec<P> = f.iter().map(|p| (p.0, p.1)).collect();
                    for e in 0..3 {
                        let (a, b) = (tri[e], tri[(e + 1) % 3]);
                        let side = |p: P| cross(a, b, p);
                        let mut out = Vec::with_capacity(poly.len() + 1);
                        for k in 0..poly.len() {
                            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
                            let (sp, sq) = (side(p), side(q));
                            if sp >= 0.0 {
                                out.push(p);
                            }
                            if (sp >= 0.0) != (sq >= 0.0) {
                                let u = sp / (sp - sq);
                                out.push((p.0 + u * (q.0 - p.0), p.1 + u * (q.1 - p.1)));
                            }
                        }
                        poly = out;
                        if poly.len() < 3 {
                            break;
                        }
                    }
                    if poly.len() < 3 || area(&poly) <= 1e-9 {
                        continue;
                    }
                    if !f.iter().all(|p| p.2.is_finite()) {
                        return None;
                    }
                    let fine = plane(f);
                    for &(x, y) in &poly {
                        err = err.max((coarse(x, y) - fine(x, y)).abs());
                    }
                }
            }
        }
    }
    ((level_area - fine_area).abs() <= 1e-6 * fine_area.max(1.0)).then_some(err)
}

/// The largest vertical distance between the fine surface (as in [`grid_level_error`]) and a
/// level triangle `c` ((column, row, height) corners) whose corners lie on one line in (x, y): at
/// every point of that segment the triangle spans the heights its edges take there, and both
/// are linear between the corners and the segment's crossings of the fine cells' sides and
/// diagonals. None where the segment runs over no fine triangle.
fn sliver_error((w, h): (usize, usize), z: &impl Fn(usize, usize) -> f64, c: [(f64, f64, f64); 3]) -> Option<f64> {
    // Along the segment from the first corner: p(s) = c0 + s d, the corners at s = 0, s1, s2.
    let d = [(c[1].0 - c[0].0, c[1].1 - c[0].1), (c[2].0 - c[0].0, c[2].1 - c[0].1)];
    let dir = if d[0].0.abs() + d[0].1.abs() >= d[1].0.abs() + d[1].1.abs() { d[0] } else { d[1] };
    let len2 = dir.0 * dir.0 + dir.1 * dir.1;
    if len2 == 0.0 {
        return Some(0.0); // a point: nothing drawn
    }
    let param = |p: (f64, f64, f64)| ((p.0 - c[0].0) * dir.0 + (p.1 - c[0].1) * dir.1) / len2;
    let s: Vec<f64> = c.iter().map(|&p| param(p)).collect();
    let (lo, hi) = (s.iter().copied().fold(f64::MAX, f64::min), s.iter().copied().fold(f64::MIN, f64::max));
    let mut at: Vec<f64> = s.clone();
    // Crossings of x = i, y = j and y - x = k.
    let mut cross_at = |a: f64, da: f64| {
        if da != 0.0 {
            let (u, v) = ((a + lo * da).min(a + hi * da), (a + lo * da).max(a + hi * da));
            for g in (u.ceil() as i64)..=(v.floor() as i64) {
                at.push((g as f64 - a) / da);
            }
        }
    };
    cross_at(c[0].0, dir.0);
    cross_at(c[0].1, dir.1);
    cross_at(c[0].1 - c[0].0, dir.1 - dir.0);
    let mut err = 0.0f64;
    for &t in &at {
        let (x, y) = (c[0].0 + t * dir.0, c[0].1 + t * dir.1);
        // The fine height there, from a fine triangle holding (x, y) whose corners are defined.
        let (i, j) = ((x.floor().max(0.0) as usize).min(w - 2), (y.floor().max(0.0) as usize).min(h - 2));
        let mut fine = None;
        for (di, dj) in [(0usize, 0usize), (1, 0), (0, 1), (1, 1)] {
            let (ci, cj) = (i.wrapping_sub(di), j.wrapping_sub(dj));
            if ci >= w - 1 || cj >= h - 1 || fine.is_some() {
                continue;
            }
            let (u, v) = (x - ci as f64, y - cj as f64);
            if !(-1e-9..=1.0 + 1e-9).contains(&u) || !(-1e-9..=1.0 + 1e-9).contains(&v) {
                continue;
            }
            let (z00, z10, z11, z01) = (z(ci, cj), z(ci + 1, cj), z(ci + 1, cj + 1), z(ci, cj + 1));
            if u >= v - 1e-9 && z00.is_finite() && z10.is_finite() && z11.is_finite() {
                fine = Some(z00 + u * (z10 - z00) + v * (z11 - z10));
            } else if v >= u - 1e-9 && z00.is_finite() && z11.is_finite() && z01.is_finite() {
                fine = Some(z00 + u * (z11 - z01) + v * (z01 - z00));
            }
        }
        let fine = fine?;
        // The triangle's heights at parameter t: on each edge whose span holds it.
        for e in 0..3 {
            let (sa, sb) = (s[e], s[(e + 1) % 3]);
            let (za, zb) = (c[e].2, c[(e + 1) % 3].2);
            if t >= sa.min(sb) - 1e-12 && t <= sa.max(sb) + 1e-12 {
                let zt = if sa == sb { za.max(zb) } else { za + (t - sa) / (sb - sa) * (zb - za) };
                let zt2 = if sa == sb { za.min(zb) } else { zt };
                err = err.max((zt - fine).abs()).max((zt2 - fine).abs());
            }
        }
    }
    Some(err)
}

/// Levels of any tile by quadric simplification: each level a quarter of the previous one's
/// triangles, border and hole outlines locked (see the module docs for the errors). `shading`:
/// how the tile is shaded, to measure the shading error; None for a height-field tile shaded
/// from its fine surface (shading error 0).
pub fn simplified_levels(positions: &[[f32; 3]], fine: &[u32], shading: Option<shading::Shading<'_>>) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::new();
    let mut prev: Vec<u32> = fine.to_vec();
    let mut error = 0.0f32;
    for _ in 0..MAX_LEVELS {
        let (idx, step) = simplify::coarse_indices(positions, &prev, 4.0);
        if idx.len() as f64 > 0.6 * prev.len() as f64 || idx.is_empty() {
            break;
        }
        error += step;
        let shading_error = shading.map_or(0.0, |sh| shading::shading_error(positions, sh, fine, &idx));
        levels.push(Level {
            indices: idx.as_slice().into(),
            error,
            error_z: error,
            shading_error,
            grouped: Vec::new(),
            grouped_error: error,
        });
        prev = idx;
    }
    levels
}

#[cfg(test)]
#[path = "levels_tests.rs"]
pub(super) mod tests;
