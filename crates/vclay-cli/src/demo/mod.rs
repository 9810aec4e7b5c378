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

mod spline;

/// What a demo step returns: a sentence describing the result, and the files it wrote.
pub type StepOutput = (String, Vec<String>);

/// A demo step: a name, the paper figure it reproduces (empty if none) and its function.
pub struct Step {
    /// Short name shown in the summary.
    pub name: &'static str,
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
            reproduces: "",
            run: spline::torus,
        },
        Step {
            name: "refined sheet",
            reproduces: "",
            run: spline::refined_sheet,
        },
        Step {
            name: "twisted volume",
            reproduces: "",
            run: spline::twisted_volume,
        },
        Step {
            name: "batched evaluation",
            reproduces: "",
            run: spline::batched_evaluation,
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

/// Runs the demo into `out`.
pub fn run(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let steps = steps();
    let total = steps.len();
    let mut records = Vec::with_capacity(total);
    for (k, s) in steps.into_iter().enumerate() {
        eprintln!("[{}/{total}] {} ...", k + 1, s.name);
        let t0 = Instant::now();
        let (what, files) = (s.run)(out).with_context(|| format!("demo step '{}'", s.name))?;
        let millis = t0.elapsed().as_secs_f64() * 1e3;
        eprintln!("[{}/{total}] {}: {what} ({millis:.1} ms)", k + 1, s.name);
        records.push(Record {
            name: s.name,
            reproduces: s.reproduces,
            what,
            files,
            millis,
        });
    }
    let summary = json!({
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
    println!("vclay demo: results in {}/", out.display());
    for r in &records {
        println!("  {:<24} {:>9.1} ms  {}", r.name, r.millis, r.what);
        for f in &r.files {
            println!("  {:<24} {:>12}  -> {}", "", "", out.join(f).display());
        }
    }
    Ok(())
}
