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
use crate::models::{ModelSpec, Spec, SpecError};
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
    /// resolves relative file names): TOML into the file's tables, each model's tables into a
    /// typed [`ModelSpec`], one validation pass, then the session.
    pub fn parse(text: &str, file: &str, stem: &str, base: &Path) -> Result<Self, SessionError> {
        let src = Src { file, text };
        let f = src.read()?;
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
        let mut session = Session::new();
        for (mname, spec, span) in src.model_specs(&f, &sim, sim_span.clone(), base)? {
            let model = spec
                .build(base)
                .map_err(|e| src.err(&span(&e), &e.key, e.what))?;
            session
                .add_model(&mname, model)
                .map_err(|e| src.err(&f.model.span(), "name", e))?;
        }
        let first_dt = session.model(None)?.dt();
        let steps = src.run_length(steps_key, duration_key, first_dt, &sim_span)?;
        let timed = src.timeline(&f.timeline, &session)?;
        session.push_schedule(timed);
        let output = src.output(f.output, &session)?;
        Ok(Self {
            session,
            name,
            steps,
            output,
        })
    }
}

/// Where a model's spec error lies in the file: the span of the table the error names.
type SpanOf = Box<dyn Fn(&SpecError) -> Range<usize>>;

impl Src<'_> {
    /// The file's tables (TOML syntax and the top-level keys).
    fn read(&self) -> Result<File, SessionError> {
        toml::from_str(self.text).map_err(|e| {
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
                file: self.file.to_string(),
                line: vclay_core::text::line_at(self.text, span.start),
                key: field.unwrap_or_else(|| "syntax".into()),
                what,
            }
        })
    }

    /// `[model]` or the `[[model]]` entries as (table, in an array).
    fn model_tables(&self, f: &File) -> Result<Vec<(toml::Table, bool)>, SessionError> {
        let mspan = f.model.span();
        match f.model.get_ref() {
            toml::Value::Table(t) => Ok(vec![(t.clone(), false)]),
            toml::Value::Array(a) => {
                if a.is_empty() {
                    return Err(self.err(&mspan, "model", "no models"));
                }
                if a.len() > MAX_MODELS {
                    return Err(self.err(
                        &mspan,
                        "model",
                        format!("{} models; at most {MAX_MODELS}", a.len()),
                    ));
                }
                a.iter()
                    .map(|m| match m.as_table() {
                        Some(t) => Ok((t.clone(), true)),
                        None => Err(self.err(&mspan, "model", "each [[model]] entry is a table")),
                    })
                    .collect()
            }
            _ => Err(self.err(&mspan, "model", "must be a table")),
        }
    }

    /// Each model's name, typed spec, and where its errors lie.
    fn model_specs(
        &self,
        f: &File,
        sim: &toml::Table,
        sim_span: Range<usize>,
        base: &Path,
    ) -> Result<Vec<(String, ModelSpec, SpanOf)>, SessionError> {
        let mspan = f.model.span();
        let entries = self.model_tables(f)?;
        let multi = entries.len() > 1 || entries.first().is_some_and(|e| e.1);
        if multi && f.material.is_some() {
            let span = f.material.as_ref().map(Spanned::span).unwrap_or(0..0);
            return Err(self.err(
                &span,
                "material",
                "with [[model]] entries, give each its own [model.material]",
            ));
        }
        let mut out = Vec::with_capacity(entries.len());
        for (k, (mut t, in_array)) in entries.into_iter().enumerate() {
            let kind = self.kind_of(&t, &mspan)?;
            let mname = match t.get("name") {
                Some(toml::Value::String(s)) => s.clone(),
                Some(_) => return Err(self.err(&mspan, "name", "must be a string")),
                None if multi => format!("model{k}"),
                None => kind.name().to_string(),
            };
            let (mat, msim) = if in_array {
                let mut sub = |key: &str| match t.remove(key) {
                    Some(toml::Value::Table(m)) => Ok(Some(m)),
                    Some(_) => Err(self.err(&mspan, key, "must be a table")),
                    None => Ok(None),
                };
                (sub("material")?, sub("simulation")?)
            } else {
                (
                    f.material.as_ref().map(|m| m.get_ref().clone()),
                    Some(sim.clone()),
                )
            };
            let tables = Spec {
                model: &t,
                material: mat.as_ref(),
                simulation: msim.as_ref().filter(|s| !s.is_empty() || !in_array),
                base,
            };
            // A model error points at the table it names (`[[material.cells]]` entries follow
            // the [material] table's own span).
            let (mat_span, end) = (f.material.as_ref().map(Spanned::span), self.text.len());
            let (mspan2, sspan) = (mspan.clone(), sim_span.clone());
            let span: SpanOf = Box::new(move |e: &SpecError| match e.table.as_str() {
                "material" if !in_array && e.key == "cells" => {
                    mat_span.clone().map_or(mspan2.clone(), |m| m.start..end)
                }
                "material" if !in_array => mat_span.clone().unwrap_or(mspan2.clone()),
                "simulation" if !in_array => sspan.clone(),
                _ => mspan2.clone(),
            });
            let spec = ModelSpec::from_tables(kind, &tables)
                .map_err(|e| self.err(&span(&e), &e.key, e.what))?;
            out.push((mname, spec, span));
        }
        Ok(out)
    }

    /// The model kind a model table names.
    fn kind_of(&self, t: &toml::Table, mspan: &Range<usize>) -> Result<ModelKind, SessionError> {
        let kind_name = match t.get("kind") {
            Some(toml::Value::String(s)) => s.clone(),
            Some(_) => return Err(self.err(mspan, "kind", "must be a string")),
            None => {
                return Err(self.err(
                    mspan,
                    "kind",
                    format!("missing; one of {}", ModelKind::names()),
                ));
            }
        };
        ModelKind::from_name(&kind_name).ok_or_else(|| {
            self.err(
                mspan,
                "kind",
                format!(
                    "unknown model kind \"{kind_name}\"; known kinds: {}",
                    ModelKind::names()
                ),
            )
        })
    }

    /// The run length in steps from `steps` or `duration` (default [`DEFAULT_DURATION`]).
    fn run_length(
        &self,
        steps_key: Option<toml::Value>,
        duration_key: Option<toml::Value>,
        first_dt: f64,
        sim_span: &Range<usize>,
    ) -> Result<u64, SessionError> {
        match (steps_key, duration_key) {
            (Some(_), Some(_)) => Err(self.err(
                sim_span,
                "duration",
                "give either `steps` or `duration`, not both",
            )),
            (Some(n), None) => match n.as_integer() {
                Some(n) if n >= 0 && (n as u64) <= MAX_STEPS => Ok(n as u64),
                _ => Err(self.err(
                    sim_span,
                    "steps",
                    format!("{n} must be a whole number from 0 to {MAX_STEPS}"),
                )),
            },
            (None, d) => {
                let d = match d {
                    None => DEFAULT_DURATION,
                    Some(v) => v
                        .as_float()
                        .or_else(|| v.as_integer().map(|i| i as f64))
                        .ok_or_else(|| {
                            self.err(sim_span, "duration", "must be a number of seconds")
                        })?,
                };
                steps_for_duration(d, first_dt).map_err(|e| self.err(sim_span, "duration", e))
            }
        }
    }

    /// The timeline entries as timed commands, each checked once here.
    fn timeline(
        &self,
        entries: &[Spanned<toml::Table>],
        session: &Session,
    ) -> Result<Vec<Timed>, SessionError> {
        if entries.len() > MAX_TIMELINE {
            return Err(self.err(
                &(0..0),
                "timeline",
                format!("{} entries; at most {MAX_TIMELINE}", entries.len()),
            ));
        }
        let mut timed = Vec::with_capacity(entries.len());
        for entry in entries {
            let span = entry.span();
            let mut t = entry.get_ref().clone();
            let at = match t.remove("at") {
                None => 0.0,
                Some(v) => v
                    .as_float()
                    .or_else(|| v.as_integer().map(|i| i as f64))
                    .ok_or_else(|| self.err(&span, "at", "must be a time in seconds"))?,
            };
            if !(at.is_finite() && at >= 0.0) {
                return Err(self.err(&span, "at", format!("{at} must be >= 0 and finite")));
            }
            let model = match t.remove("model") {
                None => None,
                Some(toml::Value::String(s)) => Some(s),
                Some(_) => return Err(self.err(&span, "model", "must be a model name")),
            };
            if let Some(m) = &model
                && session.model(Some(m)).is_err()
            {
                return Err(self.err(
                    &span,
                    "model",
                    format!(
                        "no model named `{m}` (the scenario has: {})",
                        session.model_names().join(", ")
                    ),
                ));
            }
            if !t.contains_key("action") {
                return Err(self.err(&span, "action", "missing"));
            }
            let mut edit: Edit = crate::models::typed("timeline", &t).map_err(|e| {
                let key = if e.key == "timeline" {
                    "action".to_string()
                } else {
                    e.key
                };
                self.err(&span, &key, e.what)
            })?;
            // A rope's cursor path starts at the entry's time.
            if let Edit::Rope { start, .. } = &mut edit
                && start.is_none()
            {
                *start = Some(at);
            }
            let target = session.model(model.as_deref())?;
            crate::session::check_edit(target, &edit, at)
                .map_err(|e| self.err(&span, e.key, e.what))?;
            timed.push(Timed {
                at,
                command: Command { model, edit },
            });
        }
        Ok(timed)
    }

    /// `[output]`, checked against the formats every model writes (so that a run does not
    /// fail at its end).
    fn output(
        &self,
        o: Option<Spanned<OutputKeys>>,
        session: &Session,
    ) -> Result<OutputSpec, SessionError> {
        let (ospan, out) = match o {
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
            return Err(self.err(&ospan, "every", "must be at least 1"));
        }
        for name in &out.frames {
            let Some(format) = FrameFormat::from_name(name) else {
                return Err(self.err(
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
                return Err(self.err(
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
                        .ok_or_else(|| self.err(&ospan, "final", "must be file names"))
                })
                .collect::<Result<_, _>>()?,
            Some(_) => {
                return Err(self.err(&ospan, "final", "must be a file name or a list of them"));
            }
        };
        self.check_output_names(&output, &ospan)?;
        for n in session.model_names() {
            let m = session.model(Some(n))?;
            let formats = m.export_formats();
            let list = |q: &str| {
                formats
                    .iter()
                    .map(|e| format!("{q}{e}{}", if q == "." { "" } else { q }))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            for f in &output.final_files {
                let ext = crate::model::extension(Path::new(f));
                if !formats.contains(&ext.as_str()) {
                    let what = format!("\"{f}\": a {} model writes {}", m.kind(), list("."));
                    return Err(self.err(&ospan, "final", what));
                }
            }
            for f in &output.frames {
                if !formats.contains(&f.extension()) {
                    let what = format!(
                        "\"{}\": a {} model writes {}",
                        f.extension(),
                        m.kind(),
                        list("\"")
                    );
                    return Err(self.err(&ospan, "frames", what));
                }
            }
        }
        Ok(output)
    }

    /// Output file names: plain names, none named twice.
    fn check_output_names(
        &self,
        output: &OutputSpec,
        ospan: &Range<usize>,
    ) -> Result<(), SessionError> {
        let mut names: Vec<&String> = output.final_files.iter().chain(&output.csv).collect();
        names.sort();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(self.err(
                ospan,
                "final",
                format!("\"{}\" is named by two outputs", w[0]),
            ));
        }
        for f in output.final_files.iter().chain(&output.csv) {
            if f.is_empty() || f.contains(['/', '\\']) {
                return Err(self.err(
                    ospan,
                    if output.csv.as_ref() == Some(f) {
                        "csv"
                    } else {
                        "final"
                    },
                    format!("\"{f}\" must be a plain file name (outputs go to the run's folder)"),
                ));
            }
        }
        Ok(())
    }
}

/// Steps of `dt` that make `duration` seconds (rounded), checked against [`MAX_STEPS`]; the
/// same rule wherever a duration is given (scenario `duration`, `vclay run --until`, Python).
pub fn steps_for_duration(duration: f64, dt: f64) -> Result<u64, String> {
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(format!("{duration} must be non-negative"));
    }
    let n = (duration / dt).round();
    if n > MAX_STEPS as f64 {
        return Err(format!(
            "{duration} s at dt = {dt} is {n} steps; at most {MAX_STEPS}"
        ));
    }
    Ok(n as u64)
}

/// Checks a step count given anywhere (scenario `steps`, `vclay run --steps`, Python's
/// `run(n)`) against [`MAX_STEPS`].
pub fn check_steps(steps: u64) -> Result<u64, String> {
    if steps > MAX_STEPS {
        return Err(format!(
            "{steps} steps; at most {MAX_STEPS} (a run of 10^9 steps of the smallest model takes days)"
        ));
    }
    Ok(steps)
}

/// The default output folder of a run: `./vclay-run/<name>/`.
pub fn default_out_dir(name: &str) -> PathBuf {
    PathBuf::from("vclay-run").join(name)
}
