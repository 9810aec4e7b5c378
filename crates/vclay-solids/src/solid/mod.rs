//! [`DynamicSolid`]: the one dynamic core of B-spline and subdivision solids.
//!
//! # What
//! The data points `d = A p` (`subdivision-solids-journal.txt` eqs 3-4) carry lumped masses `M`
//! and damping `D` and are joined by the edge and virtual springs of section 5.1. The control
//! points move by eq (10):
//!
//! `A^T M A p'' = A^T f_d - A^T D A p' - A^T f_springs(A p)` (the internal forces are `-K d`
//! of eq 6, here the non-linear Hooke forces), with `A^T M A` and `A^T D A` formed once (sparse,
//! level by level, see [`crate::map`]) and `A^T M A` factored once by sparse Cholesky (faer) and
//! reused until the model, the material or the fixed set changes. `A^T D A p'` equals
//! `A^T D d'` of eq (9) because `d' = A p'`, and costs nothing at the data level.
//!
//! Integrators ([`Integrator`]):
//! * [`Integrator::Explicit`]: section 4.4 as printed, `p(t+dt) = p + dt p'(t)`,
//!   `p'(t+dt) = p' + dt p''(t)` (forward Euler: stable only with enough damping,
//!   `dt < c / w^2` for damping rate `c` and highest frequency `w`).
//! * [`Integrator::SymplecticEuler`] (default): `p'(t+dt) = p' + dt p''(t)`, then
//!   `p(t+dt) = p + dt p'(t+dt)`; bounded energy error without damping, stable for `dt < 2 / w`.
//! * [`Integrator::ImplicitEuler`]: backward Euler linearized once per step (Baraff-Witkin):
//!   `(M + dt D + dt^2 K) dv = dt (F - D v - dt K v)` with `K = A^T H A` (`H` the clamped spring
//!   Hessian, [`crate::springs`]), solved by conjugate gradient preconditioned with the
//!   factored `A^T M A`; the implicit solver the paper names as future work (section 6).
//!
//! Threads: an explicit or symplectic step of a mid-sized model runs as one phased program on a
//! persistent thread team (`phased.rs`: springs by point blocks, the map passes and the control
//! points split by rows, spin barriers in between), which at 2,000 data points costs less than
//! one rayon fork-join per pass; see [`SolidParams::parallelism`].
//!
//! Fixed control points (section 5.2) are removed from the unknowns; data points that only fixed
//! control points define are dropped from every per-step pass, as are springs between them.
//!
//! Divergence: before each step the state is checked (finite, and total energy below
//! [`SolidParams::divergence_factor`] times the sum of the energy of stretching every spring by
//! its own rest length and the largest rope energy seen); on failure the state goes back to the last checked
//! state and [`SolidsError::Diverged`] names the step and a time step estimated to be stable
//! (from the highest frequency of `M^-1 K`, found by power iteration).
//!
//! Limitations: damping is per data point (no relative-velocity damping); inflation has no
//! stiffness term in the implicit scheme; edits apply to subdivision solids only.

use std::time::Instant;

use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{
    CellId, EdgeId, ExtrudeParams, FaceId, Lattice, SparseMatrix, SubdivisionMap, VertexId,
    delete_cell, extrude_face,
};

use crate::error::{SolidsError, invalid};
use crate::map::{
    MapWorkspace, Restricted, apply_active, apply_transpose_active, galerkin, influenced,
};
use crate::material::{Material, MaterialField};
use crate::metric::MetricEnergy;
use crate::model::{DataNumbering, Discretization, SolidSource};
use crate::springs::{ForceWorkspace, SpringSet};
use crate::tools::{Boundary, Falloff, Tool, nearest, within};

mod phased;
pub use phased::PHASED_POINTS;

/// Default [`SolidParams::dt`].
pub const DEFAULT_DT: f64 = 1e-3;
/// Default [`SolidParams::divergence_factor`].
pub const DEFAULT_DIVERGENCE_FACTOR: f64 = 1000.0;
/// Default [`SolidParams::cg_tolerance`].
pub const DEFAULT_CG_TOLERANCE: f64 = 1e-8;
/// Default [`SolidParams::cg_max_iterations`].
pub const DEFAULT_CG_MAX_ITERATIONS: usize = 200;

/// Time integration scheme (see the [module docs](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// Forward Euler, the explicit scheme of journal section 4.4.
    Explicit,
    /// Semi-implicit (symplectic) Euler.
    #[default]
    SymplecticEuler,
    /// Linearized backward Euler solved by preconditioned conjugate gradient.
    ImplicitEuler,
}

/// Simulation parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidParams {
    /// Integrator. Default: [`Integrator::SymplecticEuler`].
    pub integrator: Integrator,
    /// Time step (s, > 0). Default: [`DEFAULT_DT`].
    pub dt: f64,
    /// Divergence bound as a multiple of the spring energy scale (> 0). Default:
    /// [`DEFAULT_DIVERGENCE_FACTOR`].
    pub divergence_factor: f64,
    /// Relative residual at which conjugate gradient stops. Default: [`DEFAULT_CG_TOLERANCE`].
    pub cg_tolerance: f64,
    /// Iteration cap of conjugate gradient. Default: [`DEFAULT_CG_MAX_ITERATIONS`].
    pub cg_max_iterations: usize,
    /// Thread use of the per-step passes. Default: [`Parallelism::Auto`]: explicit and
    /// symplectic steps of models with at least [`PHASED_POINTS`] active data points (and a
    /// chain of at most [`vclay_lattice::SubdivisionMap::GATHER_NNZ`] non-zeros) run as one
    /// phased program on [`vclay_core::team`]'s thread team; larger models split each pass on
    /// rayon's pool; smaller ones run on the calling thread. `Rayon` takes the team from any
    /// size, `Sequential` never uses another thread.
    pub parallelism: Parallelism,
}

impl Default for SolidParams {
    fn default() -> Self {
        Self {
            integrator: Integrator::default(),
            dt: DEFAULT_DT,
            divergence_factor: DEFAULT_DIVERGENCE_FACTOR,
            cg_tolerance: DEFAULT_CG_TOLERANCE,
            cg_max_iterations: DEFAULT_CG_MAX_ITERATIONS,
            parallelism: Parallelism::Auto,
        }
    }
}

impl SolidParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), SolidsError> {
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(invalid("dt", self.dt, "positive and finite"));
        }
        if !(self.divergence_factor.is_finite() && self.divergence_factor > 0.0) {
            return Err(invalid(
                "divergence_factor",
                self.divergence_factor,
                "positive and finite",
            ));
        }
        if !(self.cg_tolerance.is_finite() && self.cg_tolerance > 0.0) {
            return Err(invalid(
                "cg_tolerance",
                self.cg_tolerance,
                "positive and finite",
            ));
        }
        if self.cg_max_iterations == 0 {
            return Err(invalid("cg_max_iterations", 0, "at least 1"));
        }
        Ok(())
    }
}

/// Handle of an added tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ToolId(pub usize);

/// Energies of a state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// `1/2 p'^T A^T M A p'`.
    pub kinetic: f64,
    /// Spring energy (edge and virtual springs).
    pub internal: f64,
    /// Energy stored in rope springs.
    pub tools: f64,
}

impl Energy {
    /// Kinetic plus internal (the conserved quantity without damping and tools).
    pub fn total(&self) -> f64 {
        self.kinetic + self.internal
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Energies at the start of the step.
    pub energy: Energy,
    /// Conjugate gradient iterations (implicit integrator; 0 otherwise).
    pub cg_iterations: usize,
    /// Wall time of the step in seconds.
    pub seconds: f64,
}

/// Sizes of the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SolidStats {
    /// Control points (all / free).
    pub control_points: usize,
    /// Free control points.
    pub free_control_points: usize,
    /// Data points.
    pub data_points: usize,
    /// Data points processed per step (influenced by a free control point).
    pub active_data_points: usize,
    /// Data cells.
    pub data_cells: usize,
    /// Edge springs.
    pub edge_springs: usize,
    /// Virtual springs.
    pub virtual_springs: usize,
    /// Springs processed per step.
    pub active_springs: usize,
}

/// The factored reduced mass matrix of the free control points.
#[derive(Clone)]
struct MassSolver {
    factor: MassFactor,
    /// Right-hand sides of the sparse solve.
    rhs: faer::Mat<f64>,
    /// Right-hand sides of the dense product, the free points' `b` (`m` points).
    columns: Vec<Vec3>,
}

/// The factorization of the free block of `A^T M A`.
#[derive(Clone)]
enum MassFactor {
    /// No free control points.
    Empty,
    /// Sparse Cholesky.
    Sparse(faer::sparse::linalg::solvers::Llt<usize, f64>),
    /// The explicit inverse (row-major, from a dense Cholesky factorization), for small,
    /// nearly dense matrices (a coarse control net couples almost every pair of control
    /// points): a product with it is faster than two triangular solves, vectorizes, and splits
    /// by rows between threads. The mass matrix is symmetric positive definite and well
    /// conditioned (lumped positive masses, a partition-of-unity map), so the inverse loses no
    /// accuracy that matters here (checked against the sparse solve in the tests).
    Dense(Vec<f64>),
}

/// `out(k, x_k)` for the rows `rows` of `x = inv b`, `inv` row-major `m x m`, `b` given as
/// points (`b.len() == m`): per coordinate four partial sums over the row's chunks of four,
/// then the tail, the three coordinates in one pass over the row (twelve independent chains
/// the compiler vectorizes). The one-thread step ([`DynamicSolid::solve_mass`]) and the phased
/// step's rows use it alike, so both give the same bits.
#[inline]
fn inverse_point_rows(
    inv: &[f64],
    b: &[Vec3],
    rows: std::ops::Range<usize>,
    mut out: impl FnMut(usize, Vec3),
) {
    let m = b.len();
    let (bch, bt) = b.as_chunks::<4>();
    for k in rows {
        let row = &inv[k * m..(k + 1) * m];
        let (rc, rt) = row.as_chunks::<4>();
        let mut s = [[0.0; 4]; 3];
        for (r4, b4) in rc.iter().zip(bch) {
            for (c, sc) in s.iter_mut().enumerate() {
                for l in 0..4 {
                    sc[l] += r4[l] * b4[l][c];
                }
            }
        }
        let acc: [f64; 3] = std::array::from_fn(|c| {
            let sc = &s[c];
            (sc[0] + sc[1])
                + (sc[2] + sc[3])
                + rt.iter().zip(bt).map(|(r, x)| r * x[c]).sum::<f64>()
        });
        out(k, Vec3::new(acc[0], acc[1], acc[2]));
    }
}

/// Free control points up to which a mass matrix at least a quarter full is factored densely.
const DENSE_MASS: usize = 512;

impl MassSolver {
    /// Factors the block of `mp` (`n x n`) on the `free` control points: densely when it is
    /// small and at least a quarter full (and `allow_dense`), else by sparse Cholesky.
    fn new(
        mp: &SparseMatrix,
        free: &[u32],
        n: usize,
        allow_dense: bool,
    ) -> Result<Self, SolidsError> {
        let m = free.len();
        let mut pos = vec![usize::MAX; n];
        for (k, &i) in free.iter().enumerate() {
            pos[i as usize] = k;
        }
        let mut trips = Vec::new();
        for &i in free {
            let (cols, vals) = mp.row(i as usize);
            let ri = pos[i as usize];
            for (&c, &v) in cols.iter().zip(vals) {
                let rc = pos[c as usize];
                if rc != usize::MAX && rc <= ri {
                    trips.push(faer::sparse::Triplet::new(ri, rc, v));
                }
            }
        }
        let factor = if m == 0 {
            MassFactor::Empty
        } else if allow_dense && m <= DENSE_MASS && 8 * trips.len() >= m * m {
            let mut a = faer::Mat::<f64>::zeros(m, m);
            for t in &trips {
                a[(t.row, t.col)] = t.val;
            }
            let llt = a
                .llt(faer::Side::Lower)
                .map_err(|e| SolidsError::MassMatrix(format!("{e:?}")))?;
            use faer::linalg::solvers::Solve;
            let inv = llt.solve(faer::Mat::<f64>::identity(m, m));
            let mut rows = vec![0.0; m * m];
            for k in 0..m {
                for j in 0..m {
                    // Symmetrized (the solve's round-off differs between the two triangles).
                    rows[k * m + j] = 0.5 * (inv[(k, j)] + inv[(j, k)]);
                }
            }
            MassFactor::Dense(rows)
        } else {
            let mat = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trips)
                .map_err(|e| SolidsError::MassMatrix(format!("{e:?}")))?;
            let llt = mat
                .sp_cholesky(faer::Side::Lower)
                .map_err(|e| SolidsError::MassMatrix(format!("{e:?}")))?;
            MassFactor::Sparse(llt)
        };
        Ok(MassSolver {
            factor,
            rhs: faer::Mat::zeros(m, 3),
            columns: vec![Vec3::zeros(); m],
        })
    }
}

impl std::fmt::Debug for MassSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MassSolver {{ n: {} }}", self.rhs.nrows())
    }
}

/// Per-step buffers.
#[derive(Clone, Debug, Default)]
struct Work {
    f: Vec<Vec3>,
    g: Vec<Vec3>,
    acc: Vec<Vec3>,
    tmp: Vec<Vec3>,
    dy: Vec<Vec3>,
    ky: Vec<Vec3>,
    force: ForceWorkspace,
    map: MapWorkspace,
    cg: [Vec<Vec3>; 4],
    phased: phased::PhasedWork,
}

/// A dynamic B-spline or subdivision solid (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct DynamicSolid {
    source: SolidSource,
    material: MaterialField,
    params: SolidParams,
    p: Vec<Vec3>,
    v: Vec<Vec3>,
    p_rest: Vec<Vec3>,
    fixed: Vec<bool>,
    good: (Vec<Vec3>, Vec<Vec3>),
    disc: Discretization,
    d: Vec<Vec3>,
    d_rest: Vec<Vec3>,
    /// The data points masses, damping and spring stiffnesses were last built from (the rest
    /// shape before any plastic reset since; a reset renews rest lengths only).
    d_phys: Vec<Vec3>,
    mass: Vec<f64>,
    damp: Vec<f64>,
    springs: SpringSet,
    active_springs: Option<SpringSet>,
    restricted: Option<Restricted>,
    active_count: usize,
    energy_scale: f64,
    tool_energy_seen: f64,
    mp: SparseMatrix,
    dp: SparseMatrix,
    /// `Some(c)` when `dp = c mp` (damping proportional to mass): `D v` is then `c (M v)`, one
    /// product per step instead of two.
    damping_ratio: Option<f64>,
    free: Vec<u32>,
    /// For each free control point, its row of the first level operator of the active map
    /// (its position among the restricted inputs; `u32::MAX` if it reaches no data point).
    free_rows: Vec<u32>,
    solver: MassSolver,
    boundary: Boundary,
    metric: Option<MetricEnergy>,
    tools: Vec<Option<Tool>>,
    time: f64,
    steps: u64,
    work: Work,
}

impl DynamicSolid {
    /// A solid at rest in configuration `p` (control points), with a uniform material.
    pub fn new(
        source: SolidSource,
        p: Vec<Vec3>,
        material: Material,
        params: SolidParams,
    ) -> Result<Self, SolidsError> {
        material.validate()?;
        let cells = source.control_cells();
        Self::with_material(source, p, MaterialField::uniform(material, cells), params)
    }

    /// A solid at rest in configuration `p` with a material per control cell.
    pub fn with_material(
        source: SolidSource,
        p: Vec<Vec3>,
        material: MaterialField,
        params: SolidParams,
    ) -> Result<Self, SolidsError> {
        Self::with_discretization(source, p, material, params, None)
    }

    /// [`DynamicSolid::with_material`] with `disc`, the discretization of `source` at `p`
    /// (`None`: [`SolidSource::discretize`]).
    fn with_discretization(
        source: SolidSource,
        p: Vec<Vec3>,
        material: MaterialField,
        params: SolidParams,
        disc: Option<Discretization>,
    ) -> Result<Self, SolidsError> {
        params.validate()?;
        for m in material.cells() {
            m.validate()?;
        }
        if material.len() != source.control_cells() {
            return Err(invalid(
                "material",
                material.len(),
                &format!("{} cell materials", source.control_cells()),
            ));
        }
        let disc = match disc {
            Some(d) => d,
            None => source.discretize(&p)?,
        };
        let n = p.len();
        let d = disc.data.points().to_vec();
        let mut s = Self {
            source,
            material,
            params,
            v: vec![Vec3::zeros(); n],
            p_rest: p.clone(),
            fixed: vec![false; n],
            good: (p.clone(), vec![Vec3::zeros(); n]),
            p,
            d_rest: d.clone(),
            d_phys: Vec::new(),
            d,
            disc,
            mass: Vec::new(),
            damp: Vec::new(),
            springs: SpringSet::default(),
            active_springs: None,
            restricted: None,
            active_count: 0,
            energy_scale: 0.0,
            tool_energy_seen: 0.0,
            mp: SparseMatrix::identity(0),
            dp: SparseMatrix::identity(0),
            damping_ratio: None,
            free: Vec::new(),
            free_rows: Vec::new(),
            solver: MassSolver {
                factor: MassFactor::Empty,
                rhs: faer::Mat::zeros(0, 3),
                columns: Vec::new(),
            },
            boundary: Boundary::default(),
            metric: None,
            tools: Vec::new(),
            time: 0.0,
            steps: 0,
            work: Work::default(),
        };
        s.rebuild_physics()?;
        Ok(s)
    }

    // ------------------------------------------------------------------------------------
    // Building
    // ------------------------------------------------------------------------------------

    /// Masses, damping, springs, reduced matrices and boundary from the rest configuration.
    fn rebuild_physics(&mut self) -> Result<(), SolidsError> {
        self.d_phys.clone_from(&self.d_rest);
        let data = &mut self.disc.data;
        data.points_mut().copy_from_slice(&self.d_rest);
        let nd = data.num_points();
        let parent = &self.disc.cell_parent;
        let mat = |c: usize| self.material.cell(parent[c] as usize);
        // Lumped masses and damping (module docs of crate::material).
        let mut mass = vec![0.0; nd];
        let mut damp = vec![0.0; nd];
        for c in 0..data.num_cells() {
            let id = CellId::new(c);
            let vol = data.cell_signed_volume(id).abs();
            let vs = data.cell_vertices(id);
            let m = mat(c);
            let share = vol / vs.len() as f64;
            for v in vs {
                mass[v.index()] += m.density * share;
                damp[v.index()] += m.damping * share;
            }
        }
        if let Some(i) = mass.iter().position(|&m| m <= 0.0 || !m.is_finite()) {
            return Err(SolidsError::MassMatrix(format!(
                "data point {i} has mass {} (degenerate cells around it)",
                mass[i]
            )));
        }
        // Springs.
        let pts = data.points();
        let mut sp = SpringSet {
            face_offsets: vec![0],
            ..Default::default()
        };
        for e in 0..data.num_edges() {
            let [a, b] = data.edge_vertices(EdgeId::new(e));
            let x = pts[b.index()] - pts[a.index()];
            let l0 = x.norm();
            let cells = data.edge_cells(EdgeId::new(e));
            let mut k = 0.0;
            for c in cells {
                let m = mat(c.index());
                let u = if l0 > 0.0 { x / l0 } else { Vec3::zeros() };
                k += m.edge_stiffness * m.direction_factor([u.x, u.y, u.z]);
            }
            k /= cells.len().max(1) as f64;
            sp.edges.push([a.0, b.0]);
            sp.edge_rest.push(l0);
            sp.edge_k.push(k * l0);
        }
        let mut boundary = Boundary {
            offsets: vec![0],
            verts: Vec::new(),
        };
        for f in 0..data.num_faces() {
            let fid = FaceId::new(f);
            let verts = data.face_vertices(fid);
            let cells: Vec<CellId> = data.face_cells(fid).iter().flatten().copied().collect();
            let k = verts.len();
            for j in 0..k {
                let m = pts[verts[j].index()];
                let v =
                    (pts[verts[(j + k - 1) % k].index()] + pts[verts[(j + 1) % k].index()]) * 0.5;
                let x = m - v;
                let l0 = x.norm();
                let u = if l0 > 0.0 { x / l0 } else { Vec3::zeros() };
                let mut kk = 0.0;
                for c in &cells {
                    let mm = mat(c.index());
                    kk += mm.virtual_stiffness * mm.direction_factor([u.x, u.y, u.z]);
                }
                kk /= cells.len().max(1) as f64;
                sp.face_verts.push(verts[j].0);
                sp.corner_rest.push(l0);
                sp.corner_k.push(kk * l0);
            }
            sp.face_offsets.push(sp.face_verts.len() as u32);
            if data.is_boundary_face(fid) {
                let outward = data.face_cells(fid)[0].is_some();
                if outward {
                    boundary.verts.extend(verts.iter().map(|v| v.0));
                } else {
                    boundary.verts.extend(verts.iter().rev().map(|v| v.0));
                }
                boundary.offsets.push(boundary.verts.len() as u32);
            }
        }
        sp.organize(nd, force_blocks());
        if self.metric.is_none() {
            self.energy_scale = spring_energy_scale(&sp);
        }
        data.points_mut().copy_from_slice(&self.d);
        self.mp = galerkin(&self.disc.map, &mass);
        // A^T D A: a multiple of A^T M A when damping is proportional to mass.
        let ratio = damp[0] / mass[0];
        let proportional = damp
            .iter()
            .zip(&mass)
            .all(|(g, m)| (g - ratio * m).abs() <= 1e-12 * g.abs().max(ratio * m));
        self.damping_ratio = proportional.then_some(ratio);
        self.dp = if proportional {
            let v: Vec<f64> = self.mp.values().iter().map(|x| x * ratio).collect();
            SparseMatrix::from_csr(
                self.mp.nrows(),
                self.mp.ncols(),
                self.mp.row_ptr().to_vec(),
                self.mp.col_indices().to_vec(),
                v,
            )
        } else {
            galerkin(&self.disc.map, &damp)
        };
        compress_large(&mut self.disc.map);
        self.mass = mass;
        self.damp = damp;
        self.springs = sp;
        self.boundary = boundary;
        self.rebuild_active()
    }

    /// The fixed-point partition (journal section 5.2) and the factorization of the free part
    /// of `A^T M A`.
    fn rebuild_active(&mut self) -> Result<(), SolidsError> {
        let n = self.p.len();
        let nd = self.d.len();
        let free_mask: Vec<bool> = self.fixed.iter().map(|f| !f).collect();
        self.free = (0..n as u32).filter(|&i| !self.fixed[i as usize]).collect();
        if self.fixed.iter().any(|&f| f) {
            let active = influenced(&self.disc.map, &free_mask);
            let rows: Vec<u32> = (0..nd as u32).filter(|&i| active[i as usize]).collect();
            self.active_count = rows.len();
            let mut act = self.springs.filter(&active);
            act.organize(nd, force_blocks());
            self.active_springs = Some(act);
            let mut r = Restricted::new(&self.disc.map, rows);
            compress_large(r.map_mut());
            self.free_rows = self
                .free
                .iter()
                .map(|i| r.inputs.binary_search(i).map_or(u32::MAX, |k| k as u32))
                .collect();
            self.restricted = Some(r);
        } else {
            self.free_rows.clone_from(&self.free);
            self.active_count = nd;
            self.active_springs = None;
            self.restricted = None;
        }
        // Factor the free block of A^T M A.
        self.solver = MassSolver::new(&self.mp, &self.free, n, true)?;
        let w = &mut self.work;
        w.f = vec![Vec3::zeros(); nd];
        w.dy = vec![Vec3::zeros(); nd];
        w.ky = vec![Vec3::zeros(); nd];
        for b in [&mut w.g, &mut w.acc, &mut w.tmp] {
            *b = vec![Vec3::zeros(); n];
        }
        for b in &mut w.cg {
            *b = vec![Vec3::zeros(); n];
        }
        Ok(())
    }

    // ------------------------------------------------------------------------------------
    // Accessors
    // ------------------------------------------------------------------------------------

    /// The source (kind and parameters) of the model.
    pub fn source(&self) -> &SolidSource {
        &self.source
    }
    /// Control points `p`.
    pub fn control_points(&self) -> &[Vec3] {
        &self.p
    }
    /// Control point velocities `p'`.
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }
    /// Rest configuration of the control points.
    pub fn rest_control_points(&self) -> &[Vec3] {
        &self.p_rest
    }
    /// Data points `d = A p` (up to date after every step), numbered as the points of
    /// [`DynamicSolid::data_lattice`] (see [`DynamicSolid::data_order`]).
    pub fn data_points(&self) -> &[Vec3] {
        &self.d
    }
    /// Data point `i` is point `data_order()[i]` of the lattice the source defines: for a
    /// subdivision solid the finest level of [`vclay_lattice::SubdivisionSolid`] (the data
    /// points are renumbered by [`vclay_lattice::Lattice::locality_order`] for cache-friendly
    /// passes, or in grid order, [`DynamicSolid::data_numbering`],
    /// [`Discretization::order`](crate::Discretization::order)); the identity for B-spline
    /// solids.
    pub fn data_order(&self) -> &[u32] {
        &self.disc.order
    }
    /// How the data points are numbered ([`DataNumbering`]; a session file records it).
    pub fn data_numbering(&self) -> DataNumbering {
        self.disc.numbering
    }
    /// Lumped data point masses.
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }
    /// The data points of the control-point configuration `x` (`A x` over all data points,
    /// in the data lattice's point order): `x` = [`DynamicSolid::rest_control_points`] gives
    /// the rest positions (journal eq 4 / eq 3), `x` = [`DynamicSolid::velocities`] the data
    /// points' velocities `A p'` (section 4.4).
    pub fn map_to_data(&self, x: &[Vec3]) -> Result<Vec<Vec3>, SolidsError> {
        if x.len() != self.p.len() {
            return Err(invalid(
                "x",
                x.len(),
                &format!("{} values, one per control point", self.p.len()),
            ));
        }
        let mut out = vec![Vec3::zeros(); self.d.len()];
        let mut ws = vclay_lattice::ChainWorkspace::default();
        self.disc
            .map
            .apply_into(x, &mut out, &mut ws, self.params.parallelism);
        Ok(out)
    }

    /// The data lattice with its points at the current `d`.
    pub fn data_lattice(&mut self) -> &Lattice {
        self.disc.data.points_mut().copy_from_slice(&self.d);
        &self.disc.data
    }
    /// The control lattice at the current control points (subdivision solids), `None` for
    /// B-spline solids.
    pub fn control_lattice(&self) -> Option<Lattice> {
        match &self.source {
            SolidSource::Subdivision { control, .. } => {
                let mut l = control.clone();
                l.set_points(self.p.clone());
                Some(l)
            }
            SolidSource::BSpline { .. } => None,
        }
    }
    /// Whether control point `i` is fixed.
    pub fn is_fixed(&self, i: usize) -> bool {
        self.fixed[i]
    }
    /// The reduced mass matrix `A^T M A` (all control points).
    pub fn reduced_mass(&self) -> &SparseMatrix {
        &self.mp
    }
    /// The spring network.
    pub fn springs(&self) -> &SpringSet {
        &self.springs
    }
    /// Simulated time.
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// Parameters.
    pub fn params(&self) -> &SolidParams {
        &self.params
    }
    /// The material field.
    pub fn material(&self) -> &MaterialField {
        &self.material
    }
    /// Sizes.
    pub fn stats(&self) -> SolidStats {
        let act = self.active_springs.as_ref().unwrap_or(&self.springs);
        SolidStats {
            control_points: self.p.len(),
            free_control_points: self.free.len(),
            data_points: self.d.len(),
            active_data_points: self.active_count,
            data_cells: self.disc.data.num_cells(),
            edge_springs: self.springs.edges.len(),
            virtual_springs: self.springs.face_verts.len(),
            active_springs: act.len(),
        }
    }

    /// Bytes held per data point by the per-step structures (level operators, their stored
    /// transposes and compact forms, [`SubdivisionMap::bytes`]; springs and their parameter
    /// index, [`SpringSet::bytes`]; data-point arrays; data lattice topology excluded).
    pub fn bytes_per_data_point(&self) -> f64 {
        let ops = self.disc.map.bytes();
        let springs = self.springs.bytes();
        let arrays = self.d.len() * (4 * 24 + 2 * 8);
        (ops + springs + arrays) as f64 / self.d.len() as f64
    }

    /// Replaces the parameters (validated).
    pub fn set_params(&mut self, params: SolidParams) -> Result<(), SolidsError> {
        params.validate()?;
        self.params = params;
        Ok(())
    }

    // ------------------------------------------------------------------------------------
    // Forces and energy
    // ------------------------------------------------------------------------------------

    /// Internal (spring) forces on the data points at the current state (for tests and tools).
    pub fn internal_forces(&self) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); self.d.len()];
        self.springs.add_forces(
            &self.d,
            &mut f,
            &mut ForceWorkspace::default(),
            Parallelism::Auto,
        );
        f
    }

    /// Energies of the current state.
    pub fn energy(&self) -> Energy {
        let mut mv = vec![Vec3::zeros(); self.p.len()];
        self.mp
            .apply_into(&self.v, &mut mv, Parallelism::Sequential);
        let kinetic = 0.5 * self.v.iter().zip(&mv).map(|(a, b)| a.dot(b)).sum::<f64>();
        let mut f = vec![Vec3::zeros(); self.d.len()];
        let tools = self
            .tools
            .iter()
            .flatten()
            .map(|t| t.add_forces(&self.d, &self.mass, &self.boundary, &mut f))
            .sum();
        let internal = match &self.metric {
            Some(m) => m.add_forces(&self.p, &mut vec![Vec3::zeros(); self.p.len()]),
            None => self.springs.energy(&self.d),
        };
        Energy {
            kinetic,
            internal,
            tools,
        }
    }

    /// Generalized forces `g = A^T f_d - A^T D A p'` at the current state (fixed entries 0);
    /// returns the energies.
    fn generalized_forces(&mut self) -> Energy {
        let par = self.params.parallelism;
        let w = &mut self.work;
        let springs = self.active_springs.as_ref().unwrap_or(&self.springs);
        let mut internal = if self.metric.is_some() {
            w.f.iter_mut().for_each(|x| *x = Vec3::zeros());
            0.0
        } else {
            // Zeroes `f` inside the spring pass (block by block when parallel).
            springs.set_forces(&self.d, &mut w.f, &mut w.force, par)
        };
        let mut tools = 0.0;
        for t in self.tools.iter().flatten() {
            tools += t.add_forces(&self.d, &self.mass, &self.boundary, &mut w.f);
        }
        apply_transpose_active(
            &self.disc.map,
            self.restricted.as_ref(),
            &w.f,
            &mut w.g,
            &mut w.map,
            par,
        );
        if let Some(m) = &self.metric {
            internal = m.add_forces(&self.p, &mut w.g);
        }
        self.mp
            .apply_into(&self.v, &mut w.acc, Parallelism::Sequential);
        match self.damping_ratio {
            Some(c) => {
                for (t, a) in w.tmp.iter_mut().zip(&w.acc) {
                    *t = a * c;
                }
            }
            None => self
                .dp
                .apply_into(&self.v, &mut w.tmp, Parallelism::Sequential),
        }
        let mut kinetic = 0.0;
        for i in 0..self.p.len() {
            kinetic += 0.5 * self.v[i].dot(&w.acc[i]);
            if self.fixed[i] {
                w.g[i] = Vec3::zeros();
            } else {
                w.g[i] -= w.tmp[i];
            }
        }
        Energy {
            kinetic,
            internal,
            tools,
        }
    }

    /// `x = (A^T M A)^-1 b` on the free control points (fixed entries 0).
    fn solve_mass(solver: &mut MassSolver, free: &[u32], b: &[Vec3], x: &mut [Vec3]) {
        use faer::linalg::solvers::Solve;
        x.iter_mut().for_each(|v| *v = Vec3::zeros());
        let MassSolver {
            factor,
            rhs,
            columns,
        } = solver;
        match factor {
            MassFactor::Empty => {}
            MassFactor::Dense(inv) => {
                for (c, &i) in columns.iter_mut().zip(free) {
                    *c = b[i as usize];
                }
                inverse_point_rows(inv, columns, 0..free.len(), |k, v| x[free[k] as usize] = v);
            }
            MassFactor::Sparse(s) => {
                for (k, &i) in free.iter().enumerate() {
                    for c in 0..3 {
                        rhs[(k, c)] = b[i as usize][c];
                    }
                }
                s.solve_in_place(rhs.as_mut());
                for (k, &i) in free.iter().enumerate() {
                    x[i as usize] = Vec3::new(rhs[(k, 0)], rhs[(k, 1)], rhs[(k, 2)]);
                }
            }
        }
    }

    /// Updates the data points from the control points.
    fn update_data(&mut self) {
        apply_active(
            &self.disc.map,
            self.restricted.as_ref(),
            &self.p,
            &mut self.d,
            &mut self.work.map,
            self.params.parallelism,
        );
    }

    /// `out = K x` on the control points: `A^T (H (A x))` plus the tools' stiffness, fixed
    /// entries 0.
    fn stiffness_product(&mut self, x: &[Vec3], out: &mut [Vec3]) {
        let par = self.params.parallelism;
        let w = &mut self.work;
        apply_active(
            &self.disc.map,
            self.restricted.as_ref(),
            x,
            &mut w.dy,
            &mut w.map,
            par,
        );
        w.ky.iter_mut().for_each(|v| *v = Vec3::zeros());
        let springs = self.active_springs.as_ref().unwrap_or(&self.springs);
        if self.metric.is_none() {
            springs.add_stiffness_product(&self.d, &w.dy, &mut w.ky);
        }
        for t in self.tools.iter().flatten() {
            t.add_stiffness_product(&self.d, &w.dy, &mut w.ky);
        }
        apply_transpose_active(
            &self.disc.map,
            self.restricted.as_ref(),
            &w.ky,
            out,
            &mut w.map,
            par,
        );
        if let Some(m) = &self.metric {
            // K x = -(g(p + h x) - g(p)) / h, a forward difference of the metric forces.
            let xmax = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
            if xmax > 0.0 {
                let size = self.model_size();
                let h = 1e-7 * size / xmax;
                let ph: Vec<Vec3> = self.p.iter().zip(x).map(|(p, x)| p + x * h).collect();
                let mut g0 = vec![Vec3::zeros(); self.p.len()];
                let mut g1 = vec![Vec3::zeros(); self.p.len()];
                m.add_forces(&self.p, &mut g0);
                m.add_forces(&ph, &mut g1);
                for i in 0..out.len() {
                    out[i] -= (g1[i] - g0[i]) / h;
                }
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            if self.fixed[i] {
                *o = Vec3::zeros();
            }
        }
    }

    /// Diagonal of the rest control points' bounding box (the length scale of tolerances).
    fn model_size(&self) -> f64 {
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        for p in &self.p_rest {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (hi - lo).norm().max(f64::MIN_POSITIVE)
    }

    /// Selects the internal energy of a B-spline solid: `Some(c)` uses the metric-tensor
    /// energy `E = integral c sum_ij (g_ij - g0_ij)^2` by Gauss quadrature ([`crate::metric`])
    /// with the current rest shape, instead of the springs; `None` goes back to the springs.
    /// Errors for subdivision solids and for a negative or non-finite `c`.
    pub fn use_metric_energy(&mut self, stiffness: Option<f64>) -> Result<(), SolidsError> {
        let Some(c) = stiffness else {
            self.metric = None;
            self.energy_scale = spring_energy_scale(&self.springs);
            return Ok(());
        };
        if !(c.is_finite() && c >= 0.0) {
            return Err(invalid("metric_stiffness", c, "non-negative and finite"));
        }
        let SolidSource::BSpline { knots, .. } = &self.source else {
            return Err(invalid(
                "energy",
                "metric-tensor",
                "a bspline-solid model (subdivision solids use springs)",
            ));
        };
        let m = MetricEnergy::new(knots, &self.p_rest, c);
        // Energy scale: every metric entry doubled.
        let mut g = vec![Vec3::zeros(); self.p.len()];
        let doubled: Vec<Vec3> = self.p_rest.iter().map(|p| p * 2.0_f64.sqrt()).collect();
        self.energy_scale = m.add_forces(&doubled, &mut g).max(f64::MIN_POSITIVE);
        self.metric = Some(m);
        Ok(())
    }

    /// Whether the metric-tensor energy replaces the springs.
    pub fn uses_metric_energy(&self) -> bool {
        self.metric.is_some()
    }

    // ------------------------------------------------------------------------------------
    // Stepping
    // ------------------------------------------------------------------------------------

    /// Advances one time step with the configured integrator.
    pub fn step(&mut self) -> Result<StepReport, SolidsError> {
        let t0 = Instant::now();
        let dt = self.params.dt;
        if self.phased_eligible() {
            let (energy, finite) = self.phased_step();
            self.tool_energy_seen = self.tool_energy_seen.max(energy.tools.abs());
            if let Err(reason) = self.verdict(&energy, finite) {
                return Err(self.diverged(reason));
            }
            self.time += dt;
            self.steps += 1;
            return Ok(StepReport {
                energy,
                cg_iterations: 0,
                seconds: t0.elapsed().as_secs_f64(),
            });
        }
        let energy = self.generalized_forces();
        self.tool_energy_seen = self.tool_energy_seen.max(energy.tools.abs());
        let finite = self
            .p
            .iter()
            .chain(&self.v)
            .all(|x| x.iter().all(|c| c.is_finite()));
        if let Err(reason) = self.verdict(&energy, finite) {
            return Err(self.diverged(reason));
        }
        self.good.0.clone_from(&self.p);
        self.good.1.clone_from(&self.v);
        let mut cg_iterations = 0;
        match self.params.integrator {
            Integrator::Explicit | Integrator::SymplecticEuler => {
                let explicit = self.params.integrator == Integrator::Explicit;
                let w = &mut self.work;
                Self::solve_mass(&mut self.solver, &self.free, &w.g, &mut w.acc);
                for &i in &self.free {
                    let i = i as usize;
                    advance(explicit, &mut self.p[i], &mut self.v[i], w.acc[i], dt);
                }
            }
            Integrator::ImplicitEuler => {
                cg_iterations = self.implicit_velocity_change(dt);
                for &i in &self.free {
                    let i = i as usize;
                    self.v[i] += self.work.acc[i];
                    self.p[i] += self.v[i] * dt;
                }
            }
        }
        self.update_data();
        self.time += dt;
        self.steps += 1;
        Ok(StepReport {
            energy,
            cg_iterations,
            seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The divergence test of the [module docs](self) on the energies of the current state
    /// (`finite`: whether the control points and velocities are finite); `Err` names why.
    /// Reads [`DynamicSolid::tool_energy_seen`] as already updated with `energy.tools`.
    fn verdict(&self, energy: &Energy, finite: bool) -> Result<(), String> {
        verdict(
            energy,
            finite,
            self.params.divergence_factor,
            self.energy_scale + self.tool_energy_seen,
        )
    }

    /// Goes back to the last checked state and returns the divergence error for `reason`.
    fn diverged(&mut self, reason: String) -> SolidsError {
        self.p.clone_from(&self.good.0);
        self.v.clone_from(&self.good.1);
        self.update_data();
        let suggested_dt = self.suggested_dt();
        SolidsError::Diverged {
            step: self.steps,
            time: self.time,
            reason,
            dt: self.params.dt,
            suggested_dt,
        }
    }

    /// Solves `(M + dt D + dt^2 K) dv = dt (g - dt K v)` by preconditioned conjugate gradient
    /// into `work.acc`; `work.g` holds `g = A^T f - D v`. Returns the iteration count.
    fn implicit_velocity_change(&mut self, dt: f64) -> usize {
        let n = self.p.len();
        let dot = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(x, y)| x.dot(y)).sum::<f64>();
        // b = dt (g - dt K v)
        let v = self.v.clone();
        let mut kv = vec![Vec3::zeros(); n];
        self.stiffness_product(&v, &mut kv);
        let b: Vec<Vec3> = (0..n)
            .map(|i| {
                if self.fixed[i] {
                    Vec3::zeros()
                } else {
                    (self.work.g[i] - kv[i] * dt) * dt
                }
            })
            .collect();
        let mut cg = std::mem::take(&mut self.work.cg);
        let [x, r, z, q] = &mut cg;
        // Operator S y = M y + dt D y + dt^2 K y.
        let apply = |s: &mut Self, y: &[Vec3], out: &mut [Vec3]| {
            let mut k = vec![Vec3::zeros(); n];
            s.stiffness_product(y, &mut k);
            s.mp.apply_into(y, out, Parallelism::Sequential);
            let mut dy = vec![Vec3::zeros(); n];
            s.dp.apply_into(y, &mut dy, Parallelism::Sequential);
            for i in 0..n {
                out[i] = if s.fixed[i] {
                    Vec3::zeros()
                } else {
                    out[i] + dy[i] * dt + k[i] * (dt * dt)
                };
            }
        };
        // Warm start from the explicit guess x = dt M^-1 g.
        Self::solve_mass(&mut self.solver, &self.free, &self.work.g, x);
        x.iter_mut().for_each(|y| *y *= dt);
        let mut sx = vec![Vec3::zeros(); n];
        apply(self, x, &mut sx);
        for i in 0..n {
            r[i] = b[i] - sx[i];
        }
        let bnorm = dot(&b, &b).sqrt();
        let tol = self.params.cg_tolerance * bnorm.max(f64::MIN_POSITIVE);
        Self::solve_mass(&mut self.solver, &self.free, r, z);
        q.copy_from_slice(z);
        let mut rz = dot(r, z);
        let mut it = 0;
        while it < self.params.cg_max_iterations && dot(r, r).sqrt() > tol {
            apply(self, q, &mut sx);
            let qsq = dot(q, &sx);
            if qsq <= 0.0 {
                break;
            }
            let alpha = rz / qsq;
            for i in 0..n {
                x[i] += q[i] * alpha;
                r[i] -= sx[i] * alpha;
            }
            Self::solve_mass(&mut self.solver, &self.free, r, z);
            let rz2 = dot(r, z);
            let beta = rz2 / rz;
            rz = rz2;
            for i in 0..n {
                q[i] = z[i] + q[i] * beta;
            }
            it += 1;
        }
        self.work.acc.copy_from_slice(x);
        self.work.cg = cg;
        it
    }

    /// Runs `steps` steps; stops at the first error.
    pub fn run(&mut self, steps: usize) -> Result<(), SolidsError> {
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }

    /// The highest angular frequency `w` of `(A^T M A)^-1 K` on the free control points at the
    /// current state (power iteration, 40 iterations from a fixed start), and the damping rate
    /// `c` of that mode (Rayleigh quotient of `A^T D A`).
    pub fn highest_mode(&mut self) -> (f64, f64) {
        let n = self.p.len();
        if self.free.is_empty() {
            return (0.0, 0.0);
        }
        // Deterministic pseudo-random start.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut x: Vec<Vec3> = (0..n)
            .map(|i| {
                if self.fixed[i] {
                    Vec3::zeros()
                } else {
                    Vec3::new(rnd(), rnd(), rnd())
                }
            })
            .collect();
        let mut kx = vec![Vec3::zeros(); n];
        let mut mx = vec![Vec3::zeros(); n];
        let dot = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(x, y)| x.dot(y)).sum::<f64>();
        let mut lambda = 0.0;
        for _ in 0..40 {
            self.stiffness_product(&x, &mut kx);
            self.mp.apply_into(&x, &mut mx, Parallelism::Sequential);
            let xm = dot(&x, &mx);
            if xm <= 0.0 {
                break;
            }
            lambda = dot(&x, &kx) / xm;
            let mut y = vec![Vec3::zeros(); n];
            Self::solve_mass(&mut self.solver, &self.free, &kx, &mut y);
            let norm = dot(&y, &y).sqrt();
            if norm == 0.0 || !norm.is_finite() {
                break;
            }
            x = y.into_iter().map(|v| v / norm).collect();
        }
        self.mp.apply_into(&x, &mut mx, Parallelism::Sequential);
        let mut dx = vec![Vec3::zeros(); n];
        self.dp.apply_into(&x, &mut dx, Parallelism::Sequential);
        let xm = dot(&x, &mx);
        let c = if xm > 0.0 { dot(&x, &dx) / xm } else { 0.0 };
        // Power iteration approaches the top eigenvalue from below: add a 10 % margin.
        ((1.1 * lambda.max(0.0)).sqrt(), c)
    }

    /// A time step estimated to be stable for the configured integrator at the current state:
    /// symplectic and implicit `1 / w` (half the `2 / w` limit of symplectic Euler); explicit
    /// (forward Euler) `0.5 min(c / w^2, 2 / c)`, which needs damping (`c > 0`; without damping
    /// no step is stable and `0` is returned).
    pub fn suggested_dt(&mut self) -> f64 {
        let (w, c) = self.highest_mode();
        if w <= 0.0 {
            return self.params.dt;
        }
        match self.params.integrator {
            Integrator::SymplecticEuler | Integrator::ImplicitEuler => 1.0 / w,
            Integrator::Explicit => {
                if c > 0.0 {
                    0.5 * (c / (w * w)).min(2.0 / c)
                } else {
                    0.0
                }
            }
        }
    }

    // ------------------------------------------------------------------------------------
    // Tools and constraints
    // ------------------------------------------------------------------------------------

    /// Adds a tool; returns its handle.
    pub fn add_tool(&mut self, tool: Tool) -> Result<ToolId, SolidsError> {
        tool.validate(self.d.len())?;
        self.tools.push(Some(tool));
        Ok(ToolId(self.tools.len() - 1))
    }

    /// Removes a tool (releasing a rope, switching off gravity).
    pub fn remove_tool(&mut self, id: ToolId) -> Result<Tool, SolidsError> {
        let count = self.tools.len();
        self.tools
            .get_mut(id.0)
            .and_then(Option::take)
            .ok_or(SolidsError::NoSuchElement {
                what: "tool",
                index: id.0,
                count,
            })
    }

    /// The tool with handle `id`, if present.
    pub fn tool(&self, id: ToolId) -> Option<&Tool> {
        self.tools.get(id.0).and_then(Option::as_ref)
    }

    /// Moves the cursor of a rope tool.
    pub fn move_cursor(&mut self, id: ToolId, cursor: Vec3) -> Result<(), SolidsError> {
        if !cursor.iter().all(|c| c.is_finite()) {
            return Err(invalid(
                "cursor",
                format!("{:?}", cursor.as_slice()),
                "finite",
            ));
        }
        match self.tools.get_mut(id.0).and_then(Option::as_mut) {
            Some(Tool::Rope { cursor: c, .. }) => {
                *c = cursor;
                Ok(())
            }
            _ => Err(invalid("tool", id.0, "a rope tool")),
        }
    }

    /// Attaches a rope to the data point nearest `cursor` (journal section 5.4).
    pub fn attach_rope(
        &mut self,
        cursor: Vec3,
        stiffness: f64,
        length: f64,
    ) -> Result<ToolId, SolidsError> {
        let point = nearest(&self.d, &cursor).ok_or(SolidsError::Empty("no data points".into()))?;
        self.add_tool(Tool::Rope {
            point,
            cursor,
            stiffness,
            length,
        })
    }

    /// A region force on the data points within `radius` of `center`, in equal shares.
    pub fn add_region_force(
        &mut self,
        center: Vec3,
        radius: f64,
        force: Vec3,
    ) -> Result<ToolId, SolidsError> {
        self.add_region_force_with(center, radius, force, Falloff::Constant)
    }

    /// A region force on the data points within `radius` of `center`, shared by `falloff` of
    /// their distance from the centre (a sculpting brush's profile; [`Falloff`]).
    pub fn add_region_force_with(
        &mut self,
        center: Vec3,
        radius: f64,
        force: Vec3,
        falloff: Falloff,
    ) -> Result<ToolId, SolidsError> {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(invalid("radius", radius, "non-negative and finite"));
        }
        let points = within(&self.d, &center, radius);
        let weights = falloff.weights(&self.d, &points, &center, radius);
        self.add_tool(Tool::RegionForce {
            points,
            force,
            center,
            radius,
            falloff,
            weights,
        })
    }

    /// Fixes (`fixed = true`) or frees control points (journal section 5.2). Fixed points stop
    /// (their velocity is zeroed) and never move; the partition and factorization are rebuilt.
    pub fn set_fixed(&mut self, points: &[usize], fixed: bool) -> Result<(), SolidsError> {
        let n = self.p.len();
        if let Some(&i) = points.iter().find(|&&i| i >= n) {
            return Err(SolidsError::NoSuchElement {
                what: "control point",
                index: i,
                count: n,
            });
        }
        for &i in points {
            self.fixed[i] = fixed;
            if fixed {
                self.v[i] = Vec3::zeros();
            }
        }
        self.rebuild_active()
    }

    /// Control points whose rest position satisfies `pred` (for fixing regions).
    pub fn control_points_where(&self, pred: impl Fn(&Vec3) -> bool) -> Vec<usize> {
        (0..self.p.len())
            .filter(|&i| pred(&self.p_rest[i]))
            .collect()
    }

    /// Makes the current shape the rest shape: every spring's rest length (edge and virtual)
    /// becomes its current length (journal section 5.4). Masses and stiffnesses stay.
    pub fn plastic_reset(&mut self) {
        self.p_rest.clone_from(&self.p);
        // Data points that only fixed control points define are not updated per step; make
        // them exact before taking lengths.
        self.d = self.disc.map.apply(&self.p);
        self.d_rest.clone_from(&self.d);
        self.springs.reset_rest(&self.d);
        if let Some(a) = &mut self.active_springs {
            a.reset_rest(&self.d);
        }
        self.energy_scale = spring_energy_scale(&self.springs);
        if let Some(m) = &mut self.metric {
            m.reset_rest(&self.p);
        }
        if let SolidSource::Subdivision { control, .. } = &mut self.source {
            control.set_points(self.p.clone());
        }
    }

    /// A material quantity `f` per data point: the mean of `f` over the materials of the control
    /// cells of the data cells around the point (the control cell of each data cell,
    /// `Discretization::cell_parent`), for showing painted material as a colour map. Points in
    /// no cell (none in a valid lattice) get `f` of the first cell's material.
    pub fn data_point_material(&self, f: impl Fn(&Material) -> f64) -> Vec<f64> {
        let data = &self.disc.data;
        let nd = self.d.len();
        let mut sum = vec![0.0; nd];
        let mut count = vec![0u32; nd];
        let values: Vec<f64> = (0..self.material.len())
            .map(|c| f(self.material.cell(c)))
            .collect();
        for c in 0..data.num_cells() {
            let v = values[self.disc.cell_parent[c] as usize];
            for p in data.cell_vertices(CellId::new(c)) {
                sum[p.index()] += v;
                count[p.index()] += 1;
            }
        }
        let fallback = values.first().copied().unwrap_or(0.0);
        sum.iter()
            .zip(&count)
            .map(|(s, &n)| if n > 0 { s / n as f64 } else { fallback })
            .collect()
    }

    /// Plastic flow (the rate form of [`Self::plastic_reset`]; `vclay_core::plasticity` has the
    /// law): every control point displaced from its rest position by more than
    /// `yield_distance` moves its rest position toward its current one,
    ///
    /// ```text
    /// p0_i <- p0_i + fraction * max(0, 1 - yield / |p_i - p0_i|) * (p_i - p0_i)
    /// ```
    ///
    /// and the springs' rest lengths (edge and virtual, journal section 5.4) are taken from the
    /// new rest data points `d0 = A p0` (eq 3's control map). Motion, masses and stiffnesses
    /// stay. `fraction = 1`, `yield_distance = 0` is the plastic reset. Returns how many control
    /// points yielded.
    ///
    /// # Errors
    /// [`SolidsError::InvalidParameter`] for `fraction` outside `[0, 1]` or a negative or
    /// non-finite `yield_distance`.
    pub fn plastic_flow(
        &mut self,
        fraction: f64,
        yield_distance: f64,
    ) -> Result<usize, SolidsError> {
        vclay_core::plasticity::check_flow(fraction, yield_distance).map_err(|why| {
            invalid(
                "plastic flow",
                format!("{fraction}, {yield_distance}"),
                &why,
            )
        })?;
        let mut rest = self.p_rest.clone();
        let mut yielded = 0;
        for (r, p) in rest.iter_mut().zip(&self.p) {
            let e = p - *r;
            let f = vclay_core::plasticity::plastic_flow_factor(fraction, yield_distance, e.norm());
            if f > 0.0 {
                *r += e * f;
                yielded += 1;
            }
        }
        if yielded > 0 {
            let d_rest = self.disc.map.apply(&rest);
            self.put_rest_shape(rest, d_rest);
        }
        Ok(yielded)
    }

    /// Replaces the rest control points (the smooth brush's smoothed rest shape): the rest data
    /// points become `A p0` (eq 3's control map) and the springs' rest lengths follow, as in
    /// [`Self::plastic_flow`]; the clay then settles towards the new rest shape by its own
    /// dynamics. Motion, masses and stiffnesses stay.
    ///
    /// # Errors
    /// [`SolidsError::InvalidParameter`] for a wrong count or non-finite points.
    pub fn set_rest_control_points(&mut self, rest: &[Vec3]) -> Result<(), SolidsError> {
        if rest.len() != self.p.len() {
            return Err(invalid(
                "rest control points",
                rest.len(),
                &format!("{} points", self.p.len()),
            ));
        }
        if let Some(i) = rest.iter().position(|x| !x.iter().all(|c| c.is_finite())) {
            return Err(invalid(
                "rest control points",
                format!("point {i}"),
                "finite",
            ));
        }
        let d_rest = self.disc.map.apply(rest);
        self.put_rest_shape(rest.to_vec(), d_rest);
        Ok(())
    }

    /// The rest shape (rest control points and rest data points, whose distances are the
    /// springs' rest lengths) for undo; [`Self::set_rest_shape`] puts it back.
    pub fn rest_shape(&self) -> (&[Vec3], &[Vec3]) {
        (&self.p_rest, &self.d_rest)
    }

    /// Puts back a rest shape taken by [`Self::rest_shape`] (the same counts): rest control
    /// points, rest data points and the rest lengths that follow from them. Nothing is done
    /// when both are bitwise the current ones.
    ///
    /// # Errors
    /// [`SolidsError::InvalidParameter`] for wrong counts or non-finite points.
    pub fn set_rest_shape(&mut self, control: &[Vec3], data: &[Vec3]) -> Result<(), SolidsError> {
        if control.len() != self.p.len() || data.len() != self.d.len() {
            return Err(invalid(
                "rest shape",
                format!("{} control and {} data points", control.len(), data.len()),
                &format!("{} and {}", self.p.len(), self.d.len()),
            ));
        }
        if let Some(i) = control
            .iter()
            .chain(data)
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(invalid("rest shape", format!("point {i}"), "finite"));
        }
        let same = |a: &[Vec3], b: &[Vec3]| {
            a.iter().zip(b).all(|(x, y)| {
                x.iter()
                    .zip(y.iter())
                    .all(|(u, v)| u.to_bits() == v.to_bits())
            })
        };
        if !(same(control, &self.p_rest) && same(data, &self.d_rest)) {
            self.put_rest_shape(control.to_vec(), data.to_vec());
        }
        Ok(())
    }

    /// Installs a rest shape: rest lengths of all springs, the metric energy's rest metric,
    /// the divergence scale.
    fn put_rest_shape(&mut self, control: Vec<Vec3>, data: Vec<Vec3>) {
        self.springs.reset_rest(&data);
        if let Some(a) = &mut self.active_springs {
            a.reset_rest(&data);
        }
        self.energy_scale = spring_energy_scale(&self.springs);
        if let Some(m) = &mut self.metric {
            m.reset_rest(&control);
        }
        self.p_rest = control;
        self.d_rest = data;
    }

    /// Stops all motion (velocities to zero).
    pub fn stop(&mut self) {
        self.v.iter_mut().for_each(|v| *v = Vec3::zeros());
    }

    /// Changes the material of some control cells (all when `cells` is `None`) at run time;
    /// masses, damping, stiffnesses and the factorization are rebuilt from the rest shape.
    pub fn update_material(
        &mut self,
        cells: Option<&[usize]>,
        f: impl Fn(&mut Material),
    ) -> Result<(), SolidsError> {
        let mut next = self.material.clone();
        next.update(cells, f)?;
        let old = std::mem::replace(&mut self.material, next);
        if let Err(e) = self.rebuild_physics() {
            self.material = old;
            self.rebuild_physics()?;
            return Err(e);
        }
        Ok(())
    }

    // ------------------------------------------------------------------------------------
    // Topology edits
    // ------------------------------------------------------------------------------------

    /// Extrudes boundary face `face` of the control lattice into a new cell (journal section
    /// 5.4) during the simulation: lattice, operators, springs, masses and factorization are
    /// rebuilt, and the motion continues from the current shape (new control points start at
    /// rest, from the face moved along its current normal).
    pub fn extrude(&mut self, face: usize, factor: f64) -> Result<(), SolidsError> {
        let params = ExtrudeParams { factor };
        self.edit(|l| extrude_face(l, FaceId::new(face), &params))
    }

    /// Deletes cell `cell` of the control lattice ("trimming", journal section 5.4) during the
    /// simulation; see [`DynamicSolid::extrude`].
    pub fn delete_cell(&mut self, cell: usize) -> Result<(), SolidsError> {
        self.edit(|l| delete_cell(l, CellId::new(cell)))
    }

    fn edit(
        &mut self,
        op: impl Fn(&Lattice) -> Result<vclay_lattice::Edit, vclay_lattice::LatticeError>,
    ) -> Result<(), SolidsError> {
        let SolidSource::Subdivision {
            control,
            features,
            rules,
            levels,
        } = &self.source
        else {
            return Err(invalid(
                "edit",
                "B-spline solid",
                "a subdivision solid (B-spline solids have a fixed tensor-product topology)",
            ));
        };
        let mut rest = control.clone();
        rest.set_points(self.p_rest.clone());
        let mut cur = control.clone();
        cur.set_points(self.p.clone());
        let er = op(&rest)?;
        let ec = op(&cur)?;
        let np = er.lattice.num_points();
        let mut v = vec![Vec3::zeros(); np];
        let mut fixed = vec![false; np];
        for (old, new) in er.point_map.iter().enumerate() {
            if let Some(n) = new {
                v[n.index()] = self.v[old];
                fixed[n.index()] = self.fixed[old];
            }
        }
        let mut cell_old = vec![None; er.lattice.num_cells()];
        for (old, new) in er.cell_map.iter().enumerate() {
            if let Some(n) = new {
                cell_old[n.index()] = Some(old);
            }
        }
        // A new cell takes the material of the first surviving cell.
        let fill = (0..control.num_cells())
            .find(|&c| er.cell_map[c].is_some())
            .map_or_else(Material::default, |c| *self.material.cell(c));
        let material = self.material.remap(&cell_old, fill);
        let source = SolidSource::Subdivision {
            control: er.lattice.clone(),
            features: er.map_features(features),
            rules: *rules,
            levels: *levels,
        };
        let p_rest = er.lattice.points().to_vec();
        let p = ec.lattice.points().to_vec();
        let disc = source.discretize(&p_rest)?;
        // Commit.
        let old_d = self.d.clone();
        self.source = source;
        self.material = material;
        self.p_rest = p_rest;
        self.p = p;
        self.v = v;
        self.fixed = fixed;
        self.d_rest = disc.data.points().to_vec();
        self.disc = disc;
        self.d = self.disc.map.apply(&self.p);
        self.good = (self.p.clone(), self.v.clone());
        self.rebuild_physics()?;
        // Tools follow the points they held.
        let d = self.d.clone();
        for t in self.tools.iter_mut().flatten() {
            match t {
                Tool::Rope { point, .. } | Tool::PointForce { point, .. } => {
                    *point = nearest(&d, &old_d[*point]).unwrap_or(0);
                }
                Tool::RegionForce {
                    points,
                    center,
                    radius,
                    falloff,
                    weights,
                    ..
                } => {
                    *points = within(&d, center, *radius);
                    *weights = falloff.weights(&d, points, center, *radius);
                }
                Tool::Gravity { .. } | Tool::Inflation { .. } => {}
            }
        }
        Ok(())
    }

    /// Index of the control lattice's boundary face whose centroid is nearest `x` (for
    /// choosing faces to extrude by position).
    pub fn boundary_face_near(&self, x: &Vec3) -> Option<usize> {
        let SolidSource::Subdivision { control, .. } = &self.source else {
            return None;
        };
        let mut best = None;
        let mut bd = f64::INFINITY;
        for f in control.boundary_faces() {
            let c = control
                .face_vertices(f)
                .iter()
                .map(|v: &VertexId| self.p[v.index()])
                .sum::<Vec3>()
                / control.face_vertices(f).len() as f64;
            let q = (c - x).norm_squared();
            if q < bd {
                bd = q;
                best = Some(f.index());
            }
        }
        best
    }

    /// Index of the control cell whose centroid is nearest `x`.
    pub fn cell_near(&self, x: &Vec3) -> Option<usize> {
        let SolidSource::Subdivision { control, .. } = &self.source else {
            return None;
        };
        let mut best = None;
        let mut bd = f64::INFINITY;
        for c in 0..control.num_cells() {
            let vs = control.cell_vertices(CellId::new(c));
            let ctr = vs.iter().map(|v| self.p[v.index()]).sum::<Vec3>() / vs.len() as f64;
            let q = (ctr - x).norm_squared();
            if q < bd {
                bd = q;
                best = Some(c);
            }
        }
        best
    }
}

/// Energy of stretching every spring by its own rest length.
/// One explicit (`explicit`: forward Euler, journal section 4.4: position from the old
/// velocity) or symplectic Euler (velocity first, then position from the new velocity) update
/// of a control point `x` with velocity `v` and acceleration `a`.
#[inline]
fn advance(explicit: bool, x: &mut Vec3, v: &mut Vec3, a: Vec3, dt: f64) {
    if explicit {
        *x += *v * dt;
        *v += a * dt;
    } else {
        *v += a * dt;
        *x += *v * dt;
    }
}

/// The divergence test: the state must be finite and its total energy at most `factor` times
/// `scale` (the spring energy scale plus the largest rope energy seen).
fn verdict(energy: &Energy, finite: bool, factor: f64, scale: f64) -> Result<(), String> {
    let bound = factor * scale;
    let total = energy.total();
    if !finite || !total.is_finite() {
        Err("non-finite state".to_string())
    } else if total > bound.max(f64::MIN_POSITIVE) {
        Err(format!(
            "energy {total:.3e} exceeds the bound {bound:.3e} ({factor} x the spring energy scale)"
        ))
    } else {
        Ok(())
    }
}

/// For a chain above [`SubdivisionMap::GATHER_NNZ`] non-zeros, whose `A^T` products scatter
/// through the operators: drops any stored transposes (`galerkin` does not keep them for such
/// a chain) and stores the compact operators ([`SubdivisionMap::compress`]), so that the
/// per-step products `A p` and `A^T f` stream 5-6 instead of 12 bytes per non-zero (same bits;
/// issue 31). Small chains, whose products run from cache, are left as they are.
fn compress_large(map: &mut SubdivisionMap) {
    let nnz: usize = map.operators().iter().map(SparseMatrix::nnz).sum();
    if nnz > SubdivisionMap::GATHER_NNZ {
        map.release_transposes();
        map.compress();
    }
}

/// Point blocks of the parallel spring passes ([`SpringSet::organize`]): one per rayon thread
/// (blocks of equal point counts carry nearly equal spring counts, and fewer cuts leave fewer
/// straddling springs for the sequential tail).
fn force_blocks() -> usize {
    rayon::current_num_threads().max(1)
}

fn spring_energy_scale(sp: &SpringSet) -> f64 {
    0.5 * (sp.edge_k.iter().zip(&sp.edge_rest))
        .chain(sp.corner_k.iter().zip(&sp.corner_rest))
        .map(|(k, l)| k * l * l)
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 31 (session h54): both steps multiply by the dense inverse of `A^T M A` from
    /// points, three coordinates in one pass; every value must be the bits of the
    /// coordinate-column product the steps used before, so that saved trajectories continue
    /// exactly (sizes with and without a tail of fewer than four columns, row ranges not
    /// starting at zero).
    #[test]
    fn inverse_rows_of_points_equal_inverse_rows_of_columns_bit_for_bit() {
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for m in [1, 3, 4, 7, 64, 65] {
            let inv: Vec<f64> = (0..m * m).map(|_| rnd()).collect();
            let b: Vec<Vec3> = (0..m).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
            let cols: [Vec<f64>; 3] = std::array::from_fn(|c| b.iter().map(|p| p[c]).collect());
            for rows in [0..m, m / 2..m] {
                // The coordinate-column form the one-thread step used before (session 20).
                let mut want = vec![Vec3::zeros(); m];
                for k in rows.clone() {
                    let row = &inv[k * m..(k + 1) * m];
                    let (rc, rt) = row.as_chunks::<4>();
                    for c in 0..3 {
                        let (bch, bt) = cols[c].as_chunks::<4>();
                        let mut s = [0.0; 4];
                        for (r4, b4) in rc.iter().zip(bch) {
                            for l in 0..4 {
                                s[l] += r4[l] * b4[l];
                            }
                        }
                        want[k][c] = (s[0] + s[1])
                            + (s[2] + s[3])
                            + rt.iter().zip(bt).map(|(r, x)| r * x).sum::<f64>();
                    }
                }
                let mut got = vec![Vec3::zeros(); m];
                inverse_point_rows(&inv, &b, rows.clone(), |k, v| got[k] = v);
                for k in rows.clone() {
                    for c in 0..3 {
                        assert_eq!(got[k][c].to_bits(), want[k][c].to_bits(), "m {m} row {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn dense_and_sparse_mass_factorizations_solve_alike() {
        let s = crate::benchmarks::cube(1, SolidParams::default()).unwrap();
        let n = s.p.len();
        // Every third control point fixed, so the factored block is a proper subset.
        let free: Vec<u32> = (0..n as u32).filter(|i| i % 3 != 0).collect();
        let mut dense = MassSolver::new(&s.mp, &free, n, true).unwrap();
        let mut sparse = MassSolver::new(&s.mp, &free, n, false).unwrap();
        assert!(matches!(dense.factor, MassFactor::Dense(_)));
        assert!(matches!(sparse.factor, MassFactor::Sparse(_)));
        let b: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i as f64).sin(), 1.0, (0.5 * i as f64).cos()))
            .collect();
        let (mut x1, mut x2) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        DynamicSolid::solve_mass(&mut dense, &free, &b, &mut x1);
        DynamicSolid::solve_mass(&mut sparse, &free, &b, &mut x2);
        let scale = x1.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(scale > 0.0);
        for i in 0..n {
            assert!((x1[i] - x2[i]).norm() <= 1e-10 * scale, "point {i}");
            if i % 3 == 0 {
                assert_eq!(x1[i], Vec3::zeros());
            }
        }
        // The solution solves the free block: (M x)_i = b_i on free points.
        let mut mx = vec![Vec3::zeros(); n];
        s.mp.apply_into(&x1, &mut mx, Parallelism::Sequential);
        for &i in &free {
            let i = i as usize;
            assert!(
                (mx[i] - b[i]).norm() <= 1e-9 * b[i].norm().max(1.0),
                "row {i}"
            );
        }
    }

    #[test]
    fn proportional_damping_shortcut_matches_the_damping_matrix() {
        let mut s = crate::benchmarks::cube(
            1,
            SolidParams {
                parallelism: Parallelism::Sequential,
                ..SolidParams::default()
            },
        )
        .unwrap();
        let c = s
            .damping_ratio
            .expect("uniform material: proportional damping");
        assert!(c > 0.0);
        for (i, v) in s.v.iter_mut().enumerate() {
            let t = i as f64;
            *v = Vec3::new(t.sin(), (2.0 * t).cos(), 0.3 * t.sin());
        }
        let e1 = s.generalized_forces();
        let g1 = s.work.g.clone();
        s.damping_ratio = None;
        let e2 = s.generalized_forces();
        let scale = g1.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(scale > 0.0);
        for (a, b) in g1.iter().zip(&s.work.g) {
            assert!((a - b).norm() <= 1e-12 * scale, "{a:?} vs {b:?}");
        }
        assert!((e1.kinetic - e2.kinetic).abs() <= 1e-12 * e1.kinetic.abs());
    }
}

// ----------------------------------------------------------------------------------------
// State: snapshots for undo and session files
// ----------------------------------------------------------------------------------------

/// The part of a [`DynamicSolid`] that evolves from step to step: control points `p`, their
/// velocities `p'`, the data points `d = A p` as the last step left them (data points that only
/// fixed control points define are not recomputed per step, so they are kept as they are), the
/// tools, the clock and the running maximum of the tool energy (which enters the divergence
/// bound). Copying it costs a few arrays (level 4 of the 4^3 cube: about 3 MB), so the session
/// layer takes one before every command; [`DynamicSolid::set_state`] puts it back bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidState {
    /// Control points `p`.
    pub control_points: Vec<Vec3>,
    /// Control point velocities `p'`.
    pub velocities: Vec<Vec3>,
    /// Data points `d`.
    pub data_points: Vec<Vec3>,
    /// Tools by handle (`None`: removed).
    pub tools: Vec<Option<Tool>>,
    /// Simulated time.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// Largest tool energy seen (divergence bound).
    pub tool_energy_seen: f64,
}

/// What a [`DynamicSolid`] holds besides its source, material, parameters and [`SolidState`]:
/// the rest shape (control points and data points: after a plastic reset the data rest shape
/// is `A p_rest` as that reset computed it, which need not equal a fresh subdivision bit for
/// bit), the fixed set, the metric-tensor energy's weight if it is on, and the divergence
/// energy scale. With these, [`DynamicSolid::from_parts`] rebuilds a solid that continues
/// exactly as the original would.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidRest {
    /// Rest control points.
    pub control_points: Vec<Vec3>,
    /// Rest data points (spring rest lengths).
    pub data_points: Vec<Vec3>,
    /// The data points that masses, damping and spring stiffnesses were built from: the rest
    /// shape before the plastic resets since the last rebuild (a reset renews rest lengths
    /// only, journal section 5.4).
    pub physics_data_points: Vec<Vec3>,
    /// Fixed flag per control point.
    pub fixed: Vec<bool>,
    /// `Some(c)` when the metric-tensor energy (weight `c`) replaces the springs.
    pub metric_stiffness: Option<f64>,
    /// Energy scale of the divergence bound.
    pub energy_scale: f64,
}

impl DynamicSolid {
    /// The evolving state (see [`SolidState`]).
    pub fn state(&self) -> SolidState {
        SolidState {
            control_points: self.p.clone(),
            velocities: self.v.clone(),
            data_points: self.d.clone(),
            tools: self.tools.clone(),
            time: self.time,
            steps: self.steps,
            tool_energy_seen: self.tool_energy_seen,
        }
    }

    /// Puts back a state taken by [`DynamicSolid::state`] from this solid with the same
    /// topology (array lengths are checked; a state from before an extrusion or deletion does
    /// not fit). Tool point indices are validated.
    pub fn set_state(&mut self, s: &SolidState) -> Result<(), SolidsError> {
        let n = self.p.len();
        let nd = self.d.len();
        for (what, len, want) in [
            ("state control points", s.control_points.len(), n),
            ("state velocities", s.velocities.len(), n),
            ("state data points", s.data_points.len(), nd),
        ] {
            if len != want {
                return Err(invalid(what, len, &format!("{want} values")));
            }
        }
        if let Some(i) = s
            .control_points
            .iter()
            .chain(&s.velocities)
            .chain(&s.data_points)
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(invalid("state", format!("value {i}"), "finite"));
        }
        for t in s.tools.iter().flatten() {
            t.validate(nd)?;
        }
        self.p.clone_from(&s.control_points);
        self.v.clone_from(&s.velocities);
        self.d.clone_from(&s.data_points);
        self.tools.clone_from(&s.tools);
        self.time = s.time;
        self.steps = s.steps;
        self.tool_energy_seen = s.tool_energy_seen;
        self.good = (self.p.clone(), self.v.clone());
        Ok(())
    }

    /// The rest shape, fixed set and energy settings (see [`SolidRest`]).
    pub fn rest(&self) -> SolidRest {
        SolidRest {
            control_points: self.p_rest.clone(),
            data_points: self.d_rest.clone(),
            physics_data_points: self.d_phys.clone(),
            fixed: self.fixed.clone(),
            metric_stiffness: self.metric.as_ref().map(|m| m.stiffness),
            energy_scale: self.energy_scale,
        }
    }

    /// Rebuilds a solid from its parts (a session file): `source` with its control lattice's
    /// topology, the material per control cell, the parameters, the rest shape and fixed set,
    /// and the state. The result steps exactly (bitwise) as the solid these parts were taken
    /// from.
    pub fn from_parts(
        source: SolidSource,
        material: MaterialField,
        params: SolidParams,
        rest: &SolidRest,
        state: &SolidState,
    ) -> Result<Self, SolidsError> {
        let s = Self::with_material(source, rest.control_points.clone(), material, params)?;
        s.put_parts(rest, state)
    }

    /// [`DynamicSolid::from_parts`] for parts whose data points (rest, physics rest and state)
    /// and tools' data-point ids are in `numbering`, which need not be the one this build
    /// gives a new solid (a session saved by an older build: every solid was
    /// [`DataNumbering::Locality`] before issue 31's grid numbering, and boxes below
    /// [`crate::model::GRID_NUMBERING_POINTS`] data points were until session 22).
    ///
    /// A solid below [`crate::model::GRID_NUMBERING_POINTS`] data points keeps `numbering`
    /// (when it can have it) and steps bit for bit as the solid the parts were taken from. A
    /// larger one gets this build's numbering: when that differs, the parts are first moved
    /// into it: data point `i` of `numbering` is the point of the same finest-lattice point (a
    /// permutation, so the values keep their bits; a region force's point list keeps its
    /// order). The result then steps as a solid built in this numbering from the moved parts;
    /// its trajectory equals the saving build's to rounding (the passes sum in another order),
    /// not bit for bit.
    pub fn from_parts_numbered(
        source: SolidSource,
        material: MaterialField,
        params: SolidParams,
        rest: &SolidRest,
        state: &SolidState,
        numbering: DataNumbering,
    ) -> Result<Self, SolidsError> {
        let p = rest.control_points.clone();
        // The discretization in the saved numbering (where the solid can have it).
        let saved = source.discretize_numbered(&p, Some(numbering))?;
        // Small: keep the saved numbering, and with it the saved trajectory's bits. Large: the
        // saved numbering if it is this build's (grid order, or a lattice that is no grid).
        let keep = saved.numbering == numbering
            && (saved.data.num_points() < crate::model::GRID_NUMBERING_POINTS
                || numbering == DataNumbering::Grid
                || crate::springs::lattice_grid_order(&saved.data).is_none());
        if keep {
            return Self::with_discretization(source, p, material, params, Some(saved))?
                .put_parts(rest, state);
        }
        let s = Self::with_discretization(source, p, material, params, None)?;
        if numbering == s.disc.numbering {
            return s.put_parts(rest, state);
        }
        // `saved` gives the finest-lattice point of each data point in the saved numbering
        // (the topology of the finest lattice does not depend on the control points).
        if saved.numbering != numbering {
            return Err(invalid(
                "data numbering",
                numbering.name(),
                &format!(
                    "a numbering this solid can have ({})",
                    s.disc.numbering.name()
                ),
            ));
        }
        let nd = s.d.len();
        let mut here = vec![u32::MAX; nd];
        for (i, &g) in s.disc.order.iter().enumerate() {
            here[g as usize] = i as u32;
        }
        // Saved data point i is data point `to[i]` here.
        let to: Vec<u32> = saved.order.iter().map(|&g| here[g as usize]).collect();
        drop(saved);
        let move_points = |x: &[Vec3], what: &str| -> Result<Vec<Vec3>, SolidsError> {
            if x.len() != nd {
                return Err(invalid(what, x.len(), &format!("{nd} values")));
            }
            let mut out = vec![Vec3::zeros(); nd];
            for (i, v) in x.iter().enumerate() {
                out[to[i] as usize] = *v;
            }
            Ok(out)
        };
        let rest = SolidRest {
            data_points: move_points(&rest.data_points, "rest data points")?,
            physics_data_points: move_points(&rest.physics_data_points, "physics data points")?,
            ..rest.clone()
        };
        let mut state = SolidState {
            data_points: move_points(&state.data_points, "state data points")?,
            ..state.clone()
        };
        for t in state.tools.iter_mut().flatten() {
            t.validate(nd)?;
            match t {
                Tool::Rope { point, .. } | Tool::PointForce { point, .. } => {
                    *point = to[*point] as usize;
                }
                Tool::RegionForce { points, .. } => {
                    for q in points.iter_mut() {
                        *q = to[*q] as usize;
                    }
                }
                Tool::Gravity { .. } | Tool::Inflation { .. } => {}
            }
        }
        s.put_parts(&rest, &state)
    }

    /// The rest of [`DynamicSolid::from_parts`]: `self` built from the rest control points.
    fn put_parts(self, rest: &SolidRest, state: &SolidState) -> Result<Self, SolidsError> {
        let mut s = self;
        for (what, len) in [
            ("rest data points", rest.data_points.len()),
            ("physics data points", rest.physics_data_points.len()),
        ] {
            if len != s.d.len() {
                return Err(invalid(what, len, &format!("{} values", s.d.len())));
            }
        }
        if rest.fixed.len() != s.p.len() {
            return Err(invalid(
                "fixed",
                rest.fixed.len(),
                &format!("{} flags", s.p.len()),
            ));
        }
        if !(rest.energy_scale.is_finite() && rest.energy_scale > 0.0) {
            return Err(invalid(
                "energy_scale",
                rest.energy_scale,
                "positive and finite",
            ));
        }
        if let Some(i) = rest
            .data_points
            .iter()
            .chain(&rest.physics_data_points)
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(invalid("rest data points", format!("value {i}"), "finite"));
        }
        // Masses and stiffnesses from the shape they were built from, then the rest lengths
        // of the plastic resets since.
        s.d_rest.clone_from(&rest.physics_data_points);
        s.d.clone_from(&rest.physics_data_points);
        s.rebuild_physics()?;
        if rest.data_points != rest.physics_data_points {
            s.springs.reset_rest(&rest.data_points);
        }
        s.d_rest.clone_from(&rest.data_points);
        if rest.metric_stiffness.is_some() {
            s.use_metric_energy(rest.metric_stiffness)?;
        }
        s.fixed.clone_from(&rest.fixed);
        s.rebuild_active()?;
        s.set_state(state)?;
        s.energy_scale = rest.energy_scale;
        Ok(s)
    }

    /// Replaces the material field wholesale (per control cell; the same count), rebuilding
    /// masses, stiffnesses and the factorization from the rest shape (the exact inverse of a
    /// material change, for undo).
    pub fn set_material(&mut self, material: MaterialField) -> Result<(), SolidsError> {
        if material.len() != self.material.len() {
            return Err(invalid(
                "material",
                material.len(),
                &format!("{} cell materials", self.material.len()),
            ));
        }
        for m in material.cells() {
            m.validate()?;
        }
        let old = std::mem::replace(&mut self.material, material);
        if let Err(e) = self.rebuild_physics() {
            self.material = old;
            self.rebuild_physics()?;
            return Err(e);
        }
        Ok(())
    }
}

impl DynamicSolid {
    /// The outward boundary face loops of the data lattice as `(offsets, vertices)`: loop `k`
    /// is `vertices[offsets[k]..offsets[k + 1]]`, data point indices at [`Self::data_points`]
    /// (what inflation pushes on; viewers draw it).
    pub fn boundary_loops(&self) -> (&[u32], &[u32]) {
        (&self.boundary.offsets, &self.boundary.verts)
    }

    /// A copy of the data lattice with its points at the current `d` (for writers that take a
    /// lattice; [`Self::data_lattice`] lends it without copying but needs `&mut self`).
    pub fn data_lattice_copy(&self) -> Lattice {
        let mut l = self.disc.data.clone();
        l.points_mut().copy_from_slice(&self.d);
        l
    }

    /// Control cell of each data cell.
    pub fn data_cell_parents(&self) -> &[u32] {
        &self.disc.cell_parent
    }
}
