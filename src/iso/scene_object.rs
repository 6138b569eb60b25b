//! An isosurface as an object of a scene (kind "isosurface"): the whole surface extracted
//! ([`super::mesh`]), cut into spatially coherent tiles culled like any mesh's, with its enclosed
//! occluder boxes ([`super::enclosed`]) for `culling = "implicit"`.
//!
//! Two steps, so that a caller holding the scene behind a lock extracts without it:
//! [`SceneIsosurface::extract`] (seconds on a large volume; reads only the volumes) then
//! [`SceneIsosurface::add_to`] (builds the tiles' levels and adds the object).

use super::enclosed::{enclosed_boxes, mesh_bounds};
use super::mesh::{isosurface_mesh, isosurface_mesh_sampled, IsoMesh};
use super::{MinMaxOctree, Volume};
use crate::error::{input_err, Result};
use crate::scene::color::resolve_clim;
use crate::scene::{AddOptions, ColorSource, Scene};

/// Triangles per tile when the caller names no tile count.
pub const TRIANGLES_PER_TILE: usize = 4096;

/// An isosurface extracted for a scene, not yet added to one.
pub struct SceneIsosurface {
    mesh: IsoMesh,
    /// The values volume at the vertices, and that volume's finite range ([`Self::extract`]'s
    /// `values`): None without one.
    values: Option<(Vec<f64>, Option<[f64; 2]>)>,
    /// The enclosed occluder boxes, world space (empty where `enclosed_boxes` gives none).
    boxes: Vec<([f64; 3], [f64; 3])>,
}

impl SceneIsosurface {
    /// The isosurface `vol == isovalue` (in `vol`'s units; `tree` is `vol`'s octree), with, when
    /// `values` is given (a volume on `vol`'s grid, [`isosurface_mesh_sampled`]), that volume's
    /// values at its vertices for colouring. Errors name `isovalue`, `volume` or `values`.
    pub fn extract(vol: &Volume, tree: &MinMaxOctree, isovalue: f64, values: Option<&Volume>) -> Result<Self> {
        let (mesh, values) = match values {
            Some(other) => {
                let (mesh, sampled) = isosurface_mesh_sampled(vol, tree, isovalue, other)?;
                (mesh, Some((sampled, other.finite_range())))
            }
            None => (isosurface_mesh(vol, tree, isovalue)?, None),
        };
        let boxes = enclosed_boxes(vol, isovalue)?;
        Ok(Self { mesh, values, boxes })
    }

    /// The surface's triangles.
    pub fn triangles(&self) -> usize {
        self.mesh.faces.len()
    }

    /// Adds the surface to `scene` as a mesh of kind "isosurface" in `tiles` tiles (None: one per
    /// `TRIANGLES_PER_TILE` triangles), with its occluder boxes. With a values volume and
    /// `opts.color_by`, the colouring's values are that volume's at the vertices, and coloured by
    /// them its clim defaults to that volume's finite range, as a slice of that volume's does
    /// (coloured by z, the scene refuses the values, naming `values`); colouring by values without
    /// a values volume is an error naming `values`. Returns the object's id.
    pub fn add_to(self, scene: &mut Scene, tiles: Option<usize>, mut opts: AddOptions) -> Result<u32> {
        let Self { mesh, values, boxes } = self;
        if let Some(c) = opts.color_by.as_mut() {
            match values {
                // Given to a colouring by z too, whose check then names `values`.
                Some((sampled, range)) => {
                    c.values = Some(sampled);
                    if c.source == ColorSource::Values && c.clim.is_none() {
                        c.clim = Some(resolve_clim(None, range.into_iter().flatten())?);
                    }
                }
                None if c.source == ColorSource::Values => {
                    return Err(input_err("values", "colouring an isosurface by values needs a values volume"));
                }
                None => {}
            }
        }
        let faces: Vec<[i64; 3]> = mesh.faces.iter().map(|f| f.map(i64::from)).collect();
        let tiles = tiles.unwrap_or_else(|| faces.len().div_ceil(TRIANGLES_PER_TILE).max(1));
        let id = scene.add_mesh(&mesh.vertices, &faces, "isosurface", Some(tiles), opts)?;
        if let (Some(bounds), false) = (mesh_bounds(&mesh.vertices), boxes.is_empty()) {
            scene.set_occluders(id, &boxes, bounds)?;
        }
        Ok(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use crate::scene::ColorByArg;

    fn ball() -> (Volume, MinMaxOctree) {
        let vol = super::super::sphere_field(17, 0.6);
        let tree = MinMaxOctree::try_build(&vol).unwrap();
        (vol, tree)
    }

    #[test]
    fn the_object_is_the_whole_surface_with_its_occluders() {
        let (vol, tree) = ball();
        let whole = isosurface_mesh(&vol, &tree, 0.0).unwrap();
        let surface = SceneIsosurface::extract(&vol, &tree, 0.0, None).unwrap();
        assert_eq!(surface.triangles(), whole.faces.len());
        let mut scene = Scene::new();
        let id = surface.add_to(&mut scene, Some(3), AddOptions::new(25.0)).unwrap();
        let o = scene.object(id).unwrap();
        assert_eq!(o.kind_name(), "isosurface");
        assert_eq!(o.tiles.len(), 3);
        assert_eq!(o.fine_triangles(), whole.faces.len());
        let occ = o.occluders.as_deref().expect("a closed ball encloses boxes");
        assert!(!occ.boxes.is_empty());
    }

    #[test]
    fn colour_by_values_takes_the_values_volume_and_its_range() {
        let (vol, tree) = ball();
        let lin = Volume::from_fn((17, 17, 17), [-1.0; 3], [0.125; 3], |x, _, _| (3.0 + x) as f32).unwrap();
        let surface = SceneIsosurface::extract(&vol, &tree, 0.0, Some(&lin)).unwrap();
        let mut scene = Scene::new();
        let opts = AddOptions { color_by: Some(ColorByArg::values(Vec::new())), ..AddOptions::new(25.0) };
        let id = surface.add_to(&mut scene, None, opts).unwrap();
        let c = scene.object(id).unwrap().color_by.as_deref().expect("coloured");
        assert_eq!(c.clim, [2.0, 4.0], "the values volume's finite range");

        let bare = SceneIsosurface::extract(&vol, &tree, 0.0, None).unwrap();
        let opts = AddOptions { color_by: Some(ColorByArg::values(Vec::new())), ..AddOptions::new(25.0) };
        let e = bare.add_to(&mut Scene::new(), None, opts).unwrap_err();
        assert!(matches!(e, Error::Input { ref arg, .. } if arg == "values"), "{e}");
    }
}
