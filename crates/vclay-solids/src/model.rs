//! The two kinds of free-form solid and their discretization into data points `d = A p`.
//!
//! * [`SolidSource::Subdivision`]: a MacCracken-Joy subdivision solid; the control points are
//!   the points of the control lattice and the data lattice is the finest subdivided lattice
//!   (`subdivision-solids-journal.txt` section 4.2, eq 4).
//! * [`SolidSource::BSpline`]: a trivariate B-spline (or frozen-weight NURBS) solid sampled on an
//!   `m0 x m1 x m2` grid of uniformly spaced parameters (journal section 4.1, eq 3: `c = B q`);
//!   the data lattice is the hexahedral grid of those samples.
//!
//! [`Discretization`] holds what the dynamics needs from either: the chain `A`, the data lattice
//! (topology, and points at the configuration it was built in) and, for each data cell, the
//! control cell it belongs to (so per-cell materials of the control lattice apply).

use vclay_core::Vec3;
use vclay_lattice::{
    CellId, Features, Lattice, SparseMatrix, SubdivisionMap, SubdivisionRules, SubdivisionSolid,
    TensorOperator, primitives,
};
use vclay_spline::KnotVector;

use crate::error::{SolidsError, invalid};

/// Largest subdivision level accepted (level 6 of the 4^3 cube has 7.3 million data points).
pub const MAX_LEVEL: usize = 6;

/// A subdivision solid loaded from a file whose finest lattice is a structured grid of at least
/// this many points (every subdivided box from level 4 of the 4^3 cube on: 117,649 points) is
/// numbered in grid order ([`DataNumbering::Grid`]) whatever numbering the file records (its
/// parts are moved into it, [`crate::DynamicSolid::from_parts_numbered`]: twice as fast a step
/// there, the trajectory continuing to rounding); a smaller one keeps the numbering its file
/// records, and with it the bits of its trajectory. New solids: [`GRID_NUMBERING_NEW_POINTS`].
pub const GRID_NUMBERING_POINTS: usize = 100_000;

/// A new subdivision solid (built by [`SolidSource::discretize`], not loaded from a file) whose
/// finest lattice is a structured grid of at least this many points (every subdivided box from
/// level 2 of the 4^3 cube on: 2,197 points) is numbered in grid order
/// ([`DataNumbering::Grid`]), which gives each level between two grids its tensor-product form
/// ([`TensorOperator`]: the phased step's map passes one axis at a time, issue 31,
/// `docs/performance.md` "Level-2 step, session 22 (h60)"); smaller ones keep
/// [`DataNumbering::Locality`]. The same bound as [`crate::PHASED_POINTS`]: below it a step
/// runs on one thread, takes a few microseconds, and the small models keep the bits of their
/// stored runs.
pub const GRID_NUMBERING_NEW_POINTS: usize = crate::PHASED_POINTS;

/// How the data points of a subdivision solid are numbered (the order of
/// [`crate::DynamicSolid::data_points`], of every per-data-point array and of the data-point ids
/// that tools hold). Saved states are in the numbering of the build that saved them; a
/// session file records it, and [`crate::DynamicSolid::from_parts_numbered`] moves the data
/// points and tool ids of a state saved in another numbering into the solid's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DataNumbering {
    /// Cuthill-McKee by [`Lattice::locality_order`] (B-spline solids and level 0: the
    /// lattice's own numbering). Every solid before session 21 (issue 31); since, every solid
    /// whose finest lattice is not a grid, new ones below [`GRID_NUMBERING_NEW_POINTS`], and
    /// (session 22) those loaded from a file that records it, below [`GRID_NUMBERING_POINTS`].
    #[default]
    Locality,
    /// Grid order `i + nx (j + ny k)` of a finest lattice that is an `nx x ny x nz` grid (x the
    /// longest axis; found from the topology alone), under which the structured-grid spring
    /// kernel (`springs/grid.rs`) reads `d` and writes `f` in order (issue 31,
    /// `docs/performance.md` "Level-5 step, session 21") and the levels of the chain between
    /// grids are applied in their tensor-product forms ([`TensorOperator`], session 22).
    Grid,
}

impl DataNumbering {
    /// The name a session file stores (`"locality"`, `"grid"`).
    pub fn name(self) -> &'static str {
        match self {
            DataNumbering::Locality => "locality",
            DataNumbering::Grid => "grid",
        }
    }

    /// The numbering named `name` ([`DataNumbering::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "locality" => Some(DataNumbering::Locality),
            "grid" => Some(DataNumbering::Grid),
            _ => None,
        }
    }
}

/// Where a dynamic solid's geometry comes from.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)] // one per solid; boxing would only add an indirection
pub enum SolidSource {
    /// A subdivision solid (journal section 4.2).
    Subdivision {
        /// Control lattice: its topology (its points are replaced by the control points).
        control: Lattice,
        /// Crease and corner tags of the control lattice.
        features: Features,
        /// Subdivision rules (boundary treatment).
        rules: SubdivisionRules,
        /// Number of subdivision levels `n` (data points = level `n`).
        levels: usize,
    },
    /// A B-spline solid sampled on a grid (journal section 4.1).
    BSpline {
        /// Knot vectors along u, v, w (their control point counts give the net size).
        knots: [KnotVector; 3],
        /// Weights of the control net (all 1 for a B-spline; frozen otherwise), index
        /// `(i n_v + j) n_w + k`.
        weights: Vec<f64>,
        /// Samples `m0, m1, m2` per parametric direction (each at least 2).
        samples: [usize; 3],
    },
}

impl SolidSource {
    /// A subdivision solid over `control` with no tagged features and `boundary` as the
    /// boundary rule, subdivided `levels` times, with the control lattice's points as the
    /// control points (what [`crate::DynamicSolid::new`] takes).
    pub fn subdivision(
        control: Lattice,
        boundary: vclay_lattice::BoundaryRule,
        levels: usize,
    ) -> (Self, Vec<Vec3>) {
        let p = control.points().to_vec();
        let source = SolidSource::Subdivision {
            features: Features::none(&control),
            control,
            rules: SubdivisionRules::new(boundary),
            levels,
        };
        (source, p)
    }

    /// Number of control points.
    pub fn control_count(&self) -> usize {
        match self {
            SolidSource::Subdivision { control, .. } => control.num_points(),
            SolidSource::BSpline { knots, .. } => {
                knots.iter().map(KnotVector::control_points).product()
            }
        }
    }

    /// Number of control cells (lattice cells, or cells of the control net grid).
    pub fn control_cells(&self) -> usize {
        match self {
            SolidSource::Subdivision { control, .. } => control.num_cells(),
            SolidSource::BSpline { knots, .. } => knots
                .iter()
                .map(|k| k.control_points().saturating_sub(1).max(1))
                .product(),
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SolidsError> {
        match self {
            SolidSource::Subdivision { levels, .. } => {
                if *levels > MAX_LEVEL {
                    return Err(invalid("level", levels, &format!("at most {MAX_LEVEL}")));
                }
            }
            SolidSource::BSpline {
                knots,
                weights,
                samples,
            } => {
                if let Some(a) = (0..3).find(|&a| samples[a] < 2) {
                    return Err(invalid(
                        &format!("samples[{a}]"),
                        samples[a],
                        "at least 2 samples per direction",
                    ));
                }
                if let Some(a) = (0..3).find(|&a| samples[a] < knots[a].control_points()) {
                    return Err(invalid(
                        &format!("samples[{a}]"),
                        samples[a],
                        &format!(
                            "at least {} (the control points along axis {a}): fewer samples \
                             cannot determine the control points (A^T M A would be singular)",
                            knots[a].control_points()
                        ),
                    ));
                }
                let n: usize = knots.iter().map(KnotVector::control_points).product();
                if weights.len() != n {
                    return Err(invalid(
                        "weights",
                        weights.len(),
                        &format!("{n} weights, one per control point"),
                    ));
                }
                if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
                    return Err(invalid(
                        &format!("weights[{i}]"),
                        weights[i],
                        "positive and finite",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Builds the discretization with control points `p`, its data points numbered as this
    /// build numbers them ([`DataNumbering`], [`GRID_NUMBERING_POINTS`]).
    pub fn discretize(&self, p: &[Vec3]) -> Result<Discretization, SolidsError> {
        self.discretize_numbered(p, None)
    }

    /// [`SolidSource::discretize`] with the data points numbered by `numbering` where that
    /// applies (`None`: this build's choice). [`DataNumbering::Grid`] applies to subdivision
    /// solids of at least one level whose finest lattice is a grid; otherwise, and for
    /// B-spline solids, the result is that of `None` (its [`Discretization::numbering`] says
    /// which one was used).
    pub fn discretize_numbered(
        &self,
        p: &[Vec3],
        numbering: Option<DataNumbering>,
    ) -> Result<Discretization, SolidsError> {
        self.validate()?;
        if p.len() != self.control_count() {
            return Err(invalid(
                "control points",
                p.len(),
                &format!("{} points", self.control_count()),
            ));
        }
        if let Some(i) = p.iter().position(|x| !x.iter().all(|c| c.is_finite())) {
            return Err(invalid(
                &format!("control point {i}"),
                format!("{:?}", p[i].as_slice()),
                "finite coordinates",
            ));
        }
        match self {
            SolidSource::Subdivision {
                control,
                features,
                rules,
                levels,
            } => {
                let mut lattice = control.clone();
                lattice.set_points(p.to_vec());
                let solid = SubdivisionSolid::new(lattice, features.clone(), *rules, *levels)?;
                // Data cell -> control cell: children of cell c are contiguous, one per vertex of
                // c, in cell order (vclay-lattice's refinement numbering).
                let mut parent: Vec<u32> = (0..solid.control().num_cells() as u32).collect();
                for j in 0..*levels {
                    let l = solid.lattice(j);
                    let mut next = Vec::with_capacity(l.num_cells() * 8);
                    for c in 0..l.num_cells() {
                        let k = l.cell_vertices(CellId::new(c)).len();
                        next.extend(std::iter::repeat_n(parent[c], k));
                    }
                    parent = next;
                }
                let map = if *levels == 0 {
                    SubdivisionMap::new(vec![SparseMatrix::identity(p.len())])
                } else {
                    solid.map().clone()
                };
                debug_assert_eq!(parent.len(), solid.finest().num_cells());
                if *levels == 0 {
                    return Ok(Discretization {
                        map,
                        data: solid.finest().clone(),
                        cell_parent: parent,
                        order: (0..p.len() as u32).collect(),
                        numbering: DataNumbering::Locality,
                    });
                }
                // Renumber the data points by a breadth-first sweep (Cuthill-McKee, from the
                // topology alone, so the numbering does not depend on the placement; cells, edges and faces keep their
                // ids): the subdivision numbering (vertex, edge, face, cell points, recursively)
                // scatters neighbours across the whole array, and the per-step spring and
                // operator passes are bound by memory access at large levels.
                // (Numbering a grid's points in grid order made the structured-grid spring
                // kernel 10-20 % faster at level 5, but a saved session stores data points in
                // this numbering: not done without a versioned migration; docs/performance.md
                // "Structured-grid spring kernel".)
                // Grids (every subdivided box from level 2 on, `GRID_NUMBERING_NEW_POINTS`) are
                // numbered in grid order instead, so that the structured-grid spring kernel
                // reads `d` and writes `f` in order and the levels between grids get their
                // tensor-product forms (issue 31; `DataNumbering`).
                let want = numbering.unwrap_or(
                    if solid.finest().num_points() >= GRID_NUMBERING_NEW_POINTS {
                        DataNumbering::Grid
                    } else {
                        DataNumbering::Locality
                    },
                );
                let grid = match want {
                    DataNumbering::Grid => crate::springs::lattice_grid_order(solid.finest()),
                    DataNumbering::Locality => None,
                };
                let (order, numbering, fine_dims) = match grid {
                    Some((dims, order)) => (order, DataNumbering::Grid, Some(dims)),
                    None => (
                        solid.finest().locality_order(),
                        DataNumbering::Locality,
                        None,
                    ),
                };
                let data = solid
                    .finest()
                    .renumber_points(&order)
                    .map_err(SolidsError::Lattice)?;
                let mut ops = map.operators().to_vec();
                drop(map);
                let last = ops.len() - 1;
                // Grid dimensions of each level numbered in grid order (`None`: not renumbered).
                let mut dims: Vec<Option<[usize; 3]>> = vec![None; levels + 1];
                dims[*levels] = fine_dims;
                if numbering == DataNumbering::Grid {
                    // The levels between the control points and the data points are internal to
                    // the chain: number the points of each (a grid too) in grid order as well,
                    // so that `A p` and `A^T f` read and write every level in the order of the
                    // data points (each level's rows and the next level's columns permuted).
                    for j in 1..*levels {
                        if let Some((d, o)) = crate::springs::lattice_grid_order(solid.lattice(j)) {
                            ops[j - 1] = ops[j - 1].select_rows(&o);
                            ops[j] = ops[j].renumber_columns(&o);
                            dims[j] = Some(d);
                        }
                    }
                }
                ops[last] = ops[last].select_rows(&order);
                let mut map = SubdivisionMap::new(ops);
                // Levels between two grids in grid order are tensor products of one-dimensional
                // subdivision operators: their products run one axis at a time.
                for j in 0..*levels {
                    if let (Some(c), Some(f)) = (dims[j], dims[j + 1])
                        && let Some(t) = TensorOperator::factor(map.operator(j), c, f)
                    {
                        map.set_tensor(j, t);
                    }
                }
                Ok(Discretization {
                    map,
                    data,
                    cell_parent: parent,
                    order,
                    numbering,
                })
            }
            SolidSource::BSpline {
                knots,
                weights,
                samples,
            } => bspline_discretization(knots, weights, *samples, p),
        }
    }
}

/// The data points of a dynamic solid and the map from its control points.
#[derive(Clone, Debug)]
pub struct Discretization {
    /// `A` as a chain of sparse levels (one level for B-spline solids).
    pub map: SubdivisionMap,
    /// The data lattice, points at `A p` for the `p` it was built with.
    pub data: Lattice,
    /// Control cell of each data cell.
    pub cell_parent: Vec<u32>,
    /// Data point `i` is point `order[i]` of the lattice the source defines (for subdivision
    /// solids the finest level of [`vclay_lattice::SubdivisionSolid`], whose numbering puts
    /// vertex, edge, face and cell points in blocks; the data points are renumbered by
    /// [`Lattice::locality_order`] for cache-friendly passes, or in grid order, see
    /// [`Discretization::numbering`]). The identity for B-spline solids and level 0.
    pub order: Vec<u32>,
    /// Which numbering `order` is.
    pub numbering: DataNumbering,
}

/// Grid sample parameters: `samples` values spread uniformly over the knot vector's domain.
fn sample_params(k: &KnotVector, samples: usize) -> Vec<f64> {
    let d = k.domain();
    (0..samples)
        .map(|a| d.min + (d.max - d.min) * a as f64 / (samples - 1) as f64)
        .collect()
}

/// Builds `B` (journal eq 3) and the sample grid lattice.
fn bspline_discretization(
    knots: &[KnotVector; 3],
    weights: &[f64],
    samples: [usize; 3],
    p: &[Vec3],
) -> Result<Discretization, SolidsError> {
    let dims = knots.each_ref().map(KnotVector::control_points);
    let deg = knots.each_ref().map(KnotVector::degree);
    // Per axis: for each sample, (first control index, basis values).
    let axis: Vec<Vec<(usize, Vec<f64>)>> = (0..3)
        .map(|a| {
            sample_params(&knots[a], samples[a])
                .into_iter()
                .map(|u| {
                    let span = knots[a].find_span(u);
                    let mut b = vec![0.0; deg[a] + 1];
                    knots[a].basis(span, u, &mut b);
                    (span - deg[a], b)
                })
                .collect()
        })
        .collect();
    // The grid lattice; its point (i, j, k) sits at (i, j, k) before we move it.
    let size = Vec3::new(
        (samples[0] - 1) as f64,
        (samples[1] - 1) as f64,
        (samples[2] - 1) as f64,
    );
    let mut data = primitives::box_lattice(samples, Vec3::zeros(), size);
    let grid: Vec<[usize; 3]> = data
        .points()
        .iter()
        .map(|x| {
            [
                x.x.round() as usize,
                x.y.round() as usize,
                x.z.round() as usize,
            ]
        })
        .collect();
    let n = dims.iter().product::<usize>();
    let mut rp = Vec::with_capacity(grid.len() + 1);
    rp.push(0usize);
    let mut cols: Vec<u32> = Vec::new();
    let mut vals: Vec<f64> = Vec::new();
    for g in &grid {
        let (i0, bu) = &axis[0][g[0]];
        let (j0, bv) = &axis[1][g[1]];
        let (k0, bw) = &axis[2][g[2]];
        let start = cols.len();
        let mut wsum = 0.0;
        for (a, nu) in bu.iter().enumerate() {
            for (b, nv) in bv.iter().enumerate() {
                for (c, nw) in bw.iter().enumerate() {
                    let idx = ((i0 + a) * dims[1] + j0 + b) * dims[2] + k0 + c;
                    let w = nu * nv * nw * weights[idx];
                    wsum += w;
                    cols.push(idx as u32);
                    vals.push(w);
                }
            }
        }
        for v in &mut vals[start..] {
            *v /= wsum;
        }
        rp.push(cols.len());
    }
    let b = SparseMatrix::from_csr(grid.len(), n, rp, cols, vals);
    data.set_points(b.apply(p));
    // Data cell -> control net cell by parameter position of the cell centre.
    let cells = dims.map(|d| d.saturating_sub(1).max(1));
    let mut cell_parent = Vec::with_capacity(data.num_cells());
    for c in 0..data.num_cells() {
        let vs = data.cell_vertices(CellId::new(c));
        let mut centre = [0.0; 3];
        for v in vs {
            for a in 0..3 {
                centre[a] += grid[v.index()][a] as f64 / vs.len() as f64;
            }
        }
        let idx: [usize; 3] = std::array::from_fn(|a| {
            let t = centre[a] / (samples[a] - 1) as f64;
            ((t * cells[a] as f64) as usize).min(cells[a] - 1)
        });
        cell_parent.push(((idx[0] * cells[1] + idx[1]) * cells[2] + idx[2]) as u32);
    }
    let order = (0..data.num_points() as u32).collect();
    Ok(Discretization {
        map: SubdivisionMap::new(vec![b]),
        data,
        cell_parent,
        order,
        numbering: DataNumbering::Locality,
    })
}
