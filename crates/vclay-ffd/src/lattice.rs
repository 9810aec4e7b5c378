//! The FFD lattice: a NURBS volume over an axis-aligned box that is the identity map at rest.
//!
//! **What.** `ffd-direct-manipulation.txt` section 2 embeds the object in a NURBS parallelepiped
//!
//! ```text
//! Q(u, v, w) = sum_{i,j,k} P_ijk R_ijk(u, v, w),   0 <= u, v, w <= 1                       (eq 1)
//! R_ijk(u, v, w) = W_ijk B_i,p(u) B_j,q(v) B_k,r(w) / sum_{a,b,c} W_abc B_a,p(u) B_b,q(v) B_c,r(w)  (eq 2)
//! ```
//!
//! with "uniformly distributed control points", so that the parameters of a point are found "through
//! simple linear transformations".
//!
//! **How.** The knots are clamped uniform on `[0, 1]` and the control points sit at the Greville
//! abscissae `xi_i = (t_{i+1} + ... + t_{i+p}) / p` mapped onto the box `[lo, hi]`. Because
//! `sum_i xi_i B_i,p(u) = u` (Greville identity, exact for any spline space containing the
//! linears), the rest lattice is exactly the affine map `Q(u, v, w) = lo + (hi - lo) * (u, v, w)`,
//! and its inverse is the linear transformation of the paper:
//!
//! ```text
//! (u, v, w) = ((x - lo_x) / (hi_x - lo_x), (y - lo_y) / (hi_y - lo_y), (z - lo_z) / (hi_z - lo_z)).
//! ```
//!
//! (With clamped knots the Greville points are not equally spaced near the faces; the paper's
//! "uniformly distributed" lattice is the uniform-knot special case. What matters for the linear
//! parameterization is the identity property, which the Greville placement gives exactly.)
//!
//! Evaluation touches only the `(p+1)(q+1)(r+1)` control points of the knot span containing the
//! parameters (Piegl & Tiller A2.1/A2.2 through [`vclay_spline::KnotVector`]).
//!
//! **Limitations.** The rest box is axis-aligned; points outside it are not embedded (they stay
//! put), points on its faces (to a relative `1e-12` of the extent) are embedded and deform.
//! Knot vectors are not edited (no knot insertion on a live lattice).

use crate::error::FfdError;
use crate::manipulation::Manipulation;
use vclay_core::{Tolerance, Vec3};
use vclay_spline::{KnotVector, MAX_DEGREE, NurbsVolume};

/// Default degree along each axis: 3, the cubic volumes of `ffd-direct-manipulation.txt` section 7.
pub const DEFAULT_DEGREE: usize = 3;
/// Default number of control points along each axis: 4, the `4 x 4 x 4` lattice of Fig. 5b.
pub const DEFAULT_CONTROL_POINTS: usize = 4;
/// Default relative margin added around a bounding box by [`FfdLattice::enclosing`]: 5% of the
/// extent on each side, so that no vertex sits on a face of the lattice.
pub const DEFAULT_MARGIN: f64 = 0.05;

/// Degrees and control-point counts of a lattice, per axis `(u, v, w)` = `(x, y, z)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeSpec {
    /// Degrees `(p, q, r)`, each at least 1. Default [`DEFAULT_DEGREE`].
    pub degree: [usize; 3],
    /// Control points per axis, each at least `degree + 1`. Default [`DEFAULT_CONTROL_POINTS`].
    pub control_points: [usize; 3],
}

impl Default for LatticeSpec {
    fn default() -> Self {
        Self {
            degree: [DEFAULT_DEGREE; 3],
            control_points: [DEFAULT_CONTROL_POINTS; 3],
        }
    }
}

impl LatticeSpec {
    /// The same degree and control-point count along all three axes.
    pub fn uniform(degree: usize, control_points: usize) -> Self {
        Self {
            degree: [degree; 3],
            control_points: [control_points; 3],
        }
    }

    fn validate(&self) -> Result<(), FfdError> {
        for axis in 0..3 {
            let degree = self.degree[axis];
            if degree < 1 {
                return Err(FfdError::Degree { axis, degree });
            }
            let count = self.control_points[axis];
            if count < degree + 1 {
                return Err(FfdError::TooFewControlPoints {
                    axis,
                    degree,
                    count,
                });
            }
        }
        Ok(())
    }
}

/// The non-zero rational basis values `R_ijk(u, v, w)` of eq (2) at one parameter triple, with
/// their flat control-point indices `(i * n_v + j) * n_w + k` in ascending order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseBasis {
    /// Flat control-point indices, ascending.
    pub indices: Vec<usize>,
    /// `R_ijk`, one per index; they sum to 1 (partition of unity).
    pub values: Vec<f64>,
}

impl SparseBasis {
    /// `sum R_ijk^2`, the denominator of eq (7).
    pub fn sum_squares(&self) -> f64 {
        self.values.iter().map(|r| r * r).sum()
    }

    /// Number of non-zero terms, `(p+1)(q+1)(r+1)`.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether there are no terms (never for a basis from a lattice).
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
}

/// Per-axis non-rational B-spline values at one parameter triple, on the stack.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalBasis {
    /// First non-zero control index per axis (`span - degree`).
    pub base: [usize; 3],
    /// `B_{base+a}` per axis, `a = 0..=degree`.
    pub values: [[f64; MAX_DEGREE + 1]; 3],
}

/// A free-form deformation lattice (`ffd-direct-manipulation.txt` section 2, eqs 1-2): a NURBS
/// volume `Q(u, v, w) = sum P_ijk R_ijk(u, v, w)` over the box `[lo, hi]` that is exactly the
/// identity map while undeformed, with the parameters of a point given by the linear map
/// `(u, v, w) = (x - lo) / (hi - lo)` (componentwise).
///
/// Control points are stored flat, index `(i * n_v + j) * n_w + k`.
#[derive(Clone, Debug, PartialEq)]
pub struct FfdLattice {
    volume: NurbsVolume,
    lo: Vec3,
    hi: Vec3,
    rest: Vec<Vec3>,
    /// `(W P, W)` per control point, kept in sync when the lattice is rational.
    homogeneous: Vec<[f64; 4]>,
    rational: bool,
}

impl FfdLattice {
    /// A lattice over the box `[lo, hi]` with clamped uniform knots and control points at the
    /// Greville abscissae (the identity at rest), unit weights.
    pub fn new(spec: LatticeSpec, lo: Vec3, hi: Vec3) -> Result<Self, FfdError> {
        spec.validate()?;
        for axis in 0..3 {
            let ok = lo[axis].is_finite() && hi[axis].is_finite() && hi[axis] > lo[axis];
            if !ok {
                return Err(FfdError::InvalidBox {
                    lo: lo.into(),
                    hi: hi.into(),
                    axis,
                });
            }
        }
        let volume = NurbsVolume::box_lattice(spec.degree, spec.control_points, lo, hi)?;
        let rest = volume.control_points().to_vec();
        Ok(Self {
            volume,
            lo,
            hi,
            rest,
            homogeneous: Vec::new(),
            rational: false,
        })
    }

    /// A lattice around the bounding box of `points`, grown by `margin` times its extent on each
    /// side (a flat axis is grown by `margin` times the largest extent). Use [`DEFAULT_MARGIN`]
    /// unless only part of the object is to be embedded (then build the box yourself and use
    /// [`FfdLattice::new`]).
    pub fn enclosing(points: &[Vec3], spec: LatticeSpec, margin: f64) -> Result<Self, FfdError> {
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(FfdError::InvalidMargin { margin });
        }
        let first = *points.first().ok_or(FfdError::NoPoints)?;
        if let Some(index) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(FfdError::NonFinitePoint { index });
        }
        let (lo, hi) = points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let ext = hi - lo;
        let largest = ext.max();
        let pad = ext.map(|e| margin * if e > 0.0 { e } else { largest });
        Self::new(spec, lo - pad, hi + pad)
    }

    /// The underlying NURBS volume (current control points and weights).
    pub fn volume(&self) -> &NurbsVolume {
        &self.volume
    }
    /// Degrees `(p, q, r)`.
    pub fn degree(&self) -> [usize; 3] {
        self.volume.degree()
    }
    /// Control points per axis `(n_u, n_v, n_w)`.
    pub fn dims(&self) -> [usize; 3] {
        self.volume.dims()
    }
    /// Total number of control points `n_u n_v n_w`.
    pub fn control_point_count(&self) -> usize {
        self.rest.len()
    }
    /// The rest box `(lo, hi)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }
    /// Length of the box diagonal: the scale that geometric tolerances are relative to.
    pub fn size(&self) -> f64 {
        (self.hi - self.lo).norm()
    }
    /// Knot vectors along u, v, w.
    pub fn knots(&self) -> &[KnotVector; 3] {
        self.volume.knots()
    }
    /// Current control points (flat).
    pub fn control_points(&self) -> &[Vec3] {
        self.volume.control_points()
    }
    /// Control points of the undeformed (identity) lattice.
    pub fn rest_control_points(&self) -> &[Vec3] {
        &self.rest
    }
    /// Current weights (flat).
    pub fn weights(&self) -> &[f64] {
        self.volume.weights()
    }
    /// Whether any weight differs from 1 (then `R_ijk` is rational).
    pub fn is_rational(&self) -> bool {
        self.rational
    }
    /// Flat index of control point `(i, j, k)`.
    pub fn flat_index(&self, i: usize, j: usize, k: usize) -> usize {
        let [_, nv, nw] = self.dims();
        (i * nv + j) * nw + k
    }
    /// Multi-index `(i, j, k)` of a flat control-point index.
    pub fn multi_index(&self, flat: usize) -> [usize; 3] {
        let [_, nv, nw] = self.dims();
        [flat / (nv * nw), (flat / nw) % nv, flat % nw]
    }

    /// Replaces the control points (same count, finite).
    pub fn set_control_points(&mut self, points: Vec<Vec3>) -> Result<(), FfdError> {
        self.volume.set_control_points(points)?;
        self.sync_homogeneous();
        Ok(())
    }

    /// Replaces the weights (same count, positive and finite).
    pub fn set_weights(&mut self, weights: Vec<f64>) -> Result<(), FfdError> {
        self.volume.set_weights(weights)?;
        self.rational = self.volume.weights().iter().any(|&w| w != 1.0);
        self.sync_homogeneous();
        Ok(())
    }

    /// Back to the undeformed lattice: rest control points and unit weights.
    pub fn reset(&mut self) {
        let n = self.rest.len();
        self.volume
            .set_weights(vec![1.0; n])
            .expect("unit weights are valid");
        self.volume
            .set_control_points(self.rest.clone())
            .expect("rest points are valid");
        self.rational = false;
        self.homogeneous.clear();
    }

    /// Adds the displacement field of a manipulation to the control points,
    /// `P_ijk <- P_ijk + delta_ijk` (`ffd-direct-manipulation.txt` eq 3).
    ///
    /// # Panics
    /// If the manipulation was made for a lattice with other dimensions (programmer error), or if
    /// a control point would overflow to infinity (a displacement near `f64::MAX`); use
    /// [`FfdLattice::try_apply`] for displacements that come from user input.
    #[track_caller]
    pub fn apply(&mut self, manipulation: &Manipulation) {
        self.try_apply(manipulation)
            .expect("finite displacements keep control points finite");
    }

    /// [`FfdLattice::apply`] that reports a control point that would leave the finite numbers
    /// ([`FfdError::Spline`] with `NonFiniteControlPoint`) and leaves the lattice unchanged then.
    ///
    /// # Panics
    /// If the manipulation was made for a lattice with other dimensions (programmer error).
    #[track_caller]
    pub fn try_apply(&mut self, manipulation: &Manipulation) -> Result<(), FfdError> {
        assert_eq!(
            manipulation.dims(),
            self.dims(),
            "manipulation made for a lattice of other dimensions"
        );
        let mut pts = self.volume.control_points().to_vec();
        for (i, d) in manipulation.iter() {
            pts[i] += d;
        }
        self.volume.set_control_points(pts)?;
        self.sync_homogeneous();
        Ok(())
    }

    fn sync_homogeneous(&mut self) {
        if self.rational {
            self.homogeneous = self
                .volume
                .control_points()
                .iter()
                .zip(self.volume.weights())
                .map(|(p, &w)| [p.x * w, p.y * w, p.z * w, w])
                .collect();
        } else {
            self.homogeneous.clear();
        }
    }

    /// Parameters `(u, v, w)` of a point of the rest box by the linear map of section 2, or `None`
    /// when it lies outside the box (by more than `1e-12` of the extent; points on the faces are
    /// clamped onto them).
    #[inline]
    pub fn parameters(&self, x: &Vec3) -> Option<[f64; 3]> {
        box_parameters(self.lo, self.hi, x)
    }

    /// Whether a point of the rest space is embedded (see [`FfdLattice::parameters`]).
    pub fn contains(&self, x: &Vec3) -> bool {
        self.parameters(x).is_some()
    }

    /// Checks parameters given by a caller: finite, inside `[0, 1]^3` up to `1e-12`; clamps.
    pub(crate) fn check_params(&self, t: [f64; 3]) -> Result<[f64; 3], FfdError> {
        let tol = Tolerance::PARAMETER.relative;
        if t.iter().all(|u| *u >= -tol && *u <= 1.0 + tol) {
            Ok(t.map(|u| u.clamp(0.0, 1.0)))
        } else {
            Err(FfdError::ParametersOutOfDomain { params: t })
        }
    }

    /// Spans and non-rational basis values at clamped parameters.
    #[inline]
    pub(crate) fn local_basis(&self, t: [f64; 3]) -> LocalBasis {
        let knots = self.volume.knots();
        let mut lb = LocalBasis {
            base: [0; 3],
            values: [[0.0; MAX_DEGREE + 1]; 3],
        };
        for a in 0..3 {
            let kv = &knots[a];
            let span = kv.find_span(t[a]);
            kv.basis(span, t[a], &mut lb.values[a]);
            lb.base[a] = span - kv.degree();
        }
        lb
    }

    /// `(W P, W)` per control point; filled only while the lattice is rational.
    pub(crate) fn homogeneous(&self) -> &[[f64; 4]] {
        &self.homogeneous
    }

    /// Flat index of the first support control point of a local basis.
    #[inline]
    pub(crate) fn base_flat(&self, base: [usize; 3]) -> usize {
        self.flat_index(base[0], base[1], base[2])
    }

    /// The non-zero `R_ijk` of eq (2) at parameters `t` (validated and clamped into `[0, 1]^3`).
    pub fn basis(&self, t: [f64; 3]) -> Result<SparseBasis, FfdError> {
        let t = self.check_params(t)?;
        Ok(self.basis_unchecked(t))
    }

    pub(crate) fn basis_unchecked(&self, t: [f64; 3]) -> SparseBasis {
        self.basis_inner(t, true)
    }

    /// The non-rational tensor-product values `B_i(u) B_j(v) B_k(w)` (the `R_ijk` of unit weights).
    pub(crate) fn basis_products_unchecked(&self, t: [f64; 3]) -> SparseBasis {
        self.basis_inner(t, false)
    }

    fn basis_inner(&self, t: [f64; 3], rational: bool) -> SparseBasis {
        let lb = self.local_basis(t);
        let [p, q, r] = self.degree();
        let [_, nv, nw] = self.dims();
        let w = self.volume.weights();
        let n = (p + 1) * (q + 1) * (r + 1);
        let mut out = SparseBasis {
            indices: Vec::with_capacity(n),
            values: Vec::with_capacity(n),
        };
        let mut sum = 0.0;
        for a in 0..=p {
            for c in 0..=q {
                let bac = lb.values[0][a] * lb.values[1][c];
                for e in 0..=r {
                    let idx = ((lb.base[0] + a) * nv + lb.base[1] + c) * nw + lb.base[2] + e;
                    let wi = if rational { w[idx] } else { 1.0 };
                    let v = wi * bac * lb.values[2][e];
                    sum += v;
                    out.indices.push(idx);
                    out.values.push(v);
                }
            }
        }
        for v in &mut out.values {
            *v /= sum;
        }
        out
    }

    /// The current volume at parameters `t`, `Q(t) = sum P_ijk R_ijk(t)` (eq 1).
    pub fn point_at(&self, t: [f64; 3]) -> Result<Vec3, FfdError> {
        let t = self.check_params(t)?;
        Ok(self.point_at_unchecked(t))
    }

    #[inline]
    pub(crate) fn point_at_unchecked(&self, t: [f64; 3]) -> Vec3 {
        let lb = self.local_basis(t);
        let [p, q, r] = self.degree();
        self.eval_local(
            self.base_flat(lb.base),
            &lb.values[0][..=p],
            &lb.values[1][..=q],
            &lb.values[2][..=r],
        )
    }

    /// Where the deformation takes a point of the rest space: `Q(u(x), v(x), w(x))` inside the
    /// box, `x` itself outside.
    pub fn deform_point(&self, x: &Vec3) -> Vec3 {
        match self.parameters(x) {
            Some(t) => self.point_at_unchecked(t),
            None => *x,
        }
    }

    /// `sum B_a(u) B_c(v) B_e(w) (W P)_{base + (a, c, e)} / sum B B B W` with per-axis non-rational
    /// values; the shared kernel of every evaluation. Contracts along w, then v, then u, so the
    /// cost is `(p+1)(q+1)(r+1) + (p+1)(q+1) + (p+1)` multiply-adds per coordinate.
    #[inline]
    pub(crate) fn eval_local(&self, base: usize, bu: &[f64], bv: &[f64], bw: &[f64]) -> Vec3 {
        let [_, nv, nw] = self.dims();
        let su = nv * nw;
        if !self.rational {
            let pts = self.volume.control_points();
            let (mut x, mut y, mut z) = (0.0, 0.0, 0.0);
            for (a, &ba) in bu.iter().enumerate() {
                let (mut xv, mut yv, mut zv) = (0.0, 0.0, 0.0);
                for (c, &bc) in bv.iter().enumerate() {
                    let start = base + a * su + c * nw;
                    let row = &pts[start..start + bw.len()];
                    let (mut xw, mut yw, mut zw) = (0.0, 0.0, 0.0);
                    for (pt, &be) in row.iter().zip(bw) {
                        xw += pt.x * be;
                        yw += pt.y * be;
                        zw += pt.z * be;
                    }
                    xv += xw * bc;
                    yv += yw * bc;
                    zv += zw * bc;
                }
                x += xv * ba;
                y += yv * ba;
                z += zv * ba;
            }
            Vec3::new(x, y, z)
        } else {
            let pts = &self.homogeneous;
            let mut acc = [0.0; 4];
            for (a, &ba) in bu.iter().enumerate() {
                let mut accv = [0.0; 4];
                for (c, &bc) in bv.iter().enumerate() {
                    let start = base + a * su + c * nw;
                    let row = &pts[start..start + bw.len()];
                    let mut accw = [0.0; 4];
                    for (pt, &be) in row.iter().zip(bw) {
                        for l in 0..4 {
                            accw[l] += pt[l] * be;
                        }
                    }
                    for l in 0..4 {
                        accv[l] += accw[l] * bc;
                    }
                }
                for l in 0..4 {
                    acc[l] += accv[l] * ba;
                }
            }
            Vec3::new(acc[0], acc[1], acc[2]) / acc[3]
        }
    }
}

/// The linear map of section 2, `(u, v, w) = (x - lo) / (hi - lo)` (componentwise), or `None`
/// outside the box by more than `1e-12` of the extent (points on the faces are clamped onto them).
/// Shared by [`FfdLattice::parameters`] and the embedded mesh, which recomputes parameters from
/// its rest positions instead of storing them.
#[inline]
pub(crate) fn box_parameters(lo: Vec3, hi: Vec3, x: &Vec3) -> Option<[f64; 3]> {
    let tol = Tolerance::PARAMETER.relative;
    let mut t = [0.0; 3];
    for a in 0..3 {
        let u = (x[a] - lo[a]) / (hi[a] - lo[a]);
        // NaN fails both comparisons and is rejected.
        if !(u >= -tol && u <= 1.0 + tol) {
            return None;
        }
        t[a] = u.clamp(0.0, 1.0);
    }
    Some(t)
}
