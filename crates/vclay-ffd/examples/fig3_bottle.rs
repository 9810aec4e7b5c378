//! Reproduces Fig. 3 of `ffd-direct-manipulation.txt`: "Modifying a bottle using four point
//! constraints. a Original bottle; b New bottle; c Computed lattice".
//!
//! A bottle-like surface of revolution is embedded in a cubic NURBS lattice (uniform knots, as in
//! section 7). Four sources on the surface get targets: the body is bulged out on both sides
//! along x, and the neck is stretched upwards and bent slightly. The four-point manipulation of
//! eq (12) computes the lattice; every source lands on its target.
//!
//! Run: `cargo run -p vclay-ffd --example fig3_bottle [output-dir]`. Writes
//! `fig3a_bottle.obj`, `fig3b_bottle.obj`, `fig3c_lattice.obj` (and the rest lattice).

mod common;

use vclay_core::{Parallelism, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
};

/// Bottle radius at height `z` in `[0, 3]`: body, shoulder, neck, lip.
fn radius(z: f64) -> f64 {
    let smooth = |a: f64, b: f64, x: f64| {
        let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let body = 1.0;
    let neck = 0.35;
    let r = body + (neck - body) * smooth(1.7, 2.4, z);
    r + 0.06 * smooth(2.85, 2.95, z)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::out_dir();
    let mut profile = vec![(0.0, 0.0)];
    profile.extend((0..=80).map(|i| {
        let z = 3.0 * i as f64 / 80.0;
        (radius(z), z)
    }));
    let bottle = vclay_core::TriMesh::revolution(&profile, 64);
    common::write_obj(&dir.join("fig3a_bottle.obj"), &bottle)?;

    let spec = LatticeSpec {
        degree: [3; 3],
        control_points: [5, 5, 7],
    };
    let mut lattice = FfdLattice::enclosing(&bottle.positions, spec, 0.1)?;
    common::write_lattice_obj(&dir.join("fig3_rest_lattice.obj"), &lattice)?;

    // Four sources on the surface and where they should go.
    let on_surface = |angle: f64, z: f64| {
        let r = radius(z);
        Vec3::new(r * angle.cos(), r * angle.sin(), z)
    };
    let pi = std::f64::consts::PI;
    let pairs = [
        (on_surface(0.0, 0.9), Vec3::new(1.45, 0.0, 0.9)),
        (on_surface(pi, 0.9), Vec3::new(-1.45, 0.0, 0.9)),
        (on_surface(0.5 * pi, 2.7), Vec3::new(0.15, 0.35, 3.3)),
        (on_surface(1.5 * pi, 2.7), Vec3::new(0.15, -0.35, 3.3)),
    ];
    let constraints = pairs
        .iter()
        .map(|&(s, t)| PointConstraint::from_rest_point(&lattice, s, t))
        .collect::<Result<Vec<_>, _>>()?;
    let m = Manipulation::multi(&lattice, &constraints, &SolveOptions::default())?;
    lattice.apply(&m);
    for (f, c) in constraints.iter().enumerate() {
        let miss = (lattice.point_at(c.params)? - c.target).norm();
        println!("constraint {f}: target missed by {miss:.2e}");
    }
    println!(
        "moved {} of {} control points, sum |delta|^2 = {:.4}",
        m.len(),
        lattice.control_point_count(),
        m.norm_squared()
    );

    let embedded = EmbeddedMesh::new(&lattice, bottle, Parallelism::Auto);
    common::write_obj(&dir.join("fig3b_bottle.obj"), embedded.mesh())?;
    common::write_lattice_obj(&dir.join("fig3c_lattice.obj"), &lattice)?;
    Ok(())
}
