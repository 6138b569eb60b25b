use super::*;
use crate::scene::{AddOptions, GridFrame};

#[test]
fn height_fields_with_a_normal_map_draw_as_fields() {
    let mut s = Scene::new();
    let z: Vec<f64> = (0..81).map(|k| (k % 9) as f64 * 0.1).collect();
    let frame = || GridFrame::new([0.0, 0.0], [10.0, 10.0]);
    s.add_heightfield(&z, 9, 9, frame(), (2, 1), None, AddOptions::new(1.0)).unwrap();
    let v = [[0.0, 0.0, -5.0], [10.0, 0.0, -5.0], [0.0, 10.0, 5.0]];
    s.add_mesh(&v, &[[0, 1, 2]], "fault", None, AddOptions::new(1.0)).unwrap();
    s.add_heightfield(&z, 9, 9, frame(), (1, 1), None, AddOptions::new(1.0)).unwrap();
    s.add_heightfield(&z, 9, 9, frame(), (1, 1), None, AddOptions::new(1.0)).unwrap();
    let tile_object: Vec<u32> =
        s.objects().iter().enumerate().flat_map(|(o, ob)| std::iter::repeat_n(o as u32, ob.tiles.len())).collect();
    assert_eq!(tile_object, [0, 0, 1, 2, 3]);
    // The last height field's normal map did not fit: it draws as a mesh (fs_main).
    let runs = draw_runs(&s, &tile_object, &[Some(0), None, Some(81), None], &[None; 4], &[false; 4]);
    let got: Vec<_> = runs.iter().map(|r| (r.tiles.clone(), r.field, r.grid_mesh)).collect();
    assert_eq!(got, [(0..2, true, false), (2..3, false, false), (3..4, true, false), (4..5, false, false)]);
    // A grid mesh is never a field.
    let (base, dims) = ([Some(0), Some(81), Some(90), Some(171)], [None, Some((2, 2)), None, None]);
    let runs = draw_runs(&s, &tile_object, &base, &dims, &[false; 4]);
    let got: Vec<_> = runs.iter().map(|r| (r.tiles.clone(), r.field, r.grid_mesh)).collect();
    assert_eq!(got, [(0..2, true, false), (2..3, false, true), (3..5, true, false)]);
}

#[test]
fn coarse_height_field_tiles_draw_with_the_fine_depth() {
    let run = |tiles: std::ops::Range<usize>, field: bool| DrawRun {
        tiles,
        grid_mesh: false,
        field,
        closed: None,
        cells: false,
        fine_depth: false,
    };
    let runs = [run(0..4, true), run(4..6, false), run(6..8, true)];
    // Every height-field tile fine (lod = full, or only meshes coarse): the scene's runs as they are.
    assert!(split_coarse_fields(&runs, |_| false).is_none());
    assert!(split_coarse_fields(&runs, |k| k == 4).is_none());
    let got: Vec<_> = split_coarse_fields(&runs, |k| matches!(k, 1 | 2 | 5 | 7))
        .unwrap()
        .iter()
        .map(|r| (r.tiles.clone(), r.field, r.fine_depth))
        .collect();
    assert_eq!(
        got,
        [
            (0..1, true, false),
            (1..3, true, true),
            (3..4, true, false),
            (4..6, false, false),
            (6..7, true, false),
            (7..8, true, true)
        ]
    );
}

#[test]
fn height_field_tiles_carry_their_samples_for_the_fine_depth() {
    let mut s = Scene::new();
    let z: Vec<f64> = (0..81).map(|k| (k % 9) as f64 * 0.1).collect();
    s.add_heightfield(&z, 9, 9, GridFrame::new([0.0, 0.0], [10.0, 10.0]), (2, 1), None, AddOptions::new(1.0)).unwrap();
    let v = [[0.0, 0.0, -5.0], [10.0, 0.0, -5.0], [0.0, 10.0, 5.0]];
    s.add_mesh(&v, &[[0, 1, 2]], "fault", None, AddOptions::new(1.0)).unwrap();
    let plan = plan::Plan::new(&s, &[Some(0), None], &[None, None]);
    let words = |t: usize| (plan.tile_grid[3 * t + 2][2].to_bits(), plan.tile_grid[3 * t + 2][3].to_bits());
    // Columns 0..=4 and 4..=8 (tiles share their border samples), rows 0..=8: i0 | i1 << 16.
    assert_eq!(words(0), (4 << 16, 8 << 16));
    assert_eq!(words(1), (4 | 8 << 16, 8 << 16));
    assert_eq!(words(2), (u32::MAX, u32::MAX), "a mesh has none");
    // A tile with holes says so in the top bit of its columns' word.
    let mut z = z.clone();
    z[9 + 2] = f64::NAN;
    let mut s = Scene::new();
    s.add_heightfield(&z, 9, 9, GridFrame::new([0.0, 0.0], [10.0, 10.0]), (2, 1), None, AddOptions::new(1.0)).unwrap();
    let plan = plan::Plan::new(&s, &[Some(0)], &[None]);
    let words = |t: usize| (plan.tile_grid[3 * t + 2][2].to_bits(), plan.tile_grid[3 * t + 2][3].to_bits());
    assert_eq!(words(0), (4 << 16 | 1 << 31, 8 << 16));
    assert_eq!(words(1), (4 | 8 << 16, 8 << 16));
}

#[test]
fn tiles_of_one_shape_share_the_patterns_each_would_compact_to() {
    // A 41 x 29 field in 4 x 3 tiles of two widths and heights, two of them with a hole: every
    // tile's run names the patterns its own compaction gives (the plan compacts a list once),
    // and hole-free tiles of one shape name the same ones.
    let (nx, ny) = (41, 29);
    let mut z: Vec<f64> = (0..nx * ny).map(|k| ((k % nx) as f64 * 0.3).sin() + (k / nx) as f64 * 0.05).collect();
    z[5 * nx + 6] = f64::NAN;
    z[20 * nx + 33] = f64::NAN;
    let mut s = Scene::new();
    let frame = GridFrame::new([0.0, 0.0], [10.0, 10.0]).rotated(25.0, false);
    s.add_heightfield(&z, ny, nx, frame, (4, 3), None, AddOptions::new(4.0)).unwrap();
    let plan = plan::Plan::new(&s, &[Some(0)], &[None]);
    let o = &s.objects()[0];
    // Hole-free tiles of one size and side masks (`lod::groups`) have the same lists.
    let mut ids_by_shape: std::collections::HashMap<(usize, usize, Vec<u8>), Vec<usize>> = Default::default();
    for (k, t) in o.tiles.iter().enumerate() {
        let local = o.tile_lattice(t).unwrap().local;
        let want: Vec<_> =
            plan::tile_patterns(t, &local, &mut Vec::new(), &mut Vec::new()).into_iter().map(|(_, p)| p).collect();
        let run = plan.runs[k].as_ref().expect("a lattice tile");
        let got: Vec<_> = run.iter().map(|&p| plan.patterns[p].clone()).collect();
        assert_eq!(got, want, "tile {k}");
        let shape =
            (local.iter().map(|p| p[0]).max().unwrap() as usize, local.iter().map(|p| p[1]).max().unwrap() as usize);
        if t.fine_triangles() == 2 * shape.0 * shape.1 {
            let masks = crate::lod::groups::masks(crate::lod::groups::open_sides(t.ix as usize, t.iy as usize, 4, 3));
            let seen = ids_by_shape.entry((shape.0, shape.1, masks)).or_insert_with(|| run.clone());
            assert_eq!(seen, run, "tile {k} of shape {shape:?}");
        }
    }
    assert!(ids_by_shape.len() >= 2);
}

#[test]
fn occluders_are_coarse_lattices_that_stop_short_of_holes() {
    // A 41 x 29 field in 2 x 2 tiles, a hole in one of them and a corner of no data in another:
    // a hole-free tile's occluder is its 8 triangles of corner, mid-side and centre samples; a
    // tile with holes gets at most 32 over samples it has (none on a hole), still far fewer than
    // its coarse proxy, and none at all for a tile too ragged to have a whole coarse cell.
    let (nx, ny) = (41, 29);
    let mut z: Vec<f64> = (0..nx * ny).map(|k| ((k % nx) as f64 * 0.3).sin() + (k / nx) as f64 * 0.05).collect();
    z[5 * nx + 6] = f64::NAN;
    for j in 15..ny {
        for i in 20..nx {
            if i + j > 50 {
                z[j * nx + i] = f64::NAN;
            }
        }
    }
    let mut s = Scene::new();
    let frame = GridFrame::new([0.0, 0.0], [10.0, 10.0]).rotated(25.0, false);
    s.add_heightfield(&z, ny, nx, frame, (2, 2), None, AddOptions::new(4.0)).unwrap();
    let o = &s.objects()[0];
    let mut holed = 0;
    for (k, t) in o.tiles.iter().enumerate() {
        let local = o.tile_lattice(t).unwrap().local;
        let (verts, idx) = plan::tile_patterns(t, &local, &mut Vec::new(), &mut Vec::new()).pop().unwrap().1;
        let (w, h) = (local.iter().map(|p| p[0]).max().unwrap(), local.iter().map(|p| p[1]).max().unwrap());
        if t.fine_triangles() == 2 * (w * h) as usize {
            assert_eq!(idx.len(), 24, "tile {k}: 8 triangles");
            continue;
        }
        holed += 1;
        assert!(idx.len() <= 96 && idx.len() % 6 == 0, "tile {k}: {} indices", idx.len());
        assert!(!idx.is_empty(), "tile {k}: most of it has data");
        assert!(idx.len() / 3 < t.coarse_triangles(), "tile {k}");
        assert!(idx.iter().all(|&v| (v as usize) < verts.len()));
        assert!(verts.iter().all(|v| local.contains(v)), "tile {k}: a vertex on a hole");
    }
    assert_eq!(holed, 2);
}
