//! Commands: every edit of a session is a plain serializable value.
//!
//! A [`Command`] names the model it is addressed to (or the session's first model) and an
//! [`Edit`]. The same values are a scenario's timeline entries (TOML, `action = "rope"`), the
//! session file's command log (JSON) and what the studio and the Python module send. Applying
//! one either succeeds or leaves the session unchanged with an error that names the command
//! and the reason ([`crate::SessionError::Command`]).
//!
//! Points are chosen by position (`near`, `from`, `min`/`max`) or by id (`points`, `face`,
//! `cell`, `index`); positions survive topology edits, ids do not.

use serde::{Deserialize, Serialize};

/// Most data points of one [`Edit::Data`] (each finds its nearest model point every step; 2,000
/// points cost about a second per step on a 16x16 sheet).
pub const MAX_DATA_POINTS: usize = 2_000;
/// Most point moves of one [`Edit::FfdMove`] (eq 12 solves a dense system of 3 rows per move).
pub const MAX_FFD_MOVES: usize = 1_000;

/// A 3-vector as it appears in files.
pub type V3 = [f64; 3];

/// One edit addressed to a model of the session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// The model's name; `None` addresses the session's first model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// The edit.
    #[serde(flatten)]
    pub edit: Edit,
}

impl Command {
    /// A command for the first model.
    pub fn new(edit: Edit) -> Self {
        Self { model: None, edit }
    }
    /// A command for the model named `model`.
    pub fn to(model: &str, edit: Edit) -> Self {
        Self {
            model: Some(model.to_string()),
            edit,
        }
    }
}

/// The edits of the papers' tools, plus the traditional direct edits. Which kinds take which
/// edit is listed in `docs/formats.md` (section "Commands"); an edit a kind does not take is a
/// [`crate::SessionError::Command`] naming the kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Edit {
    /// Attach a rope (a spring that only pulls; `subdivision-solids-journal.txt` section 5.4,
    /// `d-nurbs.txt` eq 19) from the model point nearest `from` (or the material point `param`
    /// of a D-NURBS) to a cursor that starts at `from`, optionally moves linearly to `to` by
    /// time `until` or with `velocity`, and is removed at time `release`.
    Rope {
        /// Tool name (default `rope<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Where the rope grabs the model, and the cursor's start.
        from: V3,
        /// D-NURBS: the material point `[u, v]` to attach to instead of the nearest one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        param: Option<[f64; 2]>,
        /// Cursor end position (default: stays at `from`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        to: Option<V3>,
        /// Time the cursor reaches `to` (default: at once).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
        /// Cursor velocity: the cursor is at `from + velocity t` at session time `t` (the
        /// moving spring target of `d-nurbs.txt` Fig 9a). Not with `to`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        velocity: Option<V3>,
        /// Time the rope is removed (default: never).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        release: Option<f64>,
        /// Spring stiffness (solids default 50; D-NURBS: the preset's `k`, else 50).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        stiffness: Option<f64>,
        /// Rope length: no force below it (solids; default 0).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        length: Option<f64>,
        /// D-NURBS: Gaussian kernel width in parameter units instead of the delta of eq 19.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        kernel: Option<f64>,
        /// Time the cursor starts moving towards `to` (default: when the edit applies; a
        /// scenario sets it to the entry's `at`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        start: Option<f64>,
    },
    /// Move the cursor of the rope `name` (an interactive drag).
    MoveRope {
        /// The rope.
        name: String,
        /// New cursor position.
        to: V3,
    },
    /// A constant force on the model point nearest `near` (or the material point `param`).
    Force {
        /// Tool name (default `force<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Where.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<V3>,
        /// D-NURBS material point.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        param: Option<[f64; 2]>,
        /// The force.
        force: V3,
        /// Time it is removed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
    },
    /// A total force shared by the data points within `radius` of `center` (solids).
    RegionForce {
        /// Tool name (default `region<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Centre.
        center: V3,
        /// Radius.
        radius: f64,
        /// Total force.
        force: V3,
        /// Time it is removed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
        /// How the force's share falls off from the centre (`vclay_solids::Falloff`:
        /// `constant`, the default and the paper's equal shares, `smooth`, `linear`, `sphere`,
        /// `sharp`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        falloff: Option<String>,
    },
    /// Gravity `g` (an acceleration). Giving an existing name changes its strength.
    Gravity {
        /// Tool name (default `gravity<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Acceleration.
        g: V3,
        /// Time it is removed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
    },
    /// Pressure on the boundary surface (negative deflates). Giving an existing name changes
    /// its strength.
    Inflate {
        /// Tool name (default `inflate<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Pressure.
        pressure: f64,
        /// Time it is removed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
    },
    /// Data points, each pulling the nearest point of a D-NURBS with a spring (fitting,
    /// `d-nurbs.txt` section 7.3).
    Data {
        /// Tool name (default `data<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// The points.
        points: Vec<V3>,
        /// Spring stiffness (default: the preset's `k`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        stiffness: Option<f64>,
    },
    /// Remove the tool (rope, force, gravity, ...) or constraint named `name`.
    Release {
        /// The tool.
        name: String,
    },
    /// Fix control points (see [`Selection`]).
    Fix(Selection),
    /// Free control points (the same selections as [`Edit::Fix`]).
    Free(Selection),
    /// The smooth brush: one umbrella (Laplacian) step of the **rest** shape at the control
    /// points within `radius` of `near` (current positions; fixed points stay), and the clay
    /// settles towards it by its own dynamics (`crate::smooth`).
    Smooth {
        /// Brush centre.
        near: V3,
        /// Brush radius (0: the one control point nearest `near`).
        radius: f64,
        /// Share of the step towards the neighbours' mean, in `(0, 1]` (default 0.5).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        strength: Option<f64>,
    },
    /// Change the material: solids per control cell (`cells`, or those whose centroid is in
    /// `min`/`max`, else all), D-NURBS everywhere.
    Material {
        /// Control cells (solids).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cells: Option<Vec<usize>>,
        /// Box corner (solids: cells whose centroid is inside).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        min: Option<V3>,
        /// Box corner.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max: Option<V3>,
        /// Solids: mass per volume.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        density: Option<f64>,
        /// Solids: damping per volume.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        damping: Option<f64>,
        /// Solids: edge spring modulus.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        edge_stiffness: Option<f64>,
        /// Solids: virtual spring modulus.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        virtual_stiffness: Option<f64>,
        /// Solids: stiffness scale per axis.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        anisotropy: Option<V3>,
        /// D-NURBS: mass density `mu`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu: Option<f64>,
        /// D-NURBS: damping density `gamma`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        gamma: Option<f64>,
        /// D-NURBS: tension `alpha` (all directions).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        alpha: Option<f64>,
        /// D-NURBS: rigidity `beta` (all pairs).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        beta: Option<f64>,
    },
    /// Extrude a boundary face of the control lattice into a new cell (subdivision solids,
    /// journal section 5.4): by id or nearest centroid.
    Extrude {
        /// Face id.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        face: Option<usize>,
        /// The boundary face whose centroid is nearest.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<V3>,
        /// Extrusion length relative to the face size (default 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        factor: Option<f64>,
    },
    /// Delete a control cell ("trimming", subdivision solids): by id or nearest centroid.
    #[serde(alias = "trim")]
    DeleteCell {
        /// Cell id.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cell: Option<usize>,
        /// The cell whose centroid is nearest.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<V3>,
    },
    /// Choose which face of a CAD part is sculpted (`cad-part`, issue 30): the face sculpted
    /// until now keeps its shape in the part, and the chosen face becomes the D-NURBS surface
    /// that the tools act on; by index in the part's shell, or the face nearest a point (a
    /// click on the part).
    SculptFace {
        /// Face index in the sculpted shell.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        face: Option<usize>,
        /// The face nearest this point.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<V3>,
    },
    /// The current shape becomes the rest shape.
    PlasticReset,
    /// Zero all velocities.
    Stop,
    /// Move control point `index` to `to` directly (the traditional way).
    MovePoint {
        /// Control point (FFD: lattice control point; PDE: not available).
        index: usize,
        /// New position.
        to: V3,
    },
    /// Set the weight of control point `index` (NURBS models).
    SetWeight {
        /// Control point.
        index: usize,
        /// New weight (> 0).
        weight: f64,
    },
    /// FFD direct manipulation (`ffd-direct-manipulation.txt` eqs 7 and 12): move the
    /// embedded points `from` (positions in the current deformed object) exactly to `to`.
    FfdMove {
        /// Point moves.
        moves: Vec<PointMove>,
    },
    /// Set a named constant of a PDE surface's boundary functions (`dynamic-pde-surfaces.txt`
    /// eq 3), or the time `t`.
    PdeSet {
        /// The constant's name as the spec lists it, or `t`.
        name: String,
        /// Its new value.
        value: f64,
    },
    /// Add (or, with the name of one added before, replace) a local deformation of a PDE
    /// surface (`dynamic-pde-surfaces.txt` section VI-A, eqs 30-32): over `u` x `v` of patch
    /// `patch` the surface moves by `w(u, v) p`, with `w` the G0 bump of eq 31 (peak 1/16 at
    /// the centre) or its square for G1 (eq 32, peak 1/256). Removed by [`Edit::Release`].
    PdeLocal {
        /// Name of the deformation.
        name: String,
        /// Patch index.
        #[serde(default)]
        patch: usize,
        /// `[u1, u2]` inside `[0, 1]`.
        u: [f64; 2],
        /// `[v1, v2]`, clipped to the patch's v range.
        v: [f64; 2],
        /// `"G0"` or `"G1"` (default G1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        continuity: Option<String>,
        /// The amplitude `p = (p1, p2, p3)`.
        p: V3,
    },
    /// Set a named model or simulation parameter (see `Model::params`).
    Set {
        /// Parameter name.
        name: String,
        /// New value.
        value: f64,
    },
    /// Change the integrator and/or the time step.
    Integrator {
        /// Integrator name (solids: `symplectic`, `explicit`, `implicit`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        integrator: Option<String>,
        /// Time step.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        dt: Option<f64>,
    },
    /// Add a geometric constraint (D-NURBS, `d-nurbs.txt` section 6.2): `kind = "point"` keeps
    /// the material point `param` at `target`; `kind = "normal"` keeps the surface normal at
    /// `param` along `normal`. Removed by [`Edit::Release`] with its name.
    Constraint {
        /// Constraint name (default `constraint<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// `point` or `normal`.
        #[serde(rename = "type")]
        kind: String,
        /// Material point.
        param: [f64; 2],
        /// Point constraint: the position.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        target: Option<V3>,
        /// Normal constraint: the direction.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<V3>,
    },
    /// Repulsion from a point in space (D-NURBS curves and surfaces, `d-nurbs.txt` section 6):
    /// force density `strength d / (|d|^2 + core^2)^(3/2)` per unit length or area, `d` the
    /// model point minus `center`. Giving an existing name changes the tool.
    Repel {
        /// Tool name (default `repel<N>`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// The repelling point.
        center: V3,
        /// Strength (negative attracts).
        strength: f64,
        /// Core radius that softens the force near `center` (> 0; default 0.1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        core: Option<f64>,
        /// Time it is removed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<f64>,
    },
}

/// Why an [`Edit`] is invalid: the key at fault and the message (which names it).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}")]
pub struct EditError {
    /// The key at fault (`action` where no one key is).
    pub key: &'static str,
    /// What is wrong.
    pub what: String,
}

impl EditError {
    /// An error at `key`.
    pub fn new(key: &'static str, what: impl Into<String>) -> Self {
        Self {
            key,
            what: what.into(),
        }
    }
}

/// Default core radius of [`Edit::Repel`].
pub const DEFAULT_REPULSION_CORE: f64 = 0.1;

/// Which control points an [`Edit::Fix`] or [`Edit::Free`] names, exactly one way: by id
/// (`points`); by **rest** position in a box (`min` and `max`, so a scenario's box names the same
/// points whatever has moved); or by **current** position, what a person points at: the point
/// nearest `near`, or with `radius` every point within `radius` of `near` (a brush).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Selection {
    /// Control point ids.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<usize>>,
    /// Box corner (rest positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<V3>,
    /// Box corner (rest positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<V3>,
    /// The control point nearest this position (current positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<V3>,
    /// With `near`: every control point within this distance of it (current positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
}

impl Selection {
    /// The control points `ids`.
    pub fn ids(ids: Vec<usize>) -> Self {
        Self {
            points: Some(ids),
            ..Self::default()
        }
    }
    /// The control point nearest `x` (current positions).
    pub fn nearest(x: V3) -> Self {
        Self {
            near: Some(x),
            ..Self::default()
        }
    }
    /// Every control point within `radius` of `x` (current positions): a brush.
    pub fn brush(x: V3, radius: f64) -> Self {
        Self {
            near: Some(x),
            radius: Some(radius),
            ..Self::default()
        }
    }
    /// The control points whose rest positions lie in the box `min`..`max`.
    pub fn rest_box(min: V3, max: V3) -> Self {
        Self {
            min: Some(min),
            max: Some(max),
            ..Self::default()
        }
    }

    /// Checks that exactly one way is given, with finite numbers.
    pub fn validate(&self) -> Result<(), EditError> {
        opt3("min", &self.min)?;
        opt3("max", &self.max)?;
        opt3("near", &self.near)?;
        let n = self.points.is_some() as u8
            + (self.min.is_some() || self.max.is_some()) as u8
            + self.near.is_some() as u8;
        if n != 1 {
            return Err(EditError::new(
                "points",
                "give exactly one of `points`, `min` and `max`, or `near`",
            ));
        }
        if self.min.is_some() != self.max.is_some() {
            return Err(EditError::new("min", "`min` and `max` go together"));
        }
        if self.radius.is_some() && self.near.is_none() {
            return Err(EditError::new("radius", "`radius` goes with `near`"));
        }
        pos("radius", self.radius, true)
    }
}

/// One point move of [`Edit::FfdMove`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMove {
    /// The point (in the current deformed object).
    pub from: V3,
    /// Where it goes.
    pub to: V3,
}

impl Edit {
    /// The edit's name as files spell its `action`.
    pub fn action(&self) -> &'static str {
        match self {
            Edit::Rope { .. } => "rope",
            Edit::MoveRope { .. } => "move-rope",
            Edit::Force { .. } => "force",
            Edit::RegionForce { .. } => "region-force",
            Edit::Gravity { .. } => "gravity",
            Edit::Inflate { .. } => "inflate",
            Edit::Data { .. } => "data",
            Edit::Release { .. } => "release",
            Edit::Fix(_) => "fix",
            Edit::Smooth { .. } => "smooth",
            Edit::Free(_) => "free",
            Edit::Material { .. } => "material",
            Edit::Extrude { .. } => "extrude",
            Edit::DeleteCell { .. } => "delete-cell",
            Edit::SculptFace { .. } => "sculpt-face",
            Edit::PlasticReset => "plastic-reset",
            Edit::Stop => "stop",
            Edit::MovePoint { .. } => "move-point",
            Edit::SetWeight { .. } => "set-weight",
            Edit::FfdMove { .. } => "ffd-move",
            Edit::PdeSet { .. } => "pde-set",
            Edit::PdeLocal { .. } => "pde-local",
            Edit::Set { .. } => "set",
            Edit::Integrator { .. } => "integrator",
            Edit::Constraint { .. } => "constraint",
            Edit::Repel { .. } => "repel",
        }
    }

    /// Checks what can be checked without a model: finite numbers, positive stiffnesses and
    /// radii, `until`/`release` not before `at`, exclusive keys. `at` is the time the edit is
    /// scheduled for (0 for an immediate edit).
    pub fn validate(&self, at: f64) -> Result<(), EditError> {
        match self {
            Edit::Rope { .. }
            | Edit::MoveRope { .. }
            | Edit::Force { .. }
            | Edit::RegionForce { .. }
            | Edit::Gravity { .. }
            | Edit::Inflate { .. }
            | Edit::Data { .. }
            | Edit::Release { .. }
            | Edit::PlasticReset
            | Edit::Stop => self.validate_tool(at),
            Edit::Fix(_)
            | Edit::Free(_)
            | Edit::Smooth { .. }
            | Edit::Material { .. }
            | Edit::Extrude { .. }
            | Edit::DeleteCell { .. }
            | Edit::SculptFace { .. }
            | Edit::MovePoint { .. }
            | Edit::SetWeight { .. }
            | Edit::FfdMove { .. } => self.validate_net(),
            _ => self.validate_other(at),
        }
    }

    /// [`Edit::validate`] for `Rope`, `MoveRope`, `Force`, `RegionForce`, `Gravity`, `Inflate`, `Data`, `Release`, `PlasticReset`, `Stop`.
    fn validate_tool(&self, at: f64) -> Result<(), EditError> {
        match self {
            Edit::Rope { .. } => {
                let (r, _, release) = RopeRequest::of(self).expect("a rope");
                fin("from", &r.from)?;
                opt3("to", &r.to)?;
                opt3("velocity", &r.velocity)?;
                if let Some(p) = &r.param {
                    fin("param", p)?;
                }
                if r.to.is_some() && r.velocity.is_some() {
                    return Err(EditError::new(
                        "to",
                        "`to` and `velocity` exclude each other",
                    ));
                }
                if r.until.is_some() && r.to.is_none() {
                    return Err(EditError::new("until", "`until` needs `to`"));
                }
                after("until", r.until, at)?;
                after("release", release, at)?;
                pos("stiffness", r.stiffness, false)?;
                pos("length", r.length, true)?;
                pos("kernel", r.kernel, false)?;
            }
            Edit::MoveRope { to, .. } => fin("to", to)?,
            Edit::Force {
                near,
                param,
                force,
                until,
                ..
            } => {
                fin("force", force)?;
                opt3("near", near)?;
                one_of(("near", near.is_some()), ("param", param.is_some()))?;
                after("until", *until, at)?;
            }
            Edit::RegionForce {
                center,
                radius,
                force,
                until,
                falloff,
                ..
            } => {
                fin("center", center)?;
                fin("force", force)?;
                pos("radius", Some(*radius), true)?;
                after("until", *until, at)?;
                if let Some(f) = falloff
                    && vclay_solids::Falloff::from_name(f).is_none()
                {
                    return Err(EditError::new(
                        "falloff",
                        format!(
                            "`falloff`: unknown \"{f}\"; expected one of {}",
                            vclay_solids::Falloff::ALL.map(|f| f.name()).join(", ")
                        ),
                    ));
                }
            }
            Edit::Gravity { g, until, .. } => {
                fin("g", g)?;
                after("until", *until, at)?;
            }
            Edit::Inflate {
                pressure, until, ..
            } => {
                fin("pressure", &[*pressure])?;
                after("until", *until, at)?;
            }
            Edit::Data {
                points, stiffness, ..
            } => {
                let why = " (each is matched to the nearest model point every step)";
                count("points", points.len(), MAX_DATA_POINTS, "data points", why)?;
                for p in points {
                    fin("points", p)?;
                }
                pos("stiffness", *stiffness, false)?;
            }
            Edit::Release { .. } | Edit::PlasticReset | Edit::Stop => {}
            _ => {}
        }
        Ok(())
    }

    /// [`Edit::validate`] for `Fix`, `Free`, `Material`, `Extrude`, `DeleteCell`, `SculptFace`, `MovePoint`, `SetWeight`, `FfdMove`.
    fn validate_net(&self) -> Result<(), EditError> {
        match self {
            Edit::Fix(sel) | Edit::Free(sel) => sel.validate()?,
            Edit::Smooth {
                near,
                radius,
                strength,
            } => {
                fin("near", near)?;
                pos("radius", Some(*radius), true)?;
                if let Some(s) = strength
                    && !(*s > 0.0 && *s <= 1.0)
                {
                    return Err(EditError::new(
                        "strength",
                        format!("`strength` = {s}: must be in (0, 1]"),
                    ));
                }
            }
            Edit::Material { .. } => MaterialRequest::of(self).expect("a material").validate()?,
            Edit::Extrude { face, near, factor } => {
                opt3("near", near)?;
                one_of(("face", face.is_some()), ("near", near.is_some()))?;
                pos("factor", *factor, false)?;
            }
            Edit::DeleteCell { cell, near } => {
                opt3("near", near)?;
                one_of(("cell", cell.is_some()), ("near", near.is_some()))?;
            }
            Edit::SculptFace { face, near } => {
                opt3("near", near)?;
                one_of(("face", face.is_some()), ("near", near.is_some()))?;
            }
            Edit::MovePoint { to, .. } => fin("to", to)?,
            Edit::SetWeight { weight, .. } => pos("weight", Some(*weight), false)?,
            Edit::FfdMove { moves } => {
                count("moves", moves.len(), MAX_FFD_MOVES, "point moves", "")?;
                for m in moves {
                    fin("moves.from", &m.from)?;
                    fin("moves.to", &m.to)?;
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// [`Edit::validate`] for `PdeSet`, `Set`, `PdeLocal`, `Integrator`, `Constraint`, `Repel`.
    fn validate_other(&self, at: f64) -> Result<(), EditError> {
        match self {
            Edit::PdeSet { value, .. } | Edit::Set { value, .. } => fin("value", &[*value])?,
            Edit::PdeLocal {
                name,
                u,
                v,
                continuity,
                p,
                ..
            } => {
                if name.is_empty() {
                    return Err(EditError::new("name", "`name`: must not be empty"));
                }
                fin("u", u)?;
                fin("v", v)?;
                fin("p", p)?;
                if !(0.0 <= u[0] && u[0] < u[1] && u[1] <= 1.0) {
                    return Err(EditError::new(
                        "u",
                        format!("`u`: {u:?} must be an interval inside [0, 1]"),
                    ));
                }
                if v[0] >= v[1] {
                    return Err(EditError::new(
                        "v",
                        format!("`v`: {v:?} must be an increasing interval"),
                    ));
                }
                if let Some(c) = continuity
                    && !matches!(c.as_str(), "G0" | "G1" | "g0" | "g1")
                {
                    return Err(EditError::new(
                        "continuity",
                        format!("`continuity`: \"{c}\" is not \"G0\" or \"G1\""),
                    ));
                }
            }
            Edit::Integrator { integrator, dt } => {
                if integrator.is_none() && dt.is_none() {
                    return Err(EditError::new(
                        "integrator",
                        "give `integrator` and/or `dt`",
                    ));
                }
                pos("dt", *dt, false)?;
            }
            Edit::Constraint {
                kind,
                param,
                target,
                normal,
                ..
            } => {
                fin("param", param)?;
                opt3("target", target)?;
                opt3("normal", normal)?;
                match (kind.as_str(), target, normal) {
                    ("point", Some(_), None) => {}
                    ("normal", None, Some(n)) => {
                        if n.iter().all(|x| *x == 0.0) {
                            return Err(EditError::new("normal", "`normal` must not be zero"));
                        }
                    }
                    ("point", ..) => {
                        return Err(EditError::new(
                            "target",
                            "a point constraint takes `target`",
                        ));
                    }
                    ("normal", ..) => {
                        return Err(EditError::new(
                            "normal",
                            "a normal constraint takes `normal`",
                        ));
                    }
                    (o, ..) => {
                        return Err(EditError::new(
                            "type",
                            format!("`type`: \"{o}\" is not a constraint type (point, normal)"),
                        ));
                    }
                }
            }
            Edit::Repel {
                center,
                strength,
                core,
                until,
                ..
            } => {
                fin("center", center)?;
                fin("strength", &[*strength])?;
                pos("core", *core, false)?;
                after("until", *until, at)?;
            }
            _ => {}
        }
        Ok(())
    }
}

/// Exactly one of two keys given (each with whether it is); the error names the first.
fn one_of(a: (&'static str, bool), b: (&'static str, bool)) -> Result<(), EditError> {
    if a.1 == b.1 {
        return Err(EditError::new(
            a.0,
            format!("give one of `{}` and `{}`", a.0, b.0),
        ));
    }
    Ok(())
}

/// The length `n` of list `key` of `what`: at least one, at most `max` (`why`: the reason
/// for the bound, or nothing).
fn count(key: &'static str, n: usize, max: usize, what: &str, why: &str) -> Result<(), EditError> {
    if n == 0 {
        return Err(EditError::new(key, format!("`{key}`: no {what}")));
    }
    if n > max {
        return Err(EditError::new(
            key,
            format!("`{key}`: {n} {what}; at most {max}{why}"),
        ));
    }
    Ok(())
}

fn fin(key: &'static str, v: &[f64]) -> Result<(), EditError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(EditError::new(key, format!("`{key}`: {x} is not finite"))),
        None => Ok(()),
    }
}
fn pos(key: &'static str, v: Option<f64>, allow_zero: bool) -> Result<(), EditError> {
    match v {
        Some(x) if !(x.is_finite() && (x > 0.0 || (allow_zero && x == 0.0))) => {
            Err(EditError::new(
                key,
                format!(
                    "`{key}`: {x} must be {} and finite",
                    if allow_zero {
                        "non-negative"
                    } else {
                        "positive"
                    }
                ),
            ))
        }
        _ => Ok(()),
    }
}
fn after(key: &'static str, v: Option<f64>, at: f64) -> Result<(), EditError> {
    match v {
        Some(x) if !x.is_finite() || x < at => Err(EditError::new(
            key,
            format!("`{key}`: {x} is before the edit's time {at}"),
        )),
        _ => Ok(()),
    }
}
fn opt3(key: &'static str, v: &Option<V3>) -> Result<(), EditError> {
    v.as_ref().map_or(Ok(()), |v| fin(key, v))
}

/// A rope as the kinds attach it: the keys of [`Edit::Rope`] but its name and release
/// time, which the [`ToolTable`] keeps (see the edit for each key's meaning).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RopeRequest {
    /// Where the rope grabs the model, and the cursor's start.
    pub from: V3,
    /// D-NURBS: the material point to attach to.
    pub param: Option<[f64; 2]>,
    /// Cursor end position.
    pub to: Option<V3>,
    /// Time the cursor starts moving towards `to`.
    pub start: Option<f64>,
    /// Time the cursor reaches `to`.
    pub until: Option<f64>,
    /// Cursor velocity (a moving target).
    pub velocity: Option<V3>,
    /// Spring stiffness.
    pub stiffness: Option<f64>,
    /// Rope length (solids).
    pub length: Option<f64>,
    /// D-NURBS: Gaussian kernel width.
    pub kernel: Option<f64>,
}

impl RopeRequest {
    /// The rope of an [`Edit::Rope`], with its name and release time.
    pub fn of(edit: &Edit) -> Option<(Self, Option<&str>, Option<f64>)> {
        let Edit::Rope {
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
        } = edit
        else {
            return None;
        };
        let rope = Self {
            from: *from,
            param: *param,
            to: *to,
            start: *start,
            until: *until,
            velocity: *velocity,
            stiffness: *stiffness,
            length: *length,
            kernel: *kernel,
        };
        Some((rope, name.as_deref(), *release))
    }
}

/// The keys of an [`Edit::Material`] by what they apply to: the region (solids: `cells`, or a
/// box `min`/`max`), the solid material (the densities and stiffnesses of
/// `subdivision-solids-journal.txt` eq 10) and the uniform D-NURBS densities (`d-nurbs.txt`
/// eqs 16-17); see the edit for each key's meaning.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MaterialRequest {
    /// Control cells (solids).
    pub cells: Option<Vec<usize>>,
    /// Box corners (solids).
    pub min: Option<V3>,
    /// Box corners (solids).
    pub max: Option<V3>,
    /// `density`, `damping`, `edge_stiffness`, `virtual_stiffness` (solids).
    pub solid: [Option<f64>; 4],
    /// Anisotropy factors (solids).
    pub anisotropy: Option<V3>,
    /// `mu`, `gamma`, `alpha`, `beta` (D-NURBS).
    pub dnurbs: [Option<f64>; 4],
}

impl MaterialRequest {
    /// The keys of an [`Edit::Material`].
    pub fn of(edit: &Edit) -> Option<Self> {
        let Edit::Material {
            cells,
            min,
            max,
            density,
            damping,
            edge_stiffness,
            virtual_stiffness,
            anisotropy,
            mu,
            gamma,
            alpha,
            beta,
        } = edit
        else {
            return None;
        };
        Some(Self {
            cells: cells.clone(),
            min: *min,
            max: *max,
            solid: [*density, *damping, *edge_stiffness, *virtual_stiffness],
            anisotropy: *anisotropy,
            dnurbs: [*mu, *gamma, *alpha, *beta],
        })
    }

    /// Whether a solid material key is given.
    pub fn solid_given(&self) -> bool {
        self.solid.iter().any(Option::is_some) || self.anisotropy.is_some()
    }

    /// Whether a D-NURBS material key is given.
    pub fn dnurbs_given(&self) -> bool {
        self.dnurbs.iter().any(Option::is_some)
    }

    /// Whether a region (`cells`, `min`, `max`) is given.
    pub fn region_given(&self) -> bool {
        self.cells.is_some() || self.min.is_some() || self.max.is_some()
    }

    /// [`Edit::validate`] of the keys.
    fn validate(&self) -> Result<(), EditError> {
        opt3("min", &self.min)?;
        opt3("max", &self.max)?;
        if self.min.is_some() != self.max.is_some() {
            return Err(EditError::new("min", "`min` and `max` go together"));
        }
        if self.cells.is_some() && self.min.is_some() {
            return Err(EditError::new(
                "cells",
                "give `cells` or `min` and `max`, not both",
            ));
        }
        let [density, damping, edge_stiffness, virtual_stiffness] = self.solid;
        pos("density", density, false)?;
        pos("damping", damping, true)?;
        pos("edge_stiffness", edge_stiffness, true)?;
        pos("virtual_stiffness", virtual_stiffness, true)?;
        if let Some(a) = &self.anisotropy {
            for &x in a {
                pos("anisotropy", Some(x), false)?;
            }
        }
        for (key, v) in ["mu", "gamma", "alpha", "beta"]
            .into_iter()
            .zip(self.dnurbs)
        {
            pos(key, v, true)?;
        }
        Ok(())
    }
}
