//! Element matrices and the matrix-free operator `a_M M + a_D D + a_K K`.
//!
//! Each element stores its scalar mass, damping and stiffness matrices (`d-nurbs.txt` eqs 16-17,
//! frozen weights: the 3x3 blocks are scalar multiples of the identity, so one scalar matrix acts
//! on x, y and z alike). Products with the global matrices are computed element by element and
//! never assembled (`d-nurbs.txt` section 5): each thread accumulates its chunk of elements into
//! its own buffer, and the buffers are summed.

use super::geometry::ElementSamples;
use rayon::prelude::*;
use vclay_core::Vec3;

/// Number of elements above which operator products run in parallel.
pub const PARALLEL_ELEMENTS: usize = 256;

/// One finite element: its degrees of freedom and dense local matrices (row-major, `nd x nd`).
#[derive(Clone, Debug)]
pub struct Element {
    /// Global control-point indices.
    pub dofs: Vec<usize>,
    /// Element mass matrix.
    pub mass: Vec<f64>,
    /// Element damping matrix.
    pub damping: Vec<f64>,
    /// Element stiffness matrix.
    pub stiffness: Vec<f64>,
}

/// All elements of a model.
#[derive(Clone, Debug)]
pub struct ElementSystem {
    /// Number of control points.
    pub n: usize,
    /// The elements.
    pub elements: Vec<Element>,
}

/// Densities evaluated at one quadrature point: `mu, gamma`, tension per direction, rigidity per
/// second-derivative pair.
pub(crate) struct PointDensities<'a> {
    pub mu: f64,
    pub gamma: f64,
    pub alpha: &'a [f64],
    pub beta: &'a [f64],
}

impl Element {
    /// Integrates the element matrices from quadrature samples (`d-nurbs.txt` section 5.2:
    /// `m_ij = sum_g a_g mu(u_g) f_ij(u_g)`).
    pub(crate) fn integrate(
        s: &ElementSamples,
        dim: usize,
        pairs: usize,
        mut densities: impl FnMut(usize, [f64; 2], &mut dyn FnMut(PointDensities<'_>)),
    ) -> Self {
        let nd = s.dofs.len();
        let mut mass = vec![0.0; nd * nd];
        let mut damping = vec![0.0; nd * nd];
        let mut stiffness = vec![0.0; nd * nd];
        for (q, (&param, &w)) in s.params.iter().zip(&s.weights).enumerate() {
            densities(q, param, &mut |d: PointDensities<'_>| {
                let r = &s.values[q * nd..(q + 1) * nd];
                for a in 0..nd {
                    for b in 0..nd {
                        let rr = w * r[a] * r[b];
                        mass[a * nd + b] += d.mu * rr;
                        damping[a * nd + b] += d.gamma * rr;
                    }
                }
                for dir in 0..dim {
                    let r1 = &s.first[(q * dim + dir) * nd..(q * dim + dir + 1) * nd];
                    let c = w * d.alpha[dir];
                    if c != 0.0 {
                        for a in 0..nd {
                            for b in 0..nd {
                                stiffness[a * nd + b] += c * r1[a] * r1[b];
                            }
                        }
                    }
                }
                for pair in 0..pairs {
                    let r2 = &s.second[(q * pairs + pair) * nd..(q * pairs + pair + 1) * nd];
                    let c = w * d.beta[pair];
                    if c != 0.0 {
                        for a in 0..nd {
                            for b in 0..nd {
                                stiffness[a * nd + b] += c * r2[a] * r2[b];
                            }
                        }
                    }
                }
            });
        }
        Self {
            dofs: s.dofs.clone(),
            mass,
            damping,
            stiffness,
        }
    }
}

impl ElementSystem {
    /// `out = (a_m M + a_d D + a_k K) x`.
    pub fn apply(&self, coeffs: [f64; 3], x: &[Vec3], out: &mut [Vec3]) {
        let local = |acc: &mut Vec<Vec3>, e: &Element| {
            let nd = e.dofs.len();
            for a in 0..nd {
                let mut s = Vec3::zeros();
                for b in 0..nd {
                    let k = a * nd + b;
                    let m = coeffs[0] * e.mass[k]
                        + coeffs[1] * e.damping[k]
                        + coeffs[2] * e.stiffness[k];
                    s += x[e.dofs[b]] * m;
                }
                acc[e.dofs[a]] += s;
            }
        };
        if self.elements.len() >= PARALLEL_ELEMENTS {
            let n = self.n;
            let sum = self
                .elements
                .par_chunks(
                    self.elements
                        .len()
                        .div_ceil(rayon::current_num_threads())
                        .max(1),
                )
                .map(|chunk| {
                    let mut acc = vec![Vec3::zeros(); n];
                    for e in chunk {
                        local(&mut acc, e);
                    }
                    acc
                })
                .reduce(
                    || vec![Vec3::zeros(); n],
                    |mut a, b| {
                        for (x, y) in a.iter_mut().zip(&b) {
                            *x += y;
                        }
                        a
                    },
                );
            out.copy_from_slice(&sum);
        } else {
            out.iter_mut().for_each(|o| *o = Vec3::zeros());
            let mut acc = vec![Vec3::zeros(); self.n];
            for e in &self.elements {
                local(&mut acc, e);
            }
            out.copy_from_slice(&acc);
        }
    }

    /// Diagonal of `a_m M + a_d D + a_k K` (Jacobi preconditioner).
    pub fn diagonal(&self, coeffs: [f64; 3]) -> Vec<f64> {
        let mut d = vec![0.0; self.n];
        for e in &self.elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                let k = a * nd + a;
                d[e.dofs[a]] +=
                    coeffs[0] * e.mass[k] + coeffs[1] * e.damping[k] + coeffs[2] * e.stiffness[k];
            }
        }
        d
    }

    /// `x^T A y` summed over the three coordinates, for `A = a_m M + a_d D + a_k K`.
    pub fn quadratic_form(&self, coeffs: [f64; 3], x: &[Vec3], y: &[Vec3]) -> f64 {
        let mut ay = vec![Vec3::zeros(); self.n];
        self.apply(coeffs, y, &mut ay);
        x.iter().zip(&ay).map(|(a, b)| a.dot(b)).sum()
    }

    /// Dense global matrix (for tests and small models).
    pub fn dense(&self, coeffs: [f64; 3]) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(self.n, self.n);
        for e in &self.elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                for b in 0..nd {
                    let k = a * nd + b;
                    m[(e.dofs[a], e.dofs[b])] += coeffs[0] * e.mass[k]
                        + coeffs[1] * e.damping[k]
                        + coeffs[2] * e.stiffness[k];
                }
            }
        }
        m
    }
}

/// Statistics of one linear solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverStats {
    /// Conjugate-gradient iterations taken.
    pub iterations: usize,
    /// Final relative residual `|b - A x| / |b|` (largest over x, y, z).
    pub relative_residual: f64,
}

/// A rank-one stiffness term `k r r^T` over a few control points: an implicit spring of
/// `d-nurbs.txt` eq (19) (`f = k J^T (d0 - J p)` with frozen weights is linear in `p`, so its
/// `k J^T J` part joins the system matrix and the spring stays stable for any stiffness).
#[derive(Clone, Debug)]
pub(crate) struct RankOne {
    pub indices: Vec<usize>,
    pub values: Vec<f64>,
    pub k: f64,
}

/// `A = a_m M + a_d D + a_k (K + sum of rank-one springs)`.
pub(crate) struct Operator<'a> {
    pub sys: &'a ElementSystem,
    pub coeffs: [f64; 3],
    pub springs: &'a [RankOne],
}

impl Operator<'_> {
    fn apply(&self, x: &[Vec3], out: &mut [Vec3]) {
        self.sys.apply(self.coeffs, x, out);
        for s in self.springs {
            let mut dot = Vec3::zeros();
            for (&i, &r) in s.indices.iter().zip(&s.values) {
                dot += x[i] * r;
            }
            let c = self.coeffs[2] * s.k;
            for (&i, &r) in s.indices.iter().zip(&s.values) {
                out[i] += dot * (c * r);
            }
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        let mut d = self.sys.diagonal(self.coeffs);
        for s in self.springs {
            for (&i, &r) in s.indices.iter().zip(&s.values) {
                d[i] += self.coeffs[2] * s.k * r * r;
            }
        }
        d
    }
}

/// Jacobi-preconditioned conjugate gradients on `A x = b` for the free control points (entries
/// with `fixed[i]` keep their value in `x`), run independently on x, y and z.
pub(crate) fn conjugate_gradient(
    op: &Operator<'_>,
    b: &[Vec3],
    x: &mut [Vec3],
    fixed: &[bool],
    max_iterations: usize,
    tolerance: f64,
) -> SolverStats {
    let n = op.sys.n;
    let diag = op.diagonal();
    let inv: Vec<f64> = diag
        .iter()
        .zip(fixed)
        .map(|(&d, &f)| if f || d <= 0.0 { 0.0 } else { 1.0 / d })
        .collect();
    let mut ax = vec![Vec3::zeros(); n];
    op.apply(x, &mut ax);
    let mut r: Vec<Vec3> = (0..n)
        .map(|i| {
            if fixed[i] {
                Vec3::zeros()
            } else {
                b[i] - ax[i]
            }
        })
        .collect();
    let bnorm = {
        let mut s = Vec3::zeros();
        for (i, v) in b.iter().enumerate() {
            if !fixed[i] {
                s += v.component_mul(v);
            }
        }
        s.map(f64::sqrt)
    };
    let norms = |r: &[Vec3]| {
        let mut s = Vec3::zeros();
        for v in r {
            s += v.component_mul(v);
        }
        s.map(f64::sqrt)
    };
    let rel = |rn: Vec3| -> f64 {
        (0..3)
            .map(|c| {
                if bnorm[c] > 0.0 {
                    rn[c] / bnorm[c]
                } else {
                    rn[c]
                }
            })
            .fold(0.0, f64::max)
    };
    let mut z: Vec<Vec3> = r.iter().zip(&inv).map(|(v, &d)| v * d).collect();
    let mut p = z.clone();
    let dot = |a: &[Vec3], b: &[Vec3]| {
        let mut s = Vec3::zeros();
        for (x, y) in a.iter().zip(b) {
            s += x.component_mul(y);
        }
        s
    };
    let mut rz = dot(&r, &z);
    let mut ap = vec![Vec3::zeros(); n];
    let mut stats = SolverStats {
        iterations: 0,
        relative_residual: rel(norms(&r)),
    };
    while stats.iterations < max_iterations && stats.relative_residual > tolerance {
        op.apply(&p, &mut ap);
        for (i, f) in fixed.iter().enumerate() {
            if *f {
                ap[i] = Vec3::zeros();
            }
        }
        let pap = dot(&p, &ap);
        let alpha = Vec3::from_fn(|c, _| if pap[c] > 0.0 { rz[c] / pap[c] } else { 0.0 });
        for i in 0..n {
            x[i] += p[i].component_mul(&alpha);
            r[i] -= ap[i].component_mul(&alpha);
        }
        for i in 0..n {
            z[i] = r[i] * inv[i];
        }
        let rz_new = dot(&r, &z);
        let beta = Vec3::from_fn(|c, _| if rz[c] > 0.0 { rz_new[c] / rz[c] } else { 0.0 });
        for i in 0..n {
            p[i] = z[i] + p[i].component_mul(&beta);
        }
        rz = rz_new;
        stats.iterations += 1;
        stats.relative_residual = rel(norms(&r));
    }
    stats
}
