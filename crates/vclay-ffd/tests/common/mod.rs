//! Shared helpers for the integration tests: a seeded generator and small builders.
#![allow(dead_code)]

use nalgebra::{DMatrix, SVD};
use vclay_core::Vec3;
use vclay_ffd::{FfdLattice, LatticeSpec};

/// A 64-bit linear congruential generator (Knuth's MMIX constants), seeded, for reproducible tests.
pub struct Lcg(u64);

impl Lcg {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03)
    }
    /// Uniform in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next_f64()
    }
    pub fn params(&mut self) -> [f64; 3] {
        [self.next_f64(), self.next_f64(), self.next_f64()]
    }
    pub fn vec(&mut self, scale: f64) -> Vec3 {
        Vec3::new(
            self.range(-scale, scale),
            self.range(-scale, scale),
            self.range(-scale, scale),
        )
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_f64() * n as f64) as usize).min(n - 1)
    }
}

/// The lattice shapes most tests loop over: degrees 2 and 3, several sizes, uneven ones.
pub fn specs() -> Vec<LatticeSpec> {
    vec![
        LatticeSpec::uniform(2, 3),
        LatticeSpec::uniform(2, 5),
        LatticeSpec::uniform(3, 4),
        LatticeSpec::uniform(3, 6),
        LatticeSpec {
            degree: [3, 2, 3],
            control_points: [4, 7, 5],
        },
        LatticeSpec::uniform(3, 10),
    ]
}

/// A box away from the origin with unequal sides.
pub fn test_box() -> (Vec3, Vec3) {
    (Vec3::new(-1.5, 2.0, 10.0), Vec3::new(2.5, 3.0, 13.0))
}

pub fn lattice(spec: LatticeSpec) -> FfdLattice {
    let (lo, hi) = test_box();
    FfdLattice::new(spec, lo, hi).unwrap()
}

/// Randomly displaces every control point by up to `scale` (deformed, non-identity lattice).
pub fn jiggle(lattice: &mut FfdLattice, rng: &mut Lcg, scale: f64) {
    let pts: Vec<Vec3> = lattice
        .control_points()
        .iter()
        .map(|p| p + rng.vec(scale))
        .collect();
    lattice.set_control_points(pts).unwrap();
}

/// Rest-space point at parameters `t`.
pub fn rest_point(lattice: &FfdLattice, t: [f64; 3]) -> Vec3 {
    let (lo, hi) = lattice.bounds();
    lo + (hi - lo).component_mul(&Vec3::from(t))
}

/// The dense `m x N` matrix of `R_ijk(t_f)`.
pub fn dense_r(lattice: &FfdLattice, params: &[[f64; 3]]) -> DMatrix<f64> {
    let n = lattice.control_point_count();
    let mut r = DMatrix::zeros(params.len(), n);
    for (f, t) in params.iter().enumerate() {
        let b = lattice.basis(*t).unwrap();
        for (&i, &v) in b.indices.iter().zip(&b.values) {
            r[(f, i)] = v;
        }
    }
    r
}

/// Minimum-norm least-squares `delta = R^+ D` by nalgebra's SVD (`N x 3`). The SVD is taken of the
/// tall `R^T` (`N x m`, `R^+ = ((R^T)^+)^T`): nalgebra 0.35's SVD of wide rank-deficient matrices
/// can be inaccurate.
pub fn dense_pinv_solution(r: &DMatrix<f64>, d: &[Vec3]) -> DMatrix<f64> {
    let dm = DMatrix::from_fn(d.len(), 3, |i, j| d[i][j]);
    let rt = r.transpose();
    let (rows, cols) = rt.shape();
    let pinv = if rows >= cols {
        let svd = SVD::new(rt, true, true);
        let eps = 1e-10 * svd.singular_values.max();
        svd.pseudo_inverse(eps).unwrap().transpose()
    } else {
        let svd = SVD::new(r.clone(), true, true);
        let eps = 1e-10 * svd.singular_values.max();
        svd.pseudo_inverse(eps).unwrap()
    };
    pinv * dm
}

/// `delta = R^T (R R^T)^{-1} D` by a dense Cholesky of the `m x m` Gram matrix (full row rank only):
/// the paper's eq (12) evaluated literally, an independent check of the QR-based solver.
pub fn dense_normal_equations_solution(r: &DMatrix<f64>, d: &[Vec3]) -> DMatrix<f64> {
    let dm = DMatrix::from_fn(d.len(), 3, |i, j| d[i][j]);
    let gram = r * r.transpose();
    let lambda = gram.cholesky().expect("full row rank").solve(&dm);
    r.transpose() * lambda
}
