//! The model kinds behind [`crate::Model`]: how each is built from a scenario's tables and
//! rebuilt from a session file.

pub mod dnurbs;
pub mod dnurbs_patches;
pub mod dnurbs_tri;
pub mod ffd;
pub mod pde;
mod saved;
pub mod solid;

use std::path::Path;

use serde::de::DeserializeOwned;

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

/// Deserializes a table into `T`, turning serde's message into a [`SpecError`] whose key is
/// the first name it quotes (``unknown field `fro` `` names `fro`).
pub fn typed<T: DeserializeOwned>(table: &str, t: &toml::Table) -> Result<T, SpecError> {
    // Parse the table's own TOML text, so that a type error carries a span, which names the
    // key (serde's message for a wrong type does not).
    let text = toml::to_string(t).unwrap_or_default();
    toml::from_str::<T>(&text).map_err(|e| {
        let msg = e.message().to_string();
        let from_span = e.span().and_then(|sp| {
            let start = text[..sp.start.min(text.len())]
                .rfind('\n')
                .map_or(0, |i| i + 1);
            let line = text[start..].lines().next()?;
            let (k, _) = line.split_once('=')?;
            let k = k.trim().trim_matches('"');
            (!k.is_empty() && !k.starts_with('[')).then(|| k.to_string())
        });
        let quoted = msg
            .split('`')
            .nth(1)
            .filter(|k| !k.contains(' '))
            .map(str::to_string);
        let key = quoted
            .filter(|_| msg.starts_with("unknown field") || msg.starts_with("missing field"))
            .or(from_span)
            .unwrap_or_else(|| table.to_string());
        SpecError {
            table: table.to_string(),
            key,
            what: msg,
        }
    })
}

/// For kinds without physics (FFD, PDE surfaces): refuses a non-empty `[material]` (naming
/// `what`, e.g. "an ffd model") and reads `[simulation] dt` (the clock's step; `default` when
/// absent), the only simulation key.
pub(crate) fn clock_only(spec: &Spec<'_>, what: &str, default: f64) -> Result<f64, SpecError> {
    #[derive(Debug, Default, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct SimKeys {
        dt: Option<f64>,
    }
    if let Some(t) = spec.material
        && !t.is_empty()
    {
        return Err(SpecError::new(
            "material",
            t.keys().next().map_or("material", |k| k.as_str()),
            format!("{what} has no material"),
        ));
    }
    let sim: SimKeys = match spec.simulation {
        Some(t) => typed("simulation", t)?,
        None => SimKeys::default(),
    };
    let dt = sim.dt.unwrap_or(default);
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(SpecError::new(
            "simulation",
            "dt",
            format!("{dt} must be positive and finite"),
        ));
    }
    Ok(dt)
}

/// Builds a model of `kind` from its scenario tables.
pub fn build(kind: ModelKind, spec: &Spec<'_>) -> Result<Box<dyn Model>, SpecError> {
    Ok(match kind {
        ModelKind::SubdivisionSolid | ModelKind::BsplineSolid => {
            Box::new(solid::SolidModel::from_spec(kind, spec)?)
        }
        ModelKind::DnurbsCurve | ModelKind::DnurbsSurface | ModelKind::DnurbsSwung => {
            dnurbs::build(kind, spec)?
        }
        ModelKind::Ffd => ffd::build(spec)?,
        ModelKind::PdeSurface => pde::build(spec)?,
        ModelKind::DnurbsTriangular => dnurbs_tri::build(spec)?,
        ModelKind::DnurbsPatches => dnurbs_patches::build(spec)?,
    })
}

/// Rebuilds a model of `kind` from what its [`Model::save`] wrote.
pub fn load(kind: ModelKind, saved: &serde_json::Value) -> Result<Box<dyn Model>, SessionError> {
    Ok(match kind {
        ModelKind::SubdivisionSolid | ModelKind::BsplineSolid => {
            Box::new(solid::SolidModel::load(saved)?)
        }
        ModelKind::DnurbsCurve | ModelKind::DnurbsSurface | ModelKind::DnurbsSwung => {
            dnurbs::load(kind, saved)?
        }
        ModelKind::Ffd => ffd::load(saved)?,
        ModelKind::PdeSurface => pde::load(saved)?,
        ModelKind::DnurbsTriangular => dnurbs_tri::load(saved)?,
        ModelKind::DnurbsPatches => dnurbs_patches::load(saved)?,
    })
}
