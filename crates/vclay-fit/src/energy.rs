//! The fairness energy: D-NURBS's thin plate under tension (`d-nurbs.txt` section 4.5, eq 17).
//!
//! ```text
//! U = 1/2 p^T K p,
//! K = integral ( a11 J_u^T J_u + a22 J_v^T J_v
//!              + b11 J_uu^T J_uu + b12 J_uv^T J_uv + b22 J_vv^T J_vv ) du dv      (eq 17)
//! ```
//! (the same weighting of the three rigidity terms as the engine's `Element::integrate`).
//!
//! **Scale-free coefficients.** The fit always uses the unit square `[0, 1]^2` as domain. The
//! user's tension `alpha` and rigidity `beta` act on the surface measured in *isotropic
//! normalized* parameters `u' = u L_u / L`, `v' = v L_v / L`, where `L_u x L_v` is the
//! rectangle of the base plane (see [`crate::plane`]) and `L = sqrt(L_u L_v)`; the area element
//! is unchanged (`du' dv' = du dv`), and the chain rule turns eq 17's constant densities into
//! ```text
//! a11 = alpha (L/L_u)^2,  a22 = alpha (L/L_v)^2,
//! b11 = beta (L/L_u)^4,   b12 = beta (L/L_u)^2 (L/L_v)^2,   b22 = beta (L/L_v)^4.
//! ```
//! With the data term normalized by the total point weight (see [`crate::fit_surface`]), both
//! terms are squared lengths: `alpha` and `beta` are dimensionless and mean the same for any
//! model size, point count, knot spacing or grid (the integrals are the continuum energy of the
//! surface, which refinement does not change), and the tension does not prefer one parametric
//! direction because the rectangle is long.
//!
//! **Polynomial surfaces** (the default): tensor-product B-splines make K separable,
//! `K[(i,j),(k,l)] = a11 G1u[i,k] G0v[j,l] + a22 G0u G1v + b11 G2u G0v + b12 G1u G1v + b22 G0u G2v`
//! with the one-dimensional Gram matrices `Gd[i,k] = integral N_i^(d) N_k^(d) du`, integrated
//! exactly by `p + 1` Gauss-Legendre points per knot span (the integrand has degree `<= 2p`).
//! This is O(n) work and memory, where the engine's element matrices would take several
//! kilobytes per element. **Rational surfaces** (`--weights`) use the engine itself:
//! `vclay_dynamics::DnurbsSurface::new` with these densities gives the frozen-weight element
//! stiffness matrices in the rational basis `R_i` (`d-nurbs.txt` footnote 2); the tests check
//! that both paths agree on a polynomial surface.

use crate::FitError;
use vclay_core::GaussLegendre;
use vclay_spline::KnotVector;

/// Eq 17's constant densities `[a11, a22]`, `[b11, b12, b22]` for the user's `alpha`, `beta` on
/// a base rectangle `L_u x L_v` (module docs).
pub fn densities(alpha: f64, beta: f64, extents: [f64; 2]) -> ([f64; 2], [f64; 3]) {
    let l = (extents[0] * extents[1]).sqrt();
    let su = (l / extents[0]).powi(2);
    let sv = (l / extents[1]).powi(2);
    (
        [alpha * su, alpha * sv],
        [beta * su * su, beta * su * sv, beta * sv * sv],
    )
}

/// The banded Gram matrices `[G0, G1, G2]` of one axis: `g[d][i * (2p + 1) + (k - i + p)]`.
pub fn gram(kv: &KnotVector) -> Result<[Vec<f64>; 3], FitError> {
    let p = kv.degree();
    let n = kv.control_points();
    let bw = 2 * p + 1;
    let gauss = GaussLegendre::new(p + 1).map_err(|_| FitError::Option {
        name: "degree",
        value: p.to_string(),
        why: "too high for the quadrature table".into(),
    })?;
    let mut g = [vec![0.0; n * bw], vec![0.0; n * bw], vec![0.0; n * bw]];
    let k = kv.as_slice();
    let mut ders = vec![0.0; 3 * (p + 1)];
    let mut ws = vclay_spline::BasisWorkspace::new(p);
    for span in p..n {
        let (a, b) = (k[span], k[span + 1]);
        if a >= b {
            continue;
        }
        for (u, w) in gauss.on_interval(a, b) {
            kv.basis_derivatives(span, u, 2, &mut ders, &mut ws);
            for d in 0..3 {
                let nd = &ders[d * (p + 1)..(d + 1) * (p + 1)];
                for r in 0..=p {
                    for c in 0..=p {
                        let (i, kk) = (span - p + r, span - p + c);
                        g[d][i * bw + kk + p - i] += w * nd[r] * nd[c];
                    }
                }
            }
        }
    }
    Ok(g)
}

/// Adds eq 17's `K` of a polynomial tensor-product surface to a banded matrix over the net
/// (`band[I * bw + (di + p) * (2q + 1) + dj + q]` for neighbour `J = I + di n_v + dj`).
pub fn add_separable(
    band: &mut [f64],
    knots: &[KnotVector; 2],
    alpha: [f64; 2],
    beta: [f64; 3],
) -> Result<(), FitError> {
    let (p, q) = (knots[0].degree(), knots[1].degree());
    let (nu, nv) = (knots[0].control_points(), knots[1].control_points());
    let gu = gram(&knots[0])?;
    let gv = gram(&knots[1])?;
    let (bu, bv) = (2 * p + 1, 2 * q + 1);
    let bw = bu * bv;
    for i in 0..nu {
        for j in 0..nv {
            let row = &mut band[(i * nv + j) * bw..(i * nv + j + 1) * bw];
            for a in 0..bu {
                let ua = [gu[0][i * bu + a], gu[1][i * bu + a], gu[2][i * bu + a]];
                if ua == [0.0; 3] {
                    continue;
                }
                for b in 0..bv {
                    let vb = [gv[0][j * bv + b], gv[1][j * bv + b], gv[2][j * bv + b]];
                    row[a * bv + b] += alpha[0] * ua[1] * vb[0]
                        + alpha[1] * ua[0] * vb[1]
                        + beta[0] * ua[2] * vb[0]
                        + beta[1] * ua[1] * vb[1]
                        + beta[2] * ua[0] * vb[2];
                }
            }
        }
    }
    Ok(())
}

/// The engine's frozen-weight stiffness elements of `surface` (eq 17 in the rational basis,
/// Gauss quadrature by element), through `vclay_dynamics::DnurbsSurface::new`.
pub fn engine_elements(
    surface: &vclay_spline::NurbsSurface,
    alpha: [f64; 2],
    beta: [f64; 3],
) -> Result<Vec<vclay_dynamics::dnurbs::Element>, FitError> {
    use vclay_dynamics::{Density, DnurbsSurface, Material};
    let material = Material {
        mu: Density::Constant(0.0),
        gamma: Density::Constant(0.0),
        alpha: alpha.iter().map(|&a| Density::Constant(a)).collect(),
        beta: beta.iter().map(|&b| Density::Constant(b)).collect(),
    };
    let model = DnurbsSurface::new(surface.clone(), material)
        .map_err(|e| FitError::Energy(e.to_string()))?;
    Ok(model.system().elements.clone())
}
