use super::*;
use std::f64::consts::PI;

fn spec<'a>(path: &'a [DVec3], values: Option<&'a [f64]>, radius: f64, value_tol: f64) -> TubeSpec<'a> {
    TubeSpec { path, values, radius, sides: 8, value_tol }
}

fn world(t: &TileMesh, k: u32, origin: DVec3) -> DVec3 {
    DVec3::from_array(t.positions[k as usize].map(f64::from)) + origin
}

/// A well 0.5 m a station: vertical for 150 m, building up to 60° over 200 m, then straight.
fn deviated(n: usize) -> Vec<DVec3> {
    let mut p = DVec3::new(460_000.0, 5_930_000.0, -1500.0);
    (0..n)
        .map(|k| {
            let s = k as f64 * 0.5;
            let a = ((s - 150.0) / 200.0).clamp(0.0, 1.0) * 60f64.to_radians();
            let here = p;
            p += 0.5 * DVec3::new(a.sin(), 0.0, -a.cos());
            here
        })
        .collect()
}

#[test]
fn a_straight_well_keeps_its_ends_and_drops_the_rest() {
    let path: Vec<DVec3> = (0..=256).map(|k| DVec3::new(10.0, 20.0, -0.5 * k as f64)).collect();
    let tiles = tube_tiles(&spec(&path, None, 5.0, 0.0), DVec3::ZERO, 25.0);
    assert_eq!(tiles.len(), 2);
    for t in &tiles {
        assert_eq!(t.fine_triangles(), 2 * 128 * 8 + 6); // one cap each
                                                         // Level 1: 6 sides between the two end stations, capped: 2 * 6 + 2 * 4 triangles.
        let l1 = &t.levels[0];
        assert_eq!(l1.indices.len() / 3, 2 * 6 + 2 * 4);
        // The error is the distance between the hexagon and the octagon (no station lies off the
        // axis): the hexagon of the octagon's perimeter reaches 5 * 8 sin(pi/8) / (6 sin(pi/6)).
        let r6 = 5.0 * 8.0 * (PI / 8.0).sin() / (6.0 * (PI / 6.0).sin());
        let gap = (r6 - 5.0 * (PI / 8.0).cos()).max(5.0 - r6 * (PI / 6.0).cos());
        let bound = (gap * gap + gap * gap / 8.0).sqrt(); // tube::level_errors with dev = 0
        assert!((l1.error as f64 - bound).abs() < 1e-5 && l1.error_z == 0.0, "{} vs {bound}", l1.error);
        // Radial normals on a straight path: the same shading at every level.
        assert!(t.levels.iter().all(|l| l.shading_error < 1e-9), "{:?}", t.levels);
        // The proxy is the first level with at most 1/25 of the fine triangles.
        assert_eq!(t.coarse_triangles(), 2 * 6 + 2 * 4);
    }
}

#[test]
fn every_dropped_station_lies_within_the_level_error_of_the_kept_path() {
    let path = deviated(1000);
    let radius = 2.0;
    let origin = path[0].round();
    let tiles = tube_tiles(&spec(&path, None, radius, 0.0), origin, 25.0);
    assert_eq!(tiles.len(), 999usize.div_ceil(SEGMENTS_PER_TILE));
    for (l, (&sides, &tol)) in LEVEL_SIDES.iter().zip(&LEVEL_TOL_RADII).enumerate() {
        let a = 0;
        let b = SEGMENTS_PER_TILE;
        let Decimated { kept, dev, dev_z, chord } =
            decimate(&spec(&path, None, radius, 0.0), a, b, tol * radius, LEVEL_CHORD[l]);
        assert_eq!((kept[0], *kept.last().unwrap()), (a, b));
        // Each dropped station within tol of the kept segment about it, and dev the largest such.
        let (mut largest, mut largest_z) = (0.0f64, 0.0f64);
        for w in kept.windows(2) {
            for k in w[0] + 1..w[1] {
                let (d, t) = to_segment(path[k], path[w[0]], path[w[1]]);
                largest_z = largest_z.max((path[w[0]].lerp(path[w[1]], t) - path[k]).z.abs());
                assert!(d <= tol * radius + 1e-9, "level {l}: station {k} {d} > {}", tol * radius);
                let turn = (direction(&path, k) - (path[w[1]] - path[w[0]]).normalize()).length();
                assert!(turn <= LEVEL_CHORD[l] + 1e-12 && turn <= chord + 1e-12);
                largest = largest.max(d);
            }
        }
        assert!((largest - dev).abs() < 1e-12);
        assert!((largest_z - dev_z).abs() < 1e-9 && dev_z <= dev + 1e-12);
        // A tile's level with these sides has this error.
        let polygon = level_polygon(radius, 8, sides).1;
        if let Some(lv) = tiles[0].levels.get(l) {
            let want = ((dev + polygon).powi(2) + polygon * polygon / 8.0).sqrt().max(3.0 * dev_z);
            assert!((lv.error as f64 - want).abs() < 1e-4, "level {l}: {} vs {want}", lv.error);
            assert!((lv.shading_error as f64 - chord).abs() < 1e-6);
            assert!(lv.error_z >= (3.0 * dev_z as f32) * (1.0 - 1e-6) && lv.error_z <= lv.error, "level {l}");
        }
    }
    // Every vertex of every level within its error + radius of the fine path's nearest segment.
    for t in &tiles {
        for lv in &t.levels {
            for &k in lv.indices.iter() {
                let p = world(t, k, origin);
                let d = path.windows(2).map(|s| to_segment(p, s[0], s[1]).0).fold(f64::INFINITY, f64::min);
                assert!(d <= radius + lv.error as f64 + 1e-3, "{d}");
            }
        }
    }
}

#[test]
fn level_zero_is_the_whole_tube_cut_along_the_path() {
    let path = deviated(300);
    let (v, f, _) = tube(&path, 3.0, 8);
    let origin = DVec3::new(460_000.0, 5_930_000.0, -1500.0);
    let tiles = tube_tiles(&spec(&path, None, 3.0, 0.0), origin, 25.0);
    // Side triangles in order: tile by tile they are the tube's; the caps close the end tiles.
    let n_sides = 2 * 299 * 8;
    let mut got: Vec<[DVec3; 3]> = Vec::new();
    let mut caps: Vec<[DVec3; 3]> = Vec::new();
    for t in &tiles {
        let tris: Vec<[DVec3; 3]> =
            t.fine.chunks_exact(3).map(|c| [c[0], c[1], c[2]].map(|k| world(t, k, origin))).collect();
        let s =
            if t.ix as usize == tiles.len() - 1 { 299 - t.ix as usize * SEGMENTS_PER_TILE } else { SEGMENTS_PER_TILE };
        got.extend_from_slice(&tris[..2 * s * 8]);
        caps.extend_from_slice(&tris[2 * s * 8..]);
    }
    let want: Vec<[DVec3; 3]> = f.iter().map(|t| t.map(|k| DVec3::from_array(v[k as usize]))).collect();
    assert_eq!(got.len(), n_sides);
    assert_eq!(caps.len() + got.len(), want.len());
    let close = |a: &[DVec3; 3], b: &[DVec3; 3]| (0..3).all(|i| (a[i] - b[i]).length() < 1e-4);
    assert!(got.iter().zip(&want[..n_sides]).all(|(a, b)| close(a, b)));
    // tube's caps alternate first end, last end.
    let (first, last): (Vec<_>, Vec<_>) = want[n_sides..].iter().enumerate().partition(|(i, _)| i % 2 == 0);
    let want_caps: Vec<&[DVec3; 3]> = first.into_iter().chain(last).map(|(_, t)| t).collect();
    assert!(caps.iter().zip(want_caps).all(|(a, b)| close(a, b)));
}

#[test]
fn neighbours_at_one_level_meet_ring_to_ring() {
    let path = deviated(600);
    let origin = path[0].round();
    let tiles = tube_tiles(&spec(&path, None, 2.0, 0.0), origin, 25.0);
    for w in tiles.windows(2) {
        let at = w[1].ix as usize * SEGMENTS_PER_TILE;
        let (end, axis) = (path[at], direction(&path, at));
        // The vertices of a level at the radius from the shared station: its ring (and caps).
        let ring_of = |lv: &Level, t: &TileMesh| -> Vec<[i64; 3]> {
            let mut r: Vec<[i64; 3]> = lv
                .indices
                .iter()
                .map(|&k| world(t, k, origin))
                .filter(|p| (*p - end).length() < 3.0 && (*p - end).dot(axis).abs() < 1e-3)
                .map(|p| [p.x, p.y, p.z].map(|c| (c * 1e2).round() as i64))
                .collect();
            r.sort();
            r.dedup();
            r
        };
        // Levels of the same sides on both sides of the station meet ring to ring.
        let mut pairs = 0;
        for la in &w[0].levels {
            for lb in &w[1].levels {
                let (a, b) = (ring_of(la, &w[0]), ring_of(lb, &w[1]));
                assert!(LEVEL_SIDES.contains(&a.len()) && LEVEL_SIDES.contains(&b.len()));
                if a.len() == b.len() {
                    assert_eq!(a, b);
                    pairs += 1;
                }
            }
        }
        assert!(pairs > 0 || w[0].levels.is_empty() || w[1].levels.is_empty());
    }
}

#[test]
fn a_log_keeps_its_colours_within_the_tolerance() {
    let path: Vec<DVec3> = (0..=128).map(|k| DVec3::new(0.0, 0.0, -0.5 * k as f64)).collect();
    // NaN above 40, a linear ramp to 80, then noise.
    let log: Vec<f64> = (0..=128)
        .map(|k| match k {
            0..40 => f64::NAN,
            40..80 => 0.1 + 0.002 * (k - 40) as f64,
            _ => 0.2 + 0.05 * ((k * k * 7919 + 13) % 101) as f64 / 101.0,
        })
        .collect();
    let tol = 0.3 / 512.0;
    let s = spec(&path, Some(&log), 1.0, tol);
    let kept = decimate(&s, 0, 128, 64.0, 1.0).kept;
    // The NaN run and the ramp collapse to their ends; the noise keeps every station.
    assert!(kept.contains(&39) && kept.contains(&40) && kept.contains(&79), "{kept:?}");
    assert!(!kept.contains(&20) && !kept.contains(&60), "{kept:?}");
    assert!((80..=128).all(|k| kept.contains(&k)), "{kept:?}");
    for w in kept.windows(2) {
        for k in w[0] + 1..w[1] {
            let t = (k - w[0]) as f64 / (w[1] - w[0]) as f64;
            let (a, b) = (log[w[0]], log[w[1]]);
            if log[k].is_nan() {
                assert!(a.is_nan() && b.is_nan());
            } else {
                assert!((log[k] - (a + t * (b - a))).abs() <= tol + 1e-12);
            }
        }
    }
    // Every level vertex carries its station's value.
    let tiles = tube_tiles(&s, DVec3::ZERO, 25.0);
    let t = &tiles[0];
    assert_eq!(t.values.len(), t.positions.len());
    for lv in &t.levels {
        for &k in lv.indices.iter() {
            let z = t.positions[k as usize][2] as f64;
            let station = (-z / 0.5).round() as usize;
            let (v, want) = (t.values[k as usize], log[station] as f32);
            assert!(v == want || (v.is_nan() && want.is_nan()) || (-z / 0.5 - station as f64).abs() > 0.1);
        }
    }
}

#[test]
fn levels_shrink_and_bound_the_box() {
    let path = deviated(1000);
    for t in tube_tiles(&spec(&path, None, 1.0, 0.0), DVec3::ZERO, 25.0) {
        let mut prev = t.fine_triangles();
        for lv in &t.levels {
            let n = lv.indices.len() / 3;
            assert!(n as f64 <= 0.8 * prev as f64);
            prev = n;
            for &k in lv.indices.iter() {
                let p = t.positions[k as usize];
                assert!((0..3).all(|a| t.bbox_min[a] <= p[a] && p[a] <= t.bbox_max[a]));
            }
        }
        assert!(t.levels.windows(2).all(|w| w[0].error <= w[1].error));
    }
}

#[test]
fn level_polygons_keep_the_perimeter_and_bound_the_gap() {
    for sides in [3usize, 4, 6, 8] {
        let (r, gap) = level_polygon(2.0, 8, sides);
        let perimeter = |n: usize, r: f64| 2.0 * n as f64 * r * (PI / n as f64).sin();
        assert!((perimeter(sides, r) - perimeter(8, 2.0)).abs() < 1e-12);
        // The gap bounds the radial distance between the polygons in every direction.
        let rho = |n: usize, r: f64, a: f64| {
            let h = PI / n as f64;
            r * h.cos() / ((a.rem_euclid(2.0 * h)) - h).cos()
        };
        for k in 0..3600 {
            let a = k as f64 * TAU_STEP;
            assert!((rho(sides, r, a) - rho(8, 2.0, a)).abs() <= gap + 1e-12);
        }
        if sides == 8 {
            assert!((r - 2.0).abs() < 1e-12);
        }
    }
}

const TAU_STEP: f64 = std::f64::consts::TAU / 3600.0;

#[test]
fn exaggeration_stretches_only_the_path_deviation() {
    // Straight down 0.5 m a station, wiggling sideways by up to 3 m: its dropped stations move
    // sideways, so its levels' errors are horizontal (error_z well below error).
    let path: Vec<DVec3> = (0..600).map(|k| DVec3::new(3.0 * (k as f64 * 0.02).sin(), 0.0, -0.5 * k as f64)).collect();
    let tiles = tube_tiles(&spec(&path, None, 2.0, 0.0), DVec3::ZERO, 25.0);
    let levels: Vec<&Level> = tiles.iter().flat_map(|t| &t.levels).collect();
    assert!(levels.len() >= 2 * tiles.len(), "{} levels", levels.len());
    for l in levels {
        assert!(l.error > 0.05 && l.error_z <= 0.125 * l.error, "{} vs {}", l.error_z, l.error);
    }
    // A well along the horizontal, wiggling sideways: its polygons stand upright, but rings are
    // not exaggerated (TileMesh::ring_z) and its path stays level, so no part of its error grows.
    let flat: Vec<DVec3> = (0..300).map(|k| DVec3::new(0.5 * k as f64, 3.0 * (k as f64 * 0.02).sin(), 0.0)).collect();
    for t in tube_tiles(&spec(&flat, None, 2.0, 0.0), DVec3::ZERO, 25.0) {
        assert!(!t.levels.is_empty());
        assert!(t.levels.iter().all(|l| l.error > 0.05 && l.error_z == 0.0), "{:?}", t.levels);
    }
}

#[test]
fn ring_heights_are_the_vertices_height_above_their_station() {
    // A well dipping at 45 degrees: every ring vertex minus its ring height is its station's
    // height (f32), within the tile's box; caps repeat their ring's.
    let path: Vec<DVec3> =
        (0..=300).map(|k| DVec3::new(0.4 * k as f64, 0.1 * k as f64, -0.4 * k as f64 - 1000.0)).collect();
    let origin = DVec3::new(0.0, 0.0, -1000.0);
    for t in tube_tiles(&spec(&path, None, 5.0, 0.0), origin, 25.0) {
        assert_eq!(t.ring_z.len(), t.positions.len());
        for (p, &r) in t.positions.iter().zip(t.ring_z.iter()) {
            let centre = p[2] - r;
            assert!((t.bbox_min[2]..=t.bbox_max[2]).contains(&centre));
            let near = path.iter().any(|s| (s.z - origin.z - centre as f64).abs() < 1e-3);
            assert!(near && r.abs() <= 5.0 * 1.2, "{r} {centre}");
        }
        assert!(t.ring_z.iter().any(|&r| r.abs() > 3.0), "tilted rings reach up and down");
    }
}
