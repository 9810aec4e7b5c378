//! Limit evaluation (`vclay_lattice::limit`, issue 19 "Limit evaluation"): regular cells equal
//! an independent tricubic B-spline (`vclay_spline::NurbsVolume`); everywhere (extraordinary
//! vertices, the boundary) the points of further subdivision levels converge to the evaluated
//! limit; derivatives agree with finite differences; bad queries are located errors.

use crate::common;

use common::{Rng, perturb, solid};
use vclay_core::Vec3;
use vclay_lattice::limit::{child_cell, corner_parameters};
use vclay_lattice::{
    BoundaryRule, CellId, Features, Lattice, LatticeError, LimitEvaluator, LimitParams, LimitQuery,
    SubdivisionRules, SubdivisionSolid, cell_frame, primitives,
};
use vclay_spline::{NurbsVolume, ParametricVolume};

fn evaluator<'a>(l: &'a Lattice, f: &'a Features, rule: BoundaryRule) -> LimitEvaluator<'a> {
    LimitEvaluator::new(l, f, SubdivisionRules::new(rule), LimitParams::default()).unwrap()
}

fn perturbed_box(n: usize, seed: u64) -> Lattice {
    let mut l = primitives::box_lattice([n, n, n], Vec3::zeros(), Vec3::repeat((n - 1) as f64));
    perturb(&mut l, seed, 0.25);
    l
}

#[test]
fn frame_is_right_handed_and_a_hexahedron() {
    let l = perturbed_box(4, 3);
    for c in 0..l.num_cells() {
        let f = cell_frame(&l, CellId(c as u32)).unwrap();
        let p = f.map(|v| l.point(v));
        // Jacobian at the cell centre from the trilinear map.
        let du = (p[1] - p[0] + p[3] - p[2] + p[5] - p[4] + p[7] - p[6]) / 4.0;
        let dv = (p[2] - p[0] + p[3] - p[1] + p[6] - p[4] + p[7] - p[5]) / 4.0;
        let dw = (p[4] - p[0] + p[5] - p[1] + p[6] - p[2] + p[7] - p[3]) / 4.0;
        assert!(du.cross(&dv).dot(&dw) > 0.0, "cell {c}: left-handed frame");
        // Corners 0-1, 0-2, 0-4 are cell edges.
        for a in [1, 2, 4] {
            assert!(l.edge_between(f[0], f[a]).is_some());
            assert!(l.edge_between(f[7], f[7 ^ a]).is_some());
        }
    }
}

#[test]
fn regular_cells_equal_the_tricubic_bspline() {
    let l = perturbed_box(6, 11);
    let f = Features::none(&l);
    let ev = evaluator(&l, &f, BoundaryRule::Smooth);
    let regular: Vec<usize> = (0..l.num_cells())
        .filter(|&c| ev.is_regular(CellId(c as u32)))
        .collect();
    // 5^3 cells, of which the inner 3^3 have all eight corners interior.
    assert_eq!(regular.len(), 27);
    let mut rng = Rng(5);
    for &c in &regular {
        let g = ev.control_grid(CellId(c as u32)).unwrap();
        let net: Vec<Vec<Vec<Vec3>>> = (0..4)
            .map(|a| {
                (0..4)
                    .map(|b| (0..4).map(|k| l.point(g[16 * a + 4 * b + k])).collect())
                    .collect()
            })
            .collect();
        let uniform: Vec<f64> = (0..8).map(|i| i as f64 - 3.0).collect();
        let vol = NurbsVolume::new(
            [3, 3, 3],
            [uniform.clone(), uniform.clone(), uniform],
            net,
            None,
        )
        .unwrap();
        for _ in 0..5 {
            let uvw = [
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
            ];
            let p = ev.evaluate(c, uvw).unwrap();
            assert!(p.exact && p.levels == 0);
            let d = vol.derivatives(uvw[0], uvw[1], uvw[2], 1).unwrap();
            assert!((p.position - d[0][0][0]).norm() < 1e-12);
            assert!((p.derivatives[0] - d[1][0][0]).norm() < 1e-11);
            assert!((p.derivatives[1] - d[0][1][0]).norm() < 1e-11);
            assert!((p.derivatives[2] - d[0][0][1]).norm() < 1e-11);
        }
        // The cell's corners sit at grid (1..2)^3: the corner limit is the (1,4,1)/6 mask.
        let frame = ev.frame(CellId(c as u32)).unwrap();
        assert_eq!(g[16 + 4 + 1], frame[0]);
        assert_eq!(g[2 * 16 + 2 * 4 + 2], frame[7]);
    }
}

#[test]
fn regular_limit_is_the_same_from_the_next_level() {
    // The limit of a level-0 cell equals the limit of its level-1 child at the child's
    // parameters: this checks the 4x4x4 grids (a wrong neighbour gives another patch).
    let s = solid(perturbed_box(6, 21), BoundaryRule::Smooth, 1);
    let (l0, l1) = (s.lattice(0), s.lattice(1));
    let (f0, f1) = (s.features(0), s.features(1));
    let e0 = evaluator(l0, f0, BoundaryRule::Smooth);
    let e1 = evaluator(l1, f1, BoundaryRule::Smooth);
    let mut rng = Rng(9);
    let mut checked = 0;
    for c in 0..l0.num_cells() {
        let cid = CellId(c as u32);
        if !e0.is_regular(cid) {
            continue;
        }
        for _ in 0..4 {
            let uvw = [
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
            ];
            let a = e0.evaluate(c, uvw).unwrap();
            let frame = e0.frame(cid).unwrap();
            let (cc, cf, cuvw) = child_cell(l0, l1, cid, &frame, uvw).unwrap();
            // The child frame is aligned with the parent: compare against the evaluator's own
            // frame of the child through its corner points.
            let own = e1.frame(cc).unwrap();
            let mut sorted_a = cf;
            let mut sorted_b = own;
            sorted_a.sort();
            sorted_b.sort();
            assert_eq!(sorted_a, sorted_b);
            // Evaluate at the child's parameters in the evaluator's own frame.
            let x = trilinear_corner_params(&own, &cf, cuvw);
            let b = e1.evaluate(cc.index(), x).unwrap();
            assert!(
                (a.position - b.position).norm() < 1e-12,
                "cell {c} {uvw:?}: {} vs {}",
                a.position,
                b.position
            );
            checked += 1;
        }
    }
    assert!(checked >= 100);
}

/// Parameters in frame `own` of the point with parameters `uvw` in frame `aligned` (both frames
/// of one hexahedron: the map is a symmetry of the cube).
fn trilinear_corner_params(
    own: &[vclay_lattice::VertexId; 8],
    aligned: &[vclay_lattice::VertexId; 8],
    uvw: [f64; 3],
) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (h, v) in aligned.iter().enumerate() {
        let w: f64 = (0..3)
            .map(|a| {
                let t = corner_parameters(h)[a];
                if t == 1.0 { uvw[a] } else { 1.0 - uvw[a] }
            })
            .product();
        let k = own.iter().position(|x| x == v).unwrap();
        for a in 0..3 {
            out[a] += w * corner_parameters(k)[a];
        }
    }
    out
}

/// Distances between the limit at dyadic `uvw` and the level-`j` point there, `j = 1..=levels`.
fn convergence(
    s: &SubdivisionSolid,
    ev: &LimitEvaluator<'_>,
    cell: usize,
    uvw: [f64; 3],
) -> Vec<f64> {
    let limit = ev.evaluate(cell, uvw).unwrap().position;
    let mut out = Vec::new();
    let mut c = CellId(cell as u32);
    let mut frame = cell_frame(s.lattice(0), c).unwrap();
    let mut t = uvw;
    for j in 0..s.levels() {
        let (cc, cf, ct) = child_cell(s.lattice(j), s.lattice(j + 1), c, &frame, t).unwrap();
        (c, frame, t) = (cc, cf, ct);
        // Nearest corner of the level-(j+1) cell.
        let h =
            (t[0] >= 0.5) as usize | ((t[1] >= 0.5) as usize) << 1 | ((t[2] >= 0.5) as usize) << 2;
        let exact_corner = t.iter().all(|&x| x == 0.0 || x == 1.0);
        if exact_corner {
            out.push((s.lattice(j + 1).point(frame[h]) - limit).norm());
        }
    }
    out
}

fn assert_geometric(d: &[f64], what: &str) {
    // Geometric convergence: the last level shrinks the distance by at least 0.6 and the whole
    // sequence by at least half (the first level may still be pre-asymptotic).
    assert!(d.len() >= 3, "{what}: {d:?}");
    let n = d.len();
    assert!(
        d[n - 1] < 0.6 * d[n - 2] + 1e-9 && d[n - 1] < 0.5 * d[0] + 1e-9,
        "{what}: distances do not shrink geometrically: {d:?}"
    );
}

#[test]
fn boundary_cells_converge_under_subdivision() {
    // A perturbed 4x4x4-point box: every cell touches the boundary; smooth and sharp rules.
    for rule in [
        BoundaryRule::Smooth,
        BoundaryRule::Sharp,
        BoundaryRule::Interior,
    ] {
        let s = solid(perturbed_box(4, 31), rule, 4);
        let f = Features::none(s.lattice(0));
        let ev = evaluator(s.lattice(0), &f, rule);
        for (cell, uvw) in [
            (0usize, [0.5, 0.5, 0.5]),
            (13, [0.25, 0.5, 0.75]),
            (4, [0.0, 0.5, 0.25]),
            (26, [1.0, 1.0, 0.5]),
            (9, [0.0, 0.0, 0.0]),
        ] {
            let d = convergence(&s, &ev, cell, uvw);
            assert_geometric(&d, &format!("{rule:?} cell {cell} {uvw:?}"));
            assert!(d.last().unwrap() < &0.05, "{rule:?}: {d:?}");
        }
    }
}

#[test]
fn extraordinary_vertices_converge_under_subdivision() {
    // A 5-sector cylinder: its level-1 lattice is all hexahedra, with extraordinary edges and
    // vertices along the axis (five cells around the axis) and at the former prism corners.
    let c = primitives::cylinder(1.0, 1.6, 5, 2, 1);
    let s1 = solid(c, BoundaryRule::Smooth, 1);
    let mut l1 = s1.lattice(1).clone();
    // Break the cylinder's symmetry (on the symmetric axis the points would not move at all).
    perturb(&mut l1, 17, 0.02);
    let s = solid(l1, BoundaryRule::Smooth, 3);
    let f = Features::none(s.lattice(0));
    let ev = evaluator(s.lattice(0), &f, BoundaryRule::Smooth);
    let l = s.lattice(0);
    // Cells on the axis, away from the caps: their corner on the axis is extraordinary.
    let axis_cells: Vec<usize> = (0..l.num_cells())
        .filter(|&c| {
            let ctr = l.cell_centroid(CellId(c as u32));
            ctr.xy().norm() < 0.2 && ctr.z > 0.5 && ctr.z < 1.1
        })
        .collect();
    assert!(!axis_cells.is_empty());
    let mut extraordinary = 0;
    for &c in &axis_cells {
        assert!(!ev.is_regular(CellId(c as u32)));
        for uvw in [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5],
            [0.5, 0.0, 0.0],
            [1.0, 0.0, 1.0],
        ] {
            let d = convergence(&s, &ev, c, uvw);
            assert_geometric(&d, &format!("cell {c} {uvw:?}"));
            extraordinary += 1;
        }
        // Off the extraordinary corner, points become exact after a few levels.
        let p = ev.evaluate(c, [0.3, 0.6, 0.45]).unwrap();
        assert!(p.exact && p.levels >= 1, "{p:?}");
    }
    assert!(extraordinary >= 8);
}

#[test]
fn derivatives_match_finite_differences() {
    let c = primitives::cylinder(1.0, 1.6, 5, 4, 2);
    let s1 = solid(c, BoundaryRule::Smooth, 1);
    let l = s1.lattice(1);
    let f = s1.features(1);
    let ev = evaluator(l, f, BoundaryRule::Smooth);
    let mut rng = Rng(77);
    let mut tested = 0;
    let h = 1e-5;
    for _ in 0..60 {
        let cell = (rng.next_u64() % l.num_cells() as u64) as usize;
        let uvw = [
            0.5 + 0.4 * rng.sym(),
            0.5 + 0.4 * rng.sym(),
            0.5 + 0.4 * rng.sym(),
        ];
        let p = ev.evaluate(cell, uvw).unwrap();
        if !p.exact {
            continue;
        }
        for a in 0..3 {
            let mut up = uvw;
            let mut dn = uvw;
            up[a] += h;
            dn[a] -= h;
            let pu = ev.evaluate(cell, up).unwrap();
            let pd = ev.evaluate(cell, dn).unwrap();
            if !(pu.exact && pd.exact) {
                continue;
            }
            let fd = (pu.position - pd.position) / (2.0 * h);
            let scale = p.derivatives[a].norm().max(1e-3);
            assert!(
                (fd - p.derivatives[a]).norm() < 1e-5 * scale,
                "cell {cell} {uvw:?} axis {a}: {fd} vs {}",
                p.derivatives[a]
            );
            tested += 1;
        }
    }
    assert!(tested >= 30, "{tested}");
}

#[test]
fn bad_queries_are_located_errors() {
    let c = primitives::cylinder(1.0, 1.0, 4, 1, 1);
    let f = Features::none(&c);
    let ev = evaluator(&c, &f, BoundaryRule::Smooth);
    let n = c.num_cells();
    let hex = (0..n)
        .find(|&i| ev.frame(CellId(i as u32)).is_some())
        .unwrap();
    let prism = (0..n)
        .find(|&i| ev.frame(CellId(i as u32)).is_none())
        .unwrap();
    let qs = [
        LimitQuery {
            cell: hex,
            uvw: [0.5; 3],
        },
        LimitQuery {
            cell: n,
            uvw: [0.5; 3],
        },
    ];
    let e = ev.evaluate_many(&qs).unwrap_err();
    assert!(
        matches!(&e, LatticeError::LimitQuery { index: 1, message } if message.contains("out of range")),
        "{e}"
    );
    let e = ev.evaluate(hex, [0.5, 1.5, 0.0]).unwrap_err();
    assert!(e.to_string().contains("v = 1.5 is outside [0, 1]"), "{e}");
    let e = ev.evaluate(hex, [f64::NAN, 0.5, 0.0]).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    let e = ev.evaluate(prism, [0.5; 3]).unwrap_err();
    assert!(matches!(e, LatticeError::NotHexahedral { .. }), "{e}");
    let bad = LimitParams {
        tolerance: 0.0,
        ..LimitParams::default()
    };
    assert!(LimitEvaluator::new(&c, &f, SubdivisionRules::default(), bad).is_err());
}

#[test]
fn batch_equals_single_evaluations() {
    let l = perturbed_box(5, 41);
    let f = Features::none(&l);
    let ev = LimitEvaluator::new(
        &l,
        &f,
        SubdivisionRules::default(),
        LimitParams {
            parallelism: vclay_core::Parallelism::Rayon,
            ..LimitParams::default()
        },
    )
    .unwrap();
    let mut rng = Rng(3);
    let qs: Vec<LimitQuery> = (0..300)
        .map(|_| LimitQuery {
            cell: (rng.next_u64() % l.num_cells() as u64) as usize,
            uvw: [
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
            ],
        })
        .collect();
    let many = ev.evaluate_many(&qs).unwrap();
    for (q, m) in qs.iter().zip(&many) {
        assert_eq!(*m, ev.evaluate(q.cell, q.uvw).unwrap());
    }
    let _ = SubdivisionSolid::new(l.clone(), f.clone(), SubdivisionRules::default(), 0).unwrap();
}
