//! # vclay-fit
//!
//! Smooth B-spline and NURBS surfaces fitted to scanned point clouds, with D-NURBS's
//! thin-plate-under-tension energy as fairness: the static case of `d-nurbs.txt` section 7.2
//! ("optimal fitting"), which couples the surface to the data by springs (eq 19) and minimizes
//! the deformation energy of eq 17 — here solved directly as one regularized least-squares
//! problem instead of integrating eq 18 to rest.
//!
//! **What.** [`fit_surface`] takes points (`x_k`, any number from 3 to [`MAX_POINTS`]) and
//! returns a degree-`p` surface with an `n_u x n_v` control net over `[0, 1]^2` (clamped
//! uniform knots) that minimizes
//! ```text
//! F(P) = 1/(2W) sum_k w_k |S(u_k, v_k) - x_k|^2 + 1/2 P^T K P,       W = sum_k w_k,
//! ```
//! with `K` the stiffness matrix of `d-nurbs.txt` eq 17 (tension `alpha`, rigidity `beta`,
//! scaled so that they are dimensionless: [`energy`]).
//!
//! **How.**
//! 1. Parametrize: project onto the cloud's principal plane ([`plane`]).
//! 2. Solve the normal equations `(A^T D A / W + K) P = A^T D x / W` ([`system`]: assembled
//!    from the basis values point by point, never forming `A`; sparse Cholesky).
//! 3. Parameter correction ([`project`]): every point's parameter moves to its closest point
//!    on the new surface (Newton); repeat 2-3 `corrections` times. A round is kept only when
//!    it lowers the robust objective (Tukey's loss of the distances plus the fairness energy,
//!    [`robust`]): on a scan with outliers, corrections that move the outliers' parameters
//!    toward their foot points pull the surface to them, and such a round is thrown away, so
//!    corrections never make a fit worse, by that objective, than its first solve
//!    (`corrections = 0`).
//! 4. Robust when asked or needed: the weights `w_k` are re-estimated from the distances after
//!    each round (IRLS with Huber or Tukey weights, [`robust`]), for `robust_rounds` extra
//!    rounds. The default, [`RobustMode::Auto`], starts plain and turns to Tukey's weights when
//!    its first round leaves more than 0.1 % of the points as gross outliers (far beyond the
//!    scale of their neighbours' distances); otherwise it stays plain least squares.
//!    Robust or not, the base rectangle is trimmed to where the inliers are when the fringe
//!    it leaves out holds mostly outliers (points beyond `4.685 sigma`, [`plane`]); the
//!    points outside get weight 0, and a new domain gets a round of its own.
//! 5. Optionally rational (`rational = true`, D-NURBS's dynamic weights, `d-nurbs.txt` eqs 3-6):
//!    a few damped Gauss-Newton iterations on the control points *and* weights ([`rational`]).
//! 6. Report: closest-point distances (Gauss-Newton to convergence, carried on from the last
//!    round's correction: [`project::Evaluator::project_continued`]), RMS and maximum, the
//!    fairness energy `U = 1/2 P^T K P`, the worst cell of an 8 x 8 partition of the domain,
//!    how many points were down-weighted, warnings (fewer points than control points), time
//!    per phase ([`FitReport`]).
//!
//! **Limitations.** The cloud must be a height field over its principal plane, possibly with
//! folds that parameter correction can untangle (a scanned face, terrain, a car panel, half a
//! sphere); closed or strongly folded shapes (a whole bunny) need a base surface, which is not
//! implemented. Knots are uniform, not adapted to the data. Data outside the base rectangle's
//! corners (round scans) leave corner control points to the fairness energy alone, which is
//! why some rigidity is on by default.
#![warn(missing_docs)]

pub mod energy;
pub mod error;
pub mod plane;
pub mod project;
pub mod rational;
pub mod robust;
pub mod system;

pub use error::FitError;
pub use plane::{BasePlane, base_plane};
pub use robust::{Robust, RobustMode};

use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;
use vclay_core::{Parallelism, Vec3};
use vclay_spline::{KnotVector, NurbsSurface};

/// Default control points per direction (`--grid 32x32`).
pub const DEFAULT_GRID: usize = 32;
/// Default degree in both directions.
pub const DEFAULT_DEGREE: usize = 3;
/// Default tension `alpha` (none: tension shrinks the surface toward its boundary).
pub const DEFAULT_TENSION: f64 = 0.0;
/// Default rigidity `beta`: enough to fill holes and empty corners smoothly (the solve stays
/// well conditioned for nets up to 512 x 512), small enough that its bias stays below scan
/// noise. The data term against the bending term makes a boundary layer of width
/// `beta^(1/4)` (in the unit-square parameters: 0.6 % of the width here) in which the surface
/// leaves the data by about `beta^(1/2) |S_uu|` (3e-5 of the second derivative).
pub const DEFAULT_RIGIDITY: f64 = 1e-9;
/// Default number of parameter-correction rounds.
pub const DEFAULT_CORRECTIONS: usize = 2;
/// Default number of extra IRLS rounds when robust weights are on.
pub const DEFAULT_ROBUST_ROUNDS: usize = 3;
/// Default Gauss-Newton iterations of the rational (dynamic-weight) fit.
pub const DEFAULT_WEIGHT_ITERATIONS: usize = 4;
/// Gauss-Newton steps per point in a parameter-correction round.
pub const CORRECTION_NEWTON_STEPS: usize = 2;
/// Gauss-Newton steps per point (at most) for the reported distances (they converge to the
/// same foot point as Newton's method; linearly, at a rate of about distance x curvature).
pub const REPORT_NEWTON_STEPS: usize = 30;
/// Parameter step below which the reported closest-point iteration (and that of parameter
/// correction) stops (the distance is stationary at the foot point, so its error is of the
/// order of the square of this times the model size).
pub const REPORT_PARAM_TOL: f64 = 1e-9;
/// Largest number of points.
pub const MAX_POINTS: usize = 100_000_000;
/// Largest number of control points (a 512 x 512 net).
pub const MAX_CONTROL_POINTS: usize = 512 * 512;
/// Largest degree.
pub const MAX_FIT_DEGREE: usize = 7;
/// Bytes per data point held during a fit: the point (24 B), its parameter, distance and
/// weight (32 B), the candidate round's parameter and distance (24 B), and scratch (a robust
/// fit's in-plane coordinates and the median's copy, 24 B). Measured peak resident size
/// (release, `/usr/bin/time -v`, 1,000,000 points with 2 % outliers, 32 x 32 net, less the
/// process's 6 MB): 111 B per point, with or without `--robust` (the estimate reads 0.98 of
/// the peak).
pub const BYTES_PER_POINT: usize = 112;

/// Options of a fit; each default is the named constant.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Control points `[n_u, n_v]` ([`DEFAULT_GRID`]).
    pub grid: [usize; 2],
    /// Degree in both directions ([`DEFAULT_DEGREE`]).
    pub degree: usize,
    /// Tension `alpha` ([`DEFAULT_TENSION`]; dimensionless, [`energy`]).
    pub tension: f64,
    /// Rigidity `beta` ([`DEFAULT_RIGIDITY`]; dimensionless, [`energy`]).
    pub rigidity: f64,
    /// Parameter-correction rounds ([`DEFAULT_CORRECTIONS`]).
    pub corrections: usize,
    /// Outliers: plain least squares that turns robust when the first round shows gross
    /// outliers ([`RobustMode::Auto`], the default), plain always, or a robust loss throughout.
    pub robust: RobustMode,
    /// Extra IRLS rounds when robust weights are on ([`DEFAULT_ROBUST_ROUNDS`]).
    pub robust_rounds: usize,
    /// Fit the weights too (rational surface, D-NURBS dynamic weights); default false.
    pub rational: bool,
    /// Gauss-Newton iterations of the rational fit ([`DEFAULT_WEIGHT_ITERATIONS`]).
    pub weight_iterations: usize,
    /// Threads ([`Parallelism::Auto`]).
    pub parallelism: Parallelism,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            grid: [DEFAULT_GRID; 2],
            degree: DEFAULT_DEGREE,
            tension: DEFAULT_TENSION,
            rigidity: DEFAULT_RIGIDITY,
            corrections: DEFAULT_CORRECTIONS,
            robust: RobustMode::Auto,
            robust_rounds: DEFAULT_ROBUST_ROUNDS,
            rational: false,
            weight_iterations: DEFAULT_WEIGHT_ITERATIONS,
            parallelism: Parallelism::Auto,
        }
    }
}

impl FitOptions {
    /// Checks the options on their own (not against a cloud).
    pub fn validate(&self) -> Result<(), FitError> {
        let opt = |name, value: String, why: &str| FitError::Option {
            name,
            value,
            why: why.into(),
        };
        if !(1..=MAX_FIT_DEGREE).contains(&self.degree) {
            return Err(opt(
                "degree",
                self.degree.to_string(),
                &format!("must be 1 to {MAX_FIT_DEGREE}"),
            ));
        }
        let [nu, nv] = self.grid;
        let grid = format!("{nu}x{nv}");
        if nu <= self.degree || nv <= self.degree {
            return Err(opt(
                "grid",
                grid,
                &format!(
                    "needs more than degree = {} control points per direction",
                    self.degree
                ),
            ));
        }
        if nu.checked_mul(nv).is_none_or(|n| n > MAX_CONTROL_POINTS) {
            return Err(opt(
                "grid",
                grid,
                &format!("more than {MAX_CONTROL_POINTS} control points"),
            ));
        }
        for (name, v) in [("tension", self.tension), ("rigidity", self.rigidity)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(opt(name, v.to_string(), "must be finite and non-negative"));
            }
        }
        if self.corrections > 100 || self.robust_rounds > 100 || self.weight_iterations > 100 {
            return Err(opt(
                "iterations",
                format!(
                    "{}/{}/{}",
                    self.corrections, self.robust_rounds, self.weight_iterations
                ),
                "corrections, robust rounds and weight iterations are at most 100",
            ));
        }
        Ok(())
    }

    /// Whether some fairness is on.
    pub fn has_fairness(&self) -> bool {
        self.tension > 0.0 || self.rigidity > 0.0
    }
}

/// Memory a fit of `points` points takes, in bytes (checked by the CLI against `--max-memory`
/// before the cloud is read into the fit): per point [`BYTES_PER_POINT`], per thread one banded
/// system, the Cholesky factor (about four times the band), and for rational fits the 4n x 4n
/// Gauss-Newton system (16 times the band, with fill).
pub fn memory_estimate(points: usize, opts: &FitOptions, threads: usize) -> u128 {
    let d = [opts.degree; 2];
    let band = system::Normal::bytes(opts.grid, d) as u128;
    let per_point = points as u128 * BYTES_PER_POINT as u128;
    let rational = if opts.rational { 16 * band * 4 } else { 0 };
    per_point + band * (threads as u128 + 5) + rational
}

/// Time per phase, in seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Base plane and first parameters.
    pub parametrize: f64,
    /// Normal equations (all rounds).
    pub assemble: f64,
    /// Fairness matrix, factorization and solves (all rounds).
    pub solve: f64,
    /// Parameter corrections and robust weights (all rounds).
    pub correct: f64,
    /// The rational (dynamic-weight) iterations.
    pub rational: f64,
    /// Final closest-point distances and statistics.
    pub distances: f64,
    /// Everything.
    pub total: f64,
}

/// What a fit reports (`--report`, `docs/formats.md`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitReport {
    /// Number of points.
    pub points: usize,
    /// Control net `[n_u, n_v]`.
    pub grid: [usize; 2],
    /// Degree in both directions.
    pub degree: usize,
    /// Whether the weights were fitted (rational surface).
    pub rational: bool,
    /// Tension `alpha` as given.
    pub tension: f64,
    /// Rigidity `beta` as given.
    pub rigidity: f64,
    /// Parameter-correction rounds.
    pub corrections: usize,
    /// The outlier mode as asked: `auto`, `none`, `huber` or `tukey` ([`RobustMode`]).
    pub robust_mode: RobustMode,
    /// The robust loss the fit used, if any (`tukey` when `auto` detected outliers).
    pub robust: Option<Robust>,
    /// Whether `auto` found gross outliers after the first round and went on robustly (false
    /// in the other modes).
    pub outliers_detected: bool,
    /// Gross outliers of the first (plain) round: points beyond Tukey's rejection distance of
    /// the larger of the global and their neighbours' robust scale, and beyond `1e-4` of the
    /// model size; what `auto` decides by ([`robust::gross_outliers`]; counted in every mode).
    pub first_round_outliers: usize,
    /// RMS of the closest-point distances of all points.
    pub rms: f64,
    /// Largest closest-point distance.
    pub max: f64,
    /// Mean closest-point distance.
    pub mean: f64,
    /// RMS over the points whose final weight is positive (without `robust`: all points in
    /// the domain).
    pub rms_inliers: f64,
    /// Points farther than Tukey's rejection distance `4.685 sigma` from the surface (0
    /// without `robust`).
    pub outliers: usize,
    /// Points whose final robust weight is below [`DOWNWEIGHTED`] (farther than `2.69 sigma`
    /// with Huber, `2.53 sigma` with Tukey; 0 without `robust`).
    pub downweighted: usize,
    /// Robust scale `sigma` of the last round (0 without `robust`).
    pub sigma: f64,
    /// Rounds that were computed and thrown away because they raised the robust objective
    /// ([`robust`] module docs; the fit stops at the first).
    pub rejected_rounds: usize,
    /// Times the fit trimmed its domain to the inliers ([`plane`] module docs).
    pub domain_updates: usize,
    /// Points outside the final (trimmed) rectangle, left out of the fit (weight 0; 0 unless
    /// the domain was trimmed).
    pub outside: usize,
    /// The cell of a [`REGION_CELLS`] x [`REGION_CELLS`] partition of the domain with the
    /// largest RMS distance of its points.
    pub worst_region: Region,
    /// What the user should know: a net that the points cannot determine.
    pub warnings: Vec<String>,
    /// Fairness energy `U = 1/2 P^T K P` of the result (`d-nurbs.txt` eq 17, summed over x, y,
    /// z; squared model units, like the data term).
    pub fairness_energy: f64,
    /// Data term `1/(2W) sum w_k d_k^2` of the result.
    pub data_term: f64,
    /// RMS distance after each round (round 0 is the base-plane parametrization; the
    /// distances are each round's parameter-corrected ones).
    pub history_rms: Vec<f64>,
    /// Weights range `[min, max]` of the result (`[1, 1]` for polynomial fits).
    pub weight_range: [f64; 2],
    /// The base plane.
    pub base: BasePlane,
    /// Size of the model (largest principal extent of the cloud, 2 x the rectangle diagonal).
    pub size: f64,
    /// Time per phase.
    pub timings: Timings,
}

/// Most rounds added to a fit because its domain was trimmed in its last round.
pub const MAX_EXTRA_ROUNDS: usize = 2;

/// Robust weight below which a point counts as down-weighted in the report.
pub const DOWNWEIGHTED: f64 = 0.5;

/// Cells per direction of the partition that finds the worst region of a fit.
pub const REGION_CELLS: usize = 8;

/// A region of the parameter domain and how well its points are fitted
/// ([`FitReport::worst_region`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Region {
    /// Parameter range in `u`.
    pub u: [f64; 2],
    /// Parameter range in `v`.
    pub v: [f64; 2],
    /// The surface point at the cell's centre (model coordinates).
    pub center: [f64; 3],
    /// Points whose parameter lies in the cell.
    pub points: usize,
    /// Of those, points beyond Tukey's rejection distance (0 without `robust`).
    pub outliers: usize,
    /// RMS closest-point distance of the cell's points.
    pub rms: f64,
    /// Largest closest-point distance in the cell.
    pub max: f64,
}

/// The cell of a `REGION_CELLS^2` partition of `[0, 1]^2` whose points have the largest RMS
/// distance; points farther than `cut` count as outliers.
fn worst_region(surface: &NurbsSurface, params: &[[f64; 2]], d: &[f64], cut: f64) -> Region {
    let m = REGION_CELLS;
    let mut cells = vec![(0usize, 0usize, 0.0f64, 0.0f64); m * m];
    let cell = |t: f64| ((t * m as f64) as usize).min(m - 1);
    for (uv, &dk) in params.iter().zip(d) {
        let c = &mut cells[cell(uv[0]) * m + cell(uv[1])];
        c.0 += 1;
        c.1 += usize::from(dk > cut);
        c.2 += dk * dk;
        c.3 = c.3.max(dk);
    }
    let (k, &(points, outliers, s2, max)) = cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.0 > 0)
        .max_by(|a, b| (a.1.2 / a.1.0 as f64).total_cmp(&(b.1.2 / b.1.0 as f64)))
        .unwrap_or((0, &(0, 0, 0.0, 0.0)));
    let (i, j) = (k / m, k % m);
    let h = 1.0 / m as f64;
    let (u, v) = (
        [i as f64 * h, (i + 1) as f64 * h],
        [j as f64 * h, (j + 1) as f64 * h],
    );
    let ev = project::Evaluator::new(surface);
    let c = ev
        .eval_order(
            0.5 * (u[0] + u[1]),
            0.5 * (v[0] + v[1]),
            1,
            &mut ev.scratch(),
        )
        .s;
    Region {
        u,
        v,
        center: [c[0], c[1], c[2]],
        points,
        outliers,
        rms: (s2 / points.max(1) as f64).sqrt(),
        max,
    }
}

/// A fitted surface with its data.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The surface (domain `[0, 1]^2`).
    pub surface: NurbsSurface,
    /// Each point's parameter (its closest point on the surface).
    pub params: Vec<[f64; 2]>,
    /// Each point's closest-point distance.
    pub distances: Vec<f64>,
    /// Each point's robust weight (all 1 without `robust`).
    pub weights: Vec<f64>,
    /// The report.
    pub report: FitReport,
}

/// Checks a cloud: count, finiteness.
pub fn check_points(points: &[Vec3], opts: &FitOptions) -> Result<(), FitError> {
    let n = points.len();
    if n > MAX_POINTS {
        return Err(FitError::TooManyPoints {
            found: n,
            limit: MAX_POINTS,
        });
    }
    if let Some(index) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        let p = points[index];
        return Err(FitError::NonFinite {
            index,
            x: p[0],
            y: p[1],
            z: p[2],
        });
    }
    if n < 3 {
        return Err(FitError::TooFewPoints {
            found: n,
            why: "a surface needs at least 3 points".into(),
        });
    }
    let ctrl = opts.grid[0] * opts.grid[1];
    if !opts.has_fairness() && n < ctrl {
        return Err(FitError::TooFewPoints {
            found: n,
            why: format!(
                "the grid {}x{} has {ctrl} control points and no fairness term: use a smaller \
                 grid or some fairness (tension or rigidity > 0)",
                opts.grid[0], opts.grid[1]
            ),
        });
    }
    Ok(())
}

/// Fits a surface to `points` (module docs).
pub fn fit_surface(points: &[Vec3], opts: &FitOptions) -> Result<Fit, FitError> {
    let t0 = Instant::now();
    opts.validate()?;
    check_points(points, opts)?;
    let par = opts.parallelism;
    let mut timings = Timings::default();

    let t = Instant::now();
    let mut base = base_plane(points, par)?;
    let extents = base.extents();
    let size = 2.0 * (extents[0].hypot(extents[1])).max(base.spread[0]);
    let mut params: Vec<[f64; 2]> = map_points(points, par, |x| base.param(x));
    timings.parametrize = t.elapsed().as_secs_f64();

    let p = opts.degree;
    let knots = [
        KnotVector::clamped_uniform(p, opts.grid[0]),
        KnotVector::clamped_uniform(p, opts.grid[1]),
    ];
    let knots = match knots {
        [Ok(a), Ok(b)] => [a, b],
        [Err(e), _] | [_, Err(e)] => {
            return Err(FitError::Option {
                name: "grid",
                value: format!("{}x{}", opts.grid[0], opts.grid[1]),
                why: e.to_string(),
            });
        }
    };
    let n = opts.grid[0] * opts.grid[1];
    let bw = (2 * p + 1) * (2 * p + 1);
    // The stiffness band and eq 17's densities on a base rectangle.
    type Fairness = (Vec<f64>, [f64; 2], [f64; 3]);
    let stiffness_on = |extents: [f64; 2]| -> Result<Fairness, FitError> {
        let (alpha, beta) = energy::densities(opts.tension, opts.rigidity, extents);
        let mut k = vec![0.0; n * bw];
        energy::add_separable(&mut k, &knots, alpha, beta)?;
        Ok((k, alpha, beta))
    };
    let (mut stiffness, mut alpha, mut beta) = stiffness_on(extents)?;

    let mut weights = vec![1.0; points.len()];
    let mut distances = vec![0.0; points.len()];
    // The candidate round's parameters and distances (swapped in when it is accepted).
    let mut cand_params = vec![[0.0; 2]; points.len()];
    let mut cand_distances = vec![0.0; points.len()];
    let mut history = Vec::new();
    let mut sigma = 0.0;
    // The robust loss in use: from the start, or from `auto`'s detection after round 0.
    let mut loss = opts.robust.loss();
    let (mut outliers_detected, mut first_round_outliers) = (false, 0usize);
    let mut rounds = 1
        + opts.corrections
        + if loss.is_some() {
            opts.robust_rounds
        } else {
            0
        };
    // The accepted state: control points, robust scale and fairness energy of the last
    // accepted round (its parameters and distances are `params`, `distances`).
    let mut ctrl = Vec::new();
    let (mut best_sigma, mut best_energy) = (0.0, 0.0);
    let mut judge = false;
    let (mut rejected_rounds, mut domain_updates) = (0usize, 0usize);
    // Whether each point lies outside the (trimmed) domain; rounds added for a new domain.
    let mut outside = vec![false; points.len()];
    let (mut round, mut extra_rounds) = (0usize, 0usize);
    // The accepted round's closest points run to convergence on its surface, where they moved
    // on from its corrected parameters (`correct_all`): the final distances, unless the
    // parameters were remapped afterwards.
    let mut finish: Option<Vec<(usize, [f64; 2], f64)>> = None;
    while round < rounds {
        let t = Instant::now();
        let use_w = (loss.is_some() && round > 0) || domain_updates > 0;
        let mut normal =
            system::assemble(&knots, points, &params, use_w.then_some(&weights[..]), par);
        timings.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        if normal.weight <= 0.0 {
            return Err(FitError::Diverged {
                why: "every point has robust weight 0".into(),
            });
        }
        let inv = 1.0 / normal.weight;
        for (b, k) in normal.band.iter_mut().zip(&stiffness) {
            *b = *b * inv + k;
        }
        let rhs: Vec<Vec3> = normal.rhs.iter().map(|r| r * inv).collect();
        let cand = system::solve(&normal, &rhs)?;
        timings.solve += t.elapsed().as_secs_f64();

        let t = Instant::now();
        let surface = polynomial(&knots, cand.clone())?;
        // Only the round that is the last so far goes on to the final closest points (the
        // continuation costs evaluations where the corrected parameters are still moving).
        let more = if round + 1 == rounds {
            REPORT_NEWTON_STEPS
        } else {
            0
        };
        let cand_finish = correct_all(
            &surface,
            points,
            &params,
            &mut cand_params,
            &mut cand_distances,
            more,
            par,
        );
        let cand_sigma = robust::scale(&cand_distances, size);
        let cand_energy = 0.5 * system::quadratic_form(&stiffness, opts.grid, [p, p], &cand);
        if judge {
            // Accept the round only when the robust objective falls (robust module docs).
            let c = robust::TUKEY_C * cand_sigma.min(best_sigma);
            let new = robust::objective(&cand_distances, c) + cand_energy;
            let old = robust::objective(&distances, c) + best_energy;
            if new.is_nan() || new >= old {
                rejected_rounds += 1;
                timings.correct += t.elapsed().as_secs_f64();
                break;
            }
        }
        ctrl = cand;
        (best_sigma, best_energy) = (cand_sigma, cand_energy);
        std::mem::swap(&mut params, &mut cand_params);
        std::mem::swap(&mut distances, &mut cand_distances);
        finish = cand_finish;
        history.push(rms(&distances));
        judge = true;
        if round == 0 {
            // Gross outliers in a plain fit (robust::RobustMode): `auto` goes on as `tukey`.
            first_round_outliers =
                robust::gross_outliers(&distances, &params, cand_sigma, robust::AUTO_FLOOR * size);
            if opts.robust == RobustMode::Auto
                && robust::auto_switches(first_round_outliers, points.len())
            {
                loss = Some(Robust::Tukey);
                outliers_detected = true;
                rounds += opts.robust_rounds;
            }
        }
        if let Some(loss) = loss {
            sigma = cand_sigma;
            robust::weights(loss, &distances, sigma, &mut weights);
        }
        // The domain comes from the inliers (plane module docs): it shrinks to drop a fringe
        // where most points are outliers (beyond Tukey's cut of this round's scale), never
        // one of inliers (a sharp corner of a clean scan).
        let cut = robust::TUKEY_C * cand_sigma;
        if let Some(rect) = base.dense_rect(points, |k| distances[k] <= cut) {
            let [lu, lv] = base.extents();
            let old = base.rect;
            let moved = [
                (rect[0] - old[0]) / lu,
                (old[1] - rect[1]) / lu,
                (rect[2] - old[2]) / lv,
                (old[3] - rect[3]) / lv,
            ]
            .into_iter()
            .fold(0.0f64, f64::max);
            // A point left out is an outlier when its height over the surface's new edge
            // (along the plane's normal, at the nearest point of the new rectangle) exceeds
            // the cut plus its in-plane distance to the rectangle: a slope up to 1 continues
            // the surface (a clean corner), a jump does not (a stray return displaced along
            // the scanner's axis). Distances alone cannot tell: a plain fit passes through
            // the outliers of a fringe.
            let (mut dropped, mut far) = (0usize, 0usize);
            if moved > plane::DOMAIN_TOL {
                let surface = polynomial(&knots, ctrl.clone())?;
                let ev = project::Evaluator::new(&surface);
                let mut sc = ev.scratch();
                let e3 = Vec3::from(base.axes[2]);
                for x in points {
                    let ab = base.project(x);
                    if plane::inside(&rect, ab) {
                        continue;
                    }
                    dropped += 1;
                    let ca = [ab[0].clamp(rect[0], rect[1]), ab[1].clamp(rect[2], rect[3])];
                    let delta = (ab[0] - ca[0]).hypot(ab[1] - ca[1]);
                    let uv = [(ca[0] - old[0]) / lu, (ca[1] - old[2]) / lv];
                    let edge = ev.eval_order(uv[0], uv[1], 1, &mut sc).s;
                    far += usize::from((x - edge).dot(&e3).abs() > cut + delta);
                }
            }
            if moved > plane::DOMAIN_TOL && 2 * far > dropped && extra_rounds < MAX_EXTRA_ROUNDS {
                base.rect = rect;
                for uv in params.iter_mut() {
                    *uv = base.remap(&old, *uv);
                }
                finish = None;
                for (o, x) in outside.iter_mut().zip(points) {
                    *o = !plane::inside(&rect, base.project(x));
                }
                (stiffness, alpha, beta) = stiffness_on(base.extents())?;
                // A new domain is a new problem: its first round is not judged against the
                // old one, and it gets a round of its own when it came last.
                judge = false;
                domain_updates += 1;
                if round + 1 == rounds {
                    rounds += 1;
                    extra_rounds += 1;
                }
            }
        }
        if domain_updates > 0 {
            // Points outside the domain are not fitted.
            for (w, &o) in weights.iter_mut().zip(&outside) {
                if o {
                    *w = 0.0;
                }
            }
        }
        round += 1;
        timings.correct += t.elapsed().as_secs_f64();
    }
    drop((cand_params, cand_distances));
    // The rational refinement moves the surface: its final distances are computed afresh.
    let finish = finish.filter(|_| !opts.rational);
    let mut surface = polynomial(&knots, ctrl)?;
    let mut energy_value =
        0.5 * system::quadratic_form(&stiffness, opts.grid, [p, p], surface.control_points());

    if opts.rational {
        let t = Instant::now();
        let out = rational::refine(
            surface,
            points,
            &mut params,
            &weights,
            alpha,
            beta,
            opts.weight_iterations,
            par,
        )?;
        surface = out.surface;
        energy_value = out.energy;
        timings.rational = t.elapsed().as_secs_f64();
    }

    let t = Instant::now();
    match finish {
        // The last accepted round's continuation: the same as projecting again.
        Some(moved) => {
            for (k, uv, d) in moved {
                params[k] = uv;
                distances[k] = d;
            }
        }
        None => project_all(
            &surface,
            points,
            &mut params,
            &mut distances,
            REPORT_NEWTON_STEPS,
            REPORT_PARAM_TOL,
            false,
            par,
        ),
    }
    let (mut s2, mut max, mut sum) = (0.0f64, 0.0f64, 0.0f64);
    let (mut wsum, mut wd2, mut in2, mut nin, mut outliers) = (0.0, 0.0, 0.0, 0usize, 0usize);
    for (d, w) in distances.iter().zip(&weights) {
        s2 += d * d;
        sum += d;
        max = max.max(*d);
        wsum += w;
        wd2 += w * d * d;
        if *w > 0.0 {
            in2 += d * d;
            nin += 1;
        }
        if *d > robust::TUKEY_C * sigma {
            outliers += 1;
        }
    }
    let np = points.len() as f64;
    let downweighted = if loss.is_some() {
        weights.iter().filter(|&&w| w < DOWNWEIGHTED).count()
    } else {
        0
    };
    let outside = outside.iter().filter(|&&o| o).count();
    let cut = if loss.is_some() {
        robust::TUKEY_C * sigma
    } else {
        f64::INFINITY
    };
    let worst_region = worst_region(&surface, &params, &distances, cut);
    let mut warnings = Vec::new();
    if points.len() < n {
        warnings.push(format!(
            "{} points cannot determine the {}x{} net: it has {n} control points, so at least \
             {n} points are needed (one per control point); the fairness term alone shapes the \
             rest",
            points.len(),
            opts.grid[0],
            opts.grid[1]
        ));
    }
    let wr = surface
        .weights()
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |a, &w| {
            [a[0].min(w), a[1].max(w)]
        });
    timings.distances = t.elapsed().as_secs_f64();
    timings.total = t0.elapsed().as_secs_f64();
    let report = FitReport {
        points: points.len(),
        grid: opts.grid,
        degree: p,
        rational: opts.rational,
        tension: opts.tension,
        rigidity: opts.rigidity,
        corrections: opts.corrections,
        robust_mode: opts.robust,
        robust: loss,
        outliers_detected,
        first_round_outliers,
        rms: (s2 / np).sqrt(),
        max,
        mean: sum / np,
        rms_inliers: if nin > 0 {
            (in2 / nin as f64).sqrt()
        } else {
            0.0
        },
        outliers: if loss.is_some() { outliers } else { 0 },
        downweighted,
        sigma,
        rejected_rounds,
        domain_updates,
        outside,
        worst_region,
        warnings,
        fairness_energy: energy_value,
        data_term: if wsum > 0.0 { 0.5 * wd2 / wsum } else { 0.0 },
        history_rms: history,
        weight_range: wr,
        base,
        size,
        timings,
    };
    Ok(Fit {
        surface,
        params,
        distances,
        weights,
        report,
    })
}

/// RMS of distances.
fn rms(d: &[f64]) -> f64 {
    (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt()
}

fn polynomial(knots: &[KnotVector; 2], ctrl: Vec<Vec3>) -> Result<NurbsSurface, FitError> {
    let w = vec![1.0; ctrl.len()];
    NurbsSurface::from_flat(knots.clone(), ctrl, w)
        .map_err(|e| FitError::Diverged { why: e.to_string() })
}

fn map_points<T: Send>(
    points: &[Vec3],
    par: Parallelism,
    f: impl Fn(&Vec3) -> T + Sync + Send,
) -> Vec<T> {
    if par.is_parallel_from(points.len(), system::PARALLEL_POINTS) {
        points.par_iter().map(f).collect()
    } else {
        points.iter().map(f).collect()
    }
}

/// Moves every parameter to its point's closest point on `surface` (at most `steps` Newton
/// steps, or Gauss-Newton steps when `newton` is false, from the current parameter) and writes
/// the distances.
pub fn project_all(
    surface: &NurbsSurface,
    points: &[Vec3],
    params: &mut [[f64; 2]],
    distances: &mut [f64],
    steps: usize,
    tol: f64,
    newton: bool,
    par: Parallelism,
) {
    let ev = project::Evaluator::new(surface);
    type Chunk<'a> = (&'a [Vec3], (&'a mut [[f64; 2]], &'a mut [f64]));
    let work = |(chunk_pts, (chunk_prm, chunk_d)): Chunk<'_>| {
        let mut sc = ev.scratch();
        for ((x, prm), d) in chunk_pts
            .iter()
            .zip(chunk_prm.iter_mut())
            .zip(chunk_d.iter_mut())
        {
            let (uv, dist) = ev.project(x, *prm, steps, tol, newton, &mut sc);
            *prm = uv;
            *d = dist;
        }
    };
    const CHUNK: usize = 1024;
    if par.is_parallel_from(points.len(), system::PARALLEL_POINTS) {
        points
            .par_chunks(CHUNK)
            .zip(
                params
                    .par_chunks_mut(CHUNK)
                    .zip(distances.par_chunks_mut(CHUNK)),
            )
            .for_each(work);
    } else {
        work((points, (params, distances)));
    }
}

/// One parameter-correction pass: `out` gets each point's parameter after at most
/// [`CORRECTION_NEWTON_STEPS`] Gauss-Newton steps from `params` on `surface`, `distances` its
/// distance. With `more > 0`, where those steps did not reach the tolerance
/// [`REPORT_PARAM_TOL`], the iteration goes on to convergence (at most `more` steps) and the
/// returned list holds `(index, parameter, distance)` of the points it moved: the final closest
/// points, should this round's surface be the result (what [`project_all`] from `out` with
/// `more` steps would give, without its evaluation at every start; issue 31).
fn correct_all(
    surface: &NurbsSurface,
    points: &[Vec3],
    params: &[[f64; 2]],
    out: &mut [[f64; 2]],
    distances: &mut [f64],
    more: usize,
    par: Parallelism,
) -> Option<Vec<(usize, [f64; 2], f64)>> {
    let ev = project::Evaluator::new(surface);
    const CHUNK: usize = 1024;
    type Chunk<'a> = (
        usize,
        (
            (&'a [Vec3], &'a [[f64; 2]]),
            (&'a mut [[f64; 2]], &'a mut [f64]),
        ),
    );
    let work = |(c, ((pts, prm), (out, d))): Chunk<'_>| {
        let mut sc = ev.scratch();
        let mut moved = Vec::new();
        for (k, (x, start)) in pts.iter().zip(prm).enumerate() {
            let (first, more) = ev.project_continued(
                x,
                *start,
                CORRECTION_NEWTON_STEPS,
                more,
                REPORT_PARAM_TOL,
                false,
                &mut sc,
            );
            (out[k], d[k]) = first;
            if let Some((uv, dist)) = more {
                moved.push((c * CHUNK + k, uv, dist));
            }
        }
        moved
    };
    let moved = if par.is_parallel_from(points.len(), system::PARALLEL_POINTS) {
        points
            .par_chunks(CHUNK)
            .zip(params.par_chunks(CHUNK))
            .zip(
                out.par_chunks_mut(CHUNK)
                    .zip(distances.par_chunks_mut(CHUNK)),
            )
            .enumerate()
            .map(work)
            .reduce(Vec::new, |mut a, mut b| {
                a.append(&mut b);
                a
            })
    } else {
        work((0, ((points, params), (out, distances))))
    };
    (more > 0).then_some(moved)
}

/// Closest-point distances from `points` to `surface`, each started from the given parameter
/// (for example a fit's [`Fit::params`]) and iterated to convergence.
pub fn closest_distances(
    surface: &NurbsSurface,
    points: &[Vec3],
    start: &[[f64; 2]],
    par: Parallelism,
) -> Vec<f64> {
    let mut params = start.to_vec();
    let mut d = vec![0.0; points.len()];
    project_all(
        surface,
        points,
        &mut params,
        &mut d,
        REPORT_NEWTON_STEPS,
        REPORT_PARAM_TOL,
        false,
        par,
    );
    d
}
