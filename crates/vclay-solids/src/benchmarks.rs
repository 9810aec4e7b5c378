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

/// The benchmark cube at subdivision `level`, at rest.
pub fn cube(level: usize, params: SolidParams) -> Result<DynamicSolid, SolidsError> {
    let control = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0));
    let (source, p) = SolidSource::subdivision(control, BoundaryRule::Sharp, level);
    DynamicSolid::new(source, p, Material::default(), params)
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
