//! The one session model over the D-NURBS engines ([`DnurbsEngine`]: the generalized
//! `GeneralizedDnurbs<G>`, `d-nurbs.txt` eq 15 with the matrices of eqs 16-17 of any geometry
//! `G`, and the frozen-weight `Dnurbs<G>` of footnote 2; both integrated by eq 18):
//! [`GeneralizedModel`] does what every D-NURBS kind does the same way (the clock, the step
//! and its report, undo by the engine state plus what the kind's edits change, `set dt`, the
//! pick through the display mesh, mesh exports, plastic flow); a [`GeneralizedKind`] holds
//! its engine and what differs (building it from keys, display, the edits it takes, its own
//! export formats, its saved form).
//!
//! Kinds: [`super::dnurbs::Nurbs`] (`dnurbs-curve`, `-surface`, `-swung`: rational curves and
//! surfaces and swung surfaces on the generalized engine, curves and surfaces also on the
//! frozen-weight one, with force slots, constraints and the shared tool table),
//! [`super::dnurbs_tri::Triangular`] (`dnurbs-triangular`) and
//! [`super::dnurbs_patches::Patches`] (`dnurbs-patches`).

use std::path::Path;

use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::dnurbs::{Density, ElasticReference, Material, Preset};

use super::SpecError;
pub use super::engine::DnurbsEngine;
use super::saved::step_report;
use crate::command::Edit;
use crate::error::SessionError;
use crate::model::{
    Done, Element, Energy, Hit, LineSet, Model, ModelKind, Param, Ray, StepReport, extension,
    unsupported_export,
};

/// The four accessors of [`GeneralizedKind`] that every kind writes the same way: the engine
/// (shared and mutable) and the time step, from the field paths given
/// (`generalized_accessors!(engine, settings.dt)`).
macro_rules! generalized_accessors {
    ($engine:ident, $($dt:ident).+) => {
        fn engine(&self) -> &Self::Engine {
            &self.$engine
        }
        fn engine_mut(&mut self) -> &mut Self::Engine {
            &mut self.$engine
        }
        fn dt(&self) -> f64 {
            self.$($dt).+
        }
        fn set_dt(&mut self, dt: f64) {
            self.$($dt).+ = dt;
        }
    };
}
pub(crate) use generalized_accessors;

/// A D-NURBS kind of [`GeneralizedModel`]: its engine and what it changes, and the answers
/// that differ between kinds (defaults: what the triangular and patch kinds answer).
pub trait GeneralizedKind: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The engine (`d-nurbs.txt` section 4: its geometry's Jacobian of eqs 3-6, 7 or 13).
    type Engine: DnurbsEngine;
    /// What edits change besides the engine state (kept in undo snapshots).
    type State: Clone + Send + Sync + 'static;
    /// Whether every applied edit is a new revision (kinds whose edits are drawn: ropes, forces,
    /// fixed points); otherwise an edit leaves the revision alone (`set dt`, `set
    /// weight_penalty` change nothing drawn).
    const EDITS_REDRAW: bool;
    /// The mesh's name in a `.glb` export.
    const MESH_NAME: &'static str;
    /// The kind.
    fn kind(&self) -> ModelKind;
    /// The engine.
    fn engine(&self) -> &Self::Engine;
    /// The engine, mutably.
    fn engine_mut(&mut self) -> &mut Self::Engine;
    /// The time step of eq 18 (s).
    fn dt(&self) -> f64;
    /// Sets the time step (checked by the caller: positive and finite).
    fn set_dt(&mut self, dt: f64);
    /// Steps taken. Default: the engine's count.
    fn steps(&self) -> u64 {
        self.engine().steps()
    }
    /// Takes what edits change besides the engine state.
    fn take(&self) -> Self::State;
    /// Puts back what [`GeneralizedKind::take`] took, after the engine state.
    fn put(&mut self, state: &Self::State) -> Result<(), SessionError>;
    /// What must change before the engine state is put back (a material the elements are
    /// integrated with). Default: nothing.
    fn put_before(&mut self, _state: &Self::State) -> Result<(), SessionError> {
        Ok(())
    }
    /// One line about the model (sizes).
    fn summary(&self) -> String;
    /// Before each step: the engine's forces for a step that starts at the engine's time.
    fn before_step(&mut self) {}
    /// After each step, with the engine's report.
    fn after_step(&mut self, _report: &vclay_dynamics::StepReport) {}
    /// The energies; `last` is the last step's report (the initial elastic energy before the
    /// first). Default: `last`.
    fn energy(&self, last: Energy) -> Energy {
        last
    }
    /// The display mesh.
    fn mesh(&self) -> Result<TriMesh, SessionError>;
    /// Control net, tools, fixed points, constraints; `size` is the model's size (arrows).
    fn display_lines(&self, size: f64) -> Vec<LineSet>;
    /// The control points at the current state.
    fn control_points(&self) -> Vec<Vec3> {
        self.engine().control_points(false)
    }
    /// The nearest hit of `ray`. Default: the display mesh, at the parameter nearest the hit.
    fn pick(&self, ray: &Ray, _tolerance: f64) -> Option<Hit> {
        surface_pick(ray, &self.mesh().ok()?, &[], self.engine())
    }
    /// The parameters. Default: `dt`, then [`GeneralizedKind::more_params`].
    fn params(&self) -> Vec<Param> {
        let mut v = vec![dt_param(self.dt())];
        v.extend(self.more_params());
        v
    }
    /// The parameters besides `dt` (for the default [`GeneralizedKind::params`]).
    fn more_params(&self) -> Vec<Param> {
        Vec::new()
    }
    /// Applies an edit other than `set dt`, or fails leaving everything unchanged (`before`
    /// is the state just before); says what it did and how it is undone.
    fn edit(
        &mut self,
        edit: &Edit,
        before: &(<Self::Engine as DnurbsEngine>::State, Self::State),
    ) -> Result<Done, SessionError>;
    /// The extensions [`Model::export`] writes.
    fn exports(&self) -> &'static [&'static str];
    /// Writes the formats of [`GeneralizedKind::exports`] that are the kind's own (model
    /// JSON, CAD files); `None` for a mesh format, which the model writes from the display
    /// mesh.
    fn write(&self, ext: &str, path: &Path) -> Option<Result<(), SessionError>>;
    /// The session file form; `size` is the model's size.
    fn save(&self, size: f64) -> Result<serde_json::Value, SessionError>;
}

/// The hit of `ray` on a surface's display `mesh`: the point and its parameter, interpolated
/// from `params` (one per mesh vertex) where given, else the engine's nearest parameter.
pub(crate) fn surface_pick<E: DnurbsEngine>(
    ray: &Ray,
    mesh: &TriMesh,
    params: &[[f64; 2]],
    engine: &E,
) -> Option<Hit> {
    crate::pick::ray_mesh(ray, mesh).map(|(s, tri, w)| {
        let point = ray.origin + ray.direction * s;
        let param = if params.len() == mesh.positions.len() {
            let mut q = [0.0; 2];
            for (k, &i) in mesh.triangles[tri].iter().enumerate() {
                q[0] += w[k] * params[i as usize][0];
                q[1] += w[k] * params[i as usize][1];
            }
            q
        } else {
            engine.nearest_param(&point).unwrap_or([0.0, 0.0])
        };
        Hit {
            distance: s,
            point,
            element: Element::SurfacePoint { param },
            extra: [None, None],
        }
    })
}

/// The material point a tool acts at: `param` when given, else the parameter of the point
/// nearest `near`; checked (an error names a parameter outside the domain).
pub(crate) fn param_or_near<E: DnurbsEngine>(
    engine: &E,
    param: Option<[f64; 2]>,
    near: Option<&crate::command::V3>,
) -> Result<[f64; 2], SessionError> {
    let cmd = |e: String| SessionError::command("", "", e);
    let p = match (param, near) {
        (Some(p), _) => p,
        (None, Some(x)) => engine
            .nearest_param(&crate::tools::v3(*x))
            .map_err(SessionError::command_from)?,
        (None, None) => return Err(cmd("give `param` or a position".into())),
    };
    engine
        .point_at(p)
        .map_err(|e| cmd(format!("material point {p:?}: {e}")))?;
    Ok(p)
}

/// The time step as a parameter.
pub(crate) fn dt_param(dt: f64) -> Param {
    Param::new("dt", dt, 1e-5, 0.1, "time step of eq 18 (s)")
}

/// A model over a D-NURBS engine (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct GeneralizedModel<K: GeneralizedKind> {
    kind: K,
    size: f64,
    revision: u64,
    energy: Energy,
}

impl<K: GeneralizedKind> GeneralizedModel<K> {
    /// A model of `kind` (its engine built, not stepped); `size` scales tolerances; the
    /// revision starts at `revision`.
    pub(crate) fn new(kind: K, size: f64, revision: u64) -> Self {
        let elastic = kind.engine().elastic_energy().unwrap_or(0.0);
        Self {
            kind,
            size,
            revision,
            energy: Energy {
                elastic,
                ..Energy::default()
            },
        }
    }

    /// Puts back a saved engine state (session files).
    pub(crate) fn with_state(
        mut self,
        state: <K::Engine as DnurbsEngine>::State,
    ) -> Result<Self, SessionError> {
        self.kind
            .engine_mut()
            .set_state(&state)
            .map_err(SessionError::kernel)?;
        Ok(self)
    }

    /// The engine (for tests and tools).
    pub fn engine(&self) -> &K::Engine {
        self.kind.engine()
    }

    /// The kind's part.
    pub fn kind_part(&self) -> &K {
        &self.kind
    }

    pub(crate) fn kind_mut(&mut self) -> &mut K {
        &mut self.kind
    }

    pub(crate) fn set_size(&mut self, size: f64) {
        self.size = size;
    }

    pub(crate) fn set_revision(&mut self, revision: u64) {
        self.revision = revision;
    }
}

/// A uniform material of constant densities (`d-nurbs.txt` eqs 16-17: mass `mu`, damping
/// `gamma`, tension `alpha`, rigidity `beta`).
pub(crate) fn constant_material(mu: f64, gamma: f64, alpha: &[f64], beta: &[f64]) -> Material {
    Material {
        mu: Density::Constant(mu),
        gamma: Density::Constant(gamma),
        alpha: alpha.iter().map(|&a| Density::Constant(a)).collect(),
        beta: beta.iter().map(|&b| Density::Constant(b)).collect(),
    }
}

/// The Table 1 row named by `[material] preset` (`d-nurbs.txt` Table 1).
pub(crate) fn table_one(name: &str) -> Result<&'static Preset, SpecError> {
    Preset::by_name(name).ok_or_else(|| {
        SpecError::new(
            "material",
            "preset",
            format!("{name:?} is not a Table 1 row"),
        )
    })
}

/// Checks `[material]` values (finite and non-negative) and `[simulation] dt` (positive and
/// finite); the error names the first key at fault.
pub(crate) fn check_material_and_dt(material: &[(&str, f64)], dt: f64) -> Result<(), SpecError> {
    for &(key, v) in material {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SpecError::new(
                "material",
                key,
                format!("{v} must be finite and non-negative"),
            ));
        }
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SpecError::new(
            "simulation",
            "dt",
            format!("{dt} must be positive and finite"),
        ));
    }
    Ok(())
}

/// The diagonal of the bounding box of `pts` (a model's size, which scales tolerances); 1 for
/// no points, and never below the smallest positive number.
pub(crate) fn bbox_diagonal<'a>(pts: impl IntoIterator<Item = &'a Vec3>) -> f64 {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    let mut empty = true;
    for p in pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
        empty = false;
    }
    if empty {
        return 1.0;
    }
    (hi - lo).norm().max(f64::MIN_POSITIVE)
}

/// The elastic reference of a saved flag (`absolute`).
pub(crate) fn reference(absolute: bool) -> ElasticReference {
    if absolute {
        ElasticReference::Absolute
    } else {
        ElasticReference::RestShape
    }
}

impl<K: GeneralizedKind> crate::model::Stateful for GeneralizedModel<K> {
    type State = (<K::Engine as DnurbsEngine>::State, K::State);
    const EDITS_REDRAW: bool = K::EDITS_REDRAW;
    fn take_state(&self) -> Self::State {
        (self.kind.engine().state(), self.kind.take())
    }
    fn put_state(&mut self, s: &Self::State) -> Result<(), SessionError> {
        self.kind.put_before(&s.1)?;
        self.kind
            .engine_mut()
            .set_state(&s.0)
            .map_err(SessionError::from)?;
        self.kind.put(&s.1)
    }
    fn revision_mut(&mut self) -> &mut u64 {
        &mut self.revision
    }
    fn edit(&mut self, edit: &Edit, before: &Self::State) -> Result<Done, SessionError> {
        match edit {
            Edit::Set { name, value } if name == "dt" => {
                self.kind.set_dt(crate::model::positive_dt(*value)?);
                Ok(Done::State(format!("dt = {value}")))
            }
            _ => self.kind.edit(edit, before),
        }
    }
}

impl<K: GeneralizedKind> Model for GeneralizedModel<K> {
    fn kind(&self) -> ModelKind {
        self.kind.kind()
    }
    /// The kind's tools less what the engine refuses ([`DnurbsEngine::refused_actions`]).
    fn tools(&self) -> Vec<crate::describe::ToolSpec> {
        let refused = self.kind.engine().refused_actions();
        crate::describe::tools_for(self.kind())
            .into_iter()
            .filter(|t| !refused.contains(&t.action))
            .collect()
    }
    fn summary(&self) -> String {
        self.kind.summary()
    }
    crate::model::clock_methods!(self => self.kind.engine().time(), self.kind.dt(), self.kind.steps());
    fn step(&mut self) -> Result<StepReport, SessionError> {
        self.kind.before_step();
        self.revision += 1;
        let t0 = std::time::Instant::now();
        let dt = self.kind.dt();
        let r = self
            .kind
            .engine_mut()
            .step(dt)
            .map_err(SessionError::from)?;
        self.kind.after_step(&r);
        let report = step_report(&r, t0);
        self.energy = report.energy;
        Ok(report)
    }
    fn energy(&self) -> Energy {
        self.kind.energy(self.energy)
    }
    fn size(&self) -> f64 {
        self.size
    }
    fn revision(&self) -> u64 {
        self.revision
    }
    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        self.kind.mesh()
    }
    fn display_lines(&self) -> Vec<LineSet> {
        self.kind.display_lines(self.size)
    }
    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit> {
        self.kind.pick(ray, tolerance)
    }
    fn params(&self) -> Vec<Param> {
        self.kind.params()
    }
    crate::model::stateful_methods!();
    fn control_points(&self) -> Vec<Vec3> {
        self.kind.control_points()
    }
    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        let ext = extension(path);
        let formats = self.kind.exports();
        if !formats.contains(&ext.as_str()) {
            return Err(unsupported_export(self.kind.kind(), path, formats));
        }
        if let Some(r) = self.kind.write(&ext, path) {
            return r;
        }
        let mesh = self.display_mesh()?;
        match ext.as_str() {
            "glb" => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(K::MESH_NAME.to_string(), mesh)],
            )
            .map_err(|e| io(&e)),
            _ => vclay_io::write_mesh(path, &mesh).map_err(|e| io(&e)),
        }
    }
    fn export_formats(&self) -> Vec<&'static str> {
        self.kind.exports().to_vec()
    }
    fn save(&self) -> Result<serde_json::Value, SessionError> {
        self.kind.save(self.size)
    }
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        // The undo state is the engine's, rest coordinates included.
        self.kind
            .engine_mut()
            .plastic_flow(fraction, yield_distance)
    }
}
