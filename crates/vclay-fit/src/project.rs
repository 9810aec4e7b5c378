//! Surface evaluation up to second derivatives and the closest point of a surface to a point.
//!
//! **Parameter correction** (Hoschek 1988, "Intrinsic parametrization for approximation"): after
//! each least-squares solve, every data point `x_k` moves its parameter `(u_k, v_k)` to the foot
//! of the perpendicular on the current surface, the local minimum of
//! `f(u, v) = |S(u, v) - x_k|^2 / 2`, found by Newton's method from the previous parameter:
//!
//! ```text
//! r = S - x,   g = [S_u . r, S_v . r],
//! H = [[S_u . S_u + S_uu . r,  S_u . S_v + S_uv . r],
//!      [S_u . S_v + S_uv . r,  S_v . S_v + S_vv . r]],     (u, v) <- (u, v) - H^-1 g
//! ```
//! with the Gauss-Newton matrix (the second-derivative terms dropped) where `H` is not positive
//! definite, steps clamped to the domain `[0, 1]^2`, and halved while they do not lower `f`;
//! the iteration stops at the first step shorter than its tolerance (without evaluating it).
//! The same iteration run to convergence gives the reported distances: the true (local)
//! closest-point distance from each point to the surface, not the residual at the fitted
//! parameter.
//!
//! Evaluation is rational (quotient rule on the homogeneous net, Piegl & Tiller eq 4.20 and
//! A4.4): `S = A / W`, `S_u = (A_u - W_u S) / W`, `S_uu = (A_uu - 2 W_u S_u - W_uu S) / W`,
//! `S_uv = (A_uv - W_u S_v - W_v S_u - W_uv S) / W`.
//!
//! Limitation: Newton finds the closest point near the starting parameter; for a fitted
//! surface started from the previous parameter this is the global one unless the surface folds
//! back over the point (not the case for the height-field-like scans this module targets).

use vclay_core::Vec3;
use vclay_spline::{BasisWorkspace, KnotVector, NurbsSurface};

/// A point and its first and second partial derivatives.
#[derive(Clone, Copy, Debug, Default)]
pub struct Local {
    /// `S`.
    pub s: Vec3,
    /// `S_u`.
    pub su: Vec3,
    /// `S_v`.
    pub sv: Vec3,
    /// `S_uu`.
    pub suu: Vec3,
    /// `S_uv`.
    pub suv: Vec3,
    /// `S_vv`.
    pub svv: Vec3,
}

/// A closest point: its parameter and its distance.
pub type FootPoint = ([f64; 2], f64);

/// The state of a closest-point iteration: parameter, evaluation there, squared distance.
#[derive(Clone, Copy, Debug)]
struct Foot {
    uv: [f64; 2],
    e: Local,
    f: f64,
}

/// Per-thread scratch space of an [`Evaluator`].
#[derive(Clone, Debug)]
pub struct Scratch {
    du: Vec<f64>,
    dv: Vec<f64>,
    wu: BasisWorkspace,
    wv: BasisWorkspace,
}

/// Evaluates one surface many times without allocating.
///
/// A polynomial surface (all weights 1) of equal degrees 1 to 5 takes a fast path for
/// first-order evaluation (the hot path of parameter correction): basis values on the stack,
/// no weights, no quotient rule, the knot differences' reciprocals tabulated (the same values
/// up to rounding).
#[derive(Clone, Debug)]
pub struct Evaluator<'a> {
    ku: &'a KnotVector,
    kv: &'a KnotVector,
    points: &'a [Vec3],
    weights: &'a [f64],
    nv: usize,
    polynomial: bool,
    span_u: SpanGuess,
    span_v: SpanGuess,
    inv_u: Vec<f64>,
    inv_v: Vec<f64>,
}

/// `inv[i (p + 1) + j] = 1 / (t_{i+j} - t_i)` for `j = 1..=p` (0 where the difference is not
/// positive or `i + j` is past the end): the denominators of the basis recurrences
/// (Piegl & Tiller A2.2 and eq 2.7) as multiplications.
pub(crate) fn reciprocals(kv: &KnotVector) -> Vec<f64> {
    let p = kv.degree();
    let k = kv.as_slice();
    let mut inv = vec![0.0; k.len() * (p + 1)];
    for i in 0..k.len() {
        for j in 1..=p {
            if i + j < k.len() && k[i + j] > k[i] {
                inv[i * (p + 1) + j] = 1.0 / (k[i + j] - k[i]);
            }
        }
    }
    inv
}

/// [`KnotVector::find_span`] with a first guess from uniform spacing of the domain, checked
/// against the knots: the same span, without the binary search when the knots are (nearly)
/// uniform (the fits' clamped uniform knots).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpanGuess {
    start: f64,
    scale: f64,
    first: usize,
    last: usize,
}

impl SpanGuess {
    /// The guess for `kv`.
    pub(crate) fn new(kv: &KnotVector) -> Self {
        let (p, n) = (kv.degree(), kv.control_points());
        let k = kv.as_slice();
        let len = k[n] - k[p];
        Self {
            start: k[p],
            scale: if len > 0.0 { (n - p) as f64 / len } else { 0.0 },
            first: p,
            last: n - 1,
        }
    }

    /// The span of `u` in `kv` (the knot vector this guess was made for): equal to
    /// `kv.find_span(u)`.
    #[inline(always)]
    pub(crate) fn span(&self, kv: &KnotVector, u: f64) -> usize {
        let k = kv.as_slice();
        let g = ((u - self.start) * self.scale).max(0.0) as usize + self.first;
        let g = g.min(self.last);
        // t_g <= u < t_{g+1}: g is the largest index with t_g <= u, a non-empty span, which
        // is what the binary search returns.
        if k[g] <= u && u < k[g + 1] {
            g
        } else {
            kv.find_span(u)
        }
    }
}

impl<'a> Evaluator<'a> {
    /// An evaluator of `surface`.
    pub fn new(surface: &'a NurbsSurface) -> Self {
        let [ku, kv] = surface.knots();
        Self {
            ku,
            kv,
            points: surface.control_points(),
            weights: surface.weights(),
            nv: kv.control_points(),
            polynomial: surface.weights().iter().all(|&w| w == 1.0),
            span_u: SpanGuess::new(ku),
            span_v: SpanGuess::new(kv),
            inv_u: reciprocals(ku),
            inv_v: reciprocals(kv),
        }
    }

    /// Scratch space for this surface's degrees.
    pub fn scratch(&self) -> Scratch {
        Scratch {
            du: vec![0.0; 3 * (self.ku.degree() + 1)],
            dv: vec![0.0; 3 * (self.kv.degree() + 1)],
            wu: BasisWorkspace::new(self.ku.degree()),
            wv: BasisWorkspace::new(self.kv.degree()),
        }
    }

    /// Point and derivatives up to order 2 at `(u, v)` (clamped to the domain).
    pub fn eval(&self, u: f64, v: f64, sc: &mut Scratch) -> Local {
        self.eval_order(u, v, 2, sc)
    }

    /// Point and derivatives up to `order` (1 or 2; the second derivatives are zero for 1).
    pub fn eval_order(&self, u: f64, v: f64, order: usize, sc: &mut Scratch) -> Local {
        let order = order.clamp(1, 2);
        let (p, q) = (self.ku.degree(), self.kv.degree());
        if order == 1 && self.polynomial {
            match (p, q) {
                (1, 1) => return self.eval_polynomial_first::<2, 2>(u, v),
                (2, 2) => return self.eval_polynomial_first::<3, 3>(u, v),
                (3, 3) => return self.eval_polynomial_first::<4, 4>(u, v),
                (4, 4) => return self.eval_polynomial_first::<5, 5>(u, v),
                (5, 5) => return self.eval_polynomial_first::<6, 6>(u, v),
                _ => {}
            }
        }
        let u = u.clamp(0.0, 1.0);
        let v = v.clamp(0.0, 1.0);
        let su = self.span_u.span(self.ku, u);
        let sv = self.span_v.span(self.kv, v);
        if order == 1 {
            basis_first(self.ku, su, u, &mut sc.du);
            basis_first(self.kv, sv, v, &mut sc.dv);
        } else {
            self.ku.basis_derivatives(su, u, 2, &mut sc.du, &mut sc.wu);
            self.kv.basis_derivatives(sv, v, 2, &mut sc.dv, &mut sc.wv);
        }
        let nk = order + 1;
        // Homogeneous sums a[k][l] = sum N_i^(k) M_j^(l) w P (and w), k + l <= 2.
        let mut a = [[Vec3::zeros(); 3]; 3];
        let mut w = [[0.0f64; 3]; 3];
        for iu in 0..=p {
            let row = (su - p + iu) * self.nv + sv - q;
            let mut r = [Vec3::zeros(); 3];
            let mut rw = [0.0; 3];
            for jv in 0..=q {
                let wt = self.weights[row + jv];
                let pw = self.points[row + jv] * wt;
                for l in 0..nk {
                    let m = sc.dv[l * (q + 1) + jv];
                    r[l] += pw * m;
                    rw[l] += wt * m;
                }
            }
            for k in 0..nk {
                let n = sc.du[k * (p + 1) + iu];
                for l in 0..nk - k {
                    a[k][l] += r[l] * n;
                    w[k][l] += rw[l] * n;
                }
            }
        }
        let inv = 1.0 / w[0][0];
        let s = a[0][0] * inv;
        let s_u = (a[1][0] - s * w[1][0]) * inv;
        let s_v = (a[0][1] - s * w[0][1]) * inv;
        Local {
            s,
            su: s_u,
            sv: s_v,
            suu: (a[2][0] - s_u * (2.0 * w[1][0]) - s * w[2][0]) * inv,
            suv: (a[1][1] - s_u * w[0][1] - s_v * w[1][0] - s * w[1][1]) * inv,
            svv: (a[0][2] - s_v * (2.0 * w[0][1]) - s * w[0][2]) * inv,
        }
    }

    /// `S`, `S_u`, `S_v` of a polynomial surface of degrees `P1 - 1`, `Q1 - 1` at `(u, v)`
    /// (clamped to the domain): `sum_ij N_i M_j P_ij` and its two first partials, with the
    /// basis on the stack.
    #[inline(always)]
    fn eval_polynomial_first<const P1: usize, const Q1: usize>(&self, u: f64, v: f64) -> Local {
        let u = u.clamp(0.0, 1.0);
        let v = v.clamp(0.0, 1.0);
        let su = self.span_u.span(self.ku, u);
        let sv = self.span_v.span(self.kv, v);
        let (nu, du) = basis_first_fixed::<P1>(self.ku.as_slice(), &self.inv_u, su, u);
        let (nv, dv) = basis_first_fixed::<Q1>(self.kv.as_slice(), &self.inv_v, sv, v);
        let (mut s, mut s_u, mut s_v) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
        for iu in 0..P1 {
            let row = (su + 1 - P1 + iu) * self.nv + sv + 1 - Q1;
            let pts: &[Vec3; Q1] = self.points[row..row + Q1]
                .try_into()
                .expect("Q1 control points");
            let (mut r0, mut r1) = (Vec3::zeros(), Vec3::zeros());
            for jv in 0..Q1 {
                r0 += pts[jv] * nv[jv];
                r1 += pts[jv] * dv[jv];
            }
            s += r0 * nu[iu];
            s_u += r0 * du[iu];
            s_v += r1 * nu[iu];
        }
        Local {
            s,
            su: s_u,
            sv: s_v,
            ..Local::default()
        }
    }

    /// The closest point to `x` near `start`: the same as [`Evaluator::project`], and when
    /// the iteration did not stop by itself within `iterations` steps, its continuation for
    /// at most `more` further steps (the same tolerance), returned as a second result when it
    /// moved the parameter: what a second call of `project` from the first result would
    /// return, without evaluating the surface again at that parameter. Parameter correction
    /// uses it to have the final closest-point distances of its last round at once.
    #[allow(clippy::too_many_arguments)]
    pub fn project_continued(
        &self,
        x: &Vec3,
        start: [f64; 2],
        iterations: usize,
        more: usize,
        tol: f64,
        newton: bool,
        sc: &mut Scratch,
    ) -> (FootPoint, Option<FootPoint>) {
        let order = if newton { 2 } else { 1 };
        let uv = [start[0].clamp(0.0, 1.0), start[1].clamp(0.0, 1.0)];
        let e = self.eval_order(uv[0], uv[1], order, sc);
        let mut st = Foot {
            uv,
            f: (e.s - x).norm_squared(),
            e,
        };
        let stopped = self.iterate(x, &mut st, iterations, tol, order, sc);
        let first = (st.uv, st.f.sqrt());
        if stopped || more == 0 {
            return (first, None);
        }
        let at = st.uv;
        self.iterate(x, &mut st, more, tol, order, sc);
        let moved = st.uv != at;
        (first, moved.then(|| (st.uv, st.f.sqrt())))
    }

    /// The closest point to `x` near `start` by at most `iterations` Newton steps (`newton`
    /// true; else Gauss-Newton steps, which need first derivatives only and converge almost as
    /// fast when the distance is small against the radius of curvature): returns the parameter
    /// and the distance. Stops when a step moves the parameter less than `tol`.
    pub fn project(
        &self,
        x: &Vec3,
        start: [f64; 2],
        iterations: usize,
        tol: f64,
        newton: bool,
        sc: &mut Scratch,
    ) -> ([f64; 2], f64) {
        let order = if newton { 2 } else { 1 };
        let uv = [start[0].clamp(0.0, 1.0), start[1].clamp(0.0, 1.0)];
        let e = self.eval_order(uv[0], uv[1], order, sc);
        let mut st = Foot {
            uv,
            f: (e.s - x).norm_squared(),
            e,
        };
        self.iterate(x, &mut st, iterations, tol, order, sc);
        (st.uv, st.f.sqrt())
    }

    /// At most `iterations` steps of [`Evaluator::project`] from `st`; whether the iteration
    /// stopped by itself (a step below `tol`, no descent, a singular matrix).
    #[inline(always)]
    fn iterate(
        &self,
        x: &Vec3,
        st: &mut Foot,
        iterations: usize,
        tol: f64,
        order: usize,
        sc: &mut Scratch,
    ) -> bool {
        let Foot { uv, e, f } = st;
        for _ in 0..iterations {
            let r = e.s - x;
            let g = [e.su.dot(&r), e.sv.dot(&r)];
            let (g11, g12, g22) = (e.su.dot(&e.su), e.su.dot(&e.sv), e.sv.dot(&e.sv));
            let (mut h11, mut h12, mut h22) = (
                g11 + e.suu.dot(&r),
                g12 + e.suv.dot(&r),
                g22 + e.svv.dot(&r),
            );
            if !(h11 > 0.0 && h11 * h22 - h12 * h12 > 0.0) {
                (h11, h12, h22) = (g11, g12, g22);
            }
            let det = h11 * h22 - h12 * h12;
            if !(det > 0.0 && det.is_finite()) {
                return true;
            }
            let mut step = [
                -(h22 * g[0] - h12 * g[1]) / det,
                -(h11 * g[1] - h12 * g[0]) / det,
            ];
            // A full step of at most `tol` would end the iteration whatever its evaluation
            // says (accepted, the parameter moves at most `tol`; refused, it is halved up to
            // six times without use): stop before evaluating it. Near the foot point such
            // steps are at the rounding level of `f` and were refused about half the time,
            // costing up to six evaluations each (issue 31).
            if step[0].abs() + step[1].abs() <= tol {
                return true;
            }
            let mut accepted = false;
            for _ in 0..6 {
                let cand = [
                    (uv[0] + step[0]).clamp(0.0, 1.0),
                    (uv[1] + step[1]).clamp(0.0, 1.0),
                ];
                let ec = self.eval_order(cand[0], cand[1], order, sc);
                let fc = (ec.s - x).norm_squared();
                if fc <= *f {
                    let moved = (cand[0] - uv[0]).abs() + (cand[1] - uv[1]).abs();
                    *uv = cand;
                    *e = ec;
                    *f = fc;
                    accepted = moved > tol;
                    break;
                }
                step = [step[0] * 0.5, step[1] * 0.5];
            }
            if !accepted {
                return true;
            }
        }
        false
    }
}

/// The `P1` non-zero basis functions of degree `p = P1 - 1` at `u` in span `span` of the
/// knots `k` (Piegl & Tiller A2.2) into an array on the stack, each division by a knot
/// difference a multiplication by its reciprocal in `inv` ([`reciprocals`]), the table built
/// up to degree `last` (`p - 1` leaves `N_{span-p+1+r, p-1}` in `[0..p]`, for derivatives).
#[inline(always)]
fn basis_table<const P1: usize>(
    k: &[f64],
    inv: &[f64],
    span: usize,
    u: f64,
    last: usize,
) -> [f64; P1] {
    let mut n = [0.0; P1];
    n[0] = 1.0;
    for j in 1..=last {
        basis_row::<P1>(&mut n, k, inv, span, u, j);
    }
    n
}

/// Row `j` of the triangular table of Piegl & Tiller A2.2: the degree-`j` values in
/// `n[0..=j]` from the degree-`j - 1` ones in `n[0..j]`.
#[inline(always)]
fn basis_row<const P1: usize>(
    n: &mut [f64; P1],
    k: &[f64],
    inv: &[f64],
    span: usize,
    u: f64,
    j: usize,
) {
    let mut saved = 0.0;
    for r in 0..j {
        // right + left = t_{span+r+1} - t_{span+1+r-j}, a difference of j knots apart.
        let right = k[span + r + 1] - u;
        let left = u - k[span + 1 + r - j];
        let temp = n[r] * inv[(span + 1 + r - j) * P1 + j];
        n[r] = saved + right * temp;
        saved = left * temp;
    }
    n[j] = saved;
}

/// The `P1` non-zero basis functions of degree `P1 - 1` at `u` (span `span` of the knots `k`,
/// reciprocals `inv` of [`reciprocals`]): Piegl & Tiller A2.2 on the stack, for assembly.
#[inline(always)]
pub(crate) fn basis_fixed<const P1: usize>(
    k: &[f64],
    inv: &[f64],
    span: usize,
    u: f64,
) -> [f64; P1] {
    basis_table::<P1>(k, inv, span, u, P1 - 1)
}

/// [`basis_first`] for degree `p = P1 - 1` into arrays on the stack, with the reciprocals
/// `inv` of the knot differences ([`reciprocals`]): `(N, N')` of the `P1` non-zero basis
/// functions at `u` in span `span` of the knots `k`.
#[inline(always)]
pub(crate) fn basis_first_fixed<const P1: usize>(
    k: &[f64],
    inv: &[f64],
    span: usize,
    u: f64,
) -> ([f64; P1], [f64; P1]) {
    let p = P1 - 1;
    if p == 0 {
        return ([1.0; P1], [0.0; P1]);
    }
    // N_{span-p+1+r, p-1} in n[0..p].
    let mut n = basis_table::<P1>(k, inv, span, u, p - 1);
    let mut d = [0.0; P1];
    let pf = p as f64;
    for r in 0..=p {
        let i = span - p + r;
        let mut v = 0.0;
        if r >= 1 {
            v += n[r - 1] * inv[i * P1 + p];
        }
        if r < p {
            v -= n[r] * inv[(i + 1) * P1 + p];
        }
        d[r] = pf * v;
    }
    // The last row of the table: degree p.
    basis_row::<P1>(&mut n, k, inv, span, u, p);
    (n, d)
}

/// The `p + 1` non-zero basis functions at `u` in `out[0..=p]` and their first derivatives in
/// `out[p+1..=2p+1]`: the triangular table of Piegl & Tiller A2.2 up to degree `p - 1`, the
/// derivative formula `N'_{i,p} = p (N_{i,p-1} / (t_{i+p} - t_i) - N_{i+1,p-1} / (t_{i+p+1} -
/// t_{i+1}))` (eq 2.7), then the last row of the table. Cheaper than the general A2.3 for first
/// derivatives; the hot path of parameter correction.
fn basis_first(kv: &KnotVector, span: usize, u: f64, out: &mut [f64]) {
    let p = kv.degree();
    let k = kv.as_slice();
    let (n, d) = out.split_at_mut(p + 1);
    n[0] = 1.0;
    let step = |n: &mut [f64], j: usize| {
        let mut saved = 0.0;
        for r in 0..j {
            let right = k[span + r + 1] - u;
            let left = u - k[span + 1 + r - j];
            let temp = n[r] / (right + left);
            n[r] = saved + right * temp;
            saved = left * temp;
        }
        n[j] = saved;
    };
    for j in 1..p {
        step(n, j);
    }
    // n[0..p] = N_{span-p+1+r, p-1}.
    let pf = p as f64;
    for r in 0..=p {
        let i = span - p + r;
        let mut v = 0.0;
        if r >= 1 {
            let den = k[i + p] - k[i];
            if den > 0.0 {
                v += n[r - 1] / den;
            }
        }
        if r < p {
            let den = k[i + p + 1] - k[i + 1];
            if den > 0.0 {
                v -= n[r] / den;
            }
        }
        d[r] = pf * v;
    }
    if p >= 1 {
        step(n, p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_degree_basis_matches_the_general_one() {
        fn check<const P1: usize>() {
            let p = P1 - 1;
            let kv = KnotVector::new(
                [vec![0.0; p + 1], vec![0.2, 0.5, 0.5, 0.9], vec![1.0; p + 1]].concat(),
                p,
                p + 5,
            )
            .unwrap();
            let inv = reciprocals(&kv);
            for &u in &[0.0, 0.1, 0.2, 0.35, 0.5, 0.77, 0.999, 1.0] {
                let span = kv.find_span(u);
                let mut a = vec![0.0; 2 * P1];
                let mut b = vec![0.0; P1];
                basis_first(&kv, span, u, &mut a);
                kv.basis(span, u, &mut b);
                let (n, d) = basis_first_fixed::<P1>(kv.as_slice(), &inv, span, u);
                let m = basis_fixed::<P1>(kv.as_slice(), &inv, span, u);
                for r in 0..P1 {
                    assert!((n[r] - a[r]).abs() < 1e-12, "p {p} u {u} N_{r}");
                    assert!((d[r] - a[P1 + r]).abs() < 1e-11, "p {p} u {u} N'_{r}");
                    assert!((m[r] - b[r]).abs() < 1e-12, "p {p} u {u} basis {r}");
                }
            }
        }
        check::<2>();
        check::<3>();
        check::<4>();
        check::<5>();
        check::<6>();
    }

    #[test]
    fn span_guess_matches_binary_search() {
        let uniform = KnotVector::clamped_uniform(3, 32).unwrap();
        let uneven = KnotVector::new(
            [vec![0.0; 4], vec![0.2, 0.5, 0.5, 0.9], vec![1.0; 4]].concat(),
            3,
            8,
        )
        .unwrap();
        for kv in [&uniform, &uneven] {
            let g = SpanGuess::new(kv);
            for i in 0..=2000 {
                let u = i as f64 / 2000.0;
                for u in [u, u - 1e-17, u + 1e-17, -0.1, 1.1] {
                    assert_eq!(g.span(kv, u), kv.find_span(u), "u {u}");
                }
            }
            for &t in kv.as_slice() {
                assert_eq!(g.span(kv, t), kv.find_span(t), "knot {t}");
            }
        }
    }

    #[test]
    fn polynomial_fast_path_matches_the_rational_one() {
        for p in 1..=6 {
            let n = p + 5;
            let kv = KnotVector::clamped_uniform(p, n).unwrap();
            let ctrl: Vec<Vec3> = (0..n * n)
                .map(|k| {
                    let (i, j) = ((k / n) as f64, (k % n) as f64);
                    Vec3::new(i, j, (0.7 * i).sin() * (1.3 * j).cos())
                })
                .collect();
            let poly =
                NurbsSurface::from_flat([kv.clone(), kv.clone()], ctrl.clone(), vec![1.0; n * n])
                    .unwrap();
            // One weight 1 + eps: the general (rational) path on (nearly) the same surface.
            let mut w = vec![1.0; n * n];
            w[0] = 1.0 + f64::EPSILON;
            let rat = NurbsSurface::from_flat([kv.clone(), kv], ctrl, w).unwrap();
            let (a, b) = (Evaluator::new(&poly), Evaluator::new(&rat));
            assert!(a.polynomial && !b.polynomial);
            let (mut sa, mut sb) = (a.scratch(), b.scratch());
            for &(u, v) in &[
                (0.0, 0.0),
                (0.13, 0.77),
                (0.5, 0.5),
                (0.999, 0.2),
                (1.0, 1.0),
            ] {
                let (ea, eb) = (
                    a.eval_order(u, v, 1, &mut sa),
                    b.eval_order(u, v, 1, &mut sb),
                );
                for (x, y) in [(ea.s, eb.s), (ea.su, eb.su), (ea.sv, eb.sv)] {
                    assert!(
                        (x - y).norm() < 1e-9 * (1.0 + y.norm()),
                        "p {p}: {x} vs {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn first_derivatives_match_a2_3() {
        for p in 1..=4 {
            let kv = KnotVector::new(
                [vec![0.0; p + 1], vec![0.2, 0.5, 0.5, 0.9], vec![1.0; p + 1]].concat(),
                p,
                p + 5,
            )
            .unwrap();
            let mut ws = BasisWorkspace::new(p);
            for &u in &[0.0, 0.1, 0.2, 0.35, 0.5, 0.77, 0.999, 1.0] {
                let span = kv.find_span(u);
                let mut a = vec![0.0; 2 * (p + 1)];
                let mut b = vec![0.0; 3 * (p + 1)];
                basis_first(&kv, span, u, &mut a);
                kv.basis_derivatives(span, u, 2, &mut b, &mut ws);
                for r in 0..2 * (p + 1) {
                    assert!(
                        (a[r] - b[r]).abs() < 1e-12,
                        "p {p} u {u} r {r}: {} vs {}",
                        a[r],
                        b[r]
                    );
                }
            }
        }
    }
}
