//! The engines behind the joint-space envs: `JointEnvCore` (one env) and `JointVecEnvCore`
//! (a batch), both over `sixaxis_core::joint_env`. Keywords are the core's
//! `JOINT_ENV_OPTIONS`, converted by `request::options_of` and read by
//! `JointOptions::from_options`.

use std::sync::Arc;

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sixaxis_core::joint_env::{
    JointBatch, JointBuffers, JointEpisode, JointModel, JointOptions, JOINT_ENV_OPTIONS,
};
use sixaxis_core::options::OptionInfo;
use sixaxis_core::Scenario;

use crate::convert::{column, goal_rows, repr};
use crate::errors::{invalid_argument, run, run_attached};
use crate::scenario::{scenario_from_any, PyScenario};
use crate::vec_core::{call, row_major, vec_pymethods, NumpyBuffers, StepArrays};

fn build_model(
    py: Python<'_>,
    scenario: Option<&Bound<'_, PyAny>>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Arc<Scenario>, Arc<JointModel>)> {
    let s = scenario_from_any(py, scenario)?;
    let infos: Vec<OptionInfo> = JOINT_ENV_OPTIONS.iter().map(|o| o.info).collect();
    let values = crate::request::options_of(py, "JointEnvCore", &infos, kwargs)?;
    let model = run_attached(py, || {
        JointModel::new(&s, JointOptions::from_options(&values)?)
    })?;
    Ok((s, Arc::new(model)))
}

/// Six numbers of one action from any float array or sequence; the error names `action`.
fn action_of(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<[f64; 6]> {
    let v: Option<Vec<f64>> = if let Ok(a) = obj.extract::<PyReadonlyArray1<'_, f64>>() {
        Some(a.as_array().to_vec())
    } else if let Ok(a) = obj.extract::<PyReadonlyArray1<'_, f32>>() {
        Some(a.as_array().iter().map(|&x| x as f64).collect())
    } else {
        obj.extract::<Vec<f64>>().ok()
    };
    match v {
        Some(v) if v.len() == 6 => {
            let a: [f64; 6] = std::array::from_fn(|i| v[i]);
            run_attached(py, || JointModel::check_action("action", &a))?;
            Ok(a)
        }
        _ => Err(invalid_argument(
            py,
            "action",
            repr(obj),
            "must be six numbers in [-1, 1] (one per joint)",
        )),
    }
}

/// A float32 array of shape `(n, 3)` (goals), flattened, and its `n`.
fn goals_arg(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<f32>, usize)> {
    goal_rows(
        py,
        obj,
        name,
        "must be a float32 array of shape (n, 3) (positions / reach, one row per transition)",
    )
}

/// `JointModel::goal_rewards` over NumPy arrays (`compute_reward` of both engines).
fn goal_rewards<'py>(
    py: Python<'py>,
    model: &JointModel,
    previous: &Bound<'py, PyAny>,
    achieved: &Bound<'py, PyAny>,
    desired: &Bound<'py, PyAny>,
    refused: &Bound<'py, PyAny>,
    detour_penalty: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, n) = goals_arg(py, achieved, "achieved_goal")?;
    let (p, np_) = goals_arg(py, previous, "previous_achieved_goal")?;
    let (d, nd) = goals_arg(py, desired, "desired_goal")?;
    for (name, m) in [("previous_achieved_goal", np_), ("desired_goal", nd)] {
        if m != n {
            return Err(invalid_argument(
                py,
                name,
                format!("array of shape ({m}, 3)"),
                format!("must have the shape of achieved_goal ({n}, 3)"),
            ));
        }
    }
    let per = "one per transition";
    let r: Vec<bool> = column(py, refused, "refused", "bool", n, per)?;
    let dp: Vec<f64> = column(py, detour_penalty, "detour_penalty", "float64", n, per)?;
    let out = run_attached(py, || model.goal_rewards(&p, &a, &d, &r, &dp))?;
    Ok(PyArray1::from_vec(py, out))
}

/// The observation layout as a dict of `(start, end)` index pairs (`refused`: an index).
fn layout<'py>(py: Python<'py>, model: &JointModel) -> PyResult<Bound<'py, PyDict>> {
    let l = model.obs_layout();
    let d = PyDict::new(py);
    for (k, r) in [
        ("sin", l.sin),
        ("cos", l.cos),
        ("terminal", l.terminal),
        ("target", l.target),
        ("clearance", l.clearance),
        ("direction", l.direction),
    ] {
        d.set_item(k, (r.start, r.end))?;
    }
    d.set_item("refused", l.refused)?;
    Ok(d)
}

/// The `#[pymethods]` of an engine: its own (`extra`) and those both share, over `$model` (an expression giving `&JointModel`).
macro_rules! joint_pymethods {
    (#[$attr:meta] $t:ty, |$s:ident| $model:expr, { $($extra:tt)* }) => {
        #[$attr]
        impl $t {
            $($extra)*

            /// Length of the observation (22 + number of links).
            #[getter]
            fn obs_dim(&self) -> usize {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.obs_dim()
            }
            /// Where each field sits in the observation: ``(start, end)`` per field.
            #[getter]
            fn obs_layout<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                layout(py, m)
            }
            /// Number of links (one clearance each).
            #[getter]
            fn num_links(&self) -> usize {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.num_links()
            }
            /// The polyline segments that are links (``k``: points ``k -> k + 1``).
            #[getter]
            fn links(&self) -> Vec<usize> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.links().to_vec()
            }
            /// The arm's reach (polyline length), mm: goals are positions / reach.
            #[getter]
            fn reach_mm(&self) -> f64 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.reach_mm()
            }
            /// The safe distance in use, mm.
            #[getter]
            fn safe_distance_mm(&self) -> f64 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.safe_distance_mm()
            }
            /// The link capsule radius in use, mm.
            #[getter]
            fn link_radius_mm(&self) -> f64 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.link_radius_mm()
            }
            /// The target, mm.
            #[getter]
            fn target_mm(&self) -> (f64, f64, f64) {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                let t = m.target_mm();
                (t.x, t.y, t.z)
            }
            /// beta_0, radians.
            #[getter]
            fn beta0_rad(&self) -> Vec<f64> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.beta0_rad().to_vec()
            }
            /// Joint limits, radians: ``[[low, high]] * 6``.
            #[getter]
            fn joint_limits_rad(&self) -> Vec<[f64; 2]> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.limits_rad().to_vec()
            }
            /// The step cap (``max_episode_steps``).
            #[getter]
            fn max_episode_steps(&self) -> u32 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.options().max_episode_steps
            }
            /// The model's keywords and their values (``None``: left to the scenario), the
            /// keys of ``options("joint")`` that configure the model.
            #[getter]
            fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                let d = PyDict::new(py);
                for (key, v) in m.options().values() {
                    match v {
                        Some(v) => d.set_item(key, crate::request::value_to_py(py, &v)?)?,
                        None => d.set_item(key, py.None())?,
                    }
                }
                Ok(d)
            }
            /// The largest joint increment of a step, degrees.
            #[getter]
            fn max_joint_step_deg(&self) -> f64 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.options().max_joint_step_deg
            }
            /// The termination distance, mm.
            #[getter]
            fn target_tolerance_mm(&self) -> f64 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.options().target_tolerance_mm
            }
            /// Whether the pose ``q`` (six angles, rad) is clear (gap > safe distance).
            fn pose_is_clear(&self, py: Python<'_>, q: [f64; 6]) -> PyResult<bool> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                run(py, || Ok(m.pose_is_clear(&q)))
            }
            /// Each link's exact capsule gap (mm) at pose ``q`` (rad): the core's clearance.
            fn link_gaps_mm(&self, py: Python<'_>, q: [f64; 6]) -> PyResult<Vec<f64>> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                run(py, || {
                    let mut out = vec![0.0; m.num_links()];
                    m.link_gaps_mm(&m.arm().points_mm(&q), &mut out);
                    Ok(out)
                })
            }
            /// Sub-steps the move ``from_q -> to_q`` (rad) is checked at.
            fn substeps(&self, from_q: [f64; 6], to_q: [f64; 6]) -> u32 {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                m.substeps(&from_q, &to_q)
            }
            /// Rewards of ``n`` relabelled transitions: goals float32 ``(n, 3)`` each,
            /// ``refused`` bool ``(n,)``, ``detour_penalty`` float64 ``(n,)``; the step's
            /// own arithmetic (the core's ``JointModel::goal_rewards``). ``(n,)`` float64.
            fn compute_reward<'py>(
                &self,
                py: Python<'py>,
                previous_achieved_goal: &Bound<'py, PyAny>,
                achieved_goal: &Bound<'py, PyAny>,
                desired_goal: &Bound<'py, PyAny>,
                refused: &Bound<'py, PyAny>,
                detour_penalty: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyArray1<f64>>> {
                let m: &JointModel = {
                    let $s = self;
                    $model
                };
                goal_rewards(
                    py,
                    m,
                    previous_achieved_goal,
                    achieved_goal,
                    desired_goal,
                    refused,
                    detour_penalty,
                )
            }
        }
    };
}

/// What `JointEnvCore.step` returns: observation, reward, terminated, info.
type StepResult<'py> = (Bound<'py, PyArray1<f32>>, f64, bool, Bound<'py, PyDict>);

/// One joint-space env. Used by `SixAxisAvoidJointEnv`.
#[pyclass(name = "JointEnvCore", module = "sixaxis_avoid._core")]
pub struct PyJointEnvCore {
    scenario: Arc<Scenario>,
    model: Arc<JointModel>,
    ep: JointEpisode,
}

impl PyJointEnvCore {
    fn observation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        let mut buf = vec![0f32; self.model.obs_dim()];
        self.ep.write_obs(&self.model, &mut buf);
        PyArray1::from_vec(py, buf)
    }

    fn info<'py>(
        &self,
        py: Python<'py>,
        success: bool,
        detour: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let m = &self.model;
        d.set_item(intern!(py, "is_success"), success)?;
        d.set_item(intern!(py, "clearance"), self.ep.clearance_mm(m))?;
        d.set_item(intern!(py, "refused"), self.ep.refused())?;
        d.set_item(
            intern!(py, "distance_to_target"),
            self.ep.distance_to_target_mm(m),
        )?;
        d.set_item(intern!(py, "detour_penalty"), detour)?;
        d.set_item(
            intern!(py, "previous_achieved_goal"),
            PyArray1::from_slice(py, &self.ep.previous_goal()),
        )?;
        Ok(d)
    }
}

joint_pymethods!(
    #[pymethods]
    PyJointEnvCore,
    |s| &s.model,
    {
        /// ``JointEnvCore(scenario=None, options=None)``: ``options`` is a dict of the
        /// keywords of the core's ``JOINT_ENV_OPTIONS`` that configure the model (as
        /// ``check_options("joint", ...)`` returns them).
        #[new]
        #[pyo3(signature = (scenario=None, options=None))]
        fn py_new(
            py: Python<'_>,
            scenario: Option<&Bound<'_, PyAny>>,
            options: Option<&Bound<'_, PyDict>>,
        ) -> PyResult<Self> {
            let (scenario, model) = build_model(py, scenario, options)?;
            let ep = JointEpisode::new(&model);
            Ok(PyJointEnvCore {
                scenario,
                model,
                ep,
            })
        }

        /// Start a new episode at beta_0: ``(observation, info)``.
        fn reset<'py>(
            &mut self,
            py: Python<'py>,
        ) -> PyResult<(Bound<'py, PyArray1<f32>>, Bound<'py, PyDict>)> {
            self.ep.reset(&self.model);
            Ok((self.observation(py), self.info(py, false, 0.0)?))
        }

        /// One step: ``(observation, reward, terminated, info)``.
        fn step<'py>(
            &mut self,
            py: Python<'py>,
            action: &Bound<'py, PyAny>,
        ) -> PyResult<StepResult<'py>> {
            let a = action_of(py, action)?;
            let (ep, model) = (&mut self.ep, &self.model);
            let out = run_attached(py, || ep.step(model, &a))?;
            Ok((
                self.observation(py),
                out.reward,
                out.reached,
                self.info(py, out.reached, out.detour_penalty)?,
            ))
        }

        /// The scenario.
        #[getter]
        fn scenario(&self) -> PyScenario {
            PyScenario {
                inner: self.scenario.clone(),
            }
        }
        /// The joint angles, radians.
        #[getter]
        fn joints(&self) -> Vec<f64> {
            self.ep.joints_rad().to_vec()
        }
        /// The terminal's position, mm.
        #[getter]
        fn terminal_mm(&self) -> (f64, f64, f64) {
            let t = self.ep.terminal_mm();
            (t.x, t.y, t.z)
        }
        /// Steps since the reset.
        #[getter]
        fn steps(&self) -> u32 {
            self.ep.steps()
        }
    }
);

/// N joint-space envs in one Rust object, stepped together into NumPy arrays it owns.
/// Used by `SixAxisAvoidJointVectorEnv`.
#[pyclass(name = "JointVecEnvCore", module = "sixaxis_avoid._core")]
pub struct PyJointVecEnvCore {
    batch: JointBatch,
    arrays: JointArrays,
}

/// The arrays a `JointVecEnvCore` lends to its batch ([`JointBuffers`]).
struct JointArrays {
    obs: Py<PyArray2<f32>>,
    step: StepArrays,
    refused: Py<PyArray1<bool>>,
    distance: Py<PyArray1<f64>>,
    clearance: Py<PyArray1<f64>>,
    joints: Py<PyArray2<f64>>,
    terminal: Py<PyArray2<f64>>,
    previous_goal: Py<PyArray2<f32>>,
}

impl NumpyBuffers for JointArrays {
    type Lane = JointEpisode;

    fn step_arrays(&self) -> &StepArrays {
        &self.step
    }

    fn lend<F>(&self, py: Python<'_>, f: F) -> PyResult<()>
    where
        F: for<'b> FnOnce(JointBuffers<'b>) -> PyResult<()>,
    {
        let mut o = self.obs.bind(py).try_readwrite()?;
        let mut step = self.step.lease(py)?;
        let mut rf = self.refused.bind(py).try_readwrite()?;
        let mut d = self.distance.bind(py).try_readwrite()?;
        let mut c = self.clearance.bind(py).try_readwrite()?;
        let mut j = self.joints.bind(py).try_readwrite()?;
        let mut t = self.terminal.bind(py).try_readwrite()?;
        let mut pg = self.previous_goal.bind(py).try_readwrite()?;
        let rows = step.rows()?;
        f(JointBuffers {
            obs: o.as_slice_mut()?,
            rewards: rows.rewards,
            terminated: rows.terminated,
            truncated: rows.truncated,
            refused: rf.as_slice_mut()?,
            distance_mm: d.as_slice_mut()?,
            clearance_mm: c.as_slice_mut()?,
            detour_penalty: rows.detour_penalty,
            joints: j.as_slice_mut()?,
            terminal_mm: t.as_slice_mut()?,
            previous_goal: pg.as_slice_mut()?,
        })
    }
}

vec_pymethods!(
    joint_pymethods!(
        #[pymethods]
        PyJointVecEnvCore,
        |s| &**s.batch.model()
    ),
    {
        /// ``JointVecEnvCore(scenario=None, *, num_envs, options=None)`` (``options``: as
        /// ``JointEnvCore``'s; its ``max_episode_steps`` truncates here).
        #[new]
        #[pyo3(signature = (scenario=None, *, num_envs, options=None))]
        fn py_new(
            py: Python<'_>,
            scenario: Option<&Bound<'_, PyAny>>,
            num_envs: &Bound<'_, PyAny>,
            options: Option<&Bound<'_, PyDict>>,
        ) -> PyResult<Self> {
            let info = JOINT_ENV_OPTIONS
                .iter()
                .find(|i| i.key == "num_envs")
                .expect("in the table");
            let n = crate::request::int_kw(py, "num_envs", &info.domain, Some(num_envs))?
                .ok_or_else(|| invalid_argument(py, "num_envs", "None", info.domain.reason()))?;
            let (_, model) = build_model(py, scenario, options)?;
            let n = usize::try_from(n)
                .map_err(|_| invalid_argument(py, "num_envs", n, info.domain.reason()))?;
            let d = model.obs_dim();
            let batch = run_attached(py, || JointBatch::new(model, n))?;
            Ok(PyJointVecEnvCore {
                batch,
                arrays: JointArrays {
                    obs: PyArray2::zeros(py, [n, d], false).unbind(),
                    step: StepArrays::new(py, n),
                    refused: PyArray1::from_vec(py, vec![false; n]).unbind(),
                    distance: PyArray1::zeros(py, n, false).unbind(),
                    clearance: PyArray1::zeros(py, n, false).unbind(),
                    joints: PyArray2::zeros(py, [n, 6], false).unbind(),
                    terminal: PyArray2::zeros(py, [n, 3], false).unbind(),
                    previous_goal: PyArray2::zeros(py, [n, 3], false).unbind(),
                },
            })
        }

        /// Step all envs with ``actions`` (float64 ``(num_envs, 6)``, each in [-1, 1]),
        /// writing into the buffers; the GIL is released meanwhile.
        fn step(&mut self, py: Python<'_>, actions: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
            let n = self.batch.len();
            if actions.shape() != [n, 6] {
                return Err(invalid_argument(
                    py,
                    "actions",
                    format!("array of shape {:?}", actions.shape()),
                    format!("must have shape ({n}, 6)"),
                ));
            }
            let mut owned = Vec::new();
            let acts = row_major(&actions, &mut owned);
            call(py, &mut self.batch, &self.arrays, |b, bufs| {
                b.step(acts, bufs)
            })
        }

        /// Observations ``(n, obs_dim)`` float32 (the buffer, overwritten by every call).
        #[getter]
        fn observations(&self, py: Python<'_>) -> Py<PyArray2<f32>> {
            self.arrays.obs.clone_ref(py)
        }
        /// Whether each env's last step was refused.
        #[getter]
        fn refused(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
            self.arrays.refused.clone_ref(py)
        }
        /// Terminal-target distance, mm.
        #[getter]
        fn distance_to_target(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
            self.arrays.distance.clone_ref(py)
        }
        /// Smallest link capsule gap, mm.
        #[getter]
        fn clearance(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
            self.arrays.clearance.clone_ref(py)
        }
        /// Joint angles, radians, ``(n, 6)``.
        #[getter]
        fn joints(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
            self.arrays.joints.clone_ref(py)
        }
        /// Terminal positions, mm, ``(n, 3)``.
        #[getter]
        fn terminal_mm(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
            self.arrays.terminal.clone_ref(py)
        }
        /// The achieved goal before each env's last step, ``(n, 3)`` float32.
        #[getter]
        fn previous_achieved_goal(&self, py: Python<'_>) -> Py<PyArray2<f32>> {
            self.arrays.previous_goal.clone_ref(py)
        }
    }
);
