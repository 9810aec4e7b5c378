//! Placeholder: the pde model kind is being written.

use super::{Spec, SpecError};
use crate::error::SessionError;
#[allow(unused_imports)]
use crate::model::{Model, ModelKind};

/// Builds a model from its scenario tables.
pub fn build(spec: &Spec<'_>) -> Result<Box<dyn Model>, SpecError> {
    let _ = spec;
    Err(SpecError::new("model", "kind", "not yet available"))
}

/// Rebuilds a saved model.
pub fn load(saved: &serde_json::Value) -> Result<Box<dyn Model>, SessionError> {
    let _ = saved;
    Err(SessionError::model("not yet available"))
}
