//! Running a session for a number of steps and writing what a scenario's `[output]` asks for:
//! frames every `every` steps (and at the first and last step), the final model files and an
//! energy table. `vclay run` and the Python module call [`run`].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::SessionError;
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

/// Runs `steps` session steps into `dir` writing `output`. On divergence the energy table of
/// the steps so far is still written and the error returned; the final models are not.
pub fn run(
    session: &mut Session,
    steps: u64,
    dir: &Path,
    output: &OutputSpec,
    progress: &mut dyn FnMut(Progress),
) -> Result<RunSummary, SessionError> {
    run_stoppable(session, steps, dir, output, &mut |p| {
        progress(p);
        std::ops::ControlFlow::Continue(())
    })
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
    std::fs::create_dir_all(dir).map_err(|e| SessionError::io(dir, e))?;
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
