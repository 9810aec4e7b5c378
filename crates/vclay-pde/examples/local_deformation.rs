//! Reproduces `dynamic-pde-surfaces.txt` Fig 7: local deformation of the Fig 5(a) surface in
//! 0.4 < u < 0.5, 5.03 < v < 5.65 with p = (zeta cos v, zeta sin v, zeta): (a) G1 term (32),
//! zeta = 300; (b) G0 term (31), zeta = 19. Writes `fig7a.obj`, `fig7b.obj`.
//!
//! Run: `cargo run --release -p vclay-pde --example local_deformation [OUT_DIR]`

use vclay_core::TriMesh;
use vclay_pde::PdeModel;
use vclay_pde::builtin::FIG7A;
use vclay_pde::spec::{SpecFile, Value};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let a: SpecFile = serde_json::from_str(FIG7A)?;
    let mut b = a.clone();
    b.params.insert("zeta".into(), 19.0);
    b.patches[0].local[0].continuity = "G0".into();
    assert!(matches!(b.patches[0].local[0].p[2], Value::Text(_)));
    for (name, spec) in [("fig7a", a), ("fig7b", b)] {
        let model = PdeModel::from_spec(&spec)?;
        let sol = model.solve(0.5)?;
        let mut mesh = TriMesh::new();
        model.tessellate(&sol, 80, 160, &mut mesh);
        let path = format!("{out}/{name}.obj");
        vclay_io::mesh::write_mesh(&path, &mesh)?;
        let l = &model.patches[0].local[0];
        println!(
            "{name}: {:?} term, peak offset {:.3} at the region's centre -> {path}",
            l.continuity,
            {
                let (u, v) = (0.45, 5.34);
                let d = l.offset(u, v, 0.5);
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            }
        );
    }
    Ok(())
}
