//! `d-nurbs.txt` section 6, "continuity requirements between adjacent surface patches" (issue 18):
//! two quadratic D-NURBS sheets side by side, joined G1 (or G0 with `g0` as the argument),
//! sculpted together by a spring that pulls one of them up near the joint. Prints the largest
//! gap and normal angle along the joint every 10 steps.
//!
//! Run: `cargo run --release -p vclay-dynamics --example patches_g1 [g0]`
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{Continuity, GeneralizedDnurbs, PatchesGeometry, Preset, Target};
use vclay_dynamics::{Force, Integrator};
use vclay_spline::{NurbsSurface, ParametricSurface};

fn sheet(x0: f64) -> NurbsSurface {
    let pts = (0..5)
        .flat_map(|i| (0..4).map(move |j| Vec3::new(x0 + i as f64 / 4.0, j as f64 / 3.0, 0.0)))
        .collect();
    NurbsSurface::clamped_uniform([2, 2], [5, 4], pts).expect("sheet")
}

fn main() {
    let continuity = match std::env::args().nth(1).as_deref() {
        Some("g0") => Continuity::G0,
        _ => Continuity::G1,
    };
    let preset = Preset::by_name("Egg sculpting").expect("Table 1 row");
    let g = PatchesGeometry::new(&[sheet(-1.0), sheet(0.0)]).expect("patches");
    let ties = g.join(0, 1, continuity).expect("matching edges");
    let param = g.global_param(0, [0.8, 0.5]);
    let mut d = GeneralizedDnurbs::new(g, preset.surface_material()).expect("model");
    for t in ties {
        d.add_tie(t).expect("tie");
    }
    // Hold the outer edges.
    for (patch, row) in [(0usize, 0usize), (1, 4)] {
        for j in 0..4 {
            for k in 0..3 {
                d.set_fixed_coordinate(patch * 80 + 4 * (row * 4 + j) + k, true)
                    .expect("coordinate");
            }
        }
    }
    d.forces_mut().push(Force::Spring {
        param,
        target: Target::Fixed(Vec3::new(-0.2, 0.5, 0.6)),
        stiffness: preset.k,
        kernel: None,
    });
    for block in 1..=5 {
        for _ in 0..10 {
            d.step(Integrator::Implicit { dt: preset.dt })
                .expect("stable");
        }
        let (a, b) = (
            d.geometry().patch(0).expect("0"),
            d.geometry().patch(1).expect("1"),
        );
        let (mut gap, mut angle) = (0.0f64, 0.0f64);
        for k in 0..=20 {
            let v = k as f64 / 20.0;
            gap = gap.max((a.point(1.0, v).unwrap() - b.point(0.0, v).unwrap()).norm());
            let (na, nb) = (a.normal(1.0, v).unwrap(), b.normal(0.0, v).unwrap());
            if let (Some(na), Some(nb)) = (na, nb) {
                angle = angle.max(na.normalize().dot(&nb.normalize()).clamp(-1.0, 1.0).acos());
            }
        }
        println!(
            "{continuity:?} step {:3}: pulled point z = {:.3}, joint gap {gap:.1e}, normal angle {angle:.1e} rad",
            block * 10,
            a.point(0.8, 0.5).unwrap().z
        );
    }
}
