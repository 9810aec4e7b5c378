//! A compiled PDE surface patch: boundary basic functions and coefficients, shape functions,
//! density, damping, trial functions, collocation grid, side conditions and local deformations.
//!
//! `dynamic-pde-surfaces.txt` eq (1): for each component i = x, y, z,
//! `[b_i d4/du4 + c_i d4/du2dv2 + d_i d4/dv4 + rho d2/dt2 + eta d/dt] x_i(u, v, t) = 0`
//! on `0 <= u <= 1`, `v0 <= v <= v1`, with the boundary conditions (2) written as sums of basic
//! functions (3). A [`PdePatch`] is built from a spec ([`crate::spec`]) and solved at any t by
//! [`crate::Solver`].

use crate::error::PdeError;
use crate::expr::{Expr, Var};
use crate::spectral::Method;
use crate::trial::{PatchKind, TrialBasis, TrialTable};

/// A coefficient field of (u, v, t): a constant (fast path) or an expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Field {
    /// A constant.
    Const(f64),
    /// A function of u, v and t.
    Expr(Expr),
}

impl Field {
    /// Builds a field from an expression, folding constants.
    pub fn from_expr(e: Expr) -> Self {
        match e.as_number() {
            Some(x) => Field::Const(x),
            None => Field::Expr(e),
        }
    }

    /// Value at (u, v, t).
    #[inline]
    pub fn eval(&self, u: f64, v: f64, t: f64) -> f64 {
        match self {
            Field::Const(x) => *x,
            Field::Expr(e) => e.eval(u, v, t),
        }
    }

    /// The constant, if the field is one.
    pub fn as_const(&self) -> Option<f64> {
        match self {
            Field::Const(x) => Some(*x),
            Field::Expr(_) => None,
        }
    }

    /// Whether the field depends on t.
    pub fn depends_on_time(&self) -> bool {
        match self {
            Field::Const(_) => false,
            Field::Expr(e) => e.depends_on(Var::T),
        }
    }
}

/// A basic function g_ij(v, t) of eq (3) with the exact derivatives the method needs (eq 7-8).
#[derive(Clone, Debug, PartialEq)]
pub struct BasicFunction {
    /// Text of g (for messages and reports).
    pub name: String,
    /// g(v, t).
    pub g: Expr,
    /// dg/dv (surface normals, side tangents).
    pub g_v: Expr,
    /// d2g/dv2.
    pub g_vv: Expr,
    /// d4g/dv4.
    pub g_vvvv: Expr,
    /// dg/dt.
    pub g_t: Expr,
    /// d2g/dt2.
    pub g_tt: Expr,
}

impl BasicFunction {
    /// Differentiates `g` symbolically. Unbounded (see [`Expr::derivative`]); use
    /// [`BasicFunction::try_new`] for functions that come from a file.
    pub fn new(g: Expr) -> Self {
        let g_v = g.derivative(Var::V);
        let g_vv = g_v.derivative(Var::V);
        let g_vvvv = g_vv.nth_derivative(Var::V, 2);
        let g_t = g.derivative(Var::T);
        let g_tt = g_t.derivative(Var::T);
        BasicFunction {
            name: g.to_string(),
            g,
            g_v,
            g_vv,
            g_vvvv,
            g_t,
            g_tt,
        }
    }

    /// [`BasicFunction::new`] with every derivative's size bounded first
    /// ([`Expr::try_derivative`]).
    pub fn try_new(g: Expr) -> Result<Self, crate::expr::ExprError> {
        let g_v = g.try_derivative(Var::V)?;
        let g_vv = g_v.try_derivative(Var::V)?;
        let g_vvvv = g_vv.try_nth_derivative(Var::V, 2)?;
        let g_t = g.try_derivative(Var::T)?;
        let g_tt = g_t.try_derivative(Var::T)?;
        Ok(BasicFunction {
            name: g.to_string(),
            g,
            g_v,
            g_vv,
            g_vvvv,
            g_t,
            g_tt,
        })
    }
}

/// The shape functions b_i, c_i, d_i of one component (eq 1, 29).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeFunctions {
    /// b_i, the coefficient of d4/du4.
    pub b: Field,
    /// c_i, the coefficient of d4/du2dv2.
    pub c: Field,
    /// d_i, the coefficient of d4/dv4.
    pub d: Field,
}

/// One side condition as a polynomial in u with coefficients depending on t (eq 34).
#[derive(Clone, Debug, PartialEq)]
pub struct SideCondition {
    /// Field path (for messages).
    pub place: String,
    /// Coefficient functions of t for u^0, u^1, ... (eq 34's b_ink(t)).
    pub coefficients: Vec<Expr>,
}

/// Conditions on the sides v = v0 and v = v1 of a three- or four-sided patch (eq 33).
///
/// The paper's eq (33) prints `dx_i/du` for the side tangents; on a side v = const the
/// cross-boundary tangent is `dx_i/dv` (the derivative along the side, d/du, is already fixed by
/// the position condition), which is what is used here.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sides {
    /// x_i(u, v0, t).
    pub v0: Option<SideCondition>,
    /// dx_i/dv(u, v0, t).
    pub dv0: Option<SideCondition>,
    /// x_i(u, v1, t).
    pub v1: Option<SideCondition>,
    /// dx_i/dv(u, v1, t).
    pub dv1: Option<SideCondition>,
}

impl Sides {
    /// Whether any side condition is given.
    pub fn any(&self) -> bool {
        self.v0.is_some() || self.dv0.is_some() || self.v1.is_some() || self.dv1.is_some()
    }
}

/// One position component x_i of a patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Component {
    /// The basic functions g_ij, j = 1..J (eq 3).
    pub basics: Vec<BasicFunction>,
    /// a_ijk: coefficient of basic j in condition k (x(0), x_u(0), x(1), x_u(1); only the first
    /// two for a three-sided patch).
    pub coefficients: Vec<[f64; 4]>,
    /// Shape functions.
    pub shape: ShapeFunctions,
    /// Side conditions (empty for an ordinary patch).
    pub sides: Sides,
}

/// Continuity of a local deformation with the surrounding surface (section VI-A).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Continuity {
    /// Position only: eq (31), weight `w = ub(1-ub) vb(1-vb)`.
    G0,
    /// Position and tangent: eq (32), weight `w^2`.
    G1,
}

/// A local deformation (section VI-A): the term `w(ub, vb)^k p_i(u, v, t)` added to the surface
/// in `u1 < u < u2`, `v1 < v < v2`, with `ub = (u - u1)/(u2 - u1)`, `vb = (v - v1)/(v2 - v1)` and
/// `w = ub vb - ub^2 vb - ub vb^2 + ub^2 vb^2 = ub(1 - ub) vb(1 - vb)` (eq 31, k = 1; eq 32,
/// k = 2). `w` and its first derivatives vanish on the region's border for k = 2, so the
/// surface keeps G1 continuity there; for k = 1 only the position is continuous.
///
/// The paper writes `p_i(ub, vb)`; here `p_i` is an expression in the original `u`, `v`, `t`
/// (the paper's example `zeta cos(v1 + vb (v2 - v1))` is just `zeta*cos(v)`).
#[derive(Clone, Debug, PartialEq)]
pub struct LocalDeformation {
    /// (u1, u2), inside [0, 1].
    pub u_range: (f64, f64),
    /// (v1, v2), inside the patch's v range.
    pub v_range: (f64, f64),
    /// G0 (eq 31) or G1 (eq 32).
    pub continuity: Continuity,
    /// p_1, p_2, p_3.
    pub p: [Field; 3],
}

impl LocalDeformation {
    /// The added term at (u, v, t), zero outside the region.
    #[inline]
    pub fn offset(&self, u: f64, v: f64, t: f64) -> [f64; 3] {
        let (u1, u2) = self.u_range;
        let (v1, v2) = self.v_range;
        if u <= u1 || u >= u2 || v <= v1 || v >= v2 {
            return [0.0; 3];
        }
        let ub = (u - u1) / (u2 - u1);
        let vb = (v - v1) / (v2 - v1);
        let w = ub * (1.0 - ub) * vb * (1.0 - vb);
        let w = match self.continuity {
            Continuity::G0 => w,
            Continuity::G1 => w * w,
        };
        [
            w * self.p[0].eval(u, v, t),
            w * self.p[1].eval(u, v, t),
            w * self.p[2].eval(u, v, t),
        ]
    }
}

/// Collocation grid: `nu x nv` points at the centres of a uniform grid of cells over
/// `[0, 1] x [v0, v1]` (M = nu nv, eq 9). Cell centres avoid the seam of periodic v ranges,
/// where the first and last columns of an end-point grid would coincide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Collocation {
    /// Points along u.
    pub nu: usize,
    /// Points along v.
    pub nv: usize,
}

impl Collocation {
    /// Total points M.
    pub fn points(&self) -> usize {
        self.nu * self.nv
    }

    /// A grid with `m` points, as square as possible (`nu >= nv`), e.g. 36 -> 6 x 6.
    pub fn from_count(m: usize) -> Self {
        let mut nv = (m as f64).sqrt().floor() as usize;
        while nv > 1 && !m.is_multiple_of(nv) {
            nv -= 1;
        }
        let nv = nv.max(1);
        Collocation { nu: m / nv, nv }
    }
}

/// A compiled patch, ready to solve at any t.
#[derive(Clone, Debug, PartialEq)]
pub struct PdePatch {
    /// Name (for messages and files).
    pub name: String,
    /// Trial functions of u (kind and N).
    pub trial: TrialBasis,
    /// x, y, z.
    pub components: [Component; 3],
    /// Density rho (eq 1).
    pub rho: Field,
    /// Damping eta (eq 1).
    pub eta: Field,
    /// (v0, v1).
    pub v_range: (f64, f64),
    /// Collocation grid.
    pub collocation: Collocation,
    /// Local deformations (section VI-A).
    pub local: Vec<LocalDeformation>,
    /// How the patch is solved: collocation (the paper's method, the default) or one of the
    /// methods section III compares it with ([`crate::spectral`], eq 19-23). Set by the spec's
    /// `solver` key, which checks the spectral methods' conditions.
    pub method: Method,
    /// Collocation u values.
    pub(crate) colloc_u: Vec<f64>,
    /// Collocation v values.
    pub(crate) colloc_v: Vec<f64>,
    /// Trial functions tabulated at the collocation u values.
    pub(crate) colloc_table: TrialTable,
    /// Check grid (between collocation points) for undetermined directions.
    pub(crate) check_u: Vec<f64>,
    /// Check grid v values.
    pub(crate) check_v: Vec<f64>,
    /// Trial functions tabulated at the check u values.
    pub(crate) check_table: TrialTable,
}

/// Component letters for messages.
pub const COMPONENT_NAMES: [char; 3] = ['x', 'y', 'z'];

impl PdePatch {
    /// Assembles a patch and checks that it is well posed: N large enough, the collocation grid
    /// non-empty with at least as many points as unknowns per component, v range finite and
    /// increasing, local regions inside the domain.
    pub fn new(
        name: String,
        kind: PatchKind,
        n_max: usize,
        components: [Component; 3],
        rho: Field,
        eta: Field,
        v_range: (f64, f64),
        collocation: Collocation,
        local: Vec<LocalDeformation>,
    ) -> Result<Self, PdeError> {
        let place = format!("patch '{name}'");
        let first = kind.first_unknown_power();
        if n_max < first || n_max > MAX_TRIAL_TERMS {
            return Err(PdeError::InvalidValue {
                place: format!("{place}.trial_terms"),
                message: format!(
                    "N = {n_max}; must be between {first} and {MAX_TRIAL_TERMS} (trial powers u^{first}..u^N carry the unknown constants)"
                ),
            });
        }
        let (v0, v1) = v_range;
        if !(v0.is_finite() && v1.is_finite() && v1 > v0) {
            return Err(PdeError::InvalidValue {
                place: format!("{place}.v_range"),
                message: format!("[{v0}, {v1}] must be finite with v0 < v1"),
            });
        }
        if collocation.nu == 0 || collocation.nv == 0 {
            return Err(PdeError::InvalidValue {
                place: format!("{place}.collocation"),
                message: "the collocation grid must have at least one point each way".into(),
            });
        }
        let trial = TrialBasis::new(kind, n_max)?;
        let per_basic = trial.unknowns_per_basic();
        for (i, c) in components.iter().enumerate() {
            let unknowns = c.basics.len() * per_basic;
            // With side conditions some unknowns are fixed by them; the rank check at solve
            // time covers that case.
            if !c.sides.any() && unknowns > collocation.points() {
                return Err(PdeError::TooFewCollocationPoints {
                    patch: name.clone(),
                    component: COMPONENT_NAMES[i],
                    unknowns,
                    basics: c.basics.len(),
                    per_basic,
                    points: collocation.points(),
                });
            }
            if c.coefficients.len() != c.basics.len() {
                return Err(PdeError::InvalidValue {
                    place: format!("{place}.{}", COMPONENT_NAMES[i]),
                    message: "one coefficient row per basic function is required".into(),
                });
            }
        }
        for (k, l) in local.iter().enumerate() {
            let (u1, u2) = l.u_range;
            let (lv1, lv2) = l.v_range;
            if !(0.0 <= u1 && u1 < u2 && u2 <= 1.0) {
                return Err(PdeError::InvalidValue {
                    place: format!("{place}.local[{k}].u"),
                    message: format!("[{u1}, {u2}] must satisfy 0 <= u1 < u2 <= 1"),
                });
            }
            if !(v0 <= lv1 && lv1 < lv2 && lv2 <= v1) {
                return Err(PdeError::InvalidValue {
                    place: format!("{place}.local[{k}].v"),
                    message: format!("[{lv1}, {lv2}] must satisfy {v0} <= v1 < v2 <= {v1}"),
                });
            }
        }
        let colloc_u: Vec<f64> = (0..collocation.nu)
            .map(|a| (a as f64 + 0.5) / collocation.nu as f64)
            .collect();
        let colloc_v: Vec<f64> = (0..collocation.nv)
            .map(|b| v0 + (b as f64 + 0.5) / collocation.nv as f64 * (v1 - v0))
            .collect();
        let colloc_table = TrialTable::new(&trial, &colloc_u);
        // A check grid that shares no point with the collocation grid (odd counts, offset).
        let (cu, cv) = (2 * collocation.nu + 3, 2 * collocation.nv + 3);
        let check_u: Vec<f64> = (0..cu).map(|a| (a as f64 + 0.37) / cu as f64).collect();
        let check_v: Vec<f64> = (0..cv)
            .map(|b| v0 + (b as f64 + 0.37) / cv as f64 * (v1 - v0))
            .collect();
        let check_table = TrialTable::new(&trial, &check_u);
        Ok(PdePatch {
            name,
            trial,
            components,
            rho,
            eta,
            v_range,
            collocation,
            local,
            method: Method::Collocation,
            colloc_u,
            colloc_v,
            colloc_table,
            check_u,
            check_v,
            check_table,
        })
    }

    /// Patch kind (two ends or one end).
    pub fn kind(&self) -> PatchKind {
        self.trial.kind
    }

    /// Number of unknown constants of component `i` (J (N - 3) or J (N - 1)).
    pub fn unknowns(&self, i: usize) -> usize {
        self.components[i].basics.len() * self.trial.unknowns_per_basic()
    }

    /// Collocation points (u_m, v_m), u-major.
    pub fn collocation_points(&self) -> Vec<(f64, f64)> {
        self.colloc_u
            .iter()
            .flat_map(|&u| self.colloc_v.iter().map(move |&v| (u, v)))
            .collect()
    }

    /// Whether nothing in the patch depends on t (then one solve serves every frame).
    pub fn is_static(&self) -> bool {
        let t = |e: &Expr| e.depends_on(Var::T);
        !self.rho.depends_on_time()
            && !self.eta.depends_on_time()
            && self.components.iter().all(|c| {
                c.basics.iter().all(|b| !t(&b.g))
                    && !c.shape.b.depends_on_time()
                    && !c.shape.c.depends_on_time()
                    && !c.shape.d.depends_on_time()
                    && [&c.sides.v0, &c.sides.dv0, &c.sides.v1, &c.sides.dv1]
                        .iter()
                        .all(|s| s.as_ref().is_none_or(|s| !s.coefficients.iter().any(t)))
            })
            && self
                .local
                .iter()
                .all(|l| !l.p.iter().any(Field::depends_on_time))
    }
}

/// Largest N accepted (u^N on [0, 1] and the power basis stay well conditioned below this).
pub const MAX_TRIAL_TERMS: usize = 24;
