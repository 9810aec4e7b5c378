//! One session model over the generalized D-NURBS engine `GeneralizedDnurbs<G>`
//! (`d-nurbs.txt` eq 15 with the mass, damping and stiffness matrices of eqs 16-17 of any
//! geometry `G`, integrated by eq 18): [`GeneralizedModel`] does what every such kind does the
//! same way (the clock, the step and its energies, undo by the engine state, the display mesh's
//! pick, the time step as a parameter, mesh exports, session files' engine state); a
//! [`GeneralizedKind`] holds what differs (building the geometry from keys, the display lines,
//! the edits it takes besides `set dt`, the JSON export and the saved settings).
//!
//! Kinds: `dnurbs-triangular` ([`super::dnurbs_tri::Triangular`]) and `dnurbs-patches`
//! ([`super::dnurbs_patches::Patches`]). `dnurbs-curve`, `-surface` and `-swung` are the other
//! model over the same engine, [`super::dnurbs::DnurbsModel`]: one model over an engine enum
//! whose two generalized variants (`GeneralizedDnurbs<RationalGeometry>`,
//! `GeneralizedDnurbs<SwungGeometry>`) share every line of code, beside the frozen-weight
//! engine (`d-nurbs.txt` footnote 2) that the same kinds run with the same tools, force slots,
//! saved form and display. It is not a [`GeneralizedKind`] because nearly every answer
//! [`GeneralizedModel`] gives the same way it gives differently (steps counted by the model,
//! the elastic energy read live, control points picked before the surface, material
//! parameters, STEP/IGES and curve exports, fix/free undone by their inverse edit), and the
//! frozen engine would have to leave the model. `docs/architecture.md` (vclay-session) says
//! precisely what a merge would take.

use std::path::Path;

use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::dnurbs::generalized::{GeneralizedGeometry, GeneralizedState};
use vclay_dynamics::dnurbs::{Density, ElasticReference, GeneralizedDnurbs, Material, Preset};

use super::SpecError;
use super::saved::{SavedState, step_implicit};
use crate::command::Edit;
use crate::error::SessionError;
use crate::model::{
    Done, Element, Energy, Hit, LineSet, Model, ModelKind, Param, Ray, StepReport, extension,
    unsupported_export,
};

/// What a kind over [`GeneralizedDnurbs`] adds to [`GeneralizedModel`]: its settings and tools,
/// and the few answers that differ between geometries.
pub trait GeneralizedKind: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The geometry the engine moves (`d-nurbs.txt` section 4: its Jacobian of eqs 3-6 or 13).
    type Geometry: GeneralizedGeometry + Clone + std::fmt::Debug + Send + Sync + 'static;
    /// What edits change besides the engine state (kept in undo snapshots).
    type State: Clone + Send + Sync + 'static;
    /// The kind.
    const KIND: ModelKind;
    /// The extensions [`Model::export`] writes (mesh formats through the display mesh, `json`
    /// through [`GeneralizedKind::write_json`]).
    const EXPORTS: &'static [&'static str];
    /// Whether every applied edit is a new revision (kinds whose edits are drawn: ropes, forces,
    /// fixed points); otherwise an edit leaves the revision alone (`set dt`, `set
    /// weight_penalty` change nothing drawn).
    const EDITS_REDRAW: bool;
    /// The mesh's name in a `.glb` export (where [`GeneralizedKind::EXPORTS`] has `glb`).
    const MESH_NAME: &'static str;
    /// The time step of eq 18 (s).
    fn dt(&self) -> f64;
    /// Sets the time step (checked by the caller: positive and finite).
    fn set_dt(&mut self, dt: f64);
    /// Takes what edits change.
    fn take(&self) -> Self::State;
    /// Puts back what [`GeneralizedKind::take`] took.
    fn put(&mut self, state: &Self::State);
    /// One line about the model (sizes).
    fn summary(&self, engine: &GeneralizedDnurbs<Self::Geometry>) -> String;
    /// Before each step: the engine's forces for a step that starts at the engine's time.
    fn before_step(&mut self, _engine: &mut GeneralizedDnurbs<Self::Geometry>) {}
    /// The display mesh.
    fn mesh(&self, engine: &GeneralizedDnurbs<Self::Geometry>) -> Result<TriMesh, SessionError>;
    /// Control net, tools, fixed points, constraints.
    fn display_lines(&self, engine: &GeneralizedDnurbs<Self::Geometry>) -> Vec<LineSet>;
    /// The control points at the current state.
    fn control_points(&self, engine: &GeneralizedDnurbs<Self::Geometry>) -> Vec<Vec3>;
    /// The parameters besides `dt`.
    fn params(&self) -> Vec<Param> {
        Vec::new()
    }
    /// Applies an edit other than `set dt`, or fails leaving everything unchanged; returns
    /// the log's message.
    fn apply(
        &mut self,
        engine: &mut GeneralizedDnurbs<Self::Geometry>,
        edit: &Edit,
    ) -> Result<String, SessionError>;
    /// Writes the model file (`.json`).
    fn write_json(
        &self,
        engine: &GeneralizedDnurbs<Self::Geometry>,
        path: &Path,
    ) -> Result<(), SessionError>;
    /// The session file form: the kind's settings with the engine state.
    fn save(&self, state: &GeneralizedState) -> Result<serde_json::Value, SessionError>;
}

/// A model over the generalized D-NURBS engine (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct GeneralizedModel<K: GeneralizedKind> {
    kind: K,
    engine: GeneralizedDnurbs<K::Geometry>,
    size: f64,
    revision: u64,
    energy: Energy,
}

impl<K: GeneralizedKind> GeneralizedModel<K> {
    /// A model of `kind` over `engine` (built, not stepped); `size` scales tolerances.
    pub(crate) fn new(kind: K, engine: GeneralizedDnurbs<K::Geometry>, size: f64) -> Self {
        let elastic = engine.elastic_energy().unwrap_or(0.0);
        Self {
            kind,
            engine,
            size,
            revision: 0,
            energy: Energy {
                elastic,
                ..Energy::default()
            },
        }
    }

    /// Puts back a saved engine state (session files).
    pub(crate) fn with_state(mut self, state: SavedState) -> Result<Self, SessionError> {
        self.engine
            .set_state(&GeneralizedState::from(state))
            .map_err(SessionError::kernel)?;
        Ok(self)
    }

    /// The engine (for tests and tools).
    pub fn engine(&self) -> &GeneralizedDnurbs<K::Geometry> {
        &self.engine
    }

    fn set_dt(&mut self, value: f64) -> Result<String, SessionError> {
        self.kind.set_dt(crate::model::positive_dt(value)?);
        Ok(format!("dt = {value}"))
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
    type State = (GeneralizedState, K::State);
    const EDITS_REDRAW: bool = K::EDITS_REDRAW;
    fn take_state(&self) -> Self::State {
        (self.engine.state(), self.kind.take())
    }
    fn put_state(&mut self, s: &Self::State) -> Result<(), SessionError> {
        self.engine.set_state(&s.0).map_err(SessionError::kernel)?;
        self.kind.put(&s.1);
        Ok(())
    }
    fn revision_mut(&mut self) -> &mut u64 {
        &mut self.revision
    }
    fn edit(&mut self, edit: &Edit, _before: &Self::State) -> Result<Done, SessionError> {
        Ok(Done::State(match edit {
            Edit::Set { name, value } if name == "dt" => self.set_dt(*value)?,
            _ => self.kind.apply(&mut self.engine, edit)?,
        }))
    }
    fn apply_inverse(&mut self, _edit: &Edit) -> Result<(), SessionError> {
        // The snapshot holds everything the edits change.
        Ok(())
    }
}

impl<K: GeneralizedKind> Model for GeneralizedModel<K> {
    fn kind(&self) -> ModelKind {
        K::KIND
    }
    fn summary(&self) -> String {
        self.kind.summary(&self.engine)
    }
    crate::model::clock_methods!(self => self.engine.time(), self.kind.dt(), self.engine.steps() as u64);
    fn step(&mut self) -> Result<StepReport, SessionError> {
        self.kind.before_step(&mut self.engine);
        let report = step_implicit(&mut self.engine, self.kind.dt(), &mut self.energy)?;
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
        self.kind.mesh(&self.engine)
    }
    fn display_lines(&self) -> Vec<LineSet> {
        self.kind.display_lines(&self.engine)
    }
    fn pick(&self, ray: &Ray, _tolerance: f64) -> Option<Hit> {
        let mesh = self.display_mesh().ok()?;
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
        let mut v = vec![Param::new(
            "dt",
            self.kind.dt(),
            1e-4,
            0.1,
            "time step of eq 18",
        )];
        v.extend(self.kind.params());
        v
    }
    crate::model::stateful_methods!();
    fn control_points(&self) -> Vec<Vec3> {
        self.kind.control_points(&self.engine)
    }
    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        let ext = extension(path);
        if !K::EXPORTS.contains(&ext.as_str()) {
            return Err(unsupported_export(K::KIND, path, K::EXPORTS));
        }
        match ext.as_str() {
            "json" => self.kind.write_json(&self.engine, path),
            "glb" => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(
                    K::MESH_NAME.to_string(),
                    self.display_mesh()?,
                )],
            )
            .map_err(|e| io(&e)),
            _ => vclay_io::write_mesh(path, &self.display_mesh()?).map_err(|e| io(&e)),
        }
    }
    fn export_formats(&self) -> Vec<&'static str> {
        K::EXPORTS.to_vec()
    }
    fn save(&self) -> Result<serde_json::Value, SessionError> {
        self.kind.save(&self.engine.state())
    }
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        // The undo state is the engine's, rest coordinates included.
        self.engine
            .plastic_flow(fraction, yield_distance)
            .map_err(SessionError::kernel)
    }
}
