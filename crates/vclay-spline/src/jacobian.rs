//! D-NURBS Jacobians: derivatives of a NURBS point with respect to its control points and weights.
//!
//! For a point `s = sum_i w_i p_i B_i / W`, `W = sum_j w_j B_j` (where `B_i` is the product of the
//! univariate basis functions for surfaces and volumes):
//!
//! ```text
//! ds/dp_i = R_i I,      R_i = w_i B_i / W                             (d-nurbs.txt eq 3, N_ij)
//! ds/dw_i = sum_j (p_i - p_j) w_j B_i B_j / W^2 = B_i (p_i - s) / W    (d-nurbs.txt eq 3, w_ij)
//! ```
//!
//! With the generalized coordinates ordered `p = [p_0^T w_0 ... p_n^T w_n]^T` (for surfaces the
//! second index fastest, `d-nurbs.txt` section 4.2) the 3 x 4n matrix `J = [R_0 I, ds/dw_0, ...]`
//! satisfies `s = J p` (eq 4, 6): `sum R_i p_i = s` and `sum w_i ds/dw_i = 0` because `s` is
//! homogeneous of degree zero in the weights (Euler's theorem).

use nalgebra::DMatrix;
use vclay_core::Vec3;

/// The non-zero blocks of a D-NURBS Jacobian at one parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseJacobian {
    /// Flat control-point indices (last parametric axis fastest) of the non-zero blocks.
    pub indices: Vec<usize>,
    /// The evaluated point `s`.
    pub point: Vec3,
    /// `R_i = ds/dp_i` (a scalar times the 3x3 identity), one per entry of `indices`.
    pub point_derivatives: Vec<f64>,
    /// `ds/dw_i`, one per entry of `indices`.
    pub weight_derivatives: Vec<Vec3>,
}

impl SparseJacobian {
    /// Builds the Jacobian from the non-rational basis products `B_i` of the listed control points.
    pub(crate) fn from_basis(
        indices: Vec<usize>,
        basis: &[f64],
        points: &[Vec3],
        weights: &[f64],
    ) -> Self {
        let mut wsum = 0.0;
        let mut num = Vec3::zeros();
        for (&i, &b) in indices.iter().zip(basis) {
            wsum += weights[i] * b;
            num += points[i] * (weights[i] * b);
        }
        let s = num / wsum;
        let point_derivatives = indices
            .iter()
            .zip(basis)
            .map(|(&i, &b)| weights[i] * b / wsum)
            .collect();
        let weight_derivatives = indices
            .iter()
            .zip(basis)
            .map(|(&i, &b)| (points[i] - s) * (b / wsum))
            .collect();
        Self {
            indices,
            point: s,
            point_derivatives,
            weight_derivatives,
        }
    }

    /// `J p`: the product of this Jacobian with generalized coordinates (control points and
    /// weights, full arrays). Equals [`SparseJacobian::point`] when given the object's own
    /// coordinates (`d-nurbs.txt` eq 4); with other coordinates it is the linearization.
    pub fn apply(&self, points: &[Vec3], weights: &[f64]) -> Vec3 {
        let mut s = Vec3::zeros();
        for (k, &i) in self.indices.iter().enumerate() {
            s += points[i] * self.point_derivatives[k] + self.weight_derivatives[k] * weights[i];
        }
        s
    }

    /// `J^T f`: pulls a force `f` at the point back to generalized forces, written into
    /// `point_forces[i]` and `weight_forces[i]` (accumulated). This is the integrand of the
    /// D-NURBS generalized force `f_p = integral J^T f` (`d-nurbs.txt` section 4.5).
    pub fn apply_transpose(&self, f: &Vec3, point_forces: &mut [Vec3], weight_forces: &mut [f64]) {
        for (k, &i) in self.indices.iter().enumerate() {
            point_forces[i] += f * self.point_derivatives[k];
            weight_forces[i] += self.weight_derivatives[k].dot(f);
        }
    }

    /// The dense `3 x 4n` matrix of `d-nurbs.txt` eq (3)/(6), columns ordered
    /// `[p_0x p_0y p_0z w_0 p_1x ...]`, for `n` control points.
    pub fn to_dense(&self, n: usize) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(3, 4 * n);
        for (k, &i) in self.indices.iter().enumerate() {
            for r in 0..3 {
                j[(r, 4 * i + r)] = self.point_derivatives[k];
                j[(r, 4 * i + 3)] = self.weight_derivatives[k][r];
            }
        }
        j
    }
}

/// Stacks control points and weights into the generalized coordinate vector
/// `p = [p_0^T w_0 ... p_n^T w_n]^T` of `d-nurbs.txt` section 4.1.
pub fn generalized_coordinates(points: &[Vec3], weights: &[f64]) -> nalgebra::DVector<f64> {
    let mut v = nalgebra::DVector::zeros(4 * points.len());
    for (i, (p, w)) in points.iter().zip(weights).enumerate() {
        v[4 * i] = p.x;
        v[4 * i + 1] = p.y;
        v[4 * i + 2] = p.z;
        v[4 * i + 3] = *w;
    }
    v
}
