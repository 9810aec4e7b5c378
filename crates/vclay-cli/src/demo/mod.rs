//! `vclay demo`: the main job. Builds built-in models, runs each capability once, and writes
//! meshes, model files and `summary.json` into the output folder.
//!
//! Each layer contributes steps from its own file in this folder; [`steps`] lists them in the
//! order they run. A step receives the output folder and returns a one-sentence result and the
//! files it wrote (relative to the folder).

use anyhow::{Context, Result};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

mod dnurbs;
mod exchange;
mod ffd;
mod index;
mod lattice;
mod pde;
mod rounding;
mod solids;
mod spline;
mod studio;

/// What a demo step returns: a sentence describing the result, and the files it wrote.
pub type StepOutput = (String, Vec<String>);

/// A demo step: a name, the paper figure it reproduces (empty if none) and its function.
pub struct Step {
    /// Short name shown in the summary.
    pub name: &'static str,
    /// One word that selects the step with `vclay demo --only` (e.g. `torus`, `ffd`).
    pub id: &'static str,
    /// The paper and figure it reproduces, e.g. "d-nurbs.txt Fig 6" (empty if none).
    pub reproduces: &'static str,
    /// Runs the step, writing into the output folder.
    pub run: fn(&Path) -> Result<StepOutput>,
}

/// Every demo step, in the order they run. Add new capabilities here.
fn steps() -> Vec<Step> {
    vec![
        Step {
            name: "exact torus",
            id: "torus",
            reproduces: "",
            run: spline::torus,
        },
        Step {
            name: "refined sheet",
            id: "sheet",
            reproduces: "",
            run: spline::refined_sheet,
        },
        Step {
            name: "twisted volume",
            id: "volume",
            reproduces: "",
            run: spline::twisted_volume,
        },
        Step {
            name: "batched evaluation",
            id: "batch",
            reproduces: "",
            run: spline::batched_evaluation,
        },
        Step {
            name: "d-nurbs hemisphere fit",
            id: "fit",
            reproduces: "d-nurbs.txt Fig 7a",
            run: dnurbs::hemisphere_fit,
        },
        Step {
            name: "d-nurbs fits with the paper's counts",
            id: "fits",
            reproduces: "d-nurbs.txt Fig 6, Fig 7b, Fig 7c",
            run: dnurbs::paper_fits,
        },
        Step {
            name: "d-nurbs swung egg",
            id: "egg",
            reproduces: "d-nurbs.txt Fig 9a",
            run: dnurbs::swung_egg,
        },
        Step {
            name: "d-nurbs rounding",
            id: "rounding",
            reproduces: "d-nurbs.txt Fig 8",
            run: rounding::rounding,
        },
        Step {
            name: "subdivision solids",
            id: "subdivision",
            reproduces: "subdivision-solids-conference.txt Table 1, Fig 1; journal Table 2",
            run: lattice::subdivided_solids,
        },
        Step {
            name: "ffd bottle",
            id: "ffd",
            reproduces: "ffd-direct-manipulation.txt Fig 3",
            run: ffd::bottle,
        },
        Step {
            name: "pde glass animation",
            id: "pde",
            reproduces: "dynamic-pde-surfaces.txt Fig 2",
            run: pde::glass,
        },
        Step {
            name: "pictures and exchange",
            id: "exchange",
            reproduces: "",
            run: exchange::pictures_and_exchange,
        },
        Step {
            name: "rope on a dynamic cube",
            id: "rope",
            reproduces: "subdivision-solids-journal.txt Fig 7, Fig 12",
            run: solids::rope_cube,
        },
        Step {
            name: "b-spline solid mass distribution",
            id: "mass",
            reproduces: "subdivision-solids-journal.txt Fig 3",
            run: solids::mass_distribution,
        },
        Step {
            name: "studio",
            id: "studio",
            reproduces: "",
            run: studio::screenshot,
        },
    ]
}

/// One finished step's record for the summary.
struct Record {
    name: &'static str,
    reproduces: &'static str,
    what: String,
    files: Vec<String>,
    millis: f64,
}

/// The steps that `only` names (every step when `only` is empty), in the demo's order; an
/// unknown name is an error that lists the names there are.
fn selected(only: &[String]) -> Result<Vec<Step>> {
    let steps = steps();
    if only.is_empty() {
        return Ok(steps);
    }
    let ids: Vec<&str> = steps.iter().map(|s| s.id).collect();
    if let Some(bad) = only.iter().find(|o| !ids.contains(&o.as_str())) {
        anyhow::bail!(
            "--only: no demo step `{bad}`; the steps are {}",
            ids.join(", ")
        );
    }
    Ok(steps
        .into_iter()
        .filter(|s| only.iter().any(|o| o == s.id))
        .collect())
}

/// Runs the demo into `out`: every step, or the steps `only` names (`vclay demo --only`).
pub fn run(out: &Path, only: &[String]) -> Result<()> {
    let steps = selected(only)?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let total = steps.len();
    let mut records = Vec::with_capacity(total);
    for (k, s) in steps.into_iter().enumerate() {
        if !crate::quiet() {
            eprintln!("[{}/{total}] {} ...", k + 1, s.name);
        }
        let t0 = Instant::now();
        let (what, files) = (s.run)(out).with_context(|| format!("demo step '{}'", s.name))?;
        let millis = t0.elapsed().as_secs_f64() * 1e3;
        if !crate::quiet() {
            eprintln!("[{}/{total}] {}: {what} ({millis:.1} ms)", k + 1, s.name);
        }
        records.push(Record {
            name: s.name,
            reproduces: s.reproduces,
            what,
            files,
            millis,
        });
    }
    let summary = json!({
        "complete": only.is_empty(),
        "steps": records.iter().map(|r| json!({
            "name": r.name, "reproduces": r.reproduces, "result": r.what,
            "files": r.files, "milliseconds": r.millis
        })).collect::<Vec<_>>()
    });
    let summary_path = out.join("summary.json");
    std::fs::write(
        &summary_path,
        serde_json::to_string_pretty(&summary)? + "\n",
    )
    .with_context(|| format!("cannot write {}", summary_path.display()))?;
    let (pictures, index_ms) = index::write_index(out, &records).context("demo index page")?;
    if !crate::quiet() {
        eprintln!("index.html: {pictures} pictures rendered ({index_ms:.1} ms)");
    }
    println!("vclay demo: results in {}/", out.display());
    for r in &records {
        println!("  {:<24} {:>9.1} ms  {}", r.name, r.millis, r.what);
        for f in &r.files {
            println!("  {:<24} {:>12}  -> {}", "", "", out.join(f).display());
        }
    }
    Ok(())
}
