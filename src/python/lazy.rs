//! The sample store of a lazy `Volume` (`crate::iso::store`) over a Python reader: an object with
//! `read(lo, hi)` returning the float32 residuals of the box `lo..hi` (x, y, z; exclusive) as a
//! (z, y, x) array (python/geocull/_lazy.py slices a zarr / dask / xarray array, a memory map or a
//! SEG-Y file). The GIL is taken only around each read; a Python exception becomes the store's
//! read error (an InputError naming `values`, with the exception's text).

use crate::error::input_err;
use crate::iso::store::BrickSource;
use numpy::PyReadonlyArray3;
use pyo3::prelude::*;

pub(crate) struct PySource {
    pub(crate) reader: Py<PyAny>,
}

impl BrickSource for PySource {
    fn read(&self, lo: [usize; 3], hi: [usize; 3], out: &mut [f32]) -> crate::Result<()> {
        let want = (hi[2] - lo[2], hi[1] - lo[1], hi[0] - lo[0]);
        Python::attach(|py| -> PyResult<Result<(), String>> {
            let a = self.reader.bind(py).call_method1("read", ((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])))?;
            let a: PyReadonlyArray3<'_, f32> = a.extract()?;
            let v = a.as_array();
            if v.dim() != want {
                return Ok(Err(format!("the reader gave a block of shape {:?}; expected {want:?}", v.dim())));
            }
            match v.as_slice() {
                Some(s) => out.copy_from_slice(s),
                None => out.iter_mut().zip(v.iter()).for_each(|(o, x)| *o = *x),
            }
            Ok(Ok(()))
        })
        .map_err(|e| e.to_string())
        .and_then(|r| r)
        .map_err(|msg| input_err("values", msg))
    }
}
