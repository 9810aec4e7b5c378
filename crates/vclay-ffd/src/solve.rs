//! Dense solver for the multi-point system of `ffd-direct-manipulation.txt` eqs (11)-(12).
//!
//! With `A = R^T` restricted to the union of the supports (`n_u x m`, one column per constraint:
//! the paper's `R` matrix of section 5, which is `N x h`), the constraints read `A^T delta = D`
//! and the minimum-norm solution is `delta = A (A^T A)^{-1} D` (eq 12). It is computed without
//! forming `A^T A` (whose condition number is the square of `A`'s): a Householder QR with column
//! pivoting `A P = Q_1 R_1` (Golub & Van Loan, *Matrix Computations* 4th ed., Alg. 5.4.1) gives
//!
//! ```text
//! A^T delta = D  <=>  R_1^T Q_1^T delta = P^T D;   delta = Q_1 y with R_1^T y = P^T D   (min norm)
//! lambda = (A^T A)^{-1} D = P R_1^{-1} y                                                (eq 16, M)
//! ```
//!
//! The pivoting reveals the rank: the process stops when the largest remaining column norm drops
//! below `rank_tolerance * ||A||_F`. A column left over (index `c`) is, to that tolerance, the
//! combination `A_c = sum_a x_a A_a` of the pivot columns with `x = R_11^{-1} R_12`; its constraint
//! is met exactly by any solution that meets the pivot constraints iff
//! `D_c = sum_a x_a D_a`. Otherwise the pair of lists names the conflict.
//!
//! Rank-deficient systems (consistent ones in exact mode, all in least-squares mode) are solved by
//! the SVD pseudo-inverse `A^T = U S V^T`: `delta = V S^+ U^T D` (the minimum-norm least-squares
//! solution) and `lambda = U (S^+)^2 U^T D` (the minimum-norm multipliers with `A lambda = delta`).

use crate::error::{ConstraintConflict, FfdError};
use nalgebra::DMatrix;

/// Relative size below which a combination coefficient does not name a partner constraint.
const PARTNER_RELATIVE: f64 = 1e-8;

/// How the multi-point system is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolveMode {
    /// Meet every constraint exactly (eq 12). Dependent constraints whose targets agree (for
    /// example the same source listed twice with the same target) are accepted and solved by the
    /// pseudo-inverse; dependent constraints whose targets disagree give
    /// [`FfdError::ConflictingConstraints`] naming them.
    #[default]
    Exact,
    /// Minimum-norm least squares (SVD pseudo-inverse): meets the constraints as closely as
    /// possible and, among those displacements, returns the smallest. Never reports conflicts.
    LeastSquares,
}

/// Result of [`solve`]: the control-point displacements on the support union and the multipliers.
#[derive(Debug)]
pub(crate) struct Solution {
    /// `n_u x 3`.
    pub delta: DMatrix<f64>,
    /// `m x 3`, the paper's `lambda` (= `M` of eq 16).
    pub lambda: DMatrix<f64>,
}

/// Householder QR with column pivoting, stopped at the numerical rank.
struct PivotedQr {
    /// `R` in the upper triangle of the first `rank` rows, Householder vectors (unit first entry
    /// implied) below the diagonal of the first `rank` columns.
    qr: DMatrix<f64>,
    taus: Vec<f64>,
    perm: Vec<usize>,
    rank: usize,
}

fn pivoted_qr(mut a: DMatrix<f64>, tol: f64) -> PivotedQr {
    let (n, m) = a.shape();
    let mut perm: Vec<usize> = (0..m).collect();
    let mut taus = Vec::new();
    let mut rank = 0;
    for k in 0..n.min(m) {
        // Exact recomputation of the trailing column norms: m is small (constraints), and it
        // avoids the cancellation of norm downdating.
        let (mut best, mut best_norm) = (k, -1.0);
        for j in k..m {
            let s = a.view((k, j), (n - k, 1)).norm();
            if s > best_norm {
                best = j;
                best_norm = s;
            }
        }
        if best_norm <= tol {
            break;
        }
        a.swap_columns(k, best);
        perm.swap(k, best);
        let x0 = a[(k, k)];
        let alpha = if x0 >= 0.0 { -best_norm } else { best_norm };
        let v0 = x0 - alpha;
        for i in k + 1..n {
            a[(i, k)] /= v0;
        }
        let vtv = 1.0 + a.view((k + 1, k), (n - k - 1, 1)).norm_squared();
        let tau = 2.0 / vtv;
        for j in k + 1..m {
            let mut w = a[(k, j)];
            for i in k + 1..n {
                w += a[(i, k)] * a[(i, j)];
            }
            w *= tau;
            a[(k, j)] -= w;
            for i in k + 1..n {
                let vi = a[(i, k)];
                a[(i, j)] -= w * vi;
            }
        }
        a[(k, k)] = alpha;
        taus.push(tau);
        rank = k + 1;
    }
    PivotedQr {
        qr: a,
        taus,
        perm,
        rank,
    }
}

impl PivotedQr {
    /// `Q_1 y` for `y` with `rank` rows: applies `H_0 ... H_{r-1}` to `[y; 0]`.
    fn q_mul(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let n = self.qr.nrows();
        let r = self.rank;
        let mut out = DMatrix::zeros(n, y.ncols());
        out.view_mut((0, 0), (r, y.ncols())).copy_from(y);
        for k in (0..r).rev() {
            let tau = self.taus[k];
            for c in 0..y.ncols() {
                let mut w = out[(k, c)];
                for i in k + 1..n {
                    w += self.qr[(i, k)] * out[(i, c)];
                }
                w *= tau;
                out[(k, c)] -= w;
                for i in k + 1..n {
                    out[(i, c)] -= w * self.qr[(i, k)];
                }
            }
        }
        out
    }

    fn r11(&self) -> DMatrix<f64> {
        let r = self.rank;
        self.qr.view((0, 0), (r, r)).upper_triangle()
    }
}

/// Solves `A^T delta = D` for the minimum-norm `delta` (see the module docs).
///
/// `rank_tolerance` is relative to `||A||_F`; `consistency` is the absolute distance (model units)
/// below which the targets of dependent constraints count as agreeing.
pub(crate) fn solve(
    a: DMatrix<f64>,
    d: &DMatrix<f64>,
    mode: SolveMode,
    rank_tolerance: f64,
    consistency: f64,
) -> Result<Solution, FfdError> {
    let m = a.ncols();
    let tol = rank_tolerance * a.norm();
    let qr = pivoted_qr(a.clone(), tol);
    let r = qr.rank;
    if r == m {
        let r11 = qr.r11();
        let mut pd = DMatrix::zeros(m, 3);
        for (i, &c) in qr.perm.iter().enumerate() {
            pd.set_row(i, &d.row(c));
        }
        let y = r11
            .tr_solve_upper_triangular(&pd)
            .expect("pivots above the rank tolerance are non-zero");
        let delta = qr.q_mul(&y);
        let lp = r11
            .solve_upper_triangular(&y)
            .expect("pivots above the rank tolerance are non-zero");
        let mut lambda = DMatrix::zeros(m, 3);
        for (i, &c) in qr.perm.iter().enumerate() {
            lambda.set_row(c, &lp.row(i));
        }
        return Ok(Solution { delta, lambda });
    }
    if mode == SolveMode::Exact {
        let conflicts = find_conflicts(&qr, d, consistency);
        if !conflicts.is_empty() {
            return Err(FfdError::ConflictingConstraints {
                rank: r,
                count: m,
                conflicts,
            });
        }
    }
    Ok(least_squares_solve(&qr, d))
}

/// The dependent constraints whose targets disagree with their partners'.
fn find_conflicts(qr: &PivotedQr, d: &DMatrix<f64>, consistency: f64) -> Vec<ConstraintConflict> {
    let r = qr.rank;
    let m = qr.qr.ncols();
    let r12 = qr.qr.view((0, r), (r, m - r)).into_owned();
    let x = if r == 0 {
        DMatrix::zeros(0, m - r)
    } else {
        qr.r11()
            .solve_upper_triangular(&r12)
            .expect("pivots above the rank tolerance are non-zero")
    };
    let mut out = Vec::new();
    for j in 0..m - r {
        let c = qr.perm[r + j];
        let col = x.column(j);
        let mut mismatch = d.row(c).transpose();
        for i in 0..r {
            mismatch -= col[i] * d.row(qr.perm[i]).transpose();
        }
        let mismatch = mismatch.norm();
        if mismatch > consistency {
            let big = col.amax();
            let mut depends_on: Vec<usize> = (0..r)
                .filter(|&i| col[i].abs() > PARTNER_RELATIVE * big)
                .map(|i| qr.perm[i])
                .collect();
            depends_on.sort_unstable();
            out.push(ConstraintConflict {
                constraint: c,
                depends_on,
                mismatch,
            });
        }
    }
    out.sort_by_key(|c| c.constraint);
    out
}

/// Minimum-norm least squares from the rank-revealing factorization (a complete orthogonal
/// decomposition): with `S = [R_11 R_12]` (`r x m`), `A^T = P S^T Q_1^T`, so for `delta = Q_1 y`
/// (the part orthogonal to `Q_1` only adds norm) the residual is `||S^T y - P^T D||`. `S^T` has
/// full column rank `r`; its QR `S^T = Q_2 R_2` gives `y = R_2^{-1} Q_2^T P^T D`, and the minimum-norm
/// multipliers with `A lambda = delta` are `P^T lambda = S^T (S S^T)^{-1} y = Q_2 R_2^{-T} y`.
fn least_squares_solve(qr: &PivotedQr, d: &DMatrix<f64>) -> Solution {
    let r = qr.rank;
    let m = qr.qr.ncols();
    let n = qr.qr.nrows();
    if r == 0 {
        return Solution {
            delta: DMatrix::zeros(n, 3),
            lambda: DMatrix::zeros(m, 3),
        };
    }
    let st = qr.qr.view((0, 0), (r, m)).upper_triangle().transpose();
    let qr2 = st.qr();
    let (q2, r2) = (qr2.q(), qr2.r());
    let mut pd = DMatrix::zeros(m, 3);
    for (i, &c) in qr.perm.iter().enumerate() {
        pd.set_row(i, &d.row(c));
    }
    let y = r2
        .solve_upper_triangular(&(q2.transpose() * pd))
        .expect("S has full row rank");
    let delta = qr.q_mul(&y);
    let z = &q2
        * r2.tr_solve_upper_triangular(&y)
            .expect("S has full row rank");
    let mut lambda = DMatrix::zeros(m, 3);
    for (i, &c) in qr.perm.iter().enumerate() {
        lambda.set_row(c, &z.row(i));
    }
    Solution { delta, lambda }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pivoted_qr_reconstructs_full_rank() {
        let a = DMatrix::from_fn(6, 3, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 + f64::from(u8::from(i == j))
        });
        let qr = pivoted_qr(a.clone(), 1e-12);
        assert_eq!(qr.rank, 3);
        let r = qr.r11();
        let qr_prod = qr.q_mul(&r);
        for (k, &c) in qr.perm.iter().enumerate() {
            let diff = (qr_prod.column(k) - a.column(c)).norm();
            assert!(diff < 1e-12, "{diff}");
        }
    }

    #[test]
    fn duplicate_column_is_dependent() {
        let mut a = DMatrix::from_fn(5, 3, |i, j| (i + 2 * j) as f64 + 1.0 / (1.0 + i as f64));
        let c0 = a.column(0).into_owned();
        a.set_column(2, &c0);
        let d = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0]);
        let err = solve(a, &d, SolveMode::Exact, 1e-10, 1e-9).unwrap_err();
        match err {
            FfdError::ConflictingConstraints {
                rank, conflicts, ..
            } => {
                assert_eq!(rank, 2);
                assert_eq!(conflicts.len(), 1);
                assert_eq!(conflicts[0].involved(), vec![0, 2]);
            }
            e => panic!("{e}"),
        }
    }
}

#[cfg(test)]
mod pinv_tests {
    use super::*;
    use nalgebra::SVD;

    #[test]
    fn least_squares_matches_the_svd_pseudo_inverse() {
        // A tall (n_u x m) matrix with a repeated and a combined column: rank 3 of 5.
        let mut a = DMatrix::from_fn(20, 5, |i, j| {
            ((i * 13 + j * 7) % 11) as f64 / 11.0 + 0.01 * (i * j) as f64
        });
        let c0 = a.column(0).into_owned();
        a.set_column(3, &c0);
        let c4 = a.column(1) * 0.5 - a.column(2) * 2.0;
        a.set_column(4, &c4);
        let d = DMatrix::from_fn(5, 3, |i, j| ((i + 2 * j) % 4) as f64);
        let tol = 1e-10 * a.norm();
        let qr = pivoted_qr(a.clone(), tol);
        assert_eq!(qr.rank, 3);
        let ours = least_squares_solve(&qr, &d);
        // nalgebra's SVD on the tall orientation (its wide-matrix SVD is unreliable for
        // rank-deficient input in nalgebra 0.35).
        let pinv_a = SVD::new(a.clone(), true, true).pseudo_inverse(tol).unwrap(); // m x n
        let delta = pinv_a.transpose() * &d;
        assert!(
            (&ours.delta - &delta).norm() < 1e-12,
            "{}",
            (&ours.delta - &delta).norm()
        );
        let lambda = SVD::new(a.clone(), true, true).pseudo_inverse(tol).unwrap() * &delta;
        assert!((&ours.lambda - &lambda).norm() < 1e-11);
        assert!((&a * &ours.lambda - &ours.delta).norm() < 1e-12);
    }
}
