//! Triangular D-NURBS (`d-nurbs.txt` section 4.4, eqs 10-14; finite elements of section 5):
//! a [`TriangularNurbs`] whose control points **and weights** are the generalized coordinates
//! of [`GeneralizedDnurbs`](super::GeneralizedDnurbs).
//!
//! ## Coordinates and Jacobian
//! `p = [p_0, w_0, p_1, w_1, ...]`, four numbers (x, y, z, w) per control point, as the
//! tensor-product [`RationalGeometry`](super::RationalGeometry). The Jacobian columns of eq 13
//! and their parametric derivatives (for `J_u ... J_vv` of eq 17) come from
//! [`TriangularNurbs::eval_in_element`]; `s = J p` (eq 14) is tested in `vclay-spline`.
//!
//! ## Elements and quadrature (section 5.1-5.2)
//! The degrees of freedom of a domain triangle are the control points of every basis function
//! whose support meets it (Fig 4). The basis is piecewise polynomial on the triangle: its pieces
//! are separated by the knot segments (edges of the degree-0 simplex splines of the
//! recurrence). With [`TriangleQuadrature::Subdivided`] (the default) every triangle is cut
//! along the knot segments that cross it ([`TriangularBasis::polynomial_cell_polygons`]) and
//! **each cell is a finite element** whose degrees of freedom are only the control points whose
//! functions are non-zero on it (positive at its centroid: B-splines are positive inside their
//! support). Each triangle of a cell's fan gets the symmetric rule exact for total degree
//! `2n` ([`vclay_core::TriangleRule`]: Dunavant's 6 points for `n = 2`, 12 for `n = 3`), the
//! degree of the integrands of the control-point terms of a polynomial (uniform-weight)
//! surface, so those are integrated exactly (`tests/triangular.rs`: with the weights frozen
//! the corner rounding follows the collapsed `3 x 3` rule, exact for the same degree, to
//! 1e-16). The weight columns `N_j (p_j - s) / W` make the weight terms of degree `4n` at
//! uniform weights and rational afterwards: no rule of the cells is exact for them, and a
//! `7 x 7` reference puts the symmetric rule and the collapsed `3 x 3` rule equally close
//! (3.8e-4 and 4.5e-4 after 8 corner steps in which the weights move by 25 %, model size
//! 5.5); [`TriangleQuadrature::Subdivided`] with `points: Some(k)` takes the collapsed rule
//! with `k x k` points (exact for degree `2k - 2`) for a tighter rational integral (`k = 5`:
//! 7e-7 after the same steps). The engine is told which cell a quadrature point belongs to
//! ([`GeneralizedGeometry::element_jacobian_at`]), so neighbouring cells may have different
//! degrees of freedom. Per-cell lists cut the cost of the corner rounding 5-fold (on the
//! corner a triangle touches about 40 control points, a cell about 10).
//!
//! The paper's rule, one Gauss rule per triangle ([`TriangleQuadrature::Whole`], "we can
//! further subdivide the subdomains", section 5.2), integrates across the kinks of the basis and
//! converges only algebraically. Measured on the quadratic edge-rounding net (6 triangles, knot
//! clouds of radius 0.1 of the edge, `tests/triangular.rs`): the integral of `sum N^2` agrees
//! between subdivided rules to 1e-13 and has relative errors 4.7e-3, 6.1e-4 and 4.3e-5 with one
//! 3 x 3, 6 x 6 and 12 x 12 rule per triangle; the total mass `integral sum N` (the domain area,
//! a polynomial) is exact either way. Too few whole-triangle points also under-integrate the
//! stiffness: on the corner rounding a 4 x 4 rule wrinkles the fillet (energy 1.60e4 against
//! 1.87e4 with 6 x 6 after 20 steps).
//!
//! ## Cached basis values (issue 18)
//! The summed basis functions and their parameter derivatives to second order at an element's
//! quadrature points depend only on the knots, so [`GeneralizedGeometry::element_quadrature`]
//! stores them per cell (`CellBasis`) and [`GeneralizedGeometry::element_jacobian_at`] forms
//! the rational columns of eq 13 from them each step, with the arithmetic of
//! [`TriangularNurbs::eval_in_element`] (results bit for bit those of a direct evaluation,
//! `tests/triangular.rs`). Memory: 48 bytes per kept control point per quadrature point, 2.6 MB
//! on the corner rounding with the exact cells (4,632 points), 1.1 MB with one 6 x 6 rule per
//! triangle ([`TriangularGeometry::cached_basis_bytes`]). Points other than the cached rule's
//! are evaluated directly. Fixed control points (the held far boundary of the rounding
//! models) get only their order-0 columns, the ones the engine still reads of them
//! (`ColumnHint` in `generalized.rs`).
//!
//! ## Limitations
//! Point location is a linear scan over the domain triangles; [`GeneralizedGeometry::nearest_param`]
//! samples each triangle and refines by Gauss-Newton (used by data springs).

use super::generalized::{
    GeneralizedGeometry, LocalJacobian, homogeneous_coordinate_groups,
    homogeneous_weight_coordinates, with_thread_buffer,
};
use crate::error::DynamicsError;
use std::sync::{Arc, OnceLock};
use vclay_core::{TriangleRule, Vec3};
use vclay_spline::simplex::Point2;
use vclay_spline::triangular::fan;
use vclay_spline::{SplineError, TriangularNurbs, TriangularPoint};

pub use vclay_spline::triangular::TriangularBasis;

/// How element integrals over a domain triangle are computed (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriangleQuadrature {
    /// Cut along the knot segments into polynomial cells. `points: None` (the default): on
    /// each triangle of a cell's fan, the symmetric rule exact for total degree `2n`
    /// ([`TriangleRule::exact_for_degree`]; 6 points for `n = 2`, 12 for `n = 3`), the degree
    /// of the integrands of the control-point terms. `points: Some(k)`: the collapsed Gauss
    /// rule with `k x k` points (exact for degree `2k - 2`).
    Subdivided {
        /// Collapsed Gauss points per direction on each cell (`None`: the symmetric rule).
        points: Option<usize>,
    },
    /// One collapsed Gauss rule with `k x k` points on the whole triangle (the paper's rule).
    Whole {
        /// Points per direction.
        points: usize,
    },
}

impl Default for TriangleQuadrature {
    fn default() -> Self {
        Self::Subdivided { points: None }
    }
}

fn spline(e: SplineError) -> DynamicsError {
    DynamicsError::Spline(e)
}

/// Collapsed Gauss-Legendre rule (Duffy map `x = a + xi (b - a) + xi eta (c - b)`, area factor
/// `xi |d(a, b, c)|`) with `k x k` points on the triangle `[a, b, c]`, appended to `params` and
/// `weights`. Exact for polynomials of total degree `2k - 2`.
pub fn collapsed_gauss(
    tri: [Point2; 3],
    k: usize,
    params: &mut Vec<[f64; 2]>,
    weights: &mut Vec<f64>,
) -> Result<(), DynamicsError> {
    let rule = TriangleRule::collapsed(k).map_err(|_| points_error(k))?;
    for (x, w) in rule.on_triangle(tri) {
        params.push(x);
        weights.push(w);
    }
    Ok(())
}

fn points_error(k: usize) -> DynamicsError {
    DynamicsError::Parameter {
        name: "triangle quadrature points",
        value: k as f64,
        why: "no Gauss-Legendre rule with this many points (1 to 64)",
    }
}

thread_local! {
    /// Evaluation buffers reused by `jacobian_at` (no allocation per quadrature point).
    static POINT: std::cell::RefCell<TriangularPoint> =
        std::cell::RefCell::new(TriangularPoint::default());
}

/// A triangular NURBS with dynamic control points and weights (see the module docs).
#[derive(Clone, Debug)]
pub struct TriangularGeometry {
    surface: TriangularNurbs,
    coords: Vec<f64>,
    scale: f64,
    quadrature: TriangleQuadrature,
    cells: Arc<Vec<Cell>>,
    /// Per cell: the basis values at its quadrature points, filled by `element_quadrature`
    /// (see [`CellBasis`]); shared by clones (the basis never changes, only the control).
    bases: Arc<Vec<OnceLock<Option<CellBasis>>>>,
}

/// The summed basis functions `(N, N_u, N_v, N_uu, N_uv, N_vv)` of a cell's kept control
/// points at the cell's quadrature points. They depend only on the knots and the parameter,
/// not on the control points or weights, so they are computed once and every step forms the
/// rational columns of eq 13 from them ([`rational_columns`]) instead of re-evaluating the
/// simplex-spline recurrence (about 6 us a point on the corner rounding).
/// Memory: `48 * keep` bytes a point ([`TriangularGeometry::cached_basis_bytes`]).
#[derive(Debug)]
struct CellBasis {
    /// The quadrature points, bit for bit as `element_quadrature` returned them.
    params: Vec<[f64; 2]>,
    /// `values[i * keep.len() + j]`: point `i`, kept control `j`.
    values: Vec<[f64; 6]>,
}

fn empty_bases(n: usize) -> Arc<Vec<OnceLock<Option<CellBasis>>>> {
    Arc::new((0..n).map(|_| OnceLock::new()).collect())
}

/// A finite element: a polynomial cell of a domain triangle (or the whole triangle) and the
/// positions, in the triangle's control list, of the control points whose functions are
/// non-zero on it.
#[derive(Debug)]
struct Cell {
    triangle: usize,
    polygon: Vec<Point2>,
    keep: Vec<usize>,
}

/// The elements of `surface` under `quadrature` (see the module docs).
fn build_cells(surface: &TriangularNurbs, quadrature: TriangleQuadrature) -> Vec<Cell> {
    let basis = surface.basis();
    let mut out = Vec::new();
    let mut p = TriangularPoint::default();
    for t in 0..basis.domain().triangles().len() {
        match quadrature {
            TriangleQuadrature::Whole { .. } => out.push(Cell {
                triangle: t,
                polygon: basis.domain().corners(t).to_vec(),
                keep: (0..surface.element_controls(t).len()).collect(),
            }),
            TriangleQuadrature::Subdivided { .. } => {
                for polygon in basis.polynomial_cell_polygons(t) {
                    let n = polygon.len() as f64;
                    let c = [0, 1].map(|d| polygon.iter().map(|q| q[d]).sum::<f64>() / n);
                    // B-splines are positive inside their support: a function is non-zero on
                    // the cell exactly when it is positive at an interior point.
                    let keep: Vec<usize> = match surface.eval_in_element(t, c, &mut p) {
                        Ok(()) => (0..p.basis.len())
                            .filter(|&k| p.basis[k][0] > 0.0)
                            .collect(),
                        Err(_) => (0..surface.element_controls(t).len()).collect(),
                    };
                    out.push(Cell {
                        triangle: t,
                        polygon,
                        keep,
                    });
                }
            }
        }
    }
    out
}

impl TriangularGeometry {
    /// The generalized geometry of `surface`, with the default quadrature.
    pub fn new(surface: TriangularNurbs) -> Self {
        let mut coords = Vec::with_capacity(4 * surface.control_points().len());
        for (p, w) in surface.control_points().iter().zip(surface.weights()) {
            coords.extend_from_slice(&[p.x, p.y, p.z, *w]);
        }
        let (lo, hi) = surface.control_points().iter().fold(
            (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let scale = (hi - lo).norm();
        let quadrature = TriangleQuadrature::default();
        let cells = Arc::new(build_cells(&surface, quadrature));
        let bases = empty_bases(cells.len());
        Self {
            surface,
            coords,
            scale: if scale > 0.0 && scale.is_finite() {
                scale
            } else {
                1.0
            },
            quadrature,
            cells,
            bases,
        }
    }

    /// Chooses the element quadrature (takes effect for models built afterwards).
    pub fn with_quadrature(mut self, q: TriangleQuadrature) -> Self {
        if q != self.quadrature {
            self.quadrature = q;
            self.cells = Arc::new(build_cells(&self.surface, q));
            self.bases = empty_bases(self.cells.len());
        }
        self
    }

    /// Number of finite elements (polynomial cells, or triangles for the whole-triangle rule).
    pub fn element_count(&self) -> usize {
        self.cells.len()
    }

    /// Bytes held by the cached basis values of the elements whose quadrature has been built
    /// (48 bytes per kept control point per quadrature point, plus 16 per point).
    pub fn cached_basis_bytes(&self) -> usize {
        self.bases
            .iter()
            .filter_map(|b| b.get().and_then(Option::as_ref))
            .map(|b| {
                b.values.len() * std::mem::size_of::<[f64; 6]>()
                    + b.params.len() * std::mem::size_of::<[f64; 2]>()
            })
            .sum()
    }

    /// The element quadrature.
    pub fn quadrature(&self) -> TriangleQuadrature {
        self.quadrature
    }

    /// The current surface (control points and weights from the coordinates).
    pub fn surface(&self) -> &TriangularNurbs {
        &self.surface
    }

    /// Control points.
    pub fn control_points(&self) -> &[Vec3] {
        self.surface.control_points()
    }

    /// Weights.
    pub fn weights(&self) -> &[f64] {
        self.surface.weights()
    }

    /// Quadrature points and weights of element `t` with `k` points per direction per cell.
    pub fn element_rule(
        &self,
        t: usize,
        k: usize,
    ) -> Result<(Vec<[f64; 2]>, Vec<f64>), DynamicsError> {
        let basis = self.surface.basis();
        let (mut p, mut w) = (Vec::new(), Vec::new());
        let cells = match self.quadrature {
            TriangleQuadrature::Subdivided { .. } => basis.polynomial_cells(t),
            TriangleQuadrature::Whole { .. } => vec![basis.domain().corners(t)],
        };
        for c in cells {
            collapsed_gauss(c, k, &mut p, &mut w)?;
        }
        Ok((p, w))
    }

    /// The quadrature points and weights on `polygon` (module docs).
    fn polygon_rule(&self, polygon: &[Point2]) -> Result<(Vec<[f64; 2]>, Vec<f64>), DynamicsError> {
        let (mut params, mut weights) = (Vec::new(), Vec::new());
        let k = match self.quadrature {
            TriangleQuadrature::Subdivided { points: Some(k) } => k,
            TriangleQuadrature::Whole { points } => points,
            TriangleQuadrature::Subdivided { points: None } => {
                let n = self.surface.basis().degree();
                let rule = TriangleRule::exact_for_degree(2 * n).map_err(|_| {
                    DynamicsError::Parameter {
                        name: "triangular degree",
                        value: n as f64,
                        why: "no triangle quadrature rule of twice this degree",
                    }
                })?;
                for tri in fan(polygon, 0.0) {
                    for (x, w) in rule.on_triangle(tri) {
                        params.push(x);
                        weights.push(w);
                    }
                }
                return Ok((params, weights));
            }
        };
        for tri in fan(polygon, 0.0) {
            collapsed_gauss(tri, k, &mut params, &mut weights)?;
        }
        Ok((params, weights))
    }

    fn eval(&self, param: [f64; 2], p: &mut TriangularPoint) -> Result<(), DynamicsError> {
        self.surface
            .eval(param, p)
            .map_err(|e| spline(SplineError::from(e)))
    }
}

/// The rational columns of eq 13 and the surface derivatives from the summed basis values
/// `basis[j]` of the control points `controls` (the arithmetic of
/// [`TriangularNurbs::eval_in_element`], operation for operation, so that the results are bit
/// for bit those of a direct evaluation when `controls` holds every function non-zero at the
/// point, in the element's order).
fn rational_columns(
    surface: &TriangularNurbs,
    controls: impl Iterator<Item = usize> + Clone,
    basis: &[[f64; 6]],
    param: [f64; 2],
    out: &mut LocalJacobian,
) -> Result<(), DynamicsError> {
    let (weights, points) = (surface.weights(), surface.control_points());
    let mut wa = [0.0; 6];
    let mut aa = [Vec3::zeros(); 6];
    for (b, c) in basis.iter().zip(controls.clone()) {
        let (w, p) = (weights[c], points[c]);
        for m in 0..6 {
            let v = b[m] * w;
            wa[m] += v;
            aa[m] += p * v;
        }
    }
    if wa[0].is_nan() || wa[0] <= 0.0 {
        return Err(spline(SplineError::from(
            vclay_spline::triangular::TriangularError::ZeroDenominator {
                u: param[0],
                v: param[1],
            },
        )));
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
    out.blocks.clear();
    out.vectors.clear();
    let [w1, w2, w3, w4, w5] = [wa[1], wa[2], wa[3], wa[4], wa[5]];
    let zero = Vec3::zeros();
    for (b, c) in basis.iter().zip(controls) {
        let [n0, n1, n2, n3, n4, n5] = *b;
        let (wc, pc) = (weights[c], points[c]);
        let r0 = n0 * wc * iw;
        let g0 = (pc - s[0]) * (n0 * iw);
        // A fixed control point: only its order-0 columns are read (`ColumnHint`).
        if out.hint.values_only(c) {
            out.blocks.push((4 * c, [r0, 0.0, 0.0, 0.0, 0.0, 0.0]));
            out.vectors
                .push((4 * c + 3, [g0, zero, zero, zero, zero, zero]));
            continue;
        }
        let r1 = (n1 * wc - w1 * r0) * iw;
        let r2 = (n2 * wc - w2 * r0) * iw;
        let g1 = (pc * n1 - s[1] * n0 - s[0] * n1 - g0 * w1) * iw;
        let g2 = (pc * n2 - s[2] * n0 - s[0] * n2 - g0 * w2) * iw;
        let r3 = (n3 * wc - w3 * r0 - 2.0 * w1 * r1) * iw;
        let r4 = (n4 * wc - w4 * r0 - w2 * r1 - w1 * r2) * iw;
        let r5 = (n5 * wc - w5 * r0 - 2.0 * w2 * r2) * iw;
        out.blocks.push((4 * c, [r0, r1, r2, r3, r4, r5]));
        let g3 = (pc * n3 - s[3] * n0 - s[0] * n3 - g0 * w3 - (s[1] * n1 + g1 * w1) * 2.0) * iw;
        let g4 =
            (pc * n4 - s[4] * n0 - s[0] * n4 - g0 * w4 - s[1] * n2 - g1 * w2 - s[2] * n1 - g2 * w1)
                * iw;
        let g5 = (pc * n5 - s[5] * n0 - s[0] * n5 - g0 * w5 - (s[2] * n2 + g2 * w2) * 2.0) * iw;
        out.vectors.push((4 * c + 3, [g0, g1, g2, g3, g4, g5]));
    }
    Ok(())
}

impl GeneralizedGeometry for TriangularGeometry {
    type ElementTables = ();
    fn parametric_dimension(&self) -> usize {
        2
    }
    fn coordinates(&self) -> &[f64] {
        &self.coords
    }
    fn set_coordinates(&mut self, q: &[f64]) -> Result<(), DynamicsError> {
        if q.len() != self.coords.len() {
            return Err(DynamicsError::NoSuchCoordinate {
                index: q.len(),
                count: self.coords.len(),
            });
        }
        let pts: Vec<Vec3> = q.chunks(4).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let ws: Vec<f64> = q.chunks(4).map(|c| c[3]).collect();
        self.surface
            .set_control(pts, ws)
            .map_err(|e| spline(SplineError::from(e)))?;
        self.coords.copy_from_slice(q);
        Ok(())
    }
    fn weight_coordinates(&self) -> Vec<usize> {
        homogeneous_weight_coordinates(self.coords.len())
    }
    fn coordinate_groups(&self) -> Vec<std::ops::Range<usize>> {
        homogeneous_coordinate_groups(self.coords.len())
    }
    fn default_fixed_coordinates(&self) -> Vec<usize> {
        // Gauge: s is unchanged when every weight is scaled by one factor.
        vec![3]
    }
    fn elements(&self) -> Vec<[(f64, f64); 2]> {
        // Bounding rectangles of the cells (the count and the order of the elements; their
        // quadrature comes from `element_quadrature`).
        self.cells
            .iter()
            .map(|c| {
                let lo =
                    [0, 1].map(|d| c.polygon.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min));
                let hi = [0, 1].map(|d| {
                    c.polygon
                        .iter()
                        .map(|p| p[d])
                        .fold(f64::NEG_INFINITY, f64::max)
                });
                [(lo[0], hi[0]), (lo[1], hi[1])]
            })
            .collect()
    }
    fn element_quadrature(
        &self,
        element: usize,
        _order: [usize; 2],
    ) -> Option<(Vec<[f64; 2]>, Vec<f64>)> {
        let cell = self.cells.get(element)?;
        let (p, w) = self.polygon_rule(&cell.polygon).ok()?;
        if let Some(slot) = self.bases.get(element) {
            // The first rule asked for is cached; points of another rule miss the cache and
            // are evaluated directly in `element_jacobian_at`.
            slot.get_or_init(|| {
                let mut tp = TriangularPoint::default();
                let mut values = Vec::with_capacity(p.len() * cell.keep.len());
                for &x in &p {
                    // A zero denominator (weights) leaves the point to the direct path, which
                    // reports it.
                    self.surface
                        .eval_in_element(cell.triangle, x, &mut tp)
                        .ok()?;
                    values.extend(cell.keep.iter().map(|&k| tp.basis[k]));
                }
                Some(CellBasis {
                    params: p.clone(),
                    values,
                })
            });
        }
        Some((p, w))
    }
    fn element_jacobian_at(
        &self,
        element: usize,
        param: [f64; 2],
        out: &mut LocalJacobian,
    ) -> Result<(), DynamicsError> {
        let Some(cell) = self.cells.get(element) else {
            return self.jacobian_at(param, out);
        };
        if let Some(Some(b)) = self.bases.get(element).and_then(OnceLock::get)
            && let Some(i) = b.params.iter().position(|x| *x == param)
        {
            let nk = cell.keep.len();
            let ctl = self.surface.element_controls(cell.triangle);
            return rational_columns(
                &self.surface,
                cell.keep.iter().map(|&k| ctl[k]),
                &b.values[i * nk..(i + 1) * nk],
                param,
                out,
            );
        }
        with_thread_buffer(&POINT, |p| {
            self.surface
                .eval_in_element(cell.triangle, param, p)
                .map_err(|e| spline(SplineError::from(e)))?;
            out.s = p.s;
            out.blocks.clear();
            out.vectors.clear();
            for &k in &cell.keep {
                let c = p.controls[k];
                out.blocks.push((4 * c, p.r[k]));
                out.vectors.push((4 * c + 3, p.g[k]));
            }
            Ok(())
        })
    }
    fn max_degree(&self) -> usize {
        self.surface.basis().degree()
    }
    fn scale(&self) -> f64 {
        self.scale
    }
    fn jacobian_at(&self, param: [f64; 2], out: &mut LocalJacobian) -> Result<(), DynamicsError> {
        with_thread_buffer(&POINT, |p| {
            self.eval(param, p)?;
            out.s = p.s;
            out.blocks.clear();
            out.vectors.clear();
            for (k, &c) in p.controls.iter().enumerate() {
                out.blocks.push((4 * c, p.r[k]));
                out.vectors.push((4 * c + 3, p.g[k]));
            }
            Ok(())
        })
    }
    fn velocity_terms(&self, param: [f64; 2], qdot: &[f64]) -> Result<(Vec3, Vec3), DynamicsError> {
        let mut p = TriangularPoint::default();
        self.eval(param, &mut p)?;
        let (mut w0, mut w1) = (0.0, 0.0);
        let (mut a0, mut a1, mut a2) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
        for (k, &c) in p.controls.iter().enumerate() {
            let n = p.basis[k][0];
            let (w, pc) = (self.weights()[c], self.control_points()[c]);
            let pd = Vec3::new(qdot[4 * c], qdot[4 * c + 1], qdot[4 * c + 2]);
            let wd = qdot[4 * c + 3];
            w0 += n * w;
            w1 += n * wd;
            a0 += pc * (n * w);
            a1 += (pc * wd + pd * w) * n;
            a2 += pd * (n * wd);
        }
        // Directional derivatives along (p', w'), as rational.rs derives them.
        let s = a0 / w0;
        let s1 = (a1 - s * w1) / w0;
        Ok((s1, (a2 - s1 * w1) * (2.0 / w0)))
    }
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        let dom = self.surface.basis().domain();
        let mut p = TriangularPoint::default();
        let mut best = ([0.0; 2], f64::INFINITY);
        const LEVEL: usize = 6;
        for t in 0..dom.triangles().len() {
            let [a, b, c] = dom.corners(t);
            for i in 0..=LEVEL {
                for j in 0..=LEVEL - i {
                    let (l1, l2) = (i as f64 / LEVEL as f64, j as f64 / LEVEL as f64);
                    // Slightly inside so that the point belongs to this triangle.
                    let (l1, l2) = (0.001 + 0.997 * l1, 0.001 + 0.997 * l2);
                    let l0 = 1.0 - l1 - l2;
                    let u = [0, 1].map(|d| l0 * a[d] + l1 * b[d] + l2 * c[d]);
                    self.surface
                        .eval_in_element(t, u, &mut p)
                        .map_err(|e| spline(e.into()))?;
                    let d = (p.s[0] - x).norm_squared();
                    if d < best.1 {
                        best = (u, d);
                    }
                }
            }
        }
        // Gauss-Newton on |s(u) - x|^2, staying in the domain.
        let mut u = best.0;
        for _ in 0..20 {
            self.eval(u, &mut p)?;
            let r = p.s[0] - x;
            let (su, sv) = (p.s[1], p.s[2]);
            let m = nalgebra::Matrix2::new(su.dot(&su), su.dot(&sv), su.dot(&sv), sv.dot(&sv));
            let rhs = nalgebra::Vector2::new(-su.dot(&r), -sv.dot(&r));
            let Some(step) = m.lu().solve(&rhs) else {
                break;
            };
            let next = [u[0] + step[0], u[1] + step[1]];
            if dom.locate(next).is_none() {
                break;
            }
            u = next;
            if step.norm() < 1e-14 * dom.extent() {
                break;
            }
        }
        Ok(u)
    }
}
