//! The `vclay` command line.
//!
//! Subcommands: `eval` (evaluate a model file at parameters), `demo` (the main job: build
//! built-in models and write results to `./vclay-demo/`), `bench` (timings as JSON, used by
//! `bench/compare.py`). Errors go to stderr with exit code 2 and nothing on stdout.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

mod args;
mod bench;
mod clay;
mod convert;
mod demo;
mod eval;
mod ffd;
mod fit;
mod limits;
mod manual;
mod pde;
mod progress;
mod render;
mod run;
mod studio;
mod subdivide;

/// vclay: physics-based free-form modeling (virtual clay).
#[derive(Debug, Parser)]
#[command(name = "vclay", version, about, long_about = None, disable_help_subcommand = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Largest estimated memory a command may use (4G, 512M, bytes); sizes from arguments and
    /// files are checked against it before anything is allocated (docs/limits.md).
    #[arg(long, global = true, value_name = "SIZE", default_value = "4G",
          value_parser = limits::parse_bytes)]
    max_memory: u64,
    /// Print nothing but results and errors (no progress, no notes on stderr).
    #[arg(long, short, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Print more about what is done (timings, files) on stderr.
    #[arg(long, short, global = true)]
    verbose: bool,
}

static QUIET: AtomicBool = AtomicBool::new(false);
static VERBOSE: AtomicBool = AtomicBool::new(false);

/// Whether `--quiet` was given: no notes or progress on stderr.
pub(crate) fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Whether `--verbose` was given.
pub(crate) fn verbose() -> bool {
    VERBOSE.load(Ordering::Relaxed)
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a model, mesh or scenario headless to a PNG (or a turntable or animation GIF).
    Render(render::RenderArgs),
    /// Convert between file formats, chosen by extension (model, geomdl, STEP, meshes, glTF).
    Convert(convert::ConvertArgs),
    /// Evaluate a NURBS model file at parameters; prints {"points": [...], "derivatives": [...]}.
    #[command(group(clap::ArgGroup::new("where").required(true).args(["params", "at"])))]
    Eval {
        /// Model file (JSON, see docs/formats.md).
        model: PathBuf,
        /// JSON file with an array of parameter tuples ([u], [u,v] or [u,v,w]).
        #[arg(long, conflicts_with = "at")]
        params: Option<PathBuf>,
        /// Parameters inline instead of --params: U, U,V or U,V,W (repeat for several).
        #[arg(long, value_name = "U[,V[,W]]", allow_hyphen_values = true)]
        at: Vec<String>,
        /// Also print partial derivatives up to this total order.
        #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count)]
        derivatives: Option<usize>,
        /// Which entity of the file to evaluate (0-based).
        #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = 0)]
        entity: usize,
        /// Lattice (.ovm) only: the subdivision solid's boundary rule; --params holds
        /// [cell, u, v, w] tuples (--at CELL,U,V,W).
        #[arg(long, value_enum, default_value_t = subdivide::BoundaryArg::Smooth)]
        boundary: subdivide::BoundaryArg,
    },
    /// Build the built-in models and write results to a folder (default ./vclay-demo).
    Demo {
        /// Output folder.
        #[arg(long, default_value = "vclay-demo")]
        out: PathBuf,
        /// Run only these steps (comma-separated: torus, sheet, volume, batch, fit, egg,
        /// rounding, subdivision, ffd, pde, exchange, rope, studio); default all.
        #[arg(long, value_delimiter = ',', value_name = "STEPS")]
        only: Vec<String>,
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
    /// Build a subdivision-solid control lattice of about N cells from a closed triangle mesh,
    /// its level-L boundary fitted to the mesh; write it to --out.
    Clay(clay::ClayArgs),
    /// Move points of a mesh to targets by direct manipulation of an FFD lattice.
    Ffd(ffd::FfdArgs),
    /// Fit a smooth B-spline/NURBS surface to a scanned point cloud (D-NURBS fairness energy).
    Fit(fit::FitArgs),
    /// Solve a dynamic PDE surface spec at --t or over --frames; write meshes, print residuals.
    Pde(pde::PdeArgs),
    /// Run a scenario (TOML, docs/formats.md section 8) or continue a saved session
    /// (docs/formats.md section 10); writes to --out DIR, else ./vclay-run/<name>/.
    Run {
        /// Scenario (.toml) or session file.
        file: PathBuf,
        /// Steps to run (default: to the scenario's end).
        #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count_u64, conflicts_with = "until")]
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
        /// Most bytes the run may write (frames and energy table: 500M, 2G); it is checked,
        /// with the free space, before the first step (default: the free space only).
        #[arg(long, value_name = "SIZE", value_parser = crate::limits::parse_bytes)]
        max_output: Option<u64>,
    },
    /// Start the interactive studio (the `vclay-studio` binary): `vclay studio [FILE]
    /// [--autosave PATH]`; build it with `cargo build --release -p vclay-studio`.
    Studio {
        /// Arguments passed to `vclay-studio` (FILE, --autosave PATH, ...).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Print a shell completion script to stdout, e.g. `vclay completions bash >
    /// ~/.local/share/bash-completion/completions/vclay`.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) to stdout, e.g. `vclay man > vclay.1`; `vclay man COMMAND`
    /// prints the page of one subcommand (`vclay-COMMAND.1`).
    Man {
        /// A subcommand (default: the page of `vclay` itself).
        command: Option<String>,
    },
    /// Print the help of vclay or of a subcommand (`vclay help run` is `vclay run --help`).
    Help {
        /// A subcommand (default: vclay itself).
        command: Option<String>,
    },
}

/// `vclay help [COMMAND]` (clap's own help subcommand refused `vclay help --help`).
fn help(command: Option<&str>) -> anyhow::Result<()> {
    use clap::CommandFactory;
    let mut cli = Cli::command();
    // Built, the subcommands' usage lines say `vclay run`, not `run`.
    cli.build();
    let printed = match command {
        None => cli.print_long_help(),
        Some(name) => {
            let names: Vec<String> = cli
                .get_subcommands()
                .map(|c| c.get_name().to_string())
                .collect();
            let Some(sub) = cli.find_subcommand_mut(name) else {
                anyhow::bail!("no command `{name}`; the commands: {}", names.join(", "));
            };
            sub.print_long_help()
        }
    };
    match printed {
        // `vclay help | head`: a closed pipe is not an error.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    limits::set_max_memory(cli.max_memory);
    QUIET.store(cli.quiet, Ordering::Relaxed);
    VERBOSE.store(cli.verbose, Ordering::Relaxed);
    let quiet = cli.quiet;
    let result = match cli.command {
        Command::Eval {
            model,
            params,
            at,
            derivatives,
            entity,
            boundary,
        } => {
            let params = match params {
                Some(p) => eval::Params::File(p),
                None => eval::Params::Inline(at),
            };
            eval::run(&model, &params, derivatives, entity, boundary.into())
        }
        Command::Demo { out, only } => demo::run(&out, &only),
        Command::Bench {
            seconds,
            physics,
            large,
        } => bench::run(seconds, physics, large),
        Command::Render(args) => render::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Subdivide(args) => subdivide::run(&args),
        Command::Clay(args) => clay::run(&args),
        Command::Ffd(args) => ffd::run(&args),
        Command::Fit(args) => fit::run(&args),
        Command::Pde(args) => pde::run(&args),
        Command::Run {
            file,
            steps,
            until,
            save,
            out,
            max_output,
        } => run::run(&run::RunArgs {
            file,
            steps,
            until,
            save,
            out,
            max_output,
            quiet,
        }),
        Command::Studio { args } => studio::run(&args),
        Command::Completions { shell } => manual::completions(shell),
        Command::Help { command } => help(command.as_deref()),
        Command::Man { command } => manual::man(command.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::from(2)
        }
    }
}

/// The error and its causes joined by `: `, each said once: many typed errors print their
/// source in their own message too, so a cause whose text is already there is left out (issue
/// 17: messages were repeated two or three times).
fn message(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}
