//! `d-nurbs.txt` Fig 6: a closed cubic D-NURBS curve with 11 control points pulled to 6 data
//! points by springs attached to the nearest curve points (the attachments move with the curve),
//! with the Table 1 "Curve fitting" parameters. The paper does not list its data; six points of an
//! ellipse are used.
//!
//! Run: `cargo run --release -p vclay-dynamics --example fig6_curve_fit`
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{ClosedCurve, Preset};
use vclay_dynamics::{DnurbsClosedCurve, ElasticReference, Force};

fn main() {
    let preset = Preset::by_name("Curve fitting").expect("Table 1 row");
    let ring: Vec<Vec3> = (0..11)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 11.0;
            Vec3::new(1.3 * t.cos(), 1.3 * t.sin(), 0.0)
        })
        .collect();
    let geometry = ClosedCurve::new(3, ring).expect("closed cubic");
    let mut d = DnurbsClosedCurve::new(geometry, preset.curve_material()).expect("model");
    d.set_elastic_reference(ElasticReference::Absolute);
    for k in 0..6 {
        let t = std::f64::consts::TAU * k as f64 / 6.0 + 0.3;
        d.forces_mut().push(Force::DataPoint {
            point: Vec3::new(2.0 * t.cos(), 1.2 * t.sin(), 0.0),
            stiffness: preset.k,
        });
    }
    let worst = |d: &DnurbsClosedCurve| {
        d.data_distances()
            .expect("distances")
            .into_iter()
            .fold(0.0, f64::max)
    };
    println!("step    0: largest data distance {:.4}", worst(&d));
    let t0 = std::time::Instant::now();
    for block in 1..=8 {
        d.run(preset.dt, 125).expect("stable run");
        println!(
            "step {:4}: largest data distance {:.4}, elastic energy {:.3}",
            block * 125,
            worst(&d),
            d.elastic_energy()
        );
    }
    println!("1000 steps in {:.2} s", t0.elapsed().as_secs_f64());
}
