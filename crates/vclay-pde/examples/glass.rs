//! Reproduces `dynamic-pde-surfaces.txt` Fig 2 (eq 24-26): a glass whose circular opening
//! deforms into a petal shape. Writes `glass_t{0,1,2,3,4}.obj` for t = 0, 0.25, .., 1.
//!
//! Run: `cargo run --release -p vclay-pde --example glass [OUT_DIR]`

use vclay_core::TriMesh;
use vclay_pde::builtin::GLASS;
use vclay_pde::{Animator, ModelSolution, PdeModel, frame_times};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let model = PdeModel::from_json(GLASS, "glass.json")?;
    let mut anim = Animator::new(&model);
    let mut sol = ModelSolution::default();
    for (k, t) in frame_times(0.0, 1.0, 5).into_iter().enumerate() {
        anim.solve_into(t, &mut sol)?;
        let mut mesh = TriMesh::new();
        model.tessellate(&sol, 48, 120, &mut mesh);
        let path = format!("{out}/glass_t{k}.obj");
        vclay_io::mesh::write_mesh(&path, &mesh)?;
        println!(
            "t = {t:.2}: residual rms {:.3e}, relative residual of the bowl {:?} -> {path}",
            sol.residual_rms(),
            sol.patches[0].stats.residual_relative
        );
    }
    Ok(())
}
