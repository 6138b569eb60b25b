//! geocull's exception hierarchy, defined here in the extension module (`geocull._geocull`) and
//! re-exported by the Python package (`geocull.InputError`, ... through python/geocull/_errors.py),
//! and the one mapping of the core's [`Error`] onto it (`From<Error> for PyErr`):
//!
//! ```text
//! GeocullError(Exception)                 every error geocull raises (a panic: "internal error")
//! ├── InputError(GeocullError, ValueError)     Error::Input
//! └── DeviceError(GeocullError, RuntimeError)  Error::Device
//! GeocullWarning(UserWarning)             raised with warnings.warn by the Python package
//! ```
//! (`Error::Interrupted` is Python's own KeyboardInterrupt.)
//!
//! `create_exception!` makes a class with one base; InputError and DeviceError have two (so that
//! `except ValueError` / `except RuntimeError` catch them too), and [`exception_with_bases!`] makes
//! them the way `create_exception!` does (`PyErr_NewExceptionWithDoc` calls `type(name, bases,
//! {"__module__": ..., "__doc__": ...})`). Every class is a plain heap type of module
//! `geocull._geocull`, so instances pickle (by that module path) like exceptions defined in Python.
//! The docstrings are those the classes had when defined in Python (3.11 keeps the indentation).
//!
//! GeocullWarning is defined here too although only Python code issues it: the whole hierarchy then
//! has one home, and a warning category is an ordinary exception class to `warnings.warn`, to
//! warning filters (`-W error::geocull.GeocullWarning`) and to pytest's `filterwarnings`.

use crate::error::Error;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyRuntimeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The module the classes report (`__module__`), where pickle finds them.
const MODULE: &str = "geocull._geocull";

create_exception!(geocull._geocull, GeocullError, PyException, "Base class of every error geocull raises.");

create_exception!(
    geocull._geocull,
    GeocullWarning,
    PyUserWarning,
    "Something valid but almost certainly not what was meant, e.g. a frame that cannot show
    anything because the whole scene lies nearer than the near plane."
);

/// `create_exception!` for a class with several bases: a unit struct whose `type_object(py)` is
/// the class (made on first use, once per process) and `new_err(py, msg)` an instance to raise.
macro_rules! exception_with_bases {
    ($name:ident($($base:ty),+), $doc:expr) => {
        #[doc = $doc]
        pub(crate) struct $name;

        impl $name {
            pub(crate) fn type_object(py: Python<'_>) -> &Bound<'_, PyType> {
                static TYPE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
                TYPE.get_or_init(py, || {
                    let bases = [$(py.get_type::<$base>()),+];
                    new_class(py, stringify!($name), &bases, $doc)
                        .expect(concat!("the class ", stringify!($name)))
                })
                .bind(py)
            }

            pub(crate) fn new_err(py: Python<'_>, msg: String) -> PyErr {
                PyErr::from_type(Self::type_object(py).clone(), msg)
            }
        }
    };
}

exception_with_bases!(
    InputError(GeocullError, PyValueError),
    "A bad argument: wrong shape, dtype, value or range. The message starts with the argument's
    name and points at the first offending element."
);

exception_with_bases!(
    DeviceError(GeocullError, PyRuntimeError),
    "No usable graphics adapter, or the driver rejected the work. On a machine without a GPU,
    install Mesa's lavapipe: ``apt-get install libvulkan1 mesa-vulkan-drivers``."
);

/// `type(name, bases, {"__module__": MODULE, "__doc__": doc})`, as `PyErr_NewExceptionWithDoc`
/// makes it.
fn new_class<'py>(py: Python<'py>, name: &str, bases: &[Bound<'py, PyType>], doc: &str) -> PyResult<Py<PyType>> {
    let ns = PyDict::new(py);
    ns.set_item("__module__", MODULE)?;
    ns.set_item("__doc__", doc)?;
    let class = py.get_type::<PyType>().call1((name, PyTuple::new(py, bases)?, ns))?;
    Ok(class.cast_into::<PyType>()?.unbind())
}

/// The one mapping of the core's errors onto Python exceptions.
impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e {
            Error::Input { .. } => Python::attach(|py| InputError::new_err(py, e.to_string())),
            Error::Device(msg) => Python::attach(|py| DeviceError::new_err(py, msg)),
            Error::Interrupted => PyKeyboardInterrupt::new_err("interrupted"),
        }
    }
}

/// The error for a panic caught at the boundary, whose payload says `what`.
pub(crate) fn internal_error(what: &str) -> PyErr {
    GeocullError::new_err(format!("internal error in geocull (please report): {what}"))
}

/// Adds the classes to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GeocullError", py.get_type::<GeocullError>())?;
    m.add("InputError", InputError::type_object(py))?;
    m.add("DeviceError", DeviceError::type_object(py))?;
    m.add("GeocullWarning", py.get_type::<GeocullWarning>())?;
    Ok(())
}
