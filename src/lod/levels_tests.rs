//! Tests of `lod::levels`: level errors against brute-force measures, the lattice levels' shape.

use super::shading::Shading;
use super::*;
use crate::lod::lattice::fine_height;
use std::collections::HashMap;

fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f64) -> (Vec<Level>, Vec<f64>) {
    let z: Vec<f64> = (0..w * h).map(|k| f(k % w, k / w)).collect();
    let zz = z.clone();
    (lattice_levels(w, h, |i, j| (j * w + i) as u32, move |i, j| zz[j * w + i], &[]), z)
}

#[test]
fn level_errors_equal_the_brute_force_measure() {
    // Rough heights over tiles of several shapes: every level's error (square inner cells in
    // one pass, fans by their rows' spans) is the brute-force measure's over all its
    // triangles, samples inside and edge crossings.
    let mut rng = crate::TestRng(12345);
    let mut rnd = || rng.f();
    for (w, h) in [(42, 42), (57, 33), (9, 70), (65, 65)] {
        let z: Vec<f64> = (0..w * h).map(|_| 100.0 * rnd() - 1500.0).collect();
        let zz = z.clone();
        let levels = lattice_levels(w, h, |i, j| (j * w + i) as u32, move |i, j| zz[j * w + i], &[]);
        assert!(levels.len() >= 2, "{w} x {h}");
        for l in &levels {
            let tris = sample_triangles(&l.indices, w);
            let want = brute_error(&tris, &|i: usize, j: usize| z[j * w + i]) as f32;
            assert_eq!(lattice_error(&tris, &|i: usize, j: usize| z[j * w + i]) as f32, want);
            assert!((l.error - want).abs() <= 1e-6 * want.max(1.0), "{w} x {h}: {} vs {want}", l.error);
        }
    }
}

#[test]
fn a_spike_anywhere_is_measured_as_the_brute_force_measure_does() {
    // One raised sample at a time: whichever cell holds it (square, fan or short last cell),
    // every level's error is the brute-force measure's.
    let (w, h) = (19, 14);
    for s in 0..w * h {
        let z: Vec<f64> = (0..w * h).map(|k| if k == s { 7.0 } else { 0.1 * (k % 3) as f64 }).collect();
        let zz = z.clone();
        for l in lattice_levels(w, h, |i, j| (j * w + i) as u32, move |i, j| zz[j * w + i], &[]) {
            let tris = sample_triangles(&l.indices, w);
            let want = brute_error(&tris, &|i: usize, j: usize| z[j * w + i]) as f32;
            assert_eq!(l.error, want, "spike at {s}");
        }
    }
}

#[test]
fn no_point_of_a_level_is_further_from_the_fine_surface_than_its_error() {
    // Sampled densely (eighths of a cell, barycentric over every level triangle) on rough
    // heights: a level edge that crosses a cell's diagonal over a ridge must be measured
    // there, where neither grid line nor sample shows the distance.
    let mut rng = crate::TestRng(777);
    let mut rnd = || rng.f();
    for (w, h) in [(23, 23), (30, 17)] {
        let z: Vec<f64> = (0..w * h).map(|_| 50.0 * rnd()).collect();
        let zf = |i: usize, j: usize| z[j * w + i];
        let zz = z.clone();
        for l in lattice_levels(w, h, |i, j| (j * w + i) as u32, move |i, j| zz[j * w + i], &[]) {
            let seen = distance_sampled(&l.indices, (w, h), &zf);
            assert!(l.error as f64 >= seen * (1.0 - 1e-6), "{w} x {h}: error {} below {seen}", l.error);
        }
    }
}

/// A level's triangles as local samples (column, row) of a tile `w` samples wide whose vertex
/// k is sample (k % w, k / w).
fn sample_triangles(indices: &[u32], w: usize) -> Vec<[(usize, usize); 3]> {
    indices.chunks_exact(3).map(|t| [0, 1, 2].map(|c| (t[c] as usize % w, t[c] as usize / w))).collect()
}

/// The reference measure: every sample of each triangle's box tested for inclusion, and
/// every crossing of its edges with the grid lines and the cells' diagonals.
fn brute_error(tris: &[[(usize, usize); 3]], z: &impl Fn(usize, usize) -> f64) -> f64 {
    let max = tris.iter().flatten().fold((1, 1), |m, &(i, j)| (m.0.max(i), m.1.max(j)));
    let mut err = 0.0f64;
    for t in tris {
        let p = t.map(|(i, j)| (i as f64, j as f64, z(i, j)));
        let det = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
        if det == 0.0 {
            continue;
        }
        for j in 0..=max.1 {
            for i in 0..=max.0 {
                let (x, y) = (i as f64, j as f64);
                let l1 = ((x - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (y - p[0].1)) / det;
                let l2 = ((p[1].0 - p[0].0) * (y - p[0].1) - (x - p[0].0) * (p[1].1 - p[0].1)) / det;
                let l0 = 1.0 - l1 - l2;
                if l0 >= -1e-9 && l1 >= -1e-9 && l2 >= -1e-9 {
                    err = err.max((z(i, j) - (l0 * p[0].2 + l1 * p[1].2 + l2 * p[2].2)).abs());
                }
            }
        }
        for e in 0..3 {
            let (a, b) = (p[e], p[(e + 1) % 3]);
            for (u, v) in [(a.0, b.0), (a.1, b.1), (a.0 - a.1, b.0 - b.1)] {
                if u != v {
                    for g in (u.min(v).ceil() as i64)..=(u.max(v).floor() as i64) {
                        let s = (g as f64 - u) / (v - u);
                        let (x, y) = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
                        err = err.max((fine_height(x, y, z, max) - (a.2 + s * (b.2 - a.2))).abs());
                    }
                }
            }
        }
    }
    err
}

/// Undirected edge -> number of triangles using it.
fn edges(idx: &[u32]) -> HashMap<(u32, u32), usize> {
    let mut m = HashMap::new();
    for t in idx.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *m.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    m
}

#[test]
fn lattice_levels_quarter_keep_the_border_and_cover_the_tile() {
    let (w, h) = (65, 49);
    let (levels, _) = grid(w, h, |i, j| ((i * 7 + j * 3) % 5) as f64);
    assert!(levels.len() >= 3, "{}", levels.len());
    let mut prev = 2 * (w - 1) * (h - 1);
    for lv in &levels {
        let n = lv.indices.len() / 3;
        assert!(n as f64 <= 0.6 * prev as f64, "{n} vs {prev}");
        prev = n;
        // Every fine border edge is an edge of the level, used once: the same border as level 0.
        let e = edges(&lv.indices);
        let id = |i: usize, j: usize| (j * w + i) as u32;
        for i in 0..w - 1 {
            for j in [0, h - 1] {
                let (a, b) = (id(i, j), id(i + 1, j));
                assert_eq!(e.get(&(a.min(b), a.max(b))), Some(&1), "border edge ({i},{j})");
            }
        }
        for j in 0..h - 1 {
            for i in [0, w - 1] {
                let (a, b) = (id(i, j), id(i, j + 1));
                assert_eq!(e.get(&(a.min(b), a.max(b))), Some(&1), "border edge ({i},{j})");
            }
        }
        // Interior edges are shared by two triangles: a closed disc, no holes or overlaps.
        let border = 2 * (w - 1) + 2 * (h - 1);
        assert_eq!(e.values().filter(|&&c| c == 1).count(), border);
        assert!(e.values().all(|&c| c <= 2));
        // Counter-clockwise and covering the tile: signed areas add up to the tile's area.
        let pos = |k: u32| ((k as usize % w) as f64, (k as usize / w) as f64);
        let area: f64 = lv
            .indices
            .chunks_exact(3)
            .map(|t| {
                let (a, b, c) = (pos(t[0]), pos(t[1]), pos(t[2]));
                let s = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
                assert!(s > 0.0, "triangle {t:?} is not counter-clockwise");
                s / 2.0
            })
            .sum();
        assert!((area - ((w - 1) * (h - 1)) as f64).abs() < 1e-9);
    }
}

#[test]
fn lattice_error_is_zero_on_planes_and_exact_on_a_bump() {
    let (levels, _) = grid(17, 17, |i, j| 2.0 * i as f64 - 0.5 * j as f64 + 3.0);
    assert!(!levels.is_empty() && levels.iter().all(|l| l.error < 1e-5));
    // A single raised sample off every lattice: each level that skips it misses it by its height.
    let (levels, _) = grid(17, 17, |i, j| if (i, j) == (5, 7) { 4.0 } else { 0.0 });
    assert!(
        levels.iter().all(|l| (l.error - 4.0).abs() < 1e-5),
        "{:?}",
        levels.iter().map(|l| l.error).collect::<Vec<_>>()
    );
}

/// A 33 × 33 vertex sheet z = f(x, y) as a mesh: positions, fine triangles, smooth normals.
fn mesh_sheet(f: impl Fn(f64, f64) -> f64) -> (Vec<[f32; 3]>, Vec<u32>, Vec<u32>) {
    let n = 33;
    let v: Vec<[f64; 3]> =
        (0..n * n).map(|k| [(k % n) as f64, (k / n) as f64, f((k % n) as f64, (k / n) as f64)]).collect();
    let faces = super::super::normals::sheet_faces(n);
    let normals = super::super::normals::smooth_normals(&v, &faces).expect("smooth");
    let pos = v.iter().map(|p| p.map(|c| c as f32)).collect();
    (pos, faces.into_iter().flatten().collect(), normals)
}

#[test]
fn simplified_levels_of_a_curved_sheet_have_a_shading_error_and_a_flat_ones_none() {
    let (pos, fine, normals) = mesh_sheet(|x, y| 3.0 * (x / 6.0).sin() + 0.05 * y * y);
    let levels = simplified_levels(&pos, &fine, Some(Shading { normals: &normals, grid_uv: &[] }));
    assert!(levels.len() >= 2, "{}", levels.len());
    assert!(
        levels.iter().all(|l| l.shading_error > 1e-3),
        "{:?}",
        levels.iter().map(|l| l.shading_error).collect::<Vec<_>>()
    );
    // Coarser levels turn the normals further.
    assert!(levels.last().unwrap().shading_error > levels[0].shading_error);
    // Facet shading (no normals) is measured too; a tile shaded from its fine surface is not.
    assert!(simplified_levels(&pos, &fine, Some(Shading::default())).iter().all(|l| l.shading_error > 1e-3));
    assert!(simplified_levels(&pos, &fine, None).iter().all(|l| l.shading_error == 0.0));
    let (pos, fine, normals) = mesh_sheet(|x, y| 0.4 * x - 0.3 * y + 7.0);
    let levels = simplified_levels(&pos, &fine, Some(Shading { normals: &normals, grid_uv: &[] }));
    assert!(!levels.is_empty());
    assert!(
        levels.iter().all(|l| l.shading_error < 1e-4),
        "{:?}",
        levels.iter().map(|l| l.shading_error).collect::<Vec<_>>()
    );
}

#[test]
fn grid_level_error_is_exact_and_refuses_triangles_over_holes() {
    // 5 x 5 samples, the sample (3, 3) undefined (its four cells lose one or two triangles).
    let (w, h) = (5usize, 5usize);
    let hole = |i: usize, j: usize| (i, j) == (3, 3);
    let bump = |i: usize, j: usize| if (i, j) == (1, 1) { 2.0 } else { 0.5 * i as f64 };
    let at: Vec<[u32; 2]> = (0..w * h).map(|k| [(k % w) as u32, (k / w) as u32]).collect();
    let zk: Vec<f64> = (0..w * h).map(|k| bump(k % w, k / w)).collect();
    let z = |i: usize, j: usize| if hole(i, j) { f64::NAN } else { bump(i, j) };
    let id = |i: usize, j: usize| (j * w + i) as u32;
    // The fine triangles themselves: no error.
    let mut fine = Vec::new();
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if ![(i, j), (i + 1, j), (i + 1, j + 1)].iter().any(|&(x, y)| hole(x, y)) {
                fine.extend([a, b, c]);
            }
            if ![(i, j), (i + 1, j + 1), (i, j + 1)].iter().any(|&(x, y)| hole(x, y)) {
                fine.extend([a, c, d]);
            }
        }
    }
    assert_eq!(grid_level_error((w, h), z, (&at, &zk), &fine), Some(0.0));
    // The lower-left 2 x 2 cells as two triangles miss the bump at (1, 1) by its height over the
    // plane z = 0.5 i there (2 - 0.5); the rest of the fine triangles as they are.
    let mut level: Vec<u32> = vec![id(0, 0), id(2, 0), id(2, 2), id(0, 0), id(2, 2), id(0, 2)];
    let corner = |t: &[u32]| t.iter().all(|&k| (k as usize % w) <= 2 && (k as usize / w) <= 2);
    level.extend(fine.chunks_exact(3).filter(|t| !corner(t)).flatten());
    let e = grid_level_error((w, h), z, (&at, &zk), &level).unwrap();
    assert!((e - 1.5).abs() < 1e-12, "{e}");
    // A vertical sliver over the first row, its middle corner 4.5 above the fine surface there.
    let mut zk2 = zk.clone();
    let top = zk2.len() as u32;
    let mut at2 = at.clone();
    at2.push([1, 0]);
    zk2.push(5.0);
    let mut sliver = fine.clone();
    sliver.extend([id(0, 0), top, id(2, 0)]);
    let e = grid_level_error((w, h), z, (&at2, &zk2), &sliver).unwrap();
    assert!((e - 4.5).abs() < 1e-12, "{e}");
    // A level triangle over the hole, or one missing (a gap): no bound.
    let mut over = fine.clone();
    over.extend([id(2, 2), id(4, 2), id(4, 4)]);
    assert_eq!(grid_level_error((w, h), z, (&at, &zk), &over), None);
    assert_eq!(grid_level_error((w, h), z, (&at, &zk), &fine[3..]), None);
}

#[test]
fn small_tiles_have_no_levels() {
    assert!(grid(2, 9, |_, _| 0.0).0.is_empty());
    assert!(grid(3, 3, |_, _| 0.0).0.is_empty());
}

/// The largest vertical distance between the triangles `indices` of a tile of `w` × `h` samples
/// (vertex k: sample (k % w, k / w)) and its fine surface of heights `zf`, sampled at eighths of a
/// cell over each triangle (barycentric): a level edge that crosses a cell's diagonal over a ridge
/// is measured there too. (Also `lod::groups`' tests.)
pub(in crate::lod) fn distance_sampled(
    indices: &[u32],
    (w, h): (usize, usize),
    zf: &impl Fn(usize, usize) -> f64,
) -> f64 {
    let mut seen = 0.0f64;
    for t in sample_triangles(indices, w) {
        let p = t.map(|(i, j)| (i as f64, j as f64, zf(i, j)));
        let n = 8 * t.iter().map(|q| q.0.abs_diff(t[0].0) + q.1.abs_diff(t[0].1)).max().unwrap().max(1);
        for a in 0..=n {
            for b in 0..=n - a {
                let (u, v) = (a as f64 / n as f64, b as f64 / n as f64);
                let c = 1.0 - u - v;
                let (x, y) = (c * p[0].0 + u * p[1].0 + v * p[2].0, c * p[0].1 + u * p[1].1 + v * p[2].1);
                let g = c * p[0].2 + u * p[1].2 + v * p[2].2;
                seen = seen.max((fine_height(x, y, zf, (w - 1, h - 1)) - g).abs());
            }
        }
    }
    seen
}

#[test]
fn exaggeration_stretches_only_the_vertical_part_of_an_error() {
    // A vertical error grows by the exaggeration, a horizontal one not at all, and flattening
    // shrinks nothing; between, the length of (e_xy, s e_z) at its largest.
    assert!((exaggerated(2.0, 2.0, 5.0) - 10.0).abs() < 1e-12);
    assert_eq!(exaggerated(2.0, 0.0, 10.0), 2.0);
    assert_eq!(exaggerated(2.0, 2.0, 0.5), 2.0);
    let (e, ez, s) = (5.0f32, 3.0f32, 4.0f64);
    let want = (4.0f64 * 4.0 + (s * 3.0).powi(2)).sqrt(); // e_xy = 4 when e_z = 3 takes the rest
    assert!((exaggerated(e, ez, s) - want).abs() < 1e-9);
    // An error_z above the error (damaged) counts as the error.
    assert!((exaggerated(1.0, 7.0, 3.0) - 3.0).abs() < 1e-12);
}
