//! D-NURBS with the full set of generalized coordinates: control points **and weights**
//! (`d-nurbs.txt` sections 4.1-4.3), for NURBS curves, tensor-product and swung surfaces.
//!
//! ## Equations
//! The Lagrangian of `d-nurbs.txt` eq (15) with the p-dependent matrices of eqs (16)-(17):
//!
//! ```text
//! M(p) p'' + D(p) p' + grad U(p) = f_p + g_p,      g_p = -integral mu J^T (dJ/dt) p'
//! ```
//! Derivation of `g_p` (the paper cites it): with `T = 1/2 integral mu |J p'|^2`,
//! `d/dt dT/dp' = M p'' + integral mu (J'^T J + J^T J') p'` and `dT/dp = integral mu J'^T J p'`
//! (because `d(J p')/dp = J'` for `J = ds/dp`), so the `J'^T` terms cancel and
//! `g_p = -integral mu J^T J' p'`. `J' p'` is the second directional derivative of `s` along the
//! velocity ([`GeneralizedGeometry::velocity_terms`]); it vanishes for frozen weights.
//!
//! The elastic energy is the thin-plate-under-tension functional of eq (17) evaluated on the
//! shape, `U = 1/2 integral sum_a c_a |s^a - s^a_ref|^2` over `a` in `u, v, uu, uv, vv` with
//! `c = (a11, a22, b11, b12, b22)` (curves: `alpha`, `beta`); `s_ref = 0` reproduces the paper's
//! `1/2 p^T K p` where `s = J p`, the rest shape ([`ElasticReference::RestShape`]) keeps a model
//! that is left alone still. Its gradient is `integral sum_a c_a J_a^T (s^a - s^a_ref)` and its
//! Gauss-Newton Hessian is the stiffness matrix `K` of eq (17).
//!
//! ## Time integration
//! Eq (18) with all matrices and forces evaluated at time t, written for the increment
//! `dp = p(t+dt) - p(t)` with `v = p(t) - p(t-dt)` and `K dp + grad U` in place of `K p(t+dt)`
//! (identical when `s = J p`, a linearized implicit step otherwise):
//!
//! ```text
//! (2M + dt D + 2 dt^2 K) dp = 2 dt^2 (f_p + g_p - grad U) + (2M - dt D) v
//! ```
//! solved by a sparse Cholesky factorization refactored every step on a symbolic analysis
//! cached per set of fixed coordinates ([`LinearSolver::Direct`], the default for tensor-product
//! geometries; opt-in [`GeneralizedDnurbs::block_schur`]: where the Jacobian's `R_i I3` blocks
//! make the matrix `[[S (x) I3, B], [B^T, C]]`, `S` and `C` factored apart and conjugate
//! gradients on the Schur complement, module `block_schur`), or by
//! block-Jacobi-preconditioned conjugate gradients (one 4x4 block per control
//! point: x, y, z, w), warm-started from `v`, with an iteration cap and a relative residual
//! tolerance (the paper capped CG at 10 iterations; the default for swung surfaces). The element
//! matrices are computed in parallel per element (section 5.1): the Jacobian rows of all the
//! element's quadrature points are stacked and the structured `J^T J` blocks formed by one small
//! tiled product (`Gram`). Because the elements' coordinates never change, they are summed
//! each step into a CSR matrix with a pattern built once. Delta springs (eq 19) and data springs
//! add `k J^T J` to the implicit matrix.
//!
//! ## Constraints (section 6.2)
//! Fixed coordinates (control points, single weights, `alpha`) are removed from the unknowns
//! (reduction to the free coordinates). Their rows and columns of the step matrix are never
//! used, so the element products leave them out (a geometry computes only the order-0 columns
//! of a wholly fixed control point, which the lumped mass and the velocity term still read;
//! the CSR pattern is rebuilt when the fixed set changes). On the corner rounding, 60 of 78
//! control points held, this cut a step about 2-fold; the unit tests check that no step
//! changes. Point constraints `s(u0) = d` and normal constraints
//! `s_u . n = s_v . n = 0` at `u0` are nonlinear in `p` once weights move; they are enforced by
//! Lagrange multipliers on the linearized step with Baumgarte-style feedback: each step asks
//! `C(p) + C_p dp = (1 - kappa) C(p)` for the constraint values `C`, with `kappa`
//! ([`GeneralizedDnurbs::baumgarte`], default 1: the violation is removed in one step). The
//! multipliers come from the Schur complement `C_p A^-1 C_p^T` (one CG solve per constraint row).
//! Repeated, contradictory or unsatisfiable constraints (rows that are linearly dependent on the
//! free coordinates) are reported by index.
//!
//! ## Weights
//! After every step, weights below [`GeneralizedDnurbs::weight_floor`] are projected back to it
//! (section 6.2); optionally a penalty `c/2 sum (w - w0)^2` holds them near their initial values
//! ([`GeneralizedDnurbs::set_weight_penalty`]). Because `s` does not change when every weight of
//! a NURBS is scaled by the same factor, one weight per rational curve or surface is held fixed
//! by default (a gauge choice that changes no shape).

use super::{Density, ElasticReference, Force, Integrator, LinearSolver, Material, StepReport};
use crate::SolverStats;
use crate::error::DynamicsError;
use rayon::prelude::*;
use std::sync::Arc;
use vclay_core::{GaussLegendre, Vec3};

mod block_schur;
pub use block_schur::{
    BLOCK_SCHUR_CONSTRAINT_ROWS, BLOCK_SCHUR_ITERATIONS, BLOCK_SCHUR_TOLERANCE, BlockSchur,
};
use block_schur::{SchurBuffers, SchurFactor, SchurPattern};

/// Values and Jacobian columns of a geometry at one parameter, for the six parametric
/// derivatives `s, s_u, s_v, s_uu, s_uv, s_vv` (see [`super::rational::MULTI_INDICES`]).
#[derive(Clone, Debug, Default)]
pub struct LocalJacobian {
    /// `s^a`.
    pub s: [Vec3; 6],
    /// Columns of the form `R^a e_k` for the three coordinates `base, base+1, base+2` (a control
    /// point's x, y, z): `(base, R^a)`.
    pub blocks: Vec<(usize, [f64; 6])>,
    /// General columns `(coordinate, d s^a / d q)`.
    pub vectors: Vec<(usize, [Vec3; 6])>,
    /// Evaluation buffers a geometry may reuse between calls (no allocation per point).
    pub(crate) scratch: super::rational::Local,
    /// What the engine will read of the next evaluation (a hint a geometry may ignore):
    /// see [`ColumnHint`].
    pub(crate) hint: ColumnHint,
}

/// The Jacobian columns the engine reads at the quadrature points of an element
/// ([`GeneralizedGeometry::element_jacobian_at`]). A geometry must fill the values `s` and at
/// least these columns, and may leave the others zero.
#[derive(Clone, Debug, Default)]
pub(crate) struct ColumnHint {
    /// Per coordinate, fixed (empty: none). The columns of fixed coordinates are dropped from
    /// the element products; only their order-0 columns are read (the lumped mass behind the
    /// weights' inertia and the velocity term), so a control point whose coordinates are all
    /// fixed (homogeneous layout: `4c..4c+4`) needs only `R^0` and `g^0`.
    pub fixed: Arc<[bool]>,
}

impl ColumnHint {
    /// Whether control `c` of a homogeneous `(x, y, z, w)` layout needs only its order-0
    /// columns.
    pub fn values_only(&self, c: usize) -> bool {
        !self.fixed.is_empty() && self.fixed[4 * c..4 * c + 4].iter().all(|&f| f)
    }
}

impl LocalJacobian {
    /// Local coordinate list: three per block, then one per vector column.
    fn dofs(&self) -> Vec<usize> {
        let mut d = Vec::new();
        self.dofs_into(&mut d);
        d
    }

    /// [`Self::dofs`] into a reused buffer.
    fn dofs_into(&self, d: &mut Vec<usize>) {
        d.clear();
        for &(b, _) in &self.blocks {
            d.extend_from_slice(&[b, b + 1, b + 2]);
        }
        d.extend(self.vectors.iter().map(|v| v.0));
    }

    /// Drops the columns of fixed coordinates: blocks whose three coordinates are all fixed and
    /// vectors whose coordinate is (`fixed` empty: no coordinate is fixed).
    fn retain_free(&mut self, fixed: &[bool]) {
        if fixed.is_empty() {
            return;
        }
        self.blocks
            .retain(|&(b, _)| !(fixed[b] && fixed[b + 1] && fixed[b + 2]));
        self.vectors.retain(|&(i, _)| !fixed[i]);
    }

    /// The local coordinates after [`Self::retain_free`] into `d`, without changing `self`;
    /// returns the numbers of blocks and vectors kept.
    fn free_dofs_into(&self, fixed: &[bool], d: &mut Vec<usize>) -> (usize, usize) {
        let free_block = |b: usize| fixed.is_empty() || !(fixed[b] && fixed[b + 1] && fixed[b + 2]);
        let free_vector = |i: usize| fixed.is_empty() || !fixed[i];
        d.clear();
        for &(b, _) in &self.blocks {
            if free_block(b) {
                d.extend_from_slice(&[b, b + 1, b + 2]);
            }
        }
        let nb = d.len() / 3;
        d.extend(self.vectors.iter().map(|v| v.0).filter(|&i| free_vector(i)));
        (nb, d.len() - 3 * nb)
    }

    /// `J^a x` for local coordinate values `x` (ordered as [`Self::dofs`]).
    fn apply(&self, m: usize, x: &[f64]) -> Vec3 {
        let mut s = Vec3::zeros();
        for (k, (_, r)) in self.blocks.iter().enumerate() {
            s += Vec3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]) * r[m];
        }
        let nb = 3 * self.blocks.len();
        for (k, (_, g)) in self.vectors.iter().enumerate() {
            s += g[m] * x[nb + k];
        }
        s
    }

    /// `out += c J^a^T y` in local coordinates.
    fn apply_transpose(&self, m: usize, c: f64, y: &Vec3, out: &mut [f64]) {
        for (k, (_, r)) in self.blocks.iter().enumerate() {
            let f = c * r[m];
            out[3 * k] += f * y.x;
            out[3 * k + 1] += f * y.y;
            out[3 * k + 2] += f * y.z;
        }
        let nb = 3 * self.blocks.len();
        for (k, (_, g)) in self.vectors.iter().enumerate() {
            out[nb + k] += c * g[m].dot(y);
        }
    }

    /// `out += sum_a J^a^T y[a]` in local coordinates (all six kinds in one pass).
    fn apply_transpose_all(&self, y: &[Vec3; 6], out: &mut [f64]) {
        for (k, (_, r)) in self.blocks.iter().enumerate() {
            let mut acc = Vec3::zeros();
            for m in 0..6 {
                acc += y[m] * r[m];
            }
            out[3 * k] += acc.x;
            out[3 * k + 1] += acc.y;
            out[3 * k + 2] += acc.z;
        }
        let nb = 3 * self.blocks.len();
        for (k, (_, g)) in self.vectors.iter().enumerate() {
            let mut acc = 0.0;
            for m in 0..6 {
                acc += g[m].dot(&y[m]);
            }
            out[nb + k] += acc;
        }
    }

    /// `diag += c * diag(J^0^T J^0)` (the lumped view of the mass matrix's diagonal).
    fn accumulate_value_diagonal(&self, c: f64, diag: &mut [f64]) {
        let nb = self.blocks.len();
        for (a, (_, r)) in self.blocks.iter().enumerate() {
            for k in 0..3 {
                diag[3 * a + k] += c * r[0] * r[0];
            }
        }
        for (j, (_, g)) in self.vectors.iter().enumerate() {
            diag[3 * nb + j] += c * g[0].norm_squared();
        }
    }
}

/// `sum_q sum_a coef_q[a] J_q^a^T J_q^a` over the quadrature points of one element (eqs 16-17
/// with the columns of [`LocalJacobian`]), computed as matrix products.
///
/// Each `(point, kind a)` with a nonzero coefficient contributes one row of the stacked matrix
/// `X = [P | G_x | G_y | G_z]`: `P` holds the block values `R^a_i` (a block column `R^a e_k`
/// pairs with another as the scalar `R^a_i R^a_j` times the 3x3 identity), and `G_k` the
/// component `k` of the general columns `g^a_j`. With `C` the diagonal of the coefficients:
/// - block-block and block-vector parts: `[bb | bv] = P^T C X` (`nb x (nb + 3 nv)`),
/// - vector-vector part: `vv = sum_k G_k^T C G_k`.
///
/// Collecting the rows of a whole element and multiplying once (register-tiled products,
/// [`gemm_tn`]) replaces one rank-6 update of the element matrix per quadrature point, which was
/// bound by loads and stores. [`Gram::write`] writes the dense symmetric `nd x nd` matrix.
#[derive(Clone, Debug, Default)]
struct Gram {
    nb: usize,
    nv: usize,
    /// The rows of `X`, row-major, `nc = nb + 3 nv` columns.
    x: Vec<f64>,
    /// The diagonal of `C`: each row's coefficient (the rows of `C X` are formed inside
    /// [`gemm_tn`], the same products as stored ones).
    c: Vec<f64>,
    /// `[bb | bv]`, row-major `nb x nc` (`bv` component-major per block: column
    /// `nb + k nv + j`), then `vv`, row-major `nv x nv`: the products, valid after
    /// [`Gram::finish`] ([`gram_index`] says where an entry of the dense matrix is).
    products: Vec<f64>,
}

impl Gram {
    /// An empty accumulator for Jacobians shaped like `lj`.
    fn new(lj: &LocalJacobian) -> Self {
        let mut g = Self::default();
        g.reset(lj);
        g
    }

    /// Empties the accumulator for Jacobians shaped like `lj`, keeping its buffers.
    fn reset(&mut self, lj: &LocalJacobian) {
        self.reset_shape((lj.blocks.len(), lj.vectors.len()));
    }

    /// Empties the accumulator for Jacobians with `(blocks, vectors)` columns.
    fn reset_shape(&mut self, (nb, nv): (usize, usize)) {
        self.nb = nb;
        self.nv = nv;
        self.x.clear();
        self.c.clear();
    }

    /// Columns of `X`.
    fn nc(&self) -> usize {
        self.nb + 3 * self.nv
    }

    /// Row stride of the stored `X` and `C X`: the columns and [`GEMM_PAD`] zeros, so that the
    /// product's register tiles may read past a column range's end (see [`gemm_tn`]).
    fn ld(&self) -> usize {
        self.nc() + GEMM_PAD
    }

    /// Adds `sum_a coef[a] J^a^T J^a` for one Jacobian (same columns as at construction):
    /// appends the rows of the kinds with a nonzero coefficient. Each column's six (or
    /// eighteen) values are read once and stored into the rows (reading one row at a time
    /// gathered every value with the stride of a column).
    fn add(&mut self, lj: &LocalJacobian, coef: &[f64; 6]) {
        let (nb, nv, ld) = (self.nb, self.nv, self.ld());
        debug_assert_eq!((lj.blocks.len(), lj.vectors.len()), (nb, nv));
        let mut kinds = [0usize; 6];
        let mut nk = 0;
        for (m, &c) in coef.iter().enumerate() {
            if c != 0.0 {
                kinds[nk] = m;
                nk += 1;
            }
        }
        let kinds = &kinds[..nk];
        let at = self.x.len();
        self.x.resize(at + nk * ld, 0.0);
        let rows = &mut self.x[at..];
        for (c, (_, r)) in lj.blocks.iter().enumerate() {
            for (slot, &m) in kinds.iter().enumerate() {
                rows[slot * ld + c] = r[m];
            }
        }
        for (j, (_, g)) in lj.vectors.iter().enumerate() {
            for (slot, &m) in kinds.iter().enumerate() {
                for k in 0..3 {
                    rows[slot * ld + nb + k * nv + j] = g[m][k];
                }
            }
        }
        self.c.extend(kinds.iter().map(|&m| coef[m]));
    }

    /// Forms `[bb | bv]` and `vv` from the collected rows.
    fn finish(&mut self) {
        let (nb, nv, nc, ld) = (self.nb, self.nv, self.nc(), self.ld());
        let rows = self.x.len() / ld;
        let len = nb * nc + nv * nv;
        if self.products.len() != len {
            self.products.clear();
            self.products.resize(len, 0.0);
        }
        if rows == 0 || nc == 0 {
            self.products.fill(0.0);
            return;
        }
        let (x, c) = (&self.x[..rows * ld], &self.c[..rows]);
        let (bbv, vv) = self.products.split_at_mut(nb * nc);
        struct Products<'a> {
            x: &'a [f64],
            c: &'a [f64],
            ld: usize,
            nc: usize,
            nb: usize,
            nv: usize,
            bbv: &'a mut [f64],
            vv: &'a mut [f64],
        }
        impl pulp::WithSimd for Products<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                let Products {
                    x,
                    c,
                    ld,
                    nc,
                    nb,
                    nv,
                    bbv,
                    vv,
                } = self;
                // bb and each G_k^T C G_k are symmetric: upper tiles only.
                // Every entry is written (no zeroing first); the three `vv` terms add up.
                gemm_tn(x, c, ld, 0..nb, 0..nb, bbv, nc, true, false);
                gemm_tn(x, c, ld, 0..nb, nb..nc, &mut bbv[nb..], nc, false, false);
                for k in 0..3 {
                    let cols = nb + k * nv..nb + (k + 1) * nv;
                    gemm_tn(x, c, ld, cols.clone(), cols, vv, nv, true, k > 0);
                }
            }
        }
        // Compiled for AVX2/FMA too and chosen at run time.
        pulp::Arch::new().dispatch(Products {
            x,
            c,
            ld,
            nc,
            nb,
            nv,
            bbv,
            vv,
        });
    }

    /// Writes the accumulated matrix into `out`, dense and symmetric (row-major `nd x nd`, the
    /// local order of [`LocalJacobian::dofs`]; every entry is set).
    fn write(&mut self, out: &mut [f64]) {
        let (nb, nd) = (self.nb, 3 * self.nb + self.nv);
        for a in 0..3 * nb {
            for b in 0..nb {
                // The block pair is `v I`: only the matching component is nonzero.
                out[a * nd + 3 * b..a * nd + 3 * b + 3].copy_from_slice(&[0.0; 3]);
            }
        }
        self.write_nonzero(out);
    }

    /// [`Self::write`] without the structural zeros (a block pair's entries between different
    /// components): `out` must hold zeros there already (a zeroed buffer, or one this shape
    /// was written into before).
    fn write_nonzero(&mut self, out: &mut [f64]) {
        self.finish();
        write_products((self.nb, self.nv), &self.products, out);
    }
}

/// Where entry `(a, b)` of the dense element matrix of shape `(nb, nv)` (the local order of
/// [`LocalJacobian::dofs`]: `3 nb` block columns, then `nv` general ones) lies in [`Gram`]'s
/// products `[bb | bv]`, `vv`; `None` for a structural zero (two blocks' different
/// components). The block pair `(p, q)` is `bb_pq I3`; block `p`'s component `k` against
/// general column `j` is `bv[p, nb + k nv + j]`, and its transpose the same entry.
fn gram_index((nb, nv): (usize, usize), a: usize, b: usize) -> Option<usize> {
    let nc = nb + 3 * nv;
    match (a < 3 * nb, b < 3 * nb) {
        (true, true) => (a % 3 == b % 3).then_some(a / 3 * nc + b / 3),
        (true, false) => Some(a / 3 * nc + nb + a % 3 * nv + (b - 3 * nb)),
        (false, true) => Some(b / 3 * nc + nb + b % 3 * nv + (a - 3 * nb)),
        (false, false) => Some(nb * nc + (a - 3 * nb) * nv + (b - 3 * nb)),
    }
}

/// The dense element matrix of shape `(nb, nv)` from [`Gram`]'s `products` into `out`
/// without the structural zeros (see [`Gram::write_nonzero`]).
fn write_products((nb, nv): (usize, usize), products: &[f64], out: &mut [f64]) {
    let nc = nb + 3 * nv;
    let nd = 3 * nb + nv;
    let (bbv, vv) = products.split_at(nb * nc);
    for a in 0..nb {
        let row = &bbv[a * nc..(a + 1) * nc];
        for k in 0..3 {
            let o = &mut out[(3 * a + k) * nd..(3 * a + k + 1) * nd];
            for b in 0..nb {
                o[3 * b + k] = row[b];
            }
            o[3 * nb..].copy_from_slice(&row[nb + k * nv..nb + (k + 1) * nv]);
        }
    }
    for i in 0..nv {
        let o = &mut out[(3 * nb + i) * nd..(3 * nb + i + 1) * nd];
        for a in 0..nb {
            for k in 0..3 {
                o[3 * a + k] = bbv[a * nc + nb + k * nv + i];
            }
        }
        o[3 * nb..].copy_from_slice(&vv[i * nv..(i + 1) * nv]);
    }
}

/// Zero columns after each stored row of [`Gram`]'s `X` and `C X`: [`gemm_tn`] computes whole
/// 4 x 8 register tiles and may read up to 7 columns past a range's end.
const GEMM_PAD: usize = 8;

/// `out = L^T C L` (with `add`: `out += L^T C L`) restricted to the column ranges `lc` (rows
/// of `out`) and `rc` (columns),
/// `L` row-major with row stride `ld`, `C` the diagonal `c` (one coefficient per row of `L`);
/// `out` is row-major with row stride `ldo` (entry `(a, j)` at `a ldo + j`). Each entry of
/// `R = C L` is formed in registers as `c_r * l_rj`, the same product a stored `R` held (the
/// step's values do not change; `C L` is not written out, which halved the rows' bytes). With
/// `sym` (`lc == rc`) only the tiles on or above the diagonal are computed and the rest
/// mirrored. Small products (tens of rows and columns, once per element): tiles of 4 x 8
/// accumulated in registers over all rows, without the packing buffers a general GEMM
/// allocates per call. Every tile is a whole one (vectorized); at the end of a range it reads
/// the next columns (or the [`GEMM_PAD`] zeros each row must carry after its last range) and
/// stores only the entries inside the ranges. Writing a tile (`add` false) gives the bits of
/// adding it to zeros: its sums start at `+0` and so are never `-0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn gemm_tn(
    l: &[f64],
    c: &[f64],
    ld: usize,
    lc: std::ops::Range<usize>,
    rc: std::ops::Range<usize>,
    out: &mut [f64],
    ldo: usize,
    sym: bool,
    add: bool,
) {
    const TA: usize = 4;
    const TJ: usize = 8;
    let rows = l.len() / ld;
    let (m, n) = (lc.len(), rc.len());
    // Tile (a0, j0) lies wholly below the diagonal.
    let below = |a0: usize, j0: usize| sym && j0 + TJ <= a0;
    let mut a0 = 0;
    while a0 < m {
        let ta = TA.min(m - a0);
        let mut j0 = 0;
        while j0 < n {
            let tj = TJ.min(n - j0);
            if below(a0, j0) {
                j0 += TJ;
                continue;
            }
            // Whole rows as chunks (no bounds check inside the loop), the tile's columns
            // copied out of them: the accumulators stay in registers (indexing each row with
            // a checked range kept them on the stack, one store per row and accumulator).
            let (lo, ro) = (lc.start + a0, rc.start + j0);
            let mut acc = [[0.0; TJ]; TA];
            for (lrow, &cr) in l[..rows * ld].chunks_exact(ld).zip(&c[..rows]) {
                let lr: [f64; TA] = lrow[lo..lo + TA]
                    .try_into()
                    .expect("TA columns (padded rows)");
                let rr: [f64; TJ] = lrow[ro..ro + TJ]
                    .try_into()
                    .expect("TJ columns (padded rows)");
                let rr = rr.map(|v| cr * v);
                for a in 0..TA {
                    for jj in 0..TJ {
                        acc[a][jj] += lr[a] * rr[jj];
                    }
                }
            }
            for (a, acc_a) in acc.iter().enumerate().take(ta) {
                let o = &mut out[(a0 + a) * ldo + j0..][..tj];
                if add {
                    for (o, v) in o.iter_mut().zip(acc_a) {
                        *o += v;
                    }
                } else {
                    o.copy_from_slice(&acc_a[..tj]);
                }
            }
            j0 += TJ;
        }
        a0 += TA;
    }
    if sym {
        for a in 0..m {
            for j in 0..a.min(n) {
                // Skipped entries only ever hold the mirror (so repeated calls accumulate).
                if below(a - a % TA, j - j % TJ) {
                    out[a * ldo + j] = out[j * ldo + a];
                }
            }
        }
    }
}

/// Scratch of one element's assembly (see [`GeneralizedDnurbs::step`]).
#[derive(Default)]
struct ElementScratch {
    lj: LocalJacobian,
    gram: Gram,
    /// The element's coordinate velocities.
    vl: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<ElementScratch> =
        std::cell::RefCell::new(ElementScratch::default());
}

/// Runs `f` with this thread's element scratch (a fresh one if it is already in use).
fn with_scratch<R>(f: impl FnOnce(&mut ElementScratch) -> R) -> R {
    with_thread_buffer(&SCRATCH, f)
}

/// Runs `f` with this thread's value of `key`, buffers reused from call to call instead of
/// allocated per quadrature point; a fresh default value when it is already borrowed (a
/// caller up the stack using it).
pub(crate) fn with_thread_buffer<T: Default + 'static, R>(
    key: &'static std::thread::LocalKey<std::cell::RefCell<T>>,
    f: impl FnOnce(&mut T) -> R,
) -> R {
    key.with(|cell| match cell.try_borrow_mut() {
        Ok(mut b) => f(&mut b),
        Err(_) => f(&mut T::default()),
    })
}

/// [`GeneralizedGeometry::weight_coordinates`] of the homogeneous layout `p = (x, y, z, w)` per
/// control point (`d-nurbs.txt` eq 3) with `len` coordinates: every fourth, from index 3.
pub fn homogeneous_weight_coordinates(len: usize) -> Vec<usize> {
    (0..len / 4).map(|c| 4 * c + 3).collect()
}

/// [`GeneralizedGeometry::coordinate_groups`] of the homogeneous layout (one group of four
/// per control point).
pub fn homogeneous_coordinate_groups(len: usize) -> Vec<std::ops::Range<usize>> {
    (0..len / 4).map(|c| 4 * c..4 * c + 4).collect()
}

/// A geometry whose generalized coordinates (control points, weights and any other shape
/// parameters) are simulated by [`GeneralizedDnurbs`].
pub trait GeneralizedGeometry: Clone + Send + Sync + std::fmt::Debug {
    /// 1 for curves, 2 for surfaces.
    fn parametric_dimension(&self) -> usize;
    /// The generalized coordinates `p`.
    fn coordinates(&self) -> &[f64];
    /// Replaces the generalized coordinates (validated: finite, positive weights).
    fn set_coordinates(&mut self, q: &[f64]) -> Result<(), DynamicsError>;
    /// Indices of the weights in `p`.
    fn weight_coordinates(&self) -> Vec<usize>;
    /// Coordinates held fixed by default (gauge freedoms and components without influence).
    fn default_fixed_coordinates(&self) -> Vec<usize>;
    /// Groups of coordinates that belong together (a control point's x, y, z, w), used for the
    /// block-Jacobi preconditioner. Default: each coordinate alone.
    fn coordinate_groups(&self) -> Vec<std::ops::Range<usize>> {
        (0..self.coordinates().len()).map(|i| i..i + 1).collect()
    }
    /// Finite elements as parameter rectangles (`[(u0, u1), (v0, v1)]`; curves have a
    /// degenerate v interval).
    fn elements(&self) -> Vec<[(f64, f64); 2]>;
    /// Largest polynomial degree (chooses the quadrature order).
    fn max_degree(&self) -> usize;
    /// Quadrature points and weights of element `element` (index into [`Self::elements`]) for
    /// `order` Gauss points per direction, for geometries whose elements are not the parameter
    /// rectangles of [`Self::elements`] (triangular D-NURBS: domain triangles cut along knot
    /// lines). `None` (the default): the tensor Gauss-Legendre rule on the rectangle.
    fn element_quadrature(
        &self,
        element: usize,
        order: [usize; 2],
    ) -> Option<(Vec<[f64; 2]>, Vec<f64>)> {
        let _ = (element, order);
        None
    }
    /// The rational denominator `W` of eq (1) on `element`, as univariate slices per parametric
    /// direction: for direction `d`, a list of slices, each the values of `W` at the points
    /// `nodes` (in `[-1, 1]`, mapped onto the element's interval in direction `d`) with the other
    /// parameter held (surfaces: at the same nodes of the other direction). Empty where the
    /// geometry is polynomial along a direction (the default). [`QuadratureRule::WeightAware`]
    /// reads the distance of `W`'s complex zeros from the element off these samples.
    fn element_denominators(&self, element: &[(f64, f64); 2], nodes: &[f64]) -> [Vec<Vec<f64>>; 2] {
        let _ = (element, nodes);
        [Vec::new(), Vec::new()]
    }
    /// Linear ties between coordinates that the geometry needs to stay what it is (issue 18: a
    /// closed swung surface's seam), each `sum_i c_i q_i = value` as `(terms, value)`.
    /// [`GeneralizedDnurbs::new`] enforces them like the constraints of section 6.2 (Lagrange
    /// rows, Newton projection), for the life of the model. Default: none.
    fn default_ties(&self) -> Vec<LinearTie> {
        Vec::new()
    }
    /// Size of the model (for tolerances and divergence detection).
    fn scale(&self) -> f64;
    /// Values and Jacobian columns at a parameter.
    fn jacobian_at(&self, param: [f64; 2], out: &mut LocalJacobian) -> Result<(), DynamicsError>;
    /// The six values `s, s_u, s_v, s_uu, s_uv, s_vv` at a parameter (the point and the
    /// derivatives of `d-nurbs.txt` eq (17)'s energy), without the Jacobian columns: the
    /// [`LocalJacobian::s`] of [`Self::jacobian_at`], bit for bit (the elastic energy and the
    /// rest shape read only these). Default: [`Self::jacobian_at`].
    fn values_at(&self, param: [f64; 2]) -> Result<[Vec3; 6], DynamicsError> {
        let mut lj = LocalJacobian::default();
        self.jacobian_at(param, &mut lj)?;
        Ok(lj.s)
    }
    /// [`Self::jacobian_at`] for a quadrature point of element `element`: the columns must be
    /// the same coordinates in the same order at every quadrature point of the element (the
    /// element's degrees of freedom). Default: [`Self::jacobian_at`]. Geometries whose elements
    /// share a domain region (triangular D-NURBS: the polynomial cells of a domain triangle,
    /// each with only the functions that are non-zero on it) say which element is meant.
    fn element_jacobian_at(
        &self,
        element: usize,
        param: [f64; 2],
        out: &mut LocalJacobian,
    ) -> Result<(), DynamicsError> {
        let _ = element;
        self.jacobian_at(param, out)
    }
    /// `(J p', J' p')`: the first and second directional derivatives of `s` along the
    /// coordinate velocity `qdot` (global coordinates).
    fn velocity_terms(&self, param: [f64; 2], qdot: &[f64]) -> Result<(Vec3, Vec3), DynamicsError>;
    /// What a geometry precomputes for the quadrature points of one element (for
    /// [`RationalGeometry`](super::RationalGeometry): the spans and basis function values and
    /// derivatives, which depend on the knots and the points only, not on the coordinates).
    /// The engine builds them with [`Self::element_tables`] whenever an element's rule is chosen
    /// and keeps them while the rule stays; `()` for geometries that precompute nothing.
    type ElementTables: Clone + std::fmt::Debug + Default + Send + Sync;
    /// The tables of element `element` for its quadrature points `params`. Default: empty.
    fn element_tables(&self, element: usize, params: &[[f64; 2]]) -> Self::ElementTables {
        let _ = (element, params);
        Self::ElementTables::default()
    }
    /// [`Self::element_jacobian_at`] at the quadrature point `point` (an index into the
    /// `params` that `tables` were built for; `param` is that point), reading what `tables`
    /// hold. Must give the same values, bit for bit. Default: [`Self::element_jacobian_at`].
    fn element_jacobian_tabled(
        &self,
        element: usize,
        point: usize,
        param: [f64; 2],
        tables: &Self::ElementTables,
        out: &mut LocalJacobian,
    ) -> Result<(), DynamicsError> {
        let _ = (point, tables);
        self.element_jacobian_at(element, param, out)
    }
    /// [`Self::velocity_terms`] at the parameter `lj` was just evaluated at (by
    /// [`Self::element_jacobian_tabled`] or [`Self::element_jacobian_at`]; the engine may have
    /// dropped columns since, [`LocalJacobian`]'s evaluation buffers are untouched), so a
    /// geometry may reuse that evaluation's basis values and local coordinates. Same values,
    /// bit for bit. Default: [`Self::velocity_terms`].
    fn velocity_terms_after(
        &self,
        param: [f64; 2],
        qdot: &[f64],
        lj: &LocalJacobian,
    ) -> Result<(Vec3, Vec3), DynamicsError> {
        let _ = lj;
        self.velocity_terms(param, qdot)
    }
    /// Parameter of the point of the geometry nearest to `x`.
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError>;
    /// The solver [`GeneralizedDnurbs::new`] picks for this geometry. Default
    /// [`LinearSolver::Direct`]; geometries whose coordinates are redundant (directions that
    /// change the shape little or not at all, so the step matrix is nearly singular along them)
    /// return [`LinearSolver::ConjugateGradient`]: an exact solve amplifies rounding along those
    /// directions, while CG from a symmetric start never leaves the well-determined subspace.
    fn default_solver(&self) -> LinearSolver {
        LinearSolver::Direct
    }
}

/// The evolving state of a [`GeneralizedDnurbs`] ([`GeneralizedDnurbs::state`]): the
/// generalized coordinates `p` and their velocity `p'` of eq (15), the coordinates the rest
/// shape was taken at, the held coordinates (section 6.2), the weight penalty and its targets,
/// the elastic reference, and the counters.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneralizedState {
    /// Generalized coordinates `p` (control points and weights, see the geometry).
    pub coordinates: Vec<f64>,
    /// Coordinate velocity `p'`.
    pub velocity: Vec<f64>,
    /// Coordinates of the rest shape (the shape at construction or at the last plastic reset).
    pub rest_coordinates: Vec<f64>,
    /// Held coordinates.
    pub fixed: Vec<bool>,
    /// Weight values the penalty pulls towards (one per weight coordinate).
    pub weight_targets: Vec<f64>,
    /// Weight penalty `c`.
    pub weight_penalty: f64,
    /// Elastic reference.
    pub reference: ElasticReference,
    /// Simulated time.
    pub time: f64,
    /// Steps taken.
    pub steps: usize,
    /// Sub-steps taken (see [`GeneralizedDnurbs::substeps`]).
    pub substeps: usize,
    /// Weight projections made (see [`GeneralizedDnurbs::weight_projections`]).
    pub weight_projections: usize,
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Checks a material against a geometry of parametric dimension `dim` with `ne` elements.
fn validate_material(dim: usize, ne: usize, material: &Material) -> Result<(), DynamicsError> {
    material.mu.validate("mu", ne)?;
    material.gamma.validate("gamma", ne)?;
    if material.alpha.len() != dim || material.beta.len() != if dim == 1 { 1 } else { 3 } {
        return Err(DynamicsError::Parameter {
            name: "material",
            value: material.alpha.len() as f64,
            why: "needs one alpha per parametric direction and one beta per second-derivative pair (1 and 1 for curves, 2 and 3 for surfaces)",
        });
    }
    for a in &material.alpha {
        a.validate("alpha", ne)?;
    }
    for b in &material.beta {
        b.validate("beta", ne)?;
    }
    Ok(())
}

/// The six values `s, s_u, ...` of `g` at every quadrature point (the rest shape of eq 17).
fn rest_values<G: GeneralizedGeometry>(
    g: &G,
    quad: &[Quadrature],
) -> Result<Vec<Vec<[Vec3; 6]>>, DynamicsError> {
    quad.par_iter().map(|q| element_rest_values(g, q)).collect()
}

/// One element's [`rest_values`]: the six values at each of its quadrature points.
fn element_rest_values<G: GeneralizedGeometry>(
    g: &G,
    q: &Quadrature,
) -> Result<Vec<[Vec3; 6]>, DynamicsError> {
    q.params.iter().map(|&p| g.values_at(p)).collect()
}

/// Each element's [`GeneralizedGeometry::element_tables`] for its quadrature points.
fn element_tables<G: GeneralizedGeometry>(
    g: &G,
    quad: &[Quadrature],
) -> Vec<Arc<G::ElementTables>> {
    quad.par_iter()
        .enumerate()
        .map(|(e, q)| Arc::new(g.element_tables(e, &q.params)))
        .collect()
}

/// A geometric constraint (`d-nurbs.txt` section 6.2).
#[derive(Clone, Debug, PartialEq)]
pub enum Constraint {
    /// The material point `param` stays at `target`: `s(param) = target` (3 rows).
    Point {
        /// Material point.
        param: [f64; 2],
        /// Required position.
        target: Vec3,
    },
    /// The surface normal at `param` is parallel to `normal`: `s_u . n = 0`, `s_v . n = 0`
    /// (surfaces only; 2 rows).
    Normal {
        /// Material point.
        param: [f64; 2],
        /// Required normal direction (any length but zero).
        normal: Vec3,
    },
}

/// A linear tie `sum_i c_i q_i = value` between generalized coordinates (terms `(i, c_i)`), see
/// [`GeneralizedGeometry::default_ties`] and [`GeneralizedDnurbs::add_tie`].
#[derive(Clone, Debug, PartialEq)]
pub struct LinearTie {
    /// `(coordinate, coefficient)` pairs.
    pub terms: Vec<(usize, f64)>,
    /// Right-hand side.
    pub value: f64,
}

/// One scalar constraint row: its value `C(p)` and its non-zero derivatives
/// `(coordinate, dC/dq)`.
type ConstraintRow = (f64, Vec<(usize, f64)>);

/// The rows of a constraint whose coordinates are all fixed, with the coordinates' values
/// (bits) they were computed at.
#[derive(Clone, Debug)]
struct CachedRows {
    constraint: Constraint,
    coords: Vec<(usize, u64)>,
    rows: Vec<ConstraintRow>,
}

/// Per constraint index, the rows of a constraint that acts only on fixed coordinates (the
/// rounding models' far-boundary normal constraints once their control points are held):
/// they cannot change while those coordinates stay fixed and unchanged, so each step reuses
/// them instead of evaluating the geometry at the constraint (a direct triangular evaluation
/// per constraint, several times a step with the Newton projection). Checked against the
/// constraint, the fixed set and the coordinate values on every use.
#[derive(Debug, Default)]
struct RowCache(std::sync::Mutex<Vec<Option<CachedRows>>>);

impl RowCache {
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Option<CachedRows>>> {
        self.0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

impl Clone for RowCache {
    fn clone(&self) -> Self {
        Self(std::sync::Mutex::new(self.lock().clone()))
    }
}

/// Default floor for weights (section 6.2: weights that drift below it are projected back).
pub const DEFAULT_WEIGHT_FLOOR: f64 = 1e-3;
/// Default CG iteration cap of the generalized model.
pub const GENERALIZED_CG_ITERATIONS: usize = 1000;
/// Default CG relative tolerance of the generalized model.
pub const GENERALIZED_CG_TOLERANCE: f64 = 1e-10;
/// Default relative weight inertia (see [`GeneralizedDnurbs::weight_inertia`]).
pub const DEFAULT_WEIGHT_INERTIA: f64 = 1.0;
/// Reuse of the direct solver's factorization across steps
/// ([`GeneralizedDnurbs::factor_reuse`]): a step first solves its system by conjugate gradients
/// preconditioned with the last factorization (`M^-1 = (L L^T)^-1` of an earlier step's matrix),
/// from the warm start of the module docs, and factors its own matrix (the default path's exact
/// solve) only when that does not reach [`FactorReuse::tolerance`] within
/// [`FactorReuse::max_iterations`]. The step matrix changes with the weights and the shape
/// (eqs 16-17), slowly from step to step, so the old factor is a close preconditioner and a
/// few iterations (each two triangular solves and one product with the assembled matrix) replace
/// the factorization. The result differs from the default path's by the solve tolerance per
/// step (`docs/performance.md` states what this means over many steps;
/// `tests/generalized.rs` checks it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorReuse {
    /// Relative residual `|b - A x| / |b|` on the free coordinates that a step must reach with
    /// the old factor (default [`FACTOR_REUSE_TOLERANCE`]).
    pub tolerance: f64,
    /// Iterations after which a step gives up on the old factor and factors its own matrix
    /// (default [`FACTOR_REUSE_ITERATIONS`]).
    pub max_iterations: usize,
}

/// Default [`FactorReuse::tolerance`].
pub const FACTOR_REUSE_TOLERANCE: f64 = 1e-10;
/// Default [`FactorReuse::max_iterations`].
pub const FACTOR_REUSE_ITERATIONS: usize = 6;

impl Default for FactorReuse {
    fn default() -> Self {
        Self {
            tolerance: FACTOR_REUSE_TOLERANCE,
            max_iterations: FACTOR_REUSE_ITERATIONS,
        }
    }
}

/// Largest relative weight change of one linearized step before it is split in two.
pub const MAX_RELATIVE_WEIGHT_CHANGE: f64 = 0.25;
/// Most halvings of one step.
pub const MAX_SUBSTEP_LEVELS: usize = 12;

fn unreachable_short() -> DynamicsError {
    DynamicsError::Singular {
        what: "static step was not taken".into(),
    }
}

/// Constraint tolerance relative to the model size, met after each step by Newton projection.
pub const CONSTRAINT_TOLERANCE: f64 = 1e-10;
/// Constraint rows that depend on earlier ones are redundant (dropped) when their implied
/// violation is below this, relative to the model size; contradictory otherwise.
pub const CONSTRAINT_CONSISTENCY: f64 = 1e-8;
/// Most projection iterations per step.
pub const MAX_CONSTRAINT_PROJECTIONS: usize = 8;
/// Relative threshold under which a constraint row counts as dependent on earlier ones.
pub const CONSTRAINT_DEPENDENCE_TOLERANCE: f64 = 1e-9;

#[derive(Clone, Debug)]
struct Quadrature {
    params: Vec<[f64; 2]>,
    weights: Vec<f64>,
    /// Gauss points per direction `[u, v]` (v is 1 for curves).
    order: [usize; 2],
}

impl Quadrature {
    /// The geometry's own rule for element `index` ([`GeneralizedGeometry::element_quadrature`])
    /// or the tensor Gauss-Legendre rule on its rectangle.
    fn for_element<G: GeneralizedGeometry>(
        g: &G,
        index: usize,
        element: &[(f64, f64); 2],
        order: [usize; 2],
        dim: usize,
    ) -> Result<Self, DynamicsError> {
        match g.element_quadrature(index, order) {
            Some((params, weights)) => Ok(Self {
                params,
                weights,
                order,
            }),
            None => Self::on(element, order, dim),
        }
    }

    /// The tensor Gauss-Legendre rule with `order` points per direction on `element`.
    fn on(element: &[(f64, f64); 2], order: [usize; 2], dim: usize) -> Result<Self, DynamicsError> {
        let rule = |n: usize| {
            GaussLegendre::new(n).map_err(|_| DynamicsError::Parameter {
                name: "quadrature order",
                value: n as f64,
                why: "no Gauss-Legendre rule with this many points (1 to 64)",
            })
        };
        let gu = rule(order[0])?;
        let us: Vec<(f64, f64)> = gu.on_interval(element[0].0, element[0].1).collect();
        let vs: Vec<(f64, f64)> = if dim == 2 {
            rule(order[1])?
                .on_interval(element[1].0, element[1].1)
                .collect()
        } else {
            vec![(element[1].0, 1.0)]
        };
        let mut q = Self {
            params: Vec::with_capacity(us.len() * vs.len()),
            weights: Vec::with_capacity(us.len() * vs.len()),
            order: [order[0], if dim == 2 { order[1] } else { 1 }],
        };
        for &(u, wu) in &us {
            for &(v, wv) in &vs {
                q.params.push([u, v]);
                q.weights.push(wu * wv);
            }
        }
        Ok(q)
    }
}

/// Default relative accuracy of [`QuadratureRule::WeightAware`].
pub const DEFAULT_QUADRATURE_TOLERANCE: f64 = 1e-8;
/// Most Gauss points per direction [`QuadratureRule::WeightAware`] chooses.
pub const MAX_WEIGHT_AWARE_POINTS: usize = 24;

/// How the element integrals of eqs (16)-(17) and the force integrals are computed: tensor
/// Gauss-Legendre rules per element, with the number of points per direction chosen by the rule.
///
/// With uniform weights the integrands are polynomials of degree at most `2p` per direction
/// and `p + 1` points integrate them exactly. With non-uniform weights they are rational,
/// `P / W^k` with the denominator `W = sum N_i w_i`, and no Gauss rule is exact: the error
/// of `n` points decays like `r^(-2(n - p))`, where `r` is the Bernstein-ellipse radius of the
/// nearest zero of `W` (Trefethen, *Approximation Theory and Approximation Practice*, thm 19.3).
/// For a denominator that moves monotonically from `1` to the spread `rho = max w / min w` over
/// the element, that zero lies at `t* = (rho + 1) / (rho - 1)` of the element's half width, so
/// `r = t* + sqrt(t*^2 - 1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QuadratureRule {
    /// The paper's fixed rule (`d-nurbs.txt` section 5.1 integrates with Gauss points for the
    /// polynomial degree): `(p + 1).clamp(4, 7)` points per direction for the largest degree
    /// `p`, whatever the weights. Exact for polynomial (uniform-weight) geometries only; on a
    /// rational quartic curve with weights 0.6-1.8 the static equilibrium is off by about
    /// 1e-3 of the model size (see docs/performance.md and `tests/generalized.rs`).
    Fixed,
    /// `n` points per direction on every element (a reference rule for measurements).
    Points(usize),
    /// Weight-aware (vclay's default): per element and direction, the fixed rule's order or
    /// `p + ceil(ln(1/tolerance) / (2 ln r))` points, whichever is larger (at most
    /// [`MAX_WEIGHT_AWARE_POINTS`]), with `r` from the spread of the weights acting on the element
    /// ([`GeneralizedGeometry::element_denominators`]) as in the type docs. The orders are a
    /// function of the current weights only: they are chosen again before every step (elements
    /// whose order changes get their rule and rest values rebuilt), so a saved and restored model
    /// continues bit for bit. Uniform weights keep the fixed rule exactly.
    WeightAware {
        /// Relative accuracy aimed at (default [`DEFAULT_QUADRATURE_TOLERANCE`]), in `(0, 1)`.
        tolerance: f64,
    },
}

impl Default for QuadratureRule {
    fn default() -> Self {
        Self::WeightAware {
            tolerance: DEFAULT_QUADRATURE_TOLERANCE,
        }
    }
}

impl QuadratureRule {
    /// Checks the rule's parameter.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        match *self {
            Self::Fixed => Ok(()),
            Self::Points(n) if (1..=vclay_core::quadrature::MAX_GAUSS_POINTS).contains(&n) => {
                Ok(())
            }
            Self::Points(n) => Err(DynamicsError::Parameter {
                name: "quadrature points",
                value: n as f64,
                why: "must be 1 to 64",
            }),
            Self::WeightAware { tolerance } if tolerance > 0.0 && tolerance < 1.0 => Ok(()),
            Self::WeightAware { tolerance } => Err(DynamicsError::Parameter {
                name: "quadrature tolerance",
                value: tolerance,
                why: "must be in (0, 1)",
            }),
        }
    }

    /// Points per direction for an element of degree `degree` whose denominator `W` varies by
    /// the factor `spread` (`max W / min W` on the element, at least 1) and has its nearest
    /// complex zero on the Bernstein ellipse of radius `radius` (> 1; infinite for a constant
    /// `W`), see [`denominator_radius`].
    pub fn order(&self, degree: usize, radius: f64, spread: f64) -> usize {
        let fixed = (degree + 1).clamp(4, 7);
        match *self {
            Self::Fixed => fixed,
            Self::Points(n) => n,
            Self::WeightAware { tolerance } => {
                let eps = spread - 1.0;
                // Error model `C eps^1.5 r^(-2 (n - p))`, C = QUADRATURE_ERROR_CONSTANT.
                let amplitude = QUADRATURE_ERROR_CONSTANT * eps.max(0.0).powf(1.5);
                if radius.is_nan() || radius <= 1.0 || !eps.is_finite() || amplitude <= tolerance {
                    return fixed;
                }
                if !radius.is_finite() {
                    return fixed;
                }
                let extra = ((amplitude / tolerance).ln() / (2.0 * radius.ln())).ceil();
                let n = degree as f64 + extra.max(0.0);
                (n.min(MAX_WEIGHT_AWARE_POINTS as f64) as usize).max(fixed)
            }
        }
    }
}

/// The constant `C` of the weight-aware error model `C (rho - 1)^1.5 r^(-2 (n - p))`
/// ([`QuadratureRule::WeightAware`]), measured on the rational quartic of
/// `tests/quadrature.rs` (weights 0.6-1.8 scaled towards 1 by 1e-3 to 1) and rounded up so that
/// the model over-estimates every measured error.
pub const QUADRATURE_ERROR_CONSTANT: f64 = 5.0;

/// Bernstein-ellipse radius `r` of the zero of the polynomial sampled by `values` at `nodes`
/// (in `[-1, 1]`; as many nodes as the degree plus one) nearest to `[-1, 1]`, and the spread
/// `max |W| / min |W|` of the samples. The polynomial is interpolated in the monomial basis and
/// its zeros are the eigenvalues of the companion matrix; a zero `z` lies on the ellipse with
/// foci `-1, 1` and radius `|z + sqrt(z^2 - 1)|` (the branch with modulus at least 1). A
/// constant has radius infinity. A zero on `[-1, 1]` (a weight sum that vanishes, which
/// positive weights exclude) has radius 1.
pub fn denominator_radius(values: &[f64], nodes: &[f64]) -> (f64, f64) {
    use nalgebra::{Complex, DMatrix, DVector};
    let n = values.len().min(nodes.len());
    let (lo, hi) = values[..n]
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &w| {
            (lo.min(w.abs()), hi.max(w.abs()))
        });
    if n < 2 || lo.is_nan() || lo <= 0.0 || !hi.is_finite() {
        return (f64::INFINITY, 1.0);
    }
    let spread = hi / lo;
    let v = DMatrix::from_fn(n, n, |i, j| nodes[i].powi(j as i32));
    let Some(c) = v.lu().solve(&DVector::from_column_slice(&values[..n])) else {
        return (f64::INFINITY, spread);
    };
    let cmax = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut deg = n - 1;
    while deg > 0 && c[deg].abs() <= 1e-12 * cmax {
        deg -= 1;
    }
    if deg == 0 {
        return (f64::INFINITY, spread);
    }
    let mut comp = DMatrix::<f64>::zeros(deg, deg);
    for i in 1..deg {
        comp[(i, i - 1)] = 1.0;
    }
    for i in 0..deg {
        comp[(i, deg - 1)] = -c[i] / c[deg];
    }
    let radius = comp
        .complex_eigenvalues()
        .iter()
        .map(|&z: &Complex<f64>| {
            let w = (z * z - 1.0).sqrt();
            (z + w).norm().max((z - w).norm())
        })
        .fold(f64::INFINITY, f64::min);
    (radius.max(1.0), spread)
}

/// Relative margin on the ellipse radius within which [`slice_order`] trusts its closed-form
/// zeros: both ends of `[r (1 - m), r (1 + m)]` must give the same order. The verified zeros
/// (see [`closed_form_radius`]) and nalgebra's companion eigenvalues agree to about `1e-5` of
/// the radius even at a double zero, far inside the margin.
const FAST_RADIUS_MARGIN: f64 = 1e-3;

/// The Gauss order `rule` picks for one slice of denominator samples: the integer
/// `rule.order(degree, r, spread)` with `(r, spread)` from [`denominator_radius`]. For a
/// polynomial of degree at most 3 (every cubic or lower geometry) the zeros come in closed form
/// ([`closed_form_radius`], about 30x cheaper than the companion eigenvalues, which were 10-15 %
/// of a dynamic-weight step); that order is taken when the whole interval of
/// [`FAST_RADIUS_MARGIN`] around the radius gives it, so the result is the order the companion
/// eigenvalues give. Otherwise (an order boundary within the margin, higher degrees, zeros that
/// fail the check) [`denominator_radius`] decides.
fn slice_order(rule: QuadratureRule, degree: usize, values: &[f64], nodes: &[f64]) -> usize {
    if let Some((r, spread)) = closed_form_radius(values, nodes) {
        let lo = rule.order(degree, r * (1.0 - FAST_RADIUS_MARGIN), spread);
        if lo == rule.order(degree, r * (1.0 + FAST_RADIUS_MARGIN), spread) {
            return lo;
        }
    }
    let (r, spread) = denominator_radius(values, nodes);
    rule.order(degree, r, spread)
}

/// The four Chebyshev nodes of a cubic's denominator slices ([`element_order`]) and the LU
/// factors of their Vandermonde matrix, made once (the matrix is the same for every slice).
static CHEBYSHEV4_LU: std::sync::OnceLock<Vandermonde4> = std::sync::OnceLock::new();

/// Four nodes and the LU factors of their Vandermonde matrix `V_ij = t_i^j`.
type Vandermonde4 = (
    [f64; 4],
    nalgebra::linalg::LU<f64, nalgebra::U4, nalgebra::U4>,
);

/// [`denominator_radius`] for up to 4 samples (a polynomial of degree at most 3) from the
/// closed-form zeros: the same monomial coefficients (the same LU solve) and degree; the cubic's
/// zeros by the trigonometric or Cardano formula (Numerical Recipes section 5.6), each refined by
/// two Newton steps on the polynomial, then checked against the coefficients (Vieta's
/// formulas to `1e-9` of the terms' size). `None` when the check fails or the samples are more
/// than 4 (the caller then uses the eigenvalues). Moduli and the ellipse radius are taken
/// algebraically ([`modulus`], [`ellipse_radius`]; `hypot` and the polar square root were a
/// third of this function's time) and nothing is allocated; the Vandermonde factors of the four
/// Chebyshev nodes are made once ([`CHEBYSHEV4_LU`]).
fn closed_form_radius(values: &[f64], nodes: &[f64]) -> Option<(f64, f64)> {
    use nalgebra::{Complex, DVector, Matrix4, Vector4};
    type C = Complex<f64>;
    let n = values.len().min(nodes.len());
    if n > 4 {
        return None;
    }
    let (lo, hi) = values[..n]
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &w| {
            (lo.min(w.abs()), hi.max(w.abs()))
        });
    if n < 2 || lo.is_nan() || lo <= 0.0 || !hi.is_finite() {
        return Some((f64::INFINITY, 1.0));
    }
    let spread = hi / lo;
    // The coefficients exactly as `denominator_radius` computes them (the same generic LU;
    // for the four Chebyshev nodes of every cubic its factors are made once, the same ones).
    let mut c = [0.0; 4];
    if n == 4 {
        let v = |nodes: &[f64]| Matrix4::from_fn(|i, j| nodes[i].powi(j as i32)).lu();
        let cheb = CHEBYSHEV4_LU.get_or_init(|| {
            let nodes = chebyshev_nodes(4);
            ([nodes[0], nodes[1], nodes[2], nodes[3]], v(&nodes))
        });
        let rhs = Vector4::from_column_slice(&values[..4]);
        let solved = if same_bits(&cheb.0, &nodes[..4]) {
            cheb.1.solve(&rhs)
        } else {
            v(nodes).solve(&rhs)
        };
        let Some(x) = solved else {
            return Some((f64::INFINITY, spread));
        };
        c.copy_from_slice(x.as_slice());
    } else {
        let v = nalgebra::DMatrix::from_fn(n, n, |i, j| nodes[i].powi(j as i32));
        let Some(x) = v.lu().solve(&DVector::from_column_slice(&values[..n])) else {
            return Some((f64::INFINITY, spread));
        };
        c[..n].copy_from_slice(x.as_slice());
    }
    let c = &c[..n];
    let cmax = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut deg = n - 1;
    while deg > 0 && c[deg].abs() <= 1e-12 * cmax {
        deg -= 1;
    }
    if deg == 0 {
        return Some((f64::INFINITY, spread));
    }
    // Monic coefficients: z^deg + a[deg-1] z^(deg-1) + ... + a[0].
    let mut monic = [0.0; 3];
    for (m, x) in monic.iter_mut().zip(&c[..deg]) {
        *m = x / c[deg];
    }
    let a = &monic[..deg];
    let eval = |z: C| -> (C, C) {
        let (mut p, mut dp) = (C::new(1.0, 0.0), C::new(0.0, 0.0));
        for &ak in a.iter().rev() {
            dp = dp * z + p;
            p = p * z + ak;
        }
        (p, dp)
    };
    // The zeros in a fixed buffer (no allocation per slice).
    let zero = C::new(0.0, 0.0);
    let mut buffer = [zero; 3];
    let found: &[C] = match deg {
        1 => &[C::new(-a[0], 0.0)],
        2 => {
            let (b, c0) = (a[1], a[0]);
            let disc = b * b - 4.0 * c0;
            if disc >= 0.0 {
                let q = -0.5 * (b + b.signum() * disc.sqrt());
                if q == 0.0 {
                    &[zero; 2]
                } else {
                    &[C::new(q, 0.0), C::new(c0 / q, 0.0)]
                }
            } else {
                let im = 0.5 * (-disc).sqrt();
                &[C::new(-0.5 * b, im), C::new(-0.5 * b, -im)]
            }
        }
        _ => {
            let (a2, a1, a0) = (a[2], a[1], a[0]);
            let q = (a2 * a2 - 3.0 * a1) / 9.0;
            let r = (2.0 * a2 * a2 * a2 - 9.0 * a2 * a1 + 27.0 * a0) / 54.0;
            let shift = a2 / 3.0;
            if r * r < q * q * q {
                let theta = (r / (q * q * q).sqrt()).clamp(-1.0, 1.0).acos();
                let m = -2.0 * q.sqrt();
                let tau = 2.0 * std::f64::consts::PI / 3.0;
                &[0, 1, 2].map(|k| C::new(m * (theta / 3.0 + tau * k as f64).cos() - shift, 0.0))
            } else {
                let big = -r.signum() * (r.abs() + (r * r - q * q * q).sqrt()).cbrt();
                let small = if big == 0.0 { 0.0 } else { q / big };
                let re = -0.5 * (big + small) - shift;
                let im = 0.5 * 3f64.sqrt() * (big - small);
                &[
                    C::new(big + small - shift, 0.0),
                    C::new(re, im),
                    C::new(re, -im),
                ]
            }
        }
    };
    buffer[..found.len()].copy_from_slice(found);
    let roots = &mut buffer[..found.len()];
    for z in roots.iter_mut() {
        for _ in 0..2 {
            let (p, dp) = eval(*z);
            // `|dp| > 0` (a NaN derivative gives a NaN step, which is not taken).
            if dp.re != 0.0 || dp.im != 0.0 {
                let step = p / dp;
                if step.re.is_finite() && step.im.is_finite() {
                    *z -= step;
                }
            }
        }
    }
    // Vieta: the elementary symmetric functions of the zeros against the coefficients.
    const VIETA: f64 = 1e-9;
    let close = |x: C, target: f64, size: f64| modulus(x - target) <= VIETA * size;
    let ok = match deg {
        1 => true,
        2 => {
            let (z1, z2) = (roots[0], roots[1]);
            close(z1 + z2, -a[1], modulus(z1) + modulus(z2))
                && close(z1 * z2, a[0], modulus(z1) * modulus(z2))
        }
        _ => {
            let (z1, z2, z3) = (roots[0], roots[1], roots[2]);
            let (n1, n2, n3) = (modulus(z1), modulus(z2), modulus(z3));
            close(z1 + z2 + z3, -a[2], n1 + n2 + n3)
                && close(
                    z1 * z2 + z1 * z3 + z2 * z3,
                    a[1],
                    n1 * n2 + n1 * n3 + n2 * n3,
                )
                && close(z1 * z2 * z3, -a[0], n1 * n2 * n3)
        }
    };
    if !ok
        || roots
            .iter()
            .any(|z| !(z.re.is_finite() && z.im.is_finite()))
    {
        return None;
    }
    let radius = roots
        .iter()
        .map(|&z| ellipse_radius(z))
        .fold(f64::INFINITY, f64::min);
    Some((radius.max(1.0), spread))
}

/// `|z|` as `sqrt(re^2 + im^2)`: within a few units in the last place of `hypot`, several
/// times cheaper, and without its care for overflow, which the zeros of [`closed_form_radius`]
/// (at most about `1e12` of the element: a leading coefficient above `1e-12` of the largest)
/// do not need. The radius it gives differs from `hypot`'s by far less than
/// [`FAST_RADIUS_MARGIN`], so [`slice_order`] picks the same order.
fn modulus(z: nalgebra::Complex<f64>) -> f64 {
    (z.re * z.re + z.im * z.im).sqrt()
}

/// The Bernstein-ellipse radius `max(|z + w|, |z - w|)`, `w^2 = z^2 - 1`, of a zero `z` (the
/// two products `|z + w| |z - w| = 1`, so either square root gives the same maximum). `w` by
/// the algebraic square root `sqrt((m + a) / 2) + i b / (2 sqrt((m + a) / 2))` of `a + i b`
/// (`m = |a + i b|`; the mirrored form for `a < 0`), without the polar form's `atan2`, `sin`
/// and `cos`.
fn ellipse_radius(z: nalgebra::Complex<f64>) -> f64 {
    let s = z * z - 1.0;
    let (a, b) = (s.re, s.im);
    let m = modulus(s);
    let w = if a >= 0.0 {
        let re = (0.5 * (m + a)).sqrt();
        nalgebra::Complex::new(re, if re > 0.0 { b / (2.0 * re) } else { 0.0 })
    } else {
        let im = (0.5 * (m - a)).sqrt();
        nalgebra::Complex::new(b / (2.0 * im), im)
    };
    modulus(z + w).max(modulus(z - w))
}

/// `k` Chebyshev points of the first kind in `[-1, 1]`.
fn chebyshev_nodes(k: usize) -> Vec<f64> {
    (0..k)
        .map(|i| ((2 * i + 1) as f64 * std::f64::consts::PI / (2 * k) as f64).cos())
        .collect()
}

/// The largest Gauss order per direction that `rule` picks over all elements of `g` (the frozen
/// engine's single rule, [`super::Dnurbs::with_quadrature`]).
pub(crate) fn largest_order<G: GeneralizedGeometry>(g: &G, rule: QuadratureRule) -> usize {
    g.elements()
        .iter()
        .map(|e| {
            let o = element_order(g, rule, e);
            if g.parametric_dimension() == 2 {
                o[0].max(o[1])
            } else {
                o[0]
            }
        })
        .max()
        .unwrap_or_else(|| rule.order(g.max_degree(), f64::INFINITY, 1.0))
}

/// Gauss points per direction for one element under `rule`.
fn element_order<G: GeneralizedGeometry>(
    g: &G,
    rule: QuadratureRule,
    element: &[(f64, f64); 2],
) -> [usize; 2] {
    let deg = g.max_degree();
    let fixed = rule.order(deg, f64::INFINITY, 1.0);
    let mut order = [
        fixed,
        if g.parametric_dimension() == 2 {
            fixed
        } else {
            1
        },
    ];
    if let QuadratureRule::WeightAware { .. } = rule {
        let nodes = chebyshev_nodes(deg + 1);
        let slices = g.element_denominators(element, &nodes);
        for (d, list) in slices.iter().enumerate() {
            if d == 1 && g.parametric_dimension() == 1 {
                continue;
            }
            for slice in list {
                order[d] = order[d].max(slice_order(rule, deg, slice, &nodes));
            }
        }
    }
    order
}

/// One element's contribution to a step.
#[derive(Clone, Debug, Default)]
struct ElementWork {
    /// The coordinates of `a` and `rhs`: the element's columns less the fixed coordinates.
    dofs: Vec<usize>,
    /// `(blocks, vectors)` of `dofs` ([`Gram`]'s shape): `a`'s entries between different
    /// components of two blocks are structural zeros.
    shape: (usize, usize),
    /// The element matrix, dense (row-major `nd x nd` over `dofs`): valid when `dense` is
    /// set ([`ElementWork::densify`]).
    a: Vec<f64>,
    /// Whether `a` holds this step's matrix: point forces write it at once; an element's is
    /// written from `products` only when the step needs it (the block-Schur sum reads
    /// `products`, under a third of the bytes: 1,280 values against 4,096 for a bicubic
    /// element).
    dense: bool,
    /// An element's [`Gram`] products `[bb | bv]`, `vv` (positions in [`gram_index`]).
    products: Vec<f64>,
    /// Every column of the element, fixed ones included (the coordinates of `mass_diag`).
    all_dofs: Vec<usize>,
    mass_diag: Vec<f64>,
    rhs: Vec<f64>,
    elastic: f64,
    kinetic: f64,
}

impl ElementWork {
    /// Writes `a` from `products` unless it holds this step's matrix already.
    fn densify(&mut self) {
        if self.dense {
            return;
        }
        let nd = self.dofs.len();
        if self.a.len() != nd * nd {
            // `write_products` leaves the structural zeros as they are.
            self.a.clear();
            self.a.resize(nd * nd, 0.0);
        }
        write_products(self.shape, &self.products, &mut self.a);
        self.dense = true;
    }
}

/// [`ElementWork::densify`] on every element of `works`, on rayon's threads.
fn densify(works: &mut [ElementWork]) {
    if works.iter().any(|w| !w.dense) {
        works.par_iter_mut().for_each(ElementWork::densify);
    }
}

/// A D-NURBS whose control points and weights are all dynamic (see the module docs).
#[derive(Clone, Debug)]
pub struct GeneralizedDnurbs<G: GeneralizedGeometry> {
    geometry: G,
    material: Material,
    quad: Vec<Quadrature>,
    /// Per element, the geometry's tables for the points of `quad`
    /// ([`GeneralizedGeometry::element_tables`]), rebuilt with the element's rule.
    tables: Vec<Arc<G::ElementTables>>,
    /// The elements (parameter rectangles), as [`GeneralizedGeometry::elements`].
    elements: Vec<[(f64, f64); 2]>,
    quadrature: QuadratureRule,
    pattern: Option<Arc<CsrPattern>>,
    /// Element work buffers kept between steps (scratch; no state).
    work_pool: Vec<ElementWork>,
    rest: Vec<Vec<[Vec3; 6]>>,
    /// The coordinates `rest` was evaluated at (see [`GeneralizedState::rest_coordinates`]).
    rest_coordinates: Vec<f64>,
    velocity: Vec<f64>,
    fixed: Vec<bool>,
    forces: Vec<Force>,
    constraints: Vec<Constraint>,
    /// Linear ties (kept by [`GeneralizedDnurbs::clear_constraints`]).
    ties: Vec<LinearTie>,
    reference: ElasticReference,
    weight_targets: Vec<f64>,
    weight_penalty: f64,
    time: f64,
    steps: usize,
    /// CG iteration cap (default [`GENERALIZED_CG_ITERATIONS`]).
    pub max_iterations: usize,
    /// CG relative residual tolerance (default [`GENERALIZED_CG_TOLERANCE`]).
    pub tolerance: f64,
    /// Lower bound for weights (default [`DEFAULT_WEIGHT_FLOOR`]).
    pub weight_floor: f64,
    /// Constraint feedback gain `kappa` in `(0, 1]` (default 1).
    pub baumgarte: f64,
    /// Weight projections made so far (section 6.2).
    pub weight_projections: usize,
    substeps: usize,
    /// Keep the fixed coordinates' columns in the element products (the reference the unit
    /// tests compare the default, which drops them, against).
    keep_fixed_columns: bool,
    /// Give the direct solver's numeric factorization its matrix already in the fill-reducing
    /// order ([`Permuted`]; off: faer permutes it every step, the reference the unit tests
    /// compare against).
    pre_permute: bool,
    /// Intrinsic inertia of the weights, relative (default [`DEFAULT_WEIGHT_INERTIA`]): each
    /// weight gets the extra kinetic energy `1/2 m_w w'^2` with
    /// `m_w = weight_inertia * (mean mass-matrix diagonal of the control-point coordinates) *
    /// size^2`. The paper's mass matrix gives a weight whose control point lies near the surface
    /// almost no mass (its column `N (p - s) / W` nearly vanishes), so tiny forces accelerate it
    /// without bound; this floor keeps the dynamics well posed. Set 0 for the paper's exact form.
    pub weight_inertia: f64,
    /// Whether the generalized inertial force `g_p` is applied (default true; turning it off
    /// shows its effect).
    pub inertial_force: bool,
    /// How each step's linear system is solved (default [`LinearSolver::Direct`]: a sparse
    /// Cholesky refactored every step on a symbolic analysis that is computed once per set of
    /// fixed coordinates, since the pattern never changes; [`LinearSolver::ConjugateGradient`]:
    /// block-Jacobi CG with [`GeneralizedDnurbs::max_iterations`] and
    /// [`GeneralizedDnurbs::tolerance`], the paper's method).
    pub solver: LinearSolver,
    /// Whether the direct solver reuses an earlier step's factorization as a preconditioner
    /// (see [`FactorReuse`]; default `None`: every step factors its own matrix, the path every
    /// recorded trajectory was computed with). Only for [`LinearSolver::Direct`].
    pub factor_reuse: Option<FactorReuse>,
    /// Whether the direct solver splits the step matrix into the control points' shared
    /// block and the rest and solves through a Schur complement on the rest, when the
    /// structure holds (see [`BlockSchur`]; default `None`: the full factorization, the path
    /// every recorded trajectory was computed with). Only for [`LinearSolver::Direct`] without
    /// [`Self::factor_reuse`].
    pub block_schur: Option<BlockSchur>,
    /// Numeric factorizations so far (the direct solver's; see [`FactorReuse`]).
    factorizations: usize,
    /// The block split of the current pattern (`None` inside: the structure does not hold),
    /// built once per [`CsrPattern`].
    schur: Option<(Arc<CsrPattern>, Option<Arc<SchurPattern>>)>,
    direct: Option<Arc<DirectPattern>>,
    /// Buffers of the numeric factorization kept between steps (scratch; no state).
    factor_buffers: FactorBuffers,
    /// Rows of constraints that act only on fixed coordinates (see [`RowCache`]).
    row_cache: RowCache,
}

impl<G: GeneralizedGeometry> GeneralizedDnurbs<G> {
    /// A model at rest in its current shape.
    pub fn new(geometry: G, material: Material) -> Result<Self, DynamicsError> {
        let dim = geometry.parametric_dimension();
        let geometry_solver = geometry.default_solver();
        let elements = geometry.elements();
        let ne = elements.len();
        validate_material(dim, ne, &material)?;
        let n = geometry.coordinates().len();
        let rule = QuadratureRule::default();
        let quad: Vec<Quadrature> = elements
            .iter()
            .enumerate()
            .map(|(i, e)| {
                Quadrature::for_element(&geometry, i, e, element_order(&geometry, rule, e), dim)
            })
            .collect::<Result<_, _>>()?;
        let tables = element_tables(&geometry, &quad);
        let mut fixed = vec![false; n];
        for i in geometry.default_fixed_coordinates() {
            fixed[i] = true;
        }
        let weights: Vec<f64> = geometry
            .weight_coordinates()
            .iter()
            .map(|&i| geometry.coordinates()[i])
            .collect();
        let mut m = Self {
            velocity: vec![0.0; geometry.coordinates().len()],
            geometry,
            material,
            quad,
            tables,
            elements,
            quadrature: rule,
            pattern: None,
            work_pool: Vec::new(),
            rest: vec![],
            rest_coordinates: vec![],
            fixed,
            forces: vec![],
            constraints: vec![],
            ties: vec![],
            reference: ElasticReference::RestShape,
            weight_targets: weights,
            weight_penalty: 0.0,
            time: 0.0,
            steps: 0,
            max_iterations: GENERALIZED_CG_ITERATIONS,
            tolerance: GENERALIZED_CG_TOLERANCE,
            weight_floor: DEFAULT_WEIGHT_FLOOR,
            baumgarte: 1.0,
            weight_projections: 0,
            inertial_force: true,
            solver: geometry_solver,
            factor_reuse: None,
            block_schur: None,
            factorizations: 0,
            schur: None,
            direct: None,
            factor_buffers: FactorBuffers::default(),
            row_cache: RowCache::default(),
            substeps: 0,
            keep_fixed_columns: false,
            pre_permute: true,
            weight_inertia: DEFAULT_WEIGHT_INERTIA,
        };
        m.set_rest_shape_to_current()?;
        for t in m.geometry.default_ties() {
            m.add_tie(t)?;
        }
        Ok(m)
    }

    /// The geometry.
    pub fn geometry(&self) -> &G {
        &self.geometry
    }

    /// The quadrature rule of the element integrals (default
    /// [`QuadratureRule::WeightAware`]).
    pub fn quadrature_rule(&self) -> QuadratureRule {
        self.quadrature
    }

    /// Replaces the quadrature rule (validated); the element rules and the rest values of
    /// eq (17) are rebuilt for the current weights at once.
    pub fn set_quadrature_rule(&mut self, rule: QuadratureRule) -> Result<(), DynamicsError> {
        rule.validate()?;
        self.quadrature = rule;
        self.update_quadrature()
    }

    /// Quadrature points over all elements (the cost of one assembly, in Jacobian evaluations).
    pub fn quadrature_points(&self) -> usize {
        self.quad.iter().map(|q| q.params.len()).sum()
    }

    /// Chooses every element's Gauss order for the current weights
    /// ([`QuadratureRule::order`]); elements whose order changes get their rule and their rest
    /// values (evaluated at the rest coordinates, as the plastic reset does) rebuilt. A function
    /// of the current coordinates only, so restored states continue bit for bit.
    fn update_quadrature(&mut self) -> Result<(), DynamicsError> {
        let dim = self.geometry.parametric_dimension();
        let rule = self.quadrature;
        let geometry = &self.geometry;
        let quad = &self.quad;
        let changed: Vec<(usize, [usize; 2])> = self
            .elements
            .par_iter()
            .enumerate()
            .filter_map(|(e, el)| {
                let order = element_order(geometry, rule, el);
                (order != quad[e].order).then_some((e, order))
            })
            .collect();
        if changed.is_empty() {
            return Ok(());
        }
        let mut rest_geometry = self.geometry.clone();
        rest_geometry.set_coordinates(&self.rest_coordinates)?;
        // The changed elements side by side (each one's rule, rest values and tables depend on
        // that element only; a step changes tens of them), stored in element order; the first
        // error in element order is reported.
        let elements = &self.elements;
        let rebuilt: Vec<Result<_, DynamicsError>> = changed
            .par_iter()
            .map(|&(e, order)| {
                let q = Quadrature::for_element(geometry, e, &elements[e], order, dim)?;
                let rest = element_rest_values(&rest_geometry, &q)?;
                let tables = Arc::new(geometry.element_tables(e, &q.params));
                Ok((q, rest, tables))
            })
            .collect();
        for (&(e, _), r) in changed.iter().zip(rebuilt) {
            let (q, rest, tables) = r?;
            self.tables[e] = tables;
            self.quad[e] = q;
            self.rest[e] = rest;
        }
        // Point counts changed: the element work buffers are rebuilt by the next assembly.
        Ok(())
    }

    /// Simulated time.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The applied forces (edit freely between steps).
    pub fn forces_mut(&mut self) -> &mut Vec<Force> {
        &mut self.forces
    }

    /// The constraints.
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// Adds a constraint after validating it; returns its index.
    pub fn add_constraint(&mut self, c: Constraint) -> Result<usize, DynamicsError> {
        let index = self.constraints.len();
        let bad = |what: String| DynamicsError::Constraint { index, what };
        let param = match &c {
            Constraint::Point { param, target } => {
                if !(target.iter().all(|x| x.is_finite())) {
                    return Err(bad("target is not finite".into()));
                }
                *param
            }
            Constraint::Normal { param, normal } => {
                if self.geometry.parametric_dimension() != 2 {
                    return Err(bad("normal constraints need a surface".into()));
                }
                if !(normal.iter().all(|x| x.is_finite()) && normal.norm() > 0.0) {
                    return Err(bad("normal must be finite and non-zero".into()));
                }
                *param
            }
        };
        let mut lj = LocalJacobian::default();
        self.geometry
            .jacobian_at(param, &mut lj)
            .map_err(|e| bad(format!("bad parameter {param:?}: {e}")))?;
        self.constraints.push(c);
        Ok(index)
    }

    /// Adds a linear tie between coordinates (validated: coordinates exist, finite
    /// coefficients); returns its index among the ties. Ties are enforced with the constraints
    /// and are not removed by [`Self::clear_constraints`].
    pub fn add_tie(&mut self, tie: LinearTie) -> Result<usize, DynamicsError> {
        let n = self.geometry.coordinates().len();
        let index = self.constraints.len() + self.ties.len();
        for &(i, c) in &tie.terms {
            if i >= n {
                return Err(DynamicsError::NoSuchCoordinate { index: i, count: n });
            }
            if !c.is_finite() {
                return Err(DynamicsError::Constraint {
                    index,
                    what: format!("tie coefficient {c} is not finite"),
                });
            }
        }
        if !tie.value.is_finite() {
            return Err(DynamicsError::Constraint {
                index,
                what: "tie value is not finite".into(),
            });
        }
        self.ties.push(tie);
        Ok(self.ties.len() - 1)
    }

    /// The linear ties (see [`Self::add_tie`]).
    pub fn ties(&self) -> &[LinearTie] {
        &self.ties
    }

    /// The violation `|sum c_i q_i - value|` of every tie.
    pub fn tie_violations(&self) -> Vec<f64> {
        let q = self.geometry.coordinates();
        self.ties
            .iter()
            .map(|t| (t.terms.iter().map(|&(i, c)| c * q[i]).sum::<f64>() - t.value).abs())
            .collect()
    }

    fn has_constraints(&self) -> bool {
        !self.constraints.is_empty() || !self.ties.is_empty()
    }

    /// Rows the constraints and ties add to a step (before the dependence check): a point
    /// constraint 3, a normal constraint 2, a tie 1.
    fn constraint_row_count(&self) -> usize {
        let rows: usize = self
            .constraints
            .iter()
            .map(|c| match c {
                Constraint::Point { .. } => 3,
                Constraint::Normal { .. } => 2,
            })
            .sum();
        rows + self.ties.len()
    }

    /// Removes every constraint (the ties stay).
    pub fn clear_constraints(&mut self) {
        self.constraints.clear();
    }

    /// Constraint violations `|C(p)|` per constraint (largest row magnitude).
    pub fn constraint_violations(&self) -> Result<Vec<f64>, DynamicsError> {
        let mut out = Vec::with_capacity(self.constraints.len());
        for (ci, c) in self.constraints.iter().enumerate() {
            let rows = self.cached_constraint_rows(ci, c)?;
            out.push(rows.iter().map(|r| r.0.abs()).fold(0.0, f64::max));
        }
        Ok(out)
    }

    /// Distances from each data point of the [`Force::DataPoint`] forces to the geometry.
    pub fn data_distances(&self) -> Result<Vec<f64>, DynamicsError> {
        let mut lj = LocalJacobian::default();
        let mut out = vec![];
        for f in &self.forces {
            if let Force::DataPoint { point, .. } = f {
                let p = self.geometry.nearest_param(point)?;
                self.geometry.jacobian_at(p, &mut lj)?;
                out.push((lj.s[0] - point).norm());
            }
        }
        Ok(out)
    }

    /// Holds (or frees) one generalized coordinate.
    pub fn set_fixed_coordinate(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError> {
        let n = self.fixed.len();
        *self
            .fixed
            .get_mut(i)
            .ok_or(DynamicsError::NoSuchCoordinate { index: i, count: n })? = fixed;
        Ok(())
    }

    /// Whether coordinate `i` is held.
    pub fn is_fixed_coordinate(&self, i: usize) -> bool {
        self.fixed.get(i).copied().unwrap_or(false)
    }

    /// Penalty `c/2 sum (w - w0)^2` holding weights near their initial values (0 disables).
    pub fn set_weight_penalty(&mut self, c: f64) -> Result<(), DynamicsError> {
        if !(c.is_finite() && c >= 0.0) {
            return Err(DynamicsError::Parameter {
                name: "weight penalty",
                value: c,
                why: "must be finite and non-negative",
            });
        }
        self.weight_penalty = c;
        Ok(())
    }

    /// Chooses the elastic reference (see [`ElasticReference`]).
    pub fn set_elastic_reference(&mut self, r: ElasticReference) {
        self.reference = r;
    }

    /// Plastic reset: the current shape becomes the rest shape, and the motion stops.
    pub fn set_rest_shape_to_current(&mut self) -> Result<(), DynamicsError> {
        self.rest = rest_values(&self.geometry, &self.quad)?;
        self.rest_coordinates = self.geometry.coordinates().to_vec();
        self.velocity = vec![0.0; self.velocity.len()];
        Ok(())
    }

    /// Plastic flow: moves the rest shape toward the current shape where it is deformed past a
    /// yield distance, by `fraction` of the overstress (see `vclay_core::plasticity` for the
    /// law, `docs/sculpting.md` for its derivation). Per coordinate group `g` (a control point's
    /// `x, y, z, w`; [`GeneralizedGeometry::coordinate_groups`]) with displacement
    /// `e = q_g - q0_g` measured on its non-weight coordinates,
    ///
    /// ```text
    /// q0_g <- q0_g + fraction * max(0, 1 - yield / |e|) * (q_g - q0_g)
    /// ```
    ///
    /// (the weights move with their point). `fraction = 1`, `yield = 0` is the plastic reset of
    /// [`Self::set_rest_shape_to_current`] without stopping the motion. The rest values of eq
    /// (17) are evaluated again at the new rest coordinates (one pass over the quadrature
    /// points, as the reset) when any point yielded. Returns how many groups yielded.
    ///
    /// # Errors
    /// [`DynamicsError::Parameter`] for `fraction` outside `[0, 1]` or a negative or
    /// non-finite `yield_distance`.
    pub fn plastic_flow(
        &mut self,
        fraction: f64,
        yield_distance: f64,
    ) -> Result<usize, DynamicsError> {
        super::check_flow_args(fraction, yield_distance)?;
        let q = self.geometry.coordinates();
        let weights = self.geometry.weight_coordinates();
        let mut is_weight = vec![false; q.len()];
        for w in weights {
            if let Some(x) = is_weight.get_mut(w) {
                *x = true;
            }
        }
        let mut rest = self.rest_coordinates.clone();
        let mut yielded = 0;
        for g in self.geometry.coordinate_groups() {
            let e2: f64 = g
                .clone()
                .filter(|&i| !is_weight[i])
                .map(|i| (q[i] - rest[i]).powi(2))
                .sum();
            let f =
                vclay_core::plasticity::plastic_flow_factor(fraction, yield_distance, e2.sqrt());
            if f > 0.0 {
                yielded += 1;
                for i in g {
                    rest[i] += f * (q[i] - rest[i]);
                }
            }
        }
        if yielded > 0 {
            let mut geometry = self.geometry.clone();
            geometry.set_coordinates(&rest)?;
            self.rest = rest_values(&geometry, &self.quad)?;
            self.rest_coordinates = rest;
        }
        Ok(yielded)
    }

    /// Replaces the rest coordinates `q0` (the smooth brush's smoothed rest shape) and
    /// evaluates eq (17)'s rest values at them, as the plastic reset does; the shape, its
    /// motion and the material stay, and the elastic forces then pull the shape towards the new
    /// rest shape.
    ///
    /// # Errors
    /// [`DynamicsError::NoSuchCoordinate`] for a wrong length; the geometry's own checks
    /// (finite values, positive weights).
    pub fn set_rest_coordinates(&mut self, rest: &[f64]) -> Result<(), DynamicsError> {
        let mut geometry = self.geometry.clone();
        geometry.set_coordinates(rest)?;
        self.rest = rest_values(&geometry, &self.quad)?;
        self.rest_coordinates = rest.to_vec();
        Ok(())
    }

    /// The rest coordinates `q0` (see [`Self::set_rest_coordinates`]).
    pub fn rest_coordinates(&self) -> &[f64] {
        &self.rest_coordinates
    }

    /// Steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// Replaces the material (validated as in [`GeneralizedDnurbs::new`]); the state is kept.
    /// The matrices of eqs (16)-(17) are integrated every step, so the next step uses it.
    pub fn set_material(&mut self, material: Material) -> Result<(), DynamicsError> {
        validate_material(
            self.geometry.parametric_dimension(),
            self.quad.len(),
            &material,
        )?;
        self.material = material;
        Ok(())
    }

    /// The applied forces.
    pub fn forces(&self) -> &[Force] {
        &self.forces
    }

    /// The coordinate velocity `p'` (of the last step).
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// Stops the motion: the coordinate velocity becomes zero (the shape and its rest stay).
    pub fn stop(&mut self) {
        self.velocity.iter_mut().for_each(|v| *v = 0.0);
    }

    /// The weight penalty `c` (see [`GeneralizedDnurbs::set_weight_penalty`]).
    pub fn weight_penalty(&self) -> f64 {
        self.weight_penalty
    }

    /// What the elastic energy is measured against.
    pub fn elastic_reference(&self) -> ElasticReference {
        self.reference
    }

    /// A copy of the evolving state (everything a step reads and writes except the forces,
    /// the constraints and the tunable fields): with [`GeneralizedDnurbs::set_state`] on a
    /// model built from the same initial geometry and material, with the same forces and
    /// constraints, the continued simulation is bit for bit the same.
    pub fn state(&self) -> GeneralizedState {
        GeneralizedState {
            coordinates: self.geometry.coordinates().to_vec(),
            velocity: self.velocity.clone(),
            rest_coordinates: self.rest_coordinates.clone(),
            fixed: self.fixed.clone(),
            weight_targets: self.weight_targets.clone(),
            weight_penalty: self.weight_penalty,
            reference: self.reference,
            time: self.time,
            steps: self.steps,
            substeps: self.substeps,
            weight_projections: self.weight_projections,
        }
    }

    /// Puts back a state taken by [`GeneralizedDnurbs::state`] (of this model or of one built
    /// from the same initial geometry). Checked first (lengths, finite values, positive
    /// weights); on error the model is unchanged. The rest values of eq (17)'s reference shape
    /// are evaluated again at `rest_coordinates` (the same computation as the plastic reset,
    /// hence the same bits) when they differ from the current ones.
    pub fn set_state(&mut self, s: &GeneralizedState) -> Result<(), DynamicsError> {
        let n = self.geometry.coordinates().len();
        let nw = self.weight_targets.len();
        for (len, want) in [
            (s.coordinates.len(), n),
            (s.velocity.len(), n),
            (s.rest_coordinates.len(), n),
            (s.fixed.len(), n),
            (s.weight_targets.len(), nw),
        ] {
            if len != want {
                return Err(DynamicsError::NoSuchCoordinate {
                    index: len,
                    count: want,
                });
            }
        }
        let finite = |name: &'static str, v: &[f64]| match v.iter().find(|x| !x.is_finite()) {
            Some(&x) => Err(DynamicsError::Parameter {
                name,
                value: x,
                why: "must be finite",
            }),
            None => Ok(()),
        };
        finite("velocity", &s.velocity)?;
        finite("weight target", &s.weight_targets)?;
        finite("time", &[s.time])?;
        if !(s.weight_penalty.is_finite() && s.weight_penalty >= 0.0) {
            return Err(DynamicsError::Parameter {
                name: "weight penalty",
                value: s.weight_penalty,
                why: "must be finite and non-negative",
            });
        }
        let mut geometry = self.geometry.clone();
        let rest = if same_bits(&s.rest_coordinates, &self.rest_coordinates) {
            None
        } else {
            geometry.set_coordinates(&s.rest_coordinates)?;
            Some(rest_values(&geometry, &self.quad)?)
        };
        geometry.set_coordinates(&s.coordinates)?;
        self.geometry = geometry;
        if let Some(r) = rest {
            self.rest = r;
            self.rest_coordinates = s.rest_coordinates.clone();
        }
        self.velocity = s.velocity.clone();
        self.fixed = s.fixed.clone();
        self.weight_targets = s.weight_targets.clone();
        self.weight_penalty = s.weight_penalty;
        self.reference = s.reference;
        self.time = s.time;
        self.steps = s.steps;
        self.substeps = s.substeps;
        self.weight_projections = s.weight_projections;
        Ok(())
    }

    /// The elastic energy `U` of the current shape.
    pub fn elastic_energy(&self) -> Result<f64, DynamicsError> {
        let coef = self.stiffness_coefficients_fn();
        let g = &self.geometry;
        let parts: Vec<f64> = self
            .quad
            .par_iter()
            .enumerate()
            .map(|(e, q)| {
                let mut u = 0.0;
                for (k, (&p, &w)) in q.params.iter().zip(&q.weights).enumerate() {
                    let s = g.values_at(p)?;
                    let c = coef(e, p);
                    for m in 1..6 {
                        if c[m] != 0.0 {
                            u += 0.5
                                * w
                                * c[m]
                                * (s[m] - self.reference_value(e, k, m)).norm_squared();
                        }
                    }
                }
                Ok(u)
            })
            .collect::<Result<_, DynamicsError>>()?;
        Ok(parts.iter().sum())
    }

    fn reference_value(&self, e: usize, k: usize, m: usize) -> Vec3 {
        match self.reference {
            ElasticReference::RestShape => self.rest[e][k][m],
            ElasticReference::Absolute => Vec3::zeros(),
        }
    }

    /// `[0, a11, a22, b11, b12, b22]` at an element and parameter (curves: `[0, alpha, 0,
    /// beta, 0, 0]`).
    fn stiffness_coefficients_fn(&self) -> impl Fn(usize, [f64; 2]) -> [f64; 6] + Sync + '_ {
        let mat = &self.material;
        let surface = self.geometry.parametric_dimension() == 2;
        move |e, p| {
            let ev = |d: &Density| d.eval(e, p);
            if surface {
                [
                    0.0,
                    ev(&mat.alpha[0]),
                    ev(&mat.alpha[1]),
                    ev(&mat.beta[0]),
                    ev(&mat.beta[1]),
                    ev(&mat.beta[2]),
                ]
            } else {
                [0.0, ev(&mat.alpha[0]), 0.0, ev(&mat.beta[0]), 0.0, 0.0]
            }
        }
    }

    /// [`Self::constraint_rows_and_support`]'s rows of constraint `ci`, from the [`RowCache`]
    /// when every coordinate it acts on is fixed and unchanged since the rows were computed.
    fn cached_constraint_rows(
        &self,
        ci: usize,
        c: &Constraint,
    ) -> Result<Vec<ConstraintRow>, DynamicsError> {
        let q = self.geometry.coordinates();
        let valid = |e: &CachedRows| {
            e.constraint == *c
                && e.coords
                    .iter()
                    .all(|&(i, bits)| self.fixed[i] && q[i].to_bits() == bits)
        };
        if let Some(Some(e)) = self.row_cache.lock().get(ci)
            && valid(e)
        {
            return Ok(e.rows.clone());
        }
        let (rows, support) = self.constraint_rows_and_support(c)?;
        // The rows are a function of the support's coordinates: while all of them are fixed
        // (and so unchanged), the rows cannot change.
        let coords: Vec<(usize, u64)> = support.iter().map(|&i| (i, q[i].to_bits())).collect();
        let entry = (!coords.is_empty() && coords.iter().all(|&(i, _)| self.fixed[i])).then(|| {
            CachedRows {
                constraint: c.clone(),
                coords,
                rows: rows.clone(),
            }
        });
        let mut cache = self.row_cache.lock();
        if cache.len() < self.constraints.len() {
            cache.resize_with(self.constraints.len(), || None);
        }
        cache[ci] = entry;
        Ok(rows)
    }

    /// Rows `(value, [(coordinate, derivative)])` of a constraint at the current shape, and
    /// the coordinates the constraint's value depends on: the
    /// Jacobian columns at its parameter whose orders 0 to 2 are not all zero (a geometry may
    /// list columns of basis functions that vanish there, as the triangular one lists a
    /// triangle's controls; those do not count).
    fn constraint_rows_and_support(
        &self,
        c: &Constraint,
    ) -> Result<(Vec<ConstraintRow>, Vec<usize>), DynamicsError> {
        let mut lj = LocalJacobian::default();
        let (param, dirs): ([f64; 2], Vec<(usize, Vec3, Vec3)>) = match c {
            Constraint::Point { param, target } => (
                *param,
                (0..3)
                    .map(|k| {
                        let mut e = Vec3::zeros();
                        e[k] = 1.0;
                        (0, e, *target)
                    })
                    .collect(),
            ),
            Constraint::Normal { param, normal } => {
                let n = normal.normalize();
                (*param, vec![(1, n, Vec3::zeros()), (2, n, Vec3::zeros())])
            }
        };
        self.geometry.jacobian_at(param, &mut lj)?;
        let dofs = lj.dofs();
        let rows = dirs
            .into_iter()
            .map(|(m, n, target)| {
                let value = n.dot(&(lj.s[m] - target));
                let mut local = vec![0.0; dofs.len()];
                lj.apply_transpose(m, 1.0, &n, &mut local);
                (value, dofs.iter().copied().zip(local).collect())
            })
            .collect();
        let mut support: Vec<usize> = Vec::new();
        for (b, r) in &lj.blocks {
            if r[..3].iter().any(|&x| x != 0.0) {
                support.extend([*b, b + 1, b + 2]);
            }
        }
        for (i, g) in &lj.vectors {
            if g[..3].iter().any(|x| *x != Vec3::zeros()) {
                support.push(*i);
            }
        }
        Ok((rows, support))
    }

    /// One step of the integrator. Returns what the step did; detects divergence.
    ///
    /// The step is linearized at time t; when it would change a weight by more than
    /// [`MAX_RELATIVE_WEIGHT_CHANGE`] of its value, it is replaced by two half steps
    /// (recursively, at most [`MAX_SUBSTEP_LEVELS`] times), so the nonlinearity of the rational
    /// weights never makes a linearized step overshoot. Static (Gauss-Newton) steps are shortened
    /// instead.
    pub fn step(&mut self, integrator: Integrator) -> Result<StepReport, DynamicsError> {
        match integrator {
            Integrator::Implicit { dt } => {
                if !(dt.is_finite() && dt > 0.0) {
                    return Err(DynamicsError::Parameter {
                        name: "dt",
                        value: dt,
                        why: "must be finite and positive",
                    });
                }
                self.substep(dt, 0)
            }
            Integrator::Static => self.step_once(1.0, false)?.ok_or_else(unreachable_short),
        }
    }

    /// Number of sub-steps taken so far because linearized steps were too large.
    pub fn substeps(&self) -> usize {
        self.substeps
    }

    /// Numeric factorizations of the direct solver so far (one per step unless
    /// [`Self::factor_reuse`] is set).
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }

    fn substep(&mut self, dt: f64, level: usize) -> Result<StepReport, DynamicsError> {
        if let Some(r) = self.step_once(dt, true)? {
            return Ok(r);
        }
        if level >= MAX_SUBSTEP_LEVELS {
            return Err(DynamicsError::Diverged {
                step: self.steps,
                time: self.time,
                what: format!(
                    "a step of {dt:.3e} still changes the shape too much after {level} halvings"
                ),
                suggested_dt: dt / 2.0,
            });
        }
        self.substeps += 1;
        let first = self.substep(dt / 2.0, level + 1)?;
        let second = self.substep(dt / 2.0, level + 1)?;
        Ok(StepReport {
            solver: SolverStats {
                iterations: first.solver.iterations + second.solver.iterations,
                relative_residual: first
                    .solver
                    .relative_residual
                    .max(second.solver.relative_residual),
            },
            elastic_energy: first.elastic_energy,
            ..second
        })
    }

    /// One linearized step; `None` when the step is too large to trust (dynamic mode only).
    fn step_once(&mut self, dt: f64, dynamic: bool) -> Result<Option<StepReport>, DynamicsError> {
        self.update_quadrature()?;
        let q = self.geometry.coordinates().to_vec();
        let n = q.len();
        let v: Vec<f64> = if dynamic {
            self.velocity.iter().map(|x| x * dt).collect()
        } else {
            vec![0.0; n]
        };
        // System: A dq = b with A = cm M + cd D + ck K (+ springs), per the module docs.
        let (ck, force_scale) = if dynamic {
            (2.0 * dt * dt, 2.0 * dt * dt)
        } else {
            (1.0, 1.0)
        };
        // Element buffers from the previous step (taken back at the end of a step).
        let mut works = std::mem::take(&mut self.work_pool);
        self.assemble(dt, dynamic, ck, force_scale, &v, &mut works)?;
        let elastic_before: f64 = works.iter().map(|w| w.elastic).sum();
        self.add_point_forces(&mut works, ck, force_scale)?;
        let mut b = vec![0.0; n];
        for w in &works {
            for (a, &i) in w.dofs.iter().enumerate() {
                b[i] += w.rhs[a];
            }
        }
        // Weight penalty: c/2 (w - w0)^2.
        let mut extra_diag = vec![0.0; n];
        if self.weight_penalty > 0.0 {
            for (k, &i) in self.geometry.weight_coordinates().iter().enumerate() {
                extra_diag[i] += ck * self.weight_penalty;
                b[i] -= force_scale * self.weight_penalty * (q[i] - self.weight_targets[k]);
            }
        }
        // Intrinsic weight inertia (see `weight_inertia`): m_w = kappa * mean position mass *
        // scale^2, entering eq 18 as 2 m_w on the diagonal and 2 m_w v on the right.
        let weight_mass = if dynamic && self.weight_inertia > 0.0 {
            let weights = self.geometry.weight_coordinates();
            let mut is_w = vec![false; n];
            for &i in &weights {
                is_w[i] = true;
            }
            let (mut sum, mut count) = (0.0, 0usize);
            let mut md = vec![0.0; n];
            for w in &works {
                for (a, &i) in w.all_dofs.iter().enumerate() {
                    if let Some(m) = w.mass_diag.get(a) {
                        md[i] += m;
                    }
                }
            }
            for i in 0..n {
                if !is_w[i] && md[i] > 0.0 {
                    sum += md[i];
                    count += 1;
                }
            }
            let scale = self.geometry.scale();
            let mw = if count > 0 {
                self.weight_inertia * sum / count as f64 * scale * scale
            } else {
                0.0
            };
            for &i in &weights {
                extra_diag[i] += 2.0 * mw;
                b[i] += 2.0 * mw * v[i];
            }
            mw
        } else {
            0.0
        };
        // The element matrices summed into a CSR matrix with a fixed pattern (built once: the
        // elements' coordinates never change); point forces stay element-wise.
        let ne = self.quad.len();
        // The element columns leave out the fixed coordinates: a new fixed set, a new pattern.
        if self.pattern.as_ref().is_none_or(|p| p.fixed != self.fixed) {
            self.pattern = Some(Arc::new(CsrPattern::new(n, &works[..ne], &self.fixed)));
        }
        let pattern = self.pattern.clone().expect("just built");
        let warm: Vec<f64> = (0..n)
            .map(|i| if self.fixed[i] { 0.0 } else { v[i] })
            .collect();
        let mut x = warm.clone();
        // The block split (`block_schur`): the shared position block and the rest summed
        // straight from the element matrices and factored apart, CG on the Schur complement;
        // the CSR values and the full factorization when the structure does not hold or the
        // iterations do not reach the tolerance.
        let schur = match self.block_schur {
            Some(settings)
                if self.solver == LinearSolver::Direct
                    && self.factor_reuse.is_none()
                    && self.constraint_row_count() <= settings.max_constraint_rows =>
            {
                let solved =
                    self.schur_solve(settings, &pattern, &extra_diag, &mut works, ne, &b, &mut x);
                if solved.is_none() {
                    x.copy_from_slice(&warm);
                }
                solved.map(|(f, stats)| (f, settings, stats))
            }
            _ => None,
        };
        let mut values = if schur.is_some() {
            Vec::new()
        } else {
            // Every other path reads the dense element matrices.
            densify(&mut works[..ne]);
            pattern.values(&works[..ne])
        };
        // The direct solver folds the point-force blocks into the CSR values (they lie in the
        // element pattern) and factors them; CG applies them element-wise.
        let folded = schur.is_some()
            || (self.solver == LinearSolver::Direct
                && fold_extras(&pattern, &mut values, &works[ne..], &self.fixed));
        let first_extra = if folded { works.len() } else { ne };
        // An earlier step's factor as the preconditioner (`factor_reuse`), if it fits this
        // step's pattern; the step factors its own matrix if that does not converge.
        let lagged = match (self.factor_reuse, folded) {
            (Some(reuse), true) => self
                .factor_buffers
                .lagged
                .take()
                .filter(|f| f.pattern.fixed == self.fixed)
                .map(|f| (reuse, f)),
            _ => None,
        };
        // The operator borrows a copy of the fixed mask, so that `factor` may take `self`.
        let fixed = self.fixed.clone();
        let op = Op {
            works: &works,
            // No CSR values on the block split's path (its solves do not read them).
            csr: schur.is_none().then_some((&*pattern, values.as_slice())),
            first_extra,
            extra_diag: &extra_diag,
            fixed: &fixed,
            n,
        };
        let reused = lagged.and_then(|(reuse, f)| {
            let stats = pcg(&op, &f, &b, &mut x, reuse.max_iterations, reuse.tolerance);
            if stats.relative_residual <= reuse.tolerance {
                Some((f, stats))
            } else {
                // Its buffer holds the new factor.
                self.factor_buffers.factor = f.values;
                x.copy_from_slice(&warm);
                None
            }
        });
        let (pre, mut stats) = match (reused, schur) {
            (Some((f, stats)), _) => (Solve::Reused(f), stats),
            // The CG's residual is reported, as the CG paths do.
            (None, Some((f, settings, stats))) => (Solve::Schur(f, settings), stats),
            (None, None) => {
                let direct = if folded {
                    self.factor(&pattern, &values, &extra_diag)
                } else {
                    None
                };
                let pre = match direct {
                    Some(f) => Solve::Direct(f),
                    None => Solve::Pcg(Precond::new(&op, &self.geometry.coordinate_groups())),
                };
                let stats = pre.solve(&op, &b, &mut x, self.max_iterations, self.tolerance);
                (pre, stats)
            }
        };
        if self.has_constraints() {
            stats = self.apply_constraints(&op, &pre, &b, &mut x, self.baumgarte, stats)?;
        }
        let scale = self.geometry.scale();
        if x.iter().any(|d| !d.is_finite()) {
            return Err(DynamicsError::Diverged {
                step: self.steps,
                time: self.time,
                what: "the linear solve produced non-finite values".into(),
                suggested_dt: dt / 10.0,
            });
        }
        // Trust check of the linearization (see `step`).
        let weights = self.geometry.weight_coordinates();
        let mut ratio: f64 = 0.0;
        for &i in &weights {
            ratio = ratio.max(x[i].abs() / (MAX_RELATIVE_WEIGHT_CHANGE * q[i].abs()));
        }
        if ratio > 1.0 {
            if dynamic {
                // The caller halves the step: keep the element buffers for the retry.
                self.factor_buffers.keep(pre, self.factor_reuse.is_some());
                works.truncate(ne);
                self.work_pool = works;
                return Ok(None);
            }
            for d in x.iter_mut() {
                *d /= ratio;
            }
        }
        // New coordinates with weight projection (a projected weight stops).
        let mut qn: Vec<f64> = q.iter().zip(&x).map(|(a, d)| a + d).collect();
        let mut stopped = vec![];
        for &i in &weights {
            if qn[i] < self.weight_floor {
                qn[i] = self.weight_floor;
                self.weight_projections += 1;
                stopped.push(i);
            }
        }
        let moved = qn
            .iter()
            .zip(&q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if qn.iter().any(|x| !x.is_finite())
            || moved > super::DIVERGENCE_DISPLACEMENT_FACTOR * scale
        {
            return Err(DynamicsError::Diverged {
                step: self.steps,
                time: self.time,
                what: format!("coordinates moved by {moved:.3e} (model size {scale:.3e})"),
                suggested_dt: dt / 10.0,
            });
        }
        self.geometry.set_coordinates(&qn)?;
        // Newton projection onto the constraints in the metric of A (removes the second-order
        // residual of the linearized constraint rows).
        if self.has_constraints() && self.baumgarte >= 1.0 {
            let tol = CONSTRAINT_TOLERANCE * scale;
            for _ in 0..MAX_CONSTRAINT_PROJECTIONS {
                let worst = self
                    .constraint_violations()?
                    .into_iter()
                    .chain(self.tie_violations())
                    .fold(0.0, f64::max);
                if worst <= tol {
                    break;
                }
                let zero = vec![0.0; n];
                let mut dx = vec![0.0; n];
                stats = self.apply_constraints(&op, &pre, &zero, &mut dx, 1.0, stats)?;
                let q2: Vec<f64> = self
                    .geometry
                    .coordinates()
                    .iter()
                    .zip(&dx)
                    .map(|(a, d)| a + d)
                    .collect();
                self.geometry.set_coordinates(&q2)?;
                for i in 0..n {
                    x[i] += dx[i];
                }
                qn.copy_from_slice(&q2);
            }
        }
        // Kinetic energy of the state the step started from, 1/2 p'^T M p' (the element part
        // was integrated during assembly), plus the weights' intrinsic inertia.
        let kinetic = if dynamic {
            let mut k: f64 = works.iter().map(|w| w.kinetic).sum();
            for i in self.geometry.weight_coordinates() {
                k += 0.5 * weight_mass * self.velocity[i] * self.velocity[i];
            }
            k
        } else {
            0.0
        };
        if dynamic {
            self.velocity = qn.iter().zip(&q).map(|(a, b)| (a - b) / dt).collect();
            for i in stopped {
                self.velocity[i] = 0.0;
            }
            self.time += dt;
        }
        self.steps += 1;
        self.factor_buffers.keep(pre, self.factor_reuse.is_some());
        works.truncate(ne);
        self.work_pool = works;
        Ok(Some(StepReport {
            time: self.time,
            solver: stats,
            kinetic_energy: kinetic,
            elastic_energy: elastic_before,
        }))
    }

    /// Runs `steps` implicit steps of size `dt`; returns the last report.
    pub fn run(&mut self, dt: f64, steps: usize) -> Result<Option<StepReport>, DynamicsError> {
        let mut last = None;
        for _ in 0..steps {
            last = Some(self.step(Integrator::Implicit { dt })?);
        }
        Ok(last)
    }

    /// The element work of this step into `works` (one per element; buffers reused between
    /// steps), elements in parallel, each thread with its own Jacobian and Gram scratch.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &self,
        dt: f64,
        dynamic: bool,
        ck: f64,
        fs: f64,
        v: &[f64],
        works: &mut Vec<ElementWork>,
    ) -> Result<(), DynamicsError> {
        let coef_fn = self.stiffness_coefficients_fn();
        let g = &self.geometry;
        let mat = &self.material;
        let forces = &self.forces;
        let dim = g.parametric_dimension();
        let surface = dim == 2;
        // Kernel springs: the kernel and the target, once per step rather than per point.
        let kernels = forces
            .iter()
            .map(|force| match force {
                Force::Spring {
                    target,
                    kernel: Some(sigma),
                    ..
                } => Ok(Some((
                    super::SpringKernel::new(*sigma, dim)?,
                    target.at(self.time),
                ))),
                _ => Ok(None),
            })
            .collect::<Result<Vec<_>, DynamicsError>>()?;
        works.truncate(self.quad.len());
        works.resize_with(self.quad.len(), ElementWork::default);
        // Fixed coordinates' columns are dropped from the element products (empty: none fixed).
        let fixed: &[bool] = if !self.keep_fixed_columns && self.fixed.iter().any(|&f| f) {
            &self.fixed
        } else {
            &[]
        };
        let fixed_hint: Arc<[bool]> = Arc::from(fixed);
        let tables = &self.tables;
        self.quad
            .par_iter()
            .zip(works.par_iter_mut())
            .enumerate()
            .try_for_each(|(e, (q, w))| {
                let tables = &*tables[e];
                // Per-thread scratch that outlives the step (rayon would re-create per-job
                // state for every split, and freeing those buffers each step churns the heap).
                with_scratch(|ElementScratch { lj, gram, vl }| {
                    lj.hint = ColumnHint {
                        fixed: fixed_hint.clone(),
                    };
                    // The element's columns, then without the fixed coordinates: their rows and
                    // columns of the step matrix are never used (the solve is on the free
                    // coordinates), so the products skip them. The velocity term and the lumped
                    // mass (the weights' inertia) still see every column.
                    g.element_jacobian_tabled(e, 0, q.params[0], tables, lj)?;
                    lj.dofs_into(&mut w.all_dofs);
                    w.mass_diag.clear();
                    w.mass_diag.resize(w.all_dofs.len(), 0.0);
                    vl.clear();
                    vl.extend(w.all_dofs.iter().map(|&i| v[i]));
                    let moving = vl.iter().any(|x| *x != 0.0);
                    let shape = lj.free_dofs_into(fixed, &mut w.dofs);
                    let nd = w.dofs.len();
                    if w.shape != shape {
                        // A new shape: `densify` zeroes `a` before writing it.
                        w.a.clear();
                        w.shape = shape;
                    }
                    w.dense = false;
                    w.rhs.clear();
                    w.rhs.resize(nd, 0.0);
                    (w.elastic, w.kinetic) = (0.0, 0.0);
                    gram.reset_shape(shape);
                    for (k, (&p, &qw)) in q.params.iter().zip(&q.weights).enumerate() {
                        if k > 0 {
                            g.element_jacobian_tabled(e, k, p, tables, lj)?;
                        }
                        let c = coef_fn(e, p);
                        let mu = mat.mu.eval(e, p);
                        let gamma = mat.gamma.eval(e, p);
                        // Stiffness (Gauss-Newton) coefficients; `y[m]` collects the vectors
                        // `J^m^T` is applied to for the right-hand side (one pass at the end).
                        let mut coef = [0.0; 6];
                        let mut y = [Vec3::zeros(); 6];
                        for m in 1..6 {
                            coef[m] = ck * qw * c[m];
                            if c[m] != 0.0 {
                                // Elastic gradient.
                                let d = lj.s[m] - self.reference_value(e, k, m);
                                w.elastic += 0.5 * qw * c[m] * d.norm_squared();
                                y[m] -= d * (fs * qw * c[m]);
                            }
                        }
                        // With every column (before the fixed ones are dropped).
                        let jv = if dynamic {
                            // The weights' intrinsic inertia scales with this lumped mass; a
                            // massless model (mu = 0: the first-order fitting rows of Table 1)
                            // takes the damping's share of the step matrix, dt gamma / 2.
                            let lumped = if mu > 0.0 { mu } else { 0.5 * dt * gamma };
                            lj.accumulate_value_diagonal(qw * lumped, &mut w.mass_diag);
                            lj.apply(0, vl)
                        } else {
                            Vec3::zeros()
                        };
                        lj.retain_free(fixed);
                        if dynamic {
                            coef[0] = qw * (2.0 * mu + dt * gamma);
                            // (2M - dt D) v and the inertial force g_p.
                            y[0] += jv * (qw * (2.0 * mu - dt * gamma));
                            w.kinetic += 0.5 * qw * mu * jv.norm_squared() / (dt * dt);
                            if self.inertial_force && mu != 0.0 && moving {
                                // 2 dt^2 g_p with p' = v / dt: -2 mu J^T (J' v).
                                let (_, acc) = g.velocity_terms_after(p, v, lj)?;
                                y[0] -= acc * (2.0 * qw * mu);
                            }
                        }
                        // Distributed forces.
                        let mut f = Vec3::zeros();
                        for (fi, force) in forces.iter().enumerate() {
                            match force {
                                Force::Gravity(gv) => f += gv * mu,
                                Force::Inflation(pr) if surface => {
                                    f += lj.s[1].cross(&lj.s[2]) * *pr
                                }
                                Force::Repulsion {
                                    center,
                                    strength,
                                    core,
                                } => {
                                    let da = if surface {
                                        lj.s[1].cross(&lj.s[2]).norm()
                                    } else {
                                        lj.s[1].norm()
                                    };
                                    f += super::repulsion_density(
                                        lj.s[0], *center, *strength, *core,
                                    ) * da;
                                }
                                Force::Spring {
                                    param, stiffness, ..
                                } => {
                                    if let Some((kernel, d0)) = &kernels[fi] {
                                        let kk = stiffness * kernel.at(&p[..dim], param);
                                        f += (d0 - lj.s[0]) * kk;
                                        coef[0] += ck * qw * kk;
                                    }
                                }
                                _ => {}
                            }
                        }
                        y[0] += f * (fs * qw);
                        gram.add(lj, &coef);
                        lj.apply_transpose_all(&y, &mut w.rhs);
                    }
                    gram.finish();
                    // The products move into the element (the thread's accumulator takes the
                    // element's last buffer); `a` is written only if the step needs it.
                    std::mem::swap(&mut w.products, &mut gram.products);
                    Ok(())
                })
            })
    }

    /// Delta springs, point forces and data springs as extra small "elements".
    fn add_point_forces(
        &self,
        works: &mut Vec<ElementWork>,
        ck: f64,
        fs: f64,
    ) -> Result<(), DynamicsError> {
        let mut lj = LocalJacobian::default();
        for force in &self.forces {
            let (param, spring, pull) = match force {
                Force::Spring {
                    param,
                    target,
                    stiffness,
                    kernel: None,
                } => (*param, *stiffness, Some(target.at(self.time))),
                Force::Point { param, force } => (*param, 0.0, Some(*force)),
                Force::DataPoint { point, stiffness } => (
                    self.geometry.nearest_param(point)?,
                    *stiffness,
                    Some(*point),
                ),
                _ => continue,
            };
            self.geometry.jacobian_at(param, &mut lj)?;
            let dofs = lj.dofs();
            let nd = dofs.len();
            let mut w = ElementWork {
                a: vec![0.0; nd * nd],
                dense: true,
                rhs: vec![0.0; nd],
                dofs,
                shape: (lj.blocks.len(), lj.vectors.len()),
                ..Default::default()
            };
            let f = match force {
                Force::Point { .. } => pull.unwrap_or_default(),
                _ => (pull.unwrap_or_default() - lj.s[0]) * spring,
            };
            if spring > 0.0 {
                let mut c = [0.0; 6];
                c[0] = ck * spring;
                let mut gram = Gram::new(&lj);
                gram.add(&lj, &c);
                gram.write(&mut w.a);
            }
            lj.apply_transpose(0, fs, &f, &mut w.rhs);
            works.push(w);
        }
        Ok(())
    }

    /// The block-Schur solve of this step's system `A x = b` ([`BlockSchur`], module docs of
    /// `generalized/block_schur.rs`), starting from `x`; `works` are the elements (`..ne`) and
    /// the point forces. `None` when the structure does not hold or the iterations do not
    /// reach the tolerance (the caller sums the CSR values and factors the full matrix).
    #[allow(clippy::too_many_arguments)]
    fn schur_solve(
        &mut self,
        settings: BlockSchur,
        pattern: &Arc<CsrPattern>,
        extra_diag: &[f64],
        works: &mut [ElementWork],
        ne: usize,
        b: &[f64],
        x: &mut [f64],
    ) -> Option<(SchurFactor, SolverStats)> {
        if self
            .schur
            .as_ref()
            .is_none_or(|(p, _)| !Arc::ptr_eq(p, pattern))
        {
            // Built and checked once per pattern, on this step's summed values.
            let n = self.geometry.coordinates().len();
            let homogeneous =
                self.geometry.weight_coordinates() == homogeneous_weight_coordinates(n);
            densify(&mut works[..ne]);
            let mut values = pattern.values(&works[..ne]);
            let folded = fold_extras(pattern, &mut values, &works[ne..], &self.fixed);
            let split = folded
                .then(|| {
                    SchurPattern::new(pattern, &self.fixed, homogeneous, &works[..ne], &values)
                })
                .flatten()
                .map(Arc::new);
            self.schur = Some((pattern.clone(), split));
        }
        let split = self.schur.as_ref()?.1.clone()?;
        let f = split.factor(
            works,
            ne,
            &self.fixed,
            extra_diag,
            &mut self.factor_buffers.schur,
        )?;
        let stats = f.solve(b, x, settings.max_iterations, settings.tolerance);
        if stats.relative_residual <= settings.tolerance {
            self.factorizations += 1;
            Some((f, stats))
        } else {
            self.factor_buffers.schur.keep(f);
            None
        }
    }

    /// Sparse Cholesky of this step's matrix (CSR values `full` with the point-force blocks
    /// folded in, plus `extra_diag`) on the free coordinates, reusing the symbolic analysis
    /// (cached per fixed set). `None` (the caller falls back to conjugate gradients) if the
    /// matrix is not positive definite.
    fn factor(&mut self, pattern: &CsrPattern, full: &[f64], extra_diag: &[f64]) -> Option<Factor> {
        if self.direct.as_ref().is_none_or(|d| d.fixed != self.fixed) {
            self.direct = Some(Arc::new(DirectPattern::new(
                pattern,
                &self.fixed,
                self.pre_permute,
            )?));
        }
        let dp = self.direct.clone()?;
        // The buffers of the last step's factor (faer's `Llt::try_new_with_symbolic` allocated
        // and zeroed the factor's 13 MB every step of a 32 x 32 sheet, which the numeric
        // factorization zeroes again itself); the same calls otherwise, so the same values.
        let FactorBuffers {
            matrix,
            factor,
            scratch,
            ..
        } = &mut self.factor_buffers;
        // Pre-permuted (see `Permuted`): the values straight into the order faer factors.
        let (src, col_ptr, row_idx, symbolic) = match &dp.permuted {
            Some(p) => (&p.src, &p.col_ptr, &p.row_idx, &p.symbolic),
            None => (&dp.src, &dp.col_ptr, &dp.row_idx, &dp.symbolic),
        };
        matrix.clear();
        matrix.extend(src.iter().map(|&k| full[k]));
        for (j, &i) in dp.free.iter().enumerate() {
            let at = dp.permuted.as_ref().map_or(dp.col_ptr[j], |p| p.diag[j]);
            matrix[at] += extra_diag[i];
        }
        let m = dp.free.len();
        let sym = faer::sparse::SymbolicSparseColMatRef::new_unsorted_checked(
            m, m, col_ptr, None, row_idx,
        );
        let mat = faer::sparse::SparseColMatRef::new(sym, matrix);
        let mut values = std::mem::take(factor);
        values.resize(symbolic.len_val(), 0.0);
        // Sequential (faer's `rayon` feature is off; explicit, so that a build that turns it
        // on elsewhere keeps these steps' values).
        let par = faer::Par::Seq;
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let buffer = scratch.get(req);
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                mat,
                faer::Side::Lower,
                Default::default(),
                par,
                faer::dyn_stack::MemStack::new(buffer),
                Default::default(),
            )
            .ok()?;
        self.factorizations += 1;
        Some(Factor {
            pattern: dp,
            values,
        })
    }

    /// Lagrange multipliers for the constraints on the linearized step (module docs).
    fn apply_constraints(
        &self,
        op: &Op<'_>,
        pre: &Solve,
        b: &[f64],
        x: &mut [f64],
        gain: f64,
        mut stats: SolverStats,
    ) -> Result<SolverStats, DynamicsError> {
        let n = b.len();
        // Rows restricted to the free coordinates, with their owning constraint.
        let mut rows: Vec<(usize, f64, Vec<f64>)> = Vec::new();
        for (ci, c) in self.constraints.iter().enumerate() {
            for (value, entries) in self.cached_constraint_rows(ci, c)? {
                let mut r = vec![0.0; n];
                for (i, d) in entries {
                    if !self.fixed[i] {
                        r[i] += d;
                    }
                }
                rows.push((ci, value, r));
            }
        }
        let q = self.geometry.coordinates();
        for (t, tie) in self.ties.iter().enumerate() {
            let mut r = vec![0.0; n];
            let mut value = -tie.value;
            for &(i, c) in &tie.terms {
                value += c * q[i];
                if !self.fixed[i] {
                    r[i] += c;
                }
            }
            rows.push((self.constraints.len() + t, value, r));
        }
        // Dependence check (modified Gram-Schmidt in order, carrying the constraint values
        // along). A row that depends on earlier rows is redundant when its value is what those
        // rows already imply (dropped; e.g. the x and y rows of a point constraint at the pole of
        // a swung surface, which both act only through the pole's x coordinate), and
        // contradictory otherwise (an error naming the constraint).
        let consistent = CONSTRAINT_CONSISTENCY * self.geometry.scale();
        let norm = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>().sqrt();
        let biggest = rows.iter().map(|r| norm(&r.2)).fold(0.0, f64::max);
        let mut basis: Vec<(Vec<f64>, f64)> = Vec::new();
        let mut kept = Vec::with_capacity(rows.len());
        for (ci, value, r) in rows {
            let norm0 = norm(&r);
            let mut u = r.clone();
            let mut uv = value;
            for (q, qv) in &basis {
                let d: f64 = u.iter().zip(q).map(|(a, b)| a * b).sum();
                for (ui, qi) in u.iter_mut().zip(q) {
                    *ui -= d * qi;
                }
                uv -= d * qv;
            }
            let nu = norm(&u);
            let dependent = norm0 <= CONSTRAINT_DEPENDENCE_TOLERANCE * biggest
                || nu <= CONSTRAINT_DEPENDENCE_TOLERANCE * norm0;
            if dependent {
                if uv.abs() <= consistent {
                    continue;
                }
                return Err(DynamicsError::Constraint {
                    index: ci,
                    what: if norm0 <= CONSTRAINT_DEPENDENCE_TOLERANCE * biggest {
                        format!(
                            "acts only on fixed coordinates (violation {value:.3e}); free some coordinates near it"
                        )
                    } else {
                        format!(
                            "contradicts earlier constraints (its rows depend on theirs and would need a change of {uv:.3e} they forbid)"
                        )
                    },
                });
            }
            basis.push((u.iter().map(|x| x / nu).collect(), uv / nu));
            kept.push((ci, value, r));
        }
        let rows = kept;
        if rows.is_empty() {
            return Ok(stats);
        }
        let k = rows.len();
        // Y = A^-1 C^T column by column.
        let mut ys = Vec::with_capacity(k);
        for (_, _, r) in &rows {
            let mut y = vec![0.0; n];
            let s = pre.solve(op, r, &mut y, self.max_iterations, self.tolerance);
            stats.iterations += s.iterations;
            stats.relative_residual = stats.relative_residual.max(s.relative_residual);
            ys.push(y);
        }
        let mut s = nalgebra::DMatrix::<f64>::zeros(k, k);
        let mut rhs = nalgebra::DVector::<f64>::zeros(k);
        for i in 0..k {
            for j in 0..k {
                s[(i, j)] = rows[i].2.iter().zip(&ys[j]).map(|(a, b)| a * b).sum();
            }
            let cx: f64 = rows[i].2.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
            // Want C dq = -kappa C(p).
            rhs[i] = cx + gain * rows[i].1;
        }
        let lambda = s
            .clone()
            .cholesky()
            .map(|c| c.solve(&rhs))
            .or_else(|| s.lu().solve(&rhs))
            .ok_or_else(|| DynamicsError::Constraint {
                index: rows[0].0,
                what: "the constraint system is singular".into(),
            })?;
        for j in 0..k {
            for i in 0..n {
                x[i] -= lambda[j] * ys[j][i];
            }
        }
        Ok(stats)
    }
}

/// The step operator `A = sum_e A_e + diag(extra)` on the free coordinates.
struct Op<'a> {
    works: &'a [ElementWork],
    /// The element part of `A` as CSR (pattern, values) covering `works[..first_extra]`.
    csr: Option<(&'a CsrPattern, &'a [f64])>,
    first_extra: usize,
    extra_diag: &'a [f64],
    fixed: &'a [bool],
    n: usize,
}

/// Sparsity pattern of the summed element matrices, with each element entry's position.
#[derive(Debug)]
struct CsrPattern {
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    /// Per element, the index in `cols` of each entry of `a` that is not a structural zero
    /// (see [`ElementWork::shape`]), row by row: a block row `3 b + k` has the `nb` entries
    /// `3 b' + k` and the `nv` vector columns, a vector row all `nd` entries.
    positions: Vec<Vec<u32>>,
    /// The rows cut into one band per thread, each with the element rows that fall into it
    /// (`(element, row of a, start of the row in positions[element])`, elements in order), so
    /// that [`Self::values`] adds a band's rows without scanning the others'.
    bands: Vec<(std::ops::Range<usize>, Vec<[u32; 3]>)>,
    /// The fixed coordinates the element columns were built without.
    fixed: Vec<bool>,
}

impl CsrPattern {
    fn new(n: usize, works: &[ElementWork], fixed: &[bool]) -> Self {
        let mut rows: Vec<Vec<usize>> = vec![vec![]; n];
        for w in works {
            for &i in &w.dofs {
                rows[i].extend_from_slice(&w.dofs);
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        row_ptr.push(0);
        for r in &mut rows {
            r.sort_unstable();
            r.dedup();
            cols.extend_from_slice(r);
            row_ptr.push(cols.len());
        }
        let positions = works
            .iter()
            .map(|w| {
                let nd = w.dofs.len();
                let mut pos = Vec::with_capacity(nd * nd);
                for (a, &i) in w.dofs.iter().enumerate() {
                    let row = &cols[row_ptr[i]..row_ptr[i + 1]];
                    for c in nonzero_columns(w.shape, a) {
                        let j = w.dofs[c];
                        let p = row_ptr[i] + row.binary_search(&j).expect("in pattern");
                        pos.push(u32::try_from(p).expect("fewer than 2^32 entries"));
                    }
                }
                pos
            })
            .collect();
        let nbands = rayon::current_num_threads().clamp(1, 8);
        let mut bands: Vec<(std::ops::Range<usize>, Vec<[u32; 3]>)> = (0..nbands)
            .map(|t| (n * t / nbands..n * (t + 1) / nbands, Vec::new()))
            .collect();
        let index = |x: usize| u32::try_from(x).expect("fewer than 2^32 element rows");
        for (e, w) in works.iter().enumerate() {
            let (nb, nv) = w.shape;
            let nd = w.dofs.len();
            let mut at = 0;
            for (a, &i) in w.dofs.iter().enumerate() {
                if let Some(band) = bands.iter_mut().find(|b| b.0.contains(&i)) {
                    band.1.push([index(e), index(a), index(at)]);
                }
                at += if a < 3 * nb { nb + nv } else { nd };
            }
        }
        Self {
            row_ptr,
            cols,
            positions,
            bands,
            fixed: fixed.to_vec(),
        }
    }

    /// The summed element matrices as CSR values. The rows are cut into bands
    /// ([`Self::bands`]); each band adds the element rows that fall into it, so the bands run
    /// side by side. Every entry receives its elements' terms in element order, whatever the
    /// bands, so the values do not depend on the number of threads.
    fn values(&self, works: &[ElementWork]) -> Vec<f64> {
        let mut v = vec![0.0; self.cols.len()];
        let mut slices = Vec::with_capacity(self.bands.len());
        let mut rest = v.as_mut_slice();
        let mut at = 0;
        for (rows, jobs) in &self.bands {
            let end = self.row_ptr[rows.end];
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(end - at);
            slices.push((jobs, at, head));
            rest = tail;
            at = end;
        }
        // Structural zeros are skipped: adding +0 changes no sum (a sum that starts at +0 is
        // never -0), so the values are those of adding every entry.
        slices.into_par_iter().for_each(|(jobs, base, out)| {
            for &[e, a, at] in jobs {
                let (e, a, at) = (e as usize, a as usize, at as usize);
                let (w, pos) = (&works[e], &self.positions[e]);
                let (nb, nv) = w.shape;
                let nd = w.dofs.len();
                let len = if a < 3 * nb { nb + nv } else { nd };
                let p = &pos[at..at + len];
                let row = &w.a[a * nd..(a + 1) * nd];
                if a < 3 * nb {
                    let k = a % 3;
                    let (pb, pv) = p.split_at(nb);
                    for (&p, b) in pb.iter().zip(0..nb) {
                        out[p as usize - base] += row[3 * b + k];
                    }
                    for (&p, &x) in pv.iter().zip(&row[3 * nb..]) {
                        out[p as usize - base] += x;
                    }
                } else {
                    for (&p, &x) in p.iter().zip(row) {
                        out[p as usize - base] += x;
                    }
                }
            }
        });
        v
    }
}

/// The columns of row `a` of an element matrix of shape `(nb, nv)` that are not structural
/// zeros, in order (see [`CsrPattern::positions`]).
fn nonzero_columns((nb, nv): (usize, usize), a: usize) -> impl Iterator<Item = usize> {
    let nd = 3 * nb + nv;
    let (blocks, k) = if a < 3 * nb { (nb, a % 3) } else { (0, 0) };
    let first = if a < 3 * nb { 3 * nb } else { 0 };
    (0..blocks).map(move |b| 3 * b + k).chain(first..nd)
}

impl Op<'_> {
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        let n = self.n;
        let (pattern, values) = self.csr.expect("assembled operator");
        out.par_chunks_mut(256).enumerate().for_each(|(c, chunk)| {
            for (k, o) in chunk.iter_mut().enumerate() {
                let i = c * 256 + k;
                let mut s = 0.0;
                for p in pattern.row_ptr[i]..pattern.row_ptr[i + 1] {
                    s += values[p] * x[pattern.cols[p]];
                }
                *o = s;
            }
        });
        for w in &self.works[self.first_extra..] {
            let nd = w.dofs.len();
            for a in 0..nd {
                let row = &w.a[a * nd..(a + 1) * nd];
                let mut s = 0.0;
                for (bb, &j) in w.dofs.iter().enumerate() {
                    s += row[bb] * x[j];
                }
                out[w.dofs[a]] += s;
            }
        }
        for i in 0..n {
            out[i] = if self.fixed[i] {
                0.0
            } else {
                out[i] + self.extra_diag[i] * x[i]
            };
        }
    }
}

/// Block-Jacobi preconditioner: the inverse of the diagonal blocks of `A` over the coordinate
/// groups (free coordinates only).
struct Precond {
    groups: Vec<(Vec<usize>, nalgebra::DMatrix<f64>)>,
}

impl Precond {
    fn new(op: &Op<'_>, groups: &[std::ops::Range<usize>]) -> Self {
        let n = op.n;
        let mut gid = vec![(usize::MAX, 0usize); n];
        let mut blocks: Vec<(Vec<usize>, nalgebra::DMatrix<f64>)> = Vec::new();
        for g in groups {
            let free: Vec<usize> = g.clone().filter(|&i| !op.fixed[i]).collect();
            if free.is_empty() {
                continue;
            }
            for (k, &i) in free.iter().enumerate() {
                gid[i] = (blocks.len(), k);
            }
            let m = free.len();
            blocks.push((free, nalgebra::DMatrix::zeros(m, m)));
        }
        for i in 0..n {
            if gid[i].0 == usize::MAX && !op.fixed[i] {
                gid[i] = (blocks.len(), 0);
                blocks.push((vec![i], nalgebra::DMatrix::zeros(1, 1)));
            }
        }
        for w in op.works {
            let nd = w.dofs.len();
            for (a, &i) in w.dofs.iter().enumerate() {
                let (gi, ki) = gid[i];
                if gi == usize::MAX {
                    continue;
                }
                for (bb, &j) in w.dofs.iter().enumerate() {
                    let (gj, kj) = gid[j];
                    if gj == gi {
                        blocks[gi].1[(ki, kj)] += w.a[a * nd + bb];
                    }
                }
            }
        }
        for i in 0..n {
            let (g, k) = gid[i];
            if g != usize::MAX {
                blocks[g].1[(k, k)] += op.extra_diag[i];
            }
        }
        let groups = blocks
            .into_iter()
            .map(|(idx, m)| {
                let inv = m
                    .clone()
                    .cholesky()
                    .map(|c| c.inverse())
                    .unwrap_or_else(|| {
                        nalgebra::DMatrix::from_diagonal(
                            &m.diagonal().map(|d| if d > 0.0 { 1.0 / d } else { 0.0 }),
                        )
                    });
                (idx, inv)
            })
            .collect();
        Self { groups }
    }

    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for (idx, inv) in &self.groups {
            for (a, &i) in idx.iter().enumerate() {
                let mut s = 0.0;
                for (bb, &j) in idx.iter().enumerate() {
                    s += inv[(a, bb)] * r[j];
                }
                z[i] = s;
            }
        }
    }
}

/// Adds the point-force blocks `extras` into the CSR values when every entry between free
/// coordinates lies in the pattern (they do: a point's Jacobian columns are those of its
/// element; entries of fixed coordinates are never used and are skipped); returns whether it
/// did (if not, nothing is changed).
fn fold_extras(
    pattern: &CsrPattern,
    values: &mut [f64],
    extras: &[ElementWork],
    fixed: &[bool],
) -> bool {
    let mut at = Vec::new();
    for w in extras {
        for &i in &w.dofs {
            let row = &pattern.cols[pattern.row_ptr[i]..pattern.row_ptr[i + 1]];
            for &j in &w.dofs {
                if fixed[i] || fixed[j] {
                    at.push(None);
                    continue;
                }
                match row.binary_search(&j) {
                    Ok(k) => at.push(Some(pattern.row_ptr[i] + k)),
                    Err(_) => return false,
                }
            }
        }
    }
    let mut at = at.into_iter();
    for w in extras {
        for &a in &w.a {
            if let Some(p) = at.next().expect("one position per entry") {
                values[p] += a;
            }
        }
    }
    true
}

/// The free-coordinate block of the element pattern as a lower-triangular CSC matrix, with
/// its symbolic Cholesky analysis (fill-reducing ordering, elimination tree), computed once per
/// set of fixed coordinates.
#[derive(Debug)]
struct DirectPattern {
    /// The fixed mask it was built for.
    fixed: Vec<bool>,
    /// Free coordinates in order (column `j` is coordinate `free[j]`).
    free: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// For each stored entry, its index in the CSR values of [`CsrPattern`].
    src: Vec<usize>,
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    /// The matrix laid out as faer's numeric factorization permutes it every step, built once
    /// (`None`: the factorization permutes, as with a simplicial factor).
    permuted: Option<Permuted>,
}

/// The lower triangle of a step matrix in the fill-reducing order of a supernodal
/// [`DirectPattern::symbolic`], laid out entry for entry as faer's
/// `permute_self_adjoint_to_unsorted` writes it at the start of every numeric factorization
/// (the same call, made once on entry indices), and a symbolic factorization of that layout
/// in the identity order. Factoring the permuted values with it skips faer's per-step
/// permutation of `A` (3 % of a 32 x 32 dynamic-weight step, on the step's serial part) and
/// gives the same factor to the last bit: the same permuted matrix enters the same supernodal
/// structure (checked at construction: the same number of factor values, both supernodal),
/// and the solves' permutations are copies.
#[derive(Debug)]
struct Permuted {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// For each permuted entry, its index in the CSR values of [`CsrPattern`].
    src: Vec<usize>,
    /// For each free coordinate `j` (in [`DirectPattern::free`] order), the permuted entry of
    /// its diagonal.
    diag: Vec<usize>,
    /// The coordinate of each permuted row: `free[fwd[i]]`.
    order: Vec<usize>,
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
}

impl Permuted {
    /// The layout of `symbolic`'s permutation applied to the lower triangle `(col_ptr,
    /// row_idx)` with CSR sources `src`; `None` unless `symbolic` is supernodal with a
    /// permutation and the identity-order analysis of the permuted pattern matches it.
    fn new(
        free: &[usize],
        col_ptr: &[usize],
        row_idx: &[usize],
        src: &[usize],
        symbolic: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    ) -> Option<Self> {
        use faer::sparse::linalg::cholesky::{
            CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
            factorize_symbolic_cholesky,
        };
        if !matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
            return None;
        }
        let perm = symbolic.perm()?;
        let m = free.len();
        let nnz = row_idx.len();
        // Entry indices as values (exact in f64 below 2^53): the permuted values say where
        // each permuted entry came from.
        let index: Vec<f64> = (0..nnz).map(|k| k as f64).collect();
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, col_ptr, None, row_idx);
        let a = faer::sparse::SparseColMatRef::new(sym, &index);
        let permute = |out_side: faer::Side| {
            let (mut val, mut cp, mut ri) =
                (vec![0.0; nnz], vec![0usize; m + 1], vec![0usize; nnz]);
            let mut mem = faer::dyn_stack::MemBuffer::new(
                faer::sparse::utils::permute_self_adjoint_scratch::<usize>(m),
            );
            faer::sparse::utils::permute_self_adjoint_to_unsorted(
                &mut val,
                &mut cp,
                &mut ri,
                a,
                perm,
                faer::Side::Lower,
                out_side,
                faer::dyn_stack::MemStack::new(&mut mem),
            );
            (val, cp, ri)
        };
        // What the numeric factorization builds (supernodal: the lower side) ...
        let (val, pcol_ptr, prow_idx) = permute(faer::Side::Lower);
        // ... and what the symbolic analysis analysed (the upper side).
        let (_, ucol_ptr, urow_idx) = permute(faer::Side::Upper);
        let usym = faer::sparse::SymbolicSparseColMatRef::new_unsorted_checked(
            m, m, &ucol_ptr, None, &urow_idx,
        );
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold:
                faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let identity = factorize_symbolic_cholesky(
            usym,
            faer::Side::Upper,
            SymmetricOrdering::Identity,
            params,
        )
        .ok()?;
        if identity.len_val() != symbolic.len_val() {
            return None;
        }
        let from: Vec<usize> = val.iter().map(|&v| v as usize).collect();
        let mut diag = vec![usize::MAX; m];
        for (k, &f) in from.iter().enumerate() {
            // The diagonal of column j is its first stored entry (`DirectPattern::new`).
            if let Ok(j) = col_ptr[..m].binary_search(&f) {
                diag[j] = k;
            }
        }
        if diag.contains(&usize::MAX) {
            return None;
        }
        let fwd = perm.arrays().0;
        Some(Self {
            col_ptr: pcol_ptr,
            row_idx: prow_idx,
            src: from.iter().map(|&f| src[f]).collect(),
            diag,
            order: fwd.iter().map(|&i| free[i]).collect(),
            symbolic: identity,
        })
    }
}

impl DirectPattern {
    /// The free coordinates' lower triangle of `pattern` and its symbolic factorization; with
    /// `pre_permute`, also its [`Permuted`] layout where one applies.
    fn new(pattern: &CsrPattern, fixed: &[bool], pre_permute: bool) -> Option<Self> {
        let n = fixed.len();
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        let mut pos = vec![usize::MAX; n];
        for (k, &i) in free.iter().enumerate() {
            pos[i] = k;
        }
        // The pattern is symmetric: column j's lower part is row j's entries at columns >= j.
        let (mut col_ptr, mut row_idx, mut src) = (vec![0], Vec::new(), Vec::new());
        for &i in &free {
            for p in pattern.row_ptr[i]..pattern.row_ptr[i + 1] {
                let c = pattern.cols[p];
                if pos[c] != usize::MAX && pos[c] >= pos[i] {
                    row_idx.push(pos[c]);
                    src.push(p);
                }
            }
            col_ptr.push(row_idx.len());
        }
        // Every free coordinate's diagonal is in the pattern (it lies in some element), and it
        // comes first in its column (rows sorted, all >= the column).
        if (0..free.len()).any(|j| col_ptr[j] == col_ptr[j + 1] || row_idx[col_ptr[j]] != j) {
            return None;
        }
        let m = free.len();
        let sym =
            faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
        // What `SymbolicLlt::try_new` computes (approximate minimum degree ordering, default
        // parameters), kept unwrapped for the numeric calls with reused buffers.
        let symbolic = faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(
            sym,
            faer::Side::Lower,
            Default::default(),
            Default::default(),
        )
        .ok()?;
        let permuted = if pre_permute {
            Permuted::new(&free, &col_ptr, &row_idx, &src, &symbolic)
        } else {
            None
        };
        Some(Self {
            fixed: fixed.to_vec(),
            free,
            col_ptr,
            row_idx,
            src,
            symbolic,
            permuted,
        })
    }
}

/// A numeric Cholesky factorization of one step's matrix: the values of the factor of
/// [`DirectPattern::symbolic`].
struct Factor {
    pattern: Arc<DirectPattern>,
    values: Vec<f64>,
}

/// The direct solver's buffers, kept between steps: the lower triangle of the step matrix on
/// the free coordinates, the factor's values and faer's scratch memory. A clone starts empty.
#[derive(Default)]
struct FactorBuffers {
    matrix: Vec<f64>,
    factor: Vec<f64>,
    scratch: Scratch,
    /// The last factorization, kept for [`GeneralizedDnurbs::factor_reuse`].
    lagged: Option<Factor>,
    /// The block-Schur solve's buffers ([`GeneralizedDnurbs::block_schur`]).
    schur: SchurBuffers,
}

impl FactorBuffers {
    /// Takes back a step's factor: as the preconditioner of the next steps (`reuse`) or as the
    /// buffer of the next factorization.
    fn keep(&mut self, solve: Solve, reuse: bool) {
        match solve {
            Solve::Direct(f) | Solve::Reused(f) if reuse => self.lagged = Some(f),
            Solve::Direct(f) | Solve::Reused(f) => self.factor = f.values,
            Solve::Schur(f, _) => self.schur.keep(f),
            Solve::Pcg(_) => {}
        }
    }
}

impl Clone for FactorBuffers {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for FactorBuffers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FactorBuffers")
            .field("matrix", &self.matrix.len())
            .field("factor", &self.factor.len())
            .finish_non_exhaustive()
    }
}

/// faer scratch memory, reallocated only when a larger request comes.
#[derive(Default)]
struct Scratch(Option<(faer::dyn_stack::StackReq, faer::dyn_stack::MemBuffer)>);

impl Scratch {
    /// A buffer that satisfies `req`.
    fn get(&mut self, req: faer::dyn_stack::StackReq) -> &mut faer::dyn_stack::MemBuffer {
        if self
            .0
            .as_ref()
            .is_none_or(|(have, _)| have.or(req) != *have)
        {
            self.0 = Some((req, faer::dyn_stack::MemBuffer::new(req)));
        }
        &mut self.0.as_mut().expect("just set").1
    }
}

/// How a step's systems `A x = b` are solved.
enum Solve {
    /// Block-Jacobi-preconditioned conjugate gradients.
    Pcg(Precond),
    /// The step's sparse Cholesky factorization.
    Direct(Factor),
    /// Conjugate gradients preconditioned with an earlier step's factorization
    /// ([`FactorReuse`]).
    Reused(Factor),
    /// The block split's factors, conjugate gradients on the Schur complement with the
    /// block-Schur settings' cap and tolerance ([`BlockSchur`]).
    Schur(SchurFactor, BlockSchur),
}

/// A preconditioner `z = M^-1 r` on the free coordinates (fixed entries of `z` untouched).
trait Preconditioner {
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

impl Preconditioner for Precond {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        Precond::apply(self, r, z);
    }
}

impl Preconditioner for Factor {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.solve_into(r, z);
    }
}

impl Factor {
    /// `x = (L L^T)^-1 b` on the free coordinates; fixed entries of `x` become 0.
    fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        // Pre-permuted: the right-hand side in the factor's order (the copies faer's solve
        // makes with its permutation).
        let (free, symbolic) = match &self.pattern.permuted {
            Some(p) => (&p.order, &p.symbolic),
            None => (&self.pattern.free, &self.pattern.symbolic),
        };
        let mut rhs = faer::Mat::<f64>::zeros(free.len(), 1);
        for (k, &i) in free.iter().enumerate() {
            rhs[(k, 0)] = b[i];
        }
        // As `Llt::solve_in_place` does it, sequentially (see `factor`).
        let par = faer::Par::Seq;
        faer::sparse::linalg::cholesky::LltRef::<'_, usize, f64>::new(symbolic, &self.values)
            .solve_in_place_with_conj(
                faer::Conj::No,
                rhs.as_mut(),
                par,
                faer::dyn_stack::MemStack::new(&mut faer::dyn_stack::MemBuffer::new(
                    symbolic.solve_in_place_scratch::<f64>(1, par),
                )),
            );
        x.iter_mut().for_each(|v| *v = 0.0);
        for (k, &i) in free.iter().enumerate() {
            x[i] = rhs[(k, 0)];
        }
    }
}

impl Solve {
    /// Solves `A x = b` on the free coordinates (fixed entries of `x` become 0). For the
    /// direct solver the reported residual is the true one (one product with `A`).
    fn solve(&self, op: &Op<'_>, b: &[f64], x: &mut [f64], max_it: usize, tol: f64) -> SolverStats {
        match self {
            Solve::Pcg(pre) => pcg(op, pre, b, x, max_it, tol),
            // The old factor's own cap and tolerance: the step's systems after the first
            // (constraint rows, projections) are solved like the first.
            Solve::Reused(f) => pcg(op, f, b, x, max_it, tol),
            Solve::Direct(f) => {
                f.solve_into(b, x);
                SolverStats {
                    iterations: 0,
                    relative_residual: relative_residual(op, b, x),
                }
            }
            Solve::Schur(f, settings) => f.solve(b, x, settings.max_iterations, settings.tolerance),
        }
    }
}

/// `|b - A x| / |b|` over the free coordinates (`|b - A x|` when `b` vanishes there): one
/// product with `A`.
fn relative_residual(op: &Op<'_>, b: &[f64], x: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    op.apply(x, &mut ax);
    let (mut rn, mut bn) = (0.0, 0.0);
    for i in (0..b.len()).filter(|&i| !op.fixed[i]) {
        rn += (b[i] - ax[i]).powi(2);
        bn += b[i] * b[i];
    }
    if bn > 0.0 {
        (rn / bn).sqrt()
    } else {
        rn.sqrt()
    }
}

/// Block-Jacobi-preconditioned CG on the free coordinates (fixed entries of `x` stay 0).
fn pcg(
    op: &Op<'_>,
    pre: &impl Preconditioner,
    b: &[f64],
    x: &mut [f64],
    max_it: usize,
    tol: f64,
) -> SolverStats {
    let n = b.len();
    for i in 0..n {
        if op.fixed[i] {
            x[i] = 0.0;
        }
    }
    let mut ax = vec![0.0; n];
    op.apply(x, &mut ax);
    let mut r: Vec<f64> = (0..n)
        .map(|i| if op.fixed[i] { 0.0 } else { b[i] - ax[i] })
        .collect();
    let bnorm = (0..n)
        .filter(|&i| !op.fixed[i])
        .map(|i| b[i] * b[i])
        .sum::<f64>()
        .sqrt();
    let rel = |r: &[f64]| {
        let rn = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        if bnorm > 0.0 { rn / bnorm } else { rn }
    };
    let mut z = vec![0.0; n];
    pre.apply(&r, &mut z);
    let mut p = z.clone();
    let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
    let mut ap = vec![0.0; n];
    let mut stats = SolverStats {
        iterations: 0,
        relative_residual: rel(&r),
    };
    while stats.iterations < max_it && stats.relative_residual > tol {
        op.apply(&p, &mut ap);
        let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        pre.apply(&r, &mut z);
        let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
        stats.iterations += 1;
        stats.relative_residual = rel(&r);
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Jacobian with `nb` block and `nv` general columns filled with varied values.
    fn jacobian(nb: usize, nv: usize, seed: f64) -> LocalJacobian {
        let val = |i: usize| ((i as f64 + seed) * 0.7548776662).sin();
        LocalJacobian {
            blocks: (0..nb)
                .map(|a| (3 * a, std::array::from_fn(|m| val(6 * a + m))))
                .collect(),
            vectors: (0..nv)
                .map(|j| {
                    let g = std::array::from_fn(|m| {
                        let i = 100 + 18 * j + 3 * m;
                        Vec3::new(val(i), val(i + 1), val(i + 2))
                    });
                    (3 * nb + j, g)
                })
                .collect(),
            ..Default::default()
        }
    }

    /// `J^m` as a dense `3 x nd` matrix (row-major).
    fn dense(lj: &LocalJacobian, m: usize) -> Vec<f64> {
        let (nb, nv) = (lj.blocks.len(), lj.vectors.len());
        let nd = 3 * nb + nv;
        let mut j = vec![0.0; 3 * nd];
        for (a, (_, r)) in lj.blocks.iter().enumerate() {
            for k in 0..3 {
                j[k * nd + 3 * a + k] = r[m];
            }
        }
        for (c, (_, g)) in lj.vectors.iter().enumerate() {
            for k in 0..3 {
                j[k * nd + 3 * nb + c] = g[m][k];
            }
        }
        j
    }

    #[test]
    fn gram_products_match_the_sum_of_jacobian_outer_products() {
        // Sizes past one 4 x 8 tile, with remainders, so that the symmetric skip and mirror
        // and the partial tiles all run; and the small shapes of cells with fixed columns.
        for (nb, nv) in [(13, 21), (5, 3), (1, 1), (0, 2), (3, 0), (4, 8)] {
            gram_matches(nb, nv);
        }
    }

    fn gram_matches(nb: usize, nv: usize) {
        let nd = 3 * nb + nv;
        let mut gram = Gram::default();
        let mut expected = vec![0.0; nd * nd];
        gram.reset(&jacobian(nb, nv, 0.0));
        for point in 0..3 {
            let lj = jacobian(nb, nv, point as f64 * 1.3);
            // Zero coefficients are skipped; a negative one must still count.
            let coef = [0.5, 0.0, 2.0, -0.25, 1.0, 0.0].map(|c| c * (1.0 + point as f64));
            gram.add(&lj, &coef);
            for (m, &c) in coef.iter().enumerate() {
                let j = dense(&lj, m);
                for r in 0..nd {
                    for s in 0..nd {
                        for k in 0..3 {
                            expected[r * nd + s] += c * j[k * nd + r] * j[k * nd + s];
                        }
                    }
                }
            }
        }
        // `write` sets every entry, whatever was there.
        let mut out = vec![f64::NAN; nd * nd];
        gram.write(&mut out);
        for (k, (a, b)) in out.iter().zip(&expected).enumerate() {
            assert!(
                (a - b).abs() < 1e-12,
                "entry ({}, {}): {a} != {b}",
                k / nd,
                k % nd
            );
        }
        // Reset forgets the previous rows.
        gram.reset(&jacobian(nb, nv, 0.0));
        gram.write(&mut out);
        assert!(out.iter().all(|&x| x == 0.0));
    }

    /// Dropping the fixed coordinates' columns from the element products (and computing only
    /// the order-0 columns of fixed controls) changes no step: the corner rounding (50 of 78
    /// control points fixed, 9 sliding, one more held with its weight free, triangular cells, normal
    /// constraints) and a rational sheet with a fixed edge, a fixed weight, a fixed point with
    /// a free weight, and point forces.
    #[test]
    fn dropping_fixed_columns_changes_no_step() {
        use crate::dnurbs::rounding::{RoundingKind, RoundingModel};
        use crate::dnurbs::{Integrator, TriangleQuadrature};
        fn compare<G: GeneralizedGeometry>(mut a: GeneralizedDnurbs<G>, dt: f64, steps: usize) {
            let mut b = a.clone();
            b.keep_fixed_columns = true;
            for _ in 0..steps {
                let ra = a.step(Integrator::Implicit { dt }).unwrap();
                let rb = b.step(Integrator::Implicit { dt }).unwrap();
                let de = (ra.elastic_energy - rb.elastic_energy).abs();
                assert!(
                    de <= 1e-9 * rb.elastic_energy.abs().max(1e-12),
                    "energy {de:.2e}"
                );
                let dk = (ra.kinetic_energy - rb.kinetic_energy).abs();
                assert!(
                    dk <= 1e-9 * rb.kinetic_energy.abs().max(1e-12),
                    "kinetic {dk:.2e}"
                );
            }
            let scale = a.geometry().scale();
            let worst = a
                .geometry()
                .coordinates()
                .iter()
                .zip(b.geometry().coordinates())
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 1e-10 * scale, "coordinates differ by {worst:.2e}");
            // The shape moved (the comparison is not of two still models).
            let start = b.state();
            assert!(
                b.velocity().iter().any(|v| v.abs() > 1e-8 * scale),
                "{:?}",
                start.time
            );
        }
        let r = RoundingModel::new(RoundingKind::Corner).unwrap();
        let mut corner = r.dynamics(TriangleQuadrature::default()).unwrap();
        // One more control point held in place, its weight left free.
        let c = (0..r.surface.control_points().len())
            .rev()
            .find(|c| !r.fixed_controls.contains(c) && !corner.is_fixed_coordinate(4 * c + 3))
            .unwrap();
        for k in 0..3 {
            corner.set_fixed_coordinate(4 * c + k, true).unwrap();
        }
        compare(corner, r.dt(), 3);

        let (n, m) = (5, 4);
        let pts = (0..n * m)
            .map(|k| Vec3::new((k / m) as f64, (k % m) as f64, 0.1 * (k as f64).sin()))
            .collect();
        let mut sheet = vclay_spline::NurbsSurface::clamped_uniform([2, 2], [n, m], pts).unwrap();
        sheet
            .set_weights(
                (0..n * m)
                    .map(|k| 1.0 + 0.3 * (k as f64 * 0.9).cos())
                    .collect(),
            )
            .unwrap();
        let g = super::super::RationalGeometry::from_surface(&sheet);
        let mut m =
            GeneralizedDnurbs::new(g, super::super::Material::surface(1.0, 2.0, 0.5, 0.1)).unwrap();
        for i in 0..4 {
            // The first row of control points and one weight.
            for k in 0..4 {
                m.set_fixed_coordinate(4 * i + k, true).unwrap();
            }
        }
        m.set_fixed_coordinate(4 * 9 + 3, true).unwrap();
        // A control point held in place whose weight stays free.
        for k in 0..3 {
            m.set_fixed_coordinate(4 * 12 + k, true).unwrap();
        }
        m.forces_mut().extend([
            Force::Gravity(Vec3::new(0.0, 0.0, -1.0)),
            Force::Point {
                param: [0.0, 0.5],
                force: Vec3::new(0.0, 0.0, 2.0),
            },
            Force::Spring {
                param: [0.6, 0.4],
                target: super::super::Target::Fixed(Vec3::new(2.0, 2.0, 1.0)),
                stiffness: 5.0,
                kernel: None,
            },
        ]);
        compare(m, 0.05, 4);
    }

    /// The direct solver's pre-permuted factorization ([`Permuted`], issue 31) gives the
    /// steps of faer's own per-step permutation bit for bit: coordinates, velocities and the
    /// reported residuals, on the benchmark sheets (supernodal factors: the pre-permuted path
    /// is taken), with a reused factorization, and on the corner rounding model (constraints
    /// and ties: several solves per step).
    #[test]
    fn pre_permuted_factorization_equals_faer_permutation_bit_for_bit() {
        use crate::dnurbs::rounding::{RoundingKind, RoundingModel};
        use crate::dnurbs::{Integrator, TriangleQuadrature, benchmarks};
        fn compare<G: GeneralizedGeometry>(
            mut a: GeneralizedDnurbs<G>,
            dt: f64,
            steps: usize,
            supernodal: bool,
        ) {
            let mut b = a.clone();
            b.pre_permute = false;
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            for _ in 0..steps {
                let ra = a.step(Integrator::Implicit { dt }).unwrap();
                let rb = b.step(Integrator::Implicit { dt }).unwrap();
                assert_eq!(
                    ra.solver.relative_residual.to_bits(),
                    rb.solver.relative_residual.to_bits()
                );
                assert_eq!(
                    bits(a.geometry().coordinates()),
                    bits(b.geometry().coordinates())
                );
                assert_eq!(bits(a.velocity()), bits(b.velocity()));
            }
            assert_eq!(a.factorizations(), b.factorizations());
            let permuted = a.direct.as_ref().is_some_and(|d| d.permuted.is_some());
            assert_eq!(permuted, supernodal);
            assert!(b.direct.as_ref().is_some_and(|d| d.permuted.is_none()));
        }
        compare(
            benchmarks::dynamic_sheet(16).unwrap(),
            benchmarks::DT,
            3,
            true,
        );
        let mut reuse = benchmarks::uniform_dynamic_sheet(14).unwrap();
        reuse.factor_reuse = Some(FactorReuse::default());
        compare(reuse, benchmarks::DT, 4, true);
        let r = RoundingModel::new(RoundingKind::Corner).unwrap();
        let corner = r.dynamics(TriangleQuadrature::default()).unwrap();
        let supernodal = {
            let mut c = corner.clone();
            c.step(Integrator::Implicit { dt: r.dt() }).unwrap();
            c.direct.as_ref().is_some_and(|d| {
                matches!(
                    d.symbolic.raw(),
                    faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(_)
                )
            })
        };
        compare(corner, r.dt(), 3, supernodal);
    }

    /// The rows of constraints on fixed coordinates are reused only while those coordinates
    /// stay fixed and unchanged: moving the held control points (a restored state) or freeing
    /// them gives fresh rows.
    #[test]
    fn cached_constraint_rows_follow_the_held_coordinates() {
        use crate::dnurbs::TriangleQuadrature;
        use crate::dnurbs::rounding::{RoundingKind, RoundingModel};
        let r = RoundingModel::new(RoundingKind::Corner).unwrap();
        let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
        let worst = |m: &GeneralizedDnurbs<_>| {
            m.constraint_violations()
                .unwrap()
                .into_iter()
                .fold(0.0, f64::max)
        };
        let scale = m.geometry().scale();
        assert!(worst(&m) < 1e-9 * scale);
        // The far-boundary constraints act on held coordinates (most only on them:
        // those are cached).
        let cached =
            |m: &GeneralizedDnurbs<_>| m.row_cache.lock().iter().filter(|e| e.is_some()).count();
        assert!(
            cached(&m) >= r.constraints.len() / 2,
            "{} cached",
            cached(&m)
        );
        // Shear the held points (z += 0.3 x): the normals at the constraints turn.
        let mut st = m.state();
        for &c in &r.fixed_controls {
            st.coordinates[4 * c + 2] += 0.3 * st.coordinates[4 * c];
        }
        m.set_state(&st).unwrap();
        let moved = worst(&m);
        assert!(
            moved > 1e-3,
            "violation after moving the held points: {moved}"
        );
        // The same value from a model that never cached anything.
        let mut fresh = r.dynamics(TriangleQuadrature::default()).unwrap();
        fresh.set_state(&st).unwrap();
        assert_eq!(worst(&fresh), moved);
        // Freed points: nothing is cached for constraints on them.
        for &c in &r.fixed_controls {
            for k in 0..4 {
                m.set_fixed_coordinate(4 * c + k, false).unwrap();
            }
        }
        assert_eq!(worst(&m), moved);
        assert_eq!(cached(&m), 0);
    }

    impl Gram {
        /// The row-by-row `add` this one replaced (the reference it must equal).
        fn add_reference(&mut self, lj: &LocalJacobian, coef: &[f64; 6]) {
            let (nb, nv) = (self.nb, self.nv);
            debug_assert_eq!((lj.blocks.len(), lj.vectors.len()), (nb, nv));
            for (m, &c) in coef.iter().enumerate() {
                if c == 0.0 {
                    continue;
                }
                self.x.extend(lj.blocks.iter().map(|(_, r)| r[m]));
                for k in 0..3 {
                    self.x.extend(lj.vectors.iter().map(|(_, g)| g[m][k]));
                }
                self.x.extend([0.0; GEMM_PAD]);
                self.c.push(c);
            }
        }
    }

    /// [`gemm_tn`] as it was with a stored `R = C L` (the reference the in-register `C L`
    /// must equal bit for bit).
    #[allow(clippy::too_many_arguments)]
    fn gemm_tn_stored(
        l: &[f64],
        r: &[f64],
        ld: usize,
        lc: std::ops::Range<usize>,
        rc: std::ops::Range<usize>,
        out: &mut [f64],
        ldo: usize,
        sym: bool,
    ) {
        const TA: usize = 4;
        const TJ: usize = 8;
        let rows = l.len() / ld;
        let (m, n) = (lc.len(), rc.len());
        let below = |a0: usize, j0: usize| sym && j0 + TJ <= a0;
        for a0 in (0..m).step_by(TA) {
            for j0 in (0..n).step_by(TJ) {
                if below(a0, j0) {
                    continue;
                }
                let (lo, ro) = (lc.start + a0, rc.start + j0);
                let mut acc = [[0.0; TJ]; TA];
                for row in 0..rows {
                    for a in 0..TA {
                        for jj in 0..TJ {
                            acc[a][jj] += l[row * ld + lo + a] * r[row * ld + ro + jj];
                        }
                    }
                }
                for a in 0..TA.min(m - a0) {
                    for jj in 0..TJ.min(n - j0) {
                        out[(a0 + a) * ldo + j0 + jj] += acc[a][jj];
                    }
                }
            }
        }
        if sym {
            for a in 0..m {
                for j in 0..a.min(n) {
                    if below(a - a % TA, j - j % TJ) {
                        out[a * ldo + j] = out[j * ldo + a];
                    }
                }
            }
        }
    }

    /// `Gram::finish` with `C L` formed in registers equals the products of a stored `C L`
    /// (issue 31: the step's values unchanged), bit for bit, for bicubic and odd shapes and
    /// patterns of zero coefficients.
    #[test]
    fn in_register_scaled_rows_equal_stored_scaled_rows() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (nb, nv) in [(16, 16), (9, 9), (3, 5), (0, 4), (7, 0), (13, 2)] {
            for mask in [0b111111u32, 0b000001, 0b101010] {
                let mut g = Gram::default();
                g.reset_shape((nb, nv));
                for p in 0..5 {
                    let lj = jacobian(nb, nv, 0.3 + 0.17 * p as f64);
                    let coef: [f64; 6] = std::array::from_fn(|m| {
                        if mask >> m & 1 == 1 {
                            0.37 * (p + 1) as f64 - 0.21 * m as f64
                        } else {
                            0.0
                        }
                    });
                    g.add(&lj, &coef);
                }
                let (ld, nc) = (g.ld(), g.nc());
                let rows = g.x.len() / ld;
                let cx: Vec<f64> = (0..rows * ld).map(|k| g.c[k / ld] * g.x[k]).collect();
                let (mut bbv, mut vv) = (vec![0.0; nb * nc], vec![0.0; nv * nv]);
                if rows > 0 && nc > 0 {
                    gemm_tn_stored(&g.x, &cx, ld, 0..nb, 0..nb, &mut bbv, nc, true);
                    gemm_tn_stored(&g.x, &cx, ld, 0..nb, nb..nc, &mut bbv[nb..], nc, false);
                    for k in 0..3 {
                        let cols = nb + k * nv..nb + (k + 1) * nv;
                        gemm_tn_stored(&g.x, &cx, ld, cols.clone(), cols, &mut vv, nv, true);
                    }
                }
                g.finish();
                let (gb, gv) = g.products.split_at(nb * nc);
                assert_eq!(bits(gb), bits(&bbv), "{nb} x {nv}, {mask:b}");
                assert_eq!(bits(gv), bits(&vv), "{nb} x {nv}, {mask:b}");
            }
        }
    }

    /// `Gram::add` stores the rows of the row-by-row version, bit for bit, for every pattern of
    /// zero coefficients.
    #[test]
    fn column_wise_rows_equal_row_wise_rows() {
        for (nb, nv) in [(16, 16), (3, 5), (0, 4), (7, 0)] {
            let lj = jacobian(nb, nv, 0.3);
            for mask in [0b111111u32, 0b000001, 0b101010, 0b011110, 0] {
                let coef: [f64; 6] = std::array::from_fn(|m| {
                    if mask >> m & 1 == 1 {
                        0.5 - m as f64
                    } else {
                        0.0
                    }
                });
                let (mut a, mut b) = (Gram::new(&lj), Gram::new(&lj));
                for _ in 0..3 {
                    a.add(&lj, &coef);
                    b.add_reference(&lj, &coef);
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a.x), bits(&b.x));
                assert_eq!(bits(&a.c), bits(&b.c));
            }
        }
    }

    /// Measurement (run with `--ignored --nocapture`, release): `Gram::add` against the
    /// row-by-row reference on a bicubic element's point, alternated in the same process.
    #[test]
    #[ignore]
    fn gram_add_timing() {
        let lj = jacobian(16, 16, 0.3);
        let coef = [1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125];
        let mut g = Gram::new(&lj);
        let reps = 100_000;
        for round in 0..6 {
            for reference in [false, true] {
                let t = std::time::Instant::now();
                for r in 0..reps {
                    if r % 50 == 0 {
                        g.reset(&lj);
                    }
                    if reference {
                        g.add_reference(std::hint::black_box(&lj), &coef);
                    } else {
                        g.add(std::hint::black_box(&lj), &coef);
                    }
                }
                let ns = t.elapsed().as_secs_f64() * 1e9 / reps as f64;
                eprintln!("round {round} reference {reference}: {ns:.0} ns per point");
            }
        }
    }

    /// A seeded xorshift stream in `[0, 1)` (the tests' randomness).
    fn uniform_stream(mut x: u64) -> impl FnMut() -> f64 {
        move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The closed-form zeros give the order the companion eigenvalues give, slice by slice, over
    /// random cubic and quadratic denominators whose spreads cover every order (uniform weights
    /// up to a factor 20, near-double zeros included), and the fast path is taken almost always.
    #[test]
    fn closed_form_orders_equal_eigenvalue_orders() {
        let mut rnd = uniform_stream(0x9e37_79b9_7f4a_7c15);
        let (mut fast, mut total) = (0usize, 0usize);
        for tolerance in [1e-4, 1e-8, 1e-12] {
            let rule = QuadratureRule::WeightAware { tolerance };
            for degree in [2usize, 3] {
                let nodes = chebyshev_nodes(degree + 1);
                for k in 0..4000 {
                    // Spread 10^(-7..1.3) around 1; every 7th slice a square (double zero).
                    let eps = 10f64.powf(-7.0 + 8.3 * rnd());
                    let values: Vec<f64> = if k % 7 == 0 {
                        let z0 = 1.0 + 3.0 * rnd() / eps.sqrt();
                        nodes.iter().map(|t| (t - z0) * (t - z0)).collect()
                    } else {
                        (0..=degree).map(|_| 1.0 + eps * rnd()).collect()
                    };
                    let (r, spread) = denominator_radius(&values, &nodes);
                    let exact = rule.order(degree, r, spread);
                    assert_eq!(
                        slice_order(rule, degree, &values, &nodes),
                        exact,
                        "{values:?}"
                    );
                    total += 1;
                    if let Some((rf, sf)) = closed_form_radius(&values, &nodes) {
                        assert_eq!(sf.to_bits(), spread.to_bits());
                        assert!(
                            (rf - r).abs() <= 1e-6 * r || (rf.is_infinite() && r.is_infinite()),
                            "{rf} against {r} for {values:?}"
                        );
                        fast += 1;
                    }
                }
            }
        }
        assert!(
            fast * 100 >= total * 99,
            "fast path taken {fast} of {total}"
        );
    }

    /// The algebraic ellipse radius of [`closed_form_radius`] agrees with the polar-form one
    /// (`hypot`, `atan2`, `sin`, `cos`) to a few units in the last place, far inside
    /// [`FAST_RADIUS_MARGIN`]: real zeros inside and outside `[-1, 1]`, complex ones near and
    /// far, both half planes.
    #[test]
    fn algebraic_ellipse_radius_equals_the_polar_form() {
        use nalgebra::Complex;
        let polar = |z: Complex<f64>| {
            let w = (z * z - 1.0).sqrt();
            (z + w).norm().max((z - w).norm())
        };
        let mut rnd = uniform_stream(0x2545_f491_4f6c_dd1d);
        for k in 0..20_000 {
            let size = 10f64.powf(-3.0 + 15.0 * rnd());
            let re = size * (2.0 * rnd() - 1.0);
            let im = if k % 3 == 0 {
                0.0
            } else {
                size * (2.0 * rnd() - 1.0)
            };
            let z = Complex::new(re, im);
            let (a, b) = (ellipse_radius(z), polar(z));
            assert!((a - b).abs() <= 1e-13 * b, "{z}: {a} against {b}");
            assert!((modulus(z) - z.norm()).abs() <= 1e-15 * z.norm());
        }
    }

    /// The 4 x 4 Vandermonde solve of the closed-form path gives the coefficients of the
    /// dynamic-size solve of `denominator_radius` bit for bit (the degree test reads them).
    #[test]
    fn static_vandermonde_solve_equals_dynamic_bit_for_bit() {
        use nalgebra::{DMatrix, DVector, Matrix4, Vector4};
        let nodes = chebyshev_nodes(4);
        let mut rnd = uniform_stream(7);
        for _ in 0..2000 {
            let values: Vec<f64> = (0..4).map(|_| 0.2 + 3.0 * rnd()).collect();
            let d = DMatrix::from_fn(4, 4, |i, j| nodes[i].powi(j as i32))
                .lu()
                .solve(&DVector::from_column_slice(&values))
                .unwrap();
            let s = Matrix4::from_fn(|i, j| nodes[i].powi(j as i32))
                .lu()
                .solve(&Vector4::from_column_slice(&values))
                .unwrap();
            for k in 0..4 {
                assert_eq!(d[k].to_bits(), s[k].to_bits());
            }
        }
    }
}
