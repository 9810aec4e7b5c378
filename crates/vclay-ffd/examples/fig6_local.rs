//! Reproduces Fig. 6 of `ffd-direct-manipulation.txt`: "Deforming the ears of an alien locally
//! with two point constraints; the lattice embeds only the middle part of the head".
//!
//! A procedural head (a slightly elongated sphere) is embedded only partly: the lattice box
//! covers the top middle of the head. Two point constraints pull two points of the crown up and
//! out into "ears". Vertices outside the box stay exactly where they were; the example checks it
//! and prints how many vertices were embedded and how many moved. The lattice (10 x 7 x 7 cubic)
//! is fine enough that the sources' supports do not reach the control points on the box faces
//! the head passes through, so the deformation is the identity there and the surface stays
//! closed (with a coarser lattice the face control points move and the head tears along the box).
//!
//! Run: `cargo run -p vclay-ffd --example fig6_local [output-dir]`. Writes `fig6a_head.obj`,
//! `fig6b_head_ears.obj`, `fig6_lattice.obj`.

mod common;

use vclay_core::{Parallelism, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::out_dir();
    // Head: radius 1 sphere stretched to height 1.3 (poles on z).
    let n = 96;
    let profile: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            let r = if i == 0 || i == n { 0.0 } else { th.sin() };
            (r, -1.3 * th.cos())
        })
        .collect();
    let head = vclay_core::TriMesh::revolution(&profile, 2 * n);
    common::write_obj(&dir.join("fig6a_head.obj"), &head)?;

    // Only the middle part of the crown: |x| < 0.75, |y| < 0.5, z > 0.55.
    let (lo, hi) = (Vec3::new(-0.75, -0.5, 0.55), Vec3::new(0.75, 0.5, 1.35));
    let spec = LatticeSpec {
        degree: [3; 3],
        control_points: [10, 7, 7],
    };
    let mut lattice = FfdLattice::new(spec, lo, hi)?;
    // Sources on the crown at x = +-0.4, y = 0.
    let crown = |x: f64| Vec3::new(x, 0.0, 1.3 * (1.0 - x * x).sqrt());
    let pairs = [
        (crown(-0.4), crown(-0.4) + Vec3::new(-0.15, 0.0, 0.45)),
        (crown(0.4), crown(0.4) + Vec3::new(0.15, 0.0, 0.45)),
    ];
    let constraints = pairs
        .iter()
        .map(|&(s, t)| PointConstraint::from_rest_point(&lattice, s, t))
        .collect::<Result<Vec<_>, _>>()?;
    lattice.apply(&Manipulation::multi(
        &lattice,
        &constraints,
        &SolveOptions::default(),
    )?);
    let embedded = EmbeddedMesh::new(&lattice, head.clone(), Parallelism::Auto);
    let mut outside_moved = 0;
    let mut moved = 0;
    for (v, (a, b)) in embedded
        .mesh()
        .positions
        .iter()
        .zip(&head.positions)
        .enumerate()
    {
        if a != b {
            moved += 1;
            if !embedded.is_embedded(v) {
                outside_moved += 1;
            }
        }
    }
    println!(
        "{} vertices, {} inside the lattice box, {moved} moved, {outside_moved} outside the box moved",
        head.positions.len(),
        embedded.embedded_count()
    );
    assert_eq!(outside_moved, 0);
    // Continuity across the box: vertices on (or very near) the side and bottom faces barely move.
    let near_face = |p: &Vec3| {
        let d = [p.x - lo.x, hi.x - p.x, p.y - lo.y, hi.y - p.y, p.z - lo.z];
        d.iter().all(|&v| v >= 0.0) && d.iter().any(|&v| v < 1e-3)
    };
    let seam = head
        .positions
        .iter()
        .zip(&embedded.mesh().positions)
        .filter(|(p, _)| near_face(p))
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    println!(
        "largest move of a vertex within 1e-3 of a side or bottom face of the box: {seam:.1e}"
    );
    common::write_obj(&dir.join("fig6b_head_ears.obj"), embedded.mesh())?;
    common::write_lattice_obj(&dir.join("fig6_lattice.obj"), &lattice)?;
    Ok(())
}
