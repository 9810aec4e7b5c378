//! Steps per second of a D-NURBS surface with dynamic weights (`d-nurbs.txt` sections 4.2, 5.3):
//! `cargo run --release -p vclay-dynamics --example dnurbs_dynamic_weights [N]` for an N x N
//! cubic surface (default 16; issue goal: 60 steps/s on 2 cores; optional second argument: CG
//! relative tolerance; `--cg`: block-Jacobi CG instead of the default sparse Cholesky), pulled
//! by a moving spring, one edge fixed. Every step recomputes the element matrices (they depend on the
//! weights).
use std::time::Instant;
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{GeneralizedDnurbs, GeneralizedGeometry, RationalGeometry, Target};
use vclay_dynamics::{Force, Integrator, Material};
use vclay_spline::NurbsSurface;

fn main() {
    let cg = std::env::args().any(|a| a == "--cg");
    let args: Vec<String> = std::env::args().filter(|a| a != "--cg").collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    let mut pts = Vec::with_capacity(n * n);
    let mut w = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            pts.push(Vec3::new(
                i as f64 / (n - 1) as f64,
                j as f64 / (n - 1) as f64,
                0.0,
            ));
            w.push(1.0 + 0.2 * ((i + j) % 3) as f64);
        }
    }
    let mut s = NurbsSurface::clamped_uniform([3, 3], [n, n], pts).expect("surface");
    s.set_weights(w).expect("weights");
    let t0 = Instant::now();
    let mut d = GeneralizedDnurbs::new(
        RationalGeometry::from_surface(&s),
        Material::surface(1.0, 2.0, 1.0, 0.1),
    )
    .expect("model");
    let setup = t0.elapsed().as_secs_f64();
    if let Some(tol) = args.get(2).and_then(|a| a.parse().ok()) {
        d.tolerance = tol;
    }
    if cg {
        d.solver = vclay_dynamics::LinearSolver::ConjugateGradient;
    }
    for k in 0..n {
        for c in 0..3 {
            d.set_fixed_coordinate(4 * k + c, true).expect("index");
        }
    }
    d.forces_mut().push(Force::Spring {
        param: [0.7, 0.5],
        target: Target::Moving(std::sync::Arc::new(|t| {
            Vec3::new(0.7, 0.5, 0.3 * (t * 3.0).sin())
        })),
        stiffness: 50.0,
        kernel: None,
    });
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
