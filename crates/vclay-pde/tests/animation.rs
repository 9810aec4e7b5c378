//! Animation and manipulation: the vase (eq 27, Fig 3), the glass (eq 24, Fig 2), the
//! manipulations of Figs 4-6 and the local deformation of Fig 7.

use vclay_pde::spec::SpecFile;
use vclay_pde::surface::point;
use vclay_pde::{Animator, ModelSolution, PdeModel, frame_times};

fn load(text: &str) -> SpecFile {
    serde_json::from_str(text).unwrap()
}

const VASE: &str = include_str!("../examples/specs/vase.json");
const GLASS: &str = include_str!("../examples/specs/glass.json");
const FIG7A: &str = include_str!("../examples/specs/fig7a.json");

#[test]
fn vase_boundary_curve_moves_with_t() {
    let model = PdeModel::from_spec(&load(VASE)).unwrap();
    let patch = &model.patches[0];
    // x1 has the paper's four basic functions t, cos v, t^2 cos v, t^3 cos v (eq 28).
    let mut names: Vec<&str> = patch.components[0]
        .basics
        .iter()
        .map(|b| b.name.as_str())
        .collect();
    names.sort();
    assert_eq!(names, ["cos(v)", "cos(v)*t^2", "cos(v)*t^3", "t"]);
    for t in [0.0, 0.3, 0.6, 0.8, 1.0] {
        let sol = model.solve(t).unwrap();
        let s = &sol.patches[0];
        assert!(s.stats.residual_rms.is_finite());
        for k in 0..8 {
            let v = k as f64 * 0.8;
            let p0 = point(patch, s, 0.0, v);
            let p1 = point(patch, s, 1.0, v);
            let want0 = [t + 0.9 * v.cos(), t + 0.9 * v.sin(), 3.0];
            let want1 = [0.4 * v.cos(), 0.4 * v.sin(), 0.0];
            for i in 0..3 {
                assert!((p0[i] - want0[i]).abs() < 1e-12, "t={t} v={v} u=0 comp {i}");
                assert!((p1[i] - want1[i]).abs() < 1e-12, "t={t} v={v} u=1 comp {i}");
            }
        }
    }
}

#[test]
fn glass_opening_turns_into_petals() {
    let model = PdeModel::from_spec(&load(GLASS)).unwrap();
    assert_eq!(model.patches.len(), 3);
    assert!(!model.patches[0].is_static());
    assert!(model.patches[1].is_static() && model.patches[2].is_static());
    let mut anim = Animator::new(&model);
    let mut sol = ModelSolution::default();
    let mut spread = Vec::new();
    for t in frame_times(0.0, 1.0, 5) {
        anim.solve_into(t, &mut sol).unwrap();
        // Radius of the rim over v: constant at t = 0, five petals later.
        let radii: Vec<f64> = (0..100)
            .map(|k| {
                let v = std::f64::consts::TAU * k as f64 / 100.0;
                let p = point(&model.patches[0], &sol.patches[0], 0.0, v);
                (p.x * p.x + p.y * p.y).sqrt()
            })
            .collect();
        let (lo, hi) = radii
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &r| (a.min(r), b.max(r)));
        spread.push(hi - lo);
        // The patches meet: bowl u = 1 is stem u = 0 and stem u = 1 is foot u = 0.
        for k in 0..10 {
            let v = 0.6 * k as f64;
            let a = point(&model.patches[0], &sol.patches[0], 1.0, v);
            let b = point(&model.patches[1], &sol.patches[1], 0.0, v);
            assert!((a - b).norm() < 1e-12);
        }
    }
    assert!(spread[0] < 1e-12, "round opening at t = 0: {spread:?}");
    assert!(
        spread.windows(2).all(|w| w[1] > w[0]),
        "petals grow with t: {spread:?}"
    );
}

// The manipulations of Figs 5 and 6 (shape functions, density, damping) are tested in
// tests/figs56.rs (issue 22).

#[test]
fn local_deformation_g1_and_g0() {
    let model = PdeModel::from_spec(&load(FIG7A)).unwrap();
    let patch = &model.patches[0];
    let sol = model.solve(0.5).unwrap();
    let mut plain = patch.clone();
    plain.local.clear();
    let (u1, u2, v1, v2) = (0.4, 0.5, 5.03, 5.65);
    // Outside the region nothing changes; inside, the centre moves by zeta w^2 = 300/256.
    let outside =
        point(patch, &sol.patches[0], 0.3, 5.3) - point(&plain, &sol.patches[0], 0.3, 5.3);
    assert_eq!(outside.norm(), 0.0);
    let (uc, vc) = (0.5 * (u1 + u2), 0.5 * (v1 + v2));
    let d = point(patch, &sol.patches[0], uc, vc) - point(&plain, &sol.patches[0], uc, vc);
    let want = 300.0 / 256.0 * (vc.cos().powi(2) + vc.sin().powi(2) + 1.0f64).sqrt();
    assert!((d.norm() - want).abs() < 1e-9, "{} vs {want}", d.norm());
    // G1: the offset's derivative across the border vanishes; G0: it does not.
    // Slope of the offset just inside the border u = u1, by a difference over h.
    let jump = |m: &vclay_pde::PdePatch, h: f64| {
        let inside =
            point(m, &sol.patches[0], u1 + h, vc) - point(&plain, &sol.patches[0], u1 + h, vc);
        inside.norm() / h
    };
    // G1: the slope falls with h (it is O(h)); G0: it tends to a non-zero limit.
    let (g1a, g1b) = (jump(patch, 1e-5), jump(patch, 1e-6));
    assert!(
        (g1a / g1b - 10.0).abs() < 0.1,
        "G1 slope is O(h): {g1a} {g1b}"
    );
    let g1 = g1b;
    let mut g0 = patch.clone();
    g0.local[0].continuity = vclay_pde::Continuity::G0;
    g0.local[0].p = [
        vclay_pde::Field::Expr(vclay_pde::Expr::parse("19*cos(v)").unwrap()),
        vclay_pde::Field::Expr(vclay_pde::Expr::parse("19*sin(v)").unwrap()),
        vclay_pde::Field::Const(19.0),
    ];
    let g0s = jump(&g0, 1e-6);
    assert!(
        (jump(&g0, 1e-5) / g0s - 1.0).abs() < 1e-3,
        "G0 slope has a limit"
    );
    assert!(g1 < 1e-2, "G1 slope across the border {g1}");
    assert!(g0s > 1.0, "G0 has a crease: slope {g0s}");
}

#[test]
fn animator_frames_equal_fresh_solves() {
    // The animator reuses static patches (stem, foot); its frames must equal direct solves.
    let model = PdeModel::from_spec(&load(GLASS)).unwrap();
    let mut anim = Animator::new(&model);
    let (mut sol, mut pts) = (ModelSolution::default(), Vec::new());
    let (nu, nv) = (7, 9);
    for t in [0.0, 0.4, 0.9, 0.4] {
        anim.frame(t, nu, nv, &mut sol, &mut pts).unwrap();
        let fresh = model.solve(t).unwrap();
        for (k, patch) in model.patches.iter().enumerate() {
            for r in 0..nu {
                for c in 0..nv {
                    let u = r as f64 / (nu - 1) as f64;
                    let v = patch.v_range.0
                        + (patch.v_range.1 - patch.v_range.0) * c as f64 / (nv - 1) as f64;
                    let want = point(patch, &fresh.patches[k], u, v);
                    let got = pts[k * nu * nv + r * nv + c];
                    assert!((want - got).norm() < 1e-12, "t={t} patch {k} ({r},{c})");
                }
            }
        }
    }
}
