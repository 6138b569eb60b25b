//! Tubes around well paths, cut into tiles along the path, with levels of detail.
//!
//! Contract of [`tube`]: for a path of n >= 2 stations (consecutive duplicates dropped by the
//! caller) and `sides` >= 3, the tube has one ring of `sides` vertices per station, each ring the
//! regular polygon of circumradius `radius` centred on the station in the plane normal to the
//! path's direction there (the mean of the two segments' directions at inner stations), turned
//! from station to station by parallel transport (no twist), and a flat cap at each end, in all
//! 2 (n - 1) sides plus 2 (sides - 2) triangles, wound outwards. The polygon's first vertex of
//! the first ring lies along the horizontal normal of the first segment when it has one (+x for
//! a vertical start).
//!
//! Contract of [`tube_tiles`]: the path is cut into runs of [`SEGMENTS_PER_TILE`] segments (the
//! last shorter), one tile each, neighbours sharing their end station.
//! * Level 0 of a tile is exactly its part of [`tube`]'s rings and side triangles (the caps
//!   only on the tiles holding the path's ends), so the fine tubes of all tiles together are
//!   [`tube`]'s triangles.
//! * Level l >= 1 is a tube of `sides_l` sides (non-increasing, at least 3) around a subset of
//!   the tile's stations that keeps its two end stations: a station is dropped only where it lies
//!   within `tol_l` of the segment between the kept stations about it and the path's direction
//!   there turns by a normal chord of at most `chord_l` from that segment's (Douglas–Peucker on
//!   both), and, for a tube coloured by a log, where its value is within `value_tol` of the value
//!   interpolated there between those stations (no data only between no data: both stations
//!   where a log starts or stops having data stay). Each level piece is closed by flat caps at
//!   both ends, so that neighbours drawn at different levels leave no gap to see through; its end
//!   rings use level 0's frames (a level's rings are turned by parallel transport along the kept
//!   stations, the remaining twist spread evenly), so neighbours at the same level meet ring to
//!   ring.
//! * A level's polygon has the fine polygon's perimeter (circumradius `r_l = radius * sides
//!   sin(pi / sides) / (sides_l sin(pi / sides_l))`), so its silhouette is as wide as level 0's
//!   on average over directions (a convex polygon's mean width is its perimeter over pi): an
//!   inscribed triangle would be a quarter thinner, which on a tube a few pixels wide changes
//!   most of its pixels. A level's error (world units) bounds the distance from its surface to
//!   level 0's, drawn at any exaggeration (see the next point): from the largest distance `dev`
//!   of a dropped station from the kept polyline (`dev_z` of it vertical) and the largest
//!   distance `gap` between the two polygons, `max(r_l - radius cos(pi / sides), radius - r_l
//!   cos(pi / sides_l))` (each lies between its inscribed and circumscribed circles), as
//!   `level_errors` combines them.
//! * Every vertex carries its height above its ring's centre (`TileMesh::ring_z`; a cap's, its
//!   ring's): the lit pass exaggerates the centre and not that offset, so a tube keeps its radius
//!   under exaggeration. Each vertex minus it lies within the tile's box (`fit_ring_z`).
//! * Shading: ring vertices carry radial unit normals (cap vertices none: flat). Interpolated
//!   over a side facet, a radial normal points from the axis to the facet's point, so at the same
//!   angle about the path every level's normal is level 0's up to the turn of the path's
//!   direction; a level's shading error ([`super::levels::Level::shading_error`]) is the largest
//!   such turn (a chord of unit directions) over the tile's stations. Where a ray meets two
//!   polygons at different angles (towards the silhouette), the normals differ as the points do,
//!   within the geometric error.
//! * A candidate level that would keep more than 0.8 of the triangles of the level before it is
//!   left out (the next, coarser candidate may still pay); at most
//!   [`super::levels::MAX_LEVELS`] levels. The coarse proxy (prepass) is the first level with at most
//!   1/coarse_factor of the fine triangles, else the coarsest.
//!
//! A tube a few pixels wide is thus drawn with 3 or 4 sides and a station every few pixels
//! along the path, where its fine level has `sides` sides at every station of the log.

use super::levels::{Level, MAX_LEVELS};
use super::{normals, TileMesh};
use glam::DVec3;
use rayon::prelude::*;

/// Segments per tile: a long well is cut into tiles so that culling and levels of detail apply
/// per piece.
pub const SEGMENTS_PER_TILE: usize = 128;

/// Per level l = 1.. its sides (at most the fine level's), station tolerance in radii, and the
/// largest normal chord a dropped station may cause (the turn of the path's direction there).
const LEVEL_SIDES: [usize; MAX_LEVELS] = [6, 4, 3, 3, 3];
const LEVEL_TOL_RADII: [f64; MAX_LEVELS] = [0.25, 1.0, 4.0, 16.0, 64.0];
const LEVEL_CHORD: [f64; MAX_LEVELS] = [2e-4, 1e-3, 4e-3, 1.6e-2, 6.4e-2];

/// Direction of the path at station `k`: the mean of its segments' unit directions (the
/// incoming one at a hairpin).
fn direction(path: &[DVec3], k: usize) -> DVec3 {
    let n = path.len();
    let a = if k > 0 { (path[k] - path[k - 1]).normalize() } else { DVec3::ZERO };
    let b = if k + 1 < n { (path[k + 1] - path[k]).normalize() } else { DVec3::ZERO };
    let d = a + b;
    if d.length_squared() > 1e-12 {
        d.normalize()
    } else if a != DVec3::ZERO {
        a
    } else {
        b
    }
}

/// Per station its direction d and ring axis u (unit, normal to d), transported from `u0` (or
/// the first segment's horizontal normal when None) without twist.
fn frames(path: &[DVec3], u0: Option<DVec3>) -> Vec<(DVec3, DVec3)> {
    let d0 = direction(path, 0);
    let mut u = u0.unwrap_or_else(|| {
        let u = DVec3::Z.cross(d0);
        if u.length_squared() < 1e-12 {
            DVec3::X // vertical start
        } else {
            u.normalize()
        }
    });
    let mut prev = d0;
    (0..path.len())
        .map(|k| {
            let d = direction(path, k);
            // Parallel transport: turn u by the rotation taking the previous direction onto this one.
            if prev.cross(d).length_squared() > 1e-24 {
                u = (glam::DQuat::from_rotation_arc(prev, d) * u).normalize();
            }
            u = (u - d * u.dot(d)).normalize();
            prev = d;
            (d, u)
        })
        .collect()
}

/// The ring of `sides` vertices about `p` in the plane normal to `d`, starting along `u`.
fn ring(p: DVec3, d: DVec3, u: DVec3, radius: f64, sides: usize) -> impl Iterator<Item = DVec3> {
    let v = d.cross(u);
    (0..sides).map(move |s| {
        let a = std::f64::consts::TAU * s as f64 / sides as f64;
        p + radius * (a.cos() * u + a.sin() * v)
    })
}

/// The tube around `path` (see the module's contract): (vertices, faces, the station of each
/// vertex). `path` must be finite with at least two distinct consecutive stations.
pub fn tube(path: &[DVec3], radius: f64, sides: usize) -> (Vec<[f64; 3]>, Vec<[i64; 3]>, Vec<usize>) {
    let n = path.len();
    let mut verts = Vec::with_capacity(n * sides);
    let mut station = Vec::with_capacity(n * sides);
    for (k, (p, (d, u))) in path.iter().zip(frames(path, None)).enumerate() {
        verts.extend(ring(*p, d, u, radius, sides).map(|q| q.to_array()));
        station.extend(std::iter::repeat_n(k, sides));
    }
    let mut faces = Vec::with_capacity(2 * (n - 1) * sides + 2 * sides);
    side_faces(0, n, sides, &mut |t| faces.push(t.map(i64::from)));
    let at = |k: usize, s: usize| (k * sides + s % sides) as i64;
    // Caps: fans over each end ring, facing away from the path.
    for s in 1..sides - 1 {
        faces.push([at(0, 0), at(0, s + 1), at(0, s)]);
        faces.push([at(n - 1, 0), at(n - 1, s), at(n - 1, s + 1)]);
    }
    (verts, faces, station)
}

/// The side triangles between consecutive rings `first..first + rings` of `sides` vertices each
/// (ring r's vertex s at `r * sides + s`, local to the rings given), wound outwards: (u, v, d) is
/// right-handed, so rings run counter-clockwise about d.
fn side_faces(first: usize, rings: usize, sides: usize, out: &mut impl FnMut([u32; 3])) {
    let at = |k: usize, s: usize| (k * sides + s % sides) as u32;
    for k in first..first + rings - 1 {
        for s in 0..sides {
            out([at(k, s), at(k, s + 1), at(k + 1, s + 1)]);
            out([at(k, s), at(k + 1, s + 1), at(k + 1, s)]);
        }
    }
}

/// A well's tube to be tiled: stations (distinct consecutive), the log per station (None: not
/// coloured by a log), radius and sides of the fine tube, and the value tolerance of the levels.
pub struct TubeSpec<'a> {
    pub path: &'a [DVec3],
    pub values: Option<&'a [f64]>,
    pub radius: f64,
    pub sides: usize,
    pub value_tol: f64,
}

/// Builds one piece of tube into `tile`: rings at `stations` (path indices) with the frames
/// `frames` (direction, axis) and `sides` sides, side triangles, and caps at the ends asked for.
/// Returns the piece's side triangles and its caps' (indices into `tile.positions`).
fn piece(
    spec: &TubeSpec<'_>,
    origin: DVec3,
    stations: &[usize],
    frames: &[(DVec3, DVec3)],
    (sides, radius): (usize, f64),
    caps: (bool, bool),
    tile: &mut TileMesh,
) -> (Vec<u32>, Vec<u32>) {
    let base = tile.positions.len() as u32;
    let local = |p: DVec3| (p - origin).as_vec3().to_array();
    for (&k, &(d, u)) in stations.iter().zip(frames) {
        let c = spec.path[k];
        let cz = (c - origin).z;
        for q in ring(c, d, u, radius, sides) {
            let p = local(q);
            tile.positions.push(p);
            tile.ring_z.push((p[2] as f64 - cz) as f32);
            tile.normals.push(normals::pack((q - c) / radius));
            if let Some(v) = spec.values {
                tile.values.push(v[k] as f32);
            }
        }
    }
    let mut tris = Vec::with_capacity(6 * stations.len() * sides);
    side_faces(0, stations.len(), sides, &mut |t| tris.extend(t.map(|i| i + base)));
    // Caps with their own vertices (no smooth normal: flat), facing away from the path.
    let mut caps_tris = Vec::new();
    for (end, want) in [(0usize, caps.0), (stations.len() - 1, caps.1)] {
        if !want {
            continue;
        }
        let cap = tile.positions.len() as u32;
        let ring0 = base as usize + end * sides;
        for s in 0..sides {
            tile.positions.push(tile.positions[ring0 + s]);
            tile.ring_z.push(tile.ring_z[ring0 + s]);
            tile.normals.push(normals::NONE);
            if let Some(v) = spec.values {
                tile.values.push(v[stations[end]] as f32);
            }
        }
        for s in 1..sides as u32 - 1 {
            if end == 0 {
                caps_tris.extend([cap, cap + s + 1, cap + s]);
            } else {
                caps_tris.extend([cap, cap + s, cap + s + 1]);
            }
        }
    }
    (tris, caps_tris)
}

/// The circumradius of a level's polygon of `sides` sides about a fine tube of `radius` and
/// `fine_sides` sides: the one of equal perimeter, so that the level's silhouette is as wide as
/// the fine tube's on average over directions (a polygon's mean width is its perimeter / pi);
/// and the largest distance between the two polygons, both centred on the axis: each lies between
/// its inscribed and circumscribed circles.
fn level_polygon(radius: f64, fine_sides: usize, sides: usize) -> (f64, f64) {
    use std::f64::consts::PI;
    let half = |n: usize| PI / n as f64;
    let r = radius * (fine_sides as f64 * half(fine_sides).sin()) / (sides as f64 * half(sides).sin());
    let gap = (r - radius * half(fine_sides).cos()).max(radius - r * half(sides).cos());
    (r, gap)
}

/// Distance from `p` to the segment `a`–`b`, and the segment parameter of its closest point.
fn to_segment(p: DVec3, a: DVec3, b: DVec3) -> (f64, f64) {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 { ((p - a).dot(ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    ((a + t * ab - p).length(), t)
}

/// What [`decimate`] kept and the bounds it measured.
struct Decimated {
    /// The kept stations, in order.
    kept: Vec<usize>,
    /// The largest distance of a dropped station from its kept segment, and the largest vertical
    /// part of that displacement.
    dev: f64,
    dev_z: f64,
    /// The largest chord between a station's direction and the level's there (its segment's for
    /// a dropped station, its ring's for a kept one).
    chord: f64,
}

/// The stations of `a..=b` kept at tolerance `tol` and normal chord `chord` (see the module's
/// contract) and the level's bounds.
fn decimate(spec: &TubeSpec<'_>, a: usize, b: usize, tol: f64, chord: f64) -> Decimated {
    let (path, values) = (spec.path, spec.values);
    let mut keep = vec![false; b - a + 1];
    keep[0] = true;
    keep[b - a] = true;
    // Where a log turns from no data to data or back, both stations stay.
    if let Some(v) = values {
        for k in a..b {
            if v[k].is_nan() != v[k + 1].is_nan() {
                keep[k - a] = true;
                keep[k + 1 - a] = true;
            }
        }
    }
    let runs: Vec<usize> = (a..=b).filter(|&k| keep[k - a]).collect();
    let mut stack: Vec<(usize, usize)> = runs.windows(2).map(|w| (w[0], w[1])).collect();
    let (mut max_dev, mut max_dev_z) = (0.0f64, 0.0f64);
    while let Some((i, j)) = stack.pop() {
        // The station breaking the bounds most (by its ratio to them), if any.
        let mut worst: Option<(usize, f64)> = None;
        for k in i + 1..j {
            let (d, t) = to_segment(path[k], path[i], path[j]);
            let turn = (direction(path, k) - (path[j] - path[i]).normalize()).length();
            let mut ratio = (d / tol).max(turn / chord);
            if let Some(v) = values {
                let (vi, vj, vk) = (v[i], v[j], v[k]);
                // Runs between kept stations are all data or all no data (transitions are kept).
                if !(vi.is_nan() && vj.is_nan() && vk.is_nan()) {
                    let dv = (vk - (vi + t * (vj - vi))).abs();
                    ratio = ratio.max((dv / spec.value_tol.max(1e-300)).min(1e300));
                }
            }
            if ratio > 1.0 && worst.is_none_or(|(_, r)| ratio > r) {
                worst = Some((k, ratio));
            }
        }
        match worst {
            Some((k, _)) => {
                keep[k - a] = true;
                stack.push((i, k));
                stack.push((k, j));
            }
            None => {
                for k in i + 1..j {
                    let (d, t) = to_segment(path[k], path[i], path[j]);
                    max_dev = max_dev.max(d);
                    max_dev_z = max_dev_z.max((path[i].z + t * (path[j].z - path[i].z) - path[k].z).abs());
                }
            }
        }
    }
    let kept: Vec<usize> = (a..=b).filter(|&k| keep[k - a]).collect();
    // The level's direction at a station: its segment's, or at a kept one the mean of its
    // segments' (level 0's at the tile's ends).
    let pts: Vec<DVec3> = kept.iter().map(|&k| path[k]).collect();
    let mut max_chord = 0.0f64;
    for (m, w) in kept.windows(2).enumerate() {
        let seg = (path[w[1]] - path[w[0]]).normalize();
        for k in w[0] + 1..w[1] {
            max_chord = max_chord.max((direction(path, k) - seg).length());
        }
        if m > 0 {
            max_chord = max_chord.max((direction(path, w[0]) - direction(&pts, m)).length());
        }
    }
    Decimated { kept, dev: max_dev, dev_z: max_dev_z, chord: max_chord }
}

/// Frames of a level's kept stations: level 0's at both ends, parallel transport between with
/// the twist that leaves at the last station spread evenly over the stations.
fn level_frames(path: &[DVec3], kept: &[usize], fine: &[(DVec3, DVec3)], a: usize) -> Vec<(DVec3, DVec3)> {
    let pts: Vec<DVec3> = kept.iter().map(|&k| path[k]).collect();
    let mut fr = frames(&pts, Some(fine[0].1));
    let m = fr.len();
    fr[0] = fine[0];
    let last = fine[kept[m - 1] - a];
    // Twist: the angle about the last direction from the transported axis to level 0's.
    let (d, u) = (last.0, fr[m - 1].1);
    let u = (u - d * u.dot(d)).normalize_or(last.1);
    let twist = d.dot(u.cross(last.1)).atan2(u.dot(last.1));
    for (i, f) in fr.iter_mut().enumerate().take(m - 1).skip(1) {
        let q = glam::DQuat::from_axis_angle(f.0, twist * i as f64 / (m - 1) as f64);
        f.1 = (q * f.1).normalize();
    }
    fr[m - 1] = last;
    fr
}

/// The well's tiles (see the module's contract): positions relative to `origin`, per vertex its
/// radial normal and log value. Tiles are built in parallel; `coarse_factor` picks the proxy.
pub fn tube_tiles(spec: &TubeSpec<'_>, origin: DVec3, coarse_factor: f32) -> Vec<TileMesh> {
    let n = spec.path.len();
    let fine_frames = frames(spec.path, None);
    let bounds: Vec<usize> = (0..n - 1).step_by(SEGMENTS_PER_TILE).chain([n - 1]).collect();
    bounds
        .par_windows(2)
        .enumerate()
        .map(|(t, w)| {
            let (a, b) = (w[0], w[1]);
            let mut tile = TileMesh { ix: t as u32, ..Default::default() };
            let stations: Vec<usize> = (a..=b).collect();
            let fr = &fine_frames[a..=b];
            let ends = (a == 0, b == n - 1);
            let fine = (spec.sides, spec.radius);
            let (fine_sides, caps) = piece(spec, origin, &stations, fr, fine, ends, &mut tile);
            let n_fine = (fine_sides.len() + caps.len()) / 3;
            tile.fine = fine_sides.iter().chain(&caps).copied().collect();
            let mut prev = n_fine;
            for l in 0..MAX_LEVELS {
                let sides = LEVEL_SIDES[l].min(spec.sides);
                let Decimated { kept, dev, dev_z, chord } =
                    decimate(spec, a, b, LEVEL_TOL_RADII[l] * spec.radius, LEVEL_CHORD[l]);
                let n_tris = 2 * (kept.len() - 1) * sides + 2 * (sides - 2);
                if n_tris as f64 > 0.8 * prev as f64 {
                    continue;
                }
                prev = n_tris;
                let lf = level_frames(spec.path, &kept, fr, a);
                let (r, polygon) = level_polygon(spec.radius, spec.sides, sides);
                let (sides_tris, caps) = piece(spec, origin, &kept, &lf, (sides, r), (true, true), &mut tile);
                let indices: Vec<u32> = sides_tris.into_iter().chain(caps).collect();
                let (error, error_z) = level_errors(dev, dev_z, polygon);
                let level = Level {
                    indices: indices.into(),
                    error,
                    error_z,
                    shading_error: chord as f32,
                    grouped: Vec::new(),
                    grouped_error: error,
                };
                tile.levels.push(level);
            }
            let target = n_fine as f64 / coarse_factor.max(1.0) as f64;
            let proxy = tile.levels.iter().find(|l| (l.indices.len() / 3) as f64 <= target).or(tile.levels.last());
            (tile.coarse, tile.proxy_error) = match proxy {
                Some(l) => (l.indices.clone(), l.error),
                None => (tile.fine.clone(), 0.0),
            };
            tile.compute_bbox();
            fit_ring_z(&mut tile);
            tile
        })
        .collect()
}

/// A level's `(error, error_z)` ([`Level`]) from its path's deviation `dev` (of which `dev_z`
/// vertical) and its polygon's gap to the fine one. Drawn with exaggeration `s >= 1` the level's
/// path moves by `sqrt(dh^2 + s^2 dz^2) <= sqrt(dev^2 + (s^2 - 1) dev_z^2)` and its rings (not
/// exaggerated) by at most the gap, in all by at most `sqrt(e^2 + (s^2 - 1) ez^2)` (what the
/// level choice takes, `render::levels::exaggerated`) for `e^2 = (dev + gap)^2 + gap^2 / 8` and
/// `ez = 3 dev_z`: with `X^2 = (s^2 - 1) dev_z^2`, `(sqrt(dev^2 + X^2) + gap)^2 <= (dev + gap)^2 +
/// X^2 + 2 gap X` and `2 gap X <= gap^2 / 8 + 8 X^2`. Both rounded up to f32, `error_z <= error`.
fn level_errors(dev: f64, dev_z: f64, gap: f64) -> (f32, f32) {
    let ez = 3.0 * dev_z;
    let e = ((dev + gap).powi(2) + gap * gap / 8.0).sqrt().max(ez);
    let (e, ez) = (super::f32_at_least(e), super::f32_at_least(ez));
    (e, ez.min(e))
}

/// Keeps every vertex's ring centre height, `z - ring_z` in f32 as the lit pass computes it,
/// within the tile's box (`TileMesh::ring_z`'s contract; a centre lies within its ring's heights,
/// and an f32 rounding past the box is taken back towards 0).
fn fit_ring_z(tile: &mut TileMesh) {
    let (lo, hi) = (tile.bbox_min[2], tile.bbox_max[2]);
    let positions = &tile.positions;
    let fitted: Vec<f32> = tile
        .ring_z
        .iter()
        .zip(positions)
        .map(|(&r, p)| {
            let inside = |r: f32| (lo..=hi).contains(&(p[2] - r));
            let mut r = r;
            for _ in 0..8 {
                if inside(r) {
                    return r;
                }
                r = if r > 0.0 { r.next_down() } else { r.next_up() };
            }
            if inside(r) {
                r
            } else {
                0.0
            }
        })
        .collect();
    tile.ring_z = fitted.into();
}

#[cfg(test)]
#[path = "tube_tests.rs"]
mod tests;
