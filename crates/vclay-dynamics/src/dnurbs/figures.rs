//! The data sets and starting shapes of the paper's fitting figures (`d-nurbs.txt` Fig 7), shared
//! by the examples, the tests and `vclay demo`. The paper does not list its data; these are
//! documented stand-ins with the same counts.

use vclay_core::Vec3;
use vclay_spline::{NurbsSurface, SplineError};

/// A flat `n x n` sheet of the given degree in the z = 0 plane, centred at the origin, of side
/// `extent`, on clamped uniform knots (the starting shape of Fig 7a/7b).
pub fn flat_sheet(n: usize, degree: usize, extent: f64) -> Result<NurbsSurface, SplineError> {
    let mut pts = Vec::with_capacity(n * n);
    let step = extent / (n.max(2) - 1) as f64;
    for i in 0..n {
        for j in 0..n {
            pts.push(Vec3::new(
                -0.5 * extent + step * i as f64,
                -0.5 * extent + step * j as f64,
                0.0,
            ));
        }
    }
    NurbsSurface::clamped_uniform([degree, degree], [n, n], pts)
}

/// Fig 7a: 19 points of the unit hemisphere: the pole, a ring of 6 at polar angle 0.45 and a ring
/// of 12 at polar angle 1.0.
pub fn hemisphere_points() -> Vec<Vec3> {
    let mut v = vec![Vec3::new(0.0, 0.0, 1.0)];
    for (count, polar) in [(6, 0.45f64), (12, 1.0f64)] {
        for k in 0..count {
            let t = std::f64::consts::TAU * k as f64 / count as f64;
            v.push(Vec3::new(
                polar.sin() * t.cos(),
                polar.sin() * t.sin(),
                polar.cos(),
            ));
        }
    }
    v
}

/// Fig 7b: a convex/concave set of 19 points (the paper's count), the saddle
/// `z = (x^2 - y^2) / 2` at the centre, a ring of 6 at radius 0.45 and a ring of 12 at radius
/// 0.9 (the pattern of [`hemisphere_points`]).
pub fn saddle_points() -> Vec<Vec3> {
    let mut v = vec![Vec3::zeros()];
    for (count, r) in [(6, 0.45f64), (12, 0.9f64)] {
        for k in 0..count {
            let t = std::f64::consts::TAU * k as f64 / count as f64;
            let (x, y) = (r * t.cos(), r * t.sin());
            v.push(Vec3::new(x, y, 0.5 * (x * x - y * y)));
        }
    }
    v
}
