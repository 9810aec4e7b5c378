//! The error type of `vclay-ffd`.

use std::fmt;
use thiserror::Error;
use vclay_core::Vec3;
use vclay_spline::SplineError;

const AXIS_NAMES: [&str; 3] = ["u (x)", "v (y)", "w (z)"];

/// One point constraint that the lattice cannot meet together with others (see
/// [`FfdError::ConflictingConstraints`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintConflict {
    /// Index (in the caller's list) of a constraint whose basis row `R(t_c)` is, to the rank
    /// tolerance, a linear combination of the rows of [`ConstraintConflict::depends_on`].
    pub constraint: usize,
    /// Indices of the constraints whose basis rows combine to `R(t_c)`, ascending.
    pub depends_on: Vec<usize>,
    /// Length of `D_c - sum_a x_a D_a`: how far apart the displacements that the same
    /// combination demands are (model units). Zero for redundant (repeated) constraints.
    pub mismatch: f64,
}

impl ConstraintConflict {
    /// All constraints involved, ascending: [`ConstraintConflict::constraint`] and its partners.
    pub fn involved(&self) -> Vec<usize> {
        let mut v = self.depends_on.clone();
        v.push(self.constraint);
        v.sort_unstable();
        v.dedup();
        v
    }
}

impl fmt::Display for ConstraintConflict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "constraint {} conflicts with ", self.constraint)?;
        for (n, i) in self.depends_on.iter().enumerate() {
            if n > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{i}")?;
        }
        write!(f, " (targets disagree by {:.3e})", self.mismatch)
    }
}

/// Displays a list of conflicts separated by semicolons.
fn conflict_list(c: &[ConstraintConflict]) -> String {
    c.iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

/// The error type of `vclay-ffd`.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum FfdError {
    /// A lattice degree is zero (the identity map needs degree >= 1).
    #[error("lattice degree along {} is {degree}, it must be at least 1", AXIS_NAMES[*axis])]
    Degree {
        /// Axis (0 = u/x, 1 = v/y, 2 = w/z).
        axis: usize,
        /// The degree given.
        degree: usize,
    },
    /// Fewer control points than `degree + 1` along an axis.
    #[error(
        "lattice has {count} control points along {} but degree {degree} needs at least {}",
        AXIS_NAMES[*axis], degree + 1
    )]
    TooFewControlPoints {
        /// Axis.
        axis: usize,
        /// Degree along that axis.
        degree: usize,
        /// Control points given.
        count: usize,
    },
    /// The lattice box has a non-finite corner or an extent that is not positive.
    #[error("lattice box [{lo:?}, {hi:?}] has no positive finite extent along {}", AXIS_NAMES[*axis])]
    InvalidBox {
        /// Lower corner.
        lo: [f64; 3],
        /// Upper corner.
        hi: [f64; 3],
        /// First offending axis.
        axis: usize,
    },
    /// A lattice around a point set was asked for, but there are no points.
    #[error("cannot fit a lattice around an empty point set")]
    NoPoints,
    /// A point set contains a non-finite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// Index of the point.
        index: usize,
    },
    /// The relative margin around a bounding box is negative or not finite.
    #[error("relative lattice margin {margin} must be finite and non-negative")]
    InvalidMargin {
        /// The margin given.
        margin: f64,
    },
    /// A source point lies outside the lattice box, so it has no parameters.
    #[error("source point ({}, {}, {}) lies outside the lattice box", point.x, point.y, point.z)]
    OutsideLattice {
        /// The point.
        point: Vec3,
    },
    /// Parameters given directly are not finite or lie outside `[0, 1]^3`.
    #[error("parameters {params:?} lie outside the lattice domain [0, 1]^3")]
    ParametersOutOfDomain {
        /// The parameters.
        params: [f64; 3],
    },
    /// A target or displacement is not finite.
    #[error("constraint {index} has a non-finite target or displacement")]
    NonFiniteTarget {
        /// Index of the constraint.
        index: usize,
    },
    /// A multi-point manipulation was asked for with no constraints.
    #[error("no point constraints given")]
    NoConstraints,
    /// The basis rows of some constraints are linearly dependent (`R R^T` singular to the rank
    /// tolerance) and their targets disagree: no lattice displacement meets them all
    /// (`ffd-direct-manipulation.txt` eq 12 needs `(R^T R)^{-1}`). Use
    /// [`crate::SolveMode::LeastSquares`] to meet them as closely as possible.
    #[error(
        "only {rank} of {count} point constraints are independent and their targets disagree: {}",
        conflict_list(conflicts)
    )]
    ConflictingConstraints {
        /// Numerical rank of the `m x N` basis matrix `R`.
        rank: usize,
        /// Number of constraints `m`.
        count: usize,
        /// The constraints that cannot be met, each with the constraints it depends on.
        conflicts: Vec<ConstraintConflict>,
    },
    /// A weight manipulation would drive a weight to zero or below.
    #[error(
        "weight manipulation would make weight {index} non-positive ({value}) at Newton step {iteration}"
    )]
    NonPositiveWeight {
        /// Flat control-point index.
        index: usize,
        /// The weight it would get.
        value: f64,
        /// Newton step (from 1).
        iteration: usize,
    },
    /// The weight-manipulation Newton iteration did not reach the target.
    #[error(
        "weight manipulation did not converge in {iterations} Newton steps (distance to target {residual:.3e})"
    )]
    WeightNoConvergence {
        /// Steps taken.
        iterations: usize,
        /// Remaining distance to the target (model units).
        residual: f64,
    },
    /// The weight Jacobian `J_w J_w^T` is singular: the support control points of the source
    /// cannot move it in every direction by reweighting (for example, they are coplanar).
    #[error(
        "weight Jacobian is singular at Newton step {iteration}: the target is unreachable by reweighting"
    )]
    SingularWeightJacobian {
        /// Newton step (from 1).
        iteration: usize,
    },
    /// Control points or weights given to the lattice are invalid.
    #[error(transparent)]
    Spline(#[from] SplineError),
}
