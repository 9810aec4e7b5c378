//! Scalar and vector types used throughout vclay.
//!
//! All numerics are `f64`. Points and vectors in space are [`Vec3`] (nalgebra's `Vector3<f64>`);
//! homogeneous (weighted) control points `(w x, w y, w z, w)` are [`Vec4`].

use std::fmt;

/// A point or vector in 3-space.
pub type Vec3 = nalgebra::Vector3<f64>;
/// A homogeneous point `(w x, w y, w z, w)` (Piegl & Tiller, The NURBS Book, eq. 4.4).
pub type Vec4 = nalgebra::Vector4<f64>;

/// A closed parameter interval `[min, max]` with `min <= max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub min: f64,
    /// Upper end.
    pub max: f64,
}

impl Interval {
    /// Creates `[min, max]`.
    ///
    /// # Panics
    /// If `min > max` or either end is not finite (a programmer error: intervals are produced by
    /// validated objects such as knot vectors).
    #[track_caller]
    pub fn new(min: f64, max: f64) -> Self {
        assert!(
            min.is_finite() && max.is_finite() && min <= max,
            "invalid interval [{min}, {max}]"
        );
        Self { min, max }
    }

    /// `max - min`.
    pub fn length(&self) -> f64 {
        self.max - self.min
    }

    /// Whether `t` lies in `[min - slack, max + slack]`.
    pub fn contains_with(&self, t: f64, slack: f64) -> bool {
        t >= self.min - slack && t <= self.max + slack
    }

    /// Clamps `t` into the interval.
    pub fn clamp(&self, t: f64) -> f64 {
        t.clamp(self.min, self.max)
    }

    /// `n` equally spaced samples from `min` to `max` inclusive (`n >= 2`), or `[min]` when `n == 1`.
    pub fn linspace(&self, n: usize) -> Vec<f64> {
        match n {
            0 => Vec::new(),
            1 => vec![self.min],
            _ => {
                let step = self.length() / (n - 1) as f64;
                (0..n)
                    .map(|i| {
                        if i == n - 1 {
                            self.max
                        } else {
                            self.min + step * i as f64
                        }
                    })
                    .collect()
            }
        }
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {}]", self.min, self.max)
    }
}

/// Binomial coefficient `C(n, k)` as `f64` (exact for the small arguments used by derivative
/// formulas).
pub fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    let mut r = 1.0;
    for i in 0..k {
        r = r * (n - i) as f64 / (i + 1) as f64;
    }
    r.round()
}

/// Largest absolute coordinate over a set of points: the model scale used by relative tolerances.
pub fn max_abs_coordinate<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> f64 {
    points.into_iter().map(|p| p.amax()).fold(0.0_f64, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_rows() {
        assert_eq!(binomial(5, 2), 10.0);
        assert_eq!(binomial(10, 0), 1.0);
        assert_eq!(binomial(10, 10), 1.0);
        assert_eq!(binomial(3, 4), 0.0);
        assert_eq!(binomial(20, 10), 184_756.0);
    }

    #[test]
    fn linspace_hits_both_ends_exactly() {
        let iv = Interval::new(0.1, 0.7);
        let s = iv.linspace(7);
        assert_eq!(s.len(), 7);
        assert_eq!(s[0], 0.1);
        assert_eq!(s[6], 0.7);
        assert!(s.windows(2).all(|w| w[0] < w[1]));
    }
}
