//! Several tensor-product D-NURBS patches sculpted together with G0 or G1 continuity along
//! shared boundaries (`d-nurbs.txt` section 6: "continuity requirements between adjacent surface
//! patches"), issue 18.
//!
//! ## What and how
//! [`PatchesGeometry`] stacks the generalized coordinates of `n` rational patches
//! ([`RationalGeometry`]: x, y, z, w per control point) into one vector and their elements into
//! one list, so one [`GeneralizedDnurbs`](super::GeneralizedDnurbs) integrates eq (18) for all of
//! them in one linear system. Patch `k`'s parameter domain is shifted along u by
//! `k * stride` (`stride` = the widest u domain plus one), so a global parameter names one patch
//! and one point. Continuity joins are linear ties between coordinates
//! ([`LinearTie`], enforced with the constraints of section 6.2 by Lagrange rows and a Newton
//! projection, every step):
//!
//! - **G0** along patch `a`'s `u = max` edge and patch `b`'s `u = min` edge (same v knots and
//!   control-point count): the last control-point row of `a` equals the first row of `b` in
//!   x, y, z and w, so the two boundary curves are the same NURBS curve.
//! - **G1** adds, per boundary column `j`, the collinearity of the three control points across the
//!   edge with the fixed ratio `lambda = h_b / h_a` of the adjacent knot spans:
//!   `P_b1 - P_0 = lambda (P_0 - P_a,n-2)`, and equal weights on the three rows. For clamped
//!   knots the cross-boundary derivatives are then `s_u = p w_1 (P_1 - P_0) / (h w_0)` on both
//!   sides with the same value, so the surfaces join C1 in the shared parametrization (G1: the
//!   normals agree along the whole edge).
//!
//! ## Limitations
//! Joins pair a `u = max` edge with a `u = min` edge (orient the patches accordingly). The
//! collinearity ties make the join C1, a stronger condition than G1 (fewer shapes reachable).
use super::generalized::{
    GeneralizedGeometry, LinearTie, LocalJacobian, homogeneous_coordinate_groups,
    homogeneous_weight_coordinates,
};
use super::rational::RationalGeometry;
use crate::error::DynamicsError;
use vclay_core::Vec3;
use vclay_spline::{NurbsSurface, ParametricSurface};

/// Continuity of a join between two patches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Continuity {
    /// Positional continuity (shared boundary curve).
    G0,
    /// Tangent-plane continuity (collinear control points across the edge; C1 in fact).
    G1,
}

/// Several rational tensor-product patches as one generalized geometry (see the module docs).
#[derive(Clone, Debug)]
pub struct PatchesGeometry {
    patches: Vec<RationalGeometry>,
    /// Offset of each patch's coordinates in the stacked vector.
    offsets: Vec<usize>,
    /// u shift of each patch's domain.
    shifts: Vec<f64>,
    coords: Vec<f64>,
    scale: f64,
}

impl PatchesGeometry {
    /// The patches (at least one; each a valid NURBS surface).
    pub fn new(surfaces: &[NurbsSurface]) -> Result<Self, DynamicsError> {
        if surfaces.is_empty() {
            return Err(DynamicsError::Parameter {
                name: "patches",
                value: 0.0,
                why: "needs at least one patch",
            });
        }
        let stride = surfaces
            .iter()
            .map(|s| {
                let [du, _] = s.domain();
                du.max - du.min
            })
            .fold(0.0, f64::max)
            + 1.0;
        let mut patches = Vec::with_capacity(surfaces.len());
        let mut offsets = Vec::with_capacity(surfaces.len());
        let mut shifts = Vec::with_capacity(surfaces.len());
        let mut coords = Vec::new();
        for (k, s) in surfaces.iter().enumerate() {
            let g = RationalGeometry::from_surface(s);
            offsets.push(coords.len());
            coords.extend_from_slice(g.coordinates());
            let [du, _] = s.domain();
            shifts.push(k as f64 * stride - du.min);
            patches.push(g);
        }
        let scale = patches
            .iter()
            .map(|p| p.scale())
            .fold(f64::MIN_POSITIVE, f64::max);
        Ok(Self {
            patches,
            offsets,
            shifts,
            coords,
            scale,
        })
    }

    /// Number of patches.
    pub fn len(&self) -> usize {
        self.patches.len()
    }

    /// Whether there are no patches (never: construction needs one).
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// Patch `k` as a NURBS surface (current shape).
    pub fn patch(&self, k: usize) -> Result<NurbsSurface, DynamicsError> {
        self.patches
            .get(k)
            .ok_or(DynamicsError::NoSuchCoordinate {
                index: k,
                count: self.patches.len(),
            })?
            .to_surface()
    }

    /// The global parameter of patch `k`'s local parameter `[u, v]`.
    pub fn global_param(&self, k: usize, param: [f64; 2]) -> [f64; 2] {
        [param[0] + self.shifts[k], param[1]]
    }

    /// The patch and local parameter of a global parameter.
    fn locate(&self, param: [f64; 2]) -> (usize, [f64; 2]) {
        let mut best = 0;
        for k in 0..self.patches.len() {
            if param[0] - self.shifts[k] >= -0.5 {
                best = k;
            }
        }
        (best, [param[0] - self.shifts[best], param[1]])
    }

    /// The linear ties that join patch `a`'s `u = max` edge to patch `b`'s `u = min` edge with
    /// `continuity` (module docs). Errors name patches that do not exist or whose edges do not
    /// match (different v knots or counts, or G1 with fewer than two control rows).
    pub fn join(
        &self,
        a: usize,
        b: usize,
        continuity: Continuity,
    ) -> Result<Vec<LinearTie>, DynamicsError> {
        let n = self.patches.len();
        if a >= n || b >= n || a == b {
            return Err(DynamicsError::Parameter {
                name: "join",
                value: a.max(b) as f64,
                why: "joins two different existing patches",
            });
        }
        let (sa, sb) = (self.patch(a)?, self.patch(b)?);
        let [na, ma] = sa.dims();
        let [nb, mb] = sb.dims();
        if ma != mb || sa.knots()[1].as_slice() != sb.knots()[1].as_slice() {
            return Err(DynamicsError::Parameter {
                name: "join",
                value: b as f64,
                why: "the joined edges need the same v knots and control-point count",
            });
        }
        if continuity == Continuity::G1 && (na < 2 || nb < 2) {
            return Err(DynamicsError::Parameter {
                name: "join",
                value: na.min(nb) as f64,
                why: "G1 needs two control-point rows on each side",
            });
        }
        let idx = |patch: usize, i: usize, j: usize, comp: usize| {
            self.offsets[patch] + 4 * (i * ma + j) + comp
        };
        let mut ties = Vec::new();
        for j in 0..ma {
            for comp in 0..4 {
                ties.push(LinearTie {
                    terms: vec![(idx(a, na - 1, j, comp), 1.0), (idx(b, 0, j, comp), -1.0)],
                    value: 0.0,
                });
            }
        }
        if continuity == Continuity::G1 {
            let span = |s: &NurbsSurface, last: bool| {
                let t = s.knots()[0].as_slice();
                let p = s.knots()[0].degree();
                if last {
                    let e = t.len() - 1 - p;
                    let k = t[..e].iter().rposition(|&x| x < t[e]).unwrap_or(0);
                    t[e] - t[k]
                } else {
                    let k = t[p + 1..]
                        .iter()
                        .position(|&x| x > t[p])
                        .map_or(p + 1, |i| i + p + 1);
                    t[k] - t[p]
                }
            };
            let lambda = span(&sb, false) / span(&sa, true);
            for j in 0..ma {
                for comp in 0..3 {
                    // P_b1 + lambda P_a,n-2 - (1 + lambda) P_0 = 0 (P_0 = P_b0).
                    ties.push(LinearTie {
                        terms: vec![
                            (idx(b, 1, j, comp), 1.0),
                            (idx(a, na - 2, j, comp), lambda),
                            (idx(b, 0, j, comp), -(1.0 + lambda)),
                        ],
                        value: 0.0,
                    });
                }
                for (patch, row) in [(a, na - 2), (b, 1)] {
                    ties.push(LinearTie {
                        terms: vec![(idx(patch, row, j, 3), 1.0), (idx(b, 0, j, 3), -1.0)],
                        value: 0.0,
                    });
                }
            }
        }
        Ok(ties)
    }
}

impl GeneralizedGeometry for PatchesGeometry {
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
        for (k, p) in self.patches.iter_mut().enumerate() {
            let o = self.offsets[k];
            let len = p.coordinates().len();
            p.set_coordinates(&q[o..o + len])?;
        }
        self.coords.copy_from_slice(q);
        Ok(())
    }
    fn weight_coordinates(&self) -> Vec<usize> {
        homogeneous_weight_coordinates(self.coords.len())
    }
    fn coordinate_groups(&self) -> Vec<std::ops::Range<usize>> {
        homogeneous_coordinate_groups(self.coords.len())
    }
    /// One weight per patch (the gauge of each rational patch).
    fn default_fixed_coordinates(&self) -> Vec<usize> {
        self.offsets.iter().map(|o| o + 3).collect()
    }
    fn elements(&self) -> Vec<[(f64, f64); 2]> {
        let mut out = Vec::new();
        for (k, p) in self.patches.iter().enumerate() {
            let s = self.shifts[k];
            out.extend(
                p.elements()
                    .into_iter()
                    .map(|[u, v]| [(u.0 + s, u.1 + s), v]),
            );
        }
        out
    }
    fn max_degree(&self) -> usize {
        self.patches
            .iter()
            .map(|p| p.max_degree())
            .max()
            .unwrap_or(1)
    }
    fn element_denominators(&self, element: &[(f64, f64); 2], nodes: &[f64]) -> [Vec<Vec<f64>>; 2] {
        let mid = 0.5 * (element[0].0 + element[0].1);
        let (k, _) = self.locate([mid, element[1].0]);
        let s = self.shifts[k];
        self.patches[k]
            .element_denominators(&[(element[0].0 - s, element[0].1 - s), element[1]], nodes)
    }
    fn scale(&self) -> f64 {
        self.scale
    }
    fn jacobian_at(&self, param: [f64; 2], out: &mut LocalJacobian) -> Result<(), DynamicsError> {
        let (k, local) = self.locate(param);
        self.patches[k].jacobian_at(local, out)?;
        let o = self.offsets[k];
        for b in &mut out.blocks {
            b.0 += o;
        }
        for v in &mut out.vectors {
            v.0 += o;
        }
        Ok(())
    }
    fn velocity_terms(&self, param: [f64; 2], qdot: &[f64]) -> Result<(Vec3, Vec3), DynamicsError> {
        let (k, local) = self.locate(param);
        let o = self.offsets[k];
        let len = self.patches[k].coordinates().len();
        self.patches[k].velocity_terms(local, &qdot[o..o + len])
    }
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
        let mut best = (f64::INFINITY, [0.0, 0.0]);
        for (k, p) in self.patches.iter().enumerate() {
            let prm = p.nearest_param(x)?;
            let s = p.to_surface()?;
            let d = (s.point(prm[0], prm[1]).map_err(DynamicsError::from)? - x).norm();
            if d < best.0 {
                best = (d, self.global_param(k, prm));
            }
        }
        Ok(best.1)
    }
}
