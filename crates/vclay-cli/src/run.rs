//! `vclay run FILE [--steps N | --until T] [--save SESSION] [--out DIR] [--quiet]`: runs a
//! scenario or continues a saved session through the session layer (`vclay_session`), for
//! every model kind. Output goes to `--out DIR`, else `./vclay-run/<scenario name>/`. A
//! progress bar goes to stderr; the timeline log, the summary and every file written to
//! stdout.

use anyhow::{Context, Result, bail};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use vclay::session::file::{self, RunInfo};
use vclay::session::run::{Progress, RunLimits, RunSummary};
use vclay::session::scenario::{
    DEFAULT_DURATION, OutputSpec, check_steps, default_out_dir, steps_for_duration,
};
use vclay::session::{Session, SessionError};

/// The arguments of `vclay run`.
#[derive(Debug)]
pub struct RunArgs {
    /// Scenario or session file.
    pub file: PathBuf,
    /// Steps to run.
    pub steps: Option<u64>,
    /// Time to run to.
    pub until: Option<f64>,
    /// Where to save the session at the end.
    pub save: Option<PathBuf>,
    /// Output folder.
    pub out: Option<PathBuf>,
    /// Most bytes the run may write (`--max-output`).
    pub max_output: Option<u64>,
    /// No progress bar.
    pub quiet: bool,
}

/// A file opened for running: the session and its run information.
struct Opened {
    session: Session,
    info: RunInfo,
    /// Whether the file gave a run length (a scenario, or a session saved by a run).
    has_length: bool,
}

/// Opens any file vclay reads as a session (`vclay_session::open`: scenarios, sessions, model
/// files, PDE specs, lattices, meshes, CAD files).
fn open(path: &Path) -> Result<Opened> {
    let o = vclay::session::open(path)?;
    let info = o.run_info();
    Ok(Opened {
        has_length: o.run.is_some(),
        info,
        session: o.session,
    })
}

/// Runs `vclay run`.
pub fn run(args: &RunArgs) -> Result<()> {
    let name = args.file.display().to_string();
    let t0 = Instant::now();
    let Opened {
        mut session,
        info,
        has_length,
    } = open(&args.file)?;
    let first = session.model(None)?;
    let now = first.steps();
    // The same bounds as a scenario's `steps` and `duration` (vclay_session::scenario).
    let steps = match (args.steps, args.until) {
        (Some(n), _) => check_steps(n).map_err(|e| anyhow::anyhow!("--steps: {e}"))?,
        (None, Some(t)) => {
            if !(t.is_finite() && t >= 0.0) {
                bail!("--until {t}: a time in seconds, >= 0");
            }
            steps_for_duration((t - first.time()).max(0.0), first.dt())
                .map_err(|e| anyhow::anyhow!("--until {t}: {e}"))?
        }
        (None, None) if has_length => info.end_step.saturating_sub(now),
        (None, None) => {
            let n = steps_for_duration(DEFAULT_DURATION, first.dt()).map_err(anyhow::Error::msg)?;
            if !args.quiet {
                eprintln!(
                    "{name}: the file gives no run length; running {DEFAULT_DURATION} s ({n} steps; \
                     --steps or --until for more)"
                );
            }
            n
        }
    };
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&info.name));
    if !args.quiet {
        for n in session.model_names() {
            let m = session.model(Some(n))?;
            eprintln!("{name}: model `{n}` ({}): {}", m.kind(), m.summary());
        }
        eprintln!(
            "{name}: opened in {:.2} s; {steps} steps from step {now} (t = {:.4}) into {}",
            t0.elapsed().as_secs_f64(),
            first.time(),
            dir.display()
        );
    }
    // The bar is for a person at a terminal: off with --quiet and when stderr is a file or pipe.
    let quiet = args.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last = Instant::now() - Duration::from_secs(1);
    let mut bar_shown = false;
    let mut bar = |p: Progress| {
        // Timeline events as they happen (stdout), above the bar.
        for l in &p.events {
            if bar_shown {
                eprint!("\r\x1b[2K");
                bar_shown = false;
            }
            println!("  {l}");
        }
        if quiet || (last.elapsed() < Duration::from_millis(100) && p.step != p.steps) {
            return;
        }
        bar_shown = p.step != p.steps;
        last = Instant::now();
        let width = 30;
        let done = (p.step * width)
            .checked_div(p.steps)
            .unwrap_or(width)
            .min(width) as usize;
        eprint!(
            "\r[{}{}] {}/{} t = {:.3} E = {:.4e}",
            "#".repeat(done),
            " ".repeat(width as usize - done),
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
    let limits = RunLimits {
        max_output: args.max_output,
        max_memory: Some(crate::limits::max_memory()),
    };
    let result =
        vclay::session::run::run_with(&mut session, steps, &dir, &info.output, &limits, &mut |p| {
            bar(p);
            std::ops::ControlFlow::Continue(())
        });
    let s = match result {
        Ok(s) => s,
        Err(e) => {
            if let Some(p) = &args.save
                && matches!(e, SessionError::Diverged { .. })
            {
                eprintln!("(not saving {}: the run diverged)", p.display());
            }
            if let SessionError::OverLimit(o) = &e {
                bail!("{name}: {o} (lower --steps, or raise --max-memory)");
            }
            return Err(e).with_context(|| format!("running {name}"));
        }
    };
    print_summary(&s, &dir);
    if let Some(p) = &args.save {
        file::save(p, &session, Some(&info))?;
        println!("  session saved -> {}", p.display());
    }
    Ok(())
}

/// The summary on stdout: the figures, the models, and the files written: all of them with
/// `--verbose`, else the folder, the counts and the first and last frame (a long run writes
/// hundreds). The timeline's events were printed as they happened.
fn print_summary(s: &RunSummary, dir: &Path) {
    let energies: Vec<String> = s
        .final_energy
        .iter()
        .map(|(n, e)| format!("{n} {e:.6e}"))
        .collect();
    println!(
        "vclay run: {} steps, mean {:.3} ms/step, max {:.3} ms, final energy {}",
        s.steps,
        s.mean_step_ms,
        s.max_step_ms,
        energies.join(", ")
    );
    for m in &s.models {
        println!("  model {m}");
    }
    println!(
        "  {} files written to {}: {} frames, {} other",
        s.frames.len() + s.files.len(),
        dir.display(),
        s.frames.len(),
        s.files.len()
    );
    if crate::verbose() || s.frames.len() <= 4 {
        for f in s.frames.iter().chain(&s.files) {
            println!("  -> {}", f.display());
        }
        return;
    }
    let name = |p: &PathBuf| {
        p.file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    };
    if let (Some(a), Some(b)) = (s.frames.first(), s.frames.last()) {
        println!(
            "  -> frames {} .. {} (--verbose lists them)",
            name(a),
            name(b)
        );
    }
    for f in &s.files {
        println!("  -> {}", f.display());
    }
}

/// Runs a scenario or session quietly into `dir` (a progress bar over the steps on a terminal),
/// writing about `frames` OBJ frames, and returns the frame files in order (used by `vclay
/// render SCENARIO.toml`).
pub fn run_for_frames(path: &Path, dir: &Path, frames: usize) -> Result<Vec<PathBuf>> {
    let Opened {
        mut session, info, ..
    } = open(path)?;
    let steps = info.end_step.saturating_sub(session.model(None)?.steps());
    let output = OutputSpec {
        frames: vec![vclay::session::scenario::FrameFormat::Obj],
        every: (steps / frames.max(1) as u64).max(1),
        final_files: Vec::new(),
        csv: None,
    };
    let bar = crate::progress::bar(steps, &format!("{}: steps", path.display()));
    let s = vclay::session::run::run(&mut session, steps, dir, &output, &mut |p| {
        bar.set_position(p.step)
    });
    bar.finish_and_clear();
    let s = s?;
    if s.frames.is_empty() {
        bail!("{}: the scenario wrote no frames to render", path.display());
    }
    Ok(s.frames)
}
