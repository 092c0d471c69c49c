//! `env_tables`: a scenario's env as NumPy arrays (`sixaxis_core::tables`), for the JAX twin.

use numpy::{IntoPyArray, PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sixaxis_core::env::ENV_OPTIONS;
use sixaxis_core::options::OptionInfo;
use sixaxis_core::tables::{EnvTables, NO_MEMORY, NUM_CASES, NUM_MEMORIES, TABLE_KEYS};

use crate::errors::run;
use crate::request::options_of;
use crate::scenario::scenario_from_any;

/// A flat vector as an array of `shape`.
fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    v: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let a: Bound<'py, PyArray1<T>> = v.into_pyarray(py);
    Ok(a.reshape(shape)?.into_any())
}

/// The scenario's env as arrays (``sixaxis_core::tables``; the layout is documented in
/// ``sixaxis_avoid.jax`` and docs/BENCHMARKS.md, "JAX twin"): a dict of NumPy arrays.
/// Keywords: those of the Gymnasium env that change its dynamics (``assist``,
/// ``reward_scale``, ``random_target``, ``arm_aware``, ``max_episode_steps``), checked by
/// the env's option table; ``None`` takes the env's default.
#[pyfunction]
#[pyo3(signature = (scenario=None, **env_options))]
pub fn env_tables<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
    env_options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = scenario_from_any(py, scenario)?;
    let infos: Vec<OptionInfo> = ENV_OPTIONS
        .iter()
        .filter(|o| TABLE_KEYS.contains(&o.key))
        .map(|o| o.info)
        .collect();
    let opts = options_of(py, "env_tables", &infos, env_options)?;
    let t = run(py, move || EnvTables::new(&s, &opts))?;
    let (n, nt, a) = (t.num_states, t.num_targets, 6);
    let d = PyDict::new(py);
    d.set_item("next_state", array(py, t.next_state, &[n, a])?)?;
    d.set_item("collided", array(py, t.collided, &[n, a])?)?;
    d.set_item("next_memory", array(py, t.next_memory, &[a, 2])?)?;
    d.set_item(
        "reward_case",
        array(py, t.reward_case, &[NUM_MEMORIES, a, 2])?,
    )?;
    d.set_item("rewards", array(py, t.rewards, &[nt, n, NUM_CASES])?)?;
    d.set_item("terminates", array(py, t.terminates, &[nt, n, NUM_CASES])?)?;
    d.set_item("obs_state", array(py, t.obs_state, &[n, 13])?)?;
    d.set_item("obs_target", array(py, t.obs_target, &[nt, 13])?)?;
    d.set_item("obs_memory", array(py, t.obs_memory, &[NUM_MEMORIES, 13])?)?;
    d.set_item("cells", array(py, t.cells, &[n, 3])?)?;
    d.set_item("target_states", array(py, t.target_states, &[nt])?)?;
    d.set_item("target_cells", array(py, t.target_cells, &[nt, 3])?)?;
    d.set_item("start_state", array(py, vec![t.start_state], &[])?)?;
    d.set_item(
        "max_episode_steps",
        array(py, vec![t.max_episode_steps as i64], &[])?,
    )?;
    d.set_item("random_target", array(py, vec![t.random_target], &[])?)?;
    d.set_item("no_memory", array(py, vec![NO_MEMORY], &[])?)?;
    Ok(d)
}
