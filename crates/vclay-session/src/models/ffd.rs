//! Free-form deformation in a session: [`FfdModel`] wraps a `vclay_ffd::FfdLattice` (a NURBS
//! volume that is the identity at rest, `ffd-direct-manipulation.txt` section 2, eqs 1-2) and a
//! triangle mesh embedded in it (`vclay_ffd::EmbeddedMesh`, `x = sum P_ijk R_ijk(t_x)`, eq 1).
//!
//! **Edits.** `ffd-move` is the paper's direct manipulation: each `from` (a point of the
//! *current* deformed object) is located in the lattice by inverting `Q(u, v, w) = from` with
//! Newton's method, then the least-norm control-point displacement moving it exactly onto `to`
//! is applied (eq 7 for one point, eq 12 for several; least squares on request). `move-point`
//! moves one lattice control point directly; `set-weight` changes one lattice weight (eq 2);
//! `set` changes `dt` or `least_squares`. FFD has no fixed control points (eqs 7 and 12 move
//! every control point of the support), so `fix` and `free` are errors, as is every edit of the
//! dynamic kinds.
//!
//! **Undo.** Manipulations form a commutative group (section 4): the inverse of
//! `omega(S, rho)` is `omega(S, -rho)`, which is again an `ffd-move` with `from` and `to`
//! swapped (the material point now at `to` goes back to `from`). Every edit is undone by
//! [`Undo::Inverse`]: that inverse edit (or the old control point / weight / parameter), then
//! the snapshot of the lattice control points and weights taken before the edit, which makes
//! the undo exact to the bit (the inverse alone is exact only up to rounding).
//!
//! **Time.** FFD has no dynamics: [`Model::step`] advances a clock by `dt` and changes
//! nothing else; every energy is zero.
//!
//! **Limitations.** Vertices outside the lattice box never move. The Newton inversion of
//! `ffd-move` needs `from` inside the deformed lattice and a lattice that does not fold over
//! at that point. The deformed mesh is always re-evaluated in full after an edit (no
//! incremental update) so that a session file reloads to the same bits.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vclay_core::{Parallelism, TriMesh, Vec3};
use vclay_ffd::{
    DEFAULT_CONTROL_POINTS, DEFAULT_DEGREE, DEFAULT_MARGIN, EmbeddedMesh, FfdError, FfdLattice,
    LatticeSpec, Manipulation, PointConstraint, SolveMode, SolveOptions,
};
use vclay_spline::{MAX_DEGREE, ParametricVolume};

use super::SpecError;
use crate::command::{Edit, PointMove, V3};
use crate::error::SessionError;
use crate::model::{Clock, Done};
use crate::model::{
    Element, Energy, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray, StepReport, extension,
    unsupported_export,
};
use crate::tools::{a3, v3};

/// Default `[simulation] dt` of an FFD model: 1/30 s (one display frame).
pub const DEFAULT_DT: f64 = 1.0 / 30.0;
/// Most lattice control points along one axis.
pub const MAX_CONTROL_PER_AXIS: usize = 64;
/// Most lattice control points in all.
pub const MAX_CONTROL_POINTS: usize = 100_000;
/// Newton iterations of the inversion `Q(t) = from` in `ffd-move`, per starting guess.
pub const INVERSION_ITERATIONS: usize = 50;
/// Accepted distance `|Q(t) - from|` of the inversion, relative to the lattice size.
pub const INVERSION_TOLERANCE: f64 = 1e-10;

const PAR: Parallelism = Parallelism::Auto;

/// An FFD lattice with an embedded mesh (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct FfdModel {
    lattice: FfdLattice,
    embedded: EmbeddedMesh,
    mode: SolveMode,
    clock: Clock,
    source: String,
    revision: u64,
}

/// The evolving state: control points, weights, clock and parameters.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FfdSnap {
    control_points: Vec<Vec3>,
    weights: Vec<f64>,
    mode: SolveMode,
    clock: Clock,
}

fn cmd(reason: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", reason)
}

fn mode_name(m: SolveMode) -> &'static str {
    match m {
        SolveMode::Exact => "exact",
        SolveMode::LeastSquares => "least-squares",
    }
}

fn parse_mode(s: &str) -> Option<SolveMode> {
    match s {
        "exact" => Some(SolveMode::Exact),
        "least-squares" | "least_squares" => Some(SolveMode::LeastSquares),
        _ => None,
    }
}

impl FfdModel {
    /// Embeds `mesh` (its positions are the rest positions) in `lattice` (in any state).
    pub fn new(lattice: FfdLattice, mesh: TriMesh, source: &str) -> Self {
        let mesh = TriMesh {
            normals: Vec::new(),
            ..mesh
        };
        let embedded = EmbeddedMesh::new(&lattice, mesh, PAR);
        Self {
            lattice,
            embedded,
            mode: SolveMode::Exact,
            clock: Clock::new(DEFAULT_DT),
            source: source.to_string(),
            revision: 1,
        }
    }

    /// The lattice.
    pub fn lattice(&self) -> &FfdLattice {
        &self.lattice
    }

    /// The deformed mesh (with normals).
    pub fn mesh(&self) -> &TriMesh {
        self.embedded.mesh()
    }

    /// The rest positions of the embedded mesh.
    pub fn rest_positions(&self) -> &[Vec3] {
        self.embedded.rest_positions()
    }

    /// An error unless lattice control point `index` exists.
    fn check_index(&self, index: usize) -> Result<(), SessionError> {
        let n = self.lattice.control_point_count();
        if index >= n {
            return Err(cmd(format!(
                "lattice control point {index} does not exist (there are {n})"
            )));
        }
        Ok(())
    }

    /// Replaces control points and weights (weights first, as [`FfdModel::load`] does) and
    /// re-evaluates the mesh in full.
    fn set_lattice(&mut self, points: Vec<Vec3>, weights: Vec<f64>) -> Result<(), SessionError> {
        if self.lattice.weights() != weights.as_slice() {
            self.lattice
                .set_weights(weights)
                .map_err(SessionError::kernel)?;
        }
        self.lattice
            .set_control_points(points)
            .map_err(SessionError::kernel)?;
        self.embedded.deform(&self.lattice, PAR);
        Ok(())
    }

    /// Parameters `t` of the lattice point now at `x`: Newton's method on `Q(t) = x`
    /// (`Q` of eq 1, Jacobian from the NURBS volume), started from the linear rest map of `x`
    /// (section 2) and from the parameters of the deformed mesh vertex nearest `x`.
    fn locate(&self, x: &Vec3) -> Result<[f64; 3], SessionError> {
        let tol = INVERSION_TOLERANCE * self.lattice.size();
        let mut starts: Vec<[f64; 3]> = Vec::new();
        let (lo, hi) = self.lattice.bounds();
        starts.push(std::array::from_fn(|a| {
            ((x[a] - lo[a]) / (hi[a] - lo[a])).clamp(0.0, 1.0)
        }));
        let mesh = self.embedded.mesh();
        if let Some(v) = (0..mesh.positions.len())
            .filter(|&v| self.embedded.is_embedded(v))
            .min_by(|&a, &b| {
                (mesh.positions[a] - x)
                    .norm_squared()
                    .total_cmp(&(mesh.positions[b] - x).norm_squared())
            })
            && let Some(t) = self.embedded.parameters(v)
        {
            starts.push(t);
        }
        starts.push([0.5; 3]);
        let vol = self.lattice.volume();
        let mut best = f64::INFINITY;
        for start in starts {
            let mut t = start;
            for _ in 0..INVERSION_ITERATIONS {
                let Ok(q) = self.lattice.point_at(t) else {
                    break;
                };
                let r = q - x;
                let d = r.norm();
                best = best.min(d);
                if d <= tol {
                    return Ok(t);
                }
                let Ok(j) = vol.jacobian_matrix(t[0], t[1], t[2]) else {
                    break;
                };
                let Some(step) = j.lu().solve(&r) else {
                    break;
                };
                if !step.iter().all(|s| s.is_finite()) {
                    break;
                }
                t = std::array::from_fn(|a| (t[a] - step[a]).clamp(0.0, 1.0));
            }
        }
        Err(cmd(format!(
            "the point ({}, {}, {}) is not inside the deformed lattice (nearest lattice point \
             found {best:.3e} away); give a point of the object",
            x.x, x.y, x.z
        )))
    }

    fn ffd_move(&mut self, moves: &[PointMove]) -> Result<String, SessionError> {
        let mut constraints = Vec::with_capacity(moves.len());
        for (k, m) in moves.iter().enumerate() {
            let t = self
                .locate(&v3(m.from))
                .map_err(|e| cmd(format!("move {k}: {}", reason(e))))?;
            constraints.push(PointConstraint::new(t, v3(m.to)));
        }
        let manipulation = if constraints.len() == 1 {
            Manipulation::single(&self.lattice, &constraints[0])
        } else {
            let options = SolveOptions {
                mode: self.mode,
                ..SolveOptions::default()
            };
            Manipulation::multi(&self.lattice, &constraints, &options)
        }
        .map_err(|e| match e {
            FfdError::ConflictingConstraints { .. } => cmd(format!(
                "{e} (move k is moves[k]; `set least_squares = 1` meets them as closely as \
                 possible)"
            )),
            e => cmd(e),
        })?;
        self.lattice
            .try_apply(&manipulation)
            .map_err(SessionError::command_from)?;
        self.embedded.deform(&self.lattice, PAR);
        Ok(format!(
            "{} point{} moved by direct manipulation (eq {}): {} control points moved",
            moves.len(),
            if moves.len() == 1 { "" } else { "s" },
            if moves.len() == 1 { 7 } else { 12 },
            manipulation.len()
        ))
    }

    fn param_names(&self) -> String {
        self.params()
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Builds a model from a scenario's `[model]` and `[simulation]` tables (see
    /// `docs/formats.md`, kind `ffd`).
    pub fn from_keys(spec: &FfdSpec, base: &Path) -> Result<Self, SpecError> {
        let m = &spec.model;
        let err = |key: &str, what: String| SpecError::new("model", key, what);
        let dt = spec.simulation.dt_or(DEFAULT_DT)?;
        let degree = m.degree.map_or([DEFAULT_DEGREE; 3], OneOrThree::axes);
        let control = m
            .control
            .map_or([DEFAULT_CONTROL_POINTS; 3], OneOrThree::axes);
        for a in 0..3 {
            if control[a] > MAX_CONTROL_PER_AXIS {
                return Err(err(
                    "control",
                    format!(
                        "{} control points along axis {a}; at most {MAX_CONTROL_PER_AXIS}",
                        control[a]
                    ),
                ));
            }
            if degree[a] < 1 || degree[a] > MAX_DEGREE {
                return Err(err(
                    "degree",
                    format!("{} along axis {a}; expected 1 to {MAX_DEGREE}", degree[a]),
                ));
            }
            if control[a] < degree[a] + 1 {
                return Err(err(
                    "control",
                    format!(
                        "{} control points along axis {a}; degree {} needs at least {}",
                        control[a],
                        degree[a],
                        degree[a] + 1
                    ),
                ));
            }
        }
        let total: usize = control.iter().product();
        if total > MAX_CONTROL_POINTS {
            return Err(err(
                "control",
                format!("{control:?} makes {total} control points; at most {MAX_CONTROL_POINTS}"),
            ));
        }
        let mode = match &m.mode {
            None => SolveMode::Exact,
            Some(s) => parse_mode(s).ok_or_else(|| {
                err(
                    "mode",
                    format!("unknown mode \"{s}\"; expected \"exact\" or \"least-squares\""),
                )
            })?,
        };
        let (mesh, source) = match (&m.mesh, &m.primitive) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "mesh",
                    "give either `mesh` or `primitive`, not both".into(),
                ));
            }
            (Some(f), None) => {
                let path = if f.is_absolute() {
                    f.clone()
                } else {
                    base.join(f)
                };
                (read_any_mesh(&path).map_err(|e| err("mesh", e))?, {
                    f.display().to_string()
                })
            }
            (None, p) => {
                let name = p.as_deref().unwrap_or("bottle");
                (
                    primitive(name).ok_or_else(|| {
                        err(
                            "primitive",
                            format!(
                                "unknown primitive \"{name}\"; expected {}",
                                PRIMITIVES.join(", ")
                            ),
                        )
                    })?,
                    format!("primitive {name}"),
                )
            }
        };
        let lspec = LatticeSpec {
            degree,
            control_points: control,
        };
        let lattice = match (m.min, m.max) {
            (Some(lo), Some(hi)) => {
                if m.margin.is_some() {
                    return Err(err(
                        "margin",
                        "grows the mesh's bounding box; it does not apply with `min` and `max`"
                            .into(),
                    ));
                }
                FfdLattice::new(lspec, v3(lo), v3(hi)).map_err(|e| err("max", e.to_string()))?
            }
            (None, None) => {
                let margin = m.margin.unwrap_or(DEFAULT_MARGIN);
                FfdLattice::enclosing(&mesh.positions, lspec, margin).map_err(|e| match e {
                    FfdError::InvalidMargin { .. } => err("margin", e.to_string()),
                    e => err("mesh", e.to_string()),
                })?
            }
            _ => return Err(err("min", "`min` and `max` go together".into())),
        };
        let mut model = Self::new(lattice, mesh, &source);
        model.mode = mode;
        model.clock.dt = dt;
        Ok(model)
    }

    /// Rebuilds a model saved by [`Model::save`].
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let s: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        let l = &s.lattice;
        let total = l
            .control
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n));
        if l.control.iter().any(|&n| n > MAX_CONTROL_PER_AXIS)
            || total.is_none_or(|t| t > MAX_CONTROL_POINTS)
            || l.degree.iter().any(|&d| d > MAX_DEGREE)
        {
            return Err(SessionError::model(format!(
                "lattice {:?} of degree {:?} is too large",
                l.control, l.degree
            )));
        }
        let mut lattice = FfdLattice::new(
            LatticeSpec {
                degree: l.degree,
                control_points: l.control,
            },
            v3(l.min),
            v3(l.max),
        )
        .map_err(SessionError::kernel)?;
        for a in 0..3 {
            if lattice.knots()[a].as_slice() != l.knots[a].as_slice() {
                return Err(SessionError::model(format!(
                    "knot vector {a} is not the clamped uniform one of the lattice"
                )));
            }
        }
        let n = lattice.control_point_count();
        if s.control_points.len() != n || s.weights.len() != n {
            return Err(SessionError::model(format!(
                "{} control points and {} weights for a lattice of {n}",
                s.control_points.len(),
                s.weights.len()
            )));
        }
        if s.weights.iter().any(|&w| w != 1.0) {
            lattice
                .set_weights(s.weights.clone())
                .map_err(SessionError::kernel)?;
        }
        lattice
            .set_control_points(s.control_points.iter().map(|p| v3(*p)).collect())
            .map_err(SessionError::kernel)?;
        let mesh = TriMesh {
            positions: s.mesh.positions.iter().map(|p| v3(*p)).collect(),
            normals: Vec::new(),
            triangles: s.mesh.triangles.clone(),
        };
        mesh.validate().map_err(SessionError::kernel)?;
        let mode = parse_mode(&s.mode)
            .ok_or_else(|| SessionError::model(format!("unknown mode \"{}\"", s.mode)))?;
        let clock = Clock::saved(s.time, s.dt, s.steps).ok_or_else(|| {
            SessionError::model(format!(
                "dt = {} and time = {} must be finite, dt positive",
                s.dt, s.time
            ))
        })?;
        let mut model = Self::new(lattice, mesh, &s.source);
        model.mode = mode;
        model.clock = clock;
        Ok(model)
    }

    fn lattice_edges(&self) -> LineSet {
        LineSet::grid(
            LineRole::LatticeEdges,
            self.lattice.control_points().to_vec(),
            self.lattice.dims(),
        )
    }
}

/// The reason of a command error (its message without the command and model).
fn reason(e: SessionError) -> String {
    match e {
        SessionError::Command { reason, .. } => reason,
        SessionError::Model { what, .. } => what,
        e => e.to_string(),
    }
}

impl crate::model::Stateful for FfdModel {
    type State = FfdSnap;
    const INVERSE_MAY_FAIL: bool = true;
    fn take_state(&self) -> FfdSnap {
        FfdSnap {
            control_points: self.lattice.control_points().to_vec(),
            weights: self.lattice.weights().to_vec(),
            mode: self.mode,
            clock: self.clock,
        }
    }
    fn put_state(&mut self, s: &FfdSnap) -> Result<(), SessionError> {
        self.set_lattice(s.control_points.clone(), s.weights.clone())?;
        self.mode = s.mode;
        self.clock = s.clock;
        Ok(())
    }
    fn revision_mut(&mut self) -> &mut u64 {
        &mut self.revision
    }
    fn edit(&mut self, edit: &Edit, before: &FfdSnap) -> Result<Done, SessionError> {
        let (message, inverse) = match edit {
            Edit::FfdMove { moves } => {
                let message = self.ffd_move(moves)?;
                let inverse = Edit::FfdMove {
                    moves: moves
                        .iter()
                        .map(|m| PointMove {
                            from: m.to,
                            to: m.from,
                        })
                        .collect(),
                };
                (message, inverse)
            }
            Edit::MovePoint { index, to } => {
                self.check_index(*index)?;
                let old = self.lattice.control_points()[*index];
                let mut pts = self.lattice.control_points().to_vec();
                pts[*index] = v3(*to);
                let w = self.lattice.weights().to_vec();
                self.set_lattice(pts, w).map_err(|e| cmd(reason(e)))?;
                (
                    format!("moved lattice control point {index} to {to:?}"),
                    Edit::MovePoint {
                        index: *index,
                        to: a3(&old),
                    },
                )
            }
            Edit::SetWeight { index, weight } => {
                self.check_index(*index)?;
                let old = self.lattice.weights()[*index];
                let mut w = self.lattice.weights().to_vec();
                w[*index] = *weight;
                let pts = self.lattice.control_points().to_vec();
                if let Err(e) = self.set_lattice(pts, w) {
                    self.put_state(before)?;
                    return Err(cmd(reason(e)));
                }
                (
                    format!("weight of lattice control point {index} = {weight}"),
                    Edit::SetWeight {
                        index: *index,
                        weight: old,
                    },
                )
            }
            Edit::Set { name, value } => {
                let old = match name.as_str() {
                    "dt" => self.clock.set_dt(*value)?,
                    "least_squares" => {
                        let mode = match *value {
                            0.0 => SolveMode::Exact,
                            1.0 => SolveMode::LeastSquares,
                            _ => {
                                return Err(cmd(format!(
                                    "least_squares = {value}: 0 (exact, eq 12) or 1 (least squares)"
                                )));
                            }
                        };
                        let old = self.mode == SolveMode::LeastSquares;
                        self.mode = mode;
                        f64::from(u8::from(old))
                    }
                    _ => {
                        return Err(cmd(format!(
                            "no parameter `{name}`; an ffd model has {}",
                            self.param_names()
                        )));
                    }
                };
                (
                    format!("{name} = {value}"),
                    Edit::Set {
                        name: name.clone(),
                        value: old,
                    },
                )
            }
            Edit::Fix { .. } | Edit::Free { .. } => {
                return Err(cmd(format!(
                    "an {} model has no fixed control points: direct manipulation \
                     (ffd-direct-manipulation.txt eqs 7 and 12) moves every control point of \
                     the support; use a multi-point `ffd-move` with the points to keep as moves \
                     onto themselves",
                    ModelKind::Ffd
                )));
            }
            _ => {
                let takes = "ffd-move, move-point, set-weight, set";
                return Err(super::not_taken(edit, ModelKind::Ffd, takes));
            }
        };
        Ok(Done::Inverse(message, inverse))
    }
}

impl Model for FfdModel {
    fn kind(&self) -> ModelKind {
        ModelKind::Ffd
    }

    fn summary(&self) -> String {
        format!(
            "ffd: {:?} lattice of degree {:?} ({} control points{}), {} ({} vertices, {} embedded, {} triangles)",
            self.lattice.dims(),
            self.lattice.degree(),
            self.lattice.control_point_count(),
            if self.lattice.is_rational() {
                ", rational"
            } else {
                ""
            },
            self.source,
            self.embedded.rest_positions().len(),
            self.embedded.embedded_count(),
            self.embedded.mesh().triangles.len()
        )
    }

    crate::model::clock_methods!(self => self.clock.time, self.clock.dt, self.clock.steps);

    fn step(&mut self) -> Result<StepReport, SessionError> {
        self.clock.step(|_| Ok(()))
    }

    fn energy(&self) -> Energy {
        Energy::default()
    }

    fn size(&self) -> f64 {
        self.lattice.size()
    }

    fn revision(&self) -> u64 {
        self.revision
    }

    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        Ok(self.embedded.mesh().clone())
    }

    fn display_lines(&self) -> Vec<LineSet> {
        let mut points = LineSet::new(LineRole::ControlNet);
        points.points = self.lattice.control_points().to_vec();
        vec![self.lattice_edges(), points]
    }

    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit> {
        let cp = crate::pick::control_point(ray, self.lattice.control_points(), tolerance);
        let mesh = self.embedded.mesh();
        let surf = crate::pick::ray_mesh(ray, mesh).map(|(s, t, bary)| {
            let corner = (0..3)
                .max_by(|&a, &b| bary[a].total_cmp(&bary[b]))
                .unwrap_or(0);
            Hit {
                distance: s,
                point: ray.origin + ray.direction * s,
                element: Element::MeshVertex {
                    index: mesh.triangles[t][corner] as usize,
                },
                extra: [None, None],
            }
        });
        match (cp, surf) {
            // A control point in front of (or just behind) the surface wins.
            (Some(c), Some(s)) if c.distance <= s.distance + tolerance => Some(c),
            (c, s) => s.or(c),
        }
    }

    fn params(&self) -> Vec<Param> {
        vec![
            Param::new(
                "dt",
                self.clock.dt,
                1e-4,
                1.0,
                "clock step (s); FFD has no dynamics",
            ),
            Param::new(
                "least_squares",
                f64::from(u8::from(self.mode == SolveMode::LeastSquares)),
                0.0,
                1.0,
                "multi-point ffd-move: 0 exact (eq 12, conflicts are errors), 1 minimum-norm least squares",
            ),
        ]
    }

    crate::model::stateful_methods!();

    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        match extension(path).as_str() {
            "obj" | "ply" | "stl" => {
                vclay_io::write_mesh(path, self.embedded.mesh()).map_err(|e| io(&e))
            }
            "glb" => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(
                    "ffd",
                    self.embedded.mesh().clone(),
                )],
            )
            .map_err(|e| io(&e)),
            "json" => vclay_io::write_model(
                path,
                &[vclay_io::Entity::Volume(self.lattice.volume().clone())],
            )
            .map_err(|e| io(&e)),
            _ => Err(unsupported_export(
                self.kind(),
                path,
                &["obj", "ply", "stl", "glb", "json"],
            )),
        }
    }

    fn control_points(&self) -> Vec<Vec3> {
        self.lattice.control_points().to_vec()
    }

    fn data_points(&self) -> Vec<Vec3> {
        self.embedded.mesh().positions.clone()
    }

    fn save(&self) -> Result<serde_json::Value, SessionError> {
        let (lo, hi) = self.lattice.bounds();
        let saved = Saved {
            source: self.source.clone(),
            mesh: SavedMesh {
                positions: self.embedded.rest_positions().iter().map(a3).collect(),
                triangles: self.embedded.mesh().triangles.clone(),
            },
            lattice: SavedLattice {
                degree: self.lattice.degree(),
                control: self.lattice.dims(),
                min: a3(&lo),
                max: a3(&hi),
                knots: self
                    .lattice
                    .knots()
                    .each_ref()
                    .map(|k| k.as_slice().to_vec()),
            },
            control_points: self.lattice.control_points().iter().map(a3).collect(),
            weights: self.lattice.weights().to_vec(),
            mode: mode_name(self.mode).to_string(),
            dt: self.clock.dt,
            time: self.clock.time,
            steps: self.clock.steps,
        };
        serde_json::to_value(saved).map_err(SessionError::kernel)
    }
}

// ---------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------

/// The built-in meshes of `[model] primitive`.
pub const PRIMITIVES: [&str; 3] = ["bottle", "sphere", "box"];

pub(crate) fn read_any_mesh(path: &Path) -> Result<TriMesh, String> {
    let mesh = if extension(path) == "glb" {
        let mut all = TriMesh::new();
        for m in vclay_io::gltf::read_glb(path).map_err(|e| e.to_string())? {
            all.append(&m);
        }
        all
    } else {
        vclay_io::read_mesh(path).map_err(|e| e.to_string())?
    };
    if mesh.positions.is_empty() || mesh.triangles.is_empty() {
        return Err(format!("{}: the mesh has no triangles", path.display()));
    }
    mesh.validate()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(mesh)
}

/// Bottle radius at height `z` in `[0, 3]` (the `vclay demo` bottle of
/// `ffd-direct-manipulation.txt` Fig. 3): body, shoulder, neck.
fn bottle_radius(z: f64) -> f64 {
    let t = ((z - 1.7) / 0.7).clamp(0.0, 1.0);
    1.0 - 0.65 * t * t * (3.0 - 2.0 * t)
}

/// A built-in mesh: `bottle` (the demo's bottle, radius 1, height 3, 24 x 24), `sphere`
/// (radius 1 at the origin, 12 x 24), `box` (the cube `[-1, 1]^3`, 4 x 4 quads per face).
pub fn primitive(name: &str) -> Option<TriMesh> {
    Some(match name {
        "bottle" => {
            let n = 24;
            let mut profile = vec![(0.0, 0.0)];
            profile.extend((0..=n).map(|i| {
                let z = 3.0 * i as f64 / n as f64;
                (bottle_radius(z), z)
            }));
            profile.push((0.0, 3.0));
            TriMesh::revolution(&profile, 24)
        }
        "sphere" => {
            let n = 12;
            let profile: Vec<(f64, f64)> = (0..=n)
                .map(|i| {
                    let a = std::f64::consts::PI * i as f64 / n as f64;
                    let r = if i == 0 || i == n { 0.0 } else { a.sin() };
                    (r, -a.cos())
                })
                .collect();
            TriMesh::revolution(&profile, 24)
        }
        "box" => {
            let n = 4;
            let mut mesh = TriMesh::new();
            // Each face: an origin corner and two edge vectors with e1 x e2 pointing out.
            let faces = [
                ([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
                ([-1.0, -1.0, -1.0], [0.0, 0.0, 2.0], [0.0, 2.0, 0.0]),
                ([-1.0, 1.0, -1.0], [0.0, 0.0, 2.0], [2.0, 0.0, 0.0]),
                ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
                ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
                ([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]),
            ];
            for (o, e1, e2) in faces {
                let (o, e1, e2) = (v3(o), v3(e1), v3(e2));
                let base = mesh.positions.len() as u32;
                for i in 0..=n {
                    for j in 0..=n {
                        let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                        mesh.positions.push(o + e1 * s + e2 * t);
                    }
                }
                let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
                for i in 0..n {
                    for j in 0..n {
                        mesh.triangles
                            .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                        mesh.triangles
                            .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                    }
                }
            }
            mesh.compute_normals();
            mesh
        }
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------
// Scenario keys and the session file form
// ---------------------------------------------------------------------------------------

/// The typed spec of an FFD model ([`super::ModelSpec`]).
pub type FfdSpec = super::KindSpec<ModelKeys, super::NoMaterial, super::ClockKeys>;

/// A count for all three axes or one per axis (`control = 4` or `control = [4, 4, 5]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OneOrThree {
    /// The same for every axis.
    One(usize),
    /// Per axis.
    Three([usize; 3]),
}

impl OneOrThree {
    /// Per axis.
    pub fn axes(self) -> [usize; 3] {
        match self {
            OneOrThree::One(n) => [n; 3],
            OneOrThree::Three(a) => a,
        }
    }
}

scenario_keys! {
    /// The `[model]` keys of a `ffd` model.
    pub struct ModelKeys {
        pub mesh: Option<PathBuf>,
        pub primitive: Option<String>,
        pub degree: Option<OneOrThree>,
        pub control: Option<OneOrThree>,
        pub margin: Option<f64>,
        pub min: Option<V3>,
        pub max: Option<V3>,
        pub mode: Option<String>,
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    source: String,
    mesh: SavedMesh,
    lattice: SavedLattice,
    control_points: Vec<V3>,
    weights: Vec<f64>,
    mode: String,
    dt: f64,
    time: f64,
    steps: u64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedMesh {
    positions: Vec<V3>,
    triangles: Vec<[u32; 3]>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedLattice {
    degree: [usize; 3],
    control: [usize; 3],
    min: V3,
    max: V3,
    knots: [Vec<f64>; 3],
}
