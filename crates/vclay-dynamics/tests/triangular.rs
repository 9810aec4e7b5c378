//! Triangular D-NURBS (`d-nurbs.txt` section 4.4 and section 5): element quadrature accuracy
//! (subdivided along knot lines against the paper's one-rule-per-triangle), and the rounding
//! models of section 7.3 (Fig 8): constraints hold, the fillet is smooth.

use crate::common;

use vclay_dynamics::dnurbs::generalized::GeneralizedGeometry;
use vclay_dynamics::dnurbs::rounding::{InitialShape, RoundingKind, RoundingModel, normal_jump};
use vclay_dynamics::dnurbs::{
    Density, Integrator, Material, TriangleQuadrature, TriangularGeometry,
};

/// `sum_e integral_e f(N)` over all elements with the geometry's quadrature of `k` points.
fn integrate(g: &TriangularGeometry, k: usize, f: impl Fn(&[[f64; 6]]) -> f64) -> f64 {
    let s = g.surface();
    let mut total = 0.0;
    let mut p = vclay_spline::TriangularPoint::default();
    for e in 0..s.basis().domain().triangles().len() {
        let (params, weights) = g.element_rule(e, k).unwrap();
        for (x, w) in params.iter().zip(weights) {
            s.eval_in_element(e, *x, &mut p).unwrap();
            total += w * f(&p.basis);
        }
    }
    total
}

#[test]
fn subdivided_quadrature_is_exact_for_the_piecewise_polynomial_basis() {
    let r = RoundingModel::new(RoundingKind::Edge).unwrap();
    let sub = TriangularGeometry::new(r.surface.clone());
    let whole = TriangularGeometry::new(r.surface.clone())
        .with_quadrature(TriangleQuadrature::Whole { points: 4 });
    // integral sum N = domain area (3 x 1), by the partition of unity.
    for k in [2, 3, 5] {
        let a = integrate(&sub, k, |b| b.iter().map(|v| v[0]).sum());
        assert!((a - 3.0).abs() < 1e-12, "subdivided k={k}: {a}");
    }
    // integral sum N^2 (piecewise of degree 4): the same for every exact rule (k >= 3).
    let sq =
        |g: &TriangularGeometry, k: usize| integrate(g, k, |b| b.iter().map(|v| v[0] * v[0]).sum());
    let exact_sq = sq(&sub, 3);
    assert!(
        (sq(&sub, 5) - exact_sq).abs() < 1e-13,
        "subdivided rules agree"
    );
    let errs: Vec<f64> = [3, 6, 12]
        .iter()
        .map(|&k| (sq(&whole, k) - exact_sq).abs() / exact_sq)
        .collect();
    eprintln!("whole-triangle rule relative error of integral sum N^2, k = 3, 6, 12: {errs:?}");
    assert!(
        errs[0] > 1e-8,
        "the basis is not polynomial on a triangle: {errs:?}"
    );
    // Mass-matrix entry of two neighbouring control points: subdivided rules agree to rounding
    // (exact for degree 2n = 4 from k = 3), the whole-triangle rule converges slowly.
    let m = |g: &TriangularGeometry, k: usize| integrate(g, k, |b| b[0][0] * b[1][0]);
    let exact = m(&sub, 3);
    assert!((m(&sub, 6) - exact).abs() < 1e-14 * (1.0 + exact.abs()) * 10.0);
    let werr: Vec<f64> = [3, 6, 12]
        .iter()
        .map(|&k| (m(&whole, k) - exact).abs())
        .collect();
    eprintln!("whole-triangle rule error of a mass entry ({exact:.6}), k = 3, 6, 12: {werr:?}");
    assert!(werr[2] < werr[0], "whole rule converges: {werr:?}");
}

/// Runs a rounding model and checks the far-boundary constraints and the fillet; returns the
/// normal turn over 0.05 across the old edge before and after.
fn rounding(kind: RoundingKind, quadrature: TriangleQuadrature, steps: usize) -> (f64, f64) {
    let r = RoundingModel::new(kind).unwrap();
    let mut m = r.dynamics(quadrature).unwrap();
    let e0 = m.elastic_energy().unwrap();
    // Measured on the C^1 start: the sharp one has no normal inside its collapsed column.
    let c1 = RoundingModel::with_initial(kind, InitialShape::Rounded).unwrap();
    let before = normal_jump(&c1.surface, &r.edges, 0.05, 5).unwrap();
    m.run(r.dt(), steps).unwrap();
    let e1 = m.elastic_energy().unwrap();
    let scale = m.geometry().scale();
    let worst = m
        .constraint_violations()
        .unwrap()
        .into_iter()
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-8 * scale,
        "{kind:?}: constraint violation {worst}"
    );
    assert!(e1 < e0, "{kind:?}: the energy drops ({e0} -> {e1})");
    let s = m.geometry().surface();
    // Normals are continuous across the old edge: the jump shrinks with the distance.
    let near = normal_jump(s, &r.edges, 1e-6, 7).unwrap();
    let far = normal_jump(s, &r.edges, 1e-3, 7).unwrap();
    assert!(
        near < 1e-4 && near < far,
        "{kind:?}: normal jump {near} (1e-6) {far} (1e-3)"
    );
    // The far boundary is held: its control points did not move.
    for &c in &r.fixed_controls {
        assert_eq!(s.control_points()[c], r.surface.control_points()[c]);
    }
    assert!(!r.fixed_controls.is_empty() && r.fixed_controls.len() < s.control_points().len());
    // Weights are dynamic and stay positive.
    assert!(m.geometry().weights().iter().all(|&w| w > 0.0));
    (before, normal_jump(s, &r.edges, 0.05, 5).unwrap())
}

#[test]
fn edge_rounding_keeps_constraints_and_rounds() {
    let r = RoundingModel::new(RoundingKind::Edge).unwrap();
    assert_eq!(r.surface.control_points().len(), 21);
    let (before, after) = rounding(
        RoundingKind::Edge,
        TriangleQuadrature::Whole { points: 4 },
        10,
    );
    // The edge gets rounder: the normal turns less over 0.05 across it.
    assert!(after < 0.5 * before, "edge: {before} -> {after}");
}

#[test]
fn edge_rounding_with_subdivided_quadrature() {
    rounding(RoundingKind::Edge, TriangleQuadrature::default(), 1);
}

/// The default cells use the symmetric degree-2n rule (6 points a fan triangle for the
/// quadratic corner); the collapsed 3 x 3 rule (9 points) is exact for the same degree. Both
/// integrate the control-point terms exactly, so with the weights frozen the runs agree to
/// rounding; with dynamic weights the weight columns' integrands (degree 4n at uniform weights,
/// rational after) are approximated by both, and a 7 x 7 reference shows the two rules equally
/// close to it (about 7e-5 of the model size after 8 steps in which the weights move by 25 %).
#[test]
fn symmetric_cell_rule_matches_the_collapsed_rule_of_the_same_degree() {
    let r = RoundingModel::new(RoundingKind::Corner).unwrap();
    let run = |q: TriangleQuadrature, freeze: bool| {
        let mut m = r.dynamics(q).unwrap();
        if freeze {
            for i in m.geometry().weight_coordinates() {
                m.set_fixed_coordinate(i, true).unwrap();
            }
        }
        m.run(r.dt(), 8).unwrap();
        m.geometry().coordinates().to_vec()
    };
    let gap = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let scale = TriangularGeometry::new(r.surface.clone()).scale();
    let collapsed = |k| TriangleQuadrature::Subdivided { points: Some(k) };
    let frozen = gap(
        &run(TriangleQuadrature::default(), true),
        &run(collapsed(3), true),
    );
    assert!(frozen < 1e-12 * scale, "frozen weights: {frozen:.3e}");
    let reference = run(collapsed(7), false);
    let symmetric = gap(&run(TriangleQuadrature::default(), false), &reference);
    let gauss = gap(&run(collapsed(3), false), &reference);
    let start = gap(
        &reference,
        TriangularGeometry::new(r.surface.clone()).coordinates(),
    );
    eprintln!(
        "after 8 steps (motion {start:.3e}): symmetric {symmetric:.3e}, collapsed 3x3 {gauss:.3e}"
    );
    assert!(start > 1e-2 * scale, "the fillet moved: {start:.3e}");
    assert!(symmetric < 1e-4 * scale && symmetric < 2.0 * gauss);
}

#[test]
fn corner_and_bevel_rounding_keep_constraints() {
    let c = RoundingModel::new(RoundingKind::Corner).unwrap();
    assert_eq!(c.surface.control_points().len(), 78);
    let b = RoundingModel::new(RoundingKind::Bevel).unwrap();
    assert_eq!(b.surface.control_points().len(), 108);
    // A cheap rule for debug-mode tests: one 6 x 6 collapsed Gauss rule per triangle (fewer
    // points under-integrate the corner: k = 4 wrinkles it, see docs/performance.md).
    rounding(
        RoundingKind::Corner,
        TriangleQuadrature::Whole { points: 6 },
        1,
    );
    rounding(
        RoundingKind::Bevel,
        TriangleQuadrature::Whole { points: 6 },
        1,
    );
}

/// Timing probe (run with `--release --ignored`): where a corner-rounding step spends its time.
#[test]
#[ignore]
fn probe_corner_step_cost() {
    use vclay_dynamics::dnurbs::GeneralizedGeometry as _;
    for (frozen, constrained, q) in [
        (false, true, TriangleQuadrature::Whole { points: 6 }),
        (true, true, TriangleQuadrature::Whole { points: 6 }),
        (false, false, TriangleQuadrature::Whole { points: 6 }),
        (false, true, TriangleQuadrature::default()),
        (false, false, TriangleQuadrature::default()),
        (true, false, TriangleQuadrature::default()),
    ] {
        let r = RoundingModel::new(RoundingKind::Corner).unwrap();
        let mut m = r.dynamics(q).unwrap();
        if frozen {
            for i in m.geometry().weight_coordinates() {
                m.set_fixed_coordinate(i, true).unwrap();
            }
        }
        if !constrained {
            m.clear_constraints();
        }
        m.step(Integrator::Implicit { dt: r.dt() }).unwrap();
        eprintln!(
            "{q:?}: cached basis {} bytes",
            m.geometry().cached_basis_bytes()
        );
        let t = std::time::Instant::now();
        let n = 10;
        for _ in 0..n {
            m.step(Integrator::Implicit { dt: r.dt() }).unwrap();
        }
        let per = t.elapsed().as_secs_f64() / n as f64;
        eprintln!(
            "frozen {frozen} constrained {constrained} {q:?}: {:.2} ms/step, substeps {}",
            per * 1e3,
            m.state().substeps
        );
    }
}

/// Timing probe (run with `--release --ignored --nocapture`): steps/s of the paper's corner
/// (78 points) and of the sharp corner (114 points), default quadrature, the step `vclay bench
/// --physics` times (implicit, weights dynamic, constraints on), alternated three times.
#[test]
#[ignore]
fn probe_sharp_corner_step_rate() {
    for round in 0..3 {
        for kind in [RoundingKind::Corner, RoundingKind::SharpCorner] {
            let r = RoundingModel::new(kind).unwrap();
            let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
            m.step(Integrator::Implicit { dt: r.dt() }).unwrap();
            let n = 200;
            let t = std::time::Instant::now();
            for _ in 0..n {
                m.step(Integrator::Implicit { dt: r.dt() }).unwrap();
            }
            let rate = n as f64 / t.elapsed().as_secs_f64();
            eprintln!(
                "round {round} {kind:?}: {} control points, {} quadrature points, {rate:.0} steps/s",
                r.surface.control_points().len(),
                m.quadrature_points()
            );
        }
    }
}

/// The cached basis values (filled by `element_quadrature`) give the Jacobian of a direct
/// evaluation bit for bit, after the control points and weights have moved (issue 18).
#[test]
fn cached_basis_jacobian_matches_direct_evaluation() {
    use vclay_dynamics::dnurbs::generalized::LocalJacobian;
    let r = RoundingModel::new(RoundingKind::Edge).unwrap();
    for q in [
        TriangleQuadrature::default(),
        TriangleQuadrature::Whole { points: 4 },
    ] {
        let mut cached = TriangularGeometry::new(r.surface.clone()).with_quadrature(q);
        let rules: Vec<_> = (0..cached.element_count())
            .map(|e| cached.element_quadrature(e, [3, 3]).unwrap())
            .collect();
        let bytes = cached.cached_basis_bytes();
        let points: usize = rules.iter().map(|r| r.0.len()).sum();
        assert!(bytes >= 64 * points, "{bytes} bytes for {points} points");
        // Move points and weights (deterministic, weights stay positive).
        let mut c = cached.coordinates().to_vec();
        for (i, x) in c.iter_mut().enumerate() {
            let t = (i as f64 * 0.7).sin();
            *x = if i % 4 == 3 {
                *x * (1.0 + 0.4 * t)
            } else {
                *x + 0.05 * t
            };
        }
        cached.set_coordinates(&c).unwrap();
        // A fresh geometry has no cache: every point is evaluated directly.
        let mut direct = TriangularGeometry::new(r.surface.clone()).with_quadrature(q);
        direct.set_coordinates(&c).unwrap();
        assert_eq!(direct.cached_basis_bytes(), 0);
        let (mut a, mut b) = (LocalJacobian::default(), LocalJacobian::default());
        for (e, (params, _)) in rules.iter().enumerate() {
            for &p in params {
                cached.element_jacobian_at(e, p, &mut a).unwrap();
                direct.element_jacobian_at(e, p, &mut b).unwrap();
                assert_eq!(a.s, b.s, "element {e} at {p:?}");
                assert_eq!(a.blocks, b.blocks, "element {e} at {p:?}");
                assert_eq!(a.vectors, b.vectors, "element {e} at {p:?}");
            }
        }
    }
}

/// Steady-state steps of the corner rounding as `vclay bench --physics` runs it (default
/// quadrature, far-boundary constraints), for profilers: `VCLAY_PROFILE_STEPS` steps (default
/// 100) after one untimed step; `VCLAY_PROFILE_POINTS=k` uses `k x k` collapsed points per cell.
#[test]
#[ignore = "profiling aid, run by hand"]
fn profile_corner_steps() {
    let r = RoundingModel::new(RoundingKind::Corner).unwrap();
    let points = std::env::var("VCLAY_PROFILE_POINTS")
        .ok()
        .and_then(|s| s.parse().ok());
    let mut m = r
        .dynamics(TriangleQuadrature::Subdivided { points })
        .unwrap();
    eprintln!("{} quadrature points", m.quadrature_points());
    common::profile_steps(|| {
        m.step(Integrator::Implicit { dt: r.dt() }).unwrap();
    });
}

/// The wrong-way share ([`Turning::wrong_way`]) of a rounding model's surface after `steps`
/// implicit steps with `material` (default quadrature, the scenarios' rule); writes the final
/// mesh as OBJ into `$VCLAY_ROUNDING_OBJ` when that is set (to look at it).
fn wrong_way_after(kind: RoundingKind, material: Material, steps: usize, tag: &str) -> f64 {
    use vclay_dynamics::dnurbs::rounding::mesh_turning;
    let r = RoundingModel::new(kind).unwrap();
    let mut m = r
        .dynamics_with_material(TriangleQuadrature::default(), material)
        .unwrap();
    m.run(r.dt(), steps).unwrap();
    let mut mesh = vclay_core::TriMesh::new();
    m.geometry().surface().tessellate(8, &mut mesh).unwrap();
    if let Ok(dir) = std::env::var("VCLAY_ROUNDING_OBJ") {
        let mut obj = String::new();
        for p in &mesh.positions {
            obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        for t in &mesh.triangles {
            obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        std::fs::write(format!("{dir}/{kind:?}_{tag}.obj"), obj).unwrap();
    }
    let t = mesh_turning(&mesh);
    eprintln!(
        "{kind:?} {tag} after {steps} steps: turning +{:.4} -{:.4}, wrong way {:.2} %",
        t.positive,
        t.negative,
        100.0 * t.wrong_way()
    );
    t.wrong_way()
}

/// Issue 28, the root cause of the wrong-way turning of the Fig 8 fillets, measured on the
/// edge model: the thin plate under tension with the Table 1 "Edge rounding" densities
/// (`a11 = 1000`, `b11 = 1` over unit domain spans) is tension-dominated, and its discrete
/// equilibrium next to a held boundary alternates from span to span (see the module docs of
/// `rounding.rs`): about a quarter of the turning folds the wrong way (the issue measured
/// 24-30 % on the shipped scenarios). The same model with `a11 <= 6 b11` per span turns much
/// less the wrong way. Asserts the measured directions, so a fix shows here first.
#[test]
fn issue_28_tension_dominated_rounding_folds_the_wrong_way() {
    let table1 = RoundingKind::Edge.preset().surface_material();
    let shipped = wrong_way_after(RoundingKind::Edge, table1.clone(), 100, "table1");
    let balanced = wrong_way_after(
        RoundingKind::Edge,
        RoundingKind::Edge.material(),
        100,
        "a11_6",
    );
    // The corner and the bevel with bending raised to a = 6 b (bevel: b = a / 6), printed
    // for the record (issue 28's report).
    for kind in [RoundingKind::Corner, RoundingKind::Bevel] {
        let mut m = kind.preset().surface_material();
        let a = kind.preset().alpha[0];
        m.beta = vec![Density::Constant(a / 6.0); 3];
        wrong_way_after(kind, m, 100, "b_a_over_6");
    }
    assert!(shipped > 0.1, "Table 1 edge: wrong-way share {shipped}");
    assert!(balanced < 0.02, "a11 = 6: {balanced} against {shipped}");
}

/// Issue 28, Fig 8a2 (d-nurbs.txt section 7.3): the edge relaxes into a convex fillet tangent
/// to both faces, with the densities of `RoundingKind::material` (Table 1 read over the span
/// `RoundingKind::span`). As in the paper the patch covers the region to be rounded and its
/// far boundaries are held to the faces in position and normal; the faces themselves lie
/// outside it. Checks, after the scenario's 100 steps:
/// - convex: under 2 % of the turning the wrong way. The tension-dominated reading gives 30 %;
///   this reading leaves a residual of 1.0-1.6 % (measured for a11 from 1 to 6, 100 to 300
///   steps, with and without the damping rescaled), whose source is not located yet, so the
///   tolerance bounds it rather than explains it;
/// - tangent to the faces: the normal along the held boundaries is the face normal;
/// - rounded: the middle of the old edge moved into the solid (to about 0.5 from each face).
#[test]
fn issue_28_edge_rounding_makes_a_convex_fillet_tangent_to_the_faces() {
    use vclay_dynamics::dnurbs::rounding::mesh_turning;
    let r = RoundingModel::new(RoundingKind::Edge).unwrap();
    let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
    m.run(r.dt(), 100).unwrap();
    let s = m.geometry().surface();
    let mut mesh = vclay_core::TriMesh::new();
    s.tessellate(8, &mut mesh).unwrap();
    let w = mesh_turning(&mesh).wrong_way();
    // Strips next to the held boundaries: how far they leave the face planes z = 0 and x = 1.5
    // (printed: the fillet starts at the boundary, tangentially).
    let (mut off_a, mut off_b) = (0.0f64, 0.0f64);
    for i in 0..=10 {
        for j in 0..=10 {
            let (u, v) = (0.05 * i as f64, 0.1 * j as f64);
            off_a = off_a.max(s.point([u, v]).unwrap().z.abs());
            off_b = off_b.max((s.point([3.0 - u, v]).unwrap().x - 1.5).abs());
        }
    }
    // Normals at the held boundaries against the face normals (radians).
    let mut tilt = 0.0f64;
    for j in 0..=10 {
        let v = 0.1 * j as f64;
        for (u, face) in [(0.0, vclay_core::Vec3::z()), (3.0, vclay_core::Vec3::x())] {
            let d = s.derivatives([u, v]).unwrap();
            let n = d[1].cross(&d[2]).normalize();
            tilt = tilt.max(n.dot(&face).abs().clamp(0.0, 1.0).acos());
        }
    }
    let x = s.point([1.5, 0.5]).unwrap();
    eprintln!(
        "edge: wrong way {:.2} %, face strips off their planes {off_a:.2e} / {off_b:.2e}, \
         boundary normal tilt {tilt:.2e} rad, old edge middle at {x:?}",
        100.0 * w
    );
    assert!(w < 0.02, "{:.2} % folds the wrong way", 100.0 * w);
    assert!(tilt < 1e-9, "the boundary normals tilt by {tilt}");
    assert!(x.x < 1.4 && x.z < -0.1, "the edge is not rounded: {x:?}");
}

/// Issue 28, Fig 8b2 and 8c2 (d-nurbs.txt section 7.3): the corner and the bevel relax into
/// fillets that turn one way and stay tangent to the faces, with the densities of
/// `RoundingKind::material`, the scenarios' quadrature and step counts. Checks:
/// - convex: the wrong-way share ([`Turning::wrong_way`]) under `max_wrong` (measured 3.1 %
///   for the corner, 1.7 % for the bevel; Table 1 as printed with the whole boundary held gave
///   25 % and 30 %);
/// - tangent to the faces: along the boundaries held whole, the normal is the face's
///   (an axis) and did not move;
/// - the crossing sections stay in their planes across the edges (the held coordinate);
/// - rounded: the corner point (the middle of the bevel's joint) moved by more than
///   `min_moved` into the solid (out of it for the concave bevel); measured 0.07 and 0.71 (the
///   corner's initial shape is already rounded over its edge quads by the C^1 basis, the
///   bevel starts sharp).
fn fillet_is_convex_and_tangent(kind: RoundingKind, steps: usize, max_wrong: f64, min_moved: f64) {
    use vclay_dynamics::dnurbs::rounding::mesh_turning;
    let r = RoundingModel::new(kind).unwrap();
    let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
    m.run(r.dt(), steps).unwrap();
    let s = m.geometry().surface();
    let mut mesh = vclay_core::TriMesh::new();
    s.tessellate(8, &mut mesh).unwrap();
    let w = mesh_turning(&mesh).wrong_way();
    // Normals along the boundaries held whole: the face's (the nearest axis), unchanged.
    let normal = |surf: &vclay_spline::TriangularNurbs, q: [f64; 2]| {
        let d = surf.derivatives(q).unwrap();
        d[1].cross(&d[2]).normalize()
    };
    let (mut tilt, mut moved_normal) = (0.0f64, 0.0f64);
    for seg in r.held_boundaries() {
        for k in 0..=10 {
            let f = k as f64 / 10.0;
            let q = [
                seg[0][0] + f * (seg[1][0] - seg[0][0]),
                seg[0][1] + f * (seg[1][1] - seg[0][1]),
            ];
            let (n0, n1) = (normal(&r.surface, q), normal(s, q));
            let axis = n1.iamax();
            tilt = tilt.max(n1[axis].abs().clamp(0.0, 1.0).acos());
            moved_normal = moved_normal.max(n0.dot(&n1).clamp(-1.0, 1.0).acos());
        }
    }
    // Sliding control points kept their held coordinate.
    for &(c, axis) in &r.sliding {
        assert_eq!(
            s.control_points()[c][axis],
            r.surface.control_points()[c][axis]
        );
    }
    // How far the old edge's corner (the joint's middle) moved.
    let (q, inward) = match kind {
        RoundingKind::Corner | RoundingKind::SharpCorner => {
            ([0.0, 0.0], vclay_core::Vec3::new(-1.0, 1.0, -1.0))
        }
        _ => ([1.5, 1.5], vclay_core::Vec3::new(1.0, 0.0, 1.0)),
    };
    let moved = (s.point(q).unwrap() - r.surface.point(q).unwrap()).dot(&inward.normalize());
    eprintln!(
        "{kind:?}: wrong way {:.2} %, face normal tilt {tilt:.2e} rad (moved {moved_normal:.2e}), \
         corner moved {moved:.3} inwards",
        100.0 * w
    );
    assert!(
        w < max_wrong,
        "{kind:?}: {:.2} % folds the wrong way",
        100.0 * w
    );
    assert!(
        tilt < 1e-9 && moved_normal < 1e-9,
        "{kind:?}: normals tilt {tilt} / {moved_normal}"
    );
    assert!(moved > min_moved, "{kind:?}: the corner moved {moved}");
}

#[test]
fn issue_28_corner_rounding_makes_a_convex_fillet_tangent_to_the_faces() {
    fillet_is_convex_and_tangent(RoundingKind::Corner, 60, 0.04, 0.05);
}

/// The sharp corner (`RoundingKind::SharpCorner`, the corner's exactly sharp start): measured
/// 6.5 % of its turning the wrong way (the paper's domain, whose held boundary also fixes the
/// `C^1` rounding of the edges' outer ends, 3.1 %) and the corner point 0.81 into the solid.
#[test]
fn issue_28_sharp_corner_rounding_makes_a_convex_fillet_tangent_to_the_faces() {
    fillet_is_convex_and_tangent(RoundingKind::SharpCorner, 60, 0.075, 0.2);
}

#[test]
fn issue_28_bevel_rounding_makes_a_convex_fillet_tangent_to_the_faces() {
    fillet_is_convex_and_tangent(RoundingKind::Bevel, 60, 0.025, 0.1);
}

/// [`mesh_turning`] on known surfaces: a quarter cylinder turns one way only, an S-shaped
/// sheet (two opposite quarter cylinders) half each way, a plane not at all.
#[test]
fn mesh_turning_measures_convexity() {
    use vclay_dynamics::dnurbs::rounding::mesh_turning;
    let sheet = |profile: &dyn Fn(f64) -> (f64, f64)| {
        let (nu, nv) = (32, 4);
        let mut m = vclay_core::TriMesh::new();
        for i in 0..=nu {
            let (x, z) = profile(i as f64 / nu as f64);
            for j in 0..=nv {
                m.positions
                    .push(vclay_core::Vec3::new(x, j as f64 / nv as f64, z));
            }
        }
        let id = |i: usize, j: usize| (i * (nv + 1) + j) as u32;
        for i in 0..nu {
            for j in 0..nv {
                m.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        mesh_turning(&m)
    };
    let h = std::f64::consts::FRAC_PI_2;
    let quarter = sheet(&|s| ((s * h).sin(), (s * h).cos()));
    assert_eq!(quarter.wrong_way(), 0.0);
    // 31 interior creases of pi/64 each, 1 long (the quads are planar: their diagonals turn 0).
    assert!(
        (quarter.positive - 31.0 * h / 32.0).abs() < 1e-12,
        "{quarter:?}"
    );
    let s_shape = sheet(&|s| {
        if s < 0.5 {
            ((2.0 * s * h).sin(), (2.0 * s * h).cos())
        } else {
            (
                2.0 - (2.0 * (1.0 - s) * h).sin(),
                -(2.0 * (1.0 - s) * h).cos(),
            )
        }
    });
    assert!((s_shape.wrong_way() - 0.5).abs() < 1e-6, "{s_shape:?}");
    assert_eq!(sheet(&|s| (s, 0.0)).wrong_way(), 0.0);
}

/// Issue 28, what the sliding boundaries do: the bevel with its sides held whole (the sliding
/// control points' four coordinates fixed, as before the fix) and the same densities folds
/// 35 % of its turning the wrong way against 1.7 % (it tapers back to the sharp joint at both
/// ends; 13 % from the `C^1` start). The corner's 9 sliding points change nothing measurable (3.05 % held, 3.06 %
/// sliding; printed): its gain came from the unfolded map, the deeper quads and the densities
/// (Table 1 as printed on the same model: 15.6 %).
#[test]
fn issue_28_held_crossing_boundaries_fold_the_fillet() {
    use vclay_dynamics::dnurbs::rounding::mesh_turning;
    for kind in [RoundingKind::Corner, RoundingKind::Bevel] {
        let r = RoundingModel::new(kind).unwrap();
        let share = |hold_all: bool| {
            let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
            if hold_all {
                for &(c, _) in &r.sliding {
                    for k in 0..4 {
                        m.set_fixed_coordinate(4 * c + k, true).unwrap();
                    }
                }
            }
            m.run(r.dt(), 60).unwrap();
            let mut mesh = vclay_core::TriMesh::new();
            m.geometry().surface().tessellate(8, &mut mesh).unwrap();
            mesh_turning(&mesh).wrong_way()
        };
        let (sliding, held) = (share(false), share(true));
        eprintln!(
            "{kind:?}: wrong way {:.2} % sliding, {:.2} % held whole",
            100.0 * sliding,
            100.0 * held
        );
        if kind == RoundingKind::Bevel {
            assert!(
                held > 2.0 * sliding,
                "{kind:?}: {held} held against {sliding}"
            );
        }
    }
}

/// Issue 28, Fig 8a1 and 8c1 (`d-nurbs.txt` section 7.3: "the sharp edge can be represented
/// exactly with multiple control points"): the edge and the bevel start sharp, every vertex of
/// their tessellation on one of the two face planes and the old edge's middle on the edge line
/// (the `C^1` start is off both planes by more than 0.05 there, so the check can fail), and
/// relax in the scenarios' step counts into the same fillet as the `C^1` start (the energy's
/// minimum under the held boundaries does not depend on where the run starts): surfaces
/// within 1e-6 of the model size.
#[test]
fn issue_28_edge_and_bevel_start_sharp_and_relax_into_the_same_fillet() {
    for (kind, steps, edge_x, probe) in [
        (RoundingKind::Edge, 100, 1.5f64, [1.5, 0.5]),
        (RoundingKind::Bevel, 60, -1.5, [1.5, 1.5]),
    ] {
        let sharp = RoundingModel::new(kind).unwrap();
        let rounded = RoundingModel::with_initial(kind, InitialShape::Rounded).unwrap();
        // Largest distance of a tessellation vertex from the nearer face plane (z = 0 or
        // x = edge_x; the faces lie on one side of the edge each).
        let off_faces = |s: &vclay_spline::TriangularNurbs| {
            let mut mesh = vclay_core::TriMesh::new();
            s.tessellate(8, &mut mesh).unwrap();
            // The faces: z = 0 on the edge's side of x = edge_x, x = edge_x on the side
            // z <= 0 (edge) or z >= 0 (bevel); beyond them a vertex counts by its distance.
            let inside = |x: f64| (x * edge_x.signum()).max(0.0);
            mesh.positions
                .iter()
                .map(|p| {
                    let a = p.z.abs().hypot(inside(p.x - edge_x));
                    let b = (p.x - edge_x).abs().hypot((p.z * edge_x.signum()).max(0.0));
                    a.min(b)
                })
                .fold(0.0f64, f64::max)
        };
        let (a, b) = (off_faces(&sharp.surface), off_faces(&rounded.surface));
        let size = 3.0;
        assert!(
            a < 1e-12 * size,
            "{kind:?}: the sharp start leaves the faces by {a}"
        );
        assert!(b > 0.05, "{kind:?}: the C^1 start leaves them by {b}");
        let mid = sharp.surface.point(probe).unwrap();
        assert!(
            (mid.x - edge_x).abs() < 1e-12 && mid.z.abs() < 1e-12,
            "{kind:?}: the old edge's middle is at {mid:?}"
        );
        let relaxed = |r: &RoundingModel| {
            let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
            m.run(r.dt(), steps).unwrap();
            let mut mesh = vclay_core::TriMesh::new();
            m.geometry().surface().tessellate(8, &mut mesh).unwrap();
            mesh.positions
        };
        let (pa, pb) = (relaxed(&sharp), relaxed(&rounded));
        let apart = pa
            .iter()
            .zip(&pb)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0f64, f64::max);
        eprintln!(
            "{kind:?}: sharp start off the faces {a:.1e} (C^1 start {b:.3}); after {steps} steps the two fillets {apart:.1e} apart"
        );
        assert!(
            apart < 1e-6 * size,
            "{kind:?}: the fillets differ by {apart}"
        );
    }
}

/// Largest distance of a tessellation vertex (level 8) from the three faces of the corner of
/// the solid `x <= 0, y >= 0, z <= 0` (each face a quadrant of a coordinate plane; the
/// distance to a face counts the off-plane coordinate and any coordinate outside the face).
fn corner_off_faces(s: &vclay_spline::TriangularNurbs) -> f64 {
    let mut mesh = vclay_core::TriMesh::new();
    s.tessellate(8, &mut mesh).unwrap();
    let outside = |p: &vclay_core::Vec3, j: usize| match j {
        1 => (-p[1]).max(0.0),
        _ => p[j].max(0.0),
    };
    mesh.positions
        .iter()
        .map(|p| {
            (0..3)
                .map(|i| {
                    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                    (p[i].powi(2) + outside(p, j).powi(2) + outside(p, k).powi(2)).sqrt()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0f64, f64::max)
}

/// Issue 28, Fig 8b1 (`d-nurbs.txt` section 7.3): the trihedral corner starts exactly sharp on
/// the domain of `RoundingKind::SharpCorner` (every vertex of its tessellation on one of the
/// three faces, measured 0; the `C^1` start of the same domain is 0.20 off them, so the check
/// can fail) and relaxes in the scenario's 60 steps into the fillet of the `C^1` start (both
/// hold the same far-boundary control points; measured 7.8e-15 apart, 6.5 % of the turning
/// the wrong way for both). `issue_28_sharp_corner_rounding_makes_a_convex_fillet_tangent_to_the_faces`
/// checks the fillet. With `VCLAY_ROUNDING_OBJ` set, writes both starts and both fillets as OBJ.
#[test]
fn issue_28_sharp_corner_starts_sharp_and_relaxes_into_the_same_fillet() {
    let sharp = RoundingModel::new(RoundingKind::SharpCorner).unwrap();
    let rounded =
        RoundingModel::with_initial(RoundingKind::SharpCorner, InitialShape::Rounded).unwrap();
    let n = sharp.surface.control_points().len();
    let (a, b) = (
        corner_off_faces(&sharp.surface),
        corner_off_faces(&rounded.surface),
    );
    let relaxed = |r: &RoundingModel| {
        let mut m = r.dynamics(TriangleQuadrature::default()).unwrap();
        m.run(r.dt(), 60).unwrap();
        let mut mesh = vclay_core::TriMesh::new();
        m.geometry().surface().tessellate(8, &mut mesh).unwrap();
        mesh
    };
    let (ma, mb) = (relaxed(&sharp), relaxed(&rounded));
    let apart = ma
        .positions
        .iter()
        .zip(&mb.positions)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0f64, f64::max);
    let (wa, wb) = (
        vclay_dynamics::dnurbs::rounding::mesh_turning(&ma).wrong_way(),
        vclay_dynamics::dnurbs::rounding::mesh_turning(&mb).wrong_way(),
    );
    eprintln!(
        "sharp corner: {n} control points, {} fixed, {} sliding; sharp start off the faces {a:.1e} (C^1 start {b:.3}); after 60 steps the fillets {apart:.1e} apart, wrong way {:.2} % (C^1 start {:.2} %)",
        sharp.fixed_controls.len(),
        sharp.sliding.len(),
        100.0 * wa,
        100.0 * wb
    );
    if let Ok(dir) = std::env::var("VCLAY_ROUNDING_OBJ") {
        let initial = |s: &vclay_spline::TriangularNurbs| {
            let mut mesh = vclay_core::TriMesh::new();
            s.tessellate(4, &mut mesh).unwrap();
            mesh
        };
        let (ia, ib) = (initial(&sharp.surface), initial(&rounded.surface));
        for (tag, mesh) in [
            ("sharp_initial", &ia),
            ("rounded_initial", &ib),
            ("sharp_final", &ma),
            ("rounded_final", &mb),
        ] {
            let mut obj = String::new();
            for p in &mesh.positions {
                obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
            }
            for t in &mesh.triangles {
                obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
            }
            std::fs::write(format!("{dir}/SharpCorner_{tag}.obj"), obj).unwrap();
        }
    }
    assert!(a < 1e-12 * 3.0, "the sharp start leaves the faces by {a}");
    assert!(b > 0.05, "the C^1 start leaves them by {b}");
    assert!(apart < 1e-6 * 3.0, "the fillets differ by {apart}");
}
