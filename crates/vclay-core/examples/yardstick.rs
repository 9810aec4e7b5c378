//! Prints the time of the fixed reference workload (`vclay_core::yardstick`) as one JSON line,
//! so that scripts that time other programs (`bench/peers.sh`) can record the host's speed
//! beside their figures (issue 31).
//!
//! Run: `cargo run --release -p vclay-core --example yardstick [seconds]` (default 0.5 s of
//! repeated runs; the median is printed with the 1-minute load average).

use vclay_core::yardstick;

fn main() {
    let seconds: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .filter(|s: &f64| s.is_finite() && *s >= 0.0)
        .unwrap_or(0.5);
    let y = yardstick::measure(seconds);
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "null".into());
    println!(
        "{{\"version\":{},\"ms\":{},\"runs\":{},\"load1\":{load}}}",
        yardstick::YARDSTICK_VERSION,
        y.ms,
        y.runs
    );
}
