//! Direct manipulation: control-point displacements that move source points to targets.
//!
//! **What.** `ffd-direct-manipulation.txt` sections 3-5. A source point `S` with parameters
//! `t_s = (u_s, v_s, w_s)` in the lattice is to pass through a target `T`. Among all control-point
//! displacements `delta_ijk` that achieve it (eq 3, `T = S + sum delta_ijk R_ijk(t_s)`), the one of
//! least `sum ||delta_ijk||^2` (eq 4) is, by the Lagrange conditions (5)-(6),
//!
//! ```text
//! delta_ijk = R_ijk(t_s) (T - S) / sum_abc R_abc(t_s)^2                                   (eq 7)
//! ```
//!
//! (derivation: (6b) gives `delta_ijk = (lambda / 2) R_ijk`; inserted in (6a),
//! `T - S = (lambda / 2) sum R^2`, so `lambda / 2 = (T - S) / sum R^2`). Only the
//! `(p+1)(q+1)(r+1)` control points whose basis functions do not vanish at `t_s` move (the OCR'd
//! paper says "`p` non-vanishing ones" and "`p x q x r` terms", counting by order; with degree `p`
//! there are `p + 1` per axis, `span - p ..= span`).
//!
//! For `h` constraints `(t_f, T_f)` the Lagrange conditions give, with the paper's
//! `N x h` matrix `R` (column `f` holds `R_ijk(t_f)`) and `D = [T_f - S_f]` (`h x 3`),
//!
//! ```text
//! D = R^T delta,   delta = R lambda                                                      (eq 11)
//! delta = R (R^T R)^{-1} D                                                                (eq 12)
//! ```
//!
//! (The OCR lost eqs 8-10; they are the `h`-constraint versions of (5)-(6):
//! `L = sum ||delta||^2 + sum_f lambda_f . (T_f - S_f - sum delta R(t_f))`, stationary at
//! `delta_ijk = sum_f (lambda_f / 2) R_ijk(t_f)` and eq 3 for every `f`.) `R^T R` is `h x h`
//! (the brief's `R R^T` with `R` stored as `h x N` rows): the solve is tiny. See [`SolveMode`] for
//! what happens when it is singular.
//!
//! **Group laws** (section 4). [`Manipulation`] is the displacement field `delta`; applying two
//! manipulations adds their fields, so composition is vector addition: commutative, associative,
//! with the zero field as unit and the negated field as inverse. Because `R_ijk(t_s)` depends on the
//! weights but not on the control points, `omega(S, rho_1) o omega(S, rho_2) = omega(S, rho_1 +
//! rho_2)` holds for fields computed before or after the first is applied.
//!
//! **Limitations.** Displacements are computed for the lattice's current weights: changing
//! weights afterwards changes `R` and hence where a stored manipulation moves the source. Sources
//! are given by rest-space position or directly by parameters; the current position of the source
//! is `Q(t_s)`, so manipulations may follow one another on a deformed lattice.

use crate::error::FfdError;
use crate::lattice::{FfdLattice, SparseBasis};
use crate::solve::{self, SolveMode};
use nalgebra::DMatrix;
use vclay_core::Vec3;

/// Default [`SolveOptions::rank_tolerance`]: `1e-10`, relative to the Frobenius norm of the basis
/// matrix `R` (each row has norm between `1 / sqrt((p+1)(q+1)(r+1))` and 1, since the `R_ijk` are a
/// non-negative partition of unity).
pub const DEFAULT_RANK_TOLERANCE: f64 = 1e-10;
/// Default [`SolveOptions::consistency_tolerance`]: `1e-9`, relative to the lattice size
/// ([`FfdLattice::size`]).
pub const DEFAULT_CONSISTENCY_TOLERANCE: f64 = 1e-9;

/// Options of the multi-point solve (eq 12).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOptions {
    /// Exact or least squares. Default [`SolveMode::Exact`].
    pub mode: SolveMode,
    /// Constraints whose basis rows are within this (relative to `||R||_F`) of the span of the
    /// others count as dependent. Default [`DEFAULT_RANK_TOLERANCE`].
    pub rank_tolerance: f64,
    /// Dependent constraints whose demanded displacements differ by less than this (relative to
    /// the lattice size) are redundant rather than conflicting. Default
    /// [`DEFAULT_CONSISTENCY_TOLERANCE`].
    pub consistency_tolerance: f64,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            mode: SolveMode::default(),
            rank_tolerance: DEFAULT_RANK_TOLERANCE,
            consistency_tolerance: DEFAULT_CONSISTENCY_TOLERANCE,
        }
    }
}

impl SolveOptions {
    /// Default options in least-squares mode.
    pub fn least_squares() -> Self {
        Self {
            mode: SolveMode::LeastSquares,
            ..Self::default()
        }
    }
}

/// A point constraint: the lattice point at parameters `params` (the source `S = Q(params)`)
/// must pass through `target` (`T`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointConstraint {
    /// Parameters `(u, v, w)` of the source in `[0, 1]^3`.
    pub params: [f64; 3],
    /// The target point `T`.
    pub target: Vec3,
}

impl PointConstraint {
    /// A constraint from parameters and a target.
    pub fn new(params: [f64; 3], target: Vec3) -> Self {
        Self { params, target }
    }

    /// A constraint for the source at rest-space position `source` (its parameters by the linear
    /// map of section 2).
    pub fn from_rest_point(
        lattice: &FfdLattice,
        source: Vec3,
        target: Vec3,
    ) -> Result<Self, FfdError> {
        let params = lattice
            .parameters(&source)
            .ok_or(FfdError::OutsideLattice { point: source })?;
        Ok(Self { params, target })
    }
}

/// A direct manipulation `omega`: the control-point displacement field `delta_ijk` of eqs (7) or
/// (12) (`ffd-direct-manipulation.txt`), stored sparsely (ascending flat indices) for one lattice
/// shape. Composition adds fields, inversion negates them (section 4).
#[derive(Clone, Debug, PartialEq)]
pub struct Manipulation {
    dims: [usize; 3],
    indices: Vec<usize>,
    deltas: Vec<Vec3>,
}

impl Manipulation {
    /// The unit element `omega(S, 0)`: no control point moves.
    pub fn identity(lattice: &FfdLattice) -> Self {
        Self {
            dims: lattice.dims(),
            indices: Vec::new(),
            deltas: Vec::new(),
        }
    }

    /// Eq (7): moves the source of `constraint` (currently at `Q(t_s)`) onto its target.
    pub fn single(lattice: &FfdLattice, constraint: &PointConstraint) -> Result<Self, FfdError> {
        let t = lattice.check_params(constraint.params)?;
        if !constraint.target.iter().all(|c| c.is_finite()) {
            return Err(FfdError::NonFiniteTarget { index: 0 });
        }
        let s = lattice.point_at_unchecked(t);
        Ok(Self::from_basis(
            lattice,
            &lattice.basis_unchecked(t),
            constraint.target - s,
        ))
    }

    /// Eq (7) for a displacement `rho = T - S` of the source at parameters `params`: the paper's
    /// `omega(S, rho)`.
    pub fn single_displacement(
        lattice: &FfdLattice,
        params: [f64; 3],
        rho: Vec3,
    ) -> Result<Self, FfdError> {
        let t = lattice.check_params(params)?;
        if !rho.iter().all(|c| c.is_finite()) {
            return Err(FfdError::NonFiniteTarget { index: 0 });
        }
        Ok(Self::from_basis(lattice, &lattice.basis_unchecked(t), rho))
    }

    /// `delta_ijk = R_ijk rho / sum R^2` on the support of `basis`.
    pub(crate) fn from_basis(lattice: &FfdLattice, basis: &SparseBasis, rho: Vec3) -> Self {
        let scale = rho / basis.sum_squares();
        Self {
            dims: lattice.dims(),
            indices: basis.indices.clone(),
            deltas: basis.values.iter().map(|&r| scale * r).collect(),
        }
    }

    /// Eq (12): the least-norm displacement field moving every source `Q(t_f)` onto its target.
    ///
    /// In [`SolveMode::Exact`] dependent constraints with disagreeing targets (the same source
    /// with two targets; more constraints in one span than it has control points) give
    /// [`FfdError::ConflictingConstraints`] naming them; dependent constraints that agree are met.
    /// [`SolveMode::LeastSquares`] returns the minimum-norm least-squares field instead.
    pub fn multi(
        lattice: &FfdLattice,
        constraints: &[PointConstraint],
        options: &SolveOptions,
    ) -> Result<Self, FfdError> {
        let (delta, system) = solve_multi(lattice, constraints, options)?;
        Ok(system.manipulation(lattice, &delta.delta))
    }

    /// Eq (12) with the displacements `D_f = T_f - S_f` given directly.
    ///
    /// # Panics
    /// If `params` and `displacements` differ in length (programmer error).
    #[track_caller]
    pub fn multi_displacements(
        lattice: &FfdLattice,
        params: &[[f64; 3]],
        displacements: &[Vec3],
        options: &SolveOptions,
    ) -> Result<Self, FfdError> {
        assert_eq!(
            params.len(),
            displacements.len(),
            "one displacement per source"
        );
        let system = System::assemble(lattice, params)?;
        let d = displacement_matrix(displacements)?;
        let sol = system.solve(lattice, &d, options)?;
        Ok(system.manipulation(lattice, &sol.delta))
    }

    /// Composition `self o other`: the field of applying both, `delta_1 + delta_2` (section 4).
    ///
    /// # Panics
    /// If the two were made for lattices of different dimensions (programmer error).
    #[track_caller]
    pub fn compose(&self, other: &Self) -> Self {
        assert_eq!(self.dims, other.dims, "manipulations of different lattices");
        let (mut i, mut j) = (0, 0);
        let mut indices = Vec::with_capacity(self.indices.len() + other.indices.len());
        let mut deltas = Vec::with_capacity(indices.capacity());
        while i < self.indices.len() || j < other.indices.len() {
            let a = self.indices.get(i).copied().unwrap_or(usize::MAX);
            let b = other.indices.get(j).copied().unwrap_or(usize::MAX);
            if a == b {
                indices.push(a);
                deltas.push(self.deltas[i] + other.deltas[j]);
                i += 1;
                j += 1;
            } else if a < b {
                indices.push(a);
                deltas.push(self.deltas[i]);
                i += 1;
            } else {
                indices.push(b);
                deltas.push(other.deltas[j]);
                j += 1;
            }
        }
        Self {
            dims: self.dims,
            indices,
            deltas,
        }
    }

    /// The inverse `omega(S, -rho)`: moves every target back to its source ("undo").
    pub fn inverse(&self) -> Self {
        Self {
            dims: self.dims,
            indices: self.indices.clone(),
            deltas: self.deltas.iter().map(|d| -d).collect(),
        }
    }

    /// Lattice dimensions this manipulation is for.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// Flat indices of the control points it moves (ascending).
    pub fn indices(&self) -> &[usize] {
        &self.indices
    }
    /// Their displacements `delta_ijk`.
    pub fn displacements(&self) -> &[Vec3] {
        &self.deltas
    }
    /// `(flat index, delta)` pairs.
    pub fn iter(&self) -> impl Iterator<Item = (usize, Vec3)> + '_ {
        self.indices
            .iter()
            .copied()
            .zip(self.deltas.iter().copied())
    }
    /// Number of control points it touches.
    pub fn len(&self) -> usize {
        self.indices.len()
    }
    /// Whether it touches no control point.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
    /// `sum ||delta_ijk||^2`, the objective of eq (4).
    pub fn norm_squared(&self) -> f64 {
        self.deltas.iter().map(Vec3::norm_squared).sum()
    }
    /// The dense field, one displacement per control point of the lattice.
    pub fn to_dense(&self) -> Vec<Vec3> {
        let mut out = vec![Vec3::zeros(); self.dims.iter().product()];
        for (i, d) in self.iter() {
            out[i] = d;
        }
        out
    }

    /// How far the field moves the lattice point at `params`: `sum delta_ijk R_ijk(params)`.
    pub fn displacement_at(
        &self,
        lattice: &FfdLattice,
        params: [f64; 3],
    ) -> Result<Vec3, FfdError> {
        let b = lattice.basis(params)?;
        let (mut i, mut out) = (0, Vec3::zeros());
        for (&idx, &r) in b.indices.iter().zip(&b.values) {
            // Both index lists ascend: merge.
            while i < self.indices.len() && self.indices[i] < idx {
                i += 1;
            }
            if i < self.indices.len() && self.indices[i] == idx {
                out += self.deltas[i] * r;
            }
        }
        Ok(out)
    }
}

/// The `m` basis rows of a set of sources and the union of their supports.
#[derive(Debug)]
pub(crate) struct System {
    pub bases: Vec<SparseBasis>,
    /// Union of the support indices, ascending.
    pub columns: Vec<usize>,
    /// `A = R^T` on the union, `n_u x m`.
    pub a: DMatrix<f64>,
}

impl System {
    pub fn assemble(lattice: &FfdLattice, params: &[[f64; 3]]) -> Result<Self, FfdError> {
        if params.is_empty() {
            return Err(FfdError::NoConstraints);
        }
        let bases = params
            .iter()
            .map(|&t| lattice.basis(t))
            .collect::<Result<Vec<_>, _>>()?;
        let mut columns: Vec<usize> = bases.iter().flat_map(|b| b.indices.clone()).collect();
        columns.sort_unstable();
        columns.dedup();
        let mut a = DMatrix::zeros(columns.len(), bases.len());
        for (f, b) in bases.iter().enumerate() {
            for (&idx, &r) in b.indices.iter().zip(&b.values) {
                let row = columns.binary_search(&idx).expect("index is in the union");
                a[(row, f)] = r;
            }
        }
        Ok(Self { bases, columns, a })
    }

    pub fn solve(
        &self,
        lattice: &FfdLattice,
        d: &DMatrix<f64>,
        options: &SolveOptions,
    ) -> Result<solve::Solution, FfdError> {
        solve::solve(
            self.a.clone(),
            d,
            options.mode,
            options.rank_tolerance,
            options.consistency_tolerance * lattice.size(),
        )
    }

    pub fn manipulation(&self, lattice: &FfdLattice, delta: &DMatrix<f64>) -> Manipulation {
        Manipulation {
            dims: lattice.dims(),
            indices: self.columns.clone(),
            deltas: (0..self.columns.len())
                .map(|i| Vec3::new(delta[(i, 0)], delta[(i, 1)], delta[(i, 2)]))
                .collect(),
        }
    }
}

fn displacement_matrix(displacements: &[Vec3]) -> Result<DMatrix<f64>, FfdError> {
    if let Some(index) = displacements
        .iter()
        .position(|d| !d.iter().all(|c| c.is_finite()))
    {
        return Err(FfdError::NonFiniteTarget { index });
    }
    Ok(DMatrix::from_fn(displacements.len(), 3, |i, j| {
        displacements[i][j]
    }))
}

/// Assembles and solves eq (12) for constraints given by targets; shared with the decomposition.
pub(crate) fn solve_multi(
    lattice: &FfdLattice,
    constraints: &[PointConstraint],
    options: &SolveOptions,
) -> Result<(solve::Solution, System), FfdError> {
    let params: Vec<[f64; 3]> = constraints.iter().map(|c| c.params).collect();
    let system = System::assemble(lattice, &params)?;
    let mut disp = Vec::with_capacity(constraints.len());
    for (index, c) in constraints.iter().enumerate() {
        if !c.target.iter().all(|x| x.is_finite()) {
            return Err(FfdError::NonFiniteTarget { index });
        }
        let t = lattice.check_params(c.params)?;
        disp.push(c.target - lattice.point_at_unchecked(t));
    }
    let d = displacement_matrix(&disp)?;
    let sol = system.solve(lattice, &d, options)?;
    Ok((sol, system))
}
