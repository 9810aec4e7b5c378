//! Robust weights for iteratively reweighted least squares (IRLS).
//!
//! After each solve and parameter correction the residuals are the closest-point distances
//! `d_k`. Their scale is estimated robustly from the median absolute deviation,
//! `sigma = 1.4826 median(d_k)` (the distances are the absolute values of normal residuals,
//! whose median is `0.6745 sigma` for Gaussian noise), and each point gets
//! - Huber: `w = min(1, c / d)`, `c = 1.345 sigma` (95 % efficiency under Gaussian noise);
//! - Tukey's biweight: `w = (1 - (d / c)^2)^2` for `d < c`, else 0, `c = 4.685 sigma`:
//!   far outliers get weight 0 and no influence at all.
//!
//! (Huber 1981, *Robust Statistics*; Holland & Welsch 1977 for the tuning constants.)
//! `sigma` is floored at [`SIGMA_FLOOR`] times the model size, so an exact fit does not divide
//! by zero.
//!
//! **The objective that judges rounds.** Every fit (robust or not) accepts a solve-and-correct
//! round only when it lowers the robust objective
//! ```text
//! J = 1/N sum_k rho(d_k) + U,    rho(d) = c^2/6 (1 - (1 - (d/c)^2)^3) for d < c, else c^2/6,
//! ```
//! Tukey's biweight loss with `c = 4.685 sigma` ([`objective`]) plus the fairness energy `U`.
//! For small distances `rho(d) ~ d^2 / 2`, so on clean data `J` is the fit's own least-squares
//! objective; far points add a constant and cannot make a round look good. Two rounds are
//! compared with one common scale (the smaller of their two `sigma`), so a shrinking scale
//! cannot fake progress.

use serde::Serialize;

/// Floor of the robust scale, relative to the model size.
pub const SIGMA_FLOOR: f64 = 1e-12;
/// Huber's tuning constant.
pub const HUBER_C: f64 = 1.345;
/// Tukey's tuning constant.
pub const TUKEY_C: f64 = 4.685;

/// The robust loss of `--robust`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Robust {
    /// Huber weights (outliers down-weighted as `1/d`).
    Huber,
    /// Tukey's biweight (far outliers get weight 0). The default of `--robust`.
    #[default]
    Tukey,
}

impl std::str::FromStr for Robust {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "huber" => Ok(Robust::Huber),
            "tukey" => Ok(Robust::Tukey),
            other => Err(format!(
                "unknown robust loss {other:?}, expected huber or tukey"
            )),
        }
    }
}

/// Robust scale `1.4826 median(d)`, floored at `SIGMA_FLOOR * size`.
pub fn scale(distances: &[f64], size: f64) -> f64 {
    let mut d = distances.to_vec();
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    (1.4826 * *m).max(SIGMA_FLOOR * size)
}

/// Tukey's biweight loss `rho(d)` with cut-off `c` (module docs; `c^2 / 6` beyond `c`).
pub fn tukey_rho(d: f64, c: f64) -> f64 {
    let c2 = c * c;
    if d < c {
        let t = 1.0 - d * d / c2;
        c2 / 6.0 * (1.0 - t * t * t)
    } else {
        c2 / 6.0
    }
}

/// Mean Tukey loss `1/N sum_k rho(d_k)` with cut-off `c` (the data part of the objective that
/// judges rounds, module docs).
pub fn objective(distances: &[f64], c: f64) -> f64 {
    distances.iter().map(|&d| tukey_rho(d, c)).sum::<f64>() / distances.len().max(1) as f64
}

/// Writes the weights of `loss` for `distances` with scale `sigma` into `out`.
pub fn weights(loss: Robust, distances: &[f64], sigma: f64, out: &mut [f64]) {
    match loss {
        Robust::Huber => {
            let c = HUBER_C * sigma;
            for (w, &d) in out.iter_mut().zip(distances) {
                *w = if d <= c { 1.0 } else { c / d };
            }
        }
        Robust::Tukey => {
            let c = TUKEY_C * sigma;
            for (w, &d) in out.iter_mut().zip(distances) {
                let t = d / c;
                *w = if t < 1.0 { (1.0 - t * t).powi(2) } else { 0.0 };
            }
        }
    }
}
