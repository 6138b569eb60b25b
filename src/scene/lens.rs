//! Volume lenses: a semi-transparent sub-volume (a salt dome, a channel) drawn as stacks of
//! slices through it, blended back to front over the opaque image (object kind "lens").
//!
//! The contract: a lens has one tile per slice, for each of the three axes (tile `ix` = the axis,
//! `iy` = the slice's index along it), each slice the lattice of the volume's samples on that
//! plane within the lens's box, coloured by the samples' values. A lens is never an occluder
//! (strategies see it as hidden) and writes no depth; each frame the renderer draws the stack of
//! the axis closest to the view direction, farthest slice first, unlit, with the object's opacity,
//! after testing each slice's box against the opaque image's depth (a hidden slice is not drawn,
//! a wholly hidden lens draws nothing).

use super::slice::lattice_faces;
use super::{check_color, AddOptions, ColorSource, ObjectKind, Scene};
use crate::error::{ensure, Result};
use crate::lod::TileMesh;
use glam::DVec3;

/// One slice of a lens: its axis (0, 1, 2), index along it, and its `nu` x `nv` lattice of world
/// positions (row-major) with one value each.
pub struct LensSlice {
    pub axis: u32,
    pub index: u32,
    pub positions: Vec<[f64; 3]>,
    pub values: Vec<f64>,
    pub nu: usize,
    pub nv: usize,
}

impl Scene {
    /// Adds a lens made of `slices` with `opacity` in (0, 1); `opts.color_by` gives the colour
    /// map and range (its source is forced to the values; `values` ignored).
    pub fn add_lens(&mut self, slices: Vec<LensSlice>, opacity: f64, mut opts: AddOptions) -> Result<u32> {
        ensure(opacity.is_finite() && opacity > 0.0 && opacity < 1.0, "opacity", || {
            format!("opacity is {opacity}; a lens needs a value in (0, 1) (use add_slice for opaque slices)")
        })?;
        ensure(!slices.is_empty(), "box", || "the lens's box holds no slice".into())?;
        for s in &slices {
            ensure(s.nu >= 2 && s.nv >= 2 && s.positions.len() == s.nu * s.nv, "box", || {
                format!("a lens slice needs at least 2 x 2 samples, got {} x {}", s.nu, s.nv)
            })?;
        }
        let color = check_color(None, self.next_id)?;
        let mut c = opts.color_by.take().unwrap_or_else(|| super::ColorByArg::values(Vec::new()));
        c.source = ColorSource::Values;
        c.values = None;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in slices.iter().flat_map(|s| &s.positions) {
            lo = lo.min(DVec3::from_array(*p));
            hi = hi.max(DVec3::from_array(*p));
        }
        let o = self.origin_for(lo, hi);
        let color_by = c.resolve(slices.iter().flat_map(|s| s.values.iter().copied()))?;
        let tiles: Vec<TileMesh> = slices
            .iter()
            .map(|s| {
                let mut t = TileMesh {
                    ix: s.axis,
                    iy: s.index,
                    positions: s.positions.iter().map(|p| (DVec3::from_array(*p) - o).as_vec3().to_array()).collect(),
                    values: s.values.iter().map(|&v| v as f32).collect(),
                    fine: lattice_faces(s.nu, s.nv).into_iter().flatten().map(|k| k as u32).collect(),
                    ..Default::default()
                };
                t.compute_bbox();
                t
            })
            .collect();
        let id = self.push(o, opts.name, ObjectKind::Mesh { kind: "lens".into() }, color, Some(color_by), tiles);
        self.object_mut(id)?.opacity = opacity as f32;
        Ok(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lens_has_one_tile_per_slice_and_is_translucent() {
        let sl = |axis: u32, index: u32| LensSlice {
            axis,
            index,
            positions: vec![
                [0.0, 0.0, index as f64],
                [1.0, 0.0, index as f64],
                [0.0, 1.0, index as f64],
                [1.0, 1.0, index as f64],
            ],
            values: vec![0.0, 1.0, 2.0, 3.0],
            nu: 2,
            nv: 2,
        };
        let mut s = Scene::new();
        let id = s.add_lens(vec![sl(2, 0), sl(2, 1)], 0.5, AddOptions::new(1.0)).unwrap();
        let o = s.object(id).unwrap();
        assert_eq!((o.tiles.len(), o.opacity, o.kind_name()), (2, 0.5, "lens"));
        assert_eq!(o.tiles[1].fine.len(), 6);
        assert!(o.tiles.iter().all(|t| t.coarse.is_empty() && t.levels.is_empty()));
        for bad in [0.0, 1.0, f64::NAN] {
            let e = s.add_lens(vec![sl(2, 0)], bad, AddOptions::new(1.0)).unwrap_err();
            assert!(e.to_string().starts_with("opacity"), "{e}");
        }
    }
}
