//! `Ffd`: a free-form deformation lattice over a box (`vclay_ffd::FfdLattice`) with direct
//! manipulation (`ffd-direct-manipulation.txt` eq 7 for one point, eq 12 for many) and
//! deformation of `(n, 3)` point arrays (in parallel, without the GIL).

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_core::Vec3;
use vclay_ffd::{FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions};
use vclay_io::model::Entity as IoEntity;

use crate::errors::{GeometryError, PyResultExt};
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Ffd>()
}

/// A trivariate NURBS lattice over a box, the identity at rest: `Q(u, v, w)` with control
/// points at the Greville abscissae. Moving points of space (direct manipulation) moves the
/// control points by the least-norm displacement field (eqs 7, 12); `deform` maps points.
#[pyclass(module = "vclay", eq)]
#[derive(Debug, PartialEq)]
pub struct Ffd {
    lattice: FfdLattice,
}

/// The lattice spec of `degree` and `control_points` (one count or three), its size checked
/// against the memory limit (`vclay ffd --lattice`'s estimate) before anything is built.
fn spec(
    py: Python<'_>,
    degree: usize,
    control_points: Option<&Bound<'_, PyAny>>,
) -> PyResult<LatticeSpec> {
    let bad = || {
        PyValueError::new_err(
            "control_points: expected a non-negative integer or three (one per axis)",
        )
    };
    let cp: [usize; 3] = match control_points {
        None => [vclay_ffd::DEFAULT_CONTROL_POINTS.max(degree + 1); 3],
        Some(c) => {
            let v: Vec<i128> = if let Ok(n) = c.extract::<i128>() {
                vec![n; 3]
            } else {
                c.extract().map_err(|_| bad())?
            };
            let v: Vec<usize> = v
                .into_iter()
                .map(|n| usize::try_from(n).map_err(|_| bad()))
                .collect::<PyResult<_>>()?;
            v.try_into().map_err(|_| bad())?
        }
    };
    crate::limits::check(
        py,
        || format!("control_points={cp:?}"),
        vclay_session::limits::ffd_bytes(cp),
    )?;
    Ok(LatticeSpec {
        degree: [degree; 3],
        control_points: cp,
    })
}

#[pymethods]
impl Ffd {
    /// `Ffd(lo, hi, degree=3, control_points=4)`: a lattice over the box `[lo, hi]`;
    /// `control_points` is one count or three (per axis), each at least `degree + 1`.
    #[new]
    #[pyo3(signature = (lo, hi, degree = vclay_ffd::DEFAULT_DEGREE as i64, control_points = None),
        text_signature = "(lo, hi, degree=3, control_points=None)")]
    fn new(
        py: Python<'_>,
        lo: &Bound<'_, PyAny>,
        hi: &Bound<'_, PyAny>,
        degree: i64,
        control_points: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let s = spec(py, util::count(degree, "degree")?, control_points)?;
        let (lo, hi) = (util::vec3(lo, "lo")?, util::vec3(hi, "hi")?);
        let lattice = py.detach(|| FfdLattice::new(s, lo, hi)).py()?;
        Ok(Self { lattice })
    }

    /// `Ffd.enclosing(points, degree=3, control_points=4, margin=0.05)`: a lattice around the
    /// bounding box of an `(n, 3)` array, grown by `margin` times its extent.
    #[staticmethod]
    #[pyo3(signature = (points, degree = vclay_ffd::DEFAULT_DEGREE as i64, control_points = None, margin = vclay_ffd::DEFAULT_MARGIN),
        text_signature = "(points, degree=3, control_points=None, margin=0.05)")]
    fn enclosing(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        degree: i64,
        control_points: Option<&Bound<'_, PyAny>>,
        margin: f64,
    ) -> PyResult<Self> {
        let s = spec(py, util::count(degree, "degree")?, control_points)?;
        let pts = util::points(points, "points")?;
        let lattice = FfdLattice::enclosing(&pts, s, margin).py()?;
        Ok(Self { lattice })
    }

    /// Control points per axis.
    #[getter]
    fn dims(&self) -> [usize; 3] {
        self.lattice.dims()
    }

    /// The box `(lo, hi)`.
    #[getter]
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let (lo, hi) = self.lattice.bounds();
        (lo.into(), hi.into())
    }

    /// Current control points, `(nu, nv, nw, 3)` (a copy).
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArrayDyn<f64>> {
        let d = self.lattice.dims();
        let v: Vec<f64> = self
            .lattice
            .control_points()
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        util::array_dyn(py, v, &[d[0], d[1], d[2], 3])
    }

    /// Replaces the control points: a `(nu, nv, nw, 3)` array of finite numbers (the
    /// deformation follows; `reset` goes back to the rest lattice).
    #[setter]
    fn set_control_points(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let d = self.lattice.dims();
        let (data, shape) = util::flat(value, "control_points")?;
        if shape != [d[0], d[1], d[2], 3] {
            return Err(PyValueError::new_err(format!(
                "control_points: expected shape [{}, {}, {}, 3], got {shape:?}",
                d[0], d[1], d[2]
            )));
        }
        let pts = data
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        self.lattice.set_control_points(pts).py()
    }

    /// Weights `(nu, nv, nw)` (a copy; 1 at rest).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArrayDyn<f64>> {
        let d = self.lattice.dims();
        util::array_dyn(py, self.lattice.weights().to_vec(), &[d[0], d[1], d[2]])
    }

    /// Replaces the weights: a `(nu, nv, nw)` array, positive and finite.
    #[setter]
    fn set_weights(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let d = self.lattice.dims();
        let (data, shape) = util::flat(value, "weights")?;
        if shape != d {
            return Err(PyValueError::new_err(format!(
                "weights: expected shape {d:?}, got {shape:?}"
            )));
        }
        self.lattice.set_weights(data).py()
    }

    /// Parameters `(n, 3)` in `[0, 1]^3` of rest-space points `(n, 3)` (the linear map of
    /// section 2); a point outside the box raises `GeometryError`.
    fn parameters<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let pts = util::points(points, "points")?;
        let mut out = Vec::with_capacity(pts.len() * 3);
        for (i, p) in pts.iter().enumerate() {
            let t = self.lattice.parameters(p).ok_or_else(|| {
                GeometryError::new_err(format!(
                    "points[{i}] = ({}, {}, {}) is outside the lattice box",
                    p.x, p.y, p.z
                ))
            })?;
            out.extend_from_slice(&t);
        }
        Ok(util::array2(py, out, pts.len(), 3))
    }

    /// Where the deformation takes rest-space points: an `(n, 3)` array to an `(n, 3)` array
    /// (`Q(u(x), v(x), w(x))` inside the box, `x` itself outside). In parallel, GIL released.
    fn deform<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let (x, n) = util::rows(points, 3, "points")?;
        let mut out = vec![0.0; n * 3];
        let lat = &self.lattice;
        py.detach(|| {
            util::fill(&mut out, 3, |start, chunk| {
                for (k, o) in chunk.chunks_exact_mut(3).enumerate() {
                    let i = start + k;
                    let p = lat.deform_point(&Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]));
                    o.copy_from_slice(&[p.x, p.y, p.z]);
                }
                Ok::<(), ()>(())
            })
        })
        .expect("deform_point does not fail");
        Ok(util::array2(py, out, n, 3))
    }

    /// Direct manipulation of one point (eq 7): the rest-space point `source` goes to
    /// `target`. Afterwards `deform([source])` is `target`.
    fn move_point(&mut self, source: &Bound<'_, PyAny>, target: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = PointConstraint::from_rest_point(
            &self.lattice,
            util::vec3(source, "source")?,
            util::vec3(target, "target")?,
        )
        .py()?;
        let m = Manipulation::single(&self.lattice, &c).py()?;
        // `apply` panics only if a control point would overflow to infinity (pyo3 turns that
        // into a PanicException); `try_apply` (uncommitted in vclay-ffd) will report it.
        self.lattice.apply(&m);
        Ok(())
    }

    /// Direct manipulation of many points at once (eq 12): rest-space `sources` `(m, 3)` go to
    /// `targets` `(m, 3)` by the least-norm displacement. Conflicting constraints raise
    /// `GeometryError` naming them unless `least_squares=True`.
    #[pyo3(signature = (sources, targets, least_squares = false))]
    fn move_points(
        &mut self,
        py: Python<'_>,
        sources: &Bound<'_, PyAny>,
        targets: &Bound<'_, PyAny>,
        least_squares: bool,
    ) -> PyResult<()> {
        let s = util::points(sources, "sources")?;
        let t = util::points(targets, "targets")?;
        if s.len() != t.len() {
            return Err(PyValueError::new_err(format!(
                "sources ({}) and targets ({}) differ in length",
                s.len(),
                t.len()
            )));
        }
        let cs = s
            .iter()
            .zip(&t)
            .map(|(a, b)| PointConstraint::from_rest_point(&self.lattice, *a, *b))
            .collect::<Result<Vec<_>, _>>()
            .py()?;
        let opts = if least_squares {
            SolveOptions::least_squares()
        } else {
            SolveOptions::default()
        };
        let lat = &self.lattice;
        let m = py.detach(|| Manipulation::multi(lat, &cs, &opts)).py()?;
        // `apply` panics only if a control point would overflow to infinity (pyo3 turns that
        // into a PanicException); `try_apply` (uncommitted in vclay-ffd) will report it.
        self.lattice.apply(&m);
        Ok(())
    }

    /// Back to the rest lattice.
    fn reset(&mut self) {
        self.lattice.reset();
    }

    /// The lattice as a `Volume` (current control points and weights).
    fn volume(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        crate::nurbs::wrap(py, IoEntity::Volume(self.lattice.volume().clone()), None)
    }

    /// Pickling and `copy`: the constructor's arguments (`lo, hi, degree, control_points`)
    /// and, as the state, the current control points and weights (exact to the bit).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let f = slf.borrow();
        let (lo, hi) = f.bounds();
        let d = f.lattice.dims();
        let w = f.weights(py);
        let args = (lo, hi, f.lattice.degree()[0], d);
        (slf.get_type(), args, (f.control_points(py), w))
            .into_pyobject(py)
            .map(|t| t.into_any())
    }

    /// Restores the control points and weights saved by `__reduce__`.
    fn __setstate__(&mut self, state: (Bound<'_, PyAny>, Bound<'_, PyAny>)) -> PyResult<()> {
        self.set_weights(&state.1)?;
        self.set_control_points(&state.0)
    }

    fn __repr__(&self) -> String {
        let (lo, hi) = self.lattice.bounds();
        format!(
            "<vclay Ffd degree {:?}, {:?} control points over [{:?}, {:?}]>",
            self.lattice.degree(),
            self.lattice.dims(),
            <[f64; 3]>::from(lo),
            <[f64; 3]>::from(hi)
        )
    }
}
