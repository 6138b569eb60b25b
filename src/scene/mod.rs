//! The scene: objects (height fields, meshes) cut into tiles with LOD levels, stored relative to
//! one f64 origin so that positions fit f32 on the GPU with full precision.
//!
//! Geometry changes (add/remove) bump `geometry_version`, which tells renderers to re-upload;
//! visibility, colour and translation are per-object state read every frame (no re-upload).

use crate::camera::MAX_COORD;
use crate::error::{ensure, input_err, num, Interrupt, Result};
use crate::lod::TileMesh;
use glam::DVec3;
use std::sync::atomic::{AtomicU64, Ordering};

mod heightfield;
mod mesh;

static NEXT_SCENE_UID: AtomicU64 = AtomicU64::new(1);

#[derive(Clone, Debug)]
pub enum ObjectKind {
    /// A height field: its grid layout (x0, y0 relative to the scene origin). The heights live only
    /// in the tiles' vertices; [`Object::height_grid`] rebuilds the grid when a CPU culler needs it.
    Heightfield { nx: usize, ny: usize, x0: f64, y0: f64, dx: f64, dy: f64, tiles: (usize, usize) },
    /// A triangle mesh; `kind` is the user's label ("fault", "mesh", ...).
    Mesh { kind: String },
}

#[derive(Clone, Debug)]
pub struct Object {
    pub id: u32,
    pub name: String,
    pub kind: ObjectKind,
    pub color: [f32; 3],
    pub visible: bool,
    /// Translation applied at draw time (world units).
    pub offset: DVec3,
    pub tiles: Vec<TileMesh>,
}

impl Object {
    pub fn kind_name(&self) -> &str {
        match &self.kind {
            ObjectKind::Heightfield { .. } => "heightfield",
            ObjectKind::Mesh { kind } => kind,
        }
    }
    pub fn fine_triangles(&self) -> usize {
        self.tiles.iter().map(|t| t.fine_triangles()).sum()
    }
    /// Origin-relative bounds of the object's geometry without its offset, or None when empty.
    pub fn local_bounds(&self) -> Option<(DVec3, DVec3)> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in self.tiles.iter().filter(|t| !t.is_empty()) {
            lo = lo.min(DVec3::from_array(t.bbox_min.map(f64::from)));
            hi = hi.max(DVec3::from_array(t.bbox_max.map(f64::from)));
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }
}

/// Options shared by `add_heightfield` and `add_mesh`.
#[derive(Clone, Debug)]
pub struct AddOptions {
    pub coarse_factor: f64,
    pub name: Option<String>,
    pub color: Option<[f64; 3]>,
    /// Polled while the tiles are built (between tiles); when it fires the add returns
    /// `Error::Interrupted` and the scene is unchanged.
    pub interrupt: Interrupt,
}

impl AddOptions {
    /// `coarse_factor` with the default name and colour and no interrupt.
    pub fn new(coarse_factor: f64) -> Self {
        Self { coarse_factor, name: None, color: None, interrupt: Interrupt::default() }
    }
}

/// An object's triangles in world coordinates: (vertices, faces).
pub type Geometry = (Vec<[f64; 3]>, Vec<[u32; 3]>);

pub struct Scene {
    uid: u64,
    geometry_version: u64,
    origin: Option<DVec3>,
    objects: Vec<Object>,
    next_id: u32,
}

impl Default for Scene {
    fn default() -> Self {
        Self::new()
    }
}

/// Default colours, cycled by object id.
const PALETTE: [[f32; 3]; 8] = [
    [0.90, 0.62, 0.30],
    [0.35, 0.65, 0.85],
    [0.55, 0.80, 0.45],
    [0.85, 0.45, 0.55],
    [0.75, 0.70, 0.40],
    [0.60, 0.50, 0.85],
    [0.40, 0.80, 0.75],
    [0.85, 0.85, 0.85],
];

pub(super) fn check_color(c: Option<[f64; 3]>, id: u32) -> Result<[f32; 3]> {
    match c {
        None => Ok(PALETTE[id as usize % PALETTE.len()]),
        Some(c) => {
            for (i, v) in c.iter().enumerate() {
                ensure(v.is_finite() && (0.0..=1.0).contains(v), "color", || {
                    format!("component {i} is {v}; colours are (r, g, b) in [0, 1]")
                })?;
            }
            Ok(c.map(|v| v as f32))
        }
    }
}

pub(super) fn check_coarse_factor(cf: f64) -> Result<f32> {
    ensure(cf.is_finite() && cf >= 1.0, "coarse_factor", || format!("coarse_factor is {cf}; expected a number >= 1"))?;
    Ok(cf as f32)
}

impl Scene {
    pub fn new() -> Self {
        Self {
            uid: NEXT_SCENE_UID.fetch_add(1, Ordering::Relaxed),
            geometry_version: 0,
            origin: None,
            objects: Vec::new(),
            next_id: 0,
        }
    }

    /// Identifies this scene and its geometry; renderers cache GPU buffers by it.
    pub fn geometry_key(&self) -> (u64, u64) {
        (self.uid, self.geometry_version)
    }

    /// The f64 origin all positions are stored relative to (set by the first object).
    pub fn origin(&self) -> DVec3 {
        self.origin.unwrap_or(DVec3::ZERO)
    }

    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    pub fn object(&self, id: u32) -> Result<&Object> {
        self.objects
            .iter()
            .find(|o| o.id == id)
            .ok_or_else(|| input_err("id", format!("no object with id {id} in this scene")))
    }

    fn object_mut(&mut self, id: u32) -> Result<&mut Object> {
        self.objects
            .iter_mut()
            .find(|o| o.id == id)
            .ok_or_else(|| input_err("id", format!("no object with id {id} in this scene")))
    }

    pub fn n_tiles(&self) -> usize {
        self.objects.iter().map(|o| o.tiles.len()).sum()
    }

    pub fn n_triangles(&self) -> usize {
        self.objects.iter().map(|o| o.fine_triangles()).sum()
    }

    /// Origin-relative bounds of the visible objects (offsets applied, no exaggeration).
    pub fn visible_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.objects
            .iter()
            .filter(|o| o.visible)
            .filter_map(|o| o.local_bounds().map(|(a, b)| (a + o.offset, b + o.offset)))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The scene's origin, or the one the first object with bounds `lo`, `hi` will set (the
    /// centre, rounded to a metre so that it is a tidy number in reports). Set by `push`, so that
    /// an interrupted or failed add leaves the scene as it was.
    pub(super) fn origin_for(&self, lo: DVec3, hi: DVec3) -> DVec3 {
        self.origin.unwrap_or_else(|| ((lo + hi) * 0.5).round())
    }

    /// Adds an object whose tiles are relative to `origin` (from [`Self::origin_for`]).
    pub(super) fn push(
        &mut self,
        origin: DVec3,
        name: Option<String>,
        kind: ObjectKind,
        color: [f32; 3],
        tiles: Vec<TileMesh>,
    ) -> u32 {
        self.origin = Some(origin);
        let id = self.next_id;
        self.next_id += 1;
        let name = name.unwrap_or_else(|| format!("object{id}"));
        self.objects.push(Object { id, name, kind, color, visible: true, offset: DVec3::ZERO, tiles });
        self.geometry_version += 1;
        id
    }

    pub fn remove(&mut self, id: u32) -> Result<()> {
        let idx = self
            .objects
            .iter()
            .position(|o| o.id == id)
            .ok_or_else(|| input_err("id", format!("no object with id {id} in this scene")))?;
        self.objects.remove(idx);
        self.geometry_version += 1;
        Ok(())
    }

    pub fn set_visible(&mut self, id: u32, visible: bool) -> Result<()> {
        self.object_mut(id)?.visible = visible;
        Ok(())
    }

    pub fn translate(&mut self, id: u32, d: [f64; 3]) -> Result<()> {
        for (i, v) in d.iter().enumerate() {
            ensure(v.is_finite(), "offset", || format!("component {i} is {v}; expected a finite number"))?;
        }
        let o = self.object_mut(id)?;
        let new = o.offset + DVec3::from_array(d);
        for (i, v) in new.to_array().iter().enumerate() {
            ensure(v.abs() <= MAX_COORD, "offset", || {
                format!(
                    "component {i}: the total offset would be {}; coordinates must be within +-{MAX_COORD:e}",
                    num(*v)
                )
            })?;
        }
        o.offset = new;
        Ok(())
    }

    pub fn set_color(&mut self, id: u32, color: [f64; 3]) -> Result<()> {
        let c = check_color(Some(color), id)?;
        self.object_mut(id)?.color = c;
        Ok(())
    }

    /// The fine triangles of an object in world coordinates (offset applied): (vertices, faces).
    pub fn geometry(&self, id: u32) -> Result<Geometry> {
        let o = self.object(id)?;
        let origin = self.origin() + o.offset;
        let mut verts = Vec::new();
        let mut faces = Vec::new();
        for t in &o.tiles {
            let base = verts.len() as u32;
            verts.extend(
                t.positions.iter().map(|p| [p[0] as f64 + origin.x, p[1] as f64 + origin.y, p[2] as f64 + origin.z]),
            );
            faces.extend(t.fine.chunks_exact(3).map(|c| [c[0] + base, c[1] + base, c[2] + base]));
        }
        Ok((verts, faces))
    }

    /// Bytes of geometry held on the host (vertices, both index levels, height grids).
    pub fn host_bytes(&self) -> usize {
        self.objects
            .iter()
            .map(|o| {
                o.tiles.iter().map(|t| t.positions.len() * 12 + (t.fine.len() + t.coarse.len()) * 4).sum::<usize>()
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> AddOptions {
        AddOptions::new(1.0)
    }

    #[test]
    fn utm_origin_keeps_precision() {
        let mut s = Scene::new();
        let z = vec![-2500.0; 4];
        s.add_heightfield(&z, 2, 2, [450_000.0, 6_780_000.0], [10.0, 10.0], (1, 1), None, opts()).unwrap();
        let z2 = vec![-2500.5; 4];
        s.add_heightfield(&z2, 2, 2, [450_000.0, 6_780_000.0], [10.0, 10.0], (1, 1), None, opts()).unwrap();
        let (a, _) = s.geometry(0).unwrap();
        let (b, _) = s.geometry(1).unwrap();
        assert_eq!(a[0][0], 450_000.0);
        assert!((a[0][2] - b[0][2] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn errors_name_arguments() {
        let mut s = Scene::new();
        let z = vec![0.0; 4];
        let e = s.add_heightfield(&z, 2, 2, [0.0, 0.0], [0.0, 1.0], (1, 1), None, opts()).unwrap_err();
        assert!(e.to_string().starts_with("spacing"), "{e}");
        let e = s.add_heightfield(&z, 2, 2, [0.0, 0.0], [1.0, 1.0], (2, 1), None, opts()).unwrap_err();
        assert!(e.to_string().starts_with("tiles"), "{e}");
        let e = s.add_mesh(&[[0.0; 3]], &[[0, 0, 1]], "mesh", None, opts()).unwrap_err();
        assert!(e.to_string().starts_with("faces[0, 2]"), "{e}");
        let e = s.add_mesh(&[[0.0, f64::NAN, 0.0]], &[[0, 0, 0]], "mesh", None, opts()).unwrap_err();
        assert!(e.to_string().starts_with("vertices[0, 1]"), "{e}");
    }

    #[test]
    fn null_value_makes_holes() {
        let mut s = Scene::new();
        let mut z = vec![0.0; 9];
        z[4] = -999.25;
        s.add_heightfield(&z, 3, 3, [0.0, 0.0], [1.0, 1.0], (1, 1), Some(-999.25), opts()).unwrap();
        assert_eq!(s.n_triangles(), 8 - 6);
    }
}
