//! D-NURBS: dynamic NURBS curves and tensor-product surfaces (`d-nurbs.txt`).
//!
//! ## Model
//! The control points `p` are generalized coordinates of the Lagrangian equations of motion
//! (`d-nurbs.txt` eq 15) `M p'' + D p' + K p = f_p + g_p` with
//!
//! ```text
//! M = integral mu J^T J,   D = integral gamma J^T J                                   (eq 16)
//! K = integral (a11 J_u^T J_u + a22 J_v^T J_v + b11 J_uu^T J_uu + b12 J_uv^T J_uv + b22 J_vv^T J_vv)  (eq 17)
//! f_p = integral J^T f                                                       (virtual work)
//! ```
//! (for curves `K = integral (alpha J_u^T J_u + beta J_uu^T J_uu)`, footnote 3). Each non-empty
//! knot span (curve) or span rectangle (surface) is a finite element (section 5.1) whose matrices
//! are integrated by Gauss-Legendre quadrature with `max(4, p + 1)` points per direction
//! (section 5.2: 4 to 7 points; `p + 1` points integrate the polynomial mass integrand exactly).
//!
//! The delta spring of eq (19) is linear in `p` when weights are frozen, so vclay splits it:
//! `k J^T d0` is an explicit force and `k J^T J` joins the stiffness in the implicit solve, which
//! keeps stiff springs stable at any time step (the paper evaluates all forces at time t).
//!
//! ## Time integration
//! Eq (18): `(2M + dt D + 2 dt^2 K) p(t+dt) = 2 dt^2 f_p + 4 M p(t) - (2M - dt D) p(t-dt)`, a
//! central difference in M and D that is implicit in K, solved each step by Jacobi-preconditioned
//! conjugate gradients working element by element without assembling the global matrices. The
//! paper caps CG at 10 iterations ([`PAPER_CG_ITERATIONS`]); vclay iterates to a relative residual
//! ([`DEFAULT_CG_TOLERANCE`]) with a higher cap by default. The static variant (`mu = gamma = 0`,
//! section 5.3 and footnote 6) solves `K p = f_p` ([`Integrator::Static`]).
//!
//! Each step's linear system is solved by default with a cached sparse Cholesky factorization
//! ([`LinearSolver::Direct`]; the matrix is constant with frozen weights), or by the paper's
//! element-by-element CG ([`LinearSolver::ConjugateGradient`]).
//!
//! ## Two engines
//! This module's [`Dnurbs`] keeps weights frozen (footnote 2): `g_p` vanishes, the weight columns
//! of J drop out, and the matrices are constant. [`GeneralizedDnurbs`] (`generalized.rs`)
//! simulates every generalized coordinate (weights included, and swung surfaces), with the
//! generalized inertial force and constraints; with all weights held it reproduces this engine
//! (tested to 1e-8).

pub mod benchmarks;
pub mod figures;
pub mod generalized;
mod geometry;
pub mod patches;
pub mod presets;
pub mod rational;
pub mod rounding;
mod system;
pub mod triangular;

pub use generalized::{
    BlockSchur, Constraint, DEFAULT_QUADRATURE_TOLERANCE, FactorReuse, GeneralizedDnurbs,
    GeneralizedGeometry, GeneralizedState, LinearTie, LocalJacobian, QuadratureRule,
    denominator_radius,
};
pub use geometry::{ClosedCurve, DnurbsGeometry, ElementSamples};
pub use patches::{Continuity, PatchesGeometry};
pub use presets::{Preset, TABLE_1};
pub use rational::{RationalGeometry, SwungGeometry};
pub use system::{Element, ElementSystem, SolverStats};
pub use triangular::{TriangleQuadrature, TriangularGeometry};

use crate::error::DynamicsError;
use std::fmt;
use std::sync::Arc;
use vclay_core::{GaussLegendre, Vec3};
use vclay_spline::{NurbsCurve, NurbsSurface};

/// CG iteration cap used by the paper (section 5.3).
pub const PAPER_CG_ITERATIONS: usize = 10;
/// Default CG iteration cap.
pub const DEFAULT_CG_ITERATIONS: usize = 500;
/// Default relative residual at which CG stops.
pub const DEFAULT_CG_TOLERANCE: f64 = 1e-10;
/// A run is declared divergent when a control point moves farther than this many model sizes.
pub const DIVERGENCE_DISPLACEMENT_FACTOR: f64 = 1e6;

/// A density or elasticity function over the parametric domain.
#[derive(Clone)]
pub enum Density {
    /// The same value everywhere.
    Constant(f64),
    /// One value per element (elements ordered span by span, v fastest for surfaces).
    PerElement(Vec<f64>),
    /// A function of the parameter `[u, v]` (`v = 0` for curves).
    Function(Arc<dyn Fn([f64; 2]) -> f64 + Send + Sync>),
}

impl fmt::Debug for Density {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Density::Constant(v) => write!(f, "Constant({v})"),
            Density::PerElement(v) => write!(f, "PerElement({} values)", v.len()),
            Density::Function(_) => write!(f, "Function(..)"),
        }
    }
}

impl Density {
    fn eval(&self, element: usize, param: [f64; 2]) -> f64 {
        match self {
            Density::Constant(v) => *v,
            Density::PerElement(v) => v[element],
            Density::Function(f) => f(param),
        }
    }

    fn validate(&self, name: &'static str, elements: usize) -> Result<(), DynamicsError> {
        let bad = |value: f64| DynamicsError::Parameter {
            name,
            value,
            why: "must be finite and non-negative",
        };
        match self {
            Density::Constant(v) if !(v.is_finite() && *v >= 0.0) => Err(bad(*v)),
            Density::PerElement(v) if v.len() != elements => Err(DynamicsError::ElementCount {
                name,
                found: v.len(),
                expected: elements,
            }),
            Density::PerElement(v) => match v.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                Some(x) => Err(bad(*x)),
                None => Ok(()),
            },
            _ => Ok(()),
        }
    }
}

/// Default mass density `mu`.
pub const DEFAULT_MU: f64 = 1.0;
/// Default damping density `gamma`.
pub const DEFAULT_GAMMA: f64 = 1.0;
/// Default tension `alpha` (per direction).
pub const DEFAULT_ALPHA: f64 = 1.0;
/// Default rigidity `beta` (per second-derivative pair).
pub const DEFAULT_BETA: f64 = 0.1;

/// Physical parameters of a D-NURBS (`d-nurbs.txt` eqs 16-17).
#[derive(Clone, Debug)]
pub struct Material {
    /// Mass density `mu` (default [`DEFAULT_MU`]).
    pub mu: Density,
    /// Damping density `gamma` (default [`DEFAULT_GAMMA`]).
    pub gamma: Density,
    /// Tension `alpha` per parametric direction (`[alpha]` for curves, `[a11, a22]` for
    /// surfaces; default [`DEFAULT_ALPHA`]).
    pub alpha: Vec<Density>,
    /// Rigidity `beta` per second-derivative pair (`[beta]` for curves, `[b11, b12, b22]` for
    /// surfaces; default [`DEFAULT_BETA`]).
    pub beta: Vec<Density>,
}

impl Material {
    /// Constant densities for a curve.
    pub fn curve(mu: f64, gamma: f64, alpha: f64, beta: f64) -> Self {
        Self {
            mu: Density::Constant(mu),
            gamma: Density::Constant(gamma),
            alpha: vec![Density::Constant(alpha)],
            beta: vec![Density::Constant(beta)],
        }
    }

    /// The same material with its densities read **per unit knot span** (issue 18): each
    /// element `[u0, u1] x [v0, v1]` of widths `h_u`, `h_v` gets the densities that the
    /// functional of eqs (16)-(17) has when that element is reparametrized onto the unit square
    /// (`t = u / h_u`, the classic integer knots of the paper's examples):
    /// `mu, gamma / (h_u h_v)`, `alpha_11 h_u / h_v`, `alpha_22 h_v / h_u`, `beta_11 h_u^3 / h_v`,
    /// `beta_12 h_u h_v`, `beta_22 h_v^3 / h_u` (curves: `h_v = 1`, so `mu / h`, `alpha h`,
    /// `beta h^3`). The dynamics then do not depend on the knot spacing or the domain length:
    /// a curve on `[0, 1]` with `n` spans moves as the same curve on `[0, n]`. `spans` lists the
    /// non-empty knot spans per direction (`spans[1]` empty for curves); elements are taken
    /// span by span, v fastest, as [`Density::PerElement`] orders them. Constant and
    /// per-element densities are scaled; a [`Density::Function`] is kept as it is.
    pub fn per_unit_knot_span(&self, spans: [&[(f64, f64)]; 2]) -> Self {
        let curve = spans[1].is_empty();
        let vs: Vec<(f64, f64)> = if curve {
            vec![(0.0, 1.0)]
        } else {
            spans[1].to_vec()
        };
        let widths: Vec<(f64, f64)> = spans[0]
            .iter()
            .flat_map(|u| vs.iter().map(move |v| (u.1 - u.0, v.1 - v.0)))
            .collect();
        let scale = |d: &Density, f: &dyn Fn(f64, f64) -> f64| match d {
            Density::Constant(c) => {
                Density::PerElement(widths.iter().map(|&(hu, hv)| c * f(hu, hv)).collect())
            }
            Density::PerElement(v) if v.len() == widths.len() => Density::PerElement(
                v.iter()
                    .zip(&widths)
                    .map(|(c, &(hu, hv))| c * f(hu, hv))
                    .collect(),
            ),
            other => other.clone(),
        };
        let inertial = |hu: f64, hv: f64| 1.0 / (hu * hv);
        let alpha: Vec<Density> = self
            .alpha
            .iter()
            .enumerate()
            .map(|(k, a)| {
                if k == 0 {
                    scale(a, &|hu, hv| hu / hv)
                } else {
                    scale(a, &|hu, hv| hv / hu)
                }
            })
            .collect();
        let beta: Vec<Density> = self
            .beta
            .iter()
            .enumerate()
            .map(|(k, b)| match k {
                0 => scale(b, &|hu, hv| hu.powi(3) / hv),
                1 => scale(b, &|hu, hv| hu * hv),
                _ => scale(b, &|hu, hv| hv.powi(3) / hu),
            })
            .collect();
        Self {
            mu: scale(&self.mu, &inertial),
            gamma: scale(&self.gamma, &inertial),
            alpha,
            beta,
        }
    }

    /// Constant densities for a surface (same tension in u and v, same rigidity for all pairs).
    pub fn surface(mu: f64, gamma: f64, alpha: f64, beta: f64) -> Self {
        Self {
            mu: Density::Constant(mu),
            gamma: Density::Constant(gamma),
            alpha: vec![Density::Constant(alpha); 2],
            beta: vec![Density::Constant(beta); 3],
        }
    }
}

/// Where a spring pulls to.
#[derive(Clone)]
pub enum Target {
    /// A fixed point in space.
    Fixed(Vec3),
    /// A point moving with time.
    Moving(Arc<dyn Fn(f64) -> Vec3 + Send + Sync>),
}

impl fmt::Debug for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Target::Fixed(p) => write!(f, "Fixed({p:?})"),
            Target::Moving(_) => write!(f, "Moving(..)"),
        }
    }
}

impl Target {
    fn at(&self, t: f64) -> Vec3 {
        match self {
            Target::Fixed(p) => *p,
            Target::Moving(f) => f(t),
        }
    }
}

/// Applied forces (`d-nurbs.txt` section 6.1).
#[derive(Clone, Debug)]
pub enum Force {
    /// The spring of eq (19): `f = k (d0 - s(u0))` at the material point `u0`; with
    /// `kernel = Some(sigma)` the delta is replaced by a unit Gaussian of width `sigma` (in
    /// parameter units) and the force is integrated over the elements.
    Spring {
        /// Material point `[u, v]` (`v` ignored for curves).
        param: [f64; 2],
        /// Point in space `d0`.
        target: Target,
        /// Spring stiffness `k`.
        stiffness: f64,
        /// Gaussian kernel width, or `None` for the delta of eq (19).
        kernel: Option<f64>,
    },
    /// A constant force at a material point.
    Point {
        /// Material point.
        param: [f64; 2],
        /// The force.
        force: Vec3,
    },
    /// Gravity: force density `mu g`.
    Gravity(Vec3),
    /// Inflation: pressure along the surface normal, `f = P s_u x s_v` (surfaces only).
    Inflation(f64),
    /// Repulsion from a point (`d-nurbs.txt` section 6 names repulsion forces beside springs,
    /// gravity and inflation; the form of its ref. \[34\]): the force density per unit length
    /// (curves) or area (surfaces) `f = k d / (|d|^2 + c^2)^(3/2)` with `d = s - center`, an
    /// inverse-square push away from `center` softened within the core radius `c`. Evaluated at
    /// the start of each step (explicit), integrated over the elements with `|s_u|` or
    /// `|s_u x s_v|` as the length or area element. The frozen-weight engine applies it to
    /// surfaces only.
    Repulsion {
        /// The repelling point.
        center: Vec3,
        /// Strength `k` (negative attracts).
        strength: f64,
        /// Core radius `c` (> 0).
        core: f64,
    },
    /// A data point pulling the nearest point of the geometry with a spring of `stiffness`
    /// (`d-nurbs.txt` section 7.3: "spring forces ... are always applied to the nearest points";
    /// the attachment is searched again at every step).
    DataPoint {
        /// The data point.
        point: Vec3,
        /// Spring stiffness.
        stiffness: f64,
    },
}

/// The energy stored in the springs among `forces` at time `t` (what `StepReport`'s elastic
/// energy leaves out): `1/2 k |s(u0) - d0(t)|^2` for each spring of eq (19) (a Gaussian-kernel
/// spring is counted at its centre `u0`), and `1/2 k |s(u*) - d|^2` for each data point with
/// `u*` its nearest material point (section 7.3). Constant forces, gravity, inflation and
/// repulsion store none here (their work is not a spring's). `point_at` evaluates `s`,
/// `nearest` finds `u*`.
///
/// # Errors
/// The first evaluation that fails.
pub fn spring_energy(
    forces: &[Force],
    t: f64,
    point_at: &dyn Fn([f64; 2]) -> Result<Vec3, DynamicsError>,
    nearest: &dyn Fn(&Vec3) -> Result<[f64; 2], DynamicsError>,
) -> Result<f64, DynamicsError> {
    let mut e = 0.0;
    for f in forces {
        match f {
            Force::Spring {
                param,
                target,
                stiffness,
                ..
            } => e += 0.5 * stiffness * (point_at(*param)? - target.at(t)).norm_squared(),
            Force::DataPoint { point, stiffness } => {
                let u = nearest(point)?;
                e += 0.5 * stiffness * (point_at(u)? - point).norm_squared();
            }
            _ => {}
        }
    }
    Ok(e)
}

/// The repulsion density `k d / (|d|^2 + c^2)^(3/2)`, `d = x - center`, of
/// [`Force::Repulsion`] (per unit length or area).
pub fn repulsion_density(x: Vec3, center: Vec3, strength: f64, core: f64) -> Vec3 {
    let d = x - center;
    let r2 = d.norm_squared() + core * core;
    if r2 > 0.0 {
        d * (strength / (r2 * r2.sqrt()))
    } else {
        Vec3::zeros()
    }
}

/// The unit Gaussian that replaces the delta of eq (19) for a [`Force::Spring`] with
/// `kernel = Some(sigma)`: `exp(-|q - c|^2 / (2 sigma^2)) / (2 pi sigma^2)^(dim/2)` over the
/// parametric dimension `dim = q.len()`. Both engines weight the spring force density with it.
pub(crate) struct SpringKernel {
    sigma: f64,
    norm: f64,
}

impl SpringKernel {
    /// The kernel of width `sigma` in `dim` parameters; an error names a width that is not
    /// positive and finite.
    pub(crate) fn new(sigma: f64, dim: usize) -> Result<Self, DynamicsError> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(DynamicsError::Parameter {
                name: "kernel width",
                value: sigma,
                why: "must be positive",
            });
        }
        let norm = (2.0 * std::f64::consts::PI * sigma * sigma).powf(dim as f64 / 2.0);
        Ok(Self { sigma, norm })
    }

    /// The kernel at parameter `q` around the centre `c` (the first `q.len()` entries).
    pub(crate) fn at(&self, q: &[f64], c: &[f64]) -> f64 {
        let d2: f64 = q.iter().zip(c).map(|(a, b)| (a - b).powi(2)).sum();
        (-d2 / (2.0 * self.sigma * self.sigma)).exp() / self.norm
    }
}

/// Time integration scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// `d-nurbs.txt` eq (18) with time step `dt`.
    Implicit {
        /// Time step.
        dt: f64,
    },
    /// Static equilibrium `K p = f_p` (mu = gamma = 0, footnote 6: a shape optimizer).
    Static,
}

/// What the elastic energy measures deformation against.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ElasticReference {
    /// `U = 1/2 (p - p_rest)^T K (p - p_rest)`: the shape at construction (or at the last
    /// [`Dnurbs::set_rest_shape_to_current`], the plastic reset) is at rest, so a model left alone
    /// keeps its shape. vclay's default.
    #[default]
    RestShape,
    /// `U = 1/2 p^T K p`, the paper's form (eq 15): the energy is the thin-plate-under-tension
    /// functional of the shape itself, so without forces or constraints the shape shrinks towards
    /// minimal area and bending (fairing). Use it for fitting and fairness optimization.
    Absolute,
}

/// How each step's linear system is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// Sparse Cholesky of the reduced system, factored once and reused while the time step,
    /// springs and fixed set are unchanged (frozen weights make the matrix constant). Default.
    #[default]
    Direct,
    /// Jacobi-preconditioned conjugate gradients, element by element without assembly
    /// (`d-nurbs.txt` section 5.3), with [`Dnurbs::max_iterations`] and [`Dnurbs::tolerance`].
    ConjugateGradient,
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Simulated time after the step.
    pub time: f64,
    /// Linear solve statistics.
    pub solver: SolverStats,
    /// Kinetic energy `1/2 v^T M v` after the step ([`GeneralizedDnurbs`]: of the state the
    /// step started from, like its elastic energy, both integrated during assembly).
    pub kinetic_energy: f64,
    /// Elastic energy `1/2 p^T K p` after the step.
    pub elastic_energy: f64,
}

/// The plastic flow's arguments of both engines ([`Dnurbs::plastic_flow`],
/// [`GeneralizedDnurbs::plastic_flow`]), checked by `vclay_core::plasticity::check_flow`;
/// the error names the first bad one.
fn check_flow_args(fraction: f64, yield_distance: f64) -> Result<(), DynamicsError> {
    if vclay_core::plasticity::check_flow(fraction, yield_distance).is_ok() {
        return Ok(());
    }
    let (name, value) = if (0.0..=1.0).contains(&fraction) {
        ("yield distance", yield_distance)
    } else {
        ("plastic flow fraction", fraction)
    };
    Err(DynamicsError::Parameter {
        name,
        value,
        why: "fraction in [0, 1], yield distance finite and non-negative",
    })
}

/// A D-NURBS with frozen weights over a geometry `G` (curve or tensor-product surface).
#[derive(Clone, Debug)]
pub struct Dnurbs<G: DnurbsGeometry> {
    geometry: G,
    material: Material,
    samples: Vec<ElementSamples>,
    system: ElementSystem,
    previous: Vec<Vec3>,
    rest: Vec<Vec3>,
    reference: ElasticReference,
    rest_scale: f64,
    fixed: Vec<bool>,
    forces: Vec<Force>,
    time: f64,
    steps: usize,
    /// CG iteration cap (default [`DEFAULT_CG_ITERATIONS`]; the paper used
    /// [`PAPER_CG_ITERATIONS`]).
    pub max_iterations: usize,
    /// CG relative residual tolerance (default [`DEFAULT_CG_TOLERANCE`]).
    pub tolerance: f64,
    /// Linear solver (default [`LinearSolver::Direct`]).
    pub solver: LinearSolver,
    /// With [`LinearSolver::Direct`]: solve the three coordinate columns (`x`, `y`, `z`) with
    /// the cached factor in one call on one thread, one pass over the factor, instead of the
    /// default split (`x` on one thread, `y` and `z` on another, for models with at least
    /// 1,024 free control points). Default `false`, the path every recorded
    /// trajectory was computed with: faer's kernels for three columns round differently from
    /// those for one and two, so the steps differ in the last bits (tested within `1e-12` of
    /// the model size over 100 steps). Issue 31: on the shared 2-core host it saved about
    /// 0.3 ms of CPU time per step of the 64 x 64 frozen sheet, and its steps per second were
    /// higher in 9 of 12 alternated pairs, within the host's noise (`docs/performance.md`,
    /// session h47).
    pub solve_together: bool,
    direct: Option<system::DirectSolver>,
    cache: StepCache,
}

/// Products carried from one step to the next, so that a frozen-weight step makes a single
/// pass over the assembled matrices: the end-of-step pass at the new points gives `M x`,
/// `D x` (and `K x` for the residual, and both energies), and the next step's right-hand side
/// `M (4 p - 2 p_prev) + dt D p_prev` is a combination of those and the previous step's.
#[derive(Clone, Debug, Default)]
struct StepCache {
    /// `K p_rest` (without the coefficient) while the rest shape is unchanged.
    k_rest: Option<Vec<Vec3>>,
    /// `[M p, D p, M p_prev, D p_prev]` for the current and previous points, while neither
    /// has changed outside [`Dnurbs::step`].
    products: Option<[Vec<Vec3>; 4]>,
}

/// The evolving state of a frozen-weight [`Dnurbs`] ([`Dnurbs::state`]): the control points
/// `p(t)` and `p(t - dt)` of eq (18), the rest shape, the fixed points, the counters, and the
/// matrix products `[M p, D p, M p_prev, D p_prev]` the last step left for the next one's
/// right-hand side (recomputing them in another order could change the last bit, so they are
/// part of the state).
#[derive(Clone, Debug, PartialEq)]
pub struct DnurbsState {
    /// Control points `p(t)`.
    pub points: Vec<Vec3>,
    /// Control points of the previous step `p(t - dt)`.
    pub previous: Vec<Vec3>,
    /// Rest shape.
    pub rest: Vec<Vec3>,
    /// Elastic reference.
    pub reference: ElasticReference,
    /// Fixed control points.
    pub fixed: Vec<bool>,
    /// Simulated time.
    pub time: f64,
    /// Steps taken.
    pub steps: usize,
    /// `[M p, D p, M p_prev, D p_prev]` carried to the next step (`None`: computed then).
    pub products: Option<[Vec<Vec3>; 4]>,
}

/// A dynamic NURBS curve.
pub type DnurbsCurve = Dnurbs<NurbsCurve>;
/// A dynamic tensor-product NURBS surface.
pub type DnurbsSurface = Dnurbs<NurbsSurface>;
/// A dynamic closed (periodic) curve.
pub type DnurbsClosedCurve = Dnurbs<ClosedCurve>;

impl<G: DnurbsGeometry> Dnurbs<G> {
    /// Distances from each data point of the [`Force::DataPoint`] forces to the geometry.
    pub fn data_distances(&self) -> Result<Vec<f64>, DynamicsError> {
        let mut out = Vec::new();
        for f in &self.forces {
            if let Force::DataPoint { point, .. } = f {
                let prm = self.geometry.nearest_param(point)?;
                let (_, _, x) = self.geometry.basis_at(&prm[..G::DIM])?;
                out.push((x - point).norm());
            }
        }
        Ok(out)
    }
}

impl<G: DnurbsGeometry> Dnurbs<G> {
    /// Builds the model: element samples and matrices are computed once (frozen weights).
    pub fn new(geometry: G, material: Material) -> Result<Self, DynamicsError> {
        Self::with_quadrature(geometry, material, QuadratureRule::default())
    }

    /// [`Dnurbs::new`] with a chosen quadrature rule (issue 18). The weights are frozen, so
    /// one Gauss order serves the whole model: [`QuadratureRule::Fixed`] takes the paper's
    /// `max(p, 3) + 1` points per direction; [`QuadratureRule::WeightAware`] (the default of
    /// `new`) the largest order it picks over the elements for the model's weights (the fixed
    /// order when the weights are uniform, so polynomial models are unchanged).
    pub fn with_quadrature(
        geometry: G,
        material: Material,
        rule: QuadratureRule,
    ) -> Result<Self, DynamicsError> {
        rule.validate()?;
        let fixed = geometry.max_degree().max(3) + 1;
        let ng = match (rule, geometry.rational()) {
            (QuadratureRule::Fixed, _) | (_, None) => fixed,
            (QuadratureRule::Points(n), _) => n,
            (r, Some(g)) => generalized::largest_order(&g, r).max(fixed),
        };
        let gauss = GaussLegendre::new(ng).map_err(|_| DynamicsError::Parameter {
            name: "degree",
            value: geometry.max_degree() as f64,
            why: "too high for the quadrature table",
        })?;
        let samples = geometry.element_samples(&gauss);
        let ne = samples.len();
        if material.alpha.len() != G::DIM || material.beta.len() != G::PAIRS {
            return Err(DynamicsError::Parameter {
                name: "alpha/beta count",
                value: material.alpha.len() as f64,
                why: "curves take 1 alpha and 1 beta, surfaces 2 alphas and 3 betas",
            });
        }
        material.mu.validate("mu", ne)?;
        material.gamma.validate("gamma", ne)?;
        for a in &material.alpha {
            a.validate("alpha", ne)?;
        }
        for b in &material.beta {
            b.validate("beta", ne)?;
        }
        let system = build_system::<G>(&geometry, &material, &samples)?;
        let points = geometry.points().to_vec();
        let rest_scale = vclay_core::math::max_abs_coordinate(&points).max(1.0);
        let n = points.len();
        Ok(Self {
            geometry,
            material,
            samples,
            system,
            previous: points.clone(),
            rest: points,
            reference: ElasticReference::default(),
            rest_scale,
            fixed: vec![false; n],
            forces: Vec::new(),
            time: 0.0,
            steps: 0,
            max_iterations: DEFAULT_CG_ITERATIONS,
            tolerance: DEFAULT_CG_TOLERANCE,
            solver: LinearSolver::default(),
            solve_together: false,
            direct: None,
            cache: StepCache::default(),
        })
    }

    /// The current geometry.
    pub fn geometry(&self) -> &G {
        &self.geometry
    }
    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }
    /// The element matrices.
    pub fn system(&self) -> &ElementSystem {
        &self.system
    }
    /// Simulated time.
    pub fn time(&self) -> f64 {
        self.time
    }
    /// What the elastic energy is measured against.
    pub fn elastic_reference(&self) -> ElasticReference {
        self.reference
    }

    /// Chooses what the elastic energy is measured against.
    pub fn set_elastic_reference(&mut self, reference: ElasticReference) {
        self.reference = reference;
    }

    /// Steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The applied forces.
    pub fn forces(&self) -> &[Force] {
        &self.forces
    }

    /// Replaces the material: the element matrices of eqs (16)-(17) are integrated again
    /// (validated as in [`Dnurbs::new`]); the state (points, previous points, rest, fixed
    /// points, time) is kept, the carried products and the factorization are dropped. On error
    /// the model is unchanged.
    pub fn set_material(&mut self, material: Material) -> Result<(), DynamicsError> {
        let ne = self.samples.len();
        if material.alpha.len() != G::DIM || material.beta.len() != G::PAIRS {
            return Err(DynamicsError::Parameter {
                name: "alpha/beta count",
                value: material.alpha.len() as f64,
                why: "curves take 1 alpha and 1 beta, surfaces 2 alphas and 3 betas",
            });
        }
        material.mu.validate("mu", ne)?;
        material.gamma.validate("gamma", ne)?;
        for a in &material.alpha {
            a.validate("alpha", ne)?;
        }
        for b in &material.beta {
            b.validate("beta", ne)?;
        }
        self.system = build_system::<G>(&self.geometry, &material, &self.samples)?;
        self.material = material;
        self.direct = None;
        self.cache = StepCache::default();
        Ok(())
    }

    /// Stops the motion: the previous points become the current ones (zero velocity in eq 18;
    /// the carried products are updated exactly: `M p_prev = M p`, `D p_prev = D p`).
    pub fn stop(&mut self) {
        self.previous = self.geometry.points().to_vec();
        if let Some([mp, dp, mpp, dpp]) = &mut self.cache.products {
            mpp.clone_from(mp);
            dpp.clone_from(dp);
        }
    }

    /// A copy of the evolving state: with [`Dnurbs::set_state`] on a model built from the same
    /// initial geometry and material, with the same forces, the continued simulation is bit
    /// for bit the same.
    pub fn state(&self) -> DnurbsState {
        DnurbsState {
            points: self.geometry.points().to_vec(),
            previous: self.previous.clone(),
            rest: self.rest.clone(),
            reference: self.reference,
            fixed: self.fixed.clone(),
            time: self.time,
            steps: self.steps,
            products: self.cache.products.clone(),
        }
    }

    /// Puts back a state taken by [`Dnurbs::state`]. Checked first (lengths, finite values);
    /// on error the model is unchanged.
    pub fn set_state(&mut self, s: &DnurbsState) -> Result<(), DynamicsError> {
        let n = self.fixed.len();
        let mut lens = vec![
            s.points.len(),
            s.previous.len(),
            s.rest.len(),
            s.fixed.len(),
        ];
        if let Some(p) = &s.products {
            lens.extend(p.iter().map(Vec::len));
        }
        if let Some(&bad) = lens.iter().find(|&&l| l != n) {
            return Err(DynamicsError::NoSuchControlPoint {
                index: bad,
                count: n,
            });
        }
        let all = s
            .previous
            .iter()
            .chain(&s.rest)
            .chain(s.products.iter().flatten().flatten());
        for v in all {
            if let Some(&x) = v.iter().find(|x| !x.is_finite()) {
                return Err(DynamicsError::Parameter {
                    name: "state",
                    value: x,
                    why: "must be finite",
                });
            }
        }
        if !s.time.is_finite() {
            return Err(DynamicsError::Parameter {
                name: "time",
                value: s.time,
                why: "must be finite",
            });
        }
        let mut geometry = self.geometry.clone();
        geometry.set_points(s.points.clone())?;
        self.geometry = geometry;
        if self.rest != s.rest {
            self.cache.k_rest = None;
        }
        self.previous = s.previous.clone();
        self.rest = s.rest.clone();
        self.reference = s.reference;
        self.fixed = s.fixed.clone();
        self.time = s.time;
        self.steps = s.steps;
        self.cache.products = s.products.clone();
        Ok(())
    }

    /// Plastic reset: the current shape becomes the rest shape.
    pub fn set_rest_shape_to_current(&mut self) {
        self.rest = self.geometry.points().to_vec();
        self.cache.k_rest = None;
    }

    /// The rest shape's control points.
    pub fn rest_shape(&self) -> &[Vec3] {
        &self.rest
    }

    /// Replaces the rest shape's control points (the smooth brush's smoothed rest shape).
    /// With frozen weights the surface is linear in its control points, `s = J p`, so the rest
    /// shape enters the step only through `K p_rest` (eq 17 with `s_ref = J p_rest`), which
    /// is recomputed on the next step; the shape, its motion and the matrices stay.
    ///
    /// # Errors
    /// [`DynamicsError::NoSuchCoordinate`] for a wrong count, [`DynamicsError::Parameter`]
    /// for a non-finite coordinate.
    pub fn set_rest_shape(&mut self, rest: &[Vec3]) -> Result<(), DynamicsError> {
        if rest.len() != self.rest.len() {
            return Err(DynamicsError::NoSuchCoordinate {
                index: rest.len(),
                count: self.rest.len(),
            });
        }
        if let Some(v) = rest
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .find(|v| !v.is_finite())
        {
            return Err(DynamicsError::Parameter {
                name: "rest shape coordinate",
                value: v,
                why: "must be finite",
            });
        }
        self.rest = rest.to_vec();
        self.cache.k_rest = None;
        Ok(())
    }

    /// Plastic flow (`vclay_core::plasticity`, the studio's sculpt mode): every control point
    /// displaced from its rest position by more than `yield_distance` moves its rest position
    /// towards it by `fraction x (1 - yield / displacement)` of the displacement, as
    /// [`GeneralizedDnurbs::plastic_flow`] does per control point. Returns how many yielded.
    ///
    /// # Errors
    /// [`DynamicsError::Parameter`] for a fraction outside `[0, 1]` or a negative or
    /// non-finite yield distance.
    pub fn plastic_flow(
        &mut self,
        fraction: f64,
        yield_distance: f64,
    ) -> Result<usize, DynamicsError> {
        check_flow_args(fraction, yield_distance)?;
        let mut yielded = 0;
        for (r, p) in self.rest.iter_mut().zip(self.geometry.points()) {
            let f = vclay_core::plasticity::plastic_flow_factor(
                fraction,
                yield_distance,
                (*p - *r).norm(),
            );
            if f > 0.0 {
                *r += (*p - *r) * f;
                yielded += 1;
            }
        }
        if yielded > 0 {
            self.cache.k_rest = None;
        }
        Ok(yielded)
    }

    /// Moves control point `i` to `position` (it keeps its fixed/free state; a fixed point stays
    /// at the new place). The velocity of the point is set to zero.
    pub fn move_control_point(&mut self, i: usize, position: Vec3) -> Result<(), DynamicsError> {
        let count = self.fixed.len();
        if i >= count {
            return Err(DynamicsError::NoSuchControlPoint { index: i, count });
        }
        let mut pts = self.geometry.points().to_vec();
        pts[i] = position;
        self.cache.products = None;
        self.geometry.set_points(pts)?;
        self.previous[i] = position;
        Ok(())
    }

    /// Applied forces (edit freely between steps).
    pub fn forces_mut(&mut self) -> &mut Vec<Force> {
        &mut self.forces
    }

    /// Fixes control point `i` at its current position (or frees it).
    pub fn set_fixed(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError> {
        let count = self.fixed.len();
        *self
            .fixed
            .get_mut(i)
            .ok_or(DynamicsError::NoSuchControlPoint { index: i, count })? = fixed;
        Ok(())
    }

    /// Whether control point `i` is fixed.
    pub fn is_fixed(&self, i: usize) -> bool {
        self.fixed.get(i).copied().unwrap_or(false)
    }

    /// Generalized force `f_p = integral J^T f` at the current time and shape.
    pub fn generalized_force(&self) -> Result<Vec<Vec3>, DynamicsError> {
        let (mut fp, springs) = self.split_forces()?;
        // Add back the implicit part -k J^T J p of the delta springs.
        let p = self.geometry.points();
        for s in &springs {
            let mut x = Vec3::zeros();
            for (&i, &r) in s.indices.iter().zip(&s.values) {
                x += p[i] * r;
            }
            for (&i, &r) in s.indices.iter().zip(&s.values) {
                fp[i] -= x * (s.k * r);
            }
        }
        Ok(fp)
    }

    /// The explicit part of the generalized force, and the delta springs as rank-one stiffness
    /// terms (their `k J^T d0` part is in the explicit force).
    fn split_forces(&self) -> Result<(Vec<Vec3>, Vec<system::RankOne>), DynamicsError> {
        let mut springs = Vec::new();
        let n = self.system.n;
        let mut fp = vec![Vec3::zeros(); n];
        let pts = self.geometry.points();
        for force in &self.forces {
            match force {
                Force::Spring {
                    param,
                    target,
                    stiffness,
                    kernel: None,
                } => {
                    if !(stiffness.is_finite() && *stiffness >= 0.0) {
                        return Err(DynamicsError::Parameter {
                            name: "spring stiffness",
                            value: *stiffness,
                            why: "must be finite and non-negative",
                        });
                    }
                    let (idx, r, _) = self.geometry.basis_at(&param[..G::DIM])?;
                    let f = target.at(self.time) * *stiffness;
                    for (&i, &ri) in idx.iter().zip(&r) {
                        fp[i] += f * ri;
                    }
                    springs.push(system::RankOne {
                        indices: idx,
                        values: r,
                        k: *stiffness,
                    });
                }
                Force::Spring {
                    param,
                    target,
                    stiffness,
                    kernel: Some(sigma),
                } => {
                    let kernel = SpringKernel::new(*sigma, G::DIM)?;
                    let d0 = target.at(self.time);
                    self.integrate_force(&mut fp, |q, s, _| {
                        (d0 - s) * (stiffness * kernel.at(&q[..G::DIM], param))
                    });
                }
                Force::DataPoint { point, stiffness } => {
                    if !(stiffness.is_finite() && *stiffness >= 0.0) {
                        return Err(DynamicsError::Parameter {
                            name: "data spring stiffness",
                            value: *stiffness,
                            why: "must be finite and non-negative",
                        });
                    }
                    let prm = self.geometry.nearest_param(point)?;
                    let (idx, r, _) = self.geometry.basis_at(&prm[..G::DIM])?;
                    for (&i, &ri) in idx.iter().zip(&r) {
                        fp[i] += point * (stiffness * ri);
                    }
                    springs.push(system::RankOne {
                        indices: idx,
                        values: r,
                        k: *stiffness,
                    });
                }
                Force::Point { param, force } => {
                    let (idx, r, _) = self.geometry.basis_at(&param[..G::DIM])?;
                    for (&i, &ri) in idx.iter().zip(&r) {
                        fp[i] += force * ri;
                    }
                }
                Force::Gravity(g) => {
                    let mu = &self.material.mu;
                    let mut e = 0;
                    // Row sums of M times g (partition of unity): sum_j M_ij = integral mu R_i.
                    for (el, s) in self.samples.iter().enumerate() {
                        let nd = s.dofs.len();
                        for (q, (&prm, &w)) in s.params.iter().zip(&s.weights).enumerate() {
                            let m = mu.eval(el, prm) * w;
                            for a in 0..nd {
                                fp[s.dofs[a]] += g * (m * s.values[q * nd + a]);
                            }
                        }
                        e += 1;
                    }
                    debug_assert_eq!(e, self.samples.len());
                }
                Force::Inflation(pressure) => {
                    if G::DIM == 2 {
                        self.integrate_force(&mut fp, |_, _, n| n * *pressure);
                    }
                }
                Force::Repulsion {
                    center,
                    strength,
                    core,
                } => {
                    if G::DIM != 2 {
                        return Err(DynamicsError::Parameter {
                            name: "repulsion",
                            value: *strength,
                            why: "the frozen-weight engine applies repulsion to surfaces only (use the generalized engine for curves)",
                        });
                    }
                    self.integrate_force(&mut fp, |_, x, n| {
                        repulsion_density(x, *center, *strength, *core) * n.norm()
                    });
                }
            }
        }
        let _ = pts;
        Ok((fp, springs))
    }

    /// Adds `integral J^T f(q, s(q), s_u x s_v)` over all elements.
    fn integrate_force(&self, fp: &mut [Vec3], f: impl Fn([f64; 2], Vec3, Vec3) -> Vec3) {
        let pts = self.geometry.points();
        for s in &self.samples {
            let nd = s.dofs.len();
            for (q, (&prm, &w)) in s.params.iter().zip(&s.weights).enumerate() {
                let r = &s.values[q * nd..(q + 1) * nd];
                let mut x = Vec3::zeros();
                for a in 0..nd {
                    x += pts[s.dofs[a]] * r[a];
                }
                let normal = if G::DIM == 2 {
                    let (mut su, mut sv) = (Vec3::zeros(), Vec3::zeros());
                    for a in 0..nd {
                        su += pts[s.dofs[a]] * s.first[(q * 2) * nd + a];
                        sv += pts[s.dofs[a]] * s.first[(q * 2 + 1) * nd + a];
                    }
                    su.cross(&sv)
                } else {
                    Vec3::zeros()
                };
                let fv = f(prm, x, normal) * w;
                for a in 0..nd {
                    fp[s.dofs[a]] += fv * r[a];
                }
            }
        }
    }

    /// Elastic energy `1/2 (p - p_ref)^T K (p - p_ref)` with `p_ref` the rest shape or zero
    /// (see [`ElasticReference`]).
    pub fn elastic_energy(&self) -> f64 {
        let p = self.geometry.points();
        let d: Vec<Vec3> = match self.reference {
            ElasticReference::RestShape => p.iter().zip(&self.rest).map(|(a, b)| a - b).collect(),
            ElasticReference::Absolute => p.to_vec(),
        };
        0.5 * self.system.quadratic_form([0.0, 0.0, 1.0], &d, &d)
    }

    /// Kinetic energy `1/2 v^T M v` with the backward-difference velocity of the last step `dt`.
    pub fn kinetic_energy(&self, dt: f64) -> f64 {
        let p = self.geometry.points();
        let v: Vec<Vec3> = p
            .iter()
            .zip(&self.previous)
            .map(|(a, b)| (a - b) / dt)
            .collect();
        0.5 * self.system.quadratic_form([1.0, 0.0, 0.0], &v, &v)
    }

    /// Advances one step with `integrator`.
    ///
    /// One pass over the assembled `M`, `D`, `K` per step (plus the solve): the right-hand side
    /// comes from products the previous step's end-of-step pass left (`StepCache`), and that
    /// pass gives the residual check and both energies too.
    pub fn step(&mut self, integrator: Integrator) -> Result<StepReport, DynamicsError> {
        let n = self.system.n;
        let (fp, springs) = self.split_forces()?;
        let p = self.geometry.points().to_vec();
        // [M p, D p, M p_prev, D p_prev], from the last step or computed now.
        let products = match self.cache.products.take() {
            Some(c) => c,
            None => {
                let mut c: [Vec<Vec3>; 4] = std::array::from_fn(|_| vec![Vec3::zeros(); n]);
                let [mp, dp, mpp, dpp] = &mut c;
                self.system.mass_damping_products(&p, mp, dp);
                self.system.mass_damping_products(&self.previous, mpp, dpp);
                c
            }
        };
        let (coeffs, mut rhs, mut x, dt) = match integrator {
            Integrator::Implicit { dt } => {
                if !(dt.is_finite() && dt > 0.0) {
                    return Err(DynamicsError::Parameter {
                        name: "dt",
                        value: dt,
                        why: "time step must be positive and finite",
                    });
                }
                let coeffs = [2.0, dt, 2.0 * dt * dt];
                // M (4p - 2p_prev) + dt D p_prev + 2 dt^2 f_p.
                let [mp, _, mpp, dpp] = &products;
                let rhs: Vec<Vec3> = (0..n)
                    .map(|i| mp[i] * 4.0 - mpp[i] * 2.0 + dpp[i] * dt + fp[i] * (2.0 * dt * dt))
                    .collect();
                // Initial guess: constant-velocity extrapolation (fixed points stay).
                let x: Vec<Vec3> = (0..n)
                    .map(|i| {
                        if self.fixed[i] {
                            p[i]
                        } else {
                            p[i] * 2.0 - self.previous[i]
                        }
                    })
                    .collect();
                (coeffs, rhs, x, dt)
            }
            Integrator::Static => ([0.0, 0.0, 1.0], fp.clone(), p.clone(), 1.0),
        };
        if self.reference == ElasticReference::RestShape {
            // K (p - p_rest) on the left: K p_rest moves to the right-hand side.
            let k_rest = self.cache.k_rest.get_or_insert_with(|| {
                let mut k = vec![Vec3::zeros(); n];
                self.system.apply([0.0, 0.0, 1.0], &self.rest, &mut k);
                k
            });
            for (r, k) in rhs.iter_mut().zip(k_rest.iter()) {
                *r += k * coeffs[2];
            }
        }
        let op = system::Operator {
            sys: &self.system,
            coeffs,
            springs: &springs,
        };
        let mut solver = match self.solver {
            LinearSolver::ConjugateGradient => system::conjugate_gradient(
                &op,
                &rhs,
                &mut x,
                &self.fixed,
                self.max_iterations,
                self.tolerance,
            ),
            LinearSolver::Direct => system::direct_solve(
                &mut self.direct,
                &op,
                &rhs,
                &mut x,
                &self.fixed,
                false,
                self.solve_together,
            )
            .map_err(|_| DynamicsError::Singular {
                what: "the system matrix is not positive definite: with no mass (static \
                       solve), fix control points so that rigid motions are excluded"
                    .into(),
            })?,
        };
        // Divergence: non-finite state or runaway displacement.
        let limit = DIVERGENCE_DISPLACEMENT_FACTOR * self.rest_scale;
        let bad = x
            .iter()
            .enumerate()
            .find(|(_, v)| !v.iter().all(|c| c.is_finite()) || v.amax() > limit);
        if let Some((i, v)) = bad {
            let what = if v.iter().all(|c| c.is_finite()) {
                format!("control point {i} moved to {v:?}, beyond {limit:.1e}")
            } else {
                format!("control point {i} became non-finite")
            };
            return Err(DynamicsError::Diverged {
                step: self.steps,
                time: self.time,
                what,
                suggested_dt: self.suggest_dt(dt),
            });
        }
        // The end-of-step pass: M x, D x, K x and the energy forms.
        let is_static = matches!(integrator, Integrator::Static);
        let [mut mx, mut dx, mut kx] = std::array::from_fn(|_| vec![Vec3::zeros(); n]);
        let rest = (self.reference == ElasticReference::RestShape).then_some(&self.rest[..]);
        let (mass_form, stiffness_form) = self.system.step_products(
            system::StepInputs {
                x: &x,
                p: if is_static { &x } else { &p },
                inv_dt: if is_static { 0.0 } else { 1.0 / dt },
                rest,
            },
            system::StepOutputs {
                mx: &mut mx,
                dx: &mut dx,
                kx: &mut kx,
            },
        );
        if matches!(self.solver, LinearSolver::Direct) {
            // A x from the pass: a_m M x + a_d D x + a_k K x + springs.
            let mut ax: Vec<Vec3> = (0..n)
                .map(|i| mx[i] * coeffs[0] + dx[i] * coeffs[1] + kx[i] * coeffs[2])
                .collect();
            op.add_springs(&x, &mut ax);
            solver.relative_residual = system::relative_residual(&rhs, &ax, &self.fixed);
        }
        self.geometry.set_points(x)?;
        let [mp, dp, _, _] = products;
        self.cache.products = Some(if is_static {
            [mx.clone(), dx.clone(), mx, dx]
        } else {
            [mx, dx, mp, dp]
        });
        self.previous = if is_static {
            self.geometry.points().to_vec()
        } else {
            p
        };
        self.time += if let Integrator::Implicit { dt } = integrator {
            dt
        } else {
            0.0
        };
        self.steps += 1;
        Ok(StepReport {
            time: self.time,
            solver,
            kinetic_energy: 0.5 * mass_form,
            elastic_energy: 0.5 * stiffness_form,
        })
    }

    /// Runs `steps` implicit steps of `dt`, returning the last report.
    pub fn run(&mut self, dt: f64, steps: usize) -> Result<Option<StepReport>, DynamicsError> {
        let mut last = None;
        for _ in 0..steps {
            last = Some(self.step(Integrator::Implicit { dt })?);
        }
        Ok(last)
    }

    /// A time step expected to be stable for the explicit (kernel) spring forces: half of the
    /// central-difference limit `2 sqrt(m / k)` with `m` the smallest lumped mass. Delta springs
    /// are implicit and do not limit the step.
    fn suggest_dt(&self, dt: f64) -> f64 {
        let k: f64 = self
            .forces
            .iter()
            .map(|f| match f {
                Force::Spring {
                    stiffness,
                    kernel: Some(_),
                    ..
                } => *stiffness,
                _ => 0.0,
            })
            .sum();
        let lumped = self.system.dense_row_sums_mass();
        let m = lumped
            .iter()
            .copied()
            .filter(|&x| x > 0.0)
            .fold(f64::INFINITY, f64::min);
        if k > 0.0 && m.is_finite() {
            (m / k).sqrt().min(dt / 4.0)
        } else {
            dt / 4.0
        }
    }
}

impl ElementSystem {
    /// Row sums of the mass matrix (lumped masses).
    pub fn dense_row_sums_mass(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        for e in &self.elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                out[e.dofs[a]] += e.mass[a * nd..(a + 1) * nd].iter().sum::<f64>();
            }
        }
        out
    }
}

fn build_system<G: DnurbsGeometry>(
    geometry: &G,
    material: &Material,
    samples: &[ElementSamples],
) -> Result<ElementSystem, DynamicsError> {
    use rayon::prelude::*;
    let elements: Vec<Element> = samples
        .par_iter()
        .enumerate()
        .map(|(el, s)| {
            let mut alpha = vec![0.0; G::DIM];
            let mut beta = vec![0.0; G::PAIRS];
            Element::integrate(s, G::DIM, G::PAIRS, |_, prm, sink| {
                for (a, d) in alpha.iter_mut().zip(&material.alpha) {
                    *a = d.eval(el, prm);
                }
                for (b, d) in beta.iter_mut().zip(&material.beta) {
                    *b = d.eval(el, prm);
                }
                sink(system::PointDensities {
                    mu: material.mu.eval(el, prm),
                    gamma: material.gamma.eval(el, prm),
                    alpha: &alpha,
                    beta: &beta,
                });
            })
        })
        .collect();
    // Closures may return anything: check the integrated matrices.
    for (i, e) in elements.iter().enumerate() {
        if e.mass
            .iter()
            .chain(&e.damping)
            .chain(&e.stiffness)
            .any(|v| !v.is_finite())
        {
            return Err(DynamicsError::Parameter {
                name: "density function",
                value: i as f64,
                why: "produced a non-finite element matrix (value is the element index)",
            });
        }
    }
    Ok(ElementSystem::new(geometry.control_point_count(), elements))
}
