use super::*;

fn spec<'a>(path: &'a [DVec3], values: Option<&'a [f64]>, radius: f64) -> TubeSpec<'a> {
    TubeSpec { path, values, radius, sides: 8 }
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

/// `deviated` with survey noise: each station off the smooth path by up to `noise` (world units).
fn noisy(n: usize, noise: f64) -> Vec<DVec3> {
    let h = |k: usize, m: usize| ((k * 7919 + m * 104_729) % 1000) as f64 / 500.0 - 1.0;
    deviated(n).into_iter().enumerate().map(|(k, p)| p + noise * DVec3::new(h(k, 1), h(k, 2), h(k, 3))).collect()
}

/// A log per station: noise about a trend, no data over the first quarter.
fn log_of(n: usize) -> Vec<f64> {
    (0..n).map(|k| if k < n / 4 { f64::NAN } else { 0.2 + 0.05 * ((k * k * 7919 + 13) % 101) as f64 / 101.0 }).collect()
}

/// Per level vertex, its station along the whole path (the tile's `stations` from its first).
fn station_of(t: &TileMesh, k: u32) -> usize {
    t.ix as usize * SEGMENTS_PER_TILE + t.stations[k as usize] as usize
}

/// A level's kept stations: those its vertices carry.
fn kept_of(t: &TileMesh, lv: &Level) -> Vec<usize> {
    let mut kept: Vec<usize> = lv.indices.iter().map(|&k| station_of(t, k)).collect();
    kept.sort();
    kept.dedup();
    kept
}

/// Level 0's ring vertex of station `k` at side `s` (world units), and its unit radial.
fn fine_vertex(t: &TileMesh, k: usize, s: usize, origin: DVec3) -> (DVec3, DVec3) {
    let v = ((k - t.ix as usize * SEGMENTS_PER_TILE) * 8 + s) as u32;
    (world(t, v, origin), crate::lod::normals::unpack(t.normals[v as usize]).unwrap())
}

#[test]
fn a_straight_well_keeps_its_ends_and_drops_the_rest() {
    let path: Vec<DVec3> = (0..=256).map(|k| DVec3::new(10.0, 20.0, -0.5 * k as f64)).collect();
    let tiles = tube_tiles(&spec(&path, None, 5.0), DVec3::ZERO, 25.0);
    assert_eq!(tiles.len(), 2);
    for t in &tiles {
        assert_eq!(t.fine_triangles(), 2 * 128 * 8 + 6); // one cap each
                                                         // One level: the two end rings of the fine octagon joined, with the path's cap; exact, so
                                                         // no coarser level could drop more.
        assert_eq!(t.levels.len(), 1);
        let l1 = &t.levels[0];
        assert_eq!(l1.indices.len() / 3, 2 * 8 + 6);
        assert_eq!((l1.error, l1.error_z, l1.shading_error), (0.0, 0.0, 0.0));
        // The proxy is that level.
        assert_eq!(t.coarse_triangles(), 2 * 8 + 6);
    }
}

#[test]
fn every_fine_ring_vertex_lies_within_the_level_error() {
    // Survey noise of 2 mm on a deviated well: levels keep more stations where the path bends.
    let path = noisy(1000, 0.002);
    let log = log_of(path.len());
    let radius = 2.0;
    let origin = path[0].round();
    let tiles = tube_tiles(&spec(&path, Some(&log), radius), origin, 25.0);
    assert_eq!(tiles.len(), 999usize.div_ceil(SEGMENTS_PER_TILE));
    let fr = frames(&path, None);
    let mut levels = 0;
    for t in &tiles {
        for lv in &t.levels {
            levels += 1;
            let kept = kept_of(t, lv);
            let (first, last) = (t.ix as usize * SEGMENTS_PER_TILE, (t.ix as usize + 1) * SEGMENTS_PER_TILE);
            assert_eq!((kept[0], *kept.last().unwrap()), (first, last.min(path.len() - 1)));
            for w in kept.windows(2) {
                for k in w[0] + 1..w[1] {
                    let tt = (k - w[0]) as f64 / (w[1] - w[0]) as f64;
                    for s in 0..8 {
                        // The level's point at the same station and side, on its edge between
                        // the kept rings; at exaggeration z the centres stretch, the rings not.
                        let (pk, nk) = fine_vertex(t, k, s, origin);
                        let ((pi, ni), (pj, nj)) = (fine_vertex(t, w[0], s, origin), fine_vertex(t, w[1], s, origin));
                        for z in [1.0, 5.0, 10.0] {
                            let ex = |p: DVec3, c: DVec3| c * DVec3::new(1.0, 1.0, z) + (p - c);
                            let (ck, ci, cj) = (path[k], path[w[0]], path[w[1]]);
                            let d = (ex(pk, ck) - ex(pi, ci).lerp(ex(pj, cj), tt)).length();
                            // render::levels::exaggerated
                            let (e, ez) = (lv.error as f64, lv.error_z.min(lv.error) as f64);
                            let bound = (e * e + (z * z - 1.0) * ez * ez).sqrt();
                            assert!(d <= bound + 1e-4, "z {z}: station {k} side {s} {d} > {bound}");
                        }
                        // The normal turns by at most the shading error.
                        let chord = (nk - ni.lerp(nj, tt).normalize()).length();
                        assert!(chord <= lv.shading_error as f64 + 1e-6, "{chord} > {}", lv.shading_error);
                    }
                    // Over every angle, not only the ring's: the radial gap is exact.
                    let g = radial_gap(fr[w[0]], fr[k], fr[w[1]], tt);
                    let radial = |(d, u): (DVec3, DVec3), a: f64| a.cos() * u + a.sin() * d.cross(u);
                    let most = (0..720)
                        .map(|m| m as f64 * std::f64::consts::TAU / 720.0)
                        .map(|a| (radial(fr[k], a) - radial(fr[w[0]], a).lerp(radial(fr[w[1]], a), tt)).length())
                        .fold(0.0, f64::max);
                    assert!(most <= g + 1e-12 && most >= g * (1.0 - 1e-4), "{most} vs {g}");
                }
            }
        }
    }
    assert!(levels >= 2 * tiles.len(), "{levels} levels");
}

#[test]
fn level_zero_is_the_whole_tube_cut_along_the_path() {
    let path = deviated(300);
    let (v, f, _) = tube(&path, 3.0, 8);
    let origin = DVec3::new(460_000.0, 5_930_000.0, -1500.0);
    let tiles = tube_tiles(&spec(&path, None, 3.0), origin, 25.0);
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
fn neighbours_at_any_levels_meet_ring_to_ring() {
    let path = noisy(600, 0.01);
    let origin = path[0].round();
    let tiles = tube_tiles(&spec(&path, None, 2.0), origin, 25.0);
    for w in tiles.windows(2) {
        let at = w[1].ix as usize * SEGMENTS_PER_TILE;
        let (end, axis) = (path[at], direction(&path, at));
        // The vertices of a level at the radius from the shared station: its ring.
        let ring_of = |idx: &[u32], t: &TileMesh| -> Vec<[i64; 3]> {
            let mut r: Vec<[i64; 3]> = idx
                .iter()
                .map(|&k| world(t, k, origin))
                .filter(|p| (*p - end).length() < 3.0 && (*p - end).dot(axis).abs() < 1e-3)
                .map(|p| [p.x, p.y, p.z].map(|c| (c * 1e3).round() as i64))
                .collect();
            r.sort();
            r.dedup();
            r
        };
        let fine = ring_of(&w[0].fine, &w[0]);
        assert_eq!(fine.len(), 8);
        let lists = |t: &TileMesh| {
            std::iter::once(t.fine.clone()).chain(t.levels.iter().map(|l| l.indices.clone())).collect::<Vec<_>>()
        };
        for la in lists(&w[0]) {
            assert_eq!(ring_of(&la, &w[0]), fine);
        }
        for lb in lists(&w[1]) {
            assert_eq!(ring_of(&lb, &w[1]), fine);
        }
    }
}

#[test]
fn a_log_takes_no_part_in_which_stations_stay() {
    // The same path with and without a noisy log: the same levels; every vertex carries its
    // station's value, and the tile's table holds the log by station.
    let path = noisy(700, 0.01);
    let log = log_of(path.len());
    let plain = tube_tiles(&spec(&path, None, 2.0), DVec3::ZERO, 25.0);
    let logged = tube_tiles(&spec(&path, Some(&log), 2.0), DVec3::ZERO, 25.0);
    for (a, b) in plain.iter().zip(&logged) {
        assert!(a.values.is_empty() && a.stations.is_empty());
        assert_eq!(b.values.len(), b.positions.len());
        assert_eq!(b.stations.len(), b.positions.len());
        assert_eq!(a.levels.len(), b.levels.len());
        for (la, lb) in a.levels.iter().zip(&b.levels) {
            assert_eq!(la.indices[..], lb.indices[..]);
            assert_eq!((la.error, la.shading_error), (lb.error, lb.shading_error));
        }
        for k in 0..b.positions.len() as u32 {
            let (v, want) = (b.values[k as usize], log[station_of(b, k)] as f32);
            assert!(v == want || (v.is_nan() && want.is_nan()));
        }
        let ([n, one, _], table) = log_table(b).unwrap();
        let first = b.ix as usize * SEGMENTS_PER_TILE;
        assert_eq!((n as usize, one), ((first + SEGMENTS_PER_TILE).min(path.len() - 1) - first + 1, 1));
        for (s, &v) in table.iter().enumerate() {
            assert!(v == log[first + s] as f32 || (v.is_nan() && log[first + s].is_nan()));
        }
    }
    // A noisy log on a straight well keeps only its end stations.
    let straight: Vec<DVec3> = (0..=128).map(|k| DVec3::new(0.0, 0.0, -0.5 * k as f64)).collect();
    let t = &tube_tiles(&spec(&straight, Some(&log[..129]), 1.0), DVec3::ZERO, 25.0)[0];
    assert_eq!(kept_of(t, &t.levels[0]), vec![0, 128]);
}

#[test]
fn levels_shrink_and_bound_the_box() {
    let path = noisy(1000, 0.01);
    for t in tube_tiles(&spec(&path, None, 1.0), DVec3::ZERO, 25.0) {
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
    }
}

#[test]
fn exaggeration_stretches_only_the_path_deviation() {
    // Straight down 0.5 m a station, wiggling sideways by up to 3 m: its dropped stations move
    // sideways, so its levels' errors are horizontal (error_z well below error).
    let path: Vec<DVec3> = (0..600).map(|k| DVec3::new(3.0 * (k as f64 * 0.02).sin(), 0.0, -0.5 * k as f64)).collect();
    let tiles = tube_tiles(&spec(&path, None, 2.0), DVec3::ZERO, 25.0);
    let levels: Vec<&Level> = tiles.iter().flat_map(|t| &t.levels).collect();
    assert!(levels.len() >= 2 * tiles.len(), "{} levels", levels.len());
    for l in levels {
        assert!(l.error > 0.0 && l.error_z <= 0.125 * l.error, "{} vs {}", l.error_z, l.error);
    }
    // A well along the horizontal, wiggling sideways: rings are not exaggerated
    // (TileMesh::ring_z) and its path stays level, so no part of its error grows.
    let flat: Vec<DVec3> = (0..300).map(|k| DVec3::new(0.5 * k as f64, 3.0 * (k as f64 * 0.02).sin(), 0.0)).collect();
    for t in tube_tiles(&spec(&flat, None, 2.0), DVec3::ZERO, 25.0) {
        assert!(!t.levels.is_empty());
        assert!(t.levels.iter().all(|l| l.error > 0.0 && l.error_z == 0.0), "{:?}", t.levels);
    }
}

#[test]
fn ring_heights_are_the_vertices_height_above_their_station() {
    // A well dipping at 45 degrees: every ring vertex minus its ring height is its station's
    // height (f32), within the tile's box; caps repeat their ring's.
    let path: Vec<DVec3> =
        (0..=300).map(|k| DVec3::new(0.4 * k as f64, 0.1 * k as f64, -0.4 * k as f64 - 1000.0)).collect();
    let origin = DVec3::new(0.0, 0.0, -1000.0);
    for t in tube_tiles(&spec(&path, None, 5.0), origin, 25.0) {
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
