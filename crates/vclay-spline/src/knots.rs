//! Knot vectors and B-spline basis functions.
//!
//! A knot vector `U = {t_0 <= t_1 <= ... <= t_{n+p}}` of degree `p` for `n` control points
//! (`d-nurbs.txt` section 4.1: `n + k + 1` knots for order `k = p + 1` and `n + 1` points) defines
//! the basis functions `N_{i,p}` by the Cox-de Boor recurrence
//!
//! ```text
//! N_{i,0}(u) = 1 if t_i <= u < t_{i+1}, else 0
//! N_{i,p}(u) = (u - t_i)/(t_{i+p} - t_i) N_{i,p-1}(u) + (t_{i+p+1} - u)/(t_{i+p+1} - t_{i+1}) N_{i+1,p-1}(u)
//! ```
//!
//! evaluated by Piegl & Tiller, *The NURBS Book*, A2.1 (span search), A2.2 (the `p + 1` non-zero
//! functions) and A2.3 (their derivatives). The domain is `[t_p, t_n]`.
//!
//! Limitations: degrees up to [`MAX_DEGREE`]; a knot may repeat at most `p + 1` times.

use crate::error::KnotError;
use vclay_core::{Interval, Tolerance};

/// Largest supported degree. Point evaluation keeps its `p + 1` basis values on the stack, so the
/// degree has a fixed bound; 31 is far above what CAD exchange formats use (IGES and STEP allow more
/// in principle, Rhino limits curves to 11).
pub const MAX_DEGREE: usize = 31;

/// Highest derivative order that `derivatives` of curves, surfaces and volumes computes (issue 17).
/// The quotient rule costs O(K^2) per curve point, O(K^4) per surface point and O(K^6) per volume
/// point, and the table holds O(K^3) entries for volumes: K = 10,000 took minutes and K = 2^32
/// gigabytes. Orders above the degree of a polynomial spline are zero, and the rational ones are
/// rounding noise long before 64 (a volume of order 64 takes about a second per point).
pub const MAX_DERIVATIVE_ORDER: usize = 64;

/// A validated, non-decreasing knot vector of a given degree.
///
/// Invariants (checked by every constructor): all knots finite and non-decreasing; length
/// `= control points + degree + 1`; at least `degree + 1` control points; a non-empty domain
/// `[t_p, t_n]`; no knot repeated more than `degree + 1` times; `degree <= MAX_DEGREE`.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    knots: Vec<f64>,
    degree: usize,
    /// First span index `i >= p` with `t_i < t_{i+1}`.
    first_span: usize,
    /// Last span index `i <= n - 1` with `t_i < t_{i+1}`.
    last_span: usize,
}

impl KnotVector {
    /// A knot vector from explicit knots, for `control_points` control points of `degree`.
    pub fn new(knots: Vec<f64>, degree: usize, control_points: usize) -> Result<Self, KnotError> {
        if degree > MAX_DEGREE {
            return Err(KnotError::DegreeTooHigh {
                degree,
                max: MAX_DEGREE,
            });
        }
        if control_points < degree + 1 {
            return Err(KnotError::TooFewControlPoints {
                degree,
                control_points,
            });
        }
        let expected = control_points + degree + 1;
        if knots.len() != expected {
            return Err(KnotError::Count {
                found: knots.len(),
                expected,
                control_points,
                degree,
            });
        }
        if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
            return Err(KnotError::NonFinite {
                index,
                value: knots[index],
            });
        }
        if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(KnotError::Decreasing {
                index: i,
                value: knots[i],
                previous: knots[i - 1],
            });
        }
        let mut i = 0;
        while i < knots.len() {
            let mut j = i;
            while j + 1 < knots.len() && knots[j + 1] == knots[i] {
                j += 1;
            }
            let mult = j - i + 1;
            if mult > degree + 1 {
                return Err(KnotError::Multiplicity {
                    index: i,
                    value: knots[i],
                    multiplicity: mult,
                    max: degree + 1,
                });
            }
            i = j + 1;
        }
        let n = control_points;
        let (start, end) = (knots[degree], knots[n]);
        if start >= end {
            return Err(KnotError::EmptyDomain { start, end });
        }
        let first_span = (degree..n)
            .find(|&i| knots[i] < knots[i + 1])
            .unwrap_or(degree);
        let last_span = (degree..n)
            .rev()
            .find(|&i| knots[i] < knots[i + 1])
            .unwrap_or(n - 1);
        Ok(Self {
            knots,
            degree,
            first_span,
            last_span,
        })
    }

    /// Clamped (open) uniform knots on `[0, 1]`: `p + 1` zeros, equally spaced interior knots,
    /// `p + 1` ones. The curve interpolates its end control points.
    pub fn clamped_uniform(degree: usize, control_points: usize) -> Result<Self, KnotError> {
        if control_points < degree + 1 {
            return Err(KnotError::TooFewControlPoints {
                degree,
                control_points,
            });
        }
        let spans = control_points - degree;
        let mut knots = Vec::with_capacity(control_points + degree + 1);
        knots.extend(std::iter::repeat_n(0.0, degree + 1));
        knots.extend((1..spans).map(|i| i as f64 / spans as f64));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self::new(knots, degree, control_points)
    }

    /// Uniform (unclamped, periodic-style) knots `t_i = (i - p) / (n - p)`, so that the domain
    /// `[t_p, t_n]` is `[0, 1]`.
    pub fn uniform(degree: usize, control_points: usize) -> Result<Self, KnotError> {
        if control_points < degree + 1 {
            return Err(KnotError::TooFewControlPoints {
                degree,
                control_points,
            });
        }
        let spans = (control_points - degree) as f64;
        let knots = (0..control_points + degree + 1)
            .map(|i| (i as f64 - degree as f64) / spans)
            .collect();
        Self::new(knots, degree, control_points)
    }

    /// The degree `p`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knots.
    pub fn as_slice(&self) -> &[f64] {
        &self.knots
    }

    /// Number of knots.
    pub fn len(&self) -> usize {
        self.knots.len()
    }

    /// Always false: a valid knot vector has at least `2 (p + 1)` knots.
    pub fn is_empty(&self) -> bool {
        self.knots.is_empty()
    }

    /// Number of control points `n` this knot vector serves.
    pub fn control_points(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The parameter domain `[t_p, t_n]`.
    pub fn domain(&self) -> Interval {
        Interval::new(self.knots[self.degree], self.knots[self.control_points()])
    }

    /// Absolute parameter tolerance: [`Tolerance::PARAMETER`] scaled by the domain width.
    pub fn parameter_tolerance(&self) -> f64 {
        let d = self.domain();
        Tolerance::PARAMETER.scaled(d.length().max(d.min.abs()).max(d.max.abs()))
    }

    /// Whether the first and last knots repeat `p + 1` times (the curve interpolates its end
    /// control points).
    pub fn is_clamped(&self) -> bool {
        let p = self.degree;
        let k = &self.knots;
        let m = k.len() - 1;
        (0..=p).all(|i| k[i] == k[0]) && (0..=p).all(|i| k[m - i] == k[m])
    }

    /// Span index `i` with `t_i <= u < t_{i+1}`, `p <= i <= n - 1`, skipping empty spans
    /// (Piegl & Tiller A2.1, by binary search). Parameters at or beyond the domain end give the
    /// last non-empty span, those before the start the first one, so that evaluation at `t_n`
    /// is continuous from the left.
    pub fn find_span(&self, u: f64) -> usize {
        let n = self.control_points();
        let p = self.degree;
        if u >= self.knots[n] {
            return self.last_span;
        }
        if u <= self.knots[p] {
            return self.first_span;
        }
        // Number of knots in t_p..=t_n that are <= u, minus one, offset by p.
        let idx = self.knots[p..=n].partition_point(|&t| t <= u);
        (p + idx - 1).clamp(self.first_span, self.last_span)
    }

    /// Span index `i` with `t_i < u <= t_{i+1}`: the span whose polynomial piece ends at `u`
    /// when `u` is a knot, so that evaluation there gives the limit from the left (one-sided
    /// derivatives at a C0 knot, for tessellations that split normals along creases). Away
    /// from knots it equals [`KnotVector::find_span`]; parameters at or before the domain start
    /// give the first non-empty span.
    pub fn find_span_left(&self, u: f64) -> usize {
        let n = self.control_points();
        let p = self.degree;
        if u <= self.knots[p] {
            return self.first_span;
        }
        if u > self.knots[n] {
            return self.last_span;
        }
        // Number of knots in t_p..=t_n that are < u, minus one, offset by p.
        let idx = self.knots[p..=n].partition_point(|&t| t < u);
        (p + idx - 1).clamp(self.first_span, self.last_span)
    }

    /// The interior knot values (strictly inside the domain) of multiplicity at least the
    /// degree: where a spline of this knot vector is only C0 (or discontinuous), so its
    /// derivatives may jump and a surface may have a crease (a sharp edge).
    pub fn c0_knots(&self) -> Vec<f64> {
        let d = self.domain();
        self.distinct()
            .into_iter()
            .filter(|&(t, m)| t > d.min && t < d.max && m >= self.degree.max(1))
            .map(|(t, _)| t)
            .collect()
    }

    /// How many knots equal `u` to within [`KnotVector::parameter_tolerance`].
    pub fn multiplicity(&self, u: f64) -> usize {
        let tol = self.parameter_tolerance();
        self.knots.iter().filter(|&&t| (t - u).abs() <= tol).count()
    }

    /// The distinct knot values with their multiplicities.
    pub fn distinct(&self) -> Vec<(f64, usize)> {
        let mut out: Vec<(f64, usize)> = Vec::new();
        for &t in &self.knots {
            match out.last_mut() {
                Some((v, m)) if *v == t => *m += 1,
                _ => out.push((t, 1)),
            }
        }
        out
    }

    /// Greville abscissae `xi_i = (t_{i+1} + ... + t_{i+p}) / p`, one per control point (the
    /// parameters at which a B-spline reproduces the identity: `sum xi_i N_{i,p}(u) = u`). For
    /// degree 0 the span midpoints.
    pub fn greville(&self) -> Vec<f64> {
        let p = self.degree;
        (0..self.control_points())
            .map(|i| {
                if p == 0 {
                    0.5 * (self.knots[i] + self.knots[i + 1])
                } else {
                    self.knots[i + 1..=i + p].iter().sum::<f64>() / p as f64
                }
            })
            .collect()
    }

    /// The `p + 1` non-zero basis functions `N_{span-p,p}(u) ..= N_{span,p}(u)` written to
    /// `out[0..=p]` (Piegl & Tiller A2.2). No allocation: the triangular table is built in `out`
    /// with the knot differences read directly from the knot vector.
    ///
    /// # Panics
    /// If `out.len() < p + 1` (programmer error).
    #[inline]
    pub fn basis(&self, span: usize, u: f64, out: &mut [f64]) {
        let p = self.degree;
        let k = &self.knots;
        out[0] = 1.0;
        for j in 1..=p {
            let mut saved = 0.0;
            for r in 0..j {
                // right[r+1] = t_{span+r+1} - u, left[j-r] = u - t_{span+1-j+r}
                let right = k[span + r + 1] - u;
                let left = u - k[span + 1 + r - j];
                let temp = out[r] / (right + left);
                out[r] = saved + right * temp;
                saved = left * temp;
            }
            out[j] = saved;
        }
    }

    /// Basis functions and their derivatives up to order `n` (Piegl & Tiller A2.3).
    ///
    /// Writes `ders[k * (p + 1) + j] = d^k/du^k N_{span-p+j,p}(u)` for `k = 0..=n`, using the
    /// caller's workspace (no allocation once the workspace has grown to the degree). Orders above
    /// `p` are zero.
    ///
    /// # Panics
    /// If `ders.len() < (n + 1) * (p + 1)` (programmer error).
    pub fn basis_derivatives(
        &self,
        span: usize,
        u: f64,
        n: usize,
        ders: &mut [f64],
        ws: &mut BasisWorkspace,
    ) {
        let p = self.degree;
        let w = p + 1;
        let k = &self.knots;
        ws.ensure(p);
        let ndu = &mut ws.ndu;
        let left = &mut ws.left;
        let right = &mut ws.right;
        ndu[0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[span + 1 - j];
            right[j] = k[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                // Lower triangle: knot differences.
                ndu[j * w + r] = right[r + 1] + left[j - r];
                let temp = ndu[r * w + j - 1] / ndu[j * w + r];
                // Upper triangle: basis functions.
                ndu[r * w + j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j * w + j] = saved;
        }
        for j in 0..=p {
            ders[j] = ndu[j * w + p];
        }
        let nd = n.min(p);
        let a = &mut ws.a;
        for r in 0..=p {
            let (mut s1, mut s2) = (0usize, 1usize);
            a[0] = 1.0; // a[s1][0]
            for kk in 1..=nd {
                let mut d = 0.0;
                let rk = r as isize - kk as isize;
                let pk = p - kk;
                if r >= kk {
                    a[s2 * w] = a[s1 * w] / ndu[(pk + 1) * w + rk as usize];
                    d = a[s2 * w] * ndu[(rk as usize) * w + pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if (r as isize - 1) <= pk as isize {
                    kk - 1
                } else {
                    p - r
                };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2 * w + j] = (a[s1 * w + j] - a[s1 * w + j - 1]) / ndu[(pk + 1) * w + idx];
                    d += a[s2 * w + j] * ndu[idx * w + pk];
                }
                if r <= pk {
                    a[s2 * w + kk] = -a[s1 * w + kk - 1] / ndu[(pk + 1) * w + r];
                    d += a[s2 * w + kk] * ndu[r * w + pk];
                }
                ders[kk * w + r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut fac = p as f64;
        for kk in 1..=nd {
            for j in 0..=p {
                ders[kk * w + j] *= fac;
            }
            fac *= (p - kk) as f64;
        }
        for kk in nd + 1..=n {
            for j in 0..=p {
                ders[kk * w + j] = 0.0;
            }
        }
    }

    /// Convenience: derivatives up to order `n` in a new vector (see
    /// [`KnotVector::basis_derivatives`]). Allocates; use the workspace form in hot loops.
    pub fn basis_derivatives_vec(&self, span: usize, u: f64, n: usize) -> Vec<f64> {
        let mut ders = vec![0.0; (n + 1) * (self.degree + 1)];
        let mut ws = BasisWorkspace::new(self.degree);
        self.basis_derivatives(span, u, n, &mut ders, &mut ws);
        ders
    }

    /// Builds a new knot vector with `value` inserted `times` times (no validation of the result
    /// beyond [`KnotVector::new`]).
    pub(crate) fn with_inserted(&self, value: f64, times: usize) -> Result<Self, KnotError> {
        let pos = self.knots.partition_point(|&t| t <= value);
        let mut k = Vec::with_capacity(self.knots.len() + times);
        k.extend_from_slice(&self.knots[..pos]);
        k.extend(std::iter::repeat_n(value, times));
        k.extend_from_slice(&self.knots[pos..]);
        Self::new(k, self.degree, self.control_points() + times)
    }
}

/// Scratch space for [`KnotVector::basis_derivatives`], grown on demand to the degree in use.
#[derive(Clone, Debug, Default)]
pub struct BasisWorkspace {
    ndu: Vec<f64>,
    a: Vec<f64>,
    left: Vec<f64>,
    right: Vec<f64>,
}

impl BasisWorkspace {
    /// A workspace sized for `degree`.
    pub fn new(degree: usize) -> Self {
        let mut ws = Self::default();
        ws.ensure(degree);
        ws
    }

    fn ensure(&mut self, p: usize) {
        let w = p + 1;
        if self.ndu.len() < w * w {
            self.ndu.resize(w * w, 0.0);
            self.a.resize(2 * w, 0.0);
            self.left.resize(w, 0.0);
            self.right.resize(w, 0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nurbs_book_example_2_3() {
        // The NURBS Book, Ex. 2.3: U = {0,0,0,1,2,3,4,4,5,5,5}, p = 2, u = 5/2: span 4,
        // N_{2,2} = 1/8, N_{3,2} = 6/8, N_{4,2} = 1/8.
        let kv = KnotVector::new(vec![0., 0., 0., 1., 2., 3., 4., 4., 5., 5., 5.], 2, 8).unwrap();
        let span = kv.find_span(2.5);
        assert_eq!(span, 4);
        let mut b = [0.0; 3];
        kv.basis(span, 2.5, &mut b);
        assert_eq!(b, [0.125, 0.75, 0.125]);
        let d = kv.basis_derivatives_vec(span, 2.5, 2);
        // Derivatives from the book: N'_{2,2} = -1/2, N'_{3,2} = 0, N'_{4,2} = 1/2; second: 1, -2, 1.
        assert_eq!(&d[3..6], &[-0.5, 0.0, 0.5]);
        assert_eq!(&d[6..9], &[1.0, -2.0, 1.0]);
    }

    #[test]
    fn span_search_skips_empty_spans_and_handles_ends() {
        let kv = KnotVector::new(vec![0., 0., 0., 0.5, 0.5, 1., 1., 1.], 2, 5).unwrap();
        assert_eq!(kv.find_span(0.0), 2);
        assert_eq!(kv.find_span(0.49), 2);
        assert_eq!(kv.find_span(0.5), 4);
        assert_eq!(kv.find_span(1.0), 4);
        assert_eq!(kv.multiplicity(0.5), 2);
        assert_eq!(kv.multiplicity(0.25), 0);
    }

    #[test]
    fn constructors_validate() {
        assert!(matches!(
            KnotVector::new(vec![0., 0., 1., 1.], 1, 3),
            Err(KnotError::Count {
                found: 4,
                expected: 5,
                ..
            })
        ));
        assert!(matches!(
            KnotVector::new(vec![0., 0., 1., 0.5, 1.], 1, 3),
            Err(KnotError::Decreasing { index: 3, .. })
        ));
        assert!(matches!(
            KnotVector::new(vec![0., f64::NAN, 1., 1., 1.], 1, 3),
            Err(KnotError::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            KnotVector::new(vec![0., 1., 1., 1., 2.], 1, 3),
            Err(KnotError::Multiplicity {
                index: 1,
                multiplicity: 3,
                ..
            })
        ));
        assert!(matches!(
            KnotVector::new(vec![0., 1., 1., 1., 2., 3.], 2, 3),
            Err(KnotError::EmptyDomain { .. })
        ));
        assert!(matches!(
            KnotVector::clamped_uniform(3, 3),
            Err(KnotError::TooFewControlPoints { .. })
        ));
        assert!(matches!(
            KnotVector::clamped_uniform(40, 50),
            Err(KnotError::DegreeTooHigh { .. })
        ));
    }

    #[test]
    fn greville_reproduces_identity() {
        for kv in [
            KnotVector::clamped_uniform(3, 7).unwrap(),
            KnotVector::uniform(2, 6).unwrap(),
            KnotVector::new(vec![0., 0., 0., 0.1, 0.7, 0.7, 1., 1., 1.], 2, 6).unwrap(),
        ] {
            let g = kv.greville();
            let p = kv.degree();
            for s in 0..=20 {
                let u = kv.domain().min + kv.domain().length() * s as f64 / 20.0;
                let span = kv.find_span(u);
                let mut b = vec![0.0; p + 1];
                kv.basis(span, u, &mut b);
                let x: f64 = (0..=p).map(|j| b[j] * g[span - p + j]).sum();
                assert!((x - u).abs() < 1e-14, "{x} vs {u}");
            }
        }
    }
}
