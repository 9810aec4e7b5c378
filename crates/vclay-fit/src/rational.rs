//! Dynamic weights: the rational fit (D-NURBS with control points *and* weights as generalized
//! coordinates, `d-nurbs.txt` eqs 3-6).
//!
//! With the parameters `(u_k, v_k)` fixed, the surface
//! `S = sum_a R_a P_a`, `R_a = N_a w_a / W`, `W = sum_a N_a w_a` is non-linear in the weights.
//! Its Jacobian columns are those of eq 6: `dS/dP_a = R_a I` and `dS/dw_a = N_a (P_a - S) / W`.
//! Each iteration is one damped Gauss-Newton (Levenberg-Marquardt) step on
//! ```text
//! F(P, w) = 1/(2W) sum_k w_k |S(u_k, v_k) - x_k|^2 + 1/2 P^T K(w) P + lambda/2 |w - 1|^2,
//! ```
//! where `K(w)` is eq 17's stiffness in the rational basis with the weights of the iteration
//! frozen (the engine's frozen-weight element matrices, `vclay_dynamics`, footnote 2 of the
//! paper), and the small `lambda` (1e-4 of the mean diagonal of the weight block) removes the
//! one direction the data cannot see (scaling every weight by one factor leaves `S` unchanged).
//! The normal matrix is banded over the net with 4 x 4 blocks (x, y, z, w per control point),
//! factored by faer's sparse Cholesky. A step is accepted only if `F` decreases (else the
//! damping grows tenfold, at most 6 times), and weights stay in `[W_MIN, W_MAX]`. After each
//! step the parameters are corrected (closest points, [`crate::project`]).
//!
//! This is a static Gauss-Newton solve of the fitting problem, not a time integration of eq 18:
//! the result is the rest state that the generalized engine would reach with the same springs
//! and energy, without the mass and damping terms.

use crate::{FitError, project_all};
use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};
use vclay_dynamics::dnurbs::Element;
use vclay_spline::NurbsSurface;

/// Smallest weight allowed.
pub const W_MIN: f64 = 0.05;
/// Largest weight allowed.
pub const W_MAX: f64 = 20.0;

/// The result of [`refine`].
#[derive(Clone, Debug)]
pub struct Rational {
    /// The rational surface.
    pub surface: NurbsSurface,
    /// Its fairness energy `1/2 P^T K(w) P`.
    pub energy: f64,
    /// The objective `F` after each accepted iteration.
    pub objective: Vec<f64>,
}

fn energy(elements: &[Element], p: &[Vec3]) -> f64 {
    let mut u = 0.0;
    for e in elements {
        let nd = e.dofs.len();
        for a in 0..nd {
            for b in 0..nd {
                u += e.stiffness[a * nd + b] * p[e.dofs[a]].dot(&p[e.dofs[b]]);
            }
        }
    }
    0.5 * u
}

/// Weighted data term `1/(2W) sum w |S(u_k) - x_k|^2` at fixed parameters.
fn data_term(
    s: &NurbsSurface,
    points: &[Vec3],
    params: &[[f64; 2]],
    w: &[f64],
    par: Parallelism,
) -> f64 {
    let ev = crate::project::Evaluator::new(s);
    let f = |(k, x): (usize, &Vec3)| {
        let mut sc = ev.scratch();
        let e = ev.eval(params[k][0], params[k][1], &mut sc);
        w[k] * (e.s - x).norm_squared()
    };
    let (sum, wsum): (f64, f64) =
        if par.is_parallel_from(points.len(), crate::system::PARALLEL_POINTS) {
            (
                points.par_iter().enumerate().map(f).sum(),
                w.par_iter().sum(),
            )
        } else {
            (points.iter().enumerate().map(f).sum(), w.iter().sum())
        };
    0.5 * sum / wsum
}

/// Runs `iterations` damped Gauss-Newton steps from `surface` (module docs), correcting
/// `params` after each.
pub fn refine(
    mut surface: NurbsSurface,
    points: &[Vec3],
    params: &mut [[f64; 2]],
    weights: &[f64],
    alpha: [f64; 2],
    beta: [f64; 3],
    iterations: usize,
    par: Parallelism,
) -> Result<Rational, FitError> {
    let mut elements = crate::energy::engine_elements(&surface, alpha, beta)?;
    let mut lambda = None;
    let mut objective = Vec::new();
    let mut distances = vec![0.0; points.len()];
    let total = |s: &NurbsSurface, el: &[Element], lam: f64, prm: &[[f64; 2]]| {
        data_term(s, points, prm, weights, par)
            + energy(el, s.control_points())
            + 0.5 * lam * s.weights().iter().map(|w| (w - 1.0).powi(2)).sum::<f64>()
    };
    let mut mu_scale = 1e-6;
    for _ in 0..iterations {
        let (mut band, mut grad, wsum) = assemble(&surface, points, params, weights, par);
        let [nu, nv] = [
            surface.knots()[0].control_points(),
            surface.knots()[1].control_points(),
        ];
        let n = nu * nv;
        let [p, q] = surface.degree();
        let (bu, bv) = (2 * p + 1, 2 * q + 1);
        let bw = bu * bv;
        let centre = p * bv + q;
        let inv = 1.0 / wsum;
        for b in band.iter_mut() {
            *b *= inv;
        }
        for g in grad.iter_mut() {
            *g *= inv;
        }
        let lam = *lambda.get_or_insert_with(|| {
            let s: f64 = (0..n).map(|i| band[(i * bw + centre) * 16 + 15]).sum();
            1e-4 * s / n as f64
        });
        // Fairness on P (x, y, z blocks), the gauge term on w.
        let ctrl = surface.control_points().to_vec();
        let wts = surface.weights().to_vec();
        for e in &elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                let (ia, ja) = (e.dofs[a] / nv, e.dofs[a] % nv);
                for b in 0..nd {
                    let (ib, jb) = (e.dofs[b] / nv, e.dofs[b] % nv);
                    let off = (ib + p - ia) * bv + jb + q - ja;
                    let k = e.stiffness[a * nd + b];
                    for c in 0..3 {
                        band[(e.dofs[a] * bw + off) * 16 + c * 4 + c] += k;
                        grad[e.dofs[a] * 4 + c] += k * ctrl[e.dofs[b]][c];
                    }
                }
            }
        }
        for i in 0..n {
            band[(i * bw + centre) * 16 + 15] += lam;
            grad[i * 4 + 3] += lam * (wts[i] - 1.0);
        }
        let f0 = total(&surface, &elements, lam, params);
        let mean_diag: f64 = (0..4 * n)
            .map(|r| band[((r / 4) * bw + centre) * 16 + (r % 4) * 5])
            .sum::<f64>()
            / (4 * n) as f64;
        let mut accepted = None;
        for _ in 0..6 {
            let mu = mu_scale * mean_diag;
            let step = solve4(&band, &grad, [nu, nv], [p, q], mu)?;
            // Keep the weights in range by shortening the step.
            let mut t = 1.0f64;
            for i in 0..n {
                let nw = wts[i] - step[i * 4 + 3];
                if nw < W_MIN {
                    t = t.min((wts[i] - W_MIN) / step[i * 4 + 3]);
                } else if nw > W_MAX {
                    t = t.min((W_MAX - wts[i]) / -step[i * 4 + 3]);
                }
            }
            let t = t.clamp(0.0, 1.0);
            let np: Vec<Vec3> = (0..n)
                .map(|i| ctrl[i] - Vec3::new(step[i * 4], step[i * 4 + 1], step[i * 4 + 2]) * t)
                .collect();
            let nw: Vec<f64> = (0..n)
                .map(|i| (wts[i] - t * step[i * 4 + 3]).clamp(W_MIN, W_MAX))
                .collect();
            let cand = NurbsSurface::from_flat(surface.knots().clone(), np, nw)
                .map_err(|e| FitError::Diverged { why: e.to_string() })?;
            let f1 = total(&cand, &elements, lam, params);
            if f1.is_finite() && f1 < f0 {
                accepted = Some((cand, f1));
                mu_scale = (mu_scale * 0.3).max(1e-9);
                break;
            }
            mu_scale *= 10.0;
        }
        let Some((cand, f1)) = accepted else { break };
        surface = cand;
        objective.push(f1);
        elements = crate::energy::engine_elements(&surface, alpha, beta)?;
        project_all(
            &surface,
            points,
            params,
            &mut distances,
            crate::CORRECTION_NEWTON_STEPS,
            1e-9,
            false,
            par,
        );
    }
    let energy_value = energy(&elements, surface.control_points());
    if !energy_value.is_finite() {
        return Err(FitError::Diverged {
            why: "the rational fit's energy is not finite".into(),
        });
    }
    Ok(Rational {
        surface,
        energy: energy_value,
        objective,
    })
}

/// `J^T D J` (4 x 4 blocks, banded as [`crate::system::Normal`]) and `J^T D r`, un-normalized,
/// and the total weight.
fn assemble(
    s: &NurbsSurface,
    points: &[Vec3],
    params: &[[f64; 2]],
    weights: &[f64],
    par: Parallelism,
) -> (Vec<f64>, Vec<f64>, f64) {
    let [ku, kv] = s.knots();
    let (p, q) = (ku.degree(), kv.degree());
    let nv = kv.control_points();
    let n = ku.control_points() * nv;
    let (bu, bv) = (2 * p + 1, 2 * q + 1);
    let bw = bu * bv;
    let cp = s.control_points();
    let cw = s.weights();
    let l = (p + 1) * (q + 1);
    let chunk = |range: std::ops::Range<usize>| {
        let mut band = vec![0.0; n * bw * 16];
        let mut grad = vec![0.0; n * 4];
        let mut wsum = 0.0;
        let mut nu_b = vec![0.0; p + 1];
        let mut nv_b = vec![0.0; q + 1];
        let mut nn = vec![0.0; l];
        let mut r_a = vec![0.0; l];
        let mut d_a = vec![Vec3::zeros(); l];
        for k in range {
            let wk = weights[k];
            if wk == 0.0 {
                continue;
            }
            wsum += wk;
            let [u, v] = params[k];
            let (su, sv) = (ku.find_span(u), kv.find_span(v));
            ku.basis(su, u, &mut nu_b);
            kv.basis(sv, v, &mut nv_b);
            let base = (su - p) * nv + sv - q;
            let (mut wt, mut a) = (0.0, Vec3::zeros());
            for i in 0..=p {
                for j in 0..=q {
                    let g = base + i * nv + j;
                    let nij = nu_b[i] * nv_b[j];
                    nn[i * (q + 1) + j] = nij;
                    wt += nij * cw[g];
                    a += cp[g] * (nij * cw[g]);
                }
            }
            let sp = a / wt;
            let r = sp - points[k];
            for i in 0..=p {
                for j in 0..=q {
                    let la = i * (q + 1) + j;
                    let g = base + i * nv + j;
                    r_a[la] = nn[la] * cw[g] / wt;
                    d_a[la] = (cp[g] - sp) * (nn[la] / wt);
                }
            }
            for ia in 0..=p {
                for ja in 0..=q {
                    let la = ia * (q + 1) + ja;
                    let ga = base + ia * nv + ja;
                    let (ra, da) = (r_a[la] * wk, d_a[la] * wk);
                    for c in 0..3 {
                        grad[ga * 4 + c] += ra * r[c];
                    }
                    grad[ga * 4 + 3] += da.dot(&r);
                    for ib in 0..=p {
                        for jb in 0..=q {
                            let lb = ib * (q + 1) + jb;
                            let off = (ib + p - ia) * bv + jb + q - ja;
                            let blk = &mut band[(ga * bw + off) * 16..(ga * bw + off + 1) * 16];
                            let rr = ra * r_a[lb];
                            let db = d_a[lb];
                            blk[0] += rr;
                            blk[5] += rr;
                            blk[10] += rr;
                            for c in 0..3 {
                                blk[c * 4 + 3] += ra * db[c];
                                blk[12 + c] += da[c] * r_a[lb];
                            }
                            blk[15] += da.dot(&db);
                        }
                    }
                }
            }
        }
        (band, grad, wsum)
    };
    let np = points.len();
    if par.is_parallel_from(np, crate::system::PARALLEL_POINTS) {
        let tasks = rayon::current_num_threads().max(1);
        let size = np.div_ceil(tasks).max(1);
        (0..tasks)
            .into_par_iter()
            .map(|t| chunk((t * size).min(np)..((t + 1) * size).min(np)))
            .reduce(
                || (vec![0.0; n * bw * 16], vec![0.0; n * 4], 0.0),
                |mut a, b| {
                    a.0.iter_mut().zip(&b.0).for_each(|(x, y)| *x += y);
                    a.1.iter_mut().zip(&b.1).for_each(|(x, y)| *x += y);
                    a.2 += b.2;
                    a
                },
            )
    } else {
        chunk(0..np)
    }
}

/// Solves `(H + mu I) step = grad` for the block-banded `H`.
fn solve4(
    band: &[f64],
    grad: &[f64],
    dims: [usize; 2],
    degree: [usize; 2],
    mu: f64,
) -> Result<Vec<f64>, FitError> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let [nu, nv] = dims;
    let [p, q] = degree;
    let n = nu * nv;
    let bv = 2 * q + 1;
    let bw = (2 * p + 1) * bv;
    let mut trips = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let row = i * nv + j;
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
                    let col = ii as usize * nv + jj as usize;
                    if col > row {
                        continue;
                    }
                    let blk =
                        &band[(row * bw + di * bv + dj) * 16..(row * bw + di * bv + dj + 1) * 16];
                    for a in 0..4 {
                        for b in 0..4 {
                            let (r, c) = (row * 4 + a, col * 4 + b);
                            if c > r {
                                continue;
                            }
                            let mut v = blk[a * 4 + b];
                            if r == c {
                                v += mu;
                            }
                            trips.push(Triplet::new(r, c, v));
                        }
                    }
                }
            }
        }
    }
    let m = 4 * n;
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trips).map_err(|e| {
        FitError::Singular {
            why: format!("rational pattern: {e:?}"),
        }
    })?;
    let llt = mat
        .sp_cholesky(faer::Side::Lower)
        .map_err(|e| FitError::Singular {
            why: format!("rational Cholesky: {e:?}"),
        })?;
    let mut b = faer::Mat::<f64>::zeros(m, 1);
    for (k, g) in grad.iter().enumerate() {
        b[(k, 0)] = *g;
    }
    llt.solve_in_place(b.as_mut());
    Ok((0..m).map(|k| b[(k, 0)]).collect())
}
