//! Per-step time of dynamic solids beside the update times of `subdivision-solids-conference.txt`
//! Table 1 and `subdivision-solids-journal.txt` Tables 1-2 (`benchmarks::PAPER_MODELS`).
//!
//! Run: `cargo run --release -p vclay-solids --example bench_levels -- [max_level] [seconds]
//! [--seq] [--fix-half]` (`--seq`: one thread; `--fix-half`: lower half of the control points
//! fixed, journal section 5.2).
//! Prints one Markdown table row per model: data points, springs, build time, ms per step
//! (symplectic Euler with a rope attached; the median over batches of at least 2 ms and the
//! mean), bytes per data point of the per-step structures and of the process's peak resident
//! memory (only for a model larger than all before it), and the papers' figures.

use std::time::Instant;
use vclay_core::Vec3;
use vclay_solids::{DynamicSolid, Material, SolidParams, SolidSource, benchmarks};
use vclay_spline::KnotVector;

fn peak_rss_mb() -> f64 {
    vclay_core::yardstick::peak_resident_bytes().map_or(f64::NAN, |b| b as f64 / 1048576.0)
}

/// Prints one table row. `largest` is the most data points of any model timed before in this
/// process: the peak resident size per data point means something only for a model at least
/// that large.
fn row(
    name: &str,
    s: &mut DynamicSolid,
    build: f64,
    seconds: f64,
    paper: &str,
    largest: &mut usize,
) {
    let st = s.stats();
    benchmarks::pull(s).unwrap();
    let t = benchmarks::time_steps(s, seconds);
    let (ms, mean, cpu) = (t.median_ms, t.mean_ms, t.cpu_ms);
    let peak = if st.data_points >= *largest {
        format!("{:.0}", peak_rss_mb() * 1048576.0 / st.data_points as f64)
    } else {
        "-".to_string()
    };
    *largest = (*largest).max(st.data_points);
    println!(
        "| {name} | {} | {} ({}) | {} ({}) | {:.2} | {:.4} | {:.4} | {:.4} | {:.1} | {:.0} | {peak} | {paper} |",
        st.control_points,
        st.data_points,
        st.active_data_points,
        st.edge_springs + st.virtual_springs,
        st.active_springs,
        build,
        ms,
        mean,
        cpu,
        1e3 / ms,
        s.bytes_per_data_point(),
    );
}

fn main() {
    // The same run's reference workload (issue 31), at the start and at the end.
    let yard_start = vclay_core::yardstick::measure(0.3);
    let args: Vec<String> = std::env::args().collect();
    let max_level: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(4);
    let seconds: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1.0);
    let fix_half = args.iter().any(|a| a == "--fix-half");
    let params = SolidParams {
        parallelism: if args.iter().any(|a| a == "--seq") {
            vclay_core::Parallelism::Sequential
        } else {
            vclay_core::Parallelism::Auto
        },
        ..SolidParams::default()
    };
    println!(
        "| model | control pts | data pts (active) | springs (active) | build s | wall ms/step (median) | wall ms/step (mean) | CPU ms/step | steps/s (median) | B/data pt (per-step) | B/data pt (peak RSS) | paper ms, conference / journal (PIII 550) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let paper = ["20 / 10", "121 / 72", "-", "-", "-"];
    let mut largest = 0;
    for level in 1..=max_level {
        let t0 = Instant::now();
        let mut s = benchmarks::cube(level, params).unwrap();
        let build = t0.elapsed().as_secs_f64();
        let mut name = format!("Cube (4^3) level {level}");
        if fix_half {
            // All but the top layer of control points (a local modification, section 5.2).
            let low = s.control_points_where(|x| x.z < 0.9);
            s.set_fixed(&low, true).unwrap();
            name += ", all but top layer fixed";
        }
        row(
            &name,
            &mut s,
            build,
            seconds,
            paper[level - 1],
            &mut largest,
        );
    }
    if fix_half || max_level < 2 {
        println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
        return;
    }
    // The other models of conference Table 1 / journal Table 2 that the primitives build.
    for m in &benchmarks::PAPER_MODELS {
        if m.name == "Cube (4^3)" {
            continue; // above
        }
        let t0 = Instant::now();
        let mut s = m.solid(params).unwrap();
        let build = t0.elapsed().as_secs_f64();
        let ms = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v}"));
        let paper = format!("{} / {}", ms(m.conference_ms), ms(m.journal_ms));
        row(
            &format!("{} level {}", m.name, m.level),
            &mut s,
            build,
            seconds,
            &paper,
            &mut largest,
        );
    }
    // Journal Table 1: B-spline solids (journal only).
    for (c, m, paper) in [
        ([4, 4, 4], 10, "40"),
        ([4, 4, 4], 12, "61"),
        ([4, 5, 6], 10, "41"),
        ([5, 5, 5], 10, "61"),
        ([5, 5, 5], 12, "92"),
        ([6, 6, 6], 10, "61"),
        ([6, 6, 6], 12, "111"),
    ] {
        let knots: [KnotVector; 3] =
            std::array::from_fn(|a| KnotVector::clamped_uniform(3, c[a]).unwrap());
        let vol =
            vclay_spline::NurbsVolume::box_lattice([3, 3, 3], c, Vec3::zeros(), Vec3::repeat(1.0))
                .unwrap();
        let source = SolidSource::BSpline {
            knots,
            weights: vec![1.0; vol.control_points().len()],
            samples: [m; 3],
        };
        let t0 = Instant::now();
        let mut s = DynamicSolid::new(
            source,
            vol.control_points().to_vec(),
            Material::default(),
            params,
        )
        .unwrap();
        let build = t0.elapsed().as_secs_f64();
        let name = format!("B-spline {}x{}x{}, {m}^3 samples", c[0], c[1], c[2]);
        row(&name, &mut s, build, seconds, paper, &mut largest);
    }
    println!("{}", vclay_core::yardstick::start_and_end_line(yard_start));
}
