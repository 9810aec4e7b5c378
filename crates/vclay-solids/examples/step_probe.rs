//! Times the full step of the benchmark cube (or a paper model) and prints a digest of the
//! state after a fixed number of steps, so that two builds can be compared for speed and for
//! bit-identical trajectories in the same minutes (issue 31, `docs/performance.md` "Solid step
//! memory traffic").
//!
//! Run: `cargo run --release -p vclay-solids --example step_probe -- MODEL LEVEL SECONDS
//! DIGEST_STEPS [--seq] [--fix-half]`. MODEL is `cube` (the 4^3 benchmark cube of
//! `benchmarks::cube` at LEVEL) or the name of a `benchmarks::PAPER_MODELS` entry (`Gear`,
//! `Torus`, ...: the first entry of that name, at the table's level). `--fix-half` fixes the
//! control points below z = 0.5 (journal section 5.2: the restricted chain). Prints: data
//! points, springs, median and mean wall ms per step over batches of at least 2 ms after
//! `benchmarks::pull`, CPU ms per step, bytes per data point of the per-step structures, peak
//! resident MB, an FNV-1a digest of the bits of the control points, velocities and data points
//! after `benchmarks::pull` and DIGEST_STEPS more steps of a fresh model, and the yardstick
//! (`vclay_core::yardstick`) at the start and the end.

use vclay_solids::{DynamicSolid, SolidParams, benchmarks};

fn peak_rss_mb() -> f64 {
    vclay_core::yardstick::peak_resident_bytes().map_or(f64::NAN, |b| b as f64 / 1048576.0)
}

fn digest(s: &DynamicSolid) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let all = s
        .control_points()
        .iter()
        .chain(s.velocities())
        .chain(s.data_points());
    for x in all {
        for c in x.iter() {
            for b in c.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

/// The model and its subdivision level.
fn build(model: &str, level: usize, params: SolidParams, fix_half: bool) -> (DynamicSolid, usize) {
    let (mut s, level) = if model == "cube" {
        (benchmarks::cube(level, params).unwrap(), level)
    } else {
        let m = benchmarks::PAPER_MODELS
            .iter()
            .find(|m| m.name == model)
            .unwrap_or_else(|| panic!("unknown model {model}"));
        (m.solid(params).unwrap(), m.level)
    };
    if fix_half {
        let low = s.control_points_where(|x| x.z < 0.5);
        s.set_fixed(&low, true).unwrap();
    }
    (s, level)
}

fn main() {
    let yard_start = vclay_core::yardstick::measure(0.3);
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map_or("cube", String::as_str).to_string();
    let level: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(2);
    let seconds: f64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(2.0);
    let digest_steps: usize = args.get(4).and_then(|a| a.parse().ok()).unwrap_or(20);
    let fix_half = args.iter().any(|a| a == "--fix-half");
    let params = SolidParams {
        parallelism: if args.iter().any(|a| a == "--seq") {
            vclay_core::Parallelism::Sequential
        } else {
            vclay_core::Parallelism::Auto
        },
        ..SolidParams::default()
    };
    // Digest first (a fresh model), then timing on another.
    let (mut s, level) = build(&model, level, params, fix_half);
    benchmarks::pull(&mut s).unwrap();
    s.run(digest_steps).unwrap();
    let dig = digest(&s);
    let stats = s.stats();
    let bpp = s.bytes_per_data_point();
    drop(s);
    let (mut s, _) = build(&model, level, params, fix_half);
    benchmarks::pull(&mut s).unwrap();
    let t = benchmarks::time_steps(&mut s, seconds);
    let (median, mean, cpu) = (t.median_ms, t.mean_ms, t.cpu_ms);
    println!(
        "{model} level {level}{}: {} data pts, {} springs, median {median:.4} ms/step ({:.1} \
         steps/s), mean {mean:.4}, cpu {cpu:.4} ms/step, {bpp:.0} B/data pt, peak {:.0} MB, \
         digest({digest_steps}) {dig:016x}\n{}",
        if fix_half { " fix-half" } else { "" },
        stats.data_points,
        stats.edge_springs + stats.virtual_springs,
        1e3 / median,
        peak_rss_mb(),
        vclay_core::yardstick::start_and_end_line(yard_start),
    );
}
