//! Subdivides the "Cube (4^3)" control lattice of `subdivision-solids-conference.txt` Table 1
//! (4 x 4 x 4 points, 27 hexahedra) to levels 1..5 and prints, per level, the element counts and
//! the time for topology + level operator + points (`subdivide`), the cumulative time, and the
//! time to apply `A` and `A^T` level by level to all control points (and, for comparison, `A^T`
//! through stored transposes). The time of a level includes
//! building the upward adjacency of the level before it (needed by the rules); the upward
//! adjacency of the last level is built on first use and timed separately.
//!
//! Run with `cargo run --release -p vclay-lattice --example subdivide_bench`.

use std::time::Instant;

use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{
    BoundaryRule, ChainWorkspace, Features, SubdivisionMap, SubdivisionRules, primitives, subdivide,
};

fn main() {
    let levels = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5usize);
    let rules = SubdivisionRules::new(BoundaryRule::Smooth);
    let control = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(3.0));
    println!(
        "threads: {}  control: {:?}",
        rayon::current_num_threads(),
        control.counts().to_array()
    );
    let mut lattice = control.clone();
    let mut features = Features::none(&lattice);
    let mut map = SubdivisionMap::default();
    let mut total = 0.0;
    for level in 1..=levels {
        let t = Instant::now();
        let r = subdivide(&lattice, &features, &rules).expect("subdivision");
        let dt = t.elapsed().as_secs_f64();
        total += dt;
        println!(
            "level {level}: {:>8} points {:>8} edges {:>8} faces {:>8} cells  nnz(A^({level})) {:>9}  {:>8.1} ms  (cumulative {:>8.1} ms)",
            r.lattice.num_points(),
            r.lattice.num_edges(),
            r.lattice.num_faces(),
            r.lattice.num_cells(),
            r.operator.nnz(),
            dt * 1e3,
            total * 1e3
        );
        map.push(r.operator);
        lattice = r.lattice;
        features = r.features;
    }
    let t = Instant::now();
    lattice.build_adjacency();
    println!(
        "full upward adjacency of level {levels} (built lazily, on first use): {:.1} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let p = control.points().to_vec();
    let mut d = vec![Vec3::zeros(); lattice.num_points()];
    let mut ws = ChainWorkspace::new();
    map.apply_into(&p, &mut d, &mut ws, Parallelism::Auto);
    let a_ms = best_of(7, || map.apply_into(&p, &mut d, &mut ws, Parallelism::Auto));
    println!("d = A p (level by level, best of 7): {a_ms:.1} ms");
    let err = d
        .iter()
        .zip(lattice.points())
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    println!("max |A p - subdivided points| = {err:e}");
    let mut g = vec![Vec3::zeros(); p.len()];
    map.apply_transpose_into(&d, &mut g, &mut ws, Parallelism::Auto);
    let at_ms = best_of(7, || {
        map.apply_transpose_into(&d, &mut g, &mut ws, Parallelism::Auto)
    });
    println!("g = A^T d (level by level, scattered rows, best of 7): {at_ms:.1} ms");
    // The previous method, for comparison: stored transposes applied row by row.
    let t = Instant::now();
    map.prepare_transposes();
    println!(
        "(for comparison) stored transposes of all levels: {:.1} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let mut g2 = vec![Vec3::zeros(); p.len()];
    let stored = |g2: &mut [Vec3]| {
        let mut x = d.clone();
        for j in (0..map.levels()).rev() {
            let tj = map.transpose(j);
            let mut y = vec![Vec3::zeros(); tj.nrows()];
            tj.apply_into(&x, &mut y, Parallelism::Auto);
            x = y;
        }
        g2.copy_from_slice(&x);
    };
    stored(&mut g2);
    let stored_ms = best_of(3, || stored(&mut g2));
    let diff = g
        .iter()
        .zip(&g2)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    println!(
        "(for comparison) g = A^T d with stored transposes, best of 3: {stored_ms:.1} ms (max difference {diff:e})"
    );
}

/// The shortest of `runs` timings of `f`, in milliseconds.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}
