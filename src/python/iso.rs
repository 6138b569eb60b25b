//! PyO3 bindings for isosurfaces: `Volume` (a scalar grid plus its lazily built min/max octree)
//! and `render_isosurface` (implicit-occluder culling, see `crate::iso::render`).

use super::camera::PyCamera;
use super::renderer::PyRenderer;
use super::{contiguous, run, run_interruptible};
use crate::error::{input_err, int_in};
use crate::iso::render::{IsoCulling, IsoOptions, IsoOutput};
use crate::iso::{MinMaxOctree, Volume};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::{Arc, OnceLock};

#[pyclass(name = "Volume", module = "geocull._geocull")]
pub struct PyVolume {
    pub(crate) inner: Volume,
    tree: OnceLock<Arc<MinMaxOctree>>,
}

impl PyVolume {
    fn tree(&self, py: Python<'_>) -> PyResult<Arc<MinMaxOctree>> {
        if let Some(t) = self.tree.get() {
            return Ok(t.clone());
        }
        let v = &self.inner;
        let t = run(py, move || Ok(Arc::new(MinMaxOctree::build(v))))?;
        Ok(self.tree.get_or_init(|| t).clone())
    }
}

#[pymethods]
impl PyVolume {
    /// values: (nz, ny, nx) C-contiguous float32 or float64 array (copied once into the core's
    /// float32 buffer, with the GIL released).
    #[new]
    fn new(
        py: Python<'_>,
        values: &Bound<'_, PyAny>,
        origin: (f64, f64, f64),
        spacing: (f64, f64, f64),
    ) -> PyResult<Self> {
        let (data, shape): (Arc<[f32]>, [usize; 3]) = if let Ok(a) = values.extract::<PyReadonlyArray3<'_, f32>>() {
            let s = a.shape();
            let shape = [s[0], s[1], s[2]];
            let sl = contiguous(&a, "values")?;
            (run(py, move || Ok(Arc::<[f32]>::from(sl)))?, shape)
        } else if let Ok(a) = values.extract::<PyReadonlyArray3<'_, f64>>() {
            let s = a.shape();
            let shape = [s[0], s[1], s[2]];
            let sl = contiguous(&a, "values")?;
            (run(py, move || Ok(sl.iter().map(|&v| v as f32).collect::<Arc<[f32]>>()))?, shape)
        } else {
            return Err(input_err("values", "expected a 3-D float32 or float64 array").into());
        };
        let inner = run(py, move || {
            Volume::new(
                data,
                (shape[2], shape[1], shape[0]),
                [origin.0, origin.1, origin.2],
                [spacing.0, spacing.1, spacing.2],
            )
        })?;
        Ok(Self { inner, tree: OnceLock::new() })
    }

    /// (nz, ny, nx)
    #[getter]
    fn shape(&self) -> (usize, usize, usize) {
        (self.inner.nz, self.inner.ny, self.inner.nx)
    }
    #[getter]
    fn origin(&self) -> (f64, f64, f64) {
        let o = self.inner.origin;
        (o[0], o[1], o[2])
    }
    #[getter]
    fn spacing(&self) -> (f64, f64, f64) {
        let s = self.inner.spacing;
        (s[0], s[1], s[2])
    }
    /// Depth of the single-cell leaves of the octree (root = 0); builds the octree if needed.
    fn max_depth(&self, py: Python<'_>) -> PyResult<u32> {
        Ok(self.tree(py)?.max_depth())
    }

    /// Octree nodes at `depth`: dict of index (n,3) [ix,iy,iz], bbox_min/bbox_max (n,3) world,
    /// min/max (n,) float32.
    fn nodes<'py>(&self, py: Python<'py>, depth: i64) -> PyResult<Bound<'py, PyDict>> {
        let t = self.tree(py)?;
        let depth = int_in(depth, "depth", 0, t.max_depth() as i64)? as u32;
        let nodes = t.nodes_at_depth(depth);
        let n = nodes.len();
        let d = PyDict::new(py);
        let idx: Vec<u32> = nodes.iter().flat_map(|n| [n.ix, n.iy, n.iz]).collect();
        let lo: Vec<f64> = nodes.iter().flat_map(|n| n.bbox_min).collect();
        let hi: Vec<f64> = nodes.iter().flat_map(|n| n.bbox_max).collect();
        d.set_item("index", Array2::from_shape_vec((n, 3), idx).unwrap().into_pyarray(py))?;
        d.set_item("bbox_min", Array2::from_shape_vec((n, 3), lo).unwrap().into_pyarray(py))?;
        d.set_item("bbox_max", Array2::from_shape_vec((n, 3), hi).unwrap().into_pyarray(py))?;
        d.set_item("min", Array1::from_vec(nodes.iter().map(|n| n.min).collect::<Vec<f32>>()).into_pyarray(py))?;
        d.set_item("max", Array1::from_vec(nodes.iter().map(|n| n.max).collect::<Vec<f32>>()).into_pyarray(py))?;
        Ok(d)
    }
}

fn iso_dict<'py>(py: Python<'py>, out: IsoOutput) -> PyResult<Bound<'py, PyDict>> {
    let (w, h) = (out.width as usize, out.height as usize);
    let d = PyDict::new(py);
    d.set_item("image", Array3::from_shape_vec((h, w, 4), out.image).unwrap().into_pyarray(py))?;
    d.set_item("depth", Array2::from_shape_vec((h, w), out.depth).unwrap().into_pyarray(py))?;
    let n = out.nodes.len();
    d.set_item(
        "nodes",
        Array2::from_shape_vec((n, 4), out.nodes.into_iter().flatten().collect()).unwrap().into_pyarray(py),
    )?;
    d.set_item("tile_pixels", Array1::from_vec(out.node_pixels).into_pyarray(py))?;
    d.set_item("tile_drawn", Array1::from_vec(out.node_drawn).into_pyarray(py))?;
    if let Some(m) = out.map {
        d.set_item("occlusion_map", Array2::from_shape_vec((h, w), m).unwrap().into_pyarray(py))?;
    }
    d.set_item("near", out.near)?;
    d.set_item("far", out.far)?;
    let s = &out.stats;
    let st = PyDict::new(py);
    st.set_item("surface_triangles", s.surface_triangles)?;
    st.set_item("surface_vertices", s.surface_vertices)?;
    st.set_item("nodes_tested", s.nodes_tested)?;
    st.set_item("nodes_tested_cull_depth", s.nodes_tested_cull_depth)?;
    st.set_item("nodes_visible", s.nodes_visible)?;
    st.set_item("nodes_straddling", s.nodes_straddling)?;
    st.set_item("occluder_boxes_below", s.occluder_boxes_below)?;
    st.set_item("occluder_boxes_above", s.occluder_boxes_above)?;
    st.set_item("occluder_depth", s.occluder_depth)?;
    st.set_item("cull_depth", s.cull_depth)?;
    st.set_item("max_depth", s.max_depth)?;
    st.set_item("patches_cached", s.patches_cached)?;
    st.set_item("patches_extracted", s.patches_extracted)?;
    st.set_item("occluder_ms", s.occluder_ms)?;
    st.set_item("cull_ms", s.cull_ms)?;
    st.set_item("extract_ms", s.extract_ms)?;
    st.set_item("draw_ms", s.draw_ms)?;
    st.set_item("surface_ms", s.surface_ms)?;
    st.set_item("total_ms", s.total_ms)?;
    st.set_item("readback_ms", s.readback_ms)?;
    // Names shared with scene frames, so generic code (RenderResult.__repr__) works.
    st.set_item("triangles_drawn", s.surface_triangles)?;
    st.set_item("tiles_drawn", s.nodes_visible)?;
    st.set_item("tiles_total", s.nodes_straddling)?;
    d.set_item("stats", st)?;
    Ok(d)
}

#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (renderer, volume, isovalue, camera, culling, occluder_depth, cull_depth, color, cache, return_map))]
fn render_isosurface<'py>(
    py: Python<'py>,
    mut renderer: PyRefMut<'py, PyRenderer>,
    volume: PyRef<'py, PyVolume>,
    isovalue: f64,
    camera: PyRef<'py, PyCamera>,
    culling: String,
    occluder_depth: Option<i64>,
    cull_depth: Option<i64>,
    color: (f64, f64, f64),
    cache: bool,
    return_map: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let tree = volume.tree(py)?;
    let r = &mut renderer.inner;
    let (v, c) = (&volume.inner, &camera.inner);
    let out = run_interruptible(py, move |interrupt| {
        crate::error::ensure(isovalue.is_finite() && isovalue.abs() <= f32::MAX as f64, "isovalue", || {
            format!("isovalue is {isovalue}; expected a finite number within the float32 range")
        })?;
        let culling = IsoCulling::parse(&culling)?;
        let depth = |d: Option<i64>, arg| d.map(|d| int_in(d, arg, 0, 64).map(|d| d as u32)).transpose();
        let (occluder_depth, cull_depth) = (depth(occluder_depth, "occluder_depth")?, depth(cull_depth, "cull_depth")?);
        let opts = IsoOptions {
            culling,
            occluder_depth,
            cull_depth,
            color: [color.0 as f32, color.1 as f32, color.2 as f32],
            use_cache: cache,
            return_map,
            interrupt,
        };
        r.render_isosurface(v, &tree, isovalue as f32, c, &opts)
    })?;
    iso_dict(py, out)
}

#[pyfunction]
fn clear_isosurface_cache(mut renderer: PyRefMut<'_, PyRenderer>) {
    renderer.inner.clear_isosurface_cache();
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyVolume>()?;
    m.add_function(wrap_pyfunction!(render_isosurface, m)?)?;
    m.add_function(wrap_pyfunction!(clear_isosurface_cache, m)?)?;
    Ok(())
}
