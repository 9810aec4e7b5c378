//! `vclay subdivide`: subdivide a lattice (an `.ovm` file or a built-in primitive) and print its
//! element counts or write it out. The logic lives in `vclay_lattice::command`; this is the
//! argument parsing.

use std::path::PathBuf;

use anyhow::Result;
use vclay::lattice::BoundaryRule;
use vclay::lattice::command::{
    CommandError, LatticeSource, SubdivideOptions, subdivide_command, subdivide_limit_command,
};

/// Subdivide a lattice N times (MacCracken-Joy); print counts (--stats) and/or write --out.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["input", "primitive"])))]
pub struct SubdivideArgs {
    /// Control lattice to read (OpenVolumeMesh .ovm text file).
    pub input: Option<PathBuf>,
    /// Built-in control lattice instead of INPUT: box[:AxBxC] (points per axis, default 4x4x4),
    /// cylinder[:SECTORS[xLAYERS[xRINGS]]] (default 4x2x0), torus[:SEGMENTSxCROSS] (default
    /// 8x4), paper-torus (the paper's), gear, cube-with-holes, tetrahedron-with-holes[:HOLE]
    /// (split into 10 convex cells, default 0.4), tetrahedron-with-holes-paper[:HOLE] (the
    /// paper's single cell, which folds; default 0.5), soccer-player, cactus, spiked-object,
    /// holed-object, l-solid[:ARMxWIDTH] (default 2x1; also l), t-solid[:ARMxWIDTH] (default
    /// 1x1; also t). The same names as a scenario's `primitive`.
    #[arg(long, value_name = "NAME[:ARGS]")]
    pub primitive: Option<String>,
    /// Number of subdivision levels (0 keeps the control lattice).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, value_name = "N")]
    pub levels: usize,
    /// Boundary rule: volumetric rules everywhere (interior), Catmull-Clark boundary surface
    /// (smooth), or smooth plus automatic creases and corners (sharp).
    #[arg(long, value_enum, default_value_t = BoundaryArg::Smooth)]
    pub boundary: BoundaryArg,
    /// Print {"points": P, "edges": E, "faces": F, "cells": C, "inverted_cells": I} of the
    /// result on stdout.
    #[arg(long)]
    pub stats: bool,
    /// Output file: .ovm or .vtu (the lattice), .obj, .ply or .stl (its boundary surface).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the boundary's limit surface instead (--out .obj, .ply or .stl): every boundary
    /// point of the last level moved to its Catmull-Clark limit position.
    #[arg(long)]
    pub limit: bool,
}

/// The `--boundary` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BoundaryArg {
    /// Volumetric rules everywhere.
    Interior,
    /// Catmull-Clark surface rules on the boundary.
    Smooth,
    /// Smooth, plus creases and corners where the boundary is not flat in the lattice.
    Sharp,
}

impl From<BoundaryArg> for BoundaryRule {
    fn from(b: BoundaryArg) -> Self {
        match b {
            BoundaryArg::Interior => BoundaryRule::Interior,
            BoundaryArg::Smooth => BoundaryRule::Smooth,
            BoundaryArg::Sharp => BoundaryRule::Sharp,
        }
    }
}

/// Levels from which `vclay subdivide` shows a spinner (with the elapsed time) on a terminal:
/// level 3 of a box takes about a second in a debug build, level 5 several in a release build.
const SPINNER_LEVELS: usize = 3;

/// Runs `vclay subdivide`.
pub fn run(args: &SubdivideArgs) -> Result<()> {
    let source = match (&args.input, &args.primitive) {
        (Some(path), None) => LatticeSource::File(path.clone()),
        (None, Some(spec)) => LatticeSource::Primitive(spec.clone()),
        _ => anyhow::bail!("give either an INPUT.ovm file or --primitive NAME, not both"),
    };
    let options = SubdivideOptions {
        source,
        levels: args.levels,
        boundary: args.boundary.into(),
        out: args.out.clone(),
        max_memory: crate::limits::max_memory(),
    };
    // The errors name the file, line and element (or the primitive); add the command.
    let spinner = (args.levels >= SPINNER_LEVELS)
        .then(|| crate::progress::spinner(&format!("vclay subdivide: {} levels", args.levels)));
    let outcome = if args.limit {
        subdivide_limit_command(&options)
    } else {
        subdivide_command(&options)
    };
    if let Some(s) = spinner {
        s.finish_and_clear();
    }
    let outcome = outcome.map_err(|e| match e {
        CommandError::TooMuchMemory { .. } => {
            anyhow::anyhow!("--levels {}: {e} (or raise --max-memory)", args.levels)
        }
        e => anyhow::Error::new(e).context("vclay subdivide failed"),
    })?;
    if args.stats {
        println!("{}", outcome.stats_json());
    }
    if !crate::quiet() {
        let c = &outcome.counts;
        eprintln!(
            "vclay subdivide: {} levels: {} points, {} cells{}",
            args.levels,
            c.points,
            c.cells,
            match &outcome.written {
                Some((path, _)) => format!(" -> {}", path.display()),
                None if args.stats => String::new(),
                None => " (nothing written: give --out FILE or --stats)".to_string(),
            }
        );
    }
    if outcome.inverted_cells > 0 {
        eprintln!(
            "warning: {} of {} cells of the subdivided lattice have non-positive volume \
             (folded; it happens with a control cell whose cell point lies outside it, as \
             tetrahedron-with-holes-paper's single cell, with a control cell sheared or bent \
             so much that the smooth surface rule moves its boundary layer through the cells \
             inside, with the sharp rule at the crease corners of paper-torus and gear, and \
             with the interior rule at boundary corners; docs/formats.md, `vclay subdivide`)",
            outcome.inverted_cells, outcome.counts.cells
        );
    }
    Ok(())
}
