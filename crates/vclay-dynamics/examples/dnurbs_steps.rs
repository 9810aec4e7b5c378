//! Steps per second of D-NURBS surfaces (frozen weights): `cargo run --release -p vclay-dynamics
//! --example dnurbs_steps [N]` for an N x N cubic surface (default 64), pulled by a spring.
use std::time::Instant;
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::Target;
use vclay_dynamics::{DnurbsSurface, Force, Integrator, Material};
use vclay_spline::NurbsSurface;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(64);
    let mut pts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            pts.push(Vec3::new(
                i as f64 / (n - 1) as f64,
                j as f64 / (n - 1) as f64,
                0.0,
            ));
        }
    }
    let s = NurbsSurface::clamped_uniform([3, 3], [n, n], pts).expect("surface");
    let t0 = Instant::now();
    let mut d = DnurbsSurface::new(s, Material::surface(1.0, 2.0, 1.0, 0.1)).expect("model");
    let setup = t0.elapsed().as_secs_f64();
    for k in 0..n {
        d.set_fixed(k, true).expect("index");
    }
    d.forces_mut().push(Force::Spring {
        param: [0.7, 0.5],
        target: Target::Moving(std::sync::Arc::new(|t| {
            Vec3::new(0.7, 0.5, 0.3 * (t * 3.0).sin())
        })),
        stiffness: 50.0,
        kernel: None,
    });
    // The first step assembles the CSR matrices and factors the system (kept while dt, springs
    // and the fixed set stay); it is timed on its own, the steady rate after it.
    let t0 = Instant::now();
    d.step(Integrator::Implicit { dt: 0.01 }).expect("step");
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
}
