//! Tolerance policy.
//!
//! vclay never compares against one absolute epsilon. A [`Tolerance`] is a *relative* number that
//! is scaled by the size of the thing being compared: a parameter tolerance scales with the width of
//! the parameter domain, a geometric tolerance with the largest coordinate of the model.

/// Default relative tolerance for parameters: `1e-12` of the domain width. A parameter this close
/// outside a domain is treated as lying on its boundary (round-off from a caller's arithmetic);
/// anything further out is an error.
pub const DEFAULT_PARAMETER_RELATIVE: f64 = 1e-12;

/// Default relative tolerance for geometry: `1e-10` of the model size (largest absolute coordinate,
/// or 1 for models smaller than 1).
pub const DEFAULT_GEOMETRIC_RELATIVE: f64 = 1e-10;

/// A relative tolerance, turned into an absolute one by [`Tolerance::scaled`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// The relative tolerance (dimensionless).
    pub relative: f64,
}

impl Tolerance {
    /// Tolerance used for parameter domains, [`DEFAULT_PARAMETER_RELATIVE`].
    pub const PARAMETER: Self = Self {
        relative: DEFAULT_PARAMETER_RELATIVE,
    };
    /// Tolerance used for geometry, [`DEFAULT_GEOMETRIC_RELATIVE`].
    pub const GEOMETRIC: Self = Self {
        relative: DEFAULT_GEOMETRIC_RELATIVE,
    };

    /// Absolute tolerance for something of size `scale`: `relative * max(scale, 1)`.
    ///
    /// The floor of 1 keeps tiny models (or zero-size domains) from getting a zero tolerance.
    pub fn scaled(&self, scale: f64) -> f64 {
        self.relative * scale.abs().max(1.0)
    }
}

impl Default for Tolerance {
    fn default() -> Self {
        Self::GEOMETRIC
    }
}
