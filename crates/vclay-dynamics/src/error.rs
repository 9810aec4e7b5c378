//! The error type of `vclay-dynamics`.

use thiserror::Error;
use vclay_spline::SplineError;

/// Errors of the dynamics layer.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum DynamicsError {
    /// A geometric operation failed (bad parameter, invalid net).
    #[error(transparent)]
    Spline(#[from] SplineError),
    /// A physical parameter is invalid.
    #[error("invalid parameter {name}: {value} ({why})")]
    Parameter {
        /// Which parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is required.
        why: &'static str,
    },
    /// A per-element density array has the wrong length.
    #[error("{name} has {found} per-element values, the model has {expected} elements")]
    ElementCount {
        /// Which density.
        name: &'static str,
        /// Values given.
        found: usize,
        /// Elements in the model.
        expected: usize,
    },
    /// A control-point index is out of range.
    #[error("control point {index} does not exist (the model has {count})")]
    NoSuchControlPoint {
        /// Requested index.
        index: usize,
        /// Number of control points.
        count: usize,
    },
    /// A linear system cannot be solved.
    #[error("singular system: {what}")]
    Singular {
        /// Explanation and remedy.
        what: String,
    },
    /// A constraint cannot be met (contradicts another, acts on nothing free, or is malformed).
    #[error("constraint {index}: {what}")]
    Constraint {
        /// Index of the constraint in the model's list.
        index: usize,
        /// Explanation.
        what: String,
    },
    /// A generalized coordinate index is out of range.
    #[error("generalized coordinate {index} does not exist (the model has {count})")]
    NoSuchCoordinate {
        /// Requested index.
        index: usize,
        /// Number of coordinates.
        count: usize,
    },
    /// A result could not be written (scenario outputs).
    #[error("cannot write output: {what}")]
    Output {
        /// The file and the reason.
        what: String,
    },
    /// The simulation diverged.
    #[error(
        "simulation diverged at step {step} (t = {time}): {what}; try a time step of at most {suggested_dt:.3e}"
    )]
    Diverged {
        /// Step number (0-based) at which divergence was detected.
        step: usize,
        /// Simulated time.
        time: f64,
        /// What was detected.
        what: String,
        /// A time step that is expected to be stable.
        suggested_dt: f64,
    },
}
