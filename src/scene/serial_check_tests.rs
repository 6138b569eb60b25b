//! Each rule of `serial::check`: bytes that the reader took before it are refused, naming `data`.

use super::super::tests::scene;
use super::*;
use crate::scene::{AddOptions, HeightfieldInfo, Object, Scene};

/// The error reading back `s` with object `name` changed by `f` (it must name `data`).
fn refused(mut s: Scene, name: &str, f: impl FnOnce(&mut Object)) -> String {
    f(s.objects.iter_mut().find(|o| o.name == name).expect("the object"));
    let e = Scene::from_bytes(&s.to_bytes()).expect_err("damaged bytes are refused").to_string();
    assert!(e.starts_with("data at byte "), "{e}");
    e
}

/// `scene()`'s rotated, yflipped 2 x 2-tile height field with its kind changed by `f`.
fn frame_refused(f: impl FnOnce(&mut usize, &mut usize, &mut [f64; 5], &mut (usize, usize))) -> String {
    refused(scene(), "turned", |o| {
        let ObjectKind::Heightfield(hf) = &mut o.kind else { panic!() };
        let HeightfieldInfo { nx, ny, x0, y0, dx, dy, rotation, tiles, .. } = &mut **hf;
        let mut v = [*x0, *y0, *dx, *dy, *rotation];
        f(nx, ny, &mut v, tiles);
        [*x0, *y0, *dx, *dy, *rotation] = v;
    })
}

/// `check::object` of the object `name` of `scene()` with its tiles changed by `f`.
fn object_check(name: &str, f: impl FnOnce(&mut Vec<TileMesh>)) -> Check {
    let mut s = scene();
    let o = s.objects.iter_mut().find(|o| o.name == name).unwrap();
    f(&mut o.tiles);
    object(&o.kind, &o.tiles, o.origin, 1 << 20)
}

#[test]
fn the_original_passes_every_check() {
    let s = scene();
    for o in s.objects() {
        object(&o.kind, &o.tiles, o.origin, 0).unwrap();
        o.tiles.iter().try_for_each(|t| tile(t, o.origin)).unwrap();
    }
    assert_eq!(object_check("turned", |_| {}), Ok(()));
}

#[test]
fn a_height_field_has_no_more_samples_than_its_bytes_bound() {
    // Horizon culling allocated nx * ny heights: 2^31 x 9 aborted the process.
    let e = frame_refused(|nx, _, _, _| *nx = 1 << 31);
    assert!(e.contains("9 x 2147483648 samples in"), "{e}");
    // nx * ny overflows: the frame's corners go beyond 1e12 first.
    let e = frame_refused(|nx, ny, _, _| (*nx, *ny) = (usize::MAX, usize::MAX));
    assert!(e.contains("spacing: component"), "{e}");
    // One more column (a column of holes) is a grid the tiles still draw.
    let mut s = scene();
    let o = s.objects.iter_mut().find(|o| o.name == "base").unwrap();
    let ObjectKind::Heightfield(hf) = &mut o.kind else { panic!() };
    hf.nx += 1;
    Scene::from_bytes(&s.to_bytes()).unwrap();
}

#[test]
fn tiles_cut_the_grid_as_its_tile_counts_say() {
    // tx = 0, 1, nx: index out of bounds, capacity overflow or allocations in horizon culling.
    let e = frame_refused(|_, _, _, t| t.0 = 0);
    assert!(e.contains("object 3: tiles[0] is 0; expected 1..=8"), "{e}");
    let e = frame_refused(|_, _, _, t| t.1 = 9);
    assert!(e.contains("tiles[1] is 9"), "{e}");
    let e = frame_refused(|_, _, _, t| *t = (1, 1));
    assert!(e.contains("a height field of 1 x 1 tiles has 4"), "{e}");
    let e = refused(scene(), "turned", |o| o.tiles.swap(0, 1));
    assert!(e.contains("tile 0 is tile (1, 0), not (0, 0)"), "{e}");
}

#[test]
fn a_height_field_frame_follows_the_constructor_rules() {
    let e = frame_refused(|_, _, v, _| v[2] = 5e-324);
    assert!(e.contains("spacing: component 0 is 5e-324; expected a finite number > 0 (at least"), "{e}");
    let e = frame_refused(|_, _, v, _| v[3] = -0.0);
    assert!(e.contains("spacing: component 1 is 0"), "{e}");
    let e = frame_refused(|_, _, v, _| v[0] = 1e300);
    assert!(e.contains("origin: component 0 is 1e300"), "{e}");
    let e = frame_refused(|_, _, v, _| v[4] = f64::INFINITY);
    assert!(e.contains("object 3: rotation is inf"), "{e}");
    // The constructor's rule is the same: a denormal spacing puts every sample at the origin.
    let e = Scene::new()
        .add_heightfield(&[0.0; 4], 2, 2, GridFrame::new([0.0; 2], [1.0, 1e-310]), (1, 1), None, AddOptions::new(1.0))
        .unwrap_err();
    assert!(e.to_string().starts_with("spacing: component 1 is 1e-310"), "{e}");
}

#[test]
fn vertices_are_samples_of_the_frame() {
    // A frame the vertices do not lie on: horizon culling rebuilt another surface and culled.
    for (k, v) in [(2, 26.0), (3, -31.0), (4, 34.0), (4, 1e13), (0, f64::NAN)] {
        let e = frame_refused(|_, _, f, _| f[k] = if v.is_nan() { f[0] + 10.0 } else { v });
        assert!(e.contains("is not a sample of its part of the 9 x 9 grid"), "{k} {e}");
    }
    // A sample of the grid but of another tile's part of it.
    let e = object_check("turned", |t| t[0].positions[0] = t[3].positions[5]).unwrap_err();
    assert!(e.contains("vertex 0 of tile 0 is not a sample of its part"), "{e}");
}

#[test]
fn a_sample_is_one_vertex_of_one_height() {
    let e = object_check("turned", |t| t[0].positions[1] = t[0].positions[0]).unwrap_err();
    assert!(e.contains("tile 0 has two vertices at one sample"), "{e}");
    // Tiles 0 and 1 share a column of samples: one of them at another height.
    let e = object_check("turned", |t| {
        let shared = |p: &[f32; 3]| t[1].positions.iter().any(|q| q[..2] == p[..2]);
        let k = t[0].positions.iter().position(shared).expect("a shared sample");
        t[0].positions[k][2] += 0.5;
    })
    .unwrap_err();
    assert!(e.contains("two heights"), "{e}");
}

#[test]
fn tile_boxes_are_the_bounds_of_their_vertices() {
    // A NaN box, or one that holds the tile but is larger: three_pass culled by it.
    for (a, v) in [(0, f32::NAN), (1, -1e-45), (2, -1e3)] {
        let e = refused(scene(), "f", |o| o.tiles[0].bbox_min[a] = v);
        assert!(e.contains("is not the bounds of its vertices"), "{a} {e}");
    }
    let e = refused(scene(), "base", |o| o.tiles[0].bbox_max[2] = f32::INFINITY);
    assert!(e.contains("tile 0: its box"), "{e}");
}

#[test]
fn vertices_and_placement_are_within_the_coordinate_limit() {
    let e = refused(scene(), "f", |o| o.tiles[0].positions[0][0] = 3e38);
    assert!(e.contains("vertex 0 lies at 3"), "{e}");
    let e = refused(scene(), "f", |o| o.offset.y = 1e13);
    assert!(e.contains("offset[1] is 10000000000000"), "{e}");
    let e = refused(scene(), "f", |o| o.origin.z = -1e300);
    assert!(e.contains("origin[2] is -1e300"), "{e}");
    let e = refused(scene(), "f", |o| o.color[1] = f32::NAN);
    assert!(e.contains("color: component 1 is NaN"), "{e}");
}

#[test]
fn lod_errors_are_not_nan_nor_negative() {
    let e = refused(scene(), "f", |o| o.tiles[0].proxy_error = f32::NAN);
    assert!(e.contains("an LOD error is NaN"), "{e}");
}

#[test]
fn grid_coordinates_stay_within_the_vertices() {
    // A structured mesh (grid coordinates, smooth normals): its largest packed coordinate sized a
    // 16 GiB normal grid on upload.
    let n = 6;
    let v: Vec<[f64; 3]> = (0..n * n).map(|k| [(k % n) as f64, (k / n) as f64, ((k % n) as f64).sin()]).collect();
    let mut f = Vec::new();
    for j in 0..n as i64 - 1 {
        for i in 0..n as i64 - 1 {
            let (a, b, c, d) =
                (j * n as i64 + i, j * n as i64 + i + 1, (j + 1) * n as i64 + i, (j + 1) * n as i64 + i + 1);
            f.extend([[a, b, d], [a, d, c]]);
        }
    }
    let mut s = Scene::new();
    s.add_mesh(&v, &f, "sheet", None, AddOptions { name: Some("sheet".into()), ..AddOptions::new(1.0) }).unwrap();
    assert!(!s.objects()[0].tiles[0].grid_uv.is_empty());
    Scene::from_bytes(&s.to_bytes()).unwrap();
    let e = refused(s, "sheet", |o| o.tiles[0].grid_uv[0] = u32::MAX);
    assert!(e.contains("grid coordinates reach column 65535 and row 65535 for only 36 vertices"), "{e}");
}

/// A grid object's tables.
fn grid(o: &mut Object) -> &mut GridInfo {
    match &mut o.kind {
        ObjectKind::Grid(g) => g,
        _ => panic!("not a grid"),
    }
}

#[test]
fn grid_block_tables_count_the_triangles_drawn() {
    let corners: Vec<f64> = (0..2 * 2 * 2)
        .flat_map(|c| {
            let (i, j, k) = (c % 2, (c / 2) % 2, c / 4);
            (0..8)
                .flat_map(move |q| [(i + (q & 1)) as f64, (j + ((q >> 1) & 1)) as f64, -((k + ((q >> 2) & 1)) as f64)])
        })
        .collect();
    let mut s = Scene::new();
    let o = AddOptions { name: Some("g".into()), ..AddOptions::new(1.0) };
    s.add_grid((2, 2, 2), &corners, None, None, (1, 1), o).unwrap();
    let e = refused(s.clone(), "g", |o| grid(o).block_levels[0][0].triangles += 1);
    assert!(e.contains("grid block 0 level 0"), "{e}");
    let e = refused(s.clone(), "g", |o| grid(o).cell_size[0].1 = f64::NAN);
    assert!(e.contains("cell size"), "{e}");
    // Refused as read (the tables are reserved whole, one per block), before `check::grid`.
    let e = refused(s.clone(), "g", |o| grid(o).block_levels.clear());
    assert!(e.contains("0 grid block tables for 4 blocks"), "{e}");
    let e = refused(s, "g", |o| {
        let g = grid(o);
        g.block_levels.pop();
        g.cell_size.pop();
    });
    assert!(e.contains("block tables do not match its 4 tiles"), "{e}");
    // Coloured by values: cell coordinates within the blocks and layers (they size a table).
    let mut s = Scene::new();
    let values = crate::scene::ColorByArg::values((0..8).map(f64::from).collect());
    let o = AddOptions { name: Some("v".into()), color_by: Some(values), ..AddOptions::new(1.0) };
    s.add_grid((2, 2, 2), &corners, None, None, (1, 1), o).unwrap();
    assert!(s.objects()[0].tiles.iter().all(|t| !t.grid_uv.is_empty()));
    Scene::from_bytes(&s.to_bytes()).unwrap();
    let e = refused(s, "v", |o| o.tiles[0].grid_uv[0] = crate::grid::cells::pack(1, 1, 0xfffe));
    assert!(e.contains("cell coordinates [1, 1, 65534] lie outside its block"), "{e}");
}

#[test]
fn objects_come_in_the_order_of_their_ids() {
    let mut s = scene();
    s.objects.swap(0, 1);
    let e = Scene::from_bytes(&s.to_bytes()).unwrap_err().to_string();
    assert!(e.contains("out of order"), "{e}");
}

#[test]
fn height_fields_of_every_frame_load() {
    // The vertex rule's tolerance (rounding only) never refuses a height field built here: far
    // origins with small spacings, rotations, flipped rows, holes, tiles of one cell.
    let (nx, ny) = (13, 7);
    let z: Vec<f64> =
        (0..nx * ny).map(|k| if k % 11 == 3 { f64::NAN } else { (k as f64 * 0.7).sin() * 40.0 }).collect();
    let mut n = 0;
    for origin in [0.0, 451_000.5, -6_780_000.25, 9.9e11] {
        for spacing in [1e-3, 1.0, 25.0, 1e4] {
            for rotation in [0.0, 33.0, 90.0, -137.2, 1e5] {
                for (yflip, tiles) in [(false, (3, 2)), (true, (12, 6)), (true, (1, 1))] {
                    let frame =
                        GridFrame::new([origin, -origin / 3.0], [spacing, spacing * 1.7]).rotated(rotation, yflip);
                    let mut s = Scene::new();
                    s.add_heightfield(&z, ny, nx, frame, tiles, None, AddOptions::new(4.0)).unwrap();
                    let b = s.to_bytes();
                    let back = Scene::from_bytes(&b).unwrap_or_else(|e| panic!("{origin} {spacing} {rotation}: {e}"));
                    assert_eq!(back.to_bytes(), b);
                    n += 1;
                }
            }
        }
    }
    assert_eq!(n, 240);
}

#[test]
fn a_stored_shading_error_that_is_nan_is_refused() {
    // From version 6 the shading error is stored: a NaN one was measured again (some 80 bytes of
    // temporaries per vertex, from damaged bytes); now it is refused as any NaN LOD error.
    let n = 16;
    let v: Vec<[f64; 3]> = (0..n * n)
        .map(|k| [(k % n) as f64 * 10.0, (k / n) as f64 * 10.0, ((k % n) as f64 / 3.0).sin() * 20.0])
        .collect();
    let mut f = Vec::new();
    for j in 0..n as i64 - 1 {
        for i in 0..n as i64 - 1 {
            let k = j * n as i64 + i;
            f.extend([[k, k + 1, k + n as i64], [k + 1, k + n as i64 + 1, k + n as i64]]);
        }
    }
    let mut s = Scene::new();
    s.add_mesh(&v, &f, "fault", None, AddOptions { name: Some("sheet".into()), ..AddOptions::new(4.0) }).unwrap();
    assert!(!s.objects()[0].tiles[0].levels.is_empty());
    let e = refused(s, "sheet", |o| o.tiles[0].levels[0].shading_error = f32::NAN);
    assert!(e.contains("an LOD error is NaN"), "{e}");
}

#[test]
fn a_grid_has_no_more_cell_sizes_than_tiles_fit_the_bytes() {
    // The block cell sizes (f32 pairs, stored as f64) were read whatever their count: a count
    // that took the rest of the buffer held three times its bytes before the tables were checked.
    let corners: Vec<f64> =
        (0..8).flat_map(|q| [(q & 1) as f64, ((q >> 1) & 1) as f64, -(((q >> 2) & 1) as f64)]).collect();
    let mut s = Scene::new();
    s.add_grid((1, 1, 1), &corners, None, None, (1, 1), AddOptions::new(1.0)).unwrap();
    let b = s.to_bytes();
    Scene::from_bytes(&b).unwrap();
    // The count of the cell sizes (2: one block), after nk, nj, ni, bi, bj (1 each).
    let mut head = Vec::new();
    for v in [1u64, 1, 1, 1, 1, 2] {
        head.extend(v.to_le_bytes());
    }
    let at = b.windows(head.len()).position(|w| w == head).unwrap() + 40;
    let rest = (b.len() - at - 8) as u64 / 4;
    for n in [rest / 2 * 2, rest / 8 * 2] {
        let mut v = b.clone();
        v[at..at + 8].copy_from_slice(&n.to_le_bytes());
        let e = Scene::from_bytes(&v).unwrap_err().to_string();
        assert!(e.contains("its block cell sizes are not pairs, one per tile"), "{n}: {e}");
    }
}
