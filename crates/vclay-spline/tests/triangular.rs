//! DMS triangular B-splines and triangular NURBS (`d-nurbs.txt` section 4.4, eqs 10-14):
//! partition of unity, polynomial reproduction, reduction to Bezier triangles (against an
//! independent de Casteljau), derivatives against finite differences, validation errors.

use vclay_core::Vec3;
use vclay_spline::simplex::{Point2, SimplexSpline};
use vclay_spline::triangular::{
    DEFAULT_CLOUD_RADIUS, KnotClouds, TriangularBasis, TriangularError, TriangularNurbs,
    TriangularPoint, Triangulation, multi_indices,
};

/// A small seeded generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A jittered `m x m` grid on [0, 1]^2 with random diagonals.
fn random_triangulation(m: usize, rng: &mut Rng) -> Triangulation {
    let mut v = Vec::new();
    for i in 0..=m {
        for j in 0..=m {
            let inner = i > 0 && i < m && j > 0 && j < m;
            let jit = |r: &mut Rng| {
                if inner {
                    (r.next() - 0.5) * 0.3 / m as f64
                } else {
                    0.0
                }
            };
            v.push([
                i as f64 / m as f64 + jit(rng),
                j as f64 / m as f64 + jit(rng),
            ]);
        }
    }
    let id = |i: usize, j: usize| i * (m + 1) + j;
    let mut t = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if rng.next() < 0.5 {
                t.push([a, b, c]);
                t.push([a, c, d]);
            } else {
                t.push([a, b, d]);
                t.push([b, c, d]);
            }
        }
    }
    Triangulation::new(v, t).unwrap()
}

fn basis(m: usize, n: usize, radius: f64, seed: u64) -> TriangularBasis {
    let mut rng = Rng(seed);
    let tri = random_triangulation(m, &mut rng);
    let clouds = KnotClouds::around_vertices(&tri, n, radius).unwrap();
    TriangularBasis::new(n, tri, clouds).unwrap()
}

fn sum_at(b: &TriangularBasis, x: Point2, coef: impl Fn(usize) -> f64) -> [f64; 6] {
    let mut s = [0.0; 6];
    for (f, v) in b.nonzero(x).unwrap() {
        let c = coef(f);
        for m in 0..6 {
            s[m] += c * v[m];
        }
    }
    s
}

/// The knots `r_0..r_{b0-1}, s_0..s_{b1-1}, t_0..t_{b2-1}` whose blossom is a control point.
fn blossom_args(b: &TriangularBasis, f: usize) -> Vec<Point2> {
    let (t, beta) = b.function_index(f);
    let tri = b.domain().triangles()[t];
    let mut a = Vec::new();
    for c in 0..3 {
        for k in 0..beta[c] {
            a.push(b.clouds().clouds[tri[c]][k]);
        }
    }
    a
}

/// Blossom of `F(u, v) = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2` in `n = args.len()` arguments.
fn blossom(c: [f64; 6], args: &[Point2]) -> f64 {
    let n = args.len() as f64;
    let mean = |k: usize| args.iter().map(|a| a[k]).sum::<f64>() / n;
    let pair = |k: usize, l: usize| {
        let mut s = 0.0;
        for i in 0..args.len() {
            for j in 0..args.len() {
                if i != j {
                    s += args[i][k] * args[j][l];
                }
            }
        }
        s / (n * (n - 1.0))
    };
    let mut r = c[0] + c[1] * mean(0) + c[2] * mean(1);
    if args.len() >= 2 {
        r += c[3] * pair(0, 0) + c[4] * pair(0, 1) + c[5] * pair(1, 1);
    }
    r
}

fn poly(c: [f64; 6], x: Point2) -> [f64; 6] {
    let (u, v) = (x[0], x[1]);
    [
        c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v,
        c[1] + 2.0 * c[3] * u + c[4] * v,
        c[2] + c[4] * u + 2.0 * c[5] * v,
        2.0 * c[3],
        c[4],
        2.0 * c[5],
    ]
}

#[test]
fn partition_of_unity_on_random_triangulations() {
    for (seed, n) in [(1u64, 1usize), (2, 2), (3, 3)] {
        let b = basis(3, n, DEFAULT_CLOUD_RADIUS, seed);
        let mut rng = Rng(seed + 100);
        for _ in 0..200 {
            let x = [rng.next(), rng.next()];
            let s = sum_at(&b, x, |_| 1.0);
            assert!((s[0] - 1.0).abs() < 1e-11, "n={n} x={x:?} sum={}", s[0]);
            for m in 1..6 {
                assert!(
                    s[m].abs() < 1e-8,
                    "n={n} derivative {m} of the sum = {}",
                    s[m]
                );
            }
        }
        // Points on domain edges and vertices (knot lines): the half-open convention keeps
        // the partition of unity.
        for &v in b.domain().vertices() {
            let s = sum_at(&b, v, |_| 1.0);
            assert!(
                (s[0] - 1.0).abs() < 1e-11,
                "n={n} vertex {v:?} sum={}",
                s[0]
            );
        }
        for t in b.domain().triangles() {
            let (p, q) = (b.domain().vertices()[t[0]], b.domain().vertices()[t[1]]);
            let x = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
            let s = sum_at(&b, x, |_| 1.0);
            assert!(
                (s[0] - 1.0).abs() < 1e-11,
                "n={n} edge midpoint {x:?} sum={}",
                s[0]
            );
        }
    }
}

#[test]
fn polynomial_reproduction_with_blossom_control_points() {
    let cases = [
        (11u64, 1usize, [0.3, -1.2, 0.7, 0.0, 0.0, 0.0]),
        (12, 2, [0.3, -1.2, 0.7, 2.0, -1.5, 0.8]),
        (13, 3, [-0.4, 0.5, 1.1, -0.7, 0.9, 1.3]),
    ];
    for (seed, n, c) in cases {
        let b = basis(3, n, DEFAULT_CLOUD_RADIUS, seed);
        let cp: Vec<f64> = (0..b.len())
            .map(|f| blossom(c, &blossom_args(&b, f)))
            .collect();
        let mut rng = Rng(seed * 7);
        for _ in 0..100 {
            let x = [rng.next(), rng.next()];
            let s = sum_at(&b, x, |f| cp[f]);
            let e = poly(c, x);
            for m in 0..6 {
                assert!(
                    (s[m] - e[m]).abs() < 1e-8 * (1.0 + e[m].abs()),
                    "n={n} x={x:?} derivative {m}: {} vs {}",
                    s[m],
                    e[m]
                );
            }
        }
    }
}

/// Independent de Casteljau evaluation of a Bezier triangle with coefficients indexed as
/// `multi_indices(n)` at barycentric `l`.
fn de_casteljau(n: usize, coef: &[f64], l: [f64; 3]) -> f64 {
    let idx = |b: [usize; 3], deg: usize| -> usize {
        multi_indices(deg).iter().position(|x| *x == b).unwrap()
    };
    let mut cur: Vec<f64> = coef.to_vec();
    for deg in (1..=n).rev() {
        let next: Vec<f64> = multi_indices(deg - 1)
            .iter()
            .map(|b| {
                l[0] * cur[idx([b[0] + 1, b[1], b[2]], deg)]
                    + l[1] * cur[idx([b[0], b[1] + 1, b[2]], deg)]
                    + l[2] * cur[idx([b[0], b[1], b[2] + 1], deg)]
            })
            .collect();
        cur = next;
    }
    cur[0]
}

#[test]
fn collapsed_clouds_give_bezier_triangles() {
    // Clouds of radius 1e-5 of the edge length (an exactly collapsed cloud makes the simplex
    // splines degenerate): the DMS functions of a triangle tend to its Bernstein polynomials.
    for (seed, n) in [(21u64, 2usize), (22, 3)] {
        let b = basis(2, n, 1e-5, seed);
        let per = (n + 1) * (n + 2) / 2;
        let mut rng = Rng(seed);
        let coef: Vec<f64> = (0..b.len()).map(|_| rng.next() * 2.0 - 1.0).collect();
        for t in 0..b.domain().triangles().len() {
            for _ in 0..20 {
                // Random barycentric point at least 1e-2 from the edges.
                let (mut a, mut c) = (rng.next(), rng.next());
                if a + c > 1.0 {
                    (a, c) = (1.0 - a, 1.0 - c);
                }
                let l = [
                    0.01 + 0.97 * (1.0 - a - c),
                    0.01 + 0.97 * a,
                    0.01 + 0.97 * c,
                ];
                let k = b.domain().corners(t);
                let x = [0, 1].map(|d| l[0] * k[0][d] + l[1] * k[1][d] + l[2] * k[2][d]);
                let dms = sum_at(&b, x, |f| coef[f])[0];
                let bez = de_casteljau(n, &coef[t * per..(t + 1) * per], l);
                assert!((dms - bez).abs() < 1e-3, "n={n} t={t} {dms} vs {bez}");
            }
        }
    }
}

fn fd_check(val: impl Fn(Point2) -> [f64; 6], x: Point2, tol: f64, what: &str) {
    let h = 1e-6;
    let v = val(x);
    let du = (val([x[0] + h, x[1]])[0] - val([x[0] - h, x[1]])[0]) / (2.0 * h);
    let dv = (val([x[0], x[1] + h])[0] - val([x[0], x[1] - h])[0]) / (2.0 * h);
    let duu = (val([x[0] + h, x[1]])[1] - val([x[0] - h, x[1]])[1]) / (2.0 * h);
    let duv = (val([x[0], x[1] + h])[1] - val([x[0], x[1] - h])[1]) / (2.0 * h);
    let dvv = (val([x[0], x[1] + h])[2] - val([x[0], x[1] - h])[2]) / (2.0 * h);
    let scale = v.iter().fold(1.0f64, |a, b| a.max(b.abs()));
    for (m, fd) in [(1, du), (2, dv), (3, duu), (4, duv), (5, dvv)] {
        assert!(
            (v[m] - fd).abs() < tol * scale,
            "{what}: derivative {m} at {x:?}: {} vs finite difference {fd}",
            v[m]
        );
    }
}

#[test]
fn simplex_spline_derivatives_match_finite_differences() {
    let mut rng = Rng(5);
    for n in 1..=4 {
        let knots: Vec<Point2> = (0..n + 3).map(|_| [rng.next(), rng.next()]).collect();
        let m = SimplexSpline::new(&knots).unwrap();
        assert_eq!(m.degree(), n);
        for _ in 0..20 {
            let x = [0.2 + 0.6 * rng.next(), 0.2 + 0.6 * rng.next()];
            // Second derivatives of a degree-2 spline jump on knot lines: check them for n >= 3.
            let tol = if n >= 3 { 1e-4 } else { f64::INFINITY };
            let v = m.eval(x);
            let h = 1e-6;
            let du = (m.eval([x[0] + h, x[1]])[0] - m.eval([x[0] - h, x[1]])[0]) / (2.0 * h);
            assert!(
                (v[1] - du).abs() < 1e-4 * (1.0 + v[1].abs()) || n == 1,
                "n={n}"
            );
            if tol.is_finite() {
                fd_check(|p| m.eval(p), x, tol, "simplex spline");
            }
        }
    }
}

#[test]
fn basis_derivatives_match_finite_differences() {
    let b = basis(2, 3, DEFAULT_CLOUD_RADIUS, 31);
    let mut rng = Rng(32);
    let coef: Vec<f64> = (0..b.len()).map(|_| rng.next()).collect();
    for _ in 0..30 {
        let x = [0.05 + 0.9 * rng.next(), 0.05 + 0.9 * rng.next()];
        fd_check(|p| sum_at(&b, p, |f| coef[f]), x, 1e-4, "cubic DMS spline");
    }
}

fn surface(seed: u64) -> TriangularNurbs {
    let b = basis(2, 2, DEFAULT_CLOUD_RADIUS, seed);
    let mut rng = Rng(seed + 1);
    let n = b.len();
    let pts: Vec<Vec3> = (0..n)
        .map(|f| {
            let a = blossom_args(&b, f);
            let (u, v) = ((a[0][0] + a[1][0]) / 2.0, (a[0][1] + a[1][1]) / 2.0);
            Vec3::new(u, v, 0.3 * rng.next())
        })
        .collect();
    let w: Vec<f64> = (0..n).map(|_| 0.5 + rng.next()).collect();
    TriangularNurbs::new(b, pts, w, None).unwrap()
}

#[test]
fn rational_surface_derivatives_and_jacobian() {
    let s = surface(41);
    let mut rng = Rng(42);
    let mut p = TriangularPoint::default();
    for _ in 0..20 {
        let x = [0.05 + 0.9 * rng.next(), 0.05 + 0.9 * rng.next()];
        // Parametric derivatives against finite differences, per coordinate.
        for axis in 0..3 {
            fd_check(
                |q| s.derivatives(q).unwrap().map(|v| v[axis]),
                x,
                1e-4,
                "rational surface",
            );
        }
        s.eval(x, &mut p).unwrap();
        // s = J p (eq 14).
        let mut jp = Vec3::zeros();
        for (k, &c) in p.controls.iter().enumerate() {
            jp += s.control_points()[c] * p.r[k][0] + p.g[k][0] * s.weights()[c];
        }
        assert!(
            (jp - p.s[0]).norm() < 1e-12,
            "J p = {jp:?}, s = {:?}",
            p.s[0]
        );
        // Weight columns against finite differences of the surface in the weight.
        for (k, &c) in p.controls.iter().enumerate().take(6) {
            let h = 1e-6;
            let shift = |d: f64| {
                let mut w = s.weights().to_vec();
                w[c] += d;
                let mut t = s.clone();
                t.set_control(s.control_points().to_vec(), w).unwrap();
                t.derivatives(x).unwrap()
            };
            let (a, b) = (shift(h), shift(-h));
            for m in 0..6 {
                let fd = (a[m] - b[m]) / (2.0 * h);
                assert!(
                    (fd - p.g[k][m]).norm() < 1e-5 * (1.0 + fd.norm()),
                    "weight column {k} derivative {m}: {:?} vs {fd:?}",
                    p.g[k][m]
                );
            }
            // Position columns: s is linear in the control points.
            let mut pts = s.control_points().to_vec();
            pts[c].z += 1.0;
            let mut t = s.clone();
            t.set_control(pts, s.weights().to_vec()).unwrap();
            let d = t.derivatives(x).unwrap();
            for m in 0..6 {
                assert!((d[m].z - p.s[m].z - p.r[k][m]).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn tessellation_is_watertight_and_oriented() {
    let s = surface(51);
    let mut mesh = vclay_core::TriMesh::new();
    s.tessellate(4, &mut mesh).unwrap();
    // 8 domain triangles of a 2x2 grid, 16 sub-triangles each; shared vertices on the
    // domain edges: (2*4+1)^2 = 81 distinct vertices.
    assert_eq!(mesh.triangles.len(), 8 * 16);
    assert_eq!(mesh.positions.len(), 81);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        // The test surface is a graph over the (u, v) plane: every triangle faces +z.
        assert!(n.z > 0.0, "triangle {t:?} faces {n:?}");
        assert!(t.iter().all(|&i| mesh.normals[i as usize].z > 0.0));
    }
}

#[test]
fn validation_errors_are_located() {
    let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    assert!(matches!(
        Triangulation::new(v.clone(), vec![[0, 1, 7]]),
        Err(TriangularError::VertexIndex {
            triangle: 0,
            index: 7,
            ..
        })
    ));
    assert!(matches!(
        Triangulation::new(v.clone(), vec![[0, 1, 2], [1, 3, 2], [0, 1, 3]]),
        Err(TriangularError::NonManifoldEdge { .. }) | Err(TriangularError::Overlap { .. })
    ));
    assert!(matches!(
        Triangulation::new(vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], vec![[0, 1, 2]]),
        Err(TriangularError::DegenerateTriangle { triangle: 0, .. })
    ));
    assert!(matches!(
        Triangulation::new(v.clone(), vec![[0, 1, 2]]),
        Err(TriangularError::UnusedVertex { vertex: 3 })
    ));
    let tri = Triangulation::new(v, vec![[0, 1, 2], [1, 3, 2]]).unwrap();
    let mut clouds = KnotClouds::around_vertices(&tri, 2, 0.1).unwrap();
    clouds.clouds[2].pop();
    assert!(matches!(
        TriangularBasis::new(2, tri.clone(), clouds),
        Err(TriangularError::CloudSize {
            vertex: 2,
            found: 2,
            expected: 3
        })
    ));
    // Collinear knots: put knot 1 of vertex 0 on the line through vertex 0 and vertex 1's knot 0.
    let mut clouds = KnotClouds::around_vertices(&tri, 2, 0.1).unwrap();
    clouds.clouds[0][1] = [0.05, 0.0];
    clouds.clouds[0][2] = [0.0, 0.05];
    assert!(matches!(
        TriangularBasis::new(2, tri.clone(), clouds),
        Err(TriangularError::Knots { triangle: 0, .. }) | Err(TriangularError::KnotTriangle { .. })
    ));
    let b = TriangularBasis::new(
        2,
        tri.clone(),
        KnotClouds::around_vertices(&tri, 2, 0.1).unwrap(),
    )
    .unwrap();
    let n = b.len();
    assert!(matches!(
        TriangularNurbs::new(b.clone(), vec![Vec3::zeros(); n], vec![1.0; n - 1], None),
        Err(TriangularError::Shape { .. })
    ));
    let mut w = vec![1.0; n];
    w[3] = -1.0;
    assert!(matches!(
        TriangularNurbs::new(b.clone(), vec![Vec3::zeros(); n], w, None),
        Err(TriangularError::NonPositiveWeight { index: 3, .. })
    ));
    let s = TriangularNurbs::new(b, vec![Vec3::zeros(); n], vec![1.0; n], None).unwrap();
    assert!(matches!(
        s.point([2.0, 2.0]),
        Err(TriangularError::OutsideDomain { .. })
    ));
}

#[test]
fn bezier_net_map_joins_shared_domain_points() {
    // 3 x 1 strip of quads, 6 triangles: the continuous quadratic net of d-nurbs.txt section
    // 7.3 (edge rounding) has 7 x 3 = 21 control points for 36 basis functions.
    let mut v = Vec::new();
    for i in 0..4 {
        for j in 0..2 {
            v.push([i as f64, j as f64]);
        }
    }
    let mut t = Vec::new();
    for i in 0..3 {
        let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
        t.push([a, b, c]);
        t.push([a, c, d]);
    }
    let tri = Triangulation::new(v, t).unwrap();
    let clouds = KnotClouds::around_vertices(&tri, 2, 0.1).unwrap();
    let b = TriangularBasis::new(2, tri, clouds).unwrap();
    assert_eq!(b.len(), 36);
    let (map, pts) = b.bezier_net_map();
    assert_eq!(pts.len(), 21);
    assert_eq!(map.len(), 36);
    // Knot cells: every basis function is polynomial on each cell (integrate exactly).
    let cells = b.polynomial_cells(0);
    let area: f64 = cells
        .iter()
        .map(|c| vclay_spline::simplex::det3(c[0], c[1], c[2]).abs() / 2.0)
        .sum();
    assert!(
        (area - 0.5).abs() < 1e-12,
        "cells cover the triangle: {area}"
    );
}
