//! The error type of the PDE layer.

use crate::expr::ExprError;
use thiserror::Error;

/// Everything that can go wrong when reading, building or solving a PDE surface.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PdeError {
    /// A spec file could not be read or parsed (JSON syntax, unknown field, wrong type).
    #[error("{place}: {message}")]
    Spec {
        /// File name, with line and column where known, or a field path.
        place: String,
        /// What is wrong.
        message: String,
    },
    /// An expression does not parse, or uses a variable it may not use.
    #[error("{place}: {error}\n{pointer}")]
    Expression {
        /// Field path, e.g. `patches[0].x.u0`.
        place: String,
        /// The parse error with its column.
        error: ExprError,
        /// The expression text with a caret under the column.
        pointer: String,
    },
    /// A value is out of range (trial terms, collocation grid, parameter range, ...).
    #[error("{place}: {message}")]
    InvalidValue {
        /// Field path.
        place: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// Fewer collocation points than unknown constants: eq (9) has no unique solution.
    #[error(
        "patch '{patch}', component {component}: {unknowns} unknown constants \
         ({basics} basic functions x {per_basic} trial terms) but only {points} collocation \
         points; use at least {unknowns} points (e.g. a larger collocation grid) or fewer \
         trial terms"
    )]
    TooFewCollocationPoints {
        /// Patch name.
        patch: String,
        /// Component `x`, `y` or `z`.
        component: char,
        /// Unknown constants J (N - 3) (eq 9).
        unknowns: usize,
        /// Basic functions J.
        basics: usize,
        /// Trial terms per basic function (N - 3, or N - 1 for a three-sided patch).
        per_basic: usize,
        /// Collocation points M.
        points: usize,
    },
    /// The collocation equations do not determine an unknown constant (rank deficiency).
    #[error(
        "patch '{patch}', component {component}, t = {t}: the collocation equations do not \
         determine the constant of basic function '{basic}' with trial term u^{power} \
         (condition estimate {condition:.3e}); {hint}"
    )]
    RankDeficient {
        /// Patch name.
        patch: String,
        /// Component `x`, `y` or `z`.
        component: char,
        /// Time of the solve.
        t: f64,
        /// The basic function whose constant is undetermined.
        basic: String,
        /// The power n of the trial term u^n.
        power: usize,
        /// Ratio of the largest to the smallest kept pivot when the solve stopped.
        condition: f64,
        /// What to change.
        hint: String,
    },
    /// Side conditions (eq 33-35, 37) contradict the u-boundary conditions or each other.
    #[error("patch '{patch}', component {component}, t = {t}: {message}")]
    InconsistentSides {
        /// Patch name.
        patch: String,
        /// Component `x`, `y` or `z`.
        component: char,
        /// Time of the solve.
        t: f64,
        /// Which condition and coefficient disagree, with both values.
        message: String,
    },
    /// The solve produced NaN or infinity (e.g. a shape function evaluated to NaN).
    #[error("patch '{patch}', t = {t}: {what} is not finite")]
    NonFinite {
        /// Patch name.
        patch: String,
        /// Time of the solve.
        t: f64,
        /// What was not finite.
        what: String,
    },
}
