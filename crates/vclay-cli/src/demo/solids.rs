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
            "4^3 cube at level 2 ({}) pulled by the rope and released: {} steps at {:.3} ms/step (max {:.3} ms), final energy {:.3e}",
            sc.session.model(None)?.summary(),
            steps,
            s.mean_step_ms,
            s.max_step_ms,
            s.final_energy.first().map_or(0.0, |e| e.1)
        ),
        files,
    ))
}
