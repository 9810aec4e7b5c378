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
    primitives,
};
use vclay_spline::KnotVector;

use crate::error::{SolidsError, invalid};

/// Largest subdivision level accepted (level 6 of the 4^3 cube has 7.3 million data points).
pub const MAX_LEVEL: usize = 6;

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

    /// Builds the discretization with control points `p`.
    pub fn discretize(&self, p: &[Vec3]) -> Result<Discretization, SolidsError> {
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
                let order = solid.finest().locality_order();
                let data = solid
                    .finest()
                    .renumber_points(&order)
                    .map_err(SolidsError::Lattice)?;
                let mut ops = map.operators().to_vec();
                let last = ops.len() - 1;
                ops[last] = ops[last].select_rows(&order);
                Ok(Discretization {
                    map: SubdivisionMap::new(ops),
                    data,
                    cell_parent: parent,
                    order,
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
    /// [`Lattice::locality_order`] for cache-friendly passes). The identity for B-spline solids and
    /// level 0.
    pub order: Vec<u32>,
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
    })
}
