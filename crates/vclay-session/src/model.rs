//! The one interface every model kind implements ([`Model`]) and the values it exchanges with
//! front ends: step reports, display geometry, pick hits, parameters, undo records.

use std::any::Any;
use std::path::Path;

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};

use crate::command::Edit;
use crate::describe::ToolSpec;
use crate::error::SessionError;

/// The kinds of model a session holds (`[model] kind` in scenarios, `kind` in session files).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// D-NURBS curve (`d-nurbs.txt` section 4.2).
    DnurbsCurve,
    /// D-NURBS tensor-product surface (section 4.2).
    DnurbsSurface,
    /// Swung D-NURBS surface (section 4.3, eq 7).
    DnurbsSwung,
    /// MacCracken-Joy subdivision solid (`subdivision-solids-journal.txt` section 4.2).
    SubdivisionSolid,
    /// Trivariate B-spline solid (journal section 4.1).
    BsplineSolid,
    /// FFD lattice with an embedded mesh (`ffd-direct-manipulation.txt`).
    Ffd,
    /// Dynamic PDE surface (`dynamic-pde-surfaces.txt`).
    PdeSurface,
    /// Triangular D-NURBS (`d-nurbs.txt` section 4.4; rounding, section 7.3).
    DnurbsTriangular,
    /// Several tensor-product D-NURBS patches with G0/G1 joins (`d-nurbs.txt` section 6).
    DnurbsPatches,
    /// A CAD part of trimmed faces with one face a D-NURBS surface (issue 30;
    /// `d-nurbs.txt` section 4.2 for the face, `vclay_io::trimmed` for the part).
    CadPart,
}

impl ModelKind {
    /// Every kind, in the order files document them.
    pub const ALL: [ModelKind; 10] = [
        ModelKind::DnurbsCurve,
        ModelKind::DnurbsSurface,
        ModelKind::DnurbsSwung,
        ModelKind::SubdivisionSolid,
        ModelKind::BsplineSolid,
        ModelKind::Ffd,
        ModelKind::PdeSurface,
        ModelKind::DnurbsTriangular,
        ModelKind::DnurbsPatches,
        ModelKind::CadPart,
    ];

    /// The name files use.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::DnurbsCurve => "dnurbs-curve",
            ModelKind::DnurbsSurface => "dnurbs-surface",
            ModelKind::DnurbsSwung => "dnurbs-swung",
            ModelKind::SubdivisionSolid => "subdivision-solid",
            ModelKind::BsplineSolid => "bspline-solid",
            ModelKind::Ffd => "ffd",
            ModelKind::PdeSurface => "pde-surface",
            ModelKind::DnurbsTriangular => "dnurbs-triangular",
            ModelKind::DnurbsPatches => "dnurbs-patches",
            ModelKind::CadPart => "cad-part",
        }
    }

    /// The kind with file name `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// All names, comma separated (for error messages).
    pub fn names() -> String {
        Self::ALL.map(ModelKind::name).join(", ")
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Energies of a model's state (zero where a kind has no such energy).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    /// Kinetic energy.
    pub kinetic: f64,
    /// Elastic (internal) energy.
    pub elastic: f64,
    /// Energy stored in tools (ropes).
    pub tools: f64,
}

impl Energy {
    /// Kinetic plus elastic.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Simulated time after the step.
    pub time: f64,
    /// Energies the kernel reported for the step (solids: at its start; D-NURBS: see
    /// `vclay_dynamics::dnurbs::StepReport`).
    pub energy: Energy,
    /// Iterations of the step's iterative solver (0 if none).
    pub iterations: usize,
    /// Wall time of the step in seconds.
    pub seconds: f64,
}

/// What a set of display lines shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LineRole {
    /// The control net / control lattice edges.
    ControlNet,
    /// The edges of the data (finest) lattice or the FFD lattice.
    LatticeEdges,
    /// Data points (markers).
    DataPoints,
    /// Ropes and springs, from the model point to the cursor.
    Ropes,
    /// Forces, drawn from their point along the force (scaled to the model size).
    Forces,
    /// Fixed control points (markers).
    Fixed,
    /// Constraints (markers at their targets).
    Constraints,
    /// A curve model itself (a polyline).
    Curve,
}

/// Lines and markers for a viewer: `segments` index `points`; a set without segments is a
/// set of markers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LineSet {
    /// What the set shows.
    pub role: Option<LineRole>,
    /// Points.
    pub points: Vec<Vec3>,
    /// Segments as pairs of point indices.
    pub segments: Vec<[u32; 2]>,
}

impl LineSet {
    /// An empty set for `role`.
    pub fn new(role: LineRole) -> Self {
        Self {
            role: Some(role),
            ..Default::default()
        }
    }
    /// Markers at the points of `points` whose index `keep` accepts (fixed control points).
    pub fn markers(role: LineRole, points: &[Vec3], keep: impl Fn(usize) -> bool) -> Self {
        Self {
            role: Some(role),
            points: (0..points.len())
                .filter(|&i| keep(i))
                .map(|i| points[i])
                .collect(),
            segments: Vec::new(),
        }
    }
    /// Adds a segment from `a` to `b`.
    pub fn segment(&mut self, a: Vec3, b: Vec3) {
        let i = self.points.len() as u32;
        self.points.push(a);
        self.points.push(b);
        self.segments.push([i, i + 1]);
    }
    /// The edges of a structured `dims[0] x dims[1] x dims[2]` grid of points (point `(i, j,
    /// k)` at index `(i dims[1] + j) dims[2] + k`): control lattices of B-spline solids and FFD.
    pub fn grid(role: LineRole, points: Vec<Vec3>, dims: [usize; 3]) -> Self {
        let idx = |i: usize, j: usize, k: usize| ((i * dims[1] + j) * dims[2] + k) as u32;
        let mut segments = Vec::new();
        for i in 0..dims[0] {
            for j in 0..dims[1] {
                for k in 0..dims[2] {
                    if i + 1 < dims[0] {
                        segments.push([idx(i, j, k), idx(i + 1, j, k)]);
                    }
                    if j + 1 < dims[1] {
                        segments.push([idx(i, j, k), idx(i, j + 1, k)]);
                    }
                    if k + 1 < dims[2] {
                        segments.push([idx(i, j, k), idx(i, j, k + 1)]);
                    }
                }
            }
        }
        Self {
            role: Some(role),
            points,
            segments,
        }
    }
    /// Adds a polyline through `pts`.
    pub fn polyline(&mut self, pts: &[Vec3]) {
        let i = self.points.len() as u32;
        self.points.extend_from_slice(pts);
        for k in 1..pts.len() as u32 {
            self.segments.push([i + k - 1, i + k]);
        }
    }
}

/// A ray for picking: `origin + s direction`, `s >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin (the eye).
    pub origin: Vec3,
    /// Direction (any length but zero).
    pub direction: Vec3,
}

/// The element of a model that a pick hit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "element", rename_all = "kebab-case")]
pub enum Element {
    /// A point of a surface (D-NURBS: with its parameters `[u, v]`; PDE: `[u, v]` too).
    SurfacePoint {
        /// Parameters.
        param: [f64; 2],
    },
    /// A point of a curve at parameter `u`.
    CurvePoint {
        /// Parameter.
        u: f64,
    },
    /// A control point.
    ControlPoint {
        /// Its index.
        index: usize,
    },
    /// A data point (solids: a point of the finest lattice).
    DataPoint {
        /// Its index.
        index: usize,
    },
    /// A boundary face of the control lattice (subdivision solids), hit through the display
    /// surface; or a face of a CAD part's sculpted shell (`cad-part`).
    Face {
        /// Face id of the control lattice (a CAD part: the face's index in its shell).
        index: usize,
    },
    /// A control cell, hit through the display surface.
    Cell {
        /// Cell id of the control lattice.
        index: usize,
    },
    /// A patch of a multi-patch surface (PDE surfaces: the patch a surface point lies on).
    Patch {
        /// Patch index.
        index: usize,
    },
    /// A vertex of an embedded mesh (FFD).
    MeshVertex {
        /// Its index.
        index: usize,
    },
}

/// The nearest hit of a ray on a model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray (in units of `|direction|`).
    pub distance: f64,
    /// The point hit (on the surface, or the point element itself).
    pub point: Vec3,
    /// What was hit.
    pub element: Element,
    /// For hits through the display surface, the control face and cell under the hit
    /// (subdivision solids) as extra elements.
    pub extra: [Option<Element>; 2],
}

/// A model or simulation parameter that front ends can show and change ([`Edit::Set`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Param {
    /// Name used by [`Edit::Set`].
    pub name: String,
    /// Current value.
    pub value: f64,
    /// Smallest sensible value (a slider's end; values below are rejected where they are
    /// invalid).
    pub min: f64,
    /// Largest sensible value.
    pub max: f64,
    /// What it is.
    pub doc: String,
}

impl Param {
    /// A parameter `name` at `value`, with its range and what it is.
    pub fn new(name: &str, value: f64, min: f64, max: f64, doc: &str) -> Self {
        Self {
            name: name.into(),
            value,
            min,
            max,
            doc: doc.into(),
        }
    }
}

/// An opaque copy of a model's evolving state, taken by [`Model::snapshot`].
pub struct Snapshot(pub Box<dyn Any + Send + Sync>);

impl std::fmt::Debug for Snapshot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Snapshot(..)")
    }
}

impl Snapshot {
    /// Wraps a value.
    pub fn new<T: Any + Send + Sync>(t: T) -> Self {
        Self(Box::new(t))
    }
    /// The value, if it is a `T`.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.downcast_ref()
    }
}

/// What every kind shares for undo: the type of its state snapshot, how to take and put it,
/// and how to apply an inverse edit. [`undo_by_state`] and [`restore_state`] then implement
/// [`Model::undo`] and [`Model::restore`] the same way for every kind.
pub(crate) trait Stateful {
    /// The snapshot of the evolving state.
    type State: Clone + Any + Send + Sync;
    /// Whether an applied edit is a new revision (kinds whose edits change what is drawn);
    /// otherwise only undo and restore are.
    const EDITS_REDRAW: bool = true;
    /// The model's revision counter ([`Model::revision`]).
    fn revision_mut(&mut self) -> &mut u64;
    /// Takes a snapshot.
    fn take_state(&self) -> Self::State;
    /// Puts a snapshot back (bit for bit); the callers count the new revision.
    fn put_state(&mut self, state: &Self::State) -> Result<(), SessionError>;
    /// Applies an edit, or fails leaving the model unchanged (`before` is the state taken
    /// just before, for kinds that put it back after a partial failure); says what it did.
    fn edit(&mut self, edit: &Edit, before: &Self::State) -> Result<Done, SessionError>;
    /// Applies an edit ([`Model::apply`]): the state before it, [`Stateful::edit`], a new
    /// revision (see [`Stateful::EDITS_REDRAW`]), the undo record.
    fn apply_edit(&mut self, edit: &Edit) -> Result<Applied, SessionError> {
        let before = self.take_state();
        let done = self.edit(edit, &before)?;
        if Self::EDITS_REDRAW {
            *self.revision_mut() += 1;
        }
        Ok(done.applied(before))
    }
    /// Whether [`Stateful::apply_inverse`] ignores a failure of the inverse edit: kinds whose
    /// snapshot, put back after it, is the exact state either way (FFD and PDE surfaces: the
    /// inverse can fail where the forward edit did not, e.g. FFD's inversion of `Q` at the
    /// target).
    const INVERSE_MAY_FAIL: bool = false;
    /// Applies the exact inverse edit of an [`Undo::Inverse`] record (before the snapshot is
    /// put back), as any edit.
    fn apply_inverse(&mut self, edit: &Edit) -> Result<(), SessionError> {
        let applied = self.apply_edit(edit);
        if Self::INVERSE_MAY_FAIL {
            Ok(())
        } else {
            applied.map(drop)
        }
    }
}

impl Snapshot {
    /// A copy of the value, or an error naming the mismatch (a record of another kind).
    pub fn take<T: Any + Clone>(&self) -> Result<T, SessionError> {
        self.get::<T>()
            .cloned()
            .ok_or_else(|| SessionError::model("snapshot or undo record of another model kind"))
    }
}

/// [`Model::undo`] for a [`Stateful`] kind: the inverse edit (if any), then the snapshot.
pub(crate) fn undo_by_state<M: Stateful>(model: &mut M, undo: Undo) -> Result<(), SessionError> {
    match undo {
        Undo::State(s) => model.put_state(&s.take::<M::State>()?)?,
        Undo::Inverse { edit, state } => {
            let s = state.take::<M::State>()?;
            model.apply_inverse(&edit)?;
            model.put_state(&s)?;
        }
        Undo::Model(_) => {
            return Err(SessionError::model(
                "a whole-model undo record is the session's to apply",
            ));
        }
    }
    *model.revision_mut() += 1;
    Ok(())
}

/// [`Model::snapshot`] for a [`Stateful`] kind.
pub(crate) fn snapshot_of<M: Stateful>(model: &M) -> Snapshot {
    Snapshot::new(model.take_state())
}

/// [`Model::restore`] for a [`Stateful`] kind.
pub(crate) fn restore_state<M: Stateful>(
    model: &mut M,
    snapshot: &Snapshot,
) -> Result<(), SessionError> {
    model.put_state(&snapshot.take::<M::State>()?)?;
    *model.revision_mut() += 1;
    Ok(())
}

/// The [`Model`] methods every [`Stateful`] kind implements the same way: `apply` by
/// [`Stateful::apply_edit`], `undo` by the inverse
/// edit and the state ([`undo_by_state`]), `snapshot`, `restore`, and `clone_model` (the kind
/// is `Clone`). Used inside `impl Model for Kind`.
macro_rules! stateful_methods {
    () => {
        fn apply(
            &mut self,
            edit: &$crate::Edit,
        ) -> Result<$crate::model::Applied, $crate::SessionError> {
            $crate::model::Stateful::apply_edit(self, edit)
        }
        fn undo(&mut self, undo: $crate::model::Undo) -> Result<(), $crate::SessionError> {
            $crate::model::undo_by_state(self, undo)
        }
        fn snapshot(&self) -> $crate::model::Snapshot {
            $crate::model::snapshot_of(self)
        }
        fn restore(
            &mut self,
            snapshot: &$crate::model::Snapshot,
        ) -> Result<(), $crate::SessionError> {
            $crate::model::restore_state(self, snapshot)
        }
        fn clone_model(&self) -> Box<dyn $crate::model::Model> {
            Box::new(self.clone())
        }
    };
}
pub(crate) use stateful_methods;

/// The clock getters of [`Model`] (`time`, `dt`, `steps`), each the expression given, written
/// with `self`: `clock_methods!(self => self.time, self.dt, self.steps);` inside `impl Model for
/// Kind`.
macro_rules! clock_methods {
    ($s:ident => $time:expr, $dt:expr, $steps:expr) => {
        fn time(&$s) -> f64 {
            $time
        }
        fn dt(&$s) -> f64 {
            $dt
        }
        fn steps(&$s) -> u64 {
            $steps
        }
    };
}
pub(crate) use clock_methods;

/// How to undo an applied edit.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)] // one per history entry; boxing would only add an indirection
pub enum Undo {
    /// Put back a snapshot of the state taken just before the edit.
    State(Snapshot),
    /// Apply an exact inverse edit (FFD moves, fix/free, material), then put back the state
    /// taken just before the edit (time may have passed since).
    Inverse {
        /// The inverse edit.
        edit: Edit,
        /// The state before the edit.
        state: Snapshot,
    },
    /// Replace the whole model by the copy taken before the edit (topology edits).
    Model(Box<dyn Model>),
}

/// A time step given to `set dt`, checked: positive and finite.
pub(crate) fn positive_dt(dt: f64) -> Result<f64, SessionError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(dt)
    } else {
        Err(SessionError::command(
            "",
            "",
            format!("dt = {dt}: must be positive"),
        ))
    }
}

/// The clock of a kind with no dynamics of its own (FFD, PDE surfaces): each step advances
/// the time by `dt`. Part of the kind's undo state and of its session file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Clock {
    /// The time (s).
    pub(crate) time: f64,
    /// The time step (s), positive and finite.
    pub(crate) dt: f64,
    /// The steps taken.
    pub(crate) steps: u64,
}

impl Clock {
    /// A clock at time 0 that steps by `dt`.
    pub(crate) fn new(dt: f64) -> Self {
        Self {
            time: 0.0,
            dt,
            steps: 0,
        }
    }

    /// A saved clock, or `None` unless `time` is finite and `dt` positive and finite.
    pub(crate) fn saved(time: f64, dt: f64, steps: u64) -> Option<Self> {
        (dt > 0.0 && dt.is_finite() && time.is_finite()).then_some(Self { time, dt, steps })
    }

    /// `set dt`: the new time step (positive and finite); returns the old one.
    pub(crate) fn set_dt(&mut self, dt: f64) -> Result<f64, SessionError> {
        Ok(std::mem::replace(&mut self.dt, positive_dt(dt)?))
    }

    /// One step: `work` brings the model to the time `time + dt`, then the clock advances;
    /// the report of a model without energy. Nothing advances when `work` fails.
    pub(crate) fn step(
        &mut self,
        work: impl FnOnce(f64) -> Result<(), SessionError>,
    ) -> Result<StepReport, SessionError> {
        let t0 = std::time::Instant::now();
        let time = self.time + self.dt;
        work(time)?;
        self.time = time;
        self.steps += 1;
        Ok(StepReport {
            time,
            energy: Energy::default(),
            iterations: 0,
            seconds: t0.elapsed().as_secs_f64(),
        })
    }
}

/// What an edit did and how it is undone, before the kind pairs it with the state it took
/// just before the edit: every kind's `apply_edit` ends in one [`Done::applied`].
/// Public because a [`crate::models::generalized::GeneralizedKind`] returns it.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)] // one per applied edit, moved into the undo record at once
pub enum Done {
    /// Undone by putting back the state ([`Undo::State`]); the log's message.
    State(String),
    /// Undone by this exact inverse edit, then the state ([`Undo::Inverse`]).
    Inverse(String, Edit),
    /// Undone by this full copy of the model taken before the edit ([`Undo::Model`]).
    Model(String, Box<dyn Model>),
}

impl Done {
    /// The [`Applied`] record with `before`, the state taken just before the edit.
    pub(crate) fn applied<S: Any + Send + Sync>(self, before: S) -> Applied {
        match self {
            Done::State(message) => Applied::by_state(message, before),
            Done::Inverse(message, inverse) => Applied::by_inverse(message, inverse, before),
            Done::Model(message, copy) => Applied {
                message,
                undo: Undo::Model(copy),
            },
        }
    }
}

/// What applying an edit did.
#[derive(Debug)]
pub struct Applied {
    /// One line for the log ("rope `rope0` attached to data point 2196").
    pub message: String,
    /// How to undo it.
    pub undo: Undo,
}

impl Applied {
    /// An edit undone by putting back `before`, the state taken just before it
    /// ([`Undo::State`]).
    pub(crate) fn by_state<S: Any + Send + Sync>(message: String, before: S) -> Self {
        Self {
            message,
            undo: Undo::State(Snapshot::new(before)),
        }
    }
    /// An edit undone by its exact `inverse`, then `before` ([`Undo::Inverse`]).
    pub(crate) fn by_inverse<S: Any + Send + Sync>(
        message: String,
        inverse: Edit,
        before: S,
    ) -> Self {
        Self {
            message,
            undo: Undo::Inverse {
                edit: inverse,
                state: Snapshot::new(before),
            },
        }
    }
}

/// Export formats, chosen by file extension.
pub const EXPORT_EXTENSIONS: [&str; 9] = [
    "json", "obj", "ply", "stl", "vtu", "ovm", "glb", "step", "igs",
];

/// One model of a session, whatever its kind. Every front end drives models only through
/// this trait (via [`crate::Session`]).
pub trait Model: Send + Sync + std::fmt::Debug {
    /// The kind.
    fn kind(&self) -> ModelKind;
    /// One line about the model (sizes).
    fn summary(&self) -> String;
    /// Simulated time.
    fn time(&self) -> f64;
    /// Time step.
    fn dt(&self) -> f64;
    /// Steps taken.
    fn steps(&self) -> u64;
    /// Advances one time step (after moving scheduled rope cursors and removing expired tools).
    fn step(&mut self) -> Result<StepReport, SessionError>;
    /// Energies of the current state.
    fn energy(&self) -> Energy;
    /// Size of the model (bounding box diagonal of its rest shape): tolerances scale with it.
    fn size(&self) -> f64;
    /// A counter that grows whenever what [`Model::display_mesh`] or
    /// [`Model::display_lines`] return changes (a viewer re-uploads only then).
    fn revision(&self) -> u64;
    /// Triangles with normals for shading (curves: empty).
    fn display_mesh(&self) -> Result<TriMesh, SessionError>;
    /// Control net, lattice edges, data points, ropes, forces, fixed points, constraints.
    fn display_lines(&self) -> Vec<LineSet>;
    /// The nearest element the ray hits within `tolerance` (a distance in model units from the
    /// ray, for points and curves; surfaces are hit exactly).
    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit>;
    /// Material and simulation parameters.
    fn params(&self) -> Vec<Param>;
    /// Applies an edit, or fails leaving the model unchanged.
    fn apply(&mut self, edit: &Edit) -> Result<Applied, SessionError>;
    /// Undoes an edit ([`Undo::State`] and [`Undo::Inverse`]; the session handles
    /// [`Undo::Model`]).
    fn undo(&mut self, undo: Undo) -> Result<(), SessionError>;
    /// A copy of the evolving state.
    fn snapshot(&self) -> Snapshot;
    /// Puts back a snapshot of this model.
    fn restore(&mut self, snapshot: &Snapshot) -> Result<(), SessionError>;
    /// A full copy.
    fn clone_model(&self) -> Box<dyn Model>;
    /// Writes the model to `path` in the format its extension names (one of
    /// [`EXPORT_EXTENSIONS`] that the kind supports); an extension the kind does not write is
    /// an error that names the ones it does.
    fn export(&self, path: &Path) -> Result<(), SessionError>;
    /// Everything needed to rebuild the model exactly (session files; see `docs/formats.md`).
    fn save(&self) -> Result<serde_json::Value, SessionError>;
    /// The control points at the current state (solids and D-NURBS: the generalized
    /// coordinates' positions; FFD: the lattice's control points; empty where a kind has none).
    fn control_points(&self) -> Vec<Vec3> {
        Vec::new()
    }
    /// The sample points the physics acts on (solids: the data points `d = A p`; FFD: the
    /// embedded mesh's vertices; empty where a kind has none).
    fn data_points(&self) -> Vec<Vec3> {
        Vec::new()
    }
    /// The tools (edits) this model takes, as data ([`crate::describe`]): what front ends
    /// build their palettes and help from. Default: the kind's list.
    fn tools(&self) -> Vec<ToolSpec> {
        crate::describe::tools_for(self.kind())
    }
    /// Whether the model takes `edit` (its action is one of [`Model::tools`]); the session
    /// refuses other edits before the model sees them.
    fn accepts(&self, edit: &Edit) -> bool {
        let action = edit.action();
        self.tools().iter().any(|t| t.action == action)
    }
    /// The extensions [`Model::export`] writes (checked when a scenario is read, so a run
    /// does not fail at its end). Default: every one of [`EXPORT_EXTENSIONS`].
    fn export_formats(&self) -> Vec<&'static str> {
        EXPORT_EXTENSIONS.to_vec()
    }
    /// The scalar fields the display mesh can be coloured by (painted material, ...).
    /// Default: none.
    fn display_fields(&self) -> Vec<FieldSpec> {
        Vec::new()
    }
    /// Field `name` (one of [`Model::display_fields`]) at the vertices of
    /// [`Model::display_mesh`], in its vertex order; `None` for a field the model does not have.
    fn display_field(&self, name: &str) -> Option<Vec<f64>> {
        let _ = name;
        None
    }
    /// One step of plastic flow (`vclay_core::plasticity`): rest positions displaced past
    /// `yield_distance` move toward the current shape by `fraction` of the overstress; returns
    /// how many control points yielded. The session calls it after each step of a model whose
    /// [`Session::set_plasticity`](crate::Session::set_plasticity) is set. Models whose undo
    /// snapshots include the rest shape implement it (solids, D-NURBS with dynamic weights).
    /// Default: the kind has no rest shape to flow.
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        let _ = (fraction, yield_distance);
        Err(SessionError::model(format!(
            "a {} model has no plastic flow (no rest shape that follows the clay)",
            self.kind()
        )))
    }
}

/// A scalar field over a model's display mesh ([`Model::display_fields`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FieldSpec {
    /// Name ([`Model::display_field`] takes it).
    pub name: &'static str,
    /// Unit (`""` where none).
    pub unit: &'static str,
    /// One line.
    pub help: &'static str,
}

/// Builds the error for an extension a kind does not export.
pub fn unsupported_export(kind: ModelKind, path: &Path, supported: &[&str]) -> SessionError {
    SessionError::io(
        path,
        format!(
            "a {kind} model cannot be written as .{}; it writes {}",
            path.extension()
                .and_then(|e| e.to_str())
                .unwrap_or("(no extension)"),
            supported
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )
}

/// The lower-case extension of `path`.
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}
