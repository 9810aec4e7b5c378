//! The `vclay` command line.
//!
//! Subcommands: `eval` (evaluate a model file at parameters), `demo` (the main job: build
//! built-in models and write results to `./vclay-demo/`), `bench` (timings as JSON, used by
//! `bench/compare.py`). Errors go to stderr with exit code 2 and nothing on stdout.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

mod args;
mod bench;
mod convert;
mod demo;
mod eval;
mod ffd;
mod pde;
mod render;
mod run;
mod subdivide;

/// vclay: physics-based free-form modeling (virtual clay).
#[derive(Debug, Parser)]
#[command(name = "vclay", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a model or mesh headless to a PNG (or a turntable GIF).
    Render(render::RenderArgs),
    /// Convert between file formats, chosen by extension (model, geomdl, STEP, meshes, glTF).
    Convert(convert::ConvertArgs),
    /// Evaluate a NURBS model file at parameters; prints {"points": [...], "derivatives": [...]}.
    Eval {
        /// Model file (JSON, see docs/formats.md).
        model: PathBuf,
        /// JSON file with an array of parameter tuples ([u], [u,v] or [u,v,w]).
        #[arg(long)]
        params: PathBuf,
        /// Also print partial derivatives up to this total order.
        #[arg(long)]
        derivatives: Option<usize>,
        /// Which entity of the file to evaluate (0-based).
        #[arg(long, default_value_t = 0)]
        entity: usize,
    },
    /// Build the built-in models and write results to a folder (default ./vclay-demo).
    Demo {
        /// Output folder.
        #[arg(long, default_value = "vclay-demo")]
        out: PathBuf,
    },
    /// Time spline evaluation (and with --physics the simulations' speed goals) as JSON.
    Bench {
        /// Approximate seconds per measurement.
        #[arg(long, default_value_t = 1.0)]
        seconds: f64,
        /// Also time the D-NURBS and dynamic-solid benchmark models against their goals.
        #[arg(long)]
        physics: bool,
        /// With --physics, also the level-5 cube (912,673 data points: about 7 s to build and
        /// 2 GB of memory).
        #[arg(long)]
        large: bool,
    },
    /// Subdivide a lattice (MacCracken-Joy); print element counts (--stats) and/or write --out.
    Subdivide(subdivide::SubdivideArgs),
    /// Move points of a mesh to targets by direct manipulation of an FFD lattice.
    Ffd(ffd::FfdArgs),
    /// Solve a dynamic PDE surface spec at --t or over --frames; write meshes, print residuals.
    Pde(pde::PdeArgs),
    /// Run a scenario (TOML, docs/formats.md section 8) or continue a saved session
    /// (docs/formats.md section 10); writes to --out DIR, else ./vclay-run/<name>/.
    Run {
        /// Scenario (.toml) or session file.
        file: PathBuf,
        /// Steps to run (default: to the scenario's end).
        #[arg(long, conflicts_with = "until")]
        steps: Option<u64>,
        /// Run until the first model's clock reaches this time (s).
        #[arg(long)]
        until: Option<f64>,
        /// Save the whole session here at the end (continue it with `vclay run SESSION`).
        #[arg(long)]
        save: Option<PathBuf>,
        /// Output folder.
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Eval {
            model,
            params,
            derivatives,
            entity,
        } => eval::run(&model, &params, derivatives, entity),
        Command::Demo { out } => demo::run(&out),
        Command::Bench {
            seconds,
            physics,
            large,
        } => bench::run(seconds, physics, large),
        Command::Render(args) => render::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Subdivide(args) => subdivide::run(&args),
        Command::Ffd(args) => ffd::run(&args),
        Command::Pde(args) => pde::run(&args),
        Command::Run {
            file,
            steps,
            until,
            save,
            out,
            quiet,
        } => run::run(&run::RunArgs {
            file,
            steps,
            until,
            save,
            out,
            quiet,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
