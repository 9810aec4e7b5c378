//! Quick timing of embedded-mesh deformation (not a benchmark harness; no assertions).
//!
//! Embeds a UV sphere of about one million vertices in cubic lattices of `4^3`, `7^3`, `10^3` and `20^3`
//! control points and times: embedding (knot cells and local coordinates, bucketing, the first
//! deformation and normals; wall time including the clone of the input mesh, and the CPU time
//! of a sequential embedding), a full deformation (positions only, sequential and on rayon's
//! pool; "per-vertex kernel" is the B-spline reference path), normal recomputation, and an
//! incremental update after a single-point manipulation.
//!
//! Run: `cargo run --release -p vclay-ffd --example bench_deform [vertices-per-side [cps,...]]`
//! (the second argument picks the lattices, e.g. `4` or `4,20`; default `4,7,10,20`).

mod common;

use std::time::Instant;
use vclay_core::{Parallelism, Vec3};
use vclay_ffd::{EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation};

fn main() {
    // The same run's reference workload (issue 31), at the start and at the end.
    let yard_start = vclay_core::yardstick::measure(0.3);
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let mesh = common::uv_sphere(n);
    println!(
        "{} vertices, {} triangles, {} rayon threads",
        mesh.positions.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    let lattices: Vec<usize> = std::env::args()
        .nth(2)
        .map(|s| s.split(',').filter_map(|c| c.parse().ok()).collect())
        .unwrap_or_else(|| vec![4, 7, 10, 20]);
    for cps in lattices {
        let mut lattice =
            FfdLattice::enclosing(&mesh.positions, LatticeSpec::uniform(3, cps), 0.05).unwrap();
        // The embed figure includes cloning the input mesh (as it always has); the clone's
        // share is printed apart.
        let t = Instant::now();
        let input = mesh.clone();
        let clone_ms = t.elapsed().as_secs_f64() * 1e3;
        let mut e = EmbeddedMesh::new(&lattice, input, Parallelism::Auto);
        let embed_ms = t.elapsed().as_secs_f64() * 1e3;
        // CPU time of a sequential embedding (clone, parameters, bucketing, first deformation
        // and normals): meaningful on a busy machine, where wall times are not.
        let embed_cpu = common::best_cpu_of(3, || {
            let m = mesh.clone();
            std::hint::black_box(EmbeddedMesh::new(&lattice, m, Parallelism::Sequential));
        });
        e.set_recompute_normals(false);
        let m =
            Manipulation::single_displacement(&lattice, [0.3, 0.5, 0.8], Vec3::new(0.2, 0.1, 0.0))
                .unwrap();
        lattice.apply(&m);
        let seq = common::best_of(3, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let par = common::best_of(5, || {
            e.deform(&lattice, Parallelism::Rayon);
        });
        let seq_cpu = common::best_cpu_of(5, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        e.set_blocked_kernel(false);
        let seq_scalar_cpu = common::best_cpu_of(5, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let seq_scalar = common::best_of(3, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let par_scalar = common::best_of(5, || {
            e.deform(&lattice, Parallelism::Rayon);
        });
        e.set_blocked_kernel(true);
        let mut m2 = e.mesh().clone();
        let normals = common::best_of(3, || m2.compute_normals());
        let m =
            Manipulation::single_displacement(&lattice, [0.3, 0.5, 0.8], Vec3::new(0.0, 0.0, 0.05))
                .unwrap();
        let mut count = 0;
        // Each run applies the manipulation once more and updates the touched vertices.
        let inc = common::best_of(5, || {
            lattice.apply(&m);
            count = e.update(&lattice, m.indices(), Parallelism::Auto);
        });
        let mut check = e.clone();
        check.deform(&lattice, Parallelism::Auto);
        let diff = check
            .mesh()
            .positions
            .iter()
            .zip(&e.mesh().positions)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(
            diff < 1e-12,
            "incremental and full deformation differ by {diff:e}"
        );
        println!(
            "cubic {cps}^3: embed {embed_ms:7.1} ms (of which cloning the input {clone_ms:5.1} ms; 1-thread CPU time {embed_cpu:6.1} ms) | full deform: 1 thread {seq:6.1} ms, rayon {par:6.1} ms (per-vertex kernel: {seq_scalar:6.1}, {par_scalar:6.1}) | 1-thread CPU time: blocked {seq_cpu:6.1} ms, per-vertex {seq_scalar_cpu:6.1} ms | normals {normals:6.1} ms | incremental {inc:6.1} ms ({count} vertices)"
        );
    }
    println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
}
