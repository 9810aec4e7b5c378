//! Evaluation traits shared by every parametric object in vclay.
//!
//! Static and dynamic NURBS, FFD volumes, subdivision limits and PDE surfaces all implement these,
//! so tessellators, exporters and tools use them the same way.

use crate::error::SplineError;
use vclay_core::{Interval, Vec3};

/// A map `c: [a, b] -> R^3`.
pub trait ParametricCurve {
    /// The parameter domain.
    fn domain(&self) -> Interval;
    /// The point `c(u)`.
    fn point(&self, u: f64) -> Result<Vec3, SplineError>;
    /// `d^k c / du^k` for `k = 0..=order` (entry 0 is the point). Errors for an order above
    /// [`crate::MAX_DERIVATIVE_ORDER`].
    fn derivatives(&self, u: f64, order: usize) -> Result<Vec<Vec3>, SplineError>;
    /// The first derivative `c'(u)`.
    fn tangent(&self, u: f64) -> Result<Vec3, SplineError> {
        Ok(self.derivatives(u, 1)?[1])
    }
}

/// A map `s: [a, b] x [c, d] -> R^3`.
pub trait ParametricSurface {
    /// The domains along u and v.
    fn domain(&self) -> [Interval; 2];
    /// The point `s(u, v)`.
    fn point(&self, u: f64, v: f64) -> Result<Vec3, SplineError>;
    /// Partial derivatives `d[a][b] = d^(a+b) s / du^a dv^b` for `a + b <= order`: a triangular
    /// array where `d[a]` has `order - a + 1` entries. Errors for an order above
    /// [`crate::MAX_DERIVATIVE_ORDER`].
    fn derivatives(&self, u: f64, v: f64, order: usize) -> Result<Vec<Vec<Vec3>>, SplineError>;
    /// Unit normal `s_u x s_v / |s_u x s_v|`, or `None` where the surface is degenerate.
    fn normal(&self, u: f64, v: f64) -> Result<Option<Vec3>, SplineError> {
        let d = self.derivatives(u, v, 1)?;
        let n = d[1][0].cross(&d[0][1]);
        let len = n.norm();
        Ok((len > 0.0 && len.is_finite()).then(|| n / len))
    }
}

/// A map `V: [a0, b0] x [a1, b1] x [a2, b2] -> R^3`.
pub trait ParametricVolume {
    /// The domains along u, v and w.
    fn domain(&self) -> [Interval; 3];
    /// The point `V(u, v, w)`.
    fn point(&self, u: f64, v: f64, w: f64) -> Result<Vec3, SplineError>;
    /// Partial derivatives `d[a][b][c] = d^(a+b+c) V / du^a dv^b dw^c` for `a + b + c <= order`
    /// (triangular: `d[a]` has `order - a + 1` entries, `d[a][b]` has `order - a - b + 1`).
    /// Errors for an order above [`crate::MAX_DERIVATIVE_ORDER`].
    fn derivatives(
        &self,
        u: f64,
        v: f64,
        w: f64,
        order: usize,
    ) -> Result<Vec<Vec<Vec<Vec3>>>, SplineError>;
    /// The 3x3 Jacobian matrix of the map, columns `V_u, V_v, V_w`. Its Gram matrix `J^T J` is the
    /// metric tensor `g_ij` of `subdivision-solids-journal.txt` section 4.3.
    fn jacobian_matrix(
        &self,
        u: f64,
        v: f64,
        w: f64,
    ) -> Result<nalgebra::Matrix3<f64>, SplineError> {
        let d = self.derivatives(u, v, w, 1)?;
        Ok(nalgebra::Matrix3::from_columns(&[
            d[1][0][0], d[0][1][0], d[0][0][1],
        ]))
    }
}
