//! `vclay bench`: evaluation throughput as JSON, so that `bench/compare.py` can put vclay and
//! its peers (geomdl, OpenNURBS through rhino3dm) in one table from one run. The statistically
//! careful figures come from `cargo bench -p vclay-bench`; this is the quick, scriptable form.
//!
//! With `--physics` it also times the simulation benchmark models (the definitions shared with
//! the examples: `vclay::dynamics::dnurbs::benchmarks`, `vclay::solids::benchmarks`) and puts
//! each figure beside the speed goal it is held to (`docs/performance.md`), with whether this
//! run met it, and the models of the papers' timing tables (`solid_paper_models`) beside the
//! tables' milliseconds. The machine's speed can drift between runs; the documented figures are medians
//! of alternating runs.
//!
//! Every run also times the fixed reference workload of `vclay_core::yardstick` at its start and
//! at its end (`"yardstick"`): dividing a figure by the same run's yardstick compares runs taken
//! in different minutes of a shared machine (issue 31).

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
pub fn run(seconds: f64, physics: bool, large: bool) -> Result<()> {
    use vclay::core::yardstick;
    let yard_start = yardstick::measure(seconds.min(1.0));
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
    let (limit_seq, limit_par) = limit_rates(seconds)?;
    let mut doc = json!({
        "threads": rayon_threads(),
        "subdivision_limit_points_per_second_1_thread": limit_seq,
        "subdivision_limit": at_least((limit_par, limit_par), "points/s (1M regular-cell points, first derivatives, all threads)", LIMIT_GOAL),
        "surface_grid_points_per_second_1_thread": grid_seq,
        "surface_grid_points_per_second_all_threads": grid_par,
        "surface_point_ns": point_ns,
        "curve_point_ns": curve_ns,
    });
    if physics {
        doc["physics"] = physics_figures(seconds, large)?;
    }
    let yard_end = yardstick::measure(seconds.min(1.0));
    doc["yardstick"] = json!({
        "version": yardstick::YARDSTICK_VERSION,
        "start_ms": yard_start.ms,
        "end_ms": yard_end.ms,
        "unit": "ms per run of vclay_core::yardstick::run (one thread), median of runs",
    });
    println!("{}", serde_json::to_string_pretty(&doc)?);
    Ok(())
}

/// Goal of issue 19: limit evaluation in regular regions, points per second on 2 cores.
const LIMIT_GOAL: f64 = 20e6;

/// Limit evaluation of 1M points (position and first derivatives) in the regular cells of a
/// perturbed 14^3-point box lattice, cells and parameters pseudo-random: `(1 thread, all
/// threads)` points per second, best of repeated runs.
fn limit_rates(seconds: f64) -> Result<(f64, f64)> {
    use vclay::lattice::{
        Features, LimitEvaluator, LimitParams, LimitPoint, SubdivisionRules, limit,
    };
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
    };
    let (seq, par) = (mk(Parallelism::Sequential)?, mk(Parallelism::Rayon)?);
    let queries = limit::benchmark_queries(&seq, l.num_cells(), 1_000_000);
    let mut out = vec![LimitPoint::default(); queries.len()];
    let mut rate = |ev: &LimitEvaluator<'_>| -> Result<f64> {
        let mut err = None;
        let t = time_best(seconds, || {
            if let Err(e) = ev.evaluate_into(&queries, &mut out) {
                err = Some(e);
            }
        });
        match err {
            Some(e) => Err(e.into()),
            None => Ok(queries.len() as f64 / t),
        }
    };
    Ok((rate(&seq)?, rate(&par)?))
}

/// Steps per second of `step` run for about `seconds`, after one untimed step (the D-NURBS
/// first step assembles and factors): `(median, mean)`. The steps are timed in batches of at
/// least 2 ms (and 5 batches at least); the median is the median batch's rate, which a shared
/// machine's pauses (another process, the host) move far less than the mean; the goals are
/// checked against it and both are reported.
fn steps_per_second(seconds: f64, mut step: impl FnMut() -> Result<()>) -> Result<(f64, f64)> {
    step()?;
    // Batch size: enough steps for 2 ms.
    let t0 = Instant::now();
    let mut batch = 0usize;
    while batch == 0 || t0.elapsed().as_secs_f64() < 2e-3 {
        step()?;
        batch += 1;
    }
    let mut rates = Vec::new();
    let (mut total_steps, start) = (0usize, Instant::now());
    while rates.len() < 5 || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        for _ in 0..batch {
            step()?;
        }
        rates.push(batch as f64 / t.elapsed().as_secs_f64());
        total_steps += batch;
    }
    let mean = total_steps as f64 / start.elapsed().as_secs_f64();
    rates.sort_by(f64::total_cmp);
    Ok((rates[rates.len() / 2], mean))
}

/// `{value, mean, unit, goal, met}` for a rate `(median, mean)` with a lower bound as goal
/// (met by the median).
fn at_least((value, mean): (f64, f64), unit: &str, goal: f64) -> serde_json::Value {
    json!({
        "value": value,
        "mean": mean,
        "statistic": "median of batches (mean: all steps)",
        "unit": unit,
        "goal": format!(">= {goal}"),
        "met": value >= goal,
    })
}

/// The simulation figures and their goals (issues 4 and 5).
fn physics_figures(seconds: f64, large: bool) -> Result<serde_json::Value> {
    use vclay::dynamics::Integrator;
    use vclay::dynamics::dnurbs::benchmarks as dn;
    use vclay::solids::{SolidParams, benchmarks as so};
    let implicit = Integrator::Implicit { dt: dn::DT };
    let mut frozen = dn::frozen_sheet(64)?;
    let frozen_rate = steps_per_second(seconds, || Ok(frozen.step(implicit).map(drop)?))?;
    let mut dynamic = dn::dynamic_sheet(16)?;
    let dynamic_rate = steps_per_second(seconds, || Ok(dynamic.step(implicit).map(drop)?))?;
    // The same sheet under the paper's fixed Gauss rule (issue 18 made the weight-aware rule
    // the default: more points where the weights vary, accurate rational integrals).
    // The studio's sheet: unit initial weights (issue 31's goal: 30 steps/s).
    let mut dynamic32 = dn::uniform_dynamic_sheet(32)?;
    let dynamic32_rate = steps_per_second(seconds, || Ok(dynamic32.step(implicit).map(drop)?))?;
    // The same sheet with the opt-in block-Schur solve (`[simulation] solver = "block-schur"`;
    // the same trajectory within 1e-12 of its residual per solve, not bit for bit).
    let mut dynamic32_split = dn::uniform_dynamic_sheet(32)?;
    dynamic32_split.block_schur = Some(vclay::dynamics::dnurbs::BlockSchur::default());
    let dynamic32_split_rate =
        steps_per_second(seconds, || Ok(dynamic32_split.step(implicit).map(drop)?))?;
    let mut dynamic_fixed = dn::dynamic_sheet(16)?;
    dynamic_fixed
        .set_quadrature_rule(vclay::dynamics::dnurbs::generalized::QuadratureRule::Fixed)?;
    let dynamic_fixed_rate =
        steps_per_second(seconds, || Ok(dynamic_fixed.step(implicit).map(drop)?))?;
    let mut cube = so::cube(2, SolidParams::default())?;
    so::pull(&mut cube)?;
    let (cube_rate, cube_mean) = steps_per_second(seconds, || Ok(cube.step().map(drop)?))?;
    let cube_ms = 1e3 / cube_rate;
    let mut out = json!({
        "dnurbs_64x64_frozen_weights": at_least(frozen_rate, "steps/s", 500.0),
        "dnurbs_16x16_dynamic_weights": at_least(dynamic_rate, "steps/s", 60.0),
        "dnurbs_32x32_dynamic_weights": at_least(dynamic32_rate, "steps/s", 30.0),
        "dnurbs_32x32_dynamic_weights_block_schur": at_least(dynamic32_split_rate, "steps/s", 30.0),
        "dnurbs_16x16_dynamic_weights_fixed_rule": at_least(dynamic_fixed_rate, "steps/s", 60.0),
        "solid_cube_level2": {
            "value": cube_ms,
            "mean": 1e3 / cube_mean,
            "statistic": "median of batches (mean: all steps)",
            "unit": "ms/step",
            "goal": "< 0.1",
            "met": cube_ms < 0.1,
            "data_points": cube.data_points().len(),
        },
    });
    // The models of the papers' timing tables, beside the tables' milliseconds.
    let mut paper = Vec::new();
    for m in &so::PAPER_MODELS {
        let mut s = m.solid(SolidParams::default())?;
        so::pull(&mut s)?;
        let (rate, mean) =
            steps_per_second((seconds / 4.0).max(0.2), || Ok(s.step().map(drop)?))?;
        paper.push(json!({
            "model": m.name,
            "level": m.level,
            "data_points": s.data_points().len(),
            "value": 1e3 / rate,
            "mean": 1e3 / mean,
            "unit": "ms/step",
            "paper_conference_ms": m.conference_ms,
            "paper_journal_ms": m.journal_ms,
        }));
    }
    out["solid_paper_models"] = json!(paper);
    out["dnurbs_corner_rounding"] = corner_rounding_figures(seconds)?;
    out["session_layer"] = session_figures(seconds)?;
    if large {
        let mut big = so::cube(5, SolidParams::default())?;
        so::pull(&mut big)?;
        let rate = steps_per_second(seconds, || Ok(big.step().map(drop)?))?;
        // Issue 4 asked for 10 steps/s; issue 31 for 30.
        out["solid_cube_level5"] = at_least(rate, "steps/s", 30.0);
        out["solid_cube_level5"]["bytes_per_data_point"] = json!(big.bytes_per_data_point());
        out["solid_cube_level5"]["peak_resident_bytes"] =
            json!(vclay::core::yardstick::peak_resident_bytes());
    }
    Ok(out)
}

/// Batches of `a` and `b` alternated for about `seconds` (each batch at least 2 ms, at least
/// 8 of each, the order swapped every round), so that both see the same machine: the median milliseconds per step of each.
fn paired_ms(
    seconds: f64,
    mut a: impl FnMut() -> Result<()>,
    mut b: impl FnMut() -> Result<()>,
) -> Result<(f64, f64, f64)> {
    a()?;
    b()?;
    let t0 = Instant::now();
    let mut batch = 0usize;
    while batch == 0 || t0.elapsed().as_secs_f64() < 2e-3 {
        a()?;
        batch += 1;
    }
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    let start = Instant::now();
    let mut round = 0usize;
    while ta.len() < 8 || start.elapsed().as_secs_f64() < seconds {
        // a, b in even rounds and b, a in odd ones, so that neither always runs first.
        for k in 0..2 {
            let (f, times): (&mut dyn FnMut() -> Result<()>, &mut Vec<f64>) =
                if (k + round).is_multiple_of(2) {
                    (&mut a, &mut ta)
                } else {
                    (&mut b, &mut tb)
                };
            let t = Instant::now();
            for _ in 0..batch {
                f()?;
            }
            times.push(t.elapsed().as_secs_f64() * 1e3 / batch as f64);
        }
        round += 1;
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    // The ratio of each round's two batches (the same minute of the machine), then the median.
    let mut ratios: Vec<f64> = ta.iter().zip(&tb).map(|(a, b)| b / a).collect();
    Ok((median(&mut ta), median(&mut tb), median(&mut ratios)))
}

/// What the session layer adds (issue 15): a level-2 cube step and a 64x64 frozen D-NURBS
/// step, bare and through `Session::step` (alternating batches); the undo snapshot of a
/// level-4 cube (and the full copy that topology edits keep).
fn session_figures(seconds: f64) -> Result<serde_json::Value> {
    use vclay::dynamics::Integrator;
    use vclay::dynamics::dnurbs::benchmarks as dn;
    use vclay::session::models::{dnurbs::DnurbsModel, solid::SolidModel};
    use vclay::session::{Model, Session};
    use vclay::solids::{SolidParams, benchmarks as so};
    let overhead = |(bare, session, ratio): (f64, f64, f64), name: &str| {
        let pct = 100.0 * (ratio - 1.0);
        json!({
            "model": name,
            "bare_ms": bare,
            "session_ms": session,
            "overhead_percent": pct,
            "statistic": "medians of alternating batches; overhead: median of the rounds' ratios",
            "goal": "< 2 %",
            "met": pct < 2.0,
        })
    };
    let mut bare = so::cube(2, SolidParams::default())?;
    so::pull(&mut bare)?;
    let mut wrapped = so::cube(2, SolidParams::default())?;
    so::pull(&mut wrapped)?;
    let mut s = Session::with_model("cube", Box::new(SolidModel::new(wrapped)))?;
    let times = paired_ms(
        seconds,
        || Ok(bare.step().map(drop)?),
        || Ok(s.step().map(drop)?),
    )?;
    let cube = overhead(times, "4^3 cube, level 2");
    let implicit = Integrator::Implicit { dt: dn::DT };
    let mut bare = dn::frozen_sheet(64)?;
    let mut s = Session::with_model(
        "sheet",
        Box::new(DnurbsModel::frozen_surface(dn::frozen_sheet(64)?, dn::DT)?),
    )?;
    let times = paired_ms(
        seconds,
        || Ok(bare.step(implicit).map(drop)?),
        || Ok(s.step().map(drop)?),
    )?;
    let sheet = overhead(times, "64x64 D-NURBS sheet, frozen weights");
    // Snapshots of a level-4 cube (about 117,000 data points).
    let mut big = so::cube(4, SolidParams::default())?;
    so::pull(&mut big)?;
    let data_points = big.data_points().len();
    let model = SolidModel::new(big);
    let time = |f: &dyn Fn()| {
        let mut v: Vec<f64> = (0..7)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[3]
    };
    let snap_ms = time(&|| drop(model.snapshot()));
    let full_ms = time(&|| drop(model.clone_model()));
    Ok(json!({
        "solid_cube_level2_step": cube,
        "dnurbs_64x64_frozen_step": sheet,
        "undo_snapshot_cube_level4": {
            "value": snap_ms,
            "unit": "ms",
            "statistic": "median of 7",
            "data_points": data_points,
            "goal": "< 10",
            "met": snap_ms < 10.0,
            "full_copy_ms": full_ms,
        },
    }))
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Issue 18: the corner rounding of `d-nurbs.txt` Fig 8b (78 control points, weights dynamic,
/// Table 1 "Corner rounding", far-boundary constraints) in steps/s, with the element integrals
/// cut along the knot lines (exact, the default) and with the paper's one Gauss rule per
/// triangle (6 x 6 collapsed points; 4 x 4 wrinkles the fillet). Goal: >= 200 steps/s.
fn corner_rounding_figures(seconds: f64) -> Result<serde_json::Value> {
    use vclay::dynamics::Integrator;
    use vclay::dynamics::dnurbs::TriangleQuadrature;
    use vclay::dynamics::dnurbs::rounding::{RoundingKind, RoundingModel};
    let r = RoundingModel::new(RoundingKind::Corner)?;
    let step = Integrator::Implicit { dt: r.dt() };
    let mut out = json!({});
    for (name, q) in [
        ("subdivided", TriangleQuadrature::default()),
        ("whole_6x6", TriangleQuadrature::Whole { points: 6 }),
    ] {
        let mut m = r.dynamics(q)?;
        let points = m.quadrature_points();
        let rate = steps_per_second((seconds / 2.0).max(0.5), || Ok(m.step(step).map(drop)?))?;
        let mut v = at_least(rate, "steps/s", 200.0);
        v["quadrature_points"] = json!(points);
        out[name] = v;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_rates_come_from_at_least_five_batches_and_errors_propagate() {
        let mut calls = 0usize;
        let (median, mean) = steps_per_second(0.0, || {
            calls += 1;
            black_box((0..1000).sum::<usize>());
            Ok(())
        })
        .unwrap();
        assert!(median.is_finite() && median > 0.0 && mean.is_finite() && mean > 0.0);
        // One untimed step, a calibration batch, then at least five timed batches.
        assert!(calls >= 7, "{calls} calls");
        let mut n = 0;
        let err = steps_per_second(1.0, || {
            n += 1;
            if n == 3 {
                anyhow::bail!("diverged")
            }
            Ok(())
        });
        assert!(err.is_err());
    }

    #[test]
    fn goals_are_checked_against_the_median() {
        let v = at_least((12.0, 9.0), "steps/s", 10.0);
        assert_eq!(v["met"], true);
        assert_eq!(v["mean"], 9.0);
        assert_eq!(at_least((9.0, 12.0), "steps/s", 10.0)["met"], false);
    }
}
