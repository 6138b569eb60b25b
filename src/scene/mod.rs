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

mod cmaps;
pub mod color;
pub mod grid;
mod heightfield;
pub mod kinds;
pub mod lens;
mod mesh;
mod occluders;
pub use occluders::Occluders;
pub(crate) mod serial;
pub mod slice;
pub mod well;

pub use color::{CmapArg, ColorBy, ColorByArg, ColorSource};
pub use heightfield::{GridAxes, GridFrame, HeightfieldInfo};

static NEXT_SCENE_UID: AtomicU64 = AtomicU64::new(1);

#[derive(Clone, Debug)]
pub(crate) enum ObjectKind {
    /// A height field: its grid layout in the grid's own frame and its tiles' slabs (boxed: an
    /// object of another kind, which may be an empty record of some 84 bytes, stays small).
    Heightfield(Box<HeightfieldInfo>),
    /// A triangle mesh; `kind` is the user's label ("fault", "mesh", "well", "slice", ...).
    Mesh { kind: String },
    /// A reservoir grid: its blocks are the tiles, their levels the cell-merging levels.
    Grid(Box<grid::GridInfo>),
}

#[derive(Clone, Debug)]
pub struct Object {
    pub id: u32,
    pub name: String,
    pub(in crate::scene) kind: ObjectKind,
    /// The flat colour (used when `color_by` is None).
    pub color: [f32; 3],
    /// Colour through a colour map by z or by the tiles' values (None: the flat `color`; boxed:
    /// most objects have none, and an empty object read from bytes stays small, issue 39).
    pub color_by: Option<Box<ColorBy>>,
    /// 1 for opaque objects; below 1 a translucent one (a volume lens): never an occluder, drawn
    /// blended after the opaque image, back to front, unlit.
    pub opacity: f32,
    pub visible: bool,
    /// Translation applied at draw time (world units).
    pub offset: DVec3,
    /// The f64 origin of this object's tiles: their f32 positions are relative to it. Each object
    /// has its own (the centre of its data, rounded to a metre), so precision never depends on the
    /// order objects were added in, nor on objects added or removed before.
    pub origin: DVec3,
    pub tiles: Vec<TileMesh>,
    /// Which of two surfaces at the same depth is drawn (higher wins; 0..=[`MAX_PRIORITY`]);
    /// None: by kind ([`Object::priority`]).
    pub priority: Option<u8>,
    /// Identifies this object's geometry (kind and tiles): a fresh number whenever they are built
    /// or replaced (`new_geometry_stamp`), kept by copies of the scene (the same geometry).
    /// Caches of what is derived from one object's geometry key by it, so changes to other
    /// objects leave them valid.
    pub geometry_stamp: u64,
    /// Enclosed occluder boxes (`culling = "implicit"`, [`Scene::set_occluders`]); None for most
    /// objects and for every object read from bytes (they are not serialised). Boxed: an object
    /// without stays small (issue 39).
    pub occluders: Option<std::sync::Arc<Occluders>>,
}

static NEXT_GEOMETRY_STAMP: AtomicU64 = AtomicU64::new(1);

/// A number no object's geometry has had in this process ([`Object::geometry_stamp`]).
pub fn new_geometry_stamp() -> u64 {
    NEXT_GEOMETRY_STAMP.fetch_add(1, Ordering::Relaxed)
}

/// The largest object priority ([`Object::priority`]).
pub const MAX_PRIORITY: u8 = 15;
/// The relative depth step per priority level (2^-21: about 8 f32 steps of depth, so that two
/// coincident surfaces triangulated differently never z-fight; 0.5 mm at 1 km), counted from
/// priority 4 (horizons: drawn exactly where they are). `common.wgsl`'s `priority_clip` applies
/// it; reported depths include it (objects of priority p: (p - 4) x 2^-21 relative, at most
/// 5.2e-6, 5 cm at 10 km).
pub const PRIORITY_DEPTH_STEP: f64 = 1.0 / (1u64 << 21) as f64;

impl Object {
    /// The object's depth-tie priority: its own, or its kind's ([`kinds::KINDS`]: wells 5,
    /// horizons 4, meshes (faults, isosurfaces) 3, reservoir grids 2, seismic slices 1, volume
    /// lenses 0). Every pass draws an object as if a fraction (priority - 4) x 2^-21 of its
    /// distance nearer ([`PRIORITY_DEPTH_STEP`]), so of two coincident surfaces the higher
    /// priority is seen, in every culling mode, whatever the draw order.
    pub fn priority(&self) -> u8 {
        self.priority.unwrap_or_else(|| self.kind().priority)
    }

    /// What is decided by this object's kind ([`kinds::KINDS`]).
    pub fn kind(&self) -> &'static kinds::Kind {
        kinds::of(self.kind_name())
    }

    /// A height field's grid layout and tiles' slabs; None for objects of other kinds.
    pub fn heightfield(&self) -> Option<&HeightfieldInfo> {
        match &self.kind {
            ObjectKind::Heightfield(hf) => Some(hf),
            _ => None,
        }
    }

    /// A reservoir grid's blocks and levels; None for objects of other kinds.
    pub fn grid(&self) -> Option<&grid::GridInfo> {
        match &self.kind {
            ObjectKind::Grid(g) => Some(g),
            _ => None,
        }
    }

    pub fn kind_name(&self) -> &str {
        match &self.kind {
            ObjectKind::Heightfield(_) => "heightfield",
            ObjectKind::Mesh { kind } => kind,
            ObjectKind::Grid(_) => "grid",
        }
    }
    pub fn fine_triangles(&self) -> usize {
        self.tiles.iter().map(|t| t.fine_triangles()).sum()
    }
    /// Where this object's tiles lie relative to `origin` (a render origin): its own origin plus
    /// its offset minus `origin`, in f64, so that a render space near the camera keeps full
    /// precision whatever the objects' coordinates and offsets are.
    pub fn placement(&self, origin: DVec3) -> DVec3 {
        (self.origin - origin) + self.offset
    }

    /// A structured grid mesh's fine normals for the lit pass's grid lookup: (columns, rows, the
    /// packed normal of every grid vertex, row-major), when every tile carries grid coordinates
    /// (`lod::TileMesh::grid_uv`); None otherwise.
    pub fn grid_normals(&self) -> Option<(usize, usize, Vec<u32>)> {
        let tiles = || self.tiles.iter().filter(|t| !t.is_empty());
        if tiles().next().is_none()
            || tiles().any(|t| t.grid_uv.len() != t.positions.len() || t.normals.len() != t.positions.len())
        {
            return None;
        }
        let (mut nu, mut nv) = (0usize, 0usize);
        for &k in tiles().flat_map(|t| &t.grid_uv) {
            nu = nu.max((k & 0xffff) as usize + 1);
            nv = nv.max((k >> 16) as usize + 1);
        }
        let mut grid = vec![crate::lod::normals::NONE; nu * nv];
        for t in tiles() {
            for (&k, &n) in t.grid_uv.iter().zip(&t.normals) {
                grid[(k >> 16) as usize * nu + (k & 0xffff) as usize] = n;
            }
        }
        Some((nu, nv, grid))
    }

    /// The brightest channel (0..=1) of any colour the lit pass may give this object: its flat
    /// colour, or every row of its colour map and its no-data colour.
    pub fn max_color_channel(&self) -> f32 {
        let max3 = |c: &[f32; 3]| c[0].max(c[1]).max(c[2]);
        match &self.color_by {
            None => max3(&self.color),
            Some(c) => c.lut.iter().chain(std::iter::once(&c.nan_color)).map(max3).fold(0.0, f32::max),
        }
    }

    /// The scalars colour by `source` reads, in world units for z (every vertex of every tile).
    pub fn scalars<'a>(&'a self, source: &ColorSource) -> Box<dyn Iterator<Item = f64> + 'a> {
        tile_scalars(&self.tiles, self.origin.z, source)
    }

    /// Object-origin-relative bounds of the object's geometry without its offset, or None when empty.
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

/// The scalars colour by `source` reads in `tiles` (every vertex), z in world units with the
/// tiles' `origin_z`: what `clim = None` takes its range from.
pub(super) fn tile_scalars<'a>(
    tiles: &'a [TileMesh],
    origin_z: f64,
    source: &ColorSource,
) -> Box<dyn Iterator<Item = f64> + 'a> {
    match source {
        ColorSource::Z => {
            Box::new(tiles.iter().flat_map(move |t| t.positions.iter().map(move |p| p[2] as f64 + origin_z)))
        }
        ColorSource::Values => Box::new(tiles.iter().flat_map(|t| t.values.iter().map(|&v| v as f64))),
    }
}

/// Options shared by `add_heightfield` and `add_mesh`.
#[derive(Clone, Debug)]
pub struct AddOptions {
    pub coarse_factor: f64,
    pub name: Option<String>,
    pub color: Option<[f64; 3]>,
    /// Colour by z or by values (see `color`); None: the flat `color`, except for height fields
    /// given no `color`, which are coloured by z (what users of horizons expect).
    pub color_by: Option<ColorByArg>,
    /// Polled while the tiles are built (between tiles); when it fires the add returns
    /// `Error::Interrupted` and the scene is unchanged.
    pub interrupt: Interrupt,
}

impl AddOptions {
    /// `coarse_factor` with the default name and colour and no interrupt.
    pub fn new(coarse_factor: f64) -> Self {
        Self { coarse_factor, name: None, color: None, color_by: None, interrupt: Interrupt::default() }
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
    /// The last object added: (the version it made, its id).
    last_add: Option<(u64, u32)>,
    /// Recent changes that only replaced one object's geometry (a moved slice): (version before,
    /// version after, object id), oldest first, at most [`REPLACEMENTS_KEPT`].
    replaced: Vec<(u64, u64, u32)>,
}

/// How many geometry replacements a scene remembers for [`Scene::replaced_since`].
const REPLACEMENTS_KEPT: usize = 64;

/// A copy with the same objects (ids, tiles, state) under a fresh identity: renderers key their
/// uploaded geometry by [`Scene::geometry_key`], so a copy is never mistaken for the original
/// (whose later edits would otherwise look like the copy's).
impl Clone for Scene {
    fn clone(&self) -> Self {
        Self {
            uid: NEXT_SCENE_UID.fetch_add(1, Ordering::Relaxed),
            geometry_version: 0,
            origin: self.origin,
            objects: self.objects.clone(),
            next_id: self.next_id,
            last_add: None,
            replaced: Vec::new(),
        }
    }
}

/// A summary (the geometry is too large to print).
impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("uid", &self.uid)
            .field("objects", &self.objects.len())
            .field("tiles", &self.n_tiles())
            .field("triangles", &self.n_triangles())
            .finish()
    }
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
        Some(c) => color::check_rgb(c, "color"),
    }
}

/// The colouring an add function uses: `opts.color_by`, else `default()` when no flat colour was
/// given. A flat colour and a colour by data together are an error (one would be ignored).
pub(super) fn color_by_arg(
    color: &Option<[f64; 3]>,
    color_by: Option<ColorByArg>,
    default: impl FnOnce() -> Option<ColorByArg>,
) -> Result<Option<ColorByArg>> {
    match (color, color_by) {
        (Some(_), Some(_)) => Err(input_err(
            "color",
            "color and color_by/values were both given; pass a flat color or a colouring by data, not both",
        )),
        (Some(_), None) => Ok(None),
        (None, Some(c)) => Ok(Some(c)),
        (None, None) => Ok(default()),
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
            last_add: None,
            replaced: Vec::new(),
        }
    }

    /// Identifies this scene and its geometry; renderers cache GPU buffers by it.
    pub fn geometry_key(&self) -> (u64, u64) {
        (self.uid, self.geometry_version)
    }

    /// The ids of the objects whose geometry was replaced (and nothing else changed: no object
    /// added, removed or reordered) between geometry version `version` and now, in order; None
    /// when something else changed or the changes are older than the scene remembers. An empty
    /// list for the current version.
    pub fn replaced_since(&self, version: u64) -> Option<Vec<u32>> {
        let mut at = version;
        let mut ids = Vec::new();
        while at != self.geometry_version {
            let &(_, to, id) = self.replaced.iter().find(|(from, _, _)| *from == at)?;
            ids.push(id);
            at = to;
        }
        Some(ids)
    }

    /// Records that the change from geometry version `from` to the current one only replaced
    /// object `id`'s geometry.
    pub(super) fn log_replacement(&mut self, from: u64, id: u32) {
        if self.replaced.len() == REPLACEMENTS_KEPT {
            self.replaced.remove(0);
        }
        self.replaced.push((from, self.geometry_version, id));
    }

    /// A reference origin for reports and serialisation: the first object's origin ever added (or
    /// 0). Renders do not use it: each object stores positions relative to its own origin
    /// ([`Object::origin`]) and every frame renders relative to an origin near its camera.
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

    /// Bounds of the visible objects relative to `origin` (offsets applied, no exaggeration).
    pub fn visible_bounds(&self, origin: DVec3) -> Option<(DVec3, DVec3)> {
        self.objects
            .iter()
            .filter(|o| o.visible)
            .filter_map(|o| {
                let p = o.placement(origin);
                o.local_bounds().map(|(a, b)| (a + p, b + p))
            })
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// World bounds `(min, max)` of every object's geometry, visible and hidden, offsets applied (no
    /// exaggeration); None when the scene has no triangle (no object, or only empty ones, e.g. height
    /// fields wholly made of holes). Taken from the tiles' boxes of the stored f32 origin-relative
    /// positions, so exact to f32 precision of the coordinates relative to each object's origin.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.objects
            .iter()
            .filter_map(|ob| {
                let p = ob.origin + ob.offset;
                ob.local_bounds().map(|(a, b)| (a + p, b + p))
            })
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The origin of a new object with bounds `lo`, `hi`: their centre, rounded to a metre so that
    /// it is a tidy number in reports (independent of the scene's other objects).
    pub(super) fn origin_for(&self, lo: DVec3, hi: DVec3) -> DVec3 {
        ((lo + hi) * 0.5).round()
    }

    /// Adds an object whose tiles are relative to `origin` (from [`Self::origin_for`]).
    pub(super) fn push(
        &mut self,
        origin: DVec3,
        name: Option<String>,
        kind: ObjectKind,
        color: [f32; 3],
        color_by: Option<ColorBy>,
        tiles: Vec<TileMesh>,
    ) -> u32 {
        self.push_levels(origin, name, kind, color, color_by, tiles, false)
    }

    /// [`Self::push`], keeping the levels of an object coloured by data when `levels_keep_values`
    /// (its levels bound the error of its values too, as a well's do: `crate::lod::tube`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push_levels(
        &mut self,
        origin: DVec3,
        name: Option<String>,
        kind: ObjectKind,
        color: [f32; 3],
        color_by: Option<ColorBy>,
        mut tiles: Vec<TileMesh>,
        levels_keep_values: bool,
    ) -> u32 {
        // Levels of detail bound the geometric error only: an object coloured by data keeps its
        // full resolution (coarser levels would blur its values), its coarse proxy still culls.
        if !levels_keep_values && color_by.as_ref().is_some_and(|c| c.source == ColorSource::Values) {
            for t in &mut tiles {
                t.levels = Box::default();
            }
        }
        crate::lod::share_indices(&mut tiles);
        self.origin.get_or_insert(origin);
        let id = self.next_id;
        self.next_id += 1;
        let name = name.unwrap_or_else(|| format!("object{id}"));
        self.objects.push(Object {
            id,
            name,
            kind,
            color,
            color_by: color_by.map(Box::new),
            opacity: 1.0,
            visible: true,
            offset: DVec3::ZERO,
            origin,
            tiles,
            priority: None,
            geometry_stamp: new_geometry_stamp(),
            occluders: None,
        });
        self.geometry_version += 1;
        self.last_add = Some((self.geometry_version, id));
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

    /// Sets object `id`'s depth-tie priority ([`Object::priority`]; None: by its kind).
    pub fn set_priority(&mut self, id: u32, priority: Option<i64>) -> Result<()> {
        if let Some(p) = priority {
            ensure((0..=MAX_PRIORITY as i64).contains(&p), "priority", || {
                format!("{p} is outside 0..={MAX_PRIORITY}")
            })?;
        }
        self.object_mut(id)?.priority = priority.map(|p| p as u8);
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

    /// Draws the object in one flat colour (ending any colour by data).
    pub fn set_color(&mut self, id: u32, color: [f64; 3]) -> Result<()> {
        let c = check_color(Some(color), id)?;
        let o = self.object_mut(id)?;
        o.color = c;
        o.color_by = None;
        Ok(())
    }

    /// Colours the object through a colour map by z, or by the values it was built with
    /// (`source = Values` needs values in its tiles: `arg.values` must be None here). No re-upload.
    pub fn set_color_by(&mut self, id: u32, arg: &ColorByArg) -> Result<()> {
        ensure(arg.values.is_none(), "values", || {
            "values cannot be replaced after an object is built; add it again with new values".into()
        })?;
        let o = self.object(id)?;
        let has_values = o.tiles.iter().any(|t| !t.values.is_empty());
        ensure(arg.source == ColorSource::Z || has_values, "color_by", || {
            format!("object {id} was built without values; color_by=\"values\" needs them (add it with values=)")
        })?;
        let c = arg.resolve(o.scalars(&arg.source))?;
        self.object_mut(id)?.color_by = Some(Box::new(c));
        Ok(())
    }

    /// The fine triangles of an object in world coordinates (offset applied): (vertices, faces).
    pub fn geometry(&self, id: u32) -> Result<Geometry> {
        let o = self.object(id)?;
        let origin = o.origin + o.offset;
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

    /// Bytes of geometry held on the host: vertices with their values, normals, grid coordinates
    /// and ring heights, and the triangle lists (fine, coarse, levels), each shared list once.
    pub fn host_bytes(&self) -> usize {
        // Triangle lists shared between tiles (lod::share_indices) count once.
        let mut seen = std::collections::HashSet::new();
        let mut list = |l: &crate::lod::Indices| if seen.insert(l.as_ptr()) { l.len() * 4 } else { 0 };
        let mut bytes = 0;
        for t in self.objects.iter().flat_map(|o| &o.tiles) {
            bytes += (t.positions.len() * 3
                + t.values.len()
                + t.normals.len()
                + t.grid_uv.len()
                + t.ring_z.len()
                + t.stations.len())
                * 4;
            bytes += list(&t.fine) + list(&t.coarse);
            bytes += t.levels.iter().map(|l| list(&l.indices)).sum::<usize>();
        }
        bytes
    }
}

#[cfg(test)]
mod tests;
