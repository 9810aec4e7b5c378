//! Spline evaluation benchmarks: batched cubic surface grids (one thread and all threads),
//! point-by-point surface evaluation and curve evaluation.
//!
//! Run with `cargo bench -p vclay-bench`. Peers (geomdl, OpenNURBS via rhino3dm) are timed in the
//! same run by `bench/compare.py`, which calls `vclay bench`; figures go to `docs/performance.md`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use vclay::spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};
use vclay::{Parallelism, Vec3};

fn wavy_surface(n: usize) -> NurbsSurface {
    let mut pts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            pts.push(Vec3::new(x, y, (7.0 * x).sin() * (5.0 * y).cos() * 0.2));
        }
    }
    let mut s = NurbsSurface::clamped_uniform([3, 3], [n, n], pts).expect("valid surface");
    // Make it rational so the benchmark covers the general path.
    let w: Vec<f64> = (0..n * n)
        .map(|k| 1.0 + 0.25 * ((k * 7919) % 5) as f64)
        .collect();
    s.set_weights(w).expect("positive weights");
    s
}

fn grid(c: &mut Criterion) {
    let s = wavy_surface(16);
    let mut g = c.benchmark_group("cubic_surface_grid");
    for side in [256usize, 1024] {
        let us: Vec<f64> = (0..side).map(|i| i as f64 / (side - 1) as f64).collect();
        let mut out = vec![Vec3::zeros(); side * side];
        g.throughput(Throughput::Elements((side * side) as u64));
        for (name, par) in [
            ("1 thread", Parallelism::Sequential),
            ("all threads", Parallelism::Rayon),
        ] {
            g.bench_with_input(BenchmarkId::new(name, side * side), &side, |b, _| {
                b.iter(|| {
                    s.eval_grid_into(black_box(&us), black_box(&us), &mut out, par)
                        .expect("in domain")
                })
            });
        }
    }
    g.finish();
}

fn pointwise(c: &mut Criterion) {
    let s = wavy_surface(16);
    let params: Vec<(f64, f64)> = (0..4096)
        .map(|k| {
            (
                ((k * 37) % 4096) as f64 / 4095.0,
                ((k * 101) % 4096) as f64 / 4095.0,
            )
        })
        .collect();
    let mut g = c.benchmark_group("cubic_surface_point");
    g.throughput(Throughput::Elements(params.len() as u64));
    g.bench_function("point", |b| {
        b.iter(|| {
            let mut acc = Vec3::zeros();
            for &(u, v) in &params {
                acc += s.point(black_box(u), black_box(v)).expect("in domain");
            }
            acc
        })
    });
    g.bench_function("first derivatives", |b| {
        b.iter(|| {
            let mut acc = Vec3::zeros();
            for &(u, v) in &params {
                acc += s
                    .derivatives(black_box(u), black_box(v), 1)
                    .expect("in domain")[1][0];
            }
            acc
        })
    });
    g.finish();

    let pts: Vec<Vec3> = (0..32)
        .map(|i| Vec3::new(i as f64, (i as f64).sin(), 0.0))
        .collect();
    let curve = NurbsCurve::clamped_uniform(3, pts).expect("valid curve");
    let us: Vec<f64> = (0..4096).map(|k| k as f64 / 4095.0).collect();
    let mut g = c.benchmark_group("cubic_curve_point");
    g.throughput(Throughput::Elements(us.len() as u64));
    g.bench_function("point", |b| {
        b.iter(|| {
            let mut acc = Vec3::zeros();
            for &u in &us {
                acc += curve.point(black_box(u)).expect("in domain");
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, grid, pointwise);
criterion_main!(benches);
