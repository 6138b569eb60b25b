//! PyO3 bindings, a thin module list over the pure core: numpy in and out, the GIL released
//! around every piece of real work, errors mapped once onto geocull's exception hierarchy
//! (`From<Error> for PyErr` in errors.rs, which defines the classes) and no panic ever crossing
//! into Python. All value checking lives in the core; the Python package (python/geocull) only
//! coerces types and shapes before calling in.
//!
//! Threads: every class holding mutable core state (Scene, Renderer) keeps it in a `Mutex` and is
//! a `frozen` pyclass (methods take `&self`); [`with_lock`] takes the lock with the GIL released.
//! Lock order: a renderer before a scene, never the other way.
//!
//! One file per Python class: `scene.rs` (Scene), `camera.rs` (Camera), `renderer.rs` (Renderer
//! and the frame dict), `iso.rs` (Volume, render_isosurface); `errors.rs` the exception classes.

use crate::error::Interrupt;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

mod camera;
mod errors;
mod iso;
mod lazy;
mod renderer;
mod scene;
mod volume;

/// [`run`] with a cancellation hook for `f` (see `crate::error::Interrupt`): Ctrl-C during a long
/// render or build raises KeyboardInterrupt within about `Interrupt::POLL`, not at the end. The
/// hook runs Python's signal handlers (`check_signals`, on the calling thread, taking the GIL for a
/// moment; handlers only run on the main thread); the exception a handler raised is kept and
/// raised here, so a custom SIGINT handler's exception comes through as it is.
///
/// Progress: when a `geocull._progress.Task` is active on this thread (`with task(...)`, see
/// python/geocull/_progress.py), the hook carries it, and parallel builds call it with the count
/// of tiles finished and their total (0 where the job does not say it, and the task's own total
/// stands), on this thread with the GIL taken for a moment (`Interrupt::with_progress`); an
/// exception it raises stops the work and is raised here.
pub(crate) fn run_interruptible<T: Send>(
    py: Python<'_>,
    f: impl FnOnce(Interrupt) -> crate::Result<T> + Send,
) -> PyResult<T> {
    let raised: Arc<Mutex<Option<PyErr>>> = Arc::default();
    let slot = raised.clone();
    let mut hook = Interrupt::new(move || match Python::attach(|py| py.check_signals()) {
        Ok(()) => false,
        Err(e) => {
            *slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
            true
        }
    });
    if let Some(task) = active_progress(py)? {
        let slot = raised.clone();
        hook = hook.with_progress(move |done, total| {
            match Python::attach(|py| task.call1(py, (done, total)).map(|_| ())) {
                Ok(()) => false,
                Err(e) => {
                    *slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                    true
                }
            }
        });
    }
    let out = run(py, move || f(hook));
    let handler_error = raised.lock().unwrap_or_else(|p| p.into_inner()).take();
    match (out, handler_error) {
        (Err(_), Some(handler_error)) => Err(handler_error),
        (out, _) => out,
    }
}

/// The progress task active on this thread (`geocull._progress._active()`), if any.
fn active_progress(py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
    let t = py.import("geocull._progress")?.getattr("_active")?.call0()?;
    Ok(if t.is_none() { None } else { Some(t.unbind()) })
}

/// Runs `f` without the GIL, turning errors and panics into Python exceptions. In a process
/// forked from one that used geocull, `f` runs on that process's own thread pool
/// ([`crate::error::in_pool`]); Ctrl-C there is then honoured only when `f` returns (Python
/// checks signals on the main thread only).
pub(crate) fn run<T: Send>(py: Python<'_>, f: impl FnOnce() -> crate::Result<T> + Send) -> PyResult<T> {
    let out = py.detach(|| crate::error::in_pool(|| catch_unwind(AssertUnwindSafe(f))));
    match out {
        Ok(r) => Ok(r?),
        Err(p) => {
            let what = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(errors::internal_error(&what))
        }
    }
}

/// Runs `f` on the value behind `m` without the GIL: the lock is taken with the GIL released, so a
/// second Python thread using the same object waits here (and lets the first one finish, which may
/// need the GIL to return) instead of failing with PyO3's "Already borrowed". A lock poisoned by a
/// panic (reported as GeocullError) is taken over: every core method leaves its object whole on error.
pub(crate) fn with_lock<T: Send, R: Send>(
    py: Python<'_>,
    m: &Mutex<T>,
    f: impl FnOnce(&mut T) -> crate::Result<R> + Send,
) -> PyResult<R> {
    run(py, move || f(&mut lock(m)))
}

/// Locks `m` (call it without the GIL, i.e. inside [`run`]), recovering a poisoned lock.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A C-contiguous numpy array's data, or an InputError naming `arg`.
pub(crate) fn contiguous<'a, T: numpy::Element, D: numpy::ndarray::Dimension>(
    a: &'a numpy::PyReadonlyArray<'_, T, D>,
    arg: &str,
) -> PyResult<&'a [T]> {
    a.as_slice().map_err(|_| crate::error::input_err(arg, "array must be C-contiguous").into())
}

#[pymodule]
fn _geocull(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::error::record_process();
    errors::register(m)?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<renderer::PyRenderer>()?;
    m.add_function(wrap_pyfunction!(renderer::culling_modes, m)?)?;
    m.add_class::<volume::PyVolume>()?;
    iso::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
