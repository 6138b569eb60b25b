//! Seismic slices: an inline, crossline or sample (time/depth) plane through a volume, drawn as
//! the lattice of the volume's samples on that plane with the samples' values as per-vertex
//! scalars (coloured through a colour map in the lit pass, interpolated across each triangle), an
//! opaque occluder like any mesh (object kind "slice"), cut into tiles so culling applies.
//!
//! The scene does not know volumes (the layer rule: `scene` is below `iso`): the binding hands
//! in the slice's sample positions and values; [`Scene::replace_lattice`] moves a slice to
//! another index keeping its id, name, visibility and offset.

use super::{AddOptions, ColorByArg, ColorSource, Scene};
use crate::error::{ensure, Result};

/// Cells per tile of a slice (about 64 x 64).
const CELLS_PER_TILE: usize = 4096;

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
        let tiles = ((nu - 1) * (nv - 1)).div_ceil(CELLS_PER_TILE);
        self.add_mesh(positions, &lattice_faces(nu, nv), kind, Some(tiles), opts)
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
}
