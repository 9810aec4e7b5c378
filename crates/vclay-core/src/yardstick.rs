//! A fixed reference workload timed beside every benchmark figure (issue 31).
//!
//! # What
//! The development machines are shared virtual CPUs whose speed drifts by 2-3x from minute to
//! minute (other builds, the host's own load). A figure alone cannot tell a faster build from
//! a quieter minute. Every benchmark therefore times, in the same run, this workload, whose
//! code never changes: a figure divided by the yardstick's time ("in yardsticks") compares
//! across runs far better than the figure itself, and a yardstick much slower than its usual
//! time says the run caught a slow stretch of the host.
//!
//! # How
//! One run ([`run`]) on the calling thread: 16 passes over a 256 KiB array (fits in L2) that
//! mix a streaming multiply-add, a strided gather and a square root and a division per
//! element, the operations the simulation kernels spend their time in: 1.4-2.0 ms on the
//! 2-core development VM under a load average of 4-8 (issue 31's runs). [`measure`] takes the
//! median of repeated runs ([`Yardstick::ms`]). [`YARDSTICK_VERSION`] changes whenever the
//! workload does (it must not, save for a defect), so recorded yardsticks state which one they
//! are.
//!
//! # Limitations
//! One thread: a benchmark on two threads can be slowed by a neighbour on the other core that
//! the yardstick, on one, does not see in full. Memory beyond L2 (the level-5 solid's
//! gigabyte of springs and points) is not exercised. [`process_cpu_seconds`] reads Linux's
//! `/proc/self/stat` and is `None` elsewhere.

use std::hint::black_box;
use std::time::Instant;

/// Version of the workload of [`run`] (recorded with every yardstick figure).
pub const YARDSTICK_VERSION: u32 = 1;

/// Elements of the workload's array (256 KiB of `f64`).
const LEN: usize = 32 * 1024;
/// Passes over the array per run.
const PASSES: usize = 16;

/// The yardstick's time: the median of `runs` runs of [`run`], in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Yardstick {
    /// Median milliseconds per run.
    pub ms: f64,
    /// Runs timed.
    pub runs: usize,
}

impl Yardstick {
    /// `value_ms` in yardsticks (`value_ms / self.ms`).
    pub fn units(&self, value_ms: f64) -> f64 {
        value_ms / self.ms
    }
}

/// One run of the reference workload; returns a checksum (that keeps the work from being
/// optimized away and is the same on every run).
pub fn run() -> f64 {
    let mut x: Vec<f64> = (0..LEN).map(|i| 1.0 + (i % 97) as f64 * 1e-3).collect();
    let mut y = vec![1.0f64; LEN];
    let mut sum = 0.0;
    for pass in 0..PASSES {
        let a = black_box(0.999 - pass as f64 * 1e-4);
        // Streaming multiply-add with a strided gather (odd stride: every element once).
        for i in 0..LEN {
            y[i] = y[i] * a + x[i] * x[(i * 7 + pass) % LEN];
        }
        // A square root and a division per element, as in a spring's force.
        for (xi, yi) in x.iter_mut().zip(&y) {
            let l = (yi * yi + 1.0).sqrt();
            *xi = 1.0 + (1.0 - 1.0 / l) * 1e-3;
        }
        sum += y[pass * 17 % LEN];
    }
    black_box(sum + x[LEN / 2])
}

/// Times [`run`] for about `seconds` (at least 5 runs) and returns the median.
pub fn measure(seconds: f64) -> Yardstick {
    black_box(run());
    let start = Instant::now();
    let mut times = Vec::new();
    while times.len() < 5 || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        black_box(run());
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    Yardstick {
        ms: times[times.len() / 2],
        runs: times.len(),
    }
}

/// The line a timing example prints at its end: the yardstick taken at the run's start
/// (`start`) and one taken now, so a reader can tell a slow host from a slow build.
pub fn start_and_end_line(start: Yardstick) -> String {
    let end = measure(0.3);
    format!(
        "yardstick v{YARDSTICK_VERSION}: {:.3} ms at the start, {:.3} ms at the end (one thread; divide a figure by it to compare runs)",
        start.ms, end.ms
    )
}

/// CPU time of this process so far (user and system, all threads), in seconds: Linux only
/// (`/proc/self/stat`, clock ticks of 1/100 s), `None` elsewhere or on a read error. Time
/// spent waiting for a CPU that another process holds is not counted, so on a loaded machine
/// it moves less than the wall time.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) may hold spaces; the fields after its closing parenthesis
    // start with field 3, so utime (14) and stime (15) are the 12th and 13th there.
    let rest = stat.get(stat.rfind(')')? + 1..)?;
    let mut fields = rest.split_whitespace().skip(11);
    let utime: f64 = fields.next()?.parse().ok()?;
    let stime: f64 = fields.next()?.parse().ok()?;
    // USER_HZ is 100 on every Linux architecture's user-space ABI.
    Some((utime + stime) / 100.0)
}

/// Peak resident set size of this process so far (`VmHWM` of `/proc/self/status`), in bytes:
/// Linux only, `None` elsewhere or on a read error. The benchmarks print it beside their
/// times (issue 31: the level-5 step's peak memory must not grow).
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_workload_is_deterministic_and_timed() {
        assert_eq!(run().to_bits(), run().to_bits());
        assert!(run().is_finite());
        let y = measure(0.0);
        assert!(y.runs >= 5 && y.ms > 0.0 && y.ms.is_finite());
        assert_eq!(y.units(2.0 * y.ms), 2.0);
    }

    #[test]
    fn process_cpu_time_grows() {
        if let Some(a) = process_cpu_seconds() {
            black_box(run());
            let b = process_cpu_seconds().expect("read once, reads again");
            assert!(b >= a);
        }
    }
}
