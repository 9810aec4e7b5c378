//! Triangular B-splines (DMS splines) and triangular NURBS over an arbitrary triangulation.
//!
//! ## What (`d-nurbs.txt` section 4.4, eqs 10-14)
//! A triangulation `T` of the parameter domain; a cloud of knots `v_0 = v, v_1, ..., v_n` at
//! every domain vertex `v`; for every triangle `I = [r, s, t]` and every `beta` with
//! `|beta| = n` the knot set `V_{I,beta} = {r_0..r_b0, s_0..s_b1, t_0..t_b2}` and the basis
//! function (eq 10)
//!
//! ```text
//! N_{I,beta}(u) = |d(r_b0, s_b1, t_b2)| M(u | V_{I,beta})
//! ```
//! with `M` the bivariate simplex spline of degree `n` ([`crate::simplex`]). The rational
//! surface (eq 11) is `s(u) = sum p w N / sum w N`; its Jacobian (eq 13) has the columns
//! `R_k = w_k N_k / W` (control point `k`) and `(p_k - s) N_k / W` (weight `k`), and
//! `s = J p` (eq 14).
//!
//! Optionally several basis functions share one control point (a control map): the paper's
//! "continuous net" of the edge rounding (section 7.3), where the 36 functions of 6 quadratic
//! triangles drive 21 control points. The shared point's basis function is the sum of the
//! functions mapped to it ([`TriangularBasis::bezier_net_map`] builds the map that joins the
//! functions at the same Bezier domain point).
//!
//! ## How
//! All simplex splines of all basis functions live in one [`SimplexDag`] keyed by knot subsets,
//! so the `(n+1)(n+2)/2` functions of a triangle and the functions of neighbouring triangles
//! share their sub-splines (the evaluation strategy of Fong & Seidel 1993). Per domain triangle
//! (an element) the functions whose support (the convex hull of their knots) meets it and the
//! sub-splines they need are listed once; evaluating at a point evaluates that list once, giving
//! every non-zero basis function with its derivatives up to second order.
//!
//! ## Knot clouds (validated)
//! Every cloud has `n + 1` knots, the first at its vertex. For every triangle and every
//! `beta` with `|beta| <= n` the triangle `[r_b0, s_b1, t_b2]` must be non-degenerate with the
//! orientation of the domain triangle (the DMS condition), and the `n + 3` knots of every
//! `V_{I,beta}` must be in general position. Under these conditions the basis functions sum to
//! one on the domain (partition of unity) and reproduce polynomials of degree `n` with the
//! blossom control points `p_{I,beta} = F[r_0..r_{b0-1}, s_0..s_{b1-1}, t_0..t_{b2-1}]`
//! (Dahmen, Micchelli & Seidel 1992), provided the knots of boundary vertices lie on the outer
//! side of the boundary edges at the vertex (see [`KnotClouds::around_vertices`], which places
//! clouds this way); both are tested, on knot lines too.
//!
//! When every cloud shrinks onto its vertex the DMS functions of a triangle tend to the
//! Bernstein polynomials of that triangle (tested against de Casteljau); an exactly collapsed
//! cloud is not allowed (the simplex splines would be degenerate), a radius of `1e-4` of the
//! edge length is enough to match the Bezier triangle to `1e-3`.
//!
//! ## Limitations
//! Point location is a linear scan over the triangles (fine for the hundreds of triangles of
//! interactive models); degree at most [`MAX_TRIANGULAR_DEGREE`]; triangles at most
//! [`MAX_TRIANGLES`].

use crate::simplex::{Point2, SimplexDag, SimplexError, det3};
use std::sync::Arc;
use thiserror::Error;
use vclay_core::{MeshSink, Vec3};

/// Highest degree of a triangular B-spline.
pub const MAX_TRIANGULAR_DEGREE: usize = 5;
/// Most domain triangles.
pub const MAX_TRIANGLES: usize = 4096;
/// Relative area (of the squared domain extent) below which a domain triangle is degenerate.
pub const DEGENERATE_AREA: f64 = 1e-12;
/// Tolerance, relative to the domain extent, of point location and support tests.
pub const DOMAIN_TOLERANCE: f64 = 1e-9;
/// Default radius of automatic knot clouds, as a fraction of the shortest edge at the vertex.
pub const DEFAULT_CLOUD_RADIUS: f64 = 0.1;

/// Problems with a triangulation, knot clouds or a triangular NURBS.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum TriangularError {
    /// Degree out of range.
    #[error("degree {degree} is outside 1..={max}")]
    Degree {
        /// Requested degree.
        degree: usize,
        /// Largest supported.
        max: usize,
    },
    /// A count exceeds its limit or is zero.
    #[error("{what}: {count} (allowed 1..={max})")]
    Count {
        /// What was counted.
        what: &'static str,
        /// The count.
        count: usize,
        /// Largest allowed.
        max: usize,
    },
    /// A domain vertex is not finite.
    #[error("domain vertex {vertex} is not finite")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A triangle references a missing vertex.
    #[error("triangle {triangle} references vertex {index}, but there are {count} vertices")]
    VertexIndex {
        /// Triangle index.
        triangle: usize,
        /// Referenced vertex.
        index: usize,
        /// Number of vertices.
        count: usize,
    },
    /// A triangle has (nearly) zero area or repeats a vertex.
    #[error("triangle {triangle} is degenerate (area {area:e})")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
        /// Its area.
        area: f64,
    },
    /// Two triangles overlap.
    #[error("triangles {a} and {b} overlap")]
    Overlap {
        /// First triangle.
        a: usize,
        /// Second triangle.
        b: usize,
    },
    /// An edge is used by more than two triangles, or twice from the same side.
    #[error("edge ({a}, {b}) is not manifold: used by triangles {triangles:?}")]
    NonManifoldEdge {
        /// First vertex.
        a: usize,
        /// Second vertex.
        b: usize,
        /// Triangles using it.
        triangles: Vec<usize>,
    },
    /// A vertex belongs to no triangle.
    #[error("domain vertex {vertex} belongs to no triangle")]
    UnusedVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// A knot cloud has the wrong size.
    #[error("knot cloud of vertex {vertex} has {found} knots, expected degree + 1 = {expected}")]
    CloudSize {
        /// Vertex index.
        vertex: usize,
        /// Knots given.
        found: usize,
        /// Knots required.
        expected: usize,
    },
    /// A knot cloud does not start at its vertex, or a knot is not finite.
    #[error("knot cloud of vertex {vertex}: {why}")]
    Cloud {
        /// Vertex index.
        vertex: usize,
        /// What is wrong.
        why: &'static str,
    },
    /// The knots of a basis function are not in general position.
    #[error("triangle {triangle}, beta {beta:?}: {source}")]
    Knots {
        /// Triangle index.
        triangle: usize,
        /// The multi-index.
        beta: [usize; 3],
        /// What is wrong.
        #[source]
        source: SimplexError,
    },
    /// A knot triangle `[r_b0, s_b1, t_b2]` is degenerate or flipped against its domain
    /// triangle (the DMS condition).
    #[error(
        "triangle {triangle}, beta {beta:?}: knot triangle [r_{}, s_{}, t_{}] is degenerate or flipped against the domain triangle",
        beta[0], beta[1], beta[2]
    )]
    KnotTriangle {
        /// Triangle index.
        triangle: usize,
        /// The multi-index (`|beta| <= n`).
        beta: [usize; 3],
    },
    /// Control data of the wrong size.
    #[error("{what}: found {found}, expected {expected}")]
    Shape {
        /// What was counted.
        what: &'static str,
        /// Count found.
        found: usize,
        /// Count expected.
        expected: usize,
    },
    /// A control map entry points past the control points.
    #[error("basis function {function} maps to control point {index}, but there are {count}")]
    ControlMap {
        /// Basis function.
        function: usize,
        /// Its control point.
        index: usize,
        /// Number of control points.
        count: usize,
    },
    /// A control point is not finite.
    #[error("control point {index} has a non-finite coordinate")]
    NonFiniteControlPoint {
        /// Index.
        index: usize,
    },
    /// A weight is not positive and finite.
    #[error("weight {index} is {value}, weights must be positive and finite")]
    NonPositiveWeight {
        /// Index.
        index: usize,
        /// Value.
        value: f64,
    },
    /// A parameter lies outside the triangulated domain or is not finite.
    #[error("parameter ({u}, {v}) lies outside the triangulated domain")]
    OutsideDomain {
        /// u.
        u: f64,
        /// v.
        v: f64,
    },
    /// All basis functions vanish at a parameter (`sum w N = 0`).
    #[error("no basis function is non-zero at ({u}, {v})")]
    ZeroDenominator {
        /// u.
        u: f64,
        /// v.
        v: f64,
    },
}

/// A validated triangulation of the parameter domain, triangles stored counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangulation {
    vertices: Vec<Point2>,
    triangles: Vec<[usize; 3]>,
    extent: f64,
}

fn bbox(points: &[Point2]) -> [Point2; 2] {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    [lo, hi]
}

/// Whether two convex polygons (CCW) overlap by more than `tol` (separating axis test).
fn convex_overlap(a: &[Point2], b: &[Point2], tol: f64) -> bool {
    for (p, q) in [(a, b), (b, a)] {
        for i in 0..p.len() {
            let e0 = p[i];
            let e1 = p[(i + 1) % p.len()];
            let (eu, ev) = (e1[0] - e0[0], e1[1] - e0[1]);
            let len = eu.hypot(ev);
            if len == 0.0 {
                continue;
            }
            // Outward normal of a CCW polygon: (ev, -eu).
            let (nu, nv) = (ev / len, -eu / len);
            let dist = |x: &Point2| (x[0] - e0[0]) * nu + (x[1] - e0[1]) * nv;
            if q.iter().all(|x| dist(x) >= -tol) {
                return false;
            }
        }
    }
    true
}

/// Convex hull (counter-clockwise, Andrew's monotone chain; collinear points dropped). Fewer
/// than three distinct points are returned as they are, sorted.
pub fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<Point2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &Point2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &x in it {
            while h.len() >= start + 2 && det3(h[h.len() - 2], h[h.len() - 1], x) <= 0.0 {
                h.pop();
            }
            h.push(x);
        }
        h.pop();
    }
    h
}

impl Triangulation {
    /// Validates and stores a triangulation: finite vertices, indices in range, every vertex
    /// used, non-degenerate triangles (reoriented counter-clockwise), manifold edges, no
    /// overlapping triangles. Errors name the vertex, triangle or edge.
    pub fn new(vertices: Vec<Point2>, triangles: Vec<[usize; 3]>) -> Result<Self, TriangularError> {
        if triangles.is_empty() || triangles.len() > MAX_TRIANGLES {
            return Err(TriangularError::Count {
                what: "triangles",
                count: triangles.len(),
                max: MAX_TRIANGLES,
            });
        }
        if vertices.len() > 3 * MAX_TRIANGLES {
            return Err(TriangularError::Count {
                what: "domain vertices",
                count: vertices.len(),
                max: 3 * MAX_TRIANGLES,
            });
        }
        if let Some(v) = vertices
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(TriangularError::NonFiniteVertex { vertex: v });
        }
        let [lo, hi] = bbox(&vertices);
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let mut tris = triangles;
        let mut used = vec![false; vertices.len()];
        for (t, tri) in tris.iter_mut().enumerate() {
            for &i in tri.iter() {
                if i >= vertices.len() {
                    return Err(TriangularError::VertexIndex {
                        triangle: t,
                        index: i,
                        count: vertices.len(),
                    });
                }
                used[i] = true;
            }
            let d = det3(vertices[tri[0]], vertices[tri[1]], vertices[tri[2]]);
            if d.abs() <= 2.0 * DEGENERATE_AREA * extent * extent {
                return Err(TriangularError::DegenerateTriangle {
                    triangle: t,
                    area: d.abs() / 2.0,
                });
            }
            if d < 0.0 {
                tri.swap(1, 2);
            }
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(TriangularError::UnusedVertex { vertex: v });
        }
        let mut edges: std::collections::HashMap<(usize, usize), Vec<(usize, bool)>> =
            std::collections::HashMap::new();
        for (t, tri) in tris.iter().enumerate() {
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((t, a < b));
            }
        }
        let mut keys: Vec<_> = edges.keys().copied().collect();
        keys.sort_unstable();
        for k in keys {
            let users = &edges[&k];
            if users.len() > 2 || (users.len() == 2 && users[0].1 == users[1].1) {
                return Err(TriangularError::NonManifoldEdge {
                    a: k.0,
                    b: k.1,
                    triangles: users.iter().map(|u| u.0).collect(),
                });
            }
        }
        let tol = DOMAIN_TOLERANCE * extent;
        let polys: Vec<[Point2; 3]> = tris
            .iter()
            .map(|t| [vertices[t[0]], vertices[t[1]], vertices[t[2]]])
            .collect();
        let boxes: Vec<[Point2; 2]> = polys.iter().map(|p| bbox(p)).collect();
        for a in 0..tris.len() {
            for b in a + 1..tris.len() {
                let (ba, bb) = (boxes[a], boxes[b]);
                if ba[1][0] <= bb[0][0] + tol
                    || bb[1][0] <= ba[0][0] + tol
                    || ba[1][1] <= bb[0][1] + tol
                    || bb[1][1] <= ba[0][1] + tol
                {
                    continue;
                }
                if convex_overlap(&polys[a], &polys[b], tol) {
                    return Err(TriangularError::Overlap { a, b });
                }
            }
        }
        Ok(Self {
            vertices,
            triangles: tris,
            extent,
        })
    }

    /// The domain vertices.
    pub fn vertices(&self) -> &[Point2] {
        &self.vertices
    }

    /// The triangles (counter-clockwise vertex indices).
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Largest side of the domain's bounding box.
    pub fn extent(&self) -> f64 {
        self.extent
    }

    /// The corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [Point2; 3] {
        let tri = self.triangles[t];
        tri.map(|i| self.vertices[i])
    }

    /// Barycentric coordinates of `x` in triangle `t`.
    pub fn barycentric(&self, t: usize, x: Point2) -> [f64; 3] {
        let [a, b, c] = self.corners(t);
        let d = det3(a, b, c);
        [det3(x, b, c) / d, det3(a, x, c) / d, det3(a, b, x) / d]
    }

    /// The triangle containing `x`: the one where `x` has the largest smallest barycentric
    /// coordinate, if that is above `-DOMAIN_TOLERANCE` (so points on shared edges go to one
    /// of their triangles and interior points to theirs). `None` outside the domain.
    pub fn locate(&self, x: Point2) -> Option<usize> {
        if !(x[0].is_finite() && x[1].is_finite()) {
            return None;
        }
        let mut best = (usize::MAX, f64::NEG_INFINITY);
        for t in 0..self.triangles.len() {
            let m = self
                .barycentric(t, x)
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            if m > best.1 {
                best = (t, m);
            }
        }
        (best.1 >= -DOMAIN_TOLERANCE).then_some(best.0)
    }
}

/// The knot clouds of a triangular B-spline: `n + 1` knots per domain vertex, the first at the
/// vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotClouds {
    /// `clouds[v][k]` is knot `v_k`.
    pub clouds: Vec<Vec<Point2>>,
}

impl KnotClouds {
    /// Automatic clouds: `v_0 = v`, and `v_k` (`k >= 1`) at distance
    /// `radius * h_v * (1 - 0.35 (k - 1) / n)` from `v` (`h_v` the shortest edge at `v`,
    /// `radius` a fraction such as [`DEFAULT_CLOUD_RADIUS`]; small radii approach Bezier
    /// triangles), spread in angle at fractions `(k - 1 + 0.4142) / (n + 0.1)` (away from simple
    /// ratios, so no knot falls on the extension of an edge) of a wedge:
    /// - interior vertices: the full turn, rotated by the golden angle times the vertex index;
    /// - boundary vertices: the directions on the outer side of both boundary edges at the
    ///   vertex. This is what makes the partition of unity and polynomial reproduction hold up
    ///   to the domain boundary: the DMS identity leaves, per boundary edge `[r, s]`, a term
    ///   supported on the hull of the knots of `r` and `s`, which then lies outside the domain
    ///   (found and checked by the tests; with knots on the inner side the sum of the basis
    ///   functions drops to 0.2 near the edge). Reflex boundary vertices fall back to the whole
    ///   exterior wedge (the partition of unity may then fail near them).
    pub fn around_vertices(
        tri: &Triangulation,
        degree: usize,
        radius: f64,
    ) -> Result<Self, TriangularError> {
        if degree == 0 || degree > MAX_TRIANGULAR_DEGREE {
            return Err(TriangularError::Degree {
                degree,
                max: MAX_TRIANGULAR_DEGREE,
            });
        }
        let nv = tri.vertices().len();
        let mut h = vec![f64::INFINITY; nv];
        for t in tri.triangles() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let (pa, pb) = (tri.vertices()[a], tri.vertices()[b]);
                let l = (pa[0] - pb[0]).hypot(pa[1] - pb[1]);
                h[a] = h[a].min(l);
                h[b] = h[b].min(l);
            }
        }
        // Angles covered by the triangles at each vertex: knots of boundary vertices go into
        // the exterior wedge (outside the domain), those of interior vertices all around.
        let mut wedges: Vec<Vec<(f64, f64)>> = vec![Vec::new(); nv];
        for t in tri.triangles() {
            for e in 0..3 {
                let v = t[e];
                let p = tri.vertices()[v];
                let a = tri.vertices()[t[(e + 1) % 3]];
                let b = tri.vertices()[t[(e + 2) % 3]];
                let ta = (a[1] - p[1]).atan2(a[0] - p[0]);
                let mut tb = (b[1] - p[1]).atan2(b[0] - p[0]);
                if tb < ta {
                    tb += 2.0 * std::f64::consts::PI;
                }
                wedges[v].push((ta, tb));
            }
        }
        // Outward unit normals of the boundary edges at each vertex.
        let mut edge_count: std::collections::HashMap<(usize, usize), usize> =
            std::collections::HashMap::new();
        for t in tri.triangles() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                *edge_count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let mut boundary_normals: Vec<Vec<Point2>> = vec![Vec::new(); nv];
        for t in tri.triangles() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                if edge_count[&(a.min(b), a.max(b))] == 1 {
                    let (pa, pb) = (tri.vertices()[a], tri.vertices()[b]);
                    let (du, dv) = (pb[0] - pa[0], pb[1] - pa[1]);
                    let l = du.hypot(dv);
                    let n = [dv / l, -du / l];
                    boundary_normals[a].push(n);
                    boundary_normals[b].push(n);
                }
            }
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let clouds = (0..nv)
            .map(|v| {
                let p = tri.vertices()[v];
                let covered: f64 = wedges[v].iter().map(|w| w.1 - w.0).sum();
                let (start, span) = if covered >= two_pi - 1e-9 {
                    (golden * (v as f64 + 0.5), two_pi)
                } else if let Some(w) = outer_wedge(&boundary_normals[v]) {
                    w
                } else {
                    // Reflex or pinched boundary vertex: the exterior wedge.
                    let end = wedges[v]
                        .iter()
                        .map(|w| w.1)
                        .find(|&e| {
                            !wedges[v].iter().any(|w| {
                                let d = (w.0 - e).rem_euclid(two_pi);
                                d < 1e-9 || two_pi - d < 1e-9
                            })
                        })
                        .unwrap_or(0.0);
                    (end, two_pi - covered)
                };
                let mut c = vec![p];
                for k in 1..=degree {
                    // Fractions away from simple ratios (no knot on an edge's extension).
                    let f = ((k - 1) as f64 + 0.4142) / (degree as f64 + 0.1);
                    let th = start + span * f;
                    let r = radius * h[v] * (1.0 - 0.35 * (k - 1) as f64 / degree as f64);
                    c.push([p[0] + r * th.cos(), p[1] + r * th.sin()]);
                }
                c
            })
            .collect();
        Ok(Self { clouds })
    }
}

/// The directions on the outer side of both boundary edges at a boundary vertex, as
/// `(start angle, span)`; `None` unless there are exactly two boundary edges meeting at a convex
/// (or straight) corner.
fn outer_wedge(normals: &[Point2]) -> Option<(f64, f64)> {
    let [n1, n2] = normals else { return None };
    let m = [n1[0] + n2[0], n1[1] + n2[1]];
    let ml = m[0].hypot(m[1]);
    if ml < 1e-9 {
        return None;
    }
    let between = (n1[0] * n2[0] + n1[1] * n2[1]).clamp(-1.0, 1.0).acos();
    let half = std::f64::consts::FRAC_PI_2 - between / 2.0;
    (half > 1e-6).then(|| (m[1].atan2(m[0]) - half, 2.0 * half))
}

/// One DMS basis function `N_{I,beta}` (eq 10).
#[derive(Clone, Debug)]
struct BasisFunction {
    node: u32,
    scale: f64,
    hull: Vec<Point2>,
}

/// The DMS triangular B-spline basis of degree `n` over a triangulation with knot clouds (see the
/// module docs). Basis function `I * (n+1)(n+2)/2 + k` belongs to triangle `I` and the `k`-th
/// multi-index of [`multi_indices`].
#[derive(Clone, Debug)]
pub struct TriangularBasis {
    degree: usize,
    domain: Triangulation,
    clouds: KnotClouds,
    dag: SimplexDag,
    functions: Vec<BasisFunction>,
    /// Per domain triangle: the functions whose support meets it.
    element_functions: Vec<Vec<u32>>,
    /// Per domain triangle: the sub-splines those functions need, children first.
    element_nodes: Vec<Vec<u32>>,
}

/// The multi-indices `beta` with `|beta| = n`, in the order of the basis functions of one
/// triangle: `beta_0` descending, then `beta_1` descending.
pub fn multi_indices(n: usize) -> Vec<[usize; 3]> {
    let mut out = Vec::with_capacity((n + 1) * (n + 2) / 2);
    for b0 in (0..=n).rev() {
        for b1 in (0..=n - b0).rev() {
            out.push([b0, b1, n - b0 - b1]);
        }
    }
    out
}

/// Workspace of [`TriangularBasis`] evaluation (reuse it to avoid allocation per point).
#[derive(Clone, Debug, Default)]
pub struct BasisScratch {
    nodes: Vec<[f64; 6]>,
}

impl TriangularBasis {
    /// Builds and validates the basis (see the module docs for the conditions).
    pub fn new(
        degree: usize,
        domain: Triangulation,
        clouds: KnotClouds,
    ) -> Result<Self, TriangularError> {
        if degree == 0 || degree > MAX_TRIANGULAR_DEGREE {
            return Err(TriangularError::Degree {
                degree,
                max: MAX_TRIANGULAR_DEGREE,
            });
        }
        let nv = domain.vertices().len();
        if clouds.clouds.len() != nv {
            return Err(TriangularError::Shape {
                what: "knot clouds (one per domain vertex)",
                found: clouds.clouds.len(),
                expected: nv,
            });
        }
        for (v, c) in clouds.clouds.iter().enumerate() {
            if c.len() != degree + 1 {
                return Err(TriangularError::CloudSize {
                    vertex: v,
                    found: c.len(),
                    expected: degree + 1,
                });
            }
            if c.iter().any(|k| !(k[0].is_finite() && k[1].is_finite())) {
                return Err(TriangularError::Cloud {
                    vertex: v,
                    why: "a knot is not finite",
                });
            }
            if c[0] != domain.vertices()[v] {
                return Err(TriangularError::Cloud {
                    vertex: v,
                    why: "the first knot must be the vertex itself",
                });
            }
        }
        let n = degree;
        let knot_id = |v: usize, k: usize| (v * (n + 1) + k) as u32;
        let all: Vec<Point2> = clouds.clouds.iter().flatten().copied().collect();
        let mut dag = SimplexDag::new(all.clone()).map_err(|source| TriangularError::Knots {
            triangle: 0,
            beta: [0; 3],
            source,
        })?;
        let betas = multi_indices(n);
        let mut functions = Vec::with_capacity(domain.triangles().len() * betas.len());
        for (t, tri) in domain.triangles().iter().enumerate() {
            // DMS condition on every knot triangle with |beta| <= n.
            for s in 0..=n {
                for b in multi_indices(s) {
                    let k = [
                        all[knot_id(tri[0], b[0]) as usize],
                        all[knot_id(tri[1], b[1]) as usize],
                        all[knot_id(tri[2], b[2]) as usize],
                    ];
                    let d = det3(k[0], k[1], k[2]);
                    let tol = DEGENERATE_AREA * domain.extent() * domain.extent();
                    if d <= tol {
                        return Err(TriangularError::KnotTriangle {
                            triangle: t,
                            beta: b,
                        });
                    }
                }
            }
            for &b in &betas {
                let mut ids = Vec::with_capacity(n + 3);
                for (c, &bc) in b.iter().enumerate() {
                    for k in 0..=bc {
                        ids.push(knot_id(tri[c], k));
                    }
                }
                let node = dag.add(&ids).map_err(|source| TriangularError::Knots {
                    triangle: t,
                    beta: b,
                    source,
                })?;
                let scale = det3(
                    all[knot_id(tri[0], b[0]) as usize],
                    all[knot_id(tri[1], b[1]) as usize],
                    all[knot_id(tri[2], b[2]) as usize],
                )
                .abs();
                let pts: Vec<Point2> = ids.iter().map(|&i| all[i as usize]).collect();
                functions.push(BasisFunction {
                    node,
                    scale,
                    hull: convex_hull(&pts),
                });
            }
        }
        let tol = DOMAIN_TOLERANCE * domain.extent();
        let mut element_functions = Vec::with_capacity(domain.triangles().len());
        let mut element_nodes = Vec::with_capacity(domain.triangles().len());
        for t in 0..domain.triangles().len() {
            let corners = domain.corners(t);
            let list: Vec<u32> = functions
                .iter()
                .enumerate()
                .filter(|(_, f)| convex_overlap(&f.hull, &corners, -tol))
                .map(|(i, _)| i as u32)
                .collect();
            let roots: Vec<u32> = list.iter().map(|&f| functions[f as usize].node).collect();
            element_nodes.push(dag.closure(&roots));
            element_functions.push(list);
        }
        Ok(Self {
            degree,
            domain,
            clouds,
            dag,
            functions,
            element_functions,
            element_nodes,
        })
    }

    /// The degree `n`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The domain triangulation.
    pub fn domain(&self) -> &Triangulation {
        &self.domain
    }

    /// The knot clouds.
    pub fn clouds(&self) -> &KnotClouds {
        &self.clouds
    }

    /// Number of basis functions (`(n+1)(n+2)/2` per triangle).
    pub fn len(&self) -> usize {
        self.functions.len()
    }

    /// Whether there are no basis functions (never, for a valid basis).
    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }

    /// The functions whose support meets domain triangle `t` (the element's degrees of
    /// freedom, `d-nurbs.txt` section 5.1, Fig 4).
    pub fn element_functions(&self, t: usize) -> &[u32] {
        &self.element_functions[t]
    }

    /// The knots of basis function `f`: triangle, multi-index.
    pub fn function_index(&self, f: usize) -> (usize, [usize; 3]) {
        let per = (self.degree + 1) * (self.degree + 2) / 2;
        (f / per, multi_indices(self.degree)[f % per])
    }

    /// The values and derivatives `(N, N_u, N_v, N_uu, N_uv, N_vv)` of the functions of
    /// [`TriangularBasis::element_functions`]`(t)` at `x` (any point; those outside the
    /// functions' supports give zeros), into `out`.
    pub fn eval_element(
        &self,
        t: usize,
        x: Point2,
        scratch: &mut BasisScratch,
        out: &mut Vec<[f64; 6]>,
    ) {
        if scratch.nodes.len() != self.dag.len() {
            scratch.nodes.resize(self.dag.len(), [0.0; 6]);
        }
        self.dag
            .eval_into(&self.element_nodes[t], x, &mut scratch.nodes);
        out.clear();
        for &f in &self.element_functions[t] {
            let bf = &self.functions[f as usize];
            let m = scratch.nodes[bf.node as usize];
            out.push(m.map(|v| v * bf.scale));
        }
    }

    /// All non-zero basis functions at `x` with their derivatives up to second order:
    /// `(function index, (N, N_u, N_v, N_uu, N_uv, N_vv))`.
    pub fn nonzero(&self, x: Point2) -> Result<Vec<(usize, [f64; 6])>, TriangularError> {
        let t = self
            .domain
            .locate(x)
            .ok_or(TriangularError::OutsideDomain { u: x[0], v: x[1] })?;
        let mut sc = BasisScratch::default();
        let mut vals = Vec::new();
        self.eval_element(t, x, &mut sc, &mut vals);
        Ok(self.element_functions[t]
            .iter()
            .zip(vals)
            .filter(|(_, v)| v.iter().any(|x| *x != 0.0))
            .map(|(&f, v)| (f as usize, v))
            .collect())
    }

    /// The continuous-net control map: functions whose Bezier domain points
    /// `(b0 r + b1 s + b2 t) / n` coincide share a control point. Returns the map (function to
    /// control point) and the domain point of each control point. With clouds near their
    /// vertices this makes the surface continuous across domain edges (section 7.3's 21-point
    /// edge net).
    pub fn bezier_net_map(&self) -> (Vec<usize>, Vec<Point2>) {
        let n = self.degree as f64;
        let tol = DOMAIN_TOLERANCE * self.domain.extent();
        let mut points: Vec<Point2> = Vec::new();
        let mut map = Vec::with_capacity(self.functions.len());
        for f in 0..self.functions.len() {
            let (t, b) = self.function_index(f);
            let c = self.domain.corners(t);
            let p = [0, 1].map(|a| {
                (b[0] as f64 * c[0][a] + b[1] as f64 * c[1][a] + b[2] as f64 * c[2][a]) / n
            });
            let found = points
                .iter()
                .position(|q| (q[0] - p[0]).abs() <= tol && (q[1] - p[1]).abs() <= tol);
            map.push(match found {
                Some(i) => i,
                None => {
                    points.push(p);
                    points.len() - 1
                }
            });
        }
        (map, points)
    }

    /// The segments across which the basis restricted to triangle `t` is not polynomial (edges
    /// of the degree-0 simplex splines of its functions).
    pub fn knot_segments(&self, t: usize) -> Vec<[Point2; 2]> {
        let mut s = self.dag.leaf_segments(&self.element_nodes[t]);
        for seg in &mut s {
            if (seg[1][0], seg[1][1]) < (seg[0][0], seg[0][1]) {
                seg.swap(0, 1);
            }
        }
        s.sort_by(|a, b| {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .map(|(x, y)| x.total_cmp(y))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        s.dedup();
        s
    }

    /// Domain triangle `t` cut along every knot segment that crosses it into convex cells,
    /// each fan-triangulated, so that every basis function is a polynomial on each returned
    /// triangle (for exact element quadrature). Cells thinner than the domain tolerance are
    /// dropped.
    pub fn polynomial_cells(&self, t: usize) -> Vec<[Point2; 3]> {
        self.polynomial_cell_polygons(t)
            .iter()
            .flat_map(|p| fan(p, self.area_tolerance()))
            .collect()
    }

    /// Domain triangle `t` cut along every knot segment that crosses it: convex polygons (CCW)
    /// on each of which every basis function is a polynomial. Cells thinner than the domain
    /// tolerance are dropped.
    pub fn polynomial_cell_polygons(&self, t: usize) -> Vec<Vec<Point2>> {
        let tol = DOMAIN_TOLERANCE * self.domain.extent();
        let mut polys: Vec<Vec<Point2>> = vec![self.domain.corners(t).to_vec()];
        for seg in self.knot_segments(t) {
            let mut next = Vec::with_capacity(polys.len() + 4);
            for poly in polys {
                match split_by_segment(&poly, seg, tol) {
                    Some((a, b)) => {
                        next.push(a);
                        next.push(b);
                    }
                    None => next.push(poly),
                }
            }
            polys = next;
        }
        let area_tol = self.area_tolerance();
        polys.retain(|p| !fan(p, area_tol).is_empty());
        polys
    }

    fn area_tolerance(&self) -> f64 {
        let tol = DOMAIN_TOLERANCE * self.domain.extent();
        tol * tol
    }
}

/// Fan triangulation of a convex polygon, dropping triangles of `|d| <= area_tol`.
pub fn fan(p: &[Point2], area_tol: f64) -> Vec<[Point2; 3]> {
    let mut out = Vec::new();
    for i in 1..p.len().saturating_sub(1) {
        let tri = [p[0], p[i], p[i + 1]];
        if det3(tri[0], tri[1], tri[2]).abs() > area_tol {
            out.push(tri);
        }
    }
    out
}

/// Splits the convex polygon `poly` (CCW) by the line of `seg` when the segment crosses its
/// interior; `None` otherwise.
fn split_by_segment(
    poly: &[Point2],
    seg: [Point2; 2],
    tol: f64,
) -> Option<(Vec<Point2>, Vec<Point2>)> {
    let [a, b] = seg;
    let (du, dv) = (b[0] - a[0], b[1] - a[1]);
    let len = du.hypot(dv);
    if len == 0.0 {
        return None;
    }
    let side = |x: &Point2| (du * (x[1] - a[1]) - dv * (x[0] - a[0])) / len;
    let d: Vec<f64> = poly.iter().map(side).collect();
    if d.iter().all(|&x| x >= -tol) || d.iter().all(|&x| x <= tol) {
        return None;
    }
    // The chord of the line inside the polygon must overlap the segment.
    let mut ts = Vec::new();
    for i in 0..poly.len() {
        let j = (i + 1) % poly.len();
        if (d[i] > 0.0) != (d[j] > 0.0) {
            let f = d[i] / (d[i] - d[j]);
            let x = [
                poly[i][0] + f * (poly[j][0] - poly[i][0]),
                poly[i][1] + f * (poly[j][1] - poly[i][1]),
            ];
            ts.push(((x[0] - a[0]) * du + (x[1] - a[1]) * dv) / (len * len));
        }
    }
    let (t0, t1) = ts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &t| {
            (l.min(t), h.max(t))
        });
    let ttol = tol / len;
    if t1 <= ttol || t0 >= 1.0 - ttol {
        return None;
    }
    let mut pos = Vec::new();
    let mut neg = Vec::new();
    for i in 0..poly.len() {
        let j = (i + 1) % poly.len();
        if d[i] >= 0.0 {
            pos.push(poly[i]);
        }
        if d[i] <= 0.0 {
            neg.push(poly[i]);
        }
        if (d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0) {
            let f = d[i] / (d[i] - d[j]);
            let x = [
                poly[i][0] + f * (poly[j][0] - poly[i][0]),
                poly[i][1] + f * (poly[j][1] - poly[i][1]),
            ];
            pos.push(x);
            neg.push(x);
        }
    }
    (pos.len() >= 3 && neg.len() >= 3).then_some((pos, neg))
}

/// A triangular NURBS surface (`d-nurbs.txt` eq 11) over a [`TriangularBasis`], with a control
/// map from basis functions to control points (identity by default).
#[derive(Clone, Debug)]
pub struct TriangularNurbs {
    layout: Arc<Layout>,
    points: Vec<Vec3>,
    weights: Vec<f64>,
}

/// The parts of a triangular NURBS that do not change when control points and weights move.
#[derive(Debug)]
struct Layout {
    basis: TriangularBasis,
    map: Vec<usize>,
    /// Per element: distinct control points of its functions.
    element_controls: Vec<Vec<usize>>,
    /// Per element: for each of its functions, the local control index.
    element_local: Vec<Vec<u32>>,
}

/// Values and Jacobian columns of a triangular NURBS at one parameter, for the six parametric
/// derivatives `s, s_u, s_v, s_uu, s_uv, s_vv`.
#[derive(Clone, Debug, Default)]
pub struct TriangularPoint {
    /// The element (domain triangle) evaluated.
    pub element: usize,
    /// `s^a`.
    pub s: [Vec3; 6],
    /// The local control points (global indices, the element's list).
    pub controls: Vec<usize>,
    /// Summed basis functions per local control point, `(N, N_u, ..., N_vv)`.
    pub basis: Vec<[f64; 6]>,
    /// Position columns `R_k^a` of eq 13 and their parametric derivatives.
    pub r: Vec<[f64; 6]>,
    /// Weight columns `d s^a / d w_k` of eq 13.
    pub g: Vec<[Vec3; 6]>,
    scratch: BasisScratch,
    fvals: Vec<[f64; 6]>,
}

impl TriangularNurbs {
    /// A surface with one control point per basis function (or per entry of `control_map`),
    /// validated: sizes, finite points, positive finite weights, map entries in range.
    pub fn new(
        basis: TriangularBasis,
        points: Vec<Vec3>,
        weights: Vec<f64>,
        control_map: Option<Vec<usize>>,
    ) -> Result<Self, TriangularError> {
        let map = match control_map {
            Some(m) => {
                if m.len() != basis.len() {
                    return Err(TriangularError::Shape {
                        what: "control map entries (one per basis function)",
                        found: m.len(),
                        expected: basis.len(),
                    });
                }
                m
            }
            None => (0..basis.len()).collect(),
        };
        if let Some((f, &c)) = map.iter().enumerate().find(|(_, c)| **c >= points.len()) {
            return Err(TriangularError::ControlMap {
                function: f,
                index: c,
                count: points.len(),
            });
        }
        if weights.len() != points.len() {
            return Err(TriangularError::Shape {
                what: "weights (one per control point)",
                found: weights.len(),
                expected: points.len(),
            });
        }
        let mut used = vec![false; points.len()];
        for &c in &map {
            used[c] = true;
        }
        if let Some(c) = used.iter().position(|u| !u) {
            return Err(TriangularError::ControlMap {
                function: usize::MAX,
                index: c,
                count: points.len(),
            });
        }
        let mut element_controls = Vec::new();
        let mut element_local = Vec::new();
        for t in 0..basis.domain().triangles().len() {
            let mut ctl: Vec<usize> = Vec::new();
            let mut loc = Vec::new();
            for &f in basis.element_functions(t) {
                let c = map[f as usize];
                let k = match ctl.iter().position(|&x| x == c) {
                    Some(k) => k,
                    None => {
                        ctl.push(c);
                        ctl.len() - 1
                    }
                };
                loc.push(k as u32);
            }
            element_controls.push(ctl);
            element_local.push(loc);
        }
        let mut s = Self {
            layout: Arc::new(Layout {
                basis,
                map,
                element_controls,
                element_local,
            }),
            points: vec![],
            weights: vec![],
        };
        s.set_control(points, weights)?;
        Ok(s)
    }

    /// Replaces control points and weights (validated; the counts must stay).
    pub fn set_control(
        &mut self,
        points: Vec<Vec3>,
        weights: Vec<f64>,
    ) -> Result<(), TriangularError> {
        let nc = self.layout.map.iter().map(|&c| c + 1).max().unwrap_or(0);
        if points.len() != nc {
            return Err(TriangularError::Shape {
                what: "control points",
                found: points.len(),
                expected: nc,
            });
        }
        if weights.len() != nc {
            return Err(TriangularError::Shape {
                what: "weights",
                found: weights.len(),
                expected: nc,
            });
        }
        if let Some(i) = points.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(TriangularError::NonFiniteControlPoint { index: i });
        }
        if let Some((i, &w)) = weights
            .iter()
            .enumerate()
            .find(|(_, w)| !(w.is_finite() && **w > 0.0))
        {
            return Err(TriangularError::NonPositiveWeight { index: i, value: w });
        }
        self.points = points;
        self.weights = weights;
        Ok(())
    }

    /// The basis.
    pub fn basis(&self) -> &TriangularBasis {
        &self.layout.basis
    }

    /// The control map (basis function to control point).
    pub fn control_map(&self) -> &[usize] {
        &self.layout.map
    }

    /// Control points.
    pub fn control_points(&self) -> &[Vec3] {
        &self.points
    }

    /// Weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The control points of element `t` (global indices).
    pub fn element_controls(&self, t: usize) -> &[usize] {
        &self.layout.element_controls[t]
    }

    /// Evaluates the surface, its derivatives and the Jacobian columns (eq 13) at `x` in element
    /// `t` (see [`TriangularPoint`]). With `sum w N` the denominator `W^a` and `A^a = sum w p N^a`,
    /// the Leibniz rule on `A = W s` gives `s^a = (A^a - sum_{b<a} C(a,b) W^(a-b) s^b) / W`;
    /// differentiating with respect to `p_k` and `w_k` gives the columns
    /// `R_k^a = (N_k^a w_k - sum_{b<a} C(a,b) W^(a-b) R_k^b) / W` and
    /// `g_k^a = (N_k^a p_k - sum_{b<=a} C(a,b) N_k^(a-b) s^b - sum_{b<a} C(a,b) W^(a-b) g_k^b) / W`
    /// (Piegl & Tiller eq 4.20 for the surface derivatives).
    pub fn eval_in_element(
        &self,
        t: usize,
        x: Point2,
        out: &mut TriangularPoint,
    ) -> Result<(), TriangularError> {
        let l = &*self.layout;
        l.basis.eval_element(t, x, &mut out.scratch, &mut out.fvals);
        let ctl = &l.element_controls[t];
        out.element = t;
        out.controls.clear();
        out.controls.extend_from_slice(ctl);
        out.basis.clear();
        out.basis.resize(ctl.len(), [0.0; 6]);
        for (k, v) in l.element_local[t].iter().zip(&out.fvals) {
            let b = &mut out.basis[*k as usize];
            for m in 0..6 {
                b[m] += v[m];
            }
        }
        let mut wa = [0.0; 6];
        let mut aa = [Vec3::zeros(); 6];
        for (k, &c) in ctl.iter().enumerate() {
            let (w, p) = (self.weights[c], self.points[c]);
            for m in 0..6 {
                let v = out.basis[k][m] * w;
                wa[m] += v;
                aa[m] += p * v;
            }
        }
        if wa[0].is_nan() || wa[0] <= 0.0 {
            return Err(TriangularError::ZeroDenominator { u: x[0], v: x[1] });
        }
        let iw = 1.0 / wa[0];
        let s0 = aa[0] * iw;
        let s1 = (aa[1] - s0 * wa[1]) * iw;
        let s2 = (aa[2] - s0 * wa[2]) * iw;
        let s3 = (aa[3] - s0 * wa[3] - s1 * (2.0 * wa[1])) * iw;
        let s4 = (aa[4] - s0 * wa[4] - s1 * wa[2] - s2 * wa[1]) * iw;
        let s5 = (aa[5] - s0 * wa[5] - s2 * (2.0 * wa[2])) * iw;
        let s = [s0, s1, s2, s3, s4, s5];
        out.s = s;
        out.r.clear();
        out.g.clear();
        let [w1, w2, w3, w4, w5] = [wa[1], wa[2], wa[3], wa[4], wa[5]];
        for (k, &c) in ctl.iter().enumerate() {
            let [n0, n1, n2, n3, n4, n5] = out.basis[k];
            let (wc, pc) = (self.weights[c], self.points[c]);
            let r0 = n0 * wc * iw;
            let r1 = (n1 * wc - w1 * r0) * iw;
            let r2 = (n2 * wc - w2 * r0) * iw;
            let r3 = (n3 * wc - w3 * r0 - 2.0 * w1 * r1) * iw;
            let r4 = (n4 * wc - w4 * r0 - w2 * r1 - w1 * r2) * iw;
            let r5 = (n5 * wc - w5 * r0 - 2.0 * w2 * r2) * iw;
            out.r.push([r0, r1, r2, r3, r4, r5]);
            let g0 = (pc - s[0]) * (n0 * iw);
            let g1 = (pc * n1 - s[1] * n0 - s[0] * n1 - g0 * w1) * iw;
            let g2 = (pc * n2 - s[2] * n0 - s[0] * n2 - g0 * w2) * iw;
            let g3 = (pc * n3 - s[3] * n0 - s[0] * n3 - g0 * w3 - (s[1] * n1 + g1 * w1) * 2.0) * iw;
            let g4 = (pc * n4
                - s[4] * n0
                - s[0] * n4
                - g0 * w4
                - s[1] * n2
                - g1 * w2
                - s[2] * n1
                - g2 * w1)
                * iw;
            let g5 = (pc * n5 - s[5] * n0 - s[0] * n5 - g0 * w5 - (s[2] * n2 + g2 * w2) * 2.0) * iw;
            out.g.push([g0, g1, g2, g3, g4, g5]);
        }
        Ok(())
    }

    /// [`TriangularNurbs::eval_in_element`] at any domain point (located first).
    pub fn eval(&self, x: Point2, out: &mut TriangularPoint) -> Result<(), TriangularError> {
        let t = self
            .basis()
            .domain()
            .locate(x)
            .ok_or(TriangularError::OutsideDomain { u: x[0], v: x[1] })?;
        self.eval_in_element(t, x, out)
    }

    /// The point `s(u)` (eq 11).
    pub fn point(&self, x: Point2) -> Result<Vec3, TriangularError> {
        let mut p = TriangularPoint::default();
        self.eval(x, &mut p)?;
        Ok(p.s[0])
    }

    /// `(s, s_u, s_v, s_uu, s_uv, s_vv)` at `x`.
    pub fn derivatives(&self, x: Point2) -> Result<[Vec3; 6], TriangularError> {
        let mut p = TriangularPoint::default();
        self.eval(x, &mut p)?;
        Ok(p.s)
    }

    /// Tessellates the surface: every domain triangle is split into `level^2` triangles
    /// (vertices on shared domain edges are shared), with analytic normals `s_u x s_v`.
    /// Triangles are counter-clockwise around `s_u x s_v`.
    pub fn tessellate(&self, level: usize, sink: &mut dyn MeshSink) -> Result<(), TriangularError> {
        let level = level.max(1);
        let dom = self.basis().domain();
        let tol = DOMAIN_TOLERANCE * dom.extent();
        let q = |x: f64| (x / tol).round() as i64;
        let mut index: std::collections::HashMap<(i64, i64), u32> =
            std::collections::HashMap::new();
        let mut p = TriangularPoint::default();
        let per = (level + 1) * (level + 2) / 2;
        sink.reserve(
            dom.triangles().len() * per,
            dom.triangles().len() * level * level,
        );
        for t in 0..dom.triangles().len() {
            let [a, b, c] = dom.corners(t);
            let mut ids = vec![0u32; per];
            let mut k = 0;
            let mut row_start = Vec::with_capacity(level + 1);
            for i in 0..=level {
                row_start.push(k);
                for j in 0..=level - i {
                    let (l1, l2) = (i as f64 / level as f64, j as f64 / level as f64);
                    let l0 = 1.0 - l1 - l2;
                    let x = [
                        l0 * a[0] + l1 * b[0] + l2 * c[0],
                        l0 * a[1] + l1 * b[1] + l2 * c[1],
                    ];
                    let key = (q(x[0]), q(x[1]));
                    ids[k] = match index.get(&key) {
                        Some(&id) => id,
                        None => {
                            // Evaluate slightly inside the triangle so that the half-open
                            // convention does not pick the neighbour's side of a seam.
                            let g = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
                            let xi = [x[0] + 1e-9 * (g[0] - x[0]), x[1] + 1e-9 * (g[1] - x[1])];
                            self.eval_in_element(t, xi, &mut p)?;
                            let n = p.s[1].cross(&p.s[2]);
                            let nn = n.norm();
                            let id = sink.add_vertex(p.s[0], (nn > 0.0).then(|| n / nn));
                            index.insert(key, id);
                            id
                        }
                    };
                    k += 1;
                }
            }
            for i in 0..level {
                for j in 0..level - i {
                    let v00 = ids[row_start[i] + j];
                    let v10 = ids[row_start[i + 1] + j];
                    let v01 = ids[row_start[i] + j + 1];
                    sink.add_triangle([v00, v10, v01]);
                    if j + 1 < level - i {
                        let v11 = ids[row_start[i + 1] + j + 1];
                        sink.add_triangle([v10, v11, v01]);
                    }
                }
            }
        }
        Ok(())
    }
}
