//! Memory estimates shared by the front ends (`docs/limits.md`, "Memory estimates"): the
//! bytes a piece of work takes, computed from its sizes before anything is allocated, and the
//! one check against a limit (`vclay --max-memory`, `vclay.set_max_memory` in Python).
//!
//! The formulas of the command line's `--max-memory` checks (`vclay-cli` `limits.rs`,
//! `convert.rs`, `ffd.rs`, `render.rs`, `pde.rs`) live here, and the CLI uses them, so that the
//! Python module and the CLI judge a size the same way. Estimates are `f64`, so sizes such as
//! `usize::MAX` cannot overflow.

use std::fmt;

/// Default memory limit: 4 GiB, what a laptop can spare (`vclay --max-memory`'s default).
pub const DEFAULT_MAX_MEMORY: u64 = 4 << 30;

/// Bytes per vertex of a tessellated model (`vclay convert --samples`): position and normal
/// (48 B), two triangles (24 B), the grid evaluation's samples, the merged mesh and the
/// writer's buffers. Measured peak resident size (release, `/usr/bin/time -v`): 241 B per
/// vertex for OBJ, STL, PLY and glTF alike (4 and 9 million vertices); rounded up.
pub const BYTES_PER_MESH_VERTEX: f64 = 256.0;

/// Bytes per vertex of a PDE surface's grid mesh (`vclay pde --grid`): the grid is evaluated
/// into one mesh without the model-level copies of [`BYTES_PER_MESH_VERTEX`]. Measured 74 B
/// per vertex (the 16-patch aircraft at 1000 x 1000); rounded up.
pub const BYTES_PER_GRID_VERTEX: f64 = 96.0;

/// Bytes per control point of an FFD lattice: control and rest points, weights and the
/// solve's rows (`vclay ffd --lattice 1000x1000x1000` asked for 24 GB at once). Measured 86 B
/// at 100^3 and 81 B at 200^3 control points; rounded up.
pub const BYTES_PER_FFD_CONTROL_POINT: f64 = 96.0;

/// Bytes per cell of the sampled solid when a lattice's boundary limit surface becomes
/// bicubic patches (`vclay convert LATTICE.ovm`): the subdivision hierarchy
/// (`vclay_lattice::command::BYTES_PER_CELL`), the limit samples and the fitted patches and
/// their STEP text. Measured 1,014 B (a 5 x 5 x 5-cell box at level 1) to 1,128 B (issue 29's
/// level-3 torus, 2.07 GB) per cell of the sample level; rounded up.
pub const LIMIT_PATCH_BYTES_PER_CELL: f64 = 1200.0;

/// Bytes per sample of a picture being drawn: supersampled colour and depth.
pub const BYTES_PER_RENDER_SAMPLE: f64 = 16.0;

/// Bytes of a tessellation of `surfaces` surfaces and `volumes` volume boundaries at `samples`
/// per parametric axis: `samples^2` vertices per surface, `6 samples^2` per volume, each
/// [`BYTES_PER_MESH_VERTEX`] (`vclay convert --samples`).
pub fn tessellation_bytes(samples: usize, surfaces: usize, volumes: usize) -> f64 {
    let s2 = (samples as f64).powi(2);
    (surfaces as f64 + 6.0 * volumes as f64) * s2 * BYTES_PER_MESH_VERTEX
}

/// Bytes of a grid of `nu x nv` samples on each of `patches` patches, tessellated
/// (`vclay pde --grid`; [`BYTES_PER_GRID_VERTEX`] each).
pub fn grid_mesh_bytes(nu: usize, nv: usize, patches: usize) -> f64 {
    nu as f64 * nv as f64 * patches as f64 * BYTES_PER_GRID_VERTEX
}

/// Bytes of the boundary limit patches of a lattice of `cells` cells sampled `levels` levels
/// down ([`LIMIT_PATCH_BYTES_PER_CELL`] per cell of the sample level; `vclay convert
/// LATTICE.ovm`).
pub fn limit_patch_bytes(cells: usize, levels: usize) -> f64 {
    cells as f64 * 8f64.powi(levels.min(1024) as i32) * LIMIT_PATCH_BYTES_PER_CELL
}

/// Bytes of an FFD lattice of `dims` control points (`vclay ffd --lattice`).
pub fn ffd_bytes(dims: [usize; 3]) -> f64 {
    dims.iter().map(|&n| n as f64).product::<f64>() * BYTES_PER_FFD_CONTROL_POINT
}

/// Bytes of `frames` pictures of `width x height` pixels at `supersample` samples per pixel
/// side, `at_once` drawn at the same time (one per thread): the supersampled buffers drawn at
/// once and 3 bytes per pixel of every frame kept (`vclay render --size --frames`).
pub fn render_bytes(
    width: u32,
    height: u32,
    supersample: u32,
    frames: usize,
    at_once: usize,
) -> f64 {
    let pixels = f64::from(width) * f64::from(height);
    let ss = f64::from(supersample.clamp(1, 8));
    pixels * (ss * ss * BYTES_PER_RENDER_SAMPLE * at_once as f64 + 3.0 * frames as f64)
}

/// Bytes of `levels` subdivision levels of a lattice of `cells` cells:
/// `vclay_lattice::command::BYTES_PER_CELL` per cell of the finest level (`vclay subdivide`).
pub fn subdivision_bytes(cells: usize, levels: usize) -> f64 {
    cells as f64
        * 8f64.powi(levels.min(1024) as i32)
        * vclay_lattice::command::BYTES_PER_CELL as f64
}

/// Bytes of the JSON tree per printed point (`vclay eval`: a `Value::Array` of three numbers
/// and its text).
pub const BYTES_PER_JSON_POINT: f64 = 200.0;

/// Bytes per query of a subdivision solid's limit (`vclay eval LATTICE.ovm --params`), besides
/// the parameter file's text: the parsed JSON tuple (an array of four values), the query, the
/// limit point and its JSON tree and text. Measured with the cells' part subtracted (release,
/// `/usr/bin/time -v`): 315 B (1,000,000 queries on a level-3 torus), 341 B (200,000 on a
/// level-2 torus), 371 B (1,000,000 on a level-3 box); the middle.
pub const LIMIT_QUERY_BYTES: f64 = 360.0;

/// Bytes per cell of a lattice whose limit is evaluated (`vclay eval LATTICE.ovm`): the lattice
/// as read (points, faces, cells, their adjacency) and the evaluator's per-cell data
/// (`vclay_lattice::limit::LIMIT_BYTES_PER_CELL`, 2.3 kB). Measured, one query, less the
/// process's 6 MB: 3.88 kB per cell on a level-3 torus (65,536 cells, 260 MB) and 3.89 kB on a
/// level-3 box (13,824 cells, 60 MB); rounded up.
pub const LIMIT_EVAL_BYTES_PER_CELL: f64 = 4000.0;

/// Bytes of evaluating the limit of a lattice of `cells` cells at `queries` parameter tuples
/// read from `text_bytes` bytes of parameter file (0 for inline tuples): the text,
/// [`LIMIT_QUERY_BYTES`] per query and [`LIMIT_EVAL_BYTES_PER_CELL`] per cell (`vclay eval
/// LATTICE.ovm`).
pub fn limit_eval_bytes(cells: usize, queries: usize, text_bytes: u64) -> f64 {
    text_bytes as f64
        + queries as f64 * LIMIT_QUERY_BYTES
        + cells as f64 * LIMIT_EVAL_BYTES_PER_CELL
}

/// Bytes of `count` `f64` values (an array the caller asked for).
pub fn f64_bytes(count: f64) -> f64 {
    count * 8.0
}

/// Bytes as a short human number: `4.3 GB`, `512 MB`, `12 kB`.
pub fn human(bytes: f64) -> String {
    if bytes >= 1e15 {
        format!("{bytes:.1e} B")
    } else if bytes >= 1e9 {
        format!("{:.1} GB", bytes / 1e9)
    } else if bytes >= 1e6 {
        format!("{:.0} MB", bytes / 1e6)
    } else {
        format!("{:.0} kB", (bytes / 1e3).max(1.0))
    }
}

/// A limit as the user gives it: a whole number of `K`, `M`, `G` or `T` (powers of 1024, as
/// `--max-memory` reads them) when it is one (`4G` for the default, `512M`), else [`human`].
pub fn human_limit(bytes: u64) -> String {
    for (unit, shift) in [("T", 40), ("G", 30), ("M", 20), ("K", 10)] {
        if bytes >= 1 << shift && bytes.is_multiple_of(1 << shift) {
            return format!("{}{unit}", bytes >> shift);
        }
    }
    human(bytes as f64)
}

/// Work over the memory limit: what was asked (an argument and its value), the estimate and
/// the limit.
#[derive(Clone, Debug, PartialEq)]
pub struct OverLimit {
    /// The argument and its value, e.g. `--samples 20000` or `samples=100000`.
    pub what: String,
    /// Estimated bytes.
    pub bytes: f64,
    /// The limit in bytes.
    pub max: u64,
}

impl fmt::Display for OverLimit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} needs about {} of memory, more than the limit of {}",
            self.what,
            human(self.bytes),
            human_limit(self.max)
        )
    }
}

impl std::error::Error for OverLimit {}

/// Fails when the work described by `what` needs about `bytes`, more than `max` (a NaN
/// estimate fails too).
pub fn check(what: impl FnOnce() -> String, bytes: f64, max: u64) -> Result<(), OverLimit> {
    if bytes.is_nan() || bytes > max as f64 {
        return Err(OverLimit {
            what: what(),
            bytes,
            max,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_match_the_command_line() {
        // docs/limits.md: `--samples 20000` on one surface is about 64 GB.
        assert_eq!(human(tessellation_bytes(20000, 1, 0)), "102.4 GB");
        assert_eq!(ffd_bytes([1000; 3]), 9.6e10);
        assert_eq!(subdivision_bytes(1, 6), 262144.0 * 760.0);
        assert!(check(|| "x".into(), f64::NAN, 1).is_err());
        assert!(check(|| "x".into(), 1e6, DEFAULT_MAX_MEMORY).is_ok());
        let e = check(|| "samples=99".into(), 1e30, DEFAULT_MAX_MEMORY).unwrap_err();
        assert!(e.to_string().starts_with("samples=99 needs about"), "{e}");
        assert!(tessellation_bytes(usize::MAX, 1, 1).is_finite());
        // Issue 29 item 3: the default limit reads as given (4G), not as 4.3 GB.
        assert!(e.to_string().ends_with("the limit of 4G"), "{e}");
        assert_eq!(human_limit(512 << 20), "512M");
        assert_eq!(human_limit(1000), "1 kB");
        assert_eq!(human_limit(3 << 29), "1536M");
    }
}
