//! PyO3 bindings for isosurfaces: `render_isosurface` (implicit-occluder culling, see
//! `crate::iso::render`), its cache, and `extract_isosurface` (the whole surface as a mesh).

use super::camera::PyCamera;
use super::renderer::PyRenderer;
use super::volume::PyVolume;
use super::{lock, run, run_interruptible};
use crate::error::int_in;
use crate::iso::mesh::isosurface_mesh;
use crate::iso::render::{IsoCulling, IsoOptions, IsoOutput, IsoWalk};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::atomic::Ordering;

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
    st.set_item("occluder_nodes_nan", s.occluder_nodes_nan)?;
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
    st.set_item("bytes_read", s.bytes_read)?;
    st.set_item("brick_cache_bytes", s.brick_cache_bytes)?;
    st.set_item("total_ms", s.total_ms)?;
    st.set_item("readback_ms", s.readback_ms)?;
    st.set_item("setup_ms", s.setup_ms)?;
    st.set_item("submissions", s.submissions)?;
    st.set_item("readbacks", s.readbacks)?;
    st.set_item("cache_bytes", s.cache_bytes)?;
    st.set_item("gpu_cache_bytes", s.gpu_cache_bytes)?;
    st.set_item("contour_bytes", s.contour_bytes)?;
    st.set_item(
        "walk",
        match s.walk_on_host {
            Some(true) => "cpu",
            Some(false) => "gpu",
            None => "none",
        },
    )?;
    st.set_item("walk_rays", s.walk_rays)?;
    st.set_item("walk_steps", s.walk_steps)?;
    // Names shared with scene frames, so generic code (RenderResult.__repr__) works.
    st.set_item("triangles_drawn", s.surface_triangles)?;
    st.set_item("tiles_drawn", s.nodes_visible)?;
    st.set_item("tiles_total", s.nodes_straddling)?;
    d.set_item("stats", st)?;
    Ok(d)
}

#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (renderer, volume, isovalue, camera, culling, occluder_depth, cull_depth, color, cache, return_map, walk))]
fn render_isosurface<'py>(
    py: Python<'py>,
    renderer: PyRef<'py, PyRenderer>,
    volume: PyRef<'py, PyVolume>,
    isovalue: f64,
    camera: PyRef<'py, PyCamera>,
    culling: String,
    occluder_depth: Option<i64>,
    cull_depth: Option<i64>,
    color: (f64, f64, f64),
    cache: bool,
    return_map: bool,
    walk: String,
) -> PyResult<Bound<'py, PyDict>> {
    let tree = volume.tree(py)?;
    let r = &renderer.inner;
    let budget = renderer.iso_cache_budget.load(Ordering::Relaxed);
    let (v, c) = (&volume.inner, &camera.inner);
    let out = run_interruptible(py, move |interrupt| {
        let culling = IsoCulling::parse(&culling)?;
        let walk = IsoWalk::parse(&walk)?;
        let depth = |d: Option<i64>, arg| d.map(|d| int_in(d, arg, 0, 64).map(|d| d as u32)).transpose();
        let (occluder_depth, cull_depth) = (depth(occluder_depth, "occluder_depth")?, depth(cull_depth, "cull_depth")?);
        let opts = IsoOptions {
            culling,
            occluder_depth,
            cull_depth,
            color: [color.0 as f32, color.1 as f32, color.2 as f32],
            use_cache: cache,
            return_map,
            cache_budget: usize::try_from(budget).unwrap_or(usize::MAX),
            space_skipping: true,
            face_contours: None,
            walk,
            interrupt,
        };
        lock(r).render_isosurface(v, &tree, isovalue, c, &opts)
    })?;
    iso_dict(py, out)
}

#[pyfunction]
fn clear_isosurface_cache(py: Python<'_>, renderer: PyRef<'_, PyRenderer>) -> PyResult<()> {
    super::with_lock(py, &renderer.inner, |r| {
        r.clear_isosurface_cache();
        Ok(())
    })
}

/// Sets the memory budget (bytes) of the renderer's isosurface caches; it applies from the next
/// isosurface frame, which drops least recently used patches beyond it.
#[pyfunction]
fn set_isosurface_cache_budget(renderer: PyRef<'_, PyRenderer>, bytes: i64) -> PyResult<()> {
    let b = int_in(bytes, "bytes", 0, i64::MAX)?;
    renderer.iso_cache_budget.store(b as u64, Ordering::Relaxed);
    Ok(())
}

/// The memory budget (bytes) of the renderer's isosurface caches.
#[pyfunction]
fn isosurface_cache_budget(renderer: PyRef<'_, PyRenderer>) -> u64 {
    renderer.iso_cache_budget.load(Ordering::Relaxed)
}

/// The whole isosurface `volume == isovalue` as one welded mesh: (vertices (n, 3) float64 world,
/// faces (m, 3) int64), the triangles `render_isosurface(culling="none")` draws.
#[pyfunction]
fn extract_isosurface<'py>(
    py: Python<'py>,
    volume: PyRef<'py, PyVolume>,
    isovalue: f64,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let tree = volume.tree(py)?;
    let v = &volume.inner;
    let (verts, faces) = run(py, move || {
        let m = isosurface_mesh(v, &tree, isovalue)?;
        let (nv, nf) = (m.vertices.len(), m.faces.len());
        let verts = Array2::from_shape_vec((nv, 3), m.vertices.into_iter().flatten().collect()).unwrap();
        let faces = Array2::from_shape_vec((nf, 3), m.faces.into_iter().flatten().map(|k| k as i64).collect()).unwrap();
        Ok((verts, faces))
    })?;
    Ok((verts.into_pyarray(py).into_any(), faces.into_pyarray(py).into_any()))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(extract_isosurface, m)?)?;
    m.add_function(wrap_pyfunction!(render_isosurface, m)?)?;
    m.add_function(wrap_pyfunction!(clear_isosurface_cache, m)?)?;
    m.add_function(wrap_pyfunction!(set_isosurface_cache_budget, m)?)?;
    m.add_function(wrap_pyfunction!(isosurface_cache_budget, m)?)?;
    Ok(())
}
