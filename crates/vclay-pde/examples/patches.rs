//! Reproduces `dynamic-pde-surfaces.txt` Fig 8 (section VI-B, eq 33-37): a four-sided patch with
//! position and tangent conditions on all four sides and a three-sided patch, sharing an edge,
//! together a five-sided surface. Writes `fig8.obj`.
//!
//! Run: `cargo run --release -p vclay-pde --example patches [OUT_DIR]`

use vclay_core::TriMesh;
use vclay_pde::PdeModel;
use vclay_pde::builtin::FIG8;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let model = PdeModel::from_json(FIG8, "fig8.json")?;
    let sol = model.solve(0.0)?;
    for (p, s) in model.patches.iter().zip(&sol.patches) {
        println!(
            "{} ({:?}): unknowns {:?}, residual relative {:?}, undetermined {:?}",
            p.name,
            p.kind(),
            s.stats.unknowns,
            s.stats.residual_relative,
            s.stats.undetermined
        );
    }
    let mut mesh = TriMesh::new();
    model.tessellate(&sol, 32, 32, &mut mesh);
    let path = format!("{out}/fig8.obj");
    vclay_io::mesh::write_mesh(&path, &mesh)?;
    println!("{} vertices -> {path}", mesh.positions.len());
    Ok(())
}
