//! `vclay render (MODEL.json | MESH.obj/.ply/.stl/.glb | SCENARIO.toml) --out FILE.png|.gif [--view V]
//! [--size WxH] [--wireframe] [--frames N] [--ortho]`.
//!
//! A model's surfaces and volume boundaries are tessellated and shaded, its curves drawn as
//! polylines; `--wireframe` adds control nets and lattices (for a mesh: its triangle edges). A
//! `.gif` output is a turntable of `--frames` pictures. A scenario (`vclay run` file) is run
//! in a scratch folder and about `--frames` of its frames are animated with one camera: a
//! `.gif`, or numbered PNGs beside a `.png` path. The scene builders here are shared with
//! the demo's index page.

use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};
use vclay::TriMesh;
use vclay::io::model::Entity;
use vclay::render::scene::{CLAY, NET};
use vclay::render::{RenderOptions, Scene, View, render, turntable, write_animation, write_gif};
use vclay::spline::{ParametricCurve, tessellate_surface, tessellate_volume_boundary};

/// Arguments of `vclay render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Model file (vclay or geomdl JSON), mesh (.obj, .ply, .stl, .glb) or scenario (.toml,
    /// as `vclay run` reads: it is run in a scratch folder and its frames animated).
    pub input: PathBuf,
    /// Output picture: .png (one view; for a scenario, numbered PNGs beside it) or .gif
    /// (a turntable; for a scenario, its animation).
    #[arg(long)]
    pub out: PathBuf,
    /// View: iso, front, top or side.
    #[arg(long, default_value = "iso")]
    pub view: String,
    /// Picture size in pixels, WxH.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Draw control nets and lattices (or, for a mesh, its triangle edges).
    #[arg(long)]
    pub wireframe: bool,
    /// Number of frames: of the turntable for a .gif, or of a scenario's animation.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = 36)]
    pub frames: usize,
    /// Orthographic instead of perspective projection.
    #[arg(long)]
    pub ortho: bool,
}

/// Parses `WxH`.
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    let parts: Vec<&str> = text.split(['x', 'X']).collect();
    if let [w, h] = parts.as_slice()
        && let (Ok(w), Ok(h)) = (w.trim().parse::<u32>(), h.trim().parse::<u32>())
        && w > 0
        && h > 0
    {
        return Ok((w, h));
    }
    bail!("--size '{text}': expected WIDTHxHEIGHT with positive integers, like 640x480")
}

/// Tessellation samples per axis for a knot vector with `spans` non-empty spans.
fn samples_for(spans: usize) -> usize {
    (8 * spans).clamp(24, 96)
}

/// A scene showing model entities: shaded surfaces and volume boundaries, curves as lines,
/// control nets when `wireframe`.
pub fn scene_from_entities(entities: &[Entity], wireframe: bool) -> Result<Scene> {
    let mut scene = Scene::new();
    for (i, e) in entities.iter().enumerate() {
        let ctx = || format!("entity {i} ({})", e.type_name());
        match e {
            Entity::Curve(c) => {
                let d = c.domain();
                let n = samples_for(c.knots().distinct().len()) * 4;
                let pts = d
                    .linspace(n)
                    .into_iter()
                    .map(|u| c.point(u))
                    .collect::<Result<Vec<_>, _>>()
                    .with_context(ctx)?;
                scene.add_polyline(pts, [150, 60, 30], 2.5);
                if wireframe {
                    scene.add_control_net(c.control_points(), &[c.control_points().len()], NET)?;
                }
            }
            Entity::Surface(s) => {
                let samples = s
                    .knots()
                    .each_ref()
                    .map(|k| samples_for(k.distinct().len()));
                let mut m = TriMesh::new();
                tessellate_surface(s, samples, &mut m).with_context(ctx)?;
                scene.add_mesh(m, CLAY);
                if wireframe {
                    scene.add_control_net(s.control_points(), &s.dims(), NET)?;
                }
            }
            Entity::Volume(v) => {
                let samples = v
                    .knots()
                    .each_ref()
                    .map(|k| samples_for(k.distinct().len()) / 2);
                let mut m = TriMesh::new();
                tessellate_volume_boundary(v, samples, &mut m).with_context(ctx)?;
                scene.add_mesh(m, CLAY);
                if wireframe {
                    scene.add_control_net(v.control_points(), &v.dims(), NET)?;
                }
            }
        }
    }
    Ok(scene)
}

/// A scene showing a mesh; `wireframe` draws its triangle edges.
pub fn scene_from_mesh(mesh: TriMesh, wireframe: bool) -> Scene {
    let mut scene = Scene::new().with_mesh(mesh);
    if wireframe {
        scene.meshes[0].edges = Some([60, 40, 30]);
    }
    scene
}

/// Angle between adjacent triangles above which a rendered CAD part's mesh is shaded with a
/// sharp edge ([`TriMesh::with_creases`]), in degrees: smooth faces tessellated at 96 samples a
/// side turn by far less between triangles, fillets join their faces tangentially.
pub use vclay::core::mesh::CREASE_ANGLE_DEG;

/// Reads a model or mesh file into a scene, choosing by extension (and, for .json, content).
pub fn scene_from_file(path: &Path, wireframe: bool) -> Result<Scene> {
    match crate::convert::read_any(path)? {
        crate::convert::Loaded::Entities(e) => {
            let ents: Vec<Entity> = e.into_iter().map(|n| n.entity).collect();
            scene_from_entities(&ents, wireframe)
        }
        crate::convert::Loaded::Trimmed(e, faces, shells) => {
            // Faces cut to their trimming loops (issue 20), 96 samples a side; trimmed shells
            // with shared edges (issue 30); curves as lines.
            // Sharp edges between faces (a hole's rim, a box's edges) shaded sharp: the
            // crack-free mesh shares their vertices, whose averaged normals would smear them.
            let mesh = crate::convert::trimmed_mesh(&e, &faces, &shells, 96)?
                .with_creases(CREASE_ANGLE_DEG.to_radians());
            let mut scene = scene_from_mesh(mesh, wireframe);
            let curves: Vec<Entity> = e
                .into_iter()
                .map(|n| n.entity)
                .filter(|x| matches!(x, Entity::Curve(_)))
                .collect();
            if !curves.is_empty() {
                scene
                    .lines
                    .extend(scene_from_entities(&curves, wireframe)?.lines);
            }
            Ok(scene)
        }
        crate::convert::Loaded::Meshes(ms) => {
            let mut all = TriMesh::new();
            for m in &ms {
                all.append(m);
            }
            if all.normals.len() != all.positions.len() {
                all.compute_normals();
            }
            Ok(scene_from_mesh(all, wireframe))
        }
    }
}

/// Renders `mesh_path` (any mesh format) to a PNG of the given size with 2 x 2 samples per pixel;
/// used by the demo index.
pub fn mesh_to_png(mesh_path: &Path, png_path: &Path, width: u32, height: u32) -> Result<()> {
    let scene = scene_from_file(mesh_path, false)?;
    // 2 x 2 samples per pixel: anti-aliased, and twice as fast as the default 3 x 3.
    let opts = RenderOptions {
        supersample: 2,
        ..RenderOptions::sized(width, height)
    };
    let img =
        render(&scene, &opts).with_context(|| format!("rendering {}", mesh_path.display()))?;
    img.write_png(png_path)?;
    Ok(())
}

/// At most `n` of `items`, evenly spaced, the first and the last included (a scenario writes
/// about `--frames` frames; `--frames N` gives N pictures when it wrote at least N).
fn pick_evenly<T: Clone>(items: &[T], n: usize) -> Vec<T> {
    if items.len() <= n || n == 0 {
        return items.to_vec();
    }
    if n == 1 {
        return vec![items[items.len() - 1].clone()];
    }
    (0..n)
        .map(|k| items[k * (items.len() - 1) / (n - 1)].clone())
        .collect()
}

/// Checks the picture buffers against `--max-memory` before any rendering: per frame drawn at
/// once (one per thread) a supersampled colour and depth buffer of 16 bytes per sample, and
/// 3 bytes per pixel for every frame kept until the file is written.
fn check_render_memory(args: &RenderArgs, opts: &RenderOptions) -> Result<()> {
    let single = !is_scenario(&args.input)
        && args
            .out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let frames = if single { 1 } else { args.frames };
    let at_once = frames.min(rayon_threads());
    let bytes =
        crate::limits::render_bytes(opts.width, opts.height, opts.supersample, frames, at_once);
    crate::limits::check_memory(
        &format!("--size {} with --frames {frames}", args.size),
        bytes,
    )
}

fn is_scenario(input: &Path) -> bool {
    input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Runs `vclay render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let (width, height) = parse_size(&args.size)?;
    let view = View::parse(&args.view)
        .with_context(|| format!("--view '{}': expected iso, front, top or side", args.view))?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    crate::limits::check_frames("--frames", args.frames)?;
    let ext = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let opts = RenderOptions {
        view,
        orthographic: args.ortho,
        ..RenderOptions::sized(width, height)
    };
    check_render_memory(args, &opts)?;
    let file = || format!("rendering {}", args.input.display());
    if is_scenario(&args.input) {
        // A scenario: run it, then animate its frames with one camera.
        let dir = tempfile::tempdir().context("cannot create a scratch folder")?;
        let frames = crate::run::run_for_frames(&args.input, dir.path(), args.frames)?;
        let frames = pick_evenly(&frames, args.frames);
        let scenes = frames
            .iter()
            .map(|f| scene_from_file(f, args.wireframe))
            .collect::<Result<Vec<_>>>()?;
        let drawing = crate::progress::spinner(&format!("vclay render: {} frames", scenes.len()));
        let written = write_animation(&args.out, &scenes, &opts, 80).with_context(file);
        drawing.finish_and_clear();
        let written = written?;
        if !crate::quiet() {
            eprintln!(
                "vclay render: {} frames of {} -> {} file(s), first {}",
                scenes.len(),
                args.input.display(),
                written.len(),
                written
                    .first()
                    .map_or(String::new(), |p| p.display().to_string())
            );
        }
        return Ok(());
    }
    let scene = scene_from_file(&args.input, args.wireframe)?;
    match ext.as_deref() {
        Some("png") => render(&scene, &opts)
            .with_context(file)?
            .write_png(&args.out)?,
        Some("gif") => {
            let frames = turntable(&scene, args.frames, &opts).with_context(file)?;
            write_gif(&args.out, &frames, 80)?;
        }
        _ => bail!(
            "{}: unknown picture format; expected .png or .gif",
            args.out.display()
        ),
    }
    if !crate::quiet() {
        eprintln!("vclay render: wrote {}", args.out.display());
    }
    Ok(())
}
