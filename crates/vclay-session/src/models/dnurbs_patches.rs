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
//!
//! The model is [`GeneralizedModel`] over `GeneralizedDnurbs<PatchesGeometry>`; this file holds
//! what is the kind's own ([`Patches`]): its keys, how the patches and joins are built, the
//! forces of its ropes and point forces (named and scheduled by the shared
//! [`crate::tools::ToolTable`], saved in the layout earlier builds wrote), the patch control
//! nets, the model JSON export and the saved settings.

use std::path::{Path, PathBuf};

use crate::model::Done;
use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::dnurbs::generalized::{GeneralizedGeometry, GeneralizedState};
use vclay_dynamics::dnurbs::{
    Continuity, ElasticReference, Force, GeneralizedDnurbs, PatchesGeometry, Target,
};
use vclay_io::model::Entity;
use vclay_spline::{NurbsSurface, ParametricSurface};

use super::SpecError;
use super::generalized::{
    GeneralizedKind, GeneralizedModel, bbox_diagonal, check_material_and_dt, constant_material,
    generalized_accessors, param_or_near, table_one,
};
use super::saved::SavedState;
use crate::command::Edit;
use crate::command::RopeRequest;
use crate::error::SessionError;
use crate::model::{LineRole, LineSet, ModelKind};
use crate::tools::{CursorPath, ScheduledTool, ToolHost, ToolTable, v3};

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

/// A rope as session files keep it: a delta spring (eq 19) from the material point `param` to
/// a cursor moving linearly from `from` at `start` to `to` at `until`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedRope {
    name: String,
    param: [f64; 2],
    from: [f64; 3],
    to: [f64; 3],
    start: f64,
    until: f64,
    release: Option<f64>,
    stiffness: f64,
}

/// A constant force at a material point as session files keep it (`until`: its release).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedForce {
    name: String,
    param: [f64; 2],
    force: [f64; 3],
    until: Option<f64>,
}

/// The tools as session files keep them: ropes, then forces (the layout written before the
/// shared [`ToolTable`], so that those files load and continue unchanged).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedTools {
    ropes: Vec<SavedRope>,
    forces: Vec<SavedForce>,
    /// A counter of the old naming of unnamed tools; kept as read.
    next: usize,
}

/// What a tool's handle holds: where it acts (a global parameter) and how.
#[derive(Clone, Debug, PartialEq)]
enum Slot {
    /// A delta spring (eq 19) to a cursor; `cursor` is where it is when the tool has no path
    /// (after `move-rope`).
    Rope {
        param: [f64; 2],
        stiffness: f64,
        cursor: [f64; 3],
    },
    /// A constant force.
    Point { param: [f64; 2], force: [f64; 3] },
}

/// The tools: named and scheduled by the shared [`ToolTable`] (naming, cursor paths, release
/// times and messages are those of every kind, [`crate::tools::tool_edit`]); a handle is an
/// index into `slots`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "SavedTools", into = "SavedTools")]
pub struct Tools {
    table: ToolTable,
    slots: Vec<Option<Slot>>,
    next: usize,
}

impl Tools {
    /// The active tools of `action` with their slots, in the order they were attached.
    fn active<'a>(
        &'a self,
        action: &'a str,
    ) -> impl Iterator<Item = (&'a ScheduledTool, &'a Slot)> {
        self.table
            .tools
            .iter()
            .filter(move |e| e.action == action)
            .filter_map(|e| Some((e, self.slots.get(e.handle)?.as_ref()?)))
    }

    /// The cursor of rope `e` (slot `s`) at time `t`.
    fn cursor(e: &ScheduledTool, s: &Slot, t: f64) -> Vec3 {
        match (&e.path, s) {
            (Some(p), _) => p.at(t),
            (None, Slot::Rope { cursor, .. }) => v3(*cursor),
            (None, Slot::Point { .. }) => Vec3::zeros(),
        }
    }
}

impl From<SavedTools> for Tools {
    fn from(s: SavedTools) -> Self {
        let mut tools = Tools {
            next: s.next,
            ..Tools::default()
        };
        for r in s.ropes {
            let h = tools.slots.len();
            tools.slots.push(Some(Slot::Rope {
                param: r.param,
                stiffness: r.stiffness,
                cursor: r.to,
            }));
            let path = CursorPath::Linear {
                from: r.from,
                to: r.to,
                start: r.start,
                end: r.until,
            };
            tools.table.track(&r.name, "rope", h, Some(path), r.release);
        }
        for f in s.forces {
            let h = tools.slots.len();
            tools.slots.push(Some(Slot::Point {
                param: f.param,
                force: f.force,
            }));
            tools.table.track(&f.name, "force", h, None, f.until);
        }
        tools
    }
}

impl From<Tools> for SavedTools {
    fn from(t: Tools) -> Self {
        let ropes = t
            .active("rope")
            .filter_map(|(e, s)| {
                let Slot::Rope {
                    param,
                    stiffness,
                    cursor,
                } = *s
                else {
                    return None;
                };
                let (from, to, start, until) = match e.path {
                    Some(CursorPath::Linear {
                        from,
                        to,
                        start,
                        end,
                    }) => (from, to, start, end),
                    _ => (cursor, cursor, 0.0, 0.0),
                };
                Some(SavedRope {
                    name: e.name.clone(),
                    param,
                    from,
                    to,
                    start,
                    until,
                    release: e.release,
                    stiffness,
                })
            })
            .collect();
        let forces = t
            .active("force")
            .filter_map(|(e, s)| match *s {
                Slot::Point { param, force } => Some(SavedForce {
                    name: e.name.clone(),
                    param,
                    force,
                    until: e.release,
                }),
                Slot::Rope { .. } => None,
            })
            .collect();
        SavedTools {
            ropes,
            forces,
            next: t.next,
        }
    }
}

/// The `dnurbs-patches` kind's part of [`GeneralizedModel`]: its engine, settings and tools.
#[derive(Clone, Debug)]
pub struct Patches {
    engine: Engine,
    settings: Settings,
    tools: Tools,
}

/// Several D-NURBS patches with continuity joins (see the [module docs](self)).
pub type PatchesModel = GeneralizedModel<Patches>;

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
        let size = bbox_diagonal(surfaces.iter().flat_map(|s| s.control_points()));
        let material =
            constant_material(settings.mu, settings.gamma, &settings.alpha, &settings.beta);
        let mut engine = GeneralizedDnurbs::new(geometry, material).map_err(|e| e.to_string())?;
        engine.set_elastic_reference(ElasticReference::RestShape);
        for t in ties {
            engine.add_tie(t).map_err(|e| e.to_string())?;
        }
        Ok(Self::new(
            Patches {
                engine,
                settings,
                tools,
            },
            size,
            0,
        ))
    }

    /// Patch `k`'s current surface.
    pub fn patch(&self, k: usize) -> Result<NurbsSurface, SessionError> {
        patch(self.engine(), k)
    }

    /// Number of patches.
    pub fn patch_count(&self) -> usize {
        self.engine().geometry().len()
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
        let preset = table_one(&preset_name)?;
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
        check_material_and_dt(
            &[
                ("mu", settings.mu),
                ("gamma", settings.gamma),
                ("alpha", settings.alpha[0]),
                ("alpha", settings.alpha[1]),
                ("beta", settings.beta[0]),
                ("beta", settings.beta[1]),
                ("beta", settings.beta[2]),
            ],
            settings.dt,
        )?;
        Self::build(settings, Tools::default()).map_err(|e| SpecError::new("model", "join", e))
    }

    /// Rebuilds a saved model.
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let saved: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        Self::build(saved.settings, saved.tools)
            .map_err(model_err)?
            .with_state(saved.state.into())
    }
}

type Engine = GeneralizedDnurbs<PatchesGeometry>;

/// Patch `k`'s current surface.
fn patch(engine: &Engine, k: usize) -> Result<NurbsSurface, SessionError> {
    engine.geometry().patch(k).map_err(SessionError::kernel)
}

/// The surface point at a global parameter (the patch whose shifted domain holds it, as
/// [`PatchesGeometry`] locates it).
fn point_at(engine: &Engine, param: [f64; 2]) -> Option<Vec3> {
    let g = engine.geometry();
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

impl Patches {
    /// Adds a slot; returns its handle.
    fn add_slot(&mut self, slot: Slot) -> usize {
        self.tools.slots.push(Some(slot));
        self.tools.slots.len() - 1
    }
}

/// The patches' ropes and forces as the shared `rope`, `move-rope`, `force` and `release` edits
/// see them ([`crate::tools::tool_edit`]); a rope is a delta spring (eq 19) to a cursor moving
/// linearly from `from` to `to` between `start` and `until`, a force is constant.
impl ToolHost for Patches {
    /// No field tools: gravity, inflation and repulsion are refused.
    type Field = std::convert::Infallible;
    crate::tools::tool_table!(tools.table);
    fn attach_rope(
        &mut self,
        r: &RopeRequest,
    ) -> Result<(usize, Option<CursorPath>, String), SessionError> {
        if r.velocity.is_some() || r.length.is_some() || r.kernel.is_some() {
            return Err(cmd_err(
                "a dnurbs-patches rope takes from, param, to, start, until, release and stiffness (not velocity, length or kernel)",
            ));
        }
        finite3("from", &r.from)?;
        let to = r.to.unwrap_or(r.from);
        finite3("to", &to)?;
        let stiffness = r.stiffness.unwrap_or(self.settings.k);
        if !(stiffness.is_finite() && stiffness > 0.0) {
            return Err(cmd_err(format!("stiffness {stiffness}: must be positive")));
        }
        let param = param_or_near(&self.engine, r.param, Some(&r.from))?;
        let start = r.start.unwrap_or(self.engine.time());
        let path = CursorPath::Linear {
            from: r.from,
            to,
            start,
            end: r.until.unwrap_or(start).max(start),
        };
        let h = self.add_slot(Slot::Rope {
            param,
            stiffness,
            cursor: to,
        });
        Ok((h, Some(path), format!("at parameter {param:?}")))
    }
    fn attach_force(&mut self, edit: &Edit) -> Result<(usize, String), SessionError> {
        let Edit::Force {
            near, param, force, ..
        } = edit
        else {
            return Err(super::misrouted());
        };
        finite3("force", force)?;
        let param = param_or_near(&self.engine, *param, near.as_ref())?;
        let h = self.add_slot(Slot::Point {
            param,
            force: *force,
        });
        Ok((h, format!("at parameter {param:?}")))
    }
    fn attach_field(&mut self, field: Self::Field) -> Result<usize, SessionError> {
        match field {}
    }
    fn replace_field(&mut self, _handle: usize, field: Self::Field) -> Result<usize, SessionError> {
        match field {}
    }
    fn move_cursor(&mut self, handle: usize, to: [f64; 3]) -> Result<(), SessionError> {
        finite3("to", &to)?;
        if let Some(Some(Slot::Rope { cursor, .. })) = self.tools.slots.get_mut(handle) {
            *cursor = to;
        }
        Ok(())
    }
    fn detach(&mut self, handle: usize) {
        if let Some(s) = self.tools.slots.get_mut(handle) {
            *s = None;
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
struct PatchNet<'a>(&'a mut Engine);

impl crate::tools::ControlNet for PatchNet<'_> {
    fn current_points(&self) -> Vec<Vec3> {
        control_points(self.0)
    }
    fn rest_points(&self) -> Vec<Vec3> {
        let q = self.0.state().rest_coordinates;
        (0..q.len() / 4)
            .map(|c| Vec3::new(q[4 * c], q[4 * c + 1], q[4 * c + 2]))
            .collect()
    }
    fn is_fixed(&self, c: usize) -> bool {
        xyz(c).all(|i| self.0.is_fixed_coordinate(i))
    }
    fn set_fixed(&mut self, ids: &[usize], fix: bool) -> Result<(), SessionError> {
        for &c in ids {
            for i in xyz(c) {
                self.0
                    .set_fixed_coordinate(i, fix)
                    .map_err(SessionError::command_from)?;
            }
        }
        Ok(())
    }
}

/// Every patch's control points, patch after patch.
fn control_points(engine: &Engine) -> Vec<Vec3> {
    (0..engine.geometry().len())
        .filter_map(|k| patch(engine, k).ok())
        .flat_map(|s| s.control_points().to_vec())
        .collect()
}

impl GeneralizedKind for Patches {
    type Engine = Engine;
    /// The time step and the tools.
    type State = (f64, Tools);
    const EDITS_REDRAW: bool = true;
    const MESH_NAME: &'static str = "dnurbs-patches";
    fn kind(&self) -> ModelKind {
        ModelKind::DnurbsPatches
    }
    generalized_accessors!(engine, settings.dt);
    fn exports(&self) -> &'static [&'static str] {
        &["json", "obj", "ply", "stl"]
    }
    fn take(&self) -> (f64, Tools) {
        (self.settings.dt, self.tools.clone())
    }
    fn put(&mut self, s: &(f64, Tools)) -> Result<(), SessionError> {
        self.settings.dt = s.0;
        self.tools = s.1.clone();
        Ok(())
    }
    fn summary(&self) -> String {
        let engine = &self.engine;
        format!(
            "dnurbs-patches: {} patches, {} control points, {} joins ({} ties), {} ropes, {} forces",
            engine.geometry().len(),
            engine.geometry().coordinates().len() / 4,
            self.settings.joins.len(),
            engine.ties().len(),
            self.tools.active("rope").count(),
            self.tools.active("force").count()
        )
    }
    /// Puts the tools into the engine's force list for a step starting at the engine's time:
    /// the shared schedule first ([`ToolTable::due`]: releases, then the cursors), then the
    /// ropes' springs and the forces, ropes first.
    fn before_step(&mut self) {
        let engine = &mut self.engine;
        let t = engine.time();
        for gone in self.tools.table.due(t, self.settings.dt).expired {
            if let Some(s) = self.tools.slots.get_mut(gone.handle) {
                *s = None;
            }
        }
        let forces = engine.forces_mut();
        forces.clear();
        for (e, s) in self.tools.active("rope") {
            if let Slot::Rope {
                param, stiffness, ..
            } = *s
            {
                forces.push(Force::Spring {
                    param,
                    target: Target::Fixed(Tools::cursor(e, s, t)),
                    stiffness,
                    kernel: None,
                });
            }
        }
        for (_, s) in self.tools.active("force") {
            if let Slot::Point { param, force } = *s {
                forces.push(Force::Point {
                    param,
                    force: Vec3::from(force),
                });
            }
        }
    }
    fn mesh(&self) -> Result<TriMesh, SessionError> {
        let engine = &self.engine;
        let mut mesh = TriMesh::new();
        let n = self.settings.tessellation;
        for k in 0..engine.geometry().len() {
            let mut part = TriMesh::new();
            vclay_spline::tessellate_surface(&patch(engine, k)?, [n, n], &mut part)
                .map_err(SessionError::kernel)?;
            mesh.append(&part);
        }
        Ok(mesh)
    }
    fn display_lines(&self, _size: f64) -> Vec<LineSet> {
        let engine = &self.engine;
        let mut net = LineSet::new(LineRole::ControlNet);
        for k in 0..engine.geometry().len() {
            let Ok(s) = patch(engine, k) else { continue };
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
        let t = engine.time();
        for (e, s) in self.tools.active("rope") {
            if let Slot::Rope { param, .. } = *s
                && let Some(p) = point_at(engine, param)
            {
                ropes.segment(p, Tools::cursor(e, s, t));
            }
        }
        let f = &engine.state().fixed;
        let fixed = LineSet::markers(LineRole::Fixed, &control_points(engine), |c| f[4 * c]);
        vec![net, ropes, fixed]
    }
    fn control_points(&self) -> Vec<Vec3> {
        control_points(&self.engine)
    }
    fn edit(
        &mut self,
        edit: &Edit,
        _before: &(GeneralizedState, (f64, Tools)),
    ) -> Result<Done, SessionError> {
        Ok(Done::State(match edit {
            _ if crate::tools::is_tool_edit(edit) => crate::tools::tool_edit(self, edit)?,
            Edit::Fix { .. } | Edit::Free { .. } => {
                let r = crate::tools::fix_or_free(&mut PatchNet(&mut self.engine), edit)?;
                crate::tools::fixed_message(edit, &r)
            }
            other => {
                return Err(cmd_err(format!(
                    "a dnurbs-patches model takes rope, move-rope, force, release, fix, free and `set dt` only, not {other:?}"
                )));
            }
        }))
    }
    fn write(&self, ext: &str, path: &Path) -> Option<Result<(), SessionError>> {
        (ext == "json").then(|| {
            let n = self.engine.geometry().len();
            let entities = (0..n)
                .map(|k| patch(&self.engine, k).map(Entity::Surface))
                .collect::<Result<Vec<_>, _>>()?;
            vclay_io::model::write_model(path, &entities).map_err(|e| SessionError::io(path, e))
        })
    }
    fn save(&self, _size: f64) -> Result<serde_json::Value, SessionError> {
        serde_json::to_value(Saved {
            settings: self.settings.clone(),
            tools: self.tools.clone(),
            state: SavedState::from(&self.engine.state()),
        })
        .map_err(SessionError::kernel)
    }
}

/// The typed spec of a multi-patch D-NURBS ([`super::ModelSpec`]).
pub type PatchesSpec = super::KindSpec<ModelKeys, MaterialKeys, SimKeys>;

scenario_keys! {
    /// The `[model]` keys of a `dnurbs-patches` model.
    pub struct ModelKeys {
        #[serde(default)]
        pub patch: Vec<PatchKeys>,
        #[serde(default)]
        pub join: Vec<JoinKeys>,
        pub tessellation: Option<usize>,
    }
}

scenario_keys! {
    /// The entry keys of a `dnurbs-patches` model.
    pub struct PatchKeys {
        pub origin: Option<[f64; 3]>,
        pub size: Option<[f64; 2]>,
        pub controls: Option<[usize; 2]>,
        pub degree: Option<[usize; 2]>,
        pub file: Option<PathBuf>,
    }
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

scenario_keys! {
    /// The entry keys of a `dnurbs-patches` model.
    pub struct JoinKeys {
        pub a: usize,
        pub b: usize,
        pub continuity: String,
    }
}

scenario_keys! {
    /// The `[material]` keys of a `dnurbs-patches` model.
    pub struct MaterialKeys {
        pub preset: Option<String>,
        pub mu: Option<f64>,
        pub gamma: Option<f64>,
        pub alpha: Option<[f64; 2]>,
        pub beta: Option<[f64; 3]>,
    }
}

/// The `[simulation]` keys of this kind: only the clock's step `dt` (absent: the preset's).
pub type SimKeys = super::ClockKeys;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    settings: Settings,
    tools: Tools,
    state: SavedState,
}
