//! Reproduces `dynamic-pde-surfaces.txt` Fig 3 (eq 27-28; the vase whose upper boundary moves,
//! t = 0, 0.3, 0.6, 0.8, 1) and Fig 4(a)-(b) (boundary tangents as manipulation, lambda = 0,
//! t = 1). Writes `vase_t*.obj`, `fig4a.obj`, `fig4b.obj`.
//!
//! Run: `cargo run --release -p vclay-pde --example vase [OUT_DIR]`

use vclay_core::TriMesh;
use vclay_pde::PdeModel;
use vclay_pde::builtin::{FIG4A, VASE};
use vclay_pde::spec::SpecFile;

fn write(model: &PdeModel, t: f64, path: &str) -> Result<(), Box<dyn std::error::Error>> {
    let sol = model.solve(t)?;
    let mut mesh = TriMesh::new();
    model.tessellate(&sol, 48, 96, &mut mesh);
    vclay_io::mesh::write_mesh(path, &mesh)?;
    let s = &sol.patches[0].stats;
    println!(
        "{path}: t = {t}, residual rms {:.3e}, relative {:?}, undetermined directions {:?}",
        s.residual_rms, s.residual_relative, s.undetermined
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let vase = PdeModel::from_json(VASE, "vase.json")?;
    for t in [0.0, 0.3, 0.6, 0.8, 1.0] {
        write(&vase, t, &format!("{out}/vase_t{t}.obj"))?;
    }
    let mut spec: SpecFile = serde_json::from_str(FIG4A)?;
    write(
        &PdeModel::from_spec(&spec)?,
        1.0,
        &format!("{out}/fig4a.obj"),
    )?;
    for (k, v) in [
        ("r0p", 1.19),
        ("r1p", -1.84),
        ("h0p", 0.271),
        ("h1p", -0.257),
    ] {
        spec.params.insert(k.into(), v);
    }
    write(
        &PdeModel::from_spec(&spec)?,
        1.0,
        &format!("{out}/fig4b.obj"),
    )?;
    Ok(())
}
