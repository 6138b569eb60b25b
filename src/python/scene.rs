//! `geocull._geocull.Scene`: objects in, tile table and geometry out.

use super::{run, run_interruptible};
use crate::error::{int_in, object_id};
use crate::scene::{AddOptions, Scene};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Largest tile count accepted (the core checks it against the grid too).
const MAX_INT: i64 = i32::MAX as i64;

#[pyclass(name = "Scene", module = "geocull._geocull")]
pub struct PyScene {
    pub(crate) inner: Scene,
}

#[pymethods]
impl PyScene {
    #[new]
    fn new() -> Self {
        Self { inner: Scene::new() }
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (z, origin, spacing, tiles, coarse_factor, name, color, null_value))]
    fn add_heightfield(
        &mut self,
        py: Python<'_>,
        z: PyReadonlyArray2<'_, f64>,
        origin: (f64, f64),
        spacing: (f64, f64),
        tiles: (i64, i64),
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        null_value: Option<f64>,
    ) -> PyResult<u32> {
        let shape = z.shape();
        let (ny, nx) = (shape[0], shape[1]);
        let data = super::contiguous(&z, "z")?;
        let scene = &mut self.inner;
        let color = color.map(|c| [c.0, c.1, c.2]);
        run_interruptible(py, move |interrupt| {
            let tiles = (int_in(tiles.0, "tiles[0]", 1, MAX_INT)?, int_in(tiles.1, "tiles[1]", 1, MAX_INT)?);
            let opts = AddOptions { coarse_factor, name, color, interrupt };
            scene.add_heightfield(data, ny, nx, [origin.0, origin.1], [spacing.0, spacing.1], tiles, null_value, opts)
        })
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (vertices, faces, kind, tiles, coarse_factor, name, color))]
    fn add_mesh(
        &mut self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        kind: String,
        tiles: Option<i64>,
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
    ) -> PyResult<u32> {
        let v: &[[f64; 3]] = bytemuck::cast_slice(super::contiguous(&vertices, "vertices")?);
        let f: &[[i64; 3]] = bytemuck::cast_slice(super::contiguous(&faces, "faces")?);
        let scene = &mut self.inner;
        let color = color.map(|c| [c.0, c.1, c.2]);
        run_interruptible(py, move |interrupt| {
            let tiles = tiles.map(|t| int_in(t, "tiles", 1, MAX_INT)).transpose()?;
            scene.add_mesh(v, f, &kind, tiles, AddOptions { coarse_factor, name, color, interrupt })
        })
    }

    fn remove(&mut self, py: Python<'_>, id: i64) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.remove(object_id(id)?))
    }
    fn set_visible(&mut self, py: Python<'_>, id: i64, visible: bool) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.set_visible(object_id(id)?, visible))
    }
    fn translate(&mut self, py: Python<'_>, id: i64, offset: (f64, f64, f64)) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.translate(object_id(id)?, [offset.0, offset.1, offset.2]))
    }
    fn set_color(&mut self, py: Python<'_>, id: i64, color: (f64, f64, f64)) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.set_color(object_id(id)?, [color.0, color.1, color.2]))
    }

    #[getter]
    fn n_tiles(&self) -> usize {
        self.inner.n_tiles()
    }
    #[getter]
    fn n_triangles(&self) -> usize {
        self.inner.n_triangles()
    }
    #[getter]
    fn origin(&self) -> (f64, f64, f64) {
        let o = self.inner.origin();
        (o.x, o.y, o.z)
    }
    #[getter]
    fn host_bytes(&self) -> usize {
        self.inner.host_bytes()
    }

    fn object_ids(&self) -> Vec<u32> {
        self.inner.objects().iter().map(|o| o.id).collect()
    }

    fn object_info<'py>(&self, py: Python<'py>, id: i64) -> PyResult<Bound<'py, PyDict>> {
        let o = object_id(id).and_then(|id| self.inner.object(id))?;
        let d = PyDict::new(py);
        d.set_item("id", o.id)?;
        d.set_item("name", &o.name)?;
        d.set_item("kind", o.kind_name())?;
        d.set_item("color", (o.color[0] as f64, o.color[1] as f64, o.color[2] as f64))?;
        d.set_item("visible", o.visible)?;
        d.set_item("offset", (o.offset.x, o.offset.y, o.offset.z))?;
        d.set_item("n_tiles", o.tiles.len())?;
        d.set_item("n_triangles", o.fine_triangles())?;
        Ok(d)
    }

    /// Columns of the tile table as numpy arrays (the Python layer makes a structured array).
    fn tile_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut object = Vec::new();
        let (mut ix, mut iy, mut fine, mut coarse) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut lo, mut hi) = (Vec::new(), Vec::new());
        let origin = self.inner.origin();
        for o in self.inner.objects() {
            for t in &o.tiles {
                object.push(o.id);
                ix.push(t.ix);
                iy.push(t.iy);
                fine.push(t.fine_triangles() as u32);
                coarse.push(t.coarse_triangles() as u32);
                for a in 0..3 {
                    let off = origin[a] + o.offset[a];
                    lo.push(if t.is_empty() { f64::NAN } else { t.bbox_min[a] as f64 + off });
                    hi.push(if t.is_empty() { f64::NAN } else { t.bbox_max[a] as f64 + off });
                }
            }
        }
        let n = object.len();
        let d = PyDict::new(py);
        d.set_item("object", object.into_pyarray(py))?;
        d.set_item("ix", ix.into_pyarray(py))?;
        d.set_item("iy", iy.into_pyarray(py))?;
        d.set_item("tris_fine", fine.into_pyarray(py))?;
        d.set_item("tris_coarse", coarse.into_pyarray(py))?;
        d.set_item("bbox_min", Array2::from_shape_vec((n, 3), lo).unwrap().into_pyarray(py))?;
        d.set_item("bbox_max", Array2::from_shape_vec((n, 3), hi).unwrap().into_pyarray(py))?;
        Ok(d)
    }

    /// Fine triangles of an object in world coordinates: (vertices (n, 3) float64, faces (m, 3) int64).
    fn geometry<'py>(&self, py: Python<'py>, id: i64) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let s = &self.inner;
        let (v, f) = run(py, move || s.geometry(object_id(id)?))?;
        let (nv, nf) = (v.len(), f.len());
        let v = Array2::from_shape_vec((nv, 3), v.into_iter().flatten().collect()).unwrap();
        let f = Array2::from_shape_vec((nf, 3), f.into_iter().flatten().map(|k| k as i64).collect()).unwrap();
        Ok((v.into_pyarray(py).into_any(), f.into_pyarray(py).into_any()))
    }
}
