//! Criterion benchmark: one time step of the 4^3 cube subdivision solid at levels 2 and 3
//! (`subdivision-solids-journal.txt` Table 2, "Cube (4^3)"), symplectic Euler, rope attached.
//! The full table (levels 1-5, B-spline rows of Table 1, memory) is
//! `cargo run --release -p vclay-solids --example bench_levels`.

use criterion::{Criterion, criterion_group, criterion_main};
use vclay_solids::{DynamicSolid, SolidParams, benchmarks};

fn cube(level: usize) -> DynamicSolid {
    let mut s = benchmarks::cube(level, SolidParams::default()).unwrap();
    benchmarks::pull(&mut s).unwrap();
    s
}

fn step(c: &mut Criterion) {
    for level in [2, 3] {
        let mut s = cube(level);
        c.bench_function(&format!("cube4_level{level}_step"), |b| {
            b.iter(|| s.step().unwrap())
        });
    }
}

criterion_group!(benches, step);
criterion_main!(benches);
