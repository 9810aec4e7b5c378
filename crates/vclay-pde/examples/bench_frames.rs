//! Benchmark (`dynamic-pde-surfaces.txt` section III timing claim): time to solve the constants
//! and to evaluate a 100 x 100 grid, for the section III surface and the glass animation
//! (eq 24-26), and whole animation frames per second on one core.
//!
//! Run: `cargo run --release -p vclay-pde --example bench_frames [SECONDS [NAME]]`
//! Times are the best 1 ms batch (the build machine is shared; see `time`).
//! The paper reports "less than 10^-6 of a second on an 800 MHz PC" to determine the constants
//! of the section III problem (M = 36, N = 7).

use std::hint::black_box;
use std::time::Instant;
use vclay_pde::surface::{GridWork, eval_grid, uniform};
use vclay_pde::{Animator, ModelSolution, PdeModel, Solver};

/// Seconds per call of `f`: the smallest mean over batches of about 1 ms (batches that the
/// scheduler did not interrupt: the machine is shared), measured for about `secs` seconds after
/// a warm-up; and the number of calls.
fn time<F: FnMut()>(secs: f64, mut f: F) -> (f64, usize) {
    let t0 = Instant::now();
    for _ in 0..10 {
        f();
    }
    let per = t0.elapsed().as_secs_f64() / 10.0;
    let batch = ((1e-3 / per.max(1e-9)) as usize).clamp(1, 100_000);
    let start = Instant::now();
    let mut n = 0usize;
    let mut best = f64::INFINITY;
    while start.elapsed().as_secs_f64() < secs {
        let b0 = Instant::now();
        for _ in 0..batch {
            f();
        }
        best = best.min(b0.elapsed().as_secs_f64() / batch as f64);
        n += batch;
    }
    (best, n)
}

fn report(name: &str, model: &PdeModel, t_of: impl Fn(usize) -> f64, secs: f64) {
    let (nu, nv) = (100, 100);
    // Constants only.
    let mut solver = Solver::new();
    let mut sols: Vec<_> = model
        .patches
        .iter()
        .map(|p| solver.solve(p, 0.5).unwrap())
        .collect();
    let mut k = 0usize;
    let (solve, _) = time(secs, || {
        let t = t_of(k);
        k += 1;
        for (p, s) in model.patches.iter().zip(sols.iter_mut()) {
            solver.solve_into(p, t, s).unwrap();
        }
        black_box(&sols);
    });
    // 100 x 100 grid per patch, constants fixed.
    let us = uniform(0.0, 1.0, nu);
    let mut work = GridWork::default();
    let mut pts = Vec::new();
    let (grid, _) = time(secs, || {
        for (p, s) in model.patches.iter().zip(&sols) {
            let vs = uniform(p.v_range.0, p.v_range.1, nv);
            eval_grid(p, s, &us, &vs, &mut work, &mut pts);
            black_box(&pts);
        }
    });
    // Whole frames: constants at a new t plus every patch's grid (static patches are solved
    // once by the animator and reused).
    let mut anim = Animator::new(model);
    let mut sol = ModelSolution::default();
    let mut frame_pts = Vec::new();
    let mut k = 0usize;
    let (frame, frames) = time(secs, || {
        let t = t_of(k);
        k += 1;
        anim.frame(t, nu, nv, &mut sol, &mut frame_pts).unwrap();
        black_box(&frame_pts);
    });
    let unknowns: usize = sols
        .iter()
        .map(|s| s.stats.unknowns.iter().sum::<usize>())
        .sum();
    println!(
        "{name:<12} patches {}  unknowns {unknowns:>3}  solve all {:>8.2} us  grids 100x100 {:>8.2} us  \
         solve+grids {:>8.2} us = {:>7.0}/s  animator frame {:>8.2} us = {:>7.0} frames/s ({frames} timed)",
        model.patches.len(),
        solve * 1e6,
        grid * 1e6,
        (solve + grid) * 1e6,
        1.0 / (solve + grid),
        frame * 1e6,
        1.0 / frame
    );
}

fn main() {
    let secs: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/specs");
    let s3 = PdeModel::read(format!("{dir}/section3.json")).unwrap();
    let glass = PdeModel::read(format!("{dir}/glass.json")).unwrap();
    let vase = PdeModel::read(format!("{dir}/vase.json")).unwrap();
    println!("vclay-pde frame benchmark, one thread, {secs} s per measurement");
    // Section III is static: its "frames" re-solve at t = 0 each time (no caching: the solver
    // is called directly for the constants; the animator caches static patches for frames).
    let only = std::env::args().nth(2).unwrap_or_default();
    let want = |name: &str| only.is_empty() || name.contains(only.as_str());
    if want("section III") {
        report("section III", &s3, |_| 0.0, secs);
    }
    if want("glass") {
        report("glass", &glass, |k| (k % 1000) as f64 / 1000.0, secs);
    }
    if want("vase") {
        report("vase", &vase, |k| (k % 1000) as f64 / 1000.0, secs);
    }
    if want("aircraft") {
        // Fig 9 (issue 22): 16 patches; the wing sections move with t, the rest is static.
        let aircraft = PdeModel::from_json(vclay_pde::builtin::AIRCRAFT, "aircraft.json").unwrap();
        report("aircraft", &aircraft, |k| (k % 1000) as f64 / 1000.0, secs);
    }
}
