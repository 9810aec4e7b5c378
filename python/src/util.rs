//! numpy conversion helpers: arrays in as `float64` (any array-like is converted once by
//! `numpy.asarray`), arrays out as owned numpy arrays.

use numpy::ndarray::{Array2, ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray2, PyArrayDyn, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_core::{TriMesh, Vec3};

/// `obj` as a read-only float64 array (no copy when it already is one). An array of another
/// type is converted by numpy after its size is checked against the memory limit (a
/// broadcast view can stand for more values than memory holds).
pub fn f64_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, f64>>() {
        return Ok(a);
    }
    if let Ok(a) = obj.cast::<numpy::PyUntypedArray>() {
        let shape = a.shape().to_vec();
        let count: f64 = shape.iter().map(|&n| n as f64).product();
        crate::limits::check_f64s(obj.py(), || format!("{what} (shape {shape:?})"), count)?;
    }
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (obj, "float64"))?;
    a.extract::<PyReadonlyArrayDyn<'py, f64>>()
        .map_err(|e| PyValueError::new_err(format!("{what}: expected an array of numbers: {e}")))
}

/// The data of a float64 array in C order, with its shape (`what` names the argument in
/// errors; the copy is checked against the memory limit first).
pub fn flat(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let a = f64_array(obj, what)?;
    let shape = a.shape().to_vec();
    let count: f64 = shape.iter().map(|&n| n as f64).product();
    crate::limits::check_f64s(obj.py(), || format!("{what} (shape {shape:?})"), count)?;
    // ndarray's `as_slice` is C order only (numpy's also takes Fortran order); `iter` walks
    // the logical (C) order of any layout.
    let view = a.as_array();
    let data = match view.as_slice() {
        Some(s) => s.to_vec(),
        None => view.iter().copied().collect(),
    };
    Ok((data, shape))
}

/// An `(n, d)` array (a 1-D array is `(n, 1)` when `d == 1`), flat, and n.
pub fn rows(obj: &Bound<'_, PyAny>, d: usize, what: &str) -> PyResult<(Vec<f64>, usize)> {
    let (data, shape) = flat(obj, what)?;
    match shape.as_slice() {
        [n] if d == 1 => Ok((data, *n)),
        [n, k] if *k == d => Ok((data, *n)),
        _ => Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape (n, {d}){}, got shape {shape:?}",
            if d == 1 { " or (n,)" } else { "" }
        ))),
    }
}

/// An `(n, 3)` array as points.
pub fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vec3>> {
    let (data, _) = rows(obj, 3, what)?;
    Ok(data
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

/// A 3-vector from any sequence of three numbers.
pub fn vec3(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec3> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{what}: expected three numbers")))?;
    match v.as_slice() {
        [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(PyValueError::new_err(format!(
            "{what}: expected three numbers, got {}",
            v.len()
        ))),
    }
}

/// Points as an `(n, 3)` array.
pub fn points_array<'py>(py: Python<'py>, pts: &[Vec3]) -> Bound<'py, PyArray2<f64>> {
    let mut v = Vec::with_capacity(pts.len() * 3);
    for p in pts {
        v.extend_from_slice(&[p.x, p.y, p.z]);
    }
    array2(py, v, pts.len(), 3)
}

/// A flat C-order vector as an `(n, m)` array.
pub fn array2(py: Python<'_>, v: Vec<f64>, n: usize, m: usize) -> Bound<'_, PyArray2<f64>> {
    Array2::from_shape_vec((n, m), v)
        .expect("shape matches the data")
        .into_pyarray(py)
}

/// A flat C-order vector as an array of `shape`.
pub fn array_dyn<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    shape: &[usize],
) -> Bound<'py, PyArrayDyn<f64>> {
    ArrayD::from_shape_vec(IxDyn(shape), v)
        .expect("shape matches the data")
        .into_pyarray(py)
}

/// A mesh as `(vertices (n, 3), triangles (m, 3) uint32, normals (n, 3) or (0, 3))`.
pub fn mesh_arrays<'py>(py: Python<'py>, mesh: &TriMesh) -> PyResult<Bound<'py, PyAny>> {
    let tri: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let tri = Array2::from_shape_vec((mesh.triangles.len(), 3), tri)
        .expect("shape matches the data")
        .into_pyarray(py);
    let t = (
        points_array(py, &mesh.positions),
        tri,
        points_array(py, &mesh.normals),
    );
    Ok(t.into_pyobject(py)?.into_any())
}

/// A mesh from `(vertices, triangles)` arrays.
pub fn mesh_from(vertices: &Bound<'_, PyAny>, triangles: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let positions = points(vertices, "vertices")?;
    let (t, _) = rows(triangles, 3, "triangles")?;
    let n = positions.len();
    let mut tris = Vec::with_capacity(t.len() / 3);
    for c in t.chunks_exact(3) {
        let mut tri = [0u32; 3];
        for (k, &x) in c.iter().enumerate() {
            if !(x >= 0.0 && x.fract() == 0.0 && (x as usize) < n) {
                return Err(PyValueError::new_err(format!(
                    "triangles: index {x} is not a vertex index (there are {n} vertices)"
                )));
            }
            tri[k] = x as u32;
        }
        tris.push(tri);
    }
    let mut mesh = TriMesh::new();
    mesh.positions = positions;
    mesh.triangles = tris;
    mesh.compute_normals();
    Ok(mesh)
}

/// A `serde_json::Value` (the session layer's serde types: logs, tools, saved states, fit
/// reports) as Python objects, built in Rust (no JSON text): objects are dicts, arrays lists,
/// integers `int`, other numbers `float` (exact).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::types::{PyBool, PyDict, PyList, PyString};
    use serde_json::Value;
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

/// A Python value as a `serde_json::Value` tree, for deserializing into the session layer's
/// serde types (`Command`, `Timed`, material keys) with `serde_json::from_value`: no JSON text
/// is written or parsed. Takes dicts (string keys), lists, tuples, str, bool, int, float,
/// None, numpy arrays (any numeric or bool dtype; read from their buffers) and numpy scalars
/// (`np.float32`, `np.int64`, ...); a string is JSON text and is parsed. A NaN or infinite
/// number, or a value of another type, is an error naming its key path (`g[2]`,
/// `points[3][0]`) prefixed by `what`.
pub fn py_to_json(
    obj: &Bound<'_, PyAny>,
    what: &str,
    err: fn(String) -> PyErr,
) -> PyResult<serde_json::Value> {
    if let Ok(s) = obj.cast::<pyo3::types::PyString>() {
        let text: String = s.extract()?;
        return serde_json::from_str(&text).map_err(|e| err(format!("{what}: not JSON text: {e}")));
    }
    let mut path = String::new();
    value(obj, &mut path).map_err(|m| {
        let at = if path.is_empty() {
            String::new()
        } else {
            format!("{path}: ")
        };
        err(format!("{what}: {at}{m}"))
    })
}

/// A Python value as the serde type `T` (through [`py_to_json`]); a value of the wrong shape
/// is an error naming its key path.
pub fn from_py<T: serde::de::DeserializeOwned>(
    obj: &Bound<'_, PyAny>,
    what: &str,
    err: fn(String) -> PyErr,
) -> PyResult<T> {
    let v = py_to_json(obj, what, err)?;
    serde_path_to_error::deserialize(v).map_err(|e| {
        let path = e.path().to_string();
        if path == "." {
            err(format!("{what}: {}", e.inner()))
        } else {
            err(format!("{what}: {path}: {}", e.inner()))
        }
    })
}

/// `obj` as a value; on error, `path` is the key path of the offending value.
fn value(obj: &Bound<'_, PyAny>, path: &mut String) -> Result<serde_json::Value, String> {
    use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
    use serde_json::Value;
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(i) = obj.cast::<PyInt>() {
        return int(i);
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return float(f.value());
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(
            s.extract().map_err(|e: PyErr| e.to_string())?,
        ));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::with_capacity(d.len());
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| format!("a key of type {} (keys are strings)", type_name(&k)))?;
            let len = path.len();
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(&key);
            let v = value(&v, path)?;
            path.truncate(len);
            map.insert(key, v);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut out = Vec::with_capacity(obj.len().unwrap_or(0));
        for (i, item) in obj.try_iter().map_err(|e| e.to_string())?.enumerate() {
            let item = item.map_err(|e| e.to_string())?;
            let len = path.len();
            path.push_str(&format!("[{i}]"));
            out.push(value(&item, path)?);
            path.truncate(len);
        }
        return Ok(Value::Array(out));
    }
    if let Ok(a) = obj.cast::<numpy::PyUntypedArray>() {
        return ndarray(a, path);
    }
    // numpy scalars (np.float32, np.int64, np.bool_): their Python value.
    let py = obj.py();
    let generic = py
        .import("numpy")
        .and_then(|np| np.getattr("generic"))
        .map_err(|e| e.to_string())?;
    if obj.is_instance(&generic).unwrap_or(false) {
        let item = obj.call_method0("item").map_err(|e| e.to_string())?;
        if !item.is(obj) {
            return value(&item, path);
        }
    }
    Err(format!(
        "a value of type {} (commands take dicts, lists, numbers, strings, bools, None and numpy arrays)",
        type_name(obj)
    ))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".into(), |n| n.to_string())
}

fn float(x: f64) -> Result<serde_json::Value, String> {
    serde_json::Number::from_f64(x)
        .map(serde_json::Value::Number)
        .ok_or_else(|| format!("{x} is not a finite number"))
}

fn int(i: &Bound<'_, pyo3::types::PyInt>) -> Result<serde_json::Value, String> {
    if let Ok(v) = i.extract::<i64>() {
        Ok(v.into())
    } else if let Ok(v) = i.extract::<u64>() {
        Ok(v.into())
    } else {
        Err(format!("{i} is too large an integer"))
    }
}

/// A numpy array as nested lists of numbers, read from its buffer as float64, int64 or bool.
fn ndarray(
    a: &Bound<'_, numpy::PyUntypedArray>,
    path: &mut String,
) -> Result<serde_json::Value, String> {
    use numpy::{PyArrayDescrMethods, PyUntypedArrayMethods};
    use serde_json::Value;
    let shape = a.shape().to_vec();
    let kind = a.dtype().kind();
    let np = a.py().import("numpy").map_err(|e| e.to_string())?;
    let convert = |dtype: &str| {
        np.call_method1("ascontiguousarray", (a, dtype))
            .map_err(|e| e.to_string())
    };
    let flat: Vec<Value> = match kind {
        b'f' => {
            let c = convert("float64")?;
            let c = c
                .extract::<PyReadonlyArrayDyn<'_, f64>>()
                .map_err(|e| e.to_string())?;
            let data = c.as_slice().map_err(|e| e.to_string())?;
            let mut out = Vec::with_capacity(data.len());
            for (k, &x) in data.iter().enumerate() {
                out.push(float(x).inspect_err(|_| path.push_str(&index_of(k, &shape)))?);
            }
            out
        }
        b'i' | b'u' => {
            let c = convert("int64")?;
            let c = c
                .extract::<PyReadonlyArrayDyn<'_, i64>>()
                .map_err(|e| e.to_string())?;
            c.as_slice()
                .map_err(|e| e.to_string())?
                .iter()
                .map(|&v| Value::from(v))
                .collect()
        }
        b'b' => {
            let c = convert("bool")?;
            let c = c
                .extract::<PyReadonlyArrayDyn<'_, bool>>()
                .map_err(|e| e.to_string())?;
            c.as_slice()
                .map_err(|e| e.to_string())?
                .iter()
                .map(|&v| Value::Bool(v))
                .collect()
        }
        other => {
            return Err(format!(
                "a numpy array of dtype kind '{}' (commands take numeric and bool arrays)",
                other as char
            ));
        }
    };
    Ok(nest(flat, &shape))
}

/// `[i][j]...` of flat C-order index `k` in an array of `shape`.
fn index_of(mut k: usize, shape: &[usize]) -> String {
    let mut idx = vec![0; shape.len()];
    for (a, &n) in shape.iter().enumerate().rev() {
        if n > 0 {
            idx[a] = k % n;
            k /= n;
        }
    }
    idx.iter().map(|i| format!("[{i}]")).collect()
}

/// Flat C-order values nested as lists of `shape`.
fn nest(flat: Vec<serde_json::Value>, shape: &[usize]) -> serde_json::Value {
    use serde_json::Value;
    match shape {
        [] => flat.into_iter().next().unwrap_or(Value::Null),
        [_] => Value::Array(flat),
        [n, rest @ ..] => {
            let per: usize = rest.iter().product();
            let mut it = flat.into_iter();
            Value::Array(
                (0..*n)
                    .map(|_| nest(it.by_ref().take(per).collect(), rest))
                    .collect(),
            )
        }
    }
}

/// Runs `f` over `n` items in chunks, in parallel when `n >= PAR_MIN`: `f(start, out_chunk)`
/// fills `out_chunk` (`width` values per item) for items `start..`. The first error wins.
pub fn fill<E: Send>(
    out: &mut [f64],
    width: usize,
    f: impl Fn(usize, &mut [f64]) -> Result<(), E> + Sync,
) -> Result<(), E> {
    use rayon::prelude::*;
    const CHUNK: usize = 1024;
    let n = out.len() / width.max(1);
    if n < crate::PAR_MIN {
        return f(0, out);
    }
    out.par_chunks_mut(CHUNK * width)
        .enumerate()
        .try_for_each(|(k, c)| f(k * CHUNK, c))
}

/// A count argument (`i64` so that a negative value reaches us) as `usize`: a negative one is
/// a `ValueError` naming the argument.
pub fn count(n: i64, what: &str) -> PyResult<usize> {
    usize::try_from(n).map_err(|_| {
        crate::errors::argument(format!("{what} = {n}: expected a non-negative integer"))
    })
}
