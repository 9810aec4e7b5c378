//! Bivariate simplex splines by Micchelli's recurrence, with derivatives up to second order.
//!
//! ## What
//! The simplex spline `M(x | V)` of degree `n` over a set `V = {v_0, ..., v_{n+2}}` of `n + 3`
//! knots in the plane (the building block of the DMS triangular B-splines of `d-nurbs.txt`
//! eq 10, cited there as [7]; Dahmen, Micchelli & Seidel 1992; Micchelli 1979).
//!
//! ## How: the recurrence (normalization of Fong & Seidel 1993)
//! ```text
//! degree 0:  M(x | a, b, c) = chi_[a,b,c)(x) / |d(a, b, c)|     d = det(b - a, c - a)
//! degree n:  M(x | V) = sum_{j=0..2} lambda_j(x) M(x | V \ {w_j})
//! ```
//! where `W = {w_0, w_1, w_2}` are any three affinely independent knots of `V` and `lambda_j(x)`
//! the barycentric coordinates of `x` with respect to `W` (`x = sum lambda_j w_j`,
//! `sum lambda_j = 1`). The result does not depend on the choice of `W` (Micchelli's
//! identity); vclay chooses the triple of largest `|d|` for conditioning. The directional
//! derivative along `e = sum mu_j w_j` with `sum mu_j = 0` (so `mu_j = grad lambda_j . e`) is
//!
//! ```text
//! D_e M(x | V) = n sum_j mu_j M(x | V \ {w_j})
//! ```
//! and applying it twice gives the second derivatives from the first derivatives of the
//! children: `D_f D_e M = n sum_j mu_j(e) D_f M(x | V \ {w_j})`. Every node of the recursion
//! therefore stores `(M, M_u, M_v, M_uu, M_uv, M_vv)` computed from the `(M, M_u, M_v)` of its
//! three children.
//!
//! The sub-splines of a recursion are identified by their knot sets, so a [`SimplexDag`] holds
//! each distinct one once and any number of splines that share knots (the DMS basis functions
//! of one triangle share most of theirs) are evaluated together, leaves first.
//!
//! ## Points on knot lines (half-open convention)
//! `chi_[a,b,c)` is the half-open triangle: a point `x` counts as inside when `x + eps (1, eps)`
//! is inside for all small `eps > 0` (lexicographic perturbation). A point on an edge belongs to
//! the triangle whose inward edge normal `n` has `n_u > 0`, or `n_u = 0` and `n_v > 0`. Two
//! triangles that share an edge from opposite sides therefore never both contain a point of
//! it, and a triangulation's half-open triangles partition the plane, so sums of simplex
//! splines (the DMS partition of unity) hold on knot lines too, and values there are the limits
//! from the direction `(1, eps)`. A point counts as on an edge when its distance to the edge's
//! line is below [`SimplexDag::line_tolerance`] (`ON_LINE_TOLERANCE` times the knot extent), so
//! points computed with rounding (midpoints, vertices) follow the convention too.
//!
//! ## Limitations
//! Knots of one spline must be in general position (no three collinear, checked when nodes are
//! built: [`SimplexError::Collinear`]); degree at most [`MAX_SIMPLEX_DEGREE`].

use std::collections::HashMap;
use thiserror::Error;

/// A point of the parameter plane.
pub type Point2 = [f64; 2];

/// Highest degree of a simplex spline (`n + 3 <= 32` knots fit the node keys; the cost grows
/// like the number of knot subsets, so practical degrees are far lower).
pub const MAX_SIMPLEX_DEGREE: usize = 8;

/// Distances to a knot line below this fraction of the knot extent count as on the line (see
/// the module docs).
pub const ON_LINE_TOLERANCE: f64 = 1e-12;

/// Smallest `|d(a, b, c)|` relative to the squared knot extent for a knot triple to count as
/// non-collinear.
pub const COLLINEAR_TOLERANCE: f64 = 1e-12;

/// Problems with simplex-spline knots.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SimplexError {
    /// Wrong number of knots for a simplex spline.
    #[error("a simplex spline needs between 3 and {max} knots, {found} given")]
    KnotCount {
        /// Knots given.
        found: usize,
        /// Largest number allowed.
        max: usize,
    },
    /// A knot coordinate is NaN or infinite.
    #[error("knot {index} is not finite")]
    NonFinite {
        /// Index of the knot.
        index: usize,
    },
    /// Three knots of one spline are collinear (or two coincide).
    #[error(
        "knots {a}, {b} and {c} are collinear (|det| = {det:e}); simplex-spline knots must be in general position"
    )]
    Collinear {
        /// First knot.
        a: usize,
        /// Second knot.
        b: usize,
        /// Third knot.
        c: usize,
        /// `|d(a, b, c)|`.
        det: f64,
    },
}

/// `d(a, b, c) = det(b - a, c - a)`, twice the signed area.
pub fn det3(a: Point2, b: Point2, c: Point2) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[derive(Clone, Debug)]
enum NodeKind {
    /// A degree-0 spline: CCW triangle, its `1 / |d|`.
    Leaf { tri: [Point2; 3], inv_det: f64 },
    /// `children[j] = V \ {w_j}`, `lam[j] = (a_u, a_v, b)` with `lambda_j(x) = a . x + b`.
    Inner {
        children: [u32; 3],
        lam: [[f64; 3]; 3],
        degree: f64,
    },
}

#[derive(Clone, Debug)]
struct Node {
    kind: NodeKind,
}

/// A set of simplex splines over knots of one global list, each distinct knot subset held
/// once (see the module docs).
#[derive(Clone, Debug)]
pub struct SimplexDag {
    knots: Vec<Point2>,
    nodes: Vec<Node>,
    index: HashMap<Vec<u32>, u32>,
    line_tol: f64,
    det_tol: f64,
}

impl SimplexDag {
    /// A DAG over a global knot list (validated finite; extent sets the tolerances).
    pub fn new(knots: Vec<Point2>) -> Result<Self, SimplexError> {
        if let Some(i) = knots
            .iter()
            .position(|k| !(k[0].is_finite() && k[1].is_finite()))
        {
            return Err(SimplexError::NonFinite { index: i });
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for k in &knots {
            for a in 0..2 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let extent = if knots.is_empty() {
            1.0
        } else {
            (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE)
        };
        Ok(Self {
            knots,
            nodes: Vec::new(),
            index: HashMap::new(),
            line_tol: ON_LINE_TOLERANCE * extent,
            det_tol: COLLINEAR_TOLERANCE * extent * extent,
        })
    }

    /// Distance below which a point counts as on a knot line.
    pub fn line_tolerance(&self) -> f64 {
        self.line_tol
    }

    /// The global knots.
    pub fn knots(&self) -> &[Point2] {
        &self.knots
    }

    /// Number of distinct sub-splines held.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether no spline was added.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Adds (or finds) the spline over the knots `ids` (indices into the global list) and
    /// returns its node. Node indices are topologically ordered: children before parents.
    pub fn add(&mut self, ids: &[u32]) -> Result<u32, SimplexError> {
        if ids.len() < 3 || ids.len() > MAX_SIMPLEX_DEGREE + 3 {
            return Err(SimplexError::KnotCount {
                found: ids.len(),
                max: MAX_SIMPLEX_DEGREE + 3,
            });
        }
        if let Some(&i) = ids.iter().find(|&&i| i as usize >= self.knots.len()) {
            return Err(SimplexError::NonFinite { index: i as usize });
        }
        let mut key = ids.to_vec();
        key.sort_unstable();
        self.add_sorted(key)
    }

    fn add_sorted(&mut self, key: Vec<u32>) -> Result<u32, SimplexError> {
        if let Some(&n) = self.index.get(&key) {
            return Ok(n);
        }
        let k = |i: u32| self.knots[i as usize];
        // The best-conditioned triple (largest |d|); all triples must be non-degenerate.
        let mut best = (0usize, 1usize, 2usize, -1.0f64);
        for a in 0..key.len() {
            for b in a + 1..key.len() {
                for c in b + 1..key.len() {
                    let d = det3(k(key[a]), k(key[b]), k(key[c])).abs();
                    if d <= self.det_tol {
                        return Err(SimplexError::Collinear {
                            a: key[a] as usize,
                            b: key[b] as usize,
                            c: key[c] as usize,
                            det: d,
                        });
                    }
                    if d > best.3 {
                        best = (a, b, c, d);
                    }
                }
            }
        }
        let kind = if key.len() == 3 {
            let (a, mut b, mut c) = (k(key[0]), k(key[1]), k(key[2]));
            if det3(a, b, c) < 0.0 {
                std::mem::swap(&mut b, &mut c);
            }
            NodeKind::Leaf {
                tri: [a, b, c],
                inv_det: 1.0 / best.3,
            }
        } else {
            let w = [best.0, best.1, best.2];
            let (p0, p1, p2) = (k(key[w[0]]), k(key[w[1]]), k(key[w[2]]));
            let d = det3(p0, p1, p2);
            // lambda_0 = d(x, p1, p2) / d, lambda_1 = d(p0, x, p2) / d, lambda_2 = d(p0, p1, x) / d.
            let lin = |a: Point2, b: Point2| -> [f64; 3] {
                // d(x, a, b) = (a - x) x (b - x) = a x b - x x (b - a)... written as affine in x.
                let au = a[1] - b[1];
                let av = b[0] - a[0];
                let c0 = a[0] * b[1] - a[1] * b[0];
                [au / d, av / d, c0 / d]
            };
            let lam = [lin(p1, p2), lin(p2, p0), lin(p0, p1)];
            let mut children = [0u32; 3];
            for (j, &wj) in w.iter().enumerate() {
                let sub: Vec<u32> = key
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != wj)
                    .map(|(_, &v)| v)
                    .collect();
                children[j] = self.add_sorted(sub)?;
            }
            NodeKind::Inner {
                children,
                lam,
                degree: (key.len() - 3) as f64,
            }
        };
        let id = self.nodes.len() as u32;
        self.nodes.push(Node { kind });
        self.index.insert(key, id);
        Ok(id)
    }

    /// The nodes a set of roots depends on, sorted (children before parents).
    pub fn closure(&self, roots: &[u32]) -> Vec<u32> {
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<u32> = roots.to_vec();
        while let Some(n) = stack.pop() {
            if std::mem::replace(&mut seen[n as usize], true) {
                continue;
            }
            if let NodeKind::Inner { children, .. } = &self.nodes[n as usize].kind {
                stack.extend_from_slice(children);
            }
        }
        (0..self.nodes.len() as u32)
            .filter(|&i| seen[i as usize])
            .collect()
    }

    /// The knot pairs of every degree-0 triangle among `nodes` (the segments across which the
    /// splines are not polynomial), as coordinates.
    pub fn leaf_segments(&self, nodes: &[u32]) -> Vec<[Point2; 2]> {
        let mut out = Vec::new();
        for &n in nodes {
            if let NodeKind::Leaf { tri, .. } = &self.nodes[n as usize].kind {
                for e in 0..3 {
                    out.push([tri[e], tri[(e + 1) % 3]]);
                }
            }
        }
        out
    }

    /// Whether `x` lies in the half-open triangle `tri` (CCW), see the module docs.
    fn half_open(&self, tri: &[Point2; 3], x: Point2) -> bool {
        for e in 0..3 {
            let p = tri[e];
            let q = tri[(e + 1) % 3];
            let (eu, ev) = (q[0] - p[0], q[1] - p[1]);
            let o = eu * (x[1] - p[1]) - ev * (x[0] - p[0]);
            let len = eu.hypot(ev);
            if o > self.line_tol * len {
                continue;
            }
            if o < -self.line_tol * len {
                return false;
            }
            // On the edge's line: inward normal (-ev, eu).
            let (nu, nv) = (-ev, eu);
            if !(nu > 0.0 || (nu == 0.0 && nv > 0.0)) {
                return false;
            }
        }
        true
    }

    /// Evaluates the nodes `order` (sorted, closed under children, as from
    /// [`SimplexDag::closure`]) at `x`: `out[node] = (M, M_u, M_v, M_uu, M_uv, M_vv)`.
    /// `out` must hold [`SimplexDag::len`] entries; other entries are left as they are.
    pub fn eval_into(&self, order: &[u32], x: Point2, out: &mut [[f64; 6]]) {
        for &n in order {
            let v = match &self.nodes[n as usize].kind {
                NodeKind::Leaf { tri, inv_det } => {
                    if self.half_open(tri, x) {
                        [*inv_det, 0.0, 0.0, 0.0, 0.0, 0.0]
                    } else {
                        [0.0; 6]
                    }
                }
                NodeKind::Inner {
                    children,
                    lam,
                    degree,
                } => {
                    let mut r = [0.0; 6];
                    for j in 0..3 {
                        let c = out[children[j] as usize];
                        let [au, av, b] = lam[j];
                        let l = au * x[0] + av * x[1] + b;
                        r[0] += l * c[0];
                        r[1] += au * c[0];
                        r[2] += av * c[0];
                        r[3] += au * c[1];
                        r[4] += au * c[2];
                        r[5] += av * c[2];
                    }
                    for v in &mut r[1..] {
                        *v *= degree;
                    }
                    r
                }
            };
            out[n as usize] = v;
        }
    }
}

/// One simplex spline `M(x | V)` (see the module docs), for direct use and tests.
#[derive(Clone, Debug)]
pub struct SimplexSpline {
    dag: SimplexDag,
    order: Vec<u32>,
    root: u32,
}

impl SimplexSpline {
    /// The simplex spline of degree `knots.len() - 3` over `knots` (validated: 3 to
    /// `MAX_SIMPLEX_DEGREE + 3` finite knots in general position).
    pub fn new(knots: &[Point2]) -> Result<Self, SimplexError> {
        if knots.len() < 3 || knots.len() > MAX_SIMPLEX_DEGREE + 3 {
            return Err(SimplexError::KnotCount {
                found: knots.len(),
                max: MAX_SIMPLEX_DEGREE + 3,
            });
        }
        let mut dag = SimplexDag::new(knots.to_vec())?;
        let ids: Vec<u32> = (0..knots.len() as u32).collect();
        let root = dag.add(&ids)?;
        let order = dag.closure(&[root]);
        Ok(Self { dag, order, root })
    }

    /// Degree `n = |V| - 3`.
    pub fn degree(&self) -> usize {
        self.dag.knots().len() - 3
    }

    /// `(M, M_u, M_v, M_uu, M_uv, M_vv)` at `x` (half-open convention on knot lines).
    pub fn eval(&self, x: Point2) -> [f64; 6] {
        let mut buf = vec![[0.0; 6]; self.dag.len()];
        self.dag.eval_into(&self.order, x, &mut buf);
        buf[self.root as usize]
    }
}
