//! The models behind the D-NURBS speed figures (`docs/performance.md`, issue 5's goals), shared
//! by the examples (`dnurbs_steps`, `dnurbs_dynamic_weights`) and `vclay bench --physics`, so
//! that every figure is measured on the same definition.
//!
//! Each is an `n x n` bicubic sheet over the unit square on clamped uniform knots, material
//! `mu = 1, gamma = 2, alpha = 1, beta = 0.1` (eqs 16-17), its first row of control points
//! fixed, pulled by a spring (eq 19) from the material point `(0.7, 0.5)` towards a target
//! that moves as `(0.7, 0.5, 0.3 sin 3t)`; stepped implicitly with `dt = 0.01` (eq 18).

use super::{GeneralizedDnurbs, RationalGeometry, Target};
use crate::{DnurbsSurface, DynamicsError, Force, Material};
use std::sync::Arc;
use vclay_core::Vec3;
use vclay_spline::NurbsSurface;

/// Time step of the benchmark runs.
pub const DT: f64 = 0.01;

/// The benchmark sheet: `n x n` (at least 4) cubic control points on the unit square; with
/// `varied_weights` the weights are `1 + 0.2 ((i + j) mod 3)`, else all 1.
pub fn unit_sheet(n: usize, varied_weights: bool) -> Result<NurbsSurface, DynamicsError> {
    if n < 4 {
        return Err(DynamicsError::Parameter {
            name: "benchmark sheet size",
            value: n as f64,
            why: "needs at least 4 x 4 control points for a bicubic sheet",
        });
    }
    let mut pts = Vec::with_capacity(n * n);
    let mut w = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            pts.push(Vec3::new(x, y, 0.0));
            w.push(if varied_weights {
                1.0 + 0.2 * ((i + j) % 3) as f64
            } else {
                1.0
            });
        }
    }
    let mut s = NurbsSurface::clamped_uniform([3, 3], [n, n], pts)?;
    s.set_weights(w)?;
    Ok(s)
}

fn material() -> Material {
    Material::surface(1.0, 2.0, 1.0, 0.1)
}

fn pulling_spring() -> Force {
    Force::Spring {
        param: [0.7, 0.5],
        target: Target::Moving(Arc::new(|t| Vec3::new(0.7, 0.5, 0.3 * (t * 3.0).sin()))),
        stiffness: 50.0,
        kernel: None,
    }
}

/// The frozen-weight benchmark (the 64x64 goal): [`unit_sheet`] with unit weights as a
/// [`DnurbsSurface`] (`M`, `D`, `K` assembled once; the first step factors the system).
pub fn frozen_sheet(n: usize) -> Result<DnurbsSurface, DynamicsError> {
    let mut d = DnurbsSurface::new(unit_sheet(n, false)?, material())?;
    for k in 0..n {
        d.set_fixed(k, true)?;
    }
    d.forces_mut().push(pulling_spring());
    Ok(d)
}

/// The dynamic-weight benchmark (the 16x16 goal): [`unit_sheet`] with varied weights, every
/// control point and weight a generalized coordinate (4 per control point; the first row's
/// positions fixed, its weights free), element matrices rebuilt every step.
pub fn dynamic_sheet(n: usize) -> Result<GeneralizedDnurbs<RationalGeometry>, DynamicsError> {
    dynamic(&unit_sheet(n, true)?, n)
}

/// [`dynamic_sheet`] with unit weights, the stand-in for the studio's dynamic-weight sheet
/// (issue 31's goal: 30 steps/s at 32 x 32; the studio's scenario starts from unit weights):
/// the weight-aware rule starts at the fixed Gauss order (4 x 4 points per element) and raises
/// it only where the weights drift apart.
pub fn uniform_dynamic_sheet(
    n: usize,
) -> Result<GeneralizedDnurbs<RationalGeometry>, DynamicsError> {
    dynamic(&unit_sheet(n, false)?, n)
}

/// A dynamic-weight benchmark model of the sheet `s` (`n x n` control points).
fn dynamic(
    s: &NurbsSurface,
    n: usize,
) -> Result<GeneralizedDnurbs<RationalGeometry>, DynamicsError> {
    let mut d = GeneralizedDnurbs::new(RationalGeometry::from_surface(s), material())?;
    for k in 0..n {
        for c in 0..3 {
            d.set_fixed_coordinate(4 * k + c, true)?;
        }
    }
    d.forces_mut().push(pulling_spring());
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Integrator;

    #[test]
    fn benchmark_models_step_and_keep_their_fixed_row() {
        let mut f = frozen_sheet(5).unwrap();
        let mut g = dynamic_sheet(5).unwrap();
        let row0 = |p: &[Vec3]| p[..5].to_vec();
        let (f0, g0) = (
            row0(f.geometry().control_points()),
            g.geometry().control_points(),
        );
        for _ in 0..3 {
            f.step(Integrator::Implicit { dt: DT }).unwrap();
            g.step(Integrator::Implicit { dt: DT }).unwrap();
        }
        assert_eq!(row0(f.geometry().control_points()), f0);
        assert_eq!(g.geometry().control_points()[..5], g0[..5]);
        // The spring pulls the free part.
        let moved = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).any(|(x, y)| x != y);
        assert!(moved(
            f.geometry().control_points(),
            unit_sheet(5, false).unwrap().control_points()
        ));
        assert!(moved(&g.geometry().control_points(), &g0));
        assert!(unit_sheet(3, false).is_err());
    }
}
