//! `vclay clay MESH --cells N [--levels L] [--boundary smooth|sharp] --out LATTICE.ovm
//! [--surface S.obj] [--report R.json]`: a control lattice of about N hexahedra inside a closed
//! triangle mesh, its level-L boundary fitted to the mesh (issue 19). The logic lives in
//! `vclay_lattice::from_mesh`; this is reading, bounds, writing and the report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use vclay::TriMesh;
use vclay::lattice::command::{BYTES_PER_CELL, OutputFormat};
use vclay::lattice::from_mesh::{
    ClayParams, DEFAULT_CELLS, DEFAULT_LEVELS, MAX_CELLS, MAX_LEVELS, lattice_from_mesh,
};

use crate::subdivide::BoundaryArg;

/// Build a subdivision-solid control lattice from a closed triangle mesh (virtual clay).
#[derive(Debug, clap::Args)]
pub struct ClayArgs {
    /// Closed, consistently oriented triangle mesh: .obj, .stl, .ply or .glb (all meshes of a
    /// .glb together).
    pub mesh: PathBuf,
    /// About how many hexahedral cells the lattice gets (at most 200,000).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, value_name = "N", default_value_t = DEFAULT_CELLS)]
    pub cells: usize,
    /// Subdivision level whose boundary surface is fitted to the mesh (at most 4).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, value_name = "L", default_value_t = DEFAULT_LEVELS)]
    pub levels: usize,
    /// Boundary rule of the solid: smooth (Catmull-Clark boundary) or sharp (creases where the
    /// lattice's boundary bends).
    #[arg(long, value_enum, default_value_t = BoundaryArg::Smooth)]
    pub boundary: BoundaryArg,
    /// The control lattice: .ovm (OpenVolumeMesh, read back by `vclay subdivide`) or .vtu.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the fitted level-L boundary surface (.obj, .ply or .stl).
    #[arg(long, value_name = "FILE")]
    pub surface: Option<PathBuf>,
    /// Write the report (cells, smallest cell volume, distances relative to the bounding-box
    /// diagonal, seconds) as JSON here; it is also printed with --verbose.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

fn read_input(path: &Path) -> Result<TriMesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() == Some("glb") {
        let meshes = vclay::io::gltf::read_glb(path)?;
        let mut all = TriMesh::new();
        for m in &meshes {
            all.append(m);
        }
        Ok(all)
    } else {
        Ok(vclay::io::read_mesh(path)?)
    }
}

/// Runs `vclay clay`.
pub fn run(args: &ClayArgs) -> Result<()> {
    // Every bound before any reading or allocation.
    if args.cells == 0 || args.cells > MAX_CELLS {
        bail!("--cells {}: give 1 to {MAX_CELLS}", args.cells);
    }
    if args.levels > MAX_LEVELS {
        bail!("--levels {}: give 0 to {MAX_LEVELS}", args.levels);
    }
    let finest = args.cells as f64 * 8f64.powi(args.levels as i32);
    let bytes = finest * BYTES_PER_CELL as f64;
    if bytes > crate::limits::max_memory() as f64 {
        bail!(
            "--cells {} --levels {}: about {} of memory for {} cells at level {} \
             (lower --cells or --levels, or raise --max-memory)",
            args.cells,
            args.levels,
            crate::limits::human(bytes),
            finest,
            args.levels
        );
    }
    let out_format = OutputFormat::from_path(&args.out)?;
    if !matches!(out_format, OutputFormat::Ovm | OutputFormat::Vtu) {
        bail!(
            "--out {}: the lattice is written as .ovm or .vtu (use --surface for a surface)",
            args.out.display()
        );
    }
    let surface_format = args
        .surface
        .as_deref()
        .map(OutputFormat::from_path)
        .transpose()?;
    if matches!(surface_format, Some(OutputFormat::Ovm | OutputFormat::Vtu)) {
        bail!("--surface: give a surface file (.obj, .ply or .stl)");
    }
    let start = Instant::now();
    let mesh = read_input(&args.mesh)?;
    let params = ClayParams {
        cells: args.cells,
        levels: args.levels,
        boundary: args.boundary.into(),
        ..ClayParams::default()
    };
    let clay = lattice_from_mesh(&mesh, &params)
        .with_context(|| format!("vclay clay: {}", args.mesh.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    out_format.write(clay.solid.control(), &args.out)?;
    if let (Some(path), Some(format)) = (&args.surface, surface_format) {
        format.write(clay.solid.finest(), path)?;
    }
    let r = &clay.report;
    let json = format!("{{\"seconds\": {seconds:.3}, {}", &r.to_json()[1..]);
    if let Some(path) = &args.report {
        std::fs::write(path, format!("{json}\n"))
            .with_context(|| format!("--report {}", path.display()))?;
    }
    if crate::verbose() {
        eprintln!("{json}");
    }
    if !crate::quiet() {
        eprintln!(
            "vclay clay: {} cells, {} points -> {}; level-{} boundary to the mesh: mean {:.3} %, \
             max {:.3} % of the diagonal (voxels alone: {:.3} %, {:.3} %); smallest cell volume \
             {:.3e}; {:.2} s",
            r.cells,
            r.points,
            args.out.display(),
            r.levels,
            100.0 * r.distance.mean,
            100.0 * r.distance.max,
            100.0 * r.voxel_distance.mean,
            100.0 * r.voxel_distance.max,
            r.min_cell_volume,
            seconds
        );
    }
    if r.folded_cells + r.folded_cells_finest > 0 {
        eprintln!(
            "warning: {} control cells and {} cells at level {} have non-positive volume",
            r.folded_cells, r.folded_cells_finest, r.levels
        );
    }
    Ok(())
}
