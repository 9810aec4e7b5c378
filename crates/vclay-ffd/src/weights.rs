//! Direct manipulation through the weights instead of the control points.
//!
//! **What.** The last paragraph of `ffd-direct-manipulation.txt` section 3 says eq (7) "can be
//! extended to modify weights, instead of control points" and omits the details. Here they are.
//! Move the source at `t_s` onto `T` by changing the weights `W_i` of its support (the only
//! weights that `Q(t_s)` depends on) by `Delta` of least `||Delta||^2`. With `B_i` the non-rational
//! tensor-product basis at `t_s`, `W = sum_i W_i B_i`, and `Q = sum_i W_i B_i P_i / W` (eqs 1-2),
//!
//! ```text
//! dQ/dW_i = B_i P_i / W - B_i sum_j W_j B_j P_j / W^2 = B_i (P_i - Q) / W =: J_i     (3-vector)
//! ```
//!
//! Unlike control points, weights enter nonlinearly. Linearizing at the current total change
//! `Delta_k` and taking the least-norm total change that meets the linearized constraint (the
//! Lagrange argument of eqs 5-7 with the `3 x n` Jacobian `J_k` in place of the scalar `R`) gives
//! the minimum-norm Newton (Gauss-Newton on the constraint) iteration
//!
//! ```text
//! Delta_{k+1} = J_k^T (J_k J_k^T)^{-1} (T - Q_k + J_k Delta_k),      J_k J_k^T is 3 x 3.
//! ```
//!
//! For a small displacement the first step is already the exact analogue of eq (7). A fixed point
//! has `Q = T` and `Delta = J^T mu`, the first-order (KKT) condition of
//! `min ||Delta||^2 s.t. Q(W + Delta) = T`. Convergence is quadratic near the solution.
//!
//! **Limitations.** `Q(t_s)` is a convex combination of the support control points for positive
//! weights, so targets outside their convex hull are unreachable: the iteration then drives a weight
//! to zero and reports [`FfdError::NonPositiveWeight`]. If the support points span less than 3D
//! (degenerate lattices), `J J^T` is singular and [`FfdError::SingularWeightJacobian`] results.
//! Weight manipulations do not form a group (they are nonlinear), so they are a separate type
//! from [`crate::Manipulation`].

use crate::error::FfdError;
use crate::lattice::FfdLattice;
use crate::manipulation::PointConstraint;
use nalgebra::{Matrix3, SymmetricEigen};
use vclay_core::Vec3;

/// Default [`WeightOptions::max_iterations`]: 50 Newton steps.
pub const DEFAULT_WEIGHT_ITERATIONS: usize = 50;
/// Default [`WeightOptions::tolerance`]: `1e-13` of the lattice size.
pub const DEFAULT_WEIGHT_TOLERANCE: f64 = 1e-13;
/// Smallest eigenvalue ratio of `J J^T` accepted as non-singular.
const JACOBIAN_CONDITION: f64 = 1e-14;
/// A Newton step whose largest entry is below this fraction of the largest weight change counts
/// as settled.
const STEP_SETTLED: f64 = 1e-10;

/// Options of [`WeightChange::single`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightOptions {
    /// Newton steps allowed. Default [`DEFAULT_WEIGHT_ITERATIONS`].
    pub max_iterations: usize,
    /// Distance to the target at which the iteration stops, relative to the lattice size
    /// ([`FfdLattice::size`]). Default [`DEFAULT_WEIGHT_TOLERANCE`].
    pub tolerance: f64,
}

impl Default for WeightOptions {
    fn default() -> Self {
        Self {
            max_iterations: DEFAULT_WEIGHT_ITERATIONS,
            tolerance: DEFAULT_WEIGHT_TOLERANCE,
        }
    }
}

/// A change of lattice weights that moves one source point onto a target
/// (`ffd-direct-manipulation.txt` section 3, last paragraph; derivation in the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct WeightChange {
    dims: [usize; 3],
    indices: Vec<usize>,
    deltas: Vec<f64>,
    iterations: usize,
    residual: f64,
}

impl WeightChange {
    /// The minimum-norm (to first order, see the module docs) change of the support weights that
    /// moves the source `Q(t_s)` of `constraint` onto its target.
    pub fn single(
        lattice: &FfdLattice,
        constraint: &PointConstraint,
        options: &WeightOptions,
    ) -> Result<Self, FfdError> {
        let t = lattice.check_params(constraint.params)?;
        let target = constraint.target;
        if !target.iter().all(|c| c.is_finite()) {
            return Err(FfdError::NonFiniteTarget { index: 0 });
        }
        // Non-rational basis products B_i on the support: the R_ijk of unit weights.
        let b = lattice.basis_products_unchecked(t);
        let (indices, bvals) = (b.indices, b.values);
        let pts: Vec<Vec3> = indices
            .iter()
            .map(|&i| lattice.control_points()[i])
            .collect();
        let w0: Vec<f64> = indices.iter().map(|&i| lattice.weights()[i]).collect();
        let n = indices.len();
        let tol = options.tolerance * lattice.size();
        let mut delta = vec![0.0; n];
        let eval = |delta: &[f64]| {
            let (mut num, mut den) = (Vec3::zeros(), 0.0);
            for i in 0..n {
                let wb = (w0[i] + delta[i]) * bvals[i];
                num += pts[i] * wb;
                den += wb;
            }
            (num / den, den)
        };
        let (mut q, mut den) = eval(&delta);
        let mut residual = (target - q).norm();
        let mut iterations = 0;
        let mut jac = vec![Vec3::zeros(); n];
        // Stop when the target is met and the total change has settled (the position converges
        // first; the component of Delta along the constraint manifold, which makes it least-norm,
        // settles one or two steps later).
        let mut settled = true;
        while residual > tol || !settled {
            if iterations == options.max_iterations {
                return Err(FfdError::WeightNoConvergence {
                    iterations,
                    residual,
                });
            }
            iterations += 1;
            let mut jjt = Matrix3::zeros();
            let mut jd = Vec3::zeros();
            for i in 0..n {
                jac[i] = (pts[i] - q) * (bvals[i] / den);
                jjt += jac[i] * jac[i].transpose();
                jd += jac[i] * delta[i];
            }
            let eig = SymmetricEigen::new(jjt);
            let (lo, hi) = (eig.eigenvalues.min(), eig.eigenvalues.max());
            if !(hi > 0.0 && lo > JACOBIAN_CONDITION * hi) {
                return Err(FfdError::SingularWeightJacobian {
                    iteration: iterations,
                });
            }
            let mu = eig.eigenvectors
                * Matrix3::from_diagonal(&eig.eigenvalues.map(|e| 1.0 / e))
                * eig.eigenvectors.transpose()
                * (target - q + jd);
            let mut change: f64 = 0.0;
            for i in 0..n {
                let new = jac[i].dot(&mu);
                change = change.max((new - delta[i]).abs());
                delta[i] = new;
                let w = w0[i] + delta[i];
                if w.is_nan() || w <= 0.0 {
                    return Err(FfdError::NonPositiveWeight {
                        index: indices[i],
                        value: w,
                        iteration: iterations,
                    });
                }
            }
            (q, den) = eval(&delta);
            residual = (target - q).norm();
            let largest = delta.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
            settled = change <= STEP_SETTLED * largest;
        }
        Ok(Self {
            dims: lattice.dims(),
            indices,
            deltas: delta,
            iterations,
            residual,
        })
    }

    /// Flat indices of the weights it changes (the support of the source, ascending).
    pub fn indices(&self) -> &[usize] {
        &self.indices
    }
    /// The weight changes `Delta_i`.
    pub fn deltas(&self) -> &[f64] {
        &self.deltas
    }
    /// Newton steps taken.
    pub fn iterations(&self) -> usize {
        self.iterations
    }
    /// Final distance from the source to the target (model units).
    pub fn residual(&self) -> f64 {
        self.residual
    }
    /// `||Delta||^2`.
    pub fn norm_squared(&self) -> f64 {
        self.deltas.iter().map(|d| d * d).sum()
    }

    /// Adds the changes to the lattice weights.
    ///
    /// # Panics
    /// If `lattice` has other dimensions than the one this was computed for.
    #[track_caller]
    pub fn apply(&self, lattice: &mut FfdLattice) -> Result<(), FfdError> {
        assert_eq!(
            self.dims,
            lattice.dims(),
            "weight change for another lattice"
        );
        let mut w = lattice.weights().to_vec();
        for (&i, &d) in self.indices.iter().zip(&self.deltas) {
            w[i] += d;
        }
        lattice.set_weights(w)
    }
}
