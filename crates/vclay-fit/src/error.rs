//! The error type of `vclay-fit`.

use thiserror::Error;

/// Why a point cloud could not be fitted. Every variant names the offending value (a point
/// index, an option, a count and its limit).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FitError {
    /// Fewer points than the fit needs.
    #[error("{found} points are too few: {why}")]
    TooFewPoints {
        /// Points given.
        found: usize,
        /// The rule that was broken.
        why: String,
    },
    /// More points than [`crate::MAX_POINTS`].
    #[error("{found} points are more than the limit of {limit}")]
    TooManyPoints {
        /// Points given.
        found: usize,
        /// The limit.
        limit: usize,
    },
    /// A point with a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite {
        /// 0-based index of the point.
        index: usize,
        /// Its coordinates.
        x: f64,
        /// y.
        y: f64,
        /// z.
        z: f64,
    },
    /// The cloud does not span a surface: all points coincide, or lie on a line.
    #[error("degenerate cloud: {why}")]
    Degenerate {
        /// What was found (with the principal extents).
        why: String,
    },
    /// A bad option (grid, degree, fairness, iteration counts).
    #[error("{name} = {value}: {why}")]
    Option {
        /// The option, as the command line names it (`grid`, `degree`, `fairness`).
        name: &'static str,
        /// The value given.
        value: String,
        /// The rule.
        why: String,
    },
    /// The normal equations are singular or indefinite (Cholesky pivot not positive).
    #[error(
        "the least-squares system is singular ({why}); some control points have no data near \
         them: add fairness (e.g. --fairness 0,1e-6) or use a coarser grid"
    )]
    Singular {
        /// What the factorization reported.
        why: String,
    },
    /// A fit produced non-finite numbers (divergence of the rational iteration or overflow).
    #[error("the fit diverged: {why}")]
    Diverged {
        /// Where it was detected.
        why: String,
    },
    /// The D-NURBS stiffness assembly (`vclay-dynamics`) refused the surface.
    #[error("fairness energy: {0}")]
    Energy(String),
}
