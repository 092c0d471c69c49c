//! `sixaxis_avoid.train`: the core's tabular Q-learner (eqs. 6-8), GIL released.

use std::sync::Mutex;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyTuple};
use sixaxis_core::options::OptionValue;
use sixaxis_core::qlearning::{greedy_path, train_with_checkpoints, QTable, TrainReport};
use sixaxis_core::{Cell, GridWorld, Scenario};

use crate::convert::{cell, json_to_py, repr};
use crate::errors::{invalid_argument, run, run_attached};
use crate::request::train_request;
use crate::scenario::{scenario_from_any, PyScenario};

/// What :func:`train` returns. :meth:`to_dict` is the JSON of ``sixaxis train`` (the core's
/// one serialisation of a run, ``TrainReport``); the getters read the same report.
#[pyclass(name = "TrainResult", module = "sixaxis_avoid", frozen)]
pub struct PyTrainResult {
    world: GridWorld,
    scenario: PyScenario,
    report: TrainReport,
    q: QTable,
}

fn cells_array<'py>(py: Python<'py>, cells: &[Cell]) -> Bound<'py, PyArray2<i32>> {
    let mut a = Array2::<i32>::zeros((cells.len(), 3));
    for (i, c) in cells.iter().enumerate() {
        for k in 0..3 {
            a[[i, k]] = c[k];
        }
    }
    a.into_pyarray(py)
}

#[pymethods]
impl PyTrainResult {
    /// The learned path (greedy rollout, eq. 8) as a list of ``(x, y, z)`` cells, start to
    /// target; ``None`` if the greedy rollout does not reach the target.
    #[getter]
    fn path<'py>(&self, py: Python<'py>) -> PyResult<Option<Vec<Bound<'py, PyTuple>>>> {
        self.report
            .path
            .as_ref()
            .map(|p| p.iter().map(|c| PyTuple::new(py, c)).collect())
            .transpose()
    }
    /// The learned path as an ``(k, 3)`` int32 array (empty ``(0, 3)`` if it failed).
    #[getter]
    fn path_array<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i32>> {
        cells_array(py, self.report.path.as_deref().unwrap_or(&[]))
    }
    /// Whether the learned path reaches the target.
    #[getter]
    fn success(&self) -> bool {
        self.report.reached
    }
    /// Steps of each episode, ``(episodes,)`` uint32.
    #[getter]
    fn steps_per_episode<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, self.report.steps_per_episode.as_deref().unwrap_or(&[]))
    }
    /// Whether each episode reached the target, ``(episodes,)`` bool.
    #[getter]
    fn reached_per_episode<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(
            py,
            self.report.reached_per_episode.as_deref().unwrap_or(&[]),
        )
    }
    /// First episode (from 0) from which the greedy path no longer changed; ``None`` if the
    /// final path fails.
    #[getter]
    fn converged_episode(&self) -> Option<u32> {
        self.report.converged_episode
    }
    /// First episode (from 0) from which the greedy path's *length* no longer changed (later
    /// changes, if any, swap equally long paths); ``None`` if the final path fails.
    #[getter]
    fn length_converged_episode(&self) -> Option<u32> {
        self.report.length_converged_episode
    }
    /// The checkpoints of ``train(..., checkpoints=[...])`` the run reached, in order: one
    /// dict per checkpoint with ``env_steps``, ``episode`` (from 0), ``path`` (list of cells,
    /// or None), ``wall_time_s`` and ``cpu_time_s`` (of the learning thread, None where the
    /// OS does not tell) since the call began. Empty without checkpoints.
    #[getter]
    fn checkpoints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.report.checkpoints)
            .map_err(|e| invalid_argument(py, "checkpoints", "TrainResult", e.to_string()))?;
        json_to_py(py, &v)
    }
    #[getter]
    fn total_steps(&self) -> u64 {
        self.report.total_steps
    }
    #[getter]
    fn wall_time_s(&self) -> f64 {
        self.report.wall_time_s
    }
    #[getter]
    fn seed(&self) -> u64 {
        self.report.seed
    }
    #[getter]
    fn episodes(&self) -> u32 {
        self.report.episodes
    }
    /// The learned Q-table, ``(num_states, 6)``, float64 or float32 as the run's
    /// ``q_precision`` (a copy); row ``s`` is the state of cell ``state_cells[s]``, columns
    /// the actions ``+x -x +y -y +z -z``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        q_array(py, &self.q)
    }
    /// The type of the Q-values: ``"f64"`` or ``"f32"``.
    #[getter]
    fn q_precision(&self) -> &'static str {
        self.q.precision().name()
    }
    /// The cell of every state, ``(num_states, 3)`` int32.
    #[getter]
    fn state_cells<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i32>> {
        let cells: Vec<Cell> = (0..self.world.num_states())
            .map(|s| self.world.cell_of(s))
            .collect();
        cells_array(py, &cells)
    }
    /// The scenario trained on.
    #[getter]
    fn scenario(&self) -> PyScenario {
        self.scenario.clone()
    }
    /// The state number of a cell (row of :attr:`q`), or None outside bounds.
    fn state_of(&self, c: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
        Ok(self.world.state_of(cell(c, "cell")?))
    }
    /// Save the Q-table to a file (the core's checked format; see :func:`load_q`).
    fn save_q(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        let (q, w) = (&self.q, &self.world);
        run(py, || q.save(&path, w))
    }
    /// The run as a dict: the JSON of ``sixaxis train`` for the same scenario and options
    /// (with the per-episode curves), field for field.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.report)
            .map_err(|e| invalid_argument(py, "report", "TrainResult", e.to_string()))?;
        json_to_py(py, &v)
    }
    fn __repr__(&self) -> String {
        let r = &self.report;
        format!(
            "TrainResult(success={}, path_len={}, episodes={}, converged_episode={}, total_steps={}, wall_time_s={:.3})",
            if r.reached { "True" } else { "False" },
            r.path.as_ref().map_or(0, |p| p.len()),
            r.episodes_run,
            r.converged_episode
                .map_or_else(|| "None".to_string(), |e| e.to_string()),
            r.total_steps,
            r.wall_time_s
        )
    }
}

fn world_of(
    py: Python<'_>,
    s: &Scenario,
    extra_obstacles: Option<&Bound<'_, PyAny>>,
) -> PyResult<GridWorld> {
    let mut extra = Vec::new();
    if let Some(obj) = extra_obstacles.filter(|o| !o.is_none()) {
        for item in obj.try_iter().map_err(|_| {
            invalid_argument(
                py,
                "extra_obstacles",
                repr(obj),
                "must be a sequence of cells",
            )
        })? {
            extra.push(cell(&item?, "extra_obstacles")?);
        }
    }
    run_attached(py, || GridWorld::with_extra_obstacles(s, &extra))
}

/// A Q-table as a ``(num_states, 6)`` array of its own dtype (float64 or float32).
fn q_array<'py>(py: Python<'py>, q: &QTable) -> PyResult<Bound<'py, PyAny>> {
    let shape = (q.num_states(), 6);
    let bad_shape =
        |e: numpy::ndarray::ShapeError| invalid_argument(py, "q", "shape", e.to_string());
    Ok(match (q.values_f64(), q.values_f32()) {
        (Some(v), _) => Array2::from_shape_vec(shape, v.to_vec())
            .map_err(bad_shape)?
            .into_pyarray(py)
            .into_any(),
        (None, Some(v)) => Array2::from_shape_vec(shape, v.to_vec())
            .map_err(bad_shape)?
            .into_pyarray(py)
            .into_any(),
        (None, None) => unreachable!("a table is f64 or f32"),
    })
}

/// A ``(num_states, 6)`` float64 or float32 array as a Q-table of that precision; errors
/// name it `name`, and anything but such an array is rejected with `reason`.
fn q_from_array(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    world: &GridWorld,
    name: &str,
    reason: &str,
) -> PyResult<QTable> {
    let (shape, table) = if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f64>>() {
        let values: Vec<f64> = a.as_array().iter().copied().collect();
        let finite = values.iter().all(|v| v.is_finite());
        (a.shape().to_vec(), finite.then_some(Table::F64(values)))
    } else if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f32>>() {
        let values: Vec<f32> = a.as_array().iter().copied().collect();
        let finite = values.iter().all(|v| v.is_finite());
        (a.shape().to_vec(), finite.then_some(Table::F32(values)))
    } else {
        return Err(invalid_argument(py, name, repr(obj), reason));
    };
    if shape[1] != 6 || shape[0] != world.num_states() {
        return Err(crate::errors::to_py(
            py,
            sixaxis_core::Error::QTableMismatch(format!(
                "{name} has shape {shape:?}, the world needs ({}, 6)",
                world.num_states()
            )),
        ));
    }
    let Some(table) = table else {
        return Err(invalid_argument(
            py,
            name,
            "array",
            "every value must be finite",
        ));
    };
    let n = world.num_states();
    run_attached(py, || match table {
        Table::F64(v) => QTable::from_values(n, v),
        Table::F32(v) => QTable::from_values_f32(n, v),
    })
}

/// The values of an array given as a Q-table.
enum Table {
    F64(Vec<f64>),
    F32(Vec<f32>),
}

/// Learn a path with tabular Q-learning (eqs. 6-8) on a scenario.
///
/// Same arithmetic and random stream as the core (and the ``sixaxis train`` CLI): for the
/// same scenario, seed, episodes and assist, path and Q-table values are identical.
/// ``**options`` are the learning options, one keyword per option of the core's table (the
/// same as the CLI's flags; :func:`sixaxis_avoid.options` lists them with their domains,
/// units, docs and defaults): ``episodes`` (a number or ``"auto"``), ``episode_cap``,
/// ``seed``, ``assist`` (eqs. 9 and 10 together), ``detour`` (eq. 9), ``distance`` (eq. 10),
/// ``max_steps_per_episode``, ``q_precision``, ``alpha``, ``gamma``, ``epsilon_start``,
/// ``epsilon_decay_episodes``, ``max_env_steps`` (an env-step budget), ``epsilon_schedule``
/// (``"episodes"`` or ``"env_steps"``), ``epsilon_decay_fraction``; one left out or ``None``
/// takes the scenario's ``learning`` value. ``checkpoints`` is a list of increasing env-step
/// counts at which the learner records the greedy path of its current table without
/// stopping (:attr:`TrainResult.checkpoints`; the run is the same as without). ``initial_q`` is how the Q-table starts: ``"zero"`` (the paper's),
/// ``"distance"`` (an optimistic bound from the Manhattan distance to the target, see
/// docs/SCENARIOS.md), or a ``(num_states, 6)`` float64 or float32 array to resume from
/// (converted to the run's ``q_precision``). ``progress(episodes_done)`` is called about 100
/// times; an exception it raises is re-raised after training. The GIL is released while
/// learning.
#[pyfunction]
#[pyo3(signature = (scenario=None, *, extra_obstacles=None, initial_q=None, progress=None, checkpoints=None, **options))]
pub fn train(
    py: Python<'_>,
    scenario: Option<&Bound<'_, PyAny>>,
    extra_obstacles: Option<&Bound<'_, PyAny>>,
    initial_q: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    checkpoints: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyTrainResult> {
    let s = scenario_from_any(py, scenario)?;
    let checkpoints: Vec<u64> = match checkpoints.filter(|o| !o.is_none()) {
        None => Vec::new(),
        Some(o) => o.extract().map_err(|_| {
            invalid_argument(
                py,
                "checkpoints",
                repr(o),
                "must be a list of env-step counts (integers >= 1)",
            )
        })?,
    };
    let mut req = train_request(py, "train", options)?;
    // `initial_q`: a rule by name (an option like the others) or a table to start from.
    let table = match initial_q.filter(|o| !o.is_none()) {
        Some(o) if o.is_instance_of::<PyString>() => {
            req.0
                .insert("initial_q".into(), OptionValue::Text(o.extract()?));
            None
        }
        other => other,
    };
    let opts = run_attached(py, || req.resolve(&s))?;
    let world = world_of(py, &s, extra_obstacles)?;
    let q0 = table
        .map(|o| {
            let reason = "must be \"zero\", \"distance\", a (num_states, 6) float64 or \
                          float32 array or None";
            q_from_array(py, o, &world, "initial_q", reason)
        })
        .transpose()?;
    let cb_error: Mutex<Option<PyErr>> = Mutex::new(None);
    let result = {
        let world = &world;
        let opts = &opts;
        let cb_error = &cb_error;
        let progress = progress.as_ref();
        let checkpoints = &checkpoints;
        run(py, move || {
            let report = |done: u32| {
                if let Some(cb) = progress {
                    Python::attach(|py| {
                        if let Err(e) = cb.call1(py, (done,)) {
                            let mut slot = cb_error.lock().unwrap_or_else(|p| p.into_inner());
                            slot.get_or_insert(e);
                        }
                    });
                }
            };
            let progress_fn: Option<&dyn Fn(u32)> = if progress.is_some() {
                Some(&report)
            } else {
                None
            };
            train_with_checkpoints(world, opts, q0, progress_fn, checkpoints)
        })?
    };
    if let Some(e) = cb_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let report = TrainReport::new(&s, &world, &opts, &result, true);
    Ok(PyTrainResult {
        scenario: PyScenario { inner: s },
        report,
        q: result.q,
        world,
    })
}

/// Load a Q-table file saved by :meth:`TrainResult.save_q` (or the CLI) for a scenario;
/// raises :class:`QTableMismatchError` if it was learned on another grid or target.
/// Returns the ``(num_states, 6)`` array, float64 or float32 as the file stores it.
#[pyfunction]
#[pyo3(signature = (path, scenario=None, *, extra_obstacles=None))]
pub fn load_q<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    scenario: Option<&Bound<'py, PyAny>>,
    extra_obstacles: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = scenario_from_any(py, scenario)?;
    let world = world_of(py, &s, extra_obstacles)?;
    let q = run(py, || QTable::load(&path, &world))?;
    q_array(py, &q)
}

/// The greedy path (eq. 8) of a Q-table array (float64 or float32) on a scenario: list of
/// cells, or None.
#[pyfunction]
#[pyo3(signature = (q, scenario=None, *, max_steps=None, extra_obstacles=None))]
pub fn greedy_path_of<'py>(
    py: Python<'py>,
    q: &Bound<'py, PyAny>,
    scenario: Option<&Bound<'py, PyAny>>,
    max_steps: Option<u32>,
    extra_obstacles: Option<&Bound<'py, PyAny>>,
) -> PyResult<Option<Vec<Bound<'py, PyTuple>>>> {
    let s = scenario_from_any(py, scenario)?;
    let world = world_of(py, &s, extra_obstacles)?;
    let qt = q_from_array(
        py,
        q,
        &world,
        "q",
        "must be a (num_states, 6) float64 or float32 array",
    )?;
    let cap = max_steps.unwrap_or(s.learning.max_steps_per_episode);
    greedy_path(&world, &qt, cap)
        .map(|p| p.iter().map(|c| PyTuple::new(py, c)).collect())
        .transpose()
}

/// The breadth-first shortest path of a scenario (list of cells, start to target), or None.
#[pyfunction]
#[pyo3(signature = (scenario=None, *, extra_obstacles=None))]
pub fn shortest_path<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
    extra_obstacles: Option<&Bound<'py, PyAny>>,
) -> PyResult<Option<Vec<Bound<'py, PyTuple>>>> {
    let s = scenario_from_any(py, scenario)?;
    let world = world_of(py, &s, extra_obstacles)?;
    world
        .shortest_path()
        .map(|p| p.iter().map(|c| PyTuple::new(py, c)).collect())
        .transpose()
}
