//! Limit evaluation of a subdivision solid at any `(cell, u, v, w)`.
//!
//! # What
//! The limit of MacCracken-Joy subdivision (`subdivision-solids-conference.txt` section 3.1,
//! `subdivision-solids-journal.txt` section 3.3) is the point set the levels `d^(j)` converge to.
//! [`LimitEvaluator`] gives, for a hexahedral cell of the control lattice and parameters
//! `(u, v, w)` in `[0, 1]^3`, the limit position `x(u, v, w)` and its first derivatives
//! `x_u, x_v, x_w`.
//!
//! ## Parametrization convention ([`cell_frame`])
//! The eight corners of a hexahedral cell are numbered `i + 2 j + 4 k` for the corner at
//! `(u, v, w) = (i, j, k)`:
//! * corner 0 is the cell's vertex with the smallest id;
//! * corner 1 (the `u` axis) is the neighbour of corner 0 along a cell edge with the smallest id;
//! * corners 2 and 4 (the `v` and `w` axes) are its other two edge neighbours, ordered so that
//!   `(u, v, w)` is right-handed: the cell's outward loop of the `w = 0` face runs
//!   `corner 0 -> corner 2 -> corner 3 -> corner 1`, so its outward normal is `-(x_u x x_v)`
//!   and the Jacobian `det [x_u x_v x_w]` is positive in an unfolded cell;
//! * the other corners close the hexahedron (corner 3 opposite 0 in the `w = 0` face, etc.).
//!
//! At level `j + 1` the child of a cell at corner `(i, j, k)` covers `u in [i/2, (i+1)/2]` (and
//! likewise in `v`, `w`) with the parent's axes, so the parameters are dyadic-nested and the limit
//! map is continuous across the children. `(u, v, w) = (0.5, 0.5, 0.5)` is the limit of the cell
//! point, `(0.5, 0, 0)` that of the edge point of the edge from corner 0 to corner 1.
//!
//! ## Regular cells: exact (tricubic B-spline)
//! On a regular hexahedral lattice the four rules are the tricubic B-spline refinement masks
//! (module docs of [`mod@crate::subdivide`]), so the limit over a cell is the uniform tricubic
//! B-spline of the `4 x 4 x 4` control points around it (`subdivision-solids-journal.txt` eq 1,
//! "the MacCracken-Joy scheme reduces to the tricubic B-spline on regular lattices"):
//!
//! ```text
//! x(u, v, w) = sum_{a,b,c = 0..3} B_a(u) B_b(v) B_c(w) p_abc,
//! B_0 = (1-t)^3/6, B_1 = (3t^3 - 6t^2 + 4)/6, B_2 = (-3t^3 + 3t^2 + 3t + 1)/6, B_3 = t^3/6,
//! ```
//! where `p_abc` is grid point `(a, b, c)` and the cell's corner `(i, j, k)` is `p_{1+i,1+j,1+k}`.
//! A cell is *regular* when each of its eight corners is an interior vertex with 6 edges, 12
//! faces and 8 hexahedral cells, no crease edge and no corner tag, and the `3 x 3 x 3` cells
//! around it fit together as a grid (checked while the grid is collected). Then every rule that
//! reaches the cell's children is the regular one, at every level, so the formula is exact.
//!
//! ## Other cells: local subdivision with a stated tolerance
//! Elsewhere (extraordinary vertices, crease and corner tags, **and every cell that touches the
//! boundary**: with [`crate::BoundaryRule::Smooth`]/`Sharp` the boundary surface follows the
//! Catmull-Clark surface rules, and with `Interior` the lattice shrinks, so the limit there is not
//! the tricubic B-spline of any control net) the cell is subdivided *locally*: the cells around
//! its eight corners (its one-ring, which holds every point and every classification that the
//! children's one-rings need) are copied into a small lattice, normalized to unit size (the
//! subdivision rules are affine, so this changes nothing but rounding), subdivided once, and the
//! child containing `(u, v, w)` is taken with parameters `2 (u, v, w) - (i, j, k)`. This repeats
//! until the child is regular (then the tricubic formula above is exact), or until the trilinear
//! interpolants of the child's corner points at two successive levels differ by at most
//! `tolerance x` (the bounding-box diagonal of the control points), or until `max_levels`.
//! Away from extraordinary points the control points converge to the limit like `4^-j`
//! (second order), so the returned error estimate is that difference divided by 3
//! (`|x_j - x_inf| ~ |x_j - x_{j-1}| / 3` for a ratio of 1/4). Points on the boundary, on crease
//! tags and exactly on extraordinary vertices never become regular: they stop at the tolerance.
//! Derivatives of such points are those of the trilinear interpolant of the last sub-cell (first
//! order: their error shrinks like `2^-j`).
//!
//! # Cost
//! Regular cells: their 64 control points are copied once in [`LimitEvaluator::new`] into a
//! contiguous net of 4-lane rows `(x, y, z, 0)`; an evaluation is 112 fused multiply-adds of
//! 4 lanes (an explicit AVX2/FMA kernel through `pulp::x86::V3` where the CPU has it, else the
//! same sums written as lane arithmetic and compiled by `pulp` for the best instruction set):
//! 57-69 ns of CPU per point with derivatives (`vclay bench`, key `subdivision_limit`, and
//! `examples/limit_bench.rs`; `docs/performance.md`). Other cells: one local subdivision of
//! about 30-60 cells per level (about 250 us), 10-20 levels on the boundary at the default
//! tolerance.
//!
//! # Limitations
//! Parameters address hexahedral cells only (every cell from level 1 on is one); a query in a
//! prism, tetrahedron or pyramid of the control lattice is a [`LatticeError::NotHexahedral`]:
//! subdivide once and address its children. Derivatives at points that stop at the tolerance are
//! first-order approximations; at an extraordinary vertex itself the limit parametrization may
//! have no derivative at all.

use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};

use crate::error::LatticeError;
use crate::ids::{CellId, FaceId, VertexId};
use crate::lattice::Lattice;
use crate::subdivide::{Features, SubdivisionRules, subdivide};

/// Default of [`LimitParams::tolerance`]: `1e-7` of the bounding-box diagonal.
pub const DEFAULT_LIMIT_TOLERANCE: f64 = 1e-7;
/// Default of [`LimitParams::max_levels`]: 24 local subdivision levels (sub-cells of `6e-8` of
/// the cell's size).
pub const DEFAULT_LIMIT_MAX_LEVELS: usize = 24;
/// The largest accepted [`LimitParams::max_levels`] (beyond it sub-cells fall below `f64`
/// resolution relative to the cell).
pub const MAX_LIMIT_LEVELS: usize = 40;
/// Bytes kept per control cell by [`LimitEvaluator::new`] (at most: 64 control indices, a frame,
/// and for a regular cell a contiguous copy of its 64 control points).
pub const LIMIT_BYTES_PER_CELL: usize = 64 * 4 + 8 * 4 + 4 + 64 * 32;

/// Parameters of limit evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitParams {
    /// Stop subdividing a non-regular cell when two successive approximations differ by at most
    /// this fraction of the control points' bounding-box diagonal. Default
    /// [`DEFAULT_LIMIT_TOLERANCE`].
    pub tolerance: f64,
    /// At most this many local subdivision levels. Default [`DEFAULT_LIMIT_MAX_LEVELS`], at most
    /// [`MAX_LIMIT_LEVELS`].
    pub max_levels: usize,
    /// Threads for batches ([`LimitEvaluator::evaluate_into`]) and for the set-up. Default
    /// [`Parallelism::Auto`].
    pub parallelism: Parallelism,
}

impl Default for LimitParams {
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_LIMIT_TOLERANCE,
            max_levels: DEFAULT_LIMIT_MAX_LEVELS,
            parallelism: Parallelism::Auto,
        }
    }
}

/// One limit evaluation: position, first derivatives and how it was obtained.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitPoint {
    /// The limit position `x(u, v, w)`.
    pub position: Vec3,
    /// `[x_u, x_v, x_w]`.
    pub derivatives: [Vec3; 3],
    /// Whether the value is exact (a regular sub-cell's tricubic B-spline) rather than stopped at
    /// the tolerance.
    pub exact: bool,
    /// Local subdivision levels used (0: the control cell itself was regular).
    pub levels: u32,
    /// Estimated error of the position (0 when exact), in model units.
    pub error: f64,
}

/// A query: a cell of the control lattice and parameters in `[0, 1]^3`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitQuery {
    /// Cell index in the control lattice.
    pub cell: usize,
    /// `(u, v, w)`, each in `[0, 1]`.
    pub uvw: [f64; 3],
}

/// Limit evaluator of a control lattice under given rules and feature tags (see the
/// [module docs](self)).
#[derive(Debug)]
pub struct LimitEvaluator<'a> {
    lattice: &'a Lattice,
    features: &'a Features,
    rules: SubdivisionRules,
    params: LimitParams,
    /// Per cell: its frame (all `u32::MAX` for a non-hexahedral cell).
    frames: Vec<[VertexId; 8]>,
    /// Per cell: 64 control point indices of its tricubic patch (`u32::MAX` first: not regular).
    grids: Vec<[u32; 64]>,
    /// Per cell: index into `nets` (`u32::MAX`: not regular).
    slots: Vec<u32>,
    /// Per regular cell: its 64 control points, rows `(x, y, z, 0)` (contiguous for the kernel).
    nets: Vec<[[f64; 4]; 64]>,
    /// Absolute tolerance: `params.tolerance x` bounding-box diagonal.
    tol_abs: f64,
}

/// Uniform cubic B-spline basis functions and their derivatives at `t`.
#[inline(always)]
fn basis(t: f64) -> ([f64; 4], [f64; 4]) {
    const SIXTH: f64 = 1.0 / 6.0;
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    (
        [
            s * s * s * SIXTH,
            (3.0 * t3 - 6.0 * t2 + 4.0) * SIXTH,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) * SIXTH,
            t3 * SIXTH,
        ],
        [
            -0.5 * s * s,
            0.5 * (3.0 * t2 - 4.0 * t),
            0.5 * (-3.0 * t2 + 2.0 * t + 1.0),
            0.5 * t2,
        ],
    )
}

/// Evaluates the uniform tricubic B-spline of the grid `p(a, b, c)` (index `16 a + 4 b + c`) at
/// `(u, v, w)`: position and `[x_u, x_v, x_w]`.
#[inline(always)]
pub fn tricubic<F: Fn(usize) -> Vec3>(p: F, [u, v, w]: [f64; 3]) -> (Vec3, [Vec3; 3]) {
    let (bu, du) = basis(u);
    let (bv, dv) = basis(v);
    let (bw, dw) = basis(w);
    let mut x = Vec3::zeros();
    let mut xu = Vec3::zeros();
    let mut xv = Vec3::zeros();
    let mut xw = Vec3::zeros();
    for a in 0..4 {
        let mut ya = Vec3::zeros();
        let mut yv = Vec3::zeros();
        let mut yw = Vec3::zeros();
        for b in 0..4 {
            let mut z = Vec3::zeros();
            let mut zw = Vec3::zeros();
            for c in 0..4 {
                let q = p(16 * a + 4 * b + c);
                z += bw[c] * q;
                zw += dw[c] * q;
            }
            ya += bv[b] * z;
            yv += dv[b] * z;
            yw += bv[b] * zw;
        }
        x += bu[a] * ya;
        xu += du[a] * ya;
        xv += bu[a] * yv;
        xw += bu[a] * yw;
    }
    (x, [xu, xv, xw])
}

/// Trilinear interpolation of a frame's corner points: position and derivatives.
fn trilinear(c: &[Vec3; 8], [u, v, w]: [f64; 3]) -> (Vec3, [Vec3; 3]) {
    let lerp = |a: Vec3, b: Vec3, t: f64| a + (b - a) * t;
    let y00 = lerp(c[0], c[1], u);
    let y10 = lerp(c[2], c[3], u);
    let y01 = lerp(c[4], c[5], u);
    let y11 = lerp(c[6], c[7], u);
    let z0 = lerp(y00, y10, v);
    let z1 = lerp(y01, y11, v);
    let x = lerp(z0, z1, w);
    let du0 = lerp(c[1] - c[0], c[3] - c[2], v);
    let du1 = lerp(c[5] - c[4], c[7] - c[6], v);
    (
        x,
        [lerp(du0, du1, w), lerp(y10 - y00, y11 - y01, w), z1 - z0],
    )
}

/// The outward vertex loop of face `f` as used by cell `c`.
fn cell_loop(l: &Lattice, c: CellId, f: FaceId) -> Vec<VertexId> {
    let mut vs = l.face_vertices(f).to_vec();
    if l.cell_uses_face_reversed(c, f) {
        vs.reverse();
    }
    vs
}

/// The quad of cell `c` containing `x`, `y`, `z`; returns the vertex opposite `x` in it.
fn quad_opposite(
    l: &Lattice,
    c: CellId,
    x: VertexId,
    y: VertexId,
    z: VertexId,
) -> Option<VertexId> {
    for &f in l.cell_faces(c) {
        let vs = l.face_vertices(f);
        if vs.len() == 4
            && vs.contains(&y)
            && vs.contains(&z)
            && let Some(p) = vs.iter().position(|&q| q == x)
        {
            return Some(vs[(p + 2) % 4]);
        }
    }
    None
}

/// Whether `c` is a hexahedron: 8 vertices, 12 edges, 6 quadrilateral faces.
fn is_hex(l: &Lattice, c: CellId) -> bool {
    l.cell_vertices(c).len() == 8
        && l.cell_edges(c).len() == 12
        && l.cell_faces(c).len() == 6
        && l.cell_faces(c)
            .iter()
            .all(|&f| l.face_vertices(f).len() == 4)
}

/// The frame of hexahedron `c` with corner 0 at `v0` and corners 1, 2, 4 at `axes`.
fn hex_frame(l: &Lattice, c: CellId, v0: VertexId, axes: [VertexId; 3]) -> Option<[VertexId; 8]> {
    if !is_hex(l, c) {
        return None;
    }
    let [a, b, w] = axes;
    let mut f = [v0, a, b, v0, w, v0, v0, v0];
    f[3] = quad_opposite(l, c, v0, a, b)?;
    f[5] = quad_opposite(l, c, v0, a, w)?;
    f[6] = quad_opposite(l, c, v0, b, w)?;
    f[7] = *l.cell_vertices(c).iter().find(|v| !f[..7].contains(v))?;
    Some(f)
}

/// The frame of hexahedral cell `c` (the [module docs](self) give the convention): its corner
/// `i + 2 j + 4 k` sits at `(u, v, w) = (i, j, k)`.
pub fn cell_frame(l: &Lattice, c: CellId) -> Result<[VertexId; 8], LatticeError> {
    let not_hex = || LatticeError::NotHexahedral {
        cell: c,
        vertices: l.cell_vertices(c).len(),
        faces: l.cell_faces(c).len(),
    };
    if !is_hex(l, c) {
        return Err(not_hex());
    }
    let v0 = l.cell_vertices(c)[0];
    let mut nb: Vec<VertexId> = l
        .cell_edges(c)
        .iter()
        .filter_map(|&e| {
            let [a, b] = l.edge_vertices(e);
            if a == v0 {
                Some(b)
            } else if b == v0 {
                Some(a)
            } else {
                None
            }
        })
        .collect();
    if nb.len() != 3 {
        return Err(not_hex());
    }
    nb.sort_unstable();
    let (a, mut b, mut w) = (nb[0], nb[1], nb[2]);
    // Orientation: the outward loop of the face (v0, a, b) must run v0 -> b (normal -w).
    let fab = l
        .cell_faces(c)
        .iter()
        .copied()
        .find(|&f| {
            let vs = l.face_vertices(f);
            vs.contains(&v0) && vs.contains(&a) && vs.contains(&b)
        })
        .ok_or_else(not_hex)?;
    let lp = cell_loop(l, c, fab);
    let p = lp.iter().position(|&q| q == v0).ok_or_else(not_hex)?;
    if lp[(p + 1) % lp.len()] == a {
        std::mem::swap(&mut b, &mut w);
    }
    hex_frame(l, c, v0, [a, b, w]).ok_or_else(not_hex)
}

/// Whether `v` is a regular interior vertex of a hexahedral lattice without feature tags.
fn regular_vertex(l: &Lattice, feat: &Features, v: VertexId) -> bool {
    l.vertex_edges(v).len() == 6
        && l.vertex_faces(v).len() == 12
        && l.vertex_cells(v).len() == 8
        && !feat.is_corner(v)
        && !l.is_boundary_vertex(v)
        && l.vertex_edges(v).iter().all(|&e| !feat.is_crease(e))
}

/// The `4 x 4 x 4` control grid of a regular cell (index `16 a + 4 b + c`), or `None` when the
/// cell is not regular (see the [module docs](self)).
pub fn regular_grid(l: &Lattice, feat: &Features, frame: &[VertexId; 8]) -> Option<[u32; 64]> {
    const UNSET: u32 = u32::MAX;
    let mut grid = [UNSET; 64];
    for ci in 0..8usize {
        let v = frame[ci];
        if !regular_vertex(l, feat, v) {
            return None;
        }
        let bits = [ci & 1, (ci >> 1) & 1, (ci >> 2) & 1];
        // nb[axis][0]: neighbour towards decreasing grid index, nb[axis][1]: increasing.
        let mut nb = [[v; 2]; 3];
        for ax in 0..3 {
            let inward = frame[ci ^ (1 << ax)];
            let e_in = l.edge_between(v, inward)?;
            let fin = l.edge_faces(e_in);
            let mut out = None;
            for &e in l.vertex_edges(v) {
                if e != e_in && !l.edge_faces(e).iter().any(|f| fin.contains(f)) {
                    if out.is_some() {
                        return None;
                    }
                    out = Some(e);
                }
            }
            let [a, b] = l.edge_vertices(out?);
            let far = if a == v { b } else { a };
            // Corner bit 0 sits at grid 1: inward is +, outward is -.
            if bits[ax] == 0 {
                nb[ax] = [far, inward];
            } else {
                nb[ax] = [inward, far];
            }
        }
        for s in 0..8usize {
            let sg = [s & 1, (s >> 1) & 1, (s >> 2) & 1];
            let axes = [nb[0][sg[0]], nb[1][sg[1]], nb[2][sg[2]]];
            let cell = l.vertex_cells(v).iter().copied().find(|&c| {
                let cv = l.cell_vertices(c);
                axes.iter().all(|x| cv.binary_search(x).is_ok())
            })?;
            let hex = hex_frame(l, cell, v, axes)?;
            for (h, &x) in hex.iter().enumerate() {
                let mut g = [0usize; 3];
                for ax in 0..3 {
                    let base = 1 + bits[ax] as isize;
                    let off = ((h >> ax) & 1) as isize;
                    let dir = if sg[ax] == 1 { 1 } else { -1 };
                    let gi = base + off * dir;
                    if !(0..4).contains(&gi) {
                        return None;
                    }
                    g[ax] = gi as usize;
                }
                let slot = &mut grid[16 * g[0] + 4 * g[1] + g[2]];
                if *slot == UNSET {
                    *slot = x.0;
                } else if *slot != x.0 {
                    return None;
                }
            }
        }
    }
    if grid.contains(&UNSET) {
        return None;
    }
    Some(grid)
}

/// A cell during local descent: its lattice, frame and the map to model coordinates
/// (`model = origin + scale * local`).
struct Local {
    lattice: Lattice,
    features: Features,
    cell: CellId,
    frame: [VertexId; 8],
    origin: Vec3,
    scale: f64,
}

/// Copies the one-ring of `cell` (the cells around its corners) into a new lattice normalized to
/// unit size, with the features and the frame carried over.
fn extract(
    l: &Lattice,
    feat: &Features,
    cell: CellId,
    frame: &[VertexId; 8],
    origin: Vec3,
    scale: f64,
) -> Result<Local, LatticeError> {
    let mut cells: Vec<CellId> = frame
        .iter()
        .flat_map(|&v| l.vertex_cells(v).iter().copied())
        .collect();
    cells.sort_unstable();
    cells.dedup();
    let mut verts: Vec<VertexId> = cells
        .iter()
        .flat_map(|&c| l.cell_vertices(c).iter().copied())
        .collect();
    verts.sort_unstable();
    verts.dedup();
    let local = |v: VertexId| {
        verts
            .binary_search(&v)
            .expect("vertex of an extracted cell") as u32
    };
    let center = frame.iter().map(|&v| l.point(v)).sum::<Vec3>() / 8.0;
    let s = verts
        .iter()
        .map(|&v| (l.point(v) - center).norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let points: Vec<Vec3> = verts.iter().map(|&v| (l.point(v) - center) / s).collect();
    let faces: Vec<Vec<Vec<u32>>> = cells
        .iter()
        .map(|&c| {
            l.cell_faces(c)
                .iter()
                .map(|&f| cell_loop(l, c, f).into_iter().map(local).collect())
                .collect()
        })
        .collect();
    let sub = Lattice::from_cells(points, &faces)?;
    let mut sub_feat = Features::none(&sub);
    if feat.num_creases() > 0 || feat.num_corners() > 0 {
        for (e, &[a, b]) in sub.edges().iter().enumerate() {
            if let Some(oe) = l.edge_between(verts[a.index()], verts[b.index()])
                && feat.is_crease(oe)
            {
                sub_feat.tag_crease(crate::ids::EdgeId(e as u32))?;
            }
        }
        for (i, &v) in verts.iter().enumerate() {
            if feat.is_corner(v) {
                sub_feat.tag_corner(VertexId(i as u32))?;
            }
        }
    }
    let cell = CellId(cells.binary_search(&cell).expect("cell in its own ring") as u32);
    let frame = frame.map(|v| VertexId(local(v)));
    Ok(Local {
        lattice: sub,
        features: sub_feat,
        cell,
        frame,
        origin: origin + center * scale,
        scale: scale * s,
    })
}

/// The id in `subdivide(coarse)` of the new point of `cell` (frame `frame`) at doubled
/// parameters `q` in `{0, 1, 2}^3`: a vertex point (`q` even), edge point (one coordinate 1),
/// face point (two) or the cell point (three), numbered as in [`mod@crate::subdivide`].
fn fine_id(
    coarse: &Lattice,
    cell: CellId,
    frame: &[VertexId; 8],
    q: [usize; 3],
) -> Option<VertexId> {
    let (np, ne, nf) = (
        coarse.num_points() as u32,
        coarse.num_edges() as u32,
        coarse.num_faces() as u32,
    );
    let mids: Vec<usize> = (0..3).filter(|&a| q[a] == 1).collect();
    // The parent corners spanned by this point.
    let corners: Vec<VertexId> = (0..1usize << mids.len())
        .map(|m| {
            let mut idx = 0;
            for (a, &qa) in q.iter().enumerate() {
                let bit = match mids.iter().position(|&x| x == a) {
                    Some(k) => (m >> k) & 1,
                    None => qa / 2,
                };
                idx |= bit << a;
            }
            frame[idx]
        })
        .collect();
    Some(match mids.len() {
        0 => corners[0],
        1 => VertexId(np + coarse.edge_between(corners[0], corners[1])?.0),
        2 => {
            let f = coarse.cell_faces(cell).iter().copied().find(|&f| {
                let vs = coarse.face_vertices(f);
                vs.len() == 4 && corners.iter().all(|c| vs.contains(c))
            })?;
            VertexId(np + ne + f.0)
        }
        _ => VertexId(np + ne + nf + cell.0),
    })
}

/// The child of `cell` (frame `frame` in `coarse`) at octant `oct` in `fine = subdivide(coarse)`:
/// its cell id and its frame aligned with the parent's axes.
fn child(
    coarse: &Lattice,
    fine: &Lattice,
    cell: CellId,
    frame: &[VertexId; 8],
    oct: [usize; 3],
) -> Option<(CellId, [VertexId; 8])> {
    let mut out = [VertexId(0); 8];
    for (h, slot) in out.iter_mut().enumerate() {
        let q = [
            oct[0] + (h & 1),
            oct[1] + ((h >> 1) & 1),
            oct[2] + ((h >> 2) & 1),
        ];
        *slot = fine_id(coarse, cell, frame, q)?;
    }
    let cp = fine_id(coarse, cell, frame, [1, 1, 1])?;
    // The child at this octant contains the vertex point of the octant's parent corner (vertex
    // points keep their ids) and the cell point.
    let corner = frame[oct[0] | (oct[1] << 1) | (oct[2] << 2)];
    let c = fine
        .vertex_cells(corner)
        .iter()
        .copied()
        .find(|&c| fine.cell_vertices(c).binary_search(&cp).is_ok())?;
    Some((c, out))
}

/// How far the 27 new points of `cell` in `fine` lie from the trilinear interpolant of its
/// corners (in the lattices' own coordinates): the change one level makes, which bounds the
/// error of the trilinear approximation (see the [module docs](self)).
fn level_change(
    coarse: &Lattice,
    fine: &Lattice,
    cell: CellId,
    frame: &[VertexId; 8],
) -> Option<f64> {
    let corners = frame.map(|v| coarse.point(v));
    let mut worst = 0.0f64;
    for i in 0..27 {
        let q = [i % 3, (i / 3) % 3, i / 9];
        let id = fine_id(coarse, cell, frame, q)?;
        let (x, _) = trilinear(&corners, q.map(|t| t as f64 / 2.0));
        worst = worst.max((fine.point(id) - x).norm());
    }
    Some(worst)
}

impl<'a> LimitEvaluator<'a> {
    /// Prepares limit evaluation of `lattice` (the control lattice) subdivided with `rules` and
    /// `features`: every hexahedral cell's frame and, for regular cells, its 64 control indices.
    ///
    /// Memory: [`LIMIT_BYTES_PER_CELL`] per cell (the caller checks it against its budget).
    /// Errors: `features` not sized for `lattice`; `params` out of range (tolerance not positive
    /// and finite, `max_levels` above [`MAX_LIMIT_LEVELS`]).
    pub fn new(
        lattice: &'a Lattice,
        features: &'a Features,
        rules: SubdivisionRules,
        params: LimitParams,
    ) -> Result<Self, LatticeError> {
        if !(params.tolerance.is_finite() && params.tolerance > 0.0) {
            return Err(LatticeError::LimitParameter {
                message: format!("tolerance {} must be positive and finite", params.tolerance),
            });
        }
        if params.max_levels > MAX_LIMIT_LEVELS {
            return Err(LatticeError::LimitParameter {
                message: format!(
                    "max_levels {} is above the supported {MAX_LIMIT_LEVELS}",
                    params.max_levels
                ),
            });
        }
        // Sized-for-lattice check (the same one subdivide() makes).
        features.check(lattice)?;
        lattice.build_adjacency();
        let n = lattice.num_cells();
        let none = [VertexId(u32::MAX); 8];
        let setup = |c: usize| -> ([VertexId; 8], [u32; 64]) {
            match cell_frame(lattice, CellId(c as u32)) {
                Ok(f) => (
                    f,
                    regular_grid(lattice, features, &f).unwrap_or([u32::MAX; 64]),
                ),
                Err(_) => (none, [u32::MAX; 64]),
            }
        };
        let both: Vec<([VertexId; 8], [u32; 64])> = if params.parallelism.is_parallel_from(n, 2048)
        {
            (0..n).into_par_iter().map(setup).collect()
        } else {
            (0..n).map(setup).collect()
        };
        let (frames, grids): (Vec<_>, Vec<[u32; 64]>) = both.into_iter().unzip();
        let pts = lattice.points();
        let mut slots = vec![u32::MAX; n];
        let mut nets = Vec::new();
        for (c, g) in grids.iter().enumerate() {
            if g[0] != u32::MAX {
                slots[c] = nets.len() as u32;
                nets.push(g.map(|i| {
                    let p = pts[i as usize];
                    [p.x, p.y, p.z, 0.0]
                }));
            }
        }
        let (lo, hi) = lattice.points().iter().fold(
            (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let diag = (hi - lo).norm();
        Ok(Self {
            lattice,
            features,
            rules: SubdivisionRules {
                parallelism: Parallelism::Sequential,
                ..rules
            },
            params,
            frames,
            grids,
            slots,
            nets,
            tol_abs: params.tolerance * diag.max(f64::MIN_POSITIVE),
        })
    }

    /// The control lattice.
    pub fn lattice(&self) -> &Lattice {
        self.lattice
    }

    /// The absolute tolerance (`tolerance x` bounding-box diagonal of the control points).
    pub fn absolute_tolerance(&self) -> f64 {
        self.tol_abs
    }

    /// The frame of cell `c` ([`cell_frame`]), `None` for a non-hexahedral cell.
    pub fn frame(&self, c: CellId) -> Option<[VertexId; 8]> {
        self.frames
            .get(c.index())
            .copied()
            .filter(|f| f[0].0 != u32::MAX)
    }

    /// Whether the limit over cell `c` is the tricubic B-spline of its `4 x 4 x 4` neighbours.
    pub fn is_regular(&self, c: CellId) -> bool {
        self.grids.get(c.index()).is_some_and(|g| g[0] != u32::MAX)
    }

    /// The 64 control point ids of a regular cell (index `16 a + 4 b + c`).
    pub fn control_grid(&self, c: CellId) -> Option<[VertexId; 64]> {
        self.grids
            .get(c.index())
            .filter(|g| g[0] != u32::MAX)
            .map(|g| g.map(VertexId))
    }

    /// Checks one query: the cell exists and is hexahedral, the parameters are finite and in
    /// `[0, 1]`. `index` names the query in the error.
    pub fn check(&self, index: usize, q: &LimitQuery) -> Result<(), LatticeError> {
        let cells = self.lattice.num_cells();
        if q.cell >= cells {
            return Err(LatticeError::LimitQuery {
                index,
                message: format!("cell {} is out of range ({cells} cells)", q.cell),
            });
        }
        for (axis, &t) in q.uvw.iter().enumerate() {
            let name = ["u", "v", "w"][axis];
            if !t.is_finite() {
                return Err(LatticeError::LimitQuery {
                    index,
                    message: format!("{name} = {t} is not finite"),
                });
            }
            if !(0.0..=1.0).contains(&t) {
                return Err(LatticeError::LimitQuery {
                    index,
                    message: format!("{name} = {t} is outside [0, 1]"),
                });
            }
        }
        if self.frames[q.cell][0].0 == u32::MAX {
            let c = CellId(q.cell as u32);
            return Err(LatticeError::NotHexahedral {
                cell: c,
                vertices: self.lattice.cell_vertices(c).len(),
                faces: self.lattice.cell_faces(c).len(),
            });
        }
        Ok(())
    }

    /// The limit at one query (checked first).
    pub fn evaluate(&self, cell: usize, uvw: [f64; 3]) -> Result<LimitPoint, LatticeError> {
        let q = LimitQuery { cell, uvw };
        self.check(0, &q)?;
        self.evaluate_unchecked(&q)
    }

    /// The limit at many queries; all are checked before any is evaluated (the error names the
    /// query index). Runs in parallel per [`LimitParams::parallelism`].
    pub fn evaluate_many(&self, queries: &[LimitQuery]) -> Result<Vec<LimitPoint>, LatticeError> {
        let mut out = vec![LimitPoint::default(); queries.len()];
        self.evaluate_into(queries, &mut out)?;
        Ok(out)
    }

    /// As [`LimitEvaluator::evaluate_many`], into a caller's buffer (no allocation on the
    /// regular path).
    ///
    /// # Panics
    /// If `out.len() != queries.len()` (a programmer error).
    #[track_caller]
    pub fn evaluate_into(
        &self,
        queries: &[LimitQuery],
        out: &mut [LimitPoint],
    ) -> Result<(), LatticeError> {
        assert_eq!(queries.len(), out.len(), "one output per query");
        for (i, q) in queries.iter().enumerate() {
            self.check(i, q)?;
        }
        const CHUNK: usize = 1024;
        if self
            .params
            .parallelism
            .is_parallel_from(queries.len(), 4096)
        {
            out.par_chunks_mut(CHUNK)
                .zip(queries.par_chunks(CHUNK))
                .try_for_each(|(o, q)| self.run_chunk(q, o))
        } else {
            self.run_chunk(queries, out)
        }
    }

    fn run_chunk(&self, qs: &[LimitQuery], out: &mut [LimitPoint]) -> Result<(), LatticeError> {
        // Regular cells first, in the kernel compiled for the CPU's best instruction set.
        let pending = regular_chunk(self, qs, out);
        if pending {
            for (q, o) in qs.iter().zip(out.iter_mut()) {
                if self.grids[q.cell][0] == u32::MAX {
                    *o = self.descend(q)?;
                }
            }
        }
        Ok(())
    }

    /// The tricubic patch of a regular control cell; `None` when the cell is not regular.
    #[inline]
    fn regular(&self, q: &LimitQuery) -> Option<LimitPoint> {
        let mut out = [LimitPoint::default()];
        let pending = regular_chunk(self, std::slice::from_ref(q), &mut out);
        (!pending).then_some(out[0])
    }

    /// Evaluates a query already checked by [`LimitEvaluator::check`].
    pub fn evaluate_unchecked(&self, q: &LimitQuery) -> Result<LimitPoint, LatticeError> {
        if let Some(p) = self.regular(q) {
            return Ok(p);
        }
        self.descend(q)
    }

    /// Local subdivision until regular or within tolerance (see the [module docs](self)).
    fn descend(&self, q: &LimitQuery) -> Result<LimitPoint, LatticeError> {
        let mut uvw = q.uvw;
        let cell = CellId(q.cell as u32);
        let frame0 = self.frames[q.cell];
        let mut cur: Option<Local> = None;
        let mut change = f64::INFINITY;
        let internal = |level: usize| LatticeError::LimitParameter {
            message: format!("internal: no child at level {level} of {cell}"),
        };
        for level in 0..=self.params.max_levels {
            let (l, feat, c, frame, origin, scale) = match &cur {
                None => (
                    self.lattice,
                    self.features,
                    cell,
                    frame0,
                    Vec3::zeros(),
                    1.0,
                ),
                Some(loc) => (
                    &loc.lattice,
                    &loc.features,
                    loc.cell,
                    loc.frame,
                    loc.origin,
                    loc.scale,
                ),
            };
            let dscale = scale * (1u64 << level) as f64;
            if level > 0
                && let Some(g) = regular_grid(l, feat, &frame)
            {
                let pts = l.points();
                let (x, d) = tricubic(|i| pts[g[i] as usize], uvw);
                return Ok(LimitPoint {
                    position: origin + x * scale,
                    derivatives: d.map(|v| v * dscale),
                    exact: true,
                    levels: level as u32,
                    error: 0.0,
                });
            }
            if change <= self.tol_abs || level == self.params.max_levels {
                let corners = frame.map(|v| l.point(v));
                let (x, d) = trilinear(&corners, uvw);
                return Ok(LimitPoint {
                    position: origin + x * scale,
                    derivatives: d.map(|v| v * dscale),
                    exact: false,
                    levels: level as u32,
                    error: change / 3.0,
                });
            }
            let loc = extract(l, feat, c, &frame, origin, scale)?;
            let r = subdivide(&loc.lattice, &loc.features, &self.rules)?;
            change = level_change(&loc.lattice, &r.lattice, loc.cell, &loc.frame)
                .ok_or_else(|| internal(level))?
                * loc.scale;
            let oct = uvw.map(|t| usize::from(t >= 0.5));
            let (cc, cframe) = child(&loc.lattice, &r.lattice, loc.cell, &loc.frame, oct)
                .ok_or_else(|| internal(level))?;
            for a in 0..3 {
                uvw[a] = (2.0 * uvw[a] - oct[a] as f64).clamp(0.0, 1.0);
            }
            cur = Some(Local {
                lattice: r.lattice,
                features: r.features,
                cell: cc,
                frame: cframe,
                origin: loc.origin,
                scale: loc.scale,
            });
        }
        unreachable!("the loop returns at max_levels")
    }
}

/// The regular cells of a chunk of queries: the explicit AVX2/FMA kernel where the CPU has it
/// (x86-64), else [`RegularOp`] compiled for the best instruction set there is. Returns whether
/// some query was not regular.
fn regular_chunk(ev: &LimitEvaluator<'_>, qs: &[LimitQuery], out: &mut [LimitPoint]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return v3.vectorize(move || regular_v3(v3, ev, qs, out));
    }
    pulp::Arch::new().dispatch(RegularOp { ev, qs, out })
}

/// [`RegularOp`] with the kernel written in AVX2/FMA vectors (`pulp::x86::V3`, inlined into
/// its `vectorize`): each grid row `(x, y, z, 0)` one 4-lane register, every term one `vfmadd`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn regular_v3(
    s: pulp::x86::V3,
    ev: &LimitEvaluator<'_>,
    qs: &[LimitQuery],
    out: &mut [LimitPoint],
) -> bool {
    use pulp::f64x4;
    let mut pending = false;
    for (q, o) in qs.iter().zip(out.iter_mut()) {
        let slot = ev.slots[q.cell];
        if slot == u32::MAX {
            pending = true;
            continue;
        }
        let net = &ev.nets[slot as usize];
        let [u, v, w] = q.uvw;
        let (bu, du) = basis(u);
        let (bv, dv) = basis(v);
        let (bw, dw) = basis(w);
        let zero = s.splat_f64x4(0.0);
        let (mut x, mut xu, mut xv, mut xw) = (zero, zero, zero, zero);
        for a in 0..4 {
            let (mut ya, mut yv, mut yw) = (zero, zero, zero);
            for b in 0..4 {
                let (mut z, mut zw) = (zero, zero);
                for c in 0..4 {
                    let r = &net[16 * a + 4 * b + c];
                    let row = f64x4(r[0], r[1], r[2], r[3]);
                    z = s.mul_add_f64x4(s.splat_f64x4(bw[c]), row, z);
                    zw = s.mul_add_f64x4(s.splat_f64x4(dw[c]), row, zw);
                }
                ya = s.mul_add_f64x4(s.splat_f64x4(bv[b]), z, ya);
                yv = s.mul_add_f64x4(s.splat_f64x4(dv[b]), z, yv);
                yw = s.mul_add_f64x4(s.splat_f64x4(bv[b]), zw, yw);
            }
            let (ba, da) = (s.splat_f64x4(bu[a]), s.splat_f64x4(du[a]));
            x = s.mul_add_f64x4(ba, ya, x);
            xu = s.mul_add_f64x4(da, ya, xu);
            xv = s.mul_add_f64x4(ba, yv, xv);
            xw = s.mul_add_f64x4(ba, yw, xw);
        }
        let v3 = |l: f64x4| Vec3::new(l.0, l.1, l.2);
        *o = LimitPoint {
            position: v3(x),
            derivatives: [v3(xu), v3(xv), v3(xw)],
            exact: true,
            levels: 0,
            error: 0.0,
        };
    }
    pending
}

/// The regular-cell kernel over a chunk of queries as a [`pulp::WithSimd`] operation, so that
/// [`pulp::Arch::dispatch`] compiles it for the best instruction set the CPU has (AVX2 where
/// present; runtime detection, safe code). Returns whether some query was not regular.
struct RegularOp<'e, 'a> {
    ev: &'e LimitEvaluator<'a>,
    qs: &'e [LimitQuery],
    out: &'e mut [LimitPoint],
}

impl pulp::WithSimd for RegularOp<'_, '_> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> bool {
        let mut pending = false;
        for (q, o) in self.qs.iter().zip(self.out.iter_mut()) {
            let slot = self.ev.slots[q.cell];
            if slot == u32::MAX {
                pending = true;
                continue;
            }
            let (x, d) = tricubic_lanes(&self.ev.nets[slot as usize], q.uvw);
            *o = LimitPoint {
                position: x,
                derivatives: d,
                exact: true,
                levels: 0,
                error: 0.0,
            };
        }
        pending
    }
}

/// [`tricubic`] on a cell's contiguous net with 4-lane rows `(x, y, z, 0)`: the same sums in the
/// same order as fused multiply-adds, written as lane arithmetic so that it vectorizes (partly:
/// `vfmadd` on 4 lanes for most terms on AVX2/FMA; the scalar fallback computes the same fused
/// values more slowly).
#[inline(always)]
fn tricubic_lanes(net: &[[f64; 4]; 64], [u, v, w]: [f64; 3]) -> (Vec3, [Vec3; 3]) {
    type L = [f64; 4];
    #[inline(always)]
    fn axpy(a: f64, x: &L, y: &mut L) {
        for k in 0..4 {
            y[k] = a.mul_add(x[k], y[k]);
        }
    }
    let (bu, du) = basis(u);
    let (bv, dv) = basis(v);
    let (bw, dw) = basis(w);
    let mut x = [0.0; 4];
    let mut xu = [0.0; 4];
    let mut xv = [0.0; 4];
    let mut xw = [0.0; 4];
    for a in 0..4 {
        let mut ya = [0.0; 4];
        let mut yv = [0.0; 4];
        let mut yw = [0.0; 4];
        for b in 0..4 {
            let mut z = [0.0; 4];
            let mut zw = [0.0; 4];
            for c in 0..4 {
                let q = &net[16 * a + 4 * b + c];
                axpy(bw[c], q, &mut z);
                axpy(dw[c], q, &mut zw);
            }
            axpy(bv[b], &z, &mut ya);
            axpy(dv[b], &z, &mut yv);
            axpy(bv[b], &zw, &mut yw);
        }
        axpy(bu[a], &ya, &mut x);
        axpy(du[a], &ya, &mut xu);
        axpy(bu[a], &yv, &mut xv);
        axpy(bu[a], &yw, &mut xw);
    }
    let v3 = |l: L| Vec3::new(l[0], l[1], l[2]);
    (v3(x), [v3(xu), v3(xv), v3(xw)])
}

/// The parameters of a frame's corner `h` (`[h & 1, (h >> 1) & 1, h >> 2]` as `f64`).
pub fn corner_parameters(h: usize) -> [f64; 3] {
    [(h & 1) as f64, ((h >> 1) & 1) as f64, ((h >> 2) & 1) as f64]
}

/// The child of `cell` in the next level of a global hierarchy (`fine = subdivide(coarse)`)
/// containing `uvw`: its id, its frame aligned with the parent's axes and the child's
/// parameters. The frame of the parent is `frame` (from [`cell_frame`] or an earlier call).
///
/// With this the points of a [`crate::SubdivisionSolid`]'s levels can be matched to the limit
/// parameters (tests use it to check convergence).
pub fn child_cell(
    coarse: &Lattice,
    fine: &Lattice,
    cell: CellId,
    frame: &[VertexId; 8],
    uvw: [f64; 3],
) -> Option<(CellId, [VertexId; 8], [f64; 3])> {
    let oct = uvw.map(|t| usize::from(t >= 0.5));
    let (c, f) = child(coarse, fine, cell, frame, oct)?;
    let mut out = uvw;
    for a in 0..3 {
        out[a] = (2.0 * uvw[a] - oct[a] as f64).clamp(0.0, 1.0);
    }
    Some((c, f, out))
}

/// The limit-evaluation benchmark (issue 19's speed goal; `vclay bench` and
/// `examples/limit_bench.rs`): a `14^3`-point box lattice whose points are moved by up to 0.1 of
/// the cell size (seeded), so its 1,331 interior-regular cells are tricubic but not uniform.
pub fn benchmark_lattice() -> Lattice {
    let n = 14;
    let mut l = crate::primitives::box_lattice([n; 3], Vec3::zeros(), Vec3::repeat((n - 1) as f64));
    let mut next = benchmark_random(0x2545_f491_4f6c_dd1d);
    for p in l.points_mut() {
        *p += Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.2;
    }
    l
}

/// `count` seeded queries at uniform random parameters in uniformly chosen regular cells of the
/// evaluator's lattice (the benchmark's points); empty when no cell is regular.
pub fn benchmark_queries(
    evaluator: &LimitEvaluator<'_>,
    cells: usize,
    count: usize,
) -> Vec<LimitQuery> {
    let regular: Vec<usize> = (0..cells)
        .filter(|&c| u32::try_from(c).is_ok_and(|c| evaluator.is_regular(CellId(c))))
        .collect();
    if regular.is_empty() {
        return Vec::new();
    }
    let mut next = benchmark_random(0x9e37_79b9_7f4a_7c15);
    (0..count)
        .map(|_| LimitQuery {
            cell: regular[(next() * regular.len() as f64) as usize % regular.len()],
            uvw: [next(), next(), next()],
        })
        .collect()
}

/// Xorshift64 uniform numbers in `[0, 1)` (seeded; the benchmark's figures are reproducible).
fn benchmark_random(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The three regular-cell kernels (scalar `tricubic`, the lane kernel used where AVX2/FMA is
    /// missing, and the explicit AVX2/FMA kernel where the CPU has it) agree on a seeded net.
    #[test]
    fn the_regular_kernels_agree() {
        let mut seed = 12345u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let pts: Vec<Vec3> = (0..64)
            .map(|i| Vec3::new((i / 16) as f64, ((i / 4) % 4) as f64, (i % 4) as f64))
            .map(|p| p + Vec3::new(next(), next(), next()) * 0.3)
            .collect();
        let net: [[f64; 4]; 64] = std::array::from_fn(|i| [pts[i].x, pts[i].y, pts[i].z, 0.0]);
        for _ in 0..20 {
            let uvw = [next(), next(), next()];
            let (x0, d0) = tricubic(|i| pts[i], uvw);
            let (x1, d1) = tricubic_lanes(&net, uvw);
            assert!((x0 - x1).norm() < 1e-13);
            for a in 0..3 {
                assert!((d0[a] - d1[a]).norm() < 1e-12);
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(v3) = pulp::x86::V3::try_new() {
                let l = crate::primitives::box_lattice([6; 3], Vec3::zeros(), Vec3::repeat(5.0));
                let f = Features::none(&l);
                let mut ev = LimitEvaluator::new(
                    &l,
                    &f,
                    SubdivisionRules::default(),
                    LimitParams::default(),
                )
                .unwrap();
                let c = (0..l.num_cells())
                    .find(|&c| ev.is_regular(CellId(c as u32)))
                    .unwrap();
                ev.nets[ev.slots[c] as usize] = net;
                let q = [LimitQuery { cell: c, uvw }];
                let mut out = [LimitPoint::default()];
                assert!(!v3.vectorize(|| regular_v3(v3, &ev, &q, &mut out)));
                assert!((out[0].position - x0).norm() < 1e-13);
                for a in 0..3 {
                    assert!((out[0].derivatives[a] - d0[a]).norm() < 1e-12);
                }
            }
        }
    }
}
