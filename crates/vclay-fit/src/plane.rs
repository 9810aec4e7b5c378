//! The base plane of a cloud (principal component analysis) and the first parametrization.
//!
//! The centroid `c` and the covariance `C = (1/N) sum (x_k - c)(x_k - c)^T` give the plane
//! through `c` spanned by the eigenvectors `e1`, `e2` of the two largest eigenvalues of `C`; the
//! third, `e3 = e1 x e2`, is its normal. Within the plane, the axes are then turned to the
//! rectangle of least area around the projections (for a square scan PCA's in-plane axes are
//! arbitrary, and a rectangle turned 45 degrees leaves half the control net over empty
//! corners): angles in steps of 1 degree, then 0.02 degree around the best, over at most
//! [`ROTATION_SAMPLES`] points. Each point is projected onto the plane,
//! `(a_k, b_k) = ((x_k - c) . e1, (x_k - c) . e2)`, and the bounding rectangle of the projections
//! is mapped onto the unit square: `u_k = (a_k - a_min) / (a_max - a_min)`, likewise `v_k`.
//! This is the classical first guess for height-field-like scans (Hoschek's parameter
//! correction then improves it, see [`crate::project`]).
//!
//! **The domain of a robust fit** comes from the inliers ([`BasePlane::dense_rect`]): outliers
//! displaced across a tilted plane project beyond the scan's edge, and a rectangle stretched to
//! them leaves a strip where only outliers lie, which the surface follows up as a wall. The
//! trimmed rectangle keeps, along each axis, the inliers from the first to the last window of
//! width `1 / DOMAIN_WINDOWS` of the extent that holds at least `DOMAIN_DENSITY` times the
//! mean number of inliers per window: sparse fringes (outliers that came close to the wall,
//! stray points) fall outside. The fit ([`crate::fit_surface`], robust or not) takes the
//! trimmed rectangle only when most points it leaves out are outliers, and then gives them
//! weight 0: points whose height over the surface at the new edge (along the normal `e3`)
//! exceeds Tukey's cut `4.685 sigma` plus their in-plane distance to the rectangle (a slope
//! above 1: a jump, not the surface continued). A round scan's tip keeps its extent (its last window holds several times the
//! threshold); a clean sharp corner (a triangle's tip), whose points are inliers, too.
//!
//! Degenerate clouds are errors: all points within `DEGENERATE_RATIO` of one point, or on a
//! line (second principal extent below `DEGENERATE_RATIO` times the first).

use crate::FitError;
use nalgebra::{Matrix3, SymmetricEigen};
use rayon::prelude::*;
use serde::Serialize;
use vclay_core::{Parallelism, Vec3};

/// Smallest ratio of the second to the first principal extent (and of the first extent to the
/// coordinate magnitude) for a cloud to count as spanning a surface.
pub const DEGENERATE_RATIO: f64 = 1e-9;
/// Points (evenly strided) used to choose the rectangle's rotation.
pub const ROTATION_SAMPLES: usize = 8192;
/// Windows per axis of the inlier-density test of a robust fit's domain (module docs).
pub const DOMAIN_WINDOWS: usize = 64;
/// Smallest inlier density at the domain's edge, relative to the mean (module docs).
pub const DOMAIN_DENSITY: f64 = 0.05;
/// Smallest move of an edge of the domain, relative to its extent, for which a robust fit
/// trims its rectangle (smaller changes keep the current one).
pub const DOMAIN_TOL: f64 = 1e-3;

/// The base plane of a cloud and the rectangle its points project into.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BasePlane {
    /// Centroid `c`.
    pub origin: [f64; 3],
    /// In-plane axes `e1`, `e2` (largest spread first) and the normal `e3 = e1 x e2`.
    pub axes: [[f64; 3]; 3],
    /// Projections' rectangle: `[a_min, a_max, b_min, b_max]`.
    pub rect: [f64; 4],
    /// Square roots of the covariance eigenvalues (principal standard deviations), descending.
    pub spread: [f64; 3],
}

impl BasePlane {
    /// Extents `[L_u, L_v]` of the rectangle (lengths in model units).
    pub fn extents(&self) -> [f64; 2] {
        [self.rect[1] - self.rect[0], self.rect[3] - self.rect[2]]
    }

    /// Unit-square parameters of a point (may fall outside `[0, 1]` for points not used to
    /// build the plane).
    pub fn param(&self, x: &Vec3) -> [f64; 2] {
        let d = [
            x[0] - self.origin[0],
            x[1] - self.origin[1],
            x[2] - self.origin[2],
        ];
        let dot = |e: &[f64; 3]| d[0] * e[0] + d[1] * e[1] + d[2] * e[2];
        let [lu, lv] = self.extents();
        [
            (dot(&self.axes[0]) - self.rect[0]) / lu,
            (dot(&self.axes[1]) - self.rect[2]) / lv,
        ]
    }
}

impl BasePlane {
    /// In-plane coordinates `(a, b)` of a point.
    pub fn project(&self, x: &Vec3) -> [f64; 2] {
        let d = [
            x[0] - self.origin[0],
            x[1] - self.origin[1],
            x[2] - self.origin[2],
        ];
        let dot = |e: &[f64; 3]| d[0] * e[0] + d[1] * e[1] + d[2] * e[2];
        [dot(&self.axes[0]), dot(&self.axes[1])]
    }

    /// The rectangle of the points `k` with `inlier(k)`, trimmed to where they are dense
    /// (module docs), within the current rectangle. `None` when fewer than
    /// `DOMAIN_WINDOWS` inliers are left or the trimmed rectangle would be empty.
    pub fn dense_rect(
        &self,
        points: &[Vec3],
        inlier: impl Fn(usize) -> bool + Sync,
    ) -> Option<[f64; 4]> {
        // The two axes side by side from 65,536 points. (The projections stay on one thread:
        // a parallel collect holds its chunks and the result at once, 16 bytes per point more
        // at the fit's peak.)
        let parallel = points.len() >= 65_536;
        let mut a = Vec::new();
        let mut b = Vec::new();
        for (k, x) in points.iter().enumerate() {
            if inlier(k) {
                let [pa, pb] = self.project(x);
                a.push(pa);
                b.push(pb);
            }
        }
        if a.len() < DOMAIN_WINDOWS {
            return None;
        }
        let [lu, lv] = self.extents();
        let (ra, rb) = if parallel {
            rayon::join(|| dense_range(&mut a, lu), || dense_range(&mut b, lv))
        } else {
            (dense_range(&mut a, lu), dense_range(&mut b, lv))
        };
        let ([a0, a1], [b0, b1]) = (ra?, rb?);
        let r = self.rect;
        let rect = [a0.max(r[0]), a1.min(r[1]), b0.max(r[2]), b1.min(r[3])];
        (rect[1] > rect[0] && rect[3] > rect[2]).then_some(rect)
    }

    /// Parameters on this plane's rectangle of a point whose parameters on `old` (a rectangle
    /// of the same plane) are `uv`, clamped to the unit square.
    pub fn remap(&self, old: &[f64; 4], uv: [f64; 2]) -> [f64; 2] {
        let [lu, lv] = self.extents();
        let a = old[0] + uv[0] * (old[1] - old[0]);
        let b = old[2] + uv[1] * (old[3] - old[2]);
        [
            ((a - self.rect[0]) / lu).clamp(0.0, 1.0),
            ((b - self.rect[2]) / lv).clamp(0.0, 1.0),
        ]
    }
}

/// Whether in-plane coordinates `(a, b)` lie in `rect` (`[a_min, a_max, b_min, b_max]`).
pub fn inside(rect: &[f64; 4], [a, b]: [f64; 2]) -> bool {
    a >= rect[0] && a <= rect[1] && b >= rect[2] && b <= rect[3]
}

/// The range of the values from the first to the last window of width `extent /
/// DOMAIN_WINDOWS` holding at least `DOMAIN_DENSITY` times the mean count per window.
///
/// The windows sit at the ends of the sorted values, so only the smallest and the largest
/// [`DENSE_TAIL`] share are sorted (after two selections) and searched; the whole array is
/// sorted only when a window is not found there. Either way the sorted values, and so the
/// result, are those of a full sort (issue 31: two full sorts of the inliers per round took
/// 9 % of a 1,000,000-point fit).
fn dense_range(x: &mut [f64], extent: f64) -> Option<[f64; 2]> {
    let n = x.len();
    let h = extent / DOMAIN_WINDOWS as f64;
    let t = ((DOMAIN_DENSITY * n as f64 / DOMAIN_WINDOWS as f64).ceil() as usize).clamp(1, n - 1);
    let tail = (n / DENSE_TAIL).max(8 * t);
    if 2 * tail < n {
        // x[..tail] the smallest values, x[n - tail..] the largest, each sorted.
        x.select_nth_unstable_by(tail, f64::total_cmp);
        x[..tail].sort_unstable_by(f64::total_cmp);
        let rest = &mut x[tail..];
        let m = rest.len() - tail;
        rest.select_nth_unstable_by(m, f64::total_cmp);
        rest[m..].sort_unstable_by(f64::total_cmp);
        let lo = (0..tail - t).find(|&i| x[i + t] - x[i] <= h);
        let hi = (n - tail + t..n).rev().find(|&j| x[j] - x[j - t] <= h);
        if let (Some(lo), Some(hi)) = (lo, hi) {
            return (hi > lo).then(|| [x[lo], x[hi]]);
        }
    }
    if n >= 65_536 {
        x.par_sort_unstable_by(f64::total_cmp);
    } else {
        x.sort_unstable_by(f64::total_cmp);
    }
    let lo = (0..n - t).find(|&i| x[i + t] - x[i] <= h)?;
    let hi = (t..n).rev().find(|&j| x[j] - x[j - t] <= h)?;
    (hi > lo).then(|| [x[lo], x[hi]])
}

/// [`dense_range`] first sorts and searches the `1 / DENSE_TAIL` smallest and largest values
/// (at least eight windows' worth of points).
const DENSE_TAIL: usize = 16;

/// Points per chunk of the base plane's parallel sums (fixed, so that the sums do not depend
/// on the threads' scheduling).
const SUM_CHUNK: usize = 16_384;

/// The base plane of `points` (already checked finite and non-empty).
pub fn base_plane(points: &[Vec3], par: Parallelism) -> Result<BasePlane, FitError> {
    let n = points.len() as f64;
    let parallel = par.is_parallel(points.len());
    // Parallel sums over fixed chunks, added in order: the same rounding whatever the thread
    // scheduling (a work-stealing reduce is not, and a fit's result then changed in its last
    // bits from run to run: `tests/fit.rs` `auto_leaves_clean_scans_alone` compares two fits
    // bit for bit and failed now and then on a loaded machine).
    let sum = if parallel {
        points
            .par_chunks(SUM_CHUNK)
            .map(|c| c.iter().fold(Vec3::zeros(), |a, b| a + b))
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Vec3::zeros(), |a, b| a + b)
    } else {
        points.iter().fold(Vec3::zeros(), |a, b| a + b)
    };
    let c = sum / n;
    let outer = |x: &Vec3| {
        let d = x - c;
        d * d.transpose()
    };
    let cov = if parallel {
        points
            .par_chunks(SUM_CHUNK)
            .map(|c| c.iter().map(outer).fold(Matrix3::zeros(), |a, b| a + b))
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Matrix3::zeros(), |a, b| a + b)
    } else {
        points
            .iter()
            .map(outer)
            .fold(Matrix3::zeros(), |a, b| a + b)
    } / n;
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let lam = order.map(|i| eig.eigenvalues[i].max(0.0));
    let scale = c.amax().max(lam[0].sqrt());
    if lam[0].sqrt() <= DEGENERATE_RATIO * scale || lam[0] == 0.0 {
        return Err(FitError::Degenerate {
            why: format!(
                "all {} points coincide (spread {:.3e} around ({}, {}, {}))",
                points.len(),
                lam[0].sqrt(),
                c[0],
                c[1],
                c[2]
            ),
        });
    }
    if lam[1].sqrt() <= DEGENERATE_RATIO.sqrt() * lam[0].sqrt() {
        return Err(FitError::Degenerate {
            why: format!(
                "the points lie on a line (principal spreads {:.3e} and {:.3e}): a surface \
                 needs a two-dimensional cloud",
                lam[0].sqrt(),
                lam[1].sqrt()
            ),
        });
    }
    let p1: Vec3 = eig.eigenvectors.column(order[0]).into();
    let p2: Vec3 = eig.eigenvectors.column(order[1]).into();
    let e3 = p1.cross(&p2);
    let theta = least_area_angle(points, &c, &p1, &p2);
    let (sn, cs) = theta.sin_cos();
    let e1 = p1 * cs + p2 * sn;
    let e2 = e3.cross(&e1);
    let proj = |x: &Vec3| {
        let d = x - c;
        [d.dot(&e1), d.dot(&e2)]
    };
    let bounds = |a: [f64; 4], b: [f64; 4]| {
        [
            a[0].min(b[0]),
            a[1].max(b[1]),
            a[2].min(b[2]),
            a[3].max(b[3]),
        ]
    };
    let one = |x: &Vec3| {
        let [a, b] = proj(x);
        [a, a, b, b]
    };
    let empty = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let rect = if parallel {
        points.par_iter().map(one).reduce(|| empty, bounds)
    } else {
        points.iter().map(one).fold(empty, bounds)
    };
    let arr = |v: Vec3| [v[0], v[1], v[2]];
    Ok(BasePlane {
        origin: arr(c),
        axes: [arr(e1), arr(e2), arr(e3)],
        rect,
        spread: lam.map(f64::sqrt),
    })
}

/// The in-plane rotation (radians, `[0, pi/2)`) of the least-area rectangle around the
/// projections of (a stride of) the points onto the plane spanned by `p1`, `p2`.
fn least_area_angle(points: &[Vec3], c: &Vec3, p1: &Vec3, p2: &Vec3) -> f64 {
    let stride = points.len().div_ceil(ROTATION_SAMPLES).max(1);
    let ab: Vec<[f64; 2]> = points
        .iter()
        .step_by(stride)
        .map(|x| {
            let d = x - c;
            [d.dot(p1), d.dot(p2)]
        })
        .collect();
    let area = |t: f64| {
        let (s, c) = t.sin_cos();
        let mut r = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for &[a, b] in &ab {
            let (x, y) = (a * c + b * s, b * c - a * s);
            r = [r[0].min(x), r[1].max(x), r[2].min(y), r[3].max(y)];
        }
        (r[1] - r[0]) * (r[3] - r[2])
    };
    let step = std::f64::consts::FRAC_PI_2 / 90.0;
    let coarse = (0..90).map(|k| k as f64 * step);
    let best = coarse
        .map(|t| (area(t), t))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a });
    let fine = (-50..=50).map(|k| best.1 + k as f64 * step / 50.0);
    let best = fine
        .map(|t| (area(t), t))
        .fold(best, |a, b| if b.0 < a.0 { b } else { a });
    // Prefer the angle nearest PCA's axes when the areas tie (within rounding).
    if area(0.0) <= best.0 * (1.0 + 1e-12) {
        0.0
    } else {
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The old `dense_range`: a full sort, then the two searches.
    fn dense_range_sorted(x: &mut [f64], extent: f64) -> Option<[f64; 2]> {
        x.sort_unstable_by(f64::total_cmp);
        let n = x.len();
        let h = extent / DOMAIN_WINDOWS as f64;
        let t =
            ((DOMAIN_DENSITY * n as f64 / DOMAIN_WINDOWS as f64).ceil() as usize).clamp(1, n - 1);
        let lo = (0..n - t).find(|&i| x[i + t] - x[i] <= h)?;
        let hi = (t..n).rev().find(|&j| x[j] - x[j - t] <= h)?;
        (hi > lo).then(|| [x[lo], x[hi]])
    }

    #[test]
    fn dense_range_equals_the_full_sort() {
        let mut state = 7u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // Uniform, a sparse fringe of 2 % far out on one side, a fringe of 10 % (beyond the
        // sorted tails: the full-sort fallback), duplicates, and small arrays.
        for (n, share, far) in [
            (100_000, 0.0, 0.0),
            (100_000, 0.02, 3.0),
            (100_000, 0.10, 3.0),
            (50_000, 0.02, -2.0),
            (1000, 0.0, 0.0),
            (40, 0.1, 1.0),
        ] {
            let mut x: Vec<f64> = (0..n)
                .map(|_| {
                    let r = rnd();
                    if rnd() < share {
                        1.0 + far * r
                    } else {
                        (r * 256.0).floor() / 256.0
                    }
                })
                .collect();
            let mut y = x.clone();
            assert_eq!(
                dense_range(&mut x, 1.0),
                dense_range_sorted(&mut y, 1.0),
                "n {n} share {share}"
            );
        }
    }
}
