//! The model behind the dynamic-solid speed figures (`docs/performance.md`, the per-step times
//! of `subdivision-solids-journal.txt` Table 2 and issue 4's goals), shared by the examples
//! (`bench_levels`, `kernels`) and `vclay bench --physics`, so that every figure is measured on
//! the same definition: the unit cube of 4^3 control points (3^3 cells) subdivided `level`
//! times with the sharp boundary rule (level 2: 2,197 data points; level 5: 912,673), default
//! material, pulled by a rope from the data point nearest `(1.3, 1.2, 1.1)` (stiffness 50) for
//! three steps before timing.

use crate::{DynamicSolid, Material, SolidParams, SolidSource, SolidsError};
use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, primitives};
use vclay_spline::KnotVector;

/// The benchmark cube at subdivision `level`, at rest.
pub fn cube(level: usize, params: SolidParams) -> Result<DynamicSolid, SolidsError> {
    let (source, p) = subdivision_box(4, level);
    DynamicSolid::new(source, p, Material::default(), params)
}

/// The unit cube as a subdivision solid: `n^3` control points (a box lattice of `(n - 1)^3`
/// cells), sharp boundary rule, `levels` subdivision levels; with its control points.
pub fn subdivision_box(n: usize, levels: usize) -> (SolidSource, Vec<Vec3>) {
    let control = primitives::box_lattice([n, n, n], Vec3::zeros(), Vec3::repeat(1.0));
    SolidSource::subdivision(control, BoundaryRule::Sharp, levels)
}

/// The unit cube as a tricubic B-spline solid: `n^3` control points (`n >= 4`) at the
/// Greville abscissae of clamped uniform knots (so the solid is the identity map of the
/// cube), sampled on a `samples^3` grid; with its control points.
///
/// # Panics
/// If `n < 4` (a programmer error: a cubic needs four control points).
#[track_caller]
pub fn bspline_box(n: usize, samples: usize) -> (SolidSource, Vec<Vec3>) {
    let k = KnotVector::clamped_uniform(3, n).expect("bspline_box: n >= 4");
    let g = k.greville();
    let mut p = Vec::with_capacity(n * n * n);
    for &a in &g {
        for &b in &g {
            for &c in &g {
                p.push(Vec3::new(a, b, c));
            }
        }
    }
    let source = SolidSource::BSpline {
        knots: [k.clone(), k.clone(), k],
        weights: vec![1.0; n * n * n],
        samples: [samples; 3],
    };
    (source, p)
}

/// Attaches the benchmark rope to `s` and takes three steps (the deformed state the figures
/// time).
pub fn pull(s: &mut DynamicSolid) -> Result<(), SolidsError> {
    s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0)?;
    s.run(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_benchmark_cube_has_the_papers_counts_and_moves_when_pulled() {
        let mut s = cube(1, SolidParams::default()).unwrap();
        assert_eq!(s.data_points().len(), 343);
        let before = s.data_points().to_vec();
        pull(&mut s).unwrap();
        assert_eq!(s.steps(), 3);
        assert!(s.data_points().iter().zip(&before).any(|(a, b)| a != b));
    }
}
