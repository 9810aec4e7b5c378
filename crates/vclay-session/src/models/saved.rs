//! What the D-NURBS kinds share in session files and reports: a step as the session reports
//! it, and the generalized engine's state as session files save it; the knot vectors of a
//! saved tensor-product net (D-NURBS surfaces, B-spline solids).

use serde::{Deserialize, Serialize};
use vclay_dynamics::dnurbs::ElasticReference;
use vclay_dynamics::dnurbs::generalized::GeneralizedState;

use vclay_spline::KnotVector;

use crate::error::SessionError;
use crate::model::{Energy, StepReport};

/// The session's report of a D-NURBS engine's step (either engine) begun at `t0`: its time,
/// kinetic and elastic energy (tools: 0, D-NURBS report no tool energy) and solver iterations.
pub(crate) fn step_report(r: &vclay_dynamics::StepReport, t0: std::time::Instant) -> StepReport {
    StepReport {
        time: r.time,
        energy: Energy {
            kinetic: r.kinetic_energy,
            elastic: r.elastic_energy,
            tools: 0.0,
        },
        iterations: r.solver.iterations,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

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
            reference: super::generalized::reference(s.absolute),
            time: s.time,
            steps: s.steps,
            substeps: s.substeps,
            weight_projections: s.weight_projections,
        }
    }
}

/// The knot vectors of a saved tensor-product net: `knots[a]` of degree `degrees[a]` along
/// each axis `a` (the control point count is what the length leaves), each checked.
pub(crate) fn knot_vectors<const N: usize>(
    knots: &[Vec<f64>; N],
    degrees: &[usize; N],
) -> Result<[KnotVector; N], SessionError> {
    let mut kv = Vec::with_capacity(N);
    for (a, (k, &p)) in knots.iter().zip(degrees).enumerate() {
        let n = k.len().checked_sub(p + 1).ok_or_else(|| {
            SessionError::model(format!("knot vector {a}: too short for degree {p}"))
        })?;
        kv.push(KnotVector::new(k.clone(), p, n).map_err(SessionError::kernel)?);
    }
    Ok(kv.try_into().expect("one knot vector per axis"))
}
