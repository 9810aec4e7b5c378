//! The collocation least-squares solve (`dynamic-pde-surfaces.txt` eq 6-12, 35, 37).
//!
//! At an instant t0 the solution function (5) (or (36) for a three-sided patch) meets the
//! boundary conditions (2) for any constants p_ijn. Substituted into the PDE (1) it leaves the
//! residual (6) `R_i = sum_j [sum_n B_ijn p_ijn + C_ij]` with, for a trial term `psi_n(u) g(v,t)`,
//!
//! `B_ijn = b_i psi_n'''' g + c_i psi_n'' g_vv + psi_n (d_i g_vvvv + rho g_tt + eta g_t)` (eq 7)
//!
//! and `C_ij` the same operator applied to the known part `sum_k a_ijk h_k(u) g` (eq 8). The
//! residual is evaluated at the M collocation points (eq 9) and `|B_i P_i + C_i|^2` minimised
//! (eq 10-12) by a column-pivoted QR of `B_i` ([`crate::lsq`]), which is the direct solve of
//! (9) when M = J (N - 3). As in the paper, the constants are treated as independent of t when
//! the time derivatives are taken (eq 7), and each instant is solved on its own.
//!
//! Side conditions of three- and four-sided patches (eq 33-37) are linear equations on the
//! constants: the coefficient of u^n of `x_i(u, v_s, t)` (or of `dx_i/dv`) must equal the given
//! polynomial's. Equations that involve no constant are compatibility checks (the curves must
//! meet at the corners) and are reported when they fail; the others are imposed exactly
//! (null-space method: particular solution by SVD, least squares on the null space).
//!
//! The trial functions are tabulated once per patch at the collocation rows; the basic
//! functions and their derivatives are evaluated once per collocation column per solve.

use crate::error::PdeError;
use crate::lsq::{self, LsqWork, RANK_TOLERANCE};
use crate::patch::{COMPONENT_NAMES, Component, PdePatch, SideCondition};
use crate::spectral::{Method, SpectralSolution};
use crate::trial::{PatchKind, Poly, TrialTable};
use nalgebra::DMatrix;

/// Relative tolerance for the compatibility of side conditions with the u-boundary conditions,
/// scaled by the largest boundary coefficient involved.
pub const SIDE_TOLERANCE: f64 = 1e-9;

/// A direction of constants that the collocation equations do not determine is harmless when
/// the surface change it causes, `|G z|` on a check grid, is below this fraction of the bound
/// `sum_c |z_c| |G_c|` (G: trial term times basic function at the check points).
pub const NULL_EFFECT_TOLERANCE: f64 = 1e-8;

/// Statistics of one solve.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// `|B_i P_i + C_i|` per component at the collocation points (eq 10).
    pub residual_norm: [f64; 3],
    /// Root mean square residual over all components and collocation points.
    pub residual_rms: f64,
    /// Per component: `|B_i P_i + C_i| / |C_i|`, the fraction of the residual of the Hermite
    /// part alone (all p = 0) that the trial terms leave (0 when C_i = 0). It exceeds 1 when
    /// side conditions (eqs 33-37) fix the trial constants instead of the least squares (11):
    /// on the aircraft's three-sided caps (nose and tail cap patches) the side conditions fix
    /// all 6 constants of the y and z components, nothing is left to minimise, and the
    /// Hermite part alone nearly solves the PDE there (`|C|` 6e-7 to 6e-6) while the
    /// side-fixed terms leave 1e-3 to 1e-2, a ratio of about 1,600 to 2,500 (issue 28,
    /// measured on `tests/aircraft.rs`). Read it with `residual_norm`, not alone.
    pub residual_relative: [f64; 3],
    /// Largest condition estimate of the equilibrated collocation matrices; 1.0 for a
    /// component whose constants the side conditions fix completely (no least-squares system
    /// is solved, as on the aircraft's caps) or that has no constants.
    pub condition: f64,
    /// Collocation points M.
    pub points: usize,
    /// Unknown constants per component.
    pub unknowns: [usize; 3],
    /// Per component: directions of the constants that change the surface but that the PDE
    /// residual does not see at all (not even between collocation points), so that the
    /// minimiser of (11) is not unique; the minimum-norm constants are used. This happens when
    /// basic functions share one shape in v at an instant and shape functions make the
    /// operator's terms overlap (e.g. Fig 5's `u(u - 1)` factors). 0 in well-posed problems.
    pub undetermined: [usize; 3],
}

/// The solved constants of a patch at one instant.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PatchSolution {
    /// The instant.
    pub t: f64,
    /// p_ijn per component, basic-major: index `j * U + k` for trial power
    /// `first_unknown_power + k` (eq 5, 36).
    pub constants: [Vec<f64>; 3],
    /// The polynomial factors `W_ij(u) = sum_k a_ijk h_k(u) + sum_n p_ijn psi_n(u)`, per
    /// component, basic-major: coefficient of u^n of basic j at `j * (N + 1) + n`.
    pub weights: [Vec<f64>; 3],
    /// Residuals and conditioning.
    pub stats: SolveStats,
    /// The Fourier-series or pseudospectral solution when the patch uses one of those methods
    /// ([`crate::spectral`], eq 19-23); then `constants` and `weights` are empty and the stats
    /// report only the constants determined (the spectral methods have no collocation residual).
    pub spectral: Option<SpectralSolution>,
}

/// Reusable workspace for solving patches (repeated solves allocate nothing for patches
/// without side conditions).
#[derive(Clone, Debug, Default)]
pub struct Solver {
    /// Per collocation column and basic: g, g_vv, g_vvvv, g_t, g_tt.
    gcols: Vec<[f64; 5]>,
    /// Per collocation point: b, c, d, rho, eta.
    coefs: Vec<[f64; 5]>,
    a: Vec<f64>,
    rhs: Vec<f64>,
    skip: Vec<bool>,
    x: Vec<f64>,
    work: LsqWork,
    /// |C| of the last assembled component.
    c_norm: f64,
}

impl Solver {
    /// A new workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// Solves `patch` at time `t`.
    pub fn solve(&mut self, patch: &PdePatch, t: f64) -> Result<PatchSolution, PdeError> {
        let mut s = PatchSolution::default();
        self.solve_into(patch, t, &mut s)?;
        Ok(s)
    }

    /// Solves `patch` at time `t` into `out`, reusing its buffers.
    pub fn solve_into(
        &mut self,
        patch: &PdePatch,
        t: f64,
        out: &mut PatchSolution,
    ) -> Result<(), PdeError> {
        if !t.is_finite() {
            return Err(PdeError::NonFinite {
                patch: patch.name.clone(),
                t,
                what: "the time".into(),
            });
        }
        out.t = t;
        if patch.method != Method::Collocation {
            let spectral = SpectralSolution::solve(patch, t)?;
            out.stats = SolveStats {
                unknowns: spectral.constants(),
                condition: 1.0,
                ..SolveStats::default()
            };
            for i in 0..3 {
                out.constants[i].clear();
                out.weights[i].clear();
            }
            out.spectral = Some(spectral);
            return Ok(());
        }
        out.spectral = None;
        let m = patch.collocation.points();
        let mut sum_sq = 0.0;
        let mut condition: f64 = 1.0;
        for i in 0..3 {
            let comp = &patch.components[i];
            let (res, cond, undetermined) =
                self.solve_component(patch, i, t, &mut out.constants[i])?;
            out.stats.undetermined[i] = undetermined;
            out.stats.residual_relative[i] = if self.c_norm > 0.0 {
                res / self.c_norm
            } else {
                0.0
            };
            out.stats.residual_norm[i] = res;
            out.stats.unknowns[i] = patch.unknowns(i);
            sum_sq += res * res;
            condition = condition.max(cond);
            fill_weights(patch, comp, &out.constants[i], &mut out.weights[i]);
        }
        out.stats.points = m;
        out.stats.residual_rms = (sum_sq / (3 * m) as f64).sqrt();
        out.stats.condition = condition;
        if !out.stats.residual_rms.is_finite()
            || out.weights.iter().flatten().any(|w| !w.is_finite())
        {
            return Err(PdeError::NonFinite {
                patch: patch.name.clone(),
                t,
                what:
                    "the solution (check shape functions, rho and eta for NaN or division by zero)"
                        .into(),
            });
        }
        Ok(())
    }

    /// Assembles and solves one component; returns (residual norm, condition estimate).
    fn solve_component(
        &mut self,
        patch: &PdePatch,
        i: usize,
        t: f64,
        p: &mut Vec<f64>,
    ) -> Result<(f64, f64, usize), PdeError> {
        let comp = &patch.components[i];
        let nb = comp.basics.len();
        let nu_k = patch.trial.unknowns_per_basic();
        let k_total = nb * nu_k;
        let m = patch.collocation.points();
        p.clear();
        p.resize(k_total, 0.0);
        if k_total == 0 {
            self.c_norm = 0.0;
            return Ok((0.0, 1.0, 0));
        }
        assemble(
            patch,
            i,
            t,
            &patch.colloc_u,
            &patch.colloc_v,
            &patch.colloc_table,
            &mut self.gcols,
            &mut self.coefs,
            &mut self.a,
            &mut self.rhs,
        );
        if self.a.iter().chain(&self.rhs).any(|x| !x.is_finite()) {
            return Err(PdeError::NonFinite {
                patch: patch.name.clone(),
                t,
                what: format!(
                    "the collocation system of component {} (a shape function, rho, eta or a \
                     basic function or its derivative is NaN or infinite at a collocation point)",
                    COMPONENT_NAMES[i]
                ),
            });
        }
        self.c_norm = self.rhs.iter().map(|x| x * x).sum::<f64>().sqrt();
        self.skip.clear();
        self.skip.resize(k_total, false);
        if comp.sides.any() {
            return self.solve_with_sides(patch, i, t, p);
        }
        self.x.clear();
        self.x.resize(k_total, 0.0);
        let info = lsq::solve(
            m,
            k_total,
            &mut self.a,
            &mut self.rhs,
            &self.skip,
            &mut self.x,
            &mut self.work,
        );
        let nulls: Vec<Vec<f64>> = self
            .work
            .free_columns()
            .iter()
            .map(|&f| self.work.null_vector(&self.a, k_total, f))
            .collect();
        let undetermined = classify_null_space(patch, i, t, &nulls, info.condition)?;
        min_norm(&mut self.x, &nulls);
        p.copy_from_slice(&self.x);
        Ok((info.residual, info.condition, undetermined))
    }

    /// Equality-constrained least squares for patches with side conditions (eq 35, 37).
    fn solve_with_sides(
        &mut self,
        patch: &PdePatch,
        i: usize,
        t: f64,
        p: &mut [f64],
    ) -> Result<(f64, f64, usize), PdeError> {
        let comp = &patch.components[i];
        let nb = comp.basics.len();
        let nu_k = patch.trial.unknowns_per_basic();
        let k_total = nb * nu_k;
        let m = patch.collocation.points();
        let n1 = patch.trial.n_max + 1;
        let (v0, v1) = patch.v_range;
        let mut rows: Vec<Vec<f64>> = Vec::new();
        let mut rhs_eq: Vec<f64> = Vec::new();
        let mut scale: f64 = 1.0;
        for a_j in &comp.coefficients {
            for a in a_j {
                scale = scale.max(a.abs());
            }
        }
        let sides: [(&Option<SideCondition>, f64, bool); 4] = [
            (&comp.sides.v0, v0, false),
            (&comp.sides.dv0, v0, true),
            (&comp.sides.v1, v1, false),
            (&comp.sides.dv1, v1, true),
        ];
        for (side, vs, tangent) in sides {
            let Some(side) = side else { continue };
            let gs: Vec<f64> = comp
                .basics
                .iter()
                .map(|b| {
                    if tangent {
                        b.g_v.eval(0.0, vs, t)
                    } else {
                        b.g.eval(0.0, vs, t)
                    }
                })
                .collect();
            let beta: Vec<f64> = side
                .coefficients
                .iter()
                .map(|e| e.eval(0.0, vs, t))
                .collect();
            for b in &beta {
                scale = scale.max(b.abs());
            }
            for n in 0..n1 {
                let target = beta.get(n).copied().unwrap_or(0.0);
                let mut known = 0.0;
                let mut row = vec![0.0; k_total];
                for j in 0..nb {
                    for (kk, h) in patch.trial.known.iter().enumerate() {
                        known += comp.coefficients[j][kk] * h[n] * gs[j];
                    }
                    for (k, psi) in patch.trial.unknown.iter().enumerate() {
                        row[j * nu_k + k] = psi[n] * gs[j];
                    }
                }
                if row.iter().all(|&x| x == 0.0) {
                    if (target - known).abs() > SIDE_TOLERANCE * scale.max(known.abs()) {
                        return Err(PdeError::InconsistentSides {
                            patch: patch.name.clone(),
                            component: COMPONENT_NAMES[i],
                            t,
                            message: format!(
                                "{}: the coefficient of u^{n} is {target} but the u-boundary \
                                 conditions give {known} there; the side and the u = 0{} \
                                 conditions must agree at the corner",
                                side.place,
                                if patch.kind() == PatchKind::TwoEnds {
                                    " / u = 1"
                                } else {
                                    ""
                                }
                            ),
                        });
                    }
                    continue;
                }
                rows.push(row);
                rhs_eq.push(target - known);
            }
        }
        // Drop columns of vanishing basic functions from the constraints too.
        for row in &mut rows {
            for (x, &s) in row.iter_mut().zip(&self.skip) {
                if s {
                    *x = 0.0;
                }
            }
        }
        let b_mat = DMatrix::from_column_slice(m, k_total, &self.a);
        let rhs = nalgebra::DVector::from_column_slice(&self.rhs);
        let (p0, z) = if rows.is_empty() {
            (
                nalgebra::DVector::zeros(k_total),
                DMatrix::identity(k_total, k_total),
            )
        } else {
            let r = rows.len().max(k_total);
            let mut a_eq = DMatrix::zeros(r, k_total);
            for (q, row) in rows.iter().enumerate() {
                for (k, &x) in row.iter().enumerate() {
                    a_eq[(q, k)] = x;
                }
            }
            let mut b_eq = nalgebra::DVector::zeros(r);
            for (q, &x) in rhs_eq.iter().enumerate() {
                b_eq[q] = x;
            }
            let svd = a_eq.clone().svd(true, true);
            let (Some(u), Some(vt)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
                return Err(PdeError::NonFinite {
                    patch: patch.name.clone(),
                    t,
                    what: "the SVD of the side conditions".into(),
                });
            };
            let smax = svd.singular_values.max();
            let keep: Vec<usize> = (0..svd.singular_values.len())
                .filter(|&q| svd.singular_values[q] > RANK_TOLERANCE * smax)
                .collect();
            let mut p0 = nalgebra::DVector::zeros(k_total);
            for &q in &keep {
                let coef = u.column(q).dot(&b_eq) / svd.singular_values[q];
                p0 += vt.row(q).transpose() * coef;
            }
            let misfit = (&a_eq * &p0 - &b_eq).amax();
            if misfit > SIDE_TOLERANCE * scale * (k_total as f64) {
                return Err(PdeError::InconsistentSides {
                    patch: patch.name.clone(),
                    component: COMPONENT_NAMES[i],
                    t,
                    message: format!(
                        "the side conditions cannot all hold (misfit {misfit:.3e}): they \
                         contradict each other or need more basic functions of v to be met \
                         (each power of u can meet only as many side conditions as there are \
                         basic functions with independent values at v0 and v1)"
                    ),
                });
            }
            let null: Vec<usize> = (0..vt.nrows()).filter(|q| !keep.contains(q)).collect();
            let mut z = DMatrix::zeros(k_total, null.len());
            for (c, &q) in null.iter().enumerate() {
                z.set_column(c, &vt.row(q).transpose());
            }
            (p0, z)
        };
        let reduced_rhs = &rhs - &b_mat * &p0;
        if z.ncols() == 0 {
            p.copy_from_slice(p0.as_slice());
            return Ok((reduced_rhs.norm(), 1.0, 0));
        }
        let bz = &b_mat * &z;
        let nz = z.ncols();
        if nz > m {
            return Err(PdeError::TooFewCollocationPoints {
                patch: patch.name.clone(),
                component: COMPONENT_NAMES[i],
                unknowns: nz,
                basics: nb,
                per_basic: nu_k,
                points: m,
            });
        }
        let mut a = bz.as_slice().to_vec();
        let mut b = reduced_rhs.as_slice().to_vec();
        let mut y = vec![0.0; nz];
        let skip = vec![false; nz];
        let info = lsq::solve(m, nz, &mut a, &mut b, &skip, &mut y, &mut self.work);
        let nulls: Vec<Vec<f64>> = self
            .work
            .free_columns()
            .iter()
            .map(|&f| self.work.null_vector(&a, nz, f))
            .collect();
        min_norm(&mut y, &nulls);
        let full: Vec<Vec<f64>> = nulls
            .iter()
            .map(|zr| {
                (&z * nalgebra::DVector::from_column_slice(zr))
                    .as_slice()
                    .to_vec()
            })
            .collect();
        let undetermined = classify_null_space(patch, i, t, &full, info.condition)?;
        let pz = p0 + z * nalgebra::DVector::from_column_slice(&y);
        p.copy_from_slice(pz.as_slice());
        Ok((info.residual, info.condition, undetermined))
    }
}

fn rank_hint(patch: &PdePatch, i: usize) -> String {
    let per = patch.trial.unknowns_per_basic();
    let j = patch.components[i].basics.len();
    format!(
        "use more collocation points (now {} x {}): the u direction needs at least {per} \
         distinct values, and up to J (N - 3) = {} when basic functions have the same shape in \
         v at this instant (e.g. cos(v) and t^2*cos(v)); or fewer trial terms (N = {}); or \
         remove linearly dependent basic functions",
        patch.collocation.nu,
        patch.collocation.nv,
        j * per,
        patch.trial.n_max
    )
}

fn rank_error(
    patch: &PdePatch,
    i: usize,
    t: f64,
    column: usize,
    condition: f64,
    hint: String,
) -> PdeError {
    let nu_k = patch.trial.unknowns_per_basic();
    let j = column / nu_k;
    PdeError::RankDeficient {
        patch: patch.name.clone(),
        component: COMPONENT_NAMES[i],
        t,
        basic: patch.components[i].basics[j].name.clone(),
        power: patch.trial.power_of_unknown(column % nu_k),
        condition,
        hint,
    }
}

/// Whether the constants' direction `z` leaves the surface of component `i` unchanged at `t`
/// (checked on the patch's check grid, which differs from the collocation grid). This accepts
/// basic functions that vanish at the instant (`t*sin(5*v)` at t = 0 with no damping) or
/// coincide there (`cos(v)` and `t^2*cos(v)`), and rejects a grid too coarse to see a term.
///
/// `gs[b][j]` is basic function j at the check grid's column b.
fn harmless(patch: &PdePatch, i: usize, gs: &[Vec<f64>], z: &[f64]) -> bool {
    let comp = &patch.components[i];
    let nu_k = patch.trial.unknowns_per_basic();
    let nk = patch.trial.known.len();
    let table = &patch.check_table;
    let w = table.width;
    let nb = comp.basics.len();
    let mut effect = 0.0;
    for ra in 0..patch.check_u.len() {
        let psi = &table.value[ra * w + nk..(ra + 1) * w];
        let wj: Vec<f64> = (0..nb)
            .map(|j| (0..nu_k).map(|k| z[j * nu_k + k] * psi[k]).sum())
            .collect();
        for g in gs {
            let x: f64 = (0..nb).map(|j| wj[j] * g[j]).sum();
            effect += x * x;
        }
    }
    let mut bound = 0.0;
    for j in 0..nb {
        let gnorm = gs.iter().map(|g| g[j] * g[j]).sum::<f64>().sqrt();
        for k in 0..nu_k {
            let pnorm = (0..patch.check_u.len())
                .map(|ra| table.value[ra * w + nk + k].powi(2))
                .sum::<f64>()
                .sqrt();
            bound += z[j * nu_k + k].abs() * pnorm * gnorm;
        }
    }
    effect.sqrt() <= NULL_EFFECT_TOLERANCE * bound
}

/// Sorts the undetermined directions of a solve: harmless (the surface does not change),
/// intrinsic (the residual operator is blind to them everywhere, not only at the collocation
/// points: counted, minimum norm used), or a too coarse collocation grid (an error).
fn classify_null_space(
    patch: &PdePatch,
    i: usize,
    t: f64,
    nulls: &[Vec<f64>],
    condition: f64,
) -> Result<usize, PdeError> {
    if nulls.is_empty() {
        return Ok(0);
    }
    let comp = &patch.components[i];
    let gs: Vec<Vec<f64>> = patch
        .check_v
        .iter()
        .map(|&v| comp.basics.iter().map(|b| b.g.eval(0.0, v, t)).collect())
        .collect();
    let mut intrinsic = 0;
    for z in nulls {
        if harmless(patch, i, &gs, z) {
            continue;
        }
        if residual_blind(patch, i, t, z) {
            intrinsic += 1;
            continue;
        }
        let col = z
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map_or(0, |(k, _)| k);
        return Err(rank_error(patch, i, t, col, condition, rank_hint(patch, i)));
    }
    Ok(intrinsic)
}

/// Whether the PDE residual operator applied to the constants' direction `z` vanishes on the
/// check grid (which shares no point with the collocation grid).
fn residual_blind(patch: &PdePatch, i: usize, t: f64, z: &[f64]) -> bool {
    let (mut gcols, mut coefs, mut a, mut rhs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    assemble(
        patch,
        i,
        t,
        &patch.check_u,
        &patch.check_v,
        &patch.check_table,
        &mut gcols,
        &mut coefs,
        &mut a,
        &mut rhs,
    );
    let m = rhs.len();
    let mut effect = vec![0.0; m];
    let mut bound = 0.0;
    for (c, &zc) in z.iter().enumerate() {
        let col = &a[c * m..(c + 1) * m];
        bound += zc.abs() * col.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (e, x) in effect.iter_mut().zip(col) {
            *e += zc * x;
        }
    }
    effect.iter().map(|x| x * x).sum::<f64>().sqrt() <= NULL_EFFECT_TOLERANCE * bound
}

/// Removes from `x` its components along the span of `nulls` (giving the minimum-norm
/// minimiser when `x` is a minimiser and `nulls` spans the null space).
fn min_norm(x: &mut [f64], nulls: &[Vec<f64>]) {
    if nulls.is_empty() {
        return;
    }
    let n = DMatrix::from_fn(x.len(), nulls.len(), |r, c| nulls[c][r]);
    let xv = nalgebra::DVector::from_column_slice(x);
    let gram = n.transpose() * &n;
    if let Some(chol) = gram.cholesky() {
        let coef = chol.solve(&(n.transpose() * &xv));
        let proj = xv - n * coef;
        x.copy_from_slice(proj.as_slice());
    }
}

/// Assembles the collocation matrix B (column-major, rows `us x vs` u-major) and `rhs = -C`
/// for component `i` at `t` (eq 7-9). Basic functions are evaluated once per column of `vs`;
/// the trial functions come tabulated at `us`.
fn assemble(
    patch: &PdePatch,
    i: usize,
    t: f64,
    us: &[f64],
    vs: &[f64],
    table: &TrialTable,
    gcols: &mut Vec<[f64; 5]>,
    coefs: &mut Vec<[f64; 5]>,
    a: &mut Vec<f64>,
    rhs: &mut Vec<f64>,
) {
    let comp = &patch.components[i];
    let nb = comp.basics.len();
    let nu_k = patch.trial.unknowns_per_basic();
    let nk = patch.trial.known.len();
    let k_total = nb * nu_k;
    let (nu, nv) = (us.len(), vs.len());
    let m = nu * nv;
    gcols.clear();
    for &v in vs {
        for b in &comp.basics {
            gcols.push([
                b.g.eval(0.0, v, t),
                b.g_vv.eval(0.0, v, t),
                b.g_vvvv.eval(0.0, v, t),
                b.g_t.eval(0.0, v, t),
                b.g_tt.eval(0.0, v, t),
            ]);
        }
    }
    // Shape functions, density and damping per point (constants fast path).
    let fields = [
        &comp.shape.b,
        &comp.shape.c,
        &comp.shape.d,
        &patch.rho,
        &patch.eta,
    ];
    let all_const = fields.iter().all(|f| f.as_const().is_some());
    coefs.clear();
    if all_const {
        coefs.push(fields.map(|f| f.as_const().unwrap_or(0.0)));
    } else {
        for &u in us {
            for &v in vs {
                coefs.push(fields.map(|f| f.eval(u, v, t)));
            }
        }
    }
    a.clear();
    a.resize(m * k_total, 0.0);
    rhs.clear();
    rhs.resize(m, 0.0);
    let w = table.width;
    for ra in 0..nu {
        let h0 = &table.value[ra * w..(ra + 1) * w];
        let h2 = &table.d2[ra * w..(ra + 1) * w];
        let h4 = &table.d4[ra * w..(ra + 1) * w];
        for cb in 0..nv {
            let row = ra * nv + cb;
            let [bb, cc, dd, rho, eta] = if all_const { coefs[0] } else { coefs[row] };
            let mut c_known = 0.0;
            for j in 0..nb {
                let [g, gvv, g4, gt, gtt] = gcols[cb * nb + j];
                let e = dd * g4 + rho * gtt + eta * gt;
                let (bg, cg) = (bb * g, cc * gvv);
                let a_j = &comp.coefficients[j];
                for k in 0..nk {
                    c_known += a_j[k] * (bg * h4[k] + cg * h2[k] + e * h0[k]);
                }
                for k in 0..nu_k {
                    let q = nk + k;
                    a[row + (j * nu_k + k) * m] = bg * h4[q] + cg * h2[q] + e * h0[q];
                }
            }
            rhs[row] = -c_known;
        }
    }
}

/// W_ij(u) = sum_k a_ijk h_k(u) + sum_n p_ijn psi_n(u), as polynomial coefficients.
fn fill_weights(patch: &PdePatch, comp: &Component, p: &[f64], out: &mut Vec<f64>) {
    let n1 = patch.trial.n_max + 1;
    let nu_k = patch.trial.unknowns_per_basic();
    out.clear();
    out.resize(comp.basics.len() * n1, 0.0);
    for j in 0..comp.basics.len() {
        let w = &mut out[j * n1..(j + 1) * n1];
        for (k, h) in patch.trial.known.iter().enumerate() {
            add_scaled(w, h, comp.coefficients[j][k]);
        }
        for (k, psi) in patch.trial.unknown.iter().enumerate() {
            add_scaled(w, psi, p[j * nu_k + k]);
        }
    }
}

fn add_scaled(w: &mut [f64], poly: &Poly, s: f64) {
    if s != 0.0 {
        for (a, b) in w.iter_mut().zip(poly) {
            *a += s * b;
        }
    }
}
