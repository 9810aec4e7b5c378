//! Reproduces `dynamic-pde-surfaces.txt` section III, Fig 1(a)-(b): the collocation solution
//! (M = 36, N = 7) against the closed-form solution (14)-(17), and the error as N grows.
//! Writes `section3.obj`.
//!
//! Run: `cargo run --release -p vclay-pde --example section3 [OUT_DIR]`

#[path = "../tests/support/closed_form.rs"]
mod closed_form;

use closed_form::{ClosedForm, Section3};
use vclay_core::TriMesh;
use vclay_pde::PdeModel;
use vclay_pde::builtin::SECTION3;
use vclay_pde::spec::{CollocationSpec, SpecFile};
use vclay_pde::surface::point;

fn deviation(model: &PdeModel) -> Result<f64, Box<dyn std::error::Error>> {
    let sol = model.solve(0.0)?;
    let reference = ClosedForm::new(&Section3::paper());
    let (mut lo, mut hi, mut worst) = ([f64::MAX; 3], [f64::MIN; 3], 0.0f64);
    for a in 0..=100 {
        for b in 0..=100 {
            let (u, v) = (a as f64 / 100.0, std::f64::consts::TAU * b as f64 / 100.0);
            let r = reference.point(u, v);
            let p = point(&model.patches[0], &sol.patches[0], u, v);
            for i in 0..3 {
                lo[i] = lo[i].min(r[i]);
                hi[i] = hi[i].max(r[i]);
                worst = worst.max((p[i] - r[i]).abs());
            }
        }
    }
    let diag = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    Ok(worst / diag)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "pde-out".into());
    std::fs::create_dir_all(&out)?;
    let spec: SpecFile = serde_json::from_str(SECTION3)?;
    let model = PdeModel::from_spec(&spec)?;
    println!(
        "M = 36, N = 7: largest deviation from the closed form = {:.3e} of the surface diagonal",
        deviation(&model)?
    );
    for n in [5usize, 7, 9, 11, 13] {
        let mut s = spec.clone();
        s.trial_terms = Some(n);
        s.collocation = Some(CollocationSpec::Grid([(n - 1).max(6), 6]));
        println!(
            "N = {n:>2}, M = {:>3}: deviation {:.3e}",
            (n - 1).max(6) * 6,
            deviation(&PdeModel::from_spec(&s)?)?
        );
    }
    let sol = model.solve(0.0)?;
    let mut mesh = TriMesh::new();
    model.tessellate(&sol, 64, 128, &mut mesh);
    let path = format!("{out}/section3.obj");
    vclay_io::mesh::write_mesh(&path, &mesh)?;
    println!("-> {path}");
    Ok(())
}
