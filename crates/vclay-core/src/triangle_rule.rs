//! Quadrature on triangles: the fewest-point symmetric rules with positive weights and interior
//! points for total degrees up to 8, and the collapsed (Duffy) Gauss-Legendre product rule beyond.
//!
//! A symmetric rule is a set of orbits of barycentric points under the permutations of the
//! three vertices: the centroid, orbits of three points `(a, a, 1 - 2a)`, and orbits of six
//! points `(a, b, 1 - a - b)`. The node and weight values are those of D. A. Dunavant, "High
//! degree efficient symmetrical Gaussian quadrature rules for the triangle", Int. J. Numer.
//! Meth. Eng. 21 (1985), tables for degrees 2, 4, 6 and 8 (15 significant digits, so the rules
//! are exact to about 1e-15), and the closed-form seven-point degree-5 rule of J. Radon (1948).
//! Degrees 0-1 use the centroid, degree 3 the degree-4 rule (Dunavant's 4-point degree-3 rule
//! has a negative weight), degree 7 the degree-8 rule. Every rule is checked in the tests
//! against the exact moments `integral x^i y^j = i! j! / (i + j + 2)!` of the reference
//! triangle for all `i + j <= degree`.
//!
//! Points per rule (degree: symmetric / collapsed `k x k`): 2: 3 / 4, 4: 6 / 9, 6: 12 / 16,
//! 8: 16 / 25.

use crate::quadrature::{GaussLegendre, QuadratureError};

/// Highest degree with a tabulated symmetric rule; higher degrees use the collapsed rule.
pub const MAX_SYMMETRIC_DEGREE: usize = 8;

/// Orbits: `(weight, kind)` with the weight of each point of the orbit (the weights of a rule
/// sum to 1 over all points).
#[derive(Clone, Copy)]
enum Orbit {
    /// The centroid.
    Centroid(f64),
    /// `(a, a, 1 - 2a)` and its 2 other permutations.
    Three(f64, f64),
    /// `(a, b, 1 - a - b)` and its 5 other permutations.
    Six(f64, f64, f64),
}

fn orbits(degree: usize) -> Vec<Orbit> {
    use Orbit::*;
    match degree {
        0 | 1 => vec![Centroid(1.0)],
        2 => vec![Three(1.0 / 3.0, 1.0 / 6.0)],
        3 | 4 => vec![
            Three(0.223381589678011, 0.445948490915965),
            Three(0.109951743655322, 0.091576213509771),
        ],
        5 => {
            let r = 15f64.sqrt();
            vec![
                Centroid(9.0 / 40.0),
                Three((155.0 + r) / 1200.0, (6.0 + r) / 21.0),
                Three((155.0 - r) / 1200.0, (6.0 - r) / 21.0),
            ]
        }
        6 => vec![
            Three(0.116786275726379, 0.249286745170910),
            Three(0.050844906370207, 0.063089014491502),
            Six(0.082851075618374, 0.053145049844817, 0.310352451033784),
        ],
        7 | 8 => vec![
            Centroid(0.144315607677787),
            Three(0.095091634267285, 0.459292588292723),
            Three(0.103217370534718, 0.170569307751760),
            Three(0.032458497623198, 0.050547228317031),
            Six(0.027230314174435, 0.008394777409958, 0.263112829634638),
        ],
        _ => vec![],
    }
}

/// A quadrature rule on a triangle in barycentric coordinates, weights summing to 1 (multiply
/// by the triangle's area).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleRule {
    /// Barycentric coordinates of the points.
    points: Vec<[f64; 3]>,
    /// Weights, summing to 1.
    weights: Vec<f64>,
}

impl TriangleRule {
    /// The rule with the fewest points (among those here) exact for polynomials of total
    /// `degree`: symmetric up to [`MAX_SYMMETRIC_DEGREE`], collapsed Gauss-Legendre with
    /// `ceil((degree + 2) / 2)` points per direction beyond (errors past 64 points a direction).
    pub fn exact_for_degree(degree: usize) -> Result<Self, QuadratureError> {
        if degree > MAX_SYMMETRIC_DEGREE {
            return Self::collapsed((degree + 3) / 2);
        }
        let mut points = Vec::new();
        let mut weights = Vec::new();
        for o in orbits(degree) {
            match o {
                Orbit::Centroid(w) => {
                    points.push([1.0 / 3.0; 3]);
                    weights.push(w);
                }
                Orbit::Three(w, a) => {
                    let c = 1.0 - 2.0 * a;
                    for p in [[c, a, a], [a, c, a], [a, a, c]] {
                        points.push(p);
                        weights.push(w);
                    }
                }
                Orbit::Six(w, a, b) => {
                    let c = 1.0 - a - b;
                    for p in [
                        [a, b, c],
                        [b, c, a],
                        [c, a, b],
                        [b, a, c],
                        [a, c, b],
                        [c, b, a],
                    ] {
                        points.push(p);
                        weights.push(w);
                    }
                }
            }
        }
        Ok(Self { points, weights })
    }

    /// The collapsed (Duffy) Gauss-Legendre rule with `k x k` points: the square `[0, 1]^2`
    /// mapped by `(xi, eta) -> (1 - xi, xi (1 - eta), xi eta)` with Jacobian `xi`; exact for
    /// total degree `2k - 2`.
    pub fn collapsed(k: usize) -> Result<Self, QuadratureError> {
        let g = GaussLegendre::new(k)?;
        let pts: Vec<(f64, f64)> = g.on_interval(0.0, 1.0).collect();
        let mut points = Vec::with_capacity(k * k);
        let mut weights = Vec::with_capacity(k * k);
        for &(xi, wx) in &pts {
            for &(eta, we) in &pts {
                points.push([1.0 - xi, xi * (1.0 - eta), xi * eta]);
                // The square's weights times the Jacobian xi, over the reference area 1/2.
                weights.push(2.0 * wx * we * xi);
            }
        }
        Ok(Self { points, weights })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Never true for a constructed rule.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Barycentric coordinates of the points.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// Weights (sum 1).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The points and weights on the triangle `tri` (any orientation): points
    /// `sum_i b_i tri[i]`, weights times the triangle's area.
    pub fn on_triangle(&self, tri: [[f64; 2]; 3]) -> impl Iterator<Item = ([f64; 2], f64)> + '_ {
        let [a, b, c] = tri;
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
        self.points.iter().zip(&self.weights).map(move |(l, &w)| {
            (
                [0, 1].map(|d| l[0] * a[d] + l[1] * b[d] + l[2] * c[d]),
                w * area,
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: usize) -> f64 {
        (1..=n).map(|k| k as f64).product()
    }

    /// Largest error over the monomials `x^i y^j`, `i + j <= degree`, on the reference triangle
    /// `(0,0), (1,0), (0,1)` (exact value `i! j! / (i + j + 2)!`).
    fn worst_moment_error(rule: &TriangleRule, degree: usize) -> f64 {
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let mut worst: f64 = 0.0;
        for i in 0..=degree {
            for j in 0..=degree - i {
                let exact = factorial(i) * factorial(j) / factorial(i + j + 2);
                let got: f64 = rule
                    .on_triangle(tri)
                    .map(|(p, w)| w * p[0].powi(i as i32) * p[1].powi(j as i32))
                    .sum();
                worst = worst.max(((got - exact) / exact).abs());
            }
        }
        worst
    }

    #[test]
    fn every_rule_is_exact_for_its_degree_and_not_beyond_the_next() {
        for degree in 0..=14 {
            let rule = TriangleRule::exact_for_degree(degree).unwrap();
            let e = worst_moment_error(&rule, degree);
            assert!(e < 1e-13, "degree {degree}: relative moment error {e:.2e}");
            // Positive weights, interior points (the rules are safe on any cell).
            assert!(rule.weights().iter().all(|&w| w > 0.0), "degree {degree}");
            for p in rule.points() {
                assert!(
                    p.iter().all(|&b| b > 0.0 && b < 1.0),
                    "degree {degree}: {p:?}"
                );
                assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            }
            // The tabulated rules are not exact far beyond their degree (a check that passed
            // for any rule would be vacuous).
            if degree <= MAX_SYMMETRIC_DEGREE {
                let next = worst_moment_error(&rule, degree + 3);
                assert!(
                    next > 1e-6,
                    "degree {degree}: exact to degree {} too",
                    degree + 3
                );
            }
        }
    }

    #[test]
    fn symmetric_rules_use_fewer_points_than_the_collapsed_rule() {
        for (degree, points) in [(0, 1), (2, 3), (4, 6), (5, 7), (6, 12), (8, 16)] {
            let rule = TriangleRule::exact_for_degree(degree).unwrap();
            assert_eq!(rule.len(), points, "degree {degree}");
            let collapsed = TriangleRule::collapsed((degree + 3) / 2).unwrap();
            assert!(worst_moment_error(&collapsed, degree) < 1e-13);
            assert!(rule.len() <= collapsed.len());
        }
    }

    #[test]
    fn rules_map_onto_any_triangle_with_its_area() {
        let rule = TriangleRule::exact_for_degree(4).unwrap();
        // Clockwise triangle: area 6.
        let tri = [[1.0, 1.0], [1.0, 4.0], [5.0, 1.0]];
        let area: f64 = rule.on_triangle(tri).map(|(_, w)| w).sum();
        assert!((area - 6.0).abs() < 1e-13);
        // Integral of x over it: area * centroid x = 6 * 7/3.
        let ix: f64 = rule.on_triangle(tri).map(|(p, w)| w * p[0]).sum();
        assert!((ix - 14.0).abs() < 1e-12);
    }

    #[test]
    fn too_many_points_are_refused() {
        assert!(TriangleRule::exact_for_degree(200).is_err());
        assert!(TriangleRule::collapsed(0).is_err());
    }
}
