//! `vclay run SCENARIO.toml [--out DIR] [--quiet]`: runs a scenario file.
//!
//! The `[model] kind` key chooses the module that reads and runs the file; dynamic solids
//! (`subdivision-solid`, `bspline-solid`) are run by `vclay_solids::scenario`, D-NURBS
//! (`dnurbs-curve`, `dnurbs-surface`, `dnurbs-swung`) by `vclay_dynamics::scenario`. A progress bar
//! goes to stderr, the summary (steps, mean and max step time, final energy, files) to stdout.

use anyhow::{Context, Result, bail};
use std::io::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};
use vclay::dynamics::scenario::{DNURBS_KINDS, DnurbsScenario};
use vclay::solids::scenario::{FrameFormat, Progress, SOLID_KINDS, Scenario, model_kind};

/// Runs the scenario at `path`; `out` replaces the file's `[output] dir`.
pub fn run(path: &Path, out: Option<&Path>, quiet: bool) -> Result<()> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scenario {}", path.display()))?;
    let name = path.display().to_string();
    let kind = model_kind(&text, &name)?;
    if DNURBS_KINDS.contains(&kind.as_str()) {
        return run_dnurbs(path, &text, &name, out, quiet);
    }
    if !SOLID_KINDS.contains(&kind.as_str()) {
        bail!(
            "{name}: [model] kind \"{kind}\" is not known; known kinds: {}, {}",
            SOLID_KINDS.join(", "),
            DNURBS_KINDS.join(", ")
        );
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let t0 = Instant::now();
    let mut scenario = Scenario::parse(&text, &name, base)?;
    if let Some(o) = out {
        scenario.output.dir = o.to_path_buf();
    }
    let st = scenario.solid.stats();
    eprintln!(
        "{name}: {kind}, {} control points, {} data points, {} springs; built in {:.2} s; {} steps",
        st.control_points,
        st.data_points,
        st.edge_springs + st.virtual_springs,
        t0.elapsed().as_secs_f64(),
        scenario.steps
    );
    let mut last = Instant::now() - Duration::from_secs(1);
    let mut bar = |p: Progress| {
        if quiet || (last.elapsed() < Duration::from_millis(100) && p.step != p.steps) {
            return;
        }
        last = Instant::now();
        let width = 30;
        let done = (p.step * width)
            .checked_div(p.steps)
            .unwrap_or(width)
            .min(width);
        eprint!(
            "\r[{}{}] {}/{} t = {:.3} E = {:.4e}",
            "#".repeat(done),
            " ".repeat(width - done),
            p.step,
            p.steps,
            p.time,
            p.energy
        );
        let _ = std::io::stderr().flush();
        if p.step == p.steps {
            eprintln!();
        }
    };
    let result = scenario.run(&mut bar);
    if !quiet {
        eprintln!();
    }
    let s = result.with_context(|| format!("running {name}"))?;
    for l in &s.log {
        println!("  {l}");
    }
    println!(
        "vclay run: {} steps, mean {:.3} ms/step, max {:.3} ms, final energy {:.6e}",
        s.steps, s.mean_step_ms, s.max_step_ms, s.final_energy
    );
    println!(
        "  model: {} control points ({} free), {} data points ({} active), {} springs ({} active)",
        s.stats.control_points,
        s.stats.free_control_points,
        s.stats.data_points,
        s.stats.active_data_points,
        s.stats.edge_springs + s.stats.virtual_springs,
        s.stats.active_springs
    );
    println!("  {} files written", s.files.len());
    for f in s.files.iter().filter(|f| {
        !f.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("frame_"))
    }) {
        println!("  -> {}", f.display());
    }
    Ok(())
}

/// Runs a D-NURBS scenario (`vclay_dynamics::scenario`).
fn run_dnurbs(path: &Path, text: &str, name: &str, out: Option<&Path>, quiet: bool) -> Result<()> {
    let base = path.parent().unwrap_or(Path::new("."));
    let mut scenario = DnurbsScenario::parse(text, name, base)?;
    if let Some(o) = out {
        scenario.out_dir = o.to_path_buf();
    }
    eprintln!("{name}: {}; {} steps", scenario.description, scenario.steps);
    let mut last = Instant::now() - Duration::from_secs(1);
    let mut bar = |step: usize, steps: usize, energy: f64| {
        if quiet || (last.elapsed() < Duration::from_millis(100) && step != steps) {
            return;
        }
        last = Instant::now();
        let width = 30;
        let done = (step * width)
            .checked_div(steps)
            .unwrap_or(width)
            .min(width);
        eprint!(
            "\r[{}{}] {step}/{steps} E = {energy:.4e}",
            "#".repeat(done),
            " ".repeat(width - done)
        );
        let _ = std::io::stderr().flush();
        if step == steps {
            eprintln!();
        }
    };
    let s = scenario
        .run(&mut bar)
        .with_context(|| format!("running {name}"))?;
    println!(
        "vclay run: {} steps, mean {:.3} ms/step, max {:.3} ms, final energy {:.6e}",
        s.steps, s.mean_step_ms, s.max_step_ms, s.final_energy
    );
    println!(
        "  largest constraint violation {:.3e}, data RMS distance {:.4e}",
        s.constraint_violation, s.data_rms
    );
    println!("  {} files written", s.files.len());
    for f in s.files.iter().filter(|f| {
        !f.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("frame_"))
    }) {
        println!("  -> {}", f.display());
    }
    Ok(())
}

/// Runs a scenario quietly into `dir`, writing about `frames` OBJ frames, and returns the frame
/// files in order (used by `vclay render SCENARIO.toml`).
pub fn run_for_frames(path: &Path, dir: &Path, frames: usize) -> Result<Vec<std::path::PathBuf>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scenario {}", path.display()))?;
    let name = path.display().to_string();
    let kind = model_kind(&text, &name)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let files = if DNURBS_KINDS.contains(&kind.as_str()) {
        let mut s = DnurbsScenario::parse(&text, &name, base)?;
        s.out_dir = dir.to_path_buf();
        s.every = (s.steps / frames.max(1)).max(1);
        s.run(&mut |_, _, _| {})?.files
    } else if SOLID_KINDS.contains(&kind.as_str()) {
        let mut s = Scenario::parse(&text, &name, base)?;
        s.output.dir = dir.to_path_buf();
        s.output.frames = vec![FrameFormat::Obj];
        s.output.every = (s.steps / frames.max(1)).max(1);
        s.run(&mut |_| {})?.files
    } else {
        bail!("{name}: [model] kind \"{kind}\" is not known");
    };
    let mut frames: Vec<_> = files
        .into_iter()
        .filter(|f| {
            f.extension().is_some_and(|e| e == "obj")
                && f.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("frame_"))
        })
        .collect();
    frames.sort();
    if frames.is_empty() {
        bail!("{name}: the scenario wrote no frames to render");
    }
    Ok(frames)
}
