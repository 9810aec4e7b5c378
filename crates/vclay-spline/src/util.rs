//! Small helpers shared by the curve, surface and volume types.

use crate::error::{NetIndex, SplineError};
use crate::knots::KnotVector;
use vclay_core::{Vec3, Vec4};

/// Checks that `u` is finite and inside the knot vector's domain up to its parameter tolerance;
/// returns `u` clamped into the domain.
/// Rejects derivative orders above [`crate::MAX_DERIVATIVE_ORDER`] before anything is allocated.
pub(crate) fn check_order(order: usize) -> Result<(), SplineError> {
    if order > crate::knots::MAX_DERIVATIVE_ORDER {
        return Err(SplineError::DerivativeOrderTooHigh {
            order,
            max: crate::knots::MAX_DERIVATIVE_ORDER,
        });
    }
    Ok(())
}

pub(crate) fn check_param(kv: &KnotVector, axis: usize, u: f64) -> Result<f64, SplineError> {
    if !u.is_finite() {
        return Err(SplineError::NonFiniteParameter { axis, value: u });
    }
    let d = kv.domain();
    if !d.contains_with(u, kv.parameter_tolerance()) {
        return Err(SplineError::ParameterOutOfDomain {
            axis,
            value: u,
            min: d.min,
            max: d.max,
        });
    }
    Ok(d.clamp(u))
}

/// Validates control points and weights, naming the first bad entry by its net index.
pub(crate) fn check_net(
    points: &[Vec3],
    weights: &[f64],
    dims: &[usize],
) -> Result<(), SplineError> {
    let total: usize = dims.iter().product();
    if points.len() != total {
        return Err(SplineError::Shape {
            what: "number of control points".into(),
            found: points.len(),
            expected: total,
        });
    }
    if weights.len() != total {
        return Err(SplineError::Shape {
            what: "number of weights".into(),
            found: weights.len(),
            expected: total,
        });
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(SplineError::NonFiniteControlPoint {
            index: unflatten(i, dims),
        });
    }
    if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(SplineError::NonPositiveWeight {
            index: unflatten(i, dims),
            value: weights[i],
        });
    }
    Ok(())
}

/// Flat index (last axis fastest) to a multi-index.
pub(crate) fn unflatten(mut i: usize, dims: &[usize]) -> NetIndex {
    let mut idx = vec![0; dims.len()];
    for a in (0..dims.len()).rev() {
        idx[a] = i % dims[a];
        i /= dims[a];
    }
    NetIndex(idx)
}

/// Homogeneous control points `(w x, w y, w z, w)`.
pub(crate) fn homogeneous(points: &[Vec3], weights: &[f64]) -> Vec<Vec4> {
    points
        .iter()
        .zip(weights)
        .map(|(p, &w)| Vec4::new(p.x * w, p.y * w, p.z * w, w))
        .collect()
}

/// Splits homogeneous points back into points and weights.
pub(crate) fn dehomogenize(pw: &[Vec4]) -> (Vec<Vec3>, Vec<f64>) {
    pw.iter()
        .map(|q| (Vec3::new(q.x / q.w, q.y / q.w, q.z / q.w), q.w))
        .unzip()
}

/// A fixed-capacity stack buffer of basis values (`MAX_DEGREE + 1` entries).
pub(crate) type BasisBuf = [f64; crate::knots::MAX_DEGREE + 1];
