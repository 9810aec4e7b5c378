//! Steps per second of D-NURBS surfaces (frozen weights): `cargo run --release -p vclay-dynamics
//! --example dnurbs_steps [N]` for an N x N cubic surface (default 64), pulled by a spring
//! (the model of `vclay_dynamics::dnurbs::benchmarks::frozen_sheet`). Prints a digest of the
//! final control points (equal digests: the same trajectory to the last bit). `--together`:
//! the three coordinate columns solved in one call (`Dnurbs::solve_together`).
use std::time::Instant;
use vclay_dynamics::Integrator;
use vclay_dynamics::dnurbs::benchmarks;

fn main() {
    // The same run's reference workload (issue 31), at the start and at the end.
    let yard_start = vclay_core::yardstick::measure(0.3);
    let together = std::env::args().any(|a| a == "--together");
    let n: usize = std::env::args()
        .filter(|a| a != "--together")
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(64);
    let t0 = Instant::now();
    let mut d = benchmarks::frozen_sheet(n).expect("model");
    d.solve_together = together;
    let setup = t0.elapsed().as_secs_f64();
    // The first step assembles the CSR matrices and factors the system (kept while dt, springs
    // and the fixed set stay); it is timed on its own, the steady rate after it.
    let t0 = Instant::now();
    d.step(Integrator::Implicit { dt: benchmarks::DT })
        .expect("step");
    let first = t0.elapsed().as_secs_f64();
    let steps = 300;
    let t0 = Instant::now();
    let mut iters = 0;
    for _ in 0..steps {
        iters += d
            .step(Integrator::Implicit { dt: 0.01 })
            .expect("step")
            .solver
            .iterations;
    }
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "{n}x{n} cubic, frozen weights: setup {:.1} ms, first step (assembly, factorization) {:.1} ms, then {:.1} steps/s, {:.1} CG iterations per step",
        setup * 1e3,
        first * 1e3,
        steps as f64 / secs,
        iters as f64 / steps as f64
    );
    // FNV-1a of the control points' bits: equal digests, the same trajectory to the last bit.
    let digest = d
        .geometry()
        .control_points()
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x100_0000_01b3)
        });
    println!("  digest of the final control points {digest:016x}");
    println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
}
