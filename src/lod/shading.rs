//! Shading error of a mesh tile's level of detail: how far the normals the lit pass uses on a
//! coarser level may turn from those it uses on the fine level (level 0) at the same place.
//!
//! The lit pass shades by a normal n (two-sided, `shade = 0.2 + 0.45 |n·l| + 0.35 |n·sun|`, see
//! draw.wgsl): a tile's smooth vertex normals ([`super::normals`]) interpolated over its
//! triangles, or each triangle's facet normal where the object has none. A coarser level
//! interpolates over larger triangles, so its normal at a point can differ from the fine level's
//! even where the two surfaces lie within a fraction of a pixel of each other.
//!
//! Measure ([`shading_error`]): the largest chord `min(|n_f - n_c|, |n_f + n_c|)` between unit
//! normals (unitless, 0..=sqrt 2; `2 sin(angle / 2)`, sign-free as the lit pass is), where n_f is
//! the fine level's normal at a sample point of a fine triangle (its corners, edge midpoints and
//! centroid) and n_c the level's normal at the closest point of the level's triangles. Between
//! samples both normals are interpolated linearly, so the maximum over the samples stands for the
//! maximum over the surface up to the curvature of the normal field within a fine triangle.
//!
//! Structured grid meshes (`TileMesh::grid_uv`) shade every level from the fine grid's normals at
//! the grid coordinates the level interpolates: there n_c is the fine normal at the interpolated
//! (i, j) of the closest point (where that cell's corners are not all in the tile, the level's
//! own interpolated normal stands for it), so such a level's error is only how far its surface
//! slides along the grid, not how far its normals turn.
//!
//! Conversion to colour ([`shade_levels_per_chord`], done at render time, where the colour and
//! the vertical exaggeration are known): `| |a·x| - |b·x| | <= |a - b|` for a unit x, so the shade
//! moves by at most `(0.45 + 0.35) × chord`, and an 8-bit channel of a base colour c by at most
//! `255 c × 0.8 × chord` levels. Vertical exaggeration s turns normals by a factor of at most
//! `max(s, 1/s)`.

use super::normals;
use glam::DVec3;
use rayon::prelude::*;

/// Largest change of the lit pass's shade factor per unit of normal chord: the head light's and
/// the sun's weights (draw.wgsl).
pub const SHADE_PER_CHORD: f64 = 0.45 + 0.35;

/// 8-bit colour levels per unit of normal chord for an object whose brightest base colour
/// channel is `max_channel` (0..=1), drawn with vertical exaggeration `z_scale` (see the module
/// docs).
pub fn shade_levels_per_chord(max_channel: f64, z_scale: f64) -> f64 {
    let turn = if z_scale > 0.0 { z_scale.max(1.0 / z_scale) } else { 1.0 };
    255.0 * max_channel.clamp(0.0, 1.0) * SHADE_PER_CHORD * turn
}

/// How a tile is shaded: its packed smooth normals (one per position, `normals::NONE` = none;
/// empty for facet shading) and packed grid coordinates (`TileMesh::grid_uv`; empty unless the
/// tile shades from its grid).
#[derive(Clone, Copy, Debug, Default)]
pub struct Shading<'a> {
    pub normals: &'a [u32],
    pub grid_uv: &'a [u32],
}

/// The shading error (normal chord, unitless, see the module docs) of the triangle list `level`
/// against the tile's fine triangles `fine`, both indexing `positions`, for a tile shaded as
/// `shading` says. 0 for an empty level or an empty fine level, and for a tile whose positions
/// all carry one normal (a flat tile), without sampling.
pub fn shading_error(positions: &[[f32; 3]], shading: Shading<'_>, fine: &[u32], level: &[u32]) -> f32 {
    if fine.len() < 3 || level.len() < 3 {
        return 0.0;
    }
    // One normal for every position (a flat tile: seismic slices, planar faults): both levels
    // interpolate that normal everywhere, on their triangles and through the grid alike.
    if let Some((&first, rest)) = shading.normals.split_first() {
        if first != normals::NONE && shading.normals.len() == positions.len() && rest.iter().all(|&k| k == first) {
            return 0.0;
        }
    }
    let p: Vec<DVec3> = positions.iter().map(|v| DVec3::from_array(v.map(f64::from))).collect();
    let n: Vec<DVec3> = shading.normals.iter().map(|&k| normals::unpack(k).unwrap_or(DVec3::ZERO)).collect();
    // Grid coordinates -> vertex, for the grid lookup.
    let uv = |k: usize| (shading.grid_uv[k] & 0xffff, shading.grid_uv[k] >> 16);
    let by_uv: std::collections::HashMap<(u32, u32), usize> = if shading.grid_uv.len() == p.len() && n.len() == p.len()
    {
        (0..p.len()).map(|k| (uv(k), k)).collect()
    } else {
        Default::default()
    };
    // The fine grid's normal at grid coordinates (x, y), as the lit pass interpolates it (the
    // cell's triangle (a, b, d) where x - i >= y - j, else (a, d, c)); None where a corner is
    // not in the tile.
    let grid_normal = |x: f64, y: f64| -> Option<DVec3> {
        // On a cell edge either cell gives the same normal: try the other where one has a
        // corner outside the tile (at the grid's last row or column, the lit pass clamps so).
        let cells = |v: f64| {
            let c = v.floor().max(0.0) as u32;
            [Some(c), (v == c as f64 && c > 0).then(|| c - 1)]
        };
        for i in cells(x).into_iter().flatten() {
            for j in cells(y).into_iter().flatten() {
                let (fx, fy) = (x - i as f64, y - j as f64);
                let at = |di: u32, dj: u32| by_uv.get(&(i + di, j + dj)).map(|&k| n[k]);
                let v = if fx >= fy {
                    at(0, 0).zip(at(1, 0)).zip(at(1, 1)).map(|((a, b), d)| (1.0 - fx) * a + (fx - fy) * b + fy * d)
                } else {
                    at(0, 0).zip(at(0, 1)).zip(at(1, 1)).map(|((a, c), d)| (1.0 - fy) * a + (fy - fx) * c + fx * d)
                };
                if let Some(v) = v {
                    return v.try_normalize();
                }
            }
        }
        None
    };
    let tris = |idx: &[u32]| -> Vec<[usize; 3]> {
        idx.chunks_exact(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect()
    };
    let (fine, level) = (tris(fine), tris(level));
    // The lit pass's normal on triangle t at barycentrics b: the interpolated vertex normals, or
    // the facet's where they cancel or the object has none.
    let normal_at = |t: &[usize; 3], b: [f64; 3]| -> Option<DVec3> {
        if !n.is_empty() {
            let v = b[0] * n[t[0]] + b[1] * n[t[1]] + b[2] * n[t[2]];
            if v.length_squared() > 1e-12 {
                return Some(v.normalize());
            }
        }
        (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).try_normalize()
    };
    let grid = TriangleGrid::new(&p, &level);
    // Samples per fine triangle: its edge midpoints and centroid, and each vertex once (at the
    // first triangle that uses it).
    const MIDS: [[f64; 3]; 4] = [[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0]];
    const CORNERS: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut first = vec![false; p.len()];
    let samples: Vec<(usize, [f64; 3])> = fine
        .iter()
        .enumerate()
        .flat_map(|(k, t)| {
            let corners: Vec<(usize, [f64; 3])> =
                (0..3).filter(|&c| !std::mem::replace(&mut first[t[c]], true)).map(|c| (k, CORNERS[c])).collect();
            MIDS.iter().map(move |&b| (k, b)).chain(corners)
        })
        .collect();
    let err = samples
        .par_chunks(4096)
        .map(|chunk| {
            let mut err = 0.0f64;
            for &(k, b) in chunk {
                let t = &fine[k];
                let Some(nf) = normal_at(t, b) else { continue };
                let q = b[0] * p[t[0]] + b[1] * p[t[1]] + b[2] * p[t[2]];
                let Some((kc, bc)) = grid.closest(&p, &level, q) else { continue };
                let t = &level[kc];
                let looked_up = (!by_uv.is_empty())
                    .then(|| {
                        let (x, y) = (0..3).fold((0.0, 0.0), |(x, y), c| {
                            let (u, v) = uv(t[c]);
                            (x + bc[c] * u as f64, y + bc[c] * v as f64)
                        });
                        grid_normal(x, y)
                    })
                    .flatten();
                let Some(nc) = looked_up.or_else(|| normal_at(t, bc)) else { continue };
                err = err.max((nf - nc).length().min((nf + nc).length()));
            }
            err
        })
        .reduce(|| 0.0, f64::max);
    err as f32
}

/// A uniform grid of cells over a triangle list's bounding box, each cell listing the triangles
/// whose bounding boxes overlap it: closest-point queries visit cells in growing shells.
struct TriangleGrid {
    lo: DVec3,
    /// Cell edge length (the same on every axis), world units.
    h: f64,
    dims: [usize; 3],
    /// Per cell, its first entry in `items` (CSR; one more than the number of cells).
    start: Vec<u32>,
    items: Vec<u32>,
    /// Per triangle, its bounding box: a triangle whose box lies no nearer than the best so far
    /// is skipped without the closest-point test.
    boxes: Vec<(DVec3, DVec3)>,
}

impl TriangleGrid {
    fn new(p: &[DVec3], tris: &[[usize; 3]]) -> Self {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut area = 0.0;
        for t in tris {
            for &k in t {
                lo = lo.min(p[k]);
                hi = hi.max(p[k]);
            }
            area += 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).length();
        }
        let extent = (hi - lo).max_element().max(1e-9);
        // About two triangles' width per cell, and no more than a few cells per triangle.
        let mut h = (2.0 * (area / tris.len() as f64).sqrt()).max(extent / 256.0).max(1e-9);
        let dims_of = |h: f64| ((hi - lo) / h).to_array().map(|e| (e.floor() as usize + 1).max(1));
        let mut dims = dims_of(h);
        while dims.iter().product::<usize>() > 8 * tris.len() + 64 {
            h *= 1.5;
            dims = dims_of(h);
        }
        let boxes: Vec<(DVec3, DVec3)> = tris
            .iter()
            .map(|t| {
                t.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(a, b), &k| {
                    (a.min(p[k]), b.max(p[k]))
                })
            })
            .collect();
        let mut grid = Self { lo, h, dims, start: Vec::new(), items: Vec::new(), boxes: Vec::new() };
        let ncell = dims.iter().product::<usize>();
        let mut count = vec![0u32; ncell + 1];
        let ranges: Vec<([usize; 3], [usize; 3])> = boxes.iter().map(|&(a, b)| (grid.cell(a), grid.cell(b))).collect();
        for (c0, c1) in &ranges {
            grid.for_cells(*c0, *c1, |c| count[c + 1] += 1);
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        for (k, (c0, c1)) in ranges.iter().enumerate() {
            grid.for_cells(*c0, *c1, |c| {
                items[fill[c] as usize] = k as u32;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.items = items;
        grid.boxes = boxes;
        grid
    }

    /// The cell of a point (clamped into the grid).
    fn cell(&self, q: DVec3) -> [usize; 3] {
        let r = (q - self.lo) / self.h;
        let mut c = [0usize; 3];
        for a in 0..3 {
            c[a] = (r[a].max(0.0).floor() as usize).min(self.dims[a] - 1);
        }
        c
    }

    fn for_cells(&self, c0: [usize; 3], c1: [usize; 3], mut f: impl FnMut(usize)) {
        for z in c0[2]..=c1[2] {
            for y in c0[1]..=c1[1] {
                for x in c0[0]..=c1[0] {
                    f((z * self.dims[1] + y) * self.dims[0] + x);
                }
            }
        }
    }

    /// The triangle closest to `q` and the barycentrics of its closest point; None without
    /// triangles.
    fn closest(&self, p: &[DVec3], tris: &[[usize; 3]], q: DVec3) -> Option<(usize, [f64; 3])> {
        let c = self.cell(q);
        // How far q lies inside its cell (0 when outside the grid): cells beyond shell r are at
        // least r cell widths plus this away.
        let rel = (q - self.lo) / self.h;
        let margin = (0..3)
            .map(|a| {
                let f = rel[a] - c[a] as f64;
                if (0.0..=1.0).contains(&f) {
                    f.min(1.0 - f)
                } else {
                    0.0
                }
            })
            .fold(f64::INFINITY, f64::min)
            * self.h;
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        let reach = *self.dims.iter().max().unwrap();
        for r in 0..=reach {
            // The shell of cells at Chebyshev distance r from c.
            let lo = c.map(|v| v.saturating_sub(r));
            let hi = [0, 1, 2].map(|a| (c[a] + r).min(self.dims[a] - 1));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let d = [x.abs_diff(c[0]), y.abs_diff(c[1]), z.abs_diff(c[2])];
                        if d.into_iter().max() != Some(r) {
                            continue;
                        }
                        // A cell whose box lies no nearer than the best triangle so far holds
                        // no nearer one: skip it (the same answer, ties included, as the scan
                        // keeps the first of equally near triangles).
                        if let Some((bd, _, _)) = best {
                            let cell_lo = self.lo + DVec3::new(x as f64, y as f64, z as f64) * self.h;
                            if box_gap2(q, cell_lo, cell_lo + DVec3::splat(self.h)) >= bd {
                                continue;
                            }
                        }
                        let cell = (z * self.dims[1] + y) * self.dims[0] + x;
                        for &k in &self.items[self.start[cell] as usize..self.start[cell + 1] as usize] {
                            if let Some((bd, _, _)) = best {
                                let (blo, bhi) = self.boxes[k as usize];
                                if box_gap2(q, blo, bhi) >= bd {
                                    continue;
                                }
                            }
                            let t = &tris[k as usize];
                            let (d2, b) = closest_on_triangle(q, p[t[0]], p[t[1]], p[t[2]]);
                            if best.is_none_or(|(bd, _, _)| d2 < bd) {
                                best = Some((d2, k as usize, b));
                            }
                        }
                    }
                }
            }
            // Triangles in cells beyond this shell lie at least r cell widths plus the margin away.
            if let Some((d2, _, _)) = best {
                if d2 <= (r as f64 * self.h + margin).powi(2) {
                    break;
                }
            }
        }
        best.map(|(_, k, b)| (k, b))
    }
}

/// Squared distance from `q` to the box `lo..=hi` (0 inside).
fn box_gap2(q: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    (q.clamp(lo, hi) - q).length_squared()
}

/// Squared distance from `q` to the triangle (a, b, c) and the barycentrics of the closest point
/// (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_on_triangle(q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (f64, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, q - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    let bary = if d1 <= 0.0 && d2 <= 0.0 {
        [1.0, 0.0, 0.0]
    } else {
        let bp = q - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        let cp = q - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        let (vc, vb, va) = (d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4);
        if d3 >= 0.0 && d4 <= d3 {
            [0.0, 1.0, 0.0]
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            let v = d1 / (d1 - d3);
            [1.0 - v, v, 0.0]
        } else if d6 >= 0.0 && d5 <= d6 {
            [0.0, 0.0, 1.0]
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            let w = d2 / (d2 - d6);
            [1.0 - w, 0.0, w]
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            [0.0, 1.0 - w, w]
        } else {
            let denom = va + vb + vc;
            if denom.abs() < 1e-300 {
                [1.0, 0.0, 0.0]
            } else {
                let (v, w) = (vb / denom, vc / denom);
                [1.0 - v - w, v, w]
            }
        }
    };
    let x = bary[0] * a + bary[1] * b + bary[2] * c;
    ((q - x).length_squared(), bary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n × n sheet of unit cells, z = f(x, y), two triangles per cell; and its level at stride
    /// 2 (every other vertex), both indexing the same vertices.
    fn sheet(n: usize, f: impl Fn(f64, f64) -> f64) -> (Vec<[f32; 3]>, Vec<u32>, Vec<u32>) {
        let pos: Vec<[f32; 3]> = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f64, (k / n) as f64);
                [x as f32, y as f32, f(x, y) as f32]
            })
            .collect();
        let quads = |s: usize| -> Vec<u32> {
            let mut idx = Vec::new();
            for j in (0..n - 1).step_by(s) {
                for i in (0..n - 1).step_by(s) {
                    let k = |a: usize, b: usize| (b * n + a) as u32;
                    let (a, b, c, d) = (k(i, j), k(i + s, j), k(i + s, j + s), k(i, j + s));
                    idx.extend_from_slice(&[a, b, c, a, c, d]);
                }
            }
            idx
        };
        (pos, quads(1), quads(2))
    }

    fn sm(normals: &[u32]) -> Shading<'_> {
        Shading { normals, grid_uv: &[] }
    }

    fn smooth(pos: &[[f32; 3]], fine: &[u32]) -> Vec<u32> {
        let v: Vec<[f64; 3]> = pos.iter().map(|p| p.map(f64::from)).collect();
        let f: Vec<[u32; 3]> = fine.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        normals::smooth_normals(&v, &f).expect("smooth")
    }

    #[test]
    fn a_flat_sheet_has_no_shading_error_and_a_curved_one_has() {
        // Tilted plane: every level's normals are the plane's, smooth or facet.
        let (pos, fine, coarse) = sheet(17, |x, y| 0.3 * x - 0.2 * y);
        let n = smooth(&pos, &fine);
        assert!(shading_error(&pos, sm(&n), &fine, &coarse) < 1e-4);
        assert!(shading_error(&pos, sm(&[]), &fine, &coarse) < 1e-4);
        // A cylinder-like bend: interpolating over twice the width turns the normals.
        let (pos, fine, coarse) = sheet(17, |x, _| 0.05 * x * x);
        let n = smooth(&pos, &fine);
        let smooth_err = shading_error(&pos, sm(&n), &fine, &coarse);
        let facet_err = shading_error(&pos, sm(&[]), &fine, &coarse);
        assert!(smooth_err > 1e-3, "{smooth_err}");
        assert!(facet_err > smooth_err, "{facet_err} vs {smooth_err}");
        // The level itself has no error against itself.
        assert!(shading_error(&pos, sm(&n), &coarse, &coarse) < 1e-6);
        // Shaded from its grid, the level takes the fine normals: only a sliver of the error is
        // left (where the level lies off the fine surface).
        let uv: Vec<u32> = (0..pos.len()).map(|k| (k % 17) as u32 | (((k / 17) as u32) << 16)).collect();
        let grid_err = shading_error(&pos, Shading { normals: &n, grid_uv: &uv }, &fine, &coarse);
        assert!(grid_err < 0.2 * smooth_err, "{grid_err} vs {smooth_err}");
    }

    #[test]
    fn one_normal_everywhere_is_no_error_whatever_the_level_and_two_are_measured() {
        // A flat sheet whose level is bent far off it: with one normal for every position both
        // levels shade alike, so the error is 0 without sampling.
        let (pos, fine, _) = sheet(9, |x, y| 0.3 * x - 0.2 * y);
        let (bent, _, coarse) = sheet(9, |x, _| 0.5 * x * x);
        let mut n = smooth(&pos, &fine);
        let first = n[0];
        n.iter_mut().for_each(|k| *k = first);
        let mut both = pos.clone();
        both.extend_from_slice(&bent);
        let mut n2 = n.clone();
        n2.extend_from_slice(&n);
        let shifted: Vec<u32> = coarse.iter().map(|&k| k + pos.len() as u32).collect();
        assert_eq!(shading_error(&both, sm(&n2), &fine, &shifted), 0.0);
        // One vertex of the bent level with another normal: measured, and not 0.
        n2[shifted[0] as usize] = smooth(&bent, &fine)[coarse[0] as usize];
        assert_ne!(n2[shifted[0] as usize], n[0]);
        assert!(shading_error(&both, sm(&n2), &fine, &shifted) > 1e-3);
        // Facet shading (no normals) of the same pair is measured too.
        assert!(shading_error(&both, sm(&[]), &fine, &shifted) > 1e-3);
    }

    #[test]
    fn the_error_is_the_largest_normal_chord() {
        // A fold along x = 4: the fine level is flat for x < 4 and rises at 45° beyond. The level
        // of two triangles over the whole sheet is the plane z = x / 2, at atan(1/2) from +z and
        // at 45° - atan(1/2) from the rising half's normal: the error is the larger angle's chord.
        let n = 9;
        let (pos, fine, _) = sheet(n, |x, _| (x - 4.0).max(0.0));
        let k = |a: usize, b: usize| (b * n + a) as u32;
        let coarse = vec![k(0, 0), k(8, 0), k(8, 8), k(0, 0), k(8, 8), k(0, 8)];
        let err = shading_error(&pos, sm(&[]), &fine, &coarse) as f64;
        let a = 0.5f64.atan();
        let want = 2.0 * (a.max(std::f64::consts::FRAC_PI_4 - a) / 2.0).sin();
        assert!((err - want).abs() < 1e-5, "{err} vs {want}");
    }

    #[test]
    fn closest_point_on_a_triangle() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let (d2, bc) = closest_on_triangle(DVec3::new(0.25, 0.25, 2.0), a, b, c);
        assert!((d2 - 4.0).abs() < 1e-12 && (bc[1] - 0.25).abs() < 1e-12 && (bc[2] - 0.25).abs() < 1e-12);
        let (d2, bc) = closest_on_triangle(DVec3::new(2.0, -1.0, 0.0), a, b, c);
        assert!((d2 - 2.0).abs() < 1e-12 && bc == [0.0, 1.0, 0.0]);
    }

    #[test]
    fn grid_queries_find_the_closest_triangle() {
        let (pos, _, coarse) = sheet(21, |x, y| 2.0 * (x / 3.0).sin() * (y / 4.0).cos());
        let p: Vec<DVec3> = pos.iter().map(|v| DVec3::from_array(v.map(f64::from))).collect();
        let tris: Vec<[usize; 3]> =
            coarse.chunks_exact(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
        let grid = TriangleGrid::new(&p, &tris);
        let mut rng = crate::TestRng(12345);
        let mut rnd = || rng.f();
        // The grid's answer is as near as the nearest of all triangles.
        let check = |grid: &TriangleGrid, p: &[DVec3], tris: &[[usize; 3]], q: DVec3| {
            let (k, b) = grid.closest(p, tris, q).unwrap();
            let t = tris[k];
            let got = (q - (b[0] * p[t[0]] + b[1] * p[t[1]] + b[2] * p[t[2]])).length_squared();
            let want =
                tris.iter().map(|t| closest_on_triangle(q, p[t[0]], p[t[1]], p[t[2]]).0).fold(f64::INFINITY, f64::min);
            assert!((got - want).abs() <= 1e-9 * (1.0 + want), "{q}: {got} vs {want}");
        };
        for _ in 0..500 {
            let q = DVec3::new(rnd() * 26.0 - 3.0, rnd() * 26.0 - 3.0, rnd() * 8.0 - 4.0);
            check(&grid, &p, &tris, q);
        }
        // A soup of random triangles, slivers spanning many cells among them: the cells and
        // triangles skipped by their boxes never hide the closest one.
        let p: Vec<DVec3> = (0..300).map(|_| DVec3::new(rnd() * 10.0, rnd() * 10.0, rnd() * 2.0)).collect();
        let tris: Vec<[usize; 3]> = (0..100).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let grid = TriangleGrid::new(&p, &tris);
        for _ in 0..2000 {
            let q = DVec3::new(rnd() * 14.0 - 2.0, rnd() * 14.0 - 2.0, rnd() * 6.0 - 2.0);
            check(&grid, &p, &tris, q);
        }
    }

    #[test]
    fn conversion_to_colour_levels() {
        assert!((shade_levels_per_chord(1.0, 1.0) - 204.0).abs() < 1e-9);
        assert!((shade_levels_per_chord(0.5, 2.0) - 204.0).abs() < 1e-9);
        assert!((shade_levels_per_chord(0.5, 0.5) - 204.0).abs() < 1e-9);
    }
}
