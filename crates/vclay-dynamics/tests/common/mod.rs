//! Helpers shared by the integration tests.

/// Runs `step` once untimed, then `VCLAY_PROFILE_STEPS` times (default 100), and prints the
/// milliseconds per step: the body of the ignored `profile_*` tests, which exist for profilers
/// (`perf record ... -- --ignored profile_...`).
pub fn profile_steps(mut step: impl FnMut()) {
    step();
    let n: usize = std::env::var("VCLAY_PROFILE_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let t = std::time::Instant::now();
    for _ in 0..n {
        step();
    }
    eprintln!(
        "{:.2} ms/step over {n} steps",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
}
