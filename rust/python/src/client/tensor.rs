//! Python values <-> dm_env_rpc tensors: a setting (str, bool, number or NumPy array) as a
//! [`Tensor`] ([`tensor_of`], [`settings_of`]), a Step request from an int32 action array
//! ([`step_request`]), and an [`Answer`] as Python objects, tensors as flat NumPy arrays
//! moved from the decoded message ([`answer_to_py`]).

use std::collections::BTreeMap;

use numpy::{IntoPyArray, PyArrayDescrMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyList, PyString};
use sixaxis_server::proto::environment::Request as Req;
use sixaxis_server::proto::tensor::{
    BoolArray, DoubleArray, FloatArray, Int64Array, Payload, StringArray, Uint64Array,
};
use sixaxis_server::proto::{ActionObservationSpecs, Settings, StepRequest, Tensor, TensorSpec};

use super::error::ClientError;
use super::session::Answer;
use crate::convert::repr;

pub(super) fn bad_setting(name: &str, value: &Bound<'_, PyAny>) -> ClientError {
    ClientError::Argument {
        name: format!("settings[{name:?}]"),
        value: repr(value),
        reason: "must be a str, a bool, a number or a numeric array".into(),
    }
}

/// A setting's tensor: a str, a bool, a number or a NumPy array (bool, integer, float).
pub(super) fn tensor_of(name: &str, value: &Bound<'_, PyAny>) -> Result<Tensor, ClientError> {
    let py = value.py();
    if let Ok(s) = value.cast::<PyString>() {
        let s = s.to_cow().map_err(|_| bad_setting(name, value))?;
        return Ok(Tensor {
            payload: Some(Payload::Strings(StringArray {
                array: vec![s.into_owned()],
            })),
            shape: vec![],
        });
    }
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(Tensor {
            payload: Some(Payload::Bools(BoolArray {
                array: vec![b.is_true()],
            })),
            shape: vec![],
        });
    }
    let arr = py
        .import("numpy")
        .and_then(|np| np.call_method1("asarray", (value,)))
        .map_err(|_| bad_setting(name, value))?;
    let arr = arr
        .cast::<numpy::PyUntypedArray>()
        .map_err(|_| bad_setting(name, value))?;
    let shape: Vec<i32> = arr.shape().iter().map(|&d| d as i32).collect();
    let kind = arr.dtype().kind();
    let as_type = |t: &str| -> Result<Bound<'_, PyAny>, ClientError> {
        arr.call_method1("astype", (t,))
            .map_err(|_| bad_setting(name, value))
    };
    fn flat<T: numpy::Element + Copy>(a: &Bound<'_, PyAny>) -> Option<Vec<T>> {
        let a: PyReadonlyArrayDyn<'_, T> = a.extract().ok()?;
        Some(a.as_array().iter().copied().collect())
    }
    let payload = match kind {
        b'b' => Payload::Bools(BoolArray {
            array: flat(arr.as_any()).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'i' => Payload::Int64s(Int64Array {
            array: flat(&as_type("int64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'u' => Payload::Uint64s(Uint64Array {
            array: flat(&as_type("uint64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'f' if arr.dtype().itemsize() == 4 => Payload::Floats(FloatArray {
            array: flat(arr.as_any()).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'f' => Payload::Doubles(DoubleArray {
            array: flat(&as_type("float64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        _ => return Err(bad_setting(name, value)),
    };
    Ok(Tensor {
        payload: Some(payload),
        shape,
    })
}

pub(super) fn settings_of(settings: Option<&Bound<'_, PyDict>>) -> Result<Settings, ClientError> {
    let mut out = Settings::new();
    if let Some(d) = settings {
        for (k, v) in d.iter() {
            let name: String = k.extract().map_err(|_| ClientError::Argument {
                name: "settings".into(),
                value: repr(&k),
                reason: "its keys must be str".into(),
            })?;
            let t = tensor_of(&name, &v)?;
            out.insert(name, t);
        }
    }
    Ok(out)
}

/// A tensor's values as a flat NumPy array (moved, not copied, from the decoded message;
/// strings as a list of str).
pub(super) fn tensor_to_py<'py>(py: Python<'py>, t: Tensor) -> PyResult<Bound<'py, PyAny>> {
    Ok(match t.payload {
        None => numpy::PyArray1::<f32>::zeros(py, 0, false).into_any(),
        Some(Payload::Floats(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Doubles(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Int8s(a)) => a
            .array
            .into_iter()
            .map(|b| b as i8)
            .collect::<Vec<i8>>()
            .into_pyarray(py)
            .into_any(),
        Some(Payload::Int32s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Int64s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint8s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint32s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint64s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Bools(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Strings(a)) => PyList::new(py, a.array)?.into_any(),
        Some(Payload::Protos(a)) => {
            PyList::new(py, a.array.into_iter().map(|m| PyBytes::new(py, &m.value)))?.into_any()
        }
    })
}

pub(super) fn specs_to_py<'py>(
    py: Python<'py>,
    specs: Option<ActionObservationSpecs>,
) -> PyResult<Bound<'py, PyAny>> {
    let Some(specs) = specs else {
        return Ok(py.None().into_bound(py));
    };
    let part = |m: BTreeMap<u64, TensorSpec>| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (uid, s) in m {
            d.set_item(uid, (s.name, s.dtype, s.shape))?;
        }
        Ok(d)
    };
    let out = PyDict::new(py);
    out.set_item("actions", part(specs.actions)?)?;
    out.set_item("observations", part(specs.observations)?)?;
    Ok(out.into_any())
}

pub(super) fn answer_to_py<'py>(py: Python<'py>, a: Answer) -> PyResult<Bound<'py, PyAny>> {
    Ok(match a {
        Answer::WorldName(n) => PyString::new(py, &n).into_any(),
        Answer::Specs(s) => specs_to_py(py, s)?,
        Answer::Step(state, obs) => {
            let d = PyDict::new(py);
            for (uid, t) in obs {
                d.set_item(uid, tensor_to_py(py, t)?)?;
            }
            (state, d).into_pyobject(py)?.into_any()
        }
        Answer::Empty => py.None().into_bound(py),
        Answer::Raw(b) => PyBytes::new(py, &b).into_any(),
    })
}

pub(super) fn step_request(
    actions: Option<PyReadonlyArrayDyn<'_, i32>>,
    requested: Vec<u64>,
    action_uid: u64,
) -> Req {
    let mut a = BTreeMap::new();
    if let Some(x) = actions {
        let shape: Vec<i32> = x.shape().iter().map(|&d| d as i32).collect();
        let values: Vec<i32> = match x.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => x.as_array().iter().copied().collect(),
        };
        a.insert(
            action_uid,
            Tensor {
                payload: Some(Payload::Int32s(sixaxis_server::proto::tensor::Int32Array {
                    array: values,
                })),
                shape,
            },
        );
    }
    Req::Step(StepRequest {
        actions: a,
        requested_observations: requested,
    })
}
