//! `Session`: the session layer (`vclay_session`) from Python: load a scenario (`.toml`) or a
//! saved session (`.json`), apply commands given as dicts (the same values as a scenario's
//! timeline entries and the session file's log), undo and redo, step with the GIL released,
//! read state as numpy arrays, save bit for bit.
//!
//! Arrays of a model come from its [`Model::save`] JSON (control and data points) or its
//! display geometry (`mesh`); the session layer has no direct array accessor yet, so reading
//! points serializes the model's state once per call.

use std::path::{Path, PathBuf};

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
    Ok(())
}

impl Session {
    fn from_state_text(py: Python<'_>, text: &str, name: &str) -> PyResult<Self> {
        let (session, run) = py.detach(|| file::parse(text, name)).py()?;
        Ok(Self { session, run })
    }

    fn from_scenario(sc: Scenario) -> Self {
        Self {
            session: sc.session,
            run: Some(RunInfo {
                name: sc.name,
                end_step: sc.steps,
                output: sc.output,
            }),
        }
    }
}

/// A D-NURBS surface session built from arrays (no scenario file): `points` is a control net
/// `(nu, nv, 3)` (or a `Surface`), with `degree`, `weights (nu, nv)` (default 1) and `knots`
/// (default uniform, clamped). `material`: a dict of `preset` (a Table 1 name), `per`, `mu`,
/// `gamma`, `alpha`, `beta` (defaults: the scenario defaults); `dt`: the time step (or the
/// preset's); `engine`: "generalized" (default) or "frozen"; `dynamic_weights`: weights as
/// generalized coordinates (default: True with the generalized engine); `reference`: "rest"
/// (default) or "absolute" elastic reference; `fix`: control point ids held fixed; `name`: the
/// model name.
///
/// The values are the scenario keys of `docs/formats.md` (`[model]`, `[material]`,
/// `[simulation]`) as a typed `ModelSpec`, with the surface itself as a value. Forces, data
/// points to fit, material changes: `session.apply({"action": "data", "points": ...})`,
/// `{"action": "material", "mu": ...}`; then `session.step(n)`.
#[pyfunction]
#[pyo3(signature = (points, degree = (3, 3), weights = None, knots = None, *, material = None,
    dt = None, engine = None, dynamic_weights = None, reference = None, fix = None, name = None),
    text_signature = "(points, degree=(3, 3), weights=None, knots=None, *, material=None, dt=None, \
    engine=None, dynamic_weights=None, reference=None, fix=None, name=None)")]
#[allow(clippy::too_many_arguments)]
fn dnurbs_surface(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    degree: (usize, usize),
    weights: Option<&Bound<'_, PyAny>>,
    knots: Option<&Bound<'_, PyAny>>,
    material: Option<&Bound<'_, PyDict>>,
    dt: Option<f64>,
    engine: Option<String>,
    dynamic_weights: Option<bool>,
    reference: Option<String>,
    fix: Option<Vec<usize>>,
    name: Option<String>,
) -> PyResult<Session> {
    use vclay_session::models::{KindSpec, dnurbs};
    let surface = crate::nurbs::surface_of(points, degree, weights, knots)?;
    let material: dnurbs::MaterialKeys = match material {
        Some(d) => util::from_py(d.as_any(), "material", PyValueError::new_err)?,
        None => Default::default(),
    };
    let spec = ModelSpec::DnurbsSurface(KindSpec {
        model: dnurbs::ModelKeys {
            surface: Some(surface),
            engine,
            weights: dynamic_weights.map(|d| if d { "dynamic" } else { "frozen" }.to_string()),
            fix: fix.unwrap_or_default(),
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
    let session = py.detach(|| {
        let model = spec
            .build(Path::new("."))
            .map_err(|e| vclay_session::SessionError::File {
                file: "<dnurbs_surface>".into(),
                line: 0,
                key: e.key,
                what: e.what,
            })?;
        KSession::with_model(&name, model)
    });
    Ok(Session {
        session: session.py()?,
        run: None,
    })
}

/// `vclay.open(path)`: any file vclay reads, recognized by its content, as a `Session`: a
/// scenario, a saved session, a model file (JSON, STEP, IGES), a PDE spec, a lattice or a
/// mesh (`vclay_session::open`). A file that is not a session (a point cloud) raises
/// `FileError` naming the functions and commands that take it.
#[pyfunction]
fn open(py: Python<'_>, path: PathBuf) -> PyResult<Session> {
    let o = py.detach(|| vclay_session::open(&path)).py()?;
    Ok(Session {
        session: o.session,
        run: o.run,
    })
}

/// A session: named models of any kind (D-NURBS, subdivision and B-spline solids, FFD, PDE
/// surfaces), their scheduled commands, the command log, undo and redo.
#[pyclass(module = "vclay")]
#[derive(Debug)]
pub struct Session {
    session: KSession,
    /// Scenario or saved run information (name, end step, outputs).
    run: Option<RunInfo>,
}

impl Session {
    fn model(&self, name: Option<&str>) -> PyResult<&dyn Model> {
        self.session.model(name).py()
    }
}

#[pymethods]
impl Session {
    /// An empty session (models come from `Session.load`).
    #[new]
    fn new() -> Self {
        Self {
            session: KSession::new(),
            run: None,
        }
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
        let v = serde_json::to_value(self.model(model)?.tools())
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
        let s = &self.session;
        let run = self.run.as_ref();
        py.detach(|| file::save(&path, s, run)).py()
    }

    /// The session file's content as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = file::to_value(&self.session, self.run.as_ref()).py()?;
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
            let me = slf.borrow();
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
    fn models(&self) -> Vec<String> {
        self.session
            .model_names()
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Session time: the earliest model clock.
    #[getter]
    fn time(&self) -> f64 {
        self.session.time()
    }

    /// The scenario's run length in steps (None for a session without run information).
    #[getter]
    fn scenario_steps(&self) -> Option<u64> {
        self.run.as_ref().map(|r| r.end_step)
    }

    /// Steps taken by model `model` (default: the first).
    #[pyo3(signature = (model = None))]
    fn steps(&self, model: Option<&str>) -> PyResult<u64> {
        Ok(self.model(model)?.steps())
    }

    /// `kind` of model `model`: `dnurbs-curve`, `subdivision-solid`, ...
    #[pyo3(signature = (model = None))]
    fn kind(&self, model: Option<&str>) -> PyResult<String> {
        Ok(self.model(model)?.kind().name().to_string())
    }

    /// One line about model `model` (sizes).
    #[pyo3(signature = (model = None))]
    fn summary(&self, model: Option<&str>) -> PyResult<String> {
        Ok(self.model(model)?.summary())
    }

    /// Applies a command now: a dict (or JSON text) such as `{"action": "rope", "from": [1, 1,
    /// 1], "to": [1.5, 1.4, 1.6], "until": 0.5}` or `{"action": "set", "name":
    /// "edge_stiffness", "value": 80}`, optionally with `"model": name`. Returns the log line.
    /// A command that cannot apply raises `CommandError` and leaves the session unchanged.
    fn apply(&mut self, py: Python<'_>, command: &Bound<'_, PyAny>) -> PyResult<String> {
        let c: Command = util::from_py(command, "command", CommandError::new_err)?;
        let s = &mut self.session;
        py.detach(|| s.apply(c)).py()
    }

    /// Schedules commands (dicts with `"at"`: seconds) like a scenario's timeline.
    fn schedule(&mut self, commands: &Bound<'_, PyAny>) -> PyResult<()> {
        let timed: Vec<vclay_session::Timed> =
            util::from_py(commands, "schedule", CommandError::new_err)?;
        self.session.schedule_commands(timed).py()
    }

    /// Undoes the last command; returns its log entry as a dict.
    fn undo<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let entry = self.session.undo().py()?;
        let v = serde_json::to_value(&entry).map_err(|e| SessionError::new_err(e.to_string()))?;
        util::json_to_py(py, &v)
    }

    /// Applies the last undone command again; returns its log line.
    fn redo(&mut self) -> PyResult<String> {
        self.session.redo().py()
    }

    /// Whether there is something to undo.
    #[getter]
    fn can_undo(&self) -> bool {
        self.session.can_undo()
    }

    /// Whether there is something to redo.
    #[getter]
    fn can_redo(&self) -> bool {
        self.session.can_redo()
    }

    /// Advances every model by `n` steps (scheduled commands fire on the way), with the GIL
    /// released. Returns the log lines of the scheduled commands applied. A diverging model
    /// raises `DivergedError`.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<Vec<String>> {
        // The same bound as a scenario's `steps` and `vclay run --steps`.
        vclay_session::scenario::check_steps(n).map_err(PyValueError::new_err)?;
        let s = &mut self.session;
        py.detach(|| s.run(n)).py()
    }

    /// Steps each model until its clock reaches `t` (within half a step).
    fn advance_to(&mut self, py: Python<'_>, t: f64) -> PyResult<Vec<String>> {
        let s = &mut self.session;
        py.detach(|| s.advance_to(t)).py()
    }

    /// Runs `steps` steps (default: the rest of the scenario) writing the scenario's
    /// `[output]` (frames, final files, energy table) into `out_dir`, like `vclay run`.
    /// Returns a dict: steps, mean_step_ms, frames, files, log.
    #[pyo3(signature = (out_dir, steps = None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        out_dir: PathBuf,
        steps: Option<u64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let output = self.run.as_ref().map_or_else(
            || OutputSpec {
                every: vclay_session::scenario::DEFAULT_FRAME_EVERY,
                ..OutputSpec::default()
            },
            |r| r.output.clone(),
        );
        let done = self.model(None)?.steps();
        let steps = match (steps, &self.run) {
            (Some(n), _) => n,
            (None, Some(r)) => r.end_step.saturating_sub(done),
            (None, None) => {
                return Err(PyValueError::new_err(
                    "run: give `steps` (this session has no scenario run length)",
                ));
            }
        };
        let s = &mut self.session;
        let summary = py
            .detach(|| vclay_session::run::run(s, steps, &out_dir, &output, &mut |_| {}))
            .py()?;
        let d = PyDict::new(py);
        d.set_item("steps", summary.steps)?;
        d.set_item("mean_step_ms", summary.mean_step_ms)?;
        d.set_item("max_step_ms", summary.max_step_ms)?;
        d.set_item("frames", summary.frames)?;
        d.set_item("files", summary.files)?;
        d.set_item("log", summary.log)?;
        Ok(d)
    }

    /// Energies of model `model`: dict kinetic, elastic, tools, total.
    #[pyo3(signature = (model = None))]
    fn energy<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyDict>> {
        let e = self.model(model)?.energy();
        let d = PyDict::new(py);
        d.set_item("kinetic", e.kinetic)?;
        d.set_item("elastic", e.elastic)?;
        d.set_item("tools", e.tools)?;
        d.set_item("total", e.total())?;
        Ok(d)
    }

    /// Material and simulation parameters of model `model`: a list of dicts (name, value,
    /// min, max, doc); change one with `apply({"action": "set", "name": ..., "value": ...})`.
    #[pyo3(signature = (model = None))]
    fn params<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyList>> {
        let ps = self.model(model)?.params();
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
        let v = serde_json::to_value(self.session.log())
            .map_err(|e| SessionError::new_err(e.to_string()))?;
        util::json_to_py(py, &v)
    }

    /// Everything model `model` saves (its session-file entry) as a dict.
    #[pyo3(signature = (model = None))]
    fn state<'py>(&self, py: Python<'py>, model: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let v = self.model(model)?.save().py()?;
        util::json_to_py(py, &v)
    }

    /// Control points of model `model`, `(n, 3)` (flat, last parametric index fastest): the
    /// D-NURBS control net, a solid's control lattice, an FFD lattice.
    #[pyo3(signature = (model = None))]
    fn control_points<'py>(
        &self,
        py: Python<'py>,
        model: Option<&str>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = self.model(model)?;
        let pts = m.control_points();
        if pts.is_empty() {
            return Err(SessionError::new_err(format!(
                "a {} model has no control points (use mesh())",
                m.kind()
            )));
        }
        Ok(util::points_array(py, &pts))
    }

    /// Data points of model `model`, `(n, 3)`: a solid's data (finest) lattice points; for the
    /// other kinds the vertices of the display mesh (curves: the display polyline).
    #[pyo3(signature = (model = None))]
    fn data_points<'py>(
        &self,
        py: Python<'py>,
        model: Option<&str>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = self.model(model)?;
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
        let mesh = self.model(model)?.display_mesh().py()?;
        util::mesh_arrays(py, &mesh)
    }

    /// Writes model `model` to `path` in the format its extension names (`.json`, `.obj`,
    /// `.ply`, `.stl`, `.vtu`, `.ovm`, `.glb`, `.step`, `.igs`, as the kind supports).
    #[pyo3(signature = (path, model = None))]
    fn export(&self, py: Python<'_>, path: PathBuf, model: Option<&str>) -> PyResult<()> {
        let m = self.model(model)?;
        py.detach(|| m.export(&path)).py()
    }

    fn __repr__(&self) -> String {
        let names = self.session.model_names();
        let kinds: Vec<String> = names
            .iter()
            .filter_map(|n| {
                self.session
                    .model(Some(n))
                    .ok()
                    .map(|m| format!("{n} ({})", m.kind()))
            })
            .collect();
        format!(
            "<vclay Session t = {}: {}>",
            self.session.time(),
            kinds.join(", ")
        )
    }
}
