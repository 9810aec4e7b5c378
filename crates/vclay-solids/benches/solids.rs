//! Criterion benchmark: one time step of the 4^3 cube subdivision solid at levels 2 and 3
//! (`subdivision-solids-journal.txt` Table 2, "Cube (4^3)"), symplectic Euler, rope attached.
//! The full table (levels 1-5, B-spline rows of Table 1, memory) is
//! `cargo run --release -p vclay-solids --example bench_levels`.

use criterion::{Criterion, criterion_group, criterion_main};
use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, primitives};
use vclay_solids::{DynamicSolid, Material, SolidParams, SolidSource};

fn cube(level: usize) -> DynamicSolid {
    let c = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0));
    let (source, p) = SolidSource::subdivision(c, BoundaryRule::Sharp, level);
    let mut s = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0).unwrap();
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
