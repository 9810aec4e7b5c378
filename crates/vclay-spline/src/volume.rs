//! Trivariate (tensor-product) NURBS volumes.
//!
//! ```text
//! V(u, v, w) = sum_ijk W_ijk P_ijk N_i(u) N_j(v) N_k(w) / sum_ijk W_ijk N_i(u) N_j(v) N_k(w)
//! ```
//! (`ffd-direct-manipulation.txt` eqs 1-2; the non-rational case is the B-spline solid of
//! `subdivision-solids-journal.txt` eq 1.)
//!
//! Derivatives of any order by the trivariate quotient rule (the Leibniz rule applied to
//! `A = w V`, generalizing Piegl & Tiller A4.4):
//! `V^(a,b,c) = (A^(a,b,c) - sum_{(i,j,k) != 0} C(a,i) C(b,j) C(c,k) w^(i,j,k) V^(a-i,b-j,c-k)) / w`.
//! First derivatives give the metric tensor `g = J^T J` of `subdivision-solids-journal.txt`
//! section 4.3.
//!
//! The net is stored flat, index `(i * n_v + j) * n_w + k`.

use crate::error::SplineError;
use crate::jacobian::SparseJacobian;
use crate::knots::{BasisWorkspace, KnotVector, MAX_DEGREE};
use crate::surface::flatten2;
use crate::traits::ParametricVolume;
use crate::util::{BasisBuf, check_net, check_param, homogeneous};
use vclay_core::math::binomial;
use vclay_core::{Interval, Vec3, Vec4};

/// A trivariate NURBS volume of degrees `(p, q, r)` with an `n_u x n_v x n_w` control net.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsVolume {
    knots: [KnotVector; 3],
    points: Vec<Vec3>,
    weights: Vec<f64>,
}

fn flatten3<T: Clone>(
    net: &[Vec<Vec<T>>],
    what: &str,
) -> Result<(Vec<T>, [usize; 3]), SplineError> {
    let n0 = net.len();
    let (n1, n2) = net
        .first()
        .map_or((0, 0), |s| (s.len(), s.first().map_or(0, Vec::len)));
    let mut flat = Vec::with_capacity(n0 * n1 * n2);
    for (i, slab) in net.iter().enumerate() {
        let (f, d) = flatten2(slab, &format!("{what}[{i}]"))?;
        if d[0] != n1 {
            return Err(SplineError::Shape {
                what: format!("length of {what}[{i}]"),
                found: d[0],
                expected: n1,
            });
        }
        if d[1] != n2 {
            return Err(SplineError::Shape {
                what: format!("length of {what}[{i}][0]"),
                found: d[1],
                expected: n2,
            });
        }
        flat.extend(f);
    }
    Ok((flat, [n0, n1, n2]))
}

impl NurbsVolume {
    /// A volume from degrees, knot vectors, a nested net `points[i][j][k]` and optional weights
    /// of the same shape (all 1 when `None`).
    pub fn new(
        degree: [usize; 3],
        knots: [Vec<f64>; 3],
        points: Vec<Vec<Vec<Vec3>>>,
        weights: Option<Vec<Vec<Vec<f64>>>>,
    ) -> Result<Self, SplineError> {
        let (flat, dims) = flatten3(&points, "control_points")?;
        let w = match weights {
            Some(w) => {
                let (wf, wd) = flatten3(&w, "weights")?;
                if wd != dims {
                    let axis = (0..3).find(|&a| wd[a] != dims[a]).unwrap_or(0);
                    return Err(SplineError::Shape {
                        what: format!("weights size along axis {axis}"),
                        found: wd[axis],
                        expected: dims[axis],
                    });
                }
                wf
            }
            None => vec![1.0; flat.len()],
        };
        let mut kvs = Vec::with_capacity(3);
        for (axis, k) in knots.into_iter().enumerate() {
            kvs.push(
                KnotVector::new(k, degree[axis], dims[axis])
                    .map_err(|source| SplineError::Knots { axis, source })?,
            );
        }
        let [a, b, c]: [KnotVector; 3] = kvs.try_into().expect("three knot vectors");
        Self::from_flat([a, b, c], flat, w)
    }

    /// A volume from validated knot vectors and a flat net.
    pub fn from_flat(
        knots: [KnotVector; 3],
        points: Vec<Vec3>,
        weights: Vec<f64>,
    ) -> Result<Self, SplineError> {
        let dims = knots.each_ref().map(KnotVector::control_points);
        check_net(&points, &weights, &dims)?;
        Ok(Self {
            knots,
            points,
            weights,
        })
    }

    /// The identity-like lattice of `ffd-direct-manipulation.txt` section 2: clamped uniform knots
    /// on `[0, 1]^3`, unit weights and control points at the Greville abscissae mapped affinely
    /// onto the box `[lo, hi]`, so that `V(u, v, w) = lo + (hi - lo) * (u, v, w)` exactly.
    pub fn box_lattice(
        degree: [usize; 3],
        dims: [usize; 3],
        lo: Vec3,
        hi: Vec3,
    ) -> Result<Self, SplineError> {
        let mut kvs = Vec::with_capacity(3);
        for axis in 0..3 {
            kvs.push(
                KnotVector::clamped_uniform(degree[axis], dims[axis])
                    .map_err(|source| SplineError::Knots { axis, source })?,
            );
        }
        let g: Vec<Vec<f64>> = kvs.iter().map(KnotVector::greville).collect();
        let mut pts = Vec::with_capacity(dims.iter().product());
        for i in 0..dims[0] {
            for j in 0..dims[1] {
                for k in 0..dims[2] {
                    let t = Vec3::new(g[0][i], g[1][j], g[2][k]);
                    pts.push(lo + (hi - lo).component_mul(&t));
                }
            }
        }
        let [a, b, c]: [KnotVector; 3] = kvs.try_into().expect("three knot vectors");
        let w = vec![1.0; pts.len()];
        Self::from_flat([a, b, c], pts, w)
    }

    pub(crate) fn from_homogeneous(
        knots: [KnotVector; 3],
        pw: &[Vec4],
    ) -> Result<Self, SplineError> {
        let (p, w) = crate::util::dehomogenize(pw);
        Self::from_flat(knots, p, w)
    }

    /// Degrees `(p, q, r)`.
    pub fn degree(&self) -> [usize; 3] {
        self.knots.each_ref().map(KnotVector::degree)
    }
    /// Knot vectors along u, v, w.
    pub fn knots(&self) -> &[KnotVector; 3] {
        &self.knots
    }
    /// Net size `(n_u, n_v, n_w)`.
    pub fn dims(&self) -> [usize; 3] {
        self.knots.each_ref().map(KnotVector::control_points)
    }
    /// Flat control points, index `(i * n_v + j) * n_w + k`.
    pub fn control_points(&self) -> &[Vec3] {
        &self.points
    }
    /// Flat weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
    /// Control point `P_ijk`.
    pub fn control_point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        let [_, nv, nw] = self.dims();
        self.points[(i * nv + j) * nw + k]
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

    /// The D-NURBS-style Jacobian at `(u, v, w)`, restricted to its `(p+1)(q+1)(r+1)` non-zero
    /// blocks (`R_ijk` of `ffd-direct-manipulation.txt` eq 2, and the weight derivatives).
    pub fn jacobian(&self, u: f64, v: f64, w: f64) -> Result<SparseJacobian, SplineError> {
        let t = [
            check_param(&self.knots[0], 0, u)?,
            check_param(&self.knots[1], 1, v)?,
            check_param(&self.knots[2], 2, w)?,
        ];
        let deg = self.degree();
        let [_, nv, nw] = self.dims();
        let spans = [0, 1, 2].map(|a| self.knots[a].find_span(t[a]));
        let mut b: [BasisBuf; 3] = [[0.0; MAX_DEGREE + 1]; 3];
        for a in 0..3 {
            self.knots[a].basis(spans[a], t[a], &mut b[a]);
        }
        let n = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
        let mut idx = Vec::with_capacity(n);
        let mut basis = Vec::with_capacity(n);
        for a in 0..=deg[0] {
            for c in 0..=deg[1] {
                for e in 0..=deg[2] {
                    let i = spans[0] - deg[0] + a;
                    let j = spans[1] - deg[1] + c;
                    let k = spans[2] - deg[2] + e;
                    idx.push((i * nv + j) * nw + k);
                    basis.push(b[0][a] * b[1][c] * b[2][e]);
                }
            }
        }
        Ok(SparseJacobian::from_basis(
            idx,
            &basis,
            &self.points,
            &self.weights,
        ))
    }

    fn homogeneous_derivatives(&self, t: [f64; 3], order: usize) -> Vec<Vec<Vec<Vec4>>> {
        let deg = self.degree();
        let [_, nv, nw] = self.dims();
        let spans = [0, 1, 2].map(|a| self.knots[a].find_span(t[a]));
        let dmax = [0, 1, 2].map(|a| order.min(deg[a]));
        let mut ws = BasisWorkspace::new(deg[0].max(deg[1]).max(deg[2]));
        let nd: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                let mut d = vec![0.0; (dmax[a] + 1) * (deg[a] + 1)];
                self.knots[a].basis_derivatives(spans[a], t[a], dmax[a], &mut d, &mut ws);
                d
            })
            .collect();
        let mut out: Vec<Vec<Vec<Vec4>>> = (0..=order)
            .map(|a| {
                (0..=order - a)
                    .map(|b| vec![Vec4::zeros(); order - a - b + 1])
                    .collect()
            })
            .collect();
        for da in 0..=dmax[0] {
            for db in 0..=dmax[1].min(order - da) {
                for dc in 0..=dmax[2].min(order - da - db) {
                    let mut acc = Vec4::zeros();
                    for a in 0..=deg[0] {
                        let ba = nd[0][da * (deg[0] + 1) + a];
                        if ba == 0.0 {
                            continue;
                        }
                        for c in 0..=deg[1] {
                            let bc = ba * nd[1][db * (deg[1] + 1) + c];
                            for e in 0..=deg[2] {
                                let be = bc * nd[2][dc * (deg[2] + 1) + e];
                                let i = spans[0] - deg[0] + a;
                                let j = spans[1] - deg[1] + c;
                                let k = spans[2] - deg[2] + e;
                                let id = (i * nv + j) * nw + k;
                                let w = self.weights[id] * be;
                                let p = self.points[id];
                                acc += Vec4::new(p.x * w, p.y * w, p.z * w, w);
                            }
                        }
                    }
                    out[da][db][dc] = acc;
                }
            }
        }
        out
    }
}

impl ParametricVolume for NurbsVolume {
    fn domain(&self) -> [Interval; 3] {
        self.knots.each_ref().map(KnotVector::domain)
    }

    fn point(&self, u: f64, v: f64, w: f64) -> Result<Vec3, SplineError> {
        Ok(self.jacobian(u, v, w)?.point)
    }

    fn derivatives(
        &self,
        u: f64,
        v: f64,
        w: f64,
        order: usize,
    ) -> Result<Vec<Vec<Vec<Vec3>>>, SplineError> {
        crate::util::check_order(order)?;
        let t = [
            check_param(&self.knots[0], 0, u)?,
            check_param(&self.knots[1], 1, v)?,
            check_param(&self.knots[2], 2, w)?,
        ];
        let a = self.homogeneous_derivatives(t, order);
        let w0 = a[0][0][0].w;
        let mut s: Vec<Vec<Vec<Vec3>>> = (0..=order)
            .map(|x| {
                (0..=order - x)
                    .map(|y| vec![Vec3::zeros(); order - x - y + 1])
                    .collect()
            })
            .collect();
        for tot in 0..=order {
            for da in 0..=tot {
                for db in 0..=tot - da {
                    let dc = tot - da - db;
                    let mut v = a[da][db][dc].xyz();
                    for i in 0..=da {
                        for j in 0..=db {
                            for k in 0..=dc {
                                if i + j + k == 0 {
                                    continue;
                                }
                                let c = binomial(da, i) * binomial(db, j) * binomial(dc, k);
                                v -= c * a[i][j][k].w * s[da - i][db - j][dc - k];
                            }
                        }
                    }
                    s[da][db][dc] = v / w0;
                }
            }
        }
        Ok(s)
    }
}
