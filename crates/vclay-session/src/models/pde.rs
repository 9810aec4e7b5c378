//! Dynamic PDE surfaces in a session: [`PdeSurfaceModel`] wraps a compiled `vclay_pde::PdeModel`
//! (You & Zhang, `dynamic-pde-surfaces.txt`): every patch is the solution `x(u, v, t)` of the
//! fourth-order PDE of eq (1) with boundary conditions at `u = 0, 1` that are functions of `v`
//! and `t` (eq 2), split into basic functions (eq 3) and solved by collocation least squares
//! (eqs 4-12).
//!
//! **Time.** The PDE's `t` is the model's clock: each [`Model::step`] advances it by `dt` and
//! solves the spec again at the new instant (as the paper does, each instant is an independent
//! solve, eq 7; see the `vclay_pde` limitations), then tessellates on the `grid`.
//!
//! **Edits.** The named constants of the spec (its `params`, substituted into every expression
//! of the boundary functions, shape functions, rho, eta, ranges and local deformations) are the
//! model's handles: `pde-set` (or `set`) with a constant's name recompiles the spec with the new
//! value and solves it at the current time; `pde-set` with `name = "t"` sets the time; `set`
//! with `dt` changes the time step. Every other edit is an error naming the kind.
//!
//! **Undo.** Setting a value is undone by setting the old one ([`Undo::Inverse`]), followed by
//! the snapshot of constants, time, steps and `dt` taken before the edit; the surface is a pure
//! function of those, so the undo is exact to the bit.
//!
//! **Limitations.** Energies are reported as zero (the kernel has no energy of the moving
//! surface). A pick reports `[u, v]` in the patch it hits but not which patch. The surface is
//! solved from scratch every step (no reuse of the solution of patches that do not depend on
//! `t`), which keeps a reloaded session identical to the bit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_pde::surface::tessellation_samples;
use vclay_pde::{PdeError, PdeModel, SpecFile, builtin};

use super::SpecError;
use crate::command::Edit;
use crate::error::SessionError;
use crate::model::{Clock, Done};
use crate::model::{
    Element, Energy, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray, StepReport, extension,
    unsupported_export,
};

/// Default `[simulation] dt`: 1/30 s (one display frame).
pub const DEFAULT_DT: f64 = 1.0 / 30.0;
/// Default tessellation `grid` per patch (the `vclay pde` default).
pub const DEFAULT_GRID: [usize; 2] = [64, 64];
/// Most tessellation samples along one direction of a patch.
pub const MAX_GRID: usize = 1024;
/// The built-in specs of `[model] builtin` (`vclay_pde::builtin`).
pub const BUILTINS: [&str; 8] = [
    "section3", "glass", "vase", "fig4a", "fig5a", "fig7a", "fig8", "aircraft",
];

fn builtin_text(name: &str) -> Option<&'static str> {
    Some(match name {
        "section3" => builtin::SECTION3,
        "glass" => builtin::GLASS,
        "vase" => builtin::VASE,
        "fig4a" => builtin::FIG4A,
        "fig5a" => builtin::FIG5A,
        "fig7a" => builtin::FIG7A,
        "fig8" => builtin::FIG8,
        "aircraft" => builtin::AIRCRAFT,
        _ => return None,
    })
}

/// The tessellated surface at one instant.
#[derive(Clone, Debug, Default)]
struct Surface {
    mesh: TriMesh,
    /// `[u, v]` of every mesh vertex (in its patch).
    uv: Vec<[f64; 2]>,
    /// Per patch: first vertex and the sample counts along u and v.
    patches: Vec<(usize, usize, usize)>,
    /// Largest RMS collocation residual over the patches.
    residual: f64,
}

impl Surface {
    fn solve(model: &PdeModel, t: f64, grid: [usize; 2]) -> Result<Self, PdeError> {
        let sol = model.solve(t)?;
        let mut mesh = TriMesh::new();
        model.tessellate(&sol, grid[0], grid[1], &mut mesh);
        let mut uv = Vec::with_capacity(mesh.positions.len());
        let mut patches = Vec::with_capacity(model.patches.len());
        for p in &model.patches {
            // The samples `PdeModel::tessellate` uses, vertices row-major along u.
            let (us, vs) = tessellation_samples(p, grid[0], grid[1]);
            patches.push((uv.len(), us.len(), vs.len()));
            for &u in &us {
                uv.extend(vs.iter().map(|&v| [u, v]));
            }
        }
        debug_assert_eq!(uv.len(), mesh.positions.len());
        Ok(Self {
            mesh,
            uv,
            patches,
            residual: sol.residual_rms(),
        })
    }
}

/// A dynamic PDE surface (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct PdeSurfaceModel {
    /// The spec as given (its `params` are the initial constants).
    spec: SpecFile,
    /// Current values of the named constants.
    constants: BTreeMap<String, f64>,
    /// Local deformations added by `pde-local` commands (on top of the spec's own).
    locals: Vec<UserLocal>,
    model: PdeModel,
    grid: [usize; 2],
    clock: Clock,
    size: f64,
    surface: Surface,
    source: String,
    revision: u64,
}

/// The evolving state.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PdeSnap {
    constants: BTreeMap<String, f64>,
    locals: Vec<UserLocal>,
    clock: Clock,
}

fn cmd(reason: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", reason)
}

/// A local deformation added by a `pde-local` command (`dynamic-pde-surfaces.txt` eqs 30-32).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserLocal {
    /// Its name.
    pub name: String,
    /// Patch index.
    pub patch: usize,
    /// `[u1, u2]`.
    pub u: [f64; 2],
    /// `[v1, v2]`.
    pub v: [f64; 2],
    /// `G0` or `G1`.
    pub continuity: String,
    /// The amplitude `p`.
    pub p: [f64; 3],
}

/// Compiles `spec` with its `params` replaced by `constants` and the `locals` added to their
/// patches.
fn compile(
    spec: &SpecFile,
    constants: &BTreeMap<String, f64>,
    locals: &[UserLocal],
) -> Result<PdeModel, PdeError> {
    let mut s = spec.clone();
    s.params = constants.clone();
    for l in locals {
        let n = s.patches.len();
        let patch = s
            .patches
            .get_mut(l.patch)
            .ok_or_else(|| PdeError::InvalidValue {
                place: format!("local deformation `{}`", l.name),
                message: format!("patch {} does not exist (the spec has {n})", l.patch),
            })?;
        patch.local.push(vclay_pde::spec::LocalSpec {
            u: l.u.map(vclay_pde::spec::Value::Num),
            v: l.v.map(vclay_pde::spec::Value::Num),
            continuity: l.continuity.clone(),
            p: l.p.map(vclay_pde::spec::Value::Num),
        });
    }
    PdeModel::from_spec(&s)
}

fn bbox_size(mesh: &TriMesh) -> f64 {
    mesh.bounding_box()
        .map_or(1.0, |(lo, hi)| (hi - lo).norm())
        .max(f64::MIN_POSITIVE)
}

impl PdeSurfaceModel {
    /// Compiles `spec` (with `constants` for its `params`) and solves it at `time`.
    fn assemble(
        spec: SpecFile,
        constants: BTreeMap<String, f64>,
        grid: [usize; 2],
        dt: f64,
        time: f64,
        source: &str,
    ) -> Result<Self, PdeError> {
        let model = compile(&spec, &constants, &[])?;
        let surface = Surface::solve(&model, time, grid)?;
        Ok(Self {
            spec,
            constants,
            locals: Vec::new(),
            model,
            grid,
            clock: Clock { time, dt, steps: 0 },
            size: bbox_size(&surface.mesh),
            surface,
            source: source.to_string(),
            revision: 1,
        })
    }

    /// The compiled spec.
    pub fn pde(&self) -> &PdeModel {
        &self.model
    }

    /// Current values of the named constants.
    pub fn constants(&self) -> &BTreeMap<String, f64> {
        &self.constants
    }

    /// The spec with the current constants (what `json` export writes).
    pub fn current_spec(&self) -> SpecFile {
        let mut s = self.spec.clone();
        s.params = self.constants.clone();
        for l in &self.locals {
            if let Some(patch) = s.patches.get_mut(l.patch) {
                patch.local.push(vclay_pde::spec::LocalSpec {
                    u: l.u.map(vclay_pde::spec::Value::Num),
                    v: l.v.map(vclay_pde::spec::Value::Num),
                    continuity: l.continuity.clone(),
                    p: l.p.map(vclay_pde::spec::Value::Num),
                });
            }
        }
        s
    }

    /// The local deformations added by commands.
    pub fn locals(&self) -> &[UserLocal] {
        &self.locals
    }

    /// Sets constant `name` (recompiling and solving at the current time) or, for `t`, the
    /// time; returns the old value. Fails leaving the model unchanged.
    fn set_value(&mut self, name: &str, value: f64) -> Result<f64, SessionError> {
        if name == "t" {
            let surface = Surface::solve(&self.model, value, self.grid)
                .map_err(SessionError::command_from)?;
            self.surface = surface;
            return Ok(std::mem::replace(&mut self.clock.time, value));
        }
        let Some(&old) = self.constants.get(name) else {
            return Err(cmd(format!(
                "the spec has no constant `{name}`; it has {} (and `t`, the time)",
                if self.constants.is_empty() {
                    "none".to_string()
                } else {
                    self.constants
                        .keys()
                        .map(String::as_str)
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            )));
        };
        let mut constants = self.constants.clone();
        constants.insert(name.to_string(), value);
        let model =
            compile(&self.spec, &constants, &self.locals).map_err(SessionError::command_from)?;
        let surface = Surface::solve(&model, self.clock.time, self.grid)
            .map_err(SessionError::command_from)?;
        self.model = model;
        self.surface = surface;
        self.constants = constants;
        Ok(old)
    }

    /// Replaces the added local deformations (recompiling and solving at the current time);
    /// fails leaving the model unchanged.
    fn set_locals(&mut self, locals: Vec<UserLocal>) -> Result<(), SessionError> {
        let model =
            compile(&self.spec, &self.constants, &locals).map_err(SessionError::command_from)?;
        let surface = Surface::solve(&model, self.clock.time, self.grid)
            .map_err(SessionError::command_from)?;
        self.model = model;
        self.surface = surface;
        self.locals = locals;
        Ok(())
    }

    /// Builds a model from a scenario's `[model]` and `[simulation]` tables (see
    /// `docs/formats.md`, kind `pde-surface`).
    pub fn from_keys(spec: &PdeSpec, base: &Path) -> Result<Self, SpecError> {
        let m = &spec.model;
        let err = |key: &str, what: String| SpecError::new("model", key, what);
        let dt = spec.simulation.dt_or(DEFAULT_DT)?;
        let grid = m.grid.unwrap_or(DEFAULT_GRID);
        if let Some(n) = grid.iter().find(|&&n| !(2..=MAX_GRID).contains(&n)) {
            return Err(err(
                "grid",
                format!("{n} samples; expected 2 to {MAX_GRID} along u and v"),
            ));
        }
        let (file, source) = match (&m.spec, &m.builtin) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "spec",
                    "give either `spec` or `builtin`, not both".into(),
                ));
            }
            (None, None) => return Err(err("spec", "give `spec` (a file) or `builtin`".into())),
            (None, Some(b)) => {
                let text = builtin_text(b).ok_or_else(|| {
                    err(
                        "builtin",
                        format!(
                            "unknown builtin spec \"{b}\"; expected {}",
                            BUILTINS.join(", ")
                        ),
                    )
                })?;
                let file: SpecFile = serde_json::from_str(text)
                    .map_err(|e| err("builtin", format!("builtin {b}: {e}")))?;
                (file, format!("builtin {b}"))
            }
            (Some(f), None) => {
                let path = if f.is_absolute() {
                    f.clone()
                } else {
                    base.join(f)
                };
                let e = |e: PdeError| err("spec", e.to_string());
                let text = std::fs::read_to_string(&path)
                    .map_err(|x| err("spec", format!("{}: cannot read: {x}", path.display())))?;
                let name = path.display().to_string();
                let toml_file = extension(&path) == "toml";
                // The kernel's readers locate errors (line, column, field path).
                if toml_file {
                    PdeModel::from_toml(&text, &name).map_err(e)?;
                } else {
                    PdeModel::from_json(&text, &name).map_err(e)?;
                }
                let file: SpecFile = if toml_file {
                    toml::from_str(&text).map_err(|x| err("spec", x.to_string()))?
                } else {
                    serde_json::from_str(&text).map_err(|x| err("spec", x.to_string()))?
                };
                (file, f.display().to_string())
            }
        };
        let mut constants = file.params.clone();
        for (name, &value) in &m.params {
            match constants.get_mut(name) {
                Some(c) => *c = value,
                None => {
                    return Err(err(
                        "params",
                        format!(
                            "the spec has no constant `{name}`; it has {}",
                            file.params
                                .keys()
                                .map(String::as_str)
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
            }
        }
        let mut model = Self::assemble(file, constants, grid, dt, 0.0, &source).map_err(|e| {
            err(
                if m.params.is_empty() {
                    "spec"
                } else {
                    "params"
                },
                e.to_string(),
            )
        })?;
        model.revision = 1;
        Ok(model)
    }

    /// Rebuilds a model saved by [`Model::save`].
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let s: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        let spec: SpecFile = serde_json::from_value(s.spec).map_err(SessionError::kernel)?;
        if spec.params.keys().ne(s.constants.keys()) {
            return Err(SessionError::model(
                "the saved constants are not the spec's params",
            ));
        }
        if s.grid.iter().any(|n| !(2..=MAX_GRID).contains(n)) {
            return Err(SessionError::model(format!(
                "grid {:?}: expected 2 to {MAX_GRID} samples per direction",
                s.grid
            )));
        }
        if !(s.dt > 0.0 && s.dt.is_finite() && s.time.is_finite() && s.size.is_finite()) {
            return Err(SessionError::model(format!(
                "dt = {}, time = {}, size = {} must be finite, dt positive",
                s.dt, s.time, s.size
            )));
        }
        let mut model = Self::assemble(spec, s.constants, s.grid, s.dt, s.time, &s.source)
            .map_err(SessionError::kernel)?;
        if !s.locals.is_empty() {
            model.set_locals(s.locals).map_err(|e| e.in_model(""))?;
        }
        model.clock.steps = s.steps;
        model.size = s.size;
        Ok(model)
    }
}

impl crate::model::Stateful for PdeSurfaceModel {
    type State = PdeSnap;
    const INVERSE_MAY_FAIL: bool = true;
    fn take_state(&self) -> PdeSnap {
        PdeSnap {
            constants: self.constants.clone(),
            locals: self.locals.clone(),
            clock: self.clock,
        }
    }
    fn put_state(&mut self, s: &PdeSnap) -> Result<(), SessionError> {
        if s.constants != self.constants || s.locals != self.locals {
            let model =
                compile(&self.spec, &s.constants, &s.locals).map_err(SessionError::kernel)?;
            let surface =
                Surface::solve(&model, s.clock.time, self.grid).map_err(SessionError::kernel)?;
            self.model = model;
            self.surface = surface;
            self.constants = s.constants.clone();
            self.locals = s.locals.clone();
        } else if s.clock.time != self.clock.time {
            self.surface = Surface::solve(&self.model, s.clock.time, self.grid)
                .map_err(SessionError::kernel)?;
        }
        self.clock = s.clock;
        Ok(())
    }
    fn revision_mut(&mut self) -> &mut u64 {
        &mut self.revision
    }
    fn edit(&mut self, edit: &Edit, _before: &PdeSnap) -> Result<Done, SessionError> {
        Ok(match edit {
            Edit::PdeSet { name, value } => {
                let old = self.set_value(name, *value)?;
                Done::Inverse(
                    format!("{name} = {value} (residual {:.3e})", self.surface.residual),
                    Edit::PdeSet {
                        name: name.clone(),
                        value: old,
                    },
                )
            }
            Edit::Set { name, value } => {
                let old = if name == "dt" {
                    self.clock.set_dt(*value)?
                } else if self.constants.contains_key(name) {
                    self.set_value(name, *value)?
                } else {
                    return Err(cmd(format!(
                        "no parameter `{name}`; a {} model has {}",
                        ModelKind::PdeSurface,
                        self.params()
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                };
                Done::Inverse(
                    format!("{name} = {value}"),
                    Edit::Set {
                        name: name.clone(),
                        value: old,
                    },
                )
            }
            Edit::PdeLocal {
                name,
                patch,
                u,
                v,
                continuity,
                p,
            } => {
                let mut locals = self.locals.clone();
                // `v` is clipped to the patch's v range (a region dragged across the seam of a
                // closed surface stops at it).
                let n = self.model.patches.len();
                let (v0, v1) = self
                    .model
                    .patches
                    .get(*patch)
                    .map(|p| p.v_range)
                    .ok_or_else(|| {
                        cmd(format!("patch {patch} does not exist (the spec has {n})"))
                    })?;
                let v = [v[0].max(v0), v[1].min(v1)];
                if v[0] >= v[1] {
                    return Err(cmd(format!(
                        "`v` does not meet patch {patch}'s v range [{v0}, {v1}]"
                    )));
                }
                let local = UserLocal {
                    name: name.clone(),
                    patch: *patch,
                    u: *u,
                    v,
                    continuity: continuity.clone().unwrap_or_else(|| "G1".into()),
                    p: *p,
                };
                let replaced = match locals.iter_mut().find(|l| l.name == *name) {
                    Some(l) => {
                        *l = local;
                        true
                    }
                    None => {
                        locals.push(local);
                        false
                    }
                };
                self.set_locals(locals)?;
                Done::State(format!(
                    "local deformation `{name}` {} on patch {patch}",
                    if replaced { "changed" } else { "added" }
                ))
            }
            Edit::Release { name } => {
                let mut locals = self.locals.clone();
                let n = locals.len();
                locals.retain(|l| l.name != *name);
                if locals.len() == n {
                    return Err(cmd(format!("no local deformation named `{name}`")));
                }
                self.set_locals(locals)?;
                Done::State(format!("local deformation `{name}` removed"))
            }
            _ => {
                let takes = "pde-set, pde-local, release, set";
                return Err(super::not_taken(edit, ModelKind::PdeSurface, takes));
            }
        })
    }
}

impl Model for PdeSurfaceModel {
    fn kind(&self) -> ModelKind {
        ModelKind::PdeSurface
    }

    fn summary(&self) -> String {
        format!(
            "pde-surface `{}` ({}): {} patches, {} constants, {}x{} grid, {} vertices, residual {:.3e}",
            self.model.name,
            self.source,
            self.model.patches.len(),
            self.constants.len(),
            self.grid[0],
            self.grid[1],
            self.surface.mesh.positions.len(),
            self.surface.residual
        )
    }

    crate::model::clock_methods!(self => self.clock.time, self.clock.dt, self.clock.steps);

    fn step(&mut self) -> Result<StepReport, SessionError> {
        let report = self.clock.step(|t| {
            self.surface =
                Surface::solve(&self.model, t, self.grid).map_err(SessionError::kernel)?;
            Ok(())
        })?;
        self.revision += 1;
        Ok(report)
    }

    fn energy(&self) -> Energy {
        Energy::default()
    }

    fn size(&self) -> f64 {
        self.size
    }

    fn revision(&self) -> u64 {
        self.revision
    }

    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        Ok(self.surface.mesh.clone())
    }

    fn display_lines(&self) -> Vec<LineSet> {
        // The boundary curves u = 0 and u = 1 of every patch (eq 2).
        let mut set = LineSet::new(LineRole::Curve);
        let pos = &self.surface.mesh.positions;
        for &(base, nu, nv) in &self.surface.patches {
            for r in [0, nu - 1] {
                let row: Vec<Vec3> = pos[base + r * nv..base + (r + 1) * nv].to_vec();
                set.polyline(&row);
            }
        }
        vec![set]
    }

    fn pick(&self, ray: &Ray, _tolerance: f64) -> Option<Hit> {
        let mesh = &self.surface.mesh;
        crate::pick::ray_mesh(ray, mesh).map(|(s, t, bary)| {
            let tri = mesh.triangles[t];
            let mut param = [0.0; 2];
            for (c, &b) in tri.iter().zip(&bary) {
                let uv = self.surface.uv[*c as usize];
                param[0] += b * uv[0];
                param[1] += b * uv[1];
            }
            // The patch whose vertex range holds the triangle's first corner.
            let first = tri[0] as usize;
            let patch = self
                .surface
                .patches
                .iter()
                .rposition(|&(start, _, _)| start <= first)
                .unwrap_or(0);
            Hit {
                distance: s,
                point: ray.origin + ray.direction * s,
                element: Element::SurfacePoint { param },
                extra: [Some(Element::Patch { index: patch }), None],
            }
        })
    }

    fn params(&self) -> Vec<Param> {
        let mut out: Vec<Param> = self
            .constants
            .iter()
            .map(|(name, &value)| {
                let span = value.abs().max(1.0);
                Param {
                    name: name.clone(),
                    value,
                    min: value - 2.0 * span,
                    max: value + 2.0 * span,
                    doc:
                        "named constant of the spec's expressions (dynamic-pde-surfaces.txt eq 2-3)"
                            .into(),
                }
            })
            .collect();
        out.push(Param::new(
            "dt",
            self.clock.dt,
            1e-4,
            1.0,
            "time step of the PDE's t per session step",
        ));
        out
    }

    crate::model::stateful_methods!();

    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        match extension(path).as_str() {
            "obj" | "ply" | "stl" => {
                vclay_io::write_mesh(path, &self.surface.mesh).map_err(|e| io(&e))
            }
            "glb" => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(
                    self.model.name.clone(),
                    self.surface.mesh.clone(),
                )],
            )
            .map_err(|e| io(&e)),
            "json" => {
                let text =
                    serde_json::to_string_pretty(&self.current_spec()).map_err(|e| io(&e))?;
                vclay_io::write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))
                    .map_err(|e| io(&e))
            }
            _ => Err(unsupported_export(
                self.kind(),
                path,
                &["obj", "ply", "stl", "glb", "json"],
            )),
        }
    }

    fn save(&self) -> Result<serde_json::Value, SessionError> {
        let saved = Saved {
            source: self.source.clone(),
            spec: serde_json::to_value(&self.spec).map_err(SessionError::kernel)?,
            constants: self.constants.clone(),
            locals: self.locals.clone(),
            grid: self.grid,
            dt: self.clock.dt,
            time: self.clock.time,
            steps: self.clock.steps,
            size: self.size,
        };
        serde_json::to_value(saved).map_err(SessionError::kernel)
    }
}

// ---------------------------------------------------------------------------------------
// Scenario keys and the session file form
// ---------------------------------------------------------------------------------------

/// The typed spec of a PDE surface ([`super::ModelSpec`]).
pub type PdeSpec = super::KindSpec<ModelKeys, super::NoMaterial, super::ClockKeys>;

scenario_keys! {
    /// The `[model]` keys of a `pde-surface` model.
    pub struct ModelKeys {
        pub spec: Option<PathBuf>,
        pub builtin: Option<String>,
        pub grid: Option<[usize; 2]>,
        #[serde(default)]
        pub params: BTreeMap<String, f64>,
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    source: String,
    spec: serde_json::Value,
    constants: BTreeMap<String, f64>,
    #[serde(default)]
    locals: Vec<UserLocal>,
    grid: [usize; 2],
    dt: f64,
    time: f64,
    steps: u64,
    size: f64,
}
