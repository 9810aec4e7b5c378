//! `d-nurbs.txt` Fig 7a/7b/7c: a quadratic D-NURBS surface with 7 x 7 = 49 control points (weights
//! dynamic) pulled to 19 points of a hemisphere, and to a convex/concave data set, by springs
//! attached to the nearest surface points, with the parameters of Table 1.
//!
//! Run: `cargo run --release -p vclay-dynamics --example fig7_surface_fit`
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{GeneralizedDnurbs, Preset, RationalGeometry, figures};
use vclay_dynamics::{ElasticReference, Force, Integrator};
use vclay_spline::NurbsSurface;

fn fit(name: &str, preset: &str, data: &[Vec3], steps: usize) {
    let p = Preset::by_name(preset).expect("Table 1 row");
    let geo = RationalGeometry::from_surface(&figures::flat_sheet(7, 2, 2.4).expect("sheet"));
    let mut d = GeneralizedDnurbs::new(geo, p.surface_material()).expect("valid model");
    d.set_elastic_reference(ElasticReference::Absolute);
    for &x in data {
        d.forces_mut().push(Force::DataPoint {
            point: x,
            stiffness: p.k,
        });
    }
    let before = d.data_distances().unwrap();
    let t0 = std::time::Instant::now();
    let mut report = None;
    for _ in 0..steps {
        report = Some(
            d.step(Integrator::Implicit { dt: p.dt })
                .expect("stable run"),
        );
    }
    let secs = t0.elapsed().as_secs_f64();
    let after = d.data_distances().unwrap();
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let w = d.geometry().weights();
    let (wlo, whi) = w
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    println!(
        "{name}: {} data points, RMS distance {:.4} -> {:.4} (max {:.4}), elastic energy {:.4}, weights {wlo:.3}..{whi:.3}, {steps} steps in {:.2} s",
        data.len(),
        rms(&before),
        rms(&after),
        after.iter().cloned().fold(0.0, f64::max),
        d.elastic_energy().unwrap(),
        secs
    );
    let _ = report;
}

/// Fig 7c: 25 samples of a sinusoid, a quadratic 5x5 surface (25 control points, frozen
/// weights), springs at fixed material points (Table 1 "Sinusoidal fitting").
fn sinusoid() {
    use vclay_dynamics::DnurbsSurface;
    use vclay_dynamics::dnurbs::Target;
    let p = Preset::by_name("Sinusoidal fitting").expect("Table 1 row");
    let n = 5;
    let kv = vclay_spline::KnotVector::new(vec![0., 0., 0., 1., 2., 3., 3., 3.], 2, n).unwrap();
    let g = kv.greville();
    let mut pts = Vec::new();
    for i in 0..n {
        for j in 0..n {
            pts.push(Vec3::new(g[i], g[j], 0.0));
        }
    }
    let s = NurbsSurface::from_flat([kv.clone(), kv], pts, vec![1.0; n * n]).unwrap();
    let mut d = DnurbsSurface::new(s, p.surface_material()).unwrap();
    d.set_elastic_reference(ElasticReference::Absolute);
    let f = |u: f64, v: f64| {
        0.6 * (std::f64::consts::TAU * u / 3.0).sin() * (std::f64::consts::PI * v / 3.0).cos()
    };
    let samples: Vec<(f64, f64)> = (0..25)
        .map(|k| (0.3 + 0.6 * (k / 5) as f64, 0.3 + 0.6 * (k % 5) as f64))
        .collect();
    for &(u, v) in &samples {
        d.forces_mut().push(Force::Spring {
            param: [u, v],
            target: Target::Fixed(Vec3::new(u, v, f(u, v))),
            stiffness: p.k,
            kernel: None,
        });
    }
    for _ in 0..400 {
        d.step(Integrator::Implicit { dt: p.dt }).unwrap();
    }
    let err = samples
        .iter()
        .map(|&(u, v)| {
            let z = vclay_spline::ParametricSurface::point(d.geometry(), u, v)
                .unwrap()
                .z;
            (z - f(u, v)).abs()
        })
        .fold(0.0, f64::max);
    println!(
        "Fig 7c sinusoid: 25 data points, 25 control points, largest height error {err:.4} (amplitude 0.6), elastic energy {:.4}",
        d.elastic_energy()
    );
}

fn main() {
    fit(
        "Fig 7a hemisphere",
        "Hemisphere fitting",
        &figures::hemisphere_points(),
        300,
    );
    fit(
        "Fig 7b convex/concave",
        "Convex/Concave fitting",
        &figures::saddle_points(),
        300,
    );
    sinusoid();
}
