//! PyO3 bindings for isosurfaces (placeholder; filled in by the isosurface work).
use pyo3::prelude::*;
pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
