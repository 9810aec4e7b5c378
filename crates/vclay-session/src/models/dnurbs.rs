//! D-NURBS in a session: [`DnurbsModel`] wraps the D-NURBS engines of `vclay_dynamics`
//! (`d-nurbs.txt`: the Lagrangian equations of motion eq 15 with the mass, damping and
//! stiffness matrices of eqs 16-17, integrated by eq 18; applied forces of section 6.1, among
//! them the spring of eq 19; constraints of section 6.2).
//!
//! Kinds `dnurbs-curve`, `dnurbs-surface` and `dnurbs-swung`. Engines (`[model] engine`):
//! `"generalized"` (default) is `GeneralizedDnurbs` over `RationalGeometry` (curves, surfaces)
//! or `SwungGeometry` (swung surfaces), exactly as the old D-NURBS scenario runner built them,
//! so that scenarios give the same bits; `"frozen"` is the frozen-weight engine `Dnurbs`
//! (footnote 2: weights held, constant matrices), for curves and tensor-product surfaces only
//! and without constraints; a `ring` (closed periodic curve) runs on it only.
//!
//! Tools: every force-producing edit (rope, force, gravity, inflate, data) is one *slot*: a
//! serializable description of its forces ([`ForceDesc`]) under a handle that the
//! [`ToolTable`] names. The engine's force list is the concatenation of the slots' forces in
//! the order the slots were added, rebuilt whenever a slot changes, so a rope with a
//! `velocity` is the same `Target::Moving` closure the old runner made, and a session file
//! rebuilds it from its description.
//!
//! One model, five engines: this kind ([`Nurbs`]) is a kind of the one D-NURBS model,
//! [`GeneralizedModel`] (as the triangular and multi-patch kinds are), which does the clock,
//! the step, undo by the engine state, `set dt`, mesh exports and plastic flow once for all.
//! Its engine, [`NurbsEngine`], is one of two generalized engines (`RationalGeometry`,
//! `SwungGeometry`) or three frozen-weight ones (surface, open curve, and the closed periodic
//! curve of the `ring` primitive, `d-nurbs.txt` Fig 6); every one is a
//! [`DnurbsEngine`](super::generalized::DnurbsEngine) (the trait is implemented once for each
//! family, generically over the geometry), so the rest of the kind (slots, tool table,
//! constraints, display, pick, exports, session files) does not look at which it is. The
//! frozen engines stay in this kind rather than a model of their own because they run the
//! same scenario kinds with the same tools, slots, display and saved layout (`engine =
//! "frozen"` in one `Saved` form); where they lack something the trait's method refuses.
//!
//! Undo: every edit but fix/free restores a snapshot of the engine state (the engines'
//! `state()`/`set_state()`) and of what edits change besides it (`Edited`: the slots,
//! constraints, tool table, material, time step); fix/free apply the exact inverse (free
//! exactly the control points that the fix fixed) and restore the snapshot.
//!
//! Limitations: materials are uniform (constant densities); a material change on the frozen
//! engine integrates its element matrices again (the state is kept). Swung surfaces: control
//! point indices (fix, free, move-point, set-weight) count the profile curve's control points,
//! then the trajectory curve's, in their own planes (profile x-z, trajectory x-y); the scale
//! `alpha` has no index. Swung control points are not picked (the control net shown is the
//! tensor-product net of the exact surface, which has no simulated coordinates of its own).

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::DynamicsError;
use vclay_dynamics::dnurbs::ClosedCurve;
use vclay_dynamics::dnurbs::{
    Constraint, Density, Dnurbs, DnurbsGeometry, DnurbsState, ElasticReference, Force,
    GeneralizedDnurbs, GeneralizedGeometry, GeneralizedState, Material, Preset, QuadratureRule,
    RationalGeometry, SwungGeometry, Target,
};
use vclay_dynamics::{DnurbsClosedCurve, DnurbsCurve, DnurbsSurface};
use vclay_io::model::Entity;
use vclay_spline::{KnotVector, NurbsCurve, NurbsSurface};

use super::engine::NO_FROZEN_CONSTRAINTS;
use super::generalized::{
    DnurbsEngine, GeneralizedKind, GeneralizedModel, bbox_diagonal, generalized_accessors,
    param_or_near, reference,
};
use super::{SpecError, keyword, misrouted};
use crate::command::{Edit, V3};
use crate::command::{MaterialRequest, RopeRequest};
use crate::error::SessionError;
use crate::model::Done;
use crate::model::Stateful;
use crate::model::{Element, Energy, Hit, LineRole, LineSet, ModelKind, Param, Ray};
use crate::tools::{CursorPath, ToolHost, ToolTable, a3, field_tool, v3};

/// Rope and data spring stiffness when neither the edit nor a preset (its `k`) gives one.
pub const DEFAULT_ROPE_STIFFNESS: f64 = 50.0;
/// Tessellation grid of the display mesh (the old `[output] grid` default).
pub const DISPLAY_GRID: [usize; 2] = [32, 32];
/// Most control points of a sheet along one direction.
pub const MAX_SHEET_SIZE: usize = 512;
/// Control points of a `ring` without `size` (`d-nurbs.txt` Fig 6: 11).
pub const DEFAULT_RING_SIZE: usize = 11;
/// Most control points of a line (and of a ring).
pub const MAX_LINE_SIZE: usize = 100_000;
/// Highest degree (`vclay_spline::MAX_DEGREE`).
pub const MAX_DEGREE: usize = vclay_spline::MAX_DEGREE;
/// Default material `(mu, gamma, alpha, beta)` without `[material]` (the old reader's).
pub const DEFAULT_MATERIAL: [f64; 4] = [1.0, 2.0, 1.0, 0.1];

// ---------------------------------------------------------------------------------------
// Engines
// ---------------------------------------------------------------------------------------

/// The engine of a `dnurbs-curve`, `-surface` or `-swung` model: generalized (every
/// coordinate dynamic) over a rational curve or surface or a swung surface, or frozen-weight
/// over a surface or a curve. Each variant is a [`DnurbsEngine`]; so is the enum (by
/// delegation), which is the engine of the [`Nurbs`] kind.
#[derive(Clone, Debug)]
pub enum NurbsEngine {
    /// A rational curve or surface (eqs 3-6).
    Rational(GeneralizedDnurbs<RationalGeometry>),
    /// A swung surface (eq 7).
    Swung(GeneralizedDnurbs<SwungGeometry>),
    /// A tensor-product surface with frozen weights.
    FrozenSurface(DnurbsSurface),
    /// An open curve with frozen weights.
    FrozenCurve(DnurbsCurve),
    /// A closed (periodic) curve, `d-nurbs.txt` Fig 6's "closed cubic D-NURBS curve".
    FrozenRing(DnurbsClosedCurve),
}

/// The state of a [`NurbsEngine`]: its variant's.
#[derive(Clone, Debug, PartialEq)]
pub enum NurbsState {
    /// Of a generalized engine.
    Generalized(GeneralizedState),
    /// Of a frozen-weight engine.
    Frozen(DnurbsState),
}

/// `$body` for whichever engine `$e` is, bound to `$d` (each variant is a [`DnurbsEngine`]).
macro_rules! each {
    ($e:expr, $d:ident => $body:expr) => {
        match $e {
            NurbsEngine::Rational($d) => $body,
            NurbsEngine::Swung($d) => $body,
            NurbsEngine::FrozenSurface($d) => $body,
            NurbsEngine::FrozenCurve($d) => $body,
            NurbsEngine::FrozenRing($d) => $body,
        }
    };
}

fn dyn_err(e: DynamicsError) -> SessionError {
    SessionError::from(e)
}

fn cmd(reason: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", reason)
}

/// Why a ring refuses the generalized engine.
const RING_ENGINE: &str = "a ring (a closed periodic curve) runs on the frozen-weight engine \
     only (weights 1, its repeated control points are one coordinate): give `engine = \"frozen\"`";

impl DnurbsEngine for NurbsEngine {
    type State = NurbsState;
    fn is_frozen(&self) -> bool {
        each!(self, d => d.is_frozen())
    }
    fn time(&self) -> f64 {
        each!(self, d => DnurbsEngine::time(d))
    }
    fn steps(&self) -> u64 {
        each!(self, d => DnurbsEngine::steps(d))
    }
    fn step(&mut self, dt: f64) -> Result<vclay_dynamics::StepReport, DynamicsError> {
        each!(self, d => DnurbsEngine::step(d, dt))
    }
    fn state(&self) -> NurbsState {
        match self {
            NurbsEngine::Rational(d) => NurbsState::Generalized(d.state()),
            NurbsEngine::Swung(d) => NurbsState::Generalized(d.state()),
            NurbsEngine::FrozenSurface(d) => NurbsState::Frozen(d.state()),
            NurbsEngine::FrozenCurve(d) => NurbsState::Frozen(d.state()),
            NurbsEngine::FrozenRing(d) => NurbsState::Frozen(d.state()),
        }
    }
    fn set_state(&mut self, s: &NurbsState) -> Result<(), DynamicsError> {
        match (self, s) {
            (NurbsEngine::Rational(d), NurbsState::Generalized(s)) => d.set_state(s),
            (NurbsEngine::Swung(d), NurbsState::Generalized(s)) => d.set_state(s),
            (NurbsEngine::FrozenSurface(d), NurbsState::Frozen(s)) => d.set_state(s),
            (NurbsEngine::FrozenCurve(d), NurbsState::Frozen(s)) => d.set_state(s),
            (NurbsEngine::FrozenRing(d), NurbsState::Frozen(s)) => d.set_state(s),
            _ => Err(DynamicsError::Parameter {
                name: "state",
                value: 0.0,
                why: "belongs to the other engine",
            }),
        }
    }
    fn forces(&self) -> &[Force] {
        each!(self, d => DnurbsEngine::forces(d))
    }
    fn forces_mut(&mut self) -> &mut Vec<Force> {
        each!(self, d => DnurbsEngine::forces_mut(d))
    }
    fn set_material(&mut self, m: Material) -> Result<(), DynamicsError> {
        each!(self, d => DnurbsEngine::set_material(d, m))
    }
    fn stop(&mut self) {
        each!(self, d => DnurbsEngine::stop(d))
    }
    fn plastic_reset(&mut self) -> Result<(), DynamicsError> {
        each!(self, d => d.plastic_reset())
    }
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        each!(self, d => DnurbsEngine::plastic_flow(d, fraction, yield_distance))
    }
    fn elastic_energy(&self) -> Result<f64, DynamicsError> {
        each!(self, d => DnurbsEngine::elastic_energy(d))
    }
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        each!(self, d => d.nearest_param(x))
    }
    fn point_at(&self, param: [f64; 2]) -> Result<Vec3, DynamicsError> {
        each!(self, d => d.point_at(param))
    }
    fn data_distances(&self) -> Result<Vec<f64>, DynamicsError> {
        each!(self, d => DnurbsEngine::data_distances(d))
    }
    fn control_points(&self, rest: bool) -> Vec<Vec3> {
        each!(self, d => DnurbsEngine::control_points(d, rest))
    }
    fn is_point_fixed(&self, i: usize) -> bool {
        each!(self, d => d.is_point_fixed(i))
    }
    fn fixed_points(&self) -> Vec<bool> {
        each!(self, d => d.fixed_points())
    }
    fn set_point_fixed(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError> {
        each!(self, d => d.set_point_fixed(i, fixed))
    }
    fn move_point(&mut self, i: usize, to: Vec3) -> Result<(), SessionError> {
        each!(self, d => d.move_point(i, to))
    }
    fn set_weight(&mut self, i: usize, weight: f64) -> Result<(), SessionError> {
        each!(self, d => d.set_weight(i, weight))
    }
    fn weight_penalty(&self) -> Option<f64> {
        each!(self, d => DnurbsEngine::weight_penalty(d))
    }
    fn set_weight_penalty(&mut self, c: f64) -> Result<(), SessionError> {
        each!(self, d => DnurbsEngine::set_weight_penalty(d, c))
    }
    fn set_rest_points(&mut self, points: &[Vec3]) -> Result<(), SessionError> {
        each!(self, d => d.set_rest_points(points))
    }
    fn constraints(&self) -> Vec<Constraint> {
        each!(self, d => DnurbsEngine::constraints(d))
    }
    fn set_constraints(&mut self, cs: &[(&str, Constraint)]) -> Result<(), SessionError> {
        each!(self, d => d.set_constraints(cs))
    }
    fn quadrature_rule(&self) -> Option<QuadratureRule> {
        each!(self, d => DnurbsEngine::quadrature_rule(d))
    }
}

/// The `[simulation] solver` keyword (and saved value) of the block-Schur solve.
const BLOCK_SCHUR_SOLVER: &str = "block-schur";

/// `solver = "auto"` (the default) takes the block-Schur solve for tensor-product surfaces
/// with dynamic weights and at least this many control points (20 x 20), where the whole step
/// matrix's factorization is most of a step: `vclay bench --physics` on a quiet host, the
/// 32 x 32 sheet at 33 steps/s against 20 with the direct factorization; the 16 x 16 sheet
/// gains about 6 % of CPU time and smaller or constrained models can lose (each constraint row
/// is a conjugate-gradient run there). The choice is made once, when the model is built, and
/// saved with it (a saved model continues as it ran).
pub const AUTO_BLOCK_SCHUR_POINTS: usize = 400;

impl NurbsEngine {
    /// Whether the generalized engine solves its steps by blocks
    /// ([`GeneralizedDnurbs::block_schur`]); always `false` for the frozen engine.
    fn block_schur(&self) -> bool {
        match self {
            NurbsEngine::Rational(d) => d.block_schur.is_some(),
            NurbsEngine::Swung(d) => d.block_schur.is_some(),
            _ => false,
        }
    }

    /// Turns the block-Schur solve on or off (default settings); the frozen engine ignores it
    /// (its spec refuses the key).
    fn set_block_schur(&mut self, on: bool) {
        let b = on.then(vclay_dynamics::dnurbs::BlockSchur::default);
        match self {
            NurbsEngine::Rational(d) => d.block_schur = b,
            NurbsEngine::Swung(d) => d.block_schur = b,
            _ => {}
        }
    }

    fn is_curve(&self) -> bool {
        match self {
            NurbsEngine::Rational(d) => d.geometry().parametric_dimension() == 1,
            NurbsEngine::FrozenCurve(_) | NurbsEngine::FrozenRing(_) => true,
            _ => false,
        }
    }
    fn surface(&self) -> Result<Option<NurbsSurface>, DynamicsError> {
        Ok(match self {
            NurbsEngine::Rational(d) if d.geometry().parametric_dimension() == 2 => {
                Some(d.geometry().to_surface()?)
            }
            NurbsEngine::Swung(d) => Some(d.geometry().to_surface()?),
            NurbsEngine::FrozenSurface(d) => Some(d.geometry().clone()),
            _ => None,
        })
    }
    fn curve(&self) -> Result<Option<NurbsCurve>, DynamicsError> {
        Ok(match self {
            NurbsEngine::Rational(d) if d.geometry().parametric_dimension() == 1 => {
                Some(d.geometry().to_curve()?)
            }
            NurbsEngine::FrozenCurve(d) => Some(d.geometry().clone()),
            NurbsEngine::FrozenRing(d) => Some(d.geometry().curve().clone()),
            _ => None,
        })
    }
    /// Puts the named constraints into the engine.
    fn sync_constraints(&mut self, cs: &[NamedConstraint]) -> Result<(), SessionError> {
        let cs: Vec<(&str, Constraint)> = cs
            .iter()
            .map(|c| (c.name.as_str(), c.constraint.to_constraint()))
            .collect();
        self.set_constraints(&cs)
    }
}

// ---------------------------------------------------------------------------------------
// Serializable descriptions
// ---------------------------------------------------------------------------------------

/// One force of a tool slot, as it is saved (`d-nurbs.txt` section 6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ForceDesc {
    /// The spring of eq 19 at the material point `param`, pulling towards `target` (at time
    /// `t`: `target + velocity t` when `velocity` is given).
    Spring {
        /// Material point.
        param: [f64; 2],
        /// Target (at time 0 for a moving target).
        target: V3,
        /// Target velocity.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        velocity: Option<V3>,
        /// Stiffness `k`.
        stiffness: f64,
        /// Gaussian kernel width instead of the delta of eq 19.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        kernel: Option<f64>,
    },
    /// A constant force at a material point.
    Point {
        /// Material point.
        param: [f64; 2],
        /// The force.
        force: V3,
    },
    /// Gravity (force density `mu g`).
    Gravity {
        /// Acceleration.
        g: V3,
    },
    /// Pressure along the normal (surfaces).
    Inflation {
        /// Pressure.
        pressure: f64,
    },
    /// A data point pulling the nearest point of the model (section 7.3).
    DataPoint {
        /// The point.
        point: V3,
        /// Stiffness.
        stiffness: f64,
    },
    /// Repulsion from a point (section 6, issue 18).
    Repulsion {
        /// The repelling point.
        center: V3,
        /// Strength.
        strength: f64,
        /// Core radius.
        core: f64,
    },
}

impl ForceDesc {
    /// The engine's force (a moving spring target is the closure `t0 + vel t` of the old
    /// scenario reader, bit for bit).
    pub fn to_force(&self) -> Force {
        match self {
            ForceDesc::Spring {
                param,
                target,
                velocity,
                stiffness,
                kernel,
            } => {
                let t0 = v3(*target);
                let target = match velocity {
                    Some(vel) => {
                        let vel = v3(*vel);
                        Target::Moving(Arc::new(move |t| t0 + vel * t))
                    }
                    None => Target::Fixed(t0),
                };
                Force::Spring {
                    param: *param,
                    target,
                    stiffness: *stiffness,
                    kernel: *kernel,
                }
            }
            ForceDesc::Point { param, force } => Force::Point {
                param: *param,
                force: v3(*force),
            },
            ForceDesc::Gravity { g } => Force::Gravity(v3(*g)),
            ForceDesc::Inflation { pressure } => Force::Inflation(*pressure),
            ForceDesc::DataPoint { point, stiffness } => Force::DataPoint {
                point: v3(*point),
                stiffness: *stiffness,
            },
            ForceDesc::Repulsion {
                center,
                strength,
                core,
            } => Force::Repulsion {
                center: v3(*center),
                strength: *strength,
                core: *core,
            },
        }
    }
}

/// The forces of one named tool.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Slot {
    handle: usize,
    forces: Vec<ForceDesc>,
}

/// A geometric constraint as saved (section 6.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum ConstraintDesc {
    Point { param: [f64; 2], target: V3 },
    Normal { param: [f64; 2], normal: V3 },
}

impl ConstraintDesc {
    fn to_constraint(&self) -> Constraint {
        match self {
            ConstraintDesc::Point { param, target } => Constraint::Point {
                param: *param,
                target: v3(*target),
            },
            ConstraintDesc::Normal { param, normal } => Constraint::Normal {
                param: *param,
                normal: v3(*normal),
            },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct NamedConstraint {
    name: String,
    constraint: ConstraintDesc,
}

/// Uniform material constants (`d-nurbs.txt` eqs 16-17).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Mat {
    mu: f64,
    gamma: f64,
    alpha: Vec<f64>,
    beta: Vec<f64>,
    /// The densities are per unit knot span ([`Material::per_unit_knot_span`], issue 18);
    /// `spans` are then the model's non-empty knot spans per direction (absent: per unit
    /// parameter, as before issue 18).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    spans: Option<[Vec<(f64, f64)>; 2]>,
}

impl Mat {
    fn to_material(&self) -> Material {
        let m = super::generalized::constant_material(self.mu, self.gamma, &self.alpha, &self.beta);
        match &self.spans {
            Some([u, v]) => m.per_unit_knot_span([u, v]),
            None => m,
        }
    }
    fn from_material(m: &Material) -> Option<Self> {
        let c = |d: &Density| match d {
            Density::Constant(v) => Some(*v),
            _ => None,
        };
        Some(Self {
            mu: c(&m.mu)?,
            gamma: c(&m.gamma)?,
            alpha: m.alpha.iter().map(c).collect::<Option<_>>()?,
            beta: m.beta.iter().map(c).collect::<Option<_>>()?,
            spans: None,
        })
    }
}

/// A NURBS curve as saved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CurveData {
    degree: usize,
    knots: Vec<f64>,
    points: Vec<V3>,
    weights: Vec<f64>,
}

impl CurveData {
    fn of(c: &NurbsCurve) -> Self {
        Self {
            degree: c.degree(),
            knots: c.knots().as_slice().to_vec(),
            points: c.control_points().iter().map(a3).collect(),
            weights: c.weights().to_vec(),
        }
    }
    fn curve(&self) -> Result<NurbsCurve, SessionError> {
        let kv = KnotVector::new(self.knots.clone(), self.degree, self.points.len())
            .map_err(SessionError::kernel)?;
        NurbsCurve::from_knot_vector(
            kv,
            self.points.iter().map(|p| v3(*p)).collect(),
            self.weights.clone(),
        )
        .map_err(SessionError::kernel)
    }
}

/// The initial geometry (engines are rebuilt from it, so construction-time scales match).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum Source {
    Curve {
        curve: CurveData,
    },
    Surface {
        degree: [usize; 2],
        knots: [Vec<f64>; 2],
        points: Vec<V3>,
        weights: Vec<f64>,
    },
    Swung {
        profile: CurveData,
        trajectory: CurveData,
        alpha: f64,
    },
    /// A closed (periodic) B-spline curve ([`ClosedCurve`]): its distinct control points,
    /// unit knot spans.
    Ring {
        degree: usize,
        points: Vec<V3>,
    },
}

/// The non-empty spans `[t_i, t_i+1]` of a knot vector's domain.
fn knot_spans(k: &KnotVector) -> Vec<(f64, f64)> {
    let t = k.as_slice();
    (k.degree()..k.control_points())
        .filter(|&i| t[i] < t[i + 1])
        .map(|i| (t[i], t[i + 1]))
        .collect()
}

impl Source {
    /// The non-empty knot spans per parametric direction (curves: `[spans, []]`), the elements
    /// of [`Material::per_unit_knot_span`].
    fn spans(&self) -> Result<[Vec<(f64, f64)>; 2], SessionError> {
        Ok(match self {
            Source::Curve { curve } => [knot_spans(curve.curve()?.knots()), Vec::new()],
            Source::Surface { .. } => {
                let s = self.surface()?.expect("surface");
                [knot_spans(&s.knots()[0]), knot_spans(&s.knots()[1])]
            }
            Source::Swung {
                profile,
                trajectory,
                ..
            } => [
                knot_spans(profile.curve()?.knots()),
                knot_spans(trajectory.curve()?.knots()),
            ],
            Source::Ring { points, .. } => [
                (0..points.len())
                    .map(|k| (k as f64, k as f64 + 1.0))
                    .collect(),
                Vec::new(),
            ],
        })
    }

    fn of_surface(s: &NurbsSurface) -> Self {
        Source::Surface {
            degree: s.degree(),
            knots: s.knots().each_ref().map(|k| k.as_slice().to_vec()),
            points: s.control_points().iter().map(a3).collect(),
            weights: s.weights().to_vec(),
        }
    }
    fn surface(&self) -> Result<Option<NurbsSurface>, SessionError> {
        let Source::Surface {
            degree,
            knots,
            points,
            weights,
        } = self
        else {
            return Ok(None);
        };
        let kv = super::saved::knot_vectors(knots, degree)?;
        NurbsSurface::from_flat(kv, points.iter().map(|p| v3(*p)).collect(), weights.clone())
            .map(Some)
            .map_err(SessionError::kernel)
    }
    /// The engine over this geometry.
    fn engine(&self, frozen: bool, material: Material) -> Result<NurbsEngine, SessionError> {
        let e = |e: DynamicsError| SessionError::kernel(e);
        Ok(match (self, frozen) {
            (Source::Curve { curve }, false) => NurbsEngine::Rational(
                GeneralizedDnurbs::new(RationalGeometry::from_curve(&curve.curve()?), material)
                    .map_err(e)?,
            ),
            (Source::Curve { curve }, true) => {
                NurbsEngine::FrozenCurve(Dnurbs::new(curve.curve()?, material).map_err(e)?)
            }
            (Source::Surface { .. }, false) => NurbsEngine::Rational(
                GeneralizedDnurbs::new(
                    RationalGeometry::from_surface(&self.surface()?.expect("surface")),
                    material,
                )
                .map_err(e)?,
            ),
            (Source::Surface { .. }, true) => NurbsEngine::FrozenSurface(
                Dnurbs::new(self.surface()?.expect("surface"), material).map_err(e)?,
            ),
            (
                Source::Swung {
                    profile,
                    trajectory,
                    alpha,
                },
                false,
            ) => NurbsEngine::Swung(
                GeneralizedDnurbs::new(
                    SwungGeometry::new(&profile.curve()?, &trajectory.curve()?, *alpha)
                        .map_err(e)?,
                    material,
                )
                .map_err(e)?,
            ),
            (Source::Swung { .. }, true) => {
                return Err(SessionError::model(
                    "swung surfaces need the generalized engine",
                ));
            }
            (Source::Ring { degree, points }, true) => NurbsEngine::FrozenRing(
                Dnurbs::new(
                    ClosedCurve::new(*degree, points.iter().map(|p| v3(*p)).collect())
                        .map_err(e)?,
                    material,
                )
                .map_err(e)?,
            ),
            (Source::Ring { .. }, false) => {
                return Err(SessionError::model(RING_ENGINE));
            }
        })
    }
}

// ---------------------------------------------------------------------------------------
// The model
// ---------------------------------------------------------------------------------------

/// The `dnurbs-curve`, `-surface` and `-swung` kind of [`GeneralizedModel`]: its engine
/// (generalized or frozen-weight, [`NurbsEngine`]), the initial geometry, and its named tools,
/// force slots and constraints (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct Nurbs {
    kind: ModelKind,
    engine: NurbsEngine,
    source: Source,
    /// What edits and steps change besides the engine state.
    ed: Edited,
    default_k: f64,
    /// Forces of a wrapped engine that have no description (closures): they come first in the
    /// engine's force list, and a model holding them cannot be saved.
    external: Vec<Force>,
}

/// A D-NURBS curve, surface or swung surface with its named tools and constraints (see the
/// [module docs](self)).
pub type DnurbsModel = GeneralizedModel<Nurbs>;

/// What edits and steps change besides the engine state of a [`Nurbs`] model: kept whole in
/// undo snapshots.
#[derive(Clone, Debug)]
pub struct Edited {
    material: Mat,
    dt: f64,
    /// The force slots, in the order of the engine's force list.
    slots: Vec<Slot>,
    next_handle: usize,
    constraints: Vec<NamedConstraint>,
    tools: ToolTable,
    kinetic: f64,
    /// Steps of `dt` taken (the engines count their adaptive sub-steps too).
    steps: u64,
}

/// An undo snapshot: the engine state and [`Edited`].
type Snap = (NurbsState, Edited);

impl DnurbsModel {
    /// A model over `engine` built from `source`, with no tools (revision 1).
    fn build_model(
        kind: ModelKind,
        engine: NurbsEngine,
        source: Source,
        material: Mat,
        dt: f64,
    ) -> Result<Self, SessionError> {
        let size = match engine.surface().map_err(dyn_err)? {
            Some(s) => bbox_diagonal(s.control_points()),
            None => bbox_diagonal(&engine.control_points(false)),
        };
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SessionError::model(format!("dt = {dt} must be positive")));
        }
        let nurbs = Nurbs {
            kind,
            engine,
            source,
            ed: Edited {
                material,
                dt,
                slots: Vec::new(),
                next_handle: 0,
                constraints: Vec::new(),
                tools: ToolTable::default(),
                kinetic: 0.0,
                steps: 0,
            },
            default_k: DEFAULT_ROPE_STIFFNESS,
            external: Vec::new(),
        };
        Ok(GeneralizedModel::new(nurbs, size, 1))
    }

    fn constants(d: &Material) -> Result<Mat, SessionError> {
        Mat::from_material(d).ok_or_else(|| {
            SessionError::model("only constant material densities can be used in a session")
        })
    }

    /// Wraps a frozen-weight surface (`Dnurbs<NurbsSurface>`, e.g. the 64x64 benchmark
    /// sheet) stepped by eq 18 with `dt`. Its forces and fixed points are kept: they become
    /// one slot (`forces0`) of the tool table; if one of them is a spring with a closure
    /// target (the benchmark's), they are all kept as they are and the model cannot be saved
    /// ([`Model::save`] names the reason). Errors: a non-constant material, a time step that
    /// is not positive.
    pub fn frozen_surface(d: DnurbsSurface, dt: f64) -> Result<Self, SessionError> {
        let mat = Self::constants(d.material())?;
        let source = Source::of_surface(d.geometry());
        Self::wrap(
            ModelKind::DnurbsSurface,
            NurbsEngine::FrozenSurface(d),
            source,
            mat,
            dt,
        )
    }

    /// Wraps a frozen-weight curve (`Dnurbs<NurbsCurve>`); see [`DnurbsModel::frozen_surface`].
    pub fn frozen_curve(d: DnurbsCurve, dt: f64) -> Result<Self, SessionError> {
        let mat = Self::constants(d.material())?;
        let source = Source::Curve {
            curve: CurveData::of(d.geometry()),
        };
        Self::wrap(
            ModelKind::DnurbsCurve,
            NurbsEngine::FrozenCurve(d),
            source,
            mat,
            dt,
        )
    }

    /// Wraps a generalized curve or surface (`GeneralizedDnurbs<RationalGeometry>`) that has
    /// not stepped yet, stepped by eq 18 with `dt`; its forces become the slot `forces0`, its
    /// constraints `constraint<N>`. The initial geometry saved in session files is its current
    /// shape (so it must be at its construction shape: `steps() == 0`).
    pub fn generalized(
        d: GeneralizedDnurbs<RationalGeometry>,
        dt: f64,
    ) -> Result<Self, SessionError> {
        if d.steps() != 0 {
            return Err(SessionError::model(
                "wrap a generalized model before it steps (its initial shape is saved)",
            ));
        }
        let mat = Self::constants(d.material())?;
        let curve = d.geometry().parametric_dimension() == 1;
        let source = if curve {
            Source::Curve {
                curve: CurveData::of(&d.geometry().to_curve().map_err(dyn_err)?),
            }
        } else {
            Source::of_surface(&d.geometry().to_surface().map_err(dyn_err)?)
        };
        let kind = if curve {
            ModelKind::DnurbsCurve
        } else {
            ModelKind::DnurbsSurface
        };
        Self::wrap(kind, NurbsEngine::Rational(d), source, mat, dt)
    }

    /// Wraps a swung surface (`GeneralizedDnurbs<SwungGeometry>`) that has not stepped yet;
    /// see [`DnurbsModel::generalized`].
    pub fn swung(d: GeneralizedDnurbs<SwungGeometry>, dt: f64) -> Result<Self, SessionError> {
        if d.steps() != 0 {
            return Err(SessionError::model(
                "wrap a generalized model before it steps (its initial shape is saved)",
            ));
        }
        let mat = Self::constants(d.material())?;
        let g = d.geometry();
        let source = Source::Swung {
            profile: CurveData::of(&g.profile().map_err(dyn_err)?),
            trajectory: CurveData::of(&g.trajectory().map_err(dyn_err)?),
            alpha: g.alpha(),
        };
        Self::wrap(
            ModelKind::DnurbsSwung,
            NurbsEngine::Swung(d),
            source,
            mat,
            dt,
        )
    }

    /// A model over an engine built elsewhere: its forces become the slot `forces0`, its
    /// constraints (generalized engines) `constraint<N>`.
    fn wrap(
        kind: ModelKind,
        engine: NurbsEngine,
        source: Source,
        mat: Mat,
        dt: f64,
    ) -> Result<Self, SessionError> {
        let (forces, constraints) = (engine.forces().to_vec(), engine.constraints());
        let mut m = Self::build_model(kind, engine, source, mat, dt)?;
        let n = m.kind_mut();
        n.adopt_forces(&forces)?;
        for (k, c) in constraints.iter().enumerate() {
            n.ed.constraints.push(NamedConstraint {
                name: format!("constraint{k}"),
                constraint: match c {
                    Constraint::Point { param, target } => ConstraintDesc::Point {
                        param: *param,
                        target: a3(target),
                    },
                    Constraint::Normal { param, normal } => ConstraintDesc::Normal {
                        param: *param,
                        normal: a3(normal),
                    },
                },
            });
        }
        Ok(m)
    }
}

impl DnurbsModel {
    /// Which engine runs the model: `"generalized"` or `"frozen"`.
    pub fn engine_name(&self) -> &'static str {
        self.kind_part().engine_name()
    }

    /// The named tools.
    pub fn tools(&self) -> &ToolTable {
        &self.kind_part().ed.tools
    }

    /// Current control points (the indices fix/free/move-point use; see the module docs for
    /// swung surfaces).
    pub fn control_points(&self) -> Vec<Vec3> {
        self.engine().control_points(false)
    }

    /// The surface at the current state (`None` for a curve or a swung surface's curves'
    /// failure to form one).
    pub fn current_surface(&self) -> Result<Option<NurbsSurface>, SessionError> {
        self.engine().surface().map_err(dyn_err)
    }

    /// The generalized coordinates (generalized engine) or the control point coordinates
    /// x, y, z (frozen engine), flat: for exact comparisons.
    pub fn coordinates(&self) -> Vec<f64> {
        match self.engine() {
            NurbsEngine::Rational(d) => d.geometry().coordinates().to_vec(),
            NurbsEngine::Swung(d) => d.geometry().coordinates().to_vec(),
            e => e.control_points(false).iter().flat_map(a3).collect(),
        }
    }
}

impl Nurbs {
    fn engine_name(&self) -> &'static str {
        if self.engine.is_frozen() {
            "frozen"
        } else {
            "generalized"
        }
    }

    fn adopt_forces(&mut self, forces: &[Force]) -> Result<(), SessionError> {
        if forces.is_empty() {
            return Ok(());
        }
        let mut descs = Vec::new();
        for f in forces {
            descs.push(match f {
                Force::Spring {
                    param,
                    target: Target::Fixed(t),
                    stiffness,
                    kernel,
                } => ForceDesc::Spring {
                    param: *param,
                    target: a3(t),
                    velocity: None,
                    stiffness: *stiffness,
                    kernel: *kernel,
                },
                Force::Spring { .. } => {
                    // A closure target: keep every force as it is (order matters to the
                    // bits); the model then cannot be saved.
                    self.external = forces.to_vec();
                    self.sync_forces();
                    return Ok(());
                }
                Force::Point { param, force } => ForceDesc::Point {
                    param: *param,
                    force: a3(force),
                },
                Force::Gravity(g) => ForceDesc::Gravity { g: a3(g) },
                Force::Inflation(p) => ForceDesc::Inflation { pressure: *p },
                Force::DataPoint { point, stiffness } => ForceDesc::DataPoint {
                    point: a3(point),
                    stiffness: *stiffness,
                },
                Force::Repulsion {
                    center,
                    strength,
                    core,
                } => ForceDesc::Repulsion {
                    center: a3(center),
                    strength: *strength,
                    core: *core,
                },
            });
        }
        self.add_tool(&None, "forces", descs).map(drop)
    }

    fn sync_forces(&mut self) {
        let f = self
            .external
            .iter()
            .cloned()
            .chain(
                self.ed
                    .slots
                    .iter()
                    .flat_map(|s| s.forces.iter().map(ForceDesc::to_force)),
            )
            .collect();
        *self.engine.forces_mut() = f;
    }

    fn add_slot(&mut self, forces: Vec<ForceDesc>) -> usize {
        let h = self.ed.next_handle;
        self.ed.next_handle += 1;
        self.ed.slots.push(Slot { handle: h, forces });
        self.sync_forces();
        h
    }

    fn remove_slot(&mut self, h: usize) {
        self.ed.slots.retain(|s| s.handle != h);
        self.sync_forces();
    }

    fn slot_mut(&mut self, h: usize) -> Option<&mut Slot> {
        self.ed.slots.iter_mut().find(|s| s.handle == h)
    }

    /// Adds a slot under a new name; on a taken name nothing changes.
    fn add_tool(
        &mut self,
        name: &Option<String>,
        what: &str,
        forces: Vec<ForceDesc>,
    ) -> Result<String, SessionError> {
        let label =
            ToolHost::label(self, name.as_deref(), what, self.ed.next_handle).map_err(cmd)?;
        let h = self.add_slot(forces);
        self.ed.tools.track(&label, what, h, None, None);
        Ok(label)
    }

    fn stiffness(&self, s: Option<f64>) -> f64 {
        s.unwrap_or(self.default_k)
    }

    /// Sets the uniform material constants given (`d-nurbs.txt` eqs 16-17).
    fn set_material_values(
        &mut self,
        mu: Option<f64>,
        gamma: Option<f64>,
        alpha: Option<f64>,
        beta: Option<f64>,
    ) -> Result<(), SessionError> {
        let mut m = self.ed.material.clone();
        for (key, v) in [
            ("mu", mu),
            ("gamma", gamma),
            ("alpha", alpha),
            ("beta", beta),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(cmd(format!(
                        "`{key}` = {v} must be finite and non-negative"
                    )));
                }
                match key {
                    "mu" => m.mu = v,
                    "gamma" => m.gamma = v,
                    "alpha" => m.alpha.iter_mut().for_each(|a| *a = v),
                    _ => m.beta.iter_mut().for_each(|b| *b = v),
                }
            }
        }
        self.engine
            .set_material(m.to_material())
            .map_err(SessionError::command_from)?;
        self.ed.material = m;
        Ok(())
    }

    /// [`Edit::Inflate`], [`Edit::Repel`] and [`Edit::Data`]: the field tools that depend on
    /// the geometry or the engine.
    fn field_edit(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let surface = !self.engine.is_curve();
        match edit {
            Edit::Inflate {
                name,
                pressure,
                until,
            } => {
                if !surface {
                    return Err(cmd("inflation needs a surface (s_u x s_v), not a curve"));
                }
                let inflation = ForceDesc::Inflation {
                    pressure: *pressure,
                };
                field_tool(self, name, "inflate", inflation, *until)
            }
            Edit::Repel {
                name,
                center,
                strength,
                core,
                until,
            } => {
                let core = core.unwrap_or(crate::command::DEFAULT_REPULSION_CORE);
                if self.engine_name() == "frozen" && !surface {
                    return Err(cmd(
                        "the frozen-weight engine repels surfaces only (use engine = \"generalized\")",
                    ));
                }
                let repulsion = ForceDesc::Repulsion {
                    center: *center,
                    strength: *strength,
                    core,
                };
                field_tool(self, name, "repel", repulsion, *until)
            }
            Edit::Data {
                name,
                points,
                stiffness,
            } => {
                let k = self.stiffness(*stiffness);
                let f = points
                    .iter()
                    .map(|p| ForceDesc::DataPoint {
                        point: *p,
                        stiffness: k,
                    })
                    .collect();
                let label = self.add_tool(name, "data", f)?;
                Ok(format!("data `{label}`: {} points", points.len()))
            }
            _ => Err(misrouted()),
        }
    }

    /// [`Edit::Fix`] and [`Edit::Free`], undone by their exact inverse; a failure puts back
    /// `before`.
    fn fix_or_free(&mut self, edit: &Edit, before: &Snap) -> Result<Done, SessionError> {
        match crate::tools::fix_or_free(&mut NetOf(self), edit) {
            Ok(r) => Ok(Done::Inverse(
                crate::tools::fixed_message(edit, &r),
                r.inverse,
            )),
            Err(e) => {
                self.put_before(&before.1)?;
                self.engine.set_state(&before.0).map_err(dyn_err)?;
                self.put(&before.1)?;
                Err(e)
            }
        }
    }

    /// [`Edit::Material`]: the uniform D-NURBS material (`mu`, `gamma`, `alpha`, `beta`).
    fn material(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let m = MaterialRequest::of(edit).ok_or_else(misrouted)?;
        if m.solid_given() {
            return Err(cmd(
                "`density`, `damping`, `edge_stiffness`, `virtual_stiffness`, `anisotropy` are solid materials; D-NURBS take mu, gamma, alpha, beta",
            ));
        }
        if m.region_given() {
            return Err(cmd(
                "a D-NURBS material is uniform: `cells`, `min` and `max` do not apply",
            ));
        }
        if !m.dnurbs_given() {
            return Err(cmd("give at least one of mu, gamma, alpha, beta"));
        }
        let [mu, gamma, alpha, beta] = m.dnurbs;
        self.set_material_values(mu, gamma, alpha, beta)?;
        Ok("material changed".to_string())
    }

    /// [`Edit::MovePoint`]: control point `index` to `to`, at rest.
    fn move_point(&mut self, index: usize, to: &V3) -> Result<String, SessionError> {
        self.engine.move_point(index, v3(*to))?;
        Ok(format!("moved control point {index} to {to:?}"))
    }

    /// [`Edit::SetWeight`] (generalized engines).
    fn set_weight(&mut self, index: usize, weight: f64) -> Result<String, SessionError> {
        self.engine.set_weight(index, weight)?;
        Ok(format!("weight of control point {index} = {weight}"))
    }

    /// [`Edit::Constraint`] (section 6.2, generalized engines): a point or normal constraint
    /// at `param` under a new name.
    fn constraint(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let Edit::Constraint {
            name,
            kind,
            param,
            target,
            normal,
        } = edit
        else {
            return Err(misrouted());
        };
        if self.engine.is_frozen() {
            return Err(cmd(NO_FROZEN_CONSTRAINTS));
        }
        let c = match (kind.as_str(), target, normal) {
            ("point", Some(t), _) => ConstraintDesc::Point {
                param: *param,
                target: *t,
            },
            ("normal", _, Some(n)) => ConstraintDesc::Normal {
                param: *param,
                normal: *n,
            },
            _ => {
                return Err(cmd(
                    "a point constraint takes `target`, a normal one `normal`",
                ));
            }
        };
        let label = self.constraint_label(name.as_deref())?;
        let mut cs = self.ed.constraints.clone();
        cs.push(NamedConstraint {
            name: label.clone(),
            constraint: c,
        });
        if let Err(e) = self.engine.sync_constraints(&cs) {
            self.engine.sync_constraints(&self.ed.constraints)?;
            return Err(e);
        }
        self.ed.constraints = cs;
        Ok(format!("{kind} constraint `{label}` at {param:?}"))
    }

    /// The name of a new constraint: `name` when no tool or constraint has it, else the first
    /// free `constraintK`.
    fn constraint_label(&self, name: Option<&str>) -> Result<String, SessionError> {
        let taken = |l: &str| self.ed.constraints.iter().any(|c| c.name == l);
        match name {
            Some(n) if self.ed.tools.get(n).is_some() => {
                Err(cmd(format!("a tool named `{n}` is active")))
            }
            Some(n) if taken(n) => Err(cmd(format!(
                "a constraint named `{n}` is active (release it first)"
            ))),
            Some("") => Err(cmd("a name must not be empty")),
            Some(n) => Ok(n.to_string()),
            None => {
                let mut k = self.ed.constraints.len();
                loop {
                    let l = format!("constraint{k}");
                    if self.ed.tools.get(&l).is_none() && !taken(&l) {
                        break Ok(l);
                    }
                    k += 1;
                }
            }
        }
    }

    fn set_param(&mut self, name: &str, value: f64) -> Result<String, SessionError> {
        match name {
            "mu" => self.set_material_values(Some(value), None, None, None)?,
            "gamma" => self.set_material_values(None, Some(value), None, None)?,
            "alpha" => self.set_material_values(None, None, Some(value), None)?,
            "beta" => self.set_material_values(None, None, None, Some(value))?,
            "weight_penalty" => self.engine.set_weight_penalty(value)?,
            _ => {
                return Err(cmd(format!(
                    "no parameter `{name}`; a {} model has {}",
                    self.kind,
                    GeneralizedKind::params(self)
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        Ok(format!("{name} = {value}"))
    }

    /// Samples of the curve (curves only): `(parameter, point)`.
    fn curve_samples(&self) -> Vec<(f64, Vec3)> {
        let Ok(Some(c)) = self.engine.curve() else {
            return Vec::new();
        };
        let dom = vclay_spline::ParametricCurve::domain(&c);
        let n = DISPLAY_GRID[0].max(2) * 4;
        (0..=n)
            .filter_map(|i| {
                let u = dom.min + dom.length() * i as f64 / n as f64;
                vclay_spline::ParametricCurve::point(&c, u)
                    .ok()
                    .map(|p| (u, p))
            })
            .collect()
    }

    /// The display mesh and the parameters of its vertices.
    fn mesh_with_params(&self) -> Result<(TriMesh, Vec<[f64; 2]>), SessionError> {
        let mut mesh = TriMesh::new();
        let Some(s) = self.engine.surface().map_err(dyn_err)? else {
            return Ok((mesh, Vec::new()));
        };
        vclay_spline::tessellate_surface(&s, DISPLAY_GRID, &mut mesh)
            .map_err(SessionError::kernel)?;
        // The tessellation's own vertex parameters (lines on the C0 knots included).
        let params = vclay_spline::SurfaceSampling::new(&s, DISPLAY_GRID).vertex_params();
        debug_assert_eq!(params.len(), mesh.positions.len());
        Ok((mesh, params))
    }

    fn control_net(&self) -> LineSet {
        let mut set = LineSet::new(LineRole::ControlNet);
        if let Ok(Some(s)) = self.engine.surface() {
            let [nu, nv] = s.dims();
            set.points = s.control_points().to_vec();
            for i in 0..nu {
                for j in 0..nv {
                    let k = (i * nv + j) as u32;
                    if i + 1 < nu {
                        set.segments.push([k, k + nv as u32]);
                    }
                    if j + 1 < nv {
                        set.segments.push([k, k + 1]);
                    }
                }
            }
        } else {
            let p = self.engine.control_points(false);
            set.polyline(&p);
            if matches!(self.engine, NurbsEngine::FrozenRing(_)) && p.len() > 2 {
                // The closed polygon: last point back to the first.
                set.segments.push([p.len() as u32 - 1, 0]);
            }
        }
        set
    }
}

impl DnurbsModel {
    /// Builds a model from a scenario's `[model]`, `[material]` and `[simulation]` tables
    /// (`docs/formats.md`, D-NURBS keys).
    pub fn from_keys(kind: ModelKind, spec: &DnurbsSpec, base: &Path) -> Result<Self, SpecError> {
        let m = &spec.model;
        let err = |table: &str, key: &str, what: String| SpecError::new(table, key, what);
        let surface = kind != ModelKind::DnurbsCurve;
        let frozen = keyword(
            "model",
            "engine",
            m.engine.as_deref(),
            &[("generalized", false), ("frozen", true)],
        )?
        .unwrap_or(false);
        // Material.
        let (mat, mut consts, per_span, preset) = material_of(surface, &spec.material)?;
        // Simulation.
        let sim = &spec.simulation;
        let dt = sim.dt.or(preset.map(|p| p.dt)).ok_or_else(|| {
            err(
                "simulation",
                "dt",
                "missing (give dt or a material preset)".into(),
            )
        })?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(err("simulation", "dt", format!("{dt} must be positive")));
        }
        let reference = keyword(
            "simulation",
            "reference",
            sim.reference.as_deref(),
            &[("rest", false), ("absolute", true)],
        )?
        .map_or(ElasticReference::RestShape, reference);
        let quadrature = quadrature_of(sim)?;
        if frozen && sim.quadrature.is_some() {
            return Err(err(
                "simulation",
                "quadrature",
                "the frozen-weight engine picks its rule at construction (weight-aware, one order for the model); choosing one needs `engine = \"generalized\"`".into(),
            ));
        }
        // `None`: "auto", decided below from the model's size.
        let block_schur = keyword(
            "simulation",
            "solver",
            sim.solver.as_deref(),
            &[
                ("auto", None),
                ("direct", Some(false)),
                (BLOCK_SCHUR_SOLVER, Some(true)),
            ],
        )?
        .flatten();
        if frozen && block_schur == Some(true) {
            return Err(err(
                "simulation",
                "solver",
                "the frozen-weight engine factors its constant matrix once; the block-Schur solve needs `engine = \"generalized\"`".into(),
            ));
        }
        let penalty = sim.weight_penalty.unwrap_or(0.0);
        let dynamic_weights = keyword(
            "model",
            "weights",
            m.weights.as_deref(),
            &[("dynamic", true), ("frozen", false)],
        )?
        .unwrap_or(!frozen);
        if frozen && dynamic_weights {
            return Err(err(
                "model",
                "weights",
                "\"dynamic\" needs `engine = \"generalized\"` (the frozen engine holds its weights)".into(),
            ));
        }
        if frozen && sim.weight_penalty.is_some() {
            return Err(err(
                "simulation",
                "weight_penalty",
                "the frozen-weight engine holds its weights; a penalty needs `engine = \"generalized\"`".into(),
            ));
        }
        if !(penalty.is_finite() && penalty >= 0.0) {
            return Err(err(
                "simulation",
                "weight_penalty",
                format!("{penalty} must be finite and non-negative"),
            ));
        }
        // Geometry.
        let source = build_source(kind, m, base)?;
        if frozen && kind == ModelKind::DnurbsSwung {
            return Err(err(
                "model",
                "engine",
                "swung surfaces need the generalized engine (their coordinates are not control points)".into(),
            ));
        }
        if per_span {
            consts.spans = Some(
                source
                    .spans()
                    .map_err(|e| err("model", "material", e.to_string()))?,
            );
        }
        let mat = if per_span { consts.to_material() } else { mat };
        let engine = source
            .engine(frozen, mat)
            .map_err(|e| err("model", "material", e.to_string()))?;
        let mut model = Self::build_model(kind, engine, source, consts, dt)
            .map_err(|e| err("simulation", "dt", e.to_string()))?;
        let n = model.kind_mut();
        if let Some(p) = preset
            && p.k > 0.0
        {
            n.default_k = p.k;
        }
        let rule = quadrature.rule();
        match &mut n.engine {
            NurbsEngine::Rational(d) => {
                setup(d, reference, penalty, dynamic_weights, &m.fix, rule)?
            }
            NurbsEngine::Swung(d) => setup(d, reference, penalty, dynamic_weights, &m.fix, rule)?,
            NurbsEngine::FrozenSurface(d) => fix_frozen(d, reference, &m.fix)?,
            NurbsEngine::FrozenCurve(d) => fix_frozen(d, reference, &m.fix)?,
            NurbsEngine::FrozenRing(d) => fix_frozen(d, reference, &m.fix)?,
        }
        let auto = !frozen
            && dynamic_weights
            && kind == ModelKind::DnurbsSurface
            && n.engine
                .surface()
                .map_err(|e| err("model", "size", e.to_string()))?
                .is_some_and(|s| s.control_points().len() >= AUTO_BLOCK_SCHUR_POINTS);
        n.engine.set_block_schur(block_schur.unwrap_or(auto));
        Ok(model)
    }

    /// Rebuilds a model saved by [`Model::save`].
    pub fn load(kind: ModelKind, v: &serde_json::Value) -> Result<Self, SessionError> {
        let s: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        let frozen = match s.engine.as_str() {
            "generalized" => false,
            "frozen" => true,
            o => return Err(SessionError::model(format!("unknown engine \"{o}\""))),
        };
        let engine = s.source.engine(frozen, s.material.to_material())?;
        let mut m = Self::build_model(kind, engine, s.source, s.material, s.dt)?;
        if let Some(q) = s.quadrature {
            match &mut m.kind_mut().engine {
                NurbsEngine::Rational(d) => d.set_quadrature_rule(q.rule()).map_err(dyn_err)?,
                NurbsEngine::Swung(d) => d.set_quadrature_rule(q.rule()).map_err(dyn_err)?,
                _ => {}
            }
        }
        match s.solver.as_deref() {
            None => {}
            Some(BLOCK_SCHUR_SOLVER) if !frozen => m.kind_mut().engine.set_block_schur(true),
            Some(o) => {
                return Err(SessionError::model(format!(
                    "unknown solver \"{o}\" for the {} engine",
                    s.engine
                )));
            }
        }
        if m.engine().is_curve() != (kind == ModelKind::DnurbsCurve) {
            return Err(SessionError::model(format!(
                "the saved geometry is not a {kind}"
            )));
        }
        m.kind_mut().default_k = s.default_k;
        m.set_size(s.size);
        for t in &s.tools.tools {
            if !s.slots.iter().any(|x| x.handle == t.handle) {
                return Err(SessionError::model(format!(
                    "tool `{}` refers to slot {} which does not exist",
                    t.name, t.handle
                )));
            }
        }
        let state = match s.state {
            SavedState::Generalized(g) => NurbsState::Generalized(GeneralizedState::from(g)),
            SavedState::Frozen {
                points,
                previous,
                rest,
                absolute,
                fixed,
                time,
                steps,
                products,
            } => {
                let f = |v: Vec<V3>| v.into_iter().map(v3).collect::<Vec<_>>();
                NurbsState::Frozen(DnurbsState {
                    points: f(points),
                    previous: f(previous),
                    rest: f(rest),
                    reference: reference(absolute),
                    fixed,
                    time,
                    steps,
                    products: products.map(|p| p.map(f)),
                })
            }
        };
        let snap = (
            state,
            Edited {
                material: m.kind_part().ed.material.clone(),
                dt: s.dt,
                slots: s.slots,
                next_handle: s.next_handle,
                constraints: s.constraints,
                tools: s.tools,
                kinetic: s.kinetic,
                steps: s.steps,
            },
        );
        m.put_state(&snap)?;
        m.set_revision(1);
        Ok(m)
    }
}

/// The material of a D-NURBS from its `[material]` keys: the material, its constants, whether
/// densities are per knot span, and the Table 1 preset named.
fn material_of(
    surface: bool,
    mk: &MaterialKeys,
) -> Result<(Material, Mat, bool, Option<&'static Preset>), SpecError> {
    let err = |table: &str, key: &str, what: String| SpecError::new(table, key, what);
    let preset = match &mk.preset {
        Some(p) => Some(Preset::by_name(p).ok_or_else(|| {
            err(
                "material",
                "preset",
                format!("no Table 1 preset named \"{p}\""),
            )
        })?),
        None => None,
    };
    let [mu0, g0, a0, b0] = DEFAULT_MATERIAL;
    let mut mat = match (preset, surface) {
        (Some(p), true) => p.surface_material(),
        (Some(p), false) => p.curve_material(),
        (None, true) => Material::surface(mu0, g0, a0, b0),
        (None, false) => Material::curve(mu0, g0, a0, b0),
    };
    for (key, v) in [
        ("mu", mk.mu),
        ("gamma", mk.gamma),
        ("alpha", mk.alpha),
        ("beta", mk.beta),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v >= 0.0) {
                return Err(err(
                    "material",
                    key,
                    format!("{v} must be finite and non-negative"),
                ));
            }
            let d = Density::Constant(v);
            match key {
                "mu" => mat.mu = d,
                "gamma" => mat.gamma = d,
                "alpha" => mat.alpha.iter_mut().for_each(|a| *a = d.clone()),
                _ => mat.beta.iter_mut().for_each(|b| *b = d.clone()),
            }
        }
    }
    let consts = Mat::from_material(&mat).expect("constant densities");
    let per_span = keyword(
        "material",
        "per",
        mk.per.as_deref(),
        &[("knot-span", true), ("parameter", false)],
    )?
    .unwrap_or(!surface);
    Ok((mat, consts, per_span, preset))
}

/// The quadrature rule of a D-NURBS from its `[simulation]` keys.
fn quadrature_of(sim: &SimKeys) -> Result<Quad, SpecError> {
    let err = |table: &str, key: &str, what: String| SpecError::new(table, key, what);
    let quadrature = match (sim.quadrature.as_deref(), sim.quadrature_tolerance) {
        (Some("fixed"), Some(_)) => {
            return Err(err(
                "simulation",
                "quadrature_tolerance",
                "only the \"weight-aware\" rule takes a tolerance".into(),
            ));
        }
        (Some("fixed"), None) => Quad::Fixed,
        (None | Some("weight-aware"), t) => Quad::WeightAware {
            tolerance: t.unwrap_or(vclay_dynamics::dnurbs::DEFAULT_QUADRATURE_TOLERANCE),
        },
        (Some(o), _) => {
            return Err(err(
                "simulation",
                "quadrature",
                format!("\"{o}\": expected \"weight-aware\" or \"fixed\""),
            ));
        }
    };
    if let Err(e) = quadrature.rule().validate() {
        return Err(err("simulation", "quadrature_tolerance", e.to_string()));
    }
    Ok(quadrature)
}

/// The old runner's setup: reference, weight penalty, frozen weights, fixed control points
/// (x, y, z of the n-th control point's coordinate group), then the quadrature rule.
fn setup<G: GeneralizedGeometry>(
    d: &mut GeneralizedDnurbs<G>,
    reference: ElasticReference,
    penalty: f64,
    dynamic_weights: bool,
    fix: &[usize],
    rule: QuadratureRule,
) -> Result<(), SpecError> {
    d.set_elastic_reference(reference);
    d.set_weight_penalty(penalty)
        .map_err(|e| SpecError::new("simulation", "weight_penalty", e))?;
    if !dynamic_weights {
        for i in d.geometry().weight_coordinates() {
            d.set_fixed_coordinate(i, true)
                .map_err(|e| SpecError::new("model", "weights", e))?;
        }
    }
    let groups = d.geometry().coordinate_groups();
    for &cp in fix {
        let g = groups
            .iter()
            .filter(|g| g.len() == 4)
            .nth(cp)
            .cloned()
            .ok_or_else(|| {
                SpecError::new("model", "fix", format!("control point {cp} does not exist"))
            })?;
        for i in g.start..g.start + 3 {
            d.set_fixed_coordinate(i, true)
                .map_err(|e| SpecError::new("model", "fix", e))?;
        }
    }
    d.set_quadrature_rule(rule)
        .map_err(|e| SpecError::new("simulation", "quadrature", e))?;
    Ok(())
}

/// The frozen engine's setup: reference and fixed control points.
fn fix_frozen<G: DnurbsGeometry>(
    d: &mut Dnurbs<G>,
    reference: ElasticReference,
    fix: &[usize],
) -> Result<(), SpecError> {
    d.set_elastic_reference(reference);
    for &cp in fix {
        d.set_fixed(cp, true).map_err(|_| {
            SpecError::new("model", "fix", format!("control point {cp} does not exist"))
        })?;
    }
    Ok(())
}

/// The source of a swung D-NURBS: one of the primitives of `d-nurbs.txt` section 4.3.
fn swung_source(m: &ModelKeys) -> Result<Source, SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let ext = m.extent.unwrap_or(1.0);
    let g = match m.primitive.as_deref() {
        Some("sphere") => SwungGeometry::sphere(ext),
        Some("torus") => SwungGeometry::torus(2.0 * ext, 0.5 * ext),
        Some("hat") => SwungGeometry::hat(),
        Some("wine-glass") => SwungGeometry::wine_glass(),
        Some("cube" | "cubical") => SwungGeometry::cube(ext),
        Some(o) => {
            return Err(err(
                "primitive",
                format!(
                    "unknown swung primitive \"{o}\"; expected sphere, torus, hat, wine-glass or cube"
                ),
            ));
        }
        None => {
            return Err(err(
                "primitive",
                "missing (sphere, torus, hat, wine-glass or cube)".into(),
            ));
        }
    }
    .map_err(|e| err("primitive", e.to_string()))?;
    Ok(Source::Swung {
        profile: CurveData::of(&g.profile().map_err(|e| err("primitive", e.to_string()))?),
        trajectory: CurveData::of(
            &g.trajectory()
                .map_err(|e| err("primitive", e.to_string()))?,
        ),
        alpha: g.alpha(),
    })
}

fn build_source(kind: ModelKind, m: &ModelKeys, base: &Path) -> Result<Source, SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let surface = kind != ModelKind::DnurbsCurve;
    if let Some(x) = m.extent
        && !(x.is_finite() && x > 0.0)
    {
        return Err(err("extent", format!("{x} must be positive and finite")));
    }
    if let Some(d) = &m.degree
        && let Some(&p) = d.iter().find(|&&p| p > MAX_DEGREE || p == 0)
    {
        return Err(err(
            "degree",
            format!("{p}: degrees run from 1 to {MAX_DEGREE}"),
        ));
    }
    if kind == ModelKind::DnurbsSwung {
        return swung_source(m);
    }
    if let Some(s) = &m.surface {
        if m.file.is_some() || m.primitive.is_some() || m.size.is_some() || !surface {
            return Err(err(
                "surface",
                "a surface given as a value excludes `file`, `primitive` and `size` and needs a dnurbs-surface".into(),
            ));
        }
        return Ok(Source::of_surface(s));
    }
    if let Some(file) = &m.file {
        let path = base.join(file);
        let ents = vclay_io::model::read_model(&path).map_err(|e| err("file", e.to_string()))?;
        let idx = m.entity.unwrap_or(0);
        let e = ents
            .into_iter()
            .nth(idx)
            .ok_or_else(|| err("entity", format!("the file has no entity {idx}")))?;
        return match (e, surface) {
            (Entity::Curve(c), false) => Ok(Source::Curve {
                curve: CurveData::of(&c),
            }),
            (Entity::Surface(s), true) => Ok(Source::of_surface(&s)),
            _ => Err(err(
                "entity",
                format!(
                    "entity {idx} is not a {}",
                    if surface {
                        "nurbs-surface"
                    } else {
                        "nurbs-curve"
                    }
                ),
            )),
        };
    }
    primitive_source(kind, m)
}

/// The source of a primitive (`sheet`, `line`, `circle`, `ring`) of extent `m.extent`.
fn primitive_source(kind: ModelKind, m: &ModelKeys) -> Result<Source, SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let surface = kind != ModelKind::DnurbsCurve;
    let extent = m.extent.unwrap_or(2.0);
    match (m.primitive.as_deref(), surface) {
        (Some("sheet") | None, true) => {
            let size = m.size.clone().unwrap_or(vec![8, 8]);
            let deg = m.degree.clone().unwrap_or(vec![3, 3]);
            if size.len() != 2 || deg.len() != 2 {
                return Err(err(
                    "size",
                    "a sheet needs size = [nu, nv] and degree = [p, q]".into(),
                ));
            }
            if let Some(&n) = size.iter().find(|&&n| !(2..=MAX_SHEET_SIZE).contains(&n)) {
                return Err(err(
                    "size",
                    format!(
                        "{n} control points along a direction; a sheet takes 2 to {MAX_SHEET_SIZE}"
                    ),
                ));
            }
            let mut pts = Vec::with_capacity(size[0] * size[1]);
            for i in 0..size[0] {
                for j in 0..size[1] {
                    pts.push(Vec3::new(
                        extent * (i as f64 / (size[0].max(2) - 1) as f64 - 0.5),
                        extent * (j as f64 / (size[1].max(2) - 1) as f64 - 0.5),
                        0.0,
                    ));
                }
            }
            let s = NurbsSurface::clamped_uniform([deg[0], deg[1]], [size[0], size[1]], pts)
                .map_err(|e| err("size", e.to_string()))?;
            Ok(Source::of_surface(&s))
        }
        (Some("circle"), false) => Ok(Source::Curve {
            curve: CurveData::of(
                &NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 0.5 * extent)
                    .map_err(|e| err("primitive", e.to_string()))?,
            ),
        }),
        (Some("ring"), false) => {
            // d-nurbs.txt Fig 6: "an initial closed cubic D-NURBS curve with 11 control
            // points"; the control polygon is a regular n-gon of diameter `extent`.
            let n = m
                .size
                .as_ref()
                .and_then(|s| s.first().copied())
                .unwrap_or(DEFAULT_RING_SIZE);
            let deg = m
                .degree
                .as_ref()
                .and_then(|s| s.first().copied())
                .unwrap_or(3);
            if !(deg + 1..=MAX_LINE_SIZE).contains(&n) {
                return Err(err(
                    "size",
                    format!(
                        "{n} control points; a ring of degree {deg} takes {} to {MAX_LINE_SIZE}",
                        deg + 1
                    ),
                ));
            }
            let r = 0.5 * extent;
            let points = (0..n)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    [r * t.cos(), r * t.sin(), 0.0]
                })
                .collect();
            Ok(Source::Ring {
                degree: deg,
                points,
            })
        }
        (Some("line") | None, false) => {
            let n = m
                .size
                .as_ref()
                .and_then(|s| s.first().copied())
                .unwrap_or(8);
            let deg = m
                .degree
                .as_ref()
                .and_then(|s| s.first().copied())
                .unwrap_or(3);
            if !(2..=MAX_LINE_SIZE).contains(&n) {
                return Err(err(
                    "size",
                    format!("{n} control points; a line takes 2 to {MAX_LINE_SIZE}"),
                ));
            }
            let pts = (0..n)
                .map(|i| Vec3::new(extent * (i as f64 / (n.max(2) - 1) as f64 - 0.5), 0.0, 0.0))
                .collect();
            Ok(Source::Curve {
                curve: CurveData::of(
                    &NurbsCurve::clamped_uniform(deg, pts)
                        .map_err(|e| err("size", e.to_string()))?,
                ),
            })
        }
        (Some(o), _) => Err(err(
            "primitive",
            format!(
                "unknown primitive \"{o}\" for {kind}; expected {}",
                if surface {
                    "sheet"
                } else {
                    "line, circle or ring"
                }
            ),
        )),
    }
}

/// A D-NURBS's tools for the shared rope, force and release edits: a handle is a slot of
/// force descriptions (the engine's force list is rebuilt from the slots).
impl ToolHost for Nurbs {
    type Field = ForceDesc;
    crate::tools::tool_table!(ed.tools);
    /// [`ToolTable::label`], refusing a constraint's name (an unnamed tool skips them).
    fn label(&self, name: Option<&str>, what: &str, handle: usize) -> Result<String, String> {
        let taken = |n: &str| self.ed.constraints.iter().any(|c| c.name == n);
        if let Some(n) = name
            && taken(n)
        {
            return Err(format!(
                "a constraint named `{n}` is active (release it first)"
            ));
        }
        let mut l = self.ed.tools.label(name, what, handle)?;
        let mut k = 1;
        while taken(&l) {
            l = format!("{what}{handle}_c{k}");
            k += 1;
        }
        Ok(l)
    }
    fn attach_rope(
        &mut self,
        r: &RopeRequest,
    ) -> Result<(usize, Option<CursorPath>, String), SessionError> {
        if r.length.is_some_and(|l| l > 0.0) {
            return Err(cmd(
                "`length` is for solids; a D-NURBS spring (eq 19) pulls at any length",
            ));
        }
        let prm = param_or_near(&self.engine, r.param, Some(&r.from))?;
        let spring = ForceDesc::Spring {
            param: prm,
            target: r.from,
            velocity: r.velocity,
            stiffness: self.stiffness(r.stiffness),
            kernel: r.kernel,
        };
        let path = r.to.map(|to| {
            let start = r.start.unwrap_or(self.engine.time());
            CursorPath::Linear {
                from: r.from,
                to,
                start,
                end: r.until.unwrap_or(start),
            }
        });
        let h = self.add_slot(vec![spring]);
        Ok((h, path, format!("at material point {prm:?}")))
    }
    fn attach_force(&mut self, edit: &Edit) -> Result<(usize, String), SessionError> {
        let Edit::Force {
            near, param, force, ..
        } = edit
        else {
            return Err(misrouted());
        };
        let prm = param_or_near(&self.engine, *param, near.as_ref())?;
        let h = self.add_slot(vec![ForceDesc::Point {
            param: prm,
            force: *force,
        }]);
        Ok((h, format!("at material point {prm:?}")))
    }
    fn attach_field(&mut self, field: ForceDesc) -> Result<usize, SessionError> {
        Ok(self.add_slot(vec![field]))
    }
    fn replace_field(&mut self, handle: usize, field: ForceDesc) -> Result<usize, SessionError> {
        self.slot_mut(handle).expect("slot of a tool").forces = vec![field];
        self.sync_forces();
        Ok(handle)
    }
    fn move_cursor(&mut self, handle: usize, to: V3) -> Result<(), SessionError> {
        if let Some(ForceDesc::Spring {
            target, velocity, ..
        }) = self.slot_mut(handle).and_then(|s| s.forces.first_mut())
        {
            *target = to;
            *velocity = None;
        }
        self.sync_forces();
        Ok(())
    }
    fn detach(&mut self, handle: usize) {
        self.remove_slot(handle);
    }
    /// The slot just added goes, and its handle is free again.
    fn take_back(&mut self, handle: usize) {
        self.remove_slot(handle);
        self.ed.next_handle = handle;
    }
    /// A constraint (section 6.2) of that name.
    fn release_other(&mut self, name: &str) -> Result<(), SessionError> {
        let Some(i) = self.ed.constraints.iter().position(|c| c.name == name) else {
            return Err(cmd(format!("no active tool or constraint named `{name}`")));
        };
        let mut cs = self.ed.constraints.clone();
        cs.remove(i);
        self.engine.sync_constraints(&cs)?;
        self.ed.constraints = cs;
        Ok(())
    }
}

/// The control net of a D-NURBS for the shared fix/free tool.
struct NetOf<'a>(&'a mut Nurbs);

impl crate::tools::ControlNet for NetOf<'_> {
    fn current_points(&self) -> Vec<Vec3> {
        self.0.engine.control_points(false)
    }
    fn rest_points(&self) -> Vec<Vec3> {
        self.0.engine.control_points(true)
    }
    fn is_fixed(&self, i: usize) -> bool {
        self.0.engine.is_point_fixed(i)
    }
    fn set_fixed(&mut self, ids: &[usize], fix: bool) -> Result<(), SessionError> {
        for &i in ids {
            self.0
                .engine
                .set_point_fixed(i, fix)
                .map_err(SessionError::command_from)?;
        }
        Ok(())
    }
}

impl Nurbs {
    /// Applies an edit ([`GeneralizedKind::edit`]).
    fn apply_edit(&mut self, edit: &Edit, before: &Snap) -> Result<Done, SessionError> {
        Ok(match edit {
            _ if crate::tools::is_tool_edit(edit) => {
                Done::State(crate::tools::tool_edit(self, edit)?)
            }
            Edit::Gravity { name, g, until } => {
                let gravity = ForceDesc::Gravity { g: *g };
                Done::State(field_tool(self, name, "gravity", gravity, *until)?)
            }
            Edit::Inflate { .. } | Edit::Repel { .. } | Edit::Data { .. } => {
                Done::State(self.field_edit(edit)?)
            }
            Edit::Fix { .. } | Edit::Free { .. } => self.fix_or_free(edit, before)?,
            Edit::Material { .. } => Done::State(self.material(edit)?),
            Edit::Smooth { .. } => Done::State(self.smooth(edit)?),
            Edit::PlasticReset => {
                let e = self.engine.elastic_energy().unwrap_or(f64::NAN);
                self.engine
                    .plastic_reset()
                    .map_err(SessionError::command_from)?;
                Done::State(format!("plastic reset (elastic energy {e:.4e} -> 0)"))
            }
            Edit::Stop => {
                self.engine.stop();
                self.ed.kinetic = 0.0;
                Done::State("stopped all motion".to_string())
            }
            Edit::MovePoint { index, to } => Done::State(self.move_point(*index, to)?),
            Edit::SetWeight { index, weight } => Done::State(self.set_weight(*index, *weight)?),
            Edit::Set { name, value } => Done::State(self.set_param(name, *value)?),
            Edit::Integrator { integrator, dt } => {
                // Eq 18 is the one integrator; `dt` the time step.
                if let Some(i) = integrator
                    && i != "implicit"
                {
                    return Err(cmd(format!(
                        "unknown integrator \"{i}\": D-NURBS integrate by eq 18 (\"implicit\") only"
                    )));
                }
                if let Some(dt) = dt {
                    self.ed.dt = *dt;
                }
                Done::State(format!("integrator implicit (eq 18), dt {}", self.ed.dt))
            }
            Edit::Constraint { .. } => Done::State(self.constraint(edit)?),
            Edit::RegionForce { .. }
            | Edit::Extrude { .. }
            | Edit::DeleteCell { .. }
            | Edit::FfdMove { .. }
            | Edit::PdeSet { .. }
            | Edit::PdeLocal { .. } => return Err(super::not_taken(edit, self.kind, "")),
            _ => return Err(misrouted()),
        })
    }
}

impl GeneralizedKind for Nurbs {
    type Engine = NurbsEngine;
    type State = Edited;
    const EDITS_REDRAW: bool = true;
    const MESH_NAME: &'static str = "dnurbs";

    fn kind(&self) -> ModelKind {
        self.kind
    }

    generalized_accessors!(engine, ed.dt);

    fn steps(&self) -> u64 {
        self.ed.steps
    }

    fn take(&self) -> Edited {
        self.ed.clone()
    }

    /// The material first: the frozen engine integrates its elements with it.
    fn put_before(&mut self, s: &Edited) -> Result<(), SessionError> {
        if self.ed.material != s.material {
            self.engine
                .set_material(s.material.to_material())
                .map_err(dyn_err)?;
            self.ed.material = s.material.clone();
        }
        Ok(())
    }

    fn put(&mut self, s: &Edited) -> Result<(), SessionError> {
        self.ed = s.clone();
        self.sync_forces();
        self.engine.sync_constraints(&self.ed.constraints)
    }

    fn edit(&mut self, edit: &Edit, before: &Snap) -> Result<Done, SessionError> {
        self.apply_edit(edit, before)
    }

    fn summary(&self) -> String {
        let mut s = format!(
            "{} ({} engine): {} control points, {} tools, {} constraints",
            self.kind,
            self.engine_name(),
            self.engine.control_points(false).len(),
            self.ed.tools.tools.len(),
            self.ed.constraints.len()
        );
        // Fitting (d-nurbs.txt section 7.3, Figs 6-7): the distances of the data points to the
        // nearest points of the model.
        if let Ok(d) = self.engine.data_distances()
            && !d.is_empty()
        {
            let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
            let max = d.iter().fold(0.0f64, |m, &x| m.max(x));
            s += &format!(
                "; data fit: {} points, RMS distance {rms:.3e}, max {max:.3e}",
                d.len()
            );
        }
        s
    }

    /// The tool table's expiry and cursor paths.
    fn before_step(&mut self) {
        let due = self.ed.tools.due(self.engine.time(), self.ed.dt);
        let mut changed = !due.expired.is_empty();
        for e in &due.expired {
            self.ed.slots.retain(|s| s.handle != e.handle);
        }
        for (h, c) in &due.cursors {
            if let Some(ForceDesc::Spring {
                target,
                velocity: None,
                ..
            }) = self.slot_mut(*h).and_then(|s| s.forces.first_mut())
            {
                *target = a3(c);
                changed = true;
            }
        }
        if changed {
            self.sync_forces();
        }
    }

    fn after_step(&mut self, r: &vclay_dynamics::StepReport) {
        self.ed.kinetic = r.kinetic_energy;
        self.ed.steps += 1;
    }

    /// The kinetic energy of the last step, the elastic energy and the springs' energy now.
    fn energy(&self, _last: Energy) -> Energy {
        Energy {
            kinetic: self.ed.kinetic,
            elastic: self.engine.elastic_energy().unwrap_or(f64::NAN),
            tools: self.engine.tool_energy(),
        }
    }

    fn mesh(&self) -> Result<TriMesh, SessionError> {
        Ok(self.mesh_with_params()?.0)
    }

    fn display_lines(&self, size: f64) -> Vec<LineSet> {
        let mut out = vec![self.control_net()];
        if self.engine.is_curve() {
            let mut c = LineSet::new(LineRole::Curve);
            let pts: Vec<Vec3> = self.curve_samples().into_iter().map(|s| s.1).collect();
            c.polyline(&pts);
            out.push(c);
        }
        let p = self.engine.control_points(false);
        let fixed = self.engine.fixed_points();
        out.push(LineSet::markers(LineRole::Fixed, &p, |i| {
            fixed.get(i).copied().unwrap_or(false)
        }));
        let t = self.engine.time();
        let mut ropes = LineSet::new(LineRole::Ropes);
        let mut forces = LineSet::new(LineRole::Forces);
        let mut data = LineSet::new(LineRole::DataPoints);
        let centre = {
            let n = p.len().max(1) as f64;
            p.iter().sum::<Vec3>() / n
        };
        let arrow = |set: &mut LineSet, at: Vec3, f: Vec3| {
            let n = f.norm();
            if n > 0.0 {
                set.segment(at, at + f / n * (0.2 * size));
            }
        };
        for s in &self.ed.slots {
            for f in &s.forces {
                match f {
                    ForceDesc::Spring {
                        param,
                        target,
                        velocity,
                        ..
                    } => {
                        let d0 = v3(*target) + velocity.map_or(Vec3::zeros(), |v| v3(v) * t);
                        if let Ok(x) = self.engine.point_at(*param) {
                            ropes.segment(x, d0);
                        }
                    }
                    ForceDesc::Point { param, force } => {
                        if let Ok(x) = self.engine.point_at(*param) {
                            arrow(&mut forces, x, v3(*force));
                        }
                    }
                    ForceDesc::Gravity { g } => arrow(&mut forces, centre, v3(*g)),
                    ForceDesc::Inflation { .. } => {}
                    ForceDesc::Repulsion { center, .. } => data.points.push(v3(*center)),
                    ForceDesc::DataPoint { point, .. } => data.points.push(v3(*point)),
                }
            }
        }
        let mut cons = LineSet::new(LineRole::Constraints);
        for c in &self.ed.constraints {
            match &c.constraint {
                ConstraintDesc::Point { target, .. } => cons.points.push(v3(*target)),
                ConstraintDesc::Normal { param, normal } => {
                    if let Ok(x) = self.engine.point_at(*param) {
                        arrow(&mut cons, x, v3(*normal));
                    }
                }
            }
        }
        out.extend([ropes, forces, data, cons]);
        out
    }

    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit> {
        let cp = if matches!(self.engine, NurbsEngine::Swung(_)) {
            None
        } else {
            crate::pick::control_point(ray, &self.engine.control_points(false), tolerance)
        };
        let model = if self.engine.is_curve() {
            let mut best: Option<(f64, f64, Vec3)> = None;
            for (u, x) in self.curve_samples() {
                let (d, s) = crate::pick::ray_point(ray, &x);
                if d <= tolerance && best.is_none_or(|b| s < b.1) {
                    best = Some((u, s, x));
                }
            }
            best.map(|(u, s, x)| Hit {
                distance: s,
                point: x,
                element: Element::CurvePoint { u },
                extra: [None, None],
            })
        } else {
            let (mesh, params) = self.mesh_with_params().ok()?;
            super::generalized::surface_pick(ray, &mesh, &params, &self.engine)
        };
        match (cp, model) {
            // A control point in front of (or just behind) the model wins.
            (Some(c), Some(s)) if c.distance <= s.distance + tolerance => Some(c),
            (c, s) => s.or(c),
        }
    }

    fn params(&self) -> Vec<Param> {
        let par = Param::new;
        let m = &self.ed.material;
        let mut v = vec![
            par("mu", m.mu, 0.0, 100.0, "mass density (eq 16)"),
            par("gamma", m.gamma, 0.0, 100.0, "damping density (eq 16)"),
            par(
                "alpha",
                m.alpha.first().copied().unwrap_or(0.0),
                0.0,
                1000.0,
                "tension (eq 17; first direction shown, set applies to all)",
            ),
            par(
                "beta",
                m.beta.first().copied().unwrap_or(0.0),
                0.0,
                1000.0,
                "rigidity (eq 17; first pair shown, set applies to all)",
            ),
            super::generalized::dt_param(self.ed.dt),
        ];
        if let Some(c) = self.engine.weight_penalty() {
            v.push(par(
                "weight_penalty",
                c,
                0.0,
                1e6,
                "penalty c/2 sum (w - w0)^2 holding the weights",
            ));
        }
        v
    }

    fn exports(&self) -> &'static [&'static str] {
        if self.engine.is_curve() {
            &["json", "obj", "step", "igs"]
        } else {
            &["json", "obj", "stl", "ply", "glb", "step", "igs"]
        }
    }

    /// Model JSON, STEP and IGES of the curve or surface, and the curve's OBJ polyline.
    fn write(&self, ext: &str, path: &Path) -> Option<Result<(), SessionError>> {
        let own =
            matches!(ext, "json" | "step" | "igs") || (ext == "obj" && self.engine.is_curve());
        if !own {
            return None;
        }
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        let entity = || -> Result<Entity, SessionError> {
            Ok(match self.engine.surface().map_err(|e| io(&e))? {
                Some(s) => Entity::Surface(s),
                None => Entity::Curve(
                    self.engine
                        .curve()
                        .map_err(|e| io(&e))?
                        .expect("a curve or a surface"),
                ),
            })
        };
        Some(match ext {
            "json" => {
                entity().and_then(|e| vclay_io::model::write_model(path, &[e]).map_err(|e| io(&e)))
            }
            "step" => entity()
                .and_then(|e| vclay_io::step::write_step(path, &[e.into()]).map_err(|e| io(&e))),
            "igs" => entity()
                .and_then(|e| vclay_io::iges::write_iges(path, &[e.into()]).map_err(|e| io(&e))),
            _ => {
                use std::fmt::Write as _;
                let mut text = String::from("# vclay D-NURBS curve\n");
                let pts = self.curve_samples();
                for (_, p) in &pts {
                    let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
                }
                text.push('l');
                for i in 1..=pts.len() {
                    let _ = write!(text, " {i}");
                }
                text.push('\n');
                vclay_io::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(|e| io(&e))
            }
        })
    }

    fn save(&self, size: f64) -> Result<serde_json::Value, SessionError> {
        if !self.external.is_empty() {
            return Err(SessionError::model(
                "the wrapped engine's forces include a spring with a closure target, which a session file cannot describe (add such springs with `rope` and `velocity`)",
            ));
        }
        let arr = |v: &[Vec3]| v.iter().map(a3).collect::<Vec<_>>();
        let state = match self.engine.state() {
            NurbsState::Generalized(s) => SavedState::Generalized((&s).into()),
            NurbsState::Frozen(s) => SavedState::Frozen {
                points: arr(&s.points),
                previous: arr(&s.previous),
                rest: arr(&s.rest),
                absolute: s.reference == ElasticReference::Absolute,
                fixed: s.fixed,
                time: s.time,
                steps: s.steps,
                products: s.products.map(|p| p.map(|v| arr(&v))),
            },
        };
        let saved = Saved {
            engine: self.engine_name().to_string(),
            source: self.source.clone(),
            material: self.ed.material.clone(),
            dt: self.ed.dt,
            default_k: self.default_k,
            size,
            state,
            slots: self.ed.slots.clone(),
            next_handle: self.ed.next_handle,
            constraints: self.ed.constraints.clone(),
            tools: self.ed.tools.clone(),
            kinetic: self.ed.kinetic,
            steps: self.ed.steps,
            quadrature: self.engine.quadrature_rule().map(Quad::of),
            solver: self
                .engine
                .block_schur()
                .then(|| BLOCK_SCHUR_SOLVER.to_string()),
        };
        serde_json::to_value(saved).map_err(SessionError::kernel)
    }
}

// ---------------------------------------------------------------------------------------
// Scenario keys
// ---------------------------------------------------------------------------------------

/// The typed spec of a D-NURBS curve, surface or swung surface ([`super::ModelSpec`]).
pub type DnurbsSpec = super::KindSpec<ModelKeys, MaterialKeys, SimKeys>;

scenario_keys! {
    /// The `[model]` keys of a `dnurbs-*` model.
    pub struct ModelKeys {
        /// The surface itself, given as a value by a front end (the Python module's
        /// `dnurbs_surface`); not a scenario key.
        #[serde(skip)]
        pub surface: Option<vclay_spline::NurbsSurface>,
        #[serde(default)]
        pub engine: Option<String>,
        #[serde(default)]
        pub primitive: Option<String>,
        #[serde(default)]
        pub file: Option<std::path::PathBuf>,
        #[serde(default)]
        pub entity: Option<usize>,
        #[serde(default)]
        pub size: Option<Vec<usize>>,
        #[serde(default)]
        pub degree: Option<Vec<usize>>,
        #[serde(default)]
        pub extent: Option<f64>,
        #[serde(default)]
        pub weights: Option<String>,
        #[serde(default)]
        pub fix: Vec<usize>,
    }
}

scenario_keys! {
    /// The `[material]` keys of a `dnurbs-*` model.
    pub struct MaterialKeys {
        pub preset: Option<String>,
        /// `"knot-span"` or `"parameter"` (issue 18).
        pub per: Option<String>,
        pub mu: Option<f64>,
        pub gamma: Option<f64>,
        pub alpha: Option<f64>,
        pub beta: Option<f64>,
    }
}

scenario_keys! {
    /// The `[simulation]` keys of a `dnurbs-*` model.
    pub struct SimKeys {
        pub dt: Option<f64>,
        pub reference: Option<String>,
        pub weight_penalty: Option<f64>,
        /// `"weight-aware"` (default) or `"fixed"` (the paper's rule), issue 18.
        pub quadrature: Option<String>,
        /// Relative accuracy of the weight-aware rule.
        pub quadrature_tolerance: Option<f64>,
        /// `"auto"` (default: `"block-schur"` for surfaces with dynamic weights and at least
        /// [`AUTO_BLOCK_SCHUR_POINTS`] control points, else `"direct"`), `"direct"` (a sparse
        /// Cholesky factorization of the whole step matrix) or `"block-schur"` (the generalized
        /// engine's split solve, [`vclay_dynamics::dnurbs::BlockSchur`]: about a quarter less
        /// CPU a step on large tensor-product sheets with dynamic weights, each solve to a
        /// relative residual of 1e-12), issues 27/31.
        pub solver: Option<String>,
    }
}

/// The quadrature rule of a saved or specified model (see
/// [`vclay_dynamics::dnurbs::QuadratureRule`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "rule", rename_all = "kebab-case", deny_unknown_fields)]
enum Quad {
    /// The paper's fixed Gauss rule.
    Fixed,
    /// Weight-aware orders to a relative tolerance.
    WeightAware { tolerance: f64 },
}

impl Quad {
    fn rule(self) -> QuadratureRule {
        match self {
            Quad::Fixed => QuadratureRule::Fixed,
            Quad::WeightAware { tolerance } => QuadratureRule::WeightAware { tolerance },
        }
    }

    fn of(rule: QuadratureRule) -> Self {
        match rule {
            QuadratureRule::WeightAware { tolerance } => Quad::WeightAware { tolerance },
            _ => Quad::Fixed,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Session file form
// ---------------------------------------------------------------------------------------

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    engine: String,
    source: Source,
    material: Mat,
    dt: f64,
    default_k: f64,
    size: f64,
    state: SavedState,
    slots: Vec<Slot>,
    next_handle: usize,
    constraints: Vec<NamedConstraint>,
    tools: ToolTable,
    kinetic: f64,
    /// Steps of `dt` taken.
    steps: u64,
    /// Quadrature rule of the generalized engine (absent in files written before issue 18:
    /// the weight-aware default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    quadrature: Option<Quad>,
    /// `"block-schur"` when the generalized engine solves its steps by blocks (absent: the
    /// direct factorization, and in files written before issues 27/31).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    solver: Option<String>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum SavedState {
    /// The generalized engine's state, as the other generalized kinds save it (the same
    /// fields beside the `type` tag).
    Generalized(super::saved::SavedState),
    Frozen {
        points: Vec<V3>,
        previous: Vec<V3>,
        rest: Vec<V3>,
        absolute: bool,
        fixed: Vec<bool>,
        time: f64,
        steps: usize,
        products: Option<[Vec<V3>; 4]>,
    },
}

impl Nurbs {
    /// [`Edit::Smooth`]: one umbrella step of the rest control points under the brush
    /// (`crate::smooth`, neighbours along the control net); eq (17)'s rest values follow and
    /// the surface settles towards the smoothed rest shape as it steps. Undone with the state
    /// (the engine state holds the rest coordinates).
    fn smooth(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let net = self.control_net();
        let (smoothed, n) = crate::smooth::smoothed_rest(&NetOf(self), net, edit)?;
        self.engine.set_rest_points(&smoothed)?;
        Ok(crate::smooth::message(n))
    }
}

#[cfg(test)]
mod tests {
    use super::SavedState;

    /// The generalized state keeps the layout session files have had since the session layer
    /// (the `type` tag beside the engine's fields): such a file loads, writes back the same,
    /// and an unknown key is still refused.
    #[test]
    fn generalized_state_keeps_its_file_layout() {
        let text = r#"{"type":"generalized","coordinates":[0.0,1.5],"velocity":[0.0,0.25],"rest_coordinates":[0.0,1.0],"fixed":[true,false],"weight_targets":[1.0],"weight_penalty":0.5,"absolute":true,"time":0.125,"steps":3,"substeps":1,"weight_projections":2}"#;
        let s: SavedState = serde_json::from_str(text).unwrap();
        assert!(matches!(s, SavedState::Generalized(_)));
        assert_eq!(serde_json::to_string(&s).unwrap(), text);
        let extra = text.replace("\"steps\":3", "\"steps\":3,\"extra\":1");
        assert!(serde_json::from_str::<SavedState>(&extra).is_err());
    }
}
