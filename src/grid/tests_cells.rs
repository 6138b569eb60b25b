//! Cell coordinates (`cells`): every point of every level finds its own cell's value, and the
//! level's error bounds how far a colour can move. Known answers on box grids.

use super::*;

/// Grid positions of the pillars: column widths growing (irregular when `grow` > 0).
fn columns(n: usize, grow: f64) -> Vec<f64> {
    let mut x = vec![0.0];
    for i in 0..n {
        x.push(x[i] + 10.0 * (1.0 + grow * (i % 3) as f64));
    }
    x
}

/// A box grid on pillar positions `xs`, `ys`, layers 2 m thick (z = -2k).
fn box_on(xs: &[f64], ys: &[f64], nk: usize) -> Vec<f64> {
    grid_from(xs.len() - 1, ys.len() - 1, nk, |_, (i, j, k)| [xs[i], ys[j], -2.0 * k as f64])
}

/// The point of the fine lattice at (doubled, block-relative) cell coordinates `c` of block
/// `(i0, j0)`: x, y along the pillars' positions, z from the layer.
fn lattice_point(c: [f64; 3], (i0, j0): (usize, usize), xs: &[f64], ys: &[f64]) -> [f64; 3] {
    let along = |u: f64, p: &[f64]| {
        let f = u.floor().clamp(0.0, (p.len() - 2) as f64);
        p[f as usize] + (u - f) * (p[f as usize + 1] - p[f as usize])
    };
    [along(c[0] / 2.0 + i0 as f64, xs), along(c[1] / 2.0 + j0 as f64, ys), -c[2]]
}

/// Sample points of every triangle of level `h` of `tile`: (world position, interpolated cell
/// coordinates, the axes the triangle's coordinates are one cell's centre on).
fn samples(t: &TileMesh, h: usize) -> Vec<([f64; 3], [f64; 3], [bool; 3])> {
    let bary = [[1.0, 1.0, 1.0], [4.0, 1.0, 1.0], [1.0, 4.0, 1.0], [1.0, 1.0, 4.0], [2.0, 2.0, 1.0], [1.0, 2.0, 2.0]];
    let mut out = Vec::new();
    for tri in level_indices(t, h).chunks_exact(3) {
        let u = [0, 1, 2].map(|x| cells::unpack(t.grid_uv[tri[x] as usize]));
        let fixed = [0, 1, 2].map(|a| u[0][a] % 2 == 1 && u[1][a] == u[0][a] && u[2][a] == u[0][a]);
        for b in bary {
            let s = b[0] + b[1] + b[2];
            let mut p = [0.0; 3];
            let mut c = [0.0; 3];
            for (w, &v) in b.iter().zip(tri) {
                let u = cells::unpack(t.grid_uv[v as usize]);
                for a in 0..3 {
                    p[a] += w / s * t.positions[v as usize][a] as f64;
                    c[a] += w / s * u[a] as f64;
                }
            }
            out.push((p, c, fixed));
        }
    }
    out
}

#[test]
fn every_point_of_every_level_lies_in_the_cell_its_coordinates_name() {
    // Regular columns: the lattice's map is affine on every face, so coordinates are exact.
    let (ni, nj, nk) = (16, 12, 3);
    let (xs, ys) = (columns(ni, 0.0), columns(nj, 0.0));
    let c = box_on(&xs, &ys, nk);
    let values: Vec<f64> = (0..ni * nj * nk).map(|x| (x * 7919 % 101) as f64).collect();
    let g = CornerGrid { nk, nj, ni, corners: &c, active: None, region: None, values: Some(&values) };
    let b = build(&g, (8, 6));
    assert!(b.levels.len() >= 3, "levels merge: {}", b.levels.len());
    assert!(b.levels.last().unwrap().triangles * 4 < b.levels[0].triangles, "{:?}", b.levels);
    for t in &b.tiles {
        let (i0, j0) = (t.ix as usize * 8, t.iy as usize * 6);
        assert_eq!(t.grid_uv.len(), t.positions.len());
        let (dims, table) = cells::cell_table(t).unwrap();
        for h in 0..=t.levels.len() {
            assert_eq!(t.levels.get(h.wrapping_sub(1)).map_or(0.0, |l| l.error), 0.0, "regular grid: exact levels");
            for (p, cc, fixed) in samples(t, h) {
                let q = lattice_point(cc, (i0, j0), &xs, &ys);
                // Along the face exact; across it (a cell's centre) within half a cell; layers
                // by their range.
                for a in 0..2 {
                    let tol = if fixed[a] { 0.5 * 10.0 + 1e-3 } else { 1e-3 };
                    assert!((q[a] - p[a]).abs() <= tol, "level {h}: {p:?} has coordinates {cc:?} -> {q:?}");
                }
                assert!(fixed[2] && (-p[2] - cc[2]).abs() <= 1.0 + 1e-3, "level {h}: {p:?} in layer {cc:?}");
                let cell = cc.map(|x| (x / 2.0).floor() as usize);
                let (i, j, k) =
                    (i0 + cell[0].min(dims[0] as usize - 1), j0 + cell[1].min(dims[1] as usize - 1), cell[2]);
                let at = (cell[2] * dims[1] as usize + (j - j0)) * dims[0] as usize + (i - i0);
                assert_eq!(table[at], values[(k * nj + j) * ni + i] as f32, "level {h} at {p:?}");
            }
        }
    }
}

#[test]
fn irregular_columns_count_the_colour_drift_in_the_level_error() {
    // Columns 10, 15, 20 m wide in turn: a merged face interpolates the coordinates linearly, the
    // fine lattice does not; the level's error covers the difference.
    let (ni, nj, nk) = (16, 16, 2);
    let (xs, ys) = (columns(ni, 0.5), columns(nj, 0.5));
    let c = box_on(&xs, &ys, nk);
    let values: Vec<f64> = (0..ni * nj * nk).map(|x| x as f64).collect();
    let g = CornerGrid { nk, nj, ni, corners: &c, active: None, region: None, values: Some(&values) };
    let b = build(&g, (8, 8));
    let mut worst = 0.0f64;
    for t in &b.tiles {
        let (i0, j0) = (t.ix as usize * 8, t.iy as usize * 8);
        for h in 1..=t.levels.len() {
            let err = t.levels[h - 1].error as f64;
            for (p, cc, fixed) in samples(t, h) {
                let q = lattice_point(cc, (i0, j0), &xs, &ys);
                // How far the point is from where its coordinates put it, along the face.
                let d = (0..2).filter(|&a| !fixed[a]).map(|a| (q[a] - p[a]).powi(2)).sum::<f64>().sqrt();
                worst = worst.max(d);
                assert!(d <= err + 1e-3, "level {h}: a colour moves {d} m, error {err}");
            }
        }
    }
    assert!(worst > 1.0, "the grid is irregular enough to test: {worst}");
    // Without values the same grid merges by geometry alone: exact (flat faces).
    let g = CornerGrid { values: None, ..g };
    let plain = build(&g, (8, 8));
    for t in &plain.tiles {
        assert!(t.grid_uv.is_empty());
        assert!(t.levels.iter().all(|l| l.error < 1e-3), "{:?}", t.levels.iter().map(|l| l.error).collect::<Vec<_>>());
    }
}

#[test]
fn faulted_valued_grids_keep_pieces_flat_and_stay_watertight() {
    // Fault pieces are coloured flat by their cell's value and merge into strips only where
    // their values are equal.
    let (ni, nj, nk) = (6, 4, 3);
    let c = faulted(ni, nj, nk, 0.4, 3);
    let values: Vec<f64> = (0..ni * nj * nk).map(|x| x as f64).collect();
    let ones = vec![1.0; ni * nj * nk];
    let fault = |x: &KindCounts| x[0][super::faces::kind::FAULT_GAP as usize];
    let g = CornerGrid { nk, nj, ni, corners: &c, active: None, region: None, values: Some(&ones) };
    let b = build(&g, (6, 4));
    let top = b.levels.len() - 1;
    assert!(fault(&b.kinds[top]) < fault(&b.kinds[0]), "one value: strips");
    for h in 0..=top {
        watertight(&b.tiles, |_| h).unwrap();
    }
    let g = CornerGrid { values: Some(&values), ..g };
    let b = build(&g, (6, 4));
    assert_eq!(fault(&b.kinds[top]), fault(&b.kinds[0]), "values differ: no strips");
    let t = &b.tiles[0];
    for tri in t.fine.chunks_exact(3) {
        let flat = [0, 1, 2].map(|x| t.grid_uv[tri[x] as usize] == cells::FLAT);
        assert!(flat.iter().all(|&f| f == flat[0]), "a face is flat or not");
    }
    let (dims, table) = cells::cell_table(t).unwrap();
    assert_eq!(dims, [6, 4, 3]);
    for (x, v) in table.iter().enumerate() {
        let (i, j, k) = (x % 6, x / 6 % 4, x / 24);
        let interior = i > 0 && i < 5 && j > 0 && j < 3 && k > 0 && k < 2;
        // Cells with a drawn face know their value; interior cells (never drawn) are unset.
        if !(interior || i == 2 || i == 3) {
            assert_eq!(*v, values[(k * nj + j) * ni + i] as f32, "cell {i} {j} {k}");
        }
    }
}
