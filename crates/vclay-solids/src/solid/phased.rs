//! The explicit and symplectic step as one phased program on the thread team
//! ([`vclay_core::team`]), for mid-sized solids.
//!
//! # Why
//! A step of the 4^3 cube at level 2 (2,197 data points, 28,548 springs) takes about 0.18 ms on
//! one core, in five passes of 10-50 us each (springs, `A^T f` level by level, the control
//! points, `A p` level by level). A rayon fork-join per pass costs more than it saves at that
//! size; one program whose phases are separated by spin barriers of a persistent team does not,
//! and it also halves each thread's working set, which at this size no longer fits one core's
//! L2 cache.
//!
//! # Phases (eq 10 of `subdivision-solids-journal.txt`, as in [`DynamicSolid::step`])
//! 1. Springs, one task per point block of the organized [`SpringSet`]: each task overwrites
//!    its block's forces with those of the springs inside the block, and adds its share of the
//!    springs that straddle blocks to a buffer of its own (nonzero only on the band of points
//!    that straddling springs touch).
//! 2. Merge, one task per block: the block's band points collect every share (and the shares
//!    are cleared for the next step); then the tools' forces on the block's points
//!    ([`crate::Tool::add_forces_in`]).
//! 3. `A^T f` level by level, finest first, through the stored transposes, split by rows; the
//!    last level (to the control points) is fused into phase 4. A level with a tensor-product
//!    form ([`SubdivisionMap::tensor`], a box in grid order: `A^(j) = S_z ⊗ S_y ⊗ S_x`) is
//!    split by its coarse z-planes instead: each task runs the z^T-pass into its planes, then
//!    the y^T- and x^T-passes within them ([`vclay_lattice::TensorOperator::apply_transpose_planes`]).
//! 4. Control points, split by free points: `g = A^T f - D v`, `M v` for the kinetic energy,
//!    the finiteness check.
//! 5. Integration, split by free points: the divergence verdict (every task computes the same
//!    one from the energies of phases 1-4), the last good state, `p'' = (A^T M A)^-1 g` (rows of
//!    the dense inverse, or one sparse solve), the integrator's update.
//! 6. `d = A p` level by level, split by rows; a tensor-product level in two phases: the x-
//!    and y-passes split by coarse z-planes (each reads only its own planes), then the z-pass
//!    split by fine z-planes ([`vclay_lattice::TensorOperator::apply_xy_planes`],
//!    [`vclay_lattice::TensorOperator::apply_z_planes`]). Its two intermediate grids live in
//!    the workspace, declared in the plan like the levels.
//!
//! A tensor-product level costs about a third of the multiply-adds of the sparse rows and
//! streams no large matrix: at level 2 of the 4^3 cube its two passes took ~27 us a thread
//! and step as sparse rows; with the grid numbering the step went from 0.093-0.098 to
//! 0.073-0.077 ms, about 8 us of it the tensor form (session 22,
//! `docs/performance.md` "Level-2 step, session 22 (h60)").
//!
//! Tasks of the same part of the data have the same index in every phase, so with the team's
//! owner rule ([`vclay_core::team`]) each thread keeps its half of `d`, `f` and the levels in
//! its own cache from phase to phase and from step to step.
//!
//! Every task writes its own part, so the result does not depend on how many threads ran the
//! program; it equals the one-thread step up to the order of the force sums (a few units in the
//! last place, see the tests). The map passes themselves, sparse or tensor, are the map's
//! own products ([`SubdivisionMap::apply_into`], [`SubdivisionMap::apply_transpose_into`])
//! bit for bit.
//!
//! # Borrows
//! Tasks reach the shared buffers through a [`Plan`] that declares, before the program runs,
//! which buffers ([`Slots`]) each phase reads and which range each task writes; it is checked
//! once when the program starts, and a task then takes its part or reads a buffer with no
//! shared state touched. The run-time claims of [`vclay_core::team::SharedSlice`] used before
//! took a lock that both threads took at the same moment when a phase started, about 26 claims
//! a thread and step, each a cache-line transfer between the cores (issue 31,
//! `docs/performance.md` "Level-2 step, session 21"). The plan is rebuilt every step in the
//! workspace (a few hundred ranges, no allocation once grown), so it always matches the
//! model. `g` is one buffer of points and the energies, kinetic energies and finiteness flags
//! that the integration phase reads are one buffer of scalars (session 20).

use std::ops::Range;

use vclay_core::team::{Plan, PlannedSlice, Task, team_threads};
use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{SparseMatrix, SubdivisionMap};

use super::{DynamicSolid, Energy, Integrator, MassFactor, advance, inverse_point_rows, verdict};

/// Active data points from which [`Parallelism::Auto`] runs a step as a phased program.
/// Below it a step takes a few microseconds and the barriers would cost a good part of that.
pub const PHASED_POINTS: usize = 1000;

/// Smallest number of rows per task of a split phase.
const ROWS_PER_TASK: usize = 32;

/// Buffers of the phased step, kept between steps.
#[derive(Clone, Debug, Default)]
pub(super) struct PhasedWork {
    /// Intermediate levels of the chain (index = level; 0 and the last unused).
    levels: Vec<Vec<Vec3>>,
    /// The two intermediate grids of each level applied in its tensor-product form (index
    /// `2 j` and `2 j + 1` for level `j`; empty for the other levels).
    mids: Vec<Vec<Vec3>>,
    /// `g` on the free points.
    g: Vec<Vec3>,
    /// The scalars that the integration phase reads, in one buffer so that a task borrows
    /// them once ([`Scalars`]).
    scalars: Vec<f64>,
    /// Per spring block, the forces of its share of the straddling springs (zero outside the
    /// band between steps).
    straddle: Vec<Vec<Vec3>>,
    /// Whether `straddle` is all zero (false while a program runs, so that a panicking step
    /// leaves it to be cleared).
    clean: bool,
    /// Points per level of the chain (0: the control points).
    pts: Vec<usize>,
    /// The program's phases and their task counts.
    phases: Vec<(Phase, usize)>,
    /// The task counts alone.
    counts: Vec<usize>,
    /// The program's borrows ([`Slots`]).
    plan: Plan,
}

/// The slices of the phased program, numbered for its [`Plan`]: the fixed ones, then level
/// `j` of the chain at `LEVELS + j` (`0..=n`, the ends unused), then the two intermediate
/// grids of each level `j < n` (used by tensor-product levels), then the straddle buffer of
/// spring block `s`.
#[derive(Clone, Copy, Debug)]
struct Slots {
    n: usize,
    nb: usize,
}

impl Slots {
    const D: usize = 0;
    const F: usize = 1;
    const SCALARS: usize = 2;
    const G: usize = 3;
    const P: usize = 4;
    const V: usize = 5;
    const GOOD_P: usize = 6;
    const GOOD_V: usize = 7;
    const LEVELS: usize = 8;

    fn level(self, j: usize) -> usize {
        Self::LEVELS + j
    }

    /// Intermediate grid `w` (0 or 1) of tensor level `j`.
    fn mid(self, j: usize, w: usize) -> usize {
        Self::LEVELS + self.n + 1 + 2 * j + w
    }

    fn straddle(self, s: usize) -> usize {
        Self::LEVELS + 3 * self.n + 1 + s
    }

    fn len(self) -> usize {
        self.straddle(self.nb)
    }
}

/// The layout of [`PhasedWork::scalars`] for `nb` spring blocks: per spring block, the energy
/// of its springs and of its share of the straddling springs; per block, the tools' energy;
/// then per control task, its kinetic energy and its finiteness (1 or 0).
#[derive(Clone, Copy, Debug)]
struct Scalars {
    nb: usize,
    control_tasks: usize,
}

impl Scalars {
    fn len(self) -> usize {
        3 * self.nb + 2 * self.control_tasks
    }

    /// Spring and straddle energies of block `t`.
    fn springs(self, t: usize) -> Range<usize> {
        2 * t..2 * t + 2
    }

    /// The tools' energy on block `t`.
    fn tools(self, t: usize) -> Range<usize> {
        2 * self.nb + t..2 * self.nb + t + 1
    }

    /// Kinetic energy and finiteness of control task `t`.
    fn control(self, t: usize) -> Range<usize> {
        3 * self.nb + 2 * t..3 * self.nb + 2 * t + 2
    }

    /// The energies of phases 1-4 and whether the state was finite: the same sums in the same
    /// order wherever computed.
    fn energy(self, e: &[f64]) -> (Energy, bool) {
        let control = || (0..self.control_tasks).map(|t| &e[self.control(t)]);
        let energy = Energy {
            kinetic: control().map(|c| c[0]).sum(),
            internal: e[..2 * self.nb].iter().sum(),
            tools: e[2 * self.nb..3 * self.nb].iter().sum(),
        };
        (energy, control().all(|c| c[1] != 0.0))
    }
}

/// What a phase does.
#[derive(Clone, Copy, Debug)]
enum Phase {
    Springs,
    Merge,
    /// `A^(j)T` into level `j` (`1 <= j < n`).
    Transpose(usize),
    Control,
    Integrate,
    /// The x- and y-passes of a level `j` applied in its tensor-product form.
    ApplyXY(usize),
    /// `A^(j)` from level `j` to `j + 1` (the z-pass of a tensor level).
    Apply(usize),
}

/// Range `t` of `rows` split into `tasks`.
fn chunk(rows: usize, tasks: usize, t: usize) -> Range<usize> {
    rows * t / tasks..rows * (t + 1) / tasks
}

/// `r` scaled by `len` (a range of planes of `len` values as a range of values).
fn scaled(r: &Range<usize>, len: usize) -> Range<usize> {
    r.start * len..r.end * len
}

/// Tasks for a phase of `rows` rows on `threads` threads.
fn tasks_for(rows: usize, threads: usize) -> usize {
    (rows / ROWS_PER_TASK).clamp(1, threads)
}

/// Rows `rows` of `op x`, `x` read through `src`, stored in `out` (the rows from
/// `rows.start`), or at `to[row] - to[rows.start]` (`to` sorted) when given.
fn rows_into(
    op: &SparseMatrix,
    rows: Range<usize>,
    src: impl Fn(usize) -> Vec3,
    out: &mut [Vec3],
    to: Option<&[u32]>,
) {
    if rows.is_empty() {
        return;
    }
    match to {
        Some(o) => {
            let base = o[rows.start] as usize;
            op.apply_rows_with(rows, src, |i, x| out[o[i] as usize - base] = x);
        }
        None => {
            let base = rows.start;
            op.apply_rows_with(rows, src, |i, x| out[i - base] = x);
        }
    }
}

/// `out[q] = row rows[q] of op x` (`u32::MAX`: zero): the `A^(1)T` rows of a task's free
/// points. Two rows at a time ([`SparseMatrix::apply_row_list_with`], the same bits as one
/// row at a time) unless a row is missing (fixed points of a restricted chain).
fn free_rows_into(op: &SparseMatrix, rows: &[u32], src: impl Fn(usize) -> Vec3, out: &mut [Vec3]) {
    if !rows.contains(&u32::MAX) {
        return op.apply_row_list_with(rows, src, |q, x| out[q] = x);
    }
    for (o, &r) in out.iter_mut().zip(rows) {
        *o = Vec3::zeros();
        if r != u32::MAX {
            let r = r as usize;
            op.apply_rows_with(r..r + 1, &src, |_, x| *o = x);
        }
    }
}

impl DynamicSolid {
    /// Whether [`DynamicSolid::step`] runs as a phased program: the explicit or symplectic
    /// integrator with springs, a team of two or more threads, a chain small enough for stored
    /// transposes ([`SubdivisionMap::GATHER_NNZ`]), organized springs, and under
    /// [`Parallelism::Auto`] at least [`PHASED_POINTS`] active data points.
    pub(super) fn phased_eligible(&self) -> bool {
        let par = self.params.parallelism;
        let map = match &self.restricted {
            Some(r) => r.map(),
            None => &self.disc.map,
        };
        let springs = self.active_springs.as_ref().unwrap_or(&self.springs);
        matches!(
            self.params.integrator,
            Integrator::Explicit | Integrator::SymplecticEuler
        ) && self.metric.is_none()
            && par != Parallelism::Sequential
            && (par == Parallelism::Rayon || self.active_count >= PHASED_POINTS)
            && map.levels() > 0
            && map.operators().iter().map(|a| a.nnz()).sum::<usize>() <= SubdivisionMap::GATHER_NNZ
            && springs.blocks_for(self.d.len()).is_some()
            && team_threads() > 1
    }

    /// One explicit or symplectic step as a phased program (see the [module docs](self)).
    /// Returns the energies of the state at the start of the step and whether that state was
    /// finite; the state advances only if [`DynamicSolid::verdict`] accepts them (the caller
    /// then reports the divergence).
    pub(super) fn phased_step(&mut self) -> (Energy, bool) {
        let threads = team_threads();
        let Self {
            params,
            p,
            v,
            good,
            d,
            mass,
            springs,
            active_springs,
            restricted,
            disc,
            mp,
            dp,
            damping_ratio,
            free,
            free_rows,
            solver,
            boundary,
            tools,
            work,
            energy_scale,
            tool_energy_seen,
            ..
        } = self;
        let dt = params.dt;
        let explicit = params.integrator == Integrator::Explicit;
        let springs = active_springs.as_ref().unwrap_or(springs);
        let nd = d.len();
        let nc = p.len();
        let m = free.len();
        let blocks = springs
            .blocks_for(nd)
            .expect("phased step: organized springs");
        let (map, inputs, outputs) = match restricted.as_ref() {
            Some(r) => (r.map(), Some(&r.inputs[..]), Some(&r.outputs[..])),
            None => (&disc.map, None, None),
        };
        let n = map.levels();
        let pw = &mut work.phased;
        let PhasedWork {
            levels,
            mids,
            g,
            scalars,
            straddle,
            clean,
            pts,
            phases,
            counts,
            plan,
        } = pw;
        // Points per level: level 0 the (restricted) control points, level n the data points.
        pts.clear();
        pts.push(map.operator(0).ncols());
        pts.extend(map.operators().iter().map(|a| a.nrows()));
        let pts = &pts[..];
        // Levels applied in their tensor-product form: between two grids in grid order (never
        // the first level, whose transpose phase 4 reads; never a restricted chain's).
        let tensor = |j: usize| if j > 0 { map.tensor(j) } else { None };
        // The stored transposes of the other levels, built before the tasks read them.
        for j in 0..n {
            if tensor(j).is_none() {
                map.transpose(j);
            }
        }
        // Tasks over `planes` z-planes of `len` values each.
        let plane_tasks = |planes: usize, len: usize| tasks_for(planes * len, threads).min(planes);

        // Phases and their task counts.
        let nb = blocks.len();
        phases.clear();
        phases.extend([(Phase::Springs, nb), (Phase::Merge, nb)]);
        for j in (1..n).rev() {
            let tasks = match tensor(j) {
                Some(t) => plane_tasks(t.dims().0[2], pts[j + 1] / t.dims().1[2]),
                None => tasks_for(pts[j], threads),
            };
            phases.push((Phase::Transpose(j), tasks));
        }
        let control_tasks = tasks_for(m.max(nc), threads);
        phases.push((Phase::Control, control_tasks));
        let integrate_tasks = match solver.factor {
            MassFactor::Dense(_) => tasks_for(m, threads),
            _ => 1,
        };
        phases.push((Phase::Integrate, integrate_tasks));
        for j in 0..n {
            match tensor(j) {
                Some(t) => {
                    let ([.., cz], [fx, fy, fz]) = t.dims();
                    phases.push((Phase::ApplyXY(j), plane_tasks(cz, fx * fy)));
                    phases.push((Phase::Apply(j), plane_tasks(fz, fx * fy)));
                }
                None => phases.push((Phase::Apply(j), tasks_for(pts[j + 1], threads))),
            }
        }
        let phases = &phases[..];
        counts.clear();
        counts.extend(phases.iter().map(|p| p.1));

        // Shared buffers.
        levels.resize_with(n + 1, Vec::new);
        for j in 1..n {
            levels[j].resize(pts[j], Vec3::zeros());
        }
        mids.resize_with(2 * n, Vec::new);
        for j in 0..n {
            let [l1, l2] = tensor(j).map_or([0, 0], |t| {
                let cz = t.dims().0[2];
                t.intermediate_plane_lens().map(|l| l * cz)
            });
            mids[2 * j].resize(l1, Vec3::zeros());
            mids[2 * j + 1].resize(l2, Vec3::zeros());
        }
        g.resize(m, Vec3::zeros());
        let layout = Scalars { nb, control_tasks };
        scalars.resize(layout.len(), 0.0);
        if !*clean || straddle.len() != nb || straddle.iter().any(|b| b.len() != nd) {
            *straddle = vec![vec![Vec3::zeros(); nd]; nb];
        }
        *clean = false;

        // The rows of `p`, `v` and the good state that integration task `t` of `tasks` owns:
        // from its first free point to the next task's, the first and last tasks extended to
        // the ends, so the tasks cover every control point.
        let owned = |t: usize, tasks: usize| -> Range<usize> {
            let kr = chunk(m, tasks, t);
            let lo = if t == 0 { 0 } else { free[kr.start] as usize };
            let hi = if t + 1 == tasks {
                nc
            } else {
                free[chunk(m, tasks, t + 1).start] as usize
            };
            lo..hi
        };
        // Rows `rows` of a map into the data points go to `to[row]` (sorted) when given.
        let out_range = |rows: Range<usize>, to: Option<&[u32]>| match to {
            Some(o) if !rows.is_empty() => o[rows.start] as usize..o[rows.end - 1] as usize + 1,
            Some(_) => 0..0,
            None => rows,
        };

        // Every borrow of every task, declared and checked once (see "Borrows" above).
        let slot = Slots { n, nb };
        plan.reset(counts, slot.len());
        for (k, &(phase, tasks)) in phases.iter().enumerate() {
            for t in 0..tasks {
                match phase {
                    Phase::Springs => {
                        plan.read(Slots::D, k);
                        plan.write(Slots::F, k, t, blocks[t].clone());
                        plan.write(slot.straddle(t), k, t, 0..nd);
                        plan.write(Slots::SCALARS, k, t, layout.springs(t));
                    }
                    Phase::Merge => {
                        plan.read(Slots::D, k);
                        plan.write(Slots::F, k, t, blocks[t].clone());
                        for s in 0..nb {
                            plan.write(slot.straddle(s), k, t, blocks[t].clone());
                        }
                        plan.write(Slots::SCALARS, k, t, layout.tools(t));
                    }
                    Phase::Transpose(j) => {
                        plan.read(
                            if j + 1 == n {
                                Slots::F
                            } else {
                                slot.level(j + 1)
                            },
                            k,
                        );
                        match tensor(j) {
                            Some(op) => {
                                // Coarse z-planes, with their planes of both intermediates.
                                let ([cx, cy, cz], _) = op.dims();
                                let [l1, l2] = op.intermediate_plane_lens();
                                let e = chunk(cz, tasks, t);
                                plan.write(slot.level(j), k, t, scaled(&e, cx * cy));
                                plan.write(slot.mid(j, 0), k, t, scaled(&e, l1));
                                plan.write(slot.mid(j, 1), k, t, scaled(&e, l2));
                            }
                            None => plan.write(slot.level(j), k, t, chunk(pts[j], tasks, t)),
                        }
                    }
                    Phase::Control => {
                        plan.read(Slots::P, k);
                        plan.read(Slots::V, k);
                        plan.read(if n == 1 { Slots::F } else { slot.level(1) }, k);
                        plan.write(Slots::G, k, t, chunk(m, tasks, t));
                        plan.write(Slots::SCALARS, k, t, layout.control(t));
                    }
                    Phase::Integrate => {
                        plan.read(Slots::SCALARS, k);
                        plan.read(Slots::G, k);
                        for s in [Slots::P, Slots::V, Slots::GOOD_P, Slots::GOOD_V] {
                            plan.write(s, k, t, owned(t, tasks));
                        }
                    }
                    Phase::ApplyXY(j) => {
                        let op = tensor(j).expect("tensor level");
                        plan.read(slot.level(j), k);
                        let [l1, l2] = op.intermediate_plane_lens();
                        let e = chunk(op.dims().0[2], tasks, t);
                        plan.write(slot.mid(j, 0), k, t, scaled(&e, l1));
                        plan.write(slot.mid(j, 1), k, t, scaled(&e, l2));
                    }
                    Phase::Apply(j) if tensor(j).is_some() => {
                        // Fine z-planes (no output map: a restricted chain has no tensor levels).
                        let ([..], [fx, fy, fz]) = tensor(j).unwrap().dims();
                        plan.read(slot.mid(j, 1), k);
                        let rows = scaled(&chunk(fz, tasks, t), fx * fy);
                        let dst = if j + 1 < n {
                            slot.level(j + 1)
                        } else {
                            Slots::D
                        };
                        plan.write(dst, k, t, rows);
                    }
                    Phase::Apply(j) => {
                        plan.read(if j == 0 { Slots::P } else { slot.level(j) }, k);
                        let rows = chunk(pts[j + 1], tasks, t);
                        if j + 1 < n {
                            plan.write(slot.level(j + 1), k, t, rows);
                        } else {
                            plan.write(Slots::D, k, t, out_range(rows, outputs));
                        }
                    }
                }
            }
        }
        let mut program = plan.start();
        let straddle: Vec<PlannedSlice<'_, '_, Vec3>> = straddle
            .iter_mut()
            .enumerate()
            .map(|(s, b)| program.slice(slot.straddle(s), &mut b[..]))
            .collect();
        let band = &springs.band[..];
        let levels: Vec<PlannedSlice<'_, '_, Vec3>> = levels
            .iter_mut()
            .enumerate()
            .map(|(j, l)| program.slice(slot.level(j), &mut l[..]))
            .collect();
        let mids: Vec<PlannedSlice<'_, '_, Vec3>> = mids
            .iter_mut()
            .enumerate()
            .map(|(i, l)| program.slice(slot.mid(i / 2, i % 2), &mut l[..]))
            .collect();
        let gsh = program.slice(Slots::G, &mut g[..]);
        let scalar_sh = program.slice(Slots::SCALARS, &mut scalars[..]);
        let f = program.slice(Slots::F, &mut work.f[..]);
        let dsh = program.slice(Slots::D, &mut d[..]);
        let psh = program.slice(Slots::P, &mut p[..]);
        let vsh = program.slice(Slots::V, &mut v[..]);
        let (good_p, good_v) = (&mut good.0, &mut good.1);
        let gp = program.slice(Slots::GOOD_P, &mut good_p[..]);
        let gv = program.slice(Slots::GOOD_V, &mut good_v[..]);
        let (dense_inverse, sparse) = match &solver.factor {
            MassFactor::Empty => (None, None),
            MassFactor::Dense(inv) => (Some(&inv[..]), None),
            MassFactor::Sparse(llt) => (None, Some(llt)),
        };
        let (free, free_rows, mp, dp) = (&free[..], &free_rows[..], &*mp, &*dp);
        let (mass, boundary, tools) = (&mass[..], &*boundary, &tools[..]);
        let damping_ratio = *damping_ratio;
        let divergence = (params.divergence_factor, *energy_scale, *tool_energy_seen);
        let step = |x: &mut Vec3, y: &mut Vec3, a: Vec3| advance(explicit, x, y, a, dt);

        let run = |task: &Task| {
            let t = task.index();
            let (phase, tasks) = phases[task.phase()];
            match phase {
                Phase::Springs => {
                    let dr = dsh.read(task);
                    let e = springs.block_forces(t, dr, f.part(task).1);
                    let es = springs.straddle_forces(dr, straddle[t].part(task).1, t, nb);
                    let er = scalar_sh.part(task).1;
                    er[0] = e;
                    er[1] = es;
                }
                Phase::Merge => {
                    // The band points of block `t`: add every share, and clear the shares;
                    // then the tools' forces on the block.
                    let r = blocks[t].clone();
                    let lo = band.partition_point(|&i| (i as usize) < r.start);
                    let hi = band.partition_point(|&i| (i as usize) < r.end);
                    let fr = f.part(task).1;
                    for share in &straddle {
                        let sh = share.part(task).1;
                        for &i in &band[lo..hi] {
                            let i = i as usize - r.start;
                            fr[i] += sh[i];
                            sh[i] = Vec3::zeros();
                        }
                    }
                    let dr = dsh.read(task);
                    let mut te = 0.0;
                    for tool in tools.iter().flatten() {
                        te += tool.add_forces_in(dr, mass, boundary, fr, r.clone());
                    }
                    scalar_sh.part(task).1[0] = te;
                }
                Phase::Transpose(j) if tensor(j).is_some() => {
                    let op = tensor(j).unwrap();
                    let src = if j + 1 == n {
                        f.read(task)
                    } else {
                        levels[j + 1].read(task)
                    };
                    let planes = chunk(op.dims().0[2], tasks, t);
                    let (u2, u1) = (mids[2 * j + 1].part(task).1, mids[2 * j].part(task).1);
                    op.apply_transpose_planes(src, planes, u2, u1, levels[j].part(task).1);
                }
                Phase::Transpose(j) => {
                    let op = map.transpose(j);
                    let (rows, out) = levels[j].part(task);
                    if j + 1 == n {
                        let fr = f.read(task);
                        match outputs {
                            Some(o) => rows_into(op, rows, |c| fr[o[c] as usize], out, None),
                            None => rows_into(op, rows, |c| fr[c], out, None),
                        }
                    } else {
                        let src = levels[j + 1].read(task);
                        rows_into(op, rows, |c| src[c], out, None);
                    }
                }
                Phase::Control => {
                    let (pr, vr) = (psh.read(task), vsh.read(task));
                    let all = chunk(nc, tasks, t);
                    let ok = pr[all.clone()]
                        .iter()
                        .chain(&vr[all])
                        .all(|x| x.iter().all(|c| c.is_finite()));
                    let (kr, out) = gsh.part(task);
                    // `A^(1)T` rows of the free points, from level 1 (or the forces).
                    let op = map.transpose(0);
                    let rows = &free_rows[kr.clone()];
                    if n == 1 {
                        let fr = f.read(task);
                        match outputs {
                            Some(o) => free_rows_into(op, rows, |c| fr[o[c] as usize], out),
                            None => free_rows_into(op, rows, |c| fr[c], out),
                        }
                    } else {
                        let lr = levels[1].read(task);
                        free_rows_into(op, rows, |c| lr[c], out);
                    }
                    // `M v` (kinetic energy) and `g -= D v`, the free points two rows at a time
                    // (the same bits as one at a time).
                    let ks = &free[kr];
                    let mut kin = 0.0;
                    mp.apply_row_list_with(
                        ks,
                        |c| vr[c],
                        |q, mv| {
                            let i = ks[q] as usize;
                            kin += 0.5 * vr[i].dot(&mv);
                            let dv = match damping_ratio {
                                Some(c) => mv * c,
                                None => {
                                    let mut dv = Vec3::zeros();
                                    dp.apply_rows_with(i..i + 1, |c| vr[c], |_, x| dv = x);
                                    dv
                                }
                            };
                            out[q] -= dv;
                        },
                    );
                    let sc = scalar_sh.part(task).1;
                    sc[0] = kin;
                    sc[1] = if ok { 1.0 } else { 0.0 };
                }
                Phase::Integrate => {
                    let (energy, all_finite) = layout.energy(scalar_sh.read(task));
                    let (factor, scale, seen) = divergence;
                    let accepted = verdict(
                        &energy,
                        all_finite,
                        factor,
                        scale + seen.max(energy.tools.abs()),
                    )
                    .is_ok();
                    if !accepted {
                        return;
                    }
                    let (own, pr) = psh.part(task);
                    let vr = vsh.part(task).1;
                    let base = own.start;
                    gp.part(task).1.copy_from_slice(pr);
                    gv.part(task).1.copy_from_slice(vr);
                    let g = gsh.read(task);
                    if let Some(inv) = dense_inverse {
                        inverse_point_rows(inv, g, chunk(m, tasks, t), |k, a| {
                            let i = free[k] as usize - base;
                            step(&mut pr[i], &mut vr[i], a);
                        });
                    } else if let Some(llt) = sparse {
                        use faer::linalg::solvers::Solve;
                        let mut rhs = faer::Mat::<f64>::from_fn(m, 3, |k, j| g[k][j]);
                        llt.solve_in_place(rhs.as_mut());
                        for (k, &i) in free.iter().enumerate() {
                            let a = Vec3::new(rhs[(k, 0)], rhs[(k, 1)], rhs[(k, 2)]);
                            let i = i as usize - base;
                            step(&mut pr[i], &mut vr[i], a);
                        }
                    }
                }
                Phase::ApplyXY(j) => {
                    let op = tensor(j).unwrap();
                    let planes = chunk(op.dims().0[2], tasks, t);
                    let (t1, t2) = (mids[2 * j].part(task).1, mids[2 * j + 1].part(task).1);
                    op.apply_xy_planes(levels[j].read(task), planes, t1, t2);
                }
                Phase::Apply(j) if tensor(j).is_some() => {
                    let op = tensor(j).unwrap();
                    let planes = chunk(op.dims().1[2], tasks, t);
                    let dst = if j + 1 < n { &levels[j + 1] } else { &dsh };
                    op.apply_z_planes(mids[2 * j + 1].read(task), planes, dst.part(task).1);
                }
                Phase::Apply(j) => {
                    let op = map.operator(j);
                    let rows = chunk(pts[j + 1], tasks, t);
                    let (dst, to) = if j + 1 < n {
                        (&levels[j + 1], None)
                    } else {
                        (&dsh, outputs)
                    };
                    let out = dst.part(task).1;
                    if j == 0 {
                        let pr = psh.read(task);
                        match inputs {
                            Some(ins) => rows_into(op, rows, |c| pr[ins[c] as usize], out, to),
                            None => rows_into(op, rows, |c| pr[c], out, to),
                        }
                    } else {
                        let src = levels[j].read(task);
                        rows_into(op, rows, |c| src[c], out, to);
                    }
                }
            }
        };
        program.run(&run);
        drop((straddle, levels, mids));
        work.phased.clean = true;
        layout.energy(&work.phased.scalars)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Material, SolidParams, SolidSource, SolidsError, Tool};

    use crate::benchmarks::{bspline_box as bspline, subdivision_box as cube};

    /// Steps a model with a rope (and the control points below `fix_below` fixed) under
    /// `parallelism`; returns the final control points, velocities and data points, and
    /// whether the steps ran phased.
    fn trajectory(
        model: &(SolidSource, Vec<Vec3>),
        integrator: Integrator,
        parallelism: Parallelism,
        fix_below: Option<f64>,
        heterogeneous: bool,
        steps: usize,
    ) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec3>, bool) {
        let params = SolidParams {
            integrator,
            parallelism,
            ..SolidParams::default()
        };
        let mut s = DynamicSolid::new(
            model.0.clone(),
            model.1.clone(),
            Material::default(),
            params,
        )
        .unwrap();
        if let Some(z) = fix_below {
            let low = s.control_points_where(|x| x.z < z);
            s.set_fixed(&low, true).unwrap();
        }
        if heterogeneous {
            // Damping not proportional to mass: `D v` from its own matrix.
            s.update_material(Some(&[0]), |m| m.damping *= 4.0).unwrap();
            assert!(s.damping_ratio.is_none());
        }
        s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0).unwrap();
        // Every kind of tool (they are applied block by block in the phased step).
        s.add_tool(Tool::Gravity {
            g: Vec3::new(0.0, 0.0, -0.5),
        })
        .unwrap();
        s.add_tool(Tool::Inflation { pressure: 0.2 }).unwrap();
        s.add_region_force(Vec3::new(0.5, 0.5, 1.0), 0.3, Vec3::new(0.0, 0.4, 0.0))
            .unwrap();
        let phased = s.phased_eligible();
        for _ in 0..steps {
            s.step().unwrap();
        }
        (s.p.clone(), s.v.clone(), s.d.clone(), phased)
    }

    /// The phased step follows the one-thread step: the force sums run in another order, so
    /// the trajectories agree to round-off, relative to the motion.
    fn assert_same_motion(
        model: (SolidSource, Vec<Vec3>),
        integrator: Integrator,
        fix: Option<f64>,
        heterogeneous: bool,
    ) {
        let steps = 30;
        let run = |par| trajectory(&model, integrator, par, fix, heterogeneous, steps);
        let (p1, v1, d1, seq) = run(Parallelism::Sequential);
        let (p2, v2, d2, phased) = run(Parallelism::Rayon);
        assert!(!seq);
        assert_eq!(phased, team_threads() > 1, "phased eligibility");
        let motion = p1
            .iter()
            .zip(&model.1)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        let speed = v1.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(motion > 1e-4, "the rope moves the model ({motion})");
        for (a, b) in p1.iter().zip(&p2).chain(d1.iter().zip(&d2)) {
            assert!((a - b).norm() <= 1e-9 * motion, "position {a} vs {b}");
        }
        for (a, b) in v1.iter().zip(&v2) {
            assert!((a - b).norm() <= 1e-9 * speed, "velocity {a} vs {b}");
        }
        if let Some(z) = fix {
            for (a, b) in p2.iter().zip(&model.1) {
                if b.z < z {
                    assert_eq!(a, b, "a fixed control point moved");
                }
            }
        }
    }

    #[test]
    fn phased_symplectic_step_matches_the_one_thread_step() {
        assert_same_motion(cube(4, 2), Integrator::SymplecticEuler, None, false);
    }

    /// A model of the papers' tables, as (source, control points).
    fn paper(name: &str, level: usize) -> (SolidSource, Vec<Vec3>) {
        let m = crate::benchmarks::PAPER_MODELS
            .iter()
            .find(|m| m.name == name && m.level == level)
            .unwrap();
        SolidSource::subdivision(m.control(), vclay_lattice::BoundaryRule::Sharp, m.level)
    }

    #[test]
    fn phased_step_of_lattices_with_prisms_and_extraordinary_points_matches_the_one_thread_step() {
        // Hexahedra and prisms (gear), with fixed points and with damping not proportional to
        // mass; one non-convex cell of genus 3, whose subdivided lattice has points of many
        // valences (tetrahedron with holes).
        assert_same_motion(
            paper("Gear", 2),
            Integrator::SymplecticEuler,
            Some(0.1),
            false,
        );
        assert_same_motion(paper("Gear", 2), Integrator::Explicit, None, true);
        assert_same_motion(
            paper("Tetrahedron w/ holes", 3),
            Integrator::SymplecticEuler,
            Some(0.2),
            false,
        );
    }

    #[test]
    fn phased_step_follows_the_one_thread_step_through_run_time_edits() {
        // Every edit that rebuilds or changes what the phased program reads (extrusion, fixing
        // and freeing, plastic reset, material change, cell deletion, a moving cursor): the
        // phased run must pick each one up exactly as the one-thread run does.
        let run = |parallelism| {
            let (source, p) = cube(4, 2);
            let params = SolidParams {
                parallelism,
                ..SolidParams::default()
            };
            let mut s = DynamicSolid::new(source, p, Material::default(), params).unwrap();
            let rope = s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0).unwrap();
            let mut phased = Vec::new();
            let mut steps = |s: &mut DynamicSolid| {
                phased.push(s.phased_eligible());
                s.run(8).unwrap();
            };
            steps(&mut s);
            let face = s.boundary_face_near(&Vec3::new(0.5, 0.5, 1.0)).unwrap();
            s.extrude(face, 1.0).unwrap();
            steps(&mut s);
            let low = s.control_points_where(|x| x.z < 0.3);
            s.set_fixed(&low, true).unwrap();
            steps(&mut s);
            s.move_cursor(rope, Vec3::new(1.5, 1.0, 1.6)).unwrap();
            steps(&mut s);
            s.set_fixed(&low, false).unwrap();
            steps(&mut s);
            s.plastic_reset();
            steps(&mut s);
            s.update_material(Some(&[0, 1]), |m| m.damping *= 3.0)
                .unwrap();
            steps(&mut s);
            let c = s.cell_near(&Vec3::new(0.2, 0.2, 0.2)).unwrap();
            s.delete_cell(c).unwrap();
            steps(&mut s);
            (s.p.clone(), s.v.clone(), s.d.clone(), phased)
        };
        let (p1, v1, d1, seq) = run(Parallelism::Sequential);
        let (p2, v2, d2, phased) = run(Parallelism::Rayon);
        assert!(seq.iter().all(|&x| !x));
        if team_threads() > 1 {
            assert!(
                phased.iter().all(|&x| x),
                "phased after every edit: {phased:?}"
            );
        }
        let scale = 1.0 + p1.iter().map(|x| x.norm()).fold(0.0, f64::max);
        let speed = v1.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(speed > 1e-3, "the model moves ({speed})");
        for (a, b) in p1.iter().zip(&p2).chain(d1.iter().zip(&d2)) {
            assert!((a - b).norm() <= 1e-9 * scale, "position {a} vs {b}");
        }
        for (a, b) in v1.iter().zip(&v2) {
            assert!((a - b).norm() <= 1e-9 * speed, "velocity {a} vs {b}");
        }
    }

    /// A box of `n` control points per axis at `level`, as (source, control points).
    fn boxed(n: [usize; 3], level: usize) -> (SolidSource, Vec<Vec3>) {
        let control = vclay_lattice::primitives::box_lattice(n, Vec3::zeros(), Vec3::repeat(1.0));
        SolidSource::subdivision(control, vclay_lattice::BoundaryRule::Sharp, level)
    }

    #[test]
    fn phased_tensor_levels_give_the_maps_products_bit_for_bit() {
        // Boxes in grid order: every level after the first is a tensor product, run as phases
        // over z-planes (odd and even plane counts, one and two tensor levels); the phased
        // `A p` and `A^T f` are the map's own products (`SubdivisionMap::apply_into`,
        // `apply_transpose_into`: `TensorOperator`'s) bit for bit.
        for (n, level) in [
            ([3, 4, 5], 2),
            ([4, 4, 4], 2),
            ([2, 3, 4], 3),
            ([4, 4, 4], 3),
        ] {
            let (source, p) = boxed(n, level);
            let params = SolidParams {
                parallelism: Parallelism::Rayon,
                ..SolidParams::default()
            };
            let mut s = DynamicSolid::new(source, p, Material::default(), params).unwrap();
            assert_eq!(s.data_numbering(), crate::DataNumbering::Grid, "{n:?}");
            let tensor: Vec<bool> = (0..level).map(|j| s.disc.map.tensor(j).is_some()).collect();
            assert_eq!(
                tensor,
                (0..level).map(|j| j > 0).collect::<Vec<_>>(),
                "{n:?}"
            );
            s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0).unwrap();
            s.add_tool(Tool::Gravity {
                g: Vec3::new(0.0, 0.0, -0.5),
            })
            .unwrap();
            if team_threads() > 1 {
                assert!(s.phased_eligible(), "{n:?} level {level}");
            }
            // From rest (`D v = 0`): `g = A^T f` for the forces of the step.
            s.step().unwrap();
            let g = s.disc.map.apply_transpose(&s.work.f);
            if team_threads() > 1 {
                assert!(g == s.work.phased.g, "{n:?} level {level}: A^T f");
            }
            s.run(3).unwrap();
            assert!(
                s.d == s.disc.map.apply(&s.p),
                "{n:?} level {level}: d = A p"
            );
        }
        assert_same_motion(
            boxed([3, 4, 5], 2),
            Integrator::SymplecticEuler,
            None,
            false,
        );
        assert_same_motion(boxed([4, 4, 4], 3), Integrator::SymplecticEuler, None, true);
    }

    #[test]
    fn phased_explicit_step_with_heterogeneous_damping_matches_the_one_thread_step() {
        assert_same_motion(cube(3, 2), Integrator::Explicit, None, true);
    }

    #[test]
    fn phased_step_with_fixed_points_matches_the_one_thread_step() {
        // Restricted chain: inputs and outputs are index maps.
        assert_same_motion(cube(4, 2), Integrator::SymplecticEuler, Some(0.3), false);
    }

    #[test]
    fn phased_step_of_a_one_level_map_with_a_sparse_mass_matrix() {
        // 9^3 = 729 control points: more than the dense bound, so the sparse solve runs.
        let model = bspline(9, 12);
        let s = DynamicSolid::new(
            model.0.clone(),
            model.1.clone(),
            Material::default(),
            SolidParams::default(),
        )
        .unwrap();
        assert!(matches!(s.solver.factor, MassFactor::Sparse(_)));
        assert_same_motion(model, Integrator::SymplecticEuler, Some(0.2), false);
    }

    #[test]
    fn phased_step_reports_a_non_finite_state_and_goes_back() {
        let (source, p) = cube(3, 2);
        let params = SolidParams {
            parallelism: Parallelism::Rayon,
            ..SolidParams::default()
        };
        let mut s = DynamicSolid::new(source, p, Material::default(), params).unwrap();
        s.attach_rope(Vec3::new(1.3, 1.2, 1.1), 50.0, 0.0).unwrap();
        s.run(3).unwrap();
        let good = s.good.clone();
        s.v[5].y = f64::NAN;
        let err = s.step().unwrap_err();
        assert!(err.to_string().contains("non-finite"), "{err}");
        assert_eq!((&s.p, &s.v), (&good.0, &good.1));
        assert!(s.d.iter().all(|x| x.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn phased_step_detects_divergence_and_restores_the_last_good_state() {
        let (source, p) = cube(3, 2);
        let params = SolidParams {
            dt: 0.5,
            parallelism: Parallelism::Rayon,
            ..SolidParams::default()
        };
        let mut s = DynamicSolid::new(source, p, Material::default(), params).unwrap();
        s.attach_rope(Vec3::new(3.0, 3.0, 3.0), 1e3, 0.0).unwrap();
        let mut last = s.p.clone();
        let err = loop {
            match s.step() {
                Ok(_) => last.clone_from(&s.good.0),
                Err(e) => break e,
            }
            assert!(s.steps() < 1000, "no divergence detected");
        };
        assert!(matches!(err, SolidsError::Diverged { .. }), "{err}");
        assert!(s.p.iter().all(|x| x.iter().all(|c| c.is_finite())));
        // Back at the last state that passed the check.
        assert_eq!(s.p, last);
    }
}
