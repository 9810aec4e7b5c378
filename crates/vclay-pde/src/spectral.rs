//! The two solvers that section III of `dynamic-pde-surfaces.txt` compares with the
//! collocation method (Fig 1(c)-(e), eq 19-23): Bloor and Wilson's Fourier-series solution and
//! their pseudospectral solution (Fourier series plus a remainder function).
//!
//! **Fourier series (eq 19-21).** On a periodic v range of length `L` (period `L = v1 - v0`,
//! wavenumbers `k_n = 2 pi n / L`), every boundary function `G_ik(v)` of eq (2) is replaced by
//! its truncated Fourier series `a_0 + sum_{n=1..N} a_n cos(k_n (v - v0)) + b_n sin(k_n (v - v0))`
//! (the coefficients are computed by Gauss-Legendre quadrature, 8 points per panel and
//! `2 (N + 4)` panels, so that the paper's expansions (19) of `v` and (20) of `exp(0.1 v)` come
//! out to rounding). With constant shape functions and no time terms the PDE (1) splits into one
//! ordinary differential equation per mode (eq 21):
//!
//! `b A_n'''' - c k_n^2 A_n'' + d k_n^4 A_n = 0`,
//!
//! whose solutions are `(u - u*)^m exp(s (u - u*))` over the roots `s` of
//! `b s^4 - c k^2 s^2 + d k^4 = 0` (`s^2 = k^2 (c +- sqrt(c^2 - 4 b d)) / (2 b)`, complex in
//! general; `m` counts repeated roots: the paper's `b = 1, c = 2 a^2, d = a^4` has the double
//! roots `+-a k`, `(c0 + c1 u) e^(a k u) + (c2 + c3 u) e^(-a k u)` as in eq (17); mode 0 is a
//! cubic). `u* = 1` for roots with a positive real part and 0 otherwise, so no term overflows.
//! The four constants of each mode meet the mode's four boundary coefficients exactly (a 4 x 4
//! complex solve). The series satisfies the PDE exactly but the boundary conditions only as
//! far as the truncated series does: non-periodic data (`v`, `exp(0.1 v)` on `[0, 2 pi]`) keep a
//! Gibbs error near the seam that more terms do not remove (the paper's "small gap").
//!
//! **Pseudospectral (eq 22-23).** The remainder
//! `R_i = R_i1(v) e^(w u) + R_i2(v) u e^(w u) + R_i3(v) e^(-w u) + R_i4(v) u e^(-w u)` is added,
//! its four functions of v chosen at every v so that `x_i + R_i` meets the four boundary
//! conditions exactly: `R(v) = P^-1 (G(v) - F(v))`, where `G` are the exact boundary values,
//! `F` the truncated series' and `P` the 4 x 4 matrix of the remainder basis' values and slopes
//! at u = 0, 1 (the basis is stored as `e^(w (u - 1))`, `(u - 1) e^(w (u - 1))`, `e^(-w u)`,
//! `u e^(-w u)`, the same span). `w` is Bloor and Wilson's smoothing parameter; here it is the
//! decay rate of the first omitted mode, `w = k_(N+1) |d / b|^(1/4)` (`3 (N + 1)` for the
//! paper's `a = 3`). The boundary conditions then hold exactly but the PDE does not.
//!
//! Limitations (the methods' own, checked when a spec is compiled): constant shape functions
//! with `b != 0`, `rho = eta = 0` (the ODE per mode needs a static, constant-coefficient PDE;
//! boundary functions may still depend on t, each instant being solved on its own), conditions
//! at both u = 0 and u = 1, no side conditions and no local deformations.

use crate::error::PdeError;
use crate::patch::{COMPONENT_NAMES, PdePatch};
use nalgebra::{Complex, Matrix4, Vector4};

type C64 = Complex<f64>;

/// Default number of Fourier terms N (the paper's Fig 1(c) uses N = 20).
pub const DEFAULT_FOURIER_TERMS: usize = 20;

/// Most Fourier terms accepted (`fourier_terms` in a spec): 256 modes, about 2,000 quadrature
/// points per basic function and solve.
pub const MAX_FOURIER_TERMS: usize = 256;

/// Gauss-Legendre nodes and weights on [-1, 1], 8 points.
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// How a patch is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// The paper's method: Hermite plus trial polynomials in u, collocation least squares
    /// (eq 4-12, [`crate::solve`]).
    #[default]
    Collocation,
    /// Bloor and Wilson's Fourier series with `terms` modes (eq 19-21).
    Fourier {
        /// N, the highest mode.
        terms: usize,
    },
    /// The Fourier series plus the remainder function (eq 22-23).
    Pseudospectral {
        /// N, the highest mode.
        terms: usize,
    },
}

impl Method {
    /// The spec name: `collocation`, `fourier` or `pseudospectral`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Collocation => "collocation",
            Method::Fourier { .. } => "fourier",
            Method::Pseudospectral { .. } => "pseudospectral",
        }
    }

    /// N of the spectral methods.
    pub fn terms(self) -> Option<usize> {
        match self {
            Method::Collocation => None,
            Method::Fourier { terms } | Method::Pseudospectral { terms } => Some(terms),
        }
    }
}

/// The four solutions of `b A'''' - c k^2 A'' + d k^4 A = 0` (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct OdeBasis {
    /// Roots s.
    roots: [C64; 4],
    /// Power m of `(u - u*)` (repeated roots).
    powers: [i32; 4],
    /// Anchor u* (0 or 1).
    anchors: [f64; 4],
}

impl OdeBasis {
    /// The basis for shape constants `b, c, d` (b != 0) and wavenumber `k`.
    pub fn new(b: f64, c: f64, d: f64, k: f64) -> Self {
        let zero = C64::new(0.0, 0.0);
        let roots = if k == 0.0 {
            [zero; 4]
        } else {
            let sq = C64::new(c * c - 4.0 * b * d, 0.0).sqrt();
            let mu1 = (C64::new(c, 0.0) + sq) / (2.0 * b);
            let mu2 = (C64::new(c, 0.0) - sq) / (2.0 * b);
            let (r1, r2) = (mu1.sqrt() * k, mu2.sqrt() * k);
            [r1, -r1, r2, -r2]
        };
        let scale = roots.iter().map(|r| r.norm()).fold(1.0, f64::max);
        let mut powers = [0; 4];
        let mut clean = roots;
        for q in 0..4 {
            for p in 0..q {
                if (roots[q] - clean[p]).norm() <= 1e-7 * scale && powers[p] >= powers[q] {
                    // A repeated root: the same exponential times a higher power of u.
                    clean[q] = clean[p];
                    powers[q] = powers[p] + 1;
                }
            }
        }
        let anchors = clean.map(|s| if s.re > 0.0 { 1.0 } else { 0.0 });
        OdeBasis {
            roots: clean,
            powers,
            anchors,
        }
    }

    /// Value and first derivative of basis function `q` at `u`.
    #[inline]
    fn phi(&self, q: usize, u: f64) -> (C64, C64) {
        let x = u - self.anchors[q];
        let s = self.roots[q];
        let e = (s * x).exp();
        let m = self.powers[q];
        let xm = x.powi(m);
        let der = if m == 0 {
            s * e
        } else {
            e * (m as f64 * x.powi(m - 1)) + s * e * xm
        };
        (e * xm, der)
    }

    /// Rows: value at u = 0, slope at 0, value at 1, slope at 1; columns: basis functions.
    fn boundary_matrix(&self) -> Matrix4<C64> {
        let mut m = Matrix4::zeros();
        for q in 0..4 {
            let (a0, d0) = self.phi(q, 0.0);
            let (a1, d1) = self.phi(q, 1.0);
            m[(0, q)] = a0;
            m[(1, q)] = d0;
            m[(2, q)] = a1;
            m[(3, q)] = d1;
        }
        m
    }
}

/// One Fourier mode of one component: the ODE basis and the constants of its cosine and sine
/// parts.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// The ODE solutions of this mode.
    pub basis: OdeBasis,
    /// Constants of `A_n(u)` (cosine part).
    pub cos: [C64; 4],
    /// Constants of `B_n(u)` (sine part).
    pub sin: [C64; 4],
}

impl Mode {
    /// `(A_n(u), B_n(u))`.
    #[inline]
    pub fn at(&self, u: f64) -> (f64, f64) {
        let (mut a, mut b) = (0.0, 0.0);
        for q in 0..4 {
            let (p, _) = self.basis.phi(q, u);
            a += (self.cos[q] * p).re;
            b += (self.sin[q] * p).re;
        }
        (a, b)
    }
}

/// The series of one component.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpectralComponent {
    /// Modes n = 0..=N.
    pub modes: Vec<Mode>,
    /// Fourier coefficients `[a_n, b_n]` of the four boundary functions, per mode (for the
    /// remainder: the series' own boundary values).
    pub boundary: Vec<[[f64; 2]; 4]>,
    /// Remainder exponent w (pseudospectral only).
    pub omega: f64,
    /// `P^-1`, row-major (pseudospectral only).
    pub remainder: Option<[[f64; 4]; 4]>,
}

/// A patch solved by the Fourier-series or pseudospectral method.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpectralSolution {
    /// Fourier or pseudospectral.
    pub method: Method,
    /// v0 (start of the period).
    pub v0: f64,
    /// The period L = v1 - v0.
    pub period: f64,
    /// x, y, z.
    pub components: [SpectralComponent; 3],
}

/// The remainder basis (values and slopes) at u.
#[inline]
fn remainder_basis(w: f64, u: f64) -> [(f64, f64); 4] {
    let ep = (w * (u - 1.0)).exp();
    let em = (-w * u).exp();
    [
        (ep, w * ep),
        ((u - 1.0) * ep, ep + w * (u - 1.0) * ep),
        (em, -w * em),
        (u * em, em - w * u * em),
    ]
}

impl SpectralSolution {
    /// Solves `patch` at `t` by its spectral method (see the module docs).
    ///
    /// # Panics
    /// If the patch's method is collocation (a programmer error: [`crate::Solver`] dispatches).
    #[track_caller]
    pub fn solve(patch: &PdePatch, t: f64) -> Result<Self, PdeError> {
        let terms = patch
            .method
            .terms()
            .expect("SpectralSolution::solve: a spectral method");
        let (v0, v1) = patch.v_range;
        let period = v1 - v0;
        let mut components: [SpectralComponent; 3] = Default::default();
        for (i, out) in components.iter_mut().enumerate() {
            let comp = &patch.components[i];
            let shape = |f: &crate::patch::Field| f.as_const().unwrap_or(f64::NAN);
            let (b, c, d) = (
                shape(&comp.shape.b),
                shape(&comp.shape.c),
                shape(&comp.shape.d),
            );
            let boundary = boundary_series(patch, i, t, terms);
            let mut modes = Vec::with_capacity(terms + 1);
            for (n, coef) in boundary.iter().enumerate() {
                let k = std::f64::consts::TAU * n as f64 / period;
                let basis = OdeBasis::new(b, c, d, k);
                let lu = basis.boundary_matrix().lu();
                let rhs = |part: usize| Vector4::from_fn(|r, _| C64::new(coef[r][part], 0.0));
                let solve = |part: usize| -> Result<[C64; 4], PdeError> {
                    let x = lu.solve(&rhs(part)).ok_or_else(|| PdeError::NonFinite {
                        patch: patch.name.clone(),
                        t,
                        what: format!(
                            "the boundary system of Fourier mode {n} of component {} (singular)",
                            COMPONENT_NAMES[i]
                        ),
                    })?;
                    Ok([x[0], x[1], x[2], x[3]])
                };
                let (cos, sin) = (solve(0)?, solve(1)?);
                if cos
                    .iter()
                    .chain(&sin)
                    .any(|z| !(z.re.is_finite() && z.im.is_finite()))
                {
                    return Err(PdeError::NonFinite {
                        patch: patch.name.clone(),
                        t,
                        what: format!("Fourier mode {n} of component {}", COMPONENT_NAMES[i]),
                    });
                }
                modes.push(Mode { basis, cos, sin });
            }
            out.modes = modes;
            out.boundary = boundary;
            if let Method::Pseudospectral { .. } = patch.method {
                let k_next = std::f64::consts::TAU * (terms + 1) as f64 / period;
                let ratio = (d / b).abs().powf(0.25);
                let w = if ratio > 0.0 && ratio.is_finite() {
                    k_next * ratio
                } else {
                    k_next
                };
                let r0 = remainder_basis(w, 0.0);
                let r1 = remainder_basis(w, 1.0);
                let p = Matrix4::from_fn(|r, q| match r {
                    0 => r0[q].0,
                    1 => r0[q].1,
                    2 => r1[q].0,
                    _ => r1[q].1,
                });
                let inv = p.try_inverse().ok_or_else(|| PdeError::NonFinite {
                    patch: patch.name.clone(),
                    t,
                    what: "the remainder's boundary matrix (eq 22)".into(),
                })?;
                out.omega = w;
                out.remainder = Some(std::array::from_fn(|r| {
                    std::array::from_fn(|q| inv[(r, q)])
                }));
            }
        }
        Ok(SpectralSolution {
            method: patch.method,
            v0,
            period,
            components,
        })
    }

    /// Number of constants determined (4 per mode, cosine and sine parts, per component).
    pub fn constants(&self) -> [usize; 3] {
        self.components.each_ref().map(|c| 8 * c.modes.len())
    }

    /// `cos(k_n (v - v0))`, `sin(k_n (v - v0))` for n = 0..=N into `cs`.
    fn trig(&self, v: f64, cs: &mut Vec<(f64, f64)>) {
        let n1 = self.components[0].modes.len();
        cs.clear();
        let theta = std::f64::consts::TAU * (v - self.v0) / self.period;
        cs.extend((0..n1).map(|n| {
            let (s, c) = (n as f64 * theta).sin_cos();
            (c, s)
        }));
    }

    /// The remainder functions `R_i(v)` (eq 22-23) at v for component `i`, given the trig
    /// values at v; zero for the plain Fourier series.
    fn remainder_at(
        &self,
        patch: &PdePatch,
        i: usize,
        v: f64,
        t: f64,
        cs: &[(f64, f64)],
    ) -> [f64; 4] {
        let comp = &self.components[i];
        let Some(inv) = &comp.remainder else {
            return [0.0; 4];
        };
        // Exact boundary values G_k(v) minus the series' F_k(v).
        let mut gap = [0.0; 4];
        for (j, basic) in patch.components[i].basics.iter().enumerate() {
            let g = basic.g.eval(0.0, v, t);
            for (k, x) in gap.iter_mut().enumerate() {
                *x += patch.components[i].coefficients[j][k] * g;
            }
        }
        for (coef, &(c, s)) in comp.boundary.iter().zip(cs) {
            for (k, x) in gap.iter_mut().enumerate() {
                *x -= coef[k][0] * c + coef[k][1] * s;
            }
        }
        std::array::from_fn(|q| (0..4).map(|r| inv[q][r] * gap[r]).sum())
    }

    /// Point of component values at (u, v), t.
    pub fn point(&self, patch: &PdePatch, u: f64, v: f64, t: f64) -> [f64; 3] {
        let mut cs = Vec::new();
        self.trig(v, &mut cs);
        std::array::from_fn(|i| {
            let comp = &self.components[i];
            let mut x = 0.0;
            for (mode, &(c, s)) in comp.modes.iter().zip(&cs) {
                let (a, b) = mode.at(u);
                x += a * c + b * s;
            }
            if comp.remainder.is_some() {
                let r = self.remainder_at(patch, i, v, t, &cs);
                let basis = remainder_basis(comp.omega, u);
                x += (0..4).map(|q| r[q] * basis[q].0).sum::<f64>();
            }
            x
        })
    }

    /// Evaluates on the grid `us x vs` (row-major) into `out` (length `us.len() * vs.len()`):
    /// the trig values and remainders once per column, the mode functions once per row.
    pub fn eval_grid(
        &self,
        patch: &PdePatch,
        t: f64,
        us: &[f64],
        vs: &[f64],
        out: &mut [vclay_core::Vec3],
    ) {
        let nv = vs.len();
        let n1 = self.components[0].modes.len();
        let mut cs = Vec::new();
        let mut cols: Vec<(f64, f64)> = Vec::with_capacity(nv * n1);
        let mut rem: [Vec<[f64; 4]>; 3] = Default::default();
        for &v in vs {
            self.trig(v, &mut cs);
            cols.extend_from_slice(&cs);
            for (i, r) in rem.iter_mut().enumerate() {
                if self.components[i].remainder.is_some() {
                    r.push(self.remainder_at(patch, i, v, t, &cs));
                }
            }
        }
        let mut ab = vec![(0.0, 0.0); n1];
        let mut row = vec![[0.0; 3]; nv];
        for (ra, &u) in us.iter().enumerate() {
            for i in 0..3 {
                let comp = &self.components[i];
                for (x, mode) in ab.iter_mut().zip(&comp.modes) {
                    *x = mode.at(u);
                }
                let basis = remainder_basis(comp.omega, u);
                for (cb, p) in row.iter_mut().enumerate() {
                    let trig = &cols[cb * n1..(cb + 1) * n1];
                    let mut x = 0.0;
                    for (&(a, b), &(c, s)) in ab.iter().zip(trig) {
                        x += a * c + b * s;
                    }
                    if let Some(r) = rem[i].get(cb) {
                        x += (0..4).map(|q| r[q] * basis[q].0).sum::<f64>();
                    }
                    p[i] = x;
                }
            }
            for (cb, p) in row.iter().enumerate() {
                out[ra * nv + cb] = vclay_core::Vec3::new(p[0], p[1], p[2]);
            }
        }
    }
}

/// Fourier coefficients `[a_n, b_n]` (n = 0..=N) of the four boundary functions of component
/// `i` at `t`, by Gauss-Legendre quadrature over one period.
pub fn boundary_series(patch: &PdePatch, i: usize, t: f64, terms: usize) -> Vec<[[f64; 2]; 4]> {
    let comp = &patch.components[i];
    let (v0, v1) = patch.v_range;
    let period = v1 - v0;
    let panels = 2 * (terms + 4);
    let h = period / panels as f64;
    let mut out = vec![[[0.0; 2]; 4]; terms + 1];
    for p in 0..panels {
        let mid = v0 + (p as f64 + 0.5) * h;
        for &(x, w) in &GL8 {
            let v = mid + 0.5 * h * x;
            let weight = 0.5 * h * w;
            let mut g = [0.0; 4];
            for (j, basic) in comp.basics.iter().enumerate() {
                let gv = basic.g.eval(0.0, v, t);
                for (k, x) in g.iter_mut().enumerate() {
                    *x += comp.coefficients[j][k] * gv;
                }
            }
            let theta = std::f64::consts::TAU * (v - v0) / period;
            // cos(n theta), sin(n theta) by rotation (one sin_cos per point).
            let (s1, c1) = theta.sin_cos();
            let (mut c, mut s) = (1.0, 0.0);
            for o in out.iter_mut() {
                for k in 0..4 {
                    o[k][0] += weight * g[k] * c;
                    o[k][1] += weight * g[k] * s;
                }
                (c, s) = (c * c1 - s * s1, s * c1 + c * s1);
            }
        }
    }
    for (n, o) in out.iter_mut().enumerate() {
        let scale = if n == 0 { 1.0 / period } else { 2.0 / period };
        for x in o.iter_mut() {
            x[0] *= scale;
            x[1] *= scale;
        }
    }
    out
}
