//! STEP and IGES import (issue 20, "Read CAD files"): files written by OpenCASCADE
//! (`bench/gen_cad_test_files.py`) evaluated against OpenCASCADE's own evaluation, hand-written
//! files against closed forms, located errors, and vclay's own export read back exactly.

use std::f64::consts::FRAC_1_SQRT_2;
use std::path::Path;
use vclay_core::Vec3;
use vclay_io::iges::to_iges_string;
use vclay_io::iges_read::parse_iges;
use vclay_io::model::{Entity, NamedEntity, import_model, read_model};
use vclay_io::step::to_step_string;
use vclay_io::step_read::parse_step;
use vclay_spline::{NurbsCurve, NurbsSurface, NurbsVolume, ParametricCurve, ParametricSurface};

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/cad")
        .join(name)
}

fn close(a: Vec3, b: Vec3, rel: f64) -> bool {
    (a - b).norm() <= rel * b.norm().max(1.0)
}

/// Every curve and surface OpenCASCADE read back from each file of `occ_points.json` (its
/// points at seeded random parameters) is matched by one imported entity evaluating to the
/// same points within 1e-9 relative; the counts of entities agree.
#[test]
fn opencascade_files_evaluate_as_opencascade_does() {
    let text = std::fs::read_to_string(data("occ_points.json")).unwrap();
    let all: serde_json::Value = serde_json::from_str(&text).unwrap();
    let vec3 = |v: &serde_json::Value| {
        let a: Vec<f64> = v
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        Vec3::new(a[0], a[1], a[2])
    };
    let mut checked = 0;
    for (file, recs) in all.as_object().unwrap() {
        let imported = import_model(data(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(
            imported.entities.len(),
            recs.as_array().unwrap().len(),
            "{file}"
        );
        for rec in recs.as_array().unwrap() {
            let p0 = vec3(&rec["first_pole"]);
            let found = imported.entities.iter().find(|e| {
                rec["params"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .zip(rec["points"].as_array().unwrap())
                    .all(|(t, q)| {
                        let t = t.as_array().unwrap();
                        let p = match &e.entity {
                            Entity::Curve(c) if t.len() == 1 => c.point(t[0].as_f64().unwrap()),
                            Entity::Surface(s) if t.len() == 2 => {
                                s.point(t[0].as_f64().unwrap(), t[1].as_f64().unwrap())
                            }
                            _ => return false,
                        };
                        p.is_ok_and(|p| close(p, vec3(q), 1e-9))
                    })
            });
            let e = found.unwrap_or_else(|| panic!("{file}: no entity evaluates as {rec} ({p0})"));
            for (t, q) in rec["params"]
                .as_array()
                .unwrap()
                .iter()
                .zip(rec["points"].as_array().unwrap())
            {
                let t: Vec<f64> = t
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                let p = match &e.entity {
                    Entity::Curve(c) => c.point(t[0]).unwrap(),
                    Entity::Surface(s) => s.point(t[0], t[1]).unwrap(),
                    Entity::Volume(_) => unreachable!(),
                };
                let q = vec3(q);
                assert!(close(p, q, 1e-9), "{file} at {t:?}: {p} vs OpenCASCADE {q}");
                checked += 1;
            }
        }
    }
    assert!(checked >= 40, "{checked}");
}

#[test]
fn brep_files_warn_about_what_is_dropped() {
    let s = import_model(data("cylinder_solid.step")).unwrap();
    assert!(
        s.entities
            .iter()
            .all(|e| matches!(e.entity, Entity::Surface(_)))
    );
    let w = s.warnings.join("\n");
    // Issue 30: the faces are kept with their trims as a closed shell: not warned about.
    assert!(!w.contains("untrimmed") && !w.contains("B-rep"), "{w}");
    assert_eq!(s.shells.len(), 1);
    assert!(s.shells[0].closed);
    // Faces, loops, edges and pcurves are read into the face data, not listed as dropped.
    assert!(
        !w.contains("ADVANCED_FACE") && !w.contains("EDGE_CURVE") && !w.contains("PCURVE"),
        "{w}"
    );
    // Edge curves and pcurves are kept in the loops, the product's placement is structure:
    // nothing of either is dropped, so neither is warned about (issue 29).
    assert!(
        !w.contains("not imported as separate") && !w.contains("not read"),
        "{w}"
    );
    assert_eq!(s.faces.len(), 3);
    assert!(s.faces.iter().all(|f| !f.loops.is_empty()));
    let c = import_model(data("curve.step")).unwrap();
    assert!(
        c.warnings.join(" ").contains("1 TRIMMED_CURVE"),
        "{:?}",
        c.warnings
    );
    // Issue 30: an IGES solid of trimmed surfaces (144) is read with its trims, sewn into one
    // closed shell; its trimming curves are read into the loops, so nothing is warned about.
    let i = import_model(data("cylinder_solid.igs")).unwrap();
    assert!(i.warnings.is_empty(), "{:?}", i.warnings);
    assert_eq!(i.shells.len(), 1);
    assert!(i.shells[0].closed);
    assert_eq!(i.shells[0].faces.len(), 3);
    // The dispatch of read_model by extension.
    assert_eq!(read_model(data("torus.igs")).unwrap().len(), 1);
}

const QUARTER: &str = "ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('hand-written'),'2;1');
FILE_NAME('q.step','2026-12-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));
ENDSEC;
DATA;
#1=CARTESIAN_POINT('',(1.,0.,0.));
#2=CARTESIAN_POINT('',(1.,1.,0.));
#3=CARTESIAN_POINT('',(0.,1.,0.));
#4=( BOUNDED_CURVE() B_SPLINE_CURVE(2,(#1,#2,#3),.CIRCULAR_ARC.,.F.,.F.)
 B_SPLINE_CURVE_WITH_KNOTS((3,3),(0.,1.),.PIECEWISE_BEZIER_KNOTS.) CURVE()
 GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_CURVE((1.,0.7071067811865476,1.))
 REPRESENTATION_ITEM('quarter') );
#5=CARTESIAN_POINT('',(0.,0.,0.));
#6=CARTESIAN_POINT('',(0.,2.,1.));
#7=CARTESIAN_POINT('',(3.,0.,0.));
#8=CARTESIAN_POINT('',(3.,2.,-1.));
#9=B_SPLINE_SURFACE_WITH_KNOTS('patch',1,1,((#5,#6),(#7,#8)),.UNSPECIFIED.,.F.,.F.,.F.,
 (2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);
#10=PLANE('',#11);
#11=AXIS2_PLACEMENT_3D('',#5,$,$);
ENDSEC;
END-ISO-10303-21;
";

/// Hand-written: a rational quarter circle (Piegl & Tiller eq 7.1) and a bilinear patch.
#[test]
fn hand_written_step_matches_closed_forms() {
    let r = parse_step(QUARTER).unwrap();
    assert_eq!(r.entities.len(), 3);
    assert_eq!(r.entities[0].name.as_deref(), Some("quarter"));
    let Entity::Curve(c) = &r.entities[0].entity else {
        panic!()
    };
    for k in 0..=10 {
        let u = k as f64 / 10.0;
        let w = FRAC_1_SQRT_2;
        let (a, b, d) = ((1.0 - u).powi(2), 2.0 * u * (1.0 - u), u * u);
        let den = a + w * b + d;
        let exact = Vec3::new((a + w * b) / den, (w * b + d) / den, 0.0);
        let p = c.point(u).unwrap();
        assert!((p - exact).norm() < 1e-15 && (p.norm() - 1.0).abs() < 1e-15);
    }
    let Entity::Surface(s) = &r.entities[1].entity else {
        panic!()
    };
    let corner = [
        Vec3::zeros(),
        Vec3::new(0., 2., 1.),
        Vec3::new(3., 0., 0.),
        Vec3::new(3., 2., -1.),
    ];
    for (u, v) in [(0.25, 0.5), (0.9, 0.1), (1.0, 1.0)] {
        let exact = corner[0] * (1. - u) * (1. - v)
            + corner[1] * (1. - u) * v
            + corner[2] * u * (1. - v)
            + corner[3] * u * v;
        assert!((s.point(u, v).unwrap() - exact).norm() < 1e-15);
    }
    // The free PLANE (no face bounds it) gets the default range [-1, 1]^2 of its placement
    // (defaults: z axis, x direction).
    let Entity::Surface(plane) = &r.entities[2].entity else {
        panic!()
    };
    let d = plane.domain();
    assert_eq!([d[0].min, d[0].max, d[1].min, d[1].max], [-1., 1., -1., 1.]);
    assert_eq!(plane.point(0.5, -0.25).unwrap(), Vec3::new(0.5, -0.25, 0.));
    let w = r.warnings.join("\n");
    assert!(w.contains("1 elementary or swept surface(s)"), "{w}");
}

#[test]
fn step_errors_name_the_line_and_entity() {
    let bad = QUARTER.replace("(2,2),(2,2),(0.,1.),(0.,1.)", "(2,2),(2,2),(0.,1.),(0.)");
    let e = parse_step(&bad).unwrap_err().to_string();
    assert!(e.starts_with("STEP line 19, entity #9:"), "{e}");
    assert!(
        e.contains("v knot multiplicities and knots differ in length (2 and 1)"),
        "{e}"
    );
    let bad = QUARTER.replace("((#5,#6),(#7,#8))", "((#5,#6),(#7,#42))");
    let e = parse_step(&bad).unwrap_err().to_string();
    assert!(
        e.contains("#9") && e.contains("#42, which is not defined"),
        "{e}"
    );
    let bad = QUARTER.replace(
        "#3=CARTESIAN_POINT('',(0.,1.,0.));",
        "#3=CARTESIAN_POINT('',(0.,1.,0.);",
    );
    let e = parse_step(&bad).unwrap_err().to_string();
    assert!(e.starts_with("STEP line 10, entity #3:"), "{e}");
    let e = parse_step("ISO-10303-21;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("curve or surface to import"), "{e}");
}

#[test]
fn iges_errors_name_the_line_and_entity() {
    let c = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap();
    let text = to_iges_string(&[Entity::Curve(c).into()], "c.igs").unwrap();
    // Drop the last parameter line: the data is no longer terminated.
    let lines: Vec<&str> = text.lines().collect();
    let last_p = lines.iter().rposition(|l| &l[72..73] == "P").unwrap();
    let mut cut: Vec<&str> = lines.clone();
    cut[last_p] =
        "                                                                        P      9";
    let e = parse_iges(&cut.join("\n")).unwrap_err().to_string();
    assert!(
        e.contains("entity DE 1") && e.contains("not terminated"),
        "{e}"
    );
    // A bad number is reported on its line.
    let bad = text.replacen("126,8,2,", "126,8,x,", 1);
    let e = parse_iges(&bad).unwrap_err().to_string();
    let pline = lines.iter().position(|l| &l[72..73] == "P").unwrap() + 1;
    assert!(
        e.starts_with(&format!(
            "IGES line {pline}, entity DE 1: entity 126: degree M"
        )),
        "{e}"
    );
}

fn sample_model() -> Vec<NamedEntity> {
    let torus = NurbsSurface::torus(2.0, 0.5).unwrap();
    let bumpy = NurbsSurface::new(
        [3, 2],
        [
            vec![0., 0., 0., 0., 0.4, 1., 1., 1., 1.],
            vec![-1., -1., -1., 0.1, 2., 2., 2.],
        ],
        (0..5)
            .map(|i| {
                (0..4)
                    .map(|j| Vec3::new(i as f64, j as f64 * 0.7, ((i * j) as f64).sin() / 3.0))
                    .collect()
            })
            .collect(),
        Some(
            (0..5)
                .map(|i| (0..4).map(|j| 1.0 + 0.1 * ((i + j) % 3) as f64).collect())
                .collect(),
        ),
    )
    .unwrap();
    let line = NurbsCurve::new(
        3,
        vec![0., 0., 0., 0., 0.3, 1. / 3., 1., 1., 1., 1.],
        (0..6)
            .map(|i| Vec3::new(i as f64, 0.1 * i as f64, -1e-7 * i as f64))
            .collect(),
        None,
    )
    .unwrap();
    let circle = NurbsCurve::circle(Vec3::new(1., 2., 3.), Vec3::x(), Vec3::z(), 0.1).unwrap();
    vec![
        NamedEntity {
            name: Some("torus".into()),
            entity: Entity::Surface(torus),
        },
        Entity::Surface(bumpy).into(),
        NamedEntity {
            name: Some("it's a line".into()),
            entity: Entity::Curve(line),
        },
        Entity::Curve(circle).into(),
    ]
}

/// vclay's STEP and IGES export read back gives the same entities bit for bit.
#[test]
fn own_export_reads_back_exactly() {
    let model = sample_model();
    let step = parse_step(&to_step_string(&model, "m.step").unwrap()).unwrap();
    let iges = parse_iges(&to_iges_string(&model, "m.igs").unwrap()).unwrap();
    for back in [&step, &iges] {
        assert_eq!(back.entities.len(), model.len());
        for (a, b) in model.iter().zip(&back.entities) {
            assert_eq!(a.entity, b.entity);
        }
    }
    assert_eq!(step.entities[0].name.as_deref(), Some("torus"));
    assert_eq!(step.entities[2].name.as_deref(), Some("it's a line"));
    assert_eq!(iges.entities[0].name.as_deref(), Some("torus"));
    // Volumes go out as their six boundary surfaces.
    let v = NurbsVolume::box_lattice([1, 1, 1], [2, 2, 2], Vec3::zeros(), Vec3::new(1., 2., 3.))
        .unwrap();
    let vol: Vec<NamedEntity> = vec![Entity::Volume(v.clone()).into()];
    let faces = vclay_io::step::volume_boundary_surfaces(&v).unwrap();
    for back in [
        parse_step(&to_step_string(&vol, "v.step").unwrap()).unwrap(),
        parse_iges(&to_iges_string(&vol, "v.igs").unwrap()).unwrap(),
    ] {
        let got: Vec<&Entity> = back.entities.iter().map(|e| &e.entity).collect();
        let want: Vec<Entity> = faces.iter().cloned().map(Entity::Surface).collect();
        assert_eq!(got, want.iter().collect::<Vec<_>>());
    }
}

/// Distance from `p` to the surface `s`: the nearest of a 25 x 25 grid, then Gauss-Newton on
/// the parameters (clamped to the domain).
fn distance_to(s: &NurbsSurface, p: Vec3) -> f64 {
    let [du, dv] = s.domain();
    let at =
        |i: usize, n: usize, d: vclay_core::Interval| d.min + (d.max - d.min) * i as f64 / n as f64;
    let (mut u, mut v, mut best) = (du.min, dv.min, f64::INFINITY);
    for i in 0..=24 {
        for j in 0..=24 {
            let (a, b) = (at(i, 24, du), at(j, 24, dv));
            let d = (s.point(a, b).unwrap() - p).norm();
            if d < best {
                (u, v, best) = (a, b, d);
            }
        }
    }
    for _ in 0..40 {
        let d = s.derivatives(u, v, 1).unwrap();
        let r = d[0][0] - p;
        let (su, sv) = (d[1][0], d[0][1]);
        let (a, b, c) = (su.dot(&su), su.dot(&sv), sv.dot(&sv));
        let (gu, gv) = (su.dot(&r), sv.dot(&r));
        let det = a * c - b * b;
        if det.abs() < 1e-300 {
            break;
        }
        u = (u - (c * gu - b * gv) / det).clamp(du.min, du.max);
        v = (v - (a * gv - b * gu) / det).clamp(dv.min, dv.max);
    }
    (s.point(u, v).unwrap() - p).norm()
}

/// IGES files of analytic and swept shapes written by OpenCASCADE
/// (`bench/gen_iges_analytic.py`): planes (108) bounded by trimmed surfaces' outer
/// boundaries, surfaces of revolution (120) of lines, circular arcs and B-splines, a
/// tabulated cylinder (122), transformation matrices (124, chained for the moved cylinder).
/// Every point OpenCASCADE evaluates on a face's surface lies on one imported surface (to
/// 1e-9 of the size), one surface per face, and each face's tight box is the box of an
/// imported surface (a plane's patch is the least-area rectangle around its boundary: equal to
/// the box's rectangular faces, larger than a cylinder's disks).
#[test]
fn opencascade_iges_analytic_surfaces_lie_where_opencascade_puts_them() {
    let text = std::fs::read_to_string(data("occ_iges_points.json")).unwrap();
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    let vec3 = |v: &serde_json::Value| {
        Vec3::new(
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
        )
    };
    for (name, file) in report.as_object().unwrap() {
        let imported = parse_iges(&std::fs::read_to_string(data(&format!("{name}.igs"))).unwrap())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let surfaces: Vec<&NurbsSurface> = imported
            .entities
            .iter()
            .filter_map(|e| match &e.entity {
                Entity::Surface(s) => Some(s),
                _ => None,
            })
            .collect();
        let faces = file["faces"].as_array().unwrap();
        assert_eq!(
            surfaces.len(),
            faces.len(),
            "{name}: {:?}",
            imported.warnings
        );
        assert!(
            !imported.warnings.iter().any(|w| w.contains("not applied")),
            "{name}: {:?}",
            imported.warnings
        );
        // Each surface's box, sampled (rational arcs: 1e-4 of the size at 120 samples).
        let boxes: Vec<(Vec3, Vec3)> = surfaces
            .iter()
            .map(|s| {
                let [du, dv] = s.domain();
                let (mut lo, mut hi) =
                    (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
                for i in 0..=120 {
                    for j in 0..=120 {
                        let u = du.min + (du.max - du.min) * i as f64 / 120.0;
                        let v = dv.min + (dv.max - dv.min) * j as f64 / 120.0;
                        let p = s.point(u, v).unwrap();
                        lo = lo.inf(&p);
                        hi = hi.sup(&p);
                    }
                }
                (lo, hi)
            })
            .collect();
        for (k, face) in faces.iter().enumerate() {
            let b = face["box"].as_array().unwrap();
            let (lo, hi) = (
                vec3(&serde_json::json!([b[0], b[1], b[2]])),
                vec3(&serde_json::json!([b[3], b[4], b[5]])),
            );
            let size = (hi - lo).norm();
            let points: Vec<Vec3> = face["points"]
                .as_array()
                .unwrap()
                .iter()
                .map(vec3)
                .collect();
            let plane = face["type"] == "GeomAbs_Plane";
            // OpenCASCADE samples a plane face's parameter box in its own axes, which may
            // reach past the face (and past vclay's patch, the box of the boundary in other
            // axes): plane points are checked against the patch's plane.
            let off = |s: &NurbsSurface, p: Vec3| {
                if plane {
                    let c = s.control_points();
                    let n = (c[1] - c[0]).cross(&(c[2] - c[0])).normalize();
                    n.dot(&(p - c[0])).abs()
                } else {
                    distance_to(s, p)
                }
            };
            // The surface holding this face's points.
            let (s, worst) = surfaces
                .iter()
                .enumerate()
                .map(|(i, s)| (i, points.iter().map(|&p| off(s, p)).fold(0.0, f64::max)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            assert!(
                worst <= 1e-9 * size,
                "{name} face {k} ({}): OpenCASCADE's points are {worst:.2e} off (size {size:.3})",
                face["type"]
            );
            let (slo, shi) = boxes[s];
            let tol = 1e-3 * size + 1e-6;
            let contains = (0..3).all(|d| slo[d] <= lo[d] + tol && shi[d] >= hi[d] - tol);
            let equal =
                (0..3).all(|d| (slo[d] - lo[d]).abs() <= tol && (shi[d] - hi[d]).abs() <= tol);
            // The box's faces are rectangles: the least-area rectangle of their boundary is
            // the face itself; a disk's is the square around it.
            let exact = !plane || name.contains("box");
            assert!(
                if exact { equal } else { contains },
                "{name} face {k} ({}): box {slo:?}..{shi:?} against OpenCASCADE's {lo:?}..{hi:?}",
                face["type"]
            );
        }
    }
}
