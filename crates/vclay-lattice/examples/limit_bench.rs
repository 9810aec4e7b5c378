//! Limit evaluation speed (issue 19 goal: 1M points in regular regions at 20M points/s or more
//! on 2 cores): `cargo run --release -p vclay-lattice --example limit_bench [SECONDS]`.
//!
//! A perturbed 14^3-point box lattice; 1M queries in its regular cells, cells and parameters
//! pseudo-random; position and first derivatives. Prints best-of-runs points per second on one
//! thread and on all threads, and the irregular path's cost per point near the boundary.
//! `vclay bench` reports the same figure as `subdivision_limit`.

use std::time::Instant;
use vclay_core::Parallelism;
use vclay_lattice::{
    CellId, Features, LimitEvaluator, LimitParams, LimitPoint, LimitQuery, SubdivisionRules, limit,
};

fn best(seconds: f64, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut best = f64::INFINITY;
    let mut runs = 0;
    while runs < 3 || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
        runs += 1;
    }
    best
}

/// CPU seconds (user + system) of the calling thread, from `/proc/thread-self/stat` (Linux;
/// 100 ticks per second), or `None` where that file does not exist.
fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &text[text.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() {
    let seconds: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    let l = limit::benchmark_lattice();
    let f = Features::none(&l);
    let mk = |par| {
        LimitEvaluator::new(
            &l,
            &f,
            SubdivisionRules::default(),
            LimitParams {
                parallelism: par,
                ..LimitParams::default()
            },
        )
        .unwrap()
    };
    let t = Instant::now();
    let (seq, par) = (mk(Parallelism::Sequential), mk(Parallelism::Rayon));
    let setup = t.elapsed().as_secs_f64() / 2.0;
    let queries = limit::benchmark_queries(&seq, l.num_cells(), 1_000_000);
    let mut out = vec![LimitPoint::default(); queries.len()];
    let t1 = best(seconds, || seq.evaluate_into(&queries, &mut out).unwrap());
    let t2 = best(seconds, || par.evaluate_into(&queries, &mut out).unwrap());
    // CPU time of the one-thread runs: the cost per point on a core, whatever else the machine
    // runs (a shared machine's load stretches the wall-clock figures above).
    let reps = 8;
    let cpu = thread_cpu_seconds().map(|c0| {
        for _ in 0..reps {
            seq.evaluate_into(&queries, &mut out).unwrap();
        }
        thread_cpu_seconds().unwrap_or(c0) - c0
    });
    // The irregular path: points on the boundary (stop at the tolerance).
    let boundary: Vec<LimitQuery> = (0..l.num_cells())
        .filter(|&c| !seq.is_regular(CellId(c as u32)))
        .take(200)
        .enumerate()
        .map(|(i, cell)| LimitQuery {
            cell,
            uvw: [
                (i * 37 % 100) as f64 / 100.0,
                (i * 61 % 100) as f64 / 100.0,
                0.0,
            ],
        })
        .collect();
    let regular = (0..l.num_cells())
        .filter(|&c| seq.is_regular(CellId(c as u32)))
        .count();
    let mut bout = vec![LimitPoint::default(); boundary.len()];
    let tb = best(seconds.min(1.0), || {
        seq.evaluate_into(&boundary, &mut bout).unwrap()
    });
    let levels: f64 = bout.iter().map(|p| p.levels as f64).sum::<f64>() / bout.len() as f64;
    println!(
        "cells {} (regular {}), set-up {:.1} ms; regular: 1 thread {:.2}M points/s, {} threads {:.2}M points/s (goal >= 20M), CPU time on one thread {}; boundary (w = 0, tolerance {:.1e} of the diagonal): {:.0} us/point, {:.1} levels on average",
        l.num_cells(),
        regular,
        setup * 1e3,
        queries.len() as f64 / t1 / 1e6,
        rayon::current_num_threads(),
        queries.len() as f64 / t2 / 1e6,
        cpu.map_or("unavailable".to_string(), |c| format!(
            "{:.1} ns/point = {:.2}M points/s per core",
            c / (reps * queries.len()) as f64 * 1e9,
            (reps * queries.len()) as f64 / c / 1e6
        )),
        LimitParams::default().tolerance,
        tb / boundary.len() as f64 * 1e6,
        levels
    );
}
