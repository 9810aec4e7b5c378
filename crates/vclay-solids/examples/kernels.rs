//! Times the per-step kernels of a dynamic subdivision solid (4^3 cube) one by one: spring
//! forces (one thread and all threads, as the step runs them, then with the structured-grid
//! kernel and with the general kernel), `d = A p` and `g = A^T f` (with the `f64` level
//! operators, then compressed: `SubdivisionMap::compress`).
//!
//! Run: `cargo run --release -p vclay-solids --example kernels -- [level] [reps]`. Each figure
//! is the median wall time of `reps` runs and, after the slash, the process's CPU time per run
//! (on a shared host a one-thread pass's CPU time is its own work; its wall time includes the
//! time other tenants held the core).

use std::time::Instant;
use vclay_core::{Parallelism, Vec3};
use vclay_solids::springs::ForceWorkspace;
use vclay_solids::{SolidParams, benchmarks};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `reps` runs of `pass`: the median wall ms and the mean process CPU ms of a run.
fn time(reps: usize, mut pass: impl FnMut()) -> (f64, f64) {
    let cpu = || vclay_core::yardstick::process_cpu_seconds().unwrap_or(f64::NAN);
    let mut wall = Vec::with_capacity(reps);
    let mut busy = 0.0;
    for _ in 0..reps {
        let (c0, t0) = (cpu(), Instant::now());
        pass();
        wall.push(t0.elapsed().as_secs_f64() * 1e3);
        busy += (cpu() - c0) * 1e3;
    }
    (median(wall), busy / reps as f64)
}

fn main() {
    // The same run's reference workload (issue 31), at the start and at the end.
    let yard_start = vclay_core::yardstick::measure(0.3);
    let args: Vec<String> = std::env::args().collect();
    let level: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(4);
    let reps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(20);
    let mut s = benchmarks::cube(level, SolidParams::default()).unwrap();
    // A deformed state: pull one corner and take a few steps.
    benchmarks::pull(&mut s).unwrap();
    let d = s.data_points().to_vec();
    let springs = s.springs().clone();
    println!(
        "level {level}: {} data points, {} springs, {} straddling the thread blocks",
        d.len(),
        springs.len(),
        springs.straddling()
    );
    let mut f = vec![Vec3::zeros(); d.len()];
    let mut ws = ForceWorkspace::default();
    for (name, par) in [
        ("springs, 1 thread", Parallelism::Sequential),
        ("springs, all threads", Parallelism::Rayon),
    ] {
        // `set_forces`: the step's call (the zeroing of `f` included).
        let (t, c) = time(reps, || {
            springs.set_forces(&d, &mut f, &mut ws, par);
        });
        println!(
            "level {level}: {name}: {t:.3} / {c:.3} ms ({:.2} ns/spring)",
            t * 1e6 / springs.len() as f64
        );
    }
    // The structured-grid kernel and the general kernel on the same set, whichever the step
    // uses (issue 31; `SpringSet::GRID_SPRINGS`, `SpringSet::GRID_POINTS`).
    let mut grid = springs.clone();
    if grid.use_grid_kernel(d.len()) {
        let mut general = springs.clone();
        general.drop_grid();
        for (name, set, par) in [
            (
                "springs, grid kernel, 1 thread",
                &grid,
                Parallelism::Sequential,
            ),
            (
                "springs, grid kernel, all threads",
                &grid,
                Parallelism::Rayon,
            ),
            (
                "springs, general kernel, 1 thread",
                &general,
                Parallelism::Sequential,
            ),
            (
                "springs, general kernel, all threads",
                &general,
                Parallelism::Rayon,
            ),
        ] {
            let (t, c) = time(reps, || {
                set.set_forces(&d, &mut f, &mut ws, par);
            });
            println!(
                "level {level}: {name}: {t:.3} / {c:.3} ms ({:.2} ns/spring)",
                t * 1e6 / springs.len() as f64
            );
        }
    }
    // The control map alone: as built (`f64` operators), then compressed (issue 31).
    let mut disc = s.source().discretize(s.control_points()).unwrap();
    let mut ws = vclay_lattice::ChainWorkspace::new();
    let mut dd = vec![Vec3::zeros(); d.len()];
    let mut g = vec![Vec3::zeros(); s.control_points().len()];
    for (name, par, compress) in [
        ("1 thread", Parallelism::Sequential, false),
        ("all threads", Parallelism::Auto, false),
        ("1 thread, compressed", Parallelism::Sequential, true),
        ("all threads, compressed", Parallelism::Auto, true),
    ] {
        if compress && !disc.map.is_compressed() {
            disc.map.compress();
        }
        let (ta, ca) = time(reps, || {
            disc.map
                .apply_into(s.control_points(), &mut dd, &mut ws, par)
        });
        let (tt, ct) = time(reps, || {
            disc.map.apply_transpose_into(&f, &mut g, &mut ws, par)
        });
        println!(
            "level {level}: A p {ta:.3} / {ca:.3} ms, A^T f {tt:.3} / {ct:.3} ms ({name}, {} non-zeros)",
            disc.map.operators().iter().map(|m| m.nnz()).sum::<usize>()
        );
    }
    let (t, c) = time(reps, || {
        s.step().unwrap();
    });
    println!("level {level}: whole step: {t:.3} / {c:.3} ms");
    println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
}
