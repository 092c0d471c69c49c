//! Python exceptions of the core's errors, and the one helper that runs core code.
//!
//! Hierarchy (every error of bad input is a `ValueError` through `SixAxisError`; a caught
//! panic is a bug, not bad input, so `InternalError` is a `RuntimeError` only and
//! `except ValueError` does not swallow it):
//!
//! ```text
//! ValueError
//! └── SixAxisError
//!     ├── ScenarioError                       Error::InvalidScenario
//!     │   ├── ScenarioParseError              Error::ScenarioParse
//!     │   └── ScenarioNotFoundError           Error::ScenarioNotFound  (also a LookupError)
//!     ├── InvalidArgumentError                Error::InvalidArgument
//!     ├── QTableMismatchError                 Error::QTableMismatch
//!     └── SixAxisIOError                      Error::Io                (also an OSError)
//! RuntimeError
//! └── InternalError                           a Rust panic
//! ```
//!
//! The classes are made with Python's `type()` at import time because some of them have two
//! bases, which `create_exception!` cannot express.

use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};

use pyo3::exceptions::{PyLookupError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use sixaxis_core::Error;

/// One exception class: its name, its docstring, and its bases.
struct ExcDef {
    name: &'static str,
    doc: &'static str,
    cell: PyOnceLock<Py<PyType>>,
}

macro_rules! exc {
    ($id:ident, $name:literal, $doc:literal) => {
        static $id: ExcDef = ExcDef {
            name: $name,
            doc: $doc,
            cell: PyOnceLock::new(),
        };
    };
}

exc!(
    SIXAXIS_ERROR,
    "SixAxisError",
    "Base class of every bad-input error raised by sixaxis_avoid (a ValueError); a caught panic is InternalError instead."
);
exc!(
    SCENARIO_ERROR,
    "ScenarioError",
    "A scenario field holds a value that makes no sense. Attributes: field, value, reason."
);
exc!(
    SCENARIO_PARSE_ERROR,
    "ScenarioParseError",
    "Scenario text or dict does not match the schema (unknown field, wrong type, missing field)."
);
exc!(
    SCENARIO_NOT_FOUND_ERROR,
    "ScenarioNotFoundError",
    "No scenario file and no built-in scenario has that name (also a LookupError). Attributes: name, known."
);
exc!(
    INVALID_ARGUMENT_ERROR,
    "InvalidArgumentError",
    "A function argument or keyword is out of its domain. Attributes: name, value, reason."
);
exc!(
    QTABLE_MISMATCH_ERROR,
    "QTableMismatchError",
    "A Q-table does not fit the scenario it is used with."
);
exc!(
    IO_ERROR,
    "SixAxisIOError",
    "Reading or writing a file failed (also an OSError; errno, strerror and filename are set when the OS gave an errno)."
);
exc!(
    INTERNAL_ERROR,
    "InternalError",
    "A bug in sixaxis_avoid's Rust core (a caught panic; please report it). A RuntimeError, not a ValueError."
);

fn get<'py>(py: Python<'py>, def: &'static ExcDef) -> Bound<'py, PyType> {
    def.cell
        .get(py)
        .expect("exception classes are created when the module is imported")
        .bind(py)
        .clone()
}

/// Create the classes and add them to module `m`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let module_name = "sixaxis_avoid";
    let builtins_type = py.import("builtins")?.getattr("type")?;
    let make = |def: &'static ExcDef, bases: Vec<Bound<'_, PyAny>>| -> PyResult<()> {
        let ns = PyDict::new(py);
        ns.set_item("__doc__", def.doc)?;
        ns.set_item("__module__", module_name)?;
        let bases = PyTuple::new(py, bases)?;
        let cls = builtins_type
            .call1((def.name, bases, ns))?
            .cast_into::<PyType>()?;
        m.add(def.name, &cls)?;
        let _ = def.cell.set(py, cls.unbind());
        Ok(())
    };
    let value_error = py.get_type::<PyValueError>().into_any();
    make(&SIXAXIS_ERROR, vec![value_error])?;
    let base = || get(py, &SIXAXIS_ERROR).into_any();
    make(&SCENARIO_ERROR, vec![base()])?;
    let scen = || get(py, &SCENARIO_ERROR).into_any();
    make(&SCENARIO_PARSE_ERROR, vec![scen()])?;
    make(
        &SCENARIO_NOT_FOUND_ERROR,
        vec![scen(), py.get_type::<PyLookupError>().into_any()],
    )?;
    make(&INVALID_ARGUMENT_ERROR, vec![base()])?;
    make(&QTABLE_MISMATCH_ERROR, vec![base()])?;
    // OSError first: its constructor then fills errno / strerror / filename.
    make(
        &IO_ERROR,
        vec![py.get_type::<PyOSError>().into_any(), base()],
    )?;
    make(
        &INTERNAL_ERROR,
        vec![py.get_type::<PyRuntimeError>().into_any()],
    )?;
    Ok(())
}

/// Build an exception of class `def` from constructor `args`, then set `attrs` on it.
fn build<'py, A>(
    py: Python<'py>,
    def: &'static ExcDef,
    args: A,
    attrs: &[(&str, Bound<'py, PyAny>)],
) -> PyErr
where
    A: pyo3::call::PyCallArgs<'py>,
{
    let cls = get(py, def);
    match cls.call1(args) {
        Ok(obj) => {
            for (k, v) in attrs {
                // Attributes are a convenience; the message already says it all.
                let _ = obj.setattr(*k, v);
            }
            PyErr::from_value(obj)
        }
        Err(e) => e,
    }
}

fn s<'py>(py: Python<'py>, v: &str) -> Bound<'py, PyAny> {
    v.into_pyobject(py).expect("str converts").into_any()
}

/// The Python exception of a core error: one exhaustive `match`, so that a new variant in
/// the core does not compile here until it has its class.
pub fn to_py(py: Python<'_>, err: Error) -> PyErr {
    let msg = err.to_string();
    match &err {
        Error::InvalidScenario {
            field,
            value,
            reason,
        } => build(
            py,
            &SCENARIO_ERROR,
            (msg,),
            &[
                ("field", s(py, field)),
                ("value", s(py, value)),
                ("reason", s(py, reason)),
            ],
        ),
        Error::ScenarioParse(_) => build(py, &SCENARIO_PARSE_ERROR, (msg,), &[]),
        Error::ScenarioNotFound { name, known } => build(
            py,
            &SCENARIO_NOT_FOUND_ERROR,
            (msg,),
            &[("name", s(py, name)), ("known", s(py, known))],
        ),
        Error::InvalidArgument {
            name,
            value,
            reason,
        } => build(
            py,
            &INVALID_ARGUMENT_ERROR,
            (msg,),
            &[
                ("name", s(py, name)),
                ("value", s(py, value)),
                ("reason", s(py, reason)),
            ],
        ),
        Error::QTableMismatch(_) => build(py, &QTABLE_MISMATCH_ERROR, (msg,), &[]),
        Error::Io { path, source } => {
            let filename = path.display().to_string();
            match source.raw_os_error() {
                Some(errno) => build(py, &IO_ERROR, (errno, msg, filename), &[]),
                // No errno (bad data, a file too large): setting `filename` would make
                // OSError print "[Errno None] None: 'path'" and hide the message, which
                // names the path already.
                None => build(py, &IO_ERROR, (msg,), &[]),
            }
        }
    }
}

/// `InvalidArgumentError` for a binding-side check, worded like the core's.
pub fn invalid_argument(
    py: Python<'_>,
    name: &str,
    value: impl ToString,
    reason: impl Into<String>,
) -> PyErr {
    to_py(py, Error::argument(name, value, reason))
}

/// `InvalidArgumentError` with a message already in the core's words (an env server's
/// INVALID_ARGUMENT answer, checked there by the core's table).
pub fn invalid_argument_message(py: Python<'_>, message: String) -> PyErr {
    build(py, &INVALID_ARGUMENT_ERROR, (message,), &[])
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

fn internal(py: Python<'_>, payload: Box<dyn Any + Send>) -> PyErr {
    build(
        py,
        &INTERNAL_ERROR,
        (format!(
            "internal error in the sixaxis core (please report it): {}",
            panic_message(payload.as_ref())
        ),),
        &[],
    )
}

/// Run core code `f` with the GIL released and any panic caught; map its error.
///
/// This is the one place where long core calls run: everything that may take more than a
/// few microseconds goes through here.
pub fn run<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    F: Send + FnOnce() -> sixaxis_core::Result<T>,
    T: Send,
{
    detached(py, f, to_py)
}

/// [`run`] for code with errors of its own (the env server client's), mapped by `map`.
pub fn detached<T, E, F>(py: Python<'_>, f: F, map: fn(Python<'_>, E) -> PyErr) -> PyResult<T>
where
    F: Send + FnOnce() -> Result<T, E>,
    T: Send,
    E: Send,
{
    match py.detach(move || catch_unwind(AssertUnwindSafe(f))) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(map(py, e)),
        Err(payload) => Err(internal(py, payload)),
    }
}

/// Like [`run`] but keeps the GIL: for calls of a few microseconds, where releasing and
/// re-taking the GIL would cost more than the call.
pub fn run_attached<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    F: FnOnce() -> sixaxis_core::Result<T>,
{
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(to_py(py, e)),
        Err(payload) => Err(internal(py, payload)),
    }
}
