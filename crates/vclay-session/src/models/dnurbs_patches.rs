//! The `dnurbs-patches` model kind: several rational tensor-product D-NURBS patches sculpted
//! together in one generalized engine, with G0 or G1 joins kept as linear ties every step
//! (`d-nurbs.txt` section 6, "continuity requirements between adjacent surface patches"; the
//! ties are the constraints of section 6.2; see
//! [`vclay_dynamics::dnurbs::PatchesGeometry`]).
//!
//! Scenario keys (`[model]`): `[[model.patch]]` entries, each either a flat sheet
//! (`origin = [x, y, z]`, `size = [a, b]` along x and y, `controls = [n, m]`, `degree = [p, q]`,
//! default 2 x 2) or `file = "x.json"` (a model JSON holding one NURBS surface);
//! `[[model.join]]` entries `a`, `b` (patch indices: `a`'s `u = max` edge meets `b`'s
//! `u = min` edge) and `continuity = "G0" | "G1"`; `tessellation` (samples per patch and
//! direction of the display mesh, default [`DEFAULT_TESSELLATION`]).
//! `[material]`: `preset` (a Table 1 row, default "Egg sculpting"), overrides `mu`, `gamma`,
//! `alpha = [a11, a22]`, `beta = [b11, b12, b22]`. `[simulation]`: `dt` (default the
//! preset's).
//!
//! Edits: `rope` (delta spring of eq 19 to a cursor that moves linearly from `from` to `to`
//! between `start` and `until`; `param` is the global parameter, else the point nearest
//! `from`), `move-rope`, `force` (constant, at `param` or nearest `near`), `release`, `fix` and
//! `free` (control points by global id, box or nearest; x, y, z are frozen), `set dt`. Others
//! are refused with a message.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::dnurbs::generalized::{GeneralizedGeometry, GeneralizedState};
use vclay_dynamics::dnurbs::{
    Continuity, Density, ElasticReference, Force, GeneralizedDnurbs, Material, PatchesGeometry,
    Preset, Target,
};
use vclay_io::model::Entity;
use vclay_spline::{NurbsSurface, ParametricSurface};

use super::SpecError;
use super::saved::{SavedState, step_implicit};
use crate::command::Edit;
use crate::error::SessionError;
use crate::model::{
    Applied, Element, Energy, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray, Snapshot,
    StepReport, Undo, extension, unsupported_export,
};

/// Default display samples per patch and direction.
pub const DEFAULT_TESSELLATION: usize = 24;
/// Most patches a model takes.
pub const MAX_PATCHES: usize = 64;
/// Most control points per patch direction of a sheet.
pub const MAX_SHEET_CONTROLS: usize = 64;
/// Most control points of all patches together (checked before the engine is built: its
/// sparse system grows with them, and every step refactors it).
pub const MAX_TOTAL_CONTROL_POINTS: usize = 20_000;

/// A join between two patches (kept in session files).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Join {
    a: usize,
    b: usize,
    g1: bool,
}

/// Settings that rebuild the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Settings {
    /// The initial patches as a model JSON (embedded, so that a session stands alone).
    patches: serde_json::Value,
    joins: Vec<Join>,
    tessellation: usize,
    mu: f64,
    gamma: f64,
    alpha: [f64; 2],
    beta: [f64; 3],
    k: f64,
    dt: f64,
}

/// A rope: a delta spring (eq 19) from the material point `param` to a cursor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Rope {
    name: String,
    param: [f64; 2],
    from: [f64; 3],
    to: [f64; 3],
    start: f64,
    until: f64,
    release: Option<f64>,
    stiffness: f64,
}

impl Rope {
    fn cursor(&self, t: f64) -> Vec3 {
        let s = if self.until > self.start {
            ((t - self.start) / (self.until - self.start)).clamp(0.0, 1.0)
        } else if t >= self.start {
            1.0
        } else {
            0.0
        };
        let (a, b) = (Vec3::from(self.from), Vec3::from(self.to));
        a + (b - a) * s
    }
}

/// A constant force at a material point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PointForce {
    name: String,
    param: [f64; 2],
    force: [f64; 3],
    until: Option<f64>,
}

/// Tools and counters that evolve with the edits.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Tools {
    ropes: Vec<Rope>,
    forces: Vec<PointForce>,
    next: usize,
}

/// Several D-NURBS patches with continuity joins (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct PatchesModel {
    settings: Settings,
    tools: Tools,
    engine: GeneralizedDnurbs<PatchesGeometry>,
    size: f64,
    revision: u64,
    energy: Energy,
}

fn model_err(e: impl std::fmt::Display) -> SessionError {
    SessionError::model(e)
}

fn cmd_err(e: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", e)
}

fn surfaces_of(v: &serde_json::Value) -> Result<Vec<NurbsSurface>, String> {
    let text = serde_json::to_string(v).map_err(|e| e.to_string())?;
    vclay_io::model::parse_model(&text)
        .map_err(|e| e.to_string())?
        .into_iter()
        .enumerate()
        .map(|(i, e)| match e {
            Entity::Surface(s) => Ok(s),
            other => Err(format!(
                "patch {i}: a {} is not a surface",
                other.type_name()
            )),
        })
        .collect()
}

impl PatchesModel {
    fn build(settings: Settings, tools: Tools) -> Result<Self, String> {
        let surfaces = surfaces_of(&settings.patches)?;
        if surfaces.is_empty() || surfaces.len() > MAX_PATCHES {
            return Err(format!(
                "{} patches: give 1 to {MAX_PATCHES}",
                surfaces.len()
            ));
        }
        let total: usize = surfaces.iter().map(|s| s.control_points().len()).sum();
        if total > MAX_TOTAL_CONTROL_POINTS {
            return Err(format!(
                "{total} control points in all patches: at most {MAX_TOTAL_CONTROL_POINTS}"
            ));
        }
        let geometry = PatchesGeometry::new(&surfaces).map_err(|e| e.to_string())?;
        let mut ties = Vec::new();
        for (i, j) in settings.joins.iter().enumerate() {
            let c = if j.g1 { Continuity::G1 } else { Continuity::G0 };
            ties.extend(
                geometry
                    .join(j.a, j.b, c)
                    .map_err(|e| format!("join {i} ({} to {}): {e}", j.a, j.b))?,
            );
        }
        // Size: the bounding-box diagonal of all initial control points.
        let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
        for p in surfaces.iter().flat_map(|s| s.control_points()) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let size = (hi - lo).norm().max(f64::MIN_POSITIVE);
        let material = Material {
            mu: Density::Constant(settings.mu),
            gamma: Density::Constant(settings.gamma),
            alpha: settings
                .alpha
                .iter()
                .map(|&a| Density::Constant(a))
                .collect(),
            beta: settings
                .beta
                .iter()
                .map(|&b| Density::Constant(b))
                .collect(),
        };
        let mut engine = GeneralizedDnurbs::new(geometry, material).map_err(|e| e.to_string())?;
        engine.set_elastic_reference(ElasticReference::RestShape);
        for t in ties {
            engine.add_tie(t).map_err(|e| e.to_string())?;
        }
        let elastic = engine.elastic_energy().unwrap_or(0.0);
        Ok(Self {
            settings,
            tools,
            engine,
            size,
            revision: 0,
            energy: Energy {
                elastic,
                ..Energy::default()
            },
        })
    }

    /// The engine (for tests and tools).
    pub fn engine(&self) -> &GeneralizedDnurbs<PatchesGeometry> {
        &self.engine
    }

    /// Patch `k`'s current surface.
    pub fn patch(&self, k: usize) -> Result<NurbsSurface, SessionError> {
        self.engine
            .geometry()
            .patch(k)
            .map_err(SessionError::kernel)
    }

    /// Number of patches.
    pub fn patch_count(&self) -> usize {
        self.engine.geometry().len()
    }

    /// Builds the model from its scenario tables.
    pub fn from_keys(spec: &PatchesSpec, base: &Path) -> Result<Self, SpecError> {
        let (m, mat, sim) = (&spec.model, &spec.material, &spec.simulation);
        if m.patch.is_empty() || m.patch.len() > MAX_PATCHES {
            return Err(SpecError::new(
                "model",
                "patch",
                format!(
                    "{} [[model.patch]] entries: give 1 to {MAX_PATCHES}",
                    m.patch.len()
                ),
            ));
        }
        let mut surfaces = Vec::with_capacity(m.patch.len());
        for (i, p) in m.patch.iter().enumerate() {
            surfaces.push(
                p.surface(base)
                    .map_err(|e| SpecError::new("model", "patch", format!("patch {i}: {e}")))?,
            );
        }
        let mut joins = Vec::with_capacity(m.join.len());
        for (i, j) in m.join.iter().enumerate() {
            let g1 = match j.continuity.to_ascii_uppercase().as_str() {
                "G0" => false,
                "G1" => true,
                other => {
                    return Err(SpecError::new(
                        "model",
                        "join",
                        format!("join {i}: continuity {other:?}: expected \"G0\" or \"G1\""),
                    ));
                }
            };
            joins.push(Join { a: j.a, b: j.b, g1 });
        }
        let preset_name = mat.preset.clone().unwrap_or_else(|| "Egg sculpting".into());
        let preset: &Preset = Preset::by_name(&preset_name).ok_or_else(|| {
            SpecError::new(
                "material",
                "preset",
                format!("{preset_name:?} is not a Table 1 row"),
            )
        })?;
        let tessellation = m.tessellation.unwrap_or(DEFAULT_TESSELLATION);
        if !(2..=256).contains(&tessellation) {
            return Err(SpecError::new(
                "model",
                "tessellation",
                format!("{tessellation}: must be 2 to 256"),
            ));
        }
        let entities: Vec<Entity> = surfaces.into_iter().map(Entity::Surface).collect();
        let settings = Settings {
            patches: vclay_io::model::to_json(&entities),
            joins,
            tessellation,
            mu: mat.mu.unwrap_or(preset.mu),
            gamma: mat.gamma.unwrap_or(preset.gamma),
            alpha: mat.alpha.unwrap_or(preset.alpha),
            beta: mat.beta.unwrap_or(preset.beta),
            k: preset.k,
            dt: sim.dt.unwrap_or(preset.dt),
        };
        let all = [
            ("mu", settings.mu),
            ("gamma", settings.gamma),
            ("alpha", settings.alpha[0]),
            ("alpha", settings.alpha[1]),
            ("beta", settings.beta[0]),
            ("beta", settings.beta[1]),
            ("beta", settings.beta[2]),
        ];
        for (key, v) in all {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SpecError::new(
                    "material",
                    key,
                    format!("{v} must be finite and non-negative"),
                ));
            }
        }
        if !(settings.dt.is_finite() && settings.dt > 0.0) {
            return Err(SpecError::new(
                "simulation",
                "dt",
                format!("{} must be positive and finite", settings.dt),
            ));
        }
        Self::build(settings, Tools::default()).map_err(|e| SpecError::new("model", "join", e))
    }

    /// Rebuilds a saved model.
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let saved: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        let mut m = Self::build(saved.settings, saved.tools).map_err(model_err)?;
        m.engine
            .set_state(&GeneralizedState::from(saved.state))
            .map_err(SessionError::kernel)?;
        Ok(m)
    }

    fn mesh(&self) -> Result<TriMesh, SessionError> {
        let mut mesh = TriMesh::new();
        let n = self.settings.tessellation;
        for k in 0..self.patch_count() {
            let mut part = TriMesh::new();
            vclay_spline::tessellate_surface(&self.patch(k)?, [n, n], &mut part)
                .map_err(SessionError::kernel)?;
            mesh.append(&part);
        }
        Ok(mesh)
    }

    /// The surface point at a global parameter (the patch whose shifted domain holds it, as
    /// [`PatchesGeometry`] locates it).
    fn point_at(&self, param: [f64; 2]) -> Option<Vec3> {
        let g = self.engine.geometry();
        let k = (0..g.len())
            .rev()
            .find(|&k| param[0] - g.global_param(k, [0.0, 0.0])[0] >= -0.5)
            .unwrap_or(0);
        let shift = g.global_param(k, [0.0, 0.0])[0];
        let s = g.patch(k).ok()?;
        s.point(param[0] - shift, param[1]).ok()
    }

    /// Control point `c`'s index range of x, y, z in the coordinates.
    fn xyz(c: usize) -> std::ops::Range<usize> {
        4 * c..4 * c + 3
    }

    /// Puts the tools into the engine's force list for a step starting at `t`.
    fn load_forces(&mut self, t: f64) {
        self.tools
            .ropes
            .retain(|r| r.release.is_none_or(|rel| t < rel));
        self.tools.forces.retain(|f| f.until.is_none_or(|u| t < u));
        let forces = self.engine.forces_mut();
        forces.clear();
        for r in &self.tools.ropes {
            forces.push(Force::Spring {
                param: r.param,
                target: Target::Fixed(r.cursor(t)),
                stiffness: r.stiffness,
                kernel: None,
            });
        }
        for f in &self.tools.forces {
            forces.push(Force::Point {
                param: f.param,
                force: Vec3::from(f.force),
            });
        }
    }

    fn name(&mut self, given: &Option<String>, prefix: &str) -> Result<String, SessionError> {
        let name = match given {
            Some(n) => n.clone(),
            None => {
                self.tools.next += 1;
                format!("{prefix}{}", self.tools.next - 1)
            }
        };
        if self.tools.ropes.iter().any(|r| r.name == name)
            || self.tools.forces.iter().any(|f| f.name == name)
        {
            return Err(cmd_err(format!("a tool named {name:?} exists already")));
        }
        Ok(name)
    }

    fn param_of(&self, param: Option<[f64; 2]>, near: [f64; 3]) -> Result<[f64; 2], SessionError> {
        match param {
            Some(p) if p.iter().all(|x| x.is_finite()) => Ok(p),
            Some(p) => Err(cmd_err(format!("param {p:?} is not finite"))),
            None => self
                .engine
                .geometry()
                .nearest_param(&Vec3::from(near))
                .map_err(SessionError::command_from),
        }
    }
}

fn finite3(what: &str, v: &[f64; 3]) -> Result<(), SessionError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(cmd_err(format!("{what} {v:?} is not finite")))
    }
}

/// The patches' control points (x, y, z of coordinates `4c..4c + 3`) for the shared fix/free
/// tool.
impl crate::tools::ControlNet for PatchesModel {
    fn current_points(&self) -> Vec<Vec3> {
        Model::control_points(self)
    }
    fn rest_points(&self) -> Vec<Vec3> {
        let q = self.engine.state().rest_coordinates;
        (0..q.len() / 4)
            .map(|c| Vec3::new(q[4 * c], q[4 * c + 1], q[4 * c + 2]))
            .collect()
    }
    fn is_fixed(&self, c: usize) -> bool {
        Self::xyz(c).all(|i| self.engine.is_fixed_coordinate(i))
    }
    fn set_fixed(&mut self, ids: &[usize], fix: bool) -> Result<(), SessionError> {
        for &c in ids {
            for i in Self::xyz(c) {
                self.engine
                    .set_fixed_coordinate(i, fix)
                    .map_err(SessionError::command_from)?;
            }
        }
        Ok(())
    }
}

impl crate::model::Stateful for PatchesModel {
    type State = (GeneralizedState, f64, Tools);
    fn take_state(&self) -> Self::State {
        (self.engine.state(), self.settings.dt, self.tools.clone())
    }
    fn put_state(&mut self, s: &Self::State) -> Result<(), SessionError> {
        self.engine.set_state(&s.0).map_err(SessionError::kernel)?;
        self.settings.dt = s.1;
        self.tools = s.2.clone();
        self.revision += 1;
        Ok(())
    }
    fn apply_inverse(&mut self, _edit: &Edit) -> Result<(), SessionError> {
        // The snapshot holds everything the edits change.
        Ok(())
    }
}

impl Model for PatchesModel {
    fn kind(&self) -> ModelKind {
        ModelKind::DnurbsPatches
    }
    fn summary(&self) -> String {
        format!(
            "dnurbs-patches: {} patches, {} control points, {} joins ({} ties), {} ropes, {} forces",
            self.patch_count(),
            self.engine.geometry().coordinates().len() / 4,
            self.settings.joins.len(),
            self.engine.ties().len(),
            self.tools.ropes.len(),
            self.tools.forces.len()
        )
    }
    fn time(&self) -> f64 {
        self.engine.time()
    }
    fn dt(&self) -> f64 {
        self.settings.dt
    }
    fn steps(&self) -> u64 {
        self.engine.steps() as u64
    }
    fn step(&mut self) -> Result<StepReport, SessionError> {
        self.load_forces(self.engine.time());
        let report = step_implicit(&mut self.engine, self.settings.dt, &mut self.energy)?;
        self.revision += 1;
        Ok(report)
    }
    fn energy(&self) -> Energy {
        self.energy
    }
    fn size(&self) -> f64 {
        self.size
    }
    fn revision(&self) -> u64 {
        self.revision
    }
    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        self.mesh()
    }
    fn display_lines(&self) -> Vec<LineSet> {
        let mut net = LineSet::new(LineRole::ControlNet);
        for k in 0..self.patch_count() {
            let Ok(s) = self.patch(k) else { continue };
            let [n, m] = s.dims();
            for i in 0..n {
                for j in 0..m {
                    if i + 1 < n {
                        net.segment(s.control_point(i, j), s.control_point(i + 1, j));
                    }
                    if j + 1 < m {
                        net.segment(s.control_point(i, j), s.control_point(i, j + 1));
                    }
                }
            }
        }
        let mut ropes = LineSet::new(LineRole::Ropes);
        let t = self.engine.time();
        for r in &self.tools.ropes {
            if let Some(p) = self.point_at(r.param) {
                ropes.segment(p, r.cursor(t));
            }
        }
        let mut fixed = LineSet::new(LineRole::Fixed);
        let f = &self.engine.state().fixed;
        for (c, p) in self.control_points().into_iter().enumerate() {
            if f[4 * c] {
                fixed.points.push(p);
            }
        }
        vec![net, ropes, fixed]
    }
    fn pick(&self, ray: &Ray, _tolerance: f64) -> Option<Hit> {
        let mesh = self.mesh().ok()?;
        crate::pick::ray_mesh(ray, &mesh).map(|(s, _, _)| {
            let point = ray.origin + ray.direction * s;
            let param = self
                .engine
                .geometry()
                .nearest_param(&point)
                .unwrap_or([0.0, 0.0]);
            Hit {
                distance: s,
                point,
                element: Element::SurfacePoint { param },
                extra: [None, None],
            }
        })
    }
    fn params(&self) -> Vec<Param> {
        vec![Param {
            name: "dt".into(),
            value: self.settings.dt,
            min: 1e-4,
            max: 0.1,
            doc: "time step of eq 18".into(),
        }]
    }
    fn apply(&mut self, edit: &Edit) -> Result<Applied, SessionError> {
        let before = crate::model::Stateful::take_state(self);
        let t = self.engine.time();
        let msg = match edit {
            Edit::Set { name, value } if name == "dt" => {
                if !(value.is_finite() && *value > 0.0) {
                    return Err(cmd_err(format!("dt = {value}: must be positive")));
                }
                self.settings.dt = *value;
                format!("dt = {value}")
            }
            Edit::Rope {
                name,
                from,
                param,
                to,
                until,
                velocity,
                release,
                stiffness,
                length,
                kernel,
                start,
            } => {
                if velocity.is_some() || length.is_some() || kernel.is_some() {
                    return Err(cmd_err(
                        "a dnurbs-patches rope takes from, param, to, start, until, release and stiffness (not velocity, length or kernel)",
                    ));
                }
                finite3("from", from)?;
                let to = to.unwrap_or(*from);
                finite3("to", &to)?;
                let k = stiffness.unwrap_or(self.settings.k);
                if !(k.is_finite() && k > 0.0) {
                    return Err(cmd_err(format!("stiffness {k}: must be positive")));
                }
                let param = self.param_of(*param, *from)?;
                let name = self.name(name, "rope")?;
                let start = start.unwrap_or(t);
                let until = until.unwrap_or(start).max(start);
                self.tools.ropes.push(Rope {
                    name: name.clone(),
                    param,
                    from: *from,
                    to,
                    start,
                    until,
                    release: *release,
                    stiffness: k,
                });
                format!("rope `{name}` attached at parameter {param:?}")
            }
            Edit::MoveRope { name, to } => {
                finite3("to", to)?;
                let r = self
                    .tools
                    .ropes
                    .iter_mut()
                    .find(|r| &r.name == name)
                    .ok_or_else(|| cmd_err(format!("no rope named {name:?}")))?;
                r.from = *to;
                r.to = *to;
                format!("rope `{name}` cursor at {to:?}")
            }
            Edit::Force {
                name,
                near,
                param,
                force,
                until,
            } => {
                finite3("force", force)?;
                let param = match (param, near) {
                    (Some(_), _) => self.param_of(*param, [0.0; 3])?,
                    (None, Some(x)) => self.param_of(None, *x)?,
                    (None, None) => return Err(cmd_err("a force needs `param` or `near`")),
                };
                let name = self.name(name, "force")?;
                self.tools.forces.push(PointForce {
                    name: name.clone(),
                    param,
                    force: *force,
                    until: *until,
                });
                format!("force `{name}` at parameter {param:?}")
            }
            Edit::Release { name } => {
                let n = self.tools.ropes.len() + self.tools.forces.len();
                self.tools.ropes.retain(|r| &r.name != name);
                self.tools.forces.retain(|f| &f.name != name);
                if n == self.tools.ropes.len() + self.tools.forces.len() {
                    return Err(cmd_err(format!("no tool named {name:?}")));
                }
                format!("released `{name}`")
            }
            Edit::Fix { .. } | Edit::Free { .. } => {
                let fix = matches!(edit, Edit::Fix { .. });
                let r = crate::tools::fix_or_free(self, edit)?;
                format!(
                    "{} {} control points",
                    if fix { "fixed" } else { "freed" },
                    r.selected.len()
                )
            }
            other => {
                return Err(cmd_err(format!(
                    "a dnurbs-patches model takes rope, move-rope, force, release, fix, free and `set dt` only, not {other:?}"
                )));
            }
        };
        self.revision += 1;
        Ok(Applied {
            message: msg,
            undo: Undo::State(Snapshot::new(before)),
        })
    }
    crate::model::stateful_methods!();
    fn control_points(&self) -> Vec<Vec3> {
        (0..self.patch_count())
            .filter_map(|k| self.patch(k).ok())
            .flat_map(|s| s.control_points().to_vec())
            .collect()
    }
    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        match extension(path).as_str() {
            "json" => {
                let mut entities = Vec::with_capacity(self.patch_count());
                for k in 0..self.patch_count() {
                    entities.push(Entity::Surface(self.patch(k)?));
                }
                vclay_io::model::write_model(path, &entities).map_err(|e| io(&e))
            }
            "obj" | "ply" | "stl" => vclay_io::write_mesh(path, &self.mesh()?).map_err(|e| io(&e)),
            _ => Err(unsupported_export(
                self.kind(),
                path,
                &self.export_formats(),
            )),
        }
    }
    fn export_formats(&self) -> Vec<&'static str> {
        vec!["json", "obj", "ply", "stl"]
    }
    fn save(&self) -> Result<serde_json::Value, SessionError> {
        serde_json::to_value(Saved {
            settings: self.settings.clone(),
            tools: self.tools.clone(),
            state: SavedState::from(&self.engine.state()),
        })
        .map_err(SessionError::kernel)
    }
}

/// Rebuilds a saved model.
pub fn load(saved: &serde_json::Value) -> Result<Box<dyn Model>, SessionError> {
    Ok(Box::new(PatchesModel::load(saved)?))
}

/// The typed spec of a multi-patch D-NURBS ([`super::ModelSpec`]).
pub type PatchesSpec = super::KindSpec<ModelKeys, MaterialKeys, SimKeys>;

/// The `[model]` keys of a `dnurbs-patches` model as a typed value; each field is the key of
/// the same name in `docs/formats.md` section 8 (absent: the documented default).
#[allow(missing_docs)]
#[derive(Debug, Default, Deserialize, Clone, PartialEq, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelKeys {
    #[serde(default)]
    pub patch: Vec<PatchKeys>,
    #[serde(default)]
    pub join: Vec<JoinKeys>,
    pub tessellation: Option<usize>,
}

/// The entry keys of a `dnurbs-patches` model as a typed value; each field is the key of
/// the same name in `docs/formats.md` section 8 (absent: the documented default).
#[allow(missing_docs)]
#[derive(Debug, Default, Deserialize, Clone, PartialEq, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PatchKeys {
    pub origin: Option<[f64; 3]>,
    pub size: Option<[f64; 2]>,
    pub controls: Option<[usize; 2]>,
    pub degree: Option<[usize; 2]>,
    pub file: Option<PathBuf>,
}

impl PatchKeys {
    fn surface(&self, base: &Path) -> Result<NurbsSurface, String> {
        if let Some(f) = &self.file {
            if self.origin.is_some()
                || self.size.is_some()
                || self.controls.is_some()
                || self.degree.is_some()
            {
                return Err(
                    "give `file` or a sheet (origin, size, controls, degree), not both".into(),
                );
            }
            let path = if f.is_absolute() {
                f.clone()
            } else {
                base.join(f)
            };
            let entities = vclay_io::model::read_model(&path)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            return match entities.as_slice() {
                [Entity::Surface(s)] => Ok(s.clone()),
                _ => Err(format!(
                    "{}: expected exactly one NURBS surface ({} entities)",
                    path.display(),
                    entities.len()
                )),
            };
        }
        let (Some(origin), Some(size), Some(controls)) = (self.origin, self.size, self.controls)
        else {
            return Err("a sheet needs origin, size and controls (or give file)".into());
        };
        let degree = self.degree.unwrap_or([2, 2]);
        if !origin.iter().chain(&size).all(|x| x.is_finite()) || size.iter().any(|&s| s <= 0.0) {
            return Err(format!(
                "origin {origin:?} and size {size:?} must be finite, size positive"
            ));
        }
        for k in 0..2 {
            if !(2..=MAX_SHEET_CONTROLS).contains(&controls[k]) {
                return Err(format!(
                    "controls {controls:?}: each must be 2 to {MAX_SHEET_CONTROLS}"
                ));
            }
            if !(1..controls[k]).contains(&degree[k]) {
                return Err(format!(
                    "degree {degree:?}: each must be 1 to controls - 1 ({controls:?})"
                ));
            }
        }
        let [n, m] = controls;
        let pts = (0..n)
            .flat_map(|i| {
                (0..m).map(move |j| {
                    Vec3::new(
                        origin[0] + size[0] * i as f64 / (n - 1) as f64,
                        origin[1] + size[1] * j as f64 / (m - 1) as f64,
                        origin[2],
                    )
                })
            })
            .collect();
        NurbsSurface::clamped_uniform(degree, controls, pts).map_err(|e| e.to_string())
    }
}

/// The entry keys of a `dnurbs-patches` model as a typed value; each field is the key of
/// the same name in `docs/formats.md` section 8 (absent: the documented default).
#[allow(missing_docs)]
#[derive(Debug, Deserialize, Clone, Default, PartialEq, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JoinKeys {
    pub a: usize,
    pub b: usize,
    pub continuity: String,
}

/// The `[material]` keys of a `dnurbs-patches` model as a typed value; each field is the key of
/// the same name in `docs/formats.md` section 8 (absent: the documented default).
#[allow(missing_docs)]
#[derive(Debug, Default, Deserialize, Clone, PartialEq, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialKeys {
    pub preset: Option<String>,
    pub mu: Option<f64>,
    pub gamma: Option<f64>,
    pub alpha: Option<[f64; 2]>,
    pub beta: Option<[f64; 3]>,
}

/// The `[simulation]` keys of a `dnurbs-patches` model as a typed value; each field is the key of
/// the same name in `docs/formats.md` section 8 (absent: the documented default).
#[allow(missing_docs)]
#[derive(Debug, Default, Deserialize, Clone, PartialEq, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimKeys {
    pub dt: Option<f64>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    settings: Settings,
    tools: Tools,
    state: SavedState,
}
