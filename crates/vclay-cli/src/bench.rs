//! `vclay bench`: evaluation throughput as JSON, so that `bench/compare.py` can put vclay and
//! its peers (geomdl, OpenNURBS through rhino3dm) in one table from one run. The statistically
//! careful figures come from `cargo bench -p vclay-bench`; this is the quick, scriptable form.

use anyhow::Result;
use serde_json::json;
use std::hint::black_box;
use std::time::Instant;
use vclay::spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};
use vclay::{Parallelism, Vec3};

/// The benchmark surface: 16x16 rational bicubic (same definition as `bench/compare.py`).
pub fn bench_surface() -> Result<NurbsSurface> {
    let n = 16;
    let mut pts = Vec::with_capacity(n * n);
    let mut w = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            pts.push(Vec3::new(x, y, 0.2 * (7.0 * x).sin() * (5.0 * y).cos()));
            w.push(1.0 + 0.25 * ((i * n + j) % 5) as f64);
        }
    }
    let mut s = NurbsSurface::clamped_uniform([3, 3], [n, n], pts)?;
    s.set_weights(w)?;
    Ok(s)
}

/// Best (smallest) seconds per call of `f` over repeated runs lasting about `budget` seconds.
fn time_best(budget: f64, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut best = f64::INFINITY;
    let mut runs = 0;
    while runs < 3 || start.elapsed().as_secs_f64() < budget {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
        runs += 1;
    }
    best
}

/// Runs the measurements and prints JSON.
pub fn run(seconds: f64) -> Result<()> {
    let s = bench_surface()?;
    let side = 1000;
    let us: Vec<f64> = (0..side).map(|i| i as f64 / (side - 1) as f64).collect();
    let mut out = vec![Vec3::zeros(); side * side];
    let mut grid_rate = |par| -> Result<f64> {
        let mut err = None;
        let t = time_best(seconds, || {
            if let Err(e) = s.eval_grid_into(&us, &us, &mut out, par) {
                err = Some(e);
            }
        });
        match err {
            Some(e) => Err(e.into()),
            None => Ok((side * side) as f64 / t),
        }
    };
    let grid_seq = grid_rate(Parallelism::Sequential)?;
    let grid_par = grid_rate(Parallelism::Rayon)?;
    let params: Vec<(f64, f64)> = (0..10_000)
        .map(|k| {
            (
                ((k * 37) % 10_000) as f64 / 9999.0,
                ((k * 101) % 10_000) as f64 / 9999.0,
            )
        })
        .collect();
    let t = time_best(seconds, || {
        for &(u, v) in &params {
            black_box(s.point(black_box(u), black_box(v)).ok());
        }
    });
    let point_ns = t / params.len() as f64 * 1e9;
    let cpts: Vec<Vec3> = (0..32)
        .map(|i| Vec3::new(i as f64, (i as f64).sin(), 0.0))
        .collect();
    let curve = NurbsCurve::clamped_uniform(3, cpts)?;
    let cu: Vec<f64> = (0..10_000).map(|k| k as f64 / 9999.0).collect();
    let t = time_best(seconds, || {
        for &u in &cu {
            black_box(curve.point(black_box(u)).ok());
        }
    });
    let curve_ns = t / cu.len() as f64 * 1e9;
    let doc = json!({
        "threads": rayon_threads(),
        "surface_grid_points_per_second_1_thread": grid_seq,
        "surface_grid_points_per_second_all_threads": grid_par,
        "surface_point_ns": point_ns,
        "curve_point_ns": curve_ns,
    });
    println!("{}", serde_json::to_string_pretty(&doc)?);
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
