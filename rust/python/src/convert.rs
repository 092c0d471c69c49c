//! Conversions between Python values and the core's types, with errors that name the
//! argument or field at fault.

use pyo3::prelude::*;
use pyo3::types::{
    PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple,
};
use serde_json::{Map, Number, Value};
use sixaxis_core::{Cell, Error};

use crate::errors::invalid_argument;

/// Deepest nesting of containers [`py_to_json`] reads. The scenario schema nests 4 deep;
/// serde_json's own parser stops at 128. Without a limit a self-referential dict, a
/// 100 000-deep list or an object whose `tolist()` returns another such object recursed
/// until the native stack overflowed and the interpreter died with SIGSEGV.
pub const MAX_JSON_DEPTH: usize = 64;

/// Python object -> JSON value; `path` is the dotted field name used in errors.
/// Non-finite floats are rejected here (JSON has no NaN) with an error naming the field;
/// containers nested deeper than [`MAX_JSON_DEPTH`] (self-references included) likewise.
pub fn py_to_json(obj: &Bound<'_, PyAny>, path: &str) -> Result<Value, Error> {
    py_to_json_at(obj, path, 0)
}

fn py_to_json_at(obj: &Bound<'_, PyAny>, path: &str, depth: usize) -> Result<Value, Error> {
    if depth > MAX_JSON_DEPTH {
        let shown: String = path.chars().take(60).collect();
        return Err(Error::ScenarioParse(format!(
            "field `{shown}...`: nested more than {MAX_JSON_DEPTH} levels deep (a container that contains itself?)"
        )));
    }
    let py_to_json = |o: &Bound<'_, PyAny>, p: &str| py_to_json_at(o, p, depth + 1);
    let field = |p: &str| {
        if p.is_empty() {
            "<root>".to_string()
        } else {
            p.to_string()
        }
    };
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(obj.extract::<bool>().unwrap_or(false)));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(v) = obj.extract::<i64>() {
            return Ok(Value::Number(v.into()));
        }
        if let Ok(v) = obj.extract::<u64>() {
            return Ok(Value::Number(v.into()));
        }
        return Err(Error::invalid(
            field(path),
            repr(obj),
            "integer out of range",
        ));
    }
    if obj.is_instance_of::<PyFloat>() {
        let v: f64 = obj.extract().unwrap_or(f64::NAN);
        return float(v, &field(path));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_string()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                Error::ScenarioParse(format!(
                    "field `{}`: keys must be strings, got {}",
                    field(path),
                    repr(&k)
                ))
            })?;
            let sub = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            map.insert(key, py_to_json(&v, &sub)?);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut out = Vec::new();
        for (i, item) in obj
            .try_iter()
            .map_err(|_| parse_err(path, obj))?
            .enumerate()
        {
            let item = item.map_err(|_| parse_err(path, obj))?;
            out.push(py_to_json(&item, &format!("{}[{i}]", field(path)))?);
        }
        return Ok(Value::Array(out));
    }
    // NumPy arrays and scalars, Mappings, Path objects.
    if obj.hasattr("tolist").unwrap_or(false) {
        if let Ok(list) = obj.call_method0("tolist") {
            if !list.is(obj) {
                return py_to_json(&list, path);
            }
        }
    }
    if obj.hasattr("__index__").unwrap_or(false) {
        if let Ok(v) = obj.extract::<i64>() {
            return Ok(Value::Number(v.into()));
        }
    }
    if obj.hasattr("__float__").unwrap_or(false) {
        if let Ok(v) = obj
            .call_method0("__float__")
            .and_then(|f| f.extract::<f64>())
        {
            return float(v, &field(path));
        }
    }
    if obj.hasattr("keys").unwrap_or(false) {
        if let Ok(d) = obj
            .py()
            .get_type::<PyDict>()
            .call1((obj,))
            .and_then(|d| Ok(d.cast_into::<PyDict>()?))
        {
            return py_to_json(d.as_any(), path);
        }
    }
    if obj.hasattr("__fspath__").unwrap_or(false) {
        if let Ok(s) = obj
            .call_method0("__fspath__")
            .and_then(|s| s.extract::<String>())
        {
            return Ok(Value::String(s));
        }
    }
    Err(parse_err(path, obj))
}

fn float(v: f64, field: &str) -> Result<Value, Error> {
    match Number::from_f64(v) {
        Some(n) if v.is_finite() => Ok(Value::Number(n)),
        _ => Err(Error::invalid(field, v, "must be a finite number")),
    }
}

fn parse_err(path: &str, obj: &Bound<'_, PyAny>) -> Error {
    let ty = obj
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    Error::ScenarioParse(format!(
        "field `{}`: a value of type {ty} cannot be read as JSON",
        if path.is_empty() { "<root>" } else { path }
    ))
}

/// Longest `repr` quoted in an error message, in characters.
const MAX_REPR_CHARS: usize = 200;

/// `repr(obj)` (cut to 200 characters), or a placeholder when `repr` itself fails (a
/// huge int beyond Python's digit limit, a deeply nested list, a raising `__repr__`).
pub fn repr(obj: &Bound<'_, PyAny>) -> String {
    let Ok(r) = obj.repr() else {
        return "<unrepresentable>".to_string();
    };
    let r = r.to_string_lossy();
    match r.char_indices().nth(MAX_REPR_CHARS) {
        Some((cut, _)) => format!("{}...", &r[..cut]),
        None => r.into_owned(),
    }
}

/// The items of a sequence, at most `max_items` of them: reads by iteration and never
/// trusts `__len__` (PyO3's `Vec` extraction pre-allocates `len()` items, so a sequence
/// claiming 2**40 items aborted the process on the failed allocation). What counts as a
/// sequence is what PyO3's extraction accepted (`PySequence_Check`: lists, tuples, NumPy
/// arrays, ...), less strings and bytes; sets, dicts and generators are refused.
pub fn bounded_items<'py>(
    obj: &Bound<'py, PyAny>,
    max_items: usize,
) -> Option<Vec<Bound<'py, PyAny>>> {
    // SAFETY: `obj` is a live object and the GIL is held (we have a `Bound`).
    let is_sequence = unsafe { pyo3::ffi::PySequence_Check(obj.as_ptr()) } != 0;
    if !is_sequence
        || obj.is_instance_of::<PyString>()
        || obj.is_instance_of::<PyBytes>()
        || obj.is_instance_of::<PyByteArray>()
    {
        return None;
    }
    let mut out = Vec::new();
    for item in obj.try_iter().ok()? {
        if out.len() == max_items {
            return None;
        }
        out.push(item.ok()?);
    }
    Some(out)
}

/// A sequence of at most `max_items` values each extracted as `T`, or `None`.
pub fn bounded_vec<'py, T: FromPyObject<'py>>(
    obj: &Bound<'py, PyAny>,
    max_items: usize,
) -> Option<Vec<T>> {
    bounded_items(obj, max_items)?
        .iter()
        .map(|x| x.extract().ok())
        .collect()
}

/// JSON value -> Python object (dicts, lists, str, int, float, bool, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// `N` finite numbers from any sequence; the error names `name` and the value.
pub fn finite_array<const N: usize>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; N]> {
    let py = obj.py();
    let v: Vec<f64> = bounded_vec(obj, N + 1).ok_or_else(|| {
        invalid_argument(
            py,
            name,
            repr(obj),
            format!("must be a sequence of {N} numbers"),
        )
    })?;
    let arr: [f64; N] = v.as_slice().try_into().map_err(|_| {
        invalid_argument(
            py,
            name,
            repr(obj),
            format!("must have {N} values, got {}", v.len()),
        )
    })?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(invalid_argument(
            py,
            name,
            repr(obj),
            "every value must be finite",
        ));
    }
    Ok(arr)
}

/// A table of at most `max_rows` rows of at most `max_cols` numbers each (a D-H table, a
/// rotation matrix), or `None`; shapes are checked by the caller, values are not.
pub fn bounded_rows(
    obj: &Bound<'_, PyAny>,
    max_rows: usize,
    max_cols: usize,
) -> Option<Vec<Vec<f64>>> {
    bounded_items(obj, max_rows)?
        .iter()
        .map(|row| bounded_vec(row, max_cols))
        .collect()
}

/// Six finite joint angles from any sequence of numbers.
pub fn joints6(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; 6]> {
    finite_array::<6>(obj, name)
}

/// Three finite numbers from any sequence.
pub fn vec3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; 3]> {
    finite_array::<3>(obj, name)
}

/// Most cells a list of cells may hold: the most cells a scenario's bounds may hold.
pub const MAX_CELLS: usize = 1 << 24;

/// A list of grid cells from any iterable of cells; `None` gives an empty list.
pub fn cells(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Vec<Cell>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    let py = obj.py();
    let mut out = Vec::new();
    for item in obj
        .try_iter()
        .map_err(|_| invalid_argument(py, name, repr(obj), "must be a sequence of cells"))?
    {
        if out.len() == MAX_CELLS {
            return Err(invalid_argument(
                py,
                name,
                repr(obj),
                format!("more than {MAX_CELLS} cells (an endless iterator?)"),
            ));
        }
        out.push(cell(&item?, name)?);
    }
    Ok(out)
}

/// A grid cell from any sequence of 3 integers.
pub fn cell(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Cell> {
    let py = obj.py();
    let v: Vec<i64> = bounded_vec(obj, 4)
        .ok_or_else(|| invalid_argument(py, name, repr(obj), "must be a sequence of 3 integers"))?;
    if v.len() != 3 {
        return Err(invalid_argument(
            py,
            name,
            repr(obj),
            format!("must have 3 integers, got {}", v.len()),
        ));
    }
    let mut c = [0i32; 3];
    for i in 0..3 {
        c[i] = i32::try_from(v[i])
            .map_err(|_| invalid_argument(py, name, repr(obj), "coordinate out of range"))?;
    }
    Ok(c)
}

/// A `T` array of shape `(n, 3)` (goals, one row each), flattened row-major, and its `n`;
/// any other value is refused with `reason` naming what `name` must be.
pub fn goal_rows<T: numpy::Element + Copy>(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    name: &str,
    reason: &str,
) -> PyResult<(Vec<T>, usize)> {
    use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
    let bad = || invalid_argument(py, name, repr(obj), reason);
    let arr: PyReadonlyArray2<'_, T> = obj.extract().map_err(|_| bad())?;
    if arr.shape()[1] != 3 {
        return Err(bad());
    }
    Ok((arr.as_array().iter().copied().collect(), arr.shape()[0]))
}

/// A one-dimensional `T` array (`what` names the dtype) of `n` values, `per` saying what
/// each one belongs to (`"one per transition"`).
pub fn column<'py, T: numpy::Element + Copy>(
    py: Python<'_>,
    obj: &Bound<'py, PyAny>,
    name: &str,
    what: &str,
    n: usize,
    per: &str,
) -> PyResult<Vec<T>> {
    use numpy::{PyReadonlyArray1, PyUntypedArrayMethods};
    let bad = || {
        invalid_argument(
            py,
            name,
            repr(obj),
            format!("must be a {what} array of shape ({n},), {per}"),
        )
    };
    let arr: PyReadonlyArray1<'py, T> = obj.extract().map_err(|_| bad())?;
    if arr.len() != n {
        return Err(bad());
    }
    Ok(arr.as_array().to_vec())
}
