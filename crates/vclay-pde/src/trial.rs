//! Trial functions of `u`: the polynomial factors of the solution functions (eq 4, 5, 36).
//!
//! A solution component is `x_i = sum_j W_ij(u) g_ij(v, t)` with
//! `W_ij(u) = sum_k a_ijk h_k(u) + sum_n p_ijn psi_n(u)`:
//!
//! - [`PatchKind::TwoEnds`] (eq 5; conditions at u = 0 and u = 1): the known functions are the
//!   cubic Hermite functions `h_1 = 1 - 3u^2 + 2u^3`, `h_2 = u - 2u^2 + u^3`, `h_3 = 3u^2 - 2u^3`,
//!   `h_4 = -u^2 + u^3`, and the unknown ones `psi_n = (n-3)u^2 - (n-2)u^3 + u^n`, n = 4..N. Each
//!   `psi_n` has value and slope 0 at both ends, so the boundary conditions (2) hold for any p.
//! - [`PatchKind::OneEnd`] (eq 36; three-sided patch, conditions at u = 0 only): known `h_1 = 1`,
//!   `h_2 = u`; unknown `psi_n = u^n`, n = 2..N.
//!
//! All are stored as coefficient vectors of `u^0..u^N`, with their 1st, 2nd and 4th derivatives,
//! so that a row of a grid evaluates the powers of u once and every function by a dot product.

use crate::error::PdeError;
use crate::patch::MAX_TRIAL_TERMS;

/// Which u-boundaries carry conditions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchKind {
    /// Position and tangent at u = 0 and u = 1 (eq 2, 5); also four-sided patches (eq 33-35).
    TwoEnds,
    /// Position and tangent at u = 0 only (three-sided patch, eq 36-37).
    OneEnd,
}

impl PatchKind {
    /// Number of known boundary conditions per component (4 or 2).
    pub fn conditions(self) -> usize {
        match self {
            PatchKind::TwoEnds => 4,
            PatchKind::OneEnd => 2,
        }
    }

    /// Smallest trial power n with an unknown constant (4 or 2).
    pub fn first_unknown_power(self) -> usize {
        match self {
            PatchKind::TwoEnds => 4,
            PatchKind::OneEnd => 2,
        }
    }
}

/// A polynomial in u by its coefficients of `u^0, u^1, ...`.
pub type Poly = Vec<f64>;

/// Derivative of a polynomial.
pub fn poly_derivative(p: &[f64]) -> Poly {
    p.iter()
        .enumerate()
        .skip(1)
        .map(|(k, c)| k as f64 * c)
        .collect()
}

/// `p(u)` given the powers `u^0, u^1, ...` (at least `p.len()` of them).
#[inline]
pub fn poly_dot(p: &[f64], powers: &[f64]) -> f64 {
    p.iter().zip(powers).map(|(a, b)| a * b).sum()
}

/// Fills `powers` with `u^0 .. u^(len-1)`.
#[inline]
pub fn fill_powers(u: f64, powers: &mut [f64]) {
    let mut x = 1.0;
    for p in powers.iter_mut() {
        *p = x;
        x *= u;
    }
}

/// The known and unknown trial functions of one patch kind and N, with derivatives.
#[derive(Clone, Debug, PartialEq)]
pub struct TrialBasis {
    /// Patch kind.
    pub kind: PatchKind,
    /// N, the highest power of u (eq 4).
    pub n_max: usize,
    /// Known functions h_k (one per boundary condition), each of length N + 1.
    pub known: Vec<Poly>,
    /// Unknown functions psi_n for n = first..=N, each of length N + 1.
    pub unknown: Vec<Poly>,
}

impl TrialBasis {
    /// Builds the trial functions; `n_max` (N) must be at least the kind's first unknown power
    /// (4 or 2) and at most [`crate::patch::MAX_TRIAL_TERMS`].
    pub fn new(kind: PatchKind, n_max: usize) -> Result<Self, PdeError> {
        let first = kind.first_unknown_power();
        if n_max < first || n_max > MAX_TRIAL_TERMS {
            return Err(PdeError::InvalidValue {
                place: "trial_terms".into(),
                message: format!(
                    "N = {n_max}; must be between {first} and {MAX_TRIAL_TERMS} (trial powers u^{first}..u^N carry the unknown constants)"
                ),
            });
        }
        let len = n_max + 1;
        let poly = |coefs: &[(usize, f64)]| {
            let mut p = vec![0.0; len];
            for &(k, c) in coefs {
                p[k] += c;
            }
            p
        };
        let (known, unknown) = match kind {
            PatchKind::TwoEnds => (
                vec![
                    poly(&[(0, 1.0), (2, -3.0), (3, 2.0)]),
                    poly(&[(1, 1.0), (2, -2.0), (3, 1.0)]),
                    poly(&[(2, 3.0), (3, -2.0)]),
                    poly(&[(2, -1.0), (3, 1.0)]),
                ],
                (4..=n_max)
                    .map(|n| poly(&[(2, n as f64 - 3.0), (3, -(n as f64 - 2.0)), (n, 1.0)]))
                    .collect(),
            ),
            PatchKind::OneEnd => (
                vec![poly(&[(0, 1.0)]), poly(&[(1, 1.0)])],
                (2..=n_max).map(|n| poly(&[(n, 1.0)])).collect(),
            ),
        };
        Ok(TrialBasis {
            kind,
            n_max,
            known,
            unknown,
        })
    }

    /// Number of unknown constants per basic function (N - 3 or N - 1).
    pub fn unknowns_per_basic(&self) -> usize {
        self.unknown.len()
    }

    /// The trial power n of unknown number `k` (for messages).
    pub fn power_of_unknown(&self, k: usize) -> usize {
        self.kind.first_unknown_power() + k
    }
}

/// Values of all trial functions and their derivatives at a set of u, stored row by row:
/// `[h_0, .., h_{K-1}, psi_0, .., psi_{U-1}]` for each derivative order 0, 1, 2, 4.
#[derive(Clone, Debug, PartialEq)]
pub struct TrialTable {
    /// Functions per row (known + unknown).
    pub width: usize,
    /// Values, `[row][function]`.
    pub value: Vec<f64>,
    /// First derivatives.
    pub d1: Vec<f64>,
    /// Second derivatives.
    pub d2: Vec<f64>,
    /// Fourth derivatives.
    pub d4: Vec<f64>,
}

impl TrialTable {
    /// Tabulates `basis` at each u of `us` (powers of u computed once per row).
    pub fn new(basis: &TrialBasis, us: &[f64]) -> Self {
        let funcs: Vec<&Poly> = basis.known.iter().chain(basis.unknown.iter()).collect();
        let width = funcs.len();
        let d1: Vec<Poly> = funcs.iter().map(|p| poly_derivative(p)).collect();
        let d2: Vec<Poly> = d1.iter().map(|p| poly_derivative(p)).collect();
        let d4: Vec<Poly> = d2
            .iter()
            .map(|p| poly_derivative(&poly_derivative(p)))
            .collect();
        let mut t = TrialTable {
            width,
            value: Vec::with_capacity(width * us.len()),
            d1: Vec::with_capacity(width * us.len()),
            d2: Vec::with_capacity(width * us.len()),
            d4: Vec::with_capacity(width * us.len()),
        };
        let mut powers = vec![0.0; basis.n_max + 1];
        for &u in us {
            fill_powers(u, &mut powers);
            for k in 0..width {
                t.value.push(poly_dot(funcs[k], &powers));
                t.d1.push(poly_dot(&d1[k], &powers));
                t.d2.push(poly_dot(&d2[k], &powers));
                t.d4.push(poly_dot(&d4[k], &powers));
            }
        }
        t
    }
}
