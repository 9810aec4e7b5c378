//! The metric-tensor energy of a B-spline solid by Gauss quadrature (beyond the paper, which
//! approximates it with springs: `subdivision-solids-journal.txt` section 4.3 and 5.1).
//!
//! With `s(u, v, w) = sum_k q_k N_k(u, v, w)` and `G = [s_i . s_j]` (`s_i = ds/du_i`),
//!
//! `E = integral c sum_ij (g_ij - g0_ij)^2 du dv dw`
//!
//! (one weight `c` for all entries). Its gradient with respect to control point `q_k`, using the
//! symmetry of `D = G - G0`, is
//!
//! `dE/dq_k = integral 4 c sum_i dN_k/du_i t_i`, `t_i = sum_j D_ij s_j`,
//!
//! so the generalized internal force `-dE/dq_k` is evaluated directly on the control points
//! (no data points needed) from precomputed basis derivatives at `(p+1)(q+1)(r+1)` Gauss points
//! per knot span cell (exact for the polynomial integrand's leading part; the integrand has
//! degree `4 (p - 1)` per direction, so the rule is not exact for cubics and the energy is a
//! quadrature approximation).

use vclay_core::{GaussLegendre, Vec3};
use vclay_spline::{KnotVector, knots::BasisWorkspace};

/// One Gauss point along one axis: first control index, basis values, their derivatives, weight.
type AxisPoint = (usize, Vec<f64>, Vec<f64>, f64);

/// Default weight `c` of the metric-tensor energy (`[material] metric_stiffness`).
pub const DEFAULT_METRIC_STIFFNESS: f64 = 100.0;

/// Precomputed quadrature data of the metric-tensor energy.
#[derive(Clone, Debug)]
pub struct MetricEnergy {
    /// Weight `c`.
    pub stiffness: f64,
    /// Per quadrature point: weight (with the parameter-cell volume), offset into `idx`/`dn`.
    weights: Vec<f64>,
    /// Rest metric per quadrature point (row-major 3x3).
    g0: Vec<[f64; 9]>,
    /// Control indices per quadrature point (`per` each).
    idx: Vec<u32>,
    /// Basis derivatives `[dN/du, dN/dv, dN/dw]` per (point, index).
    dn: Vec<[f64; 3]>,
    per: usize,
}

impl MetricEnergy {
    /// Quadrature data for a B-spline solid with knots `knots` (control index
    /// `(i n_v + j) n_w + k`), rest control points `q0`, weight `c`.
    pub fn new(knots: &[KnotVector; 3], q0: &[Vec3], stiffness: f64) -> Self {
        let dims = knots.each_ref().map(KnotVector::control_points);
        let deg = knots.each_ref().map(KnotVector::degree);
        // Per axis: (first index, values N, derivatives N') at each Gauss point, with weights.
        let axis: Vec<Vec<AxisPoint>> = (0..3)
            .map(|a| {
                let k = &knots[a];
                let p = deg[a];
                let gl = GaussLegendre::new(p + 1).expect("degree + 1 Gauss points");
                let mut ws = BasisWorkspace::new(p);
                let mut out = Vec::new();
                let distinct = k.distinct();
                let dom = k.domain();
                for w in distinct.windows(2) {
                    let (lo, hi) = (w[0].0, w[1].0);
                    if lo < dom.min || hi > dom.max {
                        continue;
                    }
                    for (u, wt) in gl.on_interval(lo, hi) {
                        let span = k.find_span(u);
                        let mut ders = vec![0.0; 2 * (p + 1)];
                        k.basis_derivatives(span, u, 1, &mut ders, &mut ws);
                        out.push((span - p, ders[..=p].to_vec(), ders[p + 1..].to_vec(), wt));
                    }
                }
                out
            })
            .collect();
        let per = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
        let mut m = Self {
            stiffness,
            weights: Vec::new(),
            g0: Vec::new(),
            idx: Vec::new(),
            dn: Vec::new(),
            per,
        };
        for a in &axis[0] {
            for b in &axis[1] {
                for c in &axis[2] {
                    m.weights.push(a.3 * b.3 * c.3);
                    for (i, (na, da)) in a.1.iter().zip(&a.2).enumerate() {
                        for (j, (nb, db)) in b.1.iter().zip(&b.2).enumerate() {
                            for (k, (nc, dc)) in c.1.iter().zip(&c.2).enumerate() {
                                let id = ((a.0 + i) * dims[1] + b.0 + j) * dims[2] + c.0 + k;
                                m.idx.push(id as u32);
                                m.dn.push([da * nb * nc, na * db * nc, na * nb * dc]);
                            }
                        }
                    }
                }
            }
        }
        let n = m.weights.len();
        m.g0 = (0..n).map(|q| metric(&m.tangents(q, q0))).collect();
        m
    }

    /// Number of quadrature points.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether there are no quadrature points.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    fn tangents(&self, q: usize, p: &[Vec3]) -> [Vec3; 3] {
        let mut t = [Vec3::zeros(); 3];
        for r in q * self.per..(q + 1) * self.per {
            let x = p[self.idx[r] as usize];
            for (i, ti) in t.iter_mut().enumerate() {
                *ti += x * self.dn[r][i];
            }
        }
        t
    }

    /// Makes configuration `p` the rest state (plastic reset).
    pub fn reset_rest(&mut self, p: &[Vec3]) {
        for q in 0..self.len() {
            self.g0[q] = metric(&self.tangents(q, p));
        }
    }

    /// Adds the generalized forces `-dE/dq` at control points `p` to `g`; returns `E`.
    pub fn add_forces(&self, p: &[Vec3], g: &mut [Vec3]) -> f64 {
        let mut energy = 0.0;
        for q in 0..self.len() {
            let s = self.tangents(q, p);
            let gq = metric(&s);
            let mut d = [0.0; 9];
            for (e, (a, b)) in d.iter_mut().zip(gq.iter().zip(&self.g0[q])) {
                *e = a - b;
            }
            let cw = self.stiffness * self.weights[q];
            energy += cw * d.iter().map(|x| x * x).sum::<f64>();
            let t: [Vec3; 3] = std::array::from_fn(|i| {
                s[0] * d[3 * i] + s[1] * d[3 * i + 1] + s[2] * d[3 * i + 2]
            });
            for r in q * self.per..(q + 1) * self.per {
                let dn = self.dn[r];
                let f = (t[0] * dn[0] + t[1] * dn[1] + t[2] * dn[2]) * (4.0 * cw);
                g[self.idx[r] as usize] -= f;
            }
        }
        energy
    }
}

fn metric(s: &[Vec3; 3]) -> [f64; 9] {
    std::array::from_fn(|k| s[k / 3].dot(&s[k % 3]))
}
