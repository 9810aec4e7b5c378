//! Quick timing of vertex normals ([`TriMesh::compute_normals_with`]; not a benchmark harness).
//!
//! For UV spheres of `side x side` vertices and `2 side (side - 1)` triangles (the largest is
//! `bench_deform`'s mesh: 1,000,000 vertices, 1,998,000 triangles) and one copy of the largest
//! with its vertices and triangles in random order (no index locality, the parallel path's worst
//! case), times: the sequential code as it was before it went parallel (2026-12-03), the
//! `Sequential` policy and the `Rayon` policy, wall time (best of several runs, the normal
//! buffer reused as a deforming mesh does) and CPU time of all threads (mean per call), and
//! checks that every result is the same to the bit.
//!
//! Run: `RAYON_NUM_THREADS=2 cargo run --release -p vclay-core --example bench_normals [sides]`
//! (sides comma-separated; default `10,20,40,60,90,130,180,260,1000`).

use std::time::Instant;
use vclay_core::{Parallelism, TriMesh, Vec3};

/// The code as it was before 2026-12-03: the sequential loop (kept unchanged as the
/// `Sequential` policy) with a fresh buffer per call.
fn normals_before(m: &mut TriMesh) {
    m.normals = Vec::new();
    m.compute_normals_with(Parallelism::Sequential);
}

fn sphere(side: usize) -> TriMesh {
    let profile: Vec<(f64, f64)> = (0..side)
        .map(|i| {
            let a = std::f64::consts::PI * (i as f64 + 0.5) / side as f64;
            (a.sin(), -a.cos())
        })
        .collect();
    let mut m = TriMesh::revolution(&profile, side);
    m.normals.clear();
    m
}

/// The same surface with vertices and triangles permuted by a seeded shuffle.
fn shuffled(m: &TriMesh) -> TriMesh {
    let mut x = 0x5eed_0031_u64;
    let mut next = move |n: usize| {
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n
    };
    let n = m.positions.len();
    let mut perm: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        perm.swap(i, next(i + 1));
    }
    let mut out = TriMesh::new();
    out.positions = vec![Vec3::zeros(); n];
    for (v, &p) in perm.iter().enumerate() {
        out.positions[p as usize] = m.positions[v];
    }
    out.triangles = m
        .triangles
        .iter()
        .map(|t| t.map(|i| perm[i as usize]))
        .collect();
    for i in (1..out.triangles.len()).rev() {
        let j = next(i + 1);
        out.triangles.swap(i, j);
    }
    out
}

/// CPU time of all the process's threads in milliseconds (the sum of
/// `/proc/self/task/*/schedstat`; here it advances in scheduler ticks, so only means over many
/// calls are meaningful).
fn process_cpu_ms() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    dir.filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        * 1e-6
}

/// Best wall time and mean CPU time of all threads per call, over `runs` calls, in
/// milliseconds.
fn best(runs: usize, mut f: impl FnMut()) -> (f64, f64) {
    let mut wall = f64::INFINITY;
    let c = process_cpu_ms();
    for _ in 0..runs {
        let t = Instant::now();
        f();
        wall = wall.min(t.elapsed().as_secs_f64() * 1e3);
    }
    (wall, (process_cpu_ms() - c) / runs as f64)
}

fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|n| [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()])
        .collect()
}

fn row(name: &str, mut m: TriMesh) {
    let tris = m.triangles.len();
    let runs = (20_000_000 / tris.max(1)).clamp(5, 2000);
    normals_before(&mut m);
    let want = bits(&m.normals);
    let (old, old_cpu) = best(runs, || normals_before(&mut m));
    let (seq, seq_cpu) = best(runs, || m.compute_normals_with(Parallelism::Sequential));
    assert_eq!(bits(&m.normals), want, "sequential differs");
    let (par, par_cpu) = best(runs, || m.compute_normals_with(Parallelism::Rayon));
    assert_eq!(bits(&m.normals), want, "rayon differs");
    let auto =
        if Parallelism::Auto.is_parallel_from(tris, vclay_core::mesh::NORMALS_PARALLEL_THRESHOLD) {
            "rayon"
        } else {
            "sequential"
        };
    println!(
        "{name:>22} {:>9} vertices {tris:>9} triangles | before {old:8.3} ms (CPU {old_cpu:8.3}) | sequential {seq:8.3} ms (CPU {seq_cpu:8.3}) | rayon {par:8.3} ms (CPU {par_cpu:8.3}) | rayon/sequential {:5.2} | Auto: {auto}",
        m.positions.len(),
        par / seq
    );
}

fn main() {
    let sides: Vec<usize> = std::env::args()
        .nth(1)
        .map(|s| s.split(',').filter_map(|c| c.parse().ok()).collect())
        .unwrap_or_else(|| vec![10, 20, 40, 60, 90, 130, 180, 260, 1000]);
    println!("{} rayon threads", rayon::current_num_threads());
    for &side in &sides {
        row(&format!("sphere {side}x{side}"), sphere(side));
    }
    if let Some(&largest) = sides.iter().max() {
        row(
            &format!("shuffled {largest}x{largest}"),
            shuffled(&sphere(largest)),
        );
    }
}
