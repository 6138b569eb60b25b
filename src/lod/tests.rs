//! Tests of tiling, proxies, sub-boxes and occludee boxes (`super`).

use super::*;

#[test]
fn structured_grids_are_recognised_in_any_face_order_and_winding() {
    let (nu, nv) = (5usize, 4usize);
    let mut faces = Vec::new();
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let a = (j * nu + i) as u32;
            let (b, c, d) = (a + 1, a + nu as u32, a + nu as u32 + 1);
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
    }
    assert_eq!(structured_grid(nu * nv, &faces), Some((nu, nv)));
    let mut shuffled: Vec<[u32; 3]> = faces.iter().step_by(2).chain(faces.iter().skip(1).step_by(2)).copied().collect();
    shuffled.reverse();
    shuffled[3] = [shuffled[3][2], shuffled[3][1], shuffled[3][0]];
    assert_eq!(structured_grid(nu * nv, &shuffled), Some((nu, nv)));
    // Another diagonal, a missing or repeated face, a wrong vertex count: not this grid.
    let mut other = faces.clone();
    other[0] = [0, 1, nu as u32];
    assert_eq!(structured_grid(nu * nv, &other), None);
    assert_eq!(structured_grid(nu * nv, &faces[1..]), None);
    let mut twice = faces.clone();
    twice[2] = twice[0];
    assert_eq!(structured_grid(nu * nv, &twice), None);
    assert_eq!(structured_grid(nu * nv + 1, &faces), None);
}

#[test]
fn bounds_share_ends_and_cover() {
    assert_eq!(tile_bounds(11, 2), vec![0, 5, 10]);
    assert_eq!(tile_bounds(2, 1), vec![0, 1]);
    let b = tile_bounds(500, 10);
    assert_eq!((b[0], b[10]), (0, 499));
}

#[test]
fn grid_triangles_and_holes() {
    let (nx, ny) = (5, 4);
    let mut z = vec![0.0; nx * ny];
    let g = GridSpec { z: &z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, rot: (1.0, 0.0), yflip: false, values: None };
    let tiles = tile_heightfield(&g, DVec3::ZERO, (2, 3), 1.0, &Work::default()).0;
    let total: usize = tiles.iter().map(|t| t.fine_triangles()).sum();
    assert_eq!(total, 2 * (nx - 1) * (ny - 1));
    // One NaN sample in the interior removes the 6 triangles touching it.
    z[nx + 2] = f64::NAN;
    let g = GridSpec { z: &z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, rot: (1.0, 0.0), yflip: false, values: None };
    let tiles = tile_heightfield(&g, DVec3::ZERO, (1, 1), 1.0, &Work::default()).0;
    assert_eq!(tiles[0].fine_triangles(), 2 * (nx - 1) * (ny - 1) - 6);
    assert!(tiles[0].positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
}

#[test]
fn lattice_proxy_reaches_the_factor_and_neighbours_share_border_samples() {
    let (nx, ny) = (81, 81);
    let z: Vec<f64> = (0..nx * ny).map(|k| ((k % nx) as f64 * 0.3).sin() + ((k / nx) as f64 * 0.2).cos()).collect();
    let g = GridSpec { z: &z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, rot: (1.0, 0.0), yflip: false, values: None };
    for (cf, want) in [(25.0, 25.0), (100.0, 100.0), (400.0, 400.0)] {
        let tiles = tile_heightfield(&g, DVec3::ZERO, (2, 2), cf, &Work::default()).0;
        let fine: usize = tiles.iter().map(|t| t.fine_triangles()).sum();
        let coarse: usize = tiles.iter().map(|t| t.coarse_triangles()).sum();
        let ratio = fine as f64 / coarse as f64;
        assert!(ratio > want * 0.5 && ratio < want * 1.5, "factor {cf}: {fine}/{coarse}");
        // Tiles (0,0) and (1,0) share the column x = 40: both proxies keep the same samples there.
        let on_seam = |t: &TileMesh| {
            let mut ys: Vec<i64> = t
                .coarse
                .iter()
                .map(|&k| t.positions[k as usize])
                .filter(|p| p[0] == 40.0)
                .map(|p| p[1] as i64)
                .collect();
            ys.sort();
            ys.dedup();
            ys
        };
        assert_eq!(on_seam(&tiles[0]), on_seam(&tiles[1]));
        assert_eq!(on_seam(&tiles[0]).first(), Some(&0));
        assert_eq!(on_seam(&tiles[0]).last(), Some(&40));
    }
}

/// One tile of a 21 x 21 height field at unit spacing sloping along x (0.5 a column, a slight
/// ripple along y), its first 10 x 10 samples a hole.
fn sloping_tile_with_a_hole() -> TileMesh {
    let (nx, ny) = (21, 21);
    let mut z: Vec<f64> = (0..nx * ny).map(|k| 0.5 * (k % nx) as f64 + 0.1 * ((k / nx) as f64).sin()).collect();
    for j in 0..10 {
        for i in 0..10 {
            z[j * nx + i] = f64::NAN;
        }
    }
    let g = GridSpec { z: &z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, rot: (1.0, 0.0), yflip: false, values: None };
    tile_heightfield(&g, DVec3::ZERO, (1, 1), 4.0, &Work::default()).0.remove(0)
}

/// Every fine triangle lies in one of its tile's sub-boxes; on a sloping tile the 2 × 2
/// sub-boxes hold half the volume of the tile's box; cells without triangles (a hole) get
/// none; equal triangle lists are shared.
#[test]
fn sub_boxes_hold_the_triangles_tighter_than_the_box() {
    let mut tiles = vec![sloping_tile_with_a_hole()];
    let t = &tiles[0];
    let boxes = t.sub_boxes(2);
    assert_eq!(boxes.len(), 3, "the hole's cell has no triangles");
    assert_boxes_hold_fine_triangles(t, &boxes);
    let (sum, whole) = (boxes_volume(&boxes), boxes_volume(&[(t.bbox_min, t.bbox_max)]));
    assert!(sum < 0.5 * whole, "{sum} {whole}");
    let mut twins = vec![tiles[0].clone(), tiles.remove(0)];
    twins[1].fine = twins[0].fine.to_vec().into();
    assert!(!std::sync::Arc::ptr_eq(&twins[0].fine, &twins[1].fine));
    share_indices(&mut twins);
    assert!(std::sync::Arc::ptr_eq(&twins[0].fine, &twins[1].fine));
}

/// A height-field tile's quarters of its height blocks (the sub-boxes the upload reads off the
/// blocks instead of passing over the triangles) hold every fine triangle, also around a hole,
/// and on a sloping tile span little more than the 2 x 2 sub-boxes (its 3 x 3 blocks halve as 2
/// and 1: quarters of 13 and 7 cells a side against 10 and 10).
#[test]
fn quarter_boxes_of_the_height_blocks_hold_the_triangles() {
    let t = &sloping_tile_with_a_hole();
    let at = |li: usize, lj: usize| t.positions.iter().copied().find(|p| (p[0], p[1]) == (li as f32, lj as f32));
    let quarters = blocks::height_blocks(21, 21, at).quarter_boxes();
    assert_eq!(quarters.len(), 4);
    assert_boxes_hold_fine_triangles(t, &quarters);
    let (sum, subs) = (boxes_volume(&quarters), boxes_volume(&t.sub_boxes(2)));
    assert!(sum < 1.5 * subs, "{sum} {subs}");
}

/// A slanted tube's tile: its 8 slices along its length hold every fine triangle and a
/// fraction of the 2 x 2 sub-boxes' volume, so `occludee_boxes` takes them; a square height
/// field sloping along x keeps its sub-boxes (its slices, across y of the tied longest sides,
/// span its whole height).
#[test]
fn occludee_boxes_follow_a_tube_and_hold_its_triangles() {
    let path: Vec<DVec3> = (0..=64).map(|k| DVec3::new(k as f64, 0.5 * k as f64, -0.8 * k as f64)).collect();
    let (v, f, _) = tube::tube(&path, 0.5, 8);
    let mut t = TileMesh {
        positions: v.iter().map(|p| p.map(|c| c as f32)).collect(),
        fine: f.iter().flat_map(|t| t.map(|k| k as u32)).collect::<Vec<_>>().into(),
        ..Default::default()
    };
    t.compute_bbox();
    let slices = t.slice_boxes(8);
    assert_eq!(slices.len(), 8);
    let (sliced, grid) = (boxes_volume(&slices), boxes_volume(&t.sub_boxes(2)));
    assert!(sliced < 0.2 * grid, "{sliced} {grid}");
    assert_eq!(t.occludee_boxes(), slices);
    assert_boxes_hold_fine_triangles(&t, &slices);
    let z: Vec<f64> = (0..21 * 21).map(|k| 0.5 * (k % 21) as f64).collect();
    let g = GridSpec {
        z: &z,
        nx: 21,
        ny: 21,
        x0: 0.0,
        y0: 0.0,
        dx: 1.0,
        dy: 1.0,
        rot: (1.0, 0.0),
        yflip: false,
        values: None,
    };
    let hf = &tile_heightfield(&g, DVec3::ZERO, (1, 1), 4.0, &Work::default()).0[0];
    assert_eq!(hf.occludee_boxes(), hf.sub_boxes(2));
}

#[test]
fn all_nan_tile_is_empty() {
    let z = vec![f64::NAN; 9];
    let g = GridSpec {
        z: &z,
        nx: 3,
        ny: 3,
        x0: 0.0,
        y0: 0.0,
        dx: 1.0,
        dy: 1.0,
        rot: (1.0, 0.0),
        yflip: false,
        values: None,
    };
    let tiles = tile_heightfield(&g, DVec3::ZERO, (2, 2), 4.0, &Work::default()).0;
    assert!(tiles.iter().all(|t| t.is_empty() && t.coarse.is_empty()));
}

/// Every fine triangle of `t` lies in one of `boxes`.
fn assert_boxes_hold_fine_triangles(t: &TileMesh, boxes: &[([f32; 3], [f32; 3])]) {
    for tri in t.fine.chunks_exact(3) {
        let p = [tri[0], tri[1], tri[2]].map(|k| t.positions[k as usize]);
        let inside = |(l, h): &([f32; 3], [f32; 3])| p.iter().all(|q| (0..3).all(|d| l[d] <= q[d] && q[d] <= h[d]));
        assert!(boxes.iter().any(inside), "{p:?}");
    }
}
