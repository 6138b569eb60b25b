//! `geocull._geocull.Camera`: a look-at camera (validated in the core).

use super::run;
use crate::camera::{Camera, Lens, Orbit, Projection};
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;

#[pyclass(name = "Camera", module = "geocull._geocull", from_py_object, frozen)]
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
    /// `Camera::orbit`: the eye at `distance` from `target`, compass `azimuth`, `elevation` (degrees).
    #[allow(clippy::too_many_arguments)]
    #[staticmethod]
    #[pyo3(signature = (target, azimuth, elevation, distance, up, fov_y, near, far, projection, ortho_height, z_scale))]
    fn orbit(
        py: Python<'_>,
        target: (f64, f64, f64),
        azimuth: f64,
        elevation: f64,
        distance: f64,
        up: (f64, f64, f64),
        fov_y: f64,
        near: Option<f64>,
        far: Option<f64>,
        projection: String,
        ortho_height: Option<f64>,
        z_scale: f64,
    ) -> PyResult<Self> {
        run(py, move || {
            let projection = Projection::parse(&projection)?;
            let lens = Lens { up: up.into(), fov_y, near, far, projection, ortho_height, z_scale };
            Camera::orbit(target.into(), Orbit { azimuth, elevation, distance }, lens).map(|inner| Self { inner })
        })
    }

    /// `Camera::fit`: the closest view of the box `lo..hi` from `azimuth`, `elevation`.
    #[allow(clippy::too_many_arguments)]
    #[staticmethod]
    #[pyo3(signature = (lo, hi, azimuth, elevation, margin, aspect, up, fov_y, projection, z_scale))]
    fn fit(
        py: Python<'_>,
        lo: (f64, f64, f64),
        hi: (f64, f64, f64),
        azimuth: f64,
        elevation: f64,
        margin: f64,
        aspect: f64,
        up: (f64, f64, f64),
        fov_y: f64,
        projection: String,
        z_scale: f64,
    ) -> PyResult<Self> {
        run(py, move || {
            let projection = Projection::parse(&projection)?;
            let lens = Lens { up: up.into(), fov_y, projection, z_scale, ..Lens::default() };
            Camera::fit(lo.into(), hi.into(), azimuth, elevation, margin, aspect, lens).map(|inner| Self { inner })
        })
    }

    /// (azimuth, elevation, distance) of the eye about the target.
    fn orbit_angles(&self) -> (f64, f64, f64) {
        let o = self.inner.orbit_angles();
        (o.azimuth, o.elevation, o.distance)
    }

    fn rotated(&self, py: Python<'_>, d_azimuth: f64, d_elevation: f64) -> PyResult<Self> {
        let c = self.inner.clone();
        run(py, move || c.rotated(d_azimuth, d_elevation).map(|inner| Self { inner }))
    }

    fn zoomed(&self, py: Python<'_>, factor: f64) -> PyResult<Self> {
        let c = self.inner.clone();
        run(py, move || c.zoomed(factor).map(|inner| Self { inner }))
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
