//! The logic of the `vclay subdivide` command, as a library function so that it is tested here
//! and the command line only parses arguments.
//!
//! `vclay subdivide (INPUT.ovm | --primitive NAME[:ARGS]) --levels N
//! [--boundary interior|smooth|sharp] [--stats] [--out FILE.(ovm|vtu|obj|ply|stl)]` maps to
//! [`SubdivideOptions`] and [`subdivide_command`]; `--stats` prints
//! [`SubdivideOutcome::stats_json`]. Primitive names and arguments are listed in
//! [`PRIMITIVE_HELP`] and parsed by [`primitive`].

use std::path::{Path, PathBuf};

use thiserror::Error;
use vclay_core::Vec3;

use crate::boundary::boundary_mesh;
use crate::error::LatticeError;
use crate::formats::{FormatError, ovm, surface, vtu};
use crate::hierarchy::SubdivisionSolid;
use crate::ids::CellId;
use crate::lattice::{ElementCounts, Lattice};
use crate::subdivide::{BoundaryRule, Features, SubdivisionRules};
use crate::{gallery, primitives};

/// Help text of the primitive names accepted by [`primitive`].
pub const PRIMITIVE_HELP: &str = "box[:AxBxC] (points per axis, default 4x4x4, unit cells), \
cylinder[:SECTORS[xLAYERS[xRINGS]]] (default 4x2x0, the paper's cylinder; radius 1, height 2), \
torus[:SEGMENTSxCROSS] (square cross-section of CROSSxCROSS hexahedra, default 8x4), paper-torus (the \
paper's torus), \
gear (the paper's gear), cube-with-holes (the paper's cube with holes), \
tetrahedron-with-holes[:HOLE] (the paper's solid split into 6 prisms and 4 tetrahedra so that no cell \
folds; HOLE the relative hole size, default 0.4), tetrahedron-with-holes-paper[:HOLE] (the paper's single \
cell, Table 1's counts; it folds when subdivided; default 0.5), soccer-player, cactus (conference Table 1), \
spiked-object, holed-object (journal Table 2), \
l-solid[:ARMxWIDTH] (L solid, default 2x1; also `l`), t-solid[:ARMxWIDTH] (T solid, default 1x1; also \
`t`)";

/// One lattice primitive of the registry: its name, the same on the command line
/// (`vclay subdivide --primitive`) and in scenarios (`[model] primitive`), and the other names it
/// answers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimitiveName {
    /// The name.
    pub name: &'static str,
    /// Other names (older spellings).
    pub aliases: &'static [&'static str],
}

const fn prim(name: &'static str, aliases: &'static [&'static str]) -> PrimitiveName {
    PrimitiveName { name, aliases }
}

/// The one registry of lattice primitives (names and aliases) for the command line and
/// scenarios.
pub const PRIMITIVES: &[PrimitiveName] = &[
    prim("box", &["cube"]),
    prim("cylinder", &[]),
    prim("torus", &[]),
    prim("paper-torus", &[]),
    prim("gear", &[]),
    prim("cube-with-holes", &[]),
    prim("tetrahedron-with-holes", &["tet-with-holes"]),
    prim("tetrahedron-with-holes-paper", &["tet-with-holes-paper"]),
    prim("soccer-player", &[]),
    prim("cactus", &[]),
    prim("spiked-object", &[]),
    prim("holed-object", &[]),
    prim("l-solid", &["l"]),
    prim("t-solid", &["t"]),
];

/// The registry name of `name` (any case, aliases resolved), if it is a primitive.
pub fn canonical_primitive(name: &str) -> Option<&'static str> {
    let n = name.trim().to_ascii_lowercase();
    PRIMITIVES
        .iter()
        .find(|p| p.name == n || p.aliases.contains(&n.as_str()))
        .map(|p| p.name)
}

/// Every primitive name, comma separated (for messages).
pub fn primitive_names() -> String {
    PRIMITIVES
        .iter()
        .map(|p| p.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The name of every primitive [`primitive`] builds, each with its default arguments (the
/// tests subdivide each one and check that no cell folds, except
/// `tetrahedron-with-holes-paper`, the paper's single non-convex cell, which folds by
/// construction: see [`primitives::tetrahedron_with_holes_split`]).
pub const PRIMITIVE_NAMES: &[&str] = &[
    "box",
    "cylinder",
    "torus",
    "paper-torus",
    "gear",
    "cube-with-holes",
    "tetrahedron-with-holes",
    "tetrahedron-with-holes-paper",
    "soccer-player",
    "cactus",
    "spiked-object",
    "holed-object",
    "l-solid",
    "t-solid",
];

/// Largest predicted cell count (`cells * 8^levels`) [`subdivide_command`] accepts: 50 million.
pub const MAX_PREDICTED_CELLS: u128 = 50_000_000;

/// Estimated peak memory of [`subdivide_command`] per cell of the finest level, in bytes: the
/// whole hierarchy (every level's lattice and level operator) plus the written file's buffers.
/// Measured peak resident sizes of `vclay subdivide --primitive box --stats`: 724 B per cell at
/// level 5 (884,736 cells, 641 MB) and 661 B at level 6 (7,077,888 cells, 4.7 GB); rounded up.
pub const BYTES_PER_CELL: u64 = 760;

/// A memory limit as the user gives it (`--max-memory`: powers of 1024): `4G` for the default,
/// `512M`; bytes when it is no whole number of K, M, G or T.
fn limit_as_given(bytes: u64) -> String {
    for (unit, shift) in [("T", 40), ("G", 30), ("M", 20), ("K", 10)] {
        if bytes >= 1 << shift && bytes.is_multiple_of(1 << shift) {
            return format!("{}{unit}", bytes >> shift);
        }
    }
    format!("{bytes} bytes")
}

/// Default of [`SubdivideOptions::max_memory`]: 4 GiB, what a laptop can spare.
pub const DEFAULT_MAX_MEMORY: u64 = 4 << 30;

/// Errors of [`subdivide_command`] and [`primitive`].
#[derive(Debug, Error)]
pub enum CommandError {
    /// Reading or writing a file failed.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A primitive specification could not be understood.
    #[error("primitive '{spec}': {message} (known: {PRIMITIVE_HELP})")]
    BadPrimitive {
        /// The specification as given.
        spec: String,
        /// What is wrong.
        message: String,
    },
    /// A primitive's arguments are in range but give a degenerate lattice (a hole so small
    /// that its points coincide).
    #[error("primitive '{spec}': the lattice is degenerate: {source}; use a less extreme size")]
    DegeneratePrimitive {
        /// The specification as given.
        spec: String,
        /// What the lattice's validation found.
        source: LatticeError,
    },
    /// The output file's extension names no supported format.
    #[error("{}: unknown output format (use .ovm, .vtu, .obj, .ply or .stl)", path.display())]
    UnknownOutputFormat {
        /// The output path.
        path: PathBuf,
    },
    /// `--limit` was asked with an output that is not a surface (`.obj`, `.ply`, `.stl`).
    #[error("{}: the limit surface is written to .obj, .ply or .stl only", path.display())]
    LimitOutputFormat {
        /// The output path (empty when none was given).
        path: PathBuf,
    },
    /// The input file's extension is not `.ovm`.
    #[error("{}: unknown input format (only .ovm lattices can be read)", path.display())]
    UnknownInputFormat {
        /// The input path.
        path: PathBuf,
    },
    /// Subdivision would produce too many cells.
    #[error(
        "{levels} levels would give about {predicted} cells (more than {MAX_PREDICTED_CELLS}); use fewer levels"
    )]
    TooManyLevels {
        /// Levels asked for.
        levels: usize,
        /// Predicted cell count.
        predicted: u128,
    },
    /// Subdivision would need more memory than [`SubdivideOptions::max_memory`].
    #[error(
        "{levels} levels would give about {predicted} cells and need about {:.1} GB of memory, \
         more than the limit of {}; use fewer levels",
        *bytes as f64 / 1e9,
        limit_as_given(*max)
    )]
    TooMuchMemory {
        /// Levels asked for.
        levels: usize,
        /// Predicted cell count.
        predicted: u128,
        /// Estimated peak memory in bytes ([`BYTES_PER_CELL`] per cell).
        bytes: u128,
        /// The limit, [`SubdivideOptions::max_memory`].
        max: u64,
    },
    /// Subdivision failed.
    #[error("subdividing {source_name}: {source}")]
    Subdivision {
        /// The input file or primitive.
        source_name: String,
        /// What failed.
        source: LatticeError,
    },
}

/// Where the control lattice comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LatticeSource {
    /// An `.ovm` file.
    File(PathBuf),
    /// A primitive specification `NAME[:ARGS]` (see [`PRIMITIVE_HELP`]).
    Primitive(String),
}

impl LatticeSource {
    /// The name used in messages.
    pub fn name(&self) -> String {
        match self {
            LatticeSource::File(p) => p.display().to_string(),
            LatticeSource::Primitive(s) => format!("primitive '{s}'"),
        }
    }

    /// Loads (reads or builds) the control lattice.
    pub fn load(&self) -> Result<Lattice, CommandError> {
        match self {
            LatticeSource::File(p) => {
                let ext = extension(p);
                if ext != "ovm" {
                    return Err(CommandError::UnknownInputFormat { path: p.clone() });
                }
                Ok(ovm::read(p)?)
            }
            LatticeSource::Primitive(s) => primitive(s),
        }
    }
}

/// Output file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// OpenVolumeMesh text (`.ovm`): the subdivided lattice.
    Ovm,
    /// VTK XML unstructured grid (`.vtu`): the subdivided lattice.
    Vtu,
    /// Wavefront OBJ (`.obj`): the boundary surface.
    Obj,
    /// ASCII PLY (`.ply`): the boundary surface.
    Ply,
    /// ASCII STL (`.stl`): the boundary surface.
    Stl,
}

impl OutputFormat {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, CommandError> {
        Ok(match extension(path).as_str() {
            "ovm" => Self::Ovm,
            "vtu" => Self::Vtu,
            "obj" => Self::Obj,
            "ply" => Self::Ply,
            "stl" => Self::Stl,
            _ => {
                return Err(CommandError::UnknownOutputFormat {
                    path: path.to_path_buf(),
                });
            }
        })
    }

    /// Writes `lattice` (or its boundary surface) to `path` in this format.
    pub fn write(self, lattice: &Lattice, path: &Path) -> Result<(), FormatError> {
        match self {
            Self::Ovm => ovm::write(lattice, path),
            Self::Vtu => vtu::write(lattice, path),
            Self::Obj => surface::write_obj(&boundary_mesh(lattice), path),
            Self::Ply => surface::write_ply(&boundary_mesh(lattice), path),
            Self::Stl => surface::write_stl(&boundary_mesh(lattice), path),
        }
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Options of the `subdivide` command.
#[derive(Clone, Debug, PartialEq)]
pub struct SubdivideOptions {
    /// The control lattice.
    pub source: LatticeSource,
    /// Number of subdivision levels (0 writes the control lattice itself).
    pub levels: usize,
    /// Boundary rule.
    pub boundary: BoundaryRule,
    /// Output file; its extension picks the [`OutputFormat`].
    pub out: Option<PathBuf>,
    /// Largest estimated peak memory in bytes ([`BYTES_PER_CELL`] per predicted cell) that the
    /// command accepts before it subdivides; default [`DEFAULT_MAX_MEMORY`].
    pub max_memory: u64,
}

/// What [`subdivide_command`] did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SubdivideOutcome {
    /// Element counts of the control lattice.
    pub control: ElementCounts,
    /// Element counts of the subdivided lattice.
    pub counts: ElementCounts,
    /// The file written and its format, if any.
    pub written: Option<(PathBuf, OutputFormat)>,
    /// Cells of the subdivided lattice whose signed volume
    /// ([`Lattice::cell_signed_volume`]) is not positive: folded or degenerate cells (the
    /// subdivided tetrahedron with holes has many; see `docs/formats.md`).
    pub inverted_cells: usize,
}

impl SubdivideOutcome {
    /// `{"points": P, "edges": E, "faces": F, "cells": C, "inverted_cells": I}` of the
    /// subdivided lattice.
    pub fn stats_json(&self) -> String {
        let c = self.counts;
        format!(
            "{{\"points\": {}, \"edges\": {}, \"faces\": {}, \"cells\": {}, \"inverted_cells\": {}}}",
            c.points, c.edges, c.faces, c.cells, self.inverted_cells
        )
    }
}

/// Loads the control lattice, checks the predicted size and subdivides it `levels` times.
fn checked_solid(
    options: &SubdivideOptions,
) -> Result<(SubdivisionSolid, ElementCounts), CommandError> {
    let control = options.source.load()?;
    let predicted = (control.num_cells() as u128)
        .saturating_mul(8u128.saturating_pow(options.levels.min(64) as u32));
    if predicted > MAX_PREDICTED_CELLS {
        return Err(CommandError::TooManyLevels {
            levels: options.levels,
            predicted,
        });
    }
    let bytes = predicted.saturating_mul(BYTES_PER_CELL as u128);
    if bytes > options.max_memory as u128 {
        return Err(CommandError::TooMuchMemory {
            levels: options.levels,
            predicted,
            bytes,
            max: options.max_memory,
        });
    }
    let control_counts = control.counts();
    let features = Features::none(&control);
    let solid = SubdivisionSolid::new(
        control,
        features,
        SubdivisionRules::new(options.boundary),
        options.levels,
    )
    .map_err(|source| CommandError::Subdivision {
        source_name: options.source.name(),
        source,
    })?;
    Ok((solid, control_counts))
}

/// Loads the control lattice, subdivides it `levels` times and writes the result if asked.
/// The output format is checked before any work is done.
pub fn subdivide_command(options: &SubdivideOptions) -> Result<SubdivideOutcome, CommandError> {
    let format = options
        .out
        .as_deref()
        .map(OutputFormat::from_path)
        .transpose()?;
    let (solid, control_counts) = checked_solid(options)?;
    let finest = solid.finest();
    let written = match (&options.out, format) {
        (Some(path), Some(format)) => {
            format.write(finest, path)?;
            Some((path.clone(), format))
        }
        _ => None,
    };
    let inverted_cells = (0..finest.num_cells())
        .filter(|&c| finest.cell_signed_volume(CellId::new(c)) <= 0.0)
        .count();
    Ok(SubdivideOutcome {
        control: control_counts,
        counts: finest.counts(),
        written,
        inverted_cells,
    })
}

/// Builds a primitive from `NAME[:ARGS]` (see [`PRIMITIVE_HELP`]).
pub fn primitive(spec: &str) -> Result<Lattice, CommandError> {
    let bad = |message: String| CommandError::BadPrimitive {
        spec: spec.to_string(),
        message,
    };
    let (given, args) = match spec.split_once(':') {
        Some((n, a)) => (n.trim(), Some(a.trim())),
        None => (spec.trim(), None),
    };
    let Some(name) = canonical_primitive(given) else {
        return Err(bad(format!(
            "unknown name '{given}'; the primitives are {}",
            primitive_names()
        )));
    };
    // Parses `AxBx..` into at most `max` integers, each at least `min`.
    let nums = |max: usize, min: usize| -> Result<Vec<usize>, CommandError> {
        let Some(a) = args else { return Ok(Vec::new()) };
        let v: Vec<usize> = a
            .split(['x', 'X'])
            .map(|t| t.trim().parse::<usize>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad(format!("arguments '{a}' are not integers separated by 'x'")))?;
        if v.is_empty() || v.len() > max {
            return Err(bad(format!("expected 1 to {max} numbers, got '{a}'")));
        }
        if let Some(x) = v.iter().find(|&&x| x < min) {
            return Err(bad(format!("{x} is too small (at least {min})")));
        }
        if let Some(x) = v.iter().find(|&&x| x > 1000) {
            return Err(bad(format!("{x} is too large (at most 1000)")));
        }
        Ok(v)
    };
    let no_args = |what: &str| -> Result<(), CommandError> {
        match args {
            Some(a) => Err(bad(format!("{what} takes no arguments, got '{a}'"))),
            None => Ok(()),
        }
    };
    match name {
        "box" => {
            let v = nums(3, 2)?;
            let n = match v.len() {
                0 => [4, 4, 4],
                1 => [v[0]; 3],
                3 => [v[0], v[1], v[2]],
                _ => return Err(bad("expected N or AxBxC points per axis".into())),
            };
            let max = Vec3::new(n[0] as f64 - 1.0, n[1] as f64 - 1.0, n[2] as f64 - 1.0);
            Ok(primitives::box_lattice(n, Vec3::zeros(), max))
        }
        "cylinder" => {
            let v = nums(3, 0)?;
            let sectors = v.first().copied().unwrap_or(4);
            let layers = v.get(1).copied().unwrap_or(2);
            let rings = v.get(2).copied().unwrap_or(0);
            if sectors < 3 || layers < 1 {
                return Err(bad("needs at least 3 sectors and 1 layer".into()));
            }
            Ok(primitives::cylinder(1.0, 2.0, sectors, layers, rings))
        }
        "torus" => {
            let v = nums(2, 1)?;
            match v.len() {
                0 => Ok(primitives::torus(2.0, 0.75, 8, 4)),
                2 if v[0] >= 3 => Ok(primitives::torus(2.0, 0.75, v[0], v[1])),
                _ => Err(bad(
                    "expected SEGMENTSxCROSS with at least 3 segments".into()
                )),
            }
        }
        "paper-torus" => {
            no_args("paper-torus")?;
            Ok(primitives::paper_torus(1.0, 2.0, 1.0))
        }
        "gear" => {
            no_args("gear")?;
            Ok(primitives::gear(1.0, 2.0, 2.6, 1.0))
        }
        "cube-with-holes" => {
            no_args("cube-with-holes")?;
            Ok(primitives::cube_with_holes(1.0))
        }
        "tetrahedron-with-holes" | "tetrahedron-with-holes-paper" => {
            let paper = name.ends_with("-paper");
            let hole = match args {
                None if paper => 0.5,
                None => primitives::DEFAULT_SPLIT_HOLE,
                Some(a) => match a.parse::<f64>() {
                    Ok(h) if h > 0.0 && h < 1.0 => h,
                    _ => {
                        return Err(bad(format!(
                            "hole size '{a}' must be a number strictly between 0 and 1"
                        )));
                    }
                },
            };
            let built = if paper {
                primitives::try_tetrahedron_with_holes(2.0, hole)
            } else {
                primitives::try_tetrahedron_with_holes_split(2.0, hole)
            };
            built.map_err(|source| CommandError::DegeneratePrimitive {
                spec: spec.to_string(),
                source,
            })
        }
        "soccer-player" => {
            no_args("soccer-player")?;
            Ok(gallery::soccer_player(2.0))
        }
        "cactus" => {
            no_args("cactus")?;
            Ok(gallery::cactus(4.0))
        }
        "spiked-object" => {
            no_args("spiked-object")?;
            Ok(gallery::spiked_object(1.0))
        }
        "holed-object" => {
            no_args("holed-object")?;
            Ok(gallery::holed_object(1.0))
        }
        "l-solid" | "t-solid" => {
            let v = nums(2, 1)?;
            let default = if name == "l-solid" { [2, 1] } else { [1, 1] };
            let (arm, width) = match v.len() {
                0 => (default[0], default[1]),
                1 => (v[0], default[1]),
                _ => (v[0], v[1]),
            };
            Ok(if name == "l-solid" {
                primitives::l_solid(arm, width, 1.0)
            } else {
                primitives::t_solid(arm, width, 1.0)
            })
        }
        _ => Err(bad(format!("unknown name '{name}'"))),
    }
}

/// As [`subdivide_command`], but writes the boundary **limit** surface (issue 19): every
/// boundary vertex of the finest level at its Catmull-Clark limit position with its limit normal
/// ([`crate::limit_surface::write_limit_boundary`]), to `options.out`, which must be `.obj`,
/// `.ply` or `.stl` (these writers keep positions only; the limit normals reach
/// [`vclay_core::MeshSink`] users such as the renderer). Needs the smooth or sharp boundary
/// rule.
pub fn subdivide_limit_command(
    options: &SubdivideOptions,
) -> Result<SubdivideOutcome, CommandError> {
    let (path, format) = match options.out.as_deref().map(OutputFormat::from_path) {
        Some(Ok(f @ (OutputFormat::Obj | OutputFormat::Ply | OutputFormat::Stl))) => {
            (options.out.clone().unwrap_or_default(), f)
        }
        _ => {
            return Err(CommandError::LimitOutputFormat {
                path: options.out.clone().unwrap_or_default(),
            });
        }
    };
    let (solid, control_counts) = checked_solid(options)?;
    let finest = solid.finest();
    let mut mesh = vclay_core::TriMesh::new();
    crate::limit_surface::write_limit_boundary(
        finest,
        solid.features(solid.levels()),
        options.boundary,
        &mut mesh,
    )
    .map_err(|source| CommandError::Subdivision {
        source_name: options.source.name(),
        source,
    })?;
    match format {
        OutputFormat::Obj => surface::write_obj(&mesh, &path)?,
        OutputFormat::Ply => surface::write_ply(&mesh, &path)?,
        _ => surface::write_stl(&mesh, &path)?,
    }
    let inverted_cells = (0..finest.num_cells())
        .filter(|&c| finest.cell_signed_volume(CellId::new(c)) <= 0.0)
        .count();
    Ok(SubdivideOutcome {
        control: control_counts,
        counts: finest.counts(),
        written: Some((path, format)),
        inverted_cells,
    })
}
