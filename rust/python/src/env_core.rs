//! The engines behind the Python envs: `EnvCore` (one env) and `VecEnvCore` (a batch),
//! both over `sixaxis_core::env`.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use sixaxis_core::env::{
    BatchBuffers, BatchEnv, EnvModel, EnvOptions, Episode, ObsBuffer, VECTOR_OBS_DIM,
};
use sixaxis_core::grid::Assist;
use sixaxis_core::{Cell, Scenario};

use crate::convert::{bounded_vec, cell, column, goal_rows, repr};
use crate::errors::{invalid_argument, run_attached};
use crate::scenario::{scenario_from_any, PyScenario};
use crate::vec_core::{call, impl_block, row_major, vec_pymethods, NumpyBuffers, StepArrays};

/// Which observation the engine produces.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum ObsKind {
    Vector,
    Index,
}

fn obs_kind(py: Python<'_>, obs: &str) -> PyResult<ObsKind> {
    match obs {
        "vector" => Ok(ObsKind::Vector),
        "index" => Ok(ObsKind::Index),
        other => Err(invalid_argument(
            py,
            "obs",
            format!("{other:?}"),
            "must be \"vector\" or \"index\"",
        )),
    }
}

/// `assist=None|bool` as the core's training request resolves it (None: the scenario's
/// `learning.assist_*` flags).
fn assist_of(py: Python<'_>, assist: Option<&Bound<'_, PyAny>>, s: &Scenario) -> PyResult<Assist> {
    let mut req = sixaxis_core::request::TrainRequest::default();
    if let Some(a) = crate::request::bool_kw(py, "assist", assist)? {
        req = req.with("assist", a);
    }
    Ok(run_attached(py, || req.resolve(s))?.assist())
}

#[allow(clippy::too_many_arguments)]
fn build_model(
    py: Python<'_>,
    scenario: Option<&Bound<'_, PyAny>>,
    assist: Option<&Bound<'_, PyAny>>,
    reward_scale: f64,
    random_target: bool,
    extra_obstacles: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Arc<Scenario>, Arc<EnvModel>)> {
    let s = scenario_from_any(py, scenario)?;
    let opts = EnvOptions {
        assist: assist_of(py, assist, &s)?,
        reward_scale,
        random_target,
        extra_obstacles: crate::convert::cells(extra_obstacles, "extra_obstacles")?,
    };
    let model = run_attached(py, || EnvModel::new(&s, opts))?;
    Ok((s, Arc::new(model)))
}

/// A float64 array of shape ``(n, 3)`` (goals), flattened row-major, and its `n`.
fn goals_arg(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<f64>, usize)> {
    goal_rows(
        py,
        obj,
        name,
        "must be a float64 array of shape (n, 3) (normalised cells, one row per goal)",
    )
}

/// ``EnvModel::goal_rewards`` over NumPy arrays (the ``compute_reward`` of both engines).
fn goal_rewards<'py>(
    py: Python<'py>,
    model: &EnvModel,
    achieved_goal: &Bound<'py, PyAny>,
    desired_goal: &Bound<'py, PyAny>,
    collided: &Bound<'py, PyAny>,
    detour_penalty: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, n) = goals_arg(py, achieved_goal, "achieved_goal")?;
    let (d, m) = goals_arg(py, desired_goal, "desired_goal")?;
    if m != n {
        return Err(invalid_argument(
            py,
            "desired_goal",
            format!("array of shape ({m}, 3)"),
            format!("must have the shape of achieved_goal ({n}, 3)"),
        ));
    }
    let per = "one per goal pair";
    let c: Vec<bool> = column(py, collided, "collided", "bool", n, per)?;
    let p: Vec<f64> = column(py, detour_penalty, "detour_penalty", "float64", n, per)?;
    let r = run_attached(py, || model.goal_rewards(&a, &d, &c, &p))?;
    Ok(PyArray1::from_vec(py, r))
}

/// ``EnvModel::goal_cell`` over a ``(n, 3)`` float64 array: ``(n, 3)`` int64 cells.
fn goal_cells<'py>(
    py: Python<'py>,
    model: &EnvModel,
    goal: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let (g, n) = goals_arg(py, goal, "goal")?;
    if let Some(v) = g.iter().find(|v| !v.is_finite()) {
        return Err(invalid_argument(py, "goal", v, "must be finite numbers"));
    }
    let rows: Vec<Vec<i64>> = (0..n)
        .map(|i| {
            let c = model.goal_cell([g[3 * i], g[3 * i + 1], g[3 * i + 2]]);
            c.iter().map(|&v| v as i64).collect()
        })
        .collect();
    if n == 0 {
        return Ok(PyArray2::zeros(py, [0, 3], false));
    }
    Ok(PyArray2::from_vec2(py, &rows)?)
}

fn cell_of_state<'py>(
    py: Python<'py>,
    model: &EnvModel,
    state: usize,
) -> PyResult<Bound<'py, PyTuple>> {
    if state >= model.num_states() {
        return Err(invalid_argument(
            py,
            "state",
            state,
            format!("must be < num_states = {}", model.num_states()),
        ));
    }
    cell_tuple(py, model.world().cell_of(state))
}

fn cell_tuples<'py>(py: Python<'py>, cells: &[Cell]) -> PyResult<Vec<Bound<'py, PyTuple>>> {
    cells.iter().map(|c| cell_tuple(py, *c)).collect()
}

fn cell_tuple<'py>(py: Python<'py>, c: Cell) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(py, c)
}

fn action_of(py: Python<'_>, action: &Bound<'_, PyAny>) -> PyResult<usize> {
    match action.extract::<i64>() {
        Ok(a) if (0..6).contains(&a) => Ok(a as usize),
        _ => Err(invalid_argument(
            py,
            "action",
            repr(action),
            "must be an integer in 0..6 (0:+x 1:-x 2:+y 3:-y 4:+z 5:-z)",
        )),
    }
}

/// The `#[pymethods]` both grid engines have, over the one model they read
/// (`self.grid_model()`): the world's cells and obstacles, the reward settings and the
/// goal-reward functions. Added to the engine's own methods (`extra`) and handed to
/// `$emit!($($args)*, { items })`, as [`vec_pymethods!`] does.
macro_rules! grid_pymethods {
    ($emit:ident!($($args:tt)*), { $($extra:tt)* }) => {
        $emit!($($args)*, {
            $($extra)*

            /// Number of states (cells inside the bounds).
            #[getter]
            fn num_states(&self) -> usize {
                self.grid_model().num_states()
            }
            /// The cell of a state.
            fn cell_of<'py>(&self, py: Python<'py>, state: usize) -> PyResult<Bound<'py, PyTuple>> {
                cell_of_state(py, self.grid_model(), state)
            }
            /// The state of a cell, or None outside bounds.
            fn state_of(&self, c: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
                Ok(self.grid_model().world().state_of(cell(c, "cell")?))
            }
            /// All obstacle centres: the scenario's, then the extra ones.
            #[getter]
            fn obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
                cell_tuples(py, self.grid_model().world().obstacles())
            }
            /// The extra obstacles given at construction.
            #[getter]
            fn extra_obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
                cell_tuples(py, &self.grid_model().options().extra_obstacles)
            }
            /// The candidate targets: the cells random targets are drawn from (free, not the start).
            #[getter]
            fn target_candidates<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
                cell_tuples(py, &self.grid_model().target_candidates())
            }
            /// Rewards of ``n`` (achieved, desired) goal pairs (float64 ``(n, 3)`` each) given each
            /// step's ``collided`` (bool ``(n,)``) and ``detour_penalty`` (float64 ``(n,)``): the
            /// core's ``EnvModel::goal_rewards``, the step's own eqs. 5, 9, 10. ``(n,)`` float64.
            fn compute_reward<'py>(
                &self,
                py: Python<'py>,
                achieved_goal: &Bound<'py, PyAny>,
                desired_goal: &Bound<'py, PyAny>,
                collided: &Bound<'py, PyAny>,
                detour_penalty: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyArray1<f64>>> {
                goal_rewards(
                    py,
                    self.grid_model(),
                    achieved_goal,
                    desired_goal,
                    collided,
                    detour_penalty,
                )
            }
            /// The cells (int64 ``(n, 3)``) of normalised goals (float64 ``(n, 3)``).
            fn goal_to_cell<'py>(
                &self,
                py: Python<'py>,
                goal: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyArray2<i64>>> {
                goal_cells(py, self.grid_model(), goal)
            }
            /// The reward scale.
            #[getter]
            fn reward_scale(&self) -> f64 {
                self.grid_model().options().reward_scale
            }
            /// ``(detour, distance)``: which assisted-learning terms shape the reward.
            #[getter]
            fn assist(&self) -> (bool, bool) {
                let a = self.grid_model().options().assist;
                (a.detour, a.distance)
            }
        });
    };
}

/// One environment: episode state, observation and info. Used by `SixAxisAvoidEnv`.
#[pyclass(name = "EnvCore", module = "sixaxis_avoid._core")]
pub struct PyEnvCore {
    scenario: Arc<Scenario>,
    model: Arc<EnvModel>,
    ep: Episode,
    obs: ObsKind,
    /// States visited since the reset (start included), when tracking is on.
    path: Vec<u32>,
    track_path: bool,
}

impl PyEnvCore {
    fn grid_model(&self) -> &EnvModel {
        &self.model
    }

    fn observation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self.obs {
            ObsKind::Vector => {
                let mut buf = [0f32; VECTOR_OBS_DIM];
                self.ep.write_vector_obs(&self.model, &mut buf);
                PyArray1::from_slice(py, &buf).into_any()
            }
            ObsKind::Index => (self.ep.state() as i64).into_pyobject(py)?.into_any(),
        })
    }

    fn info<'py>(
        &self,
        py: Python<'py>,
        collided: bool,
        success: bool,
        detour: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item(intern!(py, "collided"), collided)?;
        d.set_item(
            intern!(py, "distance_to_target"),
            self.ep.distance_to_target(&self.model),
        )?;
        d.set_item(
            intern!(py, "cell"),
            cell_tuple(py, self.model.world().cell_of(self.ep.state()))?,
        )?;
        d.set_item(intern!(py, "is_success"), success)?;
        d.set_item(intern!(py, "detour_penalty"), detour)?;
        Ok(d)
    }
}

grid_pymethods!(
    impl_block!(
        #[pymethods]
        PyEnvCore
    ),
    {
        #[new]
        #[pyo3(signature = (scenario=None, *, obs="vector", assist=None, reward_scale=1.0, random_target=false, extra_obstacles=None, track_path=false))]
        #[allow(clippy::too_many_arguments)]
        fn py_new(
            py: Python<'_>,
            scenario: Option<&Bound<'_, PyAny>>,
            obs: &str,
            assist: Option<&Bound<'_, PyAny>>,
            reward_scale: f64,
            random_target: bool,
            extra_obstacles: Option<&Bound<'_, PyAny>>,
            track_path: bool,
        ) -> PyResult<Self> {
            let obs = obs_kind(py, obs)?;
            let (scenario, model) = build_model(
                py,
                scenario,
                assist,
                reward_scale,
                random_target,
                extra_obstacles,
            )?;
            let mut ep = Episode::new(&model);
            ep.reset(&model);
            Ok(PyEnvCore {
                scenario,
                path: vec![ep.state() as u32],
                model,
                ep,
                obs,
                track_path,
            })
        }

        /// Seed the generator of random targets.
        fn seed(&mut self, seed: u64) {
            self.ep.seed(seed);
        }

        /// Start a new episode: ``(observation, info)``.
        fn reset<'py>(
            &mut self,
            py: Python<'py>,
        ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
            let (ep, model) = (&mut self.ep, &self.model);
            run_attached(py, || {
                ep.reset(model);
                Ok(())
            })?;
            self.path.clear();
            self.path.push(self.ep.state() as u32);
            Ok((self.observation(py)?, self.info(py, false, false, 0.0)?))
        }

        /// One step: ``(observation, reward, terminated, info)``.
        fn step<'py>(
            &mut self,
            py: Python<'py>,
            action: &Bound<'py, PyAny>,
        ) -> PyResult<(Bound<'py, PyAny>, f64, bool, Bound<'py, PyDict>)> {
            let a = action_of(py, action)?;
            let (ep, model) = (&mut self.ep, &self.model);
            let out = run_attached(py, || Ok(ep.step(model, a)))?;
            if self.track_path && !out.collided {
                self.path.push(self.ep.state() as u32);
            }
            Ok((
                self.observation(py)?,
                out.reward,
                out.reached,
                self.info(py, out.collided, out.reached, out.detour_penalty)?,
            ))
        }

        /// The vector observation of the current state (whatever `obs` is).
        fn vector_observation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
            let mut buf = [0f32; VECTOR_OBS_DIM];
            self.ep.write_vector_obs(&self.model, &mut buf);
            PyArray1::from_slice(py, &buf)
        }

        /// The scenario.
        #[getter]
        fn scenario(&self) -> PyScenario {
            PyScenario {
                inner: self.scenario.clone(),
            }
        }
        /// The terminal's state number.
        #[getter]
        fn state(&self) -> usize {
            self.ep.state()
        }
        /// Steps since the reset.
        #[getter]
        fn steps(&self) -> u32 {
            self.ep.steps()
        }
        /// The terminal's cell.
        #[getter]
        fn cell<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
            cell_tuple(py, self.model.world().cell_of(self.ep.state()))
        }
        /// This episode's target cell.
        #[getter]
        fn target_cell<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
            cell_tuple(py, self.model.world().cell_of(self.ep.target()))
        }
        /// The start cell.
        #[getter]
        fn start_cell<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
            cell_tuple(py, self.model.world().cell_of(self.model.world().start()))
        }
        /// Blocked flag per state (the terminal collides there), as a bool array.
        #[getter]
        fn blocked<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
            let w = self.model.world();
            let v: Vec<bool> = (0..w.num_states()).map(|s| w.is_blocked(s)).collect();
            PyArray1::from_vec(py, v)
        }
        /// The cells visited since the reset, start included (only with ``track_path=True``).
        #[getter]
        fn path<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
            self.path
                .iter()
                .map(|&s| cell_tuple(py, self.model.world().cell_of(s as usize)))
                .collect()
        }
        /// `d_o`, distance from the start to this episode's target, cells.
        #[getter]
        fn start_distance(&self) -> f64 {
            self.ep.start_distance(&self.model)
        }
    }
);

/// N environments in one Rust object, stepped together into NumPy arrays it owns.
/// Used by `SixAxisAvoidVectorEnv`.
#[pyclass(name = "VecEnvCore", module = "sixaxis_avoid._core")]
pub struct PyVecEnvCore {
    batch: BatchEnv,
    arrays: GridArrays,
}

/// The arrays a `VecEnvCore` lends to its batch ([`BatchBuffers`]).
struct GridArrays {
    obs: ObsKind,
    obs_buf: Py<PyAny>,
    step: StepArrays,
    collided: Py<PyArray1<bool>>,
    distance: Py<PyArray1<f64>>,
    cells: Py<PyArray2<i32>>,
}

impl NumpyBuffers for GridArrays {
    type Lane = Episode;

    fn step_arrays(&self) -> &StepArrays {
        &self.step
    }

    fn lend<F>(&self, py: Python<'_>, f: F) -> PyResult<()>
    where
        F: for<'b> FnOnce(BatchBuffers<'b>) -> PyResult<()>,
    {
        let mut step = self.step.lease(py)?;
        let mut co = self.collided.bind(py).try_readwrite()?;
        let mut d = self.distance.bind(py).try_readwrite()?;
        let mut c = self.cells.bind(py).try_readwrite()?;
        let obs_any = self.obs_buf.bind(py);
        let mut of;
        let mut oi;
        let obs = match self.obs {
            ObsKind::Vector => {
                of = obs_any.cast::<PyArray2<f32>>()?.try_readwrite()?;
                ObsBuffer::Vector(of.as_slice_mut()?)
            }
            ObsKind::Index => {
                oi = obs_any.cast::<PyArray1<i64>>()?.try_readwrite()?;
                ObsBuffer::Index(oi.as_slice_mut()?)
            }
        };
        let rows = step.rows()?;
        f(BatchBuffers {
            obs,
            rewards: rows.rewards,
            terminated: rows.terminated,
            truncated: rows.truncated,
            collided: co.as_slice_mut()?,
            distance: d.as_slice_mut()?,
            cells: c.as_slice_mut()?,
            detour_penalty: rows.detour_penalty,
        })
    }
}

impl PyVecEnvCore {
    fn grid_model(&self) -> &EnvModel {
        self.batch.model()
    }
}

vec_pymethods!(
    grid_pymethods!(impl_block!(
        #[pymethods]
        PyVecEnvCore
    )),
    {
        #[new]
        #[pyo3(signature = (scenario=None, *, num_envs, max_episode_steps, obs="vector", assist=None, reward_scale=1.0, random_target=false, extra_obstacles=None))]
        #[allow(clippy::too_many_arguments)]
        fn py_new(
            py: Python<'_>,
            scenario: Option<&Bound<'_, PyAny>>,
            num_envs: i64,
            max_episode_steps: i64,
            obs: &str,
            assist: Option<&Bound<'_, PyAny>>,
            reward_scale: f64,
            random_target: bool,
            extra_obstacles: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<Self> {
            let obs = obs_kind(py, obs)?;
            if !(1..=(1 << 24)).contains(&num_envs) {
                return Err(invalid_argument(
                    py,
                    "num_envs",
                    num_envs,
                    "must be in 1..=16777216",
                ));
            }
            if !(1..=u32::MAX as i64).contains(&max_episode_steps) {
                return Err(invalid_argument(
                    py,
                    "max_episode_steps",
                    max_episode_steps,
                    "must be a positive integer",
                ));
            }
            let n = num_envs as usize;
            let (_, model) = build_model(
                py,
                scenario,
                assist,
                reward_scale,
                random_target,
                extra_obstacles,
            )?;
            let batch = run_attached(py, || BatchEnv::new(model, n, max_episode_steps as u32))?;
            let obs_buf = match obs {
                ObsKind::Vector => {
                    PyArray2::<f32>::zeros(py, [n, VECTOR_OBS_DIM], false).into_any()
                }
                ObsKind::Index => PyArray1::<i64>::zeros(py, n, false).into_any(),
            };
            Ok(PyVecEnvCore {
                batch,
                arrays: GridArrays {
                    obs,
                    obs_buf: obs_buf.unbind(),
                    step: StepArrays::new(py, n),
                    collided: PyArray1::from_vec(py, vec![false; n]).unbind(),
                    distance: PyArray1::zeros(py, n, false).unbind(),
                    cells: PyArray2::zeros(py, [n, 3], false).unbind(),
                },
            })
        }

        /// Seed each env's generator of random targets (one seed per env).
        fn seed(&mut self, py: Python<'_>, seeds: &Bound<'_, PyAny>) -> PyResult<()> {
            let seeds: Vec<u64> = bounded_vec(seeds, self.batch.len() + 1).ok_or_else(|| {
                invalid_argument(
                    py,
                    "seed",
                    repr(seeds),
                    format!("must be {} integers in 0..2**64", self.batch.len()),
                )
            })?;
            run_attached(py, || self.batch.seed(&seeds))
        }

        /// Step all envs with `actions` (int64, one per env), writing into the buffers; the GIL
        /// is released meanwhile.
        fn step(&mut self, py: Python<'_>, actions: PyReadonlyArray1<'_, i64>) -> PyResult<()> {
            if actions.len() != self.batch.len() {
                return Err(invalid_argument(
                    py,
                    "actions",
                    format!("array of shape {:?}", actions.shape()),
                    format!("must have shape ({},)", self.batch.len()),
                ));
            }
            let mut owned = Vec::new();
            let acts = row_major(&actions, &mut owned);
            call(py, &mut self.batch, &self.arrays, |b, bufs| {
                b.step(acts, bufs)
            })
        }

        #[getter]
        fn max_episode_steps(&self) -> u32 {
            self.batch.max_episode_steps()
        }
        /// Observation buffer: ``(n, 13)`` float32 or ``(n,)`` int64.
        #[getter]
        fn observations(&self, py: Python<'_>) -> Py<PyAny> {
            self.arrays.obs_buf.clone_ref(py)
        }
        #[getter]
        fn collided(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
            self.arrays.collided.clone_ref(py)
        }
        #[getter]
        fn distance_to_target(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
            self.arrays.distance.clone_ref(py)
        }
        #[getter]
        fn cells(&self, py: Python<'_>) -> Py<PyArray2<i32>> {
            self.arrays.cells.clone_ref(py)
        }
        /// Whether each reset draws a random target.
        #[getter]
        fn random_target(&self) -> bool {
            self.batch.model().options().random_target
        }
        /// Each env's current target cell, ``(n, 3)``.
        #[getter]
        fn current_targets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i32>>> {
            let w = self.batch.model().world();
            let v: Vec<Vec<i32>> = self
                .batch
                .episodes()
                .iter()
                .map(|e| w.cell_of(e.target()).to_vec())
                .collect();
            Ok(PyArray2::from_vec2(py, &v)?)
        }
    }
);
