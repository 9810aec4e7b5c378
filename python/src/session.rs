//! `Session`: the session layer (`vclay_session`) from Python: open any file (`vclay.open`),
//! build models from arrays (`dnurbs_surface`, `clay`), apply commands given as Python objects
//! (dicts, lists, numbers, numpy arrays and scalars, turned into the typed `Command` in Rust),
//! undo and redo, step with the GIL released, read state as numpy arrays, save, pickle and copy
//! bit for bit.
//!
//! Threads and signals: the session sits behind a mutex (the pyclass is frozen, so pyo3 keeps
//! no borrow flag); a call waits for another thread's call without holding the GIL. `step` and
//! `advance_to` run in chunks of [`STEP_CHUNK_MS`] with `check_signals` (Ctrl-C) between them.
//!
//! Arrays: control and data points come from [`Model::control_points`] and
//! [`Model::data_points`]; the control net's shape, weights and `surface()` from the model's
//! model-JSON export (the `Model` trait has no accessor for them), written to a temporary file
//! and read back (the shape is kept per model while its point count is unchanged).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, TryLockError};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use vclay_session::file::{self, RunInfo};
use vclay_session::scenario::{OutputSpec, Scenario};
use vclay_session::{Command, Model, ModelSpec, Session as KSession};

use crate::errors::{CommandError, PyResultExt, SessionError};
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Session>()?;
    m.add_function(wrap_pyfunction!(dnurbs_surface, m)?)?;
    m.add_function(wrap_pyfunction!(open, m)?)?;
    m.add_function(wrap_pyfunction!(clay, m)?)?;
    Ok(())
}

/// Wall time of one chunk of `Session.step` between checks for Ctrl-C and other threads.
pub const STEP_CHUNK_MS: u64 = 20;
/// Least time between two calls of `Session.step`'s `progress` callback.
pub const PROGRESS_EVERY_MS: u64 = 100;

/// A unique path in the temporary folder (`vclay-py-PID-N.EXT`).
fn temp_path(ext: &str) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "vclay-py-{}-{}.{ext}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ))
}

/// The exact geometry of model `m` (its model-JSON export: D-NURBS curves and surfaces, FFD
/// lattices as volumes, patches), or `None` for kinds whose geometry is not tensor-product
/// NURBS (subdivision solids, PDE surfaces, triangular D-NURBS).
fn exported_entities(m: &dyn Model) -> Option<Vec<vclay_io::model::NamedEntity>> {
    if !m.export_formats().contains(&"json") {
        return None;
    }
    let path = temp_path("json");
    let out = m
        .export(&path)
        .ok()
        .and_then(|()| vclay_io::model::read_named_model(&path).ok());
    let _ = std::fs::remove_file(&path);
    out.filter(|e| !e.is_empty())
}

/// The control net shape of model `m` with `count` control points, when its geometry is one
/// tensor-product entity with that many points: `(nu, nv)` for a surface, `(nu, nv, nw)` for
/// a volume, `(n,)` for a curve.
fn net_shape(
    entities: &Option<Vec<vclay_io::model::NamedEntity>>,
    count: usize,
) -> Option<Vec<usize>> {
    use vclay_io::model::Entity as E;
    let [one] = entities.as_deref()? else {
        return None;
    };
    let shape = match &one.entity {
        E::Curve(c) => vec![c.control_points().len()],
        E::Surface(s) => s.dims().to_vec(),
        E::Volume(v) => v.dims().to_vec(),
    };
    (shape.iter().product::<usize>() == count).then_some(shape)
}

/// `clay(mesh, cells=500, level=2, *, dt=None, name="clay")`: a closed triangle mesh as a
/// dynamic subdivision solid (virtual clay) in a new `Session`: a hexahedral lattice of about
/// `cells` cells whose level-`level` limit boundary is fitted to the mesh, as a scenario's
/// `[model] kind = "subdivision-solid"`, `file = MESH` would build it (`vclay clay`). `mesh` is a
/// mesh file path (OBJ, STL, PLY, glb) or a `(vertices (n, 3), triangles (m, 3))` pair. The size
/// is checked by the session layer before anything is built.
#[pyfunction]
#[pyo3(signature = (mesh, cells = 500, level = 2, *, dt = None, name = None),
    text_signature = "(mesh, cells=500, level=2, *, dt=None, name='clay')")]
fn clay(
    py: Python<'_>,
    mesh: &Bound<'_, PyAny>,
    cells: i64,
    level: i64,
    dt: Option<f64>,
    name: Option<String>,
) -> PyResult<Session> {
    use vclay_session::models::{KindSpec, solid};
    let cells = util::count(cells, "cells")?;
    let level = util::count(level, "level")?;
    let (file, temp) = if let Ok(p) = mesh.extract::<PathBuf>() {
        (p, false)
    } else {
        let (v, t) = mesh
            .extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>()
            .map_err(|_| {
                PyValueError::new_err("mesh: a mesh file path or a (vertices, triangles) pair")
            })?;
        let m = util::mesh_from(&v, &t)?;
        let p = temp_path("obj");
        vclay_io::mesh::write_mesh(&p, &m).py()?;
        (p, true)
    };
    let spec = ModelSpec::SubdivisionSolid(KindSpec {
        model: solid::ModelKeys {
            file: Some(std::path::absolute(&file).unwrap_or(file.clone())),
            cells: Some(cells),
            level: Some(level),
            ..Default::default()
        },
        material: Default::default(),
        simulation: solid::SimKeys {
            dt,
            ..Default::default()
        },
    });
    let name = name.unwrap_or_else(|| "clay".into());
    let built = py.detach(|| spec.build(Path::new(".")));
    if temp {
        let _ = std::fs::remove_file(&file);
    }
    let model = built.map_err(|e| {
        let key = if e.key == "file" && temp {
            "mesh".into()
        } else {
            e.key
        };
        let what = if temp {
            e.what.replace(&file.display().to_string(), "<mesh>")
        } else {
            e.what
        };
        crate::errors::argument(format!("clay: {key}: {what}"))
    })?;
    Ok(Session::wrap(
        KSession::with_model(&name, model).py()?,
        None,
    ))
}

impl Inner {
    /// Weights of model `model` and the net's shape; kinds without NURBS weights are a
    /// `SessionError`.
    fn weights(&self, model: Option<&str>) -> PyResult<(Vec<f64>, Vec<usize>)> {
        let m = self.model(model)?;
        let ents = exported_entities(m);
        let count = m.control_points().len();
        match (net_shape(&ents, count), ents.as_deref()) {
            (Some(shape), Some([e])) => {
                let w = match &e.entity {
                    vclay_io::model::Entity::Curve(c) => c.weights().to_vec(),
                    vclay_io::model::Entity::Surface(s) => s.weights().to_vec(),
                    vclay_io::model::Entity::Volume(v) => v.weights().to_vec(),
                };
                Ok((w, shape))
            }
            _ => Err(SessionError::new_err(format!(
                "a {} model has no NURBS weights",
                m.kind()
            ))),
        }
    }

    /// Applies `edits` to model `model` as one undo group; on a failure the applied part is
    /// undone. Returns how many were applied.
    fn apply_group(
        &mut self,
        py: Python<'_>,
        model: Option<&str>,
        edits: Vec<vclay_session::Edit>,
    ) -> PyResult<usize> {
        let n = edits.len();
        if n == 0 {
            return Ok(0);
        }
        let s = &mut self.session;
        let model = model.map(str::to_string);
        py.detach(|| {
            s.begin_group();
            let mut done = 0;
            let mut failed = None;
            for edit in edits {
                let c = vclay_session::Command {
                    model: model.clone(),
                    edit,
                };
                match s.apply(c) {
                    Ok(_) => done += 1,
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
            s.end_group();
            match failed {
                None => Ok(n),
                Some(e) => {
                    if done > 0 {
                        s.undo()?;
                    }
                    Err(e)
                }
            }
        })
        .py()
    }
}

impl Session {
    fn from_state_text(py: Python<'_>, text: &str, name: &str) -> PyResult<Self> {
        let (session, run) = py.detach(|| file::parse(text, name)).py()?;
        Ok(Self::wrap(session, run))
    }

    fn from_scenario(sc: Scenario) -> Self {
        let run = RunInfo {
            name: sc.name,
            end_step: sc.steps,
            output: sc.output,
        };
        Self::wrap(sc.session, Some(run))
    }
}

/// A D-NURBS surface session built from arrays (no scenario file): `points` is a control net
/// `(nu, nv, 3)` (or a `Surface`), with `degree`, `weights (nu, nv)` (default 1) and `knots`
/// (default uniform, clamped). `material`: a dict of `preset` (a Table 1 name), `per`, `mu`,
/// `gamma`, `alpha`, `beta` (defaults: the scenario defaults); `dt`: the time step (default:
/// the preset's, else 0.01 as for a model file opened by `vclay.open`); `engine`: "generalized" (default) or "frozen"; `dynamic_weights`: weights as
/// generalized coordinates (default: True with the generalized engine); `reference`: "rest"
/// (default) or "absolute" elastic reference; `fix`: control point ids held fixed; `name`: the
/// model name.
///
/// The values are the scenario keys of `docs/formats.md` (`[model]`, `[material]`,
/// `[simulation]`) as a typed `ModelSpec`, with the surface itself as a value. Forces, data
/// points to fit, material changes: `session.apply({"action": "data", "points": ...})`,
/// `{"action": "material", "mu": ...}`; then `session.step(n)`.
///
/// A bad value raises `ArgumentError` (a `ValueError`) naming the argument:
/// `dnurbs_surface: material["mu"]: -1 must be finite and non-negative`.
#[pyfunction]
#[pyo3(signature = (points, degree = (3, 3), weights = None, knots = None, *, material = None,
    dt = None, engine = None, dynamic_weights = None, reference = None, fix = None, name = None),
    text_signature = "(points, degree=(3, 3), weights=None, knots=None, *, material=None, dt=None, \
    engine=None, dynamic_weights=None, reference=None, fix=None, name=None)")]
#[allow(clippy::too_many_arguments)]
fn dnurbs_surface(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    degree: (i64, i64),
    weights: Option<&Bound<'_, PyAny>>,
    knots: Option<&Bound<'_, PyAny>>,
    material: Option<&Bound<'_, PyDict>>,
    dt: Option<f64>,
    engine: Option<String>,
    dynamic_weights: Option<bool>,
    reference: Option<String>,
    fix: Option<Vec<i64>>,
    name: Option<String>,
) -> PyResult<Session> {
    use vclay_session::models::{KindSpec, dnurbs};
    let degree = (
        util::count(degree.0, "degree[0]")?,
        util::count(degree.1, "degree[1]")?,
    );
    let fix = fix
        .unwrap_or_default()
        .into_iter()
        .enumerate()
        .map(|(i, id)| util::count(id, &format!("fix[{i}]")))
        .collect::<PyResult<Vec<usize>>>()?;
    let surface = crate::nurbs::surface_of(points, degree, weights, knots)?;
    // The session layer's bound on a sheet's size along each direction.
    let max = vclay_session::models::dnurbs::MAX_SHEET_SIZE;
    if let Some(n) = surface.dims().iter().find(|&&n| n > max) {
        return Err(crate::errors::argument(format!(
            "points: {n} control points along a direction; a D-NURBS sheet takes at most {max}"
        )));
    }
    let material: dnurbs::MaterialKeys = match material {
        Some(d) => util::from_py(d.as_any(), "material", crate::errors::argument)?,
        None => Default::default(),
    };
    // Without a time step or a preset naming one, the time step of a D-NURBS opened from a
    // model file (`vclay.open`): `dt=None` always works.
    let dt = dt.or_else(|| {
        material
            .preset
            .is_none()
            .then_some(vclay_session::open::MODEL_FILE_DT)
    });
    let spec = ModelSpec::DnurbsSurface(KindSpec {
        model: dnurbs::ModelKeys {
            surface: Some(surface),
            engine,
            weights: dynamic_weights.map(|d| if d { "dynamic" } else { "frozen" }.to_string()),
            fix,
            ..Default::default()
        },
        material,
        simulation: dnurbs::SimKeys {
            dt,
            reference,
            ..Default::default()
        },
    });
    let name = name.unwrap_or_else(|| "dnurbs-surface".into());
    let model = py.detach(|| spec.build(Path::new("."))).map_err(|e| {
        // The spec's keys are this function's arguments: name the argument, not a file.
        let arg = match e.key.as_str() {
            "weights" => "dynamic_weights".to_string(),
            k @ ("preset" | "per" | "mu" | "gamma" | "alpha" | "beta") => {
                format!("material[{k:?}]")
            }
            k => k.to_string(),
        };
        crate::errors::argument(format!("dnurbs_surface: {arg}: {}", e.what))
    })?;
    Ok(Session::wrap(
        KSession::with_model(&name, model).py()?,
        None,
    ))
}

/// `vclay.open(path)`: any file vclay reads, recognized by its content, as a `Session`: a
/// scenario, a saved session, a model file (JSON, STEP, IGES), a PDE spec, a lattice or a
/// mesh (`vclay_session::open`). A file that is not a session (a point cloud) raises
/// `FileError` naming the functions and commands that take it.
#[pyfunction]
fn open(py: Python<'_>, path: PathBuf) -> PyResult<Session> {
    let o = py.detach(|| vclay_session::open(&path)).py()?;
    Ok(Session::wrap(o.session, o.run))
}

/// A session: named models of any kind (D-NURBS, subdivision and B-spline solids, FFD, PDE
/// surfaces), their scheduled commands, the command log, undo and redo.
///
/// Threads: every method locks the session; a call from another thread while one runs (a
/// `step` in a worker thread, `energy()` from a monitor) waits for it without holding the GIL
/// (a long `step` lets others in between its chunks of about 20 ms), so no call fails with
/// "Already mutably borrowed".
#[pyclass(module = "vclay", frozen)]
#[derive(Debug)]
pub struct Session {
    inner: Mutex<Inner>,
}

#[derive(Debug)]
struct Inner {
    session: KSession,
    /// Scenario or saved run information (name, end step, outputs).
    run: Option<RunInfo>,
    /// Control net shapes by model name, with the control point count they hold for: found
    /// once by exporting the model's geometry (a refinement that changes the count finds it
    /// again).
    shapes: HashMap<String, (usize, Option<Vec<usize>>)>,
}

impl Inner {
    fn new(session: KSession, run: Option<RunInfo>) -> Self {
        Self {
            session,
            run,
            shapes: HashMap::new(),
        }
    }

    fn model(&self, name: Option<&str>) -> PyResult<&dyn Model> {
        self.session.model(name).py()
    }

    /// The control net shape of model `name` with `count` points (see [`net_shape`]).
    fn net_shape(&mut self, name: Option<&str>, count: usize) -> PyResult<Option<Vec<usize>>> {
        let key = match name {
            Some(n) => n.to_string(),
            None => self
                .session
                .model_names()
                .first()
                .map_or(String::new(), |n| n.to_string()),
        };
        if let Some((c, shape)) = self.shapes.get(&key)
            && *c == count
        {
            return Ok(shape.clone());
        }
        let shape = net_shape(&exported_entities(self.model(name)?), count);
        self.shapes.insert(key, (count, shape.clone()));
        Ok(shape)
    }
}

impl Session {
    fn wrap(session: KSession, run: Option<RunInfo>) -> Self {
        Self {
            inner: Mutex::new(Inner::new(session, run)),
        }
    }

    /// The session, locked: waits without the GIL while another thread holds it (Ctrl-C
    /// interrupts the wait).
    fn lock<'a>(&'a self, py: Python<'_>) -> PyResult<MutexGuard<'a, Inner>> {
        loop {
            match self.inner.try_lock() {
                Ok(g) => return Ok(g),
                // A panic inside a call (a pyo3 PanicException) leaves the session as the
                // kernel left it; the session layer's own checks keep it consistent.
                Err(TryLockError::Poisoned(p)) => return Ok(p.into_inner()),
                Err(TryLockError::WouldBlock) => {
                    py.detach(|| {
                        let _wait = self.inner.lock();
                    });
                    py.check_signals()?;
                }
            }
        }
    }
}

#[pymethods]
impl Session {
    /// An empty session (models come from `Session.load`).
    #[new]
    fn new() -> Self {
        Self::wrap(KSession::new(), None)
    }

    /// `Session.load(path)`: the same as `vclay.open(path)`: a scenario (models plus a
    /// scheduled timeline), a saved session, or any other file vclay opens as a session,
    /// recognized by content. Errors name the file, line and key (`FileError`).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        open(py, path)
    }

    /// The tools (edits) model `model` takes, as dicts: `action`, `acts_on`, `keys` (each with
    /// `name`, `value`, `unit`, `min`, `max`, `required`, `help`) and `help`; an action not
    /// listed raises `CommandError` when applied.
    #[pyo3(signature = (model = None))]
    fn tools<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let v = serde_json::to_value(me.model(model)?.tools())
            .map_err(|e| SessionError::new_err(e.to_string()))?;
        util::json_to_py(py, &v)
    }

    /// `Session.from_toml(text, base=".")`: a scenario given as a string (the keys of a
    /// scenario file, `docs/formats.md`); relative file names (`[model] file = ...`) are
    /// resolved against `base`. Errors name `<string>`, the line and the key (`FileError`).
    #[staticmethod]
    #[pyo3(signature = (text, base = PathBuf::from(".")), text_signature = "(text, base='.')")]
    fn from_toml(py: Python<'_>, text: &str, base: PathBuf) -> PyResult<Self> {
        let sc = py
            .detach(|| Scenario::parse(text, "<string>", "scenario", &base))
            .py()?;
        Ok(Self::from_scenario(sc))
    }

    /// Writes the session (every model's full state, the schedule, the command log) to a
    /// `.json` session file, atomically. Loading it and stepping continues bit for bit.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let s = &me.session;
        let run = me.run.as_ref();
        py.detach(|| file::save(&path, s, run)).py()
    }

    /// The session file's content as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let v = file::to_value(&me.session, me.run.as_ref()).py()?;
        util::json_to_py(py, &v)
    }

    /// `Session.from_dict(d)`: a session from the dict `to_dict` gives (the session file's
    /// content); it continues bit for bit as the saved session would have.
    #[staticmethod]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyAny>) -> PyResult<Self> {
        let v = util::py_to_json(d, "from_dict", crate::errors::FileError::new_err)?;
        let text = serde_json::to_string(&v).map_err(|e| SessionError::new_err(e.to_string()))?;
        Self::from_state_text(py, &text, "<from_dict>")
    }

    /// Pickling, `copy.deepcopy` and Dask: the session file's bytes (every model's full
    /// state, the schedule, the log and the run), loaded by `file::parse`: the copy continues
    /// bit for bit. The undo history is not kept (as in session files).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let bytes = {
            let me = slf.get().lock(py)?;
            let v = file::to_value(&me.session, me.run.as_ref()).py()?;
            serde_json::to_vec(&v).map_err(|e| SessionError::new_err(e.to_string()))?
        };
        let ctor = slf.get_type().getattr("_from_state")?;
        (ctor, (pyo3::types::PyBytes::new(py, &bytes),))
            .into_pyobject(py)
            .map(|t| t.into_any())
    }

    /// The session of `__reduce__`'s bytes.
    #[staticmethod]
    fn _from_state(py: Python<'_>, state: &[u8]) -> PyResult<Self> {
        let text = std::str::from_utf8(state)
            .map_err(|e| crate::errors::FileError::new_err(format!("<pickle>: {e}")))?;
        Self::from_state_text(py, text, "<pickle>")
    }

    /// Model names, in order.
    #[getter]
    fn models(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me
            .session
            .model_names()
            .iter()
            .map(|s| s.to_string())
            .collect())
    }

    /// Session time: the earliest model clock.
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.session.time())
    }

    /// The scenario's run length in steps (None for a session without run information).
    #[getter]
    fn scenario_steps(&self, py: Python<'_>) -> PyResult<Option<u64>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.run.as_ref().map(|r| r.end_step))
    }

    /// Steps taken by model `model` (default: the first).
    #[pyo3(signature = (model = None))]
    fn steps(&self, py: Python<'_>, model: Option<&str>) -> PyResult<u64> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.model(model)?.steps())
    }

    /// `kind` of model `model`: `dnurbs-curve`, `subdivision-solid`, ...
    #[pyo3(signature = (model = None))]
    fn kind(&self, py: Python<'_>, model: Option<&str>) -> PyResult<String> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.model(model)?.kind().name().to_string())
    }

    /// One line about model `model` (sizes).
    #[pyo3(signature = (model = None))]
    fn summary(&self, py: Python<'_>, model: Option<&str>) -> PyResult<String> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.model(model)?.summary())
    }

    /// Applies a command now: a dict (or JSON text) such as `{"action": "rope", "from": [1, 1,
    /// 1], "to": [1.5, 1.4, 1.6], "until": 0.5}` or `{"action": "set", "name":
    /// "edge_stiffness", "value": 80}`, optionally with `"model": name`. Returns the log line.
    /// A command that cannot apply raises `CommandError` and leaves the session unchanged.
    fn apply(&self, py: Python<'_>, command: &Bound<'_, PyAny>) -> PyResult<String> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let c: Command = util::from_py(command, "command", CommandError::new_err)?;
        let s = &mut me.session;
        py.detach(|| s.apply(c)).py()
    }

    /// Schedules commands (dicts with `"at"`: seconds) like a scenario's timeline.
    fn schedule(&self, py: Python<'_>, commands: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let timed: Vec<vclay_session::Timed> =
            util::from_py(commands, "schedule", CommandError::new_err)?;
        me.session.schedule_commands(timed).py()
    }

    /// Undoes the last command; returns its log entry as a dict.
    fn undo<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let entry = me.session.undo().py()?;
        let v = serde_json::to_value(&entry).map_err(|e| SessionError::new_err(e.to_string()))?;
        util::json_to_py(py, &v)
    }

    /// Applies the last undone command again; returns its log line.
    fn redo(&self, py: Python<'_>) -> PyResult<String> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        me.session.redo().py()
    }

    /// Whether there is something to undo.
    #[getter]
    fn can_undo(&self, py: Python<'_>) -> PyResult<bool> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.session.can_undo())
    }

    /// Whether there is something to redo.
    #[getter]
    fn can_redo(&self, py: Python<'_>) -> PyResult<bool> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        Ok(me.session.can_redo())
    }

    /// Advances every model by `n` steps (scheduled commands fire on the way), with the GIL
    /// released. Returns the log lines of the scheduled commands applied. A diverging model
    /// raises `DivergedError`.
    ///
    /// Long runs go in chunks of about [`STEP_CHUNK_MS`] ms: between chunks Ctrl-C (SIGINT)
    /// raises `KeyboardInterrupt` (the steps done so far stay done; `steps()` says how many),
    /// other threads may use the session, and `progress(done, n)` is called (at most every
    /// [`PROGRESS_EVERY_MS`] ms, and once at the end); an exception it raises stops the run
    /// the same way. Chunking does not change the result: stepping `n` at once or in parts
    /// gives the same bits.
    #[pyo3(signature = (n = 1, *, progress = None), text_signature = "(n=1, *, progress=None)")]
    fn step(
        &self,
        py: Python<'_>,
        n: i64,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Vec<String>> {
        let n = util::count(n, "n")? as u64;
        // The same bound as a scenario's `steps` and `vclay run --steps`.
        vclay_session::scenario::check_steps(n).map_err(PyValueError::new_err)?;
        let chunk = std::time::Duration::from_millis(STEP_CHUNK_MS);
        let every = std::time::Duration::from_millis(PROGRESS_EVERY_MS);
        let mut lines = Vec::new();
        let mut done = 0u64;
        let mut reported = std::time::Instant::now();
        while done < n {
            {
                let mut guard = self.lock(py)?;
                let s = &mut guard.session;
                let r = py.detach(|| {
                    let start = std::time::Instant::now();
                    let mut k = 0u64;
                    let mut more = Vec::new();
                    while done + k < n {
                        more.extend(s.step()?.1);
                        k += 1;
                        if start.elapsed() >= chunk {
                            break;
                        }
                    }
                    Ok::<_, vclay_session::SessionError>((k, more))
                });
                let (k, more) = r.py()?;
                done += k;
                lines.extend(more);
            }
            py.check_signals()?;
            if let Some(cb) = &progress
                && (done == n || reported.elapsed() >= every)
            {
                cb.call1((done, n))?;
                reported = std::time::Instant::now();
            }
        }
        Ok(lines)
    }

    /// Steps each model until its clock reaches `t` (within half a step), in chunks as `step`
    /// does: Ctrl-C raises `KeyboardInterrupt` between chunks (the steps done stay done).
    fn advance_to(&self, py: Python<'_>, t: f64) -> PyResult<Vec<String>> {
        let chunk = std::time::Duration::from_millis(STEP_CHUNK_MS);
        let mut lines = Vec::new();
        loop {
            let finished = {
                let mut guard = self.lock(py)?;
                let s = &mut guard.session;
                let r = py.detach(|| {
                    let start = std::time::Instant::now();
                    let mut more = Vec::new();
                    while start.elapsed() < chunk {
                        match s.advance_step(t)? {
                            Some(l) => more.extend(l),
                            None => return Ok::<_, vclay_session::SessionError>((true, more)),
                        }
                    }
                    Ok((false, more))
                });
                let (finished, more) = r.py()?;
                lines.extend(more);
                finished
            };
            if finished {
                return Ok(lines);
            }
            py.check_signals()?;
        }
    }

    /// Runs `steps` steps (default: the rest of the scenario) writing the scenario's
    /// `[output]` (frames, final files, energy table) into `out_dir`, like `vclay run`.
    /// Returns a dict: steps, mean_step_ms, frames, files, log. Ctrl-C raises
    /// `KeyboardInterrupt` within about 20 ms; the steps done stay done and their energy table
    /// is written.
    #[pyo3(signature = (out_dir, steps = None))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        out_dir: PathBuf,
        steps: Option<u64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let output = me.run.as_ref().map_or_else(
            || OutputSpec {
                every: vclay_session::scenario::DEFAULT_FRAME_EVERY,
                ..OutputSpec::default()
            },
            |r| r.output.clone(),
        );
        let done = me.model(None)?.steps();
        let steps = match (steps, &me.run) {
            (Some(n), _) => n,
            (None, Some(r)) => r.end_step.saturating_sub(done),
            (None, None) => {
                return Err(PyValueError::new_err(
                    "run: give `steps` (this session has no scenario run length)",
                ));
            }
        };
        let s = &mut me.session;
        // Ctrl-C: the callback takes the GIL about every STEP_CHUNK_MS to look for a signal, and
        // stops the run (the steps done stay done); the error is raised once the run returns.
        let mut interrupted: Option<PyErr> = None;
        let mut last = std::time::Instant::now();
        let chunk = std::time::Duration::from_millis(STEP_CHUNK_MS);
        let summary = py
            .detach(|| {
                let limits = vclay_session::run::RunLimits {
                    max_output: None,
                    max_memory: Some(crate::limits::max()),
                };
                vclay_session::run::run_with(s, steps, &out_dir, &output, &limits, &mut |_| {
                    if last.elapsed() < chunk {
                        return std::ops::ControlFlow::Continue(());
                    }
                    last = std::time::Instant::now();
                    match Python::attach(|py| py.check_signals()) {
                        Ok(()) => std::ops::ControlFlow::Continue(()),
                        Err(e) => {
                            interrupted = Some(e);
                            std::ops::ControlFlow::Break(())
                        }
                    }
                })
            })
            .py()?;
        if let Some(e) = interrupted {
            return Err(e);
        }
        let d = PyDict::new(py);
        d.set_item("steps", summary.steps)?;
        d.set_item("mean_step_ms", summary.mean_step_ms)?;
        d.set_item("max_step_ms", summary.max_step_ms)?;
        d.set_item("frames", summary.frames)?;
        d.set_item("files", summary.files)?;
        d.set_item("log", summary.log)?;
        Ok(d)
    }

    /// Energies of model `model` as a dict: `kinetic` (1/2 v^T M v), `elastic` (the internal
    /// energy of the deformation: springs or the metric-tensor energy of solids, the thin-plate
    /// under tension energy of D-NURBS), `tools` (energy stored in tools: the springs of ropes
    /// and data points), and `total` = kinetic + elastic + tools, so the parts add up to it.
    ///
    /// D-NURBS count a rope's spring at its material point and a data point's at the nearest
    /// point (`vclay_dynamics::dnurbs::spring_energy`). The command line's energy table
    /// (`vclay run`, per step) keeps D-NURBS `tools` at 0 and `total` = kinetic + elastic.
    #[pyo3(signature = (model = None))]
    fn energy<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyDict>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let e = me.model(model)?.energy();
        let d = PyDict::new(py);
        d.set_item("kinetic", e.kinetic)?;
        d.set_item("elastic", e.elastic)?;
        d.set_item("tools", e.tools)?;
        d.set_item("total", e.kinetic + e.elastic + e.tools)?;
        Ok(d)
    }

    /// Material and simulation parameters of model `model`: a list of dicts (name, value,
    /// min, max, doc); change one with `apply({"action": "set", "name": ..., "value": ...})`.
    #[pyo3(signature = (model = None))]
    fn params<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyList>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let ps = me.model(model)?.params();
        let items = ps
            .iter()
            .map(|p| {
                let d = PyDict::new(py);
                d.set_item("name", &p.name)?;
                d.set_item("value", p.value)?;
                d.set_item("min", p.min)?;
                d.set_item("max", p.max)?;
                d.set_item("doc", &p.doc)?;
                Ok(d)
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// The command log: a list of dicts (step, time, model, command, message).
    #[getter]
    fn log<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let v = serde_json::to_value(me.session.log())
            .map_err(|e| SessionError::new_err(e.to_string()))?;
        util::json_to_py(py, &v)
    }

    /// Everything model `model` saves (its session-file entry) as a dict.
    #[pyo3(signature = (model = None))]
    fn state<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let v = me.model(model)?.save().py()?;
        util::json_to_py(py, &v)
    }

    /// Control points of model `model` in the shape of its control net, as
    /// `Entity.control_points`: `(nu, nv, 3)` for a D-NURBS surface, `(n, 3)` for a curve,
    /// `(nu, nv, nw, 3)` for an FFD lattice; `(n, 3)` where the net is not a tensor grid
    /// (a subdivision solid's control lattice, patches). `.reshape(-1, 3)` flattens any.
    #[pyo3(signature = (model = None))]
    fn control_points<'py>(
        &self,
        py: Python<'py>,
        model: Option<&str>,
    ) -> PyResult<Bound<'py, numpy::PyArrayDyn<f64>>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let m = me.model(model)?;
        let pts = m.control_points();
        if pts.is_empty() {
            return Err(SessionError::new_err(format!(
                "a {} model has no control points (use mesh())",
                m.kind()
            )));
        }
        let mut shape = me.net_shape(model, pts.len())?.unwrap_or(vec![pts.len()]);
        shape.push(3);
        let v: Vec<f64> = pts.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        Ok(util::array_dyn(py, v, &shape))
    }

    /// Weights of model `model`, the shape of its control net (`(nu, nv)` for a D-NURBS
    /// surface, `(n,)` for a curve, `(nu, nv, nw)` for an FFD lattice). Kinds without NURBS
    /// weights raise `SessionError`.
    #[pyo3(signature = (model = None))]
    fn weights<'py>(
        &self,
        py: Python<'py>,
        model: Option<&str>,
    ) -> PyResult<Bound<'py, numpy::PyArrayDyn<f64>>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let (w, shape) = me.weights(model)?;
        Ok(util::array_dyn(py, w, &shape))
    }

    /// The current geometry of model `model` as a `Surface` (a D-NURBS surface, after the
    /// steps and edits so far; `entities` gives curves, volumes and every patch).
    #[pyo3(signature = (model = None))]
    fn surface(&self, py: Python<'_>, model: Option<&str>) -> PyResult<Py<PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let m = me.model(model)?;
        let ents = exported_entities(m).unwrap_or_default();
        let Some(e) = ents.into_iter().find(|e| e.entity.param_dims() == 2) else {
            return Err(SessionError::new_err(format!(
                "a {} model has no NURBS surface (see entities())",
                m.kind()
            )));
        };
        crate::nurbs::wrap(py, e.entity, e.name)
    }

    /// The current exact geometry of model `model` as a list of `Curve`/`Surface`/`Volume`
    /// (empty for kinds without tensor-product NURBS geometry: subdivision solids, PDE
    /// surfaces, triangular D-NURBS).
    #[pyo3(signature = (model = None))]
    fn entities<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyList>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let m = me.model(model)?;
        let items = exported_entities(m)
            .unwrap_or_default()
            .into_iter()
            .map(|e| crate::nurbs::wrap(py, e.entity, e.name))
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// Moves the control points of model `model` to `points` (the shape `control_points`
    /// gives, or `(n, 3)`), finite, as one undoable edit: a `move-point` command for each
    /// point that changed, grouped. Returns how many moved. A kind that does not take
    /// `move-point` raises `CommandError` and nothing changes.
    #[pyo3(signature = (points, model = None))]
    fn set_control_points(
        &self,
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        model: Option<&str>,
    ) -> PyResult<usize> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let now = me.model(model)?.control_points();
        let (data, shape) = util::flat(points, "points")?;
        if data.len() != 3 * now.len() || shape.last() != Some(&3) {
            return Err(PyValueError::new_err(format!(
                "points: expected {} points of 3 coordinates (the model's control points), got shape {shape:?}",
                now.len()
            )));
        }
        if let Some(k) = data.iter().position(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "points: value {k} (flat) is not finite"
            )));
        }
        let edits = now
            .iter()
            .zip(data.chunks_exact(3))
            .enumerate()
            .filter(|(_, (p, q))| p.x != q[0] || p.y != q[1] || p.z != q[2])
            .map(|(index, (_, q))| vclay_session::Edit::MovePoint {
                index,
                to: [q[0], q[1], q[2]],
            })
            .collect();
        me.apply_group(py, model, edits)
    }

    /// Sets the weights of model `model` (the shape `weights` gives, or flat), positive and
    /// finite, as one undoable edit (`set-weight` commands, grouped). Returns how many changed.
    #[pyo3(signature = (weights, model = None))]
    fn set_weights(
        &self,
        py: Python<'_>,
        weights: &Bound<'_, PyAny>,
        model: Option<&str>,
    ) -> PyResult<usize> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let (now, _) = me.weights(model)?;
        let (w, shape) = util::flat(weights, "weights")?;
        if w.len() != now.len() {
            return Err(PyValueError::new_err(format!(
                "weights: expected {} weights (the model's), got shape {shape:?}",
                now.len()
            )));
        }
        if let Some(k) = w.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(PyValueError::new_err(format!(
                "weights: value {k} (flat) = {} is not positive and finite",
                w[k]
            )));
        }
        let edits = now
            .iter()
            .zip(&w)
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(index, (_, &weight))| vclay_session::Edit::SetWeight { index, weight })
            .collect();
        me.apply_group(py, model, edits)
    }

    /// Data points of model `model`, `(n, 3)`: a solid's data (finest) lattice points; for the
    /// other kinds the vertices of the display mesh (curves: the display polyline).
    #[pyo3(signature = (model = None))]
    fn data_points<'py>(
        &self,
        py: Python<'py>,
        model: Option<&str>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let m = me.model(model)?;
        let p = m.data_points();
        if !p.is_empty() {
            return Ok(util::points_array(py, &p));
        }
        let mesh = m.display_mesh().py()?;
        if !mesh.positions.is_empty() {
            return Ok(util::points_array(py, &mesh.positions));
        }
        let curve = m
            .display_lines()
            .into_iter()
            .find(|l| l.role == Some(vclay_session::LineRole::Curve))
            .map(|l| l.points)
            .unwrap_or_default();
        Ok(util::points_array(py, &curve))
    }

    /// The display surface of model `model`: `(vertices, triangles, normals)`.
    #[pyo3(signature = (model = None))]
    fn mesh<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let mesh = me.model(model)?.display_mesh().py()?;
        util::mesh_arrays(py, &mesh)
    }

    /// Writes model `model` to `path` in the format its extension names (`.json`, `.obj`,
    /// `.ply`, `.stl`, `.vtu`, `.ovm`, `.glb`, `.step`, `.igs`, as the kind supports).
    #[pyo3(signature = (path, model = None))]
    fn export(&self, py: Python<'_>, path: PathBuf, model: Option<&str>) -> PyResult<()> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let m = me.model(model)?;
        py.detach(|| m.export(&path)).py()
    }

    /// `add(name, source, model=None)`: a copy of model `model` of session `source` (its
    /// current state, material and tools; not its scheduled commands) added to this session
    /// under `name`: how an empty `Session()` is filled, or models of several files are put
    /// side by side. A name already in use raises `SessionError`.
    #[pyo3(signature = (name, source, model = None))]
    fn add(
        &self,
        py: Python<'_>,
        name: &str,
        source: &Bound<'_, Session>,
        model: Option<&str>,
    ) -> PyResult<()> {
        let same = std::ptr::eq(self, source.get());
        let copy = if same {
            self.lock(py)?.model(model)?.clone_model()
        } else {
            source.get().lock(py)?.model(model)?.clone_model()
        };
        let mut guard = self.lock(py)?;
        guard.session.add_model(name, copy).py()
    }

    /// Number of models.
    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.lock(py)?.session.len())
    }

    /// Iterates over the model names.
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let names = self.models(py)?;
        PyList::new(py, names)?.try_iter().map(|i| i.into_any())
    }

    /// Whether a model of that name is in the session.
    fn __contains__(&self, py: Python<'_>, name: &str) -> PyResult<bool> {
        Ok(self.lock(py)?.session.model_names().contains(&name))
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let mut guard = self.lock(py)?;
        let me = &mut *guard;
        let names = me.session.model_names();
        let kinds: Vec<String> = names
            .iter()
            .filter_map(|n| {
                me.session
                    .model(Some(n))
                    .ok()
                    .map(|m| format!("{n} ({})", m.kind()))
            })
            .collect();
        Ok(format!(
            "<vclay Session t = {}: {}>",
            me.session.time(),
            kinds.join(", ")
        ))
    }
}
