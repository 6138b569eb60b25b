//! `geocull._geocull.Scene`: objects in, tile table and geometry out.

use super::{lock, run, run_interruptible, with_lock};
use crate::error::input_err;
use crate::error::{int_in, object_id};
use crate::iso::scene_object::SceneIsosurface;
use crate::scene::{AddOptions, CmapArg, ColorByArg, ColorSource, GridFrame, Scene};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::sync::Mutex;

/// Largest tile count accepted (the core checks it against the grid too).
const MAX_INT: i64 = i32::MAX as i64;

/// The add functions' colouring, as the Python layer passes it: (color_by "z" | "values", values,
/// colour-map name, colour-map table (n, 3), clim, nan_color).
type ColoringArgs<'py> = (
    String,
    Option<PyReadonlyArrayDyn<'py, f64>>,
    Option<String>,
    Option<PyReadonlyArray2<'py, f64>>,
    Option<(f64, f64)>,
    Option<(f64, f64, f64)>,
);

/// The core's colouring argument; `shape` is what `values` must be (`what` describes it).
fn coloring(c: Option<ColoringArgs<'_>>, shape: &[usize], what: &str) -> PyResult<Option<ColorByArg>> {
    let Some((by, values, name, table, clim, nan)) = c else { return Ok(None) };
    let source = match by.as_str() {
        "z" => ColorSource::Z,
        "values" => ColorSource::Values,
        _ => return Err(input_err("color_by", format!("{by:?}; expected \"z\" or \"values\"")).into()),
    };
    let values = match values {
        None => None,
        Some(v) => {
            if v.shape() != shape {
                return Err(input_err("values", format!("values has shape {:?}; expected {what}", v.shape())).into());
            }
            Some(super::contiguous(&v, "values")?.to_vec())
        }
    };
    let cmap = match (name, table) {
        (name, Some(t)) => {
            if t.shape()[1] != 3 {
                return Err(input_err(
                    "cmap",
                    format!("the table has shape {:?}; expected (n, 3) RGB rows", t.shape()),
                )
                .into());
            }
            Some(CmapArg::Table(bytemuck::cast_slice(super::contiguous(&t, "cmap")?).to_vec(), name))
        }
        (Some(n), None) => Some(CmapArg::Name(n)),
        (None, None) => None,
    };
    Ok(Some(ColorByArg {
        source,
        values,
        cmap,
        clim: clim.map(|c| [c.0, c.1]),
        nan_color: nan.map(|c| [c.0, c.1, c.2]),
    }))
}

/// `clim`, when not given, as the whole volume's finite range (slices and lenses of one volume
/// then share their colours).
fn volume_clim(c: &mut ColorByArg, vol: &crate::iso::Volume) -> crate::Result<()> {
    if c.clim.is_none() {
        c.clim = Some(crate::scene::color::resolve_clim(None, vol.finite_range().into_iter().flatten())?);
    }
    Ok(())
}

#[pyclass(name = "Scene", module = "geocull._geocull", frozen)]
pub struct PyScene {
    /// Locked by every method (see `super::with_lock`); renderers lock it after themselves.
    pub(crate) inner: Mutex<Scene>,
}

#[pymethods]
impl PyScene {
    #[new]
    fn new() -> Self {
        Self { inner: Mutex::new(Scene::new()) }
    }

    /// A copy: the same objects under a new identity (`Scene::clone`).
    fn copy(&self, py: Python<'_>) -> PyResult<Self> {
        with_lock(py, &self.inner, |s| Ok(Self { inner: Mutex::new(s.clone()) }))
    }

    /// The scene as bytes (`Scene::to_bytes`, a versioned little-endian layout).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let b = with_lock(py, &self.inner, |s| Ok(s.to_bytes()))?;
        Ok(PyBytes::new(py, &b))
    }

    /// A scene from `to_bytes`' bytes.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        run(py, move || Scene::from_bytes(data).map(|s| Self { inner: Mutex::new(s) }))
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (z, origin, spacing, tiles, coarse_factor, name, color, null_value, rotation, yflip, coloring=None))]
    fn add_heightfield(
        &self,
        py: Python<'_>,
        z: PyReadonlyArray2<'_, f64>,
        origin: (f64, f64),
        spacing: (f64, f64),
        tiles: (i64, i64),
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        null_value: Option<f64>,
        rotation: f64,
        yflip: bool,
        coloring: Option<ColoringArgs<'_>>,
    ) -> PyResult<u32> {
        let shape = z.shape();
        let (ny, nx) = (shape[0], shape[1]);
        let data = super::contiguous(&z, "z")?;
        let color_by = self::coloring(coloring, &[ny, nx], &format!("({ny}, {nx}), the shape of z"))?;
        let color = color.map(|c| [c.0, c.1, c.2]);
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let tiles = (int_in(tiles.0, "tiles[0]", 1, MAX_INT)?, int_in(tiles.1, "tiles[1]", 1, MAX_INT)?);
            let frame = GridFrame::new([origin.0, origin.1], [spacing.0, spacing.1]).rotated(rotation, yflip);
            let opts = AddOptions { coarse_factor, name, color, color_by, interrupt };
            lock(scene).add_heightfield(data, ny, nx, frame, tiles, null_value, opts)
        })
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (vertices, faces, kind, tiles, coarse_factor, name, color, coloring=None))]
    fn add_mesh(
        &self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        kind: String,
        tiles: Option<i64>,
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        coloring: Option<ColoringArgs<'_>>,
    ) -> PyResult<u32> {
        let v: &[[f64; 3]] = bytemuck::cast_slice(super::contiguous(&vertices, "vertices")?);
        let n = v.len();
        let color_by = self::coloring(coloring, &[n], &format!("({n},), one per vertex"))?;
        let f: &[[i64; 3]] = bytemuck::cast_slice(super::contiguous(&faces, "faces")?);
        let color = color.map(|c| [c.0, c.1, c.2]);
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let mut scene = lock(scene);
            let tiles = tiles.map(|t| int_in(t, "tiles", 1, MAX_INT)).transpose()?;
            scene.add_mesh(v, f, &kind, tiles, AddOptions { coarse_factor, name, color, color_by, interrupt })
        })
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (path, radius, sides, name, color, coloring=None))]
    fn add_well(
        &self,
        py: Python<'_>,
        path: PyReadonlyArray2<'_, f64>,
        radius: f64,
        sides: i64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        coloring: Option<ColoringArgs<'_>>,
    ) -> PyResult<u32> {
        let p: &[[f64; 3]] = bytemuck::cast_slice(super::contiguous(&path, "path")?);
        let n = p.len();
        let color_by = self::coloring(coloring, &[n], &format!("({n},), one per station of path"))?;
        let color = color.map(|c| [c.0, c.1, c.2]);
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let sides = int_in(sides, "sides", 3, 64)?;
            // The prepass proxy: a tube level with at most 1/25 of the fine triangles.
            let opts = AddOptions { coarse_factor: 25.0, name, color, color_by, interrupt };
            lock(scene).add_well(p, radius, sides, opts)
        })
    }

    /// A slice of `volume` at `index` along `axis` (0: constant i, "inline"; 1: constant j,
    /// "crossline"; 2: constant k, "sample"), coloured by its samples; `replace` = the id of a
    /// slice to move there instead of adding one.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (volume, axis, index, name, coloring, opacity=1.0, replace=None))]
    fn add_slice(
        &self,
        py: Python<'_>,
        volume: PyRef<'_, super::volume::PyVolume>,
        axis: i64,
        index: i64,
        name: Option<String>,
        coloring: ColoringArgs<'_>,
        opacity: f64,
        replace: Option<i64>,
    ) -> PyResult<u32> {
        let mut color_by =
            self::coloring(Some(coloring), &[], "none (the slice's values are the volume's)")?.expect("coloring given");
        if volume.inner.is_lazy() {
            // A lazy volume's range (the slices' colours) comes with its octree's one pass.
            volume.tree(py)?;
        }
        let vol = &volume.inner;
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let axis = int_in(axis, "axis", 0, 2)?;
            let dims = [vol.nx, vol.ny, vol.nz];
            let index = int_in(index, "index", 0, dims[axis] as i64 - 1)?;
            let whole = [(0, vol.nx - 1), (0, vol.ny - 1), (0, vol.nz - 1)];
            let (pos, vals, (nu, nv)) = vol.plane(axis, index, whole);
            vol.take_error()?;
            // The volume's range, so that every slice of it uses the same colours.
            volume_clim(&mut color_by, vol)?;
            let opts = AddOptions { coarse_factor: 16.0, name, color: None, color_by: Some(color_by), interrupt };
            let mut s = lock(scene);
            let id = s.add_lattice(&pos, vals, (nu, nv), "slice", opts)?;
            if let Err(e) = s.set_slice_opacity(id, opacity) {
                s.remove(id)?;
                return Err(e);
            }
            match replace {
                None => Ok(id),
                Some(old) => {
                    let old = object_id(old)?;
                    if let Err(e) = s.replace_lattice(old, id) {
                        s.remove(id)?;
                        return Err(e);
                    }
                    Ok(old)
                }
            }
        })
    }

    /// The isosurface `volume == isovalue` as a scene mesh (kind "isosurface") of about `tiles`
    /// spatially coherent tiles, culled like any object (three_pass: by the other objects), with
    /// its enclosed occluder boxes (`crate::iso::enclosed`) for `culling = "implicit"`.
    /// With `values` (a volume on `volume`'s grid) and `coloring`, its values at the vertices are
    /// the surface's (`coloring`'s own values stay None; coloured by them, its clim defaults to
    /// `values`' finite range, as a slice of that volume is).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (volume, isovalue, tiles, coarse_factor, name, color, coloring=None, values=None))]
    fn add_isosurface(
        &self,
        py: Python<'_>,
        volume: PyRef<'_, super::volume::PyVolume>,
        isovalue: f64,
        tiles: Option<i64>,
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        coloring: Option<ColoringArgs<'_>>,
        values: Option<PyRef<'_, super::volume::PyVolume>>,
    ) -> PyResult<u32> {
        let what = "none (an isosurface's values come from a volume on its grid: `values`)";
        let color_by = self::coloring(coloring, &[], what)?;
        let tree = volume.tree(py)?;
        let vol = &volume.inner;
        let other = values.as_ref().map(|v| &v.inner);
        let color = color.map(|c| [c.0, c.1, c.2]);
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let tiles = tiles.map(|t| int_in(t, "tiles", 1, MAX_INT)).transpose()?;
            let surface = SceneIsosurface::extract(vol, &tree, isovalue, other)?;
            let opts = AddOptions { coarse_factor, name, color, color_by, interrupt };
            surface.add_to(&mut lock(scene), tiles, opts)
        })
    }

    /// A volume lens: the sub-volume of `volume` over the inclusive sample ranges `bx`
    /// ((i0, i1), (j0, j1), (k0, k1)), as stacks of slices along each axis, blended with `opacity`.
    #[pyo3(signature = (volume, bx, opacity, name, coloring))]
    fn add_lens(
        &self,
        py: Python<'_>,
        volume: PyRef<'_, super::volume::PyVolume>,
        bx: [(i64, i64); 3],
        opacity: f64,
        name: Option<String>,
        coloring: ColoringArgs<'_>,
    ) -> PyResult<u32> {
        let mut color_by =
            self::coloring(Some(coloring), &[], "none (the lens's values are the volume's)")?.expect("coloring given");
        if volume.inner.is_lazy() {
            volume.tree(py)?;
        }
        let vol = &volume.inner;
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let dims = [vol.nx, vol.ny, vol.nz];
            let mut r = [(0usize, 0usize); 3];
            for a in 0..3 {
                let arg = ["box[0]", "box[1]", "box[2]"][a];
                let lo = int_in(bx[a].0, arg, 0, dims[a] as i64 - 1)?;
                let hi = int_in(bx[a].1, arg, 0, dims[a] as i64 - 1)?;
                crate::error::ensure(hi > lo, arg, || {
                    format!("({lo}, {hi}); a lens needs at least 2 samples along every axis (lo < hi, inclusive)")
                })?;
                r[a] = (lo, hi);
            }
            let mut slices = Vec::new();
            for axis in 0..3 {
                for index in r[axis].0..=r[axis].1 {
                    let (positions, values, (nu, nv)) = vol.plane(axis, index, r);
                    let (axis, index) = (axis as u32, index as u32);
                    slices.push(crate::scene::lens::LensSlice { axis, index, positions, values, nu, nv });
                }
            }
            vol.take_error()?;
            volume_clim(&mut color_by, vol)?;
            let opts = AddOptions { coarse_factor: 1.0, name, color: None, color_by: Some(color_by), interrupt };
            lock(scene).add_lens(slices, opacity, opts)
        })
    }

    /// A corner-point grid: `corners` (nk, nj, ni, 8, 3) float64, `active` (nk, nj, ni) bool,
    /// `region` (nk, nj, ni) int32, values (in `coloring`) one per cell.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (corners, active, region, blocks, name, color, coloring=None))]
    fn add_grid(
        &self,
        py: Python<'_>,
        corners: PyReadonlyArrayDyn<'_, f64>,
        active: Option<PyReadonlyArrayDyn<'_, bool>>,
        region: Option<PyReadonlyArrayDyn<'_, i32>>,
        blocks: (i64, i64),
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        coloring: Option<ColoringArgs<'_>>,
    ) -> PyResult<u32> {
        let sh = corners.shape().to_vec();
        if sh.len() != 5 || sh[3] != 8 || sh[4] != 3 {
            return Err(input_err("corners", format!("shape {sh:?} is not (nk, nj, ni, 8, 3)")).into());
        }
        let cells = &sh[..3];
        let what = format!("({}, {}, {}), one per cell", sh[0], sh[1], sh[2]);
        for (a, arg) in [
            (active.as_ref().map(|a| a.shape().to_vec()), "active"),
            (region.as_ref().map(|r| r.shape().to_vec()), "region"),
        ] {
            if let Some(a) = a {
                if a != cells {
                    return Err(input_err(arg, format!("shape {a:?}; expected {what}")).into());
                }
            }
        }
        let color_by = self::coloring(coloring, cells, &what)?;
        let c = super::contiguous(&corners, "corners")?;
        let act = active.as_ref().map(|a| super::contiguous(a, "active")).transpose()?;
        let reg = region.as_ref().map(|r| super::contiguous(r, "region")).transpose()?;
        let color = color.map(|c| [c.0, c.1, c.2]);
        let dims = (sh[0], sh[1], sh[2]);
        let scene = &self.inner;
        run_interruptible(py, move |interrupt| {
            let blocks = (int_in(blocks.0, "blocks[0]", 1, MAX_INT)?, int_in(blocks.1, "blocks[1]", 1, MAX_INT)?);
            let opts = AddOptions { coarse_factor: 1.0, name, color, color_by, interrupt };
            lock(scene).add_grid(dims, c, act, reg, blocks, opts)
        })
    }

    /// Per level of grid `id`: a dict of cells, faces, triangles, interior_triangles, vertices,
    /// volume (m^3).
    fn grid_levels<'py>(&self, py: Python<'py>, id: i64) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let levels = with_lock(py, &self.inner, move |s| Ok(s.grid_levels(object_id(id)?)?.to_vec()))?;
        levels
            .iter()
            .map(|l| {
                let d = PyDict::new(py);
                d.set_item("cells", l.cells)?;
                d.set_item("faces", l.faces)?;
                d.set_item("triangles", l.triangles)?;
                d.set_item("interior_triangles", l.interior_triangles)?;
                d.set_item("vertices", l.vertices)?;
                d.set_item("volume", l.volume)?;
                Ok(d)
            })
            .collect()
    }

    fn remove(&self, py: Python<'_>, id: i64) -> PyResult<()> {
        with_lock(py, &self.inner, move |s| s.remove(object_id(id)?))
    }
    #[pyo3(signature = (id, priority))]
    fn set_priority(&self, py: Python<'_>, id: i64, priority: Option<i64>) -> PyResult<()> {
        with_lock(py, &self.inner, move |s| s.set_priority(object_id(id)?, priority))
    }
    fn set_visible(&self, py: Python<'_>, id: i64, visible: bool) -> PyResult<()> {
        with_lock(py, &self.inner, move |s| s.set_visible(object_id(id)?, visible))
    }
    fn translate(&self, py: Python<'_>, id: i64, offset: (f64, f64, f64)) -> PyResult<()> {
        with_lock(py, &self.inner, move |s| s.translate(object_id(id)?, [offset.0, offset.1, offset.2]))
    }
    fn set_color(&self, py: Python<'_>, id: i64, color: (f64, f64, f64)) -> PyResult<()> {
        with_lock(py, &self.inner, move |s| s.set_color(object_id(id)?, [color.0, color.1, color.2]))
    }

    /// Colours object `id` by z or by the values it was built with (`coloring`'s values must be None).
    fn set_color_by(&self, py: Python<'_>, id: i64, coloring: ColoringArgs<'_>) -> PyResult<()> {
        let c = self::coloring(Some(coloring), &[], "none (values are fixed when an object is added)")?
            .expect("coloring given");
        with_lock(py, &self.inner, move |s| s.set_color_by(object_id(id)?, &c))
    }

    #[getter]
    fn n_tiles(&self, py: Python<'_>) -> PyResult<usize> {
        with_lock(py, &self.inner, |s| Ok(s.n_tiles()))
    }
    #[getter]
    fn n_triangles(&self, py: Python<'_>) -> PyResult<usize> {
        with_lock(py, &self.inner, |s| Ok(s.n_triangles()))
    }
    #[getter]
    fn origin(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        with_lock(py, &self.inner, |s| Ok(s.origin().into()))
    }
    /// World ((xmin, ymin, zmin), (xmax, ymax, zmax)) of every object, visible or hidden; None
    /// when the scene holds no triangle.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn bounds(&self, py: Python<'_>) -> PyResult<Option<((f64, f64, f64), (f64, f64, f64))>> {
        with_lock(py, &self.inner, |s| Ok(s.bounds().map(|(a, b)| (a.into(), b.into()))))
    }
    #[getter]
    fn host_bytes(&self, py: Python<'_>) -> PyResult<usize> {
        with_lock(py, &self.inner, |s| Ok(s.host_bytes()))
    }

    fn object_ids(&self, py: Python<'_>) -> PyResult<Vec<u32>> {
        with_lock(py, &self.inner, |s| Ok(s.objects().iter().map(|o| o.id).collect()))
    }

    fn object_info<'py>(&self, py: Python<'py>, id: i64) -> PyResult<Bound<'py, PyDict>> {
        type Info =
            (u32, String, String, [f32; 3], bool, glam::DVec3, usize, usize, Option<Box<crate::scene::ColorBy>>, u8);
        let (id, name, kind, color, visible, offset, n_tiles, n_tris, color_by, priority): Info =
            with_lock(py, &self.inner, move |s| {
                let o = s.object(object_id(id)?)?;
                Ok((
                    o.id,
                    o.name.clone(),
                    o.kind_name().to_string(),
                    o.color,
                    o.visible,
                    o.offset,
                    o.tiles.len(),
                    o.fine_triangles(),
                    o.color_by.clone(),
                    o.priority(),
                ))
            })?;
        let d = PyDict::new(py);
        d.set_item("id", id)?;
        d.set_item("name", name)?;
        d.set_item("kind", kind)?;
        d.set_item("color", (color[0] as f64, color[1] as f64, color[2] as f64))?;
        d.set_item("visible", visible)?;
        d.set_item("priority", priority)?;
        d.set_item("offset", (offset.x, offset.y, offset.z))?;
        d.set_item("n_tiles", n_tiles)?;
        d.set_item("n_triangles", n_tris)?;
        let by = color_by.as_ref().map(|c| if c.source == ColorSource::Z { "z" } else { "values" });
        d.set_item("color_by", by)?;
        d.set_item("cmap", color_by.as_ref().map(|c| c.cmap.clone()))?;
        d.set_item("clim", color_by.as_ref().map(|c| (c.clim[0], c.clim[1])))?;
        Ok(d)
    }

    /// Columns of the tile table as numpy arrays (the Python layer makes a structured array).
    fn tile_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = with_lock(py, &self.inner, |s| Ok(TileColumns::of(s)))?;
        let n = t.object.len();
        let d = PyDict::new(py);
        d.set_item("object", t.object.into_pyarray(py))?;
        d.set_item("ix", t.ix.into_pyarray(py))?;
        d.set_item("iy", t.iy.into_pyarray(py))?;
        d.set_item("tris_fine", t.fine.into_pyarray(py))?;
        d.set_item("tris_coarse", t.coarse.into_pyarray(py))?;
        d.set_item("proxy_error", t.proxy_error.into_pyarray(py))?;
        d.set_item("level_triangles", Array2::from_shape_vec((n, NL), t.level_tris).unwrap().into_pyarray(py))?;
        d.set_item("level_error", Array2::from_shape_vec((n, NL), t.level_err).unwrap().into_pyarray(py))?;
        d.set_item("level_error_z", Array2::from_shape_vec((n, NL), t.level_err_z).unwrap().into_pyarray(py))?;
        let shading = Array2::from_shape_vec((n, NL), t.level_shading).unwrap();
        d.set_item("level_shading_error", shading.into_pyarray(py))?;
        d.set_item("bbox_min", Array2::from_shape_vec((n, 3), t.lo).unwrap().into_pyarray(py))?;
        d.set_item("bbox_max", Array2::from_shape_vec((n, 3), t.hi).unwrap().into_pyarray(py))?;
        Ok(d)
    }

    /// Fine triangles of an object in world coordinates: (vertices (n, 3) float64, faces (m, 3) int64).
    fn geometry<'py>(&self, py: Python<'py>, id: i64) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let (v, f) = with_lock(py, &self.inner, move |s| s.geometry(object_id(id)?))?;
        let (nv, nf) = (v.len(), f.len());
        let (v, f) = run(py, move || {
            let v = Array2::from_shape_vec((nv, 3), v.into_iter().flatten().collect()).unwrap();
            let f = Array2::from_shape_vec((nf, 3), f.into_iter().flatten().map(|k| k as i64).collect()).unwrap();
            Ok((v, f))
        })?;
        Ok((v.into_pyarray(py).into_any(), f.into_pyarray(py).into_any()))
    }
}

/// The tile table's columns, gathered under the scene's lock.
/// LOD levels per tile in the tile table: 0..=MAX_LEVELS (level 0 = fine).
const NL: usize = 1 + crate::lod::levels::MAX_LEVELS;

#[derive(Default)]
struct TileColumns {
    object: Vec<u32>,
    ix: Vec<u32>,
    iy: Vec<u32>,
    fine: Vec<u32>,
    coarse: Vec<u32>,
    proxy_error: Vec<f64>,
    /// (n, NL) row-major: triangles, geometric and shading error (NaN where a tile has fewer
    /// levels) per level.
    level_tris: Vec<u32>,
    level_err: Vec<f64>,
    level_err_z: Vec<f64>,
    level_shading: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl TileColumns {
    fn of(s: &Scene) -> Self {
        let mut t = TileColumns::default();
        for o in s.objects() {
            for tile in &o.tiles {
                t.object.push(o.id);
                t.ix.push(tile.ix);
                t.iy.push(tile.iy);
                t.fine.push(tile.fine_triangles() as u32);
                t.coarse.push(tile.coarse_triangles() as u32);
                t.proxy_error.push(tile.proxy_error as f64);
                for l in 0..NL {
                    let lv = if l == 0 {
                        Some((tile.fine_triangles(), 0.0, 0.0, 0.0))
                    } else {
                        tile.levels.get(l - 1).map(|v| (v.indices.len() / 3, v.error, v.shading_error, v.error_z))
                    };
                    t.level_tris.push(lv.map_or(0, |v| v.0 as u32));
                    t.level_err.push(lv.map_or(f64::NAN, |v| v.1 as f64));
                    t.level_shading.push(lv.map_or(f64::NAN, |v| v.2 as f64));
                    t.level_err_z.push(lv.map_or(f64::NAN, |v| v.3 as f64));
                }
                for a in 0..3 {
                    let off = o.origin[a] + o.offset[a];
                    t.lo.push(if tile.is_empty() { f64::NAN } else { tile.bbox_min[a] as f64 + off });
                    t.hi.push(if tile.is_empty() { f64::NAN } else { tile.bbox_max[a] as f64 + off });
                }
            }
        }
        t
    }
}
