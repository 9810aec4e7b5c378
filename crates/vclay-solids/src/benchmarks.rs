//! The model behind the dynamic-solid speed figures (`docs/performance.md`, the per-step times
//! of `subdivision-solids-journal.txt` Table 2 and issue 4's goals), shared by the examples
//! (`bench_levels`, `kernels`) and `vclay bench --physics`, so that every figure is measured on
//! the same definition: the unit cube of 4^3 control points (3^3 cells) subdivided `level`
//! times with the sharp boundary rule (level 2: 2,197 data points; level 5: 912,673), default
//! material, pulled by a rope from the data point nearest `(1.3, 1.2, 1.1)` (stiffness 50) for
//! three steps before timing.

use crate::{DynamicSolid, Material, SolidParams, SolidSource, SolidsError};
use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, Lattice, gallery, primitives};
use vclay_spline::KnotVector;

/// The benchmark cube at subdivision `level`, at rest.
pub fn cube(level: usize, params: SolidParams) -> Result<DynamicSolid, SolidsError> {
    let (source, p) = subdivision_box(4, level);
    DynamicSolid::new(source, p, Material::default(), params)
}

/// The unit cube as a subdivision solid: `n^3` control points (a box lattice of `(n - 1)^3`
/// cells), sharp boundary rule, `levels` subdivision levels; with its control points.
pub fn subdivision_box(n: usize, levels: usize) -> (SolidSource, Vec<Vec3>) {
    let control = primitives::box_lattice([n, n, n], Vec3::zeros(), Vec3::repeat(1.0));
    SolidSource::subdivision(control, BoundaryRule::Sharp, levels)
}

/// The unit cube as a tricubic B-spline solid: `n^3` control points (`n >= 4`) at the
/// Greville abscissae of clamped uniform knots (so the solid is the identity map of the
/// cube), sampled on a `samples^3` grid; with its control points.
///
/// # Panics
/// If `n < 4` (a programmer error: a cubic needs four control points).
#[track_caller]
pub fn bspline_box(n: usize, samples: usize) -> (SolidSource, Vec<Vec3>) {
    let k = KnotVector::clamped_uniform(3, n).expect("bspline_box: n >= 4");
    let g = k.greville();
    let mut p = Vec::with_capacity(n * n * n);
    for &a in &g {
        for &b in &g {
            for &c in &g {
                p.push(Vec3::new(a, b, c));
            }
        }
    }
    let source = SolidSource::BSpline {
        knots: [k.clone(), k.clone(), k],
        weights: vec![1.0; n * n * n],
        samples: [samples; 3],
    };
    (source, p)
}

/// A subdivision solid of the papers' timing tables that [`vclay_lattice::primitives`] and
/// [`vclay_lattice::gallery`] build with the tables' element counts
/// (`subdivision-solids-conference.txt` Table 1, `subdivision-solids-journal.txt` Table 2; the
/// journal's spiked and holed objects match its cell counts, the only counts it gives). Each is
/// about one unit across, so that the default material and the benchmark rope of [`pull`]
/// apply unchanged.
#[derive(Clone, Copy, Debug)]
pub struct PaperModel {
    /// The tables' model name.
    pub name: &'static str,
    /// Subdivision level of the data lattice.
    pub level: usize,
    /// The tables' data points (the tests check that the model has exactly these); for the
    /// spiked and holed objects, whose table row gives only cells, the reconstruction's.
    pub data_points: usize,
    /// "Update time" in ms in the conference paper's Table 1 (Pentium III 550 MHz).
    pub conference_ms: Option<f64>,
    /// "Update time" in ms in the journal paper's Table 2 (same machine).
    pub journal_ms: Option<f64>,
    control: fn() -> Lattice,
}

impl PaperModel {
    /// The control lattice.
    pub fn control(&self) -> Lattice {
        (self.control)()
    }

    /// The model as a dynamic solid at rest (sharp boundary rule, default material).
    pub fn solid(&self, params: SolidParams) -> Result<DynamicSolid, SolidsError> {
        let (source, p) = SolidSource::subdivision(self.control(), BoundaryRule::Sharp, self.level);
        DynamicSolid::new(source, p, Material::default(), params)
    }
}

fn cube3() -> Lattice {
    primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(1.0))
}
fn cube4() -> Lattice {
    primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0))
}
fn torus() -> Lattice {
    primitives::paper_torus(0.25, 0.5, 0.25)
}
fn gear() -> Lattice {
    primitives::gear(0.25, 0.5, 0.65, 0.25)
}
fn tetrahedron_with_holes() -> Lattice {
    primitives::tetrahedron_with_holes(1.0, 0.25)
}
fn cube_with_holes() -> Lattice {
    primitives::cube_with_holes(1.0 / 3.0)
}
fn cylinder() -> Lattice {
    primitives::cylinder(0.5, 1.0, 4, 2, 0)
}
/// `l` moved so that its bounding box is centred (nearly) on the benchmark rope's cursor (see [`pull`]):
/// the rope then grabs the body of the gallery models, not the tip of a spike, hand or arm,
/// whose few light control points the rope would fling (a tip moves further than the whole
/// model's size in three steps), which is not the state the figures time.
fn at_rope(mut l: Lattice) -> Lattice {
    let (lo, hi) = l.points().iter().fold(
        (Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    // A tenth of a unit off-centre, so that the cursor is not on a data point.
    let shift = ROPE_CURSOR - Vec3::repeat(0.1) - (lo + hi) / 2.0;
    for p in l.points_mut() {
        *p += shift;
    }
    l
}
fn soccer_player() -> Lattice {
    at_rope(gallery::soccer_player(1.0))
}
fn cactus() -> Lattice {
    at_rope(gallery::cactus(1.0))
}
fn spiked_object() -> Lattice {
    at_rope(gallery::spiked_object(1.0 / 6.0))
}
fn holed_object() -> Lattice {
    at_rope(gallery::holed_object(1.0 / 9.0))
}

/// The models of the papers' timing tables that the primitives build, in the conference
/// table's order.
pub const PAPER_MODELS: [PaperModel; 14] = [
    PaperModel {
        name: "Cube (3^3)",
        level: 2,
        data_points: 729,
        conference_ms: Some(30.0),
        journal_ms: None,
        control: cube3,
    },
    PaperModel {
        name: "Cube (3^3)",
        level: 3,
        data_points: 4913,
        conference_ms: Some(189.0),
        journal_ms: None,
        control: cube3,
    },
    PaperModel {
        name: "Cube (4^3)",
        level: 1,
        data_points: 343,
        conference_ms: Some(20.0),
        journal_ms: Some(10.0),
        control: cube4,
    },
    PaperModel {
        name: "Cube (4^3)",
        level: 2,
        data_points: 2197,
        conference_ms: Some(121.0),
        journal_ms: Some(72.0),
        control: cube4,
    },
    PaperModel {
        name: "Torus",
        level: 2,
        data_points: 680,
        conference_ms: Some(28.0),
        journal_ms: Some(20.0),
        control: torus,
    },
    PaperModel {
        name: "Torus",
        level: 3,
        data_points: 4464,
        conference_ms: Some(163.0),
        journal_ms: Some(122.0),
        control: torus,
    },
    PaperModel {
        name: "Gear",
        level: 2,
        data_points: 1480,
        conference_ms: Some(71.0),
        journal_ms: Some(42.0),
        control: gear,
    },
    PaperModel {
        name: "Tetrahedron w/ holes",
        level: 3,
        data_points: 2505,
        conference_ms: Some(87.0),
        journal_ms: Some(61.0),
        control: tetrahedron_with_holes,
    },
    PaperModel {
        name: "Cube w/ holes",
        level: 2,
        data_points: 1900,
        conference_ms: Some(103.0),
        journal_ms: Some(61.0),
        control: cube_with_holes,
    },
    PaperModel {
        name: "Cylinder",
        level: 3,
        data_points: 3553,
        conference_ms: Some(110.0),
        journal_ms: None,
        control: cylinder,
    },
    PaperModel {
        name: "Soccer player",
        level: 2,
        data_points: 2450,
        conference_ms: Some(151.0),
        journal_ms: Some(92.0),
        control: soccer_player,
    },
    PaperModel {
        name: "Cactus",
        level: 2,
        data_points: 2625,
        conference_ms: Some(169.0),
        journal_ms: Some(94.0),
        control: cactus,
    },
    PaperModel {
        name: "Spiked object",
        level: 1,
        data_points: 1207,
        conference_ms: None,
        journal_ms: Some(71.0),
        control: spiked_object,
    },
    PaperModel {
        name: "Holed object",
        level: 1,
        data_points: 1827,
        conference_ms: None,
        journal_ms: Some(189.0),
        control: holed_object,
    },
];

/// Cursor of the benchmark rope of [`pull`].
const ROPE_CURSOR: Vec3 = Vec3::new(1.3, 1.2, 1.1);

/// Attaches the benchmark rope to `s` and takes three steps (the deformed state the figures
/// time).
pub fn pull(s: &mut DynamicSolid) -> Result<(), SolidsError> {
    s.attach_rope(ROPE_CURSOR, 50.0, 0.0)?;
    s.run(3)
}

/// Step times of a benchmark run ([`time_steps`]), in milliseconds per step.
#[derive(Clone, Copy, Debug)]
pub struct StepTimes {
    /// Wall time, median over batches of at least 2 ms: the figure a shared machine's pauses
    /// move least.
    pub median_ms: f64,
    /// Wall time, mean over all timed steps.
    pub mean_ms: f64,
    /// CPU time of the whole process (all threads) per step; NaN where the platform does not
    /// say ([`vclay_core::yardstick::process_cpu_seconds`]).
    pub cpu_ms: f64,
}

/// Times `s.step()` for about `seconds` (at least 5 batches, each of at least 2 ms of steps),
/// from the state `s` is in (the examples call [`pull`] first). Panics if a step fails: a
/// benchmark model that diverges is a bug to see, not a figure.
pub fn time_steps(s: &mut DynamicSolid, seconds: f64) -> StepTimes {
    let cpu = || vclay_core::yardstick::process_cpu_seconds().unwrap_or(f64::NAN);
    let t = std::time::Instant::now();
    let mut batch = 0;
    while batch == 0 || t.elapsed().as_secs_f64() < 2e-3 {
        s.step().expect("benchmark step");
        batch += 1;
    }
    let t0 = std::time::Instant::now();
    let c0 = cpu();
    let mut per_batch = Vec::new();
    while per_batch.len() < 5 || t0.elapsed().as_secs_f64() < seconds {
        let tb = std::time::Instant::now();
        for _ in 0..batch {
            s.step().expect("benchmark step");
        }
        per_batch.push(tb.elapsed().as_secs_f64() * 1e3 / batch as f64);
    }
    let n = (per_batch.len() * batch) as f64;
    let mean_ms = t0.elapsed().as_secs_f64() * 1e3 / n;
    let cpu_ms = (cpu() - c0) * 1e3 / n;
    per_batch.sort_by(f64::total_cmp);
    StepTimes {
        median_ms: per_batch[per_batch.len() / 2],
        mean_ms,
        cpu_ms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_benchmark_cube_has_the_papers_counts_and_moves_when_pulled() {
        let mut s = cube(1, SolidParams::default()).unwrap();
        assert_eq!(s.data_points().len(), 343);
        let before = s.data_points().to_vec();
        pull(&mut s).unwrap();
        assert_eq!(s.steps(), 3);
        assert!(s.data_points().iter().zip(&before).any(|(a, b)| a != b));
    }

    #[test]
    fn the_paper_models_have_the_tables_data_points_and_step() {
        for m in &PAPER_MODELS {
            let mut s = m.solid(SolidParams::default()).unwrap();
            assert_eq!(
                s.data_points().len(),
                m.data_points,
                "{} level {}",
                m.name,
                m.level
            );
            // About one unit across, so the rope and the default material apply.
            let (lo, hi) = s.data_points().iter().fold(
                (Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN)),
                |(lo, hi), x| (lo.inf(x), hi.sup(x)),
            );
            let size = (hi - lo).max();
            assert!((0.5..=1.5).contains(&size), "{}: size {size}", m.name);
            let before = s.data_points().to_vec();
            pull(&mut s).unwrap();
            let moved = s
                .data_points()
                .iter()
                .zip(&before)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            assert!(moved > 0.0 && moved < size, "{}: moved {moved}", m.name);
        }
    }
}
