//! Lattices from meshes (issue 19): a UV sphere and a torus of about 100,000 triangles each,
//! fitted at 2,000 cells (levels 2 and 3, smooth and sharp boundary) and at 300 and 20,000
//! cells; prints one row per run with the time and the report's figures (the table of
//! `docs/performance.md`, "Lattices from meshes").
//!
//! `cargo run --release -p vclay-lattice --example clay_fit`

use std::time::Instant;

use vclay_core::{TriMesh, Vec3};
use vclay_lattice::BoundaryRule;
use vclay_lattice::from_mesh::{ClayParams, lattice_from_mesh};

fn sphere(rings: usize, segments: usize) -> TriMesh {
    let profile: Vec<(f64, f64)> = (0..=rings)
        .map(|i| {
            let t = std::f64::consts::PI * i as f64 / rings as f64;
            let r = if i == 0 || i == rings { 0.0 } else { t.sin() };
            (r, -t.cos())
        })
        .collect();
    TriMesh::revolution(&profile, segments)
}

fn torus(major: f64, minor: f64, rings: usize, segments: usize) -> TriMesh {
    let mut mesh = TriMesh::new();
    for s in 0..segments {
        let a = std::f64::consts::TAU * s as f64 / segments as f64;
        for r in 0..rings {
            let b = std::f64::consts::TAU * r as f64 / rings as f64;
            let rho = major + minor * b.cos();
            mesh.positions
                .push(Vec3::new(rho * a.cos(), rho * a.sin(), minor * b.sin()));
        }
    }
    let id = |s: usize, r: usize| ((s % segments) * rings + r % rings) as u32;
    for s in 0..segments {
        for r in 0..rings {
            let (a, b, c, d) = (id(s, r), id(s + 1, r), id(s + 1, r + 1), id(s, r + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

fn main() {
    let meshes = [
        ("sphere", sphere(158, 316)),
        ("torus 1/0.4", torus(1.0, 0.4, 160, 320)),
    ];
    println!(
        "| mesh | triangles | N | L | boundary | cells | s | min cell volume (L0 / L) | voxels mean / max | fitted mean / max | reverse mean / max | refits |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let runs = [
        (2000, 2, BoundaryRule::Smooth),
        (2000, 2, BoundaryRule::Sharp),
        (2000, 3, BoundaryRule::Smooth),
        (300, 2, BoundaryRule::Smooth),
        (20000, 2, BoundaryRule::Smooth),
    ];
    let pct = |x: f64| format!("{:.4} %", 100.0 * x);
    for (name, mesh) in &meshes {
        for &(cells, levels, boundary) in &runs {
            let params = ClayParams {
                cells,
                levels,
                boundary,
                ..ClayParams::default()
            };
            let t = Instant::now();
            let r = lattice_from_mesh(mesh, &params).expect("fit").report;
            let s = t.elapsed().as_secs_f64();
            println!(
                "| {name} | {} | {cells} | {levels} | {boundary:?} | {} | {s:.2} | {:.1e} / {:.1e} | {} / {} | {} / {} | {} / {} | {} |",
                r.input_triangles,
                r.cells,
                r.min_cell_volume,
                r.min_cell_volume_finest,
                pct(r.voxel_distance.mean),
                pct(r.voxel_distance.max),
                pct(r.distance.mean),
                pct(r.distance.max),
                pct(r.reverse_distance.mean),
                pct(r.reverse_distance.max),
                r.refits
            );
        }
    }
}
