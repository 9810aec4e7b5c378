//! Tensor-product NURBS surfaces.
//!
//! ```text
//! s(u, v) = sum_ij w_ij p_ij N_i(u) N_j(v) / sum_ij w_ij N_i(u) N_j(v)        (d-nurbs.txt eq 5)
//! ```
//!
//! Derivatives of any order: homogeneous derivatives by Piegl & Tiller A3.6, then the quotient rule
//! of A4.4: `S^(k,l) = (A^(k,l) - sum_{(i,j) != (0,0)} C(k,i) C(l,j) w^(i,j) S^(k-i,l-j)) / w`.
//!
//! The control net is stored flat, index `i * n_v + j` (the second index varies fastest, as in
//! `d-nurbs.txt` section 4.2).

use crate::error::SplineError;
use crate::jacobian::SparseJacobian;
use crate::knots::{BasisWorkspace, KnotVector, MAX_DEGREE};
use crate::traits::ParametricSurface;
use crate::util::{BasisBuf, check_net, check_param, homogeneous};
use vclay_core::math::binomial;
use vclay_core::{Interval, Vec3, Vec4};

/// A tensor-product NURBS surface of degrees `(p, q)` with an `n_u x n_v` control net.
///
/// Implements `d-nurbs.txt` eq (5); its D-NURBS Jacobian (section 4.2, `N_ij` and `w_ij`) is
/// [`NurbsSurface::jacobian`].
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsSurface {
    knots: [KnotVector; 2],
    points: Vec<Vec3>,
    weights: Vec<f64>,
}

/// Flattens a nested `[i][j]` net, reporting the first ragged row.
pub(crate) fn flatten2<T: Clone>(
    net: &[Vec<T>],
    what: &str,
) -> Result<(Vec<T>, [usize; 2]), SplineError> {
    let nu = net.len();
    let nv = net.first().map_or(0, Vec::len);
    let mut flat = Vec::with_capacity(nu * nv);
    for (i, row) in net.iter().enumerate() {
        if row.len() != nv {
            return Err(SplineError::Shape {
                what: format!("length of {what}[{i}]"),
                found: row.len(),
                expected: nv,
            });
        }
        flat.extend_from_slice(row);
    }
    Ok((flat, [nu, nv]))
}

impl NurbsSurface {
    /// A surface from degrees, knot vectors, a nested control net `points[i][j]` (i along u) and
    /// optional weights of the same shape (all 1 when `None`).
    pub fn new(
        degree: [usize; 2],
        knots: [Vec<f64>; 2],
        points: Vec<Vec<Vec3>>,
        weights: Option<Vec<Vec<f64>>>,
    ) -> Result<Self, SplineError> {
        let (flat, dims) = flatten2(&points, "control_points")?;
        let w = match weights {
            Some(w) => {
                if w.len() != dims[0] {
                    return Err(SplineError::Shape {
                        what: "number of weight rows".into(),
                        found: w.len(),
                        expected: dims[0],
                    });
                }
                let (wf, wd) = flatten2(&w, "weights")?;
                if wd != dims {
                    return Err(SplineError::Shape {
                        what: "length of weights[0]".into(),
                        found: wd[1],
                        expected: dims[1],
                    });
                }
                wf
            }
            None => vec![1.0; flat.len()],
        };
        let [ku, kv] = knots;
        let ku = KnotVector::new(ku, degree[0], dims[0])
            .map_err(|source| SplineError::Knots { axis: 0, source })?;
        let kv = KnotVector::new(kv, degree[1], dims[1])
            .map_err(|source| SplineError::Knots { axis: 1, source })?;
        Self::from_flat([ku, kv], flat, w)
    }

    /// A surface from validated knot vectors and a flat net (index `i * n_v + j`).
    pub fn from_flat(
        knots: [KnotVector; 2],
        points: Vec<Vec3>,
        weights: Vec<f64>,
    ) -> Result<Self, SplineError> {
        let dims = [knots[0].control_points(), knots[1].control_points()];
        check_net(&points, &weights, &dims)?;
        Ok(Self {
            knots,
            points,
            weights,
        })
    }

    /// A non-rational B-spline surface on clamped uniform knots over `[0, 1]^2` from a flat
    /// `dims[0] x dims[1]` net.
    pub fn clamped_uniform(
        degree: [usize; 2],
        dims: [usize; 2],
        points: Vec<Vec3>,
    ) -> Result<Self, SplineError> {
        let ku = KnotVector::clamped_uniform(degree[0], dims[0])
            .map_err(|source| SplineError::Knots { axis: 0, source })?;
        let kv = KnotVector::clamped_uniform(degree[1], dims[1])
            .map_err(|source| SplineError::Knots { axis: 1, source })?;
        let w = vec![1.0; points.len()];
        Self::from_flat([ku, kv], points, w)
    }

    pub(crate) fn from_homogeneous(
        knots: [KnotVector; 2],
        pw: &[Vec4],
    ) -> Result<Self, SplineError> {
        let (p, w) = crate::util::dehomogenize(pw);
        Self::from_flat(knots, p, w)
    }

    /// Degrees `(p, q)`.
    pub fn degree(&self) -> [usize; 2] {
        [self.knots[0].degree(), self.knots[1].degree()]
    }
    /// Knot vectors along u and v.
    pub fn knots(&self) -> &[KnotVector; 2] {
        &self.knots
    }
    /// Control net size `(n_u, n_v)`.
    pub fn dims(&self) -> [usize; 2] {
        [
            self.knots[0].control_points(),
            self.knots[1].control_points(),
        ]
    }
    /// Flat control points, index `i * n_v + j`.
    pub fn control_points(&self) -> &[Vec3] {
        &self.points
    }
    /// Flat weights, index `i * n_v + j`.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
    /// Control point `p_ij`.
    pub fn control_point(&self, i: usize, j: usize) -> Vec3 {
        self.points[i * self.dims()[1] + j]
    }
    /// Homogeneous control points.
    pub fn homogeneous_points(&self) -> Vec<Vec4> {
        homogeneous(&self.points, &self.weights)
    }

    /// Replaces the control points (same count), validating them.
    pub fn set_control_points(&mut self, points: Vec<Vec3>) -> Result<(), SplineError> {
        check_net(&points, &self.weights, &self.dims())?;
        self.points = points;
        Ok(())
    }

    /// Replaces the weights (same count), validating them.
    pub fn set_weights(&mut self, weights: Vec<f64>) -> Result<(), SplineError> {
        check_net(&self.points, &weights, &self.dims())?;
        self.weights = weights;
        Ok(())
    }

    /// Applies an affine map `x -> m x + t` to the control points.
    pub fn transform(&mut self, m: &nalgebra::Matrix3<f64>, t: &Vec3) {
        for p in &mut self.points {
            *p = m * *p + t;
        }
    }

    /// The D-NURBS Jacobian at `(u, v)` (`d-nurbs.txt` section 4.2), restricted to its
    /// `(p + 1)(q + 1)` non-zero blocks.
    pub fn jacobian(&self, u: f64, v: f64) -> Result<SparseJacobian, SplineError> {
        let u = check_param(&self.knots[0], 0, u)?;
        let v = check_param(&self.knots[1], 1, v)?;
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let (su, sv) = (self.knots[0].find_span(u), self.knots[1].find_span(v));
        let mut bu: BasisBuf = [0.0; MAX_DEGREE + 1];
        let mut bv: BasisBuf = [0.0; MAX_DEGREE + 1];
        self.knots[0].basis(su, u, &mut bu);
        self.knots[1].basis(sv, v, &mut bv);
        let mut idx = Vec::with_capacity((p + 1) * (q + 1));
        let mut basis = Vec::with_capacity((p + 1) * (q + 1));
        for a in 0..=p {
            for b in 0..=q {
                idx.push((su - p + a) * nv + sv - q + b);
                basis.push(bu[a] * bv[b]);
            }
        }
        Ok(SparseJacobian::from_basis(
            idx,
            &basis,
            &self.points,
            &self.weights,
        ))
    }

    /// Homogeneous partial derivatives `A[k][l]` for `k + l <= order` (Piegl & Tiller A3.6),
    /// zero where `k > p` or `l > q`.
    fn homogeneous_derivatives(&self, u: f64, v: f64, order: usize) -> Vec<Vec<Vec4>> {
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let (su, sv) = (self.knots[0].find_span(u), self.knots[1].find_span(v));
        let (du, dv) = (order.min(p), order.min(q));
        let mut nu_d = vec![0.0; (du + 1) * (p + 1)];
        let mut nv_d = vec![0.0; (dv + 1) * (q + 1)];
        let mut ws = BasisWorkspace::new(p.max(q));
        self.knots[0].basis_derivatives(su, u, du, &mut nu_d, &mut ws);
        self.knots[1].basis_derivatives(sv, v, dv, &mut nv_d, &mut ws);
        let mut a = vec![vec![]; order + 1];
        for k in 0..=order {
            a[k] = vec![Vec4::zeros(); order - k + 1];
        }
        let mut temp = vec![Vec4::zeros(); q + 1];
        for k in 0..=du {
            for (s, t) in temp.iter_mut().enumerate() {
                *t = Vec4::zeros();
                for r in 0..=p {
                    let i = (su - p + r) * nv + sv - q + s;
                    let w = self.weights[i];
                    let pt = self.points[i];
                    *t += Vec4::new(pt.x * w, pt.y * w, pt.z * w, w) * nu_d[k * (p + 1) + r];
                }
            }
            let dd = (order - k).min(dv);
            for l in 0..=dd {
                let mut acc = Vec4::zeros();
                for s in 0..=q {
                    acc += temp[s] * nv_d[l * (q + 1) + s];
                }
                a[k][l] = acc;
            }
        }
        a
    }
}

/// Quotient rule for surfaces (Piegl & Tiller A4.4).
pub(crate) fn rational_surface_derivatives(a: &[Vec<Vec4>]) -> Vec<Vec<Vec3>> {
    let order = a.len() - 1;
    let w0 = a[0][0].w;
    let mut s: Vec<Vec<Vec3>> = (0..=order)
        .map(|k| vec![Vec3::zeros(); order - k + 1])
        .collect();
    for k in 0..=order {
        for l in 0..=order - k {
            let mut v = a[k][l].xyz();
            for j in 1..=l {
                v -= binomial(l, j) * a[0][j].w * s[k][l - j];
            }
            for i in 1..=k {
                v -= binomial(k, i) * a[i][0].w * s[k - i][l];
                let mut v2 = Vec3::zeros();
                for j in 1..=l {
                    v2 += binomial(l, j) * a[i][j].w * s[k - i][l - j];
                }
                v -= binomial(k, i) * v2;
            }
            s[k][l] = v / w0;
        }
    }
    s
}

impl ParametricSurface for NurbsSurface {
    fn domain(&self) -> [Interval; 2] {
        [self.knots[0].domain(), self.knots[1].domain()]
    }

    fn point(&self, u: f64, v: f64) -> Result<Vec3, SplineError> {
        let u = check_param(&self.knots[0], 0, u)?;
        let v = check_param(&self.knots[1], 1, v)?;
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let (su, sv) = (self.knots[0].find_span(u), self.knots[1].find_span(v));
        let mut bu: BasisBuf = [0.0; MAX_DEGREE + 1];
        let mut bv: BasisBuf = [0.0; MAX_DEGREE + 1];
        self.knots[0].basis(su, u, &mut bu);
        self.knots[1].basis(sv, v, &mut bv);
        let mut acc = Vec4::zeros();
        for a in 0..=p {
            let row = (su - p + a) * nv + sv - q;
            let mut t = Vec4::zeros();
            for b in 0..=q {
                let i = row + b;
                let w = self.weights[i] * bv[b];
                let pt = self.points[i];
                t += Vec4::new(pt.x * w, pt.y * w, pt.z * w, w);
            }
            acc += t * bu[a];
        }
        Ok(acc.xyz() / acc.w)
    }

    fn derivatives(&self, u: f64, v: f64, order: usize) -> Result<Vec<Vec<Vec3>>, SplineError> {
        crate::util::check_order(order)?;
        let u = check_param(&self.knots[0], 0, u)?;
        let v = check_param(&self.knots[1], 1, v)?;
        Ok(rational_surface_derivatives(
            &self.homogeneous_derivatives(u, v, order),
        ))
    }
}
