//! What the D-NURBS finite elements need from a geometry: elements (non-empty knot spans or span
//! rectangles), rational basis functions and their parametric derivatives at Gauss points.
//!
//! With frozen weights the Jacobian of `d-nurbs.txt` eq (3)/(6) reduces to `R_i I` (the weight
//! columns drop out), so every element matrix is a scalar matrix in the rational basis
//! `R_i = w_i N_i / W` times the 3x3 identity. Derivatives of `R_i` by the quotient rule:
//!
//! ```text
//! R_a   = (w N_a - R W_a) / W
//! R_ab  = (w N_ab - R_a W_b - R_b W_a - R W_ab) / W
//! ```
//! where `W = sum_j w_j N_j` and subscripts are parametric partial derivatives.

use crate::error::DynamicsError;
use vclay_core::{GaussLegendre, Vec3};
use vclay_spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};

/// Basis samples of one finite element at its quadrature points.
#[derive(Clone, Debug)]
pub struct ElementSamples {
    /// Global control-point indices of the element's degrees of freedom.
    pub dofs: Vec<usize>,
    /// Parameters of the quadrature points (`[u, 0]` for curves).
    pub params: Vec<[f64; 2]>,
    /// Quadrature weights including the parameter-interval scaling.
    pub weights: Vec<f64>,
    /// `R_a` at each point: `values[q * nd + a]`.
    pub values: Vec<f64>,
    /// First derivatives: `first[(q * dim + dir) * nd + a]`.
    pub first: Vec<f64>,
    /// Second derivatives: `second[(q * pairs + pair) * nd + a]` with pairs `uu` (curves) or
    /// `uu, uv, vv` (surfaces).
    pub second: Vec<f64>,
}

/// A NURBS geometry that can serve as a D-NURBS with frozen weights.
pub trait DnurbsGeometry: Clone + Send + Sync {
    /// Parametric dimension (1 or 2).
    const DIM: usize;
    /// Number of second-derivative pairs (1 or 3).
    const PAIRS: usize;
    /// Number of control points.
    fn control_point_count(&self) -> usize;
    /// Control points (flat).
    fn points(&self) -> &[Vec3];
    /// Replaces the control points.
    fn set_points(&mut self, p: Vec<Vec3>) -> Result<(), DynamicsError>;
    /// Elements with their quadrature samples (`gauss` points per direction).
    fn element_samples(&self, gauss: &GaussLegendre) -> Vec<ElementSamples>;
    /// Control indices and rational basis values at a parameter, and the point.
    fn basis_at(&self, param: &[f64]) -> Result<(Vec<usize>, Vec<f64>, Vec3), DynamicsError>;
    /// Area-weighted normal `s_u x s_v` (surfaces) at a parameter; zero for curves.
    fn area_normal(&self, param: &[f64]) -> Result<Vec3, DynamicsError>;
    /// Largest degree (for choosing the quadrature order).
    fn max_degree(&self) -> usize;
    /// Parameter of the point of the geometry closest to `x` (`[u, 0]` for curves).
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError>;
    /// The same NURBS as a [`super::RationalGeometry`] (its rational denominators choose the
    /// weight-aware quadrature order of [`super::Dnurbs::with_quadrature`]); `None` (the
    /// default) keeps the fixed rule.
    fn rational(&self) -> Option<super::RationalGeometry> {
        None
    }
}

/// Non-empty spans of a knot vector as `(span index, start, end)`.
fn spans(kv: &vclay_spline::KnotVector) -> Vec<(usize, f64, f64)> {
    let k = kv.as_slice();
    let p = kv.degree();
    (p..kv.control_points())
        .filter(|&i| k[i] < k[i + 1])
        .map(|i| (i, k[i], k[i + 1]))
        .collect()
}

/// Basis values and up to second derivatives of one axis at a parameter: `[N, N', N'']` blocks.
fn axis_basis(kv: &vclay_spline::KnotVector, span: usize, u: f64) -> Vec<f64> {
    kv.basis_derivatives_vec(span, u, 2)
}

impl DnurbsGeometry for NurbsCurve {
    fn rational(&self) -> Option<super::RationalGeometry> {
        Some(super::RationalGeometry::from_curve(self))
    }
    const DIM: usize = 1;
    const PAIRS: usize = 1;

    fn control_point_count(&self) -> usize {
        self.control_points().len()
    }
    fn points(&self) -> &[Vec3] {
        self.control_points()
    }
    fn set_points(&mut self, p: Vec<Vec3>) -> Result<(), DynamicsError> {
        Ok(self.set_control_points(p)?)
    }
    fn max_degree(&self) -> usize {
        self.degree()
    }

    fn element_samples(&self, gauss: &GaussLegendre) -> Vec<ElementSamples> {
        let kv = self.knots();
        let p = kv.degree();
        let nd = p + 1;
        let w = self.weights();
        spans(kv)
            .into_iter()
            .map(|(s, a, b)| {
                let dofs: Vec<usize> = (s - p..=s).collect();
                let mut e = ElementSamples {
                    dofs,
                    params: vec![],
                    weights: vec![],
                    values: vec![],
                    first: vec![],
                    second: vec![],
                };
                for (u, gw) in gauss.on_interval(a, b) {
                    let d = axis_basis(kv, s, u);
                    let (mut w0, mut w1, mut w2) = (0.0, 0.0, 0.0);
                    for j in 0..nd {
                        let wi = w[s - p + j];
                        w0 += wi * d[j];
                        w1 += wi * d[nd + j];
                        w2 += wi * d[2 * nd + j];
                    }
                    let r: Vec<f64> = (0..nd).map(|j| w[s - p + j] * d[j] / w0).collect();
                    let r1: Vec<f64> = (0..nd)
                        .map(|j| (w[s - p + j] * d[nd + j] - r[j] * w1) / w0)
                        .collect();
                    let r2: Vec<f64> = (0..nd)
                        .map(|j| (w[s - p + j] * d[2 * nd + j] - 2.0 * r1[j] * w1 - r[j] * w2) / w0)
                        .collect();
                    e.params.push([u, 0.0]);
                    e.weights.push(gw);
                    e.values.extend(r);
                    e.first.extend(r1);
                    e.second.extend(r2);
                }
                e
            })
            .collect()
    }

    fn basis_at(&self, param: &[f64]) -> Result<(Vec<usize>, Vec<f64>, Vec3), DynamicsError> {
        let j = self.jacobian(param[0])?;
        Ok((j.indices, j.point_derivatives, j.point))
    }

    fn area_normal(&self, param: &[f64]) -> Result<Vec3, DynamicsError> {
        // Curves have no normal; validate the parameter anyway.
        self.point(param[0])?;
        Ok(Vec3::zeros())
    }

    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        Ok([nearest_on_curve(self, x)?, 0.0])
    }
}

impl DnurbsGeometry for NurbsSurface {
    fn rational(&self) -> Option<super::RationalGeometry> {
        Some(super::RationalGeometry::from_surface(self))
    }
    const DIM: usize = 2;
    const PAIRS: usize = 3;

    fn control_point_count(&self) -> usize {
        self.control_points().len()
    }
    fn points(&self) -> &[Vec3] {
        self.control_points()
    }
    fn set_points(&mut self, p: Vec<Vec3>) -> Result<(), DynamicsError> {
        Ok(self.set_control_points(p)?)
    }
    fn max_degree(&self) -> usize {
        let [p, q] = self.degree();
        p.max(q)
    }

    fn element_samples(&self, gauss: &GaussLegendre) -> Vec<ElementSamples> {
        let [ku, kv] = self.knots();
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let (pu, pv) = (p + 1, q + 1);
        let nd = pu * pv;
        let w = self.weights();
        let mut out = Vec::new();
        for &(su, ua, ub) in &spans(ku) {
            for &(sv, va, vb) in &spans(kv) {
                let mut dofs = Vec::with_capacity(nd);
                for a in 0..pu {
                    for b in 0..pv {
                        dofs.push((su - p + a) * nv + sv - q + b);
                    }
                }
                let mut e = ElementSamples {
                    dofs,
                    params: vec![],
                    weights: vec![],
                    values: vec![],
                    first: vec![],
                    second: vec![],
                };
                let upts: Vec<(f64, f64)> = gauss.on_interval(ua, ub).collect();
                let vpts: Vec<(f64, f64)> = gauss.on_interval(va, vb).collect();
                for &(u, wu) in &upts {
                    let du = axis_basis(ku, su, u);
                    for &(v, wv) in &vpts {
                        let dv = axis_basis(kv, sv, v);
                        // Tensor-product non-rational derivatives N, N_u, N_v, N_uu, N_uv, N_vv.
                        let mut nb = [
                            vec![0.0; nd],
                            vec![0.0; nd],
                            vec![0.0; nd],
                            vec![0.0; nd],
                            vec![0.0; nd],
                            vec![0.0; nd],
                        ];
                        let mut ws = [0.0; 6];
                        for a in 0..pu {
                            for b in 0..pv {
                                let k = a * pv + b;
                                let wi = w[e.dofs[k]];
                                let vals = [
                                    du[a] * dv[b],
                                    du[pu + a] * dv[b],
                                    du[a] * dv[pv + b],
                                    du[2 * pu + a] * dv[b],
                                    du[pu + a] * dv[pv + b],
                                    du[a] * dv[2 * pv + b],
                                ];
                                for (c, val) in vals.iter().enumerate() {
                                    nb[c][k] = wi * val;
                                    ws[c] += wi * val;
                                }
                            }
                        }
                        let w0 = ws[0];
                        let r: Vec<f64> = (0..nd).map(|k| nb[0][k] / w0).collect();
                        let ru: Vec<f64> =
                            (0..nd).map(|k| (nb[1][k] - r[k] * ws[1]) / w0).collect();
                        let rv: Vec<f64> =
                            (0..nd).map(|k| (nb[2][k] - r[k] * ws[2]) / w0).collect();
                        let ruu: Vec<f64> = (0..nd)
                            .map(|k| (nb[3][k] - 2.0 * ru[k] * ws[1] - r[k] * ws[3]) / w0)
                            .collect();
                        let ruv: Vec<f64> = (0..nd)
                            .map(|k| (nb[4][k] - ru[k] * ws[2] - rv[k] * ws[1] - r[k] * ws[4]) / w0)
                            .collect();
                        let rvv: Vec<f64> = (0..nd)
                            .map(|k| (nb[5][k] - 2.0 * rv[k] * ws[2] - r[k] * ws[5]) / w0)
                            .collect();
                        e.params.push([u, v]);
                        e.weights.push(wu * wv);
                        e.values.extend(r);
                        e.first.extend(ru);
                        e.first.extend(rv);
                        e.second.extend(ruu);
                        e.second.extend(ruv);
                        e.second.extend(rvv);
                    }
                }
                out.push(e);
            }
        }
        out
    }

    fn basis_at(&self, param: &[f64]) -> Result<(Vec<usize>, Vec<f64>, Vec3), DynamicsError> {
        let j = self.jacobian(param[0], param[1])?;
        Ok((j.indices, j.point_derivatives, j.point))
    }

    fn area_normal(&self, param: &[f64]) -> Result<Vec3, DynamicsError> {
        let d = self.derivatives(param[0], param[1], 1)?;
        Ok(d[1][0].cross(&d[0][1]))
    }

    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        nearest_on_surface(self, x)
    }
}

/// A closed (periodic) NURBS curve: `n` distinct control points, the first `p` repeated at the end
/// over uniform knots, so the curve closes with `C^(p-1)` continuity. Its D-NURBS degrees of
/// freedom are the `n` distinct points (a repeated point is one coordinate, not two).
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedCurve {
    curve: NurbsCurve,
    unique: Vec<Vec3>,
}

impl ClosedCurve {
    /// A closed B-spline curve of `degree` through the control polygon `points` (at least
    /// `degree + 1` points), with the classic integer knots `t_i = i - p`, so the domain is
    /// `[0, n]` and each span has unit length. The D-NURBS energies depend on the
    /// parametrization (tension scales with `1/h`, bending with `1/h^3` for span length `h`);
    /// the parameters of `d-nurbs.txt` Table 1 assume unit spans.
    pub fn new(degree: usize, points: Vec<Vec3>) -> Result<Self, DynamicsError> {
        let n = points.len();
        if n < degree + 1 || degree == 0 {
            return Err(DynamicsError::Parameter {
                name: "closed curve control points",
                value: n as f64,
                why: "need degree >= 1 and at least degree + 1 distinct control points",
            });
        }
        let knots: Vec<f64> = (0..n + 2 * degree + 1)
            .map(|i| i as f64 - degree as f64)
            .collect();
        let kv = vclay_spline::KnotVector::new(knots, degree, n + degree)
            .map_err(|source| vclay_spline::SplineError::Knots { axis: 0, source })?;
        let wrapped: Vec<Vec3> = (0..n + degree).map(|i| points[i % n]).collect();
        let curve = NurbsCurve::from_knot_vector(kv, wrapped, vec![1.0; n + degree])?;
        Ok(Self {
            curve,
            unique: points,
        })
    }

    /// The underlying (wrapped) NURBS curve, for evaluation and export.
    pub fn curve(&self) -> &NurbsCurve {
        &self.curve
    }
}

impl DnurbsGeometry for ClosedCurve {
    fn rational(&self) -> Option<super::RationalGeometry> {
        Some(super::RationalGeometry::from_curve(&self.curve))
    }
    const DIM: usize = 1;
    const PAIRS: usize = 1;

    fn control_point_count(&self) -> usize {
        self.unique.len()
    }
    fn points(&self) -> &[Vec3] {
        &self.unique
    }
    fn set_points(&mut self, p: Vec<Vec3>) -> Result<(), DynamicsError> {
        let n = p.len();
        let deg = self.curve.degree();
        let wrapped: Vec<Vec3> = (0..n + deg).map(|i| p[i % n]).collect();
        self.curve.set_control_points(wrapped)?;
        self.unique = p;
        Ok(())
    }
    fn max_degree(&self) -> usize {
        self.curve.degree()
    }
    fn element_samples(&self, gauss: &GaussLegendre) -> Vec<ElementSamples> {
        let n = self.unique.len();
        let mut s = self.curve.element_samples(gauss);
        for e in &mut s {
            for d in &mut e.dofs {
                *d %= n;
            }
        }
        s
    }
    fn basis_at(&self, param: &[f64]) -> Result<(Vec<usize>, Vec<f64>, Vec3), DynamicsError> {
        let (idx, r, x) = self.curve.basis_at(param)?;
        let n = self.unique.len();
        Ok((idx.into_iter().map(|i| i % n).collect(), r, x))
    }
    fn area_normal(&self, param: &[f64]) -> Result<Vec3, DynamicsError> {
        self.curve.area_normal(param)
    }
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        self.curve.nearest_param(x)
    }
}

/// Number of samples per knot span used to seed closest-point searches on curves.
pub const NEAREST_SAMPLES_PER_SPAN: usize = 16;
/// Number of samples per knot span and direction used to seed closest-point searches on
/// surfaces (Newton refines from the best sample).
pub const NEAREST_SURFACE_SAMPLES_PER_SPAN: usize = 6;
/// Newton iterations of closest-point searches.
pub const NEAREST_NEWTON_STEPS: usize = 8;

/// Closest point on a curve: dense sampling, then Newton on `(c(u) - x) . c'(u) = 0`, clamped to
/// the domain.
pub(crate) fn nearest_on_curve(c: &NurbsCurve, x: &Vec3) -> Result<f64, DynamicsError> {
    let dom = c.domain();
    let spans = c.knots().distinct().len().max(2) - 1;
    let m = NEAREST_SAMPLES_PER_SPAN * spans;
    let mut best = (f64::INFINITY, dom.min);
    for i in 0..=m {
        let u = dom.min + dom.length() * i as f64 / m as f64;
        let d = (c.point(u)? - x).norm_squared();
        if d < best.0 {
            best = (d, u);
        }
    }
    let mut u = best.1;
    for _ in 0..NEAREST_NEWTON_STEPS {
        let d = c.derivatives(u, 2)?;
        let r = d[0] - x;
        let g = r.dot(&d[1]);
        let h = d[1].norm_squared() + r.dot(&d[2]);
        if h <= 0.0 {
            break;
        }
        u = dom.clamp(u - g / h);
    }
    Ok(u)
}

/// Closest point on a surface: dense sampling, then Newton on the 2x2 normal equations.
pub(crate) fn nearest_on_surface(s: &NurbsSurface, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
    let [du, dv] = s.domain();
    let nu = NEAREST_SURFACE_SAMPLES_PER_SPAN * (s.knots()[0].distinct().len().max(2) - 1);
    let nv = NEAREST_SURFACE_SAMPLES_PER_SPAN * (s.knots()[1].distinct().len().max(2) - 1);
    let us = du.linspace(nu + 1);
    let vs = dv.linspace(nv + 1);
    let grid = s.eval_grid(&us, &vs, vclay_core::Parallelism::Auto)?;
    let k = grid
        .iter()
        .enumerate()
        .map(|(k, p)| (k, (p - x).norm_squared()))
        .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
        .0;
    let (mut u, mut v) = (us[k / vs.len()], vs[k % vs.len()]);
    for _ in 0..NEAREST_NEWTON_STEPS {
        let d = s.derivatives(u, v, 2)?;
        let r = d[0][0] - x;
        let g = nalgebra::Vector2::new(r.dot(&d[1][0]), r.dot(&d[0][1]));
        let h = nalgebra::Matrix2::new(
            d[1][0].norm_squared() + r.dot(&d[2][0]),
            d[1][0].dot(&d[0][1]) + r.dot(&d[1][1]),
            d[1][0].dot(&d[0][1]) + r.dot(&d[1][1]),
            d[0][1].norm_squared() + r.dot(&d[0][2]),
        );
        let Some(step) = h.lu().solve(&g) else { break };
        u = du.clamp(u - step.x);
        v = dv.clamp(v - step.y);
    }
    Ok([u, v])
}
