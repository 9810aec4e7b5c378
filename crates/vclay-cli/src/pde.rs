//! `vclay pde`: solve a dynamic PDE surface spec (`dynamic-pde-surfaces.txt`) at one instant or
//! over a sequence of instants, write the surface mesh(es), and print residuals and solve times
//! as JSON. The numerics live in `vclay_pde`; this is argument parsing and file output.

use anyhow::{Context, Result, bail};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vclay::TriMesh;
use vclay::io::mesh::{MeshFormat, write_mesh};
use vclay::pde::{Animator, ModelSolution, PdeModel, frame_times};

/// Solve a PDE surface spec at --t (writing --out) or at --frames (writing into --out-dir).
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("when").required(true).args(["t", "frames"])))]
pub struct PdeArgs {
    /// Spec file (JSON; see docs/formats.md, "PDE surface specs").
    pub spec: PathBuf,
    /// Solve at this instant.
    #[arg(long, requires = "out", allow_negative_numbers = true)]
    pub t: Option<f64>,
    /// Tessellation grid per patch, NUxNV samples (u along the PDE direction).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value = "64x64",
        value_name = "NUxNV"
    )]
    pub grid: String,
    /// Output mesh for --t: .obj, .ply or .stl.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Animation frames T0:T1:COUNT (COUNT instants evenly spaced, both ends included).
    #[arg(
        long,
        requires = "out_dir",
        value_name = "T0:T1:COUNT",
        allow_hyphen_values = true
    )]
    pub frames: Option<String>,
    /// Output folder for --frames (files frame_0000.obj, ...).
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Mesh format for --frames: obj, ply or stl.
    #[arg(long, default_value = "obj")]
    pub format: String,
}

/// Parses `NUxNV` (each at least 2).
fn grid(text: &str) -> Result<(usize, usize)> {
    let parts: Vec<&str> = text.split(['x', 'X']).collect();
    match parts
        .iter()
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<Vec<_>, _>>()
    {
        Ok(n)
            if n.len() == 2
                && n.iter().all(|&k| k >= 2)
                && n[0].checked_mul(n[1]).is_some_and(|p| p <= 16_000_000) =>
        {
            Ok((n[0], n[1]))
        }
        _ => bail!(
            "--grid '{text}': expected two integers of at least 2 with at most 16 million \
             samples in all, like 64x64"
        ),
    }
}

/// Parses `T0:T1:COUNT`.
fn frames(text: &str) -> Result<(f64, f64, usize)> {
    let parts: Vec<&str> = text.split(':').collect();
    if parts.len() != 3 {
        bail!("--frames '{text}': expected T0:T1:COUNT like 0:1:5");
    }
    let t0: f64 = parts[0]
        .trim()
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .with_context(|| {
            format!(
                "--frames '{text}': T0 '{}' is not a finite number",
                parts[0]
            )
        })?;
    let t1: f64 = parts[1]
        .trim()
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .with_context(|| {
            format!(
                "--frames '{text}': T1 '{}' is not a finite number",
                parts[1]
            )
        })?;
    let n: usize = parts[2]
        .trim()
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .with_context(|| {
            format!(
                "--frames '{text}': COUNT '{}' is not a positive integer",
                parts[2]
            )
        })?;
    Ok((t0, t1, n))
}

/// Mean seconds of one solve at `t` (repeated for about 20 ms so that microsecond solves are
/// measurable), and the solution.
fn timed_solve(anim: &mut Animator<'_>, t: f64) -> Result<(ModelSolution, f64, usize)> {
    let mut sol = ModelSolution::default();
    let t0 = Instant::now();
    anim.solve_into(t, &mut sol)?;
    let first = t0.elapsed().as_secs_f64();
    let mut reps = 1;
    let start = Instant::now();
    if first < 0.005 {
        while start.elapsed().as_secs_f64() < 0.02 {
            // Fresh animator state each time would include cache misses of static patches;
            // the animator caches them, which is what a frame loop sees.
            anim.solve_into(t, &mut sol)?;
            reps += 1;
        }
        let mean = start.elapsed().as_secs_f64() / (reps - 1) as f64;
        return Ok((sol, mean, reps));
    }
    Ok((sol, first, reps))
}

fn report(model: &PdeModel, sol: &ModelSolution) -> serde_json::Value {
    json!(
        model
            .patches
            .iter()
            .zip(&sol.patches)
            .map(|(p, s)| json!({
                "name": p.name,
                "residual_rms": s.stats.residual_rms,
                "residual_norm": s.stats.residual_norm,
                "residual_relative": s.stats.residual_relative,
                "undetermined_directions": s.stats.undetermined,
                "condition": s.stats.condition,
                "collocation_points": s.stats.points,
                "unknowns": s.stats.unknowns,
                "trial_terms": p.trial.n_max,
            }))
            .collect::<Vec<_>>()
    )
}

fn mesh(model: &PdeModel, sol: &ModelSolution, nu: usize, nv: usize) -> (TriMesh, f64) {
    let t0 = Instant::now();
    let mut m = TriMesh::new();
    model.tessellate(sol, nu, nv, &mut m);
    (m, t0.elapsed().as_secs_f64())
}

fn write(path: &Path, m: &TriMesh) -> Result<()> {
    write_mesh(path, m).with_context(|| format!("cannot write {}", path.display()))
}

/// Runs the subcommand.
pub fn run(args: &PdeArgs) -> Result<()> {
    let (nu, nv) = grid(&args.grid)?;
    let model = PdeModel::read(&args.spec)?;
    crate::limits::check_memory(
        &format!("--grid {nu}x{nv} for {} patch(es)", model.patches.len()),
        vclay::session::limits::grid_mesh_bytes(nu, nv, model.patches.len()),
    )?;
    let mut anim = Animator::new(&model);
    if let Some(t) = args.t {
        if !t.is_finite() {
            bail!("--t {t}: not a finite number");
        }
        let out = args.out.as_ref().context("--t needs --out")?;
        MeshFormat::from_path(out).with_context(|| format!("--out {}", out.display()))?;
        let (sol, secs, reps) = timed_solve(&mut anim, t)?;
        let (m, tess) = mesh(&model, &sol, nu, nv);
        write(out, &m)?;
        let check = sol.residual_check(&model);
        let warning = check.warning();
        if let Some(w) = &warning
            && !crate::quiet()
        {
            eprintln!("vclay pde: warning: t = {t}: {w}");
        }
        let v = json!({
            "spec": args.spec.display().to_string(),
            "model": model.name,
            "t": t,
            "residual_rms": sol.residual_rms(),
            "residual_to_size": check.ratio,
            "surface_size": check.size,
            "warning": warning,
            "condition": sol.condition(),
            "solve_seconds": secs,
            "solve_repeats": reps,
            "tessellate_seconds": tess,
            "vertices": m.positions.len(),
            "triangles": m.triangles.len(),
            "patches": report(&model, &sol),
            "out": out.display().to_string(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let text = args.frames.as_deref().context("give --t or --frames")?;
    let (t0, t1, count) = frames(text)?;
    crate::limits::check_frames("--frames", count)?;
    let dir = args.out_dir.as_ref().context("--frames needs --out-dir")?;
    let ext = args.format.to_ascii_lowercase();
    if !matches!(ext.as_str(), "obj" | "ply" | "stl") {
        bail!("--format '{}': expected obj, ply or stl", args.format);
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut entries = Vec::with_capacity(count);
    let mut total_solve = 0.0;
    let bar = crate::progress::bar(count as u64, "vclay pde: frames");
    let mut large = Vec::new();
    for (k, t) in frame_times(t0, t1, count).into_iter().enumerate() {
        let (sol, secs, _) = timed_solve(&mut anim, t)?;
        total_solve += secs;
        let (m, tess) = mesh(&model, &sol, nu, nv);
        let path = dir.join(format!("frame_{k:04}.{ext}"));
        write(&path, &m)?;
        let check = sol.residual_check(&model);
        if check.is_large() {
            large.push((k, t, check.ratio));
        }
        entries.push(json!({
            "frame": k,
            "t": t,
            "residual_rms": sol.residual_rms(),
            "residual_to_size": check.ratio,
            "condition": sol.condition(),
            "solve_seconds": secs,
            "tessellate_seconds": tess,
            "vertices": m.positions.len(),
            "out": path.display().to_string(),
        }));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let warning = (!large.is_empty()).then(|| {
        let list: Vec<String> = large
            .iter()
            .map(|(k, t, r)| format!("frame {k} (t = {t}: {:.2} %)", 100.0 * r))
            .collect();
        format!(
            "the residual RMS is over {} % of the surface's size in {} of {count} frames: {}; \
             there the trial terms do not solve the PDE and the shape is a least-squares \
             compromise, look at it before trusting it",
            100.0 * vclay::pde::RESIDUAL_WARNING_RATIO,
            large.len(),
            list.join(", ")
        )
    });
    if let Some(w) = &warning
        && !crate::quiet()
    {
        eprintln!("vclay pde: warning: {w}");
    }
    let v = json!({
        "spec": args.spec.display().to_string(),
        "model": model.name,
        "warning": warning,
        "frames": entries,
        "mean_solve_seconds": total_solve / count as f64,
    });
    println!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}
