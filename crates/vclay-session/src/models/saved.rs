//! The generalized D-NURBS engine's state as session files save it, shared by the kinds that
//! wrap [`GeneralizedDnurbs`](vclay_dynamics::dnurbs::generalized::GeneralizedDnurbs) directly
//! (`dnurbs-triangular`, `dnurbs-patches`).

use serde::{Deserialize, Serialize};
use vclay_dynamics::dnurbs::ElasticReference;
use vclay_dynamics::dnurbs::generalized::GeneralizedState;

/// [`GeneralizedState`] as saved (every number in shortest exact form: a restored session
/// continues bit for bit).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SavedState {
    coordinates: Vec<f64>,
    velocity: Vec<f64>,
    rest_coordinates: Vec<f64>,
    fixed: Vec<bool>,
    weight_targets: Vec<f64>,
    weight_penalty: f64,
    absolute: bool,
    time: f64,
    steps: usize,
    substeps: usize,
    weight_projections: usize,
}

impl From<&GeneralizedState> for SavedState {
    fn from(s: &GeneralizedState) -> Self {
        Self {
            coordinates: s.coordinates.clone(),
            velocity: s.velocity.clone(),
            rest_coordinates: s.rest_coordinates.clone(),
            fixed: s.fixed.clone(),
            weight_targets: s.weight_targets.clone(),
            weight_penalty: s.weight_penalty,
            absolute: s.reference == ElasticReference::Absolute,
            time: s.time,
            steps: s.steps,
            substeps: s.substeps,
            weight_projections: s.weight_projections,
        }
    }
}

impl From<SavedState> for GeneralizedState {
    fn from(s: SavedState) -> Self {
        Self {
            coordinates: s.coordinates,
            velocity: s.velocity,
            rest_coordinates: s.rest_coordinates,
            fixed: s.fixed,
            weight_targets: s.weight_targets,
            weight_penalty: s.weight_penalty,
            reference: if s.absolute {
                ElasticReference::Absolute
            } else {
                ElasticReference::RestShape
            },
            time: s.time,
            steps: s.steps,
            substeps: s.substeps,
            weight_projections: s.weight_projections,
        }
    }
}
