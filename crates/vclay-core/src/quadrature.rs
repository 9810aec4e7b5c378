//! Gauss-Legendre quadrature.
//!
//! An `n`-point rule integrates polynomials of degree `2n - 1` exactly on an interval. Nodes are
//! the roots of the Legendre polynomial `P_n`, found by Newton's method from Tricomi's initial
//! guess `cos(pi (i - 1/4) / (n + 1/2))`, with weights `2 / ((1 - x^2) P_n'(x)^2)` (Golub & Welsch
//! give the same numbers by an eigenvalue problem; Newton is simpler and exact to rounding for the
//! small `n` used here). `d-nurbs.txt` section 5.2 uses 4 to 7 points per direction.

use thiserror::Error;

/// Largest supported number of points.
pub const MAX_GAUSS_POINTS: usize = 64;

/// Errors of [`GaussLegendre::new`].
#[derive(Clone, Debug, Error, PartialEq, Eq)]
pub enum QuadratureError {
    /// Zero or too many points requested.
    #[error("Gauss-Legendre rule with {0} points requested; supported are 1 to {MAX_GAUSS_POINTS}")]
    PointCount(usize),
}

/// An `n`-point Gauss-Legendre rule on `[-1, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule (exact for polynomials of degree `2n - 1`).
    pub fn new(n: usize) -> Result<Self, QuadratureError> {
        if n == 0 || n > MAX_GAUSS_POINTS {
            return Err(QuadratureError::PointCount(n));
        }
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            dp = if d != 0.0 { d } else { dp };
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Ok(Self { nodes, weights })
    }

    /// The smallest rule exact for polynomials of `degree`: `n = ceil((degree + 1) / 2)`.
    pub fn exact_for_degree(degree: usize) -> Result<Self, QuadratureError> {
        Self::new((degree + 2) / 2)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Nodes on `[-1, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights on `[-1, 1]` (they sum to 2).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Nodes and weights mapped to `[a, b]`.
    pub fn on_interval(&self, a: f64, b: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (h, m) = (0.5 * (b - a), 0.5 * (a + b));
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(move |(&x, &w)| (m + h * x, w * h))
    }

    /// `integral_a^b f`.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.on_interval(a, b).map(|(x, w)| w * f(x)).sum()
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_are_exact_to_degree_2n_minus_1() {
        for n in 1..=12 {
            let g = GaussLegendre::new(n).unwrap();
            assert!((g.weights().iter().sum::<f64>() - 2.0).abs() < 1e-14);
            for k in 0..2 * n {
                let exact = (3f64.powi(k as i32 + 1) - 1f64) / (k as f64 + 1.0);
                let q = g.integrate(1.0, 3.0, |x| x.powi(k as i32));
                assert!(
                    (q - exact).abs() < 1e-13 * exact.abs().max(1.0),
                    "n={n} k={k}: {q} vs {exact}"
                );
            }
            // One degree more is not exact: the error for x^(2n) is
            // 2^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^2), which stays above rounding for n <= 8.
            if n > 8 {
                continue;
            }
            let k = 2 * n;
            let exact = 2.0 / (k as f64 + 1.0);
            let q = g.integrate(-1.0, 1.0, |x| x.powi(k as i32));
            assert!(
                (q - exact).abs() > 1e-12,
                "n={n} unexpectedly exact for degree {k}"
            );
        }
    }

    #[test]
    fn known_three_point_rule() {
        let g = GaussLegendre::new(3).unwrap();
        let r = (0.6f64).sqrt();
        assert!((g.nodes()[0] + r).abs() < 1e-15 && g.nodes()[1] == 0.0);
        assert!((g.weights()[1] - 8.0 / 9.0).abs() < 1e-15);
        assert!((g.weights()[0] - 5.0 / 9.0).abs() < 1e-15);
        assert_eq!(GaussLegendre::new(0), Err(QuadratureError::PointCount(0)));
    }
}
