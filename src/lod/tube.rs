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
//! * Level l >= 1 keeps a subset of the tile's stations, its two end stations always, and at each
//!   kept station level 0's own ring (same sides, radius and frame); its side triangles join kept
//!   rings as level 0's join consecutive ones, and it has level 0's caps (only at the path's
//!   ends). So every level of a tile ends in the same rings: neighbours at any two levels meet
//!   ring to ring, with nothing to see through.
//! * Stations are dropped Douglas–Peucker fashion, comparing every dropped station k with the
//!   level at the same station: on the level's segment between kept stations i < k < j, at
//!   `t = (k - i) / (j - i)`, its axis point is `lerp(p_i, p_j, t)` and its ring vertex at angle a
//!   is `lerp(ring_i(a), ring_j(a), t)`. With `dev` the distance between the axis points (`dev_z`
//!   its vertical part) and `gap` the largest distance over every angle between level 0's unit
//!   radial at k and the interpolated radials (exact over the continuum of angles,
//!   [`radial_gap`]), each ring vertex of level 0 lies within `dev + radius gap` of the level's
//!   point at the same station and angle; between stations both levels are linear in the
//!   station, so the bound holds along the path. The normal turns there by at most `chord`, the
//!   chord between level 0's normal and the level's normalised interpolated one (at most the gap
//!   plus [`radial_shortfall`]). A station is dropped where its shading error `chord + gap + dev /
//!   radius` stays within the level's budget ([`LEVEL_SHADING`]): a tube displaced sideways by e
//!   turns the normal a pixel at its middle sees by e / radius, so on a tube a few pixels wide
//!   any displacement shows in its shade long before it shows in its outline.
//! * A level's error (world units, [`level_errors`]) bounds that displacement drawn at any
//!   exaggeration: the axis points are exaggerated, the ring offsets are not (next point). Its
//!   shading error ([`super::levels::Level::shading_error`]) is the largest `chord + gap` over
//!   its dropped stations plus its error over the radius.
//! * Every vertex carries its height above its ring's centre (`TileMesh::ring_z`; a cap's, its
//!   ring's): the lit pass exaggerates the centre and not that offset, so a tube keeps its radius
//!   under exaggeration. Each vertex minus it lies within the tile's box (`fit_ring_z`).
//! * A tube coloured by a log: every vertex carries its value (`TileMesh::values`) and its station
//!   counted from the tile's first (`TileMesh::stations`, a small exact integer). The lit pass
//!   interpolates the station and looks the log up per fragment (draw.wgsl), so every level shows
//!   level 0's colours at the same station, displaced only within the level's error: colours
//!   take no part in which stations a level keeps.
//! * Shading: ring vertices carry radial unit normals (cap vertices none: flat).
//! * A candidate level that would keep more than 0.8 of the triangles of the level before it is
//!   left out (the next, coarser candidate may still pay); at most
//!   [`super::levels::MAX_LEVELS`] levels. The coarse proxy (prepass) is the first level with at
//!   most 1/coarse_factor of the fine triangles, else the coarsest.
//!
//! Levels keep the fine polygon: a polygon of fewer sides turns the normal of most of a tube's
//! pixels (the pixels a facet covers move to another facet), which changes their shade by far
//! more than an 8-bit level, however thin the tube. A smooth path drawn with a station every
//! metre keeps a few stations per tile instead.

use super::levels::{Level, MAX_LEVELS};
use super::{normals, TileMesh};
use glam::DVec3;
use rayon::prelude::*;

/// Segments per tile: a long well is cut into tiles so that culling and levels of detail apply
/// per piece.
pub const SEGMENTS_PER_TILE: usize = 128;

/// Per level l = 1.. the largest shading error a dropped station may cause (see the module's
/// contract), doubling from level to level: 0.001 moves the lit pass's shade by at most
/// 0.001 x 0.8 x 255 = 0.2 8-bit levels (`super::shading`); `render::MAX_TUBE_SHADING_LEVELS`
/// (4 levels) takes a level whose error reaches 0.0196 unexaggerated.
const LEVEL_SHADING: [f64; MAX_LEVELS] = [1e-3, 2e-3, 4e-3, 8e-3, 1.6e-2];

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
#[cfg(test)]
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
/// coloured by a log), radius and sides of the tube.
pub struct TubeSpec<'a> {
    pub path: &'a [DVec3],
    pub values: Option<&'a [f64]>,
    pub radius: f64,
    pub sides: usize,
}

/// Builds one piece of tube into `tile`: rings at `stations` (path indices, from the tile's first
/// station `a`) with level 0's frames `frames` (direction, axis; indexed from `a`), side
/// triangles, and caps at the ends asked for. Returns the piece's triangles.
fn piece(
    spec: &TubeSpec<'_>,
    (origin, a): (DVec3, usize),
    stations: &[usize],
    frames: &[(DVec3, DVec3)],
    caps: (bool, bool),
    tile: &mut TileMesh,
) -> Vec<u32> {
    let (sides, radius) = (spec.sides, spec.radius);
    let base = tile.positions.len() as u32;
    let local = |p: DVec3| (p - origin).as_vec3().to_array();
    // A ring vertex's (or cap vertex's) scalars: its log value and its station from the tile's first.
    let scalars = |tile: &mut TileMesh, k: usize| {
        if let Some(v) = spec.values {
            tile.values.push(v[k] as f32);
            tile.stations.push((k - a) as f32);
        }
    };
    for &k in stations {
        let (c, (d, u)) = (spec.path[k], frames[k - a]);
        let cz = (c - origin).z;
        for q in ring(c, d, u, radius, sides) {
            let p = local(q);
            tile.positions.push(p);
            tile.ring_z.push((p[2] as f64 - cz) as f32);
            tile.normals.push(normals::pack((q - c) / radius));
            scalars(tile, k);
        }
    }
    let mut tris = Vec::with_capacity(6 * stations.len() * sides);
    side_faces(0, stations.len(), sides, &mut |t| tris.extend(t.map(|i| i + base)));
    // Caps with their own vertices (no smooth normal: flat), facing away from the path.
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
            scalars(tile, stations[end]);
        }
        for s in 1..sides as u32 - 1 {
            if end == 0 {
                tris.extend([cap, cap + s + 1, cap + s]);
            } else {
                tris.extend([cap, cap + s, cap + s + 1]);
            }
        }
    }
    tris
}

/// The largest distance over every angle a between `cos a A + sin a B` and 0: the square root of
/// the largest eigenvalue of the Gram matrix of A and B.
fn largest_over_angles(a: DVec3, b: DVec3) -> f64 {
    let (aa, bb, ab) = (a.length_squared(), b.length_squared(), a.dot(b));
    let h = 0.5 * (aa - bb);
    (0.5 * (aa + bb) + (h * h + ab * ab).sqrt()).sqrt()
}

/// The largest distance, over every angle, between level 0's unit radial at station k and the one
/// the level interpolates at `t` between frames `i` and `j` (frames as (direction, axis); the
/// radial at angle a is `cos a u + sin a v` with `v = d x u`).
fn radial_gap(fi: (DVec3, DVec3), fk: (DVec3, DVec3), fj: (DVec3, DVec3), t: f64) -> f64 {
    let uv = |(d, u): (DVec3, DVec3)| (u, d.cross(u));
    let ((ui, vi), (uk, vk), (uj, vj)) = (uv(fi), uv(fk), uv(fj));
    largest_over_angles(uk - ui.lerp(uj, t), vk - vi.lerp(vj, t))
}

/// How far, at most, a radial interpolated between frames `i` and `j` falls short of unit length:
/// `1 - |lerp(r_i, r_j, t)| <= 1 - sqrt(1 - |r_i - r_j|^2 / 4)` at any t. The chord between level
/// 0's normal at a dropped station and the level's normalised interpolated one is at most its
/// [`radial_gap`] plus this.
fn radial_shortfall(fi: (DVec3, DVec3), fj: (DVec3, DVec3)) -> f64 {
    let ends = largest_over_angles(fi.1 - fj.1, fi.0.cross(fi.1) - fj.0.cross(fj.1));
    1.0 - (1.0 - 0.25 * ends * ends).max(0.0).sqrt()
}

/// How a dropped station `k` between kept stations `i < k < j` differs from the level there (see
/// the module's contract), given the segment's [`radial_shortfall`] `short`: the axis
/// displacement, its vertical part, the radial gap, and the normal chord's bound.
fn station_gap(
    path: &[DVec3],
    fr: &[(DVec3, DVec3)],
    a: usize,
    (i, k, j): (usize, usize, usize),
    short: f64,
) -> [f64; 4] {
    let t = (k - i) as f64 / (j - i) as f64;
    let d = path[k] - path[i].lerp(path[j], t);
    let gap = radial_gap(fr[i - a], fr[k - a], fr[j - a], t);
    [d.length(), d.z.abs(), gap, gap + short]
}

/// What [`decimate`] kept and the bounds it measured over the dropped stations.
struct Decimated {
    /// The kept stations, in order.
    kept: Vec<usize>,
    /// The largest axis displacement, the largest vertical part of one, and the largest radial
    /// gap times the radius (world units).
    dev: f64,
    dev_z: f64,
    ring: f64,
    /// The largest turn of a dropped station's normals: chord plus radial gap (see the module's
    /// contract).
    turn: f64,
}

/// The stations of `a..=b` kept at shading error `shading` (see the module's contract), with
/// `fr` level 0's frames of `a..=b`, and the level's bounds.
fn decimate(spec: &TubeSpec<'_>, fr: &[(DVec3, DVec3)], (a, b): (usize, usize), shading: f64) -> Decimated {
    let (path, radius) = (spec.path, spec.radius);
    let mut keep = vec![false; b - a + 1];
    keep[0] = true;
    keep[b - a] = true;
    let mut stack = vec![(a, b)];
    let mut out = Decimated { kept: Vec::new(), dev: 0.0, dev_z: 0.0, ring: 0.0, turn: 0.0 };
    let mut gaps = Vec::new();
    while let Some((i, j)) = stack.pop() {
        // Per dropped station: its gaps and its shading error, the turn of its normals (chord
        // plus radial gap) and its displacement over the radius.
        let short = radial_shortfall(fr[i - a], fr[j - a]);
        gaps.clear();
        gaps.extend((i + 1..j).map(|k| {
            let [d, dz, g, c] = station_gap(path, fr, a, (i, k, j), short);
            (k, d, dz, g, c + g, c + g + d / radius)
        }));
        // The station with the largest shading error, if over the budget.
        match gaps.iter().max_by(|x, y| x.5.total_cmp(&y.5)) {
            Some(&(k, .., sh)) if sh > shading => {
                keep[k - a] = true;
                stack.push((i, k));
                stack.push((k, j));
            }
            _ => {
                for &(_, d, dz, g, turn, _) in &gaps {
                    out.dev = out.dev.max(d);
                    out.dev_z = out.dev_z.max(dz);
                    out.ring = out.ring.max(radius * g);
                    out.turn = out.turn.max(turn);
                }
            }
        }
    }
    out.kept = (a..=b).filter(|&k| keep[k - a]).collect();
    out
}

/// The well's tiles (see the module's contract): positions relative to `origin`, per vertex its
/// radial normal, and its log value and station where coloured by a log. Tiles are built in
/// parallel; `coarse_factor` picks the proxy.
pub fn tube_tiles(spec: &TubeSpec<'_>, origin: DVec3, coarse_factor: f32) -> Vec<TileMesh> {
    let n = spec.path.len();
    let sides = spec.sides;
    let fine_frames = frames(spec.path, None);
    let bounds: Vec<usize> = (0..n - 1).step_by(SEGMENTS_PER_TILE).chain([n - 1]).collect();
    bounds
        .par_windows(2)
        .enumerate()
        .map(|(t, w)| {
            let (a, b) = (w[0], w[1]);
            let mut tile = TileMesh { ix: t as u32, ..Default::default() };
            let fr = &fine_frames[a..=b];
            let caps = (a == 0, b == n - 1);
            let n_caps = 2 * (usize::from(caps.0) + usize::from(caps.1)) * (sides - 2);
            let stations: Vec<usize> = (a..=b).collect();
            tile.fine = piece(spec, (origin, a), &stations, fr, caps, &mut tile).into();
            let n_fine = tile.fine.len() / 3;
            let mut prev = n_fine;
            let mut levels = Vec::new();
            for shading in LEVEL_SHADING {
                let d = decimate(spec, fr, (a, b), shading);
                let n_tris = 2 * (d.kept.len() - 1) * sides + n_caps / 2;
                if n_tris as f64 > 0.8 * prev as f64 {
                    continue;
                }
                prev = n_tris;
                let indices = piece(spec, (origin, a), &d.kept, fr, caps, &mut tile);
                let (error, error_z) = level_errors(d.dev, d.dev_z, d.ring);
                levels.push(Level {
                    indices: indices.into(),
                    error,
                    error_z,
                    shading_error: super::f32_at_least(d.turn + error as f64 / spec.radius),
                    grouped: Vec::new(),
                    grouped_error: error,
                });
            }
            tile.levels = levels.into();
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

/// A level's `(error, error_z)` ([`Level`]) from its largest axis displacement `dev` (of which
/// `dev_z` vertical) and its largest ring gap `ring` (world units). Drawn with exaggeration
/// `s >= 1` the axis displacement grows to `sqrt(dh^2 + s^2 dz^2) <= sqrt(dev^2 + X^2)` with
/// `X^2 = (s^2 - 1) dev_z^2`, the ring gap not at all (rings are not exaggerated), and
/// `(sqrt(dev^2 + X^2) + ring)^2 <= (dev + ring)^2 + 2 ring X + X^2 <= e^2 + (s^2 - 1) ez^2` for
/// `e^2 = (dev + ring)^2 + 8 ring^2` and `ez^2 = 9/8 dev_z^2`, as `2 ring X <= 8 ring^2 + X^2 / 8`
/// (what the level choice takes, `render::levels::exaggerated`). Both rounded up to f32,
/// `error_z <= error`.
fn level_errors(dev: f64, dev_z: f64, ring: f64) -> (f32, f32) {
    let ez = (9.0f64 / 8.0).sqrt() * dev_z;
    let e = ((dev + ring).powi(2) + 8.0 * ring * ring).sqrt().max(ez);
    let (e, ez) = (super::f32_at_least(e), super::f32_at_least(ez));
    (e, ez.min(e))
}

/// A log-coloured tile's table as the lit pass reads it (`gpu::cell_values`): its values by
/// station (`TileMesh::stations`, no data as NaN), one column per station and one row, as
/// `([columns, rows, 0], values)`; None for a tile without stations.
pub fn log_table(t: &TileMesh) -> Option<([u32; 3], Vec<f32>)> {
    let n = t.stations.iter().fold(0.0f32, |a, &s| a.max(s + 1.0)) as usize;
    if n == 0 || t.values.len() != t.stations.len() {
        return None;
    }
    let mut table = vec![f32::NAN; n];
    for (&s, &v) in t.stations.iter().zip(t.values.iter()) {
        table[s as usize] = v;
    }
    Some(([n as u32, 1, 0], table))
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
