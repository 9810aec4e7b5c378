//! Reproduces `dynamic-pde-surfaces.txt` Fig 5(a)-(b) (shape functions (29) with b0 = -1,
//! c0 = -2, d0 = -1.3 and -9, the reading of `docs/pde-figures.md`; the text prints 1, 2, -1300
//! and -9000) and Fig 6(a)-(b) (density rho = 8, damping eta = 9) at t = 0.5, and prints the
//! mean radius of the middle row u = 0.5 of each. Writes `fig5a.obj`, `fig5b.obj`, `fig6a.obj`,
//! `fig6b.obj`.
//!
//! Run: `cargo run --release -p vclay-pde --example manipulation [OUT_DIR]`

use vclay_core::TriMesh;
use vclay_pde::PdeModel;
use vclay_pde::builtin::FIG5A;
use vclay_pde::spec::SpecFile;
use vclay_pde::surface::point;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let base: SpecFile = serde_json::from_str(FIG5A)?;
    let mut b = base.clone();
    b.params.insert("d0".into(), -9.0);
    let mut c = base.clone();
    c.rho = Some(8.0.into());
    let mut d = base.clone();
    d.eta = Some(9.0.into());
    for (name, spec) in [("fig5a", base), ("fig5b", b), ("fig6a", c), ("fig6b", d)] {
        let model = PdeModel::from_spec(&spec)?;
        let sol = model.solve(0.5)?;
        let (p, s) = (&model.patches[0], &sol.patches[0]);
        let mid = (0..64)
            .map(|k| {
                let q = point(p, s, 0.5, std::f64::consts::TAU * k as f64 / 64.0);
                q.x.hypot(q.y)
            })
            .sum::<f64>()
            / 64.0;
        let mut mesh = TriMesh::new();
        model.tessellate(&sol, 64, 96, &mut mesh);
        let path = format!("{out}/{name}.obj");
        vclay_io::mesh::write_mesh(&path, &mesh)?;
        println!(
            "{name}: mid-row radius {mid:.3}, residual relative {:?}, undetermined directions {:?} -> {path}",
            s.stats.residual_relative, s.stats.undetermined
        );
    }
    Ok(())
}
