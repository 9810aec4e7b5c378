//! NURBS curves.
//!
//! ```text
//! c(u) = sum_i w_i p_i N_{i,p}(u) / sum_i w_i N_{i,p}(u)          (d-nurbs.txt eq 1)
//! ```
//!
//! Points by the `p + 1` non-zero basis functions (Piegl & Tiller A4.1), derivatives of any order
//! by the quotient rule on the homogeneous curve `C^w = (w c, w)` (Piegl & Tiller A4.2):
//! `c^(k) = (A^(k) - sum_{i=1}^{k} C(k,i) w^(i) c^(k-i)) / w`.

use crate::KnotError;
use crate::error::SplineError;
use crate::jacobian::SparseJacobian;
use crate::knots::{BasisWorkspace, KnotVector};
use crate::traits::ParametricCurve;
use crate::util::{BasisBuf, check_net, check_param, homogeneous};
use vclay_core::math::binomial;
use vclay_core::{Interval, Vec3, Vec4};

/// A NURBS curve of degree `p` with `n` control points `p_i` and positive weights `w_i`.
///
/// Implements `d-nurbs.txt` eq (1); its D-NURBS Jacobian (eq 3) is [`NurbsCurve::jacobian`].
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    knots: KnotVector,
    points: Vec<Vec3>,
    weights: Vec<f64>,
}

impl NurbsCurve {
    /// A curve from degree, knots, control points and optional weights (all 1 when `None`).
    pub fn new(
        degree: usize,
        knots: Vec<f64>,
        points: Vec<Vec3>,
        weights: Option<Vec<f64>>,
    ) -> Result<Self, SplineError> {
        let kv = KnotVector::new(knots, degree, points.len())
            .map_err(|source| SplineError::Knots { axis: 0, source })?;
        let weights = weights.unwrap_or_else(|| vec![1.0; points.len()]);
        Self::from_knot_vector(kv, points, weights)
    }

    /// A curve from a validated knot vector.
    pub fn from_knot_vector(
        knots: KnotVector,
        points: Vec<Vec3>,
        weights: Vec<f64>,
    ) -> Result<Self, SplineError> {
        if points.len() != knots.control_points() {
            return Err(SplineError::Knots {
                axis: 0,
                source: KnotError::Count {
                    found: knots.len(),
                    expected: points.len() + knots.degree() + 1,
                    control_points: points.len(),
                    degree: knots.degree(),
                },
            });
        }
        check_net(&points, &weights, &[points.len()])?;
        Ok(Self {
            knots,
            points,
            weights,
        })
    }

    /// A non-rational B-spline curve on clamped uniform knots over `[0, 1]`.
    pub fn clamped_uniform(degree: usize, points: Vec<Vec3>) -> Result<Self, SplineError> {
        let kv = KnotVector::clamped_uniform(degree, points.len())
            .map_err(|source| SplineError::Knots { axis: 0, source })?;
        let w = vec![1.0; points.len()];
        Self::from_knot_vector(kv, points, w)
    }

    /// From homogeneous control points (used by refinement).
    pub(crate) fn from_homogeneous(knots: KnotVector, pw: &[Vec4]) -> Result<Self, SplineError> {
        let (points, weights) = crate::util::dehomogenize(pw);
        Self::from_knot_vector(knots, points, weights)
    }

    /// Degree `p`.
    pub fn degree(&self) -> usize {
        self.knots.degree()
    }
    /// The knot vector.
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }
    /// Control points.
    pub fn control_points(&self) -> &[Vec3] {
        &self.points
    }
    /// Weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
    /// Homogeneous control points `(w p, w)`.
    pub fn homogeneous_points(&self) -> Vec<Vec4> {
        homogeneous(&self.points, &self.weights)
    }
    /// Whether all weights are equal (the curve is a polynomial B-spline).
    pub fn is_polynomial(&self) -> bool {
        self.weights.iter().all(|&w| w == self.weights[0])
    }

    /// Replaces the control points (same count), validating them.
    pub fn set_control_points(&mut self, points: Vec<Vec3>) -> Result<(), SplineError> {
        check_net(&points, &self.weights, &[self.points.len()])?;
        self.points = points;
        Ok(())
    }

    /// Replaces the weights (same count), validating them.
    pub fn set_weights(&mut self, weights: Vec<f64>) -> Result<(), SplineError> {
        check_net(&self.points, &weights, &[self.points.len()])?;
        self.weights = weights;
        Ok(())
    }

    /// Applies an affine map `x -> m x + t` to the control points (NURBS are affinely invariant).
    pub fn transform(&mut self, m: &nalgebra::Matrix3<f64>, t: &Vec3) {
        for p in &mut self.points {
            *p = m * *p + t;
        }
    }

    /// Homogeneous derivatives `A^(k) = (sum N^(k) w p, sum N^(k) w)` for `k = 0..=order`.
    fn homogeneous_derivatives(&self, u: f64, order: usize) -> Vec<Vec4> {
        let p = self.degree();
        let span = self.knots.find_span(u);
        let du = order.min(p);
        let mut nd = vec![0.0; (du + 1) * (p + 1)];
        let mut ws = BasisWorkspace::new(p);
        self.knots.basis_derivatives(span, u, du, &mut nd, &mut ws);
        let mut out = vec![Vec4::zeros(); order + 1];
        for k in 0..=du {
            for j in 0..=p {
                let i = span - p + j;
                let w = self.weights[i] * nd[k * (p + 1) + j];
                out[k] += Vec4::new(
                    self.points[i].x * w,
                    self.points[i].y * w,
                    self.points[i].z * w,
                    w,
                );
            }
        }
        out
    }

    /// The D-NURBS Jacobian at `u` (`d-nurbs.txt` eq 3), restricted to its `p + 1` non-zero
    /// blocks: `dc/dp_i = R_i = w_i N_i / W` (times the identity) and
    /// `dc/dw_i = N_i (p_i - c) / W` with `W = sum_j w_j N_j` (this is the paper's
    /// `sum_j (p_i - p_j) w_j N_i N_j / W^2` simplified with `sum_j w_j N_j p_j = W c`).
    pub fn jacobian(&self, u: f64) -> Result<SparseJacobian, SplineError> {
        let u = check_param(&self.knots, 0, u)?;
        let p = self.degree();
        let span = self.knots.find_span(u);
        let mut b: BasisBuf = [0.0; crate::knots::MAX_DEGREE + 1];
        self.knots.basis(span, u, &mut b);
        let indices: Vec<usize> = (span - p..=span).collect();
        let basis: Vec<f64> = b[..=p].to_vec();
        Ok(SparseJacobian::from_basis(
            indices,
            &basis,
            &self.points,
            &self.weights,
        ))
    }
}

impl ParametricCurve for NurbsCurve {
    fn domain(&self) -> Interval {
        self.knots.domain()
    }

    fn point(&self, u: f64) -> Result<Vec3, SplineError> {
        let u = check_param(&self.knots, 0, u)?;
        let p = self.degree();
        let span = self.knots.find_span(u);
        let mut b: BasisBuf = [0.0; crate::knots::MAX_DEGREE + 1];
        self.knots.basis(span, u, &mut b);
        let mut acc = Vec4::zeros();
        for j in 0..=p {
            let i = span - p + j;
            let w = self.weights[i] * b[j];
            acc += Vec4::new(
                self.points[i].x * w,
                self.points[i].y * w,
                self.points[i].z * w,
                w,
            );
        }
        Ok(acc.xyz() / acc.w)
    }

    fn derivatives(&self, u: f64, order: usize) -> Result<Vec<Vec3>, SplineError> {
        crate::util::check_order(order)?;
        let u = check_param(&self.knots, 0, u)?;
        let a = self.homogeneous_derivatives(u, order);
        Ok(rational_curve_derivatives(&a))
    }
}

/// Quotient rule for curves (Piegl & Tiller A4.2): Euclidean derivatives from homogeneous ones.
pub(crate) fn rational_curve_derivatives(a: &[Vec4]) -> Vec<Vec3> {
    let w0 = a[0].w;
    let mut ck: Vec<Vec3> = Vec::with_capacity(a.len());
    for k in 0..a.len() {
        let mut v = a[k].xyz();
        for i in 1..=k {
            v -= binomial(k, i) * a[i].w * ck[k - i];
        }
        ck.push(v / w0);
    }
    ck
}
