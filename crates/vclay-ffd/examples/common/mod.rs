//! Helpers shared by the examples: procedural meshes and a tiny OBJ writer (the io crate is not a
//! dependency of this layer).
#![allow(dead_code)]

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use vclay_core::{TriMesh, Vec3};
use vclay_ffd::FfdLattice;

/// Output directory: the first command-line argument, or `target/ffd-examples`.
pub fn out_dir() -> PathBuf {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/ffd-examples"));
    std::fs::create_dir_all(&dir).expect("create output directory");
    dir
}

/// Writes positions, normals (when present) and triangles as Wavefront OBJ.
pub fn write_obj(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let mut f = BufWriter::new(File::create(path)?);
    writeln!(f, "# vclay-ffd example output")?;
    for p in &mesh.positions {
        writeln!(f, "v {} {} {}", p.x, p.y, p.z)?;
    }
    let normals = mesh.normals.len() == mesh.positions.len();
    if normals {
        for n in &mesh.normals {
            writeln!(f, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        if normals {
            writeln!(f, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(f, "f {a} {b} {c}")?;
        }
    }
    f.flush()?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Writes the control net of a lattice as OBJ polylines (the paper's "computed lattice").
pub fn write_lattice_obj(path: &Path, lattice: &FfdLattice) -> std::io::Result<()> {
    let mut f = BufWriter::new(File::create(path)?);
    writeln!(f, "# vclay-ffd lattice control net")?;
    for p in lattice.control_points() {
        writeln!(f, "v {} {} {}", p.x, p.y, p.z)?;
    }
    let [nu, nv, nw] = lattice.dims();
    let id = |i, j, k| lattice.flat_index(i, j, k) + 1;
    for i in 0..nu {
        for j in 0..nv {
            for k in 0..nw {
                if i + 1 < nu {
                    writeln!(f, "l {} {}", id(i, j, k), id(i + 1, j, k))?;
                }
                if j + 1 < nv {
                    writeln!(f, "l {} {}", id(i, j, k), id(i, j + 1, k))?;
                }
                if k + 1 < nw {
                    writeln!(f, "l {} {}", id(i, j, k), id(i, j, k + 1))?;
                }
            }
        }
    }
    f.flush()?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Radius of the fish's body of revolution at `s` in `[0, 3]` (mouth at 0, tail fin at 3).
fn fish_radius(s: f64) -> f64 {
    if s <= 2.4 {
        // Body: a blunt nose, widest at s = 1.1, narrowing to the tail stalk.
        let x = s / 2.4;
        0.12 + 0.85 * (std::f64::consts::PI * x.powf(0.8)).sin().max(0.0)
    } else {
        // Tail fin: flares from the stalk to the fin's edge.
        let x = (s - 2.4) / 0.6;
        0.12 + 0.55 * x * x
    }
}

/// A fish-like closed surface (the model of `ffd-direct-manipulation.txt` Figs. 5 and 7, made
/// procedurally): a body of revolution along `+y` from the mouth (`y = 0`) to the tail fin
/// (`y = 3`), laterally compressed (x scaled by 0.45), `rings x segments` vertices plus poles.
pub fn fish(rings: usize, segments: usize) -> TriMesh {
    let mut profile = vec![(0.0, 0.0)];
    profile.extend((1..rings).map(|i| {
        let s = 3.0 * i as f64 / rings as f64;
        (fish_radius(s), s)
    }));
    profile.push((0.0, 3.0));
    let mut mesh = TriMesh::revolution(&profile, segments);
    for p in &mut mesh.positions {
        *p = Vec3::new(0.45 * p.x, p.z, p.y);
    }
    // The map (x, y, z) -> (0.45 x, z, y) is a reflection (negative determinant): flip triangles
    // to keep them counter-clockwise seen from outside.
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    mesh.compute_normals();
    mesh
}

/// The point of the fish's surface at length `s` in `(0, 3)` and angle `angle` around its axis
/// (0: towards +x, pi/2: the top, +z).
pub fn fish_point(s: f64, angle: f64) -> Vec3 {
    let r = fish_radius(s);
    Vec3::new(0.45 * r * angle.cos(), s, r * angle.sin())
}

/// UV sphere of radius 1 with `n x n` vertices (rings at polar angles `pi (i + 1/2) / n`, `n`
/// vertices a ring) and `2 n (n - 1)` triangles: the benchmark mesh of `bench_deform` and
/// `ffd_peer`.
pub fn uv_sphere(n: usize) -> TriMesh {
    let mut m = TriMesh::new();
    for i in 0..n {
        let th = std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let ph = std::f64::consts::TAU * j as f64 / n as f64;
            m.positions.push(Vec3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    for i in 0..n - 1 {
        for j in 0..n {
            let a = (i * n + j) as u32;
            let b = (i * n + (j + 1) % n) as u32;
            let (c, d) = (b + n as u32, a + n as u32);
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    m
}

/// The smallest wall time of `runs` calls of `f` (milliseconds).
pub fn best_of<F: FnMut()>(runs: usize, mut f: F) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

/// CPU time of the calling thread in milliseconds (Linux `/proc/thread-self/schedstat`, first
/// field: nanoseconds on a CPU), or `None` where unavailable. Unlike wall time it does not count
/// time spent waiting for a CPU, so it stays meaningful on a busy machine.
pub fn thread_cpu_ms() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-6)
}

/// The smallest thread CPU time of `runs` calls of `f` (milliseconds; NaN where unavailable).
pub fn best_cpu_of<F: FnMut()>(runs: usize, mut f: F) -> f64 {
    (0..runs)
        .map(|_| {
            let t0 = thread_cpu_ms();
            f();
            match (t0, thread_cpu_ms()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            }
        })
        .fold(f64::INFINITY, f64::min)
}
