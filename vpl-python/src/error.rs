//! The exception every toolkit error becomes.

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::PyException;

create_exception!(
    vpl,
    VplError,
    PyException,
    "An error of the toolkit (a scene that does not load, a parameter a sampler does not read, \
     a bad size); its message is the toolkit's one line."
);

/// The toolkit's error `e` as a [`VplError`] carrying its one-line message.
pub fn vpl_err(e: impl std::fmt::Display) -> PyErr {
    VplError::new_err(e.to_string())
}
