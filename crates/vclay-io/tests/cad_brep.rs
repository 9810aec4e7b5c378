//! STEP B-rep import (issue 20): elementary and swept surfaces converted exactly to NURBS, and
//! the faces' trimming loops, checked against OpenCASCADE's own evaluation of the files it wrote
//! (`bench/gen_cad_test_files.py` -> `tests/data/cad/brep_*.step`, `occ_brep_points.json`).

use std::f64::consts::TAU;
use std::path::Path;
use vclay_core::Vec3;
use vclay_io::model::{Entity, import_model};
use vclay_io::step_read::{CadImport, ParamAxis, TrimEdge, TrimmedFace, parse_step};
use vclay_spline::{NurbsSurface, ParametricCurve, ParametricSurface};

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/cad")
        .join(name)
}

/// Relative tolerance of the comparisons (relative to the model size, at least 1).
const TOL: f64 = 1e-9;

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).norm() <= TOL * b.norm().max(1.0)
}

fn nums(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn vec3(v: &serde_json::Value) -> Vec3 {
    let a = nums(v);
    Vec3::new(a[0], a[1], a[2])
}

fn surface(imp: &CadImport, f: &TrimmedFace) -> NurbsSurface {
    match &imp.entities[f.entity].entity {
        Entity::Surface(s) => s.clone(),
        e => panic!("face on {e:?}"),
    }
}

/// An angle parameter of OpenCASCADE moved by whole turns into the axis' range.
fn in_range(axis: &ParamAxis, t: f64) -> f64 {
    match *axis {
        ParamAxis::Angle { start, end, .. } => {
            let w = start + (t - start).rem_euclid(TAU);
            if w > end + 1e-9 && (w - TAU - start).abs() < 1e-9 {
                start
            } else {
                w
            }
        }
        ParamAxis::Linear => t,
    }
}

fn edge_point(e: &TrimEdge, t: f64) -> Option<Vec3> {
    let t = e.axis.to_nurbs(in_range(&e.axis, t));
    let d = e.curve.domain();
    if t < e.range[0] - 1e-9 || t > e.range[1] + 1e-9 {
        return None;
    }
    e.curve.point(t.clamp(d.min, d.max)).ok()
}

/// Every face OpenCASCADE reads back from each B-rep file is matched by one imported face whose
/// NURBS surface, at the NURBS parameters of OpenCASCADE's (STEP) parameters, gives OpenCASCADE's
/// points to 1e-9 relative; every boundary edge by a trimming edge whose 3D curve does the same
/// at the edge parameters, and whose pcurve mapped through the surface lands on the same points.
#[test]
fn elementary_surfaces_and_trims_evaluate_as_opencascade_does() {
    let text = std::fs::read_to_string(data("occ_brep_points.json")).unwrap();
    let all: serde_json::Value = serde_json::from_str(&text).unwrap();
    let (mut surf_pts, mut edge_pts, mut pcurve_pts) = (0, 0, 0);
    let mut kinds = std::collections::BTreeSet::new();
    for (file, faces) in all.as_object().unwrap() {
        let imp = import_model(data(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let faces = faces.as_array().unwrap();
        assert_eq!(imp.faces.len(), faces.len(), "{file}");
        for rec in faces {
            let params: Vec<Vec<f64>> =
                rec["params"].as_array().unwrap().iter().map(nums).collect();
            let points: Vec<Vec3> = rec["points"].as_array().unwrap().iter().map(vec3).collect();
            let on = |f: &TrimmedFace| {
                let s = surface(&imp, f);
                params.iter().zip(&points).all(|(t, q)| {
                    let [u, v] = f.to_nurbs_params(t[0], t[1]);
                    s.point(u, v).is_ok_and(|p| close(p, *q))
                })
            };
            let face = imp
                .faces
                .iter()
                .find(|f| on(f))
                .unwrap_or_else(|| panic!("{file}: no face evaluates as {}", rec["surface"]));
            kinds.insert(face.surface_type.clone());
            surf_pts += params.len();
            let s = surface(&imp, face);
            let edges: Vec<&TrimEdge> = face.loops.iter().flat_map(|l| &l.edges).collect();
            if edges.is_empty() {
                // A sphere's VERTEX_LOOP: OpenCASCADE makes a seam edge on reading; no curve in
                // the file.
                assert_eq!(face.surface_type, "SPHERICAL_SURFACE");
                continue;
            }
            for er in rec["edges"].as_array().unwrap() {
                let ts = nums(&er["params"]);
                let pts: Vec<Vec3> = er["points"].as_array().unwrap().iter().map(vec3).collect();
                let uv: Vec<Vec<f64>> = er["uv"].as_array().unwrap().iter().map(nums).collect();
                let e = edges
                    .iter()
                    .find(|e| {
                        ts.iter()
                            .zip(&pts)
                            .all(|(&t, q)| edge_point(e, t).is_some_and(|p| close(p, *q)))
                    })
                    .unwrap_or_else(|| panic!("{file}: no trimming edge matches {er}"));
                edge_pts += ts.len();
                // The pcurve: its ends go through the surface onto the edge's ends;
                // OpenCASCADE's pcurve parameters (u, v) land on its 3D points; a straight
                // pcurve passes through them (up to whole turns of u).
                let pc = e.pcurve.as_ref().expect("OpenCASCADE writes pcurves");
                let (a, b) = (
                    e.curve.point(e.range[0]).unwrap(),
                    e.curve.point(e.range[1]).unwrap(),
                );
                let ends = [e.pcurve_range[0], e.pcurve_range[1]].map(|t| {
                    let x = pc.point(t).unwrap();
                    let [u, v] = face.to_nurbs_params(x.x, x.y);
                    s.point(u, v).unwrap()
                });
                assert!(
                    close(ends[0], a) && close(ends[1], b),
                    "{file}: pcurve ends {ends:?} vs {a} {b}"
                );
                for (q, w) in pts.iter().zip(&uv) {
                    let [u, v] = face.to_nurbs_params(w[0], w[1]);
                    assert!(close(s.point(u, v).unwrap(), *q), "{file}: uv {w:?}");
                    if pc.degree() == 1 && pc.control_points().len() == 2 {
                        let (p0, p1) = (pc.control_points()[0], pc.control_points()[1]);
                        let d = (p1 - p0).normalize();
                        // Whole turns along u, and along v where v is an angle (torus).
                        let kv = if matches!(face.axes[1], ParamAxis::Angle { periodic: true, .. })
                        {
                            2
                        } else {
                            0
                        };
                        let off = (0..25)
                            .filter(|k| (k / 5) - 2 <= kv && 2 - (k / 5) <= kv)
                            .map(|k| {
                                let (ku, kv) = ((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0);
                                let x = Vec3::new(w[0] + TAU * ku, w[1] + TAU * kv, 0.0) - p0;
                                (x - d * x.dot(&d)).norm()
                            });
                        assert!(
                            off.fold(f64::INFINITY, f64::min) < TOL,
                            "{file}: uv {w:?} off the pcurve"
                        );
                    }
                    pcurve_pts += 1;
                }
            }
        }
    }
    for k in [
        "PLANE",
        "CYLINDRICAL_SURFACE",
        "CONICAL_SURFACE",
        "SPHERICAL_SURFACE",
        "TOROIDAL_SURFACE",
        "SURFACE_OF_REVOLUTION",
        "SURFACE_OF_LINEAR_EXTRUSION",
    ] {
        assert!(kinds.contains(k), "{k} not checked: {kinds:?}");
    }
    assert!(
        surf_pts >= 90 && edge_pts >= 150 && pcurve_pts >= 150,
        "{surf_pts} {edge_pts} {pcurve_pts}"
    );
}

/// Unbounded surfaces are cut to the box of their faces' boundaries: the box's planes are
/// exactly its faces, the cylinder's height is its own.
#[test]
fn unbounded_surfaces_take_their_faces_ranges() {
    let imp = import_model(data("brep_box.step")).unwrap();
    assert_eq!(imp.entities.len(), 6);
    let (lo, hi) = (Vec3::new(-1.0, -0.5, 0.25), Vec3::new(1.0, 1.0, 1.0));
    for f in &imp.faces {
        let s = surface(&imp, f);
        let cps = s.control_points();
        assert_eq!(cps.len(), 4);
        // Corners of the box, all four distinct.
        for p in cps {
            for k in 0..3 {
                assert!(
                    (p[k] - lo[k]).abs() < 1e-12 || (p[k] - hi[k]).abs() < 1e-12,
                    "{p}"
                );
            }
        }
        assert_eq!(f.loops.len(), 1);
        assert_eq!(f.loops[0].edges.len(), 4);
        // The loop closes: each edge ends where the next starts (in loop direction).
        let ends = |e: &TrimEdge| {
            let a = e.curve.point(e.range[0]).unwrap();
            let b = e.curve.point(e.range[1]).unwrap();
            if e.forward { (a, b) } else { (b, a) }
        };
        let es = &f.loops[0].edges;
        for i in 0..4 {
            assert!((ends(&es[i]).1 - ends(&es[(i + 1) % 4]).0).norm() < 1e-12);
        }
    }
    let cyl = import_model(data("brep_cylinder.step")).unwrap();
    let side = cyl
        .faces
        .iter()
        .find(|f| f.surface_type == "CYLINDRICAL_SURFACE")
        .unwrap();
    let Entity::Surface(s) = &cyl.entities[side.entity].entity else {
        panic!()
    };
    let d = s.domain();
    assert!((d[1].max - d[1].min - 1.7).abs() < 1e-12, "{d:?}");
    // Issue 30: the faces are a trimmed B-rep (one closed shell), so nothing is warned about
    // trims.
    let w = cyl.warnings.join("\n");
    assert!(!w.contains("untrimmed") && !w.contains("trims"), "{w}");
    assert_eq!(cyl.shells.len(), 1);
    assert!(cyl.shells[0].closed && cyl.shells[0].faces.len() == 3);
}

const HAND: &str = "ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('h.step','',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));
ENDSEC;
DATA;
#1=CARTESIAN_POINT('',(1.,2.,3.));
#2=DIRECTION('',(0.,0.,2.));
#3=DIRECTION('',(0.,1.,0.));
#4=AXIS2_PLACEMENT_3D('',#1,#2,#3);
#5=CONICAL_SURFACE('cone',#4,1.,30.);
#6=TOROIDAL_SURFACE('torus',#4,3.,1.);
#7=( NAMED_UNIT(*) PLANE_ANGLE_UNIT() CONVERSION_BASED_UNIT('DEGREE',#8) );
#8=PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.01745329252),#9);
#9=( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) );
ENDSEC;
END-ISO-10303-21;
";

/// Closed forms: a cone with its semi-angle in degrees (the file's unit), a torus; defaults for
/// the axis placement's x direction and the default range of a free cone.
#[test]
fn hand_written_elementary_surfaces_match_closed_forms() {
    let r = parse_step(HAND).unwrap();
    assert_eq!(r.entities.len(), 2);
    assert_eq!(r.entities[0].name.as_deref(), Some("cone"));
    let (c, z, x) = (Vec3::new(1., 2., 3.), Vec3::z(), Vec3::y());
    let y = z.cross(&x);
    let Entity::Surface(cone) = &r.entities[0].entity else {
        panic!()
    };
    let Entity::Surface(torus) = &r.entities[1].entity else {
        panic!()
    };
    let ax = ParamAxis::Angle {
        start: 0.0,
        end: TAU,
        segment: TAU / 4.0,
        periodic: true,
    };
    let tan30 = (30f64).to_radians().tan();
    for k in 0..20 {
        let u = 0.37 * k as f64;
        let v = -1.0 + 0.1 * k as f64;
        let want = c + (x * u.cos() + y * u.sin()) * (1.0 + v * tan30) + z * v;
        let got = cone.point(ax.to_nurbs(u), v).unwrap();
        assert!((got - want).norm() < 1e-14, "{got} vs {want}");
        let w = 0.91 * k as f64;
        let want = c + (x * u.cos() + y * u.sin()) * (3.0 + w.cos()) + z * w.sin();
        let got = torus.point(ax.to_nurbs(u), ax.to_nurbs(w)).unwrap();
        assert!((got - want).norm() < 1e-14, "{got} vs {want}");
    }
    let d = cone.domain();
    assert_eq!([d[1].min, d[1].max], vclay_io::step_read::DEFAULT_RANGE);
}

#[test]
fn malformed_elementary_surfaces_are_located_errors() {
    for (from, to, want) in [
        (
            "TOROIDAL_SURFACE('torus',#4,3.,1.)",
            "TOROIDAL_SURFACE('torus',#4,3.,-1.)",
            "minor_radius must be positive",
        ),
        (
            "CONICAL_SURFACE('cone',#4,1.,30.)",
            "CONICAL_SURFACE('cone',#4,1.,95.)",
            "semi_angle",
        ),
        (
            "#2=DIRECTION('',(0.,0.,2.))",
            "#2=DIRECTION('',(0.,0.,0.))",
            "zero",
        ),
        (
            "#3=DIRECTION('',(0.,1.,0.))",
            "#3=DIRECTION('',(0.,0.,1.))",
            "parallel",
        ),
        (
            "CONICAL_SURFACE('cone',#4,1.,30.)",
            "CONICAL_SURFACE('cone',#44,1.,30.)",
            "#44, which is not defined",
        ),
    ] {
        let bad = HAND.replace(from, to);
        assert_ne!(bad, HAND);
        let e = parse_step(&bad).unwrap_err().to_string();
        assert!(e.starts_with("STEP line "), "{e}");
        assert!(e.contains(want), "{e}");
    }
}

fn area(m: &vclay_core::TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            (b - a).cross(&(c - a)).norm() / 2.0
        })
        .sum()
}

/// The area of the face `bench/gen_cad_test_files.py` extrudes: the cubic Bezier `c(u)` swept
/// by `V`, `int_0^1 |c'(u) x V| du` (midpoint rule, 20,000 points).
fn extruded_area() -> f64 {
    let p = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(2.0, -1.0, 0.0),
        Vec3::new(3.0, 0.5, 0.0),
    ];
    let v = Vec3::new(0.2, 0.3, 1.5);
    let n = 20_000;
    (0..n)
        .map(|k| {
            let u = (k as f64 + 0.5) / n as f64;
            let d = (p[1] - p[0]) * (3.0 * (1.0 - u) * (1.0 - u))
                + (p[2] - p[1]) * (6.0 * (1.0 - u) * u)
                + (p[3] - p[2]) * (3.0 * u * u);
            d.cross(&v).norm() / n as f64
        })
        .sum()
}

/// Trimming applied by `tessellate_trimmed`: a cylinder's caps (planes cut to the box of their
/// circles) become discs, its side and a box's faces stay whole; areas match the closed forms up
/// to the grid spacing.
#[test]
fn trimmed_tessellation_cuts_faces_to_their_loops() {
    use vclay_io::step_read::tessellate_trimmed;
    let (r, h) = (0.8, 1.7);
    let imp = import_model(data("brep_cylinder.step")).unwrap();
    let mut caps = 0;
    for f in &imp.faces {
        let s = surface(&imp, f);
        let m = tessellate_trimmed(f, &s, [96, 96]).unwrap();
        let a = area(&m);
        match f.surface_type.as_str() {
            "PLANE" => {
                caps += 1;
                let disc = std::f64::consts::PI * r * r;
                assert!((a - disc).abs() < 0.03 * disc, "cap area {a} vs {disc}");
                // The untrimmed square is 4 r^2.
                assert!(a < 0.85 * 4.0 * r * r);
            }
            "CYLINDRICAL_SURFACE" => {
                let side = TAU * r * h;
                assert!((a - side).abs() < 2e-3 * side, "side area {a} vs {side}");
            }
            t => panic!("{t}"),
        }
    }
    assert_eq!(caps, 2);
    let bx = import_model(data("brep_box.step")).unwrap();
    let total: f64 = bx
        .faces
        .iter()
        .map(|f| area(&tessellate_trimmed(f, &surface(&bx, f), [8, 8]).unwrap()))
        .sum();
    let want = 2.0 * (2.0 * 1.5 + 2.0 * 0.75 + 1.5 * 0.75);
    assert!((total - want).abs() < 1e-12 * want, "{total} vs {want}");
    let f = &bx.faces[0];
    assert!(tessellate_trimmed(f, &surface(&bx, f), [1, 8]).is_err());
    // Faces bounded through seams (two pcurves of one edge) stay whole: the cone's side and
    // caps, the torus (tilted frame), the revolved and extruded B-splines.
    let pi = std::f64::consts::PI;
    let (r0, r1, hc) = (1.0f64, 0.4f64, 1.5f64);
    let cases: [(&str, f64, f64); 4] = [
        (
            "brep_cone.step",
            pi * (r0 + r1) * hc.hypot(r0 - r1) + pi * (r0 * r0 + r1 * r1),
            0.01,
        ),
        ("brep_torus.step", 4.0 * pi * pi * 2.0 * 0.6, 0.01),
        ("brep_revolution.step", f64::NAN, 0.0),
        ("brep_extrusion.step", extruded_area(), 0.02),
    ];
    for (file, want, tol) in cases {
        let imp = import_model(data(file)).unwrap();
        let (mut trimmed, mut whole) = (0.0, 0.0);
        for f in &imp.faces {
            let s = surface(&imp, f);
            trimmed += area(&tessellate_trimmed(f, &s, [64, 64]).unwrap());
            let mut untrimmed = f.clone();
            untrimmed.loops.clear();
            whole += area(&tessellate_trimmed(&untrimmed, &s, [64, 64]).unwrap());
        }
        if want.is_nan() {
            // One face covering its whole surface.
            assert!(
                (trimmed - whole).abs() < 1e-12 * whole,
                "{file}: {trimmed} vs {whole}"
            );
        } else {
            assert!(
                (trimmed - want).abs() < tol * want,
                "{file}: {trimmed} vs {want}"
            );
        }
    }
    // The parameter maps invert each other.
    for a in &imp.faces[0].axes {
        for x in [0.1, 1.0, 2.5, 4.0, 6.0] {
            assert!((a.from_nurbs(a.to_nurbs(x)) - x).abs() < 1e-12);
        }
    }
}
