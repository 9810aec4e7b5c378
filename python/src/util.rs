//! numpy conversion helpers: arrays in as `float64` (any array-like is converted once by
//! `numpy.asarray`), arrays out as owned numpy arrays.

use numpy::ndarray::{Array2, ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray2, PyArrayDyn, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_core::{TriMesh, Vec3};

/// `obj` as a read-only float64 array (no copy when it already is one).
pub fn f64_array<'py>(obj: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, f64>>() {
        return Ok(a);
    }
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (obj, "float64"))?;
    a.extract::<PyReadonlyArrayDyn<'py, f64>>()
        .map_err(|e| PyValueError::new_err(format!("expected an array of numbers: {e}")))
}

/// The data of a float64 array in C order, with its shape.
pub fn flat(obj: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let a = f64_array(obj)?;
    let shape = a.shape().to_vec();
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
    let (data, shape) = flat(obj)?;
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

/// A JSON value as a Python object (via the `json` module: sessions' dicts are small).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A Python object (dict, list, numbers, strings) as a JSON value.
pub fn py_to_json(obj: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    let text: String = if let Ok(s) = obj.extract::<String>() {
        s
    } else {
        obj.py()
            .import("json")?
            .call_method1("dumps", (obj,))?
            .extract()?
    };
    serde_json::from_str(&text).map_err(|e| PyValueError::new_err(format!("not JSON: {e}")))
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
