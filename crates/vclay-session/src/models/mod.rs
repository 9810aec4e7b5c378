//! The model kinds behind [`crate::Model`]: how each is built from a scenario's tables and
//! rebuilt from a session file.

/// A scenario table's keys as a typed value: serde with unknown keys refused, `Default` (every
/// key absent), documented once here: each field is the key of the same name in
/// `docs/formats.md` section 8 (absent: the documented default).
macro_rules! scenario_keys {
    ($(#[$meta:meta])* pub struct $name:ident { $($body:tt)* }) => {
        $(#[$meta])*
        ///
        /// Each field is the key of the same name in `docs/formats.md` section 8 (absent: the
        /// documented default).
        #[allow(missing_docs)]
        #[derive(Debug, Default, serde::Deserialize, Clone, PartialEq, serde::Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name { $($body)* }
    };
}

pub mod dnurbs;
pub mod dnurbs_patches;
pub mod dnurbs_tri;
mod engine;
pub mod ffd;
pub mod generalized;
pub mod part;
pub mod pde;
mod saved;
pub mod solid;

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::SessionError;
use crate::model::{Model, ModelKind};

/// The tables of a scenario that describe one model.
#[derive(Debug, Clone, Copy)]
pub struct Spec<'a> {
    /// `[model]` (or one `[[model]]` entry).
    pub model: &'a toml::Table,
    /// `[material]`, if present.
    pub material: Option<&'a toml::Table>,
    /// `[simulation]` without the run-length keys (`steps`, `duration`), if present.
    pub simulation: Option<&'a toml::Table>,
    /// Folder that relative file names are resolved against (the scenario's folder).
    pub base: &'a Path,
}

/// An error in a model's tables: which table, which key, what is wrong (the scenario parser
/// adds the file and line).
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError {
    /// `model`, `material` or `simulation`.
    pub table: String,
    /// The key.
    pub key: String,
    /// What is wrong.
    pub what: String,
}

impl SpecError {
    /// An error at `table.key`.
    pub fn new(table: &str, key: &str, what: impl std::fmt::Display) -> Self {
        Self {
            table: table.to_string(),
            key: key.to_string(),
            what: what.to_string(),
        }
    }
}

/// Deserializes a table into `T` (serde on the parsed value, no text round trip), turning the
/// error into a [`SpecError`] whose key is the field that failed: the name an unknown or
/// missing field error quotes, else the first segment of the path `serde_path_to_error` kept
/// (`cells[1].density` names `cells`).
pub fn typed<T: DeserializeOwned>(table: &str, t: &toml::Table) -> Result<T, SpecError> {
    serde_path_to_error::deserialize(toml::Value::Table(t.clone())).map_err(|e| {
        let path = e.path().to_string();
        let msg = e.into_inner().message().to_string();
        let quoted = msg
            .split('`')
            .nth(1)
            .filter(|k| !k.contains(' '))
            .map(str::to_string);
        let first = path
            .split(['.', '['])
            .next()
            .filter(|k| !k.is_empty() && *k != "?")
            .map(str::to_string);
        let key = quoted
            .filter(|_| msg.starts_with("unknown field") || msg.starts_with("missing field"))
            .or(first)
            .unwrap_or_else(|| table.to_string());
        let msg = plain_types(&msg);
        let what = if path.is_empty() || path == "." || msg.contains(&path) {
            msg
        } else {
            format!("`{path}`: {msg}")
        };
        SpecError {
            table: table.to_string(),
            key,
            what,
        }
    })
}

/// serde's Rust type names in a message as a scenario's author reads them: `expected usize`
/// becomes `expected a whole number >= 0`, `expected f64` `expected a number`, and so on.
fn plain_types(msg: &str) -> String {
    const NAMES: [(&str, &str); 12] = [
        ("expected usize", "expected a whole number >= 0"),
        ("expected u64", "expected a whole number >= 0"),
        ("expected u32", "expected a whole number >= 0"),
        ("expected u8", "expected a whole number from 0 to 255"),
        ("expected i64", "expected a whole number"),
        ("expected i32", "expected a whole number"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected a boolean", "expected true or false"),
        ("expected a string", "expected a text in quotes"),
        ("expected a sequence", "expected a list [a, b, ...]"),
        ("expected a borrowed string", "expected a text in quotes"),
    ];
    let mut out = msg.to_string();
    for (rust, plain) in NAMES {
        if let Some(i) = out.find(rust)
            && !out[i + rust.len()..].starts_with(|c: char| c.is_alphanumeric())
        {
            out.replace_range(i..i + rust.len(), plain);
        }
    }
    out
}

/// A model as a typed value: its kind and the keys of its `[model]`, `[material]` and
/// `[simulation]` tables (`docs/formats.md` section 8), without the run length. Scenarios are
/// read into this ([`ModelSpec::from_tables`]: serde plus the key that failed); the studio, the
/// Python module and [`crate::open`] build the same values directly. [`ModelSpec::build`] then
/// validates the values once and makes the model.
///
/// Serialized, it mirrors a scenario's model: `kind` beside `model`, `material` and
/// `simulation` tables.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum ModelSpec {
    /// `dnurbs-curve`.
    DnurbsCurve(dnurbs::DnurbsSpec),
    /// `dnurbs-surface`.
    DnurbsSurface(dnurbs::DnurbsSpec),
    /// `dnurbs-swung`.
    DnurbsSwung(dnurbs::DnurbsSpec),
    /// `subdivision-solid`.
    SubdivisionSolid(solid::SolidSpec),
    /// `bspline-solid`.
    BsplineSolid(solid::SolidSpec),
    /// `ffd`.
    Ffd(ffd::FfdSpec),
    /// `pde-surface`.
    PdeSurface(pde::PdeSpec),
    /// `dnurbs-triangular`.
    DnurbsTriangular(dnurbs_tri::TriangularSpec),
    /// `dnurbs-patches`.
    DnurbsPatches(dnurbs_patches::PatchesSpec),
    /// `cad-part`.
    CadPart(part::PartSpec),
}

/// The keys of a kind's `[model]`, `[material]` and `[simulation]` tables as one value.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KindSpec<M, A, S> {
    /// `[model]`.
    #[serde(default)]
    pub model: M,
    /// `[material]`.
    #[serde(default)]
    pub material: A,
    /// `[simulation]` without `steps` and `duration` (the run length is the scenario's).
    #[serde(default)]
    pub simulation: S,
}

impl<M, A: Default, S: Default> KindSpec<M, A, S> {
    /// The spec of `model` with the default material and simulation.
    pub fn of_model(model: M) -> Self {
        Self {
            model,
            material: A::default(),
            simulation: S::default(),
        }
    }

    /// This spec with `simulation` instead.
    pub fn with_simulation(self, simulation: S) -> Self {
        Self { simulation, ..self }
    }
}

impl<M: DeserializeOwned + Default, A: DeserializeOwned + Default, S: DeserializeOwned + Default>
    KindSpec<M, A, S>
{
    /// Reads the three tables (absent ones take their defaults); `kind` and `name` in the
    /// model table are the scenario's and are left out.
    pub fn from_tables(spec: &Spec<'_>) -> Result<Self, SpecError> {
        let mut model = spec.model.clone();
        model.remove("kind");
        model.remove("name");
        Ok(Self {
            model: typed("model", &model)?,
            material: match spec.material {
                Some(t) => typed("material", t)?,
                None => A::default(),
            },
            simulation: match spec.simulation {
                Some(t) => typed("simulation", t)?,
                None => S::default(),
            },
        })
    }
}

/// A kind without a material (FFD, PDE surfaces): `[material]` has no keys, and any key is an
/// error that says so.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct NoMaterial {}

impl<'de> Deserialize<'de> for NoMaterial {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let keys = std::collections::BTreeMap::<String, serde::de::IgnoredAny>::deserialize(d)?;
        match keys.keys().next() {
            None => Ok(NoMaterial {}),
            Some(k) => Err(serde::de::Error::custom(format_args!(
                "unknown field `{k}`: this kind of model has no material"
            ))),
        }
    }
}

/// `[simulation]` of kinds whose only simulation key is the clock's step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClockKeys {
    /// Time step (s) of the model's clock (default: the kind's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
}

impl ClockKeys {
    /// The step, `default` when absent; an error unless it is positive and finite.
    pub fn dt_or(&self, default: f64) -> Result<f64, SpecError> {
        let dt = self.dt.unwrap_or(default);
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(SpecError::new(
                "simulation",
                "dt",
                format!("{dt} must be positive and finite"),
            ));
        }
        Ok(dt)
    }
}

impl ModelSpec {
    /// The kind.
    pub fn kind(&self) -> ModelKind {
        match self {
            ModelSpec::DnurbsCurve(_) => ModelKind::DnurbsCurve,
            ModelSpec::DnurbsSurface(_) => ModelKind::DnurbsSurface,
            ModelSpec::DnurbsSwung(_) => ModelKind::DnurbsSwung,
            ModelSpec::SubdivisionSolid(_) => ModelKind::SubdivisionSolid,
            ModelSpec::BsplineSolid(_) => ModelKind::BsplineSolid,
            ModelSpec::Ffd(_) => ModelKind::Ffd,
            ModelSpec::PdeSurface(_) => ModelKind::PdeSurface,
            ModelSpec::DnurbsTriangular(_) => ModelKind::DnurbsTriangular,
            ModelSpec::DnurbsPatches(_) => ModelKind::DnurbsPatches,
            ModelSpec::CadPart(_) => ModelKind::CadPart,
        }
    }

    /// Reads a scenario's tables for a model of `kind` (serde; the error names the table and
    /// the key).
    pub fn from_tables(kind: ModelKind, spec: &Spec<'_>) -> Result<Self, SpecError> {
        Ok(match kind {
            ModelKind::DnurbsCurve => ModelSpec::DnurbsCurve(KindSpec::from_tables(spec)?),
            ModelKind::DnurbsSurface => ModelSpec::DnurbsSurface(KindSpec::from_tables(spec)?),
            ModelKind::DnurbsSwung => ModelSpec::DnurbsSwung(KindSpec::from_tables(spec)?),
            ModelKind::SubdivisionSolid => {
                ModelSpec::SubdivisionSolid(KindSpec::from_tables(spec)?)
            }
            ModelKind::BsplineSolid => ModelSpec::BsplineSolid(KindSpec::from_tables(spec)?),
            ModelKind::Ffd => ModelSpec::Ffd(KindSpec::from_tables(spec)?),
            ModelKind::PdeSurface => ModelSpec::PdeSurface(KindSpec::from_tables(spec)?),
            ModelKind::DnurbsTriangular => {
                ModelSpec::DnurbsTriangular(KindSpec::from_tables(spec)?)
            }
            ModelKind::DnurbsPatches => ModelSpec::DnurbsPatches(KindSpec::from_tables(spec)?),
            ModelKind::CadPart => ModelSpec::CadPart(KindSpec::from_tables(spec)?),
        })
    }

    /// Validates the values and builds the model; relative file names resolve against `base`.
    /// The error names the table and key at fault.
    pub fn build(&self, base: &Path) -> Result<Box<dyn Model>, SpecError> {
        let kind = self.kind();
        Ok(match self {
            ModelSpec::DnurbsCurve(s) | ModelSpec::DnurbsSurface(s) | ModelSpec::DnurbsSwung(s) => {
                Box::new(dnurbs::DnurbsModel::from_keys(kind, s, base)?)
            }
            ModelSpec::SubdivisionSolid(s) | ModelSpec::BsplineSolid(s) => {
                Box::new(solid::SolidModel::from_keys(kind, s, base)?)
            }
            ModelSpec::Ffd(s) => Box::new(ffd::FfdModel::from_keys(s, base)?),
            ModelSpec::PdeSurface(s) => Box::new(pde::PdeSurfaceModel::from_keys(s, base)?),
            ModelSpec::DnurbsTriangular(s) => {
                Box::new(dnurbs_tri::TriangularModel::from_keys(s, base)?)
            }
            ModelSpec::DnurbsPatches(s) => {
                Box::new(dnurbs_patches::PatchesModel::from_keys(s, base)?)
            }
            ModelSpec::CadPart(s) => Box::new(part::PartModel::from_keys(s, base)?),
        })
    }
}

/// Builds a model of `kind` from its scenario tables ([`ModelSpec::from_tables`], then
/// [`ModelSpec::build`]).
pub fn build(kind: ModelKind, spec: &Spec<'_>) -> Result<Box<dyn Model>, SpecError> {
    ModelSpec::from_tables(kind, spec)?.build(spec.base)
}

/// Rebuilds a model of `kind` from what its [`Model::save`] wrote.
pub fn load(kind: ModelKind, saved: &serde_json::Value) -> Result<Box<dyn Model>, SessionError> {
    Ok(match kind {
        ModelKind::SubdivisionSolid | ModelKind::BsplineSolid => {
            Box::new(solid::SolidModel::load(saved)?)
        }
        ModelKind::DnurbsCurve | ModelKind::DnurbsSurface | ModelKind::DnurbsSwung => {
            Box::new(dnurbs::DnurbsModel::load(kind, saved)?)
        }
        ModelKind::Ffd => Box::new(ffd::FfdModel::load(saved)?),
        ModelKind::PdeSurface => Box::new(pde::PdeSurfaceModel::load(saved)?),
        ModelKind::DnurbsTriangular => Box::new(dnurbs_tri::TriangularModel::load(saved)?),
        ModelKind::DnurbsPatches => Box::new(dnurbs_patches::PatchesModel::load(saved)?),
        ModelKind::CadPart => Box::new(part::PartModel::load(saved)?),
    })
}

/// The error of an edit that a model of `kind` does not take; `takes`, when given, lists
/// the edits it does take.
pub(crate) fn not_taken(edit: &crate::command::Edit, kind: ModelKind, takes: &str) -> SessionError {
    let article = if kind == ModelKind::Ffd { "an" } else { "a" };
    let takes = if takes.is_empty() {
        String::new()
    } else {
        format!(" (it takes {takes})")
    };
    SessionError::command(
        "",
        "",
        format!(
            "`{}` does not apply to {article} {kind} model{takes}",
            edit.action()
        ),
    )
}

/// The value paired with the keyword `given` at `table.key` among `words` (`None` when the
/// key is absent); an error names the words the key takes (`"x": expected "a" or "b"`).
pub(crate) fn keyword<T: Copy>(
    table: &str,
    key: &str,
    given: Option<&str>,
    words: &[(&str, T)],
) -> Result<Option<T>, SpecError> {
    let Some(g) = given else {
        return Ok(None);
    };
    match words.iter().find(|(w, _)| *w == g) {
        Some(&(_, v)) => Ok(Some(v)),
        None => {
            let names: Vec<String> = words.iter().map(|(w, _)| format!("\"{w}\"")).collect();
            let list = match names.split_last() {
                Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
                _ => names.concat(),
            };
            Err(SpecError::new(
                table,
                key,
                format!("{g:?}: expected {list}"),
            ))
        }
    }
}

/// The error of a kind's edit dispatcher handing an edit to a group of arms that does not
/// hold it (a bug, reported instead of a panic).
pub(crate) fn misrouted() -> SessionError {
    SessionError::model("internal: an edit was dispatched to the wrong group")
}
