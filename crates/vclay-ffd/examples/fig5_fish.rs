//! Reproduces Fig. 5 of `ffd-direct-manipulation.txt`: "Stretching a fish with four point
//! constraints using lattices of different resolutions. a Original fish; b Deformed with a
//! 4 x 4 x 4 lattice; c 4 x 7 x 4; d 4 x 10 x 4".
//!
//! A procedural fish (body of revolution along y, laterally compressed, tail fin) is embedded in
//! cubic lattices with 4, 7 and 10 control points along its length. Two constraints near the
//! mouth pull it forwards and open it; two near the tail pull the fin backwards and spread it.
//! The paper's observation, "with lattices of higher resolutions, the deformation is confined to
//! regions closer to the specified source points", is measured: the share of vertices that move
//! and how far the middle of the body moves both shrink as the resolution grows.
//!
//! Run: `cargo run -p vclay-ffd --example fig5_fish [output-dir]`. Writes `fig5a_fish.obj` and
//! `fig5{b,c,d}_fish_4xNx4.obj` with their lattices.

mod common;

use vclay_core::{Parallelism, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::out_dir();
    let fish = common::fish(96, 48);
    common::write_obj(&dir.join("fig5a_fish.obj"), &fish)?;
    let pi = std::f64::consts::PI;
    // Sources: upper and lower lip, upper and lower tip of the tail fin.
    let pairs = [
        (
            common::fish_point(0.15, 0.5 * pi),
            Vec3::new(0.0, -0.35, 0.55),
        ),
        (
            common::fish_point(0.15, 1.5 * pi),
            Vec3::new(0.0, -0.35, -0.55),
        ),
        (
            common::fish_point(2.95, 0.5 * pi),
            Vec3::new(0.0, 3.45, 0.95),
        ),
        (
            common::fish_point(2.95, 1.5 * pi),
            Vec3::new(0.0, 3.45, -0.95),
        ),
    ];
    // "Middle of the body": vertices with 1.2 < y < 1.8.
    let middle: Vec<usize> = (0..fish.positions.len())
        .filter(|&v| (1.2..1.8).contains(&fish.positions[v].y))
        .collect();
    for (label, ny) in [('b', 4), ('c', 7), ('d', 10)] {
        let spec = LatticeSpec {
            degree: [3; 3],
            control_points: [4, ny, 4],
        };
        let mut lattice = FfdLattice::enclosing(&fish.positions, spec, 0.05)?;
        let constraints = pairs
            .iter()
            .map(|&(s, t)| PointConstraint::from_rest_point(&lattice, s, t))
            .collect::<Result<Vec<_>, _>>()?;
        let m = Manipulation::multi(&lattice, &constraints, &SolveOptions::default())?;
        lattice.apply(&m);
        let miss = constraints
            .iter()
            .map(|c| lattice.point_at(c.params).map(|x| (x - c.target).norm()))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .fold(0.0, f64::max);
        let embedded = EmbeddedMesh::new(&lattice, fish.clone(), Parallelism::Auto);
        let moved = |v: usize| (embedded.mesh().positions[v] - fish.positions[v]).norm();
        let tol = 1e-3 * lattice.size();
        let changed = (0..fish.positions.len())
            .filter(|&v| moved(v) > tol)
            .count();
        let mid = middle.iter().map(|&v| moved(v)).fold(0.0, f64::max);
        println!(
            "4x{ny}x4: targets missed by at most {miss:.1e}; {:.1}% of the vertices move by more \
             than 0.1% of the lattice size; the middle of the body moves by at most {mid:.4}",
            100.0 * changed as f64 / fish.positions.len() as f64
        );
        let name = format!("fig5{label}_fish_4x{ny}x4");
        common::write_obj(&dir.join(format!("{name}.obj")), embedded.mesh())?;
        common::write_lattice_obj(&dir.join(format!("{name}_lattice.obj")), &lattice)?;
    }
    Ok(())
}
