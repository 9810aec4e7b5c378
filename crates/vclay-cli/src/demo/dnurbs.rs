//! Demo steps of D-NURBS (issue 5): surface fitting with dynamic weights (`d-nurbs.txt` Fig 7a)
//! and sculpting a swung surface (Fig 9a). Each writes the result as an OBJ mesh and as a NURBS
//! model file that `vclay eval` reads.

use anyhow::{Result, ensure};
use std::path::Path;
use std::sync::Arc;
use vclay::dynamics::dnurbs::{
    Constraint, GeneralizedDnurbs, Preset, RationalGeometry, SwungGeometry, Target, figures,
};
use vclay::dynamics::{ElasticReference, Force, Integrator};
use vclay::io::mesh::write_mesh;
use vclay::io::model::{Entity, write_model};
use vclay::spline::tessellate_surface;
use vclay::{TriMesh, Vec3};

/// Fig 7a: a quadratic 7 x 7 D-NURBS sheet (49 control points, weights dynamic) pulled to 19
/// points of a hemisphere by springs on the nearest surface points (Table 1 parameters).
pub fn hemisphere_fit(out: &Path) -> Result<(String, Vec<String>)> {
    let p = Preset::by_name("Hemisphere fitting").expect("Table 1 row");
    let sheet = figures::flat_sheet(7, 2, 2.4)?;
    let mut d =
        GeneralizedDnurbs::new(RationalGeometry::from_surface(&sheet), p.surface_material())?;
    d.set_elastic_reference(ElasticReference::Absolute);
    let data = figures::hemisphere_points();
    for &x in &data {
        d.forces_mut().push(Force::DataPoint {
            point: x,
            stiffness: p.k,
        });
    }
    let rms = |v: Vec<f64>| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let before = rms(d.data_distances()?);
    let steps = 300;
    for k in 0..steps {
        d.step(Integrator::Implicit { dt: p.dt })?;
        if k % 100 == 99 && !crate::quiet() {
            eprintln!("    fitting: step {}/{steps}", k + 1);
        }
    }
    let after = rms(d.data_distances()?);
    ensure!(
        after < 0.05 * before,
        "fit did not converge: {before} -> {after}"
    );
    let surface = d.geometry().to_surface()?;
    let mut mesh = TriMesh::new();
    tessellate_surface(&surface, [48, 48], &mut mesh)?;
    write_mesh(out.join("dnurbs_hemisphere_fit.obj"), &mesh)?;
    write_model(
        out.join("dnurbs_hemisphere_fit.json"),
        &[Entity::Surface(surface)],
    )?;
    let w = d.geometry().weights();
    let (lo, hi) = w
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    Ok((
        format!(
            "quadratic 7x7 D-NURBS with dynamic weights fitted to 19 hemisphere points: RMS distance {before:.3} -> {after:.4} in {steps} implicit steps, weights now {lo:.2}..{hi:.2}"
        ),
        vec![
            "dnurbs_hemisphere_fit.obj".into(),
            "dnurbs_hemisphere_fit.json".into(),
        ],
    ))
}

/// Fig 9a: a swung sphere (quadratic profiles with 4 and 7 control points) pulled into an egg by
/// a spring whose target rises over time, the south pole held by a point constraint.
pub fn swung_egg(out: &Path) -> Result<(String, Vec<String>)> {
    let p = Preset::by_name("Egg sculpting").expect("Table 1 row");
    let mut d = GeneralizedDnurbs::new(SwungGeometry::sphere(1.0)?, p.surface_material())?;
    d.add_constraint(Constraint::Point {
        param: [0.0, 0.0],
        target: Vec3::new(0.0, 0.0, -1.0),
    })?;
    let steps = 400;
    let dt = p.dt;
    let ramp = 0.5 * dt * steps as f64;
    d.forces_mut().push(Force::Spring {
        param: [1.0, 0.0],
        target: Target::Moving(Arc::new(move |t| {
            Vec3::new(0.0, 0.0, 1.0 + 0.8 * (t / ramp).min(1.0))
        })),
        stiffness: p.k,
        kernel: None,
    });
    for _ in 0..steps {
        d.step(Integrator::Implicit { dt })?;
    }
    let g = d.geometry();
    let height = g.point([1.0, 0.0])?.z - g.point([0.0, 0.0])?.z;
    let width = (0..=40)
        .map(|i| {
            let q = g.point([i as f64 / 40.0, 0.0]).unwrap_or_default();
            2.0 * (q.x * q.x + q.y * q.y).sqrt()
        })
        .fold(0.0, f64::max);
    ensure!(height > 2.3, "the sphere did not stretch (height {height})");
    // Closed (issue 18): the seam v = 0 / v = 1 and both poles, so the egg exports as a solid.
    let mut seam = 0.0f64;
    let mut pole = 0.0f64;
    for i in 0..=40 {
        let t = i as f64 / 40.0;
        seam = seam.max((g.point([t, 0.0])? - g.point([t, 1.0])?).norm());
        for u in [0.0, 1.0] {
            pole = pole.max((g.point([u, t])? - g.point([u, 0.0])?).norm());
        }
    }
    ensure!(
        seam < 1e-9 && pole < 1e-9,
        "the egg opened: seam gap {seam:.1e}, pole spread {pole:.1e}"
    );
    let surface = g.to_surface()?;
    let mut mesh = TriMesh::new();
    tessellate_surface(&surface, [48, 64], &mut mesh)?;
    write_mesh(out.join("dnurbs_swung_egg.obj"), &mesh)?;
    write_model(
        out.join("dnurbs_swung_egg.json"),
        &[Entity::Surface(surface)],
    )?;
    Ok((
        format!(
            "swung D-NURBS sphere sculpted into an egg by a moving spring (Table 1 'Egg sculpting'): height 2.00 -> {height:.2}, width 2.00 -> {width:.2}, south pole held to {:.1e}, seam gap {seam:.1e}, pole spread {pole:.1e}",
            d.constraint_violations()?.into_iter().fold(0.0, f64::max)
        ),
        vec![
            "dnurbs_swung_egg.obj".into(),
            "dnurbs_swung_egg.json".into(),
        ],
    ))
}

/// The fitting scenarios of `d-nurbs.txt` Figs 6, 7b and 7c with the paper's counts (issue 28),
/// embedded: (file stem, text).
const FITS: [(&str, &str); 3] = [
    (
        "fig06_curve_fit",
        include_str!("../../../../examples/scenarios/fig06_curve_fit.toml"),
    ),
    (
        "fig7b_saddle_fit",
        include_str!("../../../../examples/scenarios/fig7b_saddle_fit.toml"),
    ),
    (
        "fig7c_wave_fit",
        include_str!("../../../../examples/scenarios/fig7c_wave_fit.toml"),
    ),
];

/// Figs 6, 7b, 7c: the shipped scenarios run through the session layer to their end; the
/// surfaces' final meshes are rendered by the index, the Fig 6 curve is drawn here from the top
/// with its six data points.
pub fn paper_fits(out: &Path) -> Result<(String, Vec<String>)> {
    use vclay::render::{RenderOptions, Scene, View, render};
    use vclay::session::scenario::Scenario;
    let mut files = Vec::new();
    let mut lines = Vec::new();
    for (stem, text) in FITS {
        let mut sc = Scenario::parse(text, &format!("{stem}.toml"), stem, Path::new("."))?;
        let steps = sc.steps;
        let dir = out.join(format!("dnurbs_{stem}"));
        let mut output = sc.output.clone();
        output.frames.clear();
        output.csv = None;
        output.final_files = vec!["final.obj".into()];
        vclay::session::run::run(&mut sc.session, steps, &dir, &output, &mut |_| {})?;
        let model = sc.session.model(None)?;
        lines.push(format!("{stem}: {}", model.summary()));
        if stem == "fig06_curve_fit" {
            let mut scene = Scene::new();
            for set in model.display_lines() {
                use vclay::session::LineRole;
                match set.role {
                    Some(LineRole::Curve) => {
                        scene.add_polyline(set.points.clone(), [150, 60, 40], 2.0);
                    }
                    Some(LineRole::DataPoints) => {
                        scene.add_markers(&set.points, [200, 40, 40], 5.0)
                    }
                    _ => {}
                }
            }
            let opts = RenderOptions {
                supersample: 2,
                view: View::Top,
                ..RenderOptions::sized(400, 300)
            };
            let png = format!("dnurbs_{stem}.png");
            render(&scene, &opts)?.write_png(out.join(&png))?;
            files.push(png);
        } else {
            files.push(format!("dnurbs_{stem}/final.obj"));
        }
    }
    Ok((lines.join("; "), files))
}
