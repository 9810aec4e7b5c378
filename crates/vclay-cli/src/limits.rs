//! The command line's resource policy (issue 17; docs/limits.md).
//!
//! Every size that comes from an argument or a file is checked before anything is allocated,
//! either against a fixed limit (the constants below, and those of the library crates:
//! `vclay_spline::MAX_DERIVATIVE_ORDER`, `vclay_pde::expr::MAX_NODES`, ...) or against an
//! estimate of the memory the work takes, compared with `--max-memory` (default
//! [`DEFAULT_MAX_MEMORY`]). Over it, the error names the option and the estimate.
//!
//! Estimates are computed in `f64`, so sizes such as `18446744073709551615` cannot overflow.

use anyhow::{Result, bail};
use std::sync::atomic::{AtomicU64, Ordering};

/// Default of `--max-memory`: 4 GiB, what a laptop can spare (the session layer's, shared
/// with the Python module).
pub use vclay::session::limits::DEFAULT_MAX_MEMORY;

/// Most animation frames `vclay pde --frames` and `vclay render --frames` accept: each frame is
/// a solve and a file or a picture; 10,000 frames are minutes of animation at 60 frames per
/// second.
pub const MAX_FRAMES: usize = 10_000;

/// The memory estimates (bytes per mesh vertex, per FFD control point, of a picture, of a
/// subdivision) are the session layer's, so the command line and the Python module judge a
/// size the same way.
pub use vclay::session::limits::{BYTES_PER_MESH_VERTEX, ffd_bytes, human, render_bytes};

static MAX_MEMORY: AtomicU64 = AtomicU64::new(DEFAULT_MAX_MEMORY);

/// Sets the limit (from `--max-memory`).
pub fn set_max_memory(bytes: u64) {
    MAX_MEMORY.store(bytes, Ordering::Relaxed);
}

/// The limit in bytes.
pub fn max_memory() -> u64 {
    MAX_MEMORY.load(Ordering::Relaxed)
}

/// Fails when the work described by `what` (an option and its value, e.g.
/// `--samples 20000`) needs about `bytes` of memory, more than `--max-memory`.
pub fn check_memory(what: &str, bytes: f64) -> Result<()> {
    vclay::session::limits::check(|| what.to_string(), bytes, max_memory())
        .map_err(|e| anyhow::anyhow!("{e} (lower it, or raise --max-memory)"))
}

/// At most [`QUOTE_CHARS`] characters of a user's text, for error messages (`...` marks the cut).
pub fn quote(text: &str) -> String {
    if text.chars().count() <= QUOTE_CHARS {
        text.to_string()
    } else {
        let head: String = text.chars().take(QUOTE_CHARS).collect();
        format!("{head}...")
    }
}

/// Most characters of an offending token that an error message quotes.
pub const QUOTE_CHARS: usize = 80;

/// Fails when `count` frames (of `option`) exceed [`MAX_FRAMES`].
pub fn check_frames(option: &str, count: usize) -> Result<()> {
    if count > MAX_FRAMES {
        bail!("{option}: {count} frames is more than the limit of {MAX_FRAMES}");
    }
    Ok(())
}

/// Parses a count given on the command line (steps, levels, samples, frames, ...): a whole
/// number >= 0. clap's own parser says "invalid digit found in string" for `-5` or `ten`.
pub fn parse_count(text: &str) -> Result<usize, String> {
    parse_count_u64(text)
        .and_then(|n| usize::try_from(n).map_err(|_| format!("{n} is too large for this machine")))
}

/// [`parse_count`] as `u64`.
pub fn parse_count_u64(text: &str) -> Result<u64, String> {
    let t = text.trim();
    if t.starts_with('-') && t[1..].parse::<f64>().is_ok() {
        return Err(format!("{t} is negative; give a whole number >= 0"));
    }
    t.replace('_', "")
        .parse::<u64>()
        .map_err(|_| format!("{t:?} is not a whole number >= 0 (digits only, e.g. 100 or 1_000)"))
}

/// Parses `--max-memory`: bytes, or a number with a unit `K`, `M`, `G`, `T` (powers of 1024,
/// optionally followed by `B` or `iB`): `4G`, `512MiB`, `1.5GB`, `1000000`.
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (num, scale) = match body.chars().last() {
        Some('K') => (&body[..body.len() - 1], 1024f64),
        Some('M') => (&body[..body.len() - 1], 1024f64.powi(2)),
        Some('G') => (&body[..body.len() - 1], 1024f64.powi(3)),
        Some('T') => (&body[..body.len() - 1], 1024f64.powi(4)),
        _ => (body, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 && x * scale < 1.8e19 => Ok((x * scale) as u64),
        _ => Err(format!(
            "'{text}': expected a positive size like 4G, 512M or 1000000 (bytes)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_bytes("4G").unwrap(), 4 << 30);
        assert_eq!(parse_bytes("512MiB").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        assert_eq!(parse_bytes("1.5gb").unwrap(), 3 << 29);
        for bad in ["", "-1G", "G", "nan", "1e30", "4X"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
        assert_eq!(human(4.3e9), "4.3 GB");
        assert_eq!(human(5.12e8), "512 MB");
        let e = check_memory("--samples 99", 1e30).unwrap_err().to_string();
        assert!(
            e.contains("--samples 99") && e.contains("--max-memory"),
            "{e}"
        );
        assert!(check_memory("x", f64::NAN).is_err());
        assert!(check_memory("x", 1e6).is_ok());
        assert!(check_frames("--frames", MAX_FRAMES + 1).is_err());
    }
}
