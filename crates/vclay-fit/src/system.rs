//! The normal equations of the energy-regularized least squares, assembled without forming `A`.
//!
//! For a polynomial tensor-product surface `S(u, v) = sum_I N_I(u, v) P_I` and data `x_k` with
//! parameters `(u_k, v_k)` and weights `w_k`, minimizing
//! `F(P) = 1/(2 W) sum_k w_k |S(u_k, v_k) - x_k|^2 + 1/2 P^T K P` (`W = sum w_k`, `K` of
//! [`crate::energy`]) gives, for each coordinate,
//! ```text
//! (A^T D A / W + K) P = A^T D x / W,      A[k, I] = N_I(u_k, v_k),  D = diag(w_k).
//! ```
//! `A^T D A` is summed point by point from the `(p+1)(q+1)` non-zero basis products straight
//! into a banded array over the net (control point `I = i n_v + j` couples only with
//! `|di| <= p`, `|dj| <= q`: `(2p+1)(2q+1)` entries per row), one array per thread on rayon,
//! summed at the end. The lower triangle goes to faer's sparse Cholesky (supernodal, AMD
//! ordering), solved for the x, y and z right-hand sides at once.

use crate::FitError;
use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};
use vclay_spline::KnotVector;

/// Points per rayon task below which assembly runs on one thread.
pub const PARALLEL_POINTS: usize = 8_192;

/// Banded normal equations over a control net.
#[derive(Clone, Debug)]
pub struct Normal {
    /// Net size `[n_u, n_v]`.
    pub dims: [usize; 2],
    /// Degrees `[p, q]`.
    pub degree: [usize; 2],
    /// `band[I * bw + (di + p) (2q + 1) + dj + q]`, `bw = (2p+1)(2q+1)`.
    pub band: Vec<f64>,
    /// Right-hand sides.
    pub rhs: Vec<Vec3>,
    /// `sum w_k`.
    pub weight: f64,
}

impl Normal {
    /// Band width (entries per row).
    pub fn bw(&self) -> usize {
        (2 * self.degree[0] + 1) * (2 * self.degree[1] + 1)
    }

    fn zeros(dims: [usize; 2], degree: [usize; 2]) -> Self {
        let n = dims[0] * dims[1];
        let bw = (2 * degree[0] + 1) * (2 * degree[1] + 1);
        Self {
            dims,
            degree,
            band: vec![0.0; n * bw],
            rhs: vec![Vec3::zeros(); n],
            weight: 0.0,
        }
    }

    fn add(mut self, other: Self) -> Self {
        for (a, b) in self.band.iter_mut().zip(&other.band) {
            *a += b;
        }
        for (a, b) in self.rhs.iter_mut().zip(&other.rhs) {
            *a += b;
        }
        self.weight += other.weight;
        self
    }

    /// Bytes one banded system takes (per thread during assembly).
    pub fn bytes(dims: [usize; 2], degree: [usize; 2]) -> usize {
        let n = dims[0] * dims[1];
        n * ((2 * degree[0] + 1) * (2 * degree[1] + 1) + 3) * 8
    }
}

/// Sums `A^T D A` and `A^T D x` (un-normalized) over the points.
pub fn assemble(
    knots: &[KnotVector; 2],
    points: &[Vec3],
    params: &[[f64; 2]],
    weights: Option<&[f64]>,
    par: Parallelism,
) -> Normal {
    let dims = [knots[0].control_points(), knots[1].control_points()];
    let degree = [knots[0].degree(), knots[1].degree()];
    let chunk = |range: std::ops::Range<usize>| {
        let mut acc = Normal::zeros(dims, degree);
        match (degree[0], degree[1]) {
            (1, 1) => add_points::<2, 2>(&mut acc, knots, points, params, weights, range),
            (2, 2) => add_points::<3, 3>(&mut acc, knots, points, params, weights, range),
            (3, 3) => add_points::<4, 4>(&mut acc, knots, points, params, weights, range),
            (4, 4) => add_points::<5, 5>(&mut acc, knots, points, params, weights, range),
            (5, 5) => add_points::<6, 6>(&mut acc, knots, points, params, weights, range),
            _ => add_points_any(&mut acc, knots, points, params, weights, range),
        }
        acc
    };
    let n = points.len();
    let mut normal = if par.is_parallel_from(n, PARALLEL_POINTS) {
        let tasks = rayon::current_num_threads().max(1);
        let size = n.div_ceil(tasks).max(1);
        (0..tasks)
            .into_par_iter()
            .map(|t| chunk((t * size).min(n)..((t + 1) * size).min(n)))
            .reduce(|| Normal::zeros(dims, degree), Normal::add)
    } else {
        chunk(0..n)
    };
    mirror_upper(&mut normal.band, dims, degree);
    normal
}

/// Adds the points `range` to `acc` for degrees `P1 - 1`, `Q1 - 1`: the basis on the stack and
/// each row's upper part written as whole runs of `Q1` entries (SIMD-friendly; the entries of
/// a run left of the diagonal are lower-triangle ones, overwritten by [`mirror_upper`]).
fn add_points<const P1: usize, const Q1: usize>(
    acc: &mut Normal,
    knots: &[KnotVector; 2],
    points: &[Vec3],
    params: &[[f64; 2]],
    weights: Option<&[f64]>,
    range: std::ops::Range<usize>,
) {
    let (p, q) = (P1 - 1, Q1 - 1);
    let nv = acc.dims[1];
    let bv = 2 * q + 1;
    let bw = (2 * p + 1) * bv;
    let guess = [
        crate::project::SpanGuess::new(&knots[0]),
        crate::project::SpanGuess::new(&knots[1]),
    ];
    let inv = [
        crate::project::reciprocals(&knots[0]),
        crate::project::reciprocals(&knots[1]),
    ];
    let k = [knots[0].as_slice(), knots[1].as_slice()];
    for i in range {
        let w = weights.map_or(1.0, |w| w[i]);
        if w == 0.0 {
            continue;
        }
        let [u, v] = params[i];
        let su = guess[0].span(&knots[0], u);
        let sv = guess[1].span(&knots[1], v);
        let nu_b = crate::project::basis_fixed::<P1>(k[0], &inv[0], su, u);
        let nv_b = crate::project::basis_fixed::<Q1>(k[1], &inv[1], sv, v);
        let mut prod = [[0.0; Q1]; P1];
        for a in 0..P1 {
            for b in 0..Q1 {
                prod[a][b] = nu_b[a] * nv_b[b];
            }
        }
        let x = points[i] * w;
        acc.weight += w;
        let base = (su - p) * nv + sv - q;
        for a in 0..P1 {
            for b in 0..Q1 {
                let pa = prod[a][b];
                let row = base + a * nv + b;
                acc.rhs[row] += x * pa;
                let wpa = w * pa;
                let r = &mut acc.band[row * bw..(row + 1) * bw];
                // Neighbours (c, d), c >= a: di = c - a, dj = d - b; the run d = 0..=q starts
                // at column (c - a + p) bv + q - b.
                for (c, pc) in prod.iter().enumerate().skip(a) {
                    let off = (c + p - a) * bv + q - b;
                    let run: &mut [f64; Q1] =
                        (&mut r[off..off + Q1]).try_into().expect("Q1 entries");
                    for d in 0..Q1 {
                        run[d] += wpa * pc[d];
                    }
                }
            }
        }
    }
}

/// [`add_points`] for any degrees.
fn add_points_any(
    acc: &mut Normal,
    knots: &[KnotVector; 2],
    points: &[Vec3],
    params: &[[f64; 2]],
    weights: Option<&[f64]>,
    range: std::ops::Range<usize>,
) {
    let dims = acc.dims;
    let degree = acc.degree;
    let (p, q) = (degree[0], degree[1]);
    let nv = dims[1];
    let bv = 2 * q + 1;
    let bw = (2 * p + 1) * bv;
    let mut nu_b = vec![0.0; p + 1];
    let mut nv_b = vec![0.0; q + 1];
    let mut prod = vec![0.0; (p + 1) * (q + 1)];
    for k in range {
        let w = weights.map_or(1.0, |w| w[k]);
        if w == 0.0 {
            continue;
        }
        let [u, v] = params[k];
        let su = knots[0].find_span(u);
        let sv = knots[1].find_span(v);
        knots[0].basis(su, u, &mut nu_b);
        knots[1].basis(sv, v, &mut nv_b);
        for a in 0..=p {
            for b in 0..=q {
                prod[a * (q + 1) + b] = nu_b[a] * nv_b[b];
            }
        }
        let x = points[k] * w;
        acc.weight += w;
        let base = (su - p) * nv + sv - q;
        for a in 0..=p {
            for b in 0..=q {
                let pa = prod[a * (q + 1) + b];
                let row = base + a * nv + b;
                acc.rhs[row] += x * pa;
                let wpa = w * pa;
                let r = &mut acc.band[row * bw..(row + 1) * bw];
                // Neighbours (c, d) at or after (a, b) in the net's order (the upper
                // triangle; mirrored after the sum): di = c - a, dj = d - b.
                for c in a..=p {
                    let d0 = if c == a { b } else { 0 };
                    let off = (c + p - a) * bv + q - b;
                    let pc = &prod[c * (q + 1)..(c + 1) * (q + 1)];
                    for d in d0..=q {
                        r[off + d] += wpa * pc[d];
                    }
                }
            }
        }
    }
}

/// Copies each entry `(I, J)`, `J > I` in the net's order, to `(J, I)`.
fn mirror_upper(band: &mut [f64], dims: [usize; 2], degree: [usize; 2]) {
    let [nu, nv] = dims;
    let [p, q] = degree;
    let bv = 2 * q + 1;
    let bw = (2 * p + 1) * bv;
    for i in 0..nu {
        for j in 0..nv {
            let row = i * nv + j;
            for di in 0..=p {
                if i + di >= nu {
                    break;
                }
                let dj_lo = if di == 0 { 1 } else { -(q as isize) };
                for dj in dj_lo..=q as isize {
                    let jj = j as isize + dj;
                    if jj < 0 || jj >= nv as isize {
                        continue;
                    }
                    let col = (i + di) * nv + jj as usize;
                    let v = band[row * bw + (di + p) * bv + (dj + q as isize) as usize];
                    band[col * bw + (p - di) * bv + (q as isize - dj) as usize] = v;
                }
            }
        }
    }
}

/// Solves `band x = rhs` (three right-hand sides) by faer's sparse Cholesky of the lower
/// triangle.
pub fn solve(normal: &Normal, rhs: &[Vec3]) -> Result<Vec<Vec3>, FitError> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let [nu, nv] = normal.dims;
    let [p, q] = normal.degree;
    let n = nu * nv;
    let bv = 2 * q + 1;
    let bw = normal.bw();
    let mut trips = Vec::with_capacity(n * (bw / 2 + 1));
    for i in 0..nu {
        for j in 0..nv {
            let row = i * nv + j;
            for di in -(p as isize)..=0 {
                let ii = i as isize + di;
                if ii < 0 {
                    continue;
                }
                let djmax = if di == 0 { 0 } else { q as isize };
                for dj in -(q as isize)..=djmax {
                    let jj = j as isize + dj;
                    if jj < 0 || jj >= nv as isize {
                        continue;
                    }
                    let v = normal.band
                        [row * bw + (di + p as isize) as usize * bv + (dj + q as isize) as usize];
                    if v != 0.0 || di == 0 && dj == 0 {
                        trips.push(Triplet::new(row, ii as usize * nv + jj as usize, v));
                    }
                }
            }
        }
    }
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trips).map_err(|e| {
        FitError::Singular {
            why: format!("sparse pattern: {e:?}"),
        }
    })?;
    let llt = mat
        .sp_cholesky(faer::Side::Lower)
        .map_err(|e| FitError::Singular {
            why: format!("Cholesky: {e:?}"),
        })?;
    let mut b = faer::Mat::<f64>::zeros(n, 3);
    for (k, r) in rhs.iter().enumerate() {
        for c in 0..3 {
            b[(k, c)] = r[c];
        }
    }
    llt.solve_in_place(b.as_mut());
    let out: Vec<Vec3> = (0..n)
        .map(|k| Vec3::new(b[(k, 0)], b[(k, 1)], b[(k, 2)]))
        .collect();
    if let Some(k) = out.iter().position(|x| !x.iter().all(|c| c.is_finite())) {
        return Err(FitError::Singular {
            why: format!("control point {k} is not finite"),
        });
    }
    Ok(out)
}

/// `x^T B x` summed over the three coordinates, for a banded `B` (as [`Normal::band`]).
pub fn quadratic_form(band: &[f64], dims: [usize; 2], degree: [usize; 2], x: &[Vec3]) -> f64 {
    let [nu, nv] = dims;
    let [p, q] = degree;
    let bv = 2 * q + 1;
    let bw = (2 * p + 1) * bv;
    let mut s = 0.0;
    for i in 0..nu {
        for j in 0..nv {
            let row = i * nv + j;
            let mut acc = Vec3::zeros();
            for di in 0..2 * p + 1 {
                let ii = i as isize + di as isize - p as isize;
                if ii < 0 || ii >= nu as isize {
                    continue;
                }
                for dj in 0..bv {
                    let jj = j as isize + dj as isize - q as isize;
                    if jj < 0 || jj >= nv as isize {
                        continue;
                    }
                    acc += x[ii as usize * nv + jj as usize] * band[row * bw + di * bv + dj];
                }
            }
            s += x[row].dot(&acc);
        }
    }
    s
}
