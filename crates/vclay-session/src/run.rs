//! Running a session for a number of steps and writing what a scenario's `[output]` asks for:
//! frames every `every` steps (and at the first and last step), the final model files and an
//! energy table. `vclay run` and the Python module call [`run`].
//!
//! **Before the first step** ([`check_output`]) a run makes sure it can finish: the output
//! folder is created and a file is created and removed in it (an unwritable folder is an error
//! now, not after the whole simulation); one frame of every model and format is written to a
//! scratch file to measure its size, and the run's output, `frames x bytes per frame` plus the
//! energy table, is compared with the free space of the folder's file system and with the
//! caller's limit ([`RunLimits`]). The memory the run keeps (the energy table, built in memory
//! and written atomically at the end, and the frame names) is compared with the memory limit.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::SessionError;
use crate::limits::{human, human_limit};
use crate::scenario::OutputSpec;
use crate::session::Session;

/// Progress after a step.
#[derive(Clone, Debug)]
pub struct Progress {
    /// Steps done in this run.
    pub step: u64,
    /// Steps of this run.
    pub steps: u64,
    /// Time of the first model.
    pub time: f64,
    /// Total energy of the first model (kinetic + elastic) at the start of the step.
    pub energy: f64,
    /// The log lines of the scheduled commands this step applied (a front end shows them as
    /// they happen; [`RunSummary::log`] has them all).
    pub events: Vec<String>,
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct RunSummary {
    /// Steps taken (per model).
    pub steps: u64,
    /// Mean wall time of one session step (all models) in milliseconds.
    pub mean_step_ms: f64,
    /// Largest step time.
    pub max_step_ms: f64,
    /// Total energy of each model at the end (name, energy).
    pub final_energy: Vec<(String, f64)>,
    /// One line per model (sizes).
    pub models: Vec<String>,
    /// The log lines of the commands applied during the run.
    pub log: Vec<String>,
    /// Frame files written, in order.
    pub frames: Vec<PathBuf>,
    /// Other files written (final models, energy table).
    pub files: Vec<PathBuf>,
    /// The progress callback stopped the run before its end ([`run_stoppable`]): the final
    /// models were not written.
    pub stopped: bool,
}

/// Bytes per row of the energy table (one row per step and model; rows measured 90-140 bytes,
/// rounded up).
pub const CSV_ROW_BYTES: f64 = 160.0;
/// Bytes of memory per frame file the summary lists (the path and its vector slot).
pub const FRAME_NAME_BYTES: f64 = 128.0;

/// Limits a run checks before its first step ([`check_output`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunLimits {
    /// Most bytes the run may write (besides the free space, always checked); `None`: only
    /// the free space.
    pub max_output: Option<u64>,
    /// Most bytes of memory the run's energy table and frame list may take; `None`: no check.
    pub max_memory: Option<u64>,
}

/// What a run will write, estimated before its first step ([`check_output`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputPlan {
    /// Frames written per model and format (the first, every multiple of `every`, the last).
    pub frames: u64,
    /// Bytes of one frame of every model and format together (measured by writing one).
    pub frame_bytes: u64,
    /// Bytes of the energy table (estimated, [`CSV_ROW_BYTES`] per row).
    pub csv_bytes: f64,
    /// Bytes of everything the run writes (the final model files not counted).
    pub total: f64,
    /// Bytes of memory the run keeps for its output (the energy table and the frame list).
    pub memory: f64,
    /// Free bytes for this user on the output folder's file system (`None` where unknown).
    pub available: Option<u64>,
}

/// Frames a run of `steps` steps from step `now` writes with a frame every `every` steps: the
/// first, each step that is a multiple of `every`, and the last.
pub fn frames_written(now: u64, steps: u64, every: u64) -> u64 {
    let every = every.max(1);
    let end = now.saturating_add(steps);
    if steps == 0 {
        return 1;
    }
    1 + (end / every - now / every) + u64::from(!end.is_multiple_of(every))
}

/// Free bytes for this user on the file system of `dir` (`None` where unknown).
pub fn available_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let st = rustix::fs::statvfs(dir).ok()?;
        Some(st.f_bavail.saturating_mul(st.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// Checks, before the first step, that a run of `steps` steps can write its output to `dir`
/// (module docs): creates the folder, checks it is writable, measures one frame of every model
/// and format, and compares the whole output with the free space and `limits`. Writes nothing
/// that stays.
pub fn check_output(
    session: &Session,
    steps: u64,
    dir: &Path,
    output: &OutputSpec,
    limits: &RunLimits,
) -> Result<OutputPlan, SessionError> {
    let kind = |e: std::io::Error| e.kind();
    std::fs::create_dir_all(dir).map_err(|e| {
        SessionError::io(
            dir,
            format!("cannot create the output folder ({})", kind(e)),
        )
    })?;
    let probe = |suffix: &str| {
        tempfile::Builder::new()
            .prefix(".vclay-probe-")
            .suffix(suffix)
            .tempfile_in(dir)
            .map_err(|e| {
                SessionError::io(
                    dir,
                    format!(
                        "the output folder is not writable ({}); choose another folder",
                        kind(e)
                    ),
                )
            })
    };
    drop(probe("")?);
    let names = session.model_names();
    let mut frame_bytes = 0u64;
    for name in &names {
        let m = session.model(Some(name))?;
        for f in &output.frames {
            let tmp = probe(&format!(".{}", f.extension()))?;
            m.export(tmp.path()).map_err(|e| e.in_model(name))?;
            let len = std::fs::metadata(tmp.path()).map_or(0, |m| m.len());
            frame_bytes = frame_bytes.saturating_add(len);
        }
    }
    let now = session.model(None)?.steps();
    let frames = frames_written(now, steps, output.every);
    let rows = (steps as f64 + 1.0) * names.len() as f64;
    let csv_bytes = if output.csv.is_some() {
        rows * CSV_ROW_BYTES
    } else {
        0.0
    };
    let total = frames as f64 * frame_bytes as f64 + csv_bytes;
    let frame_files = frames as f64 * (names.len() * output.frames.len()) as f64;
    let memory = csv_bytes + frame_files * FRAME_NAME_BYTES;
    let plan = OutputPlan {
        frames,
        frame_bytes,
        csv_bytes,
        total,
        memory,
        available: available_space(dir),
    };
    let what = || {
        let mut w = format!(
            "{steps} steps would write about {}: {frames} frames of {}",
            human(total),
            human(frame_bytes as f64)
        );
        if csv_bytes > 0.0 {
            let _ = write!(w, " and an energy table of {}", human(csv_bytes));
        }
        w
    };
    let advice = "write frames less often ([output] every), fewer formats, or run fewer steps";
    // The output limit first, then the free space: the first one `total` exceeds is the error.
    let bounds = [
        limits
            .max_output
            .map(|max| (max, format!("the output limit of {}", human_limit(max)))),
        plan.available
            .map(|free| (free, format!("the {} free there", human(free as f64)))),
    ];
    if let Some((_, bound)) = bounds
        .into_iter()
        .flatten()
        .find(|(b, _)| total > *b as f64)
    {
        return Err(SessionError::io(
            dir,
            format!("{}, more than {bound}; {advice}", what()),
        ));
    }
    if let Some(max) = limits.max_memory {
        crate::limits::check(
            || {
                format!(
                    "{steps} steps (the energy table and the list of {frame_files} frame files)"
                )
            },
            memory,
            max,
        )?;
    }
    Ok(plan)
}

/// Runs `steps` session steps into `dir` writing `output`. On divergence the energy table of
/// the steps so far is still written and the error returned; the final models are not.
/// Checks the output first ([`check_output`], free space only); [`run_with`] takes limits.
pub fn run(
    session: &mut Session,
    steps: u64,
    dir: &Path,
    output: &OutputSpec,
    progress: &mut dyn FnMut(Progress),
) -> Result<RunSummary, SessionError> {
    run_with(
        session,
        steps,
        dir,
        output,
        &RunLimits::default(),
        &mut |p| {
            progress(p);
            std::ops::ControlFlow::Continue(())
        },
    )
}

/// [`run`] whose `progress` may stop it (`ControlFlow::Break`, e.g. Ctrl-C in Python): the
/// steps done stay done, the energy table of those steps is written (as on divergence), the
/// final models are not, and the summary says [`RunSummary::stopped`].
pub fn run_stoppable(
    session: &mut Session,
    steps: u64,
    dir: &Path,
    output: &OutputSpec,
    progress: &mut dyn FnMut(Progress) -> std::ops::ControlFlow<()>,
) -> Result<RunSummary, SessionError> {
    run_with(session, steps, dir, output, &RunLimits::default(), progress)
}

/// [`run_stoppable`] with `limits` checked before the first step ([`check_output`]).
pub fn run_with(
    session: &mut Session,
    steps: u64,
    dir: &Path,
    output: &OutputSpec,
    limits: &RunLimits,
    progress: &mut dyn FnMut(Progress) -> std::ops::ControlFlow<()>,
) -> Result<RunSummary, SessionError> {
    check_output(session, steps, dir, output, limits)?;
    let names: Vec<String> = session
        .model_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let multi = names.len() > 1;
    let file_name = |model: &str, base: &str| {
        if multi {
            format!("{model}_{base}")
        } else {
            base.to_string()
        }
    };
    let mut summary = RunSummary::default();
    let mut csv = String::from("step,model,time,kinetic,elastic,tools,total,step_ms,iterations\n");
    let write_frames = |session: &Session, frames: &mut Vec<PathBuf>| -> Result<(), SessionError> {
        for name in &names {
            let m = session.model(Some(name))?;
            for f in &output.frames {
                let p = dir.join(file_name(
                    name,
                    &format!("frame_{:06}.{}", m.steps(), f.extension()),
                ));
                m.export(&p).map_err(|e| e.in_model(name))?;
                frames.push(p);
            }
        }
        Ok(())
    };
    write_frames(session, &mut summary.frames)?;
    let (mut sum_ms, mut max_ms) = (0.0, 0.0f64);
    let mut result = Ok(());
    for k in 0..steps {
        let t0 = std::time::Instant::now();
        let starts: Vec<(u64, f64)> = names
            .iter()
            .map(|n| session.model(Some(n)).map(|m| (m.steps(), m.time())))
            .collect::<Result<_, _>>()?;
        let (reports, lines) = match session.step() {
            Ok(r) => r,
            Err(e) => {
                result = Err(e);
                break;
            }
        };
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        sum_ms += ms;
        max_ms = max_ms.max(ms);
        summary.log.extend(lines.iter().cloned());
        for ((name, r), (step, time)) in names.iter().zip(&reports).zip(&starts) {
            let _ = writeln!(
                csv,
                "{step},{name},{time},{},{},{},{},{},{}",
                r.energy.kinetic,
                r.energy.elastic,
                r.energy.tools,
                r.energy.total(),
                r.seconds * 1e3,
                r.iterations
            );
        }
        summary.steps = k + 1;
        let flow = progress(Progress {
            step: k + 1,
            steps,
            time: session.model(None)?.time(),
            energy: reports.first().map_or(0.0, |r| r.energy.total()),
            events: lines,
        });
        if flow.is_break() {
            summary.stopped = true;
            break;
        }
        let done = session.model(None)?.steps();
        if done % output.every == 0 || k + 1 == steps {
            write_frames(session, &mut summary.frames)?;
        }
    }
    if let Some(c) = &output.csv {
        let p = dir.join(c);
        vclay_io::write_atomic(&p, |w| w.write_all(csv.as_bytes()))
            .map_err(|e| SessionError::io(&p, e))?;
        summary.files.push(p);
    }
    result?;
    if summary.stopped {
        summary.mean_step_ms = sum_ms / summary.steps.max(1) as f64;
        summary.max_step_ms = max_ms;
        return Ok(summary);
    }
    for name in &names {
        let m = session.model(Some(name))?;
        for f in &output.final_files {
            let p = dir.join(file_name(name, f));
            m.export(&p).map_err(|e| e.in_model(name))?;
            summary.files.push(p);
        }
        summary
            .final_energy
            .push((name.clone(), m.energy().total()));
        summary
            .models
            .push(format!("`{name}` ({}): {}", m.kind(), m.summary()));
    }
    summary.mean_step_ms = if summary.steps > 0 {
        sum_ms / summary.steps as f64
    } else {
        0.0
    };
    summary.max_step_ms = max_ms;
    Ok(summary)
}
