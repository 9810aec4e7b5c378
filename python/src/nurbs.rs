//! NURBS entities (`Curve`, `Surface`, `Volume`, all subclasses of `Entity`), model files and
//! conversion.
//!
//! Evaluation is `d-nurbs.txt` eq (1) and its bivariate and trivariate forms (Piegl & Tiller
//! A4.1-A4.4, through `vclay_spline`): batched over an `(n, d)` parameter array in Rust, in
//! parallel above [`crate::PAR_MIN`] points, with the GIL released. Knot insertion (A5.1) and
//! degree elevation (A5.9) return new entities.

use std::path::{Path, PathBuf};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyList;
use vclay_core::{TriMesh, Vec3};
use vclay_io::geomdl::{parse_geomdl, write_geomdl};
use vclay_io::gltf::{GlbMesh, read_glb, write_glb};
use vclay_io::iges::write_iges;
use vclay_io::mesh::{read_mesh, write_mesh};
use vclay_io::model::{Entity as IoEntity, NamedEntity, write_named_model};
use vclay_io::step::write_step;
use vclay_io::step_read::{TrimmedFace, tessellate_trimmed};
use vclay_spline::{
    KnotVector, NurbsCurve, NurbsSurface, NurbsVolume, ParametricCurve, ParametricSurface,
    ParametricVolume, SplineError, tessellate_surface, tessellate_volume_boundary,
};

use crate::errors::{FileError, GeometryError, PyResultExt};
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Entity>()?;
    m.add_class::<Curve>()?;
    m.add_class::<Surface>()?;
    m.add_class::<Volume>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(convert, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh_py, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh_py, m)?)?;
    Ok(())
}

/// A NURBS curve, surface or volume (the base class of `Curve`, `Surface`, `Volume`).
///
/// Arrays: control points `(n, 3)`, `(nu, nv, 3)` or `(nu, nv, nw, 3)` (last parametric index
/// fastest), weights of the same shape without the last axis, one knot array per axis.
#[pyclass(subclass, module = "vclay", eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct Entity {
    pub(crate) entity: IoEntity,
    name: Option<String>,
}

/// A NURBS curve `C(u) = sum N_i,p(u) w_i P_i / sum N_i,p(u) w_i` (`d-nurbs.txt` eq 1).
#[pyclass(extends = Entity, module = "vclay")]
#[derive(Debug)]
pub struct Curve;

/// A tensor-product NURBS surface `S(u, v)`.
#[pyclass(extends = Entity, module = "vclay")]
#[derive(Debug)]
pub struct Surface;

/// A trivariate NURBS volume `V(u, v, w)` (FFD lattices and B-spline solids are volumes).
#[pyclass(extends = Entity, module = "vclay")]
#[derive(Debug)]
pub struct Volume;

/// Wraps a kernel entity as the Python subclass of its kind.
pub fn wrap(py: Python<'_>, entity: IoEntity, name: Option<String>) -> PyResult<Py<PyAny>> {
    let base = Entity { entity, name };
    let obj = match &base.entity {
        IoEntity::Curve(_) => {
            Py::new(py, PyClassInitializer::from(base).add_subclass(Curve))?.into_any()
        }
        IoEntity::Surface(_) => {
            Py::new(py, PyClassInitializer::from(base).add_subclass(Surface))?.into_any()
        }
        IoEntity::Volume(_) => {
            Py::new(py, PyClassInitializer::from(base).add_subclass(Volume))?.into_any()
        }
    };
    Ok(obj)
}

fn knot_vector(
    obj: &Bound<'_, PyAny>,
    degree: usize,
    count: usize,
    axis: usize,
) -> PyResult<KnotVector> {
    let (k, _) = util::rows(obj, 1, "knots")?;
    KnotVector::new(k, degree, count)
        .map_err(|source| SplineError::Knots { axis, source })
        .py()
}

/// Control points and weights of a net of `dims` parametric axes: `(points, weights, shape)`.
fn net(
    points: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
    dims: usize,
) -> PyResult<(Vec<Vec3>, Vec<f64>, Vec<usize>)> {
    let (data, shape) = util::flat(points, "control_points")?;
    if shape.len() != dims + 1 || shape[dims] != 3 {
        let want = ["(n, 3)", "(nu, nv, 3)", "(nu, nv, nw, 3)"][dims - 1];
        return Err(PyValueError::new_err(format!(
            "control_points: expected shape {want}, got {shape:?}"
        )));
    }
    let net_shape = shape[..dims].to_vec();
    let pts: Vec<Vec3> = data
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let w = match weights {
        None => vec![1.0; pts.len()],
        Some(w) if w.is_none() => vec![1.0; pts.len()],
        Some(w) => {
            let (wd, ws) = util::flat(w, "weights")?;
            if ws != net_shape {
                return Err(PyValueError::new_err(format!(
                    "weights: expected shape {net_shape:?} (the control net's), got {ws:?}"
                )));
            }
            wd
        }
    };
    Ok((pts, w, net_shape))
}

fn degrees(obj: &Bound<'_, PyAny>, dims: usize) -> PyResult<Vec<usize>> {
    if dims == 1
        && let Ok(p) = obj.extract::<usize>()
    {
        return Ok(vec![p]);
    }
    let v: Vec<usize> = obj.extract().map_err(|_| {
        PyValueError::new_err(format!("degree: expected {dims} non-negative integers"))
    })?;
    if v.len() != dims {
        return Err(PyValueError::new_err(format!(
            "degree: expected {dims} integers, got {}",
            v.len()
        )));
    }
    Ok(v)
}

fn knot_list<'py>(obj: &Bound<'py, PyAny>, dims: usize) -> PyResult<Vec<Bound<'py, PyAny>>> {
    if dims == 1 {
        return Ok(vec![obj.clone()]);
    }
    let v: Vec<Bound<'_, PyAny>> = obj.try_iter()?.collect::<PyResult<_>>()?;
    if v.len() != dims {
        return Err(PyValueError::new_err(format!(
            "knots: expected {dims} knot arrays (one per parametric axis), got {}",
            v.len()
        )));
    }
    Ok(v)
}

fn build(
    dims: usize,
    degree: &Bound<'_, PyAny>,
    knots: &Bound<'_, PyAny>,
    control_points: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
) -> PyResult<IoEntity> {
    let deg = degrees(degree, dims)?;
    let kl = knot_list(knots, dims)?;
    let (pts, w, shape) = net(control_points, weights, dims)?;
    let mut kvs = Vec::with_capacity(dims);
    for a in 0..dims {
        kvs.push(knot_vector(&kl[a], deg[a], shape[a], a)?);
    }
    Ok(match dims {
        1 => IoEntity::Curve(NurbsCurve::from_knot_vector(kvs.remove(0), pts, w).py()?),
        2 => {
            let [a, b]: [KnotVector; 2] = kvs.try_into().expect("two knot vectors");
            IoEntity::Surface(NurbsSurface::from_flat([a, b], pts, w).py()?)
        }
        _ => {
            let [a, b, c]: [KnotVector; 3] = kvs.try_into().expect("three knot vectors");
            IoEntity::Volume(NurbsVolume::from_flat([a, b, c], pts, w).py()?)
        }
    })
}

/// A surface for `dnurbs_surface`: a `Surface` entity as it is, or a control net `(nu, nv, 3)`
/// with `degree`, optional `weights (nu, nv)` and optional knots (default: uniform, clamped).
pub(crate) fn surface_of(
    net_or_surface: &Bound<'_, PyAny>,
    degree: (usize, usize),
    weights: Option<&Bound<'_, PyAny>>,
    knots: Option<&Bound<'_, PyAny>>,
) -> PyResult<NurbsSurface> {
    if let Ok(e) = net_or_surface.cast::<Entity>() {
        return match &e.borrow().entity {
            IoEntity::Surface(s) => Ok(s.clone()),
            other => Err(PyValueError::new_err(format!(
                "expected a Surface or a control net (nu, nv, 3), got a {}",
                other.type_name()
            ))),
        };
    }
    let (pts, w, shape) = net(net_or_surface, weights, 2)?;
    let deg = [degree.0, degree.1];
    let kvs = match knots {
        Some(k) if !k.is_none() => {
            let kl = knot_list(k, 2)?;
            [
                knot_vector(&kl[0], deg[0], shape[0], 0)?,
                knot_vector(&kl[1], deg[1], shape[1], 1)?,
            ]
        }
        _ => {
            let uniform = |axis: usize| {
                let (n, p) = (shape[axis], deg[axis]);
                let mut k = vec![0.0; p + 1];
                let spans = n.saturating_sub(p).max(1);
                k.extend((1..spans).map(|i| i as f64 / spans as f64));
                k.extend(std::iter::repeat_n(1.0, p + 1));
                KnotVector::new(k, p, n)
                    .map_err(|source| SplineError::Knots { axis, source })
                    .py()
            };
            [uniform(0)?, uniform(1)?]
        }
    };
    NurbsSurface::from_flat(kvs, pts, w).py()
}

#[pymethods]
impl Curve {
    /// `Curve(degree, knots, control_points, weights=None, name=None)`: knots
    /// `(n + degree + 1,)`, control points `(n, 3)`, weights `(n,)` (all 1 when omitted).
    #[new]
    #[pyo3(signature = (degree, knots, control_points, weights = None, name = None))]
    fn new(
        degree: &Bound<'_, PyAny>,
        knots: &Bound<'_, PyAny>,
        control_points: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let e = build(1, degree, knots, control_points, weights)?;
        Ok(PyClassInitializer::from(Entity { entity: e, name }).add_subclass(Curve))
    }
}

#[pymethods]
impl Surface {
    /// `Surface((p, q), (knots_u, knots_v), control_points (nu, nv, 3), weights (nu, nv) = None,
    /// name=None)`.
    #[new]
    #[pyo3(signature = (degree, knots, control_points, weights = None, name = None))]
    fn new(
        degree: &Bound<'_, PyAny>,
        knots: &Bound<'_, PyAny>,
        control_points: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let e = build(2, degree, knots, control_points, weights)?;
        Ok(PyClassInitializer::from(Entity { entity: e, name }).add_subclass(Surface))
    }
}

#[pymethods]
impl Volume {
    /// `Volume((p, q, r), (ku, kv, kw), control_points (nu, nv, nw, 3), weights (nu, nv, nw) =
    /// None, name=None)`.
    #[new]
    #[pyo3(signature = (degree, knots, control_points, weights = None, name = None))]
    fn new(
        degree: &Bound<'_, PyAny>,
        knots: &Bound<'_, PyAny>,
        control_points: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let e = build(3, degree, knots, control_points, weights)?;
        Ok(PyClassInitializer::from(Entity { entity: e, name }).add_subclass(Volume))
    }
}

/// Evaluates the point at `t` (d parameters) of an entity.
#[inline]
fn point_of(e: &IoEntity, t: &[f64]) -> Result<Vec3, SplineError> {
    match e {
        IoEntity::Curve(c) => c.point(t[0]),
        IoEntity::Surface(s) => s.point(t[0], t[1]),
        IoEntity::Volume(v) => v.point(t[0], t[1], t[2]),
    }
}

impl Entity {
    fn dims(&self) -> usize {
        self.entity.param_dims()
    }

    fn net_shape(&self) -> Vec<usize> {
        match &self.entity {
            IoEntity::Curve(c) => vec![c.control_points().len()],
            IoEntity::Surface(s) => s.dims().to_vec(),
            IoEntity::Volume(v) => v.dims().to_vec(),
        }
    }

    fn knot_vectors(&self) -> Vec<&KnotVector> {
        match &self.entity {
            IoEntity::Curve(c) => vec![c.knots()],
            IoEntity::Surface(s) => s.knots().iter().collect(),
            IoEntity::Volume(v) => v.knots().iter().collect(),
        }
    }

    fn control_slice(&self) -> (&[Vec3], &[f64]) {
        match &self.entity {
            IoEntity::Curve(c) => (c.control_points(), c.weights()),
            IoEntity::Surface(s) => (s.control_points(), s.weights()),
            IoEntity::Volume(v) => (v.control_points(), v.weights()),
        }
    }

    fn check_axis(&self, axis: usize) -> PyResult<()> {
        if axis >= self.dims() {
            return Err(PyValueError::new_err(format!(
                "axis {axis}: a {} has parametric axes 0..{}",
                self.entity.type_name(),
                self.dims()
            )));
        }
        Ok(())
    }

    /// Same Python class, new kernel entity.
    fn with(&self, py: Python<'_>, entity: IoEntity) -> PyResult<Py<PyAny>> {
        wrap(py, entity, self.name.clone())
    }
}

#[pymethods]
impl Entity {
    /// `"nurbs-curve"`, `"nurbs-surface"` or `"nurbs-volume"`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.entity.type_name()
    }

    /// The entity's name in its file (or None).
    #[getter]
    fn name(&self) -> Option<String> {
        self.name.clone()
    }

    /// Number of parameters: 1, 2 or 3.
    #[getter]
    fn param_dims(&self) -> usize {
        self.dims()
    }

    /// Degree per parametric axis, as a tuple.
    #[getter]
    fn degree(&self) -> Vec<usize> {
        self.knot_vectors().iter().map(|k| k.degree()).collect()
    }

    /// Knot vectors, one float64 array per parametric axis.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, numpy::PyArray1<f64>>> {
        use numpy::IntoPyArray;
        self.knot_vectors()
            .iter()
            .map(|k| k.as_slice().to_vec().into_pyarray(py))
            .collect()
    }

    /// Control points, shape `(n, 3)`, `(nu, nv, 3)` or `(nu, nv, nw, 3)` (a copy).
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArrayDyn<f64>> {
        let (p, _) = self.control_slice();
        let mut shape = self.net_shape();
        shape.push(3);
        let v: Vec<f64> = p.iter().flat_map(|q| [q.x, q.y, q.z]).collect();
        util::array_dyn(py, v, &shape)
    }

    /// Weights, the control net's shape (a copy).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArrayDyn<f64>> {
        let (_, w) = self.control_slice();
        util::array_dyn(py, w.to_vec(), &self.net_shape())
    }

    /// Replaces the control points: an array of the shape the getter gives (`(n, 3)`,
    /// `(nu, nv, 3)`, `(nu, nv, nw, 3)`), finite; the knots and weights stay.
    #[setter]
    fn set_control_points(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut want = self.net_shape();
        want.push(3);
        let (data, shape) = util::flat(value, "control_points")?;
        if shape != want {
            return Err(PyValueError::new_err(format!(
                "control_points: expected shape {want:?} (the control net's), got {shape:?}"
            )));
        }
        if let Some(k) = data.iter().position(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "control_points: value {k} (flat) is not finite"
            )));
        }
        let pts: Vec<Vec3> = data
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        match &mut self.entity {
            IoEntity::Curve(c) => c.set_control_points(pts),
            IoEntity::Surface(s) => s.set_control_points(pts),
            IoEntity::Volume(v) => v.set_control_points(pts),
        }
        .py()
    }

    /// Replaces the weights: an array of the control net's shape, positive and finite.
    #[setter]
    fn set_weights(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let want = self.net_shape();
        let (w, shape) = util::flat(value, "weights")?;
        if shape != want {
            return Err(PyValueError::new_err(format!(
                "weights: expected shape {want:?} (the control net's), got {shape:?}"
            )));
        }
        if let Some(k) = w.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(PyValueError::new_err(format!(
                "weights: value {k} (flat) = {} is not positive and finite",
                w[k]
            )));
        }
        match &mut self.entity {
            IoEntity::Curve(c) => c.set_weights(w),
            IoEntity::Surface(s) => s.set_weights(w),
            IoEntity::Volume(v) => v.set_weights(w),
        }
        .py()
    }

    /// Parameter domain per axis: a list of `(min, max)`.
    #[getter]
    fn domain(&self) -> Vec<(f64, f64)> {
        self.knot_vectors()
            .iter()
            .map(|k| {
                let d = k.domain();
                (d.min, d.max)
            })
            .collect()
    }

    /// Points at an `(n, d)` array of parameters (d = 1, 2, 3; a curve also takes `(n,)`):
    /// an `(n, 3)` array. Runs in Rust without the GIL, in parallel for large n. A parameter
    /// outside the domain raises `GeometryError` naming it.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let d = self.dims();
        let (t, n) = util::rows(params, d, "params")?;
        crate::limits::check_f64s(py, || format!("evaluate: {n} points"), 3.0 * n as f64)?;
        let mut out = vec![0.0; n * 3];
        let e = &self.entity;
        let work = |out: &mut [f64]| {
            util::fill(out, 3, |start, chunk| {
                for (k, o) in chunk.chunks_exact_mut(3).enumerate() {
                    let i = start + k;
                    let p = point_of(e, &t[i * d..i * d + d]).map_err(|err| (i, err))?;
                    o.copy_from_slice(&[p.x, p.y, p.z]);
                }
                Ok::<(), (usize, SplineError)>(())
            })
        };
        let r = if n < 256 {
            work(&mut out)
        } else {
            py.detach(|| work(&mut out))
        };
        r.map_err(|(i, err)| GeometryError::new_err(format!("params[{i}]: {err}")))?;
        Ok(util::array2(py, out, n, 3))
    }

    /// One point: `point(u)`, `point(u, v)` or `point(u, v, w)` as a tuple `(x, y, z)` (the
    /// low-overhead call for single points).
    #[pyo3(signature = (u, v = None, w = None))]
    fn point(&self, u: f64, v: Option<f64>, w: Option<f64>) -> PyResult<(f64, f64, f64)> {
        let p = match (&self.entity, v, w) {
            (IoEntity::Curve(c), None, None) => c.point(u),
            (IoEntity::Surface(s), Some(v), None) => s.point(u, v),
            (IoEntity::Volume(x), Some(v), Some(w)) => x.point(u, v, w),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "point: a {} takes {} parameters",
                    self.entity.type_name(),
                    self.dims()
                )));
            }
        }
        .py()?;
        Ok((p.x, p.y, p.z))
    }

    /// Partial derivatives up to `order` at an `(n, d)` parameter array. Curves: `(n, order+1,
    /// 3)`, `[:, k]` = d^k C/du^k. Surfaces: `(n, order+1, order+1, 3)`, `[:, a, b]` =
    /// d^(a+b) S / du^a dv^b (zero where a + b > order). Volumes: `(n, o+1, o+1, o+1, 3)` the
    /// same way. Index 0 is the point itself.
    fn derivatives<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        order: i64,
    ) -> PyResult<Bound<'py, numpy::PyArrayDyn<f64>>> {
        let order = util::count(order, "order")?;
        if order == 0 {
            // The points alone: `evaluate`'s loop (no derivative tables), reshaped.
            let mut shape = vec![0isize];
            let d = self.dims();
            shape[0] = -1;
            shape.extend(std::iter::repeat_n(1isize, d));
            shape.push(3);
            let pts = self.evaluate(py, params)?;
            return pts
                .call_method1("reshape", (shape,))?
                .cast_into()
                .map_err(Into::into);
        }
        if order > vclay_spline::MAX_DEGREE {
            return Err(PyValueError::new_err(format!(
                "order {order} is larger than {}",
                vclay_spline::MAX_DEGREE
            )));
        }
        let d = self.dims();
        let (t, n) = util::rows(params, d, "params")?;
        let o = order + 1;
        let per = o.pow(d as u32) * 3;
        crate::limits::check_f64s(
            py,
            || format!("derivatives: order={order} at {n} points"),
            n as f64 * per as f64,
        )?;
        let mut out = vec![0.0; n * per];
        let e = &self.entity;
        let r = py.detach(|| {
            util::fill(&mut out, per, |start, chunk| {
                for (k, dst) in chunk.chunks_exact_mut(per).enumerate() {
                    let i = start + k;
                    let q = &t[i * d..i * d + d];
                    let mut put = |idx: usize, p: &Vec3| {
                        dst[idx * 3..idx * 3 + 3].copy_from_slice(&[p.x, p.y, p.z])
                    };
                    match e {
                        IoEntity::Curve(c) => {
                            let ds = c.derivatives(q[0], order).map_err(|err| (i, err))?;
                            for (a, p) in ds.iter().enumerate().take(o) {
                                put(a, p);
                            }
                        }
                        IoEntity::Surface(s) => {
                            let ds = s.derivatives(q[0], q[1], order).map_err(|err| (i, err))?;
                            for (a, row) in ds.iter().enumerate().take(o) {
                                for (b, p) in row.iter().enumerate().take(o) {
                                    if a + b <= order {
                                        put(a * o + b, p);
                                    }
                                }
                            }
                        }
                        IoEntity::Volume(v) => {
                            let ds = v
                                .derivatives(q[0], q[1], q[2], order)
                                .map_err(|err| (i, err))?;
                            for (a, pl) in ds.iter().enumerate().take(o) {
                                for (b, row) in pl.iter().enumerate().take(o) {
                                    for (c, p) in row.iter().enumerate().take(o) {
                                        if a + b + c <= order {
                                            put((a * o + b) * o + c, p);
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
                Ok::<(), (usize, SplineError)>(())
            })
        });
        r.map_err(|(i, err)| GeometryError::new_err(format!("params[{i}]: {err}")))?;
        let mut shape = vec![n];
        shape.extend(std::iter::repeat_n(o, d));
        shape.push(3);
        Ok(util::array_dyn(py, out, &shape))
    }

    /// Surfaces: points on the tensor grid `u x v` (1-D arrays): a `(len(u), len(v), 3)` array
    /// (basis values once per axis; rows in parallel; the GIL released).
    ///
    /// `out`: an existing C-contiguous, writeable float64 array of shape `(len(u), len(v), 3)`
    /// to write the points into (as numpy's ufuncs do); it is returned. Without it a new array
    /// is returned. Reusing `out` saves the allocation of a fresh array per call.
    #[pyo3(signature = (u, v, out = None))]
    fn evaluate_grid<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        use numpy::{PyArrayMethods, PyUntypedArrayMethods};
        let IoEntity::Surface(s) = &self.entity else {
            return Err(PyValueError::new_err(
                "evaluate_grid: only surfaces have a grid evaluation (use evaluate)",
            ));
        };
        let (us, nu) = util::rows(u, 1, "u")?;
        let (vs, nv) = util::rows(v, 1, "v")?;
        let par = vclay_core::Parallelism::Auto;
        let Some(out) = out else {
            crate::limits::check_f64s(
                py,
                || format!("evaluate_grid: u ({nu} values) x v ({nv} values)"),
                3.0 * nu as f64 * nv as f64,
            )?;
            let mut flat = vec![0.0; 3 * nu * nv];
            py.detach(|| s.eval_grid_into_flat(&us, &vs, &mut flat, par))
                .py()?;
            return Ok(util::array_dyn(py, flat, &[nu, nv, 3]).into_any());
        };
        let arr = out.cast::<numpy::PyArrayDyn<f64>>().map_err(|_| {
            PyValueError::new_err("evaluate_grid: out must be a numpy float64 array")
        })?;
        if arr.shape() != [nu, nv, 3] {
            return Err(PyValueError::new_err(format!(
                "evaluate_grid: out has shape {:?}, expected ({nu}, {nv}, 3)",
                arr.shape()
            )));
        }
        if !arr.is_c_contiguous() {
            return Err(PyValueError::new_err(
                "evaluate_grid: out must be C-contiguous",
            ));
        }
        let mut rw = arr.try_readwrite().map_err(|e| {
            PyValueError::new_err(format!(
                "evaluate_grid: out is not writeable or is borrowed: {e}"
            ))
        })?;
        let slice = rw.as_slice_mut().map_err(|e| {
            PyValueError::new_err(format!("evaluate_grid: out must be C-contiguous: {e}"))
        })?;
        py.detach(|| s.eval_grid_into_flat(&us, &vs, slice, par))
            .py()?;
        drop(rw);
        Ok(out.clone())
    }

    /// A new entity with `value` inserted `times` times into the knot vector of `axis`
    /// (Piegl & Tiller A5.1); the shape is unchanged.
    #[pyo3(signature = (value, times = 1, axis = 0))]
    fn insert_knot(
        &self,
        py: Python<'_>,
        value: f64,
        times: i64,
        axis: i64,
    ) -> PyResult<Py<PyAny>> {
        let (times, axis) = (util::count(times, "times")?, util::count(axis, "axis")?);
        self.check_axis(axis)?;
        let e = match &self.entity {
            IoEntity::Curve(c) => IoEntity::Curve(c.insert_knot(value, times).py()?),
            IoEntity::Surface(s) => IoEntity::Surface(s.insert_knot(axis, value, times).py()?),
            IoEntity::Volume(v) => IoEntity::Volume(v.insert_knot(axis, value, times).py()?),
        };
        self.with(py, e)
    }

    /// A new entity with the degree along `axis` raised by `times` (Piegl & Tiller A5.9); the
    /// shape is unchanged.
    #[pyo3(signature = (times = 1, axis = 0))]
    fn elevate_degree(&self, py: Python<'_>, times: i64, axis: i64) -> PyResult<Py<PyAny>> {
        let (times, axis) = (util::count(times, "times")?, util::count(axis, "axis")?);
        self.check_axis(axis)?;
        let e = match &self.entity {
            IoEntity::Curve(c) => IoEntity::Curve(c.elevate_degree(times).py()?),
            IoEntity::Surface(s) => IoEntity::Surface(s.elevate_degree(axis, times).py()?),
            IoEntity::Volume(v) => IoEntity::Volume(v.elevate_degree(axis, times).py()?),
        };
        self.with(py, e)
    }

    /// Surfaces and volume boundaries as triangles: `(vertices (n, 3), triangles (m, 3) uint32,
    /// normals (n, 3))`, `samples` per parametric axis.
    #[pyo3(signature = (samples = 32))]
    fn tessellate<'py>(&self, py: Python<'py>, samples: i64) -> PyResult<Bound<'py, PyAny>> {
        let samples = util::count(samples, "samples")?;
        check_tessellation(py, &[self.dims()], samples)?;
        let e = &self.entity;
        let mesh = py.detach(|| tessellate_one(e, samples))?;
        util::mesh_arrays(py, &mesh)
    }

    /// Pickling and `copy`: the constructor's arguments (`degree, knots, control_points,
    /// weights, name`) as arrays, so the copy is exact to the bit.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let e = slf.borrow();
        let knots = e.knots(py);
        let knots: Bound<'py, PyAny> = if e.dims() == 1 {
            knots[0].clone().into_any()
        } else {
            pyo3::types::PyTuple::new(py, knots)?.into_any()
        };
        let args = (
            e.degree(),
            knots,
            e.control_points(py),
            e.weights(py),
            e.name.clone(),
        );
        (slf.get_type(), args)
            .into_pyobject(py)
            .map(|t| t.into_any())
    }

    /// The entity as a dict of the vclay model JSON format (`docs/formats.md`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = vclay_io::to_json(std::slice::from_ref(&self.entity));
        let first = v
            .get("entities")
            .and_then(|e| e.get(0))
            .cloned()
            .unwrap_or(v);
        util::json_to_py(py, &first)
    }

    fn __repr__(&self) -> String {
        let shape = self.net_shape();
        format!(
            "<vclay {} degree {:?}, {} control points{}>",
            self.entity.type_name(),
            self.degree(),
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(" x "),
            match &self.name {
                Some(n) => format!(", name {n:?}"),
                None => String::new(),
            }
        )
    }
}

/// Checks a tessellation of `entities` at `samples` per axis against the memory limit
/// (`vclay convert --samples`'s estimate).
/// `dims`: the entities' parameter counts (1 curve, 2 surface, 3 volume).
fn check_tessellation(py: Python<'_>, dims: &[usize], samples: usize) -> PyResult<()> {
    let count = |d: usize| dims.iter().filter(|&&k| k == d).count();
    let (surfaces, volumes) = (count(2), count(3));
    crate::limits::check(
        py,
        || {
            format!(
                "samples={samples} ({surfaces} surfaces, {volumes} volumes: about {:.3e} vertices)",
                (samples as f64).powi(2) * (surfaces as f64 + 6.0 * volumes as f64)
            )
        },
        vclay_session::limits::tessellation_bytes(samples, surfaces, volumes),
    )
}

fn tessellate_one(e: &IoEntity, samples: usize) -> PyResult<TriMesh> {
    if samples < 2 {
        return Err(PyValueError::new_err("samples must be at least 2"));
    }
    let mut m = TriMesh::new();
    match e {
        IoEntity::Curve(_) => {
            return Err(PyValueError::new_err(
                "a curve has no triangles (use evaluate for a polyline)",
            ));
        }
        IoEntity::Surface(s) => tessellate_surface(s, [samples; 2], &mut m).py()?,
        IoEntity::Volume(v) => tessellate_volume_boundary(v, [samples; 3], &mut m).py()?,
    }
    Ok(m)
}

/// The extension as the converter sees it (`.geomdl.json` is one extension).
pub fn ext_of(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.ends_with(".geomdl.json") {
        return "geomdl.json".into();
    }
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// What a file held.
pub enum Loaded {
    /// Exact geometry; with STEP B-rep faces, their trimming loops (applied when meshing).
    Entities(Vec<NamedEntity>, Vec<TrimmedFace>),
    /// Triangle meshes.
    Meshes(Vec<TriMesh>),
}

/// Domain-triangle subdivision level of a triangular NURBS file when it is meshed (`level^2`
/// triangles per domain triangle; `vclay convert`'s `TRIANGULAR_TESSELLATION_LEVEL`).
pub const TRIANGULAR_TESSELLATION_LEVEL: usize = 8;

fn file_err(path: &Path, e: impl std::fmt::Display) -> PyErr {
    FileError::new_err(format!("{}: {e}", path.display()))
}

/// Reads any file the command line's `convert`/`eval`/`render` read, recognized by content
/// through the session layer's one way in (`vclay_session::open::identify`): model JSON,
/// geomdl JSON, STEP and IGES (`vclay_io::model::import_model`; STEP faces keep their
/// trimming loops), triangular NURBS (meshed), lattices (`.ovm`: the boundary limit surface
/// as bicubic patches; `.vtu`: the boundary faces), meshes (OBJ, STL, PLY, glb). Scenarios,
/// sessions, PDE specs and point clouds raise `FileError` naming what opens them. Without the
/// GIL.
pub fn read_any(path: &Path) -> PyResult<Loaded> {
    use vclay_session::FileKind as K;
    if ext_of(path) == "gltf" {
        return Ok(Loaded::Meshes(read_gltf(path)?));
    }
    let kind = vclay_session::open::identify(path).py()?;
    let ext = ext_of(path);
    let wrong_ext = |allowed: &str| {
        file_err(
            path,
            format!(
                "holds {} but its extension .{ext} is not one of {allowed}; rename it",
                kind.describe()
            ),
        )
    };
    match kind {
        K::ModelJson | K::Step | K::Iges => {
            let want = match kind {
                K::Step => ["step", "stp", "p21"].as_slice(),
                K::Iges => ["igs", "iges"].as_slice(),
                _ => ["json", "geomdl.json"].as_slice(),
            };
            if !want.contains(&ext.as_str()) {
                return Err(wrong_ext(&format!(".{}", want.join(", ."))));
            }
            let m = vclay_io::model::import_model(path).py()?;
            Ok(Loaded::Entities(m.entities, m.faces))
        }
        K::Geomdl => {
            let text = std::fs::read_to_string(path).map_err(|e| file_err(path, e))?;
            let ents = parse_geomdl(&text).map_err(|e| file_err(path, e))?;
            Ok(Loaded::Entities(ents, Vec::new()))
        }
        K::Triangular => {
            let t = vclay_io::triangular::read_triangular(path).py()?;
            let mut mesh = TriMesh::new();
            t.surface
                .tessellate(TRIANGULAR_TESSELLATION_LEVEL, &mut mesh)
                .map_err(|e| file_err(path, e))?;
            Ok(Loaded::Meshes(vec![mesh]))
        }
        K::Lattice if ext == "ovm" => Ok(Loaded::Entities(lattice_patches(path)?, Vec::new())),
        K::Lattice if ext == "vtu" => {
            let lattice = vclay_lattice::formats::vtu::read(path).py()?;
            let mut mesh = vclay_lattice::boundary_mesh(&lattice);
            if mesh.triangles.is_empty() {
                return Err(file_err(path, "the lattice has no boundary faces"));
            }
            mesh.compute_normals();
            Ok(Loaded::Meshes(vec![mesh]))
        }
        K::Lattice => Err(wrong_ext(".ovm, .vtu")),
        K::Mesh => match ext.as_str() {
            "glb" => Ok(Loaded::Meshes(read_glb(path).py()?)),
            "obj" | "stl" | "ply" => Ok(Loaded::Meshes(vec![read_mesh(path).py()?])),
            _ => Err(wrong_ext(".obj, .stl, .ply, .glb")),
        },
        K::Scenario | K::Session | K::PdeSpec | K::PointCloud => Err(file_err(
            path,
            format!(
                "{}, not a model or mesh file: {} (in Python: {})",
                kind.describe(),
                kind.commands(),
                match kind {
                    K::PdeSpec => "vclay.PdeSurface.read, vclay.open",
                    K::PointCloud => "vclay.fit_surface",
                    _ => "vclay.open",
                }
            ),
        )),
    }
}

/// A `.gltf` file (JSON with one buffer, embedded as a `data:` URI or in a file beside it)
/// read by vclay-io's glb reader (`decode_glb`): the JSON and the buffer are packed into the
/// binary container glb is, so both forms share one reader (meshes' triangles, y-up to z-up).
fn read_gltf(path: &Path) -> PyResult<Vec<TriMesh>> {
    let text = std::fs::read_to_string(path).map_err(|e| file_err(path, e))?;
    let mut json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| file_err(path, format!("invalid JSON: {e}")))?;
    let buffers = json.get_mut("buffers").and_then(|b| b.as_array_mut());
    let bin = match buffers {
        None => Vec::new(),
        Some(b) if b.len() > 1 => {
            return Err(file_err(
                path,
                format!(
                    "{} buffers: vclay reads glTF files with one buffer",
                    b.len()
                ),
            ));
        }
        Some(b) if b.is_empty() => Vec::new(),
        Some(b) => {
            let buf = b[0]
                .as_object_mut()
                .ok_or_else(|| file_err(path, "buffers[0] is not an object"))?;
            let uri = buf
                .remove("uri")
                .and_then(|u| u.as_str().map(str::to_string))
                .ok_or_else(|| file_err(path, "buffers[0] has no uri"))?;
            if let Some(data) = uri.strip_prefix("data:") {
                let (_, b64) = data
                    .split_once(";base64,")
                    .ok_or_else(|| file_err(path, "buffers[0].uri: a data URI without ;base64,"))?;
                base64(b64).ok_or_else(|| file_err(path, "buffers[0].uri: invalid base64"))?
            } else {
                let file = path.parent().unwrap_or(Path::new(".")).join(&uri);
                std::fs::read(&file).map_err(|e| file_err(path, format!("buffer {uri}: {e}")))?
            }
        }
    };
    let mut head = serde_json::to_vec(&json).map_err(|e| file_err(path, e))?;
    while head.len() % 4 != 0 {
        head.push(b' ');
    }
    let mut body = bin;
    while body.len() % 4 != 0 {
        body.push(0);
    }
    let total = 12 + 8 + head.len() + if body.is_empty() { 0 } else { 8 + body.len() };
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(head.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&head);
    if !body.is_empty() {
        glb.extend_from_slice(&(body.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"BIN\0");
        glb.extend_from_slice(&body);
    }
    vclay_io::gltf::decode_glb(&glb).map_err(|e| file_err(path, e))
}

/// Standard base64 (RFC 4648, padding optional) to bytes; `None` on a character outside it.
fn base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in text.bytes().filter(|c| !c.is_ascii_whitespace()) {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            b'=' => break,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// The boundary limit surface of the subdivision solid whose control lattice is the `.ovm`
/// file `path` (smooth boundary rule) as bicubic patches (`vclay_lattice::boundary_patches`,
/// as `vclay convert LATTICE.ovm` reads it), its memory checked first (`vclay convert`'s
/// estimate: the solid sampled at the patch levels).
fn lattice_patches(path: &Path) -> PyResult<Vec<NamedEntity>> {
    use vclay_lattice::limit_surface::DEFAULT_PATCH_SAMPLE_LEVELS as LEVELS;
    use vclay_lattice::{BoundaryRule, Features, SubdivisionRules, boundary_patches};
    let lattice = vclay_lattice::formats::ovm::read(path).py()?;
    Python::attach(|py| {
        crate::limits::check(
            py,
            || format!("{}: limit patches ({LEVELS} sample levels)", path.display()),
            vclay_session::limits::subdivision_bytes(lattice.num_cells(), LEVELS + 1),
        )
    })?;
    let p = boundary_patches(
        &lattice,
        &Features::none(&lattice),
        SubdivisionRules::new(BoundaryRule::Smooth),
        LEVELS,
    )
    .map_err(|e| file_err(path, format!("boundary limit patches: {e}")))?;
    Ok(p.patches
        .into_iter()
        .zip(p.exact)
        .zip(p.faces)
        .map(|((s, exact), f)| NamedEntity {
            name: Some(format!(
                "limit patch of boundary {f} ({})",
                if exact { "exact" } else { "fitted" }
            )),
            entity: IoEntity::Surface(s),
        })
        .collect())
}

pub fn mesh_of(loaded: &Loaded, samples: usize) -> PyResult<TriMesh> {
    let mut all = TriMesh::new();
    match loaded {
        Loaded::Entities(es, faces) => {
            let dims: Vec<usize> = es.iter().map(|e| e.entity.param_dims()).collect();
            // Called without the GIL (inside `detach`): take it for the check's exception.
            Python::attach(|py| check_tessellation(py, &dims, samples))?;
            let on_face: std::collections::HashSet<usize> =
                faces.iter().map(|f| f.entity).collect();
            for (i, e) in es.iter().enumerate() {
                if !on_face.contains(&i) && !matches!(e.entity, IoEntity::Curve(_)) {
                    all.append(&tessellate_one(&e.entity, samples)?);
                }
            }
            // STEP faces: their surfaces with the trimming loops applied.
            for f in faces {
                let Some(IoEntity::Surface(s)) = es.get(f.entity).map(|e| &e.entity) else {
                    continue;
                };
                let m = tessellate_trimmed(f, s, [samples; 2])
                    .map_err(|e| GeometryError::new_err(format!("face #{}: {e}", f.step_id)))?;
                all.append(&m);
            }
            if all.triangles.is_empty() {
                return Err(GeometryError::new_err(
                    "the model holds only curves (or faces trimmed to nothing): nothing to tessellate into a mesh",
                ));
            }
        }
        Loaded::Meshes(ms) => {
            for m in ms {
                all.append(m);
            }
        }
    }
    Ok(all)
}

/// Writes `loaded` to `out` in the format its extension names.
pub fn write_any(loaded: &Loaded, out: &Path, samples: usize, stem: &str) -> PyResult<()> {
    let exact = || match loaded {
        Loaded::Entities(e, _) => Ok(e),
        Loaded::Meshes(_) => Err(FileError::new_err(format!(
            "{}: a mesh cannot be converted to exact NURBS geometry",
            out.display()
        ))),
    };
    match ext_of(out).as_str() {
        "geomdl.json" => write_geomdl(out, exact()?).py(),
        "json" => write_named_model(out, exact()?).py(),
        "step" | "stp" => write_step(out, exact()?).py(),
        "igs" | "iges" => write_iges(out, exact()?).py(),
        "obj" | "stl" | "ply" => write_mesh(out, &mesh_of(loaded, samples)?).py(),
        "glb" => write_glb(out, &[GlbMesh::new(stem, mesh_of(loaded, samples)?)]).py(),
        other => Err(FileError::new_err(format!(
            "{}: unknown output format \".{other}\"; expected .json, .geomdl.json, .step, .stp, .igs, .iges, .obj, .stl, .ply or .glb",
            out.display()
        ))),
    }
}

/// `load(path)`: the entities of a model file as a list of `Curve`/`Surface`/`Volume`: vclay
/// model JSON, geomdl JSON, STEP, IGES (recognized by content, as `vclay.open` and the command
/// line do), or a lattice `.ovm` (its boundary limit surface as bicubic patches). Errors name
/// the file and the place (`FileError`, e.g. `m.json: entities[0].knots[1]: ...`).
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyList>> {
    let ents = match py.detach(|| read_any(&path))? {
        Loaded::Entities(e, _) => e,
        Loaded::Meshes(_) => {
            return Err(FileError::new_err(format!(
                "{}: a mesh or a triangular NURBS file holds no tensor-product NURBS entities (use read_mesh for its triangles, vclay.open for a session)",
                path.display()
            )));
        }
    };
    let items = ents
        .into_iter()
        .map(|n| wrap(py, n.entity, n.name))
        .collect::<PyResult<Vec<_>>>()?;
    PyList::new(py, items)
}

fn named(entities: &Bound<'_, PyAny>) -> PyResult<Vec<NamedEntity>> {
    let mut out = Vec::new();
    for item in entities.try_iter()? {
        let item = item?;
        let e = item.cast::<Entity>().map_err(|_| {
            PyValueError::new_err("save: expected a list of vclay Curve/Surface/Volume")
        })?;
        let e = e.borrow();
        out.push(NamedEntity {
            name: e.name.clone(),
            entity: e.entity.clone(),
        });
    }
    Ok(out)
}

/// `save(path, entities, samples=48)`: writes entities in the format the extension names:
/// `.json` (vclay model), `.geomdl.json`, `.step`/`.stp`, `.igs`/`.iges`, or a tessellated mesh
/// (`.obj`, `.stl`, `.ply`, `.glb`; curves left out). Writes are atomic.
#[pyfunction]
#[pyo3(signature = (path, entities, samples = 48))]
fn save(path: PathBuf, entities: &Bound<'_, PyAny>, samples: i64) -> PyResult<()> {
    let samples = util::count(samples, "samples")?;
    let ents = named(entities)?;
    let stem = path
        .file_stem()
        .map_or("vclay".into(), |s| s.to_string_lossy().into_owned());
    entities
        .py()
        .detach(|| write_any(&Loaded::Entities(ents, Vec::new()), &path, samples, &stem))
}

/// `convert(input, output, samples=48)`: like `vclay convert`: reads what `load` and
/// `read_mesh` read (model JSON, geomdl JSON, STEP with its trimmed faces, IGES, triangular
/// NURBS, lattices `.ovm`/`.vtu`, meshes OBJ, STL, PLY, glb; by content) and writes the format
/// the output's extension names (model JSON, geomdl JSON, STEP, IGES, OBJ, STL, PLY, glb;
/// `samples` per parametric axis for meshes). A mesh cannot become exact geometry.
#[pyfunction]
#[pyo3(signature = (input, output, samples = 48))]
fn convert(py: Python<'_>, input: PathBuf, output: PathBuf, samples: i64) -> PyResult<()> {
    let samples = util::count(samples, "samples")?;
    if samples < 2 {
        return Err(PyValueError::new_err("samples must be at least 2"));
    }
    let stem = input
        .file_stem()
        .map_or("vclay".into(), |s| s.to_string_lossy().into_owned());
    py.detach(|| {
        let loaded = read_any(&input)?;
        write_any(&loaded, &output, samples, &stem)
    })
}

/// `read_mesh(path)`: an OBJ/STL/PLY/glb mesh, a `.vtu` lattice's boundary or a triangular
/// NURBS file (meshed) as `(vertices, triangles, normals)` arrays.
#[pyfunction]
#[pyo3(name = "read_mesh")]
fn read_mesh_py(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let mesh = match py.detach(|| read_any(&path))? {
        Loaded::Meshes(ms) => {
            let mut all = TriMesh::new();
            for m in &ms {
                all.append(m);
            }
            all
        }
        Loaded::Entities(..) => {
            return Err(FileError::new_err(format!(
                "{}: a model file, not a mesh (use load)",
                path.display()
            )));
        }
    };
    util::mesh_arrays(py, &mesh)
}

/// `write_mesh(path, vertices, triangles)`: writes an OBJ/STL/PLY/glb mesh (normals computed).
#[pyfunction]
#[pyo3(name = "write_mesh")]
fn write_mesh_py(
    path: PathBuf,
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mesh = util::mesh_from(vertices, triangles)?;
    let stem = path
        .file_stem()
        .map_or("vclay".into(), |s| s.to_string_lossy().into_owned());
    write_any(&Loaded::Meshes(vec![mesh]), &path, 2, &stem)
}
