//! Lattices from meshes: a hexahedral control lattice whose subdivided boundary follows a closed
//! triangle mesh ("any shape as virtual clay", issue 19).
//!
//! # What
//! [`lattice_from_mesh`] takes a closed, consistently oriented triangle mesh and returns a
//! [`SubdivisionSolid`] of about [`ClayParams::cells`] hexahedra whose level-`L` boundary surface
//! lies close to the mesh, with a [`ClayReport`] (cell count, smallest cell volume, distances).
//!
//! # How
//! 1. **Check** ([`check_mesh`]): exact duplicate positions are welded; every undirected edge
//!    must be used by exactly two triangles, once in each direction. An edge in one triangle
//!    (open mesh), in three or more (non-manifold) or twice in the same direction (inconsistent
//!    orientation) is a [`ClayError`] naming the edges and triangles. A mesh of negative volume
//!    (consistently inside out) is flipped.
//! 2. **Voxelize**: a grid of cubes of side `h = (V / N)^(1/3)` (`V` the enclosed volume by the
//!    divergence theorem), rescaled up to three times by `(count / N)^(1/3)`; a voxel is inside
//!    when the winding number of the mesh at its centre is non-zero (one ray per grid row along
//!    `x`; point-in-triangle tests in the `yz` projection break ties by simulation of simplicity,
//!    so a ray through an edge or a vertex counts once).
//! 3. **Repair**: the voxel set is made *well-composed* (Latecki 1997): in every `2x2x2` block of
//!    voxels the filled and the empty voxels are each face-connected inside the block, which is
//!    exactly the condition for the boundary of the union of cubes to be a 2-manifold (no two
//!    cells touching by an edge or a vertex alone). A bad block gets the empty voxel with the
//!    most filled neighbours filled, until no bad block remains (filling only, so it ends).
//!    Voxels with at most two filled face neighbours (fins and spikes one cell thick, four or
//!    more boundary faces) are emptied and the repair repeated: fitted, such cells come out too
//!    thin for their subdivided cells to stay positive. Then the largest face-connected
//!    component is kept and enclosed voids are filled.
//! 4. **Fit the boundary**: with the smooth and sharp rules the level-`L` boundary points depend
//!    on the boundary control points alone (the Catmull-Clark surface rules, see
//!    [`crate::subdivide`](mod@crate::subdivide)), so `d_b = B x` with `B` the product of the level operators
//!    restricted to boundary rows and columns (`subdivision-solids-journal.txt` eq 4,
//!    `d = A p`). Each iteration finds for every `d_i` its closest point `c_i` on the mesh (a
//!    bounding-volume hierarchy) with the triangle normal `n_i` and solves for the update
//!    `delta` of the boundary control points
//!
//!    `min sum_i (B delta - r)_i^T W_i (B delta - r)_i + lambda |L delta|^2 + eps |delta|^2`,
//!    `r_i = c_i - d_i`, `W_i = n_i n_i^T + mu (I - n_i n_i^T)`,
//!
//!    (point-to-plane with a weak tangential pull `mu`, an umbrella Laplacian `L` of the control
//!    boundary surface keeping the update smooth, `lambda` and `eps` scaled by the mean diagonal
//!    of `B^T B`) by Jacobi-preconditioned conjugate gradients.
//! 5. **Place the interior**: the interior control points move by the harmonic extension of the
//!    boundary displacement (graph Laplacian over the lattice edges, boundary fixed), which keeps
//!    the grid's cells positive while the displacement is small against the cell size. If a cell
//!    of any level `0..=L` is not positive, the fit is repeated from the voxels with `lambda`
//!    times [`REFIT_FACTOR`] (at most [`MAX_REFITS`] times); the report says how often and what
//!    remains.
//!
//! On a sphere and a torus of 100,000 triangles at 2,000 cells this gives 0.004 % mean and
//! 0.03 % maximum distance (of the bounding-box diagonal) in under a second
//! (`docs/performance.md`, "Lattices from meshes"; the plain voxel lattice: 0.5 % and 1.6 %).
//!
//! # Limitations
//! Self-intersecting input is not detected: the voxelization takes the union (non-zero winding).
//! Inner shells (voids) are filled; only the largest piece of a mesh with several components is
//! kept. The lattice is a pure hexahedral grid, so features thinner than about two cells are lost
//! or thickened; sharp edges of the input are rounded (the sharp rule makes crease edges of the
//! voxel staircase, not of the input). Distances are measured at the level-`L` vertices (lattice
//! to mesh) and at the input vertices (mesh to the level-`L` triangles).

use std::fmt;

use rayon::prelude::*;
use thiserror::Error;
use vclay_core::mesh::closest_on_triangle;
use vclay_core::{MeshError, Parallelism, TriMesh, Vec3};

use crate::boundary::boundary_mesh;
use crate::error::LatticeError;
use crate::hierarchy::SubdivisionSolid;
use crate::ids::{CellId, EdgeId};
use crate::lattice::Lattice;
use crate::primitives::voxel_lattice;
use crate::sparse::SparseMatrix;
use crate::subdivide::{BoundaryRule, Features, SubdivisionRules};

/// Default of [`ClayParams::cells`]: 2,000 cells.
pub const DEFAULT_CELLS: usize = 2000;
/// Default of [`ClayParams::levels`]: 2 levels.
pub const DEFAULT_LEVELS: usize = 2;
/// Largest accepted [`ClayParams::cells`]: 200,000.
pub const MAX_CELLS: usize = 200_000;
/// Largest accepted [`ClayParams::levels`]: 4.
pub const MAX_LEVELS: usize = 4;
/// Largest accepted `cells * 8^levels` (cells of the finest level): 20 million.
pub const MAX_FINEST_CELLS: u128 = 20_000_000;
/// Default of [`ClayParams::iterations`]: 8 closest-point and solve rounds.
pub const DEFAULT_ITERATIONS: usize = 8;
/// Default of [`ClayParams::smoothness`]: 0.05.
pub const DEFAULT_SMOOTHNESS: f64 = 0.05;
/// Default of [`ClayParams::tangential`]: 0.1.
pub const DEFAULT_TANGENTIAL: f64 = 0.1;
/// Default of [`ClayParams::damping`]: 0.001.
pub const DEFAULT_DAMPING: f64 = 1e-3;
/// Fits repeated with a larger smoothness when a cell at some level is not positive: 3.
pub const MAX_REFITS: usize = 3;
/// Factor on the smoothness at each refit: 4.
pub const REFIT_FACTOR: f64 = 4.0;
/// Smallest smoothness of a refit (when [`ClayParams::smoothness`] is 0): 0.05.
pub const REFIT_FLOOR: f64 = 0.05;
/// Conjugate-gradient iterations per solve, at most: 500.
const CG_MAX_ITERATIONS: usize = 500;
/// Relative residual at which a conjugate-gradient solve stops: 1e-6.
const CG_TOLERANCE: f64 = 1e-6;
/// Rounds of spike removal and well-composed repair, at most: 8.
const SPIKE_ROUNDS: usize = 8;
/// Faulty edges listed in a [`ClayError`] (the count names all of them).
pub const LISTED_FAULTS: usize = 8;

/// Parameters of [`lattice_from_mesh`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClayParams {
    /// Wanted number of cells (the result is within a few per cent). Default [`DEFAULT_CELLS`];
    /// at most [`MAX_CELLS`].
    pub cells: usize,
    /// Subdivision level `L` whose boundary is fitted. Default [`DEFAULT_LEVELS`]; at most
    /// [`MAX_LEVELS`].
    pub levels: usize,
    /// Boundary rule, smooth or sharp ([`BoundaryRule::Interior`] is refused: its boundary
    /// depends on interior points). Default [`BoundaryRule::Smooth`].
    pub boundary: BoundaryRule,
    /// Closest-point and solve rounds. Default [`DEFAULT_ITERATIONS`].
    pub iterations: usize,
    /// Weight `lambda` of the Laplacian of the update, relative to the data term. Default
    /// [`DEFAULT_SMOOTHNESS`].
    pub smoothness: f64,
    /// Weight `mu` of the tangential part of each residual. Default [`DEFAULT_TANGENTIAL`].
    pub tangential: f64,
    /// Weight `eps` of `|delta|^2`, relative to the data term. Default [`DEFAULT_DAMPING`].
    pub damping: f64,
    /// Thread use. Default [`Parallelism::Auto`].
    pub parallelism: Parallelism,
}

impl Default for ClayParams {
    fn default() -> Self {
        Self {
            cells: DEFAULT_CELLS,
            levels: DEFAULT_LEVELS,
            boundary: BoundaryRule::Smooth,
            iterations: DEFAULT_ITERATIONS,
            smoothness: DEFAULT_SMOOTHNESS,
            tangential: DEFAULT_TANGENTIAL,
            damping: DEFAULT_DAMPING,
            parallelism: Parallelism::Auto,
        }
    }
}

/// An edge of the input mesh at fault and the triangles using it.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeFault {
    /// First end vertex (input index).
    pub a: u32,
    /// Second end vertex (input index).
    pub b: u32,
    /// Position of `a`.
    pub pa: Vec3,
    /// Position of `b`.
    pub pb: Vec3,
    /// Input indices of the triangles using the edge.
    pub triangles: Vec<usize>,
}

impl fmt::Display for EdgeFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "edge ({}, {}) from ({}, {}, {}) to ({}, {}, {}) in triangles {:?}",
            self.a,
            self.b,
            self.pa.x,
            self.pa.y,
            self.pa.z,
            self.pb.x,
            self.pb.y,
            self.pb.z,
            self.triangles
        )
    }
}

/// A list of faults, printed `; `-separated.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeFaults(pub Vec<EdgeFault>);

impl fmt::Display for EdgeFaults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str("; ")?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

/// Why [`lattice_from_mesh`] refused its input or failed.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ClayError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// Non-finite coordinates or out-of-range indices.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A triangle uses one vertex (or one position) twice.
    #[error("triangle {triangle} {vertices:?} is degenerate: it uses a vertex position twice")]
    DegenerateTriangle {
        /// Input index of the triangle.
        triangle: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
    },
    /// Edges used by one triangle only: the mesh has holes.
    #[error("the mesh is open: {count} edges are used by one triangle only, e.g. {first}")]
    Open {
        /// Number of such edges.
        count: usize,
        /// The first [`LISTED_FAULTS`] of them.
        first: EdgeFaults,
    },
    /// Edges used by three or more triangles.
    #[error(
        "the mesh is non-manifold: {count} edges are used by three or more triangles, e.g. {first}"
    )]
    NonManifold {
        /// Number of such edges.
        count: usize,
        /// The first [`LISTED_FAULTS`] of them.
        first: EdgeFaults,
    },
    /// Edges traversed twice in the same direction: neighbouring triangles face opposite ways.
    #[error(
        "the mesh is not consistently oriented: {count} edges are traversed twice in the same direction, e.g. {first}"
    )]
    Orientation {
        /// Number of such edges.
        count: usize,
        /// The first [`LISTED_FAULTS`] of them.
        first: EdgeFaults,
    },
    /// The enclosed volume is zero (a flat or self-cancelling mesh).
    #[error("the mesh encloses no volume")]
    NoVolume,
    /// A parameter is out of range.
    #[error("{name} = {value} is out of range ({range})")]
    Parameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: String,
        /// The accepted range.
        range: String,
    },
    /// No voxel centre lies inside the mesh.
    #[error("no grid cell of size {cell_size:e} lies inside the mesh")]
    NothingInside {
        /// The cell size tried last.
        cell_size: f64,
    },
    /// The lattice could not be built or subdivided (a bug if it happens).
    #[error("lattice: {0}")]
    Lattice(#[from] LatticeError),
}

/// Mean and maximum of a set of distances, relative to the input's bounding-box diagonal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DistanceStats {
    /// Mean distance / diagonal.
    pub mean: f64,
    /// Maximum distance / diagonal.
    pub max: f64,
}

/// What [`lattice_from_mesh`] built and how well it fits.
#[derive(Clone, Debug, PartialEq)]
pub struct ClayReport {
    /// Triangles of the input.
    pub input_triangles: usize,
    /// Whether the input was inside out and was flipped.
    pub flipped: bool,
    /// Cells of the control lattice.
    pub cells: usize,
    /// Points of the control lattice.
    pub points: usize,
    /// Boundary points of the control lattice (the fitted ones).
    pub boundary_points: usize,
    /// Side of the grid cubes.
    pub cell_size: f64,
    /// Subdivision level of the fitted boundary.
    pub levels: usize,
    /// Diagonal of the input's bounding box (the distance unit).
    pub diagonal: f64,
    /// Smallest signed volume of a control cell ([`Lattice::cell_signed_volume`]).
    pub min_cell_volume: f64,
    /// Smallest signed volume of a cell at level `L`.
    pub min_cell_volume_finest: f64,
    /// Control cells with non-positive volume.
    pub folded_cells: usize,
    /// Cells at level `L` with non-positive volume.
    pub folded_cells_finest: usize,
    /// Level-`L` boundary vertices to the input, before the fit (the plain voxel lattice).
    pub voxel_distance: DistanceStats,
    /// Level-`L` boundary vertices to the input, after the fit.
    pub distance: DistanceStats,
    /// Input vertices to the level-`L` boundary triangles, after the fit.
    pub reverse_distance: DistanceStats,
    /// Conjugate-gradient iterations, all rounds together.
    pub cg_iterations: usize,
    /// The smoothness weight of the last fit ([`ClayParams::smoothness`], raised by each refit).
    pub smoothness: f64,
    /// Fits repeated with a larger smoothness because a cell at some level was not positive.
    pub refits: usize,
}

impl ClayReport {
    /// The report as a JSON object (one line).
    pub fn to_json(&self) -> String {
        let d = |s: DistanceStats| format!("{{\"mean\": {:e}, \"max\": {:e}}}", s.mean, s.max);
        format!(
            "{{\"input_triangles\": {}, \"flipped\": {}, \"cells\": {}, \"points\": {}, \
             \"boundary_points\": {}, \"cell_size\": {:e}, \"levels\": {}, \"diagonal\": {:e}, \
             \"min_cell_volume\": {:e}, \"min_cell_volume_finest\": {:e}, \"folded_cells\": {}, \
             \"folded_cells_finest\": {}, \"voxel_distance\": {}, \"distance\": {}, \
             \"reverse_distance\": {}, \"cg_iterations\": {}, \"smoothness\": {}, \"refits\": {}}}",
            self.input_triangles,
            self.flipped,
            self.cells,
            self.points,
            self.boundary_points,
            self.cell_size,
            self.levels,
            self.diagonal,
            self.min_cell_volume,
            self.min_cell_volume_finest,
            self.folded_cells,
            self.folded_cells_finest,
            d(self.voxel_distance),
            d(self.distance),
            d(self.reverse_distance),
            self.cg_iterations,
            self.smoothness,
            self.refits
        )
    }
}

/// The result of [`lattice_from_mesh`].
#[derive(Clone, Debug)]
pub struct Clay {
    /// The fitted solid: control lattice (level 0) and its subdivision to level `L`.
    pub solid: SubdivisionSolid,
    /// Sizes and fit figures.
    pub report: ClayReport,
}

// ---------------------------------------------------------------------------------------------
// Mesh check
// ---------------------------------------------------------------------------------------------

/// A checked input: welded positions, triangles (outward), and each welded vertex's input index.
#[derive(Clone, Debug)]
pub struct CheckedMesh {
    /// Triangles as corner positions, counter-clockwise seen from outside.
    pub triangles: Vec<[Vec3; 3]>,
    /// Distinct vertex positions.
    pub vertices: Vec<Vec3>,
    /// Whether the triangles were reversed (the input was inside out).
    pub flipped: bool,
    /// Enclosed volume (positive).
    pub volume: f64,
}

/// Checks that `mesh` is a closed, oriented 2-manifold (see the [module docs](self)).
pub fn check_mesh(mesh: &TriMesh) -> Result<CheckedMesh, ClayError> {
    mesh.validate()?;
    if mesh.triangles.is_empty() {
        return Err(ClayError::Empty);
    }
    // Weld exact duplicates; each welded vertex keeps its smallest input index.
    let mut order: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    let key = |i: u32| {
        let p = mesh.positions[i as usize];
        [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
    };
    order.sort_by_key(|&i| (key(i), i));
    let mut weld = vec![0u32; mesh.positions.len()];
    let mut rep = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        if k == 0 || key(order[k - 1]) != key(i) {
            rep.push(i);
        }
        weld[i as usize] = rep[rep.len() - 1];
    }
    let mut edges: Vec<(u32, u32, bool, usize)> = Vec::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let w = tri.map(|i| weld[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[2] == w[0] {
            return Err(ClayError::DegenerateTriangle {
                triangle: t,
                vertices: *tri,
            });
        }
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), a < b, t));
        }
    }
    edges.sort_unstable();
    let (mut open, mut nonmanifold, mut orient) = (Vec::new(), Vec::new(), Vec::new());
    let (mut n_open, mut n_nm, mut n_or) = (0, 0, 0);
    let mut s = 0;
    while s < edges.len() {
        let mut e = s + 1;
        while e < edges.len() && edges[e].0 == edges[s].0 && edges[e].1 == edges[s].1 {
            e += 1;
        }
        let fault = || EdgeFault {
            a: edges[s].0,
            b: edges[s].1,
            pa: mesh.positions[edges[s].0 as usize],
            pb: mesh.positions[edges[s].1 as usize],
            triangles: edges[s..e].iter().map(|x| x.3).collect(),
        };
        match e - s {
            1 => {
                n_open += 1;
                if open.len() < LISTED_FAULTS {
                    open.push(fault());
                }
            }
            2 => {
                if edges[s].2 == edges[s + 1].2 {
                    n_or += 1;
                    if orient.len() < LISTED_FAULTS {
                        orient.push(fault());
                    }
                }
            }
            _ => {
                n_nm += 1;
                if nonmanifold.len() < LISTED_FAULTS {
                    nonmanifold.push(fault());
                }
            }
        }
        s = e;
    }
    if n_open > 0 {
        return Err(ClayError::Open {
            count: n_open,
            first: EdgeFaults(open),
        });
    }
    if n_nm > 0 {
        return Err(ClayError::NonManifold {
            count: n_nm,
            first: EdgeFaults(nonmanifold),
        });
    }
    if n_or > 0 {
        return Err(ClayError::Orientation {
            count: n_or,
            first: EdgeFaults(orient),
        });
    }
    let mut triangles: Vec<[Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let centre = triangles[0][0];
    let volume: f64 = triangles
        .iter()
        .map(|[a, b, c]| (a - centre).dot(&(b - centre).cross(&(c - centre))) / 6.0)
        .sum();
    let (lo, hi) = mesh.bounding_box().expect("non-empty");
    let scale = (hi - lo).norm();
    if volume.is_nan() || volume.abs() <= 1e-12 * scale * scale * scale {
        return Err(ClayError::NoVolume);
    }
    let flipped = volume < 0.0;
    if flipped {
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    Ok(CheckedMesh {
        triangles,
        vertices: rep.iter().map(|&i| mesh.positions[i as usize]).collect(),
        flipped,
        volume: volume.abs(),
    })
}

// ---------------------------------------------------------------------------------------------
// Closest points
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
struct BvhNode {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first triangle in `order`; inner: index of the left child (right is `+ 1`).
    start: u32,
    /// Leaf: number of triangles; inner: 0.
    count: u32,
}

/// A bounding-volume hierarchy over triangles for closest-point queries (median splits on the
/// longest axis, leaves of at most 4 triangles).
struct Bvh {
    nodes: Vec<BvhNode>,
    tris: Vec<[Vec3; 3]>,
}

impl Bvh {
    fn new(tris: &[[Vec3; 3]]) -> Self {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let centroids: Vec<Vec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = vec![BvhNode {
            lo: Vec3::zeros(),
            hi: Vec3::zeros(),
            start: 0,
            count: 0,
        }];
        let mut stack = vec![(0usize, 0usize, tris.len())];
        while let Some((n, s, e)) = stack.pop() {
            let mut lo = Vec3::repeat(f64::INFINITY);
            let mut hi = Vec3::repeat(f64::NEG_INFINITY);
            for &t in &order[s..e] {
                for v in &tris[t as usize] {
                    lo = lo.inf(v);
                    hi = hi.sup(v);
                }
            }
            nodes[n].lo = lo;
            nodes[n].hi = hi;
            if e - s <= 4 {
                nodes[n].start = s as u32;
                nodes[n].count = (e - s) as u32;
                continue;
            }
            let ext = hi - lo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (s + e) / 2;
            order[s..e].select_nth_unstable_by(mid - s, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = nodes.len();
            nodes[n].start = left as u32;
            nodes[n].count = 0;
            let empty = nodes[n];
            nodes.push(empty);
            nodes.push(empty);
            stack.push((left, s, mid));
            stack.push((left + 1, mid, e));
        }
        Self {
            nodes,
            tris: order.iter().map(|&t| tris[t as usize]).collect(),
        }
    }

    fn box_distance2(n: &BvhNode, p: Vec3) -> f64 {
        let d = (n.lo - p).sup(&(p - n.hi)).sup(&Vec3::zeros());
        d.norm_squared()
    }

    /// Closest point on the triangles to `p` and the index (in `self.tris`) of its triangle.
    fn closest(&self, p: Vec3) -> (Vec3, usize) {
        let mut best = (f64::INFINITY, p, 0usize);
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if Self::box_distance2(node, p) >= best.0 {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                for t in s..s + node.count as usize {
                    let q = closest_on_triangle(p, self.tris[t]);
                    let d2 = (q - p).norm_squared();
                    if d2 < best.0 {
                        best = (d2, q, t);
                    }
                }
            } else {
                let (l, r) = (node.start, node.start + 1);
                let dl = Self::box_distance2(&self.nodes[l as usize], p);
                let dr = Self::box_distance2(&self.nodes[r as usize], p);
                // Visit the nearer child first (pushed last).
                if dl < dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        (best.1, best.2)
    }

    fn normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.tris[t];
        (b - a).cross(&(c - a)).normalize()
    }
}

fn distances(bvh: &Bvh, points: &[Vec3], diagonal: f64) -> DistanceStats {
    if points.is_empty() {
        return DistanceStats::default();
    }
    let d: Vec<f64> = points
        .par_iter()
        .map(|&p| (bvh.closest(p).0 - p).norm())
        .collect();
    DistanceStats {
        mean: d.iter().sum::<f64>() / d.len() as f64 / diagonal,
        max: d.iter().fold(0.0f64, |m, &x| m.max(x)) / diagonal,
    }
}

// ---------------------------------------------------------------------------------------------
// Voxelization
// ---------------------------------------------------------------------------------------------

/// A voxel grid: `dims` cubes of side `h` from `origin`, index `(k * ny + j) * nx + i`.
#[derive(Clone, Debug)]
struct Grid {
    origin: Vec3,
    h: f64,
    dims: [usize; 3],
    filled: Vec<bool>,
}

impl Grid {
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.dims[1] + j) * self.dims[0] + i
    }
    fn coords(&self, v: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [v % nx, (v / nx) % ny, v / (nx * ny)]
    }
    fn count(&self) -> usize {
        self.filled.iter().filter(|&&f| f).count()
    }
    /// Face neighbours of voxel `v` inside the grid.
    fn neighbours(&self, v: usize, out: &mut Vec<usize>) {
        out.clear();
        let [i, j, k] = self.coords(v);
        let [nx, ny, nz] = self.dims;
        if i > 0 {
            out.push(v - 1);
        }
        if i + 1 < nx {
            out.push(v + 1);
        }
        if j > 0 {
            out.push(v - nx);
        }
        if j + 1 < ny {
            out.push(v + nx);
        }
        if k > 0 {
            out.push(v - nx * ny);
        }
        if k + 1 < nz {
            out.push(v + nx * ny);
        }
    }
}

/// Sign of the orientation of `p` against the directed line `a -> b` in the `yz` plane, with
/// `p` perturbed by `(eps, eps^2)` (simulation of simplicity) so that it is never zero unless
/// `a == b` in projection; antisymmetric in `a, b` to the last bit.
fn orient_sos(a: Vec3, b: Vec3, p: (f64, f64)) -> i8 {
    let (a, b, flip) = if (a.y, a.z) <= (b.y, b.z) {
        (a, b, 1)
    } else {
        (b, a, -1)
    };
    let w = (b.y - a.y) * (p.1 - a.z) - (b.z - a.z) * (p.0 - a.y);
    let s = if w > 0.0 {
        1
    } else if w < 0.0 {
        -1
    } else if b.z != a.z {
        if b.z > a.z { -1 } else { 1 }
    } else if b.y != a.y {
        if b.y > a.y { 1 } else { -1 }
    } else {
        0
    };
    s * flip
}

/// Fills the voxels whose centres have non-zero winding number.
fn voxelize(tris: &[[Vec3; 3]], origin: Vec3, h: f64, dims: [usize; 3]) -> Grid {
    let [nx, ny, nz] = dims;
    let mut rows: Vec<Vec<(f64, i32)>> = vec![Vec::new(); ny * nz];
    for &[a, b, c] in tris {
        let n = (b - a).cross(&(c - a));
        let area = (b.y - a.y) * (c.z - a.z) - (b.z - a.z) * (c.y - a.y);
        if area == 0.0 {
            continue;
        }
        let s: i8 = if area > 0.0 { 1 } else { -1 };
        let lo = a.inf(&b).inf(&c);
        let hi = a.sup(&b).sup(&c);
        let j0 = (((lo.y - origin.y) / h - 0.5).ceil().max(0.0)) as usize;
        let j1 = (((hi.y - origin.y) / h - 0.5).floor().min(ny as f64 - 1.0)) as isize;
        let k0 = (((lo.z - origin.z) / h - 0.5).ceil().max(0.0)) as usize;
        let k1 = (((hi.z - origin.z) / h - 0.5).floor().min(nz as f64 - 1.0)) as isize;
        for k in k0 as isize..=k1 {
            let z = origin.z + (k as f64 + 0.5) * h;
            for j in j0 as isize..=j1 {
                let y = origin.y + (j as f64 + 0.5) * h;
                let p = (y, z);
                if orient_sos(a, b, p) == s && orient_sos(b, c, p) == s && orient_sos(c, a, p) == s
                {
                    let x = a.x - (n.y * (y - a.y) + n.z * (z - a.z)) / n.x;
                    // An outward normal facing -x means the ray enters the solid here.
                    rows[k as usize * ny + j as usize].push((x, -(s as i32)));
                }
            }
        }
    }
    let mut filled = vec![false; nx * ny * nz];
    for (r, row) in rows.iter_mut().enumerate() {
        row.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut w = 0;
        let mut c = 0;
        for i in 0..nx {
            let x = origin.x + (i as f64 + 0.5) * h;
            while c < row.len() && row[c].0 < x {
                w += row[c].1;
                c += 1;
            }
            filled[r * nx + i] = w != 0;
        }
    }
    Grid {
        origin,
        h,
        dims,
        filled,
    }
}

/// `GOOD[mask]`: whether the filled voxels (bits of `mask`, bit `dx + 2 dy + 4 dz`) and the empty
/// ones of a `2x2x2` block are each face-connected inside the block.
fn good_blocks() -> [bool; 256] {
    let connected = |set: u8| -> bool {
        if set == 0 {
            return true;
        }
        let start = set.trailing_zeros() as u8;
        let mut seen = 1u8 << start;
        let mut stack = vec![start];
        while let Some(v) = stack.pop() {
            for bit in [1u8, 2, 4] {
                let w = v ^ bit;
                if set & (1 << w) != 0 && seen & (1 << w) == 0 {
                    seen |= 1 << w;
                    stack.push(w);
                }
            }
        }
        seen == set
    };
    let mut good = [false; 256];
    for (m, g) in good.iter_mut().enumerate() {
        *g = connected(m as u8) && connected(!(m as u8));
    }
    good
}

/// Makes the filled set well-composed by filling voxels (see the [module docs](self)). Blocks are
/// named by their lowest voxel; the outermost grid layer is never filled.
fn make_well_composed(g: &mut Grid) {
    let good = good_blocks();
    let [nx, ny, nz] = g.dims;
    let block = |g: &Grid, b: usize| -> (u8, [usize; 8]) {
        let [i, j, k] = g.coords(b);
        let mut mask = 0u8;
        let mut vox = [0usize; 8];
        for (bit, v) in vox.iter_mut().enumerate() {
            *v = g.index(i + (bit & 1), j + ((bit >> 1) & 1), k + ((bit >> 2) & 1));
            if g.filled[*v] {
                mask |= 1 << bit;
            }
        }
        (mask, vox)
    };
    let mut queue: Vec<usize> = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                queue.push(g.index(i, j, k));
            }
        }
    }
    let mut nb = Vec::new();
    while let Some(b) = queue.pop() {
        let (mask, vox) = block(g, b);
        if good[mask as usize] {
            continue;
        }
        // The empty voxel of the block with the most filled neighbours in the block, then in
        // the grid.
        let mut best: Option<(usize, usize, usize)> = None;
        for bit in 0..8 {
            if mask & (1 << bit) != 0 {
                continue;
            }
            let [i, j, k] = g.coords(vox[bit]);
            if i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1 {
                continue;
            }
            let inblock = [1, 2, 4]
                .iter()
                .filter(|&&f| mask & (1 << (bit ^ f)) != 0)
                .count();
            g.neighbours(vox[bit], &mut nb);
            let around = nb.iter().filter(|&&w| g.filled[w]).count();
            if best.is_none_or(|(bi, ba, _)| (inblock, around) > (bi, ba)) {
                best = Some((inblock, around, vox[bit]));
            }
        }
        let Some((_, _, v)) = best else { continue };
        g.filled[v] = true;
        let [i, j, k] = g.coords(v);
        for dk in 0..2 {
            for dj in 0..2 {
                for di in 0..2 {
                    if i >= di
                        && j >= dj
                        && k >= dk
                        && i - di < nx - 1
                        && j - dj < ny - 1
                        && k - dk < nz - 1
                    {
                        queue.push(g.index(i - di, j - dj, k - dk));
                    }
                }
            }
        }
    }
}

/// Empties the filled voxels with at most two filled face neighbours (cells with four or more
/// boundary faces: fins and spikes one cell thick, whose fitted control cells come out too thin
/// for the subdivided cells to stay positive); returns how many.
fn remove_spikes(g: &mut Grid) -> usize {
    let mut nb = Vec::new();
    let spikes: Vec<usize> = (0..g.filled.len())
        .filter(|&v| {
            g.filled[v] && {
                g.neighbours(v, &mut nb);
                nb.iter().filter(|&&w| g.filled[w]).count() <= 2
            }
        })
        .collect();
    for &v in &spikes {
        g.filled[v] = false;
    }
    spikes.len()
}

/// Face-connected components of the voxels with `filled[v] == value`: labels (`u32::MAX` for
/// the others) and sizes.
fn components(g: &Grid, value: bool) -> (Vec<u32>, Vec<usize>) {
    let mut label = vec![u32::MAX; g.filled.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    let mut nb = Vec::new();
    for s in 0..g.filled.len() {
        if g.filled[s] != value || label[s] != u32::MAX {
            continue;
        }
        let id = sizes.len() as u32;
        label[s] = id;
        stack.push(s);
        let mut size = 0;
        while let Some(v) = stack.pop() {
            size += 1;
            g.neighbours(v, &mut nb);
            for &w in &nb {
                if g.filled[w] == value && label[w] == u32::MAX {
                    label[w] = id;
                    stack.push(w);
                }
            }
        }
        sizes.push(size);
    }
    (label, sizes)
}

/// Keeps the largest face-connected piece and fills enclosed voids.
fn keep_largest(g: &mut Grid) {
    let (label, sizes) = components(g, true);
    if let Some(big) = (0..sizes.len()).max_by_key(|&c| sizes[c]) {
        for (f, &l) in g.filled.iter_mut().zip(&label) {
            *f = l == big as u32;
        }
    }
    // Voxel 0 is in the (empty) outer layer: every other empty component is a void.
    let (label, _) = components(g, false);
    let outside = label[0];
    for (f, &l) in g.filled.iter_mut().zip(&label) {
        if l != u32::MAX && l != outside {
            *f = true;
        }
    }
}

/// The grid for about `cells` cells inside `mesh`: well-composed, one piece, no voids.
fn grid_for(mesh: &CheckedMesh, cells: usize) -> Result<Grid, ClayError> {
    let (lo, hi) = mesh
        .vertices
        .iter()
        .fold((mesh.vertices[0], mesh.vertices[0]), |(l, h), p| {
            (l.inf(p), h.sup(p))
        });
    let centre = (lo + hi) / 2.0;
    let mut h = (mesh.volume / cells as f64).cbrt();
    let mut best: Option<Grid> = None;
    for _ in 0..4 {
        let dims = ((hi - lo) / h).map(|e| e.ceil() as usize + 4);
        let dims = [dims.x, dims.y, dims.z];
        let origin = centre - Vec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * h / 2.0;
        let g = voxelize(&mesh.triangles, origin, h, dims);
        let count = g.count();
        let err = |c: usize| (c as f64 / cells as f64).ln().abs();
        if count > 0 && best.as_ref().is_none_or(|b| err(count) < err(b.count())) {
            best = Some(g);
        }
        if count == 0 {
            h /= 2.0;
            continue;
        }
        if err(count) < 0.01 {
            break;
        }
        h *= (count as f64 / cells as f64).cbrt();
    }
    let Some(mut g) = best else {
        return Err(ClayError::NothingInside { cell_size: h });
    };
    for _ in 0..SPIKE_ROUNDS {
        make_well_composed(&mut g);
        if remove_spikes(&mut g) == 0 {
            break;
        }
    }
    make_well_composed(&mut g);
    keep_largest(&mut g);
    if g.count() == 0 {
        return Err(ClayError::NothingInside { cell_size: g.h });
    }
    Ok(g)
}

// ---------------------------------------------------------------------------------------------
// Fitting
// ---------------------------------------------------------------------------------------------

/// Compact indices of the boundary points of `lattice` (`u32::MAX` for interior points) and
/// the list of boundary point ids.
fn boundary_points(lattice: &Lattice) -> (Vec<u32>, Vec<u32>) {
    let mut compact = vec![u32::MAX; lattice.num_points()];
    for f in lattice.boundary_faces() {
        for &v in lattice.face_vertices(f) {
            compact[v.index()] = 0;
        }
    }
    let mut list = Vec::new();
    for (v, c) in compact.iter_mut().enumerate() {
        if *c == 0 {
            *c = list.len() as u32;
            list.push(v as u32);
        }
    }
    (compact, list)
}

/// `B`: the level operators restricted to boundary rows and columns, multiplied out.
fn boundary_operator(solid: &SubdivisionSolid) -> Result<SparseMatrix, ClayError> {
    let (mut compact, list) = boundary_points(solid.control());
    let mut b = SparseMatrix::identity(list.len());
    for j in 0..solid.levels() {
        let (fine_compact, fine_list) = boundary_points(solid.lattice(j + 1));
        let op = solid.map().operator(j).select_rows(&fine_list);
        let mut row_ptr = vec![0usize];
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for r in 0..op.nrows() {
            let (c, v) = op.row(r);
            for (&c, &v) in c.iter().zip(v) {
                let k = compact[c as usize];
                if k == u32::MAX {
                    return Err(LatticeError::Invariant {
                        element: format!("level {} point {}", j + 1, fine_list[r]),
                        message: "a boundary point depends on an interior point".into(),
                    }
                    .into());
                }
                cols.push(k);
                vals.push(v);
            }
            row_ptr.push(cols.len());
        }
        let restricted = SparseMatrix::from_csr(op.nrows(), b.nrows(), row_ptr, cols, vals);
        b = restricted.mul(&b);
        compact = fine_compact;
    }
    Ok(b)
}

/// Umbrella Laplacian of the boundary control surface: `(L x)_k = x_k - mean of neighbours`.
fn boundary_laplacian(control: &Lattice, compact: &[u32], n: usize) -> SparseMatrix {
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (e, &[a, b]) in control.edges().iter().enumerate() {
        if control.is_boundary_edge(EdgeId::new(e)) {
            let (ka, kb) = (compact[a.index()], compact[b.index()]);
            nbrs[ka as usize].push(kb);
            nbrs[kb as usize].push(ka);
        }
    }
    let mut row_ptr = vec![0usize];
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for (k, nb) in nbrs.iter_mut().enumerate() {
        nb.push(k as u32);
        nb.sort_unstable();
        nb.dedup();
        let w = -1.0 / (nb.len() - 1).max(1) as f64;
        for &j in nb.iter() {
            cols.push(j);
            vals.push(if j as usize == k { 1.0 } else { w });
        }
        row_ptr.push(cols.len());
    }
    SparseMatrix::from_csr(n, n, row_ptr, cols, vals)
}

/// Jacobi-preconditioned conjugate gradients on `Vec3` unknowns for the SPD operator `apply`;
/// returns the iterations used.
fn pcg(
    apply: &dyn Fn(&[Vec3], &mut [Vec3]),
    rhs: &[Vec3],
    inv_diag: &[f64],
    x: &mut [Vec3],
    max_iter: usize,
    tol: f64,
) -> usize {
    let n = rhs.len();
    let dot = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(p, q)| p.dot(q)).sum::<f64>();
    let mut ax = vec![Vec3::zeros(); n];
    apply(x, &mut ax);
    let mut r: Vec<Vec3> = rhs.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut z: Vec<Vec3> = r.iter().zip(inv_diag).map(|(r, d)| r * *d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let stop = tol * tol * dot(rhs, rhs).max(f64::MIN_POSITIVE);
    let mut ap = vec![Vec3::zeros(); n];
    for it in 0..max_iter {
        if dot(&r, &r) <= stop {
            return it;
        }
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            return it;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += p[i] * alpha;
            r[i] -= ap[i] * alpha;
            z[i] = r[i] * inv_diag[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + p[i] * beta;
        }
    }
    max_iter
}

/// Moves the interior points of `lattice` by the harmonic extension of the boundary
/// displacement `moved - original` (graph Laplacian over the edges); returns all points.
fn place_interior(
    lattice: &Lattice,
    orig: &[Vec3],
    moved_boundary: &[(u32, Vec3)],
) -> (Vec<Vec3>, usize) {
    let np = lattice.num_points();
    let mut u = vec![Vec3::zeros(); np];
    let mut fixed = vec![false; np];
    for &(v, p) in moved_boundary {
        u[v as usize] = p - orig[v as usize];
        fixed[v as usize] = true;
    }
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); np];
    for &[a, b] in lattice.edges() {
        nbrs[a.index()].push(b.0);
        nbrs[b.index()].push(a.0);
    }
    let interior: Vec<u32> = (0..np as u32).filter(|&v| !fixed[v as usize]).collect();
    let mut slot = vec![u32::MAX; np];
    for (k, &v) in interior.iter().enumerate() {
        slot[v as usize] = k as u32;
    }
    let rhs: Vec<Vec3> = interior
        .iter()
        .map(|&v| {
            nbrs[v as usize]
                .iter()
                .filter(|&&w| fixed[w as usize])
                .map(|&w| u[w as usize])
                .sum()
        })
        .collect();
    let inv_diag: Vec<f64> = interior
        .iter()
        .map(|&v| 1.0 / nbrs[v as usize].len() as f64)
        .collect();
    let apply = |x: &[Vec3], y: &mut [Vec3]| {
        for (k, &v) in interior.iter().enumerate() {
            let nb = &nbrs[v as usize];
            let mut s = x[k] * nb.len() as f64;
            for &w in nb {
                let sw = slot[w as usize];
                if sw != u32::MAX {
                    s -= x[sw as usize];
                }
            }
            y[k] = s;
        }
    };
    let mut x = vec![Vec3::zeros(); interior.len()];
    let iters = if interior.is_empty() {
        0
    } else {
        pcg(&apply, &rhs, &inv_diag, &mut x, 2000, 1e-10)
    };
    for (k, &v) in interior.iter().enumerate() {
        u[v as usize] = x[k];
    }
    (orig.iter().zip(&u).map(|(p, d)| p + d).collect(), iters)
}

fn volumes(lattice: &Lattice) -> (f64, usize) {
    let v: Vec<f64> = (0..lattice.num_cells())
        .into_par_iter()
        .map(|c| lattice.cell_signed_volume(CellId::new(c)))
        .collect();
    (
        v.iter().copied().fold(f64::INFINITY, f64::min),
        v.iter().filter(|&&x| x <= 0.0).count(),
    )
}

/// Builds a control lattice of about `params.cells` hexahedra inside `mesh` and fits its
/// level-`L` boundary to the mesh (see the [module docs](self) for the method).
pub fn lattice_from_mesh(mesh: &TriMesh, params: &ClayParams) -> Result<Clay, ClayError> {
    let bad = |name: &'static str, value: String, range: String| ClayError::Parameter {
        name,
        value,
        range,
    };
    if params.cells == 0 || params.cells > MAX_CELLS {
        return Err(bad(
            "cells",
            params.cells.to_string(),
            format!("1..={MAX_CELLS}"),
        ));
    }
    if params.levels > MAX_LEVELS {
        return Err(bad(
            "levels",
            params.levels.to_string(),
            format!("0..={MAX_LEVELS}"),
        ));
    }
    let finest = params.cells as u128 * 8u128.pow(params.levels as u32);
    if finest > MAX_FINEST_CELLS {
        return Err(bad(
            "cells * 8^levels",
            finest.to_string(),
            format!("at most {MAX_FINEST_CELLS}"),
        ));
    }
    if params.boundary == BoundaryRule::Interior {
        return Err(bad("boundary", "interior".into(), "smooth or sharp".into()));
    }
    for (name, v) in [
        ("smoothness", params.smoothness),
        ("tangential", params.tangential),
        ("damping", params.damping),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(name, v.to_string(), "a finite number >= 0".into()));
        }
    }
    let checked = check_mesh(mesh)?;
    let grid = grid_for(&checked, params.cells)?;
    let filled = |i: usize, j: usize, k: usize| grid.filled[grid.index(i, j, k)];
    let control = voxel_lattice(grid.dims, grid.origin, Vec3::repeat(grid.h), filled)?;
    let rules = SubdivisionRules {
        boundary: params.boundary,
        parallelism: params.parallelism,
    };
    let features = Features::none(&control);
    let mut solid = SubdivisionSolid::new(control, features, rules, params.levels)?;
    for j in 0..=params.levels {
        solid.lattice(j).build_adjacency();
    }
    let b = boundary_operator(&solid)?;
    let bt = b.transpose();
    let (compact, list) = boundary_points(solid.control());
    let lap = boundary_laplacian(solid.control(), &compact, list.len());
    let lapt = lap.transpose();

    let bvh = Bvh::new(&checked.triangles);
    let (lo, hi) = checked
        .vertices
        .iter()
        .fold((checked.vertices[0], checked.vertices[0]), |(l, h), p| {
            (l.inf(p), h.sup(p))
        });
    let diagonal = (hi - lo).norm();

    // Scale of the data term: mean diagonal of B^T B.
    let mut col2 = vec![0.0f64; list.len()];
    for (&c, &v) in b.col_indices().iter().zip(b.values()) {
        col2[c as usize] += v * v;
    }
    let scale = col2.iter().sum::<f64>() / col2.len().max(1) as f64;
    let eps = params.damping * scale;
    let mu = params.tangential;
    let mut lap_diag = vec![0.0f64; list.len()];
    for (&c, &v) in lap.col_indices().iter().zip(lap.values()) {
        lap_diag[c as usize] += v * v;
    }
    let par = params.parallelism;
    let original: Vec<Vec3> = solid.control().points().to_vec();
    let x0: Vec<Vec3> = list.iter().map(|&v| original[v as usize]).collect();
    let mut d = vec![Vec3::zeros(); b.nrows()];
    b.apply_into(&x0, &mut d, par);
    let voxel_distance = distances(&bvh, &d, diagonal);
    let mut cg_iterations = 0;
    let mut smoothness = params.smoothness;
    let mut refits = 0;
    let mut x;
    loop {
        x = x0.clone();
        let lambda = smoothness * scale;
        let inv_diag: Vec<f64> = (0..list.len())
            .map(|k| 1.0 / (col2[k] * (1.0 + 2.0 * mu) / 3.0 + lambda * lap_diag[k] + eps))
            .collect();
        for _ in 0..params.iterations {
            b.apply_into(&x, &mut d, par);
            let targets: Vec<(Vec3, Vec3)> = d
                .par_iter()
                .map(|&p| {
                    let (c, t) = bvh.closest(p);
                    (c, bvh.normal(t))
                })
                .collect();
            let weigh = |n: Vec3, r: Vec3| {
                let rn = n * n.dot(&r);
                rn + (r - rn) * mu
            };
            let wr: Vec<Vec3> = d
                .iter()
                .zip(&targets)
                .map(|(p, (c, n))| weigh(*n, c - p))
                .collect();
            let rhs = bt.apply(&wr);
            let apply = |v: &[Vec3], out: &mut [Vec3]| {
                let mut bv = vec![Vec3::zeros(); b.nrows()];
                b.apply_into(v, &mut bv, par);
                for (y, (_, n)) in bv.iter_mut().zip(&targets) {
                    *y = weigh(*n, *y);
                }
                bt.apply_into(&bv, out, par);
                let ltlv = lapt.apply(&lap.apply(v));
                for ((o, l), v) in out.iter_mut().zip(&ltlv).zip(v) {
                    *o += l * lambda + v * eps;
                }
            };
            let mut delta = vec![Vec3::zeros(); list.len()];
            cg_iterations += pcg(
                &apply,
                &rhs,
                &inv_diag,
                &mut delta,
                CG_MAX_ITERATIONS,
                CG_TOLERANCE,
            );
            for (x, dl) in x.iter_mut().zip(&delta) {
                *x += dl;
            }
        }
        let moved: Vec<(u32, Vec3)> = list.iter().copied().zip(x.iter().copied()).collect();
        let (points, _) = place_interior(solid.control(), &original, &moved);
        solid.set_control_points(points);
        let folded = (0..=params.levels).any(|j| volumes(solid.lattice(j)).1 > 0);
        if !folded || refits == MAX_REFITS {
            break;
        }
        refits += 1;
        smoothness = (smoothness * REFIT_FACTOR).max(REFIT_FLOOR);
    }
    solid.control().validate()?;

    b.apply_into(&x, &mut d, par);
    let distance = distances(&bvh, &d, diagonal);
    let surface = boundary_mesh(solid.finest());
    let surface_tris: Vec<[Vec3; 3]> = surface
        .triangles
        .iter()
        .map(|t| t.map(|i| surface.positions[i as usize]))
        .collect();
    let reverse_distance = distances(&Bvh::new(&surface_tris), &checked.vertices, diagonal);
    let (min_cell_volume, folded_cells) = volumes(solid.control());
    let (min_cell_volume_finest, folded_cells_finest) = volumes(solid.finest());
    let control = solid.control();
    let report = ClayReport {
        input_triangles: mesh.triangles.len(),
        flipped: checked.flipped,
        cells: control.num_cells(),
        points: control.num_points(),
        boundary_points: list.len(),
        cell_size: grid.h,
        levels: params.levels,
        diagonal,
        min_cell_volume,
        min_cell_volume_finest,
        folded_cells,
        folded_cells_finest,
        voxel_distance,
        distance,
        reverse_distance,
        cg_iterations,
        smoothness,
        refits,
    };
    Ok(Clay { solid, report })
}
