//! Steps per second of a D-NURBS surface with dynamic weights (`d-nurbs.txt` sections 4.2, 5.3):
//! `cargo run --release -p vclay-dynamics --example dnurbs_dynamic_weights [N]` for an N x N
//! cubic surface (default 16; issue goal: 60 steps/s on 2 cores; optional second argument: CG
//! relative tolerance; `--cg`: block-Jacobi CG instead of the default sparse Cholesky), pulled
//! by a moving spring, one edge fixed (`vclay_dynamics::dnurbs::benchmarks::dynamic_sheet`).
//! Every step recomputes the element matrices (they depend on the weights).
use std::time::Instant;
use vclay_dynamics::Integrator;
use vclay_dynamics::dnurbs::{GeneralizedGeometry, benchmarks};

fn main() {
    let cg = std::env::args().any(|a| a == "--cg");
    let args: Vec<String> = std::env::args().filter(|a| a != "--cg").collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    let t0 = Instant::now();
    let mut d = benchmarks::dynamic_sheet(n).expect("model");
    let setup = t0.elapsed().as_secs_f64();
    if let Some(tol) = args.get(2).and_then(|a| a.parse().ok()) {
        d.tolerance = tol;
    }
    if cg {
        d.solver = vclay_dynamics::LinearSolver::ConjugateGradient;
    }
    let steps = 60;
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
    let ws = d.geometry().weights();
    let (lo, hi) = ws
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    println!(
        "{n}x{n} cubic, dynamic weights ({} coordinates, {:?}): setup {:.1} ms, {:.1} steps/s, {:.1} CG iterations per step, {} sub-steps, weights now {lo:.3}..{hi:.3}",
        d.geometry().coordinates().len(),
        d.solver,
        setup * 1e3,
        steps as f64 / secs,
        iters as f64 / steps as f64,
        d.substeps()
    );
}
