//! Quick timing of embedded-mesh deformation (not a benchmark harness; no assertions).
//!
//! Embeds a UV sphere of about one million vertices in cubic lattices of `4^3`, `7^3`, `10^3` and `20^3`
//! control points and times: embedding (parameters and basis values), a full deformation (positions
//! only, sequential and on rayon's pool), normal recomputation, and an incremental update after a
//! single-point manipulation.
//!
//! Run: `cargo run --release -p vclay-ffd --example bench_deform [vertices-per-side]`.

use std::time::Instant;
use vclay_core::{Parallelism, TriMesh, Vec3};
use vclay_ffd::{EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation};

/// UV sphere with `n x n` vertices.
fn sphere(n: usize) -> TriMesh {
    let mut m = TriMesh::new();
    for i in 0..n {
        let th = std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let ph = std::f64::consts::TAU * j as f64 / n as f64;
            m.positions.push(Vec3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    for i in 0..n - 1 {
        for j in 0..n {
            let a = (i * n + j) as u32;
            let b = (i * n + (j + 1) % n) as u32;
            let (c, d) = (b + n as u32, a + n as u32);
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    m
}

fn best_of<F: FnMut()>(runs: usize, mut f: F) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

/// CPU time of the calling thread in milliseconds (Linux `/proc/thread-self/schedstat`, first
/// field: nanoseconds on a CPU), or `None` where unavailable. Unlike wall time it does not count
/// time spent waiting for a CPU, so it stays meaningful on a busy machine.
fn thread_cpu_ms() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-6)
}

/// The smallest thread CPU time of `runs` calls of `f` (milliseconds; NaN where unavailable).
fn best_cpu_of<F: FnMut()>(runs: usize, mut f: F) -> f64 {
    (0..runs)
        .map(|_| {
            let t0 = thread_cpu_ms();
            f();
            match (t0, thread_cpu_ms()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            }
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    // The same run's reference workload (issue 31), at the start and at the end.
    let yard_start = vclay_core::yardstick::measure(0.3);
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let mesh = sphere(n);
    println!(
        "{} vertices, {} triangles, {} rayon threads",
        mesh.positions.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    for cps in [4, 7, 10, 20] {
        let mut lattice =
            FfdLattice::enclosing(&mesh.positions, LatticeSpec::uniform(3, cps), 0.05).unwrap();
        let t = Instant::now();
        let mut e = EmbeddedMesh::new(&lattice, mesh.clone(), Parallelism::Auto);
        let embed_ms = t.elapsed().as_secs_f64() * 1e3;
        e.set_recompute_normals(false);
        let m =
            Manipulation::single_displacement(&lattice, [0.3, 0.5, 0.8], Vec3::new(0.2, 0.1, 0.0))
                .unwrap();
        lattice.apply(&m);
        let seq = best_of(3, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let par = best_of(5, || {
            e.deform(&lattice, Parallelism::Rayon);
        });
        let seq_cpu = best_cpu_of(5, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        e.set_blocked_kernel(false);
        let seq_scalar_cpu = best_cpu_of(5, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let seq_scalar = best_of(3, || {
            e.deform(&lattice, Parallelism::Sequential);
        });
        let par_scalar = best_of(5, || {
            e.deform(&lattice, Parallelism::Rayon);
        });
        e.set_blocked_kernel(true);
        let mut m2 = e.mesh().clone();
        let normals = best_of(3, || m2.compute_normals());
        let m =
            Manipulation::single_displacement(&lattice, [0.3, 0.5, 0.8], Vec3::new(0.0, 0.0, 0.05))
                .unwrap();
        let mut count = 0;
        // Each run applies the manipulation once more and updates the touched vertices.
        let inc = best_of(5, || {
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
            "cubic {cps}^3: embed {embed_ms:7.1} ms | full deform: 1 thread {seq:6.1} ms, rayon {par:6.1} ms (per-vertex kernel: {seq_scalar:6.1}, {par_scalar:6.1}) | 1-thread CPU time: blocked {seq_cpu:6.1} ms, per-vertex {seq_scalar_cpu:6.1} ms | normals {normals:6.1} ms | incremental {inc:6.1} ms ({count} vertices)"
        );
    }
    println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
}
