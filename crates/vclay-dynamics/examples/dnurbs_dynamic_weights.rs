//! Steps per second of a D-NURBS surface with dynamic weights (`d-nurbs.txt` sections 4.2, 5.3):
//! `cargo run --release -p vclay-dynamics --example dnurbs_dynamic_weights [N]` for an N x N
//! cubic surface (default 16; issue goal: 60 steps/s on 2 cores; optional second argument: CG
//! relative tolerance; `--cg`: block-Jacobi CG instead of the default sparse Cholesky;
//! `--uniform`: unit initial weights, `benchmarks::uniform_dynamic_sheet`; `--reuse`: the
//! direct solver reuses earlier factorizations as CG preconditioners, `FactorReuse`;
//! `--schur`: the direct solver's block split with CG on the weights' Schur complement,
//! `BlockSchur`), pulled
//! by a moving spring, one edge fixed (`vclay_dynamics::dnurbs::benchmarks::dynamic_sheet`).
//! Every step recomputes the element matrices (they depend on the weights). Prints the wall and
//! process CPU time per step and the same run's yardstick (`vclay_core::yardstick`, before and
//! after the steps), and a digest of the final coordinates (equal digests: the same trajectory to
//! the last bit).
use std::time::Instant;
use vclay_core::yardstick;
use vclay_dynamics::Integrator;
use vclay_dynamics::dnurbs::{GeneralizedGeometry, benchmarks};

fn main() {
    let cg = std::env::args().any(|a| a == "--cg");
    let uniform = std::env::args().any(|a| a == "--uniform");
    let reuse = std::env::args().any(|a| a == "--reuse");
    let schur = std::env::args().any(|a| a == "--schur");
    let args: Vec<String> = std::env::args()
        .filter(|a| !["--cg", "--uniform", "--reuse", "--schur"].contains(&a.as_str()))
        .collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    let t0 = Instant::now();
    let mut d = if uniform {
        benchmarks::uniform_dynamic_sheet(n)
    } else {
        benchmarks::dynamic_sheet(n)
    }
    .expect("model");
    let setup = t0.elapsed().as_secs_f64();
    if let Some(tol) = args.get(2).and_then(|a| a.parse().ok()) {
        d.tolerance = tol;
    }
    if cg {
        d.solver = vclay_dynamics::LinearSolver::ConjugateGradient;
    }
    if reuse {
        d.factor_reuse = Some(Default::default());
    }
    if schur {
        d.block_schur = Some(Default::default());
    }
    let steps = 60;
    let before = yardstick::measure(0.3);
    let cpu0 = yardstick::process_cpu_seconds();
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
    let cpu_ms = cpu0
        .zip(yardstick::process_cpu_seconds())
        .map_or(f64::NAN, |(a, b)| (b - a) * 1e3 / steps as f64);
    let after = yardstick::measure(0.3);
    let ws = d.geometry().weights();
    let (lo, hi) = ws
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    // FNV-1a of the coordinates' bits: equal digests, the same trajectory to the last bit.
    let digest = d
        .geometry()
        .coordinates()
        .iter()
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x100_0000_01b3)
        });
    println!(
        "{n}x{n} cubic, dynamic weights ({} coordinates, {} quadrature points, {:?}{}): setup {:.1} ms, {:.1} steps/s, {:.1} CG iterations per step, {} factorizations, {} sub-steps, weights now {lo:.3}..{hi:.3}, digest {digest:016x}",
        d.geometry().coordinates().len(),
        d.quadrature_points(),
        d.solver,
        if d.block_schur.is_some() {
            " + block Schur"
        } else {
            ""
        },
        setup * 1e3,
        steps as f64 / secs,
        iters as f64 / steps as f64,
        d.factorizations(),
        d.substeps()
    );
    let ms = secs * 1e3 / steps as f64;
    println!(
        "  wall {ms:.2} ms/step, CPU {cpu_ms:.2} ms/step (all threads); yardstick v{} {:.3} / {:.3} ms (before / after): {:.1} yardsticks per step",
        yardstick::YARDSTICK_VERSION,
        before.ms,
        after.ms,
        ms / (0.5 * (before.ms + after.ms))
    );
}
