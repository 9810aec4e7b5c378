//! Exports one mass-spring lattice for the peer comparison in `bench/solids_peers.py` (Taichi and
//! NVIDIA Warp on the CPU) and times vclay's own mass-spring step on it.
//!
//! Run: `cargo run --release -p vclay-solids --example spring_export -- LEVEL OUT_DIR [seconds]`
//!
//! The model is the 4^3 cube primitive subdivided `LEVEL` times (as in `bench_levels`), with its
//! data points perturbed deterministically (`d_i += 0.03 h (sin(7 y + 3 z), sin(5 z + 2 x),
//! sin(6 x + 4 y))`, `h` the mean edge rest length) so that every spring is stretched or
//! compressed.
//!
//! # Files written to `OUT_DIR` (NumPy `.npy` format version 1.0, little-endian, C order)
//! | file | dtype | shape | content |
//! |---|---|---|---|
//! | `points.npy` | `<f8` | `(n, 3)` | perturbed data points |
//! | `masses.npy` | `<f8` | `(n,)` | lumped data point masses |
//! | `edges.npy` | `<u4` | `(ne, 2)` | edge spring endpoints `a, b` |
//! | `edge_rest.npy`, `edge_k.npy` | `<f8` | `(ne,)` | rest length, stiffness |
//! | `corners.npy` | `<u4` | `(nc, 3)` | virtual springs `m, a, b` (face corner `m`, its two face neighbours) |
//! | `corner_rest.npy`, `corner_k.npy` | `<f8` | `(nc,)` | rest length, stiffness |
//! | `forces.npy` | `<f8` | `(n, 3)` | vclay's spring forces at `points` (`SpringSet::add_forces`) |
//! | `meta.json` | JSON | | the line printed to stdout |
//!
//! Force law (see `vclay_solids::springs`): edge `x = d_b - d_a`, `l = |x|`,
//! `g = k (l - l0) x / l`, `f_a += g`, `f_b -= g`; virtual spring `x = d_m - (d_a + d_b) / 2`,
//! `g` as before, `f_m -= g`, `f_a += g/2`, `f_b += g/2`.
//!
//! # Timed step
//! One mass-spring step = zero the force buffer, all spring forces (`add_forces`), then
//! symplectic Euler on the data points with lumped masses: `v += dt f / m`, `x += dt v`
//! (`dt` = 1e-4). Timed with `Parallelism::Sequential` (one thread) and `Parallelism::Auto`
//! (rayon's pool; the update pass then runs in rayon chunks too); median over repetitions.
//! Prints one JSON line (with `load1`, the machine's 1-minute load average before timing).

use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{BoundaryRule, primitives};
use vclay_solids::springs::{ForceWorkspace, SpringSet};
use vclay_solids::{DynamicSolid, Material, SolidParams, SolidSource};

/// Fixed time step of the timed step (s).
const DT: f64 = 1e-4;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Writes `data` (raw little-endian values of `descr`) as a `.npy` file via a temp file + rename.
fn write_npy(path: &Path, descr: &str, shape: &[usize], data: &[u8]) -> Res<()> {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {dims}, }}");
    // Magic (6) + version (2) + header length (2) + header + '\n' is a multiple of 64.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let tmp = path.with_extension("npy.tmp");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        w.write_all(b"\x93NUMPY\x01\x00")?;
        w.write_all(&(header.len() as u16).to_le_bytes())?;
        w.write_all(header.as_bytes())?;
        w.write_all(data)?;
        w.flush()?;
    }
    std::fs::rename(&tmp, path)?;
    Ok(())
}

fn f64_bytes(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(f64::to_le_bytes).collect()
}

fn u32_bytes(v: impl IntoIterator<Item = u32>) -> Vec<u8> {
    v.into_iter().flat_map(u32::to_le_bytes).collect()
}

fn vec3_bytes(v: &[Vec3]) -> Vec<u8> {
    f64_bytes(v.iter().flat_map(|p| [p.x, p.y, p.z]))
}

/// Virtual springs flattened to `(m, a, b)` triples with their rest lengths and stiffnesses.
fn corners(s: &SpringSet) -> (Vec<[u32; 3]>, Vec<f64>, Vec<f64>) {
    let mut tri = Vec::with_capacity(s.face_verts.len());
    for f in 0..s.num_faces() {
        let (lo, hi) = (s.face_offsets[f] as usize, s.face_offsets[f + 1] as usize);
        let v = &s.face_verts[lo..hi];
        let k = v.len();
        for j in 0..k {
            tri.push([v[j], v[(j + k - 1) % k], v[(j + 1) % k]]);
        }
    }
    (tri, s.corner_rest.clone(), s.corner_k.clone())
}

/// Symplectic Euler on a chunk of points: `v += dt f / m`, `x += dt v`.
fn update(x: &mut [Vec3], v: &mut [Vec3], f: &[Vec3], inv_m: &[f64]) {
    for i in 0..x.len() {
        v[i] += f[i] * (DT * inv_m[i]);
        x[i] += v[i] * DT;
    }
}

/// One mass-spring step (see the module docs).
fn step(
    s: &SpringSet,
    x: &mut [Vec3],
    v: &mut [Vec3],
    f: &mut [Vec3],
    inv_m: &[f64],
    ws: &mut ForceWorkspace,
    par: Parallelism,
) {
    const CHUNK: usize = 8192;
    let parallel = par.is_parallel(x.len());
    if parallel {
        f.par_chunks_mut(CHUNK).for_each(|c| c.fill(Vec3::zeros()));
    } else {
        f.fill(Vec3::zeros());
    }
    s.add_forces(x, f, ws, par);
    if parallel {
        x.par_chunks_mut(CHUNK)
            .zip(v.par_chunks_mut(CHUNK))
            .zip(f.par_chunks(CHUNK))
            .zip(inv_m.par_chunks(CHUNK))
            .for_each(|(((x, v), f), im)| update(x, v, f, im));
    } else {
        update(x, v, f, inv_m);
    }
}

/// Median milliseconds of one step over repetitions for about `seconds` (at least 5, at most 500).
fn time_step(
    s: &SpringSet,
    x0: &[Vec3],
    inv_m: &[f64],
    par: Parallelism,
    seconds: f64,
) -> (f64, usize) {
    let mut x = x0.to_vec();
    let mut v = vec![Vec3::zeros(); x.len()];
    let mut f = vec![Vec3::zeros(); x.len()];
    let mut ws = ForceWorkspace::default();
    for _ in 0..3 {
        step(s, &mut x, &mut v, &mut f, inv_m, &mut ws, par);
    }
    let mut times = Vec::new();
    let t0 = Instant::now();
    while times.len() < 5 || (t0.elapsed().as_secs_f64() < seconds && times.len() < 500) {
        let t = Instant::now();
        step(s, &mut x, &mut v, &mut f, inv_m, &mut ws, par);
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    assert!(
        x.iter().all(|p| p.iter().all(|c| c.is_finite())),
        "the timed steps diverged"
    );
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], times.len())
}

fn run(level: usize, out: &Path, seconds: f64) -> Res<String> {
    if !(1..=6).contains(&level) {
        return Err(format!("level must be 1..6, got {level}").into());
    }
    std::fs::create_dir_all(out)?;
    let cube = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0));
    let (source, p) = SolidSource::subdivision(cube, BoundaryRule::Sharp, level);
    let t0 = Instant::now();
    let solid = DynamicSolid::new(source, p, Material::default(), SolidParams::default())?;
    let build_s = t0.elapsed().as_secs_f64();
    let springs = solid.springs();
    let h = springs.edge_rest.iter().sum::<f64>() / springs.edge_rest.len().max(1) as f64;
    let x0: Vec<Vec3> = solid
        .data_points()
        .iter()
        .map(|d| {
            d + Vec3::new(
                (7.0 * d.y + 3.0 * d.z).sin(),
                (5.0 * d.z + 2.0 * d.x).sin(),
                (6.0 * d.x + 4.0 * d.y).sin(),
            ) * (0.03 * h)
        })
        .collect();
    let masses = solid.masses();
    if let Some(i) = masses.iter().position(|&m| !(m.is_finite() && m > 0.0)) {
        return Err(format!("data point {i} has mass {}", masses[i]).into());
    }
    let inv_m: Vec<f64> = masses.iter().map(|m| 1.0 / m).collect();
    let mut forces = vec![Vec3::zeros(); x0.len()];
    let energy = springs.add_forces(
        &x0,
        &mut forces,
        &mut ForceWorkspace::default(),
        Parallelism::Sequential,
    );
    let (tri, crest, ck) = corners(springs);
    let (n, ne, nc) = (x0.len(), springs.edges.len(), tri.len());
    write_npy(&out.join("points.npy"), "<f8", &[n, 3], &vec3_bytes(&x0))?;
    write_npy(
        &out.join("masses.npy"),
        "<f8",
        &[n],
        &f64_bytes(masses.iter().copied()),
    )?;
    write_npy(
        &out.join("edges.npy"),
        "<u4",
        &[ne, 2],
        &u32_bytes(springs.edges.iter().flatten().copied()),
    )?;
    write_npy(
        &out.join("edge_rest.npy"),
        "<f8",
        &[ne],
        &f64_bytes(springs.edge_rest.iter().copied()),
    )?;
    write_npy(
        &out.join("edge_k.npy"),
        "<f8",
        &[ne],
        &f64_bytes(springs.edge_k.iter().copied()),
    )?;
    write_npy(
        &out.join("corners.npy"),
        "<u4",
        &[nc, 3],
        &u32_bytes(tri.iter().flatten().copied()),
    )?;
    write_npy(
        &out.join("corner_rest.npy"),
        "<f8",
        &[nc],
        &f64_bytes(crest),
    )?;
    write_npy(&out.join("corner_k.npy"), "<f8", &[nc], &f64_bytes(ck))?;
    write_npy(
        &out.join("forces.npy"),
        "<f8",
        &[n, 3],
        &vec3_bytes(&forces),
    )?;
    let load1: f64 = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(f64::NAN);
    let (seq_ms, seq_reps) = time_step(springs, &x0, &inv_m, Parallelism::Sequential, seconds);
    let (par_ms, par_reps) = time_step(springs, &x0, &inv_m, Parallelism::Auto, seconds);
    let json = format!(
        "{{\"level\": {level}, \"points\": {n}, \"edges\": {ne}, \"corners\": {nc}, \
         \"springs\": {}, \"dt\": {DT:e}, \"energy\": {energy:e}, \"build_s\": {build_s:.3}, \
         \"threads\": {}, \"seq_ms\": {seq_ms:.6}, \"seq_reps\": {seq_reps}, \
         \"par_ms\": {par_ms:.6}, \"par_reps\": {par_reps}, \"load1\": {load1:.2}}}",
        ne + nc,
        rayon::current_num_threads(),
    );
    std::fs::write(out.join("meta.json"), format!("{json}\n"))?;
    Ok(json)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: spring_export LEVEL OUT_DIR [seconds]";
    let (Some(level), Some(out)) = (
        args.get(1).and_then(|a| a.parse::<usize>().ok()),
        args.get(2).map(PathBuf::from),
    ) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let seconds = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(2.0);
    match run(level, &out, seconds) {
        Ok(json) => println!("{json}"),
        Err(e) => {
            eprintln!("spring_export: {e}");
            std::process::exit(2);
        }
    }
}
