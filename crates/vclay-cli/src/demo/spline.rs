//! Demo steps of the spline layer (issue 2): exact primitives, refinement, volumes, batched
//! evaluation.

use anyhow::Result;
use std::path::Path;
use std::time::Instant;
use vclay::io::mesh::write_mesh;
use vclay::io::model::{Entity, write_model};
use vclay::spline::{
    NurbsSurface, NurbsVolume, ParametricSurface, tessellate_surface, tessellate_volume_boundary,
};
use vclay::{TriMesh, Vec3};

/// A wavy bicubic B-spline sheet (the kind of surface D-NURBS later sculpts).
fn wavy_sheet() -> Result<NurbsSurface> {
    let n = 8;
    let mut pts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let z = 0.15 * (6.0 * x).sin() * (4.0 * y).cos();
            pts.push(Vec3::new(2.0 * x - 1.0, 2.0 * y - 1.0, z));
        }
    }
    Ok(NurbsSurface::clamped_uniform([3, 3], [n, n], pts)?)
}

/// A NURBS volume: an identity box lattice, twisted about its axis and bulged in the middle.
fn twisted_block() -> Result<NurbsVolume> {
    let mut v = NurbsVolume::box_lattice(
        [2, 2, 3],
        [4, 4, 7],
        Vec3::new(-0.5, -0.5, 0.0),
        Vec3::new(0.5, 0.5, 2.0),
    )?;
    let pts: Vec<Vec3> = v
        .control_points()
        .iter()
        .map(|p| {
            let t = p.z / 2.0;
            let angle = std::f64::consts::FRAC_PI_2 * t;
            let bulge = 1.0 + 0.5 * (std::f64::consts::PI * t).sin();
            let (s, c) = angle.sin_cos();
            Vec3::new(
                bulge * (c * p.x - s * p.y),
                bulge * (s * p.x + c * p.y),
                p.z,
            )
        })
        .collect();
    v.set_control_points(pts)?;
    Ok(v)
}

/// Exact rational torus: tessellated, checked against the implicit torus, written as OBJ and model JSON.
pub fn torus(out: &Path) -> Result<(String, Vec<String>)> {
    let p = |f: &str| out.join(f);
    let rel = |f: &str| f.to_string();
    let torus = NurbsSurface::torus(2.0, 0.6)?;
    let mut mesh = TriMesh::new();
    tessellate_surface(&torus, [48, 96], &mut mesh)?;
    // Exactness check: every tessellation vertex lies on the torus.
    let dev = mesh
        .positions
        .iter()
        .map(|q| {
            let rho = (q.x * q.x + q.y * q.y).sqrt();
            (((rho - 2.0).powi(2) + q.z * q.z).sqrt() - 0.6).abs()
        })
        .fold(0.0, f64::max);
    write_mesh(p("torus.obj"), &mesh)?;
    write_model(p("torus.json"), &[Entity::Surface(torus)])?;
    Ok((
        format!(
            "rational bi-quadratic torus, {} triangles, largest distance from the true torus {dev:.1e}",
            mesh.triangles.len()
        ),
        vec![rel("torus.obj"), rel("torus.json")],
    ))
}

/// Knot insertion and degree elevation of a bicubic sheet; the shape change is measured.
pub fn refined_sheet(out: &Path) -> Result<(String, Vec<String>)> {
    let p = |f: &str| out.join(f);
    let rel = |f: &str| f.to_string();
    let sheet = wavy_sheet()?;
    let refined = sheet
        .insert_knot(0, 0.5, 2)?
        .insert_knot(1, 0.25, 1)?
        .elevate_degree(0, 1)?
        .elevate_degree(1, 1)?;
    let mut dev: f64 = 0.0;
    for i in 0..=50 {
        for j in 0..=50 {
            let (u, v) = (i as f64 / 50.0, j as f64 / 50.0);
            dev = dev.max((sheet.point(u, v)? - refined.point(u, v)?).norm());
        }
    }
    let mut mesh = TriMesh::new();
    tessellate_surface(&refined, [64, 64], &mut mesh)?;
    write_mesh(p("sheet.obj"), &mesh)?;
    write_model(
        p("sheet.json"),
        &[
            Entity::Surface(sheet.clone()),
            Entity::Surface(refined.clone()),
        ],
    )?;
    Ok((
        format!(
            "bicubic 8x8 sheet refined by knot insertion and degree elevation to {}x{} control points (degree {:?}); shape change {dev:.1e}",
            refined.dims()[0],
            refined.dims()[1],
            refined.degree()
        ),
        vec![rel("sheet.obj"), rel("sheet.json")],
    ))
}

/// A twisted, bulged NURBS volume; its boundary exported as OBJ.
pub fn twisted_volume(out: &Path) -> Result<(String, Vec<String>)> {
    let p = |f: &str| out.join(f);
    let rel = |f: &str| f.to_string();
    let vol = twisted_block()?;
    let mut mesh = TriMesh::new();
    tessellate_volume_boundary(&vol, [16, 16, 32], &mut mesh)?;
    write_mesh(p("twisted_volume.obj"), &mesh)?;
    write_model(p("twisted_volume.json"), &[Entity::Volume(vol)])?;
    Ok((
        format!(
            "trivariate NURBS volume (degrees 2,2,3; 4x4x7 control points) twisted 90 degrees and bulged; boundary of {} triangles",
            mesh.triangles.len()
        ),
        vec![rel("twisted_volume.obj"), rel("twisted_volume.json")],
    ))
}

/// Batched grid evaluation speed on a 1000 x 1000 grid.
pub fn batched_evaluation(_out: &Path) -> Result<(String, Vec<String>)> {
    let sheet = wavy_sheet()?;
    let n = 1000;
    let us: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let t0 = Instant::now();
    let pts = sheet.eval_grid(&us, &us, vclay::Parallelism::Auto)?;
    let secs = t0.elapsed().as_secs_f64();
    Ok((
        format!(
            "{} surface points on a 1000x1000 grid in {:.1} ms ({:.0} million points/s)",
            pts.len(),
            secs * 1e3,
            pts.len() as f64 / secs / 1e6
        ),
        vec![],
    ))
}
