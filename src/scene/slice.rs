//! Seismic slices: an inline, crossline or sample (time/depth) plane through a volume, drawn as
//! the lattice of the volume's samples on that plane with the samples' values as per-vertex
//! scalars (coloured through a colour map in the lit pass, interpolated across each triangle), an
//! opaque occluder like any mesh (object kind "slice"), cut into blocks of cells so culling
//! applies (`lod::plane`: the lattice's own blocks, each with its plane as its coarse proxy).
//!
//! The scene does not know volumes (the layer rule: `scene` is below `iso`): the binding hands
//! in the slice's sample positions and values; [`Scene::replace_lattice`] moves a slice to
//! another index keeping its id, name, visibility and offset.

use super::mesh::Shape;
use super::{AddOptions, ColorByArg, ColorSource, Scene};
use crate::error::{ensure, Result};
use crate::lod;
use glam::DVec3;

/// Cells per tile side of a slice (tiles of at most 64 x 64 cells).
const TILE_CELLS: usize = 64;

/// The triangles of an `nu` x `nv` lattice, row-major (vertex `v * nu + u`), two per cell with
/// the diagonal from (u, v) to (u + 1, v + 1), as height fields.
pub fn lattice_faces(nu: usize, nv: usize) -> Vec<[i64; 3]> {
    let mut f = Vec::with_capacity(2 * (nu - 1) * (nv - 1));
    for v in 0..nv - 1 {
        for u in 0..nu - 1 {
            let a = (v * nu + u) as i64;
            let (b, c, d) = (a + 1, a + 1 + nu as i64, a + nu as i64);
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    f
}

impl Scene {
    /// Adds an `nu` x `nv` lattice of world `positions` (row-major, `v * nu + u`) coloured by
    /// `values` (one per position; NaN = no data) through `color_by`'s colour map and range
    /// (`color_by.values` is ignored and `source` must be Values). `kind` labels it ("slice").
    pub fn add_lattice(
        &mut self,
        positions: &[[f64; 3]],
        values: Vec<f64>,
        (nu, nv): (usize, usize),
        kind: &str,
        mut opts: AddOptions,
    ) -> Result<u32> {
        ensure(nu >= 2 && nv >= 2 && positions.len() == nu * nv, "index", || {
            format!("a slice needs at least 2 x 2 samples, got {nu} x {nv} ({} positions)", positions.len())
        })?;
        let mut c = opts.color_by.take().unwrap_or_else(|| ColorByArg::values(Vec::new()));
        c.source = ColorSource::Values;
        c.values = Some(values);
        opts.color_by = Some(c);
        super::mesh::check_vertices(positions)?;
        // The lattice's own blocks, its plane as each block's coarse proxy (`lod::plane`): no
        // clustering or simplification of a mesh whose shape is known.
        let shape = lattice_shape(positions, nu, nv);
        self.add_tiled(positions, shape, kind, opts, |attrs, o, cf, stop| {
            lod::plane::tile_plane(positions, attrs, (nu, nv), o, TILE_CELLS, cf, stop)
        })
    }

    /// Sets the opacity of slice `id`: 1 = opaque (an occluder), (0, 1) = translucent (drawn
    /// blended after the opaque image, unlit, never occluding, as lenses are).
    pub fn set_slice_opacity(&mut self, id: u32, opacity: f64) -> Result<()> {
        ensure(opacity.is_finite() && opacity > 0.0 && opacity <= 1.0, "opacity", || {
            format!("opacity is {opacity}; expected a number in (0, 1]")
        })?;
        self.object_mut(id)?.opacity = opacity as f32;
        Ok(())
    }

    /// Replaces object `id`'s geometry by that of object `with` (just added, e.g. by
    /// [`Scene::add_lattice`]), which is removed: `id` keeps its id, name, place in the scene,
    /// visibility and offset, and takes `with`'s tiles and colouring.
    pub fn replace_lattice(&mut self, id: u32, with: u32) -> Result<()> {
        self.object(id)?;
        let idx = self.objects.iter().position(|o| o.id == with);
        let new = match idx {
            Some(i) => self.objects.remove(i),
            None => return self.object(with).map(|_| ()),
        };
        let o = self.object_mut(id)?;
        o.tiles = new.tiles;
        o.geometry_stamp = new.geometry_stamp;
        o.origin = new.origin;
        o.color_by = new.color_by;
        o.opacity = new.opacity;
        // Added just before (the version its addition made): the two changes together only
        // replaced `id`'s geometry, which a renderer may rewrite in place.
        let just_added = self.last_add == Some((self.geometry_version, with));
        self.geometry_version += 1;
        if just_added {
            self.log_replacement(self.geometry_version - 2, id);
        }
        Ok(())
    }
}

/// The shape of an `nu` x `nv` lattice on a plane (`Scene::add_lattice`): the bounds of all its
/// positions, every vertex's normal the plane's (from its corner samples, in the winding of
/// [`lattice_faces`]: what a smooth mean of its faces' normals gives a plane, without a pass over
/// 2 (nu - 1) (nv - 1) faces), and its grid coordinates; facet shading (no normals) where the
/// corners span no plane.
fn lattice_shape(positions: &[[f64; 3]], nu: usize, nv: usize) -> Shape {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in positions {
        lo = lo.min(DVec3::from_array(*p));
        hi = hi.max(DVec3::from_array(*p));
    }
    let p = |u: usize, v: usize| DVec3::from_array(positions[v * nu + u]);
    let n = (p(nu - 1, 0) - p(0, 0)).cross(p(0, nv - 1) - p(0, 0)).normalize_or_zero();
    let fits = nu <= lod::MAX_GRID_SIDE && nv <= lod::MAX_GRID_SIDE;
    let normals = (n != DVec3::ZERO).then(|| vec![lod::normals::pack(n); positions.len()]);
    let grid_uv = (normals.is_some() && fits).then(|| super::mesh::grid_coords(nu, positions.len()));
    Shape { lo, hi, normals, grid_uv }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lattice_is_two_triangles_per_cell_and_keeps_its_values() {
        let (nu, nv) = (5, 3);
        let pos: Vec<[f64; 3]> = (0..nu * nv).map(|k| [(k % nu) as f64, 0.0, -((k / nu) as f64)]).collect();
        let vals: Vec<f64> = (0..nu * nv).map(|k| k as f64).collect();
        let mut s = Scene::new();
        let id = s.add_lattice(&pos, vals, (nu, nv), "slice", AddOptions::new(1.0)).unwrap();
        let o = s.object(id).unwrap();
        assert_eq!(o.fine_triangles(), 2 * (nu - 1) * (nv - 1));
        assert_eq!(o.kind_name(), "slice");
        assert_eq!(o.color_by.as_ref().unwrap().clim, [0.0, 14.0]);
        // Each vertex keeps its own value: value = u + nu * v, recovered from its position.
        let t = &o.tiles[0];
        for (p, v) in t.positions.iter().zip(&t.values) {
            let (u, w) = ((p[0] as f64 + o.origin.x).round(), -(p[2] as f64 + o.origin.z).round());
            assert_eq!(*v as f64, u + nu as f64 * w);
        }
        let other = s.add_lattice(&pos, vec![1.0; nu * nv], (nu, nv), "slice", AddOptions::new(1.0)).unwrap();
        s.set_visible(id, false).unwrap();
        s.replace_lattice(id, other).unwrap();
        assert_eq!(s.objects().len(), 1);
        let o = s.object(id).unwrap();
        assert!(!o.visible && o.tiles[0].values.iter().all(|&v| v == 1.0));
        assert!(s.add_lattice(&pos[..3], vec![0.0; 3], (3, 1), "slice", AddOptions::new(1.0)).is_err());
    }

    #[test]
    fn a_lattice_draws_what_the_same_mesh_draws_with_the_same_shading() {
        // A tilted plane far from the origin, 150 x 90 samples: several tiles.
        let (nu, nv) = (150, 90);
        let pos: Vec<[f64; 3]> = (0..nu * nv)
            .map(|k| {
                let (u, v) = ((k % nu) as f64, (k / nu) as f64);
                [456_000.0 + 12.5 * u + 0.3 * v, 6_780_000.0 + 6.0 * u, -1500.0 - 4.0 * v + 0.01 * u]
            })
            .collect();
        let vals: Vec<f64> = (0..nu * nv).map(|k| ((k * 7919) % 1000) as f64).collect();
        let faces: Vec<[i64; 3]> = lattice_faces(nu, nv);
        let mut s = Scene::new();
        let lat = s.add_lattice(&pos, vals.clone(), (nu, nv), "slice", AddOptions::new(1.0)).unwrap();
        let mut opts = AddOptions::new(1.0);
        opts.color_by = Some(ColorByArg::values(vals));
        let mesh = s.add_mesh(&pos, &faces, "slice", Some(4), opts).unwrap();
        // Per object: each triangle as its corners' (world position, value, normal), sorted.
        let drawn = |id: u32| {
            let o = s.object(id).unwrap();
            let mut tris: Vec<[([i64; 3], u32, u32); 3]> = Vec::new();
            for t in &o.tiles {
                assert!(!t.normals.is_empty() && !t.grid_uv.is_empty(), "a plane shades smooth, from its grid");
                for f in t.fine.chunks_exact(3) {
                    tris.push([0, 1, 2].map(|i| {
                        let k = f[i] as usize;
                        let w = t.positions[k].map(f64::from);
                        let p = [0, 1, 2].map(|a| ((w[a] + o.origin[a]) * 100.0).round() as i64);
                        (p, t.values[k].to_bits(), t.grid_uv[k])
                    }));
                }
            }
            tris.sort_unstable();
            (tris, o.color_by.as_ref().unwrap().clim)
        };
        assert_eq!(drawn(lat), drawn(mesh));
        // The normals agree to the packing's precision (the mesh's are means over faces).
        let normal = |id: u32| lod::normals::unpack(s.object(id).unwrap().tiles[0].normals[0]).unwrap();
        assert!(normal(lat).angle_between(normal(mesh)) < 1e-3);
        assert!(s.object(lat).unwrap().tiles.len() > 1);
    }
}
