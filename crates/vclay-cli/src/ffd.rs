//! `vclay ffd`: direct manipulation of a free-form deformation (`ffd-direct-manipulation.txt`).
//!
//! Embeds a triangle mesh in a NURBS-volume lattice (identity at rest), computes the least-norm
//! control-point displacement that moves each `--move SOURCE:TARGET` source point exactly onto
//! its target (eq 7 for one point, eq 12 for several), deforms the mesh, writes it and,
//! optionally, the deformed lattice as a `nurbs-volume` model file that `vclay eval` reads.
//! Prints a JSON report on stdout. The numerics live in `vclay_ffd`; this is argument handling.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde_json::json;
use vclay::Vec3;
use vclay::core::Parallelism;
use vclay::ffd::{
    DEFAULT_MARGIN, EmbeddedMesh, FfdError, FfdLattice, LatticeSpec, Manipulation, PointConstraint,
    SolveOptions,
};
use vclay::io::mesh::{MeshFormat, read_mesh, stage_mesh};
use vclay::io::model::{Entity, stage_model};

use crate::args;

/// Move points of a mesh to targets by direct manipulation of an FFD lattice; print a JSON report.
#[derive(Debug, clap::Args)]
pub struct FfdArgs {
    /// Input triangle mesh (.obj, .ply or .stl).
    pub input: PathBuf,
    /// Output mesh (.obj, .ply or .stl; STL and PLY are written binary).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Control points per axis, AxBxC (or N for NxNxN).
    #[arg(long, value_name = "AxBxC", default_value = "4x4x4")]
    pub lattice: String,
    /// B-spline degree along every axis (at most control points - 1).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = 3)]
    pub degree: usize,
    /// Lattice box xmin,ymin,zmin,xmax,ymax,zmax (default: the mesh's bounding box grown by 5%
    /// per side). Vertices outside the box stay put.
    #[arg(
        long = "box",
        value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
        allow_hyphen_values = true
    )]
    pub bbox: Option<String>,
    /// A point constraint SX,SY,SZ:TX,TY,TZ: the source S (a point of the undeformed space inside
    /// the box, usually on the object) goes to the target T. Repeat for several.
    #[arg(
        long = "move",
        value_name = "SX,SY,SZ:TX,TY,TZ",
        required = true,
        allow_hyphen_values = true
    )]
    pub moves: Vec<String>,
    /// Meet conflicting constraints as closely as possible (least squares) instead of failing.
    #[arg(long)]
    pub least_squares: bool,
    /// Also write the deformed lattice as a nurbs-volume model file (JSON, for `vclay eval`).
    #[arg(long, value_name = "L.json")]
    pub lattice_out: Option<PathBuf>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Runs `vclay ffd`.
pub fn run(a: &FfdArgs) -> Result<()> {
    let t_total = Instant::now();
    // Everything that can be checked without reading the mesh first.
    MeshFormat::from_path(&a.out).context("--out")?;
    let dims = args::triple_usize(&a.lattice, "--lattice")?;
    // Control points, rest points, weights and the solve's rows (1000x1000x1000 asked for
    // 24 GB at once).
    crate::limits::check_memory(
        &format!("--lattice {}", crate::limits::quote(&a.lattice)),
        crate::limits::ffd_bytes(dims),
    )?;
    let spec = LatticeSpec {
        degree: [a.degree; 3],
        control_points: dims,
    };
    let bbox = a.bbox.as_deref().map(args::bbox).transpose()?;
    let moves: Vec<(Vec3, Vec3)> = a
        .moves
        .iter()
        .map(|m| args::movement(m))
        .collect::<Result<_>>()?;

    let t = Instant::now();
    let mesh = read_mesh(&a.input)?;
    let read_ms = ms(t);
    if mesh.positions.is_empty() {
        bail!("{}: the mesh has no vertices", a.input.display());
    }
    if mesh.triangles.is_empty() {
        bail!("{}: the mesh has no triangles", a.input.display());
    }
    mesh.validate()
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;

    let t = Instant::now();
    let mut lattice = match bbox {
        Some((lo, hi)) => FfdLattice::new(spec, lo, hi),
        None => FfdLattice::enclosing(&mesh.positions, spec, DEFAULT_MARGIN),
    }
    .map_err(|e| lattice_error(e, &a.input))?;
    let (lo, hi) = lattice.bounds();
    let constraints: Vec<PointConstraint> = moves
        .iter()
        .enumerate()
        .map(|(k, &(s, target))| {
            PointConstraint::from_rest_point(&lattice, s, target).map_err(|_| {
                anyhow::anyhow!(
                    "--move {} ('{}'): source ({}, {}, {}) lies outside the lattice box \
                     [{}, {}, {}] - [{}, {}, {}]",
                    k + 1,
                    a.moves[k],
                    s.x,
                    s.y,
                    s.z,
                    lo.x,
                    lo.y,
                    lo.z,
                    hi.x,
                    hi.y,
                    hi.z
                )
            })
        })
        .collect::<Result<_>>()?;
    let manipulation = if constraints.len() == 1 {
        Manipulation::single(&lattice, &constraints[0])
    } else {
        let options = if a.least_squares {
            SolveOptions::least_squares()
        } else {
            SolveOptions::default()
        };
        Manipulation::multi(&lattice, &constraints, &options)
    }
    .map_err(|e| match e {
        FfdError::ConflictingConstraints { .. } => anyhow::anyhow!(
            "{} (constraint k is the (k+1)-th --move; use --least-squares to meet them as \
             closely as possible)",
            e
        ),
        e => anyhow::anyhow!(e),
    })?;
    lattice.try_apply(&manipulation).map_err(|e| {
        anyhow::anyhow!(
            "--move: the targets are too far away: the lattice's control points would leave the \
             finite numbers ({e})"
        )
    })?;
    let solve_ms = ms(t);

    let t = Instant::now();
    let embedded = EmbeddedMesh::new(&lattice, mesh, Parallelism::Auto);
    let deform_ms = ms(t);
    let size = lattice.size();
    let max_distance = constraints
        .iter()
        .map(|c| {
            lattice
                .point_at(c.params)
                .map(|x| (x - c.target).norm())
                .unwrap_or(f64::INFINITY)
        })
        .fold(0.0, f64::max);
    // A vertex counts as changed when it moved by more than 1e-12 of the lattice size.
    let tol = 1e-12 * size;
    let changed = embedded
        .mesh()
        .positions
        .iter()
        .zip(embedded.rest_positions())
        .filter(|(x, r)| (*x - *r).norm() > tol)
        .count();

    let t = Instant::now();
    // All or none: both files are written to temporaries first and renamed only when both
    // succeeded (issue 17: a failed lattice write left the mesh written).
    let mesh_file = stage_mesh(&a.out, embedded.mesh())?;
    let lattice_file = match &a.lattice_out {
        Some(path) => Some(stage_model(
            path,
            &[Entity::Volume(lattice.volume().clone())],
        )?),
        None => None,
    };
    mesh_file.commit()?;
    if let Some(f) = lattice_file {
        f.commit()?;
    }
    let write_ms = ms(t);

    let report = json!({
        "max_target_distance": max_distance,
        "max_target_distance_relative": max_distance / size,
        "vertices": embedded.mesh().positions.len(),
        "vertices_embedded": embedded.embedded_count(),
        "vertices_changed": changed,
        "constraints": constraints.len(),
        "control_points_moved": manipulation.len(),
        "lattice": {
            "control_points": lattice.dims(),
            "degree": lattice.degree(),
            "box": [[lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]],
        },
        "milliseconds": {
            "read": read_ms,
            "solve": solve_ms,
            "embed_and_deform": deform_ms,
            "write": write_ms,
            "total": ms(t_total),
        },
    });
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

/// Names the option behind a lattice construction error.
fn lattice_error(e: FfdError, input: &Path) -> anyhow::Error {
    match e {
        FfdError::Degree { .. } | FfdError::TooFewControlPoints { .. } => {
            anyhow::anyhow!("--lattice/--degree: {e}")
        }
        FfdError::InvalidBox { .. } => anyhow::anyhow!("--box: {e}"),
        FfdError::NonFinitePoint { .. } | FfdError::NoPoints => {
            anyhow::anyhow!("{}: {e}", input.display())
        }
        e => anyhow::anyhow!(e),
    }
}
