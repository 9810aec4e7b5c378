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

/// How a fit treats outliers (`FitOptions::robust`, `vclay fit --robust MODE`).
///
/// `Auto` (the default) fits by plain least squares, then looks at the first round's distances:
/// when more than [`AUTO_SHARE`] of the points (and at least [`AUTO_MIN_POINTS`]) lie beyond
/// Tukey's rejection distance `4.685 sigma` (`sigma` from the median of the distances, module
/// docs), which Gaussian noise puts 3 points in a million beyond, the scan holds gross outliers
/// and the fit continues as with `Tukey` (IRLS rounds judged by the robust objective, domain
/// from the inliers). Otherwise it stays plain least squares, bit for bit the fit of `None`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RobustMode {
    /// Plain least squares, robust (Tukey) once the first round shows gross outliers.
    #[default]
    Auto,
    /// Plain least squares always (`--robust none`, `--no-robust`).
    None,
    /// Robust weights with this loss from the second round on (`--robust huber|tukey`).
    Always(Robust),
}

/// Smallest share of the points that [`gross_outliers`] finds after the first round for which
/// [`RobustMode::Auto`] treats a scan as holding gross outliers: 0.1 %. Normal noise puts
/// 2.8e-6 of the points beyond the rejection distance; the Jacksboro DEM at 32 x 32 (real
/// terrain, model error 38 m RMS; `bench/check_fit.sh`) shows 1 point in 138,632; the
/// benchmark's wave with 1 % stray returns 0.93 %.
pub const AUTO_SHARE: f64 = 1e-3;
/// Points per cell of the partition that gives [`gross_outliers`] its local scales.
pub const AUTO_CELL_POINTS: usize = 32;
/// Fewest points of a cell for its own scale (fewer: the global scale).
pub const AUTO_CELL_MIN: usize = 8;
/// Most cells per direction of that partition.
pub const AUTO_MAX_CELLS: usize = 256;
/// Smallest distance of a gross outlier, relative to the model size: a plain fit moves by
/// about the outliers' share times their distance, so smaller ones cannot spoil it beyond
/// 1e-4 of the model size, and exact data's distances (rounding, the rigidity's boundary layer
/// of about 1e-5) are not mistaken for outliers.
pub const AUTO_FLOOR: f64 = 1e-4;
/// Fewest points beyond the rejection distance for [`RobustMode::Auto`] to switch (small clouds:
/// a single far point of 300 is not yet a pattern).
pub const AUTO_MIN_POINTS: usize = 3;

impl RobustMode {
    /// The loss the fit starts with (`None` for `Auto` and `None`).
    pub fn loss(self) -> Option<Robust> {
        match self {
            RobustMode::Always(l) => Some(l),
            _ => None,
        }
    }
    /// The name `--robust` takes: `auto`, `none`, `huber` or `tukey`.
    pub fn name(self) -> &'static str {
        match self {
            RobustMode::Auto => "auto",
            RobustMode::None => "none",
            RobustMode::Always(Robust::Huber) => "huber",
            RobustMode::Always(Robust::Tukey) => "tukey",
        }
    }
}

impl std::fmt::Display for RobustMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for RobustMode {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl std::str::FromStr for RobustMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(RobustMode::Auto),
            "none" | "off" => Ok(RobustMode::None),
            "huber" => Ok(RobustMode::Always(Robust::Huber)),
            "tukey" => Ok(RobustMode::Always(Robust::Tukey)),
            other => Err(format!(
                "unknown robust mode {other:?}, expected auto, none, tukey or huber"
            )),
        }
    }
}

/// Points a plain fit leaves as gross outliers ([`RobustMode::Auto`]): their distance exceeds
/// Tukey's rejection distance `TUKEY_C * max(sigma, sigma_c)` and `floor`. `sigma` is the
/// global robust scale, `sigma_c = 1.4826 median` of the distances in the point's cell of an
/// `m x m` partition of the parameter square (`m = sqrt(N / AUTO_CELL_POINTS)`, at most
/// [`AUTO_MAX_CELLS`]; cells with fewer than [`AUTO_CELL_MIN`] points use `sigma` alone). The
/// local scale tells stray returns from model error: where the net cannot follow the surface
/// (a coarse grid, exact data's boundary layer) the distances grow together over a region,
/// and a point is far only from the distances of its own neighbours; a gross outlier is far
/// from its neighbours, which lie on the surface. `floor` (the caller's
/// `AUTO_FLOOR * size`) keeps exact data's rounding-level distances out.
pub fn gross_outliers(distances: &[f64], params: &[[f64; 2]], sigma: f64, floor: f64) -> usize {
    let n = distances.len();
    let m = ((n / AUTO_CELL_POINTS) as f64)
        .sqrt()
        .floor()
        .clamp(1.0, AUTO_MAX_CELLS as f64) as usize;
    let cell = |uv: &[f64; 2]| {
        let i = |t: f64| ((t.clamp(0.0, 1.0) * m as f64) as usize).min(m - 1);
        i(uv[0]) * m + i(uv[1])
    };
    // Counting sort of the distances by cell, then each cell's median.
    let mut start = vec![0usize; m * m + 1];
    for uv in params {
        start[cell(uv) + 1] += 1;
    }
    for c in 0..m * m {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut sorted = vec![0.0; n];
    for (uv, &d) in params.iter().zip(distances) {
        let c = cell(uv);
        sorted[fill[c]] = d;
        fill[c] += 1;
    }
    drop(fill);
    let local: Vec<f64> = (0..m * m)
        .map(|c| {
            let s = &mut sorted[start[c]..start[c + 1]];
            if s.len() < AUTO_CELL_MIN {
                return sigma;
            }
            let mid = s.len() / 2;
            let (_, med, _) = s.select_nth_unstable_by(mid, f64::total_cmp);
            (1.4826 * *med).max(sigma)
        })
        .collect();
    params
        .iter()
        .zip(distances)
        .filter(|&(uv, &d)| d > floor && d > TUKEY_C * local[cell(uv)])
        .count()
}

/// Whether `count` gross outliers of `n` points make [`RobustMode::Auto`] switch to robust
/// weights: more than [`AUTO_SHARE`] of them and at least [`AUTO_MIN_POINTS`].
pub fn auto_switches(count: usize, n: usize) -> bool {
    count >= AUTO_MIN_POINTS && count as f64 > AUTO_SHARE * n as f64
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

#[cfg(test)]
mod tests {
    use super::*;

    /// 4096 points on a 64 x 64 grid of parameters with distances `d(u, v)`.
    fn grid(d: impl Fn(usize, usize) -> f64) -> (Vec<f64>, Vec<[f64; 2]>) {
        let (mut dist, mut params) = (Vec::new(), Vec::new());
        for i in 0..64 {
            for j in 0..64 {
                params.push([(i as f64 + 0.5) / 64.0, (j as f64 + 0.5) / 64.0]);
                dist.push(d(i, j));
            }
        }
        (dist, params)
    }

    #[test]
    fn isolated_far_points_are_gross_a_far_region_is_not() {
        // Noise-like distances 1e-3 (varying 0.5-1.5e-3), 1 % of the points at 0.5: isolated.
        let base = |i: usize, j: usize| 1e-3 * (1.0 + 0.5 * ((i * 7 + j * 13) as f64).sin());
        let (d, p) = grid(|i, j| {
            if (i * 64 + j) % 100 == 0 {
                0.5
            } else {
                base(i, j)
            }
        });
        let sigma = 1.4826 * 1e-3;
        let n = gross_outliers(&d, &p, sigma, 1e-6);
        assert_eq!(n, 41);
        assert!(auto_switches(n, d.len()));
        // A whole corner (a 17 x 17 block, 7 % of the points, about 3 x 3 of the test's cells)
        // 20 times farther: model error spread over a region, far only against the global
        // scale. (A region smaller than a cell is flagged: formats.md section 11.)
        let (d, p) = grid(|i, j| base(i, j) * if i < 17 && j < 17 { 20.0 } else { 1.0 });
        let n = gross_outliers(&d, &p, sigma, 1e-6);
        assert!(!auto_switches(n, d.len()), "{n}");
        // Below the floor nothing counts.
        let (d, p) = grid(|i, j| {
            if (i * 64 + j) % 100 == 0 {
                0.5
            } else {
                base(i, j)
            }
        });
        assert_eq!(gross_outliers(&d, &p, sigma, 1.0), 0);
    }

    #[test]
    fn modes_parse_and_print() {
        for (s, m) in [
            ("auto", RobustMode::Auto),
            ("none", RobustMode::None),
            ("off", RobustMode::None),
            ("Tukey", RobustMode::Always(Robust::Tukey)),
            ("huber", RobustMode::Always(Robust::Huber)),
        ] {
            assert_eq!(s.parse::<RobustMode>().unwrap(), m);
        }
        assert_eq!(RobustMode::default().to_string(), "auto");
        let e = "cauchy".parse::<RobustMode>().unwrap_err();
        assert!(e.contains("auto, none, tukey or huber"), "{e}");
        // Fewer than 3, or at most 0.1 %, is not a pattern.
        assert!(!auto_switches(2, 100) && !auto_switches(10, 10_000) && auto_switches(11, 10_000));
    }
}
