//! Reproduces Fig. 4 of `ffd-direct-manipulation.txt`: "Transforming a hollow cylinder into a cup
//! with multiple point constraints. a Hollow cylinder; b Sculpted cup; c Computed lattice".
//!
//! A closed hollow cylinder (outer and inner walls, top rim and bottom annulus) is embedded in a
//! cubic lattice. Many point constraints ("the target points are not shown in the figure due to
//! their large number") on both walls scale the radius by a goblet-like profile `s(z)`: narrow
//! waist, flared mouth, wide foot. The multi-point manipulation of eq (12) is solved exactly when
//! the constraints are independent, else (reported) in least-squares mode.
//!
//! Run: `cargo run -p vclay-ffd --example fig4_cup [output-dir]`. Writes `fig4a_cylinder.obj`,
//! `fig4b_cup.obj`, `fig4c_lattice.obj`.

mod common;

use vclay_core::{Parallelism, TriMesh, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdError, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
};

const HEIGHT: f64 = 2.0;
const OUTER: f64 = 1.0;
const INNER: f64 = 0.85;

/// Radial scale of the cup at height `z`: 0.9 at the foot, about 0.45 at the waist, 1.35 at the
/// mouth.
fn scale(z: f64) -> f64 {
    let x = z / HEIGHT;
    0.9 - 2.2 * x + 2.65 * x * x
}

/// Hollow cylinder: outer wall up, rim in, inner wall down, bottom out (a closed profile).
fn hollow_cylinder() -> TriMesh {
    let n = 24;
    let mut profile = Vec::new();
    profile.extend((0..=n).map(|i| (OUTER, HEIGHT * i as f64 / n as f64)));
    profile.extend((1..=4).map(|i| (OUTER + (INNER - OUTER) * i as f64 / 4.0, HEIGHT)));
    profile.extend((1..=n).map(|i| (INNER, HEIGHT * (1.0 - i as f64 / n as f64))));
    profile.extend((1..4).map(|i| (INNER + (OUTER - INNER) * i as f64 / 4.0, 0.0)));
    // Close the loop back to the first ring.
    profile.push(profile[0]);
    vclay_core::TriMesh::revolution(&profile, 64)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::out_dir();
    let cylinder = hollow_cylinder();
    common::write_obj(&dir.join("fig4a_cylinder.obj"), &cylinder)?;

    let spec = LatticeSpec {
        degree: [3; 3],
        control_points: [7, 7, 8],
    };
    let mut lattice = FfdLattice::enclosing(&cylinder.positions, spec, 0.35)?;

    // Sources on both walls: 12 angles x 7 heights x 2 walls = 168 constraints.
    let mut constraints = Vec::new();
    for h in 0..7 {
        let z = HEIGHT * h as f64 / 6.0;
        for a in 0..12 {
            let angle = std::f64::consts::TAU * a as f64 / 12.0;
            let dir2 = Vec3::new(angle.cos(), angle.sin(), 0.0);
            for r in [OUTER, INNER] {
                let s = dir2 * r + Vec3::new(0.0, 0.0, z);
                let t = dir2 * (r * scale(z)) + Vec3::new(0.0, 0.0, z);
                constraints.push(PointConstraint::from_rest_point(&lattice, s, t)?);
            }
        }
    }
    let m = match Manipulation::multi(&lattice, &constraints, &SolveOptions::default()) {
        Ok(m) => m,
        Err(FfdError::ConflictingConstraints { rank, count, .. }) => {
            println!("{count} constraints have rank {rank}: solving in least-squares mode");
            Manipulation::multi(&lattice, &constraints, &SolveOptions::least_squares())?
        }
        Err(e) => return Err(e.into()),
    };
    lattice.apply(&m);
    let worst = constraints
        .iter()
        .map(|c| lattice.point_at(c.params).map(|p| (p - c.target).norm()))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .fold(0.0, f64::max);
    println!(
        "{} constraints, {} of {} control points moved, worst target miss {worst:.2e}",
        constraints.len(),
        m.len(),
        lattice.control_point_count()
    );

    let cup = EmbeddedMesh::new(&lattice, cylinder, Parallelism::Auto);
    common::write_obj(&dir.join("fig4b_cup.obj"), cup.mesh())?;
    common::write_lattice_obj(&dir.join("fig4c_lattice.obj"), &lattice)?;
    Ok(())
}
