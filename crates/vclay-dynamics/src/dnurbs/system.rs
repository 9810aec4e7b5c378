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
    /// The global matrices in compressed-row form, assembled once on first use (frozen weights
    /// make them constant); products use them instead of the element loop.
    csr: std::sync::OnceLock<Csr3>,
}

/// `M`, `D` and `K` sharing one compressed-row pattern.
#[derive(Clone, Debug)]
struct Csr3 {
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    /// Interleaved `[m, d, k]` per entry.
    vals: Vec<[f64; 3]>,
}

impl Csr3 {
    /// `(M x, D x)` in one pass.
    fn mass_damping(&self, x: &[Vec3], mx: &mut [Vec3], dx: &mut [Vec3]) {
        let row = |(i, (m, d)): (usize, (&mut Vec3, &mut Vec3))| {
            let (mut sm, mut sd) = (Vec3::zeros(), Vec3::zeros());
            let r = self.row_ptr[i]..self.row_ptr[i + 1];
            for (&j, v) in self.cols[r.clone()].iter().zip(&self.vals[r]) {
                sm += x[j] * v[0];
                sd += x[j] * v[1];
            }
            *m = sm;
            *d = sd;
        };
        if mx.len() >= 4 * PARALLEL_ELEMENTS {
            mx.par_iter_mut()
                .zip(dx.par_iter_mut())
                .enumerate()
                .for_each(row);
        } else {
            mx.iter_mut().zip(dx.iter_mut()).enumerate().for_each(row);
        }
    }

    /// The end-of-step pass (see [`ElementSystem::step_products`]). The three vectors each
    /// entry reads (`x`, `x - p`, `x - rest`) are packed per point first, so the pass gathers
    /// one record per matrix entry.
    fn step_products(&self, inp: StepInputs<'_>, out: StepOutputs<'_>) -> (f64, f64) {
        let StepInputs { x, p, inv_dt, rest } = inp;
        let packed: Vec<[Vec3; 3]> = (0..x.len())
            .map(|i| [x[i], x[i] - p[i], rest.map_or(x[i], |r| x[i] - r[i])])
            .collect();
        let row = |(i, ((m, d), k)): (usize, ((&mut Vec3, &mut Vec3), &mut Vec3))| {
            let (mut sm, mut sd, mut sk) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
            let (mut mv, mut kd) = (Vec3::zeros(), Vec3::zeros());
            let r = self.row_ptr[i]..self.row_ptr[i + 1];
            for (&j, v) in self.cols[r.clone()].iter().zip(&self.vals[r]) {
                let [xj, vj, ej] = &packed[j];
                sm += xj * v[0];
                sd += xj * v[1];
                sk += xj * v[2];
                mv += vj * v[0];
                kd += ej * v[2];
            }
            *m = sm;
            *d = sd;
            *k = sk;
            let [_, vi, ei] = &packed[i];
            (vi.dot(&mv) * inv_dt * inv_dt, ei.dot(&kd))
        };
        let StepOutputs { mx, dx, kx } = out;
        let add = |a: (f64, f64), b: (f64, f64)| (a.0 + b.0, a.1 + b.1);
        if mx.len() >= 4 * PARALLEL_ELEMENTS {
            mx.par_iter_mut()
                .zip(dx.par_iter_mut())
                .zip(kx.par_iter_mut())
                .enumerate()
                .map(row)
                .reduce(|| (0.0, 0.0), add)
        } else {
            mx.iter_mut()
                .zip(dx.iter_mut())
                .zip(kx.iter_mut())
                .enumerate()
                .map(row)
                .fold((0.0, 0.0), add)
        }
    }

    fn assemble(n: usize, elements: &[Element]) -> Self {
        let mut rows: Vec<Vec<(usize, [f64; 3])>> = vec![Vec::new(); n];
        for e in elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                for b in 0..nd {
                    let k = a * nd + b;
                    rows[e.dofs[a]].push((e.dofs[b], [e.mass[k], e.damping[k], e.stiffness[k]]));
                }
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut vals: Vec<[f64; 3]> = Vec::new();
        row_ptr.push(0);
        for mut r in rows {
            r.sort_by_key(|x| x.0);
            let start = cols.len();
            for (c, v) in r {
                if cols.len() > start && *cols.last().expect("non-empty") == c {
                    let last = vals.last_mut().expect("non-empty");
                    for t in 0..3 {
                        last[t] += v[t];
                    }
                } else {
                    cols.push(c);
                    vals.push(v);
                }
            }
            row_ptr.push(cols.len());
        }
        Self {
            row_ptr,
            cols,
            vals,
        }
    }

    fn apply(&self, coeffs: [f64; 3], x: &[Vec3], out: &mut [Vec3]) {
        let row = |i: usize| {
            let mut s = Vec3::zeros();
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                let v = self.vals[k];
                s += x[self.cols[k]] * (coeffs[0] * v[0] + coeffs[1] * v[1] + coeffs[2] * v[2]);
            }
            s
        };
        if out.len() >= 4 * PARALLEL_ELEMENTS {
            out.par_iter_mut()
                .enumerate()
                .for_each(|(i, o)| *o = row(i));
        } else {
            for (i, o) in out.iter_mut().enumerate() {
                *o = row(i);
            }
        }
    }
}

/// Inputs of [`ElementSystem::step_products`].
pub(crate) struct StepInputs<'a> {
    pub x: &'a [Vec3],
    pub p: &'a [Vec3],
    pub inv_dt: f64,
    pub rest: Option<&'a [Vec3]>,
}

/// Outputs of [`ElementSystem::step_products`]: `M x`, `D x`, `K x`.
pub(crate) struct StepOutputs<'a> {
    pub mx: &'a mut [Vec3],
    pub dx: &'a mut [Vec3],
    pub kx: &'a mut [Vec3],
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
    /// A system from its elements.
    pub fn new(n: usize, elements: Vec<Element>) -> Self {
        Self {
            n,
            elements,
            csr: std::sync::OnceLock::new(),
        }
    }

    /// `out = (a_m M + a_d D + a_k K) x` with the assembled matrices.
    pub fn apply(&self, coeffs: [f64; 3], x: &[Vec3], out: &mut [Vec3]) {
        self.csr
            .get_or_init(|| Csr3::assemble(self.n, &self.elements))
            .apply(coeffs, x, out);
    }

    fn csr(&self) -> &Csr3 {
        self.csr
            .get_or_init(|| Csr3::assemble(self.n, &self.elements))
    }

    /// `(M x, D x)` in one pass over the assembled matrices.
    pub fn mass_damping_products(&self, x: &[Vec3], mx: &mut [Vec3], dx: &mut [Vec3]) {
        self.csr().mass_damping(x, mx, dx);
    }

    /// One pass at the end of an implicit step at the new points `x` (previous points `p`):
    /// writes `M x`, `D x`, `K x` (the next step's right-hand side and this step's residual
    /// need them) and returns the forms `v^T M v` and `e^T K e` with `v = (x - p) inv_dt` and
    /// `e = x - rest` (`e = x` without a rest shape), summed over coordinates.
    pub(crate) fn step_products(&self, inp: StepInputs<'_>, out: StepOutputs<'_>) -> (f64, f64) {
        self.csr().step_products(inp, out)
    }

    /// `out = (a_m M + a_d D + a_k K) x` element by element, without assembly (`d-nurbs.txt`
    /// section 5); gives the same result as [`ElementSystem::apply`].
    pub fn apply_elementwise(&self, coeffs: [f64; 3], x: &[Vec3], out: &mut [Vec3]) {
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
        self.add_springs(x, out);
    }

    /// `out += a_k sum k r r^T x` (the rank-one springs' part of the operator).
    pub(crate) fn add_springs(&self, x: &[Vec3], out: &mut [Vec3]) {
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
    // Relative residuals use the norm of the whole right-hand side (all three coordinates), so a
    // coordinate whose right-hand side is ~0 does not make the ratio meaningless.
    let bnorm = {
        let mut s = 0.0;
        for (i, v) in b.iter().enumerate() {
            if !fixed[i] {
                s += v.norm_squared();
            }
        }
        Vec3::repeat(s.sqrt())
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

/// A cached sparse Cholesky factorization of the reduced system matrix (free control points
/// only). With frozen weights the matrix changes only when the time step, the delta springs or
/// the set of fixed points change, so one factorization serves many steps (faer's supernodal
/// Cholesky with a fill-reducing ordering).
pub(crate) struct DirectSolver {
    key: u64,
    free: Vec<usize>,
    /// `A_free,fixed x_fixed` for the fixed positions it was computed with.
    coupling: Option<(Vec<Vec3>, Vec<Vec3>)>,
    llt: faer::sparse::linalg::solvers::Llt<usize, f64>,
}

impl std::fmt::Debug for DirectSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DirectSolver {{ free: {} }}", self.free.len())
    }
}

impl Clone for DirectSolver {
    fn clone(&self) -> Self {
        Self {
            key: self.key,
            free: self.free.clone(),
            coupling: self.coupling.clone(),
            llt: self.llt.clone(),
        }
    }
}

fn operator_key(op: &Operator<'_>, fixed: &[bool]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for c in op.coeffs {
        c.to_bits().hash(&mut h);
    }
    fixed.hash(&mut h);
    for s in op.springs {
        s.indices.hash(&mut h);
        for v in &s.values {
            v.to_bits().hash(&mut h);
        }
        s.k.to_bits().hash(&mut h);
    }
    h.finish()
}

/// Error of a direct factorization: the reduced matrix is not positive definite (for example a
/// static solve with nothing fixed, where rigid translations have zero stiffness).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct NotPositiveDefinite;

impl DirectSolver {
    fn factor(op: &Operator<'_>, fixed: &[bool]) -> Result<Self, NotPositiveDefinite> {
        use faer::sparse::{SparseColMat, Triplet};
        let n = op.sys.n;
        let mut pos = vec![usize::MAX; n];
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        for (k, &i) in free.iter().enumerate() {
            pos[i] = k;
        }
        let mut trips = Vec::new();
        let c = op.coeffs;
        for e in &op.sys.elements {
            let nd = e.dofs.len();
            for a in 0..nd {
                let ra = pos[e.dofs[a]];
                if ra == usize::MAX {
                    continue;
                }
                for b in 0..nd {
                    let rb = pos[e.dofs[b]];
                    if rb == usize::MAX || rb > ra {
                        continue;
                    }
                    let k = a * nd + b;
                    let v = c[0] * e.mass[k] + c[1] * e.damping[k] + c[2] * e.stiffness[k];
                    trips.push(Triplet::new(ra, rb, v));
                }
            }
        }
        for s in op.springs {
            for (&i, &ri) in s.indices.iter().zip(&s.values) {
                for (&j, &rj) in s.indices.iter().zip(&s.values) {
                    let (a, b) = (pos[i], pos[j]);
                    if a != usize::MAX && b != usize::MAX && b <= a {
                        trips.push(Triplet::new(a, b, c[2] * s.k * ri * rj));
                    }
                }
            }
        }
        let m = free.len();
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trips)
            .map_err(|_| NotPositiveDefinite)?;
        let llt = mat
            .sp_cholesky(faer::Side::Lower)
            .map_err(|_| NotPositiveDefinite)?;
        Ok(Self {
            key: operator_key(op, fixed),
            free,
            coupling: None,
            llt,
        })
    }
}

/// Solves `A x = b` on the free control points with a (cached) sparse Cholesky factorization.
pub(crate) fn direct_solve(
    cache: &mut Option<DirectSolver>,
    op: &Operator<'_>,
    b: &[Vec3],
    x: &mut [Vec3],
    fixed: &[bool],
    verify: bool,
    together: bool,
) -> Result<SolverStats, NotPositiveDefinite> {
    use faer::linalg::solvers::Solve;
    let n = op.sys.n;
    let key = operator_key(op, fixed);
    if cache.as_ref().is_none_or(|c| c.key != key) {
        *cache = Some(DirectSolver::factor(op, fixed)?);
    }
    let solver = cache.as_mut().expect("just factored");
    // Move the fixed values to the right-hand side: b_free - A_free,fixed x_fixed (cached while
    // the fixed points stay where they are).
    let fixed_values: Vec<Vec3> = (0..n).filter(|&i| fixed[i]).map(|i| x[i]).collect();
    let fresh = solver
        .coupling
        .as_ref()
        .is_none_or(|(v, _)| *v != fixed_values);
    if fresh {
        let mut axf = vec![Vec3::zeros(); n];
        if !fixed_values.is_empty() {
            let xf: Vec<Vec3> = (0..n)
                .map(|i| if fixed[i] { x[i] } else { Vec3::zeros() })
                .collect();
            op.apply(&xf, &mut axf);
        }
        solver.coupling = Some((fixed_values, axf));
    }
    let solver = cache.as_ref().expect("just factored");
    let axf = &solver.coupling.as_ref().expect("just computed").1;
    let m = solver.free.len();
    let mut rhs = faer::Mat::<f64>::zeros(m, 3);
    for (k, &i) in solver.free.iter().enumerate() {
        for c in 0..3 {
            rhs[(k, c)] = b[i][c] - axf[i][c];
        }
    }
    // The x column on one thread, y and z on another (faer runs sequentially here: its rayon
    // feature is off), for models big enough to pay for the split.
    if together {
        // One call, one pass over the factor for the three columns (`Dnurbs::solve_together`).
        solver.llt.solve_in_place(rhs.as_mut());
    } else if m >= 4 * PARALLEL_ELEMENTS {
        let (first, rest) = rhs.as_mut().split_at_col_mut(1);
        rayon::join(
            || solver.llt.solve_in_place(first),
            || solver.llt.solve_in_place(rest),
        );
    } else {
        solver.llt.solve_in_place(rhs.as_mut());
    }
    for (k, &i) in solver.free.iter().enumerate() {
        x[i] = Vec3::new(rhs[(k, 0)], rhs[(k, 1)], rhs[(k, 2)]);
    }
    // Report the true residual (unless the caller computes it from its own pass).
    let rel = if verify {
        let mut ax = vec![Vec3::zeros(); n];
        op.apply(x, &mut ax);
        relative_residual(b, &ax, fixed)
    } else {
        f64::NAN
    };
    Ok(SolverStats {
        iterations: 0,
        relative_residual: rel,
    })
}

/// `|b - A x| / |b|` over the free entries (all coordinates together), from `ax = A x`.
pub(crate) fn relative_residual(b: &[Vec3], ax: &[Vec3], fixed: &[bool]) -> f64 {
    let (mut rn, mut bn) = (0.0, 0.0);
    for i in 0..b.len() {
        if !fixed[i] {
            rn += (b[i] - ax[i]).norm_squared();
            bn += b[i].norm_squared();
        }
    }
    if bn > 0.0 {
        (rn / bn).sqrt()
    } else {
        rn.sqrt()
    }
}
