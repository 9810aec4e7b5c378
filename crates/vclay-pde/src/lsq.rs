//! Small dense least squares by Householder QR with column equilibration and column pivoting.
//!
//! Solves `min |A x - b|` for the collocation system (`dynamic-pde-surfaces.txt` eq 10-12).
//! Eq (12) forms the normal equations `B^T B P = B^T C`, which square the condition number; QR on
//! `B` itself gives the same minimiser without that loss. Columns are first scaled to unit norm
//! (their magnitudes differ by n(n-1)(n-2)(n-3) between trial terms), then Householder steps pick
//! the remaining column of largest norm (rank-revealing QR), and stop when that norm falls below
//! [`RANK_TOLERANCE`] times the first pivot. The columns left over (and columns that are exactly
//! zero) are "free": the returned basic solution sets them to 0, and [`LsqWork::null_vector`]
//! gives the null-space direction of each, so the caller can decide whether the freedom matters
//! (it does not when basic functions coincide at an instant, e.g. `cos v` and `t^2 cos v`, whose
//! sum alone shapes the surface) or is a real gap to report. With `m = n` and full rank this is
//! the direct solve of eq (9).
//!
//! Works in caller-owned buffers, so repeated solves (animation frames) allocate nothing.

/// Relative size below which a pivot counts as zero (after columns are scaled to unit norm).
pub const RANK_TOLERANCE: f64 = 1e-10;

/// Result of a solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LsqInfo {
    /// Residual norm `|A x - b|`.
    pub residual: f64,
    /// Ratio of the first to the last kept pivot of the equilibrated matrix (a condition
    /// estimate of the determined part).
    pub condition: f64,
    /// Numerical rank (kept pivots).
    pub rank: usize,
}

/// Reusable buffers for [`solve`]; after a solve it also holds the factorization needed by
/// [`LsqWork::null_vector`].
#[derive(Clone, Debug, Default)]
pub struct LsqWork {
    scale: Vec<f64>,
    norms2: Vec<f64>,
    v: Vec<f64>,
    perm: Vec<usize>,
    y: Vec<f64>,
    m: usize,
    rank: usize,
}

impl LsqWork {
    /// Columns (original indices) not determined by the last solve: zero columns and columns
    /// beyond the numerical rank, skipped columns excluded.
    pub fn free_columns(&self) -> &[usize] {
        &self.perm[self.rank..]
    }

    /// The null-space vector of free column `f` (original index) for the matrix `a` as left by
    /// the last [`solve`]: `z[f] = 1`, free others 0, and the determined entries such that
    /// `A z = 0` up to the rank tolerance. Length n.
    pub fn null_vector(&self, a: &[f64], n: usize, f: usize) -> Vec<f64> {
        let (m, r) = (self.m, self.rank);
        let mut z = vec![0.0; n];
        // In scaled coordinates: R11 y = -R12[:, f], z_f = 1.
        let mut y = vec![0.0; r];
        for k in (0..r).rev() {
            let mut s = -a[f * m + k];
            for q in k + 1..r {
                s -= a[self.perm[q] * m + k] * y[q];
            }
            y[k] = s / a[self.perm[k] * m + k];
        }
        for k in 0..r {
            let j = self.perm[k];
            z[j] = y[k] / self.scale[j];
        }
        z[f] = if self.scale[f] > 0.0 {
            1.0 / self.scale[f]
        } else {
            1.0
        };
        z
    }
}

/// Solves `min |A x - b|` in place (basic solution: free columns set to 0; see
/// [`LsqWork::free_columns`]).
///
/// `a` is column-major `m x n` (`a[i + j*m]`), overwritten by the factorization; `b` (length m) is
/// overwritten by `Q^T b`; `skip[j] = true` removes column j from the problem (its `x[j]` is 0).
///
/// # Panics
/// If the slice lengths disagree with `m` and `n` (a programming error).
#[track_caller]
pub fn solve(
    m: usize,
    n: usize,
    a: &mut [f64],
    b: &mut [f64],
    skip: &[bool],
    x: &mut [f64],
    work: &mut LsqWork,
) -> LsqInfo {
    assert_eq!(a.len(), m * n);
    assert_eq!(b.len(), m);
    assert_eq!(x.len(), n);
    assert_eq!(skip.len(), n);
    work.scale.clear();
    work.perm.clear();
    work.m = m;
    let mut zero_cols = Vec::new();
    for j in 0..n {
        x[j] = 0.0;
        let col = &mut a[j * m..(j + 1) * m];
        let s = col.iter().map(|v| v * v).sum::<f64>().sqrt();
        let s = if skip[j] || !s.is_finite() { 0.0 } else { s };
        work.scale.push(s);
        if s > 0.0 {
            col.iter_mut().for_each(|v| *v /= s);
            work.perm.push(j);
        } else if !skip[j] {
            zero_cols.push(j);
        }
    }
    let active = work.perm.len();
    let mut first_pivot = 0.0;
    let mut last_pivot = 1.0;
    let mut r = 0;
    // Squared norms of the remaining parts of the columns (rows r..m), downdated after each
    // step and recomputed when cancellation has eaten most of them (as LAPACK's xGEQP3).
    work.norms2.clear();
    work.norms2.resize(n, 0.0);
    for &j in &work.perm {
        work.norms2[j] = 1.0;
    }
    while r < active.min(m) {
        let k = r;
        // Pivot: remaining column of largest norm.
        let mut best = k;
        let mut best_norm = -1.0;
        for (q, &j) in work.perm.iter().enumerate().skip(k) {
            if work.norms2[j] > best_norm {
                best_norm = work.norms2[j];
                best = q;
            }
        }
        work.perm.swap(k, best);
        let jk = work.perm[k];
        // Recompute the pivot's norm exactly (the downdated value only chose it).
        let best_norm = a[jk * m + k..(jk + 1) * m]
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        if k == 0 {
            first_pivot = best_norm;
        }
        if best_norm <= RANK_TOLERANCE * first_pivot || best_norm == 0.0 {
            break;
        }
        last_pivot = best_norm;
        // Householder reflector for column jk, rows k..m, stored below the diagonal with
        // v[0] = 1 implicit; tau = (beta - alpha) / beta.
        let alpha = a[jk * m + k];
        let beta = if alpha >= 0.0 { -best_norm } else { best_norm };
        let v0 = alpha - beta;
        a[jk * m + k] = beta;
        let tau = -v0 / beta;
        work.v.clear();
        for x in &mut a[jk * m + k + 1..(jk + 1) * m] {
            *x /= v0;
            work.v.push(*x);
        }
        let v = &work.v;
        for &j in &work.perm[k + 1..] {
            let col = &mut a[j * m + k..(j + 1) * m];
            let (head, tail) = col.split_first_mut().expect("k < m");
            let dot = tau * (*head + tail.iter().zip(v).map(|(x, y)| x * y).sum::<f64>());
            *head -= dot;
            for (x, y) in tail.iter_mut().zip(v) {
                *x -= dot * y;
            }
            let nj = &mut work.norms2[j];
            *nj -= *head * *head;
            if *nj <= 1e-6 {
                *nj = tail.iter().map(|x| x * x).sum::<f64>();
            }
        }
        let (head, tail) = b[k..].split_first_mut().expect("k < m");
        let dot = tau * (*head + tail.iter().zip(v).map(|(x, y)| x * y).sum::<f64>());
        *head -= dot;
        for (x, y) in tail.iter_mut().zip(v) {
            *x -= dot * y;
        }
        r += 1;
    }
    work.rank = r;
    work.perm.extend_from_slice(&zero_cols);
    // Back substitution R y = (Q^T b)[0..r].
    work.y.clear();
    work.y.resize(r, 0.0);
    for k in (0..r).rev() {
        let mut s = b[k];
        for q in k + 1..r {
            s -= a[work.perm[q] * m + k] * work.y[q];
        }
        work.y[k] = s / a[work.perm[k] * m + k];
    }
    for k in 0..r {
        let j = work.perm[k];
        x[j] = work.y[k] / work.scale[j];
    }
    let residual = b[r..].iter().map(|v| v * v).sum::<f64>().sqrt();
    LsqInfo {
        residual,
        condition: if r == 0 {
            1.0
        } else {
            first_pivot / last_pivot
        },
        rank: r,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_overdetermined_consistent_system() {
        // A = [[1,0],[1,1],[1,2]] col-major, x = (2, -1): b = (2, 1, 0).
        let mut a = vec![1.0, 1.0, 1.0, 0.0, 1.0, 2.0];
        let mut b = vec![2.0, 1.0, 0.0];
        let mut x = vec![0.0; 2];
        let info = solve(
            3,
            2,
            &mut a,
            &mut b,
            &[false; 2],
            &mut x,
            &mut LsqWork::default(),
        );
        assert_eq!(info.rank, 2);
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] + 1.0).abs() < 1e-12,
            "{x:?}"
        );
        assert!(info.residual < 1e-12);
    }

    #[test]
    fn least_squares_matches_normal_equations() {
        // Fit a line to (0,0), (1,1), (2,1): slope 0.5, intercept 1/6.
        let mut a = vec![1.0, 1.0, 1.0, 0.0, 1.0, 2.0];
        let mut b = vec![0.0, 1.0, 1.0];
        let mut x = vec![0.0; 2];
        let info = solve(
            3,
            2,
            &mut a,
            &mut b,
            &[false; 2],
            &mut x,
            &mut LsqWork::default(),
        );
        assert_eq!(info.rank, 2);
        assert!((x[0] - 1.0 / 6.0).abs() < 1e-12 && (x[1] - 0.5).abs() < 1e-12);
        assert!((info.residual - (1.0f64 / 6.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn dependent_columns_are_reported() {
        let mut a = vec![1.0, 2.0, 3.0, 2.0, 4.0, 6.0];
        let mut b = vec![1.0, 1.0, 1.0];
        let a0 = a.clone();
        let mut x = vec![0.0; 2];
        let mut w = LsqWork::default();
        let info = solve(3, 2, &mut a, &mut b, &[false; 2], &mut x, &mut w);
        assert_eq!(info.rank, 1);
        assert_eq!(w.free_columns().len(), 1);
        // The null vector is a null vector of the original matrix.
        let f = w.free_columns()[0];
        let z = w.null_vector(&a, 2, f);
        for i in 0..3 {
            let az = a0[i] * z[0] + a0[3 + i] * z[1];
            assert!(az.abs() < 1e-12, "{z:?}");
        }
    }
}
