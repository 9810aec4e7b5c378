//! Several D-NURBS patches sculpted together with G0/G1 joins (`d-nurbs.txt` section 6,
//! issue 18): the joins hold through the simulation.
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{Continuity, GeneralizedDnurbs, PatchesGeometry, Target};
use vclay_dynamics::{Force, Integrator, Material};
use vclay_spline::{NurbsSurface, ParametricSurface};

/// A flat quadratic sheet `[x0, x0 + 1] x [0, 1]` with 5 x 4 control points.
fn sheet(x0: f64) -> NurbsSurface {
    let mut pts = Vec::new();
    for i in 0..5 {
        for j in 0..4 {
            pts.push(Vec3::new(x0 + i as f64 / 4.0, j as f64 / 3.0, 0.0));
        }
    }
    NurbsSurface::clamped_uniform([2, 2], [5, 4], pts).unwrap()
}

/// Sculpts two joined sheets with a spring pulling patch 0 near the joint up; returns the
/// largest gap and the largest angle between the normals along the joint.
fn sculpt(continuity: Continuity) -> (f64, f64) {
    let g = PatchesGeometry::new(&[sheet(-1.0), sheet(0.0)]).unwrap();
    let ties = g.join(0, 1, continuity).unwrap();
    let param = g.global_param(0, [0.8, 0.5]);
    let mut d = GeneralizedDnurbs::new(g, Material::surface(1.0, 2.0, 1.0, 0.05)).unwrap();
    for t in ties {
        d.add_tie(t).unwrap();
    }
    // Hold the far edges (x, y, z of the outer control-point columns).
    for (patch, row) in [(0usize, 0usize), (1, 4)] {
        for j in 0..4 {
            for k in 0..3 {
                d.set_fixed_coordinate(patch * 80 + 4 * (row * 4 + j) + k, true)
                    .unwrap();
            }
        }
    }
    d.forces_mut().push(Force::Spring {
        param,
        target: Target::Fixed(Vec3::new(-0.2, 0.5, 0.6)),
        stiffness: 30.0,
        kernel: None,
    });
    for _ in 0..25 {
        d.step(Integrator::Implicit { dt: 0.05 }).unwrap();
    }
    let (a, b) = (
        d.geometry().patch(0).unwrap(),
        d.geometry().patch(1).unwrap(),
    );
    let (mut gap, mut angle) = (0.0f64, 0.0f64);
    for k in 0..=10 {
        let v = k as f64 / 10.0;
        gap = gap.max((a.point(1.0, v).unwrap() - b.point(0.0, v).unwrap()).norm());
        let na = a.normal(1.0, v).unwrap().expect("regular");
        let nb = b.normal(0.0, v).unwrap().expect("regular");
        angle = angle.max(na.normalize().dot(&nb.normalize()).clamp(-1.0, 1.0).acos());
    }
    let top = a.point(0.8, 0.5).unwrap().z;
    assert!(top > 0.1, "the spring should lift patch 0 ({top})");
    (gap, angle)
}

#[test]
fn g1_join_keeps_position_and_normals_g0_keeps_position_only() {
    let (gap1, angle1) = sculpt(Continuity::G1);
    assert!(gap1 < 1e-9, "G1 gap {gap1:e}");
    assert!(angle1 < 1e-6, "G1 normal angle {angle1:e}");
    let (gap0, angle0) = sculpt(Continuity::G0);
    eprintln!(
        "G1: gap {gap1:.1e}, normal angle {angle1:.1e}; G0: gap {gap0:.1e}, normal angle {angle0:.1e}"
    );
    assert!(gap0 < 1e-9, "G0 gap {gap0:e}");
    // Only position is joined: a crease forms where the pulled patch meets the other.
    assert!(angle0 > 1e-2, "G0 normal angle {angle0:e}");
}

#[test]
fn joins_check_their_patches() {
    let g = PatchesGeometry::new(&[sheet(-1.0), sheet(0.0)]).unwrap();
    assert!(g.join(0, 0, Continuity::G0).is_err());
    assert!(g.join(0, 2, Continuity::G0).is_err());
    let other = NurbsSurface::clamped_uniform(
        [2, 2],
        [3, 3],
        (0..9)
            .map(|i| Vec3::new((i / 3) as f64, (i % 3) as f64, 0.0))
            .collect(),
    )
    .unwrap();
    let g = PatchesGeometry::new(&[sheet(-1.0), other]).unwrap();
    assert!(g.join(0, 1, Continuity::G1).is_err());
    assert!(PatchesGeometry::new(&[]).is_err());
}
