//! Reproduces Fig. 7 of `ffd-direct-manipulation.txt`: "Decomposability of multiple point
//! constraints: a Original fish; b Result of an FFD with four point constraints; c-f Results of
//! four manipulations with single point constraints".
//!
//! The four-point manipulation of eq (12) is computed on the procedural fish, then decomposed
//! (section 6, eqs 13-19) into four single-point manipulations, each moving only its own source by
//! `D_q^(q)`. Applied one after the other to the undeformed lattice (writing the fish after each
//! step), they end exactly (to rounding) at the four-point result; the example prints the
//! largest difference of control points and of fish vertices.
//!
//! Run: `cargo run -p vclay-ffd --example fig7_decomposition [output-dir]`. Writes
//! `fig7a_fish.obj`, `fig7b_four_points.obj`, `fig7{c,d,e,f}_step{1..4}.obj`.

mod common;

use vclay_core::{Parallelism, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions, decompose,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::out_dir();
    let fish = common::fish(96, 48);
    common::write_obj(&dir.join("fig7a_fish.obj"), &fish)?;
    let pi = std::f64::consts::PI;
    let pairs = [
        (common::fish_point(0.3, 0.5 * pi), Vec3::new(0.0, 0.1, 0.75)),
        (common::fish_point(1.2, 0.0), Vec3::new(0.65, 1.2, 0.1)),
        (
            common::fish_point(1.8, 1.5 * pi),
            Vec3::new(0.0, 1.9, -0.85),
        ),
        (common::fish_point(2.9, 0.5 * pi), Vec3::new(0.3, 3.2, 0.7)),
    ];
    let spec = LatticeSpec {
        degree: [3; 3],
        control_points: [4, 7, 4],
    };
    let rest = FfdLattice::enclosing(&fish.positions, spec, 0.05)?;
    let constraints = pairs
        .iter()
        .map(|&(s, t)| PointConstraint::from_rest_point(&rest, s, t))
        .collect::<Result<Vec<_>, _>>()?;
    let options = SolveOptions::default();

    let mut multi = rest.clone();
    multi.apply(&Manipulation::multi(&rest, &constraints, &options)?);
    let four = EmbeddedMesh::new(&multi, fish.clone(), Parallelism::Auto);
    common::write_obj(&dir.join("fig7b_four_points.obj"), four.mesh())?;

    let steps = decompose(&rest, &constraints, &options)?;
    let mut lattice = rest.clone();
    let mut embedded = EmbeddedMesh::new(&lattice, fish.clone(), Parallelism::Auto);
    for (k, step) in steps.iter().enumerate() {
        // A user would drag source q to this target on the lattice as the earlier steps left it.
        let target = step.target(&lattice)?;
        let single = Manipulation::single(&lattice, &PointConstraint::new(step.params, target))?;
        lattice.apply(&single);
        embedded.update(&lattice, single.indices(), Parallelism::Auto);
        let name = format!("fig7{}_step{}.obj", ['c', 'd', 'e', 'f'][k], k + 1);
        common::write_obj(&dir.join(&name), embedded.mesh())?;
        println!(
            "step {}: source {} moved by |D| = {:.4}",
            k + 1,
            step.constraint,
            step.displacement.norm()
        );
    }
    let cp = lattice
        .control_points()
        .iter()
        .zip(multi.control_points())
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let vx = embedded
        .mesh()
        .positions
        .iter()
        .zip(&four.mesh().positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    println!(
        "four single-point steps vs one four-point manipulation: control points differ by at \
         most {cp:.1e}, fish vertices by at most {vx:.1e} (lattice size {:.2})",
        rest.size()
    );
    assert!(cp < 1e-12 * rest.size() && vx < 1e-12 * rest.size());
    Ok(())
}
