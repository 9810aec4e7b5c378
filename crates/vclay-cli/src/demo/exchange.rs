//! Demo step of the pictures and exchange formats (issue 8): an exact torus to STEP (a B-rep
//! solid, issue 20) and geomdl JSON, a travelling wave on a bicubic sheet as an animated GIF, a glTF file with the motion as
//! morph targets, and an SVG plot of the frames' amplitude and render time.

use anyhow::Result;
use std::path::Path;
use std::time::Instant;
use vclay::io::geomdl::write_geomdl;
use vclay::io::gltf::{GlbMesh, MorphAnimation, write_glb};
use vclay::io::model::{Entity, NamedEntity};
use vclay::io::step::write_step;
use vclay::render::plot::{Plot, Series, panels_svg, write_svg};
use vclay::render::{RenderOptions, Scene, render, write_gif};
use vclay::spline::{NurbsSurface, tessellate_surface};
use vclay::{TriMesh, Vec3};

/// Frames of the wave animation.
const FRAMES: usize = 12;

/// A bicubic sheet with a travelling wave of phase `phase` in its control net.
fn wave_sheet(phase: f64) -> Result<NurbsSurface> {
    let n = 10;
    let mut pts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let z = 0.2 * (std::f64::consts::TAU * x - phase).sin() * (1.0 - 0.5 * y);
            pts.push(Vec3::new(2.0 * x - 1.0, 2.0 * y - 1.0, z));
        }
    }
    Ok(NurbsSurface::clamped_uniform([3, 3], [n, n], pts)?)
}

/// Writes torus.step (a `MANIFOLD_SOLID_BREP`), torus.geomdl.json, wave.gif, wave.glb and
/// wave.svg.
pub fn pictures_and_exchange(out: &Path) -> Result<(String, Vec<String>)> {
    let surface = NurbsSurface::torus(2.0, 0.6)?;
    let shell = vclay::io::brep::Shell::of_surface(&surface)?;
    let torus: NamedEntity = NamedEntity {
        name: Some("torus".into()),
        entity: Entity::Surface(surface),
    };
    write_step(out.join("torus.step"), std::slice::from_ref(&torus))?;
    write_geomdl(out.join("torus.geomdl.json"), std::slice::from_ref(&torus))?;

    let mut meshes = Vec::with_capacity(FRAMES);
    let mut amplitude = Vec::with_capacity(FRAMES);
    for k in 0..FRAMES {
        let s = wave_sheet(std::f64::consts::TAU * k as f64 / FRAMES as f64)?;
        let mut m = TriMesh::new();
        tessellate_surface(&s, [40, 40], &mut m)?;
        amplitude.push(m.positions.iter().map(|p| p.z.abs()).fold(0.0, f64::max));
        meshes.push(m);
    }
    let opts = RenderOptions::sized(320, 240);
    let scenes: Vec<Scene> = meshes
        .iter()
        .map(|m| Scene::new().with_mesh(m.clone()))
        .collect();
    let camera = opts.camera_for_scenes(&scenes)?;
    let fixed = RenderOptions {
        camera: Some(camera),
        ..opts
    };
    let mut frames = Vec::with_capacity(FRAMES);
    let mut frame_ms = Vec::with_capacity(FRAMES);
    for s in &scenes {
        let t0 = Instant::now();
        frames.push(render(s, &fixed)?);
        frame_ms.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    write_gif(out.join("wave.gif"), &frames, 100)?;

    let base = meshes[0].clone();
    let anim = MorphAnimation {
        times: (0..FRAMES).map(|k| k as f64 * 0.1).collect(),
        frames: meshes.iter().map(|m| m.positions.clone()).collect(),
    };
    write_glb(
        out.join("wave.glb"),
        &[GlbMesh {
            animation: Some(anim),
            ..GlbMesh::new("wave", base)
        }],
    )?;

    let series = |name: &str, y: &[f64]| Series {
        name: name.into(),
        points: y.iter().enumerate().map(|(k, &v)| (k as f64, v)).collect(),
    };
    let svg = panels_svg(
        &[
            Plot {
                title: "Wave amplitude per frame".into(),
                x_label: "frame".into(),
                y_label: "max |z|".into(),
                log_y: false,
                series: vec![series("amplitude", &amplitude)],
            },
            Plot {
                title: "Render time per frame (320x240, 9 samples/pixel)".into(),
                x_label: "frame".into(),
                y_label: "ms".into(),
                log_y: false,
                series: vec![series("render", &frame_ms)],
            },
        ],
        640,
        220,
    )?;
    write_svg(out.join("wave.svg"), &svg)?;
    let mean_ms = frame_ms.iter().sum::<f64>() / FRAMES as f64;
    Ok((
        format!(
            "torus as exact rational B-spline STEP ({}: {} face, {} seam edges, {} vertex) and geomdl JSON; {FRAMES}-frame wave as GIF and glTF morph targets, {:.1} ms per 320x240 frame ({} triangles)",
            if shell.closed {
                "a solid"
            } else {
                "an open shell"
            },
            shell.faces.len(),
            shell.edges.len(),
            shell.vertices.len(),
            mean_ms,
            meshes[0].triangles.len()
        ),
        [
            "torus.step",
            "torus.geomdl.json",
            "wave.gif",
            "wave.glb",
            "wave.svg",
        ]
        .map(String::from)
        .to_vec(),
    ))
}
