use super::*;

fn opts() -> AddOptions {
    AddOptions::new(1.0)
}

#[test]
fn utm_origin_keeps_precision() {
    let mut s = Scene::new();
    let z = vec![-2500.0; 4];
    s.add_heightfield(&z, 2, 2, GridFrame::new([450_000.0, 6_780_000.0], [10.0, 10.0]), (1, 1), None, opts()).unwrap();
    let z2 = vec![-2500.5; 4];
    s.add_heightfield(&z2, 2, 2, GridFrame::new([450_000.0, 6_780_000.0], [10.0, 10.0]), (1, 1), None, opts()).unwrap();
    let (a, _) = s.geometry(0).unwrap();
    let (b, _) = s.geometry(1).unwrap();
    assert_eq!(a[0][0], 450_000.0);
    assert!((a[0][2] - b[0][2] - 0.5).abs() < 1e-6);
}

/// The normal map's gradients are the world gradient of a plane z = a x + b y, whatever the
/// grid's rotation and row direction, and its heights the plane's, holes included (filled
/// from their neighbours).
#[test]
fn shading_samples_of_a_plane_in_every_grid_frame() {
    let (a, b) = (0.3, -0.7);
    for (rotation, yflip) in [(0.0, false), (30.0, false), (-112.5, true), (90.0, true)] {
        let frame = GridFrame::new([1000.0, 2000.0], [5.0, 8.0]).rotated(rotation, yflip);
        let (c, s) = crate::lod::cos_sin_deg(rotation);
        let (nx, ny) = (7, 6);
        let mut plane = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (u, v) = (i as f64 * 5.0, j as f64 * 8.0 * if yflip { -1.0 } else { 1.0 });
                let (x, y) = (c * u - s * v, s * u + c * v);
                plane.push(a * x + b * y);
            }
        }
        let mut z = plane.clone();
        z[2 * nx + 3] = f64::NAN;
        let mut sc = Scene::new();
        let id = sc.add_heightfield(&z, ny, nx, frame, (2, 2), None, opts()).unwrap();
        let o = sc.object(id).unwrap();
        let g = o.shading_samples().unwrap();
        assert_eq!(g.len(), nx * ny);
        for (k, gk) in g.iter().enumerate() {
            assert!((gk[0] as f64 - a).abs() < 1e-4 && (gk[1] as f64 - b).abs() < 1e-4, "{rotation} {k} {gk:?}");
            // The hole (3, 2) gets its neighbours' mean: the plane's height there too.
            assert!((gk[2] as f64 + o.origin.z - plane[k]).abs() < 1e-3, "{rotation} {k} {gk:?}");
        }
    }
    let mut sc = Scene::new();
    let id = sc.add_mesh(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]], "fault", None, opts()).unwrap();
    assert!(sc.object(id).unwrap().shading_samples().is_none());
}

/// Every vertex of every tile is the sample its lattice coordinates name: rebuilding it as
/// the vertex stage does (corner + column u + row v in f32, height from the normal map) gives
/// the stored f32 vertex within a few units in the last place, in every grid frame, holes
/// included; a mesh has no lattice.
#[test]
fn tile_lattices_rebuild_the_vertices() {
    for (rotation, yflip) in [(0.0, false), (30.0, false), (-112.5, true), (90.0, true)] {
        let frame = GridFrame::new([451_000.0, 6_780_000.0], [12.5, 25.0]).rotated(rotation, yflip);
        let (nx, ny) = (23, 17);
        let mut z: Vec<f64> = (0..nx * ny).map(|k| -2000.0 + (k as f64 * 0.37).sin() * 40.0).collect();
        z[5 * nx + 7] = f64::NAN;
        let mut sc = Scene::new();
        let id = sc.add_heightfield(&z, ny, nx, frame, (3, 2), None, opts()).unwrap();
        let o = sc.object(id).unwrap();
        let g = o.grid_axes().unwrap();
        let heights = o.shading_samples().unwrap();
        for t in o.tiles.iter().filter(|t| !t.is_empty()) {
            let l = o.tile_lattice(t).unwrap();
            assert_eq!(l.local.len(), t.positions.len());
            let c = g.pos(l.i0, l.j0).map(|v| v as f32);
            let (u, v) = (g.u.map(|x| x as f32), g.v.map(|x| x as f32));
            for (p, &[li, lj]) in t.positions.iter().zip(&l.local) {
                let (a, b) = (li as f32, lj as f32);
                let q = [c[0] + a * u[0] + b * v[0], c[1] + a * u[1] + b * v[1]];
                let k = (l.j0 + lj as usize) * nx + l.i0 + li as usize;
                assert_eq!(heights[k][2].to_bits(), p[2].to_bits(), "{rotation} {p:?}");
                for d in 0..2 {
                    assert!((q[d] - p[d]).abs() <= 4.0 * f32::EPSILON * 400.0, "{rotation} {q:?} {p:?}");
                }
            }
        }
    }
    let mut sc = Scene::new();
    let id = sc.add_mesh(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]], "fault", None, opts()).unwrap();
    let o = sc.object(id).unwrap();
    assert!(o.grid_axes().is_none() && o.tile_lattice(&o.tiles[0]).is_none());
}

#[test]
fn errors_name_arguments() {
    let mut s = Scene::new();
    let z = vec![0.0; 4];
    let e = s.add_heightfield(&z, 2, 2, GridFrame::new([0.0, 0.0], [0.0, 1.0]), (1, 1), None, opts()).unwrap_err();
    assert!(e.to_string().starts_with("spacing"), "{e}");
    let e = s.add_heightfield(&z, 2, 2, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (2, 1), None, opts()).unwrap_err();
    assert!(e.to_string().starts_with("tiles"), "{e}");
    let e = s.add_mesh(&[[0.0; 3]], &[[0, 0, 1]], "mesh", None, opts()).unwrap_err();
    assert!(e.to_string().starts_with("faces[0, 2]"), "{e}");
    let e = s.add_mesh(&[[0.0, f64::NAN, 0.0]], &[[0, 0, 0]], "mesh", None, opts()).unwrap_err();
    assert!(e.to_string().starts_with("vertices[0, 1]"), "{e}");
}

#[test]
fn bounds_cover_hidden_objects_and_offsets() {
    let mut s = Scene::new();
    assert!(s.bounds().is_none());
    let z = vec![1.0, 2.0, 3.0, 4.0];
    let a = s.add_heightfield(&z, 2, 2, GridFrame::new([10.0, 20.0], [1.0, 2.0]), (1, 1), None, opts()).unwrap();
    assert_eq!(s.bounds(), Some((DVec3::new(10.0, 20.0, 1.0), DVec3::new(11.0, 22.0, 4.0))));
    s.set_visible(a, false).unwrap();
    s.translate(a, [0.0, 0.0, -1.0]).unwrap();
    assert_eq!(s.bounds(), Some((DVec3::new(10.0, 20.0, 0.0), DVec3::new(11.0, 22.0, 3.0))));
    let holes = vec![f64::NAN; 4];
    s.add_heightfield(&holes, 2, 2, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (1, 1), None, opts()).unwrap();
    assert_eq!(s.bounds().unwrap().0.x, 10.0);
}

#[test]
fn rotated_grids_turn_about_their_origin() {
    let mut s = Scene::new();
    let z = vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    // 3 columns, 2 rows; 90° turns the x axis onto +y and the y axis onto -x.
    let f = GridFrame::new([100.0, 200.0], [10.0, 5.0]).rotated(90.0, false);
    let id = s.add_heightfield(&z, 2, 3, f, (1, 1), None, opts()).unwrap();
    let (v, _) = s.geometry(id).unwrap();
    let at = |x: f64, y: f64| v.iter().find(|p| p[0] == x && p[1] == y).map(|p| p[2]);
    assert_eq!(at(100.0, 200.0), Some(0.0));
    assert_eq!(at(100.0, 220.0), Some(2.0)); // column 2
    assert_eq!(at(95.0, 200.0), Some(3.0)); // row 1
                                            // yflip: row 1 at -dy in the grid frame, i.e. +x after the quarter turn.
    let id = s.add_heightfield(&z, 2, 3, f.rotated(90.0, true), (1, 1), None, opts()).unwrap();
    let (v, _) = s.geometry(id).unwrap();
    assert!(v.iter().any(|p| p[0] == 105.0 && p[1] == 200.0 && p[2] == 3.0));
    // 180°: both axes reversed; the grid rebuilt from the vertices is the input.
    let id = s.add_heightfield(&z, 2, 3, f.rotated(180.0, false), (1, 1), None, opts()).unwrap();
    let (v, _) = s.geometry(id).unwrap();
    assert!(v.iter().any(|p| p[0] == 80.0 && p[1] == 195.0 && p[2] == 5.0));
    for (deg, flip) in [(30.0, false), (-123.4, true), (180.0, false)] {
        let id = s.add_heightfield(&z, 2, 3, f.rotated(deg, flip), (1, 1), None, opts()).unwrap();
        let g = s.object(id).unwrap().height_grid().unwrap();
        let o = s.object(id).unwrap().origin.z as f32;
        assert_eq!(g.iter().map(|h| h + o).collect::<Vec<_>>(), vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0], "{deg}");
    }
    let e = s.add_heightfield(&z, 2, 3, f.rotated(f64::NAN, false), (1, 1), None, opts()).unwrap_err();
    assert!(e.to_string().starts_with("rotation"), "{e}");
}

#[test]
fn null_value_makes_holes() {
    let mut s = Scene::new();
    let mut z = vec![0.0; 9];
    z[4] = -999.25;
    s.add_heightfield(&z, 3, 3, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (1, 1), Some(-999.25), opts()).unwrap();
    assert_eq!(s.n_triangles(), 8 - 6);
}

#[test]
fn undefined_marker_is_named() {
    let mut s = Scene::new();
    for undef in [1e30, -1e30, 1e33] {
        let mut z = vec![0.0; 9];
        z[5] = undef;
        let e = s
            .add_heightfield(&z, 3, 3, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (1, 1), None, opts())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("z[1, 2]") && e.contains("xtgeo") && e.contains("null_value="), "{e}");
        s.add_heightfield(&z, 3, 3, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (1, 1), Some(undef), opts()).unwrap();
    }
    let mut z = vec![0.0; 9];
    z[5] = 1e20;
    let e = s
        .add_heightfield(&z, 3, 3, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (1, 1), None, opts())
        .unwrap_err()
        .to_string();
    assert!(!e.contains("xtgeo"), "{e}");
}

/// `nearest_index` is `f64::round` kept in `0..n`, at the values where `floor(v + 0.5)` is not:
/// just below a half (where v + 0.5 rounds up to the next integer), halves, the grid's ends.
#[test]
fn nearest_index_rounds_as_round_does() {
    let want = |v: f64, n: usize| {
        let r = v.round();
        (0.0..n as f64).contains(&r).then_some(r as usize)
    };
    let below_half = 0.5f64.next_down();
    let mut values = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.5, -0.49, -0.0, 0.0, below_half];
    for k in [1.0, 2.0, 7.0, 9.0, 4503599627370495.0] {
        for d in [-0.5, 0.0, 0.5] {
            let x: f64 = k + d;
            values.extend([x.next_down(), x, x.next_up()]);
        }
        values.push(k - 0.5 + below_half);
    }
    for v in values {
        for n in [1, 2, 8, 10] {
            assert_eq!(heightfield::nearest_index(v, n), want(v, n), "v {v:e}, n {n}");
        }
    }
}
