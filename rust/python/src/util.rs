//! Small helpers the Python scripts share with the CLI, so that each exists once (in the
//! core): atomic file writes, the machine description of reports, scenario-name lists.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyString};

use crate::convert::repr;
use crate::errors::{invalid_argument, run, run_attached};

/// Write ``data`` (``bytes`` or ``str``, written as UTF-8) to ``path`` atomically: the
/// core's ``io::write_atomic`` (temporary file beside it, synced, renamed over it), so a
/// reader never sees a half-written file. The GIL is released while writing.
#[pyfunction]
pub fn write_atomic(
    py: Python<'_>,
    path: std::path::PathBuf,
    data: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let bytes: Vec<u8> = if let Ok(b) = data.cast::<PyBytes>() {
        b.as_bytes().to_vec()
    } else if let Ok(s) = data.cast::<PyString>() {
        s.to_cow()?.as_bytes().to_vec()
    } else {
        return Err(invalid_argument(
            py,
            "data",
            repr(data),
            "must be bytes or str",
        ));
    };
    run(py, || sixaxis_core::io::write_atomic(&path, &bytes))
}

/// One line describing this machine (CPU model, cores, OS, architecture), as in the
/// reports of ``sixaxis reproduce``.
#[pyfunction]
pub fn machine() -> String {
    sixaxis_core::host::machine()
}

/// A comma-separated list of scenario names with ``generated:A..B`` expanded to
/// ``generated:A``, ..., ``generated:B`` (as ``sixaxis reproduce --scenarios`` does).
#[pyfunction]
pub fn expand_names(py: Python<'_>, names: &str) -> PyResult<Vec<String>> {
    run_attached(py, || sixaxis_core::names::expand_names(names))
}
