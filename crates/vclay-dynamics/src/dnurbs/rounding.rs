//! Solid rounding with triangular D-NURBS (`d-nurbs.txt` section 7.3, Fig 8, Table 1 rows
//! "Edge rounding", "Corner rounding", "Bevel rounding").
//!
//! ## What
//! The fillet is the minimum of the thin-plate-under-tension energy (eq 17, the paper's
//! absolute form `1/2 p^T K p`, [`ElasticReference::Absolute`]) subject to position and normal
//! constraints (section 6.2) along the far boundaries of the faces; the damped dynamics of eq 18
//! with the Table 1 parameters (`mu = 0`) relax the sharp initial shape into it.
//!
//! ## The three models (the paper gives only their control-point counts)
//! - **Edge** (Fig 8a): a quadratic surface over a strip of 3 x 1 quads (6 triangles, 36 basis
//!   functions) with the paper's "continuous net": functions at the same Bezier domain point
//!   share a control point, 7 x 3 = 21 control points. The initial net is folded by 90 degrees
//!   along its middle column (a convex edge), whose points lie on the edge (the sharp start,
//!   below); far boundaries `u = 0` and `u = 3`.
//! - **Corner** (Fig 8b): a trihedral corner of a cube, 13 triangles (a central cap, three quads
//!   across the three cube edges and three rhombi on the faces) times 6 = 78 control points.
//!   The edges are the domain rays at 30, 150 and 270 degrees, through the middles of the edge
//!   quads ([`CORNER_QUAD_DEPTH`] deep); the initial shape is the corner of the solid
//!   `x <= 0, y >= 0, z <= 0`
//!   unfolded onto the domain (`corner_map`: linear on each half of the 120-degree sectors,
//!   so that each segment across an edge maps into a plane across that edge).
//!   Far boundary: the outer hexagon. Starts from the `C^1` rounding of its map (below).
//! - **Sharp corner** ([`RoundingKind::SharpCorner`], issue 28): the same corner, map and
//!   material over a domain of 19 triangles, 114 control points (`sharp_corner_domain`),
//!   that starts exactly sharp (below).
//! - **Bevel** (Fig 8c): a right-angle (concave) joint of two plates, a 3 x 3 quad grid (18
//!   triangles) times 6 = 108 control points, folded along its middle (sharp); far boundaries
//!   `u = 0` and `u = 3`.
//!
//! Control points are the piecewise-linear initial map `F` evaluated at the mean of each basis
//! function's blossom knots (exact for `F` linear on the function's support, DMS polynomial
//! reproduction) or, for the shared net, at the Bezier domain point. Knot clouds have radius
//! [`ROUNDING_CLOUD_RADIUS`] of the shortest edge at each vertex: the quadratic basis is `C^1`
//! (a crease by coincident knots is excluded by simplex splines).
//!
//! ## The sharp initial edge (Fig 8a1, 8c1; issue 28)
//! The paper: "the sharp edge can be represented exactly with multiple control points or with
//! multiple knots". With the control points at `F`'s images the `C^1` basis rounds the edge
//! over the middle column ([`InitialShape::Rounded`]: the old edge's middle lies 0.12 off
//! both faces). The edge and the bevel start instead from [`InitialShape::Sharp`], the paper's
//! multiple control points: every control point of a function over a triangle of the middle
//! column (for the edge's continuous net: the columns `u = 1, 1.5, 2`) lies on the edge line,
//! keeping its coordinate along the edge (`RoundingModel::sharp_target`). A point of the
//! middle column then depends on points of the edge line only and lies on it; a point of a
//! side column or next to the middle column's sides on points of one face and of the edge,
//! all in that face's plane. The image is exactly the two faces meeting at the edge (every
//! vertex of the tessellation within 6.7e-16 of its face), a fold of the parameter
//! domain's middle column onto the edge line (`s_u = 0` there: no normal inside it). The
//! held boundaries' control points are not moved, so both starts have the same constrained
//! minimum: the sharp start relaxes into the fillet of the `C^1` start within the scenarios'
//! steps (surfaces 2.2e-16 apart after 100 steps for the edge, 4.1e-11 after 60 for the
//! bevel; `tests/triangular.rs`).
//!
//! ## The sharp corner (Fig 8b1; issue 28)
//! The paper's 78-point corner keeps the `C^1` start. Each edge quad's two triangles reach the
//! outer hexagon at the quad's outer corners, where the held rhombus boundaries begin, so
//! functions acting on a held boundary (and held at their `C^1` positions with it) reach both
//! faces next to the edge: 18 of its 50 held functions cannot lie on the faces (`corner_part`,
//! unit test of this module; none of the sharp corner's 42). Collapsing the other quad functions and the cap
//! (measured earlier with a test written for it, not kept) makes the start sharp only at the
//! corner point: 0.5 along an edge the surface is 0.006 off it, 1.5 along it 0.11 (the `C^1`
//! start: 0.125). Collapsing the held ones as well pins a sharp profile at the edges' outer
//! ends, and the first step diverges (the engine's weight trust check refuses every halving of
//! the step). No other 13-triangle domain with the corner's three-fold symmetry does better:
//! the triangles at the vertex `P` where a face's held boundary meets the sliding boundary may
//! not reach the edge's ray, so each sliding boundary needs a vertex `Q` between `P` and the
//! ray on either side (a `Q` on the ray puts its outside knots, and with them the supports of
//! held functions of both sides, across it): 12 boundary vertices, while a triangulated disk
//! with `V_b` boundary and `V_i` interior vertices has `2 V_i + V_b - 2` triangles, 13 of them
//! only with `V_b` odd (9 or 15 under the symmetry; 15 leaves no interior vertex, and the
//! triangle holding the corner point then acts on the sliding boundary and would have to
//! collapse onto the point). Repeated control points cannot bring the count back to 78 either:
//! sharing a free point ties its functions together for the whole run.
//!
//! [`RoundingKind::SharpCorner`] therefore has a domain of its own (`sharp_corner_domain`):
//! the paper's central triangle; for each edge a strip of two triangles from the central edge
//! across the ray to `Q_A Q_B` ([`SHARP_CORNER_LENGTH`] along, [`SHARP_CORNER_STRIP`] across);
//! for each face a fan of four triangles from its central vertex to `Q_B`, `P_B`, a far vertex
//! and `P_A'`, `Q_A'` (`P` at [`SHARP_CORNER_SLIDE`] across). The boundary `P_A Q_A Q_B P_B`
//! across each edge slides, `P_B F P_A'` is held. Every control point goes onto the part of the
//! corner that its function's support (the convex hull of its knots) reaches inside the domain
//! (`corner_part`): one face's sector (onto that face's plane, where the initial map already
//! put it), the two sectors next to an edge (onto the edge line, keeping the coordinate along
//! the edge, the one a sliding point holds), or all three (onto the corner point: the central
//! triangle's functions and those at its vertices). At a point of sector `s` every function
//! that does not vanish there has its support meeting sector `s`, so it lies on face `s`, on
//! an edge of face `s` or at the corner: the image is exactly the three faces (every vertex of
//! the tessellation on its face, measured 0 to the last bit), the central triangle and the
//! strips folded onto the corner point and the edges. The constructor checks that no held
//! coordinate moves (a held function on one face, a sliding one on a face or on its own edge).
//! Both starts of this domain hold the same control points and relax into the same fillet
//! (after 60 steps 7.8e-15 apart, `tests/triangular.rs`): tangent to the faces along the held
//! boundaries (normals unchanged to the last bit), the corner point 0.81 into the solid, 6.5 %
//! of its turning the wrong way. That share is larger than the paper's domain's 3.1 %, whose
//! held boundary also holds the `C^1` rounding of the edges' outer ends; here those ends are
//! free to slide across the edges, and the fillet meets the held faces beside them with a
//! ripple (the wrong-way turning lies 1.5-2.5 along the edges, about 0.5 off them). Tried for
//! the domain's sizes (60 steps): length 1.8-3.0, strip 0.35-0.87, sliding half-width
//! 0.7-2.0, far vertex at 2.3-3.5 or none: 6.5-12 %.
//!
//! ## Constraints
//! Far boundaries of the faces (section 7.3, "position and normal constraints along the far
//! boundaries of the faces"): the edge's two sides parallel to the old edge; the corner's and
//! the bevel's outer boundary where it lies in a face. Positions and normals along them are
//! held by the paper's linear constraints, the freezing of control points (section 6.2): every
//! control point (and weight) whose basis function is positive somewhere on such a boundary is
//! fixed ([`RoundingModel::fixed_controls`]). Because the quadratic DMS basis is `C^1` and
//! non-negative, a function that vanishes at a boundary point has a zero gradient there, so
//! the boundary curve **and** the surface tangents along it depend on the fixed coordinates
//! only: position and normal hold exactly along the whole boundary, not just at samples.
//! [`ROUNDING_BOUNDARY_SAMPLES`] normal constraints ([`Constraint::Normal`]) per held edge are
//! registered as well and checked every step (their rows act only on fixed coordinates, so
//! the engine finds them satisfied and drops them without cost). Constraining the boundary by
//! point constraints instead (5 rows per sample) costs 90 constraint rows on the corner, whose
//! dense Schur complement and Newton projection made a step 5x slower.
//!
//! Boundaries that cross an old edge (the corner's three outer quad sides, the bevel's sides
//! `v = 0` and `v = 3`) **slide** (issue 28, [`RoundingModel::sliding`]): a control point
//! acting on one keeps its coordinate along the edge (and its weight) and is free across it,
//! so the fillet's cross-section there lies in its plane across the edge and rounds like the
//! rest of the edge; the tension's natural boundary condition (no derivative across the
//! boundary in the free coordinates) is met by a fillet extruded along the edge. Held whole,
//! as before, they pinned the sharp profile at the patch's ends: the bevel's fillet tapered
//! back to a sharp joint there (13 % of its turning the wrong way with the densities below
//! from the `C^1` start, 35 % from the sharp one; 1.7 % sliding). On the corner only 9 control points slide and the difference is not
//! measurable (3.05 % against 3.06 %); the corner's gain came from the unfolded map and the
//! deeper quads (Table 1 as printed: 25 % before, 15.6 % on the new model) and from the
//! densities (3.1 %). The edge's sides are free (its Table 1 row has no `v` terms).
//!
//! ## Reading Table 1: why the fillets folded the wrong way (issue 28)
//! With Table 1 as printed over our unit domain spans the relaxed surfaces are not the convex
//! fillets of Fig 8a2-c2: 30 % (edge), 25 % (corner) and 30 % (bevel) of their turning folds
//! the wrong way ([`mesh_turning`]; the initial shapes 0-0.3 %). The cause is the material,
//! not the constraints:
//! over our unit domain spans the Table 1 rows are tension-dominated (edge `a11 / b11 = 1000`,
//! corner 100, bevel `b = 0`), and a tension-dominated quadratic spline cannot turn smoothly
//! from a held tangent. In one dimension (uniform quadratic B-spline, control differences
//! `D_i`, energy per span `a (|D_i|^2 + D_i . D_(i+1) + |D_(i+1)|^2) / 3 + b |D_(i+1) - D_i|^2`,
//! eq 17 restricted to a curve) the free differences satisfy
//! `(4a/3 + 4b) D_i + (a/3 - 2b) (D_(i-1) + D_(i+1)) = lambda`, whose homogeneous solutions
//! `r^i` have `r + 1/r = -(4a/3 + 4b) / (a/3 - 2b)`: for `a > 6 b` per span `r` is negative
//! (`-2 + sqrt 3 = -0.268` for `b = 0`), so the correction from a held tangent alternates in
//! sign span by span. A 90-degree fold between held faces then turns -60, +19, -5, +1.5, ...
//! degrees: 24 % of its turning the wrong way, for `a / b = 1000` and for `b = 0` alike; for
//! `a <= 6 b` every turn has the same sign (exact Euler-Lagrange solution, checked with a
//! small script for 6 to 20 spans). The minimum of the paper's absolute energy is then a
//! chamfer with ripples at its ends, which is what the scenarios show. In two dimensions the
//! tension term is invariant under a scaling of the domain and the bending term is not, so
//! Table 1's values would give convex fillets over spans of parameter length
//! `h <= sqrt(6 b / a)` (0.077 for the edge, 0.24 for the corner; the paper gives no domain
//! size) and never for the bevel's pure membrane. The continuous net of the edge adds a second
//! effect: its shared points make the surface close to a `C^0` piecewise Bezier surface, and
//! tension pulls a free junction point back towards the held ones (the minimum of a quadratic
//! segment's `integral |r'|^2` over its end point `C` is `C = B - (B - A) / 2`). (A first try
//! of the sharp start, with Table 1 as printed, barely moved the corner in 60 steps; with the
//! densities below the edge and the bevel reach their fillets from it, see above.)
//!
//! What is done: each model reads Table 1 over spans of length [`RoundingKind::span`]
//! ([`RoundingKind::material`]): the edge with `a11 h^2 = 6 b11`, the corner with `a h^2 = b`
//! (three fillets meeting need more bending than the one-dimensional bound), and the bevel,
//! whose row has no bending at all, with its bending densities raised to `a11 / 6`. With the
//! bevel's sides sliding and the corner unfolded, the three relax into fillets tangent to the
//! faces whose turning
//! folds the wrong way by 1.6 % (edge), 3.1 % (corner) and 1.7 % (bevel), against 30 %, 25 %
//! and 30 % before (`tests/triangular.rs`). What is left of the corner's share lies along the
//! middle of its edge fillets, where the held face boundaries converge on the edges (the
//! rhombi's outer sides meet the quads' at 60 degrees, so the fillet narrows towards the
//! crossing ends) and along the rhombus diagonals; a domain whose held sides run parallel to
//! the edges (tried: a Y-shaped domain of one-span-wide strips) leaves almost every control
//! point fixed, and the fillet is then the initial `C^1` rounding (largest motion 0.05).
//! The sharp corner's own domain starts sharp and turns 6.5 % the wrong way (above).

use super::generalized::{Constraint, GeneralizedDnurbs};
use super::presets::Preset;
use super::triangular::{TriangleQuadrature, TriangularGeometry};
use super::{ElasticReference, Material};
use crate::error::DynamicsError;
use vclay_core::Vec3;
use vclay_spline::simplex::Point2;
use vclay_spline::triangular::{
    KnotClouds, TriangularBasis, TriangularNurbs, Triangulation, convex_hull,
};

/// Knot cloud radius of the rounding models (fraction of the shortest edge at a vertex).
pub const ROUNDING_CLOUD_RADIUS: f64 = 0.1;
/// Constraint points per far boundary edge (its two ends and interior points, equally spaced).
pub const ROUNDING_BOUNDARY_SAMPLES: usize = 3;

/// Depth of the corner's edge quads along the cube edges (domain units; the central triangle
/// has circumradius 1). Issue 28: with 1.5 the held face boundaries converge on the edges over
/// a shorter stretch and the fillet tapers more (3.5 % of its turning the wrong way against
/// 3.0 % with 2.0, 3.6 % with 3.0; 100 steps, `tests/triangular.rs`).
pub const CORNER_QUAD_DEPTH: f64 = 2.0;

/// Weight penalty `c` of the rounding models ([`GeneralizedDnurbs::set_weight_penalty`]). Table
/// 1 gives `mu = 0` for rounding, so the weights have neither mass nor (for control points near
/// the surface) damping, and the paper's energy can drop by moving weights alone: the edge run
/// with free weights (`c = 1`) drives a weight to 2e-3 and diverges after 48 steps; with
/// `c = 100` the weights stay within 0.93-1.11 and the energy reaches that of frozen weights
/// (786 against 794).
pub const ROUNDING_WEIGHT_PENALTY: f64 = 100.0;

/// Basis-function value below which the sharp corner ([`RoundingKind::SharpCorner`]) does not
/// count a function as acting on a far boundary: round-off on the edge of a support (the
/// functions sum to 1; measured values where the exact one is 0 reach 1e-14).
const SUPPORT_ROUND_OFF: f64 = 1e-12;

/// Boundary samples per far edge at which the acting control points are found (the basis is
/// evaluated at `FIXING_SAMPLES + 1` equally spaced points).
const FIXING_SAMPLES: usize = 32;

/// The initial shape of a rounding model ([`RoundingModel::with_initial`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitialShape {
    /// The sharp edge of the paper's Fig 8a1 and 8c1: the control points of the functions over
    /// the triangles that carry the old edge collapse onto it (the paper's "multiple control
    /// points"), so the surface is exactly the faces meeting at the edge. The sharp corner
    /// ([`RoundingKind::SharpCorner`]) puts each control point onto the face, edge or corner
    /// point its function's support reaches. The paper's corner ([`RoundingKind::Corner`])
    /// keeps [`InitialShape::Rounded`] (module docs).
    Sharp,
    /// The control points at the initial map's images (`C^1`: the edge is rounded over the
    /// width of the triangles that carry it).
    Rounded,
}

/// Which Fig 8 model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoundingKind {
    /// Fig 8a: a convex edge, 21 control points.
    Edge,
    /// Fig 8b: a trihedral cube corner, 78 control points.
    Corner,
    /// Fig 8c: a concave right-angle (bevel) joint, 108 control points.
    Bevel,
    /// Fig 8b with an exactly sharp start (issue 28): the trihedral corner over a domain whose
    /// strips along the cube edges are free of the held boundary (`sharp_corner_domain`, 19
    /// triangles, 114 control points); same Table 1 row and densities as
    /// [`RoundingKind::Corner`].
    SharpCorner,
}

impl RoundingKind {
    /// Parses `edge`, `corner`, `bevel`, `sharp-corner`.
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "edge" => Some(Self::Edge),
            "corner" => Some(Self::Corner),
            "bevel" => Some(Self::Bevel),
            "sharp-corner" => Some(Self::SharpCorner),
            _ => None,
        }
    }

    /// The parameter length `h` of the paper's domain span that one unit span of ours stands
    /// for, when the model reads the Table 1 densities ([`RoundingKind::material`]): the paper
    /// gives no domain size. The edge uses `h = sqrt(6 b11 / a11)` (0.077), the largest span
    /// over which the thin plate under tension does not alternate next to a held tangent
    /// (`a h^2 <= 6 b`, see the module docs). The corner, where three fillets meet, needs more
    /// bending than that one-dimensional bound: `h = sqrt(b11 / a11)` (0.1; wrong-way share
    /// after 60 steps 6.0 % at `a h^2 = 6 b`, 3.1 % at `a h^2 = b`, 2.5 % for pure bending,
    /// with the fillet moving less as the tension drops). The bevel uses `h = 1`: its `b = 0`
    /// has no such span, and [`RoundingKind::material`] adds bending instead.
    pub fn span(self) -> f64 {
        self.span_squared().sqrt()
    }

    /// [`RoundingKind::span`] squared (computed without the square root, so that `a11 h^2` is
    /// exactly `6 b11`).
    fn span_squared(self) -> f64 {
        let p = self.preset();
        match self {
            Self::Edge => 6.0 * p.beta[0] / p.alpha[0],
            Self::Corner | Self::SharpCorner => p.beta[0] / p.alpha[0],
            Self::Bevel => 1.0,
        }
    }

    /// The Table 1 densities read over domain spans of length [`RoundingKind::span`] and
    /// written for our unit spans. Scaling the parameter domain by `h` leaves the tension term
    /// of eq 17 (`integral a |s_u|^2 du dv`) unchanged, divides the bending term by `h^2` and
    /// multiplies the mass and damping terms (eq 16) by `h^2`; multiplying every term by `h^2`
    /// (which leaves the motion of eq 18 with `mu = 0` unchanged) gives `a h^2`, `b`, `gamma
    /// h^4`, `mu h^4` over unit spans. Edge: `a11 = 6`, `b11 = 1`, `gamma = 0.018`. Corner:
    /// `a11 = a22 = 10`, `b = 10`, `gamma = 0.005`. The bevel's row is a membrane (`b = 0`),
    /// whose minimum under held positions is a chamfer that cannot meet the held normals (a
    /// second-order energy takes positions only as boundary data): its bending densities are
    /// raised to `a11 / 6` (16.7), the least bending for which a unit span does not alternate,
    /// the rest of the row kept. Section 7.3 asks for "a smooth fillet by minimizing its
    /// internal deformation energy subject to position and normal constraints"; section 7.1
    /// says "increasing beta tends to make objects more rigid".
    pub fn material(self) -> Material {
        let p = self.preset();
        let h2 = self.span_squared();
        let c = |x: f64| super::Density::Constant(x);
        let beta = |b: f64| match self {
            Self::Bevel => b.max(p.alpha[0] / 6.0),
            Self::Edge | Self::Corner | Self::SharpCorner => b,
        };
        Material {
            mu: c(p.mu * h2 * h2),
            gamma: c(p.gamma * h2 * h2),
            alpha: p.alpha.iter().map(|&a| c(a * h2)).collect(),
            beta: p.beta.iter().map(|&b| c(beta(b))).collect(),
        }
    }

    /// The Table 1 row.
    pub fn preset(self) -> &'static Preset {
        let name = match self {
            Self::Edge => "Edge rounding",
            Self::Corner | Self::SharpCorner => "Corner rounding",
            Self::Bevel => "Bevel rounding",
        };
        Preset::by_name(name).expect("Table 1 has the rounding rows")
    }
}

/// A rounding model: the surface, its sharp-edge lines and its far-boundary constraints.
#[derive(Clone, Debug)]
pub struct RoundingModel {
    /// Which model.
    pub kind: RoundingKind,
    /// The initial surface.
    pub surface: TriangularNurbs,
    /// The far-boundary normal constraints.
    pub constraints: Vec<Constraint>,
    /// Control points held fixed (with their weights): those whose basis functions are
    /// non-zero on the far boundary, so the boundary curve keeps its position exactly (the
    /// paper's linear constraints, "the freezing of control points", section 6.2).
    pub fixed_controls: Vec<usize>,
    /// Control points held in one coordinate only (with their weights), as `(control, axis)`:
    /// those acting on a far boundary that crosses an old sharp edge, held in the coordinate
    /// along that edge and free across it, so the fillet's cross-section there can round (see
    /// the module docs). None of them is in [`RoundingModel::fixed_controls`].
    pub sliding: Vec<(usize, usize)>,
    /// The old sharp edges in the parameter domain, as segments.
    pub edges: Vec<[Point2; 2]>,
    /// The far boundaries held whole (position and normal), as segments.
    held: Vec<[Point2; 2]>,
}

/// A `cols x rows` grid of unit quads, each split along the diagonal `(i, j)-(i+1, j+1)`.
fn grid(cols: usize, rows: usize) -> Result<Triangulation, DynamicsError> {
    let mut v = Vec::new();
    for i in 0..=cols {
        for j in 0..=rows {
            v.push([i as f64, j as f64]);
        }
    }
    let id = |i: usize, j: usize| i * (rows + 1) + j;
    let mut t = Vec::new();
    for i in 0..cols {
        for j in 0..rows {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Triangulation::new(v, t).map_err(|e| DynamicsError::Spline(e.into()))
}

/// The corner domain: central triangle, three edge quads, three corner rhombi (13 triangles).
/// The central vertices lie at distance 1 on the bisectors (90, 210, 330 degrees); edge quad
/// `k` extends the central edge `k` by [`CORNER_QUAD_DEPTH`] along its outward normal, the
/// ray of a cube edge.
fn corner_domain() -> Result<Triangulation, DynamicsError> {
    let r = 1.0;
    let h = CORNER_QUAD_DEPTH;
    let ang = |deg: f64| {
        let a = deg.to_radians();
        [a.cos(), a.sin()]
    };
    // Central vertices at 90, 210, 330 degrees; outward edge normals at 30, 150, 270.
    let c: Vec<Point2> = [90.0, 210.0, 330.0]
        .iter()
        .map(|&d| {
            let p = ang(d);
            [r * p[0], r * p[1]]
        })
        .collect();
    // Edge k joins c[k] and c[(k+1)%3]; its outward normal:
    let edge_normal = |k: usize| {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let l = m[0].hypot(m[1]);
        [m[0] / l, m[1] / l]
    };
    let mut v: Vec<Point2> = c.clone();
    // Outer vertices of edge quad k: c[k] + h n_k (index 3 + 2k), c[k+1] + h n_k (4 + 2k).
    for k in 0..3 {
        let n = edge_normal(k);
        let (a, b) = (c[k], c[(k + 1) % 3]);
        v.push([a[0] + h * n[0], a[1] + h * n[1]]);
        v.push([b[0] + h * n[0], b[1] + h * n[1]]);
    }
    // Far vertex of the rhombus at c[k]: c[k] + h (n_{k-1} + n_k) (index 9 + k).
    for k in 0..3 {
        let (n1, n2) = (edge_normal((k + 2) % 3), edge_normal(k));
        v.push([c[k][0] + h * (n1[0] + n2[0]), c[k][1] + h * (n1[1] + n2[1])]);
    }
    let mut t = vec![[0, 1, 2]];
    for k in 0..3 {
        let (a, b) = (k, (k + 1) % 3);
        let (oa, ob) = (3 + 2 * k, 4 + 2 * k);
        t.push([a, oa, ob]);
        t.push([a, ob, b]);
        // Rhombus at c[k]: c[k], outer of previous edge at c[k] (4 + 2(k-1)), far, oa.
        let prev = 4 + 2 * ((k + 2) % 3);
        let far = 9 + k;
        t.push([k, prev, far]);
        t.push([k, far, oa]);
    }
    Triangulation::new(v, t).map_err(|e| DynamicsError::Spline(e.into()))
}

/// Distance along each cube edge's ray from the corner to the sliding boundary across it, in
/// the sharp corner's domain (`sharp_corner_domain`; the paper's corner: `0.5 +`
/// [`CORNER_QUAD_DEPTH`]).
pub const SHARP_CORNER_LENGTH: f64 = 2.0;
/// Half-width, across the ray, of the sharp corner's edge strip at the sliding boundary.
pub const SHARP_CORNER_STRIP: f64 = 0.5;
/// Half-width, across the ray, of the sharp corner's sliding boundary: the held boundary of the
/// faces begins there.
pub const SHARP_CORNER_SLIDE: f64 = 1.0;
/// Distance from the corner of the sharp corner's far vertices, on the faces' bisectors.
pub const SHARP_CORNER_FAR: f64 = 2.6;

/// The sharp corner's domain ([`RoundingKind::SharpCorner`], 19 triangles): a central triangle
/// `c_0 c_1 c_2` (circumradius 1, vertices on the faces' bisectors at 90, 210, 330 degrees,
/// the corner at its centre, as in the paper's domain); for each cube edge's ray `k` (30, 150,
/// 270 degrees) a strip of two triangles from the central edge across the ray to `Q_A, Q_B`,
/// [`SHARP_CORNER_LENGTH`] along the ray and [`SHARP_CORNER_STRIP`] across it; for each face
/// (the 120-degree sector between two rays, holding `c_s`) a fan of four triangles from `c_s`
/// to `Q_B`, `P_B`, the far vertex `F_s` ([`SHARP_CORNER_FAR`] out on the bisector), `P_A'`
/// and `Q_A'` (`P` at [`SHARP_CORNER_SLIDE`] across the rays). The boundary `P_A Q_A Q_B P_B`
/// across each ray slides; the polygon `P_B F_s P_A'` of each face is held. No triangle at a
/// held vertex reaches a ray, so every function acting on the held boundary lies in one face
/// ([`corner_part`]).
fn sharp_corner_domain() -> Result<Triangulation, DynamicsError> {
    let (l, w, wh, rf) = (
        SHARP_CORNER_LENGTH,
        SHARP_CORNER_STRIP,
        SHARP_CORNER_SLIDE,
        SHARP_CORNER_FAR,
    );
    // c_s on the bisector of sector s, then F_s further out on it.
    let bisector = |s: usize, r: f64| {
        let a = (corner_ray(s) + 60.0).to_radians();
        [r * a.cos(), r * a.sin()]
    };
    let mut v: Vec<Point2> = (0..3).map(|s| bisector(s, 1.0)).collect();
    for k in 0..3 {
        let a = corner_ray(k).to_radians();
        let (r, n) = ([a.cos(), a.sin()], [-a.sin(), a.cos()]);
        // Q_A, Q_B, P_A, P_B (A: clockwise of the ray, B: counter-clockwise).
        for off in [-w, w, -wh, wh] {
            v.push([l * r[0] + off * n[0], l * r[1] + off * n[1]]);
        }
    }
    v.extend((0..3).map(|s| bisector(s, rf)));
    let (qa, qb, pa, pb) = (
        |k: usize| 3 + 4 * k,
        |k: usize| 4 + 4 * k,
        |k: usize| 5 + 4 * k,
        |k: usize| 6 + 4 * k,
    );
    let far = |s: usize| 15 + s;
    // Sector s (face s) lies between rays s and s + 1 and holds c_s; ray k lies between
    // sectors k - 1 and k.
    let mut t = vec![[0, 1, 2]];
    for k in 0..3 {
        let prev = (k + 2) % 3;
        t.push([prev, qa(k), qb(k)]);
        t.push([prev, qb(k), k]);
    }
    for s in 0..3 {
        let j = (s + 1) % 3;
        t.push([s, qb(s), pb(s)]);
        t.push([s, pb(s), far(s)]);
        t.push([s, far(s), pa(j)]);
        t.push([s, pa(j), qa(j)]);
    }
    Triangulation::new(v, t).map_err(|e| DynamicsError::Spline(e.into()))
}

/// The axis of the cube edge along which a boundary segment of the sharp corner's domain
/// slides: the one whose ray the segment crosses at [`SHARP_CORNER_LENGTH`] (the three segments
/// `P_A Q_A Q_B P_B`), or `None` for a held segment.
fn sharp_corner_crossing(seg: [Point2; 2]) -> Option<usize> {
    (0..3).find(|&k| {
        let a = corner_ray(k).to_radians();
        seg.iter()
            .all(|q| (q[0] * a.cos() + q[1] * a.sin() - SHARP_CORNER_LENGTH).abs() < 1e-9)
    })
}

/// What a basis function's support reaches in the sharp corner ([`corner_part`]): the inside of
/// one face's sector, the two sectors next to a cube edge, or all three.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CornerPart {
    /// The sector between rays `s` and `s + 1`: the face spanned by the cube edges `s` and
    /// `s + 1`, the plane where coordinate `(s + 2) % 3` is zero.
    Face(usize),
    /// Both sectors next to ray `k`: the cube edge `k`, the line where only coordinate `k` is
    /// non-zero.
    Edge(usize),
    /// All three sectors: the corner point (the origin).
    Point,
}

impl CornerPart {
    /// The control point `p` (the initial map's image) moved onto the part: onto the face's
    /// plane (a no-op for points the map sent into that face), onto the edge line keeping the
    /// coordinate along the edge (the sliding coordinate), or onto the corner.
    fn target(self, p: Vec3) -> Vec3 {
        match self {
            Self::Face(s) => {
                let mut q = p;
                q[(s + 2) % 3] = 0.0;
                q
            }
            Self::Edge(k) => {
                let mut q = Vec3::zeros();
                q[k] = p[k];
                q
            }
            Self::Point => Vec3::zeros(),
        }
    }
}

/// The sectors of the corner domain (between consecutive rays of [`corner_ray`]) that the
/// support of basis function `f` (the convex hull of its knots) meets inside the domain with a
/// positive area (above `1e-9` of the squared domain extent), as a [`CornerPart`]. With every
/// control point on its function's part ([`CornerPart::target`]) the surface is exactly the
/// three faces: at a domain point of sector `s` every function that does not vanish there has
/// its support meeting sector `s`, so its part is face `s`, an edge of face `s` or the corner,
/// all in face `s`'s plane.
fn corner_part(basis: &TriangularBasis, f: usize) -> CornerPart {
    let (t, b) = basis.function_index(f);
    let dom = basis.domain();
    let tri = dom.triangles()[t];
    let mut knots = Vec::new();
    for c in 0..3 {
        knots.extend_from_slice(&basis.clouds().clouds[tri[c]][..=b[c]]);
    }
    let hull = convex_hull(&knots);
    let tol = 1e-9 * dom.extent().powi(2);
    let met: Vec<usize> = (0..3)
        .filter(|&s| {
            let (a0, a1) = (
                corner_ray(s).to_radians(),
                corner_ray((s + 1) % 3).to_radians(),
            );
            // Left of ray s, right of ray s + 1.
            let sector = clip(
                &clip(&hull, [0.0, 0.0], [a0.cos(), a0.sin()]),
                [0.0, 0.0],
                [-a1.cos(), -a1.sin()],
            );
            let area: f64 = (0..dom.triangles().len())
                .map(|t| {
                    let [p, q, r] = dom.corners(t);
                    let inside = clip(&sector, p, [q[0] - p[0], q[1] - p[1]]);
                    let inside = clip(&inside, q, [r[0] - q[0], r[1] - q[1]]);
                    polygon_area(&clip(&inside, r, [p[0] - r[0], p[1] - r[1]]))
                })
                .sum();
            area > tol
        })
        .collect();
    match met[..] {
        [s] => CornerPart::Face(s),
        // Sectors s and s + 1 share ray s + 1; sectors 0 and 2 share ray 0.
        [s0, s1] if s1 == s0 + 1 => CornerPart::Edge(s1),
        [_, _] => CornerPart::Edge(0),
        _ => CornerPart::Point,
    }
}

/// The part of a polygon left of the directed line through `o` along `d` (Sutherland-Hodgman;
/// the polygon convex, either orientation).
fn clip(poly: &[Point2], o: Point2, d: Point2) -> Vec<Point2> {
    let side = |q: Point2| d[0] * (q[1] - o[1]) - d[1] * (q[0] - o[0]);
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &p) in poly.iter().enumerate() {
        let q = poly[(i + 1) % poly.len()];
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let f = sp / (sp - sq);
            out.push([p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]);
        }
    }
    out
}

/// Area of a simple polygon (shoelace, absolute).
fn polygon_area(poly: &[Point2]) -> f64 {
    let mut a = 0.0;
    for (i, p) in poly.iter().enumerate() {
        let q = poly[(i + 1) % poly.len()];
        a += p[0] * q[1] - p[1] * q[0];
    }
    0.5 * a.abs()
}

/// The corner's initial map: the corner of the solid `x <= 0, y >= 0, z <= 0` unfolded onto
/// the domain. The rays at 30, 150 and 270 degrees go to the edges along `-x`, `+y` and `-z` (unit
/// speed). Each 120-degree sector between two rays goes to the quadrant of the face between
/// their edges, linearly on each half of the sector: on the half next to ray `k` (edge `E_k`),
/// towards ray `j`, `F(q) = (q . r_k) E_k + (q . n_kj) / sqrt 3 E_j` with `r_k` the ray's
/// direction and `n_kj` the unit normal of the ray towards ray `j`. The two halves agree on
/// the bisector (`cos 60 = sin 60 / sqrt 3`), and a segment across ray `k` at `q . r_k = l`
/// within 60 degrees of it goes into the plane `E_k . x = l` across the edge.
fn corner_map(q: Point2) -> Vec3 {
    // Nearest ray (the half-sector q lies in) and the ray on q's side of it.
    let angle = q[1].atan2(q[0]).to_degrees();
    let (k, _) = (0..3)
        .map(|k| {
            let d = (angle - corner_ray(k)).rem_euclid(360.0);
            (k, d.min(360.0 - d))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 0.0));
    let r = corner_ray(k).to_radians();
    let (rk, nk) = ([r.cos(), r.sin()], [-r.sin(), r.cos()]);
    let (along, across) = (q[0] * rk[0] + q[1] * rk[1], q[0] * nk[0] + q[1] * nk[1]);
    // Counter-clockwise of ray k lies ray k + 1.
    let j = if across >= 0.0 {
        (k + 1) % 3
    } else {
        (k + 2) % 3
    };
    corner_edge(k) * along + corner_edge(j) * (across.abs() / 3f64.sqrt())
}

/// The direction (degrees) of the corner domain's ray `k` (the cube edge along [`corner_edge`]).
fn corner_ray(k: usize) -> f64 {
    30.0 + 120.0 * k as f64
}

/// The cube edge `k` of the corner: along `-x`, `+y`, `-z` (the corner of the solid
/// `x <= 0, y >= 0, z <= 0`, whose outside faces the renderer's iso view from `(+x, -y, +z)`).
fn corner_edge(k: usize) -> Vec3 {
    let sign = if k == 1 { 1.0 } else { -1.0 };
    Vec3::ith(k, sign)
}

impl RoundingModel {
    /// Builds one of the Fig 8 models (see the module docs).
    pub fn new(kind: RoundingKind) -> Result<Self, DynamicsError> {
        Self::with_initial(kind, InitialShape::Sharp)
    }

    /// [`RoundingModel::new`] with the initial shape chosen (the sharp one of the paper's
    /// Fig 8a1-c1, or the `C^1` rounding of the initial map; the paper's corner has only the
    /// latter, the sharp corner both).
    /// Both relax into the same fillet (`tests/triangular.rs`).
    pub fn with_initial(kind: RoundingKind, initial: InitialShape) -> Result<Self, DynamicsError> {
        let err = |e: vclay_spline::triangular::TriangularError| DynamicsError::Spline(e.into());
        let (domain, map): (Triangulation, Box<dyn Fn(Point2) -> Vec3>) = match kind {
            RoundingKind::Edge => (
                grid(3, 1)?,
                // Convex edge at u = 1.5: flat for u < 1.5, then down.
                Box::new(|q: Point2| Vec3::new(q[0].min(1.5), 2.0 * q[1], -(q[0] - 1.5).max(0.0))),
            ),
            RoundingKind::Bevel => (
                grid(3, 3)?,
                // Concave joint at u = 1.5: floor, then a wall going up (turned half a turn
                // about z, so that the renderer's iso view sees the joint's open side).
                Box::new(|q: Point2| Vec3::new(-q[0].min(1.5), -q[1], (q[0] - 1.5).max(0.0))),
            ),
            RoundingKind::Corner => (corner_domain()?, Box::new(corner_map)),
            RoundingKind::SharpCorner => (sharp_corner_domain()?, Box::new(corner_map)),
        };
        let clouds = KnotClouds::around_vertices(&domain, 2, ROUNDING_CLOUD_RADIUS).map_err(err)?;
        let basis = TriangularBasis::new(2, domain, clouds).map_err(err)?;
        let (points, control_map) = match kind {
            RoundingKind::Edge => {
                let (m, pts) = basis.bezier_net_map();
                (pts.iter().map(|&q| map(q)).collect::<Vec<_>>(), Some(m))
            }
            _ => {
                let pts = (0..basis.len())
                    .map(|f| {
                        let (t, b) = basis.function_index(f);
                        let tri = basis.domain().triangles()[t];
                        let mut acc = [0.0; 2];
                        for c in 0..3 {
                            for k in 0..b[c] {
                                let q = basis.clouds().clouds[tri[c]][k];
                                acc[0] += q[0] / 2.0;
                                acc[1] += q[1] / 2.0;
                            }
                        }
                        map(acc)
                    })
                    .collect();
                (pts, None)
            }
        };
        // The sharp initial shape (Fig 8a1, 8c1): the control points of every function of a
        // triangle that carries the old edge collapse onto it, see
        // [`RoundingModel::sharp_target`].
        let mut points = points;
        for f in (0..basis.len()).filter(|_| initial == InitialShape::Sharp) {
            let t = basis.function_index(f).0;
            let c = control_map.as_ref().map_or(f, |m| m[f]);
            if let Some(target) = Self::sharp_target(kind, t, points[c]) {
                points[c] = target;
            }
        }
        // The sharp corner: every control point onto the face, edge or corner point that its
        // function's support reaches ([`CornerPart`]).
        let parts: Vec<CornerPart> =
            if kind == RoundingKind::SharpCorner && initial == InitialShape::Sharp {
                (0..basis.len()).map(|f| corner_part(&basis, f)).collect()
            } else {
                Vec::new()
            };
        for (p, part) in points.iter_mut().zip(&parts) {
            *p = part.target(*p);
        }
        let n = points.len();
        let surface =
            TriangularNurbs::new(basis, points, vec![1.0; n], control_map).map_err(err)?;
        // Far boundary edges and the sharp edges.
        let dom = surface.basis().domain().clone();
        let ext = dom.extent();
        // Far boundaries: held whole (`None`) or, where they cross an old edge, along the
        // edge's axis only (`Some(axis)`).
        let far: Vec<([Point2; 2], Option<usize>)> = match kind {
            RoundingKind::Edge => vec![
                ([[0.0, 0.0], [0.0, 1.0]], None),
                ([[3.0, 0.0], [3.0, 1.0]], None),
            ],
            RoundingKind::Bevel => boundary_edges(&dom)
                .into_iter()
                .map(|seg| {
                    // The sides v = 0 and v = 3 cross the edge (along y).
                    let side = (seg[0][1] - seg[1][1]).abs() < 1e-9 * ext
                        && (seg[0][1].abs() < 1e-9 * ext || (seg[0][1] - 3.0).abs() < 1e-9 * ext);
                    (seg, side.then_some(1))
                })
                .collect(),
            RoundingKind::Corner => boundary_edges(&dom)
                .into_iter()
                .map(|seg| (seg, corner_crossing(seg)))
                .collect(),
            RoundingKind::SharpCorner => boundary_edges(&dom)
                .into_iter()
                .map(|seg| (seg, sharp_corner_crossing(seg)))
                .collect(),
        };
        let edges: Vec<[Point2; 2]> = match kind {
            RoundingKind::Edge => vec![[[1.5, 0.0], [1.5, 1.0]]],
            RoundingKind::Bevel => vec![[[1.5, 0.0], [1.5, 3.0]]],
            RoundingKind::Corner => [30.0f64, 150.0, 270.0]
                .iter()
                .map(|d| {
                    let a = d.to_radians();
                    // The ray from the corner to the far boundary (0.5 + depth).
                    let l = 0.5 + CORNER_QUAD_DEPTH;
                    [[0.0, 0.0], [l * a.cos(), l * a.sin()]]
                })
                .collect(),
            RoundingKind::SharpCorner => (0..3)
                .map(|k| {
                    let a = corner_ray(k).to_radians();
                    let l = SHARP_CORNER_LENGTH;
                    [[0.0, 0.0], [l * a.cos(), l * a.sin()]]
                })
                .collect(),
        };
        let mut constraints = Vec::new();
        let mut seen: Vec<Point2> = Vec::new();
        let mut fixed = vec![false; surface.control_points().len()];
        let mut slide: Vec<Option<usize>> = vec![None; fixed.len()];
        let mut p = vclay_spline::TriangularPoint::default();
        // A function acts on a boundary where its value exceeds `acting`. The sharp corner
        // does not count round-off on a support's edge (values up to 1e-14 where the exact
        // value is 0: the function of `O`'s strip triangle at `O` is otherwise "acting" on the
        // sliding boundary and would have to keep a coordinate that the sharp start moves);
        // the other models keep the strict test they were measured with.
        let acting = if kind == RoundingKind::SharpCorner {
            SUPPORT_ROUND_OFF
        } else {
            0.0
        };
        // Whole holds first, so that the normal constraints sit on them only.
        let mut far = far;
        far.sort_by_key(|f| f.1.is_some());
        for &(seg, hold) in &far {
            // Position: every control point acting on the boundary is held.
            for k in 0..=FIXING_SAMPLES {
                let f = k as f64 / FIXING_SAMPLES as f64;
                let q = [
                    seg[0][0] + f * (seg[1][0] - seg[0][0]),
                    seg[0][1] + f * (seg[1][1] - seg[0][1]),
                ];
                surface
                    .eval(q, &mut p)
                    .map_err(|e| DynamicsError::Spline(e.into()))?;
                for (k, &c) in p.controls.iter().enumerate() {
                    if p.basis[k][0] > acting {
                        match hold {
                            None => fixed[c] = true,
                            Some(axis) => slide[c] = Some(axis),
                        }
                    }
                }
            }
            if hold.is_some() {
                continue;
            }
            // Normal: constraints at samples.
            for k in 0..ROUNDING_BOUNDARY_SAMPLES {
                let f = k as f64 / (ROUNDING_BOUNDARY_SAMPLES - 1) as f64;
                let q = [
                    seg[0][0] + f * (seg[1][0] - seg[0][0]),
                    seg[0][1] + f * (seg[1][1] - seg[0][1]),
                ];
                if seen
                    .iter()
                    .any(|s| (s[0] - q[0]).abs() + (s[1] - q[1]).abs() < 1e-9 * ext)
                {
                    continue;
                }
                seen.push(q);
                let d = surface
                    .derivatives(q)
                    .map_err(|e| DynamicsError::Spline(e.into()))?;
                let normal = d[1].cross(&d[2]);
                constraints.push(Constraint::Normal { param: q, normal });
            }
        }
        // The sharp corner's held coordinates keep their places: a held control point lies on
        // a face, a sliding one on a face or on the edge it slides along.
        for (c, part) in parts.iter().enumerate() {
            let keeps = match (part, slide[c]) {
                (CornerPart::Face(_), _) => true,
                (CornerPart::Edge(k), Some(axis)) => !fixed[c] && *k == axis,
                _ => !fixed[c] && slide[c].is_none(),
            };
            if !keeps {
                return Err(DynamicsError::Parameter {
                    name: "sharp corner: held control point",
                    value: c as f64,
                    why: "its function reaches across a cube edge, so the sharp start would move a held coordinate",
                });
            }
        }
        let held = far.iter().filter(|f| f.1.is_none()).map(|f| f.0).collect();
        let fixed_controls = (0..fixed.len()).filter(|&c| fixed[c]).collect();
        let sliding = (0..fixed.len())
            .filter(|&c| !fixed[c])
            .filter_map(|c| slide[c].map(|a| (c, a)))
            .collect();
        Ok(Self {
            kind,
            surface,
            constraints,
            fixed_controls,
            sliding,
            edges,
            held,
        })
    }

    /// Where a control point of a function of domain triangle `t`, placed at `p` by the
    /// initial map, goes in the sharp initial shape ([`InitialShape::Sharp`]): onto the old
    /// edge if `t` carries it (the edge's and the bevel's middle column; the point keeps its
    /// coordinate along the edge), nowhere else (`None`: the faces keep the initial map). The
    /// paper's "multiple control points" (section 7.3): every point on which the surface
    /// depends over such a triangle lies on the edge, so the triangle's image is the edge
    /// line, and every domain point next to it combines points of one face and of the edge,
    /// which lie in that face's plane: the image is exactly the two faces meeting at a sharp
    /// edge. With the edge's continuous net the shared points of the columns `u = 1` and
    /// `u = 2` go onto the edge as well (they belong to the middle column's functions).
    fn sharp_target(kind: RoundingKind, t: usize, p: Vec3) -> Option<Vec3> {
        match kind {
            // The middle column of the 3 x 1 (3 x 3) quads: triangles 2 and 3 (6 to 11) of
            // `grid`, whose edge lies at x = 1.5 (x = -1.5) with z = 0.
            RoundingKind::Edge | RoundingKind::Bevel => {
                let rows = if kind == RoundingKind::Edge { 1 } else { 3 };
                (t / (2 * rows) == 1).then(|| Vec3::new(1.5f64.copysign(p.x), p.y, 0.0))
            }
            // The paper's corner keeps the `C^1` rounding of its initial map (see the module
            // docs: its edge quads' functions are mostly held with the far boundary); the sharp
            // corner places its points by their supports ([`CornerPart`]).
            RoundingKind::Corner | RoundingKind::SharpCorner => None,
        }
    }

    /// The far boundaries held whole (position and normal, section 6.2), as segments of the
    /// parameter domain; the others (where a boundary crosses an old edge) slide.
    pub fn held_boundaries(&self) -> &[[Point2; 2]] {
        &self.held
    }

    /// The held generalized coordinates (`4 c + k`, `k = 3` the weight): all four of each
    /// [`RoundingModel::fixed_controls`] entry, the axis and the weight of each
    /// [`RoundingModel::sliding`] entry.
    pub fn fixed_coordinates(&self) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .fixed_controls
            .iter()
            .flat_map(|&c| (0..4).map(move |k| 4 * c + k))
            .chain(
                self.sliding
                    .iter()
                    .flat_map(|&(c, a)| [4 * c + a, 4 * c + 3]),
            )
            .collect();
        out.sort_unstable();
        out
    }

    /// The D-NURBS model: the Table 1 material read over [`RoundingKind::span`]
    /// ([`RoundingKind::material`]), the paper's absolute energy, the constraints, and
    /// the weight penalty [`ROUNDING_WEIGHT_PENALTY`] (weights stay dynamic).
    pub fn dynamics(
        &self,
        quadrature: TriangleQuadrature,
    ) -> Result<GeneralizedDnurbs<TriangularGeometry>, DynamicsError> {
        self.dynamics_with_material(quadrature, self.kind.material())
    }

    /// [`RoundingModel::dynamics`] with another material (the limitation study of issue 28,
    /// see the module docs).
    pub fn dynamics_with_material(
        &self,
        quadrature: TriangleQuadrature,
        material: Material,
    ) -> Result<GeneralizedDnurbs<TriangularGeometry>, DynamicsError> {
        let geometry = TriangularGeometry::new(self.surface.clone()).with_quadrature(quadrature);
        let mut m = GeneralizedDnurbs::new(geometry, material)?;
        m.set_elastic_reference(ElasticReference::Absolute);
        m.set_weight_penalty(ROUNDING_WEIGHT_PENALTY)?;
        for i in self.fixed_coordinates() {
            m.set_fixed_coordinate(i, true)?;
        }
        for c in &self.constraints {
            m.add_constraint(c.clone())?;
        }
        Ok(m)
    }

    /// The Table 1 time step.
    pub fn dt(&self) -> f64 {
        self.kind.preset().dt
    }
}

/// The axis (0, 1, 2 for x, y, z) of the old cube edge that a boundary segment of the corner
/// domain crosses, or `None` for a segment inside one face. The edges are the rays at 30, 150
/// and 270 degrees; [`corner_map`] sends each onto a negative coordinate axis.
fn corner_crossing(seg: [Point2; 2]) -> Option<usize> {
    [30.0f64, 150.0, 270.0].iter().find_map(|&deg| {
        let a = deg.to_radians();
        let d = [a.cos(), a.sin()];
        // Signed distances of the ends from the ray's line, and the crossing point's position
        // along the ray.
        let side = |q: Point2| q[0] * d[1] - q[1] * d[0];
        let (s0, s1) = (side(seg[0]), side(seg[1]));
        if s0 * s1 >= 0.0 {
            return None;
        }
        let f = s0 / (s0 - s1);
        let x = [
            seg[0][0] + f * (seg[1][0] - seg[0][0]),
            seg[0][1] + f * (seg[1][1] - seg[0][1]),
        ];
        if x[0] * d[0] + x[1] * d[1] <= 0.0 {
            return None;
        }
        let e = corner_map(x);
        (0..3).max_by(|&i, &j| e[i].abs().total_cmp(&e[j].abs()))
    })
}

/// The boundary edges of a triangulation, as segments.
fn boundary_edges(dom: &Triangulation) -> Vec<[Point2; 2]> {
    let mut count = std::collections::HashMap::new();
    for t in dom.triangles() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
        }
    }
    let mut out = Vec::new();
    for t in dom.triangles() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            if count[&(a.min(b), a.max(b))] == 1 {
                out.push([dom.vertices()[a], dom.vertices()[b]]);
            }
        }
    }
    out
}

/// The largest angle (radians) between surface normals at parameter pairs straddling the
/// segments `edges` at distance `delta` on either side, sampled at `samples` points per
/// segment (ends excluded). For a `C^1` surface it tends to 0 with `delta`. A pair where the
/// surface has no normal (`|s_u x s_v|` under 1e-9 of `(|s_u| + |s_v|)^2`, inside the collapsed column of an
/// [`InitialShape::Sharp`] model, whose image is the edge line) is skipped.
pub fn normal_jump(
    surface: &TriangularNurbs,
    edges: &[[Point2; 2]],
    delta: f64,
    samples: usize,
) -> Result<f64, DynamicsError> {
    let dom = surface.basis().domain();
    let mut worst = 0.0f64;
    for seg in edges {
        let d = [seg[1][0] - seg[0][0], seg[1][1] - seg[0][1]];
        let l = d[0].hypot(d[1]);
        let n = [-d[1] / l, d[0] / l];
        for k in 1..=samples {
            let f = k as f64 / (samples + 1) as f64;
            let q = [seg[0][0] + f * d[0], seg[0][1] + f * d[1]];
            let a = [q[0] + delta * n[0], q[1] + delta * n[1]];
            let b = [q[0] - delta * n[0], q[1] - delta * n[1]];
            if dom.locate(a).is_none() || dom.locate(b).is_none() {
                continue;
            }
            let nor = |x: Point2| -> Result<Option<Vec3>, DynamicsError> {
                let s = surface
                    .derivatives(x)
                    .map_err(|e| DynamicsError::Spline(e.into()))?;
                // No normal where the tangents are parallel to rounding (1e-9 of their size).
                let size = (s[1].norm() + s[2].norm()).powi(2);
                Ok(s[1].cross(&s[2]).try_normalize(1e-9 * size))
            };
            if let (Some(na), Some(nb)) = (nor(a)?, nor(b)?) {
                worst = worst.max(na.dot(&nb).clamp(-1.0, 1.0).acos());
            }
        }
    }
    Ok(worst)
}

/// Signed turning of a surface mesh across its interior edges: for each edge shared by two
/// non-degenerate triangles, `l theta` with `l` the edge length and `theta` the signed angle
/// between the two triangle normals, positive where the surface bends away from its normal
/// (convex on the normal side), negative where it bends towards it. A convex fillet turns one
/// way only; the share of the other way ([`Turning::wrong_way`]) measures folds and ripples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Turning {
    /// Sum of `l theta` over the edges with `theta > 0`.
    pub positive: f64,
    /// Sum of `l |theta|` over the edges with `theta < 0`.
    pub negative: f64,
}

impl Turning {
    /// The smaller of the two sums as a share of their total (0 for a surface that turns one
    /// way only, 0.5 for equal turning both ways; 0 for a plane).
    pub fn wrong_way(&self) -> f64 {
        let total = self.positive + self.negative;
        if total > 0.0 {
            self.positive.min(self.negative) / total
        } else {
            0.0
        }
    }
}

/// The [`Turning`] of a counter-clockwise triangle mesh (vertices shared between triangles;
/// triangles with an area below `1e-12` of the largest are skipped, so collapsed regions
/// count as holes).
pub fn mesh_turning(mesh: &vclay_core::TriMesh) -> Turning {
    let p = &mesh.positions;
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| p[i as usize]);
        (b - a).cross(&(c - a))
    };
    let largest = mesh
        .triangles
        .iter()
        .map(|t| normal(t).norm())
        .fold(0.0, f64::max);
    let mut by_edge: std::collections::HashMap<(u32, u32), Vec3> = Default::default();
    for t in &mesh.triangles {
        let n = normal(t);
        if n.norm() <= 1e-12 * largest {
            continue;
        }
        for e in 0..3 {
            by_edge.insert((t[e], t[(e + 1) % 3]), n.normalize());
        }
    }
    let mut out = Turning::default();
    for (&(a, b), n1) in &by_edge {
        // Each interior edge once: from the triangle that runs it a -> b with a < b.
        if a > b {
            continue;
        }
        let Some(n2) = by_edge.get(&(b, a)) else {
            continue;
        };
        let e = p[b as usize] - p[a as usize];
        let l = e.norm();
        if l == 0.0 {
            continue;
        }
        let theta = (n1.cross(n2).dot(&e) / l).atan2(n1.dot(n2));
        if theta > 0.0 {
            out.positive += l * theta;
        } else {
            out.negative -= l * theta;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 28, why the paper's 78-point corner keeps the `C^1` start: on its domain some
    /// held control points belong to functions whose supports reach both faces next to a cube
    /// edge ([`corner_part`]), so no placement of them is both on the faces and at the held
    /// position of the fillet; on the sharp corner's domain none does (its constructor checks
    /// it). Printed: the counts.
    #[test]
    fn held_functions_reach_across_an_edge_on_the_paper_domain_only() {
        let count = |kind| {
            let r = RoundingModel::with_initial(kind, InitialShape::Rounded).unwrap();
            let basis = r.surface.basis();
            let held = r
                .fixed_controls
                .iter()
                .filter(|&&c| !matches!(corner_part(basis, c), CornerPart::Face(_)))
                .count();
            let sliding = r
                .sliding
                .iter()
                .filter(|&&(c, axis)| {
                    !matches!(corner_part(basis, c), CornerPart::Face(_))
                        && corner_part(basis, c) != CornerPart::Edge(axis)
                })
                .count();
            eprintln!(
                "{kind:?}: {} functions, {} held ({held} reach across an edge), {} sliding ({sliding} off their edge)",
                basis.len(),
                r.fixed_controls.len(),
                r.sliding.len()
            );
            held + sliding
        };
        assert!(count(RoundingKind::Corner) > 0);
        assert_eq!(count(RoundingKind::SharpCorner), 0);
    }
}
