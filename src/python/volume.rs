//! PyO3 binding of `Volume`: a scalar grid (in memory or read lazily through a brick cache) plus
//! its min/max octree, built on first use. Scenes (slices, lenses, isosurfaces) and
//! `render_isosurface` take it.

use super::run;
use crate::error::{input_err, int_in};
use crate::iso::layout::{self, AxisOrder, ZPositive};
use crate::iso::{BrickCache, MinMaxOctree, Volume};
use numpy::ndarray::{Array1, Array2, ArrayView3, Axis};
use numpy::{IntoPyArray, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::sync::{Arc, OnceLock};

#[pyclass(name = "Volume", module = "geocull._geocull", frozen)]
pub struct PyVolume {
    pub(crate) inner: Volume,
    tree: OnceLock<Arc<MinMaxOctree>>,
}

impl PyVolume {
    pub(crate) fn tree(&self, py: Python<'_>) -> PyResult<Arc<MinMaxOctree>> {
        if let Some(t) = self.tree.get() {
            return Ok(t.clone());
        }
        let v = &self.inner;
        let t = run(py, move || MinMaxOctree::try_build(v).map(Arc::new))?;
        Ok(self.tree.get_or_init(|| t).clone())
    }
}

#[pymethods]
impl PyVolume {
    /// values: a 3-D float32 or float64 array of any strides, indexed as `order` says ("zyx":
    /// [k, j, i]; "xyz": [i, j, k]), its z axis growing upwards or downwards (`z_positive`, see
    /// `crate::iso::layout`). The transpose and the flip are views; the samples are copied once,
    /// with the GIL released, into the core's float32 buffer (float64 as residuals about `offset`).
    #[new]
    #[pyo3(signature = (values, origin, spacing, order, z_positive, rotation))]
    fn new(
        py: Python<'_>,
        values: &Bound<'_, PyAny>,
        origin: (f64, f64, f64),
        spacing: (f64, f64, f64),
        order: &str,
        z_positive: &str,
        rotation: f64,
    ) -> PyResult<Self> {
        let (o, sp) = ([origin.0, origin.1, origin.2], [spacing.0, spacing.1, spacing.2]);
        let order = AxisOrder::parse(order)?;
        let z = ZPositive::parse(z_positive)?;
        layout::check_grid(o, sp, z)?;
        let inner = if let Ok(a) = values.extract::<PyReadonlyArray3<'_, f32>>() {
            let view = stored_view(a.as_array(), order, z);
            let (nz, ny, nx) = view.dim();
            let so = layout::stored_origin(o, sp, nz, z);
            match view.as_slice() {
                Some(sl) => run(py, move || Volume::new(Arc::<[f32]>::from(sl), (nx, ny, nz), so, sp))?,
                None => {
                    run(py, move || Volume::from_f32_slices((nx, ny, nz), so, sp, |k, out| copy_slice(&view, k, out)))?
                }
            }
        } else if let Ok(a) = values.extract::<PyReadonlyArray3<'_, f64>>() {
            // f64 samples: f32 residuals about the midrange (see `Volume::from_f64`).
            let view = stored_view(a.as_array(), order, z);
            let (nz, ny, nx) = view.dim();
            let so = layout::stored_origin(o, sp, nz, z);
            match view.as_slice() {
                Some(sl) => run(py, move || Volume::from_f64(sl, (nx, ny, nz), so, sp))?,
                None => {
                    run(py, move || Volume::from_f64_slices((nx, ny, nz), so, sp, |k, out| copy_slice(&view, k, out)))?
                }
            }
        } else {
            return Err(input_err("values", "expected a 3-D float32 or float64 array").into());
        };
        let inner = inner.with_rotation(rotation)?;
        Ok(Self { inner, tree: OnceLock::new() })
    }

    /// A lazy volume (`Volume::lazy`) over `reader` (see `super::lazy`), whose `read` gives boxes
    /// of the stored grid (x fastest, z up): `shape` (nx, ny, nz), the user's origin and spacing
    /// for `z_positive` (as `new`), the f64 `offset` the reader's residuals are relative to, and a
    /// brick cache of at most `cache_bytes` bytes.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (reader, shape, origin, spacing, z_positive, offset, rotation, cache_bytes))]
    fn lazy(
        reader: Py<PyAny>,
        shape: (usize, usize, usize),
        origin: (f64, f64, f64),
        spacing: (f64, f64, f64),
        z_positive: &str,
        offset: f64,
        rotation: f64,
        cache_bytes: i64,
    ) -> PyResult<Self> {
        let budget = int_in(cache_bytes, "cache_bytes", 0, i64::MAX)?;
        let (o, sp) = ([origin.0, origin.1, origin.2], [spacing.0, spacing.1, spacing.2]);
        let z = ZPositive::parse(z_positive)?;
        layout::check_grid(o, sp, z)?;
        let so = layout::stored_origin(o, sp, shape.2, z);
        let dims = [shape.0, shape.1, shape.2];
        let store = BrickCache::new(Box::new(super::lazy::PySource { reader }), dims, budget);
        let inner = Volume::lazy(Arc::new(store), offset, shape, so, sp)?.with_rotation(rotation)?;
        Ok(Self { inner, tree: OnceLock::new() })
    }

    /// True when the samples are read on demand (`lazy`).
    #[getter]
    fn is_lazy(&self) -> bool {
        self.inner.is_lazy()
    }
    /// Bytes read from a lazy volume's source so far (0 in memory).
    #[getter]
    fn bytes_read(&self) -> u64 {
        self.inner.bytes_read()
    }
    /// A lazy volume's brick cache: (budget, bytes held now, most bytes ever held); None in memory.
    #[getter]
    fn cache_info(&self) -> Option<(usize, usize, u64)> {
        self.inner.store().map(|s| (s.budget(), s.held_bytes(), s.peak_bytes()))
    }

    /// Drops a lazy volume's cached bricks (the next reads go to its source); nothing in memory.
    fn clear_cache(&self) {
        if let Some(s) = self.inner.store() {
            s.clear();
        }
    }

    /// The volume as bytes (`Volume::to_bytes`: shape, origin, spacing, offset, rotation, residuals).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let v = &self.inner;
        let b = run(py, move || {
            let b = v.to_bytes();
            v.take_error().map(|()| b)
        })?;
        Ok(PyBytes::new(py, &b))
    }

    /// A volume from `to_bytes`' bytes.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        run(py, move || Volume::from_bytes(data).map(|inner| Self { inner, tree: OnceLock::new() }))
    }

    /// Degrees counter-clockwise about the vertical through `origin`.
    #[getter]
    fn rotation(&self) -> f64 {
        self.inner.rotation
    }
    /// World ((xmin, ymin, zmin), (xmax, ymax, zmax)) of the samples, rotation applied.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn bounds(&self) -> ((f64, f64, f64), (f64, f64, f64)) {
        let (a, b) = self.inner.world_bounds();
        ((a[0], a[1], a[2]), (b[0], b[1], b[2]))
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
    /// The f64 value the stored float32 residuals are relative to.
    #[getter]
    fn offset(&self) -> f64 {
        self.inner.offset
    }
    /// Depth of the single-cell leaves of the octree (root = 0); builds the octree if needed.
    fn max_depth(&self, py: Python<'_>) -> PyResult<u32> {
        Ok(self.tree(py)?.max_depth())
    }

    /// Octree nodes at `depth`: dict of index (n,3) [ix,iy,iz], bbox_min/bbox_max (n,3) world,
    /// min/max (n,) float64 in the volume's units.
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
        // In the volume's units (residual + offset); +inf / -inf for nodes without data.
        let v = &self.inner;
        d.set_item(
            "min",
            Array1::from_vec(nodes.iter().map(|n| v.value(n.min)).collect::<Vec<f64>>()).into_pyarray(py),
        )?;
        d.set_item(
            "max",
            Array1::from_vec(nodes.iter().map(|n| v.value(n.max)).collect::<Vec<f64>>()).into_pyarray(py),
        )?;
        Ok(d)
    }
}

/// `a` (the user's array) as the stored (z, y, x) view, z upwards: transposed for "xyz", the z
/// axis reversed for z_positive = "down". No sample is copied.
fn stored_view<T>(a: ArrayView3<'_, T>, order: AxisOrder, z: ZPositive) -> ArrayView3<'_, T> {
    let mut v = match order {
        AxisOrder::Zyx => a,
        AxisOrder::Xyz => a.reversed_axes(),
    };
    if z == ZPositive::Down {
        v.invert_axis(Axis(0));
    }
    v
}

/// Copies z slice `k` of a stored view into `out` (x fastest).
fn copy_slice<T: Copy>(view: &ArrayView3<'_, T>, k: usize, out: &mut [T]) {
    for (d, s) in out.iter_mut().zip(view.index_axis(Axis(0), k).iter()) {
        *d = *s;
    }
}
