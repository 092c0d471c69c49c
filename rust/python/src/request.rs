//! Python keywords -> the core's options ([`sixaxis_core::options`],
//! [`sixaxis_core::request`]): the keywords are the keys of the core's tables, and only the
//! conversion of each value's Python type happens here; ranges, defaults and the rules that
//! combine keywords are the core's, shared with the `sixaxis` CLI.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};
use sixaxis_core::env::{ENV_NULLABLE, ENV_OPTIONS};
use sixaxis_core::generator::{generator_options, GeneratorOptions, GENERATOR_OPTIONS};
use sixaxis_core::joint_env::{JOINT_ENV_OPTIONS, JOINT_NULLABLE};
use sixaxis_core::options::{check_value, Domain, OptionInfo, OptionValue, Options};
use sixaxis_core::request::{option_values, plan_options, train_options, TrainRequest};
use sixaxis_core::Scenario;

use crate::convert::repr;
use crate::errors::{invalid_argument, run_attached};

fn is_numpy_bool(o: &Bound<'_, PyAny>) -> bool {
    o.get_type()
        .name()
        .map(|n| n == "bool" || n == "bool_")
        .unwrap_or(false)
}

/// An integer keyword (bools and non-integers rejected with the domain's words), or `None`.
pub fn int_kw(
    py: Python<'_>,
    name: &str,
    domain: &Domain,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<i128>> {
    let Some(o) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let bad = || invalid_argument(py, name, repr(o), domain.reason());
    if o.is_instance_of::<PyBool>() || is_numpy_bool(o) {
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
    if o.is_instance_of::<PyBool>() || is_numpy_bool(o) {
        return o.is_truthy().map(Some);
    }
    Err(invalid_argument(
        py,
        name,
        repr(o),
        "must be True, False or None",
    ))
}

/// The value of one keyword of option `info`, converted by its domain's kind (not yet
/// checked against the domain: the core does that).
fn value_of(
    py: Python<'_>,
    info: &OptionInfo,
    o: &Bound<'_, PyAny>,
) -> PyResult<Option<OptionValue>> {
    if o.is_none() {
        return Ok(None);
    }
    let key = info.key;
    let bad = || invalid_argument(py, key, repr(o), info.domain.reason());
    Ok(Some(match info.domain {
        Domain::Bool => OptionValue::Bool(bool_kw(py, key, Some(o))?.unwrap_or_default()),
        Domain::Int { .. } => {
            OptionValue::Int(int_kw(py, key, &info.domain, Some(o))?.unwrap_or_default())
        }
        Domain::IntOrAuto { .. } => match o.cast::<PyString>() {
            Ok(t) => OptionValue::Text(t.to_string()),
            Err(_) => OptionValue::Int(int_kw(py, key, &info.domain, Some(o))?.unwrap_or_default()),
        },
        Domain::Float { .. } => {
            if o.is_instance_of::<PyBool>() || is_numpy_bool(o) {
                return Err(bad());
            }
            if o.is_instance_of::<PyInt>() {
                OptionValue::Int(o.extract::<i128>().map_err(|_| bad())?)
            } else if o.is_instance_of::<PyFloat>() || o.hasattr("__float__")? {
                OptionValue::Float(o.extract::<f64>().map_err(|_| bad())?)
            } else {
                return Err(bad());
            }
        }
        Domain::Choice(_) | Domain::Text => match o.cast::<PyString>() {
            Ok(t) => OptionValue::Text(t.to_string()),
            Err(_) => return Err(bad()),
        },
    }))
}

/// The options of `kwargs` (the keywords of function `function`) as the core's
/// [`Options`]; a keyword `infos` does not have is a `TypeError`, as Python gives for an
/// unknown keyword.
pub fn options_of(
    py: Python<'_>,
    function: &str,
    infos: &[OptionInfo],
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Options> {
    let mut out = Options::new();
    let Some(kwargs) = kwargs else {
        return Ok(out);
    };
    for (k, v) in kwargs.iter() {
        let key: String = k.extract()?;
        let Some(info) = infos.iter().find(|i| i.key == key) else {
            let keys: Vec<&str> = infos.iter().map(|i| i.key).collect();
            return Err(PyTypeError::new_err(format!(
                "{function}() got an unexpected keyword argument '{key}' (its options: {})",
                keys.join(", ")
            )));
        };
        if let Some(value) = value_of(py, info, &v)? {
            out.insert(key, value);
        }
    }
    Ok(out)
}

/// The keywords of :func:`train` (and `assist` of the envs) as a training request.
pub fn train_request(
    py: Python<'_>,
    function: &str,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<TrainRequest> {
    Ok(TrainRequest(options_of(
        py,
        function,
        &train_options(),
        kwargs,
    )?))
}

/// [`int_kw`], then checked against its domain (for keywords no core request resolves).
pub fn int_in(
    py: Python<'_>,
    name: &str,
    domain: &Domain,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<i128>> {
    int_kw(py, name, domain, obj)?
        .map(|v| {
            run_attached(py, || {
                <u64 as sixaxis_core::options::FromOption>::from_option(
                    name,
                    domain,
                    &OptionValue::Int(v),
                )
                .map(|_| v)
            })
        })
        .transpose()
}

pub fn value_to_py<'py>(py: Python<'py>, v: &OptionValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        OptionValue::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        OptionValue::Int(i) => i.into_pyobject(py)?.into_any(),
        OptionValue::Float(x) => PyFloat::new(py, *x).into_any(),
        OptionValue::Text(t) => PyString::new(py, t).into_any(),
    })
}

/// The options of :func:`train` (``"train"``), :func:`plan` (``"plan"``) or
/// :func:`generate_scenario` (``"generate_scenario"``; defaults its own) or of the
/// grid Gymnasium envs (``"env"``) or of the joint-space envs (``"joint"``; their keywords,
/// ``default`` None where None is the default) as a list of
/// dicts, one per keyword, in the order they apply: ``key``, ``field`` (the scenario field
/// it overrides, or ``""``), ``kind`` (``int``, ``int|auto``, ``float``, ``bool``,
/// ``choice``), ``min``/``max`` (numbers), ``choices`` (names), ``unit``, ``doc`` and
/// ``default`` (what a call that leaves the keyword out gets with ``scenario``, default
/// ``paper_simple``). The CLI's flags are the same options (``--key-with-dashes``).
#[pyfunction]
#[pyo3(signature = (function="train", scenario=None))]
pub fn options<'py>(
    py: Python<'py>,
    function: &str,
    scenario: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let s: Scenario = crate::scenario::scenario_from_any(py, scenario)?
        .as_ref()
        .clone();
    let (infos, defaults) = match function {
        "env" => (
            ENV_OPTIONS.iter().map(|o| o.info).collect(),
            ENV_OPTIONS
                .iter()
                .filter_map(|o| o.default.value().map(|v| (o.key, v)))
                .collect(),
        ),
        "joint" => (
            JOINT_ENV_OPTIONS.iter().map(|o| o.info).collect(),
            JOINT_ENV_OPTIONS
                .iter()
                .filter_map(|o| o.default.value().map(|v| (o.key, v)))
                .collect(),
        ),
        "train" => (train_options(), option_values(&s)),
        "plan" => (plan_options(), option_values(&s)),
        "generate_scenario" => (
            generator_options(),
            GENERATOR_OPTIONS
                .iter()
                .map(|o| (o.info.key, (o.get)(&GeneratorOptions::default())))
                .collect(),
        ),
        other => {
            return Err(invalid_argument(
                py,
                "function",
                other,
                "must be \"train\", \"plan\", \"generate_scenario\", \"env\" or \"joint\"",
            ))
        }
    };
    let out = PyList::empty(py);
    for i in infos {
        let d = PyDict::new(py);
        d.set_item("key", i.key)?;
        d.set_item("field", i.field)?;
        d.set_item("kind", i.domain.kind())?;
        match i.domain {
            Domain::Int { min, max } | Domain::IntOrAuto { min, max } => {
                d.set_item("min", min)?;
                d.set_item("max", max)?;
            }
            Domain::Float { min, max, open_min } => {
                d.set_item("min", min)?;
                d.set_item("max", max)?;
                d.set_item("min_exclusive", open_min)?;
            }
            Domain::Choice(names) => d.set_item("choices", names.to_vec())?,
            Domain::Bool | Domain::Text => {}
        }
        d.set_item("unit", i.unit)?;
        d.set_item("doc", i.doc_line())?;
        let default = match defaults.iter().find(|(k, _)| *k == i.key) {
            Some((_, v)) => value_to_py(py, v)?,
            _ => py.None().into_bound(py),
        };
        d.set_item("default", default)?;
        out.append(d)?;
    }
    Ok(out)
}

/// Check the keywords of a Gymnasium env (``function="env"``: the grid envs, the core's
/// ``ENV_OPTIONS``; ``function="joint"``: the joint-space envs, ``JOINT_ENV_OPTIONS``) and return them as a dict of plain values (``bool``, ``int``,
/// ``float``, ``str`` or ``None``): each bad value raises :class:`InvalidArgumentError`
/// naming the keyword and its ``repr``; ``None`` is accepted only where the table allows
/// it. An unknown keyword is a ``TypeError``.
#[pyfunction]
#[pyo3(signature = (function, **kwargs))]
pub fn check_options<'py>(
    py: Python<'py>,
    function: &str,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let env_infos: Vec<OptionInfo>;
    let (table, nullable): (&[OptionInfo], &[&str]) = match function {
        "env" => {
            env_infos = ENV_OPTIONS.iter().map(|o| o.info).collect();
            (&env_infos, ENV_NULLABLE)
        }
        "joint" => {
            env_infos = JOINT_ENV_OPTIONS.iter().map(|o| o.info).collect();
            (&env_infos, JOINT_NULLABLE)
        }
        other => {
            return Err(invalid_argument(
                py,
                "function",
                other,
                "must be \"env\" or \"joint\"",
            ))
        }
    };
    let out = PyDict::new(py);
    let Some(kwargs) = kwargs else {
        return Ok(out);
    };
    for (k, v) in kwargs.iter() {
        let key: String = k.extract()?;
        let Some(info) = table.iter().find(|i| i.key == key) else {
            let keys: Vec<&str> = table.iter().map(|i| i.key).collect();
            return Err(PyTypeError::new_err(format!(
                "got an unexpected keyword argument '{key}' (the env's keywords: {})",
                keys.join(", ")
            )));
        };
        let reason = match info.domain {
            Domain::Bool => "must be True or False".to_string(),
            d => d.reason(),
        };
        let bad = || invalid_argument(py, &key, repr(&v), reason.clone());
        if v.is_none() {
            if nullable.contains(&key.as_str()) {
                out.set_item(&key, py.None())?;
                continue;
            }
            return Err(bad());
        }
        let value = value_of(py, info, &v).map_err(|_| bad())?.ok_or_else(bad)?;
        check_value(&key, &info.domain, &value).map_err(|_| bad())?;
        // A whole number given for a float option is that float.
        let value = match (&info.domain, value) {
            (Domain::Float { .. }, OptionValue::Int(i)) => OptionValue::Float(i as f64),
            (_, value) => value,
        };
        out.set_item(&key, value_to_py(py, &value)?)?;
    }
    Ok(out)
}
