//! The cells of a height field's sample lattice at a stride: their triangles, and the largest
//! vertical distance between them and the fine surface (exact: both are piecewise linear, so it
//! is reached at a fine sample or where a coarse edge crosses a fine one). Shared by the levels
//! (`super::levels`) and their group variants (`super::groups`).

/// Triangles (counter-clockwise in x, y) of the lattice cell `lo..hi` (local sample indices) of a
/// tile of `size` samples: two if no side lies on a tile side drawn at full resolution, else a fan
/// from the cell's centre sample to every sample of those sides and the corners of its other
/// sides. `coarse`: the tile's sides drawn at the lattice's stride (bits 1 bottom, row 0; 2 right;
/// 4 top; 8 left, column 0), 0 for a tile whose whole border is at full resolution. Each side is
/// drawn as its bit says along its whole length, corner cells included (so that two tiles that
/// agree on their shared side's bit draw the same edges there, whatever their other sides are:
/// `lod::groups`).
pub(super) fn cell_triangles(
    lo: (usize, usize),
    hi: (usize, usize),
    size: (usize, usize),
    coarse: u8,
    out: &mut Vec<[(usize, usize); 3]>,
) {
    let (a, b) = lo;
    let (a1, b1) = hi;
    let on = [b == 0, a1 == size.0 - 1, b1 == size.1 - 1, a == 0];
    let full = |s: usize| on[s] && coarse & (1 << s) == 0;
    let (bottom, right, top, left) = (full(0), full(1), full(2), full(3));
    if !(bottom || right || top || left) {
        out.push([(a, b), (a1, b), (a1, b1)]);
        out.push([(a, b), (a1, b1), (a, b1)]);
        return;
    }
    // The cell's outline, counter-clockwise from (a, b), full resolution on border sides.
    let mut ring: Vec<(usize, usize)> = Vec::new();
    let side = |ring: &mut Vec<(usize, usize)>, full: bool, pts: &dyn Fn(usize) -> (usize, usize), n: usize| {
        if full {
            ring.extend((0..n).map(pts));
        } else {
            ring.push(pts(0));
        }
    };
    side(&mut ring, bottom, &|t| (a + t, b), a1 - a);
    side(&mut ring, right, &|t| (a1, b + t), b1 - b);
    side(&mut ring, top, &|t| (a1 - t, b1), a1 - a);
    side(&mut ring, left, &|t| (a, b1 - t), b1 - b);
    let c = (a + (a1 - a) / 2, b + (b1 - b) / 2);
    for i in 0..ring.len() {
        out.push([c, ring[i], ring[(i + 1) % ring.len()]]);
    }
}

/// The largest vertical distance between the fine surface and the two triangles of the square
/// lattice cell of side `k` at local sample (a, b), split along its diagonal from (a, b) to
/// (a + k, b + k) as [`cell_triangles`] splits an inner cell: the same as [`lattice_error`] of
/// those two triangles, in one pass over the cell's samples. The cell's diagonal runs along the
/// fine cells' diagonals (split the same way), so every fine triangle of the cell lies in one of
/// its two triangles, where both surfaces are linear: their difference is largest at a fine
/// sample.
pub(super) fn square_cell_error((a, b): (usize, usize), k: usize, z: &impl Fn(usize, usize) -> f64) -> f64 {
    let (z00, z10, z11, z01) = (z(a, b), z(a + k, b), z(a + k, b + k), z(a, b + k));
    let kf = k as f64;
    let mut err = 0.0f64;
    for dj in 0..=k {
        let v = dj as f64 / kf;
        for di in 0..=k {
            let u = di as f64 / kf;
            let g =
                if u >= v { z00 + u * (z10 - z00) + v * (z11 - z10) } else { z00 + u * (z11 - z01) + v * (z01 - z00) };
            err = err.max((z(a + di, b + dj) - g).abs());
        }
    }
    err
}

/// Height of the fine surface at a point (x, y) ≥ 0 of local sample coordinates: two triangles
/// per cell, split along the diagonal from (i, j) to (i + 1, j + 1), as the fine level is built.
pub(super) fn fine_height(x: f64, y: f64, z: &impl Fn(usize, usize) -> f64, max: (usize, usize)) -> f64 {
    // A cast truncates: the floor for x, y ≥ 0 (and 0 for a rounding below it).
    let i = (x as usize).min(max.0 - 1);
    let j = (y as usize).min(max.1 - 1);
    let (u, v) = (x - i as f64, y - j as f64);
    let (z00, z10, z11, z01) = (z(i, j), z(i + 1, j), z(i + 1, j + 1), z(i, j + 1));
    if u >= v {
        z00 + u * (z10 - z00) + v * (z11 - z10)
    } else {
        z00 + u * (z11 - z01) + v * (z01 - z00)
    }
}

/// The largest vertical distance between the triangles `tris` and the fine surface, where `tris`
/// are whole lattice cells' triangles, counter-clockwise, corners at samples (so that an edge
/// that is neither axis-aligned nor along the fine diagonals lies inside a cell, between two of
/// its triangles, once in each direction). The two surfaces are linear over every piece where a
/// level triangle meets a fine one, so the distance is largest at a corner of such a piece: a
/// fine sample inside or on a level triangle, or a point where a level edge crosses a fine edge
/// (a grid line x = i or y = j, or a cell's diagonal x - y = c). An edge along a grid line or a
/// diagonal meets them only at samples; any other edge is measured once, from its lower end.
pub(super) fn lattice_error(tris: &[[(usize, usize); 3]], z: &impl Fn(usize, usize) -> f64) -> f64 {
    let max = tris.iter().flatten().fold((1, 1), |m, &(i, j)| (m.0.max(i), m.1.max(j)));
    let mut err = 0.0f64;
    // Whether the segment a -> b can bend the fine surface between its ends.
    let bends = |a: (usize, usize), b: (usize, usize)| {
        let (dx, dy) = (b.0 as i64 - a.0 as i64, b.1 as i64 - a.1 as i64);
        dx != 0 && dy != 0 && dx != dy
    };
    for t in tris {
        let p = t.map(|(i, j)| (i as f64, j as f64, z(i, j)));
        let det = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            // A flat triangle's edges whatever their direction: their twins may be its own.
            if bends(a, b) && (a < b || det == 0.0) {
                err = err.max(edge_error(a, b, z, max));
            }
        }
        if det == 0.0 {
            continue;
        }
        let plane = |x: f64, y: f64| {
            let l1 = ((x - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (y - p[0].1)) / det;
            let l2 = ((p[1].0 - p[0].0) * (y - p[0].1) - (x - p[0].0) * (p[1].1 - p[0].1)) / det;
            (1.0 - l1 - l2, l1, l2)
        };
        let (x0, x1) = (t.iter().map(|q| q.0).min().unwrap(), t.iter().map(|q| q.0).max().unwrap());
        let (y0, y1) = (t.iter().map(|q| q.1).min().unwrap(), t.iter().map(|q| q.1).max().unwrap());
        for j in y0..=y1 {
            // Only the columns between the triangle's edges at this row (widened: the barycentric
            // test below decides), so a thin fan triangle costs its area, not its box's.
            let y = j as f64;
            let (mut xl, mut xr) = (f64::INFINITY, f64::NEG_INFINITY);
            for e in 0..3 {
                let (a, b) = (p[e], p[(e + 1) % 3]);
                if (a.1 - y) * (b.1 - y) <= 0.0 {
                    let x = if a.1 == b.1 { a.0.min(b.0) } else { a.0 + (y - a.1) * (b.0 - a.0) / (b.1 - a.1) };
                    let x2 = if a.1 == b.1 { a.0.max(b.0) } else { x };
                    (xl, xr) = (xl.min(x), xr.max(x2));
                }
            }
            let from = ((xl - 1e-6).ceil().max(x0 as f64)) as usize;
            let to = ((xr + 1e-6).floor().min(x1 as f64)) as usize;
            for i in from..=to {
                let (l0, l1, l2) = plane(i as f64, j as f64);
                if l0 >= -1e-9 && l1 >= -1e-9 && l2 >= -1e-9 {
                    let g = l0 * p[0].2 + l1 * p[1].2 + l2 * p[2].2;
                    err = err.max((z(i, j) - g).abs());
                }
            }
        }
    }
    err
}

/// The largest vertical distance between the segment from sample `a` to sample `b` (linear
/// between their heights) and the fine surface under it: at the segment's crossings with the
/// grid lines x = i, y = j and the cells' diagonals x - y = c, where the fine surface along it
/// bends (at its ends, samples, the two agree).
fn edge_error(a: (usize, usize), b: (usize, usize), z: &impl Fn(usize, usize) -> f64, max: (usize, usize)) -> f64 {
    let (ax, ay, bx, by) = (a.0 as i64, a.1 as i64, b.0 as i64, b.1 as i64);
    let (za, zb) = (z(a.0, a.1), z(b.0, b.1));
    let mut err = 0.0f64;
    for (u, v) in [(ax, bx), (ay, by), (ax - ay, bx - by)] {
        for g in u.min(v) + 1..u.max(v) {
            let s = (g - u) as f64 / (v - u) as f64;
            let (x, y) = (ax as f64 + s * (bx - ax) as f64, ay as f64 + s * (by - ay) as f64);
            err = err.max((fine_height(x, y, z, max) - (za + s * (zb - za))).abs());
        }
    }
    err
}
