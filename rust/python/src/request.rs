//! Python keywords -> the core's requests ([`sixaxis_core::request`]): only the conversion
//! of each value's Python type happens here; ranges, defaults and the rules that combine
//! keywords are the core's, shared with the `sixaxis` CLI.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyInt, PyString};
use sixaxis_core::request::{
    in_domain, int_domain, TrainRequest, EPISODES, EPISODE_CAP, MAX_STEPS, SEED,
};

use crate::convert::repr;
use crate::errors::invalid_argument;

/// An integer keyword (bools and non-integers rejected with the core's words), or `None`.
pub fn int_kw(
    py: Python<'_>,
    domain: (&str, i128, i128),
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<i128>> {
    let Some(o) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let (name, min, max) = domain;
    let bad = || invalid_argument(py, name, repr(o), int_domain(min, max));
    if o.is_instance_of::<PyBool>() {
        return Err(bad());
    }
    // Python ints and integer-like objects (numpy integers) through __index__.
    let as_int = if o.is_instance_of::<PyInt>() {
        o.clone()
    } else {
        o.call_method0("__index__").map_err(|_| bad())?
    };
    as_int.extract::<i128>().map(Some).map_err(|_| bad())
}

/// A bool keyword (`True`, `False`, a numpy bool, or `None`).
pub fn bool_kw(
    py: Python<'_>,
    name: &str,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<bool>> {
    let Some(o) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let is_numpy_bool = o
        .get_type()
        .name()
        .map(|n| n == "bool" || n == "bool_")
        .unwrap_or(false);
    if o.is_instance_of::<PyBool>() || is_numpy_bool {
        return o.is_truthy().map(Some);
    }
    Err(invalid_argument(
        py,
        name,
        repr(o),
        "must be True, False or None",
    ))
}

/// The keywords `train` and `plan` share, as a training request.
#[allow(clippy::too_many_arguments)]
pub fn train_request(
    py: Python<'_>,
    episodes: Option<&Bound<'_, PyAny>>,
    episode_cap: Option<&Bound<'_, PyAny>>,
    seed: Option<&Bound<'_, PyAny>>,
    assist: Option<&Bound<'_, PyAny>>,
    detour: Option<&Bound<'_, PyAny>>,
    distance: Option<&Bound<'_, PyAny>>,
    max_steps_per_episode: Option<&Bound<'_, PyAny>>,
    initial_q: Option<&Bound<'_, PyAny>>,
    q_precision: Option<&Bound<'_, PyAny>>,
) -> PyResult<TrainRequest> {
    // `episodes="auto"`: train until the greedy path settles (the core's rule).
    let auto = match episodes {
        Some(e) if e.is_instance_of::<PyString>() => e.extract::<String>()? == "auto",
        _ => false,
    };
    Ok(TrainRequest {
        episodes: if auto {
            None
        } else {
            int_kw(py, EPISODES, episodes)?
        },
        episodes_auto: auto.then_some(true),
        episode_cap: int_kw(py, EPISODE_CAP, episode_cap)?,
        seed: int_kw(py, SEED, seed)?,
        assist: bool_kw(py, "assist", assist)?,
        detour: bool_kw(py, "detour", detour)?,
        distance: bool_kw(py, "distance", distance)?,
        max_steps_per_episode: int_kw(py, MAX_STEPS, max_steps_per_episode)?,
        initial_q: str_kw(
            py,
            "initial_q",
            initial_q,
            "must be \"zero\", \"distance\" or None",
        )?,
        q_precision: str_kw(
            py,
            "q_precision",
            q_precision,
            "must be \"f64\", \"f32\" or None",
        )?,
    })
}

/// A string keyword (the core checks the name), or `None`; anything else is rejected with
/// `reason`.
pub fn str_kw(
    py: Python<'_>,
    name: &str,
    obj: Option<&Bound<'_, PyAny>>,
    reason: &str,
) -> PyResult<Option<String>> {
    match obj.filter(|o| !o.is_none()) {
        None => Ok(None),
        Some(o) => match o.cast::<PyString>() {
            Ok(t) => Ok(Some(t.to_string())),
            Err(_) => Err(invalid_argument(py, name, repr(o), reason)),
        },
    }
}

/// [`int_kw`], then checked against its domain (for keywords no core request resolves).
pub fn int_in(
    py: Python<'_>,
    domain: (&str, i128, i128),
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<i128>> {
    int_kw(py, domain, obj)?
        .map(|v| crate::errors::run_attached(py, || in_domain(domain, v)))
        .transpose()
}
