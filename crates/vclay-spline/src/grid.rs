//! Batched evaluation over parameter grids.
//!
//! A tensor-product grid `u_0..u_a x v_0..v_b` shares basis values along each axis, so each
//! parameter's span and `p + 1` basis values are computed once. For each `u_i` the net is first
//! contracted along u into a homogeneous "row curve" `Q_j(u_i) = sum_r N_r(u_i) P^w_{r j}` (cost
//! `(p + 1) n_v`), after which every grid point costs only `q + 1` homogeneous multiply-adds and
//! one division. Rows run in parallel on rayon's pool above a size threshold
//! ([`vclay_core::Parallelism`]).

use crate::error::SplineError;
use crate::knots::{BasisWorkspace, KnotVector};
use crate::surface::NurbsSurface;
use crate::util::check_param;
use crate::volume::NurbsVolume;
use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3, Vec4};

/// Spans and basis values (and optionally first derivatives) of a list of parameters on one axis.
#[derive(Clone, Debug)]
pub struct AxisBasis {
    /// Degree.
    pub degree: usize,
    /// Span index of each parameter.
    pub spans: Vec<usize>,
    /// `(p + 1)` basis values per parameter.
    pub values: Vec<f64>,
    /// `(p + 1)` first derivatives per parameter (empty unless requested).
    pub derivs: Vec<f64>,
}

impl AxisBasis {
    /// Computes spans and basis values (and first derivatives when `with_derivs`), validating every
    /// parameter against the domain.
    pub fn new(
        kv: &KnotVector,
        axis: usize,
        params: &[f64],
        with_derivs: bool,
    ) -> Result<Self, SplineError> {
        Self::with_sides(kv, axis, params, with_derivs, &[])
    }

    /// [`AxisBasis::new`] with the parameters whose `from_left` entry is true evaluated on the
    /// span that ends there ([`KnotVector::find_span_left`]): at a C0 knot, the basis values
    /// and derivatives of the piece on the left (its one-sided limit). Entries beyond
    /// `from_left`'s length count as false.
    pub fn with_sides(
        kv: &KnotVector,
        axis: usize,
        params: &[f64],
        with_derivs: bool,
        from_left: &[bool],
    ) -> Result<Self, SplineError> {
        let p = kv.degree();
        let w = p + 1;
        let mut spans = Vec::with_capacity(params.len());
        let mut values = vec![0.0; params.len() * w];
        let mut derivs = if with_derivs {
            vec![0.0; params.len() * w]
        } else {
            Vec::new()
        };
        let mut ws = BasisWorkspace::new(p);
        let mut tmp = vec![0.0; 2 * w];
        for (i, &u) in params.iter().enumerate() {
            let u = check_param(kv, axis, u)?;
            let s = if from_left.get(i).copied().unwrap_or(false) {
                kv.find_span_left(u)
            } else {
                kv.find_span(u)
            };
            spans.push(s);
            if with_derivs {
                kv.basis_derivatives(s, u, 1, &mut tmp, &mut ws);
                values[i * w..(i + 1) * w].copy_from_slice(&tmp[..w]);
                derivs[i * w..(i + 1) * w].copy_from_slice(&tmp[w..]);
            } else {
                kv.basis(s, u, &mut values[i * w..(i + 1) * w]);
            }
        }
        Ok(Self {
            degree: p,
            spans,
            values,
            derivs,
        })
    }

    fn value(&self, i: usize) -> &[f64] {
        let w = self.degree + 1;
        &self.values[i * w..(i + 1) * w]
    }

    fn deriv(&self, i: usize) -> &[f64] {
        let w = self.degree + 1;
        &self.derivs[i * w..(i + 1) * w]
    }
}

/// Points and first partial derivatives of a surface on a grid (index `i * vs.len() + j`).
#[derive(Clone, Debug, Default)]
pub struct SurfaceGrid {
    /// Points.
    pub points: Vec<Vec3>,
    /// `ds/du`.
    pub du: Vec<Vec3>,
    /// `ds/dv`.
    pub dv: Vec<Vec3>,
}

impl NurbsSurface {
    /// Points on the grid `us x vs`, index `i * vs.len() + j` (allocating form of
    /// [`NurbsSurface::eval_grid_into`]).
    pub fn eval_grid(
        &self,
        us: &[f64],
        vs: &[f64],
        par: Parallelism,
    ) -> Result<Vec<Vec3>, SplineError> {
        let mut out = vec![Vec3::zeros(); us.len() * vs.len()];
        self.eval_grid_into(us, vs, &mut out, par)?;
        Ok(out)
    }

    /// Points on the grid `us x vs` written to `out` (length `us.len() * vs.len()`).
    ///
    /// # Panics
    /// If `out` has the wrong length (programmer error).
    #[track_caller]
    pub fn eval_grid_into(
        &self,
        us: &[f64],
        vs: &[f64],
        out: &mut [Vec3],
        par: Parallelism,
    ) -> Result<(), SplineError> {
        assert_eq!(
            out.len(),
            us.len() * vs.len(),
            "output length must be us.len() * vs.len()"
        );
        self.grid_rows::<Vec3, 1>(us, vs, out, par, |o, x, y, z| {
            o[0] = Vec3::new(x, y, z);
        })
    }

    /// Points on the grid `us x vs` written to `out` as flat `x, y, z` triples (length
    /// `3 * us.len() * vs.len()`, point `i * vs.len() + j` at `3 * (i * vs.len() + j)`): the
    /// layout of a C-contiguous `(nu, nv, 3)` float64 array. Same algorithm and results, bit for
    /// bit, as [`NurbsSurface::eval_grid_into`].
    ///
    /// # Panics
    /// If `out` has the wrong length (programmer error).
    #[track_caller]
    pub fn eval_grid_into_flat(
        &self,
        us: &[f64],
        vs: &[f64],
        out: &mut [f64],
        par: Parallelism,
    ) -> Result<(), SplineError> {
        assert_eq!(
            out.len(),
            3 * us.len() * vs.len(),
            "output length must be 3 * us.len() * vs.len()"
        );
        self.grid_rows::<f64, 3>(us, vs, out, par, |o, x, y, z| {
            o[0] = x;
            o[1] = y;
            o[2] = z;
        })
    }

    /// The row loop shared by the grid evaluators: `K` elements of `T` per point, written by
    /// `put(point_slot, x, y, z)`; `out.len()` must be `K * us.len() * vs.len()`.
    fn grid_rows<T: Send, const K: usize>(
        &self,
        us: &[f64],
        vs: &[f64],
        out: &mut [T],
        par: Parallelism,
        put: impl Fn(&mut [T], f64, f64, f64) + Sync,
    ) -> Result<(), SplineError> {
        if out.is_empty() {
            return Ok(());
        }
        let bu = AxisBasis::new(&self.knots()[0], 0, us, false)?;
        let bv = AxisBasis::new(&self.knots()[1], 1, vs, false)?;
        let pw = self.homogeneous_points();
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let row = |i: usize, q_row: &mut Vec<Vec4>, out_row: &mut [T]| {
            let su = bu.spans[i];
            let nu = bu.value(i);
            for (j, qj) in q_row.iter_mut().enumerate() {
                let mut acc = Vec4::zeros();
                for r in 0..=p {
                    acc += pw[(su - p + r) * nv + j] * nu[r];
                }
                *qj = acc;
            }
            for (j, o) in out_row.chunks_exact_mut(K).enumerate() {
                let sv = bv.spans[j];
                let b = bv.value(j);
                let base = &q_row[sv - q..=sv];
                let mut acc = Vec4::zeros();
                for s in 0..=q {
                    acc += base[s] * b[s];
                }
                let inv = 1.0 / acc.w;
                put(o, acc.x * inv, acc.y * inv, acc.z * inv);
            }
        };
        let row_len = vs.len() * K;
        if par.is_parallel(out.len() / K) {
            out.par_chunks_mut(row_len)
                .enumerate()
                .for_each_init(|| vec![Vec4::zeros(); nv], |qr, (i, o)| row(i, qr, o));
        } else {
            let mut qr = vec![Vec4::zeros(); nv];
            for (i, o) in out.chunks_mut(row_len).enumerate() {
                row(i, &mut qr, o);
            }
        }
        Ok(())
    }

    /// Points and first partial derivatives on the grid `us x vs` (for normals and shading).
    pub fn eval_grid_with_derivatives(
        &self,
        us: &[f64],
        vs: &[f64],
        par: Parallelism,
    ) -> Result<SurfaceGrid, SplineError> {
        self.eval_grid_with_derivatives_sided(us, vs, [&[], &[]], par)
    }

    /// [`NurbsSurface::eval_grid_with_derivatives`] with one-sided limits: `from_left[0][i]`
    /// (`from_left[1][j]`) evaluates `us[i]` (`vs[j]`) on the knot span that ends there
    /// ([`AxisBasis::with_sides`]), so that at a C0 knot the derivatives are those of the
    /// piece before it. Missing entries count as false (the piece after, as usual).
    pub fn eval_grid_with_derivatives_sided(
        &self,
        us: &[f64],
        vs: &[f64],
        from_left: [&[bool]; 2],
        par: Parallelism,
    ) -> Result<SurfaceGrid, SplineError> {
        let n = us.len() * vs.len();
        let mut grid = SurfaceGrid {
            points: vec![Vec3::zeros(); n],
            du: vec![Vec3::zeros(); n],
            dv: vec![Vec3::zeros(); n],
        };
        if n == 0 {
            return Ok(grid);
        }
        let bu = AxisBasis::with_sides(&self.knots()[0], 0, us, true, from_left[0])?;
        let bv = AxisBasis::with_sides(&self.knots()[1], 1, vs, true, from_left[1])?;
        let pw = self.homogeneous_points();
        let [p, q] = self.degree();
        let nv = self.dims()[1];
        let nvp = vs.len();
        let row = |i: usize,
                   qr: &mut (Vec<Vec4>, Vec<Vec4>),
                   (pts, (du, dv)): (&mut [Vec3], (&mut [Vec3], &mut [Vec3]))| {
            let su = bu.spans[i];
            let (nu, ndu) = (bu.value(i), bu.deriv(i));
            for j in 0..nv {
                let (mut a, mut b) = (Vec4::zeros(), Vec4::zeros());
                for r in 0..=p {
                    let c = pw[(su - p + r) * nv + j];
                    a += c * nu[r];
                    b += c * ndu[r];
                }
                qr.0[j] = a;
                qr.1[j] = b;
            }
            for j in 0..nvp {
                let sv = bv.spans[j];
                let (b, db) = (bv.value(j), bv.deriv(j));
                let (mut s, mut su_, mut sv_) = (Vec4::zeros(), Vec4::zeros(), Vec4::zeros());
                for t in 0..=q {
                    let k = sv - q + t;
                    s += qr.0[k] * b[t];
                    su_ += qr.1[k] * b[t];
                    sv_ += qr.0[k] * db[t];
                }
                let pt = s.xyz() / s.w;
                pts[j] = pt;
                du[j] = (su_.xyz() - pt * su_.w) / s.w;
                dv[j] = (sv_.xyz() - pt * sv_.w) / s.w;
            }
        };
        let init = || (vec![Vec4::zeros(); nv], vec![Vec4::zeros(); nv]);
        if par.is_parallel(n) {
            grid.points
                .par_chunks_mut(nvp)
                .zip(grid.du.par_chunks_mut(nvp).zip(grid.dv.par_chunks_mut(nvp)))
                .enumerate()
                .for_each_init(init, |qr, (i, o)| row(i, qr, o));
        } else {
            let mut qr = init();
            for (i, o) in grid
                .points
                .chunks_mut(nvp)
                .zip(grid.du.chunks_mut(nvp).zip(grid.dv.chunks_mut(nvp)))
                .enumerate()
            {
                row(i, &mut qr, o);
            }
        }
        Ok(grid)
    }
}

impl NurbsVolume {
    /// Points on the grid `us x vs x ws`, index `(i * vs.len() + j) * ws.len() + k`.
    ///
    /// For each `(u_i, v_j)` the net is contracted to a homogeneous curve in w, then each `w_k`
    /// costs `r + 1` multiply-adds.
    pub fn eval_grid(
        &self,
        us: &[f64],
        vs: &[f64],
        ws: &[f64],
        par: Parallelism,
    ) -> Result<Vec<Vec3>, SplineError> {
        let n = us.len() * vs.len() * ws.len();
        let mut out = vec![Vec3::zeros(); n];
        if n == 0 {
            return Ok(out);
        }
        let b = [
            AxisBasis::new(&self.knots()[0], 0, us, false)?,
            AxisBasis::new(&self.knots()[1], 1, vs, false)?,
            AxisBasis::new(&self.knots()[2], 2, ws, false)?,
        ];
        let pw = self.homogeneous_points();
        let [p, q, r] = self.degree();
        let [_, nv, nw] = self.dims();
        let nvp = vs.len();
        let nwp = ws.len();
        let slab = |i: usize, cw: &mut Vec<Vec4>, out: &mut [Vec3]| {
            let su = b[0].spans[i];
            let bu = b[0].value(i);
            for j in 0..nvp {
                let sv = b[1].spans[j];
                let bv = b[1].value(j);
                for (k, c) in cw.iter_mut().enumerate() {
                    let mut acc = Vec4::zeros();
                    for a in 0..=p {
                        for e in 0..=q {
                            acc += pw[((su - p + a) * nv + sv - q + e) * nw + k] * (bu[a] * bv[e]);
                        }
                    }
                    *c = acc;
                }
                for k in 0..nwp {
                    let sw = b[2].spans[k];
                    let bw = b[2].value(k);
                    let mut acc = Vec4::zeros();
                    for t in 0..=r {
                        acc += cw[sw - r + t] * bw[t];
                    }
                    out[j * nwp + k] = acc.xyz() / acc.w;
                }
            }
        };
        if par.is_parallel(n) {
            out.par_chunks_mut(nvp * nwp)
                .enumerate()
                .for_each_init(|| vec![Vec4::zeros(); nw], |cw, (i, o)| slab(i, cw, o));
        } else {
            let mut cw = vec![Vec4::zeros(); nw];
            for (i, o) in out.chunks_mut(nvp * nwp).enumerate() {
                slab(i, &mut cw, o);
            }
        }
        Ok(out)
    }
}
