//! Demo steps of the FFD layer (issue 6): direct manipulation of free-form deformation.

use anyhow::{Result, ensure};
use std::path::Path;
use std::time::Instant;
use vclay::core::Parallelism;
use vclay::ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
};
use vclay::io::mesh::write_mesh;
use vclay::io::model::{Entity, write_model};
use vclay::{TriMesh, Vec3};

/// Bottle radius at height `z` in `[0, 3]`: body, shoulder, neck.
fn bottle_radius(z: f64) -> f64 {
    let t = ((z - 1.7) / 0.7).clamp(0.0, 1.0);
    1.0 - 0.65 * t * t * (3.0 - 2.0 * t)
}

/// `ffd-direct-manipulation.txt` Fig. 3: a bottle reshaped by four point constraints at once
/// (eq 12): the body bulged along x, the neck stretched up and bent. Writes the original and the
/// new bottle (OBJ) and the computed lattice (`nurbs-volume` model file, readable by
/// `vclay eval`).
pub fn bottle(out: &Path) -> Result<(String, Vec<String>)> {
    std::fs::create_dir_all(out.join("ffd"))?;
    let n = 120;
    let mut profile = vec![(0.0, 0.0)];
    profile.extend((0..=n).map(|i| {
        let z = 3.0 * i as f64 / n as f64;
        (bottle_radius(z), z)
    }));
    profile.push((0.0, 3.0));
    let original = TriMesh::revolution(&profile, 96);
    let spec = LatticeSpec {
        degree: [3; 3],
        control_points: [5, 5, 7],
    };
    let mut lattice = FfdLattice::enclosing(&original.positions, spec, 0.1)?;
    let on_surface = |angle: f64, z: f64| {
        let r = bottle_radius(z);
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
    let t0 = Instant::now();
    let m = Manipulation::multi(&lattice, &constraints, &SolveOptions::default())?;
    lattice.apply(&m);
    let embedded = EmbeddedMesh::new(&lattice, original.clone(), Parallelism::Auto);
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let miss = constraints
        .iter()
        .map(|c| lattice.point_at(c.params).map(|x| (x - c.target).norm()))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .fold(0.0, f64::max);
    ensure!(
        miss <= 1e-12 * lattice.size(),
        "targets missed by {miss:e} (more than 1e-12 of the lattice size)"
    );
    let files = [
        "ffd/fig3a-bottle.obj",
        "ffd/fig3b-bottle.obj",
        "ffd/fig3c-lattice.json",
    ];
    write_mesh(out.join(files[0]), &original)?;
    write_mesh(out.join(files[1]), embedded.mesh())?;
    write_model(
        out.join(files[2]),
        &[Entity::Volume(lattice.volume().clone())],
    )?;
    Ok((
        format!(
            "bottle of {} vertices reshaped by 4 point constraints in {ms:.1} ms \
             ({} of {} control points moved); largest target miss {miss:.1e}",
            original.positions.len(),
            m.len(),
            lattice.control_point_count()
        ),
        files.iter().map(|s| s.to_string()).collect(),
    ))
}
