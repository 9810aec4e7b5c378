//! `dynamic-pde-surfaces.txt` Figs 5-6 (section V-B, V-C, eq 29): which reading of the printed
//! shape constants gives the shapes and trends the paper describes (issue 22). For each reading
//! of `(b0, c0, d0)` (Fig 5(b): the second d0) it prints the vase's middle radius, its bulge
//! (mean signed distance of the profile at v = 0 from the chord joining its ends, outward
//! positive: negative = concave) and the change of the bulge under each of the paper's
//! statements: Fig 5(b) (d0 -> second value), b0 / 2, c0 / 2, d0 x 2 ("smaller |xi|, |zeta|
//! or larger |beta|: more concave"), rho = 8 ("more concave", Fig 6(a)) and eta = 9 ("more
//! convex", Fig 6(b)). The reasoning is in `docs/pde-figures.md`.
//!
//! Run: `cargo run --release -p vclay-pde --example fig56_readings`

use vclay_pde::PdeModel;
use vclay_pde::builtin::FIG5A;
use vclay_pde::spec::SpecFile;
use vclay_pde::surface::point;

/// (middle radius, smallest radius, bulge) of the profile at v = 0, t = 0.5.
fn profile(spec: &SpecFile) -> Result<(f64, f64, f64), Box<dyn std::error::Error>> {
    let model = PdeModel::from_spec(spec)?;
    let sol = model.solve(0.5)?;
    let (p, s) = (&model.patches[0], &sol.patches[0]);
    let n = 201;
    let pts: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let q = point(p, s, k as f64 / (n - 1) as f64, 0.0);
            (q.x, q.z)
        })
        .collect();
    let (a, b) = (pts[0], pts[n - 1]);
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    // Unit normal of the chord pointing away from the axis (positive r).
    let (mut nx, mut nz) = ((b.1 - a.1) / len, -(b.0 - a.0) / len);
    if nx < 0.0 {
        (nx, nz) = (-nx, -nz);
    }
    let bulge = pts
        .iter()
        .map(|&(x, z)| (x - a.0) * nx + (z - a.1) * nz)
        .sum::<f64>()
        / n as f64;
    let rmin = pts.iter().map(|p| p.0).fold(f64::MAX, f64::min);
    Ok((pts[n / 2].0, rmin, bulge))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let base: SpecFile = serde_json::from_str(FIG5A)?;
    println!(
        "| reading (b0, c0, d0 / Fig 5(b) d0) | mid radius 5(a) / 5(b) | smallest radius 5(a) | bulge 5(a) | 5(b) | b0/2 | c0/2 | d0x2 | rho=8 | eta=9 |"
    );
    println!("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (name, b0, c0, d0, d0b) in [
        ("as printed", 1.0, 2.0, -1300.0, -9000.0),
        ("decimal points lost", 1.0, 2.0, -1.3, -9.0),
        ("d0 sign and decimal points lost", 1.0, 2.0, 1.3, 9.0),
        (
            "b0, c0 signs and decimal points lost (used)",
            -1.0,
            -2.0,
            -1.3,
            -9.0,
        ),
    ] {
        let at = |fb: f64, fc: f64, d: f64, rho: f64, eta: f64| {
            let mut s = base.clone();
            s.params.insert("b0".into(), b0 * fb);
            s.params.insert("c0".into(), c0 * fc);
            s.params.insert("d0".into(), d);
            s.rho = Some(rho.into());
            s.eta = Some(eta.into());
            profile(&s)
        };
        let a = at(1.0, 1.0, d0, 1.0, 1.0)?;
        let b = at(1.0, 1.0, d0b, 1.0, 1.0)?;
        let mark = |x: f64, want_up: bool| {
            let ok = (x > 0.0) == want_up;
            format!("{x:+.4} {}", if ok { "yes" } else { "no" })
        };
        println!(
            "| {name} | {:.3} / {:.3} | {:.3} | {:+.4} | {} | {} | {} | {} | {} | {} |",
            a.0,
            b.0,
            a.1,
            a.2,
            mark(b.2 - a.2, false),
            mark(at(0.5, 1.0, d0, 1.0, 1.0)?.2 - a.2, false),
            mark(at(1.0, 0.5, d0, 1.0, 1.0)?.2 - a.2, false),
            mark(at(1.0, 1.0, 2.0 * d0, 1.0, 1.0)?.2 - a.2, false),
            mark(at(1.0, 1.0, d0, 8.0, 1.0)?.2 - a.2, false),
            mark(at(1.0, 1.0, d0, 1.0, 9.0)?.2 - a.2, true),
        );
    }
    Ok(())
}
