//! Wells: a deviated well path drawn as a closed tube (an occluder like any mesh), optionally
//! coloured by a log sampled along the path. The tube, its tiles along the path and their levels
//! of detail are [`crate::lod::tube`]'s.

use super::{check_coarse_factor, check_color, AddOptions, ObjectKind, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use crate::lod::tube::{tube_tiles, TubeSpec};
use glam::DVec3;

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
        let cf = check_coarse_factor(opts.coarse_factor)?;
        let color = check_color(opts.color, self.next_id)?;
        let color_by = super::color_by_arg(&opts.color, opts.color_by.take(), || None)?;
        if let Some(c) = &color_by {
            c.check(Some((path.len(), &format!("one per station of path, {}", path.len()))))?;
        }
        let values = color_by.as_ref().and_then(|c| c.values.as_deref());
        // Distinct consecutive stations, keeping each one's log value.
        let mut stations: Vec<DVec3> = Vec::with_capacity(path.len());
        let mut logs: Vec<f64> = Vec::new();
        for (i, p) in path.iter().enumerate() {
            let p = DVec3::from_array(*p);
            if stations.last() != Some(&p) {
                stations.push(p);
                if let Some(v) = values {
                    logs.push(v[i]);
                }
            }
        }
        ensure(stations.len() >= 2, "path", || {
            format!("path has {} distinct station(s); a well needs at least 2", stations.len())
        })?;
        let (lo, hi) = stations.iter().fold((stations[0], stations[0]), |(a, b), p| (a.min(*p), b.max(*p)));
        let o = self.origin_for(lo - radius, hi + radius);
        let spec = TubeSpec { path: &stations, values: values.is_some().then_some(&logs[..]), radius, sides };
        let tiles = opts.interrupt.run_parallel(|_stop| tube_tiles(&spec, o, cf as f32))?;
        let color_by = color_by.map(|c| c.resolve(super::tile_scalars(&tiles, o.z, &c.source))).transpose()?;
        Ok(self.push_levels(o, opts.name, ObjectKind::Mesh { kind: "well".into() }, color, color_by, tiles, true))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::tube::tube;

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
