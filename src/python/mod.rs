//! PyO3 bindings: numpy in and out, errors mapped onto geocull's exception hierarchy, the GIL
//! released around every piece of real work, and no panic ever crossing into Python. All
//! argument checking lives in the core (`crate::scene`, `crate::camera`, `crate::gpu`); the Python
//! package (python/geocull) coerces dtypes and layouts before calling in here.

use crate::camera::{Camera, Projection};
use crate::cull::Culling;
use crate::error::Error;
use crate::gpu::{RenderOptions, RenderOutput, Renderer};
use crate::scene::{AddOptions, Scene};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use std::panic::{catch_unwind, AssertUnwindSafe};

mod iso;

/// Raises geocull's exception class `name` (defined in python/geocull/_errors.py).
pub(crate) fn raise(py: Python<'_>, name: &str, msg: String) -> PyErr {
    match py.import("geocull._errors").and_then(|m| m.getattr(name)) {
        Ok(cls) => match cls.cast_into::<PyType>() {
            Ok(t) => PyErr::from_type(t, msg),
            Err(_) => pyo3::exceptions::PyRuntimeError::new_err(msg),
        },
        Err(_) => pyo3::exceptions::PyRuntimeError::new_err(msg),
    }
}

pub(crate) fn to_py(py: Python<'_>, e: Error) -> PyErr {
    match e {
        Error::Input { .. } => raise(py, "InputError", e.to_string()),
        Error::Device(m) => raise(py, "DeviceError", m),
    }
}

/// Runs `f` without the GIL, turning errors and panics into Python exceptions.
pub(crate) fn run<T: Send>(py: Python<'_>, f: impl FnOnce() -> crate::Result<T> + Send) -> PyResult<T> {
    let r = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match r {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(to_py(py, e)),
        Err(p) => {
            let what = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(raise(py, "GeocullError", format!("internal error in geocull (please report): {what}")))
        }
    }
}

fn slice2<'a, T: numpy::Element>(a: &'a PyReadonlyArray2<'_, T>, arg: &str) -> PyResult<&'a [T]> {
    a.as_slice().map_err(|_| pyo3::exceptions::PyValueError::new_err(format!("{arg}: array must be C-contiguous")))
}

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
        tiles: (usize, usize),
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
        null_value: Option<f64>,
    ) -> PyResult<u32> {
        let shape = z.shape();
        let (ny, nx) = (shape[0], shape[1]);
        let data = slice2(&z, "z")?;
        let scene = &mut self.inner;
        let opts = AddOptions { coarse_factor, name, color: color.map(|c| [c.0, c.1, c.2]) };
        run(py, move || {
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
        tiles: Option<usize>,
        coarse_factor: f64,
        name: Option<String>,
        color: Option<(f64, f64, f64)>,
    ) -> PyResult<u32> {
        let v: &[[f64; 3]] = bytemuck::cast_slice(slice2(&vertices, "vertices")?);
        let f: &[[i64; 3]] = bytemuck::cast_slice(slice2(&faces, "faces")?);
        let scene = &mut self.inner;
        let opts = AddOptions { coarse_factor, name, color: color.map(|c| [c.0, c.1, c.2]) };
        run(py, move || scene.add_mesh(v, f, &kind, tiles, opts))
    }

    fn remove(&mut self, py: Python<'_>, id: u32) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.remove(id))
    }
    fn set_visible(&mut self, py: Python<'_>, id: u32, visible: bool) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.set_visible(id, visible))
    }
    fn translate(&mut self, py: Python<'_>, id: u32, offset: (f64, f64, f64)) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.translate(id, [offset.0, offset.1, offset.2]))
    }
    fn set_color(&mut self, py: Python<'_>, id: u32, color: (f64, f64, f64)) -> PyResult<()> {
        let s = &mut self.inner;
        run(py, move || s.set_color(id, [color.0, color.1, color.2]))
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

    fn object_info<'py>(&self, py: Python<'py>, id: u32) -> PyResult<Bound<'py, PyDict>> {
        let o = self.inner.object(id).map_err(|e| to_py(py, e))?;
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
    fn geometry<'py>(&self, py: Python<'py>, id: u32) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let s = &self.inner;
        let (v, f) = run(py, move || s.geometry(id))?;
        let (nv, nf) = (v.len(), f.len());
        let v = Array2::from_shape_vec((nv, 3), v.into_iter().flatten().collect()).unwrap();
        let f = Array2::from_shape_vec((nf, 3), f.into_iter().flatten().map(|k| k as i64).collect()).unwrap();
        Ok((v.into_pyarray(py).into_any(), f.into_pyarray(py).into_any()))
    }
}

#[pyclass(name = "Camera", module = "geocull._geocull", from_py_object)]
#[derive(Clone)]
pub struct PyCamera {
    pub(crate) inner: Camera,
}

#[pymethods]
impl PyCamera {
    #[allow(clippy::too_many_arguments)]
    #[staticmethod]
    #[pyo3(signature = (eye, target, up, fov_y, near, far, projection, ortho_height, z_scale))]
    fn look_at(
        py: Python<'_>,
        eye: (f64, f64, f64),
        target: (f64, f64, f64),
        up: (f64, f64, f64),
        fov_y: f64,
        near: Option<f64>,
        far: Option<f64>,
        projection: String,
        ortho_height: Option<f64>,
        z_scale: f64,
    ) -> PyResult<Self> {
        let v = |t: (f64, f64, f64)| [t.0, t.1, t.2];
        run(py, move || {
            let p = Projection::parse(&projection)?;
            Camera::look_at(v(eye), v(target), v(up), fov_y, near, far, p, ortho_height, z_scale)
                .map(|inner| Self { inner })
        })
    }
    #[getter]
    fn eye(&self) -> (f64, f64, f64) {
        self.inner.eye.into()
    }
    #[getter]
    fn target(&self) -> (f64, f64, f64) {
        self.inner.target.into()
    }
    #[getter]
    fn up(&self) -> (f64, f64, f64) {
        self.inner.up.into()
    }
    #[getter]
    fn fov_y(&self) -> f64 {
        self.inner.fov_y
    }
    #[getter]
    fn near(&self) -> Option<f64> {
        self.inner.near
    }
    #[getter]
    fn far(&self) -> Option<f64> {
        self.inner.far
    }
    #[getter]
    fn projection(&self) -> &'static str {
        self.inner.projection.name()
    }
    #[getter]
    fn ortho_height(&self) -> Option<f64> {
        self.inner.ortho_height
    }
    #[getter]
    fn z_scale(&self) -> f64 {
        self.inner.z_scale
    }
    /// The view matrix (4, 4) in world coordinates with exaggeration (row-major numpy).
    fn view_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let f = self.inner.frame(glam::DVec3::ZERO, None, 1.0);
        let m = f.view.transpose().to_cols_array().to_vec();
        Array2::from_shape_vec((4, 4), m).unwrap().into_pyarray(py).into_any()
    }
}

#[pyclass(name = "Renderer", module = "geocull._geocull")]
pub struct PyRenderer {
    pub(crate) inner: Renderer,
}

fn output_dict<'py>(py: Python<'py>, out: RenderOutput) -> PyResult<Bound<'py, PyDict>> {
    let (w, h) = (out.width as usize, out.height as usize);
    let d = PyDict::new(py);
    d.set_item("image", Array3::from_shape_vec((h, w, 4), out.image).unwrap().into_pyarray(py))?;
    d.set_item("depth", Array2::from_shape_vec((h, w), out.depth).unwrap().into_pyarray(py))?;
    d.set_item("tile_pixels", Array1::from_vec(out.tile_pixels).into_pyarray(py))?;
    d.set_item("tile_drawn", Array1::from_vec(out.tile_drawn).into_pyarray(py))?;
    d.set_item("near", out.near)?;
    d.set_item("far", out.far)?;
    let s = &out.stats;
    let st = PyDict::new(py);
    st.set_item("triangles_fine_total", s.triangles_fine_total)?;
    st.set_item("triangles_drawn", s.triangles_drawn)?;
    st.set_item("triangles_prepass", s.triangles_prepass)?;
    st.set_item("tiles_total", s.tiles_total)?;
    st.set_item("tiles_drawn", s.tiles_drawn)?;
    st.set_item("prepass_ms", s.prepass_ms)?;
    st.set_item("count_ms", s.count_ms)?;
    st.set_item("draw_ms", s.draw_ms)?;
    st.set_item("cull_ms", s.cull_ms)?;
    st.set_item("total_ms", s.total_ms)?;
    st.set_item("readback_ms", s.readback_ms)?;
    st.set_item("gpu_timestamps", s.gpu_timestamps)?;
    st.set_item("nodes_visited", s.nodes_visited)?;
    st.set_item("nodes_culled", s.nodes_culled)?;
    if let Some(hz) = out.horizon {
        d.set_item("horizon", Array1::from_vec(hz).into_pyarray(py))?;
    }
    d.set_item("stats", st)?;
    Ok(d)
}

#[pymethods]
impl PyRenderer {
    #[new]
    fn new(py: Python<'_>, width: u32, height: u32, backend: String) -> PyResult<Self> {
        run(py, move || Renderer::new(width, height, &backend).map(|inner| Self { inner }))
    }
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width()
    }
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height()
    }
    #[getter]
    fn adapter_info(&self) -> String {
        self.inner.adapter_info()
    }
    #[getter]
    fn max_texture_size(&self) -> u32 {
        self.inner.max_texture_size()
    }
    #[getter]
    fn gpu_bytes(&self) -> u64 {
        self.inner.gpu_bytes()
    }

    #[pyo3(signature = (scene, camera, culling, pixel_threshold, prepass_scale))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        scene: PyRef<'py, PyScene>,
        camera: PyRef<'py, PyCamera>,
        culling: String,
        pixel_threshold: f64,
        prepass_scale: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let r = &mut self.inner;
        let (s, c) = (&scene.inner, &camera.inner);
        let out = run(py, move || {
            let culling = Culling::parse(&culling)?;
            r.render(s, c, &RenderOptions { culling, pixel_threshold, prepass_scale })
        })?;
        output_dict(py, out)
    }
}

/// Names of the culling strategies `Renderer.render` accepts, from the core's registry.
#[pyfunction]
fn culling_modes() -> Vec<&'static str> {
    Culling::ALL.iter().map(|c| c.name()).collect()
}

#[pymodule]
fn _geocull(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyCamera>()?;
    m.add_class::<PyRenderer>()?;
    m.add_function(wrap_pyfunction!(culling_modes, m)?)?;
    iso::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
