//! The solids of the papers' figures that are not timing models (those are in
//! [`crate::benchmarks`]), shared by `vclay demo` and the tests.

use crate::{SolidSource, SolidsError};
use vclay_core::Vec3;
use vclay_spline::KnotVector;

/// The knot vector of `subdivision-solids-journal.txt` Fig 3's first solid (all three
/// directions): cubic, 6 control points, uniform interior knots.
pub const FIG3_UNIFORM_KNOTS: [f64; 10] = [3.0, 3.0, 3.0, 3.0, 4.0, 5.0, 6.0, 6.0, 6.0, 6.0];

/// The knot vector of Fig 3's second solid as vclay reads it. The text prints
/// `[3, 3, 3, 3, 5, 4, 6, 6, 6, 6]`, which is not non-decreasing (a knot vector must be; the
/// OCR or the original swapped or lost a digit), so the figure's point, "different knot
/// vectors blend and distribute the mass differently", is shown with both interior knots
/// moved towards the end: `[3, 3, 3, 3, 5, 5.5, 6, 6, 6, 6]`.
pub const FIG3_NONUNIFORM_KNOTS: [f64; 10] = [3.0, 3.0, 3.0, 3.0, 5.0, 5.5, 6.0, 6.0, 6.0, 6.0];

/// Mass-point samples per direction of the Fig 3 solids (the paper does not give `m0, m1, m2`).
pub const FIG3_SAMPLES: usize = 10;

/// `subdivision-solids-journal.txt` Fig 3: a tricubic B-spline solid with a `6 x 6 x 6`
/// control lattice on the uniform grid of `[0, 1]^3` (the same control points, "identical
/// masses", for both solids) and the knot vector [`FIG3_UNIFORM_KNOTS`] or
/// [`FIG3_NONUNIFORM_KNOTS`] in all three directions; its mass points are the
/// `FIG3_SAMPLES^3` samples `c = B q` (journal eq 3) at uniformly spaced parameters, the data
/// lattice of [`SolidSource::discretize`]. Returns the source, the control points and the mass
/// points.
pub fn fig3_solid(nonuniform: bool) -> Result<(SolidSource, Vec<Vec3>, Vec<Vec3>), SolidsError> {
    let t = if nonuniform {
        FIG3_NONUNIFORM_KNOTS
    } else {
        FIG3_UNIFORM_KNOTS
    };
    let k = KnotVector::new(t.to_vec(), 3, 6)
        .map_err(|e| crate::error::invalid("knots", format!("{t:?}"), &e.to_string()))?;
    let mut q = Vec::with_capacity(216);
    for i in 0..6 {
        for j in 0..6 {
            for l in 0..6 {
                q.push(Vec3::new(i as f64, j as f64, l as f64) / 5.0);
            }
        }
    }
    let source = SolidSource::BSpline {
        knots: [k.clone(), k.clone(), k],
        weights: vec![1.0; 216],
        samples: [FIG3_SAMPLES; 3],
    };
    let c = source.discretize(&q)?.data.points().to_vec();
    Ok((source, q, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Centroid and the spread (largest / smallest) of the gaps between neighbouring mass
    /// points along the x edge `(i, 0, 0)` of the sample grid.
    fn shape(c: &[Vec3]) -> (Vec3, f64) {
        let n = FIG3_SAMPLES;
        let centroid = c.iter().sum::<Vec3>() / c.len() as f64;
        // Mass points of the x edge: the ones with y = z = 0 (the solid's y = z = 0 edge).
        let mut edge: Vec<f64> = c
            .iter()
            .filter(|p| p.y.abs() < 1e-12 && p.z.abs() < 1e-12)
            .map(|p| p.x)
            .collect();
        edge.sort_by(f64::total_cmp);
        assert_eq!(edge.len(), n);
        let gaps: Vec<f64> = edge.windows(2).map(|w| w[1] - w[0]).collect();
        let (lo, hi) = gaps
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &g| (a.min(g), b.max(g)));
        (centroid, hi / lo)
    }

    /// Journal Fig 3: the same 6^3 control points with identical masses, two knot vectors:
    /// the uniform one spreads the mass points symmetrically about the centre, the
    /// non-uniform one shifts and bunches them.
    #[test]
    fn fig3_knot_vectors_distribute_the_mass_differently() {
        let (_, q0, c0) = fig3_solid(false).unwrap();
        let (_, q1, c1) = fig3_solid(true).unwrap();
        assert_eq!(q0, q1, "the same control points");
        assert_eq!(q0.len(), 216);
        assert_eq!(c0.len(), FIG3_SAMPLES.pow(3));
        assert_eq!(c1.len(), c0.len());
        let (m0, spread0) = shape(&c0);
        let (m1, spread1) = shape(&c1);
        for a in 0..3 {
            assert!((m0[a] - 0.5).abs() < 1e-12, "uniform centroid {m0:?}");
            assert!(m1[a] < 0.5 - 0.05, "non-uniform centroid {m1:?}");
        }
        assert!(spread1 > 1.5 * spread0, "gap spread {spread0} -> {spread1}");
        // Both solids span the control lattice's cube (clamped ends interpolate).
        for c in [&c0, &c1] {
            let hi = c.iter().map(|p| p.x).fold(f64::MIN, f64::max);
            let lo = c.iter().map(|p| p.x).fold(f64::MAX, f64::min);
            assert!((hi - 1.0).abs() < 1e-12 && lo.abs() < 1e-12);
        }
    }
}
