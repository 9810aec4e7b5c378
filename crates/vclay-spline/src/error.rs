//! The error type of the spline layer.

use std::fmt;
use thiserror::Error;

/// Names of the parametric axes, for messages.
pub const AXIS_NAMES: [&str; 3] = ["u", "v", "w"];

/// A multi-index into a control net (`[i]`, `[i][j]` or `[i][j][k]`), printed as JSON-style
/// brackets so that it matches the nesting of the model file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NetIndex(pub Vec<usize>);

impl fmt::Display for NetIndex {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for i in &self.0 {
            write!(f, "[{i}]")?;
        }
        Ok(())
    }
}

/// Problems with a knot vector.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum KnotError {
    /// Wrong number of knots for the number of control points and the degree.
    #[error(
        "{found} knots given, expected {expected} (= {control_points} control points + degree {degree} + 1)"
    )]
    Count {
        /// Number of knots given.
        found: usize,
        /// Number required.
        expected: usize,
        /// Number of control points.
        control_points: usize,
        /// Degree.
        degree: usize,
    },
    /// A knot is NaN or infinite.
    #[error("knot {index} is not finite ({value})")]
    NonFinite {
        /// Position in the knot vector.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Knots decrease.
    #[error("knots decrease at index {index}: {value} after {previous}")]
    Decreasing {
        /// Position of the smaller knot.
        index: usize,
        /// The smaller knot.
        value: f64,
        /// The knot before it.
        previous: f64,
    },
    /// Too few control points for the degree.
    #[error("degree {degree} needs at least {} control points, {control_points} given", degree + 1)]
    TooFewControlPoints {
        /// Degree.
        degree: usize,
        /// Number of control points.
        control_points: usize,
    },
    /// The degree exceeds [`crate::MAX_DEGREE`].
    #[error("degree {degree} exceeds the supported maximum {max}")]
    DegreeTooHigh {
        /// Requested degree.
        degree: usize,
        /// Supported maximum.
        max: usize,
    },
    /// The domain `[t_p, t_n]` has zero length: no non-empty knot span.
    #[error(
        "the parameter domain [{start}, {end}] is empty: the knot vector has no non-empty span"
    )]
    EmptyDomain {
        /// Start of the domain (knot `p`).
        start: f64,
        /// End of the domain (knot `n`).
        end: f64,
    },
    /// A knot repeats more than `degree + 1` times, so a basis function vanishes identically.
    #[error(
        "knot {value} (first at index {index}) has multiplicity {multiplicity}, more than degree + 1 = {max}"
    )]
    Multiplicity {
        /// Position of the first copy.
        index: usize,
        /// The knot value.
        value: f64,
        /// How many times it repeats.
        multiplicity: usize,
        /// Largest allowed multiplicity.
        max: usize,
    },
}

/// The error type of `vclay-spline`.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SplineError {
    /// A knot vector is invalid.
    #[error("knot vector along {}: {source}", AXIS_NAMES[*axis])]
    Knots {
        /// Parametric axis (0 = u, 1 = v, 2 = w).
        axis: usize,
        /// What is wrong.
        #[source]
        source: KnotError,
    },
    /// A control point has a non-finite coordinate.
    #[error("control point {index} has a non-finite coordinate")]
    NonFiniteControlPoint {
        /// Its index in the net.
        index: NetIndex,
    },
    /// A weight is not a positive finite number.
    #[error("weight {index} is {value}, weights must be positive and finite")]
    NonPositiveWeight {
        /// Its index in the net.
        index: NetIndex,
        /// Its value.
        value: f64,
    },
    /// Control net and weights (or counts per axis) disagree.
    #[error("{what}: found {found}, expected {expected}")]
    Shape {
        /// What was counted.
        what: String,
        /// Count found.
        found: usize,
        /// Count expected.
        expected: usize,
    },
    /// A parameter lies outside the domain.
    #[error("parameter {} = {value} lies outside the domain [{min}, {max}]", AXIS_NAMES[*axis])]
    ParameterOutOfDomain {
        /// Parametric axis.
        axis: usize,
        /// The parameter.
        value: f64,
        /// Domain start.
        min: f64,
        /// Domain end.
        max: f64,
    },
    /// Knot insertion would raise a knot's multiplicity above the degree.
    #[error(
        "cannot insert {value} {times} time(s) along {}: it already has multiplicity {multiplicity} and degree is {degree}",
        AXIS_NAMES[*axis]
    )]
    InsertionMultiplicity {
        /// Parametric axis.
        axis: usize,
        /// The knot value.
        value: f64,
        /// Requested insertions.
        times: usize,
        /// Existing multiplicity.
        multiplicity: usize,
        /// Degree along that axis.
        degree: usize,
    },
    /// An axis index was not 0, 1 (or 2 for volumes).
    #[error("axis {axis} does not exist on an object with {dims} parametric dimension(s)")]
    NoSuchAxis {
        /// Requested axis.
        axis: usize,
        /// Parametric dimension of the object.
        dims: usize,
    },
    /// A derivative order above [`crate::MAX_DERIVATIVE_ORDER`] was requested.
    #[error("derivative order {order} exceeds the supported maximum {max}")]
    DerivativeOrderTooHigh {
        /// Requested order.
        order: usize,
        /// Supported maximum.
        max: usize,
    },
    /// A parameter is NaN or infinite.
    #[error("parameter {} is not finite ({value})", AXIS_NAMES[*axis])]
    NonFiniteParameter {
        /// Parametric axis.
        axis: usize,
        /// The parameter.
        value: f64,
    },
    /// A triangular B-spline or triangular NURBS is invalid or was evaluated outside its domain.
    #[error(transparent)]
    Triangular(#[from] crate::triangular::TriangularError),
}
