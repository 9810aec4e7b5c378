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

    /// Largest condition estimate over the patches.
    pub fn condition(&self) -> f64 {
        self.patches
            .iter()
            .map(|p| p.stats.condition)
            .fold(1.0, f64::max)
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
