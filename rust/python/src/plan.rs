//! `sixaxis_avoid.plan` (Algorithm 2) and `sixaxis_avoid.generate_scenario` (the core's
//! random cluttered scenarios). Thin: argument checks here, everything else in the core,
//! long calls through [`crate::errors::run`] (GIL released, panics caught).

use std::sync::Mutex;
use std::time::Instant;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyTuple};
use sixaxis_core::generator::{generate, generator_options, GeneratorOptions};
use sixaxis_core::options::{Domain, OptionValue};
use sixaxis_core::replanning::{
    plan as core_plan, BfsLearner, LearnedPath, PathLearner, PlanResult, Round,
};
use sixaxis_core::request::{plan_options, LearnerKind, PlanRequest};
use sixaxis_core::scenario::Bounds;
use sixaxis_core::{Cell, Error as CoreError, GridWorld, Result as CoreResult};

use crate::convert::{cell, json_to_py, repr};
use crate::errors::{invalid_argument, run, run_attached};
use crate::request::{int_in, options_of};
use crate::scenario::{scenario_from_any, PyScenario};

/// What :func:`plan` returns: the core's ``PlanResult`` (Algorithm 2), read-only.
///
/// :meth:`to_dict` is the JSON of ``sixaxis plan`` (same serialisation code).
#[pyclass(name = "PlanResult", module = "sixaxis_avoid", frozen)]
pub struct PyPlanResult {
    inner: PlanResult,
}

fn tuples<'py>(py: Python<'py>, cells: &[Cell]) -> PyResult<Vec<Bound<'py, PyTuple>>> {
    cells.iter().map(|c| PyTuple::new(py, c)).collect()
}

fn rows<'py, const N: usize>(py: Python<'py>, v: &[[f64; N]]) -> Bound<'py, PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((v.len(), N));
    for (i, r) in v.iter().enumerate() {
        for (j, x) in r.iter().enumerate() {
            a[[i, j]] = *x;
        }
    }
    a.into_pyarray(py)
}

/// Serialise a core value with serde_json (the CLI's serialisation): it cannot fail for
/// these types, but a failure would still surface as a Python error rather than a panic.
macro_rules! to_value {
    ($py:expr, $v:expr) => {
        serde_json::to_value($v)
            .map_err(|e| crate::errors::invalid_argument($py, "result", "?", e.to_string()))
    };
}

#[pymethods]
impl PyPlanResult {
    /// Whether every path point got a safe pose.
    #[getter]
    fn success(&self) -> bool {
        self.inner.success
    }
    /// The final terminal path, ``(x, y, z)`` cells from start to target (the last learned
    /// path on failure; empty if no path was learned).
    #[getter]
    fn path<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
        tuples(py, &self.inner.path)
    }
    /// One pose per path point, start included: ``(k, 6)`` float64, radians (``(0, 6)`` on
    /// failure).
    #[getter]
    fn poses_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.inner.poses_rad)
    }
    /// The terminal orientation ``(rt_x, rt_y, rt_z)`` chosen at each path point: ``(k, 3)``
    /// float64, degrees.
    #[getter]
    fn orientations_rpy_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.inner.orientations_rpy_deg)
    }
    /// Number of re-plans (rounds after the first).
    #[getter]
    fn replans(&self) -> u32 {
        self.inner.replans
    }
    /// Points recorded as new obstacles (for the terminal), in order.
    #[getter]
    fn added_obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
        tuples(py, &self.inner.added_obstacles)
    }
    /// ``None`` on success; otherwise why, naming the points that could not be reached.
    #[getter]
    fn failure(&self) -> Option<&str> {
        self.inner.failure.as_deref()
    }
    /// Per-round learning figures: a list of dicts with ``added_obstacles`` (count before
    /// the round), ``path`` (or ``None``), ``converged_episode``,
    /// ``length_converged_episode``, ``total_steps``,
    /// ``learning_time_s`` and ``blocked_at`` (``[index, [x, y, z]]`` or ``None``).
    #[getter]
    fn rounds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &to_value!(py, &self.inner.rounds)?)
    }
    /// Wall time of the whole run, seconds.
    #[getter]
    fn wall_time_s(&self) -> f64 {
        self.inner.wall_time_s
    }
    /// Seed of the learner.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
    /// Eq. 11's figure for the final motion: smallest distance from an obstacle centre to
    /// the arm's polyline over every interpolation step, cells (``None`` without poses).
    #[getter]
    fn min_centre_clearance_cells(&self) -> Option<f64> {
        self.inner.min_centre_clearance_cells
    }
    /// Exact geometry for the same motion: smallest distance from the arm's polyline to an
    /// obstacle cube, mm (``None`` without poses).
    #[getter]
    fn min_cube_distance_mm(&self) -> Option<f64> {
        self.inner.min_cube_distance_mm
    }
    /// The scenario's own obstacles (before any were added).
    #[getter]
    fn obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
        tuples(py, &self.inner.obstacles)
    }
    /// The scenario's obstacles as boxes in mm, as in the scenario file: a list of dicts
    /// ``{"min_mm": [x, y, z], "max_mm": [x, y, z]}`` (plus ``"distance_to": "centre"`` for
    /// centre-measured boxes); empty for a world of cells only.
    #[getter]
    fn obstacle_boxes_mm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &to_value!(py, &self.inner.obstacle_boxes_mm)?)
    }
    /// Edge of a cell, mm.
    #[getter]
    fn cell_mm(&self) -> f64 {
        self.inner.cell_mm
    }
    /// d_p, cells: the whole arm's safe distance (eq. 11).
    #[getter]
    fn arm_safe_distance(&self) -> f64 {
        self.inner.arm_safe_distance
    }
    /// t: joint-space interpolation steps between two poses (Algorithm 1).
    #[getter]
    fn interpolation_steps(&self) -> u32 {
        self.inner.interpolation_steps
    }
    /// The clearance model of the arm, as in the scenario file (a dict).
    #[getter]
    fn clearance_model<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &to_value!(py, &self.inner.clearance_model)?)
    }
    /// Start cell.
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.inner.start)
    }
    /// Target cell.
    #[getter]
    fn target<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.inner.target)
    }
    /// The JSON of ``sixaxis plan`` as a dict (serialised by the core, so the two agree).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &to_value!(py, &self.inner)?)
    }
    /// The JSON of ``sixaxis plan`` as text (pretty-printed).
    fn to_json(&self, py: Python<'_>) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner)
            .map_err(|e| invalid_argument(py, "result", "?", e.to_string()))
    }
    fn __repr__(&self) -> String {
        format!(
            "PlanResult(success={}, path_len={}, replans={}, added_obstacles={}, wall_time_s={:.3})",
            if self.inner.success { "True" } else { "False" },
            self.inner.path.len(),
            self.inner.replans,
            self.inner.added_obstacles.len(),
            self.inner.wall_time_s
        )
    }
}

/// A Python path learner: a callable `learner(scenario, seed)` or an object with a
/// `learn_path(scenario, seed)` method, called with the GIL held once per round (the rest of
/// Algorithm 2 runs with the GIL released). Its first exception is kept in `error` and
/// re-raised unchanged once the core loop has stopped.
struct PyLearner<'a> {
    callable: Py<PyAny>,
    seed: u64,
    error: &'a Mutex<Option<PyErr>>,
}

/// Stops the core loop after the Python learner raised; the binding re-raises the original.
fn learner_raised() -> CoreError {
    CoreError::argument("learner", "a Python learner", "raised an exception")
}

impl PathLearner for PyLearner<'_> {
    fn learn_path(&mut self, _world: &GridWorld, round: &Round<'_>) -> CoreResult<LearnedPath> {
        let t0 = Instant::now();
        let outcome = Python::attach(|py| -> PyResult<LearnedPath> {
            let mut world = round.scenario.clone();
            world.obstacles.extend_from_slice(round.added_obstacles);
            let arg = Bound::new(py, PyScenario::new(world))?;
            let ret = self.callable.bind(py).call1((arg, self.seed))?;
            learned_of(py, &ret, t0)
        });
        match outcome {
            Ok(r) => Ok(r),
            Err(e) => {
                let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
                slot.get_or_insert(e);
                Err(learner_raised())
            }
        }
    }

    fn no_path_reason(&self, round: u32) -> String {
        format!("the Python path learner returned no path (round {round})")
    }
}

/// A Python learner's return value: a list of cells, `None`, or a dict with `path` and
/// optional `total_steps`, `converged_episode`, `length_converged_episode`, `wall_time_s`,
/// `reason` (why `path` is `None`: the plan's failure reason, the round appended).
fn learned_of(py: Python<'_>, ret: &Bound<'_, PyAny>, t0: Instant) -> PyResult<LearnedPath> {
    let mut out = LearnedPath::default();
    let path_obj = if let Ok(d) = ret.cast::<PyDict>() {
        for (k, v) in d.iter() {
            let key: String = k.extract()?;
            let field = format!("learner result `{key}`");
            match key.as_str() {
                "path" => {}
                "total_steps" => {
                    out.total_steps =
                        int_in(py, &field, &Domain::u64_from(0), Some(&v))?.map_or(0, |v| v as u64)
                }
                "converged_episode" => {
                    out.converged_episode =
                        int_in(py, &field, &Domain::u32_from(0), Some(&v))?.map(|v| v as u32)
                }
                "length_converged_episode" => {
                    out.length_converged_episode =
                        int_in(py, &field, &Domain::u32_from(0), Some(&v))?.map(|v| v as u32)
                }
                "wall_time_s" => out.wall_time_s = v.extract()?,
                "reason" => {
                    out.no_path_reason = if v.is_none() {
                        None
                    } else {
                        Some(v.extract().map_err(|_| {
                            invalid_argument(py, &field, repr(&v), "must be a string or None")
                        })?)
                    }
                }
                _ => {}
            }
        }
        d.get_item("path")?.ok_or_else(|| {
            invalid_argument(
                py,
                "learner",
                repr(ret),
                "a dict result needs a \"path\" key",
            )
        })?
    } else {
        ret.clone()
    };
    if out.wall_time_s == 0.0 {
        out.wall_time_s = t0.elapsed().as_secs_f64();
    }
    if !path_obj.is_none() {
        let items = path_obj.try_iter().map_err(|_| {
            invalid_argument(
                py,
                "learner",
                repr(&path_obj),
                "must return a list of (x, y, z) cells, None, or a dict with a \"path\"",
            )
        })?;
        let cells = items
            .map(|c| cell(&c?, "path"))
            .collect::<PyResult<Vec<Cell>>>()?;
        out.path = Some(cells);
    }
    Ok(out)
}

/// Run Algorithm 2 on a scenario: learn a terminal path, plan the arm's poses along it
/// (Algorithm 1), and re-plan around every path point no safe pose reaches.
///
/// Keywords as :func:`train` (``None`` takes the scenario's ``learning`` value;
/// ``assist`` switches eqs. 9 and 10 together, ``detour`` / ``distance`` each on its own);
/// ``initial_q`` names how each round's Q-table starts (``"zero"``, the paper's, or
/// ``"distance"``; default the scenario's ``learning.initial_q``); ``q_precision`` the type
/// of each round's Q-values (``"f64"``, the default, or ``"f32"``, half the memory; default
/// the scenario's ``learning.q_precision``);
/// ``max_replans`` defaults to the scenario's ``planning.max_replans``. ``learner`` is
/// ``"qlearning"`` (default, the paper's), ``"bfs"`` (breadth-first shortest path), or a
/// Python callable ``learner(scenario, seed)`` / an object with a ``learn_path(scenario,
/// seed)`` method: called once per round with the round's world (the scenario with every
/// point added so far appended to its obstacles), it returns the path as a list of
/// ``(x, y, z)`` cells from start to target, ``None`` when it found none, or a dict
/// ``{"path": ..., "total_steps": int, "reason": str, ...}`` (``reason``: why ``path`` is
/// ``None``, the plan's ``failure`` with `` (round k)`` appended). The core checks every path (start, target,
/// neighbouring steps, no obstacle); an exception the learner raises propagates unchanged.
/// Same arithmetic and random stream as ``sixaxis plan``. A plan that cannot be completed
/// is returned with ``success=False`` and a ``failure`` reason; bad arguments raise
/// :class:`InvalidArgumentError`. The GIL is released while the core works.
#[pyfunction]
#[pyo3(signature = (scenario=None, *, learner=None, **options))]
pub fn plan(
    py: Python<'_>,
    scenario: Option<&Bound<'_, PyAny>>,
    learner: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyPlanResult> {
    let s = scenario_from_any(py, scenario)?;
    let mut req = PlanRequest(options_of(py, "plan", &plan_options(), options)?);
    let mut callable: Option<Py<PyAny>> = None;
    if let Some(l) = learner.filter(|l| !l.is_none()) {
        if let Ok(name) = l.cast::<PyString>() {
            req.0
                .insert("learner".into(), OptionValue::Text(name.to_string()));
        } else if let Ok(method) = l.getattr("learn_path") {
            callable = Some(method.unbind());
        } else if l.is_callable() {
            callable = Some(l.clone().unbind());
        } else {
            return Err(invalid_argument(
                py,
                "learner",
                repr(l),
                "must be \"qlearning\", \"bfs\", a callable learner(scenario, seed) or an object with a learn_path(scenario, seed) method",
            ));
        }
    }
    let (opts, kind) = run_attached(py, || req.resolve(&s))?;
    let error: Mutex<Option<PyErr>> = Mutex::new(None);
    let result = match callable {
        Some(callable) => {
            let mut l = PyLearner {
                callable,
                seed: opts.train.seed,
                error: &error,
            };
            run(py, || core_plan(&s, &opts, Some(&mut l), None))
        }
        None => match kind {
            LearnerKind::Qlearning => run(py, || core_plan(&s, &opts, None, None)),
            LearnerKind::Bfs => run(py, || core_plan(&s, &opts, Some(&mut BfsLearner), None)),
        },
    };
    if let Some(e) = error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    Ok(PyPlanResult { inner: result? })
}

fn bounds_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Bounds> {
    let bad = || {
        invalid_argument(
            py,
            "bounds",
            repr(obj),
            "must be a pair of cells (min, max) or a dict {\"min\": cell, \"max\": cell}",
        )
    };
    let (lo, hi) = if let Ok(d) = obj.cast::<PyDict>() {
        let lo = d.get_item("min")?.ok_or_else(bad)?;
        let hi = d.get_item("max")?.ok_or_else(bad)?;
        if d.len() != 2 {
            return Err(bad());
        }
        (lo, hi)
    } else {
        let items: Vec<Bound<'_, PyAny>> = obj
            .try_iter()
            .map_err(|_| bad())?
            .collect::<PyResult<_>>()
            .map_err(|_| bad())?;
        if items.len() != 2 {
            return Err(bad());
        }
        let mut it = items.into_iter();
        (it.next().ok_or_else(bad)?, it.next().ok_or_else(bad)?)
    };
    Ok(Bounds {
        min: cell(&lo, "bounds")?,
        max: cell(&hi, "bounds")?,
    })
}

/// A random cluttered scenario, deterministic per ``seed`` (the core's generator).
///
/// Unit-cube clutter at ``density`` (fraction of the cells, in [0, 0.6]) inside ``bounds``
/// (``(min_cell, max_cell)``, inclusive; default ``((-3, -3, -2), (3, 5, 5))``, the paper's
/// box); start and target at least ``min_start_target_distance`` cells apart and connected
/// (breadth-first search); with ``require_arm_reachable`` both reachable by a clear arm pose.
/// beta_0 is the clearest arm pose at the start. Every other field comes from ``template``
/// (a scenario name or file). With the default options, seed ``i`` gives the scenario that
/// ``Scenario.load("generated:i")`` loads. Raises :class:`InvalidArgumentError` for a bad
/// keyword, or when ``max_attempts`` draws find no scenario meeting the guarantees.
#[pyfunction]
#[pyo3(signature = (seed, *, bounds=None, **options))]
pub fn generate_scenario(
    py: Python<'_>,
    seed: &Bound<'_, PyAny>,
    bounds: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyScenario> {
    let seed_domain = Domain::u64_from(0);
    let seed = int_in(py, "seed", &seed_domain, Some(seed))?
        .ok_or_else(|| invalid_argument(py, "seed", "None", seed_domain.reason()))?
        as u64;
    let values = options_of(py, "generate_scenario", &generator_options(), options)?;
    let mut opts = run_attached(py, || GeneratorOptions::default().with(&values))?;
    if let Some(b) = bounds.filter(|b| !b.is_none()) {
        opts.bounds = bounds_arg(py, b)?;
    }
    let s = run(py, || generate(&opts, seed))?;
    Ok(PyScenario::new(s))
}
