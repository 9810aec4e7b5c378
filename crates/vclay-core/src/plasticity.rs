//! Plastic flow of a rest shape: the viscoplastic law under the studio's sculpt mode.
//!
//! The papers' plastic reset (`d-nurbs.txt`'s rest-shape reference; `solids-journal.txt` section
//! 5.4) makes the current shape the rest shape at once. Plastic flow is its rate form: each
//! control point's rest position `x0` follows its current position `x` where the point is
//! displaced past a yield distance `sigma`, at a rate `gamma` (a Perzyna-type overstress law,
//! written on displacements instead of stresses):
//!
//! ```text
//! dx0/dt = gamma * max(0, 1 - sigma / |x - x0|) * (x - x0)
//! ```
//!
//! Held at `x` for a step of length `h`, the overstress `|x - x0| - sigma` decays by the exact
//! factor `exp(-gamma h)`, so one step moves the rest position by
//!
//! ```text
//! x0 <- x0 + f * max(0, 1 - sigma / |x - x0|) * (x - x0),     f = 1 - exp(-gamma h)
//! ```
//!
//! ([`Plasticity::fraction`], [`plastic_flow_factor`]). Below the yield distance the clay is
//! elastic and springs back; above it the excess stays at the rate `gamma`. `gamma -> inf`,
//! `sigma = 0` is the plastic reset applied every step; `gamma = 0` is the papers' elastic clay.
//! `docs/sculpting.md` has the derivation and how the studio uses it.

/// The plastic-flow law's two constants (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plasticity {
    /// Flow rate `gamma` in 1/s (`0` is elastic, large is a reset every step).
    pub rate: f64,
    /// Yield distance `sigma` in model length units: displacements up to it spring back.
    pub yield_distance: f64,
}

/// The largest rate accepted (1/s): `exp(-gamma h)` is 0 in f64 for any step past this.
pub const MAX_RATE: f64 = 1e9;

impl Plasticity {
    /// Validated constants: `rate` in `[0, MAX_RATE]`, `yield_distance` finite and `>= 0`.
    ///
    /// # Errors
    /// A message naming the bad value.
    pub fn new(rate: f64, yield_distance: f64) -> Result<Self, String> {
        if !(rate.is_finite() && (0.0..=MAX_RATE).contains(&rate)) {
            return Err(format!(
                "plastic flow rate {rate} must be in [0, {MAX_RATE:e}] (1/s)"
            ));
        }
        if !(yield_distance.is_finite() && yield_distance >= 0.0) {
            return Err(format!(
                "yield distance {yield_distance} must be finite and non-negative"
            ));
        }
        Ok(Self {
            rate,
            yield_distance,
        })
    }

    /// The fraction `f = 1 - exp(-gamma h)` of the overstress removed in a step of length `h`.
    pub fn fraction(&self, h: f64) -> f64 {
        (-(-self.rate * h).exp_m1()).clamp(0.0, 1.0)
    }
}

/// Checks a step's flow arguments: `fraction` in `[0, 1]`, `yield_distance` finite and
/// non-negative.
///
/// # Errors
/// A message naming the bad value.
pub fn check_flow(fraction: f64, yield_distance: f64) -> Result<(), String> {
    if !(0.0..=1.0).contains(&fraction) {
        return Err(format!(
            "plastic flow fraction {fraction} must be in [0, 1]"
        ));
    }
    Plasticity::new(0.0, yield_distance).map(|_| ())
}

/// The share of a displacement of length `e` that moves the rest position in one step:
/// `fraction * max(0, 1 - yield / e)` (0 for `e <= yield`).
pub fn plastic_flow_factor(fraction: f64, yield_distance: f64, e: f64) -> f64 {
    if e > yield_distance && e > 0.0 {
        fraction * (1.0 - yield_distance / e)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overstress_decays_by_the_exact_exponential() {
        let p = Plasticity::new(3.0, 0.2).unwrap();
        let h = 0.01;
        let x = 1.0;
        let mut x0 = 0.0;
        for _ in 0..100 {
            x0 += plastic_flow_factor(p.fraction(h), p.yield_distance, x - x0) * (x - x0);
        }
        // After t = 1 the overstress 0.8 is 0.8 exp(-3).
        let over = (x - x0) - 0.2;
        assert!((over - 0.8 * (-3.0_f64).exp()).abs() < 1e-12, "{over}");
    }

    #[test]
    fn below_yield_nothing_flows_and_an_infinite_rate_is_the_reset() {
        assert_eq!(plastic_flow_factor(1.0, 0.5, 0.4), 0.0);
        let p = Plasticity::new(MAX_RATE, 0.0).unwrap();
        assert_eq!(plastic_flow_factor(p.fraction(1e-3), 0.0, 2.0), 1.0);
        assert_eq!(Plasticity::new(0.0, 0.0).unwrap().fraction(1.0), 0.0);
    }

    #[test]
    fn bad_constants_are_refused() {
        assert!(Plasticity::new(-1.0, 0.0).is_err());
        assert!(Plasticity::new(f64::NAN, 0.0).is_err());
        assert!(Plasticity::new(1.0, -0.1).is_err());
        assert!(check_flow(1.5, 0.0).is_err());
    }
}
