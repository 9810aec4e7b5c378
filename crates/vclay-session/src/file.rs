//! Session files: a whole session (every model with its current state, rest shape, velocities,
//! materials, fixed set and active tools; the scheduled commands; the command log with the
//! step and time of each command; and what a run writes) as versioned JSON
//! (`docs/formats.md` section 10).
//!
//! Floats are written by serde_json's shortest round-trip form and read back with its exact
//! parser (`float_roundtrip`), so a loaded session continues bit for bit as the saved one
//! would have. Saving goes to a temporary file renamed over the target. A file of a newer
//! format version, an unknown model kind, a command addressed to a model that is not in the
//! file, or a model whose parts do not fit together is an error naming the file and the place
//! (JSON line, or the path of the entry such as `models[1].kind`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::SessionError;
use crate::model::ModelKind;
use crate::scenario::OutputSpec;
use crate::session::{LogEntry, Session, Timed};

/// The `format` value of a session file.
pub const FORMAT: &str = "vclay-session";
/// The format version this build writes and the newest it reads.
pub const VERSION: u32 = 1;

/// What a scenario run needs to go on from a session file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// The scenario's name (default output folder `./vclay-run/<name>/`).
    pub name: String,
    /// Step count of the first model at which the scenario ends.
    pub end_step: u64,
    /// What the run writes.
    pub output: OutputSpec,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedModel {
    name: String,
    kind: String,
    state: serde_json::Value,
    /// Plastic flow after each step (absent: off; files without it read as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    plasticity: Option<SavedPlasticity>,
}

/// [`vclay_core::Plasticity`] in a session file.
#[derive(Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedPlasticity {
    rate: f64,
    yield_distance: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedSession {
    format: String,
    version: u32,
    models: Vec<SavedModel>,
    #[serde(default)]
    schedule: Vec<Timed>,
    #[serde(default)]
    log: Vec<LogEntry>,
    #[serde(default)]
    run: Option<RunInfo>,
}

/// The session as a JSON value.
pub fn to_value(
    session: &Session,
    run: Option<&RunInfo>,
) -> Result<serde_json::Value, SessionError> {
    let (models, schedule, log) = session.parts();
    let mut saved = Vec::with_capacity(models.len());
    for (name, m) in models {
        saved.push(SavedModel {
            name: name.to_string(),
            kind: m.kind().name().to_string(),
            state: m.save().map_err(|e| e.in_model(name))?,
            plasticity: session.plasticity(Some(name)).map(|p| SavedPlasticity {
                rate: p.rate,
                yield_distance: p.yield_distance,
            }),
        });
    }
    serde_json::to_value(SavedSession {
        format: FORMAT.into(),
        version: VERSION,
        models: saved,
        schedule: schedule.to_vec(),
        log: log.to_vec(),
        run: run.cloned(),
    })
    .map_err(SessionError::kernel)
}

/// Writes the session to `path` (atomically).
pub fn save(path: &Path, session: &Session, run: Option<&RunInfo>) -> Result<(), SessionError> {
    let v = to_value(session, run)?;
    vclay_io::write_atomic(path, |w| {
        serde_json::to_writer(&mut *w, &v).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(|e| SessionError::io(path, e))
}

/// Reads a session file.
pub fn load(path: &Path) -> Result<(Session, Option<RunInfo>), SessionError> {
    let text = std::fs::read_to_string(path).map_err(|e| SessionError::io(path, e))?;
    parse(&text, &path.display().to_string())
}

/// Parses session file `text` (`file` names it in errors).
pub fn parse(text: &str, file: &str) -> Result<(Session, Option<RunInfo>), SessionError> {
    let err = |line: usize, key: &str, what: String| SessionError::File {
        file: file.to_string(),
        line,
        key: key.to_string(),
        what,
    };
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| err(e.line(), "syntax", e.to_string()))?;
    // Format and version first, so a newer file says so instead of failing on a new field.
    match v.get("format").and_then(|f| f.as_str()) {
        Some(FORMAT) => {}
        other => {
            return Err(err(
                0,
                "format",
                format!("{other:?} is not a vclay session file (expected \"{FORMAT}\")"),
            ));
        }
    }
    match v.get("version").and_then(|x| x.as_u64()) {
        Some(n) if n as u32 == VERSION && n <= u32::MAX as u64 => {}
        Some(n) if n > VERSION as u64 => {
            return Err(err(
                0,
                "version",
                format!(
                    "the file is format version {n}; this vclay reads up to version {VERSION} (update vclay)"
                ),
            ));
        }
        other => {
            return Err(err(
                0,
                "version",
                format!("{other:?} is not a version this vclay reads ({VERSION})"),
            ));
        }
    }
    // Deserialized with the path of a bad value (`models[0].state: missing field ...`).
    let saved: SavedSession = serde_path_to_error::deserialize(v).map_err(|e| {
        let path = e.path().to_string();
        err(
            0,
            if path == "." { "session" } else { &path },
            e.into_inner().to_string(),
        )
    })?;
    let mut session = Session::new();
    for (i, m) in saved.models.iter().enumerate() {
        let kind = ModelKind::from_name(&m.kind).ok_or_else(|| {
            err(
                0,
                &format!("models[{i}].kind"),
                format!(
                    "unknown model kind \"{}\"; known kinds: {}",
                    m.kind,
                    ModelKind::names()
                ),
            )
        })?;
        let model = crate::models::load(kind, &m.state)
            .map_err(|e| err(0, &format!("models[{i}] ({})", m.name), e.to_string()))?;
        session
            .add_model(&m.name, model)
            .map_err(|e| err(0, &format!("models[{i}].name"), e.to_string()))?;
        if let Some(p) = m.plasticity {
            let key = format!("models[{i}].plasticity");
            let p = vclay_core::Plasticity::new(p.rate, p.yield_distance)
                .map_err(|what| err(0, &key, what))?;
            session
                .set_plasticity(Some(&m.name), Some(p))
                .map_err(|e| err(0, &key, e.to_string()))?;
        }
    }
    for (k, t) in saved.schedule.iter().enumerate() {
        if let Some(name) = &t.command.model
            && session.model(Some(name)).is_err()
        {
            return Err(err(
                0,
                &format!("schedule[{k}].model"),
                format!("no model named `{name}` in the file"),
            ));
        }
        // The one check of a scheduled edit (the kind takes it, its values), as for a scenario:
        // it is not checked again when it fires.
        let target = session.model(t.command.model.as_deref())?;
        crate::session::check_edit(target, &t.command.edit, t.at)
            .map_err(|e| err(0, &format!("schedule[{k}].{}", e.key), e.what))?;
    }
    for (k, l) in saved.log.iter().enumerate() {
        if session.model(Some(&l.model)).is_err() {
            return Err(err(
                0,
                &format!("log[{k}].model"),
                format!("no model named `{}` in the file", l.model),
            ));
        }
    }
    if saved.models.is_empty() {
        return Err(err(0, "models", "the session has no models".into()));
    }
    let mut schedule = saved.schedule;
    schedule.sort_by(|a, b| a.at.total_cmp(&b.at));
    session.set_history(schedule, saved.log);
    Ok((session, saved.run))
}
