//! The data-point numbering ([`DataNumbering`], issue 31): new subdivided boxes from
//! [`GRID_NUMBERING_NEW_POINTS`] data points are numbered in grid order, everything else keeps
//! the Cuthill-McKee numbering; parts saved in the old numbering load into the new one meaning
//! the same points from [`GRID_NUMBERING_POINTS`] on, and keep their numbering below it.

use vclay_core::Vec3;
use vclay_solids::benchmarks::{self, subdivision_box};
use vclay_solids::model::{GRID_NUMBERING_NEW_POINTS, GRID_NUMBERING_POINTS};
use vclay_solids::{
    DataNumbering, DynamicSolid, Material, SolidParams, SolidRest, SolidState, Tool,
};

fn cube(level: usize) -> DynamicSolid {
    let (source, p) = subdivision_box(4, level);
    DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap()
}

/// The largest coordinate difference of two point arrays.
fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).amax())
        .fold(0.0, f64::max)
}

#[test]
fn large_boxes_are_numbered_in_grid_order_and_the_rest_keep_locality() {
    let small = cube(1);
    assert!(small.data_points().len() < GRID_NUMBERING_NEW_POINTS);
    assert_eq!(small.data_numbering(), DataNumbering::Locality);
    for level in [2, 3] {
        let mid = cube(level);
        assert!(mid.data_points().len() >= GRID_NUMBERING_NEW_POINTS);
        assert_eq!(mid.data_numbering(), DataNumbering::Grid, "level {level}");
        assert_eq!(
            mid.springs().grid_dims(),
            None,
            "level {level}: the general kernel"
        );
    }
    let large = cube(4);
    assert!(large.data_points().len() >= GRID_NUMBERING_POINTS);
    assert_eq!(large.data_numbering(), DataNumbering::Grid);
    assert_eq!(large.springs().grid_dims(), Some([49, 49, 49]));
    // Grid order: point (i, j, k) at index i + 49 (j + 49 k), so consecutive points are one
    // grid step apart along x (the cube's axes, either direction) except at row ends.
    let d = large.data_points();
    let h = 1.0 / 48.0;
    for g in [0, 1, 47, 49 * 20 + 3, 49 * 49 * 30 + 49 * 7 + 11] {
        let step = d[g + 1] - d[g];
        assert!(
            (step.norm() - h).abs() < 1e-9 && step.iter().filter(|c| c.abs() > 1e-9).count() == 1,
            "points {g} and {} are grid neighbours: {step:?}",
            g + 1
        );
    }
    // B-spline solids and level 0 keep their own numbering.
    let (source, p) = benchmarks::bspline_box(4, 10);
    let b = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
    assert_eq!(b.data_numbering(), DataNumbering::Locality);
    // Asking for the old numbering gives it; the same points in another order.
    let (source, p) = subdivision_box(4, 4);
    let old = source
        .discretize_numbered(&p, Some(DataNumbering::Locality))
        .unwrap();
    assert_eq!(old.numbering, DataNumbering::Locality);
    let new = source.discretize(&p).unwrap();
    assert_eq!(new.numbering, DataNumbering::Grid);
    let mut a = old.order.clone();
    let mut b = new.order.clone();
    assert_ne!(a, b);
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(
        a, b,
        "both orders are permutations of the finest lattice's points"
    );
}

/// Regression for the blocker of session h51 (`docs/performance.md` "Structured-grid spring
/// kernel"): a state saved in the Cuthill-McKee numbering (every build before the grid
/// numbering) of a level-4 cube loads into the grid numbering with every data point and every
/// tool's data-point id meaning the same point of the solid.
#[test]
fn parts_saved_in_the_locality_numbering_load_into_the_grid_numbering() {
    let (source, p) = subdivision_box(4, 4);
    // The parts as the old build held them, built from its own discretization: data points
    // `A p` in the old numbering, a rope and a point force on old data points, a region force.
    let old = source
        .discretize_numbered(&p, Some(DataNumbering::Locality))
        .unwrap();
    let old_d: Vec<Vec3> = old.data.points().to_vec();
    let moved: Vec<Vec3> = p
        .iter()
        .map(|x| x + Vec3::new(0.01 * x.y, -0.02 * x.z, 0.015 * x.x))
        .collect();
    let old_moved = old.map.apply(&moved);
    let (rope_at, force_at) = (1234, 98_765);
    let region: Vec<usize> = vec![5, 77, 40_000, 117_000];
    let rest = SolidRest {
        control_points: p.clone(),
        data_points: old_d.clone(),
        physics_data_points: old_d.clone(),
        fixed: vec![false; p.len()],
        metric_stiffness: None,
        energy_scale: 1.0,
    };
    let state = SolidState {
        control_points: moved.clone(),
        velocities: vec![Vec3::zeros(); p.len()],
        data_points: old_moved.clone(),
        tools: vec![
            Some(Tool::Rope {
                point: rope_at,
                cursor: Vec3::new(2.0, 0.5, 0.5),
                stiffness: 50.0,
                length: 0.0,
            }),
            Some(Tool::PointForce {
                point: force_at,
                force: Vec3::new(0.0, 0.0, -1.0),
            }),
            Some(Tool::RegionForce {
                points: region.clone(),
                force: Vec3::new(1.0, 0.0, 0.0),
                center: Vec3::repeat(0.5),
                radius: 0.1,
                falloff: vclay_solids::Falloff::Constant,
                weights: vec![1.0, 2.0, 3.0, 4.0],
            }),
        ],
        time: 0.25,
        steps: 250,
        tool_energy_seen: 0.5,
    };
    let material =
        vclay_solids::MaterialField::uniform(Material::default(), source.control_cells());
    let s = DynamicSolid::from_parts_numbered(
        source.clone(),
        material.clone(),
        SolidParams::default(),
        &rest,
        &state,
        DataNumbering::Locality,
    )
    .unwrap();
    assert_eq!(s.data_numbering(), DataNumbering::Grid);
    // The same point set, each at its own place: the data points of this build's chain.
    let fresh = s.map_to_data(&moved).unwrap();
    let dd = max_diff(s.data_points(), &fresh);
    assert!(dd < 1e-14, "state data points {dd:e}");
    let rest_now = s.rest();
    let fresh_rest = s.map_to_data(&p).unwrap();
    let dr = max_diff(&rest_now.data_points, &fresh_rest);
    assert!(dr < 1e-14, "rest data points {dr:e}");
    // Each tool holds the point it held: same position as the old point.
    let st = s.state();
    let at = |i: usize| st.data_points[i];
    match st.tools[0].as_ref().unwrap() {
        Tool::Rope { point, .. } => assert_eq!(at(*point), old_moved[rope_at]),
        t => panic!("{t:?}"),
    }
    match st.tools[1].as_ref().unwrap() {
        Tool::PointForce { point, .. } => assert_eq!(at(*point), old_moved[force_at]),
        t => panic!("{t:?}"),
    }
    match st.tools[2].as_ref().unwrap() {
        Tool::RegionForce {
            points, weights, ..
        } => {
            assert_eq!(
                weights,
                &[1.0, 2.0, 3.0, 4.0],
                "the weights keep their points"
            );
            for (q, &o) in points.iter().zip(&region) {
                assert_eq!(at(*q), old_moved[o]);
            }
        }
        t => panic!("{t:?}"),
    }
    assert_eq!((st.time, st.steps, st.tool_energy_seen), (0.25, 250, 0.5));
    // Parts in the solid's own numbering load bit for bit (what a new file holds).
    let again = DynamicSolid::from_parts_numbered(
        source,
        material,
        SolidParams::default(),
        &s.rest(),
        &s.state(),
        DataNumbering::Grid,
    )
    .unwrap();
    assert_eq!(again.state(), s.state());
    assert_eq!(again.rest(), s.rest());
}

/// The levels of a box in grid order run as tensor products (`vclay_lattice::TensorOperator`),
/// and the chain's products agree with the sparse operators' to rounding, with the same bits
/// on one thread and on all.
#[test]
fn grid_numbered_chains_run_the_tensor_levels_and_agree_with_the_sparse_products() {
    use vclay_core::Parallelism;
    use vclay_lattice::SubdivisionMap;
    use vclay_lattice::map::ChainWorkspace;
    for level in [1, 2, 3, 4] {
        let (source, p) = subdivision_box(4, level);
        let d = source
            .discretize_numbered(&p, Some(DataNumbering::Grid))
            .unwrap();
        assert_eq!(d.numbering, DataNumbering::Grid);
        // Level 0 is the control lattice (its own numbering); every later level is a grid.
        let tensor: Vec<bool> = (0..level).map(|j| d.map.tensor(j).is_some()).collect();
        let want: Vec<bool> = (0..level).map(|j| j > 0).collect();
        assert_eq!(tensor, want, "level {level}");
        let sparse = SubdivisionMap::new(d.map.operators().to_vec());
        let x: Vec<Vec3> = p
            .iter()
            .enumerate()
            .map(|(i, q)| q + Vec3::new((i % 7) as f64, (i % 5) as f64, (i % 3) as f64) * 0.01)
            .collect();
        let mut ws = ChainWorkspace::new();
        let mut a = vec![Vec3::zeros(); d.data.num_points()];
        let mut b = a.clone();
        d.map
            .apply_into(&x, &mut a, &mut ws, Parallelism::Sequential);
        sparse.apply_into(&x, &mut b, &mut ws, Parallelism::Sequential);
        let da = max_diff(&a, &b);
        assert!(da < 1e-14, "level {level}: A x {da:e}");
        let mut c = b.clone();
        d.map.apply_into(&x, &mut c, &mut ws, Parallelism::Rayon);
        assert!(a == c, "level {level}: A x, one thread = all threads");
        let f: Vec<Vec3> = a
            .iter()
            .enumerate()
            .map(|(i, q)| q * ((i % 11) as f64 - 5.0))
            .collect();
        let mut g = vec![Vec3::zeros(); p.len()];
        let mut h = g.clone();
        d.map
            .apply_transpose_into(&f, &mut g, &mut ws, Parallelism::Sequential);
        sparse.apply_transpose_into(&f, &mut h, &mut ws, Parallelism::Sequential);
        let scale = h.iter().map(|v| v.amax()).fold(0.0, f64::max);
        let dg = max_diff(&g, &h) / scale;
        assert!(dg < 1e-13, "level {level}: A^T f {dg:e} relative");
        let mut k = h.clone();
        d.map
            .apply_transpose_into(&f, &mut k, &mut ws, Parallelism::Rayon);
        assert!(g == k, "level {level}: A^T f, one thread = all threads");
    }
}

/// A box below [`GRID_NUMBERING_POINTS`] loaded from parts in the Cuthill-McKee numbering (a
/// session saved before session 22, when such boxes were not grid-numbered) keeps it: its data
/// points keep their places and it continues bit for bit, while a new solid of the same box is
/// numbered in grid order.
#[test]
fn small_boxes_saved_in_the_locality_numbering_keep_it() {
    let (source, p) = subdivision_box(4, 2);
    assert_eq!(cube(2).data_numbering(), DataNumbering::Grid);
    let old = source
        .discretize_numbered(&p, Some(DataNumbering::Locality))
        .unwrap();
    assert_eq!(old.numbering, DataNumbering::Locality);
    assert!(old.data.num_points() < GRID_NUMBERING_POINTS);
    let d: Vec<Vec3> = old.data.points().to_vec();
    let rest = SolidRest {
        control_points: p.clone(),
        data_points: d.clone(),
        physics_data_points: d.clone(),
        fixed: vec![false; p.len()],
        metric_stiffness: None,
        energy_scale: 1.0,
    };
    let state = SolidState {
        control_points: p.clone(),
        velocities: vec![Vec3::zeros(); p.len()],
        data_points: d.clone(),
        tools: vec![Some(Tool::Rope {
            point: 1000,
            cursor: Vec3::new(1.3, 1.2, 1.1),
            stiffness: 50.0,
            length: 0.0,
        })],
        time: 0.0,
        steps: 0,
        tool_energy_seen: 0.0,
    };
    let material =
        vclay_solids::MaterialField::uniform(Material::default(), source.control_cells());
    let load = |rest: &SolidRest, state: &SolidState| {
        DynamicSolid::from_parts_numbered(
            source.clone(),
            material.clone(),
            SolidParams::default(),
            rest,
            state,
            DataNumbering::Locality,
        )
        .unwrap()
    };
    let mut s = load(&rest, &state);
    assert_eq!(s.data_numbering(), DataNumbering::Locality);
    assert_eq!(s.data_points(), &d[..], "the data points keep their places");
    s.run(10).unwrap();
    // Saved and loaded again mid-run: the same trajectory, bit for bit.
    let mut t = load(&s.rest(), &s.state());
    s.run(10).unwrap();
    t.run(10).unwrap();
    assert_eq!(t.state(), s.state());
    assert!(s.state().control_points != p, "the rope moves the box");
}
