//! Properties of the dynamic core (`subdivision-solids-journal.txt` sections 4-5).

use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, Features, SubdivisionRules};
use vclay_solids::{
    DynamicSolid, Integrator, Material, SolidParams, SolidSource, SolidsError, Tool,
};

use vclay_solids::benchmarks::{bspline_box as bspline_source, subdivision_box as cube_source};

fn params(integrator: Integrator, dt: f64) -> SolidParams {
    SolidParams {
        integrator,
        dt,
        ..SolidParams::default()
    }
}

fn undamped() -> Material {
    Material {
        damping: 0.0,
        ..Material::default()
    }
}

/// Model size for tolerances.
const SIZE: f64 = 1.0;

#[test]
fn rest_shape_is_equilibrium() {
    for (source, p) in [cube_source(3, 1), bspline_source(4, 6)] {
        let mut s =
            DynamicSolid::new(source, p.clone(), undamped(), SolidParams::default()).unwrap();
        let f = s.internal_forces();
        let fmax = f.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(fmax < 1e-9, "rest force {fmax}");
        s.run(20).unwrap();
        let moved = s
            .control_points()
            .iter()
            .zip(&p)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(moved < 1e-12 * SIZE, "rest shape moved by {moved}");
    }
}

#[test]
fn rigid_motion_gives_no_internal_force() {
    for (source, p) in [cube_source(3, 1), bspline_source(4, 5)] {
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let t = Vec3::new(2.0, -1.0, 0.5);
        let q: Vec<Vec3> = p.iter().map(|x| r * x + t).collect();
        let mut s =
            DynamicSolid::new(source, p.clone(), undamped(), SolidParams::default()).unwrap();
        // Move the solid rigidly through the fix/step API: fix nothing, set positions by a
        // plastic-free route: build a second solid at rest in p and compare forces at q.
        let k = s.springs().edge_k.iter().cloned().fold(0.0, f64::max);
        let source2 = s.source().clone();
        let moved = DynamicSolid::new(source2, q, undamped(), SolidParams::default()).unwrap();
        // Forces of the rest-p springs evaluated at the rigidly moved data points.
        let d = moved.data_points().to_vec();
        let mut f = vec![Vec3::zeros(); d.len()];
        let e = s.springs().energy(&d);
        s.springs().add_forces(
            &d,
            &mut f,
            &mut Default::default(),
            vclay_core::Parallelism::Sequential,
        );
        let fmax = f.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(fmax < 1e-10 * k * SIZE, "rigid force {fmax}");
        assert!(e < 1e-18 * k * SIZE * SIZE, "rigid energy {e}");
        s.run(1).unwrap();
    }
}

fn perturbed(s: &mut DynamicSolid) {
    // Pull a corner with a rope, then release it.
    let rope = s.attach_rope(Vec3::new(1.4, 1.3, 1.2), 40.0, 0.0).unwrap();
    s.run(60).unwrap();
    s.remove_tool(rope).unwrap();
}

/// Energy band (max - min) / initial over `t` seconds of free, undamped motion after a rope
/// pull, and the same over the first and second halves.
fn energy_band(dt: f64) -> (f64, f64, f64) {
    let (source, p) = cube_source(2, 1);
    let mut s = DynamicSolid::new(
        source,
        p,
        undamped(),
        params(Integrator::SymplecticEuler, dt),
    )
    .unwrap();
    let rope = s.attach_rope(Vec3::new(1.4, 1.3, 1.2), 40.0, 0.0).unwrap();
    s.run((0.1 / dt) as usize).unwrap();
    s.remove_tool(rope).unwrap();
    let e0 = s.energy().total();
    assert!(e0 > 1e-3, "the rope put energy in: {e0}");
    let steps = (0.4 / dt) as usize;
    let mut band = [(e0, e0), (e0, e0)];
    for k in 0..steps {
        s.step().unwrap();
        let e = s.energy().total();
        let b = &mut band[2 * k / steps];
        b.0 = b.0.min(e);
        b.1 = b.1.max(e);
    }
    let all = (band[0].0.min(band[1].0), band[0].1.max(band[1].1));
    (
        (all.1 - all.0) / e0,
        (band[0].1 - band[0].0) / e0,
        (band[1].1 - band[1].0) / e0,
    )
}

#[test]
fn symplectic_energy_is_conserved_without_damping() {
    let (coarse, first, second) = energy_band(2e-3);
    let (fine, _, _) = energy_band(1e-3);
    // Bounded: no secular growth from the first half to the second.
    assert!(
        second < 1.5 * first + 1e-3,
        "drift grows: {first} -> {second}"
    );
    // First order in dt, and small.
    assert!(fine < 0.1, "energy band {fine}");
    assert!(
        fine < 0.7 * coarse,
        "band does not shrink with dt: {coarse} -> {fine}"
    );
}

#[test]
fn damping_dissipates_energy() {
    let (source, p) = cube_source(2, 1);
    let mut s = DynamicSolid::new(
        source,
        p,
        Material::default(),
        params(Integrator::SymplecticEuler, 2e-3),
    )
    .unwrap();
    perturbed(&mut s);
    let e0 = s.energy().total();
    s.run(400).unwrap();
    assert!(s.energy().total() < 0.5 * e0);
}

#[test]
fn fixed_control_points_never_move_and_skip_work() {
    let (source, p) = cube_source(4, 1);
    let mut s = DynamicSolid::new(
        source,
        p.clone(),
        Material::default(),
        SolidParams::default(),
    )
    .unwrap();
    let bottom = s.control_points_where(|x| x.z < 0.5);
    s.set_fixed(&bottom, true).unwrap();
    let st = s.stats();
    assert!(st.active_data_points < st.data_points, "{st:?}");
    assert!(st.active_springs < st.edge_springs + st.virtual_springs);
    s.add_tool(Tool::Gravity {
        g: Vec3::new(0.0, 0.0, -9.8),
    })
    .unwrap();
    s.attach_rope(Vec3::new(1.5, 0.5, 1.5), 30.0, 0.0).unwrap();
    s.run(50).unwrap();
    for &i in &bottom {
        assert_eq!(s.control_points()[i], p[i]);
    }
    let top = s.control_points_where(|x| x.z > 0.9);
    assert!(
        top.iter()
            .any(|&i| (s.control_points()[i] - p[i]).norm() > 1e-3)
    );
    // Data points of the restricted passes agree with the full product.
    let full = s.clone();
    let d_full = vclay_lattice::SubdivisionSolid::new(
        full.control_lattice().unwrap(),
        Features::none(&full.control_lattice().unwrap()),
        SubdivisionRules::new(BoundaryRule::Sharp),
        1,
    )
    .unwrap();
    let finest = d_full.finest().points();
    assert_eq!(s.data_order().len(), finest.len());
    for (&o, b) in s.data_order().iter().zip(s.data_points()) {
        assert!((finest[o as usize] - b).norm() < 1e-12);
    }
    // Freeing them lets them move again.
    s.set_fixed(&bottom, false).unwrap();
    s.run(20).unwrap();
    assert!(bottom.iter().any(|&i| s.control_points()[i] != p[i]));
}

#[test]
fn plastic_reset_makes_current_shape_force_free() {
    let (source, p) = bspline_source(4, 5);
    let mut s = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    let rope = s.attach_rope(Vec3::new(1.5, 1.5, 1.5), 40.0, 0.0).unwrap();
    s.run(100).unwrap();
    let f = s.internal_forces();
    let before = f.iter().map(|x| x.norm()).fold(0.0, f64::max);
    assert!(
        before > 1e-3,
        "deformed shape should be under stress: {before}"
    );
    s.remove_tool(rope).unwrap();
    s.plastic_reset();
    s.stop();
    let after = s
        .internal_forces()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max);
    assert!(after < 1e-9 * before, "after reset {after}");
    let shape = s.control_points().to_vec();
    s.run(50).unwrap();
    let moved = s
        .control_points()
        .iter()
        .zip(&shape)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(moved < 1e-10, "new rest shape drifted {moved}");
}

#[test]
fn explicit_and_implicit_agree_for_small_dt() {
    let run = |integrator: Integrator, dt: f64| {
        let (source, p) = cube_source(2, 1);
        let mut s = DynamicSolid::new(
            source,
            p,
            Material {
                damping: 20.0,
                ..Material::default()
            },
            params(integrator, dt),
        )
        .unwrap();
        s.add_tool(Tool::PointForce {
            point: 0,
            force: Vec3::new(-1.0, -2.0, 0.5),
        })
        .unwrap();
        let steps = (0.025 / dt).round() as usize;
        s.run(steps).unwrap();
        s.control_points().to_vec()
    };
    let diff = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max)
    };
    let e_coarse = diff(
        &run(Integrator::Explicit, 5e-4),
        &run(Integrator::ImplicitEuler, 5e-4),
    );
    let e_fine = diff(
        &run(Integrator::Explicit, 1.25e-4),
        &run(Integrator::ImplicitEuler, 1.25e-4),
    );
    let sym = run(Integrator::SymplecticEuler, 1.25e-4);
    let moved = diff(&sym, &run(Integrator::SymplecticEuler, 1.0));
    assert!(moved > 1e-3, "the force moved the solid: {moved}");
    assert!(
        e_fine < 0.05 * moved,
        "explicit vs implicit differ by {e_fine}"
    );
    assert!(
        e_fine < 0.5 * e_coarse,
        "first-order convergence: {e_coarse} -> {e_fine}"
    );
}

#[test]
fn divergence_names_step_and_suggests_dt() {
    let (source, p) = cube_source(2, 1);
    let mut s = DynamicSolid::new(
        source,
        p,
        undamped(),
        params(Integrator::SymplecticEuler, 0.5),
    )
    .unwrap();
    s.attach_rope(Vec3::new(3.0, 3.0, 3.0), 1e3, 0.0).unwrap();
    let err = s.run(1000).unwrap_err();
    match &err {
        SolidsError::Diverged {
            step, suggested_dt, ..
        } => {
            assert!(*step > 0 && *step < 1000);
            assert!(*suggested_dt < 0.5 && *suggested_dt > 0.0);
            // The suggestion is stable.
            let (source, p) = cube_source(2, 1);
            let mut t = DynamicSolid::new(
                source,
                p,
                undamped(),
                params(Integrator::SymplecticEuler, *suggested_dt),
            )
            .unwrap();
            t.attach_rope(Vec3::new(3.0, 3.0, 3.0), 1e3, 0.0).unwrap();
            t.run(300).unwrap();
        }
        e => panic!("unexpected {e}"),
    }
    let msg = err.to_string();
    assert!(msg.contains("step") && msg.contains("try dt"), "{msg}");
    assert!(
        s.control_points()
            .iter()
            .all(|x| x.iter().all(|c| c.is_finite()))
    );
}

#[test]
fn extrude_and_delete_mid_run_continue_from_current_shape() {
    let (source, p) = cube_source(3, 1);
    let mut s = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    let rope = s.attach_rope(Vec3::new(1.3, 0.5, 0.5), 30.0, 0.0).unwrap();
    s.run(30).unwrap();
    let before = s.control_points().to_vec();
    let cells = s.control_lattice().unwrap().num_cells();
    let face = s.boundary_face_near(&Vec3::new(0.5, 0.5, 1.0)).unwrap();
    s.extrude(face, 1.0).unwrap();
    assert_eq!(s.control_lattice().unwrap().num_cells(), cells + 1);
    // Old control points keep their ids and current positions.
    for (a, b) in before.iter().zip(s.control_points()) {
        assert_eq!(a, b);
    }
    assert!(s.tool(rope).is_some());
    s.run(30).unwrap();
    let c = s.cell_near(&Vec3::new(0.2, 0.2, 0.2)).unwrap();
    s.delete_cell(c).unwrap();
    assert_eq!(s.control_lattice().unwrap().num_cells(), cells);
    s.run(30).unwrap();
    assert!(s.energy().total().is_finite());
}

#[test]
fn runtime_material_change_and_bad_inputs() {
    let (source, p) = cube_source(3, 1);
    let mut s = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    let m0 = s.masses().iter().sum::<f64>();
    // Total mass = density x volume (unit cube).
    assert!((m0 - 1.0).abs() < 1e-9 * 1.0, "total mass {m0}");
    s.update_material(Some(&[0]), |m| m.density = 3.0).unwrap();
    let m1 = s.masses().iter().sum::<f64>();
    assert!((m1 - (1.0 + 2.0 / 8.0)).abs() < 1e-9, "{m1}");
    let err = s
        .update_material(None, |m| m.edge_stiffness = -1.0)
        .unwrap_err();
    assert!(err.to_string().contains("edge_stiffness"), "{err}");
    assert!(s.set_fixed(&[1000], true).is_err());
    assert!(
        s.add_tool(Tool::PointForce {
            point: 1 << 30,
            force: Vec3::zeros()
        })
        .is_err()
    );
}

#[test]
fn spring_forces_are_minus_energy_gradient() {
    // Perturbed configuration; compare forces with central differences of the energy.
    let (source, p) = cube_source(2, 1);
    let s = DynamicSolid::new(source, p, undamped(), SolidParams::default()).unwrap();
    let mut d = s.data_points().to_vec();
    for (i, x) in d.iter_mut().enumerate() {
        let t = i as f64;
        *x += Vec3::new((1.3 * t).sin(), (2.1 * t).cos(), (0.7 * t).sin()) * 0.05;
    }
    let sp = s.springs();
    let mut f = vec![Vec3::zeros(); d.len()];
    sp.add_forces(
        &d,
        &mut f,
        &mut Default::default(),
        vclay_core::Parallelism::Sequential,
    );
    let h = 1e-6;
    let fmax = f.iter().map(|x| x.norm()).fold(0.0, f64::max);
    for i in (0..d.len()).step_by(3) {
        for c in 0..3 {
            let mut dp = d.clone();
            dp[i][c] += h;
            let mut dm = d.clone();
            dm[i][c] -= h;
            let g = (sp.energy(&dp) - sp.energy(&dm)) / (2.0 * h);
            assert!(
                (f[i][c] + g).abs() < 1e-6 * fmax,
                "point {i} axis {c}: force {} vs -dE {}",
                f[i][c],
                -g
            );
        }
    }
}

#[test]
fn metric_tensor_energy_rest_rigid_gradient_and_motion() {
    let (source, p) = bspline_source(4, 5);
    let mut s = DynamicSolid::new(source, p.clone(), undamped(), SolidParams::default()).unwrap();
    s.use_metric_energy(Some(50.0)).unwrap();
    assert!(s.uses_metric_energy());
    // Rest: no energy, no motion.
    assert!(s.energy().internal < 1e-20);
    s.run(5).unwrap();
    assert!(
        s.control_points()
            .iter()
            .zip(&p)
            .all(|(a, b)| (a - b).norm() < 1e-12)
    );
    // Rigid motion keeps G: a rotated copy has no metric energy against the rest shape.
    let r = nalgebra::Rotation3::from_euler_angles(0.4, 0.2, -0.9);
    let q: Vec<Vec3> = p.iter().map(|x| r * x + Vec3::new(1.0, 2.0, 3.0)).collect();
    let m = vclay_solids::metric::MetricEnergy::new(
        match s.source() {
            SolidSource::BSpline { knots, .. } => knots,
            _ => unreachable!(),
        },
        &p,
        50.0,
    );
    let mut g = vec![Vec3::zeros(); p.len()];
    assert!(m.add_forces(&q, &mut g) < 1e-18);
    assert!(g.iter().all(|x| x.norm() < 1e-9));
    // Forces are minus the energy gradient (central differences).
    let x: Vec<Vec3> = p
        .iter()
        .enumerate()
        .map(|(i, v)| v + Vec3::new((i as f64).sin(), (2.0 * i as f64).cos(), 0.3) * 0.05)
        .collect();
    let mut f = vec![Vec3::zeros(); p.len()];
    m.add_forces(&x, &mut f);
    let fmax = f.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let h = 1e-6;
    for i in (0..p.len()).step_by(7) {
        for c in 0..3 {
            let mut xp = x.clone();
            xp[i][c] += h;
            let mut xm = x.clone();
            xm[i][c] -= h;
            let e = |y: &[Vec3]| m.add_forces(y, &mut vec![Vec3::zeros(); p.len()]);
            let grad = (e(&xp) - e(&xm)) / (2.0 * h);
            assert!((f[i][c] + grad).abs() < 1e-6 * fmax, "{i} {c}");
        }
    }
    // A rope deforms it and the implicit integrator runs with the metric stiffness.
    s.set_params(params(Integrator::ImplicitEuler, 5e-3))
        .unwrap();
    s.attach_rope(Vec3::new(1.4, 1.4, 1.4), 40.0, 0.0).unwrap();
    s.run(6).unwrap();
    assert!(s.energy().internal > 0.0);
    // Subdivision solids refuse it.
    let (source, p) = cube_source(2, 1);
    let mut t = DynamicSolid::new(source, p, undamped(), SolidParams::default()).unwrap();
    assert!(t.use_metric_energy(Some(1.0)).is_err());
}

/// Spring forces by the textbook formula, one spring at a time (journal section 5.1).
fn reference_forces(sp: &vclay_solids::springs::SpringSet, d: &[Vec3]) -> Vec<Vec3> {
    let mut f = vec![Vec3::zeros(); d.len()];
    let force = |x: Vec3, k: f64, l0: f64| x * (k * (x.norm() - l0) / x.norm());
    for (i, &[a, b]) in sp.edges.iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        let g = force(d[b] - d[a], sp.edge_k[i], sp.edge_rest[i]);
        f[b] -= g;
        f[a] += g;
    }
    for w in sp.face_offsets.windows(2) {
        let vs = &sp.face_verts[w[0] as usize..w[1] as usize];
        let n = vs.len();
        for j in 0..n {
            let (m, a, b) = (
                vs[j] as usize,
                vs[(j + n - 1) % n] as usize,
                vs[(j + 1) % n] as usize,
            );
            let c = w[0] as usize + j;
            let g = force(
                d[m] - (d[a] + d[b]) * 0.5,
                sp.corner_k[c],
                sp.corner_rest[c],
            );
            f[m] -= g;
            f[a] += g * 0.5;
            f[b] += g * 0.5;
        }
    }
    f
}

#[test]
fn batched_and_parallel_spring_forces_match_the_reference() {
    // Level 2 (28,548 springs): batches, remainders and the organized thread blocks; the
    // solid's springs come organized, `filter` gives an unorganized copy.
    let (source, p) = cube_source(4, 2);
    let s = DynamicSolid::new(source, p, undamped(), SolidParams::default()).unwrap();
    let mut d = s.data_points().to_vec();
    for (i, x) in d.iter_mut().enumerate() {
        let t = i as f64;
        *x += Vec3::new((1.3 * t).sin(), (2.1 * t).cos(), (0.7 * t).sin()) * 0.01;
    }
    let organized = s.springs().clone();
    assert!(organized.straddling() < organized.len() / 2);
    let plain = organized.filter(&vec![true; d.len()]);
    assert_eq!(plain.straddling(), plain.len());
    // A set with a triangle and a pentagon besides quads (the corner-by-corner path).
    let mut mixed = vclay_solids::springs::SpringSet::default();
    mixed.face_offsets = vec![0, 3, 8];
    mixed.face_verts = vec![0, 5, 9, 1, 2, 3, 4, 7];
    mixed.corner_rest = vec![0.1; 8];
    mixed.corner_k = vec![2.0; 8];
    let want = reference_forces(&organized, &d);
    let scale = want.iter().map(|x| x.norm()).fold(0.0, f64::max);
    assert!(scale > 0.0);
    for (set, name) in [
        (&organized, "organized"),
        (&plain, "unorganized"),
        (&mixed, "mixed"),
    ] {
        let want = reference_forces(set, &d);
        for par in [
            vclay_core::Parallelism::Sequential,
            vclay_core::Parallelism::Rayon,
        ] {
            let mut f = vec![Vec3::zeros(); d.len()];
            let e = set.add_forces(&d, &mut f, &mut Default::default(), par);
            assert!(
                (e - set.energy(&d)).abs() <= 1e-12 * e.abs().max(1e-300),
                "{name}"
            );
            for (i, (a, b)) in f.iter().zip(&want).enumerate() {
                assert!(
                    (a - b).norm() <= 1e-12 * scale,
                    "{name} {par:?}: point {i}: {a:?} vs {b:?}"
                );
            }
        }
    }
}

#[test]
fn data_points_are_renumbered_for_locality_consistently() {
    // The data lattice, the data points and the map agree under the locality renumbering, and
    // the renumbered lattice passes every invariant check.
    let (source, p) = cube_source(3, 2);
    let mut s = DynamicSolid::new(
        source,
        p.clone(),
        Material::default(),
        SolidParams::default(),
    )
    .unwrap();
    let order = s.data_order().to_vec();
    let mut seen = vec![false; order.len()];
    for &o in &order {
        assert!(!std::mem::replace(&mut seen[o as usize], true));
    }
    assert_ne!(order, (0..order.len() as u32).collect::<Vec<_>>());
    let lattice = s.data_lattice().clone();
    lattice.validate().unwrap();
    let reference = vclay_lattice::SubdivisionSolid::new(
        s.control_lattice().unwrap(),
        Features::none(&s.control_lattice().unwrap()),
        SubdivisionRules::new(BoundaryRule::Sharp),
        2,
    )
    .unwrap();
    let fine = reference.finest();
    assert_eq!(lattice.counts(), fine.counts());
    for (i, &o) in order.iter().enumerate() {
        assert!((lattice.points()[i] - fine.points()[o as usize]).norm() < 1e-12);
        assert!((s.data_points()[i] - fine.points()[o as usize]).norm() < 1e-12);
    }
    // Faces keep their ids and loops (in the new numbering).
    for f in 0..fine.num_faces() {
        let id = vclay_lattice::FaceId::new(f);
        let a: Vec<u32> = lattice
            .face_vertices(id)
            .iter()
            .map(|v| order[v.index()])
            .collect();
        let b: Vec<u32> = fine.face_vertices(id).iter().map(|v| v.0).collect();
        assert_eq!(a, b, "face {f}");
    }
}

/// Plastic flow (`vclay_core::plasticity`): a full fraction with no yield is the plastic
/// reset; a yield larger than every displacement changes nothing; a partial flow keeps the
/// shape under stress and puts the springs' rest lengths between the two; the rest shape goes
/// back exactly (undo).
#[test]
fn plastic_flow_is_the_reset_in_its_limit_and_goes_back_exactly() {
    let pulled = || {
        let (source, p) = bspline_source(4, 5);
        let mut s =
            DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
        let rope = s.attach_rope(Vec3::new(1.5, 1.5, 1.5), 40.0, 0.0).unwrap();
        s.run(100).unwrap();
        s.remove_tool(rope).unwrap();
        s.stop();
        s
    };
    let max_force = |s: &DynamicSolid| {
        s.internal_forces()
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max)
    };
    let mut full = pulled();
    let before = max_force(&full);
    let (rest0, data0) = {
        let (c, d) = full.rest_shape();
        (c.to_vec(), d.to_vec())
    };
    let moved_most = full
        .control_points()
        .iter()
        .zip(&rest0)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(full.plastic_flow(1.0, 0.0).unwrap() > 0);
    assert!(max_force(&full) < 1e-9 * before, "{}", max_force(&full));

    let mut stiff = pulled();
    assert_eq!(stiff.plastic_flow(1.0, 1.01 * moved_most).unwrap(), 0);
    assert_eq!(max_force(&stiff), before);

    let mut half = pulled();
    let n = half.plastic_flow(0.5, 0.0).unwrap();
    assert!(n > 0);
    let mid = max_force(&half);
    assert!(
        mid > 1e-3 * before && mid < 0.9 * before,
        "{mid} vs {before}"
    );
    half.set_rest_shape(&rest0, &data0).unwrap();
    assert_eq!(max_force(&half), before, "rest shape put back exactly");
    assert!(half.plastic_flow(1.5, 0.0).is_err());
    assert!(half.plastic_flow(0.5, -1.0).is_err());
    assert!(half.set_rest_shape(&rest0[1..], &data0).is_err());
}

/// `set_rest_control_points` (the smooth brush's rest shape): the current control points as the
/// rest shape leave no internal force (as the plastic reset); a wrong count is refused.
#[test]
fn the_rest_control_points_can_be_set() {
    let (source, p) = bspline_source(4, 5);
    let mut s = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    let rope = s.attach_rope(Vec3::new(1.5, 1.5, 1.5), 40.0, 0.0).unwrap();
    s.run(50).unwrap();
    s.remove_tool(rope).unwrap();
    s.stop();
    let now = s.control_points().to_vec();
    s.set_rest_control_points(&now).unwrap();
    let f = s
        .internal_forces()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max);
    assert!(f < 1e-9, "{f}");
    assert_eq!(s.rest_shape().0, now.as_slice());
    assert!(s.set_rest_control_points(&now[1..]).is_err());
    let mut bad = now.clone();
    bad[0].x = f64::NAN;
    assert!(s.set_rest_control_points(&bad).is_err());
}
