//! The error type of the crate.

use vclay_lattice::{FormatError, LatticeError};
use vclay_spline::SplineError;

/// Everything that can go wrong when building, stepping, editing or scripting a dynamic solid.
#[derive(Debug, thiserror::Error)]
pub enum SolidsError {
    /// A parameter is out of its valid range (name, value and what is expected).
    #[error("invalid parameter `{name}` = {value}: {expected}")]
    InvalidParameter {
        /// Parameter name as the API or scenario file spells it.
        name: String,
        /// The offending value, formatted.
        value: String,
        /// What would be accepted.
        expected: String,
    },
    /// An index (control point, data point, cell, face, tool) is out of range.
    #[error("{what} {index} does not exist (there are {count})")]
    NoSuchElement {
        /// Kind of element ("control point", "control cell", ...).
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many exist.
        count: usize,
    },
    /// The simulation diverged: a non-finite state or an energy past the bound. The state is
    /// left at the last good step.
    #[error(
        "simulation diverged at step {step} (t = {time:.6}): {reason}; time step {dt:e} is too large, try dt <= {suggested_dt:.3e}"
    )]
    Diverged {
        /// Index of the step that failed (0-based count of steps taken before it).
        step: u64,
        /// Simulated time at the start of that step.
        time: f64,
        /// What was detected.
        reason: String,
        /// The time step used.
        dt: f64,
        /// A time step estimated to be stable for the integrator in use.
        suggested_dt: f64,
    },
    /// The mass matrix `A^T M A` of the free control points is not positive definite (for
    /// example a control point that no data point depends on).
    #[error("mass matrix A^T M A is not positive definite ({0})")]
    MassMatrix(String),
    /// All control points are fixed, or the edit left nothing to simulate.
    #[error("nothing to simulate: {0}")]
    Empty(String),
    /// A lattice construction or edit failed.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
    /// A spline construction failed.
    #[error(transparent)]
    Spline(#[from] SplineError),
    /// Reading or writing a lattice file failed.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A scenario file is invalid (file, line, key and message).
    #[error("{file}:{line}: {message}")]
    Scenario {
        /// File name as given.
        file: String,
        /// 1-based line of the offending key (0 when unknown).
        line: usize,
        /// Message naming the key.
        message: String,
    },
    /// An I/O error while writing outputs (path and cause).
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
}

/// Builds [`SolidsError::InvalidParameter`].
pub(crate) fn invalid(name: &str, value: impl std::fmt::Display, expected: &str) -> SolidsError {
    SolidsError::InvalidParameter {
        name: name.to_string(),
        value: value.to_string(),
        expected: expected.to_string(),
    }
}
