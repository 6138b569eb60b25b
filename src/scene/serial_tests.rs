//! `Scene::to_bytes` / `Scene::from_bytes`: round trips, older versions, damaged bytes.

use super::*;
use crate::scene::{AddOptions, GridFrame};

pub(super) fn scene() -> Scene {
    let mut s = Scene::new();
    let opts = |name: &str| AddOptions { name: Some(name.into()), ..AddOptions::new(4.0) };
    let z: Vec<f64> = (0..81).map(|k| ((k % 9) as f64 * 0.3).sin() + if k == 40 { f64::NAN } else { 0.0 }).collect();
    s.add_heightfield(&z, 9, 9, GridFrame::new([451_000.0, 6_780_000.0], [25.0, 25.0]), (3, 2), None, opts("top"))
        .unwrap();
    let v = [[451_000.0, 6_780_000.0, -5.0], [451_100.0, 6_780_000.0, -5.0], [451_000.0, 6_780_100.0, 5.0]];
    s.add_mesh(&v, &[[0, 1, 2]], "fault", None, opts("f")).unwrap();
    s.translate(1, [1.0, 2.0, 3.0]).unwrap();
    s.set_visible(0, false).unwrap();
    s.remove(0).unwrap();
    s.add_heightfield(
        &z,
        9,
        9,
        GridFrame::new([451_000.0, 6_780_000.0], [25.0, 25.0]),
        (1, 1),
        Some(0.0),
        opts("base"),
    )
    .unwrap();
    // a rotated, yflipped grid keeps its frame (horizon culling rebuilds the grid from it)
    let turned = GridFrame::new([451_000.0, 6_780_000.0], [25.0, 30.0]).rotated(33.0, true);
    s.add_heightfield(&z, 9, 9, turned, (2, 2), None, opts("turned")).unwrap();
    s
}

#[test]
fn slabs_are_rebuilt_as_they_were_built() {
    // Holes, a rotated yflipped frame, tiles of one sample row: every slab comes back equal.
    let s = scene();
    let t = Scene::from_bytes(&s.to_bytes()).unwrap();
    let mut n = 0;
    for (a, b) in s.objects().iter().zip(t.objects()) {
        // Loading builds none: they are built on first use.
        if let ObjectKind::Heightfield(hf) = &b.kind {
            assert!(hf.slabs.get().is_none(), "object {}", b.id);
        }
        for (k, ta) in a.tiles.iter().enumerate() {
            assert_eq!(a.slab(k), b.slab(k), "object {} tile {} {}", a.id, ta.ix, ta.iy);
            n += a.slab(k).is_some() as usize;
        }
    }
    assert!(n >= 5, "{n}");
    // A tile whose vertex left its grid sample gets no slab (it is box-tested).
    let mut u = Scene::from_bytes(&s.to_bytes()).unwrap();
    let o = u.objects.iter_mut().find(|o| o.name == "turned").unwrap();
    o.tiles[0].positions[0][0] += 3.0;
    assert!(o.slab(0).is_none() && o.slab(1).is_some());
}

#[test]
fn round_trip_is_exact_under_a_new_identity() {
    let s = scene();
    let b = s.to_bytes();
    let t = Scene::from_bytes(&b).unwrap();
    assert_eq!(t.to_bytes(), b);
    assert_ne!(t.geometry_key().0, s.geometry_key().0);
    assert_eq!(t.origin(), s.origin());
    for o in s.objects() {
        assert_eq!(format!("{:?}", t.object(o.id).unwrap().kind), format!("{:?}", o.kind));
        assert_eq!(t.geometry(o.id).unwrap(), s.geometry(o.id).unwrap());
        let bits = |g: Option<Vec<f32>>| g.map(|g| g.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
        assert_eq!(bits(t.object(o.id).unwrap().height_grid()), bits(o.height_grid()));
    }
    // ids continue where the original's would
    let (mut s2, mut t2) = (s.clone(), t);
    let z = vec![0.0; 4];
    let o = AddOptions::new(1.0);
    let a = s2.add_heightfield(&z, 2, 2, GridFrame::new([0.0; 2], [1.0; 2]), (1, 1), None, o.clone()).unwrap();
    assert_eq!(t2.add_heightfield(&z, 2, 2, GridFrame::new([0.0; 2], [1.0; 2]), (1, 1), None, o).unwrap(), a);
    assert_ne!(s2.geometry_key().0, s.geometry_key().0, "a clone has its own identity");
    // the empty scene too
    let e = Scene::from_bytes(&Scene::new().to_bytes()).unwrap();
    assert!(e.objects().is_empty() && e.origin() == DVec3::ZERO);
}

#[test]
fn version_1_height_fields_read_as_unrotated() {
    let mut s = Scene::new();
    let o = AddOptions { name: Some("a".into()), color: Some([0.5; 3]), ..AddOptions::new(1.0) };
    s.add_heightfield(&[0.0, 1.0, 2.0, 3.0], 2, 2, GridFrame::new([5.0, 6.0], [1.0, 2.0]), (1, 1), None, o).unwrap();
    let v2 = s.to_bytes_version(8);
    // version 1: no rotation after dy (magic 8, version 4, origin 1 + 24, next_id 4, count 4,
    // id 4, name 4 + 1, kind 1, nx ny 16, x0 y0 dx dy 32), no object origin (after rotation 8,
    // tx ty 16, color 12, visible 1, offset 24; read as the scene's, which it is), no colouring
    // byte and opacity after it (flat, 1), and no tile values, normals nor grid coordinates
    // (three empty arrays after the tile's n_tiles 4, ix iy 8, bbox 24 and 4 positions 8 + 48)
    let at = 8 + 4 + 25 + 4 + 4 + 4 + 5 + 1 + 16 + 32;
    let origin_at = at + 8 + 16 + 12 + 1 + 24;
    // (and no priority byte after the opacity: version 7)
    let values_at = origin_at + 24 + 1 + 4 + 1 + 4 + 8 + 24 + 56;
    let mut v1 = [&v2[..at], &v2[at + 8..origin_at], &v2[origin_at + 30..values_at], &v2[values_at + 24..]].concat();
    v1[8..12].copy_from_slice(&1u32.to_le_bytes());
    let t = Scene::from_bytes(&v1).unwrap();
    assert_eq!(t.to_bytes_version(8), v2);
}

#[test]
fn version_5_meshes_measure_their_shading_error_again() {
    // A curved sheet, one tile: its levels have a shading error.
    let n = 24;
    let v: Vec<[f64; 3]> = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 * 10.0, (k / n) as f64 * 10.0);
            [x, y, 30.0 * (x / 60.0).sin()]
        })
        .collect();
    let mut f = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            // The other diagonal: not a structured grid (no grid coordinates to strip).
            let k = (j * n + i) as i64;
            f.push([k, k + 1, k + n as i64]);
            f.push([k + 1, k + n as i64 + 1, k + n as i64]);
        }
    }
    let mut s = Scene::new();
    s.add_mesh(&v, &f, "fault", None, AddOptions::new(4.0)).unwrap();
    let t = &s.objects()[0].tiles[0];
    assert!(!t.levels.is_empty() && t.levels.iter().all(|l| l.shading_error > 0.0));
    let v8 = s.to_bytes_version(8);
    // Version 5: the same bytes without the object's priority byte (by kind, after its opacity),
    let mut pri = 1.0f32.to_le_bytes().to_vec();
    pri.extend([u8::MAX]);
    pri.extend(1u32.to_le_bytes());
    let pri_at = v8.windows(pri.len()).position(|w| w == pri).unwrap() + 4;
    let v6 = [&v8[..pri_at], &v8[pri_at + 1..]].concat();
    // without the tile's (empty) grid coordinates, after its
    // normals, and without each level's shading error and vertical error (the f32s after its error).
    let mut normals_then = (t.normals.len() as u64).to_le_bytes().to_vec();
    normals_then.extend(t.normals.iter().flat_map(|n| n.to_le_bytes()));
    normals_then.extend(0u64.to_le_bytes());
    normals_then.extend((t.fine.len() as u64).to_le_bytes());
    let grid_at = v6.windows(normals_then.len()).position(|w| w == normals_then).unwrap() + normals_then.len() - 16;
    let v6_no_grid = [&v6[..grid_at], &v6[grid_at + 8..]].concat();
    let mut head = t.proxy_error.to_le_bytes().to_vec();
    head.extend((t.levels.len() as u32).to_le_bytes());
    head.extend(t.levels[0].error.to_le_bytes());
    head.extend(t.levels[0].shading_error.to_le_bytes());
    let w = &v6_no_grid;
    let start = w.windows(head.len()).position(|x| x == head).unwrap() + 8;
    let mut v5 = w[..start].to_vec();
    let mut at = start;
    for l in &t.levels {
        v5.extend(&w[at..at + 4]); // error
        at += 12; // and the shading and vertical errors, dropped
        let len = 8 + 4 * l.indices.len();
        v5.extend(&w[at..at + len]);
        at += len;
    }
    v5.extend(&w[at..]);
    v5[8..12].copy_from_slice(&5u32.to_le_bytes());
    let back = Scene::from_bytes(&v5).unwrap();
    assert_eq!(back.to_bytes_version(8), v8);
}

#[test]
fn version_7_levels_take_their_whole_error_as_vertical() {
    // A vertical well: its levels' errors are horizontal (error_z well below error).
    let path: Vec<[f64; 3]> = (0..400).map(|k| [3.0 * (k as f64 * 0.02).sin(), 0.0, -0.5 * k as f64]).collect();
    let mut s = Scene::new();
    s.add_well(&path, 2.0, 8, AddOptions::new(4.0)).unwrap();
    let levels: Vec<_> = s.objects()[0].tiles.iter().flat_map(|t| t.levels.clone()).collect();
    assert!(!levels.is_empty() && levels.iter().all(|l| l.error_z < 0.5 * l.error));
    let v8 = s.to_bytes_version(8);
    assert_eq!(Scene::from_bytes(&v8).unwrap().to_bytes_version(8), v8);
    // Version 7: the same bytes without each level's error_z (the f32 after its shading error).
    let mut v7 = v8.clone();
    for l in levels.iter().rev() {
        let mut at_level = l.error.to_le_bytes().to_vec();
        at_level.extend(l.shading_error.to_le_bytes());
        at_level.extend(l.error_z.to_le_bytes());
        at_level.extend((l.indices.len() as u64).to_le_bytes());
        let at = v7.windows(at_level.len()).rposition(|w| w == at_level).unwrap() + 8;
        v7.drain(at..at + 4);
    }
    v7[8..12].copy_from_slice(&7u32.to_le_bytes());
    let back = Scene::from_bytes(&v7).unwrap();
    // Read as bounded by the whole error: what the level choice took before version 8.
    let got: Vec<_> = back.objects()[0].tiles.iter().flat_map(|t| t.levels.clone()).collect();
    assert_eq!(got.len(), levels.len());
    assert!(got.iter().zip(&levels).all(|(g, l)| g.error_z == l.error && g.error == l.error));
}

#[test]
fn damaged_bytes_are_input_errors() {
    let b = scene().to_bytes();
    for bad in [&b[..b.len() - 1], &b[..10], &b"not a scene"[..], &[]] {
        let e = Scene::from_bytes(bad).unwrap_err().to_string();
        assert!(e.starts_with("data"), "{e}");
    }
    let mut v = b.clone();
    v[8] = 13; // version 13
    assert!(Scene::from_bytes(&v).unwrap_err().to_string().contains("version 13"));
    let mut extra = b.clone();
    extra.push(0);
    assert!(Scene::from_bytes(&extra).unwrap_err().to_string().contains("trailing"));
}

#[test]
fn priorities_round_trip_and_a_bad_one_is_refused() {
    let mut s = scene();
    let id = s.objects()[0].id;
    s.set_priority(id, Some(9)).unwrap();
    assert!(s.set_priority(id, Some(16)).unwrap_err().to_string().starts_with("priority"));
    let back = Scene::from_bytes(&s.to_bytes()).unwrap();
    assert_eq!(back.objects()[0].priority, Some(9));
    assert_eq!(back.objects()[1].priority, None);
    // The byte after the first object's opacity: 9; 16 is no priority.
    let b = s.to_bytes();
    let mut bad = b.clone();
    let mut pat = 1.0f32.to_le_bytes().to_vec();
    pat.push(9);
    let at = b.windows(5).position(|w| w == pat).unwrap() + 4;
    bad[at] = 16;
    assert!(Scene::from_bytes(&bad).unwrap_err().to_string().contains("priority 16"));
}

#[test]
fn a_count_reserves_only_records_the_unclaimed_bytes_hold() {
    // n_objects, n_tiles and a grid's table counts reserved up to 2^16 records each (some 19 MB
    // for u32::MAX objects in a 45-byte buffer): now a count is refused unless the bytes no
    // record claims hold that many of its smallest records, which then claim them.
    let mut r = Reader::new(&[0; 1000], "data");
    assert!(r.records(usize::MAX, 2, "objects").unwrap_err().to_string().contains("truncated"));
    assert!(r.records(12, 84, "objects").is_err());
    r.records(11, 84, "objects").unwrap();
    assert_eq!(r.unclaimed(), 1000 - 11 * 84);
    assert!(r.records(2, 40, "tiles").is_err());
    // An array takes unclaimed bytes only.
    let mut a = Reader::new(&[0; 1000], "data");
    a.records(1, 960, "tiles").unwrap();
    a.take(4).unwrap();
    assert_eq!(a.unclaimed(), 36);
    let nine = [&9u64.to_le_bytes()[..], &[0; 992]].concat();
    let mut b = Reader::new(&nine, "data");
    b.records(1, 960, "tiles").unwrap();
    assert!(b.f32s().unwrap_err().to_string().contains("does not fit"));
    // A record started no longer claims its bytes.
    b.record(960);
    assert_eq!(b.unclaimed(), 992);
    // Such counts are refused when the records run out.
    let b = Scene::new().to_bytes();
    let mut v = b.clone();
    v[b.len() - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(Scene::from_bytes(&v).unwrap_err().to_string().contains("truncated"));
    for version in 1..=VERSION {
        assert_eq!(min_object_bytes(version), [54, 54, 78, 83, 83, 83, 84, 84, 84, 84, 84, 84][version as usize - 1]);
        assert_eq!(min_tile_bytes(version), [64, 64, 64, 72, 80, 88, 88, 88, 96, 96, 104, 104][version as usize - 1]);
    }
}

#[test]
fn the_smallest_records_take_at_most_twice_their_bytes_in_memory() {
    // An object with no name nor tiles and an empty tile (tests/alloc_bound.rs, issue 39): the
    // structs they are read into, reserved whole (`Reader::records`), within twice their bytes.
    assert!(std::mem::size_of::<Object>() <= 2 * min_object_bytes(VERSION), "{}", std::mem::size_of::<Object>());
    assert!(std::mem::size_of::<TileMesh>() <= 2 * min_tile_bytes(VERSION), "{}", std::mem::size_of::<TileMesh>());
    // Older versions' smaller records claim half a struct each: the current format's claims are
    // its records' sizes.
    for version in 1..=VERSION {
        assert!(std::mem::size_of::<Object>() <= 2 * object_claim(version));
        assert!(std::mem::size_of::<TileMesh>() <= 2 * tile_claim(version));
        assert!(object_claim(version) >= min_object_bytes(version) && tile_claim(version) >= min_tile_bytes(version));
    }
    assert_eq!((object_claim(VERSION), tile_claim(VERSION)), (min_object_bytes(VERSION), min_tile_bytes(VERSION)));
}

#[test]
fn ring_heights_round_trip_and_a_centre_out_of_the_box_is_refused() {
    let path: Vec<[f64; 3]> = (0..300).map(|k| [0.5 * k as f64, 0.2 * k as f64, -0.4 * k as f64]).collect();
    let mut s = Scene::new();
    s.add_well(&path, 5.0, 8, AddOptions::new(25.0)).unwrap();
    let t = &s.objects()[0].tiles[0];
    assert_eq!(t.ring_z.len(), t.positions.len());
    let b = s.to_bytes();
    let back = Scene::from_bytes(&b).unwrap();
    assert_eq!(back.objects()[0].tiles[0].ring_z[..], t.ring_z[..]);
    // Version 8 has none: the tube is drawn exaggerated whole, as it was then.
    let v8 = Scene::from_bytes(&s.to_bytes_version(8)).unwrap();
    assert!(v8.objects()[0].tiles.iter().all(|t| t.ring_z.is_empty()));
    // A ring height taking its vertex's ring centre below the tile's box.
    let depth = t.positions[0][2] - t.bbox_min[2];
    let mut word = (t.ring_z.len() as u64).to_le_bytes().to_vec();
    word.extend(t.ring_z[0].to_le_bytes());
    let at = b.windows(word.len()).position(|w| w == word).unwrap() + 8;
    let mut bad = b.clone();
    bad[at..at + 4].copy_from_slice(&(depth + 1.0).to_le_bytes());
    let e = Scene::from_bytes(&bad).unwrap_err().to_string();
    assert!(e.starts_with("data") && e.contains("ring height"), "{e}");
}

#[test]
fn stations_round_trip_and_a_bad_one_is_refused() {
    let path: Vec<[f64; 3]> = (0..300).map(|k| [0.5 * k as f64, 0.2 * k as f64, -0.4 * k as f64]).collect();
    let log: Vec<f64> = (0..300).map(|k| (k % 7) as f64).collect();
    let mut s = Scene::new();
    let mut opts = AddOptions::new(25.0);
    opts.color_by = Some(crate::scene::color::ColorByArg::values(log));
    s.add_well(&path, 5.0, 8, opts).unwrap();
    let t = &s.objects()[0].tiles[1];
    assert_eq!(t.stations.len(), t.positions.len());
    assert_eq!(t.stations.iter().fold(0.0f32, |a, &b| a.max(b)), 128.0);
    let b = s.to_bytes();
    let back = Scene::from_bytes(&b).unwrap();
    assert_eq!(back.objects()[0].tiles[1].stations[..], t.stations[..]);
    // Version 10 has none: the tube is coloured by its vertices' values, as it was then.
    let v10 = Scene::from_bytes(&s.to_bytes_version(10)).unwrap();
    assert!(v10.objects()[0].tiles.iter().all(|t| t.stations.is_empty()));
    // A station past a tile's last, and one that is not whole.
    let mut word = (t.stations.len() as u64).to_le_bytes().to_vec();
    word.extend(t.stations[0].to_le_bytes());
    let at = b.windows(word.len()).position(|w| w == word).unwrap() + 8;
    for bad_station in [129.0f32, 0.5, f32::NAN] {
        let mut bad = b.clone();
        bad[at..at + 4].copy_from_slice(&bad_station.to_le_bytes());
        let e = Scene::from_bytes(&bad).unwrap_err().to_string();
        assert!(e.starts_with("data") && e.contains("station"), "{e}");
    }
}

#[test]
fn group_variants_round_trip_and_older_versions_read_without_them() {
    // A 41 x 41 field in 2 x 2 tiles: levels from 3 on have variants by side mask (`lod::groups`).
    let mut s = Scene::new();
    let z: Vec<f64> = (0..41 * 41).map(|k| ((k % 41) as f64 * 0.4).sin() * 3.0 + (k / 41) as f64 * 0.1).collect();
    s.add_heightfield(&z, 41, 41, GridFrame::new([0.0; 2], [10.0; 2]), (2, 2), None, AddOptions::new(4.0)).unwrap();
    let levels = |s: &Scene| -> Vec<crate::lod::levels::Level> {
        s.objects()[0].tiles.iter().flat_map(|t| t.levels.clone()).collect()
    };
    let before = levels(&s);
    assert!(before.iter().any(|l| !l.grouped.is_empty()));
    let back = levels(&Scene::from_bytes(&s.to_bytes()).unwrap());
    assert_eq!(back.len(), before.len());
    for (a, b) in back.iter().zip(&before) {
        assert_eq!((&a.grouped, a.grouped_error.to_bits()), (&b.grouped, b.grouped_error.to_bits()));
    }
    assert!(before.iter().all(|l| l.grouped.is_empty() || l.grouped.len() == crate::lod::groups::VARIANTS));
    // Version 9 has none, and versions 10 and 11 had variants by group depth, which reading drops:
    // their levels draw with full borders, the group error their error.
    for version in [9, 10, 11] {
        let old = levels(&Scene::from_bytes(&s.to_bytes_version(version)).unwrap());
        assert_eq!(old.len(), before.len());
        assert!(old.iter().all(|l| l.grouped.is_empty() && l.grouped_error == l.error), "version {version}");
    }
    // A group error below the level's error is damage.
    let mut bad = s.clone();
    let l = bad.objects[0].tiles[0].levels.iter_mut().find(|l| !l.grouped.is_empty()).unwrap();
    l.grouped_error = l.error * 0.5;
    let e = Scene::from_bytes(&bad.to_bytes()).unwrap_err().to_string();
    assert!(e.contains("group error below its error"), "{e}");
}

impl Scene {
    /// The bytes of format `version` 8 to 12 (8: no ring heights; before 10: no group variants;
    /// before 11: no stations; 10 and 11: the first 6 variants in place of those by group depth),
    /// for tests of older formats.
    pub(super) fn to_bytes_version(&self, version: u32) -> Vec<u8> {
        assert!((8..=VERSION).contains(&version));
        self.write(version)
    }
}
