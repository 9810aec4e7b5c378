//! Solving, animating and tessellating a whole model (all its patches) at any instant.

use crate::error::PdeError;
use crate::solve::{PatchSolution, Solver};
use crate::spec::PdeModel;
use crate::surface::{GridWork, eval_grid_into, tessellate, uniform};
use vclay_core::{MeshSink, Vec3};

/// All patches of a model solved at one instant.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelSolution {
    /// The instant.
    pub t: f64,
    /// One solution per patch, in the model's order.
    pub patches: Vec<PatchSolution>,
}

impl ModelSolution {
    /// Largest root-mean-square collocation residual over the patches.
    pub fn residual_rms(&self) -> f64 {
        self.patches
            .iter()
            .map(|p| p.stats.residual_rms)
            .fold(0.0, f64::max)
    }

    /// The residual checked against the surface's size ([`ResidualCheck`]): the surface is
    /// tessellated on [`RESIDUAL_CHECK_GRID`] samples per patch for its bounding box.
    pub fn residual_check(&self, model: &PdeModel) -> ResidualCheck {
        let mut mesh = vclay_core::TriMesh::new();
        let [nu, nv] = RESIDUAL_CHECK_GRID;
        model.tessellate(self, nu, nv, &mut mesh);
        let size = bbox_diagonal(&mesh.positions);
        ResidualCheck::new(self.residual_rms(), size)
    }

    /// Largest condition estimate over the patches.
    pub fn condition(&self) -> f64 {
        self.patches
            .iter()
            .map(|p| p.stats.condition)
            .fold(1.0, f64::max)
    }
}

/// Largest residual RMS, as a fraction of the surface's size (its bounding-box diagonal), that
/// passes without a warning ([`ResidualCheck`]). The shipped figures that keep their shape sit
/// far below it (Fig 4(a), Fig 5(a) up to t = 0.5, the aircraft: 1e-16 to 5e-5; Fig 5(a) at
/// t = 1: 3.8e-3); fig6a at t = 1, whose surface has collapsed to a disc on a pinched
/// spindle, is at 2.1e-2 (docs/pde-figures.md lists every shipped spec).
pub const RESIDUAL_WARNING_RATIO: f64 = 1e-2;

/// Samples per patch `[nu, nv]` on which [`ModelSolution::residual_check`] measures the
/// surface's size.
pub const RESIDUAL_CHECK_GRID: [usize; 2] = [17, 33];

/// Diagonal of the bounding box of `points` (0 when empty).
fn bbox_diagonal(points: &[Vec3]) -> f64 {
    let Some(first) = points.first() else {
        return 0.0;
    };
    let (lo, hi) = points
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    (hi - lo).norm()
}

/// The collocation residual against the size of the surface it shapes. The residual of eq (10)
/// scales with the surface (a surface scaled by s has s times the residual, the coefficients
/// and parameter domains unchanged), so `ratio = residual_rms / size` is a scale-free measure of
/// how far the solution is from solving the PDE; above [`RESIDUAL_WARNING_RATIO`] the trial
/// terms cannot satisfy the PDE and the shape is a least-squares compromise that can look
/// nothing like the figure (fig6a at t = 1). It measures the PDE's residual, not a distance
/// between shapes: a fourth-order operator can leave a large residual on a good shape, so a
/// warning asks to look, it does not prove the shape wrong.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualCheck {
    /// Largest RMS collocation residual over the patches.
    pub residual_rms: f64,
    /// Bounding-box diagonal of the surface.
    pub size: f64,
    /// `residual_rms / size` (infinite when the size is 0 and the residual is not).
    pub ratio: f64,
}

impl ResidualCheck {
    /// The check of a residual against a surface size.
    pub fn new(residual_rms: f64, size: f64) -> Self {
        let ratio = if residual_rms == 0.0 {
            0.0
        } else if size > 0.0 {
            residual_rms / size
        } else {
            f64::INFINITY
        };
        Self {
            residual_rms,
            size,
            ratio,
        }
    }

    /// Whether the ratio is over [`RESIDUAL_WARNING_RATIO`] (or not a number).
    pub fn is_large(&self) -> bool {
        self.ratio.is_nan() || self.ratio > RESIDUAL_WARNING_RATIO
    }

    /// The warning to show when [`Self::is_large`], naming the figures.
    pub fn warning(&self) -> Option<String> {
        self.is_large().then(|| {
            format!(
                "residual RMS {:.3e} is {:.2} % of the surface's size {:.3} (over {} %): the trial \
                 terms do not solve the PDE here; the shape is a least-squares compromise, look \
                 at it before trusting it (more trial terms, other shape functions or another t \
                 may help)",
                self.residual_rms,
                100.0 * self.ratio,
                self.size,
                100.0 * RESIDUAL_WARNING_RATIO
            )
        })
    }
}

/// `count` instants evenly spaced over `[t0, t1]` (both included; one instant `t0` if
/// `count == 1`).
pub fn frame_times(t0: f64, t1: f64, count: usize) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![t0],
        n => (0..n)
            .map(|k| t0 + (t1 - t0) * k as f64 / (n - 1) as f64)
            .collect(),
    }
}

impl PdeModel {
    /// Solves every patch at `t`.
    pub fn solve(&self, t: f64) -> Result<ModelSolution, PdeError> {
        let mut s = ModelSolution::default();
        Animator::new(self).solve_into(t, &mut s)?;
        Ok(s)
    }

    /// Tessellates every patch on `nu x nv` samples into `sink`.
    pub fn tessellate(&self, sol: &ModelSolution, nu: usize, nv: usize, sink: &mut dyn MeshSink) {
        for (p, s) in self.patches.iter().zip(&sol.patches) {
            tessellate(p, s, nu, nv, sink);
        }
    }
}

/// Frame-by-frame solver for a model: reuses its workspaces, and solves patches in which
/// nothing depends on t only once.
#[derive(Debug)]
pub struct Animator<'a> {
    model: &'a PdeModel,
    solver: Solver,
    cached: Vec<Option<PatchSolution>>,
    grid: GridWork,
    us: Vec<f64>,
    vs: Vec<f64>,
    /// Grid points of static patches, with the grid size they were evaluated on.
    static_points: Vec<Option<(usize, usize, Vec<Vec3>)>>,
    /// [`crate::PdePatch::is_static`] of each patch (the model is borrowed, so it cannot change).
    statics: Vec<bool>,
}

impl<'a> Animator<'a> {
    /// A new animator for `model`.
    pub fn new(model: &'a PdeModel) -> Self {
        Animator {
            model,
            solver: Solver::new(),
            cached: vec![None; model.patches.len()],
            grid: GridWork::default(),
            us: Vec::new(),
            vs: Vec::new(),
            static_points: vec![None; model.patches.len()],
            statics: model.patches.iter().map(|p| p.is_static()).collect(),
        }
    }

    /// Solves all patches at `t` into `out`.
    pub fn solve_into(&mut self, t: f64, out: &mut ModelSolution) -> Result<(), PdeError> {
        out.t = t;
        out.patches
            .resize(self.model.patches.len(), PatchSolution::default());
        for (k, patch) in self.model.patches.iter().enumerate() {
            if self.statics[k] {
                if let Some(c) = &self.cached[k] {
                    out.patches[k].clone_from(c);
                    out.patches[k].t = t;
                    continue;
                }
                self.solver.solve_into(patch, t, &mut out.patches[k])?;
                self.cached[k] = Some(out.patches[k].clone());
            } else {
                self.solver.solve_into(patch, t, &mut out.patches[k])?;
            }
        }
        Ok(())
    }

    /// One whole frame: solves at `t` and evaluates every patch on a uniform `nu x nv` grid
    /// into `points` (patch after patch, each row-major). Patches in which nothing depends on
    /// t are solved and evaluated once and then copied. This is the unit of the frame-rate
    /// benchmark; with reused buffers it allocates nothing after the first frame.
    pub fn frame(
        &mut self,
        t: f64,
        nu: usize,
        nv: usize,
        sol: &mut ModelSolution,
        points: &mut Vec<Vec3>,
    ) -> Result<(), PdeError> {
        self.solve_into(t, sol)?;
        let per = nu * nv;
        points.resize(per * self.model.patches.len(), Vec3::zeros());
        if self.us.len() != nu {
            self.us = uniform(0.0, 1.0, nu);
        }
        for (k, patch) in self.model.patches.iter().enumerate() {
            let dst = &mut points[k * per..(k + 1) * per];
            if let Some((cu, cv, cached)) = &self.static_points[k]
                && (*cu, *cv) == (nu, nv)
            {
                dst.copy_from_slice(cached);
                continue;
            }
            let (v0, v1) = patch.v_range;
            if self.vs.len() != nv || self.vs.first() != Some(&v0) || self.vs.last() != Some(&v1) {
                self.vs = uniform(v0, v1, nv);
            }
            eval_grid_into(
                patch,
                &sol.patches[k],
                &self.us,
                &self.vs,
                &mut self.grid,
                dst,
            );
            if self.statics[k] {
                self.static_points[k] = Some((nu, nv, dst.to_vec()));
            }
        }
        Ok(())
    }
}
