//! Wells: a deviated well path drawn as a closed tube (an occluder like any mesh), optionally
//! coloured by a log sampled along the path.
//!
//! The contract of [`tube`]: for a path of n >= 2 stations (consecutive duplicates dropped) and
//! `sides` >= 3, the tube has one ring of `sides` vertices per station, each ring the regular
//! polygon of circumradius `radius` centred on the station in the plane normal to the path's
//! direction there (the mean of the two segments' directions at inner stations), turned from
//! station to station by parallel transport (no twist), and a flat cap at each end, in all
//! 2 (n - 1) sides plus 2 (sides - 2) triangles, wound outwards. The polygon's first vertex of the first ring lies
//! along the horizontal normal of the first segment when it has one (+x for a vertical start).

use super::{AddOptions, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use glam::DVec3;

/// Segments per tile: a long well is cut into tiles so that culling can drop the parts out of
/// view or hidden.
const SEGMENTS_PER_TILE: usize = 128;

/// The tube around `path` (see the module's contract): (vertices, faces, the station of each
/// vertex). `path` must be finite with at least two distinct consecutive stations.
pub fn tube(path: &[DVec3], radius: f64, sides: usize) -> (Vec<[f64; 3]>, Vec<[i64; 3]>, Vec<usize>) {
    let n = path.len();
    let dir = |k: usize| -> DVec3 {
        let a = if k > 0 { (path[k] - path[k - 1]).normalize() } else { DVec3::ZERO };
        let b = if k + 1 < n { (path[k + 1] - path[k]).normalize() } else { DVec3::ZERO };
        let d = a + b;
        // A hairpin (a = -b) has no mean direction: take the incoming one.
        if d.length_squared() > 1e-12 {
            d.normalize()
        } else if a != DVec3::ZERO {
            a
        } else {
            b
        }
    };
    let d0 = dir(0);
    let mut u = DVec3::Z.cross(d0);
    if u.length_squared() < 1e-12 {
        u = DVec3::X; // vertical start
    }
    let mut u = u.normalize();
    let (mut verts, mut station) = (Vec::with_capacity(n * sides + 2), Vec::with_capacity(n * sides + 2));
    let mut prev = d0;
    for (k, p) in path.iter().enumerate() {
        let d = dir(k);
        // Parallel transport: turn u by the rotation taking the previous direction onto this one.
        let axis = prev.cross(d);
        if axis.length_squared() > 1e-24 {
            let q = glam::DQuat::from_rotation_arc(prev, d);
            u = (q * u).normalize();
        }
        u = (u - d * u.dot(d)).normalize();
        let v = d.cross(u);
        prev = d;
        for s in 0..sides {
            let a = std::f64::consts::TAU * s as f64 / sides as f64;
            verts.push((*p + radius * (a.cos() * u + a.sin() * v)).to_array());
            station.push(k);
        }
    }
    let ring = |k: usize, s: usize| (k * sides + s % sides) as i64;
    let mut faces = Vec::with_capacity(2 * (n - 1) * sides + 2 * sides);
    for k in 0..n - 1 {
        for s in 0..sides {
            // (u, v, d) is right-handed, so rings run counter-clockwise about d: this winding faces out.
            faces.push([ring(k, s), ring(k, s + 1), ring(k + 1, s + 1)]);
            faces.push([ring(k, s), ring(k + 1, s + 1), ring(k + 1, s)]);
        }
    }
    // Caps: fans over each end ring, facing away from the path.
    for s in 1..sides - 1 {
        faces.push([ring(0, 0), ring(0, s + 1), ring(0, s)]);
        faces.push([ring(n - 1, 0), ring(n - 1, s), ring(n - 1, s + 1)]);
    }
    (verts, faces, station)
}

impl Scene {
    /// Adds a well: `path` (n, 3) world stations along the well (any deviation), drawn as a tube
    /// of `radius` (world units) with `sides` sides; `opts.color_by` values, when given, are one per
    /// station (a log), interpolated along the tube. Stations repeating the previous one are dropped.
    pub fn add_well(&mut self, path: &[[f64; 3]], radius: f64, sides: usize, mut opts: AddOptions) -> Result<u32> {
        for (i, p) in path.iter().enumerate() {
            for (a, c) in p.iter().enumerate() {
                ensure(c.is_finite() && c.abs() <= MAX_COORD, "path", || {
                    format!("path[{i}, {a}] is {}; stations must be finite, within +-{MAX_COORD:e}", num(*c))
                })?;
            }
        }
        ensure(radius.is_finite() && radius > 0.0, "radius", || format!("radius is {radius}; expected a number > 0"))?;
        ensure((3..=64).contains(&sides), "sides", || format!("sides is {sides}; expected 3..=64"))?;
        let values = match opts.color_by.as_mut() {
            Some(c) => c.values.take(),
            None => None,
        };
        if let Some(v) = &values {
            ensure(v.len() == path.len(), "values", || {
                format!("values has {} entries; expected one per station of path, {}", v.len(), path.len())
            })?;
        }
        // Distinct consecutive stations, keeping each one's log value.
        let mut stations: Vec<DVec3> = Vec::with_capacity(path.len());
        let mut logs: Vec<f64> = Vec::new();
        for (i, p) in path.iter().enumerate() {
            let p = DVec3::from_array(*p);
            if stations.last() != Some(&p) {
                stations.push(p);
                if let Some(v) = &values {
                    logs.push(v[i]);
                }
            }
        }
        ensure(stations.len() >= 2, "path", || {
            format!("path has {} distinct station(s); a well needs at least 2", stations.len())
        })?;
        let (verts, faces, station) = tube(&stations, radius, sides);
        if let Some(c) = opts.color_by.as_mut() {
            if values.is_some() {
                c.values = Some(station.iter().map(|&k| logs[k]).collect());
            }
        }
        let tiles = (stations.len() - 1).div_ceil(SEGMENTS_PER_TILE);
        self.add_mesh(&verts, &faces, "well", Some(tiles), opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signed_volume(v: &[[f64; 3]], f: &[[i64; 3]]) -> f64 {
        f.iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| DVec3::from_array(v[k as usize]));
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn a_straight_tube_is_a_closed_prism_wound_outwards() {
        let path = [DVec3::ZERO, DVec3::new(0.0, 0.0, -100.0)];
        for sides in [3, 8, 16] {
            let (v, f, _) = tube(&path, 2.0, sides);
            assert_eq!(v.len(), 2 * sides);
            assert_eq!(f.len(), 2 * sides + 2 * (sides - 2));
            // Every edge shared by exactly two triangles, in opposite directions.
            let mut edges = std::collections::HashMap::new();
            for t in &f {
                for e in 0..3 {
                    *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
                }
            }
            assert!(edges.iter().all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1)));
            // Positive volume = the prism's (outward winding): area of the regular polygon x length.
            let area = 0.5 * sides as f64 * 4.0 * (std::f64::consts::TAU / sides as f64).sin();
            assert!((signed_volume(&v, &f) - area * 100.0).abs() < 1e-6 * area * 100.0);
        }
    }

    #[test]
    fn rings_stay_round_and_untwisted_along_a_deviated_path() {
        let path: Vec<DVec3> =
            (0..50).map(|k| DVec3::new((k as f64 * 0.1).sin() * 300.0, k as f64 * 5.0, -(k as f64) * 20.0)).collect();
        let (v, f, st) = tube(&path, 3.0, 8);
        assert_eq!(st.len(), v.len());
        for (k, p) in path.iter().enumerate() {
            for s in 0..8 {
                let d = DVec3::from_array(v[k * 8 + s]) - *p;
                assert!((d.length() - 3.0).abs() < 1e-9);
            }
        }
        assert!(signed_volume(&v, &f) > 0.0);
    }

    #[test]
    fn bad_paths_are_named() {
        let mut s = Scene::new();
        let e = s.add_well(&[[0.0; 3], [0.0; 3]], 1.0, 8, AddOptions::new(1.0)).unwrap_err().to_string();
        assert!(e.starts_with("path") && e.contains("1 distinct"), "{e}");
        let e = s.add_well(&[[0.0; 3], [0.0, f64::NAN, 0.0]], 1.0, 8, AddOptions::new(1.0)).unwrap_err();
        assert!(e.to_string().starts_with("path[1, 1]"), "{e}");
        let e = s.add_well(&[[0.0; 3], [0.0, 0.0, 1.0]], 0.0, 8, AddOptions::new(1.0)).unwrap_err();
        assert!(e.to_string().starts_with("radius"), "{e}");
        let id = s.add_well(&[[0.0; 3], [0.0; 3], [0.0, 0.0, -10.0]], 1.0, 8, AddOptions::new(1.0)).unwrap();
        assert_eq!(s.object(id).unwrap().kind_name(), "well");
    }
}
