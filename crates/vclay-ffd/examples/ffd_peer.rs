//! Exports one free-form deformation for the peer comparison in `bench/ffd_peers.py` (PyGeM's
//! `FFD`) and times vclay's (issue 31).
//!
//! Run: `cargo run --release -p vclay-ffd --example ffd_peer -- OUT_DIR [vertices-per-side] [runs]`
//!
//! # The deformation
//! The mesh is the UV sphere of `bench_deform` (`common::uv_sphere`, default 1000 x 1000 =
//! 1,000,000 vertices). The lattice is cubic with 4 control points per axis around the sphere's
//! bounding box grown by [`vclay_ffd::DEFAULT_MARGIN`] (`FfdLattice::enclosing`): clamped knots
//! with 4 control points make it one Bezier volume, `sum_ijk P_ijk b_i(u) b_j(v) b_k(w)` with
//! the Bernstein polynomials `b_i` of degree 3 (`ffd-direct-manipulation.txt` eq 1 with unit
//! weights), and the rest control points sit at `lo + (hi - lo) (i, j, k) / 3`: the lattice of
//! Sederberg and Parry that PyGeM's `FFD(n_control_points=[4, 4, 4])` builds. Every control
//! point `(i, j, k)` moves by
//!
//! ```text
//! d_ijk = 0.08 (hi - lo) * (sin(1.3 i + 0.7 j + 2.1 k + 0.4),
//!                           sin(0.9 i + 1.7 j + 0.5 k + 1.1),
//!                           sin(1.1 i + 0.3 j + 1.9 k + 2.3))      (componentwise product)
//! ```
//!
//! so PyGeM's box-normalized weights are `mu_x[i, j, k] = 0.08 sin(1.3 i + ...)` and so on.
//!
//! # Timed
//! `embed`: `EmbeddedMesh::new` (each vertex's parameters and basis values); `deform`: one full
//! deformation of the positions (`EmbeddedMesh::deform`, normals off), each with
//! `Parallelism::Sequential` (1 thread) and `Parallelism::Rayon` (rayon's pool), best of `runs`
//! (default 5) wall times. A one-shot FFD of a point set (what one PyGeM call does) is
//! `embed + deform`.
//!
//! # Files written to `OUT_DIR`
//! | file | content |
//! |---|---|
//! | `rest.f64` | rest positions, `n x 3` little-endian `f64`, row by row |
//! | `deformed.f64` | vclay's deformed positions, same layout |
//! | `meta.json` | the JSON line printed to stdout: sizes, box, displacements, timings, load, yardstick |

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vclay_core::{Parallelism, Vec3, yardstick};
use vclay_ffd::{DEFAULT_MARGIN, EmbeddedMesh, FfdLattice, LatticeSpec};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Control points per axis (a cubic Bezier volume).
const CONTROL_POINTS: usize = 4;
/// Displacement amplitude, as a fraction of the box's extent along each axis.
const AMPLITUDE: f64 = 0.08;

/// The displacement of control point `(i, j, k)` divided by the box extent (PyGeM's `mu`).
fn normalized_displacement(i: usize, j: usize, k: usize) -> [f64; 3] {
    let (i, j, k) = (i as f64, j as f64, k as f64);
    [
        AMPLITUDE * (1.3 * i + 0.7 * j + 2.1 * k + 0.4).sin(),
        AMPLITUDE * (0.9 * i + 1.7 * j + 0.5 * k + 1.1).sin(),
        AMPLITUDE * (1.1 * i + 0.3 * j + 1.9 * k + 2.3).sin(),
    ]
}

fn write_f64(path: &Path, points: &[Vec3]) -> Res<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    for p in points {
        for c in p.iter() {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    w.flush()?;
    Ok(())
}

fn load1() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(f64::NAN)
}

/// Best wall time (ms) of `runs` embeddings of a fresh copy of `mesh` (the copy is not timed).
fn embed_ms(
    lattice: &FfdLattice,
    mesh: &vclay_core::TriMesh,
    par: Parallelism,
    runs: usize,
) -> f64 {
    (0..runs)
        .map(|_| {
            let m = mesh.clone();
            let t = Instant::now();
            let e = EmbeddedMesh::new(lattice, m, par);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            drop(e);
            ms
        })
        .fold(f64::INFINITY, f64::min)
}

fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

fn main() -> Res<()> {
    let yard_start = yardstick::measure(0.3);
    let mut args = std::env::args().skip(1);
    let out: PathBuf = args
        .next()
        .ok_or("usage: ffd_peer OUT_DIR [vertices-per-side] [runs]")?
        .into();
    let side: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1000);
    let runs: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(5);
    if side < 2 || runs == 0 {
        return Err("vertices-per-side must be at least 2 and runs at least 1".into());
    }
    std::fs::create_dir_all(&out)?;
    let mesh = common::uv_sphere(side);
    let mut lattice = FfdLattice::enclosing(
        &mesh.positions,
        LatticeSpec::uniform(3, CONTROL_POINTS),
        DEFAULT_MARGIN,
    )?;
    let (lo, hi) = lattice.bounds();
    let ext = hi - lo;
    let mut moved = lattice.control_points().to_vec();
    let mut displacements = Vec::new();
    for (flat, p) in moved.iter_mut().enumerate() {
        let [i, j, k] = lattice.multi_index(flat);
        let mu = normalized_displacement(i, j, k);
        let d = Vec3::new(mu[0] * ext.x, mu[1] * ext.y, mu[2] * ext.z);
        *p += d;
        displacements.push(format!("[{i},{j},{k},{},{},{}]", d.x, d.y, d.z));
    }
    lattice.set_control_points(moved)?;
    let load_before = load1();

    let embed_seq = embed_ms(&lattice, &mesh, Parallelism::Sequential, runs);
    let embed_par = embed_ms(&lattice, &mesh, Parallelism::Rayon, runs);
    let mut e = EmbeddedMesh::new(&lattice, mesh.clone(), Parallelism::Rayon);
    e.set_recompute_normals(false);
    let deform_seq = common::best_of(runs, || {
        e.deform(&lattice, Parallelism::Sequential);
    });
    let deform_par = common::best_of(runs, || {
        e.deform(&lattice, Parallelism::Rayon);
    });
    let deform_seq_cpu = common::best_cpu_of(runs, || {
        e.deform(&lattice, Parallelism::Sequential);
    });
    write_f64(&out.join("rest.f64"), &mesh.positions)?;
    write_f64(&out.join("deformed.f64"), &e.mesh().positions)?;
    let yard_end = yardstick::measure(0.3);

    let v = |p: Vec3| format!("[{},{},{}]", p.x, p.y, p.z);
    let line = format!(
        concat!(
            "{{\"vertices\":{},\"embedded\":{},\"control_points\":[{c},{c},{c}],\"degree\":3,",
            "\"box_lo\":{},\"box_hi\":{},\"displacements\":[{}],\"threads\":{},\"runs\":{},",
            "\"embed_ms_1_thread\":{},\"embed_ms_all_threads\":{},",
            "\"deform_ms_1_thread\":{},\"deform_ms_all_threads\":{},\"deform_cpu_ms_1_thread\":{},",
            "\"load1\":{},\"yardstick\":{{\"version\":{},\"start_ms\":{},\"end_ms\":{}}}}}"
        ),
        mesh.positions.len(),
        e.embedded_count(),
        v(lo),
        v(hi),
        displacements.join(","),
        rayon::current_num_threads(),
        runs,
        embed_seq,
        embed_par,
        deform_seq,
        deform_par,
        json_num(deform_seq_cpu),
        json_num(load_before),
        yardstick::YARDSTICK_VERSION,
        yard_start.ms,
        yard_end.ms,
        c = CONTROL_POINTS,
    );
    std::fs::write(out.join("meta.json"), format!("{line}\n"))?;
    println!("{line}");
    Ok(())
}
