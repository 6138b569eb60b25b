//! Tiles of a planar lattice: a seismic slice, the samples of a volume on one of its planes.
//!
//! Contract of [`tile_plane`]: given `nu` × `nv` world positions (row-major, vertex `v nu + u`)
//! that lie on one plane (affine in (u, v), as a regular volume's samples on a plane do) and
//! optional per-vertex attributes (one per position each):
//! * the tiles are blocks of whole cells, at most `block` a side, cut by [`super::tile_bounds`]
//!   (neighbours share their border samples), tile (ix, iy) = (column, row) of blocks;
//! * each tile's fine triangles are its cells' two triangles with the diagonal from (u, v) to
//!   (u + 1, v + 1) and the winding of [`crate::scene::slice::lattice_faces`], so the tiles'
//!   triangles together are exactly the lattice's, with the same positions (f32 of position minus
//!   `origin`) and attributes as [`super::tile_mesh`] gives each vertex;
//! * its coarse proxy is the two triangles over its four corner samples (the plane itself, with
//!   the same diagonal), its `proxy_error` the largest distance of its positions (as stored) from
//!   that proxy's plane, rounded up: 0 up to f32 round-off, where a mesh's quadric simplification
//!   costs most of the build of a large slice (1024 × 1024: ~1 s of a move's 1.2 s);
//! * levels as [`super::tile_mesh`] makes them (none for a lattice coloured by data, a slice).
//!
//! Once `stop` is set, tiles not yet started are left empty.

use super::{tile_bounds, Indices, TileMesh, VertexAttributes, Work};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// The tiles of the `nu` x `nv` lattice of `positions` (see the module's contract).
pub fn tile_plane(
    positions: &[[f64; 3]],
    attrs: VertexAttributes<'_>,
    (nu, nv): (usize, usize),
    origin: DVec3,
    block: usize,
    coarse_factor: f32,
    stop: &Work,
) -> Vec<TileMesh> {
    assert!(nu >= 2 && nv >= 2 && positions.len() == nu * nv && block >= 1, "tile_plane: a {nu} x {nv} lattice");
    let us = tile_bounds(nu, (nu - 1).div_ceil(block));
    let vs = tile_bounds(nv, (nv - 1).div_ceil(block));
    let (tu, tv) = (us.len() - 1, vs.len() - 1);
    // The tiles' few shapes (even cuts: two widths and two heights at most), each one triangle
    // list that its tiles share.
    let sides = |b: &[usize]| {
        let mut s: Vec<usize> = b.windows(2).map(|p| p[1] - p[0] + 1).collect();
        s.sort_unstable();
        s.dedup();
        s
    };
    let lists: Vec<((usize, usize), Indices)> = sides(&us)
        .into_iter()
        .flat_map(|w| sides(&vs).into_iter().map(move |h| ((w, h), Indices::from(cells(w, h)))))
        .collect();
    stop.set_total(tu * tv);
    (0..tu * tv)
        .into_par_iter()
        .map(|t| {
            if stop.load(Ordering::Relaxed) {
                return TileMesh::default();
            }
            let (ix, iy) = (t % tu, t / tu);
            let (u0, u1, v0, v1) = (us[ix], us[ix + 1], vs[iy], vs[iy + 1]);
            let mut tile = TileMesh { ix: ix as u32, iy: iy as u32, ..Default::default() };
            for v in v0..=v1 {
                for u in u0..=u1 {
                    let k = v * nu + u;
                    tile.positions.push((DVec3::from_array(positions[k]) - origin).as_vec3().to_array());
                    if let Some(vals) = attrs.values {
                        tile.values.push(vals[k] as f32);
                    }
                    if let Some(ns) = attrs.normals {
                        tile.normals.push(ns[k]);
                    }
                    if let Some(uv) = attrs.grid_uv {
                        tile.grid_uv.push(uv[k]);
                    }
                }
            }
            let w = u1 - u0 + 1;
            let h = v1 - v0 + 1;
            let corners = [0, w - 1, h * w - 1, (h - 1) * w].map(|k| k as u32);
            let coarse = vec![corners[0], corners[1], corners[2], corners[0], corners[2], corners[3]];
            let error = off_plane(&tile.positions, corners);
            // Every cut's width and height is listed, so every tile's shape is.
            tile.fine = lists.iter().find(|(shape, _)| *shape == (w, h)).expect("a listed tile shape").1.clone();
            tile.finish(coarse_factor, Some((coarse, error)), false)
        })
        .inspect(|_| stop.item_done())
        .collect()
}

/// The triangle list of a `w` x `h` lattice (row-major local vertices), two triangles per cell.
fn cells(w: usize, h: usize) -> Vec<u32> {
    let mut out = Vec::with_capacity(6 * (w - 1) * (h - 1));
    for v in 0..h - 1 {
        for u in 0..w - 1 {
            let a = (v * w + u) as u32;
            let (b, c, d) = (a + 1, a + 1 + w as u32, a + w as u32);
            out.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    out
}

/// The largest distance of `positions` from the plane through the corners `c[0]`, `c[1]`, `c[3]`
/// (f64 from the stored f32), rounded up to f32; the largest corner-to-corner extent where the
/// corners span no plane (a degenerate lattice: no tighter bound is claimed).
fn off_plane(positions: &[[f32; 3]], c: [u32; 4]) -> f32 {
    let p = |k: u32| DVec3::from_array(positions[k as usize].map(f64::from));
    let (o, a, b) = (p(c[0]), p(c[1]), p(c[3]));
    let n = (a - o).cross(b - o);
    let len = n.length();
    let extent = [a, b, p(c[2])].iter().map(|q| (*q - o).length()).fold(0.0, f64::max);
    if len <= 1e-12 * extent * extent || !len.is_finite() {
        return super::f32_at_least(extent);
    }
    let n = n / len;
    let worst = positions.iter().map(|q| (DVec3::from_array(q.map(f64::from)) - o).dot(n).abs()).fold(0.0, f64::max);
    super::f32_at_least(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tilted plane's lattice, `nu` x `nv`, values = the vertex number.
    fn plane(nu: usize, nv: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
        let p = (0..nu * nv)
            .map(|k| {
                let (u, v) = ((k % nu) as f64, (k / nu) as f64);
                [1000.0 + 12.5 * u + 3.0 * v, 2000.0 - 4.0 * u + 12.5 * v, -1500.0 + 0.5 * u - 4.0 * v]
            })
            .collect();
        (p, (0..nu * nv).map(|k| k as f64).collect())
    }

    #[test]
    fn tiles_hold_the_lattice_triangles_once_with_their_positions_and_values() {
        let (nu, nv) = (37, 21);
        let (pos, vals) = plane(nu, nv);
        let origin = DVec3::new(1000.0, 2000.0, -1500.0);
        let attrs = VertexAttributes { values: Some(&vals), ..Default::default() };
        let tiles = tile_plane(&pos, attrs, (nu, nv), origin, 8, 25.0, &Work::default());
        assert_eq!(tiles.len(), 5 * 3);
        // Every lattice triangle once, by its vertices' values (= their numbers), winding kept.
        let mut got: Vec<[i64; 3]> = tiles
            .iter()
            .flat_map(|t| {
                t.fine.chunks_exact(3).map(|f| [0, 1, 2].map(|i| t.values[f[i] as usize] as i64)).collect::<Vec<_>>()
            })
            .collect();
        // The lattice's triangles as `scene::slice::lattice_faces` lists them.
        let mut want: Vec<[i64; 3]> = (0..nv - 1)
            .flat_map(|v| (0..nu - 1).map(move |u| (v * nu + u) as i64))
            .flat_map(|a| [[a, a + 1, a + 1 + nu as i64], [a, a + 1 + nu as i64, a + nu as i64]])
            .collect();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want);
        // Tiles of one shape (cut by tile_bounds into 5 x 3) share one triangle list.
        let (us, vs) = (tile_bounds(nu, 5), tile_bounds(nv, 3));
        let shape = |t: &TileMesh| {
            let (i, j) = (t.ix as usize, t.iy as usize);
            (us[i + 1] - us[i], vs[j + 1] - vs[j])
        };
        for a in &tiles {
            for b in &tiles {
                assert_eq!(std::sync::Arc::ptr_eq(&a.fine, &b.fine), shape(a) == shape(b));
            }
        }
        for t in &tiles {
            for (p, &v) in t.positions.iter().zip(&t.values) {
                let q = pos[v as usize];
                assert_eq!(*p, (DVec3::from_array(q) - origin).as_vec3().to_array());
            }
            assert!(t.levels.is_empty(), "a lattice coloured by data keeps its full resolution");
        }
    }

    #[test]
    fn the_coarse_proxy_is_the_tile_corners_plane_within_its_error() {
        let (nu, nv) = (30, 30);
        let (pos, _) = plane(nu, nv);
        let tiles = tile_plane(&pos, VertexAttributes::default(), (nu, nv), DVec3::ZERO, 16, 25.0, &Work::default());
        for t in &tiles {
            assert_eq!(t.coarse_triangles(), 2);
            // Far from the origin, f32 positions leave the plane by round-off only.
            assert!(t.proxy_error > 0.0 && t.proxy_error < 1e-3, "{}", t.proxy_error);
            // The proxy's corners are the tile box's extremes: it spans the tile.
            let (lo, hi) = t.tight_bbox();
            let cs: Vec<[f32; 3]> = t.coarse.iter().map(|&k| t.positions[k as usize]).collect();
            for a in 0..3 {
                assert_eq!(cs.iter().map(|c| c[a]).fold(f32::INFINITY, f32::min), lo[a]);
                assert_eq!(cs.iter().map(|c| c[a]).fold(f32::NEG_INFINITY, f32::max), hi[a]);
            }
        }
        // A bent "plane" is measured, not assumed: the bend is the error.
        let mut bent = pos.clone();
        bent[15 * nu + 15][2] += 7.0;
        let tiles = tile_plane(&bent, VertexAttributes::default(), (nu, nv), DVec3::ZERO, 64, 25.0, &Work::default());
        assert_eq!(tiles.len(), 1);
        let n = DVec3::new(12.5, -4.0, 0.5).cross(DVec3::new(3.0, 12.5, -4.0)).normalize();
        let want = 7.0 * n.z.abs();
        assert!((tiles[0].proxy_error as f64 - want).abs() < 1e-3, "{} vs {want}", tiles[0].proxy_error);
    }

    #[test]
    fn a_set_stop_leaves_tiles_empty() {
        let (pos, _) = plane(20, 20);
        let stop = Work::default();
        stop.store(true, Ordering::Relaxed);
        let tiles = tile_plane(&pos, VertexAttributes::default(), (20, 20), DVec3::ZERO, 4, 25.0, &stop);
        assert!(tiles.iter().all(TileMesh::is_empty));
    }
}
