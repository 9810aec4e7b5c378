//! Decomposition of a multi-point manipulation into single-point ones.
//!
//! **What.** `ffd-direct-manipulation.txt` section 6 (theorem, eqs 13-19): the `h`-constraint
//! manipulation of eq (12) equals `h` single-point manipulations (eq 7) applied one after the
//! other, step `q` moving only the `q`-th source, by a displacement `D_q^(q)` that the theorem
//! computes explicitly.
//!
//! **How.** Step `q` is eq (13), `delta^(q)_ijk = R_ijk(t_q) D_q^(q) / sum R^2(t_q)`. It moves
//! every source `p` by `D_p^(q) = sum delta^(q) R(t_p)` (eq 14); summing over the steps (eq 15)
//! gives `D_p = sum_q [R(t_q) . R(t_p) / sum R^2(t_q)] D_q^(q)`, i.e. `R^T R M = D` with
//! `M_q = D_q^(q) / sum R^2(t_q)` (eq 16). Hence
//!
//! ```text
//! M = (R^T R)^{-1} D = lambda of eq (12),      D_q^(q) = M_q sum_ijk R_ijk^2(t_q),
//! delta = sum_q delta^(q) = R M                                               (eqs 17-18)
//! ```
//!
//! which is eq (12): the steps add up to the multi-point field. (Eq 19 recovers `D_q^(q)` from any
//! non-zero `delta^(q)_ijk`; we compute it from `M` directly.) Since each step's field depends only
//! on `R(t_q)` and `D_q^(q)`, not on the control points, the steps may be applied in any order
//! (section 4); a user who drags source `q` by `D_q^(q)` at step `q` ends at the multi-point
//! result.
//!
//! **Limitations.** The multipliers come from the same solve as eq (12): in least-squares mode, or
//! with redundant constraints, they are the minimum-norm multipliers.

use crate::error::FfdError;
use crate::lattice::FfdLattice;
use crate::manipulation::{Manipulation, PointConstraint, SolveOptions, solve_multi};
use vclay_core::Vec3;

/// One single-point step of a decomposed multi-point manipulation (`ffd-direct-manipulation.txt`
/// eqs 13 and 16: `D_q^(q) = M_q sum R^2(t_q)`).
#[derive(Clone, Debug, PartialEq)]
pub struct DecompositionStep {
    /// Index `q` of the constraint this step moves.
    pub constraint: usize,
    /// Its source parameters `t_q`.
    pub params: [f64; 3],
    /// `D_q^(q)`: how far this step moves source `q` (from wherever earlier steps left it).
    pub displacement: Vec3,
    /// The step's field `delta^(q)` (eq 13), the single-point manipulation
    /// `omega(S_q, D_q^(q))`.
    pub manipulation: Manipulation,
}

impl DecompositionStep {
    /// The target to give a single-point manipulation at this step, `T_q^(q) = Q(t_q) + D_q^(q)`,
    /// for the lattice as the earlier steps left it.
    pub fn target(&self, lattice: &FfdLattice) -> Result<Vec3, FfdError> {
        Ok(lattice.point_at(self.params)? + self.displacement)
    }
}

/// Decomposes the multi-point manipulation of `constraints` (eq 12) into one single-point step per
/// constraint (section 6), in the order given. Fails as [`Manipulation::multi`] does.
pub fn decompose(
    lattice: &FfdLattice,
    constraints: &[PointConstraint],
    options: &SolveOptions,
) -> Result<Vec<DecompositionStep>, FfdError> {
    let (sol, system) = solve_multi(lattice, constraints, options)?;
    Ok(constraints
        .iter()
        .enumerate()
        .map(|(q, c)| {
            let basis = &system.bases[q];
            let m = Vec3::new(sol.lambda[(q, 0)], sol.lambda[(q, 1)], sol.lambda[(q, 2)]);
            let displacement = m * basis.sum_squares();
            DecompositionStep {
                constraint: q,
                params: c.params,
                displacement,
                manipulation: Manipulation::from_basis(lattice, basis, displacement),
            }
        })
        .collect())
}
