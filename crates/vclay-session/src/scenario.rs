//! The one scenario format: a session's initial models plus a timeline of commands (TOML;
//! `docs/formats.md` section 8 documents every key).
//!
//! ```toml
//! [model]                 # or [[model]] entries with `name`, each with its own
//! kind = "subdivision-solid"   #   [model.material] and [model.simulation]
//! primitive = "box"
//! [material]              # kind-specific keys
//! [simulation]            # `steps` or `duration` (run length) + kind-specific keys
//! [[timeline]]            # any number: `at` (s, default 0), optional `model`, an `action`
//! at = 0.0                #   and its keys: see `crate::command::Edit`
//! action = "rope"
//! from = [1.0, 1.0, 1.0]
//! [output]                # frames, every, final, csv
//! ```
//!
//! Parsing goes in one pass: the TOML parser reports syntax errors with their place; each
//! model's tables go to its kind's builder ([`crate::models::build`]); each timeline entry
//! becomes a [`Timed`] command checked by [`crate::Edit::validate`]. Every error names the
//! file, the line and the key.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::command::{Command, Edit};
use crate::error::SessionError;
use crate::model::ModelKind;
use crate::models::{Spec, SpecError};
use crate::session::{Session, Timed};

/// Default run length when a scenario gives neither `steps` nor `duration` (s).
pub const DEFAULT_DURATION: f64 = 1.0;
/// Default `[output] every`.
pub const DEFAULT_FRAME_EVERY: u64 = 50;
/// Most steps a scenario may ask for (a run of 10^9 steps of the smallest model takes days).
pub const MAX_STEPS: u64 = 100_000_000;
/// Most models in one scenario.
pub const MAX_MODELS: usize = 64;
/// Most timeline entries.
pub const MAX_TIMELINE: usize = 100_000;

/// Frame file formats of `[output] frames`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    /// Wavefront OBJ.
    Obj,
    /// ASCII PLY.
    Ply,
    /// ASCII STL.
    Stl,
    /// VTK unstructured grid (solids: data lattice with point data).
    Vtu,
    /// glTF binary.
    Glb,
}

impl FrameFormat {
    /// Every format.
    pub const ALL: [FrameFormat; 5] = [
        FrameFormat::Obj,
        FrameFormat::Ply,
        FrameFormat::Stl,
        FrameFormat::Vtu,
        FrameFormat::Glb,
    ];
    /// File extension.
    pub fn extension(self) -> &'static str {
        match self {
            FrameFormat::Obj => "obj",
            FrameFormat::Ply => "ply",
            FrameFormat::Stl => "stl",
            FrameFormat::Vtu => "vtu",
            FrameFormat::Glb => "glb",
        }
    }
    /// The format with extension `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.extension() == name)
    }
}

/// What a run writes (`[output]`), kept in session files so a continued run writes the same.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutputSpec {
    /// Frame formats.
    #[serde(default)]
    pub frames: Vec<FrameFormat>,
    /// A frame every this many steps (and at the first and last step).
    pub every: u64,
    /// Final model files written at the end (per model; names carry the model name when the
    /// session has several).
    #[serde(default)]
    pub final_files: Vec<String>,
    /// Energy table, one row per step and model.
    #[serde(default)]
    pub csv: Option<String>,
}

/// A parsed scenario: the session (models and scheduled timeline), its name, the run length
/// and the outputs.
#[derive(Debug)]
pub struct Scenario {
    /// The session, with the timeline scheduled.
    pub session: Session,
    /// The scenario's name (the file stem): `vclay run` writes to `./vclay-run/<name>/`.
    pub name: String,
    /// Steps to run.
    pub steps: u64,
    /// Outputs.
    pub output: OutputSpec,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    name: Option<String>,
    model: Spanned<toml::Value>,
    #[serde(default)]
    material: Option<Spanned<toml::Table>>,
    #[serde(default)]
    simulation: Option<Spanned<toml::Table>>,
    #[serde(default)]
    timeline: Vec<Spanned<toml::Table>>,
    #[serde(default)]
    output: Option<Spanned<OutputKeys>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputKeys {
    #[serde(default)]
    frames: Vec<String>,
    #[serde(default)]
    every: Option<u64>,
    #[serde(default, rename = "final")]
    final_files: Option<toml::Value>,
    #[serde(default)]
    csv: Option<String>,
}

struct Src<'a> {
    file: &'a str,
    text: &'a str,
}

impl Src<'_> {
    fn err(&self, span: &Range<usize>, key: &str, what: impl std::fmt::Display) -> SessionError {
        SessionError::File {
            file: self.file.to_string(),
            line: if span.is_empty() && span.start == 0 {
                0
            } else {
                vclay_core::text::key_line(self.text, span, key)
            },
            key: key.to_string(),
            what: what.to_string(),
        }
    }
}

/// The model kind named in a scenario's `[model]` (or first `[[model]]`) table, without
/// parsing the rest (for front ends that dispatch on it).
pub fn model_kind(text: &str) -> Option<String> {
    let v: toml::Table = toml::from_str(text).ok()?;
    let m = v.get("model")?;
    let t = match m {
        toml::Value::Array(a) => a.first()?.as_table()?,
        toml::Value::Table(t) => t,
        _ => return None,
    };
    t.get("kind")?.as_str().map(str::to_string)
}

impl Scenario {
    /// Reads and parses the scenario at `path`.
    pub fn from_file(path: &Path) -> Result<Self, SessionError> {
        let text = std::fs::read_to_string(path).map_err(|e| SessionError::io(path, e))?;
        let name = path.display().to_string();
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "scenario".into());
        Self::parse(&text, &name, &stem, path.parent().unwrap_or(Path::new(".")))
    }

    /// Parses scenario `text` (`file` names it in errors, `stem` is its default name, `base`
    /// resolves relative file names).
    pub fn parse(text: &str, file: &str, stem: &str, base: &Path) -> Result<Self, SessionError> {
        let src = Src { file, text };
        let f: File = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let msg = e.message().to_string();
            let field = msg
                .strip_prefix("unknown field `")
                .and_then(|r| r.split('`').next())
                .map(str::to_string);
            let what = if field.as_deref() == Some("dir") {
                format!("{msg}; a run writes to `vclay run --out DIR`, else ./vclay-run/<scenario name>/")
            } else {
                msg
            };
            SessionError::File {
                file: file.to_string(),
                line: vclay_core::text::line_at(text, span.start),
                key: field.unwrap_or_else(|| "syntax".into()),
                what,
            }
        })?;
        let name = f.name.clone().unwrap_or_else(|| stem.to_string());
        if name.is_empty() || name.contains(['/', '\\']) || name == "." || name == ".." {
            return Err(src.err(
                &(0..0),
                "name",
                format!("\"{name}\" cannot name an output folder"),
            ));
        }
        // Run length: `steps` / `duration` are the scenario's; the rest of [simulation] is the
        // model's.
        let (sim_span, mut sim) = match &f.simulation {
            Some(s) => (s.span(), s.get_ref().clone()),
            None => (0..0, toml::Table::new()),
        };
        let steps_key = sim.remove("steps");
        let duration_key = sim.remove("duration");
        // Models.
        let mspan = f.model.span();
        let mut session = Session::new();
        let entries: Vec<(toml::Table, bool)> = match f.model.get_ref() {
            toml::Value::Table(t) => vec![(t.clone(), false)],
            toml::Value::Array(a) => {
                if a.is_empty() {
                    return Err(src.err(&mspan, "model", "no models"));
                }
                if a.len() > MAX_MODELS {
                    return Err(src.err(
                        &mspan,
                        "model",
                        format!("{} models; at most {MAX_MODELS}", a.len()),
                    ));
                }
                let mut v = Vec::new();
                for m in a {
                    match m.as_table() {
                        Some(t) => v.push((t.clone(), true)),
                        None => {
                            return Err(src.err(
                                &mspan,
                                "model",
                                "each [[model]] entry is a table",
                            ));
                        }
                    }
                }
                v
            }
            _ => return Err(src.err(&mspan, "model", "must be a table")),
        };
        let multi = entries.len() > 1 || entries.first().is_some_and(|e| e.1);
        if multi && f.material.is_some() {
            let span = f.material.as_ref().map(Spanned::span).unwrap_or(0..0);
            return Err(src.err(
                &span,
                "material",
                "with [[model]] entries, give each its own [model.material]",
            ));
        }
        for (k, (mut t, in_array)) in entries.into_iter().enumerate() {
            let kind_name = match t.get("kind") {
                Some(toml::Value::String(s)) => s.clone(),
                Some(_) => return Err(src.err(&mspan, "kind", "must be a string")),
                None => {
                    return Err(src.err(
                        &mspan,
                        "kind",
                        format!("missing; one of {}", ModelKind::names()),
                    ));
                }
            };
            let kind = ModelKind::from_name(&kind_name).ok_or_else(|| {
                src.err(
                    &mspan,
                    "kind",
                    format!(
                        "unknown model kind \"{kind_name}\"; known kinds: {}",
                        ModelKind::names()
                    ),
                )
            })?;
            let mname = match t.get("name") {
                Some(toml::Value::String(s)) => s.clone(),
                Some(_) => return Err(src.err(&mspan, "name", "must be a string")),
                None if multi => format!("model{k}"),
                None => kind.name().to_string(),
            };
            let (mat, msim) = if in_array {
                let mat = match t.remove("material") {
                    Some(toml::Value::Table(m)) => Some(m),
                    Some(_) => return Err(src.err(&mspan, "material", "must be a table")),
                    None => None,
                };
                let ms = match t.remove("simulation") {
                    Some(toml::Value::Table(m)) => Some(m),
                    Some(_) => return Err(src.err(&mspan, "simulation", "must be a table")),
                    None => None,
                };
                (mat, ms)
            } else {
                (
                    f.material.as_ref().map(|m| m.get_ref().clone()),
                    Some(sim.clone()),
                )
            };
            let spec = Spec {
                model: &t,
                material: mat.as_ref(),
                simulation: msim.as_ref().filter(|s| !s.is_empty() || !in_array),
                base,
            };
            let model = crate::models::build(kind, &spec).map_err(|e: SpecError| {
                let span = match e.table.as_str() {
                    // `[[material.cells]]` entries follow the [material] table's own span.
                    "material" if !in_array && e.key == "cells" => f
                        .material
                        .as_ref()
                        .map_or(mspan.clone(), |m| m.span().start..text.len()),
                    "material" if !in_array => f
                        .material
                        .as_ref()
                        .map(Spanned::span)
                        .unwrap_or(mspan.clone()),
                    "simulation" if !in_array => sim_span.clone(),
                    _ => mspan.clone(),
                };
                src.err(&span, &e.key, e.what)
            })?;
            session
                .add_model(&mname, model)
                .map_err(|e| src.err(&mspan, "name", e))?;
        }
        // Run length.
        let first_dt = session.model(None)?.dt();
        let steps = match (steps_key, duration_key) {
            (Some(_), Some(_)) => {
                return Err(src.err(
                    &sim_span,
                    "duration",
                    "give either `steps` or `duration`, not both",
                ));
            }
            (Some(n), None) => match n.as_integer() {
                Some(n) if n >= 0 && (n as u64) <= MAX_STEPS => n as u64,
                _ => {
                    return Err(src.err(
                        &sim_span,
                        "steps",
                        format!("{n} must be a whole number from 0 to {MAX_STEPS}"),
                    ));
                }
            },
            (None, d) => {
                let d = match d {
                    None => DEFAULT_DURATION,
                    Some(v) => v
                        .as_float()
                        .or_else(|| v.as_integer().map(|i| i as f64))
                        .ok_or_else(|| {
                            src.err(&sim_span, "duration", "must be a number of seconds")
                        })?,
                };
                if !(d.is_finite() && d >= 0.0) {
                    return Err(src.err(
                        &sim_span,
                        "duration",
                        format!("{d} must be non-negative"),
                    ));
                }
                let n = (d / first_dt).round();
                if n > MAX_STEPS as f64 {
                    return Err(src.err(
                        &sim_span,
                        "duration",
                        format!("{d} s at dt = {first_dt} is {n} steps; at most {MAX_STEPS}"),
                    ));
                }
                n as u64
            }
        };
        // Timeline.
        if f.timeline.len() > MAX_TIMELINE {
            return Err(src.err(
                &(0..0),
                "timeline",
                format!("{} entries; at most {MAX_TIMELINE}", f.timeline.len()),
            ));
        }
        let mut timed = Vec::with_capacity(f.timeline.len());
        for entry in &f.timeline {
            let span = entry.span();
            let mut t = entry.get_ref().clone();
            let at = match t.remove("at") {
                None => 0.0,
                Some(v) => v
                    .as_float()
                    .or_else(|| v.as_integer().map(|i| i as f64))
                    .ok_or_else(|| src.err(&span, "at", "must be a time in seconds"))?,
            };
            if !(at.is_finite() && at >= 0.0) {
                return Err(src.err(&span, "at", format!("{at} must be >= 0 and finite")));
            }
            let model = match t.remove("model") {
                None => None,
                Some(toml::Value::String(s)) => Some(s),
                Some(_) => return Err(src.err(&span, "model", "must be a model name")),
            };
            if let Some(m) = &model
                && session.model(Some(m)).is_err()
            {
                return Err(src.err(
                    &span,
                    "model",
                    format!(
                        "no model named `{m}` (the scenario has: {})",
                        session.model_names().join(", ")
                    ),
                ));
            }
            if !t.contains_key("action") {
                return Err(src.err(&span, "action", "missing"));
            }
            let mut edit: Edit = crate::models::typed("timeline", &t).map_err(|e| {
                let key = if e.key == "timeline" {
                    "action".to_string()
                } else {
                    e.key
                };
                src.err(&span, &key, e.what)
            })?;
            // A rope's cursor path starts at the entry's time.
            if let Edit::Rope { start, .. } = &mut edit
                && start.is_none()
            {
                *start = Some(at);
            }
            edit.validate(at).map_err(|r| {
                let key = r.split('`').nth(1).unwrap_or("action").to_string();
                src.err(&span, &key, r)
            })?;
            timed.push(Timed {
                at,
                command: Command { model, edit },
            });
        }
        session.schedule_commands(timed)?;
        // Output.
        let (ospan, out) = match f.output {
            Some(o) => (o.span(), o.into_inner()),
            None => (0..0, OutputKeys::default()),
        };
        let mut output = OutputSpec {
            frames: Vec::new(),
            every: out.every.unwrap_or(DEFAULT_FRAME_EVERY),
            final_files: Vec::new(),
            csv: out.csv,
        };
        if output.every == 0 {
            return Err(src.err(&ospan, "every", "must be at least 1"));
        }
        for name in &out.frames {
            let Some(format) = FrameFormat::from_name(name) else {
                return Err(src.err(
                    &ospan,
                    "frames",
                    format!(
                        "unknown frame format \"{name}\"; expected one of {}",
                        FrameFormat::ALL
                            .map(|f| format!("\"{}\"", f.extension()))
                            .join(", ")
                    ),
                ));
            };
            if output.frames.contains(&format) {
                return Err(src.err(
                    &ospan,
                    "frames",
                    format!("frame format \"{name}\" is listed twice"),
                ));
            }
            output.frames.push(format);
        }
        output.final_files = match out.final_files {
            None => Vec::new(),
            Some(toml::Value::String(s)) => vec![s],
            Some(toml::Value::Array(a)) => a
                .iter()
                .map(|v| {
                    v.as_str()
                        .map(str::to_string)
                        .ok_or_else(|| src.err(&ospan, "final", "must be file names"))
                })
                .collect::<Result<_, _>>()?,
            Some(_) => {
                return Err(src.err(&ospan, "final", "must be a file name or a list of them"));
            }
        };
        let mut names: Vec<&String> = output.final_files.iter().chain(&output.csv).collect();
        names.sort();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(src.err(
                &ospan,
                "final",
                format!("\"{}\" is named by two outputs", w[0]),
            ));
        }
        for f in output.final_files.iter().chain(&output.csv) {
            if f.is_empty() || f.contains(['/', '\\']) {
                return Err(src.err(
                    &ospan,
                    if output.csv.as_ref() == Some(f) {
                        "csv"
                    } else {
                        "final"
                    },
                    format!("\"{f}\" must be a plain file name (outputs go to the run's folder)"),
                ));
            }
        }
        // Final files and frames must be formats every model writes (checked now, so that a
        // run does not fail at its end).
        for n in session.model_names() {
            let m = session.model(Some(n))?;
            let formats = m.export_formats();
            for f in &output.final_files {
                let ext = crate::model::extension(Path::new(f));
                if !formats.contains(&ext.as_str()) {
                    return Err(src.err(
                        &ospan,
                        "final",
                        format!(
                            "\"{f}\": a {} model writes {}",
                            m.kind(),
                            formats
                                .iter()
                                .map(|e| format!(".{e}"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
            }
            for f in &output.frames {
                if !formats.contains(&f.extension()) {
                    return Err(src.err(
                        &ospan,
                        "frames",
                        format!(
                            "\"{}\": a {} model writes {}",
                            f.extension(),
                            m.kind(),
                            formats
                                .iter()
                                .map(|e| format!("\"{e}\""))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(Self {
            session,
            name,
            steps,
            output,
        })
    }
}

/// The default output folder of a run: `./vclay-run/<name>/`.
pub fn default_out_dir(name: &str) -> PathBuf {
    PathBuf::from("vclay-run").join(name)
}
