//! Exact refinement: knot insertion, clamping and degree elevation.
//!
//! All three work on homogeneous control points `(w p, w)` along one parametric axis, so a
//! surface or volume is refined by applying the curve algorithm to every line of its net along
//! that axis. None of them changes the shape (tests check this to rounding).
//!
//! - Knot insertion: Piegl & Tiller A5.1 (Boehm's algorithm).
//! - Clamping: insert the domain ends until they have multiplicity `p`, then drop the control
//!   points and knots outside the domain; the shape on the domain is unchanged.
//! - Degree elevation: Piegl & Tiller A5.9 (Bezier decomposition, elevation of each segment,
//!   knot removal), applied after clamping. Each distinct interior knot gains one multiplicity
//!   per elevation step, so continuity is kept.

use crate::KnotError;
use crate::curve::NurbsCurve;
use crate::error::SplineError;
use crate::knots::{KnotVector, MAX_DEGREE};
use crate::surface::NurbsSurface;
use crate::volume::NurbsVolume;
use vclay_core::Vec4;
use vclay_core::math::binomial;

type LineResult = Result<(KnotVector, Vec<Vec4>), SplineError>;

fn kerr(axis: usize) -> impl Fn(KnotError) -> SplineError {
    move |source| SplineError::Knots { axis, source }
}

/// Boehm insertion of `u` `r` times (Piegl & Tiller A5.1). `k` is the index with
/// `U[k] <= u < U[k+1]`, `s` the existing multiplicity.
fn insert_line(kv: &KnotVector, pw: &[Vec4], u: f64, r: usize, axis: usize) -> LineResult {
    if r == 0 {
        return Ok((kv.clone(), pw.to_vec()));
    }
    let p = kv.degree();
    let up = kv.as_slice();
    let np = pw.len() - 1;
    // Largest k with U[k] <= u (and U[k] < U[k+1]).
    let k = up.partition_point(|&t| t <= u) - 1;
    let s = up.iter().filter(|&&t| t == u).count();
    if r + s > p {
        return Err(SplineError::InsertionMultiplicity {
            axis,
            value: u,
            times: r,
            multiplicity: s,
            degree: p,
        });
    }
    let new_kv = kv.with_inserted(u, r).map_err(kerr(axis))?;
    let mut qw = vec![Vec4::zeros(); pw.len() + r];
    qw[..=(k - p)].copy_from_slice(&pw[..=(k - p)]);
    qw[(k - s + r)..=(np + r)].copy_from_slice(&pw[(k - s)..=np]);
    let mut rw: Vec<Vec4> = (0..=p - s).map(|i| pw[k - p + i]).collect();
    let mut l = 0;
    for j in 1..=r {
        l = k - p + j;
        for i in 0..=(p - j - s) {
            let alpha = (u - up[l + i]) / (up[i + k + 1] - up[l + i]);
            rw[i] = rw[i + 1] * alpha + rw[i] * (1.0 - alpha);
        }
        qw[l] = rw[0];
        qw[k + r - j - s] = rw[p - j - s];
    }
    if l + 1 < k - s {
        qw[(l + 1)..(k - s)].copy_from_slice(&rw[1..(k - s - l)]);
    }
    Ok((new_kv, qw))
}

/// Clamps both ends of a line (see module docs).
fn clamp_line(kv: &KnotVector, pw: &[Vec4], axis: usize) -> LineResult {
    if kv.is_clamped() {
        return Ok((kv.clone(), pw.to_vec()));
    }
    let p = kv.degree();
    let (mut kv, mut pw) = (kv.clone(), pw.to_vec());
    // Start.
    let a = kv.domain().min;
    let s = kv.as_slice().iter().filter(|&&t| t == a).count();
    if s <= p {
        let (k2, p2) = insert_line(&kv, &pw, a, p - s, axis)?;
        let knots = k2.as_slice();
        let first = knots.partition_point(|&t| t < a);
        let mut nk = vec![a];
        nk.extend_from_slice(&knots[first..]);
        let np: Vec<Vec4> = p2[first - 1..].to_vec();
        kv = KnotVector::new(nk, p, np.len()).map_err(kerr(axis))?;
        pw = np;
    }
    // End.
    let b = kv.domain().max;
    let s = kv.as_slice().iter().filter(|&&t| t == b).count();
    if s <= p {
        let (k2, p2) = insert_line(&kv, &pw, b, p - s, axis)?;
        let knots = k2.as_slice();
        let last = knots.partition_point(|&t| t <= b) - 1;
        let mut nk = knots[..=last].to_vec();
        nk.push(b);
        let np: Vec<Vec4> = p2[..=last - p].to_vec();
        kv = KnotVector::new(nk, p, np.len()).map_err(kerr(axis))?;
        pw = np;
    }
    Ok((kv, pw))
}

/// Degree elevation by `t` (Piegl & Tiller A5.9) of a clamped line. The loop structure follows
/// the book's listing line by line, so that it can be checked against it.
#[allow(clippy::explicit_counter_loop)]
fn elevate_line(kv: &KnotVector, pw: &[Vec4], t: usize, axis: usize) -> LineResult {
    if t == 0 {
        return Ok((kv.clone(), pw.to_vec()));
    }
    let (kv, pw) = clamp_line(kv, pw, axis)?;
    let p = kv.degree();
    let ph = p + t;
    if ph > MAX_DEGREE {
        return Err(SplineError::Knots {
            axis,
            source: KnotError::DegreeTooHigh {
                degree: ph,
                max: MAX_DEGREE,
            },
        });
    }
    let u = kv.as_slice();
    let n = pw.len() - 1;
    let m = n + p + 1;
    let ph2 = ph / 2;
    // Bezier degree-elevation coefficients.
    let mut bezalfs = vec![vec![0.0; p + 1]; ph + 1];
    bezalfs[0][0] = 1.0;
    bezalfs[ph][p] = 1.0;
    for i in 1..=ph2 {
        let inv = 1.0 / binomial(ph, i);
        let mpi = p.min(i);
        for j in i.saturating_sub(t)..=mpi {
            bezalfs[i][j] = inv * binomial(p, j) * binomial(t, i - j);
        }
    }
    for i in ph2 + 1..ph {
        let mpi = p.min(i);
        for j in i.saturating_sub(t)..=mpi {
            bezalfs[i][j] = bezalfs[ph - i][p - j];
        }
    }
    let distinct_interior = kv.distinct().len().saturating_sub(2);
    let cap_q = pw.len() + t * (distinct_interior + 1) + 1;
    let mut qw = vec![Vec4::zeros(); cap_q];
    let mut uh = vec![0.0; cap_q + ph + 2];
    let mut bpts = vec![Vec4::zeros(); p + 1];
    let mut ebpts = vec![Vec4::zeros(); ph + 1];
    let mut next_bpts = vec![Vec4::zeros(); p.max(1)];
    let mut alfs = vec![0.0; p.max(1)];

    let mut mh = ph;
    let mut kind = ph + 1;
    let mut r: isize = -1;
    let mut a = p;
    let mut b = p + 1;
    let mut cind = 1;
    let mut ua = u[0];
    qw[0] = pw[0];
    for x in uh.iter_mut().take(ph + 1) {
        *x = ua;
    }
    bpts[..=p].copy_from_slice(&pw[..=p]);
    while b < m {
        let i0 = b;
        while b < m && u[b] == u[b + 1] {
            b += 1;
        }
        let mul = b - i0 + 1;
        mh += mul + t;
        let ub = u[b];
        let oldr = r;
        r = p as isize - mul as isize;
        let lbz = if oldr > 0 {
            ((oldr + 2) / 2) as usize
        } else {
            1
        };
        let rbz = if r > 0 {
            ph - ((r + 1) / 2) as usize
        } else {
            ph
        };
        if r > 0 {
            let numer = ub - ua;
            for k in ((mul + 1)..=p).rev() {
                alfs[k - mul - 1] = numer / (u[a + k] - ua);
            }
            for j in 1..=r as usize {
                let save = r as usize - j;
                let s = mul + j;
                for k in (s..=p).rev() {
                    bpts[k] = bpts[k] * alfs[k - s] + bpts[k - 1] * (1.0 - alfs[k - s]);
                }
                next_bpts[save] = bpts[p];
            }
        }
        for i in lbz..=ph {
            ebpts[i] = Vec4::zeros();
            let mpi = p.min(i);
            for j in i.saturating_sub(t)..=mpi {
                ebpts[i] += bpts[j] * bezalfs[i][j];
            }
        }
        if oldr > 1 {
            let mut first = kind - 2;
            let mut last = kind;
            let den = ub - ua;
            let bet = (ub - uh[kind - 1]) / den;
            for tr in 1..oldr as usize {
                let mut i = first;
                let mut j = last;
                let mut kj = j - kind + 1;
                while j - i > tr {
                    if i < cind {
                        let alf = (ub - uh[i]) / (ua - uh[i]);
                        qw[i] = qw[i] * alf + qw[i - 1] * (1.0 - alf);
                    }
                    if j >= lbz {
                        if (j as isize - tr as isize) <= (kind as isize - ph as isize + oldr) {
                            let gam = (ub - uh[j - tr]) / den;
                            ebpts[kj] = ebpts[kj] * gam + ebpts[kj + 1] * (1.0 - gam);
                        } else {
                            ebpts[kj] = ebpts[kj] * bet + ebpts[kj + 1] * (1.0 - bet);
                        }
                    }
                    i += 1;
                    j -= 1;
                    kj = kj.wrapping_sub(1);
                }
                first -= 1;
                last += 1;
            }
        }
        if a != p {
            for _ in 0..(ph as isize - oldr) as usize {
                uh[kind] = ua;
                kind += 1;
            }
        }
        for j in lbz..=rbz {
            qw[cind] = ebpts[j];
            cind += 1;
        }
        if b < m {
            let rr = r.max(0) as usize;
            bpts[..rr].copy_from_slice(&next_bpts[..rr]);
            for j in r.max(0) as usize..=p {
                bpts[j] = pw[b - p + j];
            }
            a = b;
            b += 1;
            ua = ub;
        } else {
            for i in 0..=ph {
                uh[kind + i] = ub;
            }
        }
    }
    let nh = mh - ph; // number of new control points
    qw.truncate(nh);
    uh.truncate(nh + ph + 1);
    let new_kv = KnotVector::new(uh, ph, nh).map_err(kerr(axis))?;
    Ok((new_kv, qw))
}

/// Applies a line operation along `axis` of a flat net with `dims` (last axis fastest).
fn along_axis(
    kv: &KnotVector,
    pw: &[Vec4],
    dims: &[usize],
    axis: usize,
    op: impl Fn(&KnotVector, &[Vec4]) -> LineResult,
) -> Result<(KnotVector, Vec<Vec4>, Vec<usize>), SplineError> {
    let stride: usize = dims[axis + 1..].iter().product();
    let outer: usize = dims[..axis].iter().product();
    let n = dims[axis];
    let mut new_kv = None;
    let mut new_n = 0;
    let mut lines: Vec<Vec<Vec4>> = Vec::with_capacity(outer * stride);
    let mut line = vec![Vec4::zeros(); n];
    for o in 0..outer {
        for s in 0..stride {
            for (i, l) in line.iter_mut().enumerate() {
                *l = pw[(o * n + i) * stride + s];
            }
            let (k, q) = op(kv, &line)?;
            new_n = q.len();
            new_kv = Some(k);
            lines.push(q);
        }
    }
    let mut out = vec![Vec4::zeros(); outer * new_n * stride];
    for o in 0..outer {
        for s in 0..stride {
            let q = &lines[o * stride + s];
            for i in 0..new_n {
                out[(o * new_n + i) * stride + s] = q[i];
            }
        }
    }
    let mut nd = dims.to_vec();
    nd[axis] = new_n;
    Ok((new_kv.expect("nets are never empty"), out, nd))
}

fn check_insert_param(kv: &KnotVector, axis: usize, u: f64) -> Result<(), SplineError> {
    let d = kv.domain();
    if !u.is_finite() {
        return Err(SplineError::NonFiniteParameter { axis, value: u });
    }
    if u < d.min || u > d.max {
        return Err(SplineError::ParameterOutOfDomain {
            axis,
            value: u,
            min: d.min,
            max: d.max,
        });
    }
    Ok(())
}

impl NurbsCurve {
    /// Inserts the knot `u` `times` times (Piegl & Tiller A5.1). The shape is unchanged.
    pub fn insert_knot(&self, u: f64, times: usize) -> Result<Self, SplineError> {
        check_insert_param(self.knots(), 0, u)?;
        let (kv, pw) = insert_line(self.knots(), &self.homogeneous_points(), u, times, 0)?;
        Self::from_homogeneous(kv, &pw)
    }

    /// Inserts every knot of `values` once (knot refinement).
    pub fn refine(&self, values: &[f64]) -> Result<Self, SplineError> {
        values
            .iter()
            .try_fold(self.clone(), |c, &u| c.insert_knot(u, 1))
    }

    /// The same curve on its domain with end knots of multiplicity `p + 1`.
    pub fn clamped(&self) -> Result<Self, SplineError> {
        let (kv, pw) = clamp_line(self.knots(), &self.homogeneous_points(), 0)?;
        Self::from_homogeneous(kv, &pw)
    }

    /// Raises the degree by `times` (Piegl & Tiller A5.9); clamps first if needed. The shape is
    /// unchanged.
    pub fn elevate_degree(&self, times: usize) -> Result<Self, SplineError> {
        let (kv, pw) = elevate_line(self.knots(), &self.homogeneous_points(), times, 0)?;
        Self::from_homogeneous(kv, &pw)
    }
}

impl NurbsSurface {
    fn check_axis(axis: usize) -> Result<(), SplineError> {
        if axis > 1 {
            return Err(SplineError::NoSuchAxis { axis, dims: 2 });
        }
        Ok(())
    }

    fn apply_line_op(
        &self,
        axis: usize,
        op: impl Fn(&KnotVector, &[Vec4]) -> LineResult,
    ) -> Result<Self, SplineError> {
        Self::check_axis(axis)?;
        let (kv, pw, _) = along_axis(
            &self.knots()[axis],
            &self.homogeneous_points(),
            &self.dims(),
            axis,
            op,
        )?;
        let mut knots = self.knots().clone();
        knots[axis] = kv;
        Self::from_homogeneous(knots, &pw)
    }

    /// Inserts the knot `value` `times` times along `axis` (0 = u, 1 = v).
    pub fn insert_knot(&self, axis: usize, value: f64, times: usize) -> Result<Self, SplineError> {
        Self::check_axis(axis)?;
        check_insert_param(&self.knots()[axis], axis, value)?;
        self.apply_line_op(axis, |k, l| insert_line(k, l, value, times, axis))
    }

    /// Clamps the knot vector along `axis`.
    pub fn clamped(&self, axis: usize) -> Result<Self, SplineError> {
        self.apply_line_op(axis, |k, l| clamp_line(k, l, axis))
    }

    /// Raises the degree along `axis` by `times`.
    pub fn elevate_degree(&self, axis: usize, times: usize) -> Result<Self, SplineError> {
        self.apply_line_op(axis, |k, l| elevate_line(k, l, times, axis))
    }
}

impl NurbsVolume {
    fn apply_line_op(
        &self,
        axis: usize,
        op: impl Fn(&KnotVector, &[Vec4]) -> LineResult,
    ) -> Result<Self, SplineError> {
        if axis > 2 {
            return Err(SplineError::NoSuchAxis { axis, dims: 3 });
        }
        let (kv, pw, _) = along_axis(
            &self.knots()[axis],
            &self.homogeneous_points(),
            &self.dims(),
            axis,
            op,
        )?;
        let mut knots = self.knots().clone();
        knots[axis] = kv;
        Self::from_homogeneous(knots, &pw)
    }

    /// Inserts the knot `value` `times` times along `axis` (0 = u, 1 = v, 2 = w).
    pub fn insert_knot(&self, axis: usize, value: f64, times: usize) -> Result<Self, SplineError> {
        if axis > 2 {
            return Err(SplineError::NoSuchAxis { axis, dims: 3 });
        }
        check_insert_param(&self.knots()[axis], axis, value)?;
        self.apply_line_op(axis, |k, l| insert_line(k, l, value, times, axis))
    }

    /// Clamps the knot vector along `axis`.
    pub fn clamped(&self, axis: usize) -> Result<Self, SplineError> {
        self.apply_line_op(axis, |k, l| clamp_line(k, l, axis))
    }

    /// Raises the degree along `axis` by `times`.
    pub fn elevate_degree(&self, axis: usize, times: usize) -> Result<Self, SplineError> {
        self.apply_line_op(axis, |k, l| elevate_line(k, l, times, axis))
    }
}
