//! The limit boundary surface of a subdivision solid: points and normals for display, and
//! bicubic patches for exchange formats (issues 19 and 20).
//!
//! # What
//! With [`BoundaryRule::Smooth`] or [`BoundaryRule::Sharp`] the boundary points of every level
//! depend only on boundary points, through the Catmull-Clark surface rules with simple creases
//! (module docs of [`mod@crate::subdivide`]). The boundary limit surface is therefore the
//! Catmull-Clark limit surface of the boundary net, and its points at the vertices of any level
//! are given by the limit masks (Halstead, Kass, DeRose 1993, "Efficient, fair interpolation
//! using Catmull-Clark surfaces", eq 5 and the tangent masks of their appendix):
//!
//! ```text
//! smooth vertex of valence n:  x = (n^2 p + 4 sum_i e_i + sum_i f_i) / (n (n + 5))
//! tangents:  t1 = sum_i A_n cos(2 pi i/n) e_i + (cos(2 pi i/n) + cos(2 pi (i+1)/n)) f_i,
//!            t2 = the same with sin,  A_n = 1 + cos(2 pi/n) + cos(pi/n) sqrt(2 (9 + cos(2 pi/n)))
//! crease vertex (two crease edges to q1, q2):  x = (q1 + 4 p + q2) / 6
//! corner vertex:  x = p
//! ```
//! where `e_i` are the edge neighbours of `p` on the boundary in counter-clockwise order (seen
//! from outside) and `f_i` the diagonal vertices of the quads between `e_i` and `e_{i+1}`.
//! The normal of a smooth vertex is `t1 x t2` (unit); at crease and corner vertices it is the
//! average of the adjacent face normals (an approximation: the surface has no single normal
//! there).
//!
//! * [`write_limit_boundary`]: the boundary faces of a subdivided level with every vertex moved
//!   to its limit position and given its normal, through a [`MeshSink`] (the display path).
//! * [`boundary_patches`]: one bicubic Bezier patch per boundary quad of the control lattice:
//!   **exact** where the quad's four corners are smooth vertices of valence 4 (the boundary limit
//!   there is the uniform bicubic B-spline of the `4 x 4` neighbouring boundary points, converted
//!   to Bezier form), **least-squares fitted** elsewhere to the limit points of the
//!   `(2^L + 1)^2` level-`L` vertices on the quad (corners interpolated, each edge curve fitted
//!   to the samples on that edge alone so neighbouring patches share their boundary curves, then
//!   the four inner points), with the fit error reported (maximum and mean distance at the
//!   samples, relative to the bounding-box diagonal).
//!
//! # Limitations
//! * [`BoundaryRule::Interior`] has no surface rule (the lattice shrinks): refused.
//! * Darts (a boundary vertex on exactly one crease edge) use the smooth mask, which is exact
//!   only when no crease edge ends there; fitted patches near them carry the error.
//! * Fitted patches meet their neighbours with position continuity along the shared edge curves
//!   (identical fits of identical samples), not tangent continuity; the error is measured at the
//!   samples the fit used.

use vclay_core::{MeshSink, Vec3};
use vclay_spline::NurbsSurface;

use crate::error::LatticeError;
use crate::hierarchy::SubdivisionSolid;
use crate::ids::{EdgeId, FaceId, VertexId};
use crate::lattice::Lattice;
use crate::subdivide::{BoundaryRule, Features, SubdivisionRules};

/// Default of `levels` in [`boundary_patches`]: 3 (9 x 9 limit samples per control quad).
pub const DEFAULT_PATCH_SAMPLE_LEVELS: usize = 3;
/// Most subdivided cells [`boundary_patches`] will build (the level-`L` solid): 4 million.
pub const MAX_PATCH_SAMPLE_CELLS: usize = 4_000_000;

/// The limit position and normal of one boundary vertex, and how it was obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceLimit {
    /// Limit position.
    pub position: Vec3,
    /// Unit outward normal.
    pub normal: Vec3,
    /// Whether the vertex is smooth (Catmull-Clark limit mask) rather than crease or corner.
    pub smooth: bool,
}

/// The ordered one-ring of a boundary vertex on the boundary surface: edge neighbours `e_i` and
/// diagonal vertices `f_i`, counter-clockwise seen from outside. `None` when a boundary face at
/// the vertex is not a quad or the faces do not form one closed fan.
fn ring(l: &Lattice, v: VertexId) -> Option<(Vec<VertexId>, Vec<VertexId>, Vec<FaceId>)> {
    let faces: Vec<FaceId> = l
        .vertex_faces(v)
        .iter()
        .copied()
        .filter(|&f| l.is_boundary_face(f))
        .collect();
    let mut parts = Vec::with_capacity(faces.len());
    for &f in &faces {
        let vs = l.face_vertices(f);
        if vs.len() != 4 {
            return None;
        }
        let p = vs.iter().position(|&x| x == v)?;
        // A boundary face's stored loop is outward: v -> e_a -> diag -> e_b.
        parts.push((vs[(p + 1) % 4], vs[(p + 2) % 4], vs[(p + 3) % 4], f));
    }
    let n = parts.len();
    if n < 3 {
        return None;
    }
    let (mut e, mut d, mut fs) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::new());
    let mut cur = 0;
    for _ in 0..n {
        let (ea, diag, eb, f) = parts[cur];
        e.push(ea);
        d.push(diag);
        fs.push(f);
        cur = parts.iter().position(|q| q.0 == eb)?;
    }
    if cur != 0 {
        return None;
    }
    let mut seen = fs.clone();
    seen.sort_unstable();
    seen.dedup();
    (seen.len() == n).then_some((e, d, fs))
}

/// Which boundary edges act as creases under `rule` (the classification of
/// [`mod@crate::subdivide`]).
fn crease_edges(l: &Lattice, features: &Features, rule: BoundaryRule) -> Vec<bool> {
    (0..l.num_edges())
        .map(|e| {
            let eid = EdgeId(e as u32);
            let nb = l
                .edge_faces(eid)
                .iter()
                .filter(|&&f| l.is_boundary_face(f))
                .count();
            features.is_crease(eid)
                || (nb > 0 && nb != 2)
                || (rule == BoundaryRule::Sharp && nb > 0 && l.edge_cells(eid).len() != 2)
        })
        .collect()
}

fn face_normal(l: &Lattice, f: FaceId) -> Vec3 {
    let vs = l.face_vertices(f);
    let mut n = Vec3::zeros();
    for i in 0..vs.len() {
        let a = l.point(vs[i]);
        let b = l.point(vs[(i + 1) % vs.len()]);
        n += a.cross(&b);
    }
    n
}

fn unit(v: Vec3) -> Vec3 {
    let n = v.norm();
    if n > 0.0 { v / n } else { v }
}

/// Limit positions and normals of every boundary vertex of `l` (a level of a subdivision solid
/// with `features` and `rule`); `None` for interior vertices. See the [module docs](self).
pub fn boundary_limits(
    l: &Lattice,
    features: &Features,
    rule: BoundaryRule,
) -> Result<Vec<Option<SurfaceLimit>>, LatticeError> {
    if rule == BoundaryRule::Interior {
        return Err(LatticeError::LimitParameter {
            message: "the boundary limit surface needs the Smooth or Sharp boundary rule (the Interior rule has no surface rule)".into(),
        });
    }
    l.build_adjacency();
    let crease = crease_edges(l, features, rule);
    let mut out = vec![None; l.num_points()];
    for (i, slot) in out.iter_mut().enumerate() {
        let v = VertexId(i as u32);
        if !l.is_boundary_vertex(v) {
            continue;
        }
        let avg_normal = unit(
            l.vertex_faces(v)
                .iter()
                .filter(|&&f| l.is_boundary_face(f))
                .map(|&f| unit(face_normal(l, f)))
                .sum(),
        );
        let ce: Vec<VertexId> = l
            .vertex_edges(v)
            .iter()
            .filter(|&&e| crease[e.index()])
            .map(|&e| {
                let [a, b] = l.edge_vertices(e);
                if a == v { b } else { a }
            })
            .collect();
        let p = l.point(v);
        let r = if features.is_corner(v) || ce.len() >= 3 {
            None
        } else if ce.len() == 2 {
            Some((l.point(ce[0]) + 4.0 * p + l.point(ce[1])) / 6.0)
        } else {
            Some(p)
        };
        let ring = if ce.len() <= 1 && !features.is_corner(v) {
            ring(l, v)
        } else {
            None
        };
        *slot = Some(match (ring, r) {
            (Some((e, d, _)), _) => {
                let n = e.len();
                let nf = n as f64;
                let mut x = nf * nf * p;
                let (mut t1, mut t2) = (Vec3::zeros(), Vec3::zeros());
                let tau = std::f64::consts::TAU;
                let c = (tau / nf).cos();
                let a = 1.0 + c + (std::f64::consts::PI / nf).cos() * (2.0 * (9.0 + c)).sqrt();
                for i in 0..n {
                    let (pe, pd) = (l.point(e[i]), l.point(d[i]));
                    x += 4.0 * pe + pd;
                    let (ci, cj) = (
                        (tau * i as f64 / nf).cos(),
                        (tau * (i + 1) as f64 / nf).cos(),
                    );
                    let (si, sj) = (
                        (tau * i as f64 / nf).sin(),
                        (tau * (i + 1) as f64 / nf).sin(),
                    );
                    t1 += a * ci * pe + (ci + cj) * pd;
                    t2 += a * si * pe + (si + sj) * pd;
                }
                let mut normal = unit(t1.cross(&t2));
                if normal.dot(&avg_normal) < 0.0 {
                    normal = -normal;
                }
                SurfaceLimit {
                    position: x / (nf * (nf + 5.0)),
                    normal,
                    smooth: true,
                }
            }
            (None, r) => SurfaceLimit {
                // Corners stay; crease vertices follow the cubic B-spline curve; a vertex whose
                // fan is not a closed ring of quads (level 0 only) keeps its point.
                position: r.unwrap_or(p),
                normal: avg_normal,
                smooth: false,
            },
        });
    }
    Ok(out)
}

/// Writes the boundary of `l` (a level of a subdivision solid, usually the finest) with every
/// vertex at its limit position and with its limit normal; returns the number of triangles.
/// Faces are fan-triangulated, oriented outward (as [`crate::write_boundary`]).
pub fn write_limit_boundary<S: MeshSink + ?Sized>(
    l: &Lattice,
    features: &Features,
    rule: BoundaryRule,
    sink: &mut S,
) -> Result<usize, LatticeError> {
    let limits = boundary_limits(l, features, rule)?;
    let mut remap = vec![u32::MAX; l.num_points()];
    let faces: Vec<FaceId> = l.boundary_faces().collect();
    let ntris: usize = faces.iter().map(|&f| l.face_vertices(f).len() - 2).sum();
    let nverts = limits.iter().filter(|x| x.is_some()).count();
    sink.reserve(nverts, ntris);
    for (v, lim) in limits.iter().enumerate() {
        if let Some(s) = lim {
            remap[v] = sink.add_vertex(s.position, Some(s.normal));
        }
    }
    for f in faces {
        let vs = l.face_vertices(f);
        for i in 1..vs.len() - 1 {
            sink.add_triangle([
                remap[vs[0].index()],
                remap[vs[i].index()],
                remap[vs[i + 1].index()],
            ]);
        }
    }
    Ok(ntris)
}

/// Bicubic patches of the boundary limit surface and their fit error (see
/// [`boundary_patches`]).
#[derive(Clone, Debug)]
pub struct LimitPatches {
    /// One bicubic Bezier patch (degree 3 x 3, knots `[0,0,0,0,1,1,1,1]`) per boundary quad of
    /// the base level, `s x t` pointing outward.
    pub patches: Vec<NurbsSurface>,
    /// Per patch: exact (regular region) or fitted.
    pub exact: Vec<bool>,
    /// Per patch: the boundary face of the base level it covers.
    pub faces: Vec<FaceId>,
    /// The base level: 0, or 1 when the control lattice has a non-quadrilateral boundary face.
    pub base_level: usize,
    /// Level whose vertices were the limit samples.
    pub sample_level: usize,
    /// Largest distance between a patch and the limit at the samples, relative to the
    /// bounding-box diagonal of the control points.
    pub max_error: f64,
    /// Mean of those distances (relative), over every sample of every patch.
    pub mean_error: f64,
    /// Largest relative distance over the exact patches alone (rounding only: it checks that the
    /// regular-region B-spline equals the Catmull-Clark limit).
    pub max_error_exact: f64,
}

/// `points[a][b]` of the uniform bicubic B-spline grid (4 x 4) in Bezier form.
fn bspline_to_bezier(g: &[[Vec3; 4]; 4]) -> Vec<Vec<Vec3>> {
    let m = [
        [1.0, 4.0, 1.0, 0.0],
        [0.0, 4.0, 2.0, 0.0],
        [0.0, 2.0, 4.0, 0.0],
        [0.0, 1.0, 4.0, 1.0],
    ];
    let mut tmp = [[Vec3::zeros(); 4]; 4];
    for i in 0..4 {
        for b in 0..4 {
            tmp[i][b] = (0..4).map(|a| m[i][a] / 6.0 * g[a][b]).sum();
        }
    }
    (0..4)
        .map(|i| {
            (0..4)
                .map(|j| (0..4).map(|b| m[j][b] / 6.0 * tmp[i][b]).sum())
                .collect()
        })
        .collect()
}

fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

fn bezier_point(b: &[Vec<Vec3>], s: f64, t: f64) -> Vec3 {
    let (bs, bt) = (bernstein(s), bernstein(t));
    let mut x = Vec3::zeros();
    for i in 0..4 {
        for j in 0..4 {
            x += bs[i] * bt[j] * b[i][j];
        }
    }
    x
}

/// The `4 x 4` boundary grid around a boundary quad whose corners are smooth valence-4 vertices,
/// `None` otherwise. Loop `c0 c1 c2 c3` (outward); `s` along `c0 -> c1`, `t` along `c0 -> c3`.
fn regular_quad_grid(
    l: &Lattice,
    limits: &[Option<SurfaceLimit>],
    crease: &[bool],
    f: FaceId,
) -> Option<[[VertexId; 4]; 4]> {
    let c = l.face_vertices(f);
    const D: [(i32, i32); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];
    const POS: [(i32, i32); 4] = [(1, 1), (2, 1), (2, 2), (1, 2)];
    let mut g = [[None::<VertexId>; 4]; 4];
    for m in 0..4 {
        let v = c[m];
        if !limits[v.index()].is_some_and(|s| s.smooth)
            || l.vertex_edges(v)
                .iter()
                .any(|&e| crease[e.index()] && l.is_boundary_edge(e))
        {
            return None;
        }
        let (e, d, fs) = ring(l, v)?;
        if e.len() != 4 {
            return None;
        }
        let k0 = fs.iter().position(|&x| x == f)?;
        let mut set = |(a, b): (i32, i32), x: VertexId| -> Option<()> {
            if !(0..4).contains(&a) || !(0..4).contains(&b) {
                return None;
            }
            let slot = &mut g[a as usize][b as usize];
            match slot {
                Some(y) if *y != x => None,
                _ => {
                    *slot = Some(x);
                    Some(())
                }
            }
        };
        let (pa, pb) = POS[m];
        set((pa, pb), v)?;
        for r in 0..4 {
            let (da, db) = D[(m + r) % 4];
            let (ea, eb) = D[(m + r + 1) % 4];
            set((pa + da, pb + db), e[(k0 + r) % 4])?;
            set((pa + da + ea, pb + db + eb), d[(k0 + r) % 4])?;
        }
    }
    let mut out = [[VertexId(0); 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            out[a][b] = g[a][b]?;
        }
    }
    Some(out)
}

/// Refines a face's vertex grid (`(n+1)^2` ids in `coarse`, `[i][j]` with `i` along `s`) to the
/// `(2n+1)^2` ids in `fine = subdivide(coarse)`.
fn refine_grid(coarse: &Lattice, grid: &[Vec<VertexId>]) -> Option<Vec<Vec<VertexId>>> {
    let n = grid.len() - 1;
    let (np, ne) = (coarse.num_points() as u32, coarse.num_edges() as u32);
    let mut out = vec![vec![VertexId(0); 2 * n + 1]; 2 * n + 1];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, slot) in row.iter_mut().enumerate() {
            let (a, b) = (i / 2, j / 2);
            *slot = match (i % 2, j % 2) {
                (0, 0) => grid[a][b],
                (1, 0) => VertexId(np + coarse.edge_between(grid[a][b], grid[a + 1][b])?.0),
                (0, 1) => VertexId(np + coarse.edge_between(grid[a][b], grid[a][b + 1])?.0),
                _ => {
                    let f = coarse.face_with_vertices(&[
                        grid[a][b],
                        grid[a + 1][b],
                        grid[a + 1][b + 1],
                        grid[a][b + 1],
                    ])?;
                    VertexId(np + ne + f.0)
                }
            };
        }
    }
    Some(out)
}

/// Least-squares fit of the two inner control points of a cubic Bezier curve with fixed ends
/// to samples at `t_k = k / (m - 1)`.
fn fit_edge(samples: &[Vec3]) -> [Vec3; 4] {
    let m = samples.len();
    let (p0, p3) = (samples[0], samples[m - 1]);
    let (mut a11, mut a12, mut a22) = (0.0, 0.0, 0.0);
    let (mut r1, mut r2) = (Vec3::zeros(), Vec3::zeros());
    for (k, x) in samples.iter().enumerate() {
        let b = bernstein(k as f64 / (m - 1) as f64);
        let rhs = x - b[0] * p0 - b[3] * p3;
        a11 += b[1] * b[1];
        a12 += b[1] * b[2];
        a22 += b[2] * b[2];
        r1 += b[1] * rhs;
        r2 += b[2] * rhs;
    }
    let det = a11 * a22 - a12 * a12;
    let p1 = (a22 * r1 - a12 * r2) / det;
    let p2 = (a11 * r2 - a12 * r1) / det;
    [p0, p1, p2, p3]
}

/// Bicubic Bezier patch fitted to a `(m x m)` sample grid at `s_i = i/(m-1)`, `t_j = j/(m-1)`:
/// corners interpolated, edges fitted per edge, the four inner points by least squares.
fn fit_patch(x: &[Vec<Vec3>]) -> Vec<Vec<Vec3>> {
    let m = x.len();
    let mut b = vec![vec![Vec3::zeros(); 4]; 4];
    let e0 = fit_edge(&(0..m).map(|i| x[i][0]).collect::<Vec<_>>());
    let e1 = fit_edge(&(0..m).map(|i| x[i][m - 1]).collect::<Vec<_>>());
    let e2 = fit_edge(&x[0]);
    let e3 = fit_edge(&x[m - 1]);
    for k in 0..4 {
        b[k][0] = e0[k];
        b[k][3] = e1[k];
        b[0][k] = e2[k];
        b[3][k] = e3[k];
    }
    // Normal equations for the unknowns b[1][1], b[1][2], b[2][1], b[2][2].
    let idx = [(1, 1), (1, 2), (2, 1), (2, 2)];
    let mut a = nalgebra::Matrix4::<f64>::zeros();
    let mut r = nalgebra::Matrix4x3::<f64>::zeros();
    for (i, row) in x.iter().enumerate() {
        for (j, xij) in row.iter().enumerate() {
            let (bs, bt) = (
                bernstein(i as f64 / (m - 1) as f64),
                bernstein(j as f64 / (m - 1) as f64),
            );
            let mut rhs = *xij;
            for p in 0..4 {
                for q in 0..4 {
                    if !idx.contains(&(p, q)) {
                        rhs -= bs[p] * bt[q] * b[p][q];
                    }
                }
            }
            let w: [f64; 4] = idx.map(|(p, q)| bs[p] * bt[q]);
            for u in 0..4 {
                for v in 0..4 {
                    a[(u, v)] += w[u] * w[v];
                }
                for c in 0..3 {
                    r[(u, c)] += w[u] * rhs[c];
                }
            }
        }
    }
    if let Some(sol) = a.lu().solve(&r) {
        for (u, &(p, q)) in idx.iter().enumerate() {
            b[p][q] = Vec3::new(sol[(u, 0)], sol[(u, 1)], sol[(u, 2)]);
        }
    }
    b
}

/// Bicubic patches of the boundary limit surface of the solid with control lattice `control`
/// (see the [module docs](self)): exact in regular regions, fitted elsewhere to the limit at the
/// level-`levels` vertices, with the error.
///
/// Errors: [`BoundaryRule::Interior`]; `levels` of 0 or a level-`levels` solid above
/// [`MAX_PATCH_SAMPLE_CELLS`] cells; a lattice without boundary.
pub fn boundary_patches(
    control: &Lattice,
    features: &Features,
    rules: SubdivisionRules,
    levels: usize,
) -> Result<LimitPatches, LatticeError> {
    if rules.boundary == BoundaryRule::Interior {
        return Err(LatticeError::LimitParameter {
            message: "boundary patches need the Smooth or Sharp boundary rule".into(),
        });
    }
    control.build_adjacency();
    let base_level = usize::from(
        control
            .boundary_faces()
            .any(|f| control.face_vertices(f).len() != 4),
    );
    let total = levels + base_level;
    let cells = (control.num_cells() as f64) * 8f64.powi(total as i32);
    if levels == 0 || cells > MAX_PATCH_SAMPLE_CELLS as f64 {
        return Err(LatticeError::LimitParameter {
            message: format!(
                "{levels} sample levels would subdivide to about {cells:.0} cells (1 to {} levels and at most {MAX_PATCH_SAMPLE_CELLS} cells)",
                levels.max(1)
            ),
        });
    }
    let solid = SubdivisionSolid::new(control.clone(), features.clone(), rules, total)?;
    let base = solid.lattice(base_level);
    let base_feat = solid.features(base_level);
    let crease = crease_edges(base, base_feat, rules.boundary);
    let base_limits = boundary_limits(base, base_feat, rules.boundary)?;
    let fine = solid.finest();
    let fine_limits = boundary_limits(fine, solid.features(total), rules.boundary)?;
    let (lo, hi) = control.points().iter().fold(
        (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let diag = (hi - lo).norm().max(f64::MIN_POSITIVE);
    let knots = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
    let mut out = LimitPatches {
        patches: Vec::new(),
        exact: Vec::new(),
        faces: Vec::new(),
        base_level,
        sample_level: total,
        max_error: 0.0,
        mean_error: 0.0,
        max_error_exact: 0.0,
    };
    let mut sum = 0.0;
    let mut count = 0usize;
    let faces: Vec<FaceId> = base.boundary_faces().collect();
    if faces.is_empty() {
        return Err(LatticeError::LimitParameter {
            message: "the lattice has no boundary face".into(),
        });
    }
    for f in faces {
        let vs = base.face_vertices(f);
        // Sample grid: [i][j], i along s = c0 -> c1, j along t = c0 -> c3.
        let mut grid = vec![vec![vs[0], vs[3]], vec![vs[1], vs[2]]];
        for j in base_level..total {
            grid = refine_grid(solid.lattice(j), &grid).ok_or(LatticeError::LimitParameter {
                message: format!("internal: cannot follow boundary {f} to level {}", j + 1),
            })?;
        }
        let samples: Vec<Vec<Vec3>> = grid
            .iter()
            .map(|row| {
                row.iter()
                    .map(|v| fine_limits[v.index()].map_or(fine.point(*v), |s| s.position))
                    .collect()
            })
            .collect();
        let (bez, exact) = match regular_quad_grid(base, &base_limits, &crease, f) {
            Some(g) => {
                let pts = g.map(|row| row.map(|v| base.point(v)));
                (bspline_to_bezier(&pts), true)
            }
            None => (fit_patch(&samples), false),
        };
        let m = samples.len();
        for (i, row) in samples.iter().enumerate() {
            for (j, x) in row.iter().enumerate() {
                let d = (bezier_point(&bez, i as f64 / (m - 1) as f64, j as f64 / (m - 1) as f64)
                    - x)
                    .norm()
                    / diag;
                out.max_error = out.max_error.max(d);
                if exact {
                    out.max_error_exact = out.max_error_exact.max(d);
                }
                sum += d;
                count += 1;
            }
        }
        let patch =
            NurbsSurface::new([3, 3], [knots.clone(), knots.clone()], bez, None).map_err(|e| {
                LatticeError::LimitParameter {
                    message: format!("patch of {f}: {e}"),
                }
            })?;
        out.patches.push(patch);
        out.exact.push(exact);
        out.faces.push(f);
    }
    out.mean_error = sum / count.max(1) as f64;
    Ok(out)
}
