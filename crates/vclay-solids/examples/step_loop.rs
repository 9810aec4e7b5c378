//! Temporary: steps the benchmark cube; prints the median ms/step over batches of 100 steps.
use vclay_solids::{SolidParams, benchmarks};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let level: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(2);
    let batches: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(100);
    let par = match args.get(3).map(String::as_str) {
        Some("rayon") => vclay_core::Parallelism::Rayon,
        Some("seq") => vclay_core::Parallelism::Sequential,
        _ => vclay_core::Parallelism::Auto,
    };
    let mut s = benchmarks::cube(
        level,
        SolidParams {
            parallelism: par,
            ..SolidParams::default()
        },
    )
    .unwrap();
    benchmarks::pull(&mut s).unwrap();
    let mut t: Vec<f64> = (0..batches)
        .map(|_| {
            let t0 = std::time::Instant::now();
            for _ in 0..100 {
                s.step().unwrap();
            }
            t0.elapsed().as_secs_f64() * 10.0
        })
        .collect();
    t.sort_by(f64::total_cmp);
    if args.iter().any(|a| a == "--hist") {
        let mut v: Vec<f64> = (0..20000)
            .map(|_| {
                let t0 = std::time::Instant::now();
                s.step().unwrap();
                t0.elapsed().as_secs_f64() * 1e6
            })
            .collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        v.sort_by(f64::total_cmp);
        println!(
            "single steps us: mean {:.1} p1 {:.1} p10 {:.1} p50 {:.1} p90 {:.1} p99 {:.1} max {:.1}",
            mean, v[200], v[2000], v[10000], v[18000], v[19800], v[19999]
        );
        let mut b = [0usize; 8];
        for x in &v {
            b[((*x / 25.0) as usize).min(7)] += 1;
        }
        println!("histogram by 25 us: {:?}", b);
    }
    println!(
        "median {:.4} ms/step, p10 {:.4}, p90 {:.4}",
        t[t.len() / 2],
        t[t.len() / 10],
        t[t.len() * 9 / 10]
    );
}
