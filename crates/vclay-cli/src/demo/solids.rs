//! Demo step of the dynamic solids layer: the rope on the 4^3 cube
//! (`subdivision-solids-conference.txt` Fig 7; the journal has no such figure), run from the shipped scenario file
//! through the session layer.

use anyhow::Result;
use std::path::Path;
use vclay::session::scenario::Scenario;

use super::StepOutput;

/// The scenario `examples/scenarios/fig07_rope_cube.toml`, embedded.
const FIG07: &str = include_str!("../../../../examples/scenarios/fig07_rope_cube.toml");

/// Runs the Fig 7 rope scenario into `out/solids_fig07`.
pub fn rope_cube(out: &Path) -> Result<StepOutput> {
    let mut sc = Scenario::parse(
        FIG07,
        "fig07_rope_cube.toml",
        "fig07_rope_cube",
        Path::new("."),
    )?;
    let steps = sc.steps;
    let dir = out.join("solids_fig07");
    let s = vclay::session::run::run(&mut sc.session, steps, &dir, &sc.output, &mut |_| {})?;
    let files = s
        .frames
        .iter()
        .chain(&s.files)
        .filter_map(|f| f.strip_prefix(out).ok())
        .map(|f| f.display().to_string())
        .collect();
    Ok((
        format!(
            "4^3 cube at level 2 ({}) pulled by the rope, kept by a plastic reset and released: {} steps at {:.3} ms/step (max {:.3} ms), final energy {:.3e}",
            sc.session.model(None)?.summary(),
            steps,
            s.mean_step_ms,
            s.max_step_ms,
            s.final_energy.first().map_or(0.0, |e| e.1)
        ),
        files,
    ))
}

/// Picture of mass points: the data lattice's edges (thin) and its points (markers), seen
/// along the iso view.
fn mass_picture(
    lattice_points: &[vclay::Vec3],
    edges: &[(vclay::Vec3, vclay::Vec3)],
    png: &Path,
) -> Result<()> {
    use vclay::render::{RenderOptions, Scene, render};
    let mut scene = Scene::new();
    scene.add_segments(edges, [150, 160, 180], 1.0);
    scene.add_markers(lattice_points, [200, 120, 90], 2.5);
    let opts = RenderOptions {
        supersample: 2,
        ..RenderOptions::sized(360, 360)
    };
    render(&scene, &opts)?.write_png(png)?;
    Ok(())
}

/// `subdivision-solids-journal.txt` Fig 3: the mass points `c = B q` (eq 3) of two tricubic
/// B-spline solids with the same 6 x 6 x 6 control lattice and different knot vectors
/// (`vclay_solids::figures::fig3_solid`).
pub fn mass_distribution(out: &Path) -> Result<StepOutput> {
    let mut files = Vec::new();
    let mut what = Vec::new();
    for (nonuniform, name, knots) in [
        (
            false,
            "bspline_mass_uniform.png",
            vclay::solids::figures::FIG3_UNIFORM_KNOTS,
        ),
        (
            true,
            "bspline_mass_nonuniform.png",
            vclay::solids::figures::FIG3_NONUNIFORM_KNOTS,
        ),
    ] {
        let (source, q, c) = vclay::solids::figures::fig3_solid(nonuniform)?;
        let data = source.discretize(&q)?.data;
        let p = data.points();
        let edges: Vec<_> = data
            .edges()
            .iter()
            .map(|e| (p[e[0].index()], p[e[1].index()]))
            .collect();
        mass_picture(&c, &edges, &out.join(name))?;
        let centroid = c.iter().sum::<vclay::Vec3>() / c.len() as f64;
        what.push(format!(
            "knots {knots:?}: {} mass points, centroid ({:.3}, {:.3}, {:.3})",
            c.len(),
            centroid.x,
            centroid.y,
            centroid.z
        ));
        files.push(name.to_string());
    }
    Ok((
        format!(
            "two tricubic B-spline solids with the same 6x6x6 control points on a uniform grid of the unit cube; {}",
            what.join("; ")
        ),
        files,
    ))
}
