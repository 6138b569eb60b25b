//! `geocull._geocull.Renderer`: frames as dicts of numpy arrays and stats.

use super::camera::PyCamera;
use super::scene::PyScene;
use super::{lock, run, run_interruptible, with_lock};
use crate::cull::{self, CullOptions, Stat};
use crate::error::int_in;
use crate::render::{GridLod, Lod, RenderOptions, RenderOutput, Renderer};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::atomic::AtomicU64;
use std::sync::Mutex;

#[pyclass(name = "Renderer", module = "geocull._geocull", frozen)]
pub struct PyRenderer {
    /// Locked by every method (see `super::with_lock`), before any scene it draws.
    pub(crate) inner: Mutex<Renderer>,
    /// Memory budget of the isosurface caches, bytes (`IsoOptions::cache_budget` of every frame).
    pub(crate) iso_cache_budget: AtomicU64,
}

/// Names of the culling strategies `Renderer.render` accepts, from the core's registry.
#[pyfunction]
pub fn culling_modes() -> Vec<&'static str> {
    cull::names()
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
    st.set_item("tiles_total", s.tiles_total)?;
    st.set_item("tiles_drawn", s.tiles_drawn)?;
    st.set_item("cull_ms", s.cull_ms)?;
    st.set_item("draw_ms", s.draw_ms)?;
    st.set_item("total_ms", s.total_ms)?;
    st.set_item("readback_ms", s.readback_ms)?;
    st.set_item("gpu_timestamps", s.gpu_timestamps)?;
    for (name, v) in &s.extra {
        match v {
            Stat::Count(n) => st.set_item(*name, *n)?,
            Stat::Ms(ms) => st.set_item(*name, *ms)?,
            Stat::Float(v) => st.set_item(*name, *v)?,
        }
    }
    for (name, a) in out.arrays {
        d.set_item(name, Array1::from_vec(a).into_pyarray(py))?;
    }
    for (name, c) in out.tile_counts {
        d.set_item(name, Array1::from_vec(c).into_pyarray(py))?;
    }
    d.set_item("stats", st)?;
    Ok(d)
}

#[pymethods]
impl PyRenderer {
    #[new]
    fn new(py: Python<'_>, width: i64, height: i64, backend: String) -> PyResult<Self> {
        run(py, move || {
            let max = u32::MAX as i64;
            let (w, h) = (int_in(width, "width", 1, max)? as u32, int_in(height, "height", 1, max)? as u32);
            Renderer::new(w, h, &backend).map(|r| Self {
                inner: Mutex::new(r),
                iso_cache_budget: AtomicU64::new(crate::iso::march::DEFAULT_CACHE_BUDGET as u64),
            })
        })
    }
    #[getter]
    fn width(&self, py: Python<'_>) -> PyResult<u32> {
        with_lock(py, &self.inner, |r| Ok(r.width()))
    }
    #[getter]
    fn height(&self, py: Python<'_>) -> PyResult<u32> {
        with_lock(py, &self.inner, |r| Ok(r.height()))
    }
    #[getter]
    fn adapter_info(&self, py: Python<'_>) -> PyResult<String> {
        with_lock(py, &self.inner, |r| Ok(r.adapter_info()))
    }
    #[getter]
    fn max_texture_size(&self, py: Python<'_>) -> PyResult<u32> {
        with_lock(py, &self.inner, |r| Ok(r.max_texture_size()))
    }
    #[getter]
    fn gpu_bytes(&self, py: Python<'_>) -> PyResult<u64> {
        with_lock(py, &self.inner, |r| Ok(r.gpu_bytes()))
    }
    #[getter]
    fn cache_budget(&self, py: Python<'_>) -> PyResult<u64> {
        with_lock(py, &self.inner, |r| Ok(r.cache_budget()))
    }
    #[setter]
    fn set_cache_budget(&self, py: Python<'_>, bytes: i64) -> PyResult<()> {
        with_lock(py, &self.inner, |r| {
            r.set_cache_budget(int_in(bytes, "cache_budget", 0, i64::MAX)? as u64);
            Ok(())
        })
    }
    /// The background put into every image where nothing was drawn: `rgb` 3 bytes (RGB8) per
    /// image row, top row first; None: black.
    #[pyo3(signature = (rgb))]
    fn set_background(&self, py: Python<'_>, rgb: Option<Vec<u8>>) -> PyResult<()> {
        with_lock(py, &self.inner, |r| r.set_background(rgb.as_deref()))
    }
    #[getter]
    fn pass_triangles(&self, py: Python<'_>) -> PyResult<Option<u64>> {
        with_lock(py, &self.inner, |r| Ok(r.pass_triangles()))
    }
    #[setter]
    fn set_pass_triangles(&self, py: Python<'_>, max: Option<i64>) -> PyResult<()> {
        with_lock(py, &self.inner, |r| {
            let max = max.map(|m| int_in(m, "pass_triangles", 1, i64::MAX)).transpose()?;
            r.set_pass_triangles(max.map(|m| m as u64))?;
            Ok(())
        })
    }

    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (scene, camera, culling, pixel_threshold, prepass_scale, conservative, predict_errors, lod, max_pixel_error, grid_lod, alpha, lam))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: PyRef<'py, PyScene>,
        camera: PyRef<'py, PyCamera>,
        culling: String,
        pixel_threshold: f64,
        prepass_scale: Option<f64>,
        conservative: bool,
        predict_errors: bool,
        lod: String,
        max_pixel_error: f64,
        grid_lod: String,
        alpha: f64,
        lam: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (r, s, c) = (&self.inner, &scene.inner, &camera.inner);
        let prepass_scale = prepass_scale.unwrap_or_else(|| CullOptions::default_prepass_scale(conservative));
        let cull = CullOptions { pixel_threshold, prepass_scale, conservative, predict_errors };
        // Renderer first, then the scene (the lock order of every binding).
        let out = run_interruptible(py, move |interrupt| {
            let grid_lod = GridLod::parse(&grid_lod, alpha, lam, max_pixel_error)?;
            let opts = RenderOptions { culling, cull, lod: Lod::parse(&lod, max_pixel_error)?, grid_lod, interrupt };
            lock(r).render(&lock(s), c, &opts)
        })?;
        output_dict(py, out)
    }
}
