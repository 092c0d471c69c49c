//! `sixaxis_avoid.Scenario`: one experiment's world, immutable.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use sixaxis_core::scenario::BUILTIN_NAMES;
use sixaxis_core::{Cell, Error, Scenario};

use crate::convert::{json_to_py, py_to_json, repr};
use crate::errors::{invalid_argument, run_attached, to_py};

/// The scenario used when none is given: the paper's simple case.
pub const DEFAULT_SCENARIO: &str = "paper_simple";

/// A scenario: grid bounds, start, target, obstacles, arm, rewards, learning and planning
/// parameters. Immutable; make a changed copy with :meth:`replace`.
///
/// ``Scenario()`` is the paper's simple case; ``Scenario("paper_complex")`` a built-in by
/// name; ``Scenario("my/file.json")`` a file. Every constructor validates, and raises a
/// :class:`ScenarioError` (a ``ValueError``) naming the field and value at fault.
#[pyclass(name = "Scenario", module = "sixaxis_avoid", frozen)]
#[derive(Clone)]
pub struct PyScenario {
    pub inner: Arc<Scenario>,
}

impl PyScenario {
    pub fn new(s: Scenario) -> Self {
        PyScenario { inner: Arc::new(s) }
    }
}

fn cell_tuple<'py>(py: Python<'py>, c: Cell) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(py, c)
}

/// Anything a user may pass as a scenario: `Scenario`, name or path (str / PathLike),
/// dict, or `None` for the default.
pub fn scenario_from_any(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Arc<Scenario>> {
    let obj = match obj {
        Some(o) if !o.is_none() => o,
        _ => return run_attached(py, || Scenario::builtin(DEFAULT_SCENARIO)).map(Arc::new),
    };
    if let Ok(s) = obj.cast::<PyScenario>() {
        return Ok(s.get().inner.clone());
    }
    if let Ok(name) = obj.extract::<String>() {
        return run_attached(py, || Scenario::load(&name)).map(Arc::new);
    }
    if obj.hasattr("__fspath__").unwrap_or(false) {
        let p = fspath(obj, "scenario")?;
        return run_attached(py, || Scenario::load(&p)).map(Arc::new);
    }
    if obj.hasattr("keys").unwrap_or(false) {
        return from_dict_inner(obj).map(Arc::new);
    }
    Err(invalid_argument(
        py,
        "scenario",
        repr(obj),
        "must be a Scenario, a built-in name, a path to a JSON file, a dict, or None",
    ))
}

/// `os.fspath(obj)` as a `str`; a bytes path or a non-str result is an error naming `name`
/// (an exception raised by `__fspath__` itself propagates).
fn fspath(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    let p = obj.call_method0("__fspath__")?;
    p.extract().map_err(|_| {
        invalid_argument(
            obj.py(),
            name,
            repr(obj),
            format!("its __fspath__() gave {}, not a str path", repr(&p)),
        )
    })
}

fn from_dict_inner(obj: &Bound<'_, PyAny>) -> PyResult<Scenario> {
    let py = obj.py();
    let value = py_to_json(obj, "").map_err(|e| to_py(py, e))?;
    from_value(py, value)
}

fn from_value(py: Python<'_>, value: serde_json::Value) -> PyResult<Scenario> {
    if !value.is_object() {
        return Err(to_py(
            py,
            Error::ScenarioParse("a scenario must be a JSON object / dict".into()),
        ));
    }
    let text = value.to_string();
    run_attached(py, || Scenario::from_json(&text))
}

#[pymethods]
impl PyScenario {
    /// ``Scenario(name_or_path="paper_simple")``: a built-in scenario by name, or a JSON file.
    #[new]
    #[pyo3(signature = (name_or_path = None))]
    fn py_new(py: Python<'_>, name_or_path: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        Ok(PyScenario {
            inner: scenario_from_any(py, name_or_path)?,
        })
    }

    /// Load by built-in name (``paper_simple``, ...) or by JSON file path.
    #[staticmethod]
    fn load(py: Python<'_>, name_or_path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let name: String = if name_or_path.hasattr("__fspath__").unwrap_or(false) {
            fspath(name_or_path, "name_or_path")?
        } else {
            name_or_path.extract().map_err(|_| {
                invalid_argument(
                    py,
                    "name_or_path",
                    repr(name_or_path),
                    "must be a str or a path",
                )
            })?
        };
        run_attached(py, || Scenario::load(&name)).map(PyScenario::new)
    }

    /// A built-in scenario by name.
    #[staticmethod]
    fn builtin(py: Python<'_>, name: &str) -> PyResult<Self> {
        run_attached(py, || Scenario::builtin(name)).map(PyScenario::new)
    }

    /// Names of the built-in scenarios.
    #[staticmethod]
    fn builtin_names() -> Vec<&'static str> {
        BUILTIN_NAMES.to_vec()
    }

    /// Parse and validate scenario JSON text.
    #[staticmethod]
    fn from_json(py: Python<'_>, text: &str) -> PyResult<Self> {
        run_attached(py, || Scenario::from_json(text)).map(PyScenario::new)
    }

    /// Build and validate a scenario from a dict of the JSON schema (as :meth:`to_dict` gives).
    #[staticmethod]
    fn from_dict(d: &Bound<'_, PyAny>) -> PyResult<Self> {
        from_dict_inner(d).map(PyScenario::new)
    }

    /// The same physical world at ``cell_mm`` mm cells (``sixaxis regrid``): obstacle boxes
    /// and safe distances kept in mm, start and target at the same points; raises
    /// :class:`InvalidArgumentError` if a point is not a cell centre of the new grid.
    fn regrid(&self, py: Python<'_>, cell_mm: f64) -> PyResult<Self> {
        run_attached(py, || sixaxis_core::regrid::regrid(&self.inner, cell_mm)).map(PyScenario::new)
    }

    /// Pretty JSON text.
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// A dict of the JSON schema (a fresh copy; changing it does not change the scenario).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&*self.inner)
            .map_err(|e| to_py(py, Error::ScenarioParse(e.to_string())))?;
        json_to_py(py, &v)
    }

    /// Check every field again (a constructed scenario is always valid; this exists for symmetry
    /// with the core and raises :class:`ScenarioError` if not).
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        run_attached(py, || self.inner.validate())
    }

    /// A copy with top-level fields replaced; dict values of nested sections
    /// (``rewards``, ``learning``, ``arm``, ``planning``, ``bounds``) are merged into them:
    /// ``s.replace(start=(0, -2, 3), learning={"episodes": 500})``.
    #[pyo3(signature = (**changes))]
    fn replace(&self, py: Python<'_>, changes: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut base = serde_json::to_value(&*self.inner)
            .map_err(|e| to_py(py, Error::ScenarioParse(e.to_string())))?;
        if let Some(changes) = changes {
            let ch = py_to_json(changes.as_any(), "").map_err(|e| to_py(py, e))?;
            if let (Some(obj), serde_json::Value::Object(ch)) = (base.as_object_mut(), ch) {
                for (k, v) in ch {
                    match (obj.get_mut(&k), v) {
                        (Some(serde_json::Value::Object(dst)), serde_json::Value::Object(src))
                            if k != "planning" || !src.contains_key("clearance_model") =>
                        {
                            for (k2, v2) in src {
                                dst.insert(k2, v2);
                            }
                        }
                        (_, v) => {
                            obj.insert(k, v);
                        }
                    }
                }
            }
        }
        from_value(py, base).map(PyScenario::new)
    }

    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    #[getter]
    fn notes(&self) -> &str {
        &self.inner.notes
    }
    /// Edge of one grid cell, mm.
    #[getter]
    fn cell_mm(&self) -> f64 {
        self.inner.cell_mm
    }
    /// ``(min_cell, max_cell)``, both inclusive.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let b = self.inner.bounds;
        PyTuple::new(py, [cell_tuple(py, b.min)?, cell_tuple(py, b.max)?])
    }
    /// Number of cells along x, y, z.
    #[getter]
    fn shape(&self) -> [usize; 3] {
        self.inner.bounds.size()
    }
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        cell_tuple(py, self.inner.start)
    }
    #[getter]
    fn target<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        cell_tuple(py, self.inner.target)
    }
    /// Obstacle cells, as a list of ``(x, y, z)`` tuples.
    #[getter]
    fn obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
        self.inner
            .obstacles
            .iter()
            .map(|c| cell_tuple(py, *c))
            .collect()
    }
    /// Obstacles as axis-aligned boxes in mm, as in the scenario file: a list of dicts
    /// ``{"min_mm": [x, y, z], "max_mm": [x, y, z]}`` (plus ``"distance_to": "centre"`` for
    /// centre-measured boxes); empty for a world of cells only.
    #[getter]
    fn obstacle_boxes_mm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.inner.obstacle_boxes_mm)
            .map_err(|e| to_py(py, Error::ScenarioParse(e.to_string())))?;
        json_to_py(py, &v)
    }
    /// d_s (eq. 5), cells.
    #[getter]
    fn terminal_safe_distance(&self) -> f64 {
        self.inner.terminal_safe_distance
    }
    /// d_p (eq. 11), cells.
    #[getter]
    fn arm_safe_distance(&self) -> f64 {
        self.inner.arm_safe_distance
    }
    /// Step cap of one episode (``learning.max_steps_per_episode``).
    #[getter]
    fn max_steps_per_episode(&self) -> u32 {
        self.inner.learning.max_steps_per_episode
    }
    /// The reward parameters, as a dict.
    #[getter]
    fn rewards<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(self.inner.rewards)
            .map_err(|e| to_py(py, Error::ScenarioParse(e.to_string())))?;
        json_to_py(py, &v)
    }
    /// The learning parameters, as a dict.
    #[getter]
    fn learning<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(self.inner.learning)
            .map_err(|e| to_py(py, Error::ScenarioParse(e.to_string())))?;
        json_to_py(py, &v)
    }
    /// beta_0, the arm's initial pose, degrees.
    #[getter]
    fn beta0_deg(&self) -> [f64; 6] {
        self.inner.arm.beta0_deg
    }

    fn __repr__(&self) -> String {
        let s = &*self.inner;
        format!(
            "Scenario(name={:?}, start={:?}, target={:?}, obstacles={}, bounds={:?}..{:?})",
            s.name,
            s.start,
            s.target,
            s.obstacles.len(),
            s.bounds.min,
            s.bounds.max
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<PyScenario>() {
            Ok(o) => *self.inner == *o.get().inner,
            Err(_) => false,
        }
    }

    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        self.inner.to_json().hash(&mut h);
        h.finish()
    }

    /// Pickle / copy / deepcopy through the JSON text.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let cls = py.get_type::<PyScenario>();
        let ctor = cls.getattr("from_json")?;
        PyTuple::new(
            py,
            [ctor, PyTuple::new(py, [self.inner.to_json()])?.into_any()],
        )
    }
}
