//! `vclay fit`: a smooth surface fitted to a scanned point cloud (issue 20).
//!
//! Reads the cloud (`vclay_io::cloud`: `.xyz` text or the vertices of `.ply`, `.obj`, `.stl`),
//! fits a B-spline (or, with `--weights`, NURBS) surface with the D-NURBS fairness energy
//! (`vclay_fit`), writes it as a model file (`.json`), STEP (`.step`, `.stp`) or IGES (`.igs`,
//! `.iges`), and prints the fit report as JSON on stdout (and to `--report`; format in
//! `docs/formats.md`). Sizes are checked before allocation: the file size bounds the points read,
//! then `vclay_fit::memory_estimate` the fit, both against `--max-memory`. The numerics live in
//! `vclay_fit`; this is argument handling.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use vclay::fit::{FitOptions, RobustMode, fit_surface, memory_estimate};
use vclay::io::model::{Entity, NamedEntity};

/// Smallest bytes per point of any cloud file (`0 0 0\n` in `.xyz`): the bound on the points
/// of a mesh file before it is read.
const MIN_BYTES_PER_POINT: f64 = 6.0;
/// Bytes per point while reading, besides the file's bytes (`.xyz` is read whole): the point
/// (24 B) and the growing vector's slack (up to twice that while it is moved).
const READ_BYTES_PER_POINT: f64 = 56.0;

/// The most points `path` can hold: its lines for `.xyz` text (one point per line, counted in
/// one pass over the file), else its size over [`MIN_BYTES_PER_POINT`].
fn point_bound(path: &Path, size: f64) -> Result<f64> {
    let ext = ext_of(path);
    if !vclay::io::cloud::XYZ_EXTENSIONS.contains(&ext.as_str()) {
        return Ok(size / MIN_BYTES_PER_POINT);
    }
    use std::io::Read as _;
    let mut f = std::fs::File::open(path).with_context(|| format!("{}", path.display()))?;
    let mut buf = vec![0u8; 1 << 16];
    let mut lines = 1u64;
    loop {
        let n = f
            .read(&mut buf)
            .with_context(|| format!("{}", path.display()))?;
        if n == 0 {
            break;
        }
        lines += buf[..n].iter().filter(|&&b| b == b'\n').count() as u64;
    }
    Ok(lines as f64)
}

/// Fit a surface to a point cloud; print the report as JSON.
#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Scan: .xyz (.pts, .txt, .csv: x y z per line) or the vertices of a .ply, .obj or .stl.
    pub scan: PathBuf,
    /// Control points per direction, NUxNV (or N for NxN).
    #[arg(
        allow_hyphen_values = true,
        long,
        value_name = "NUxNV",
        default_value = "32x32"
    )]
    pub grid: String,
    /// B-spline degree in both directions.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = vclay::fit::DEFAULT_DEGREE)]
    pub degree: usize,
    /// Fairness: tension alpha and rigidity beta of the D-NURBS thin plate under tension
    /// (d-nurbs.txt eq 17), dimensionless (docs/formats.md); default 0,1e-9.
    #[arg(long, value_name = "ALPHA,BETA")]
    pub fairness: Option<String>,
    /// Fit the weights too (rational surface; D-NURBS dynamic weights, Gauss-Newton).
    #[arg(long)]
    pub weights: bool,
    /// Outliers: auto (default: plain least squares, robust with Tukey's weights once the
    /// first round shows gross outliers), none (plain least squares), or robust weights (IRLS)
    /// throughout: tukey (`--robust` alone) or huber.
    #[arg(long, value_name = "MODE", num_args = 0..=1, default_missing_value = "tukey")]
    pub robust: Option<RobustMode>,
    /// Plain least squares even on scans with outliers (same as `--robust none`).
    #[arg(long, conflicts_with = "robust")]
    pub no_robust: bool,
    /// Parameter-correction rounds (closest points, then refit).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = vclay::fit::DEFAULT_CORRECTIONS)]
    pub corrections: usize,
    /// Output surface: .json (vclay model), .step/.stp or .igs/.iges.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the report (JSON) to this file.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
}

fn ext_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// `NUxNV` or `N`.
fn parse_grid(s: &str) -> Result<[usize; 2]> {
    let parts: Vec<&str> = s.split(['x', 'X']).collect();
    let num = |t: &str| -> Result<usize> {
        match t.trim().parse::<usize>() {
            Ok(n) => Ok(n),
            Err(_) if t.trim().parse::<f64>().is_ok() => {
                bail!(
                    "--grid {s}: {t:?}: sizes are whole numbers of at least the degree + 1 (e.g. 32x32)"
                )
            }
            Err(_) => bail!("--grid {s}: {t:?} is not a whole number (e.g. 32x32)"),
        }
    };
    match parts.as_slice() {
        [n] => {
            let n = num(n)?;
            Ok([n, n])
        }
        [a, b] => Ok([num(a)?, num(b)?]),
        _ => bail!("--grid {s}: expected NUxNV (e.g. 32x32) or N"),
    }
}

/// `ALPHA,BETA`.
fn parse_fairness(s: &str) -> Result<(f64, f64)> {
    let parts: Vec<&str> = s.split(',').collect();
    let [a, b] = parts.as_slice() else {
        bail!("--fairness {s}: expected ALPHA,BETA (e.g. 0,1e-6)");
    };
    let num = |t: &str| -> Result<f64> {
        let v: f64 = t
            .trim()
            .parse()
            .with_context(|| format!("--fairness {s}: {t:?} is not a number"))?;
        if !(v.is_finite() && v >= 0.0) {
            bail!("--fairness {s}: {t} must be finite and non-negative");
        }
        Ok(v)
    };
    Ok((num(a)?, num(b)?))
}

/// Runs `vclay fit`.
pub fn run(args: &FitArgs) -> Result<()> {
    let t0 = Instant::now();
    let ext = ext_of(&args.out);
    if !["json", "step", "stp", "igs", "iges"].contains(&ext.as_str()) {
        bail!(
            "{}: unknown output format; expected .json, .step, .stp, .igs or .iges",
            args.out.display()
        );
    }
    let mut opts = FitOptions {
        grid: parse_grid(&args.grid)?,
        degree: args.degree,
        rational: args.weights,
        robust: if args.no_robust {
            RobustMode::None
        } else {
            args.robust.unwrap_or_default()
        },
        corrections: args.corrections,
        ..FitOptions::default()
    };
    if let Some(f) = &args.fairness {
        (opts.tension, opts.rigidity) = parse_fairness(f)?;
    }
    opts.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let size = std::fs::metadata(&args.scan)
        .with_context(|| format!("{}", args.scan.display()))?
        .len() as f64;
    let bound = point_bound(&args.scan, size)?;
    crate::limits::check_memory(
        &format!(
            "reading {} ({} bytes, up to {bound:.0} points)",
            args.scan.display(),
            size,
        ),
        size + bound * READ_BYTES_PER_POINT,
    )?;
    let points = vclay::io::cloud::read_point_cloud(&args.scan)?;
    let read_s = t0.elapsed().as_secs_f64();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    crate::limits::check_memory(
        &format!("--grid {} on {} points", args.grid, points.len()),
        memory_estimate(points.len(), &opts, threads) as f64,
    )?;
    let fit =
        fit_surface(&points, &opts).map_err(|e| anyhow::anyhow!("{}: {e}", args.scan.display()))?;
    if !crate::quiet() {
        for w in &fit.report.warnings {
            eprintln!("vclay: warning: {}: {w}", args.scan.display());
        }
        let r = &fit.report;
        if r.outliers_detected {
            eprintln!(
                "vclay: note: {}: {} of {} points ({:.2} %) lie beyond 4.685 sigma of the plain \
                 fit: gross outliers, fitted robustly (tukey; --robust none keeps plain least \
                 squares)",
                args.scan.display(),
                r.first_round_outliers,
                r.points,
                100.0 * r.first_round_outliers as f64 / r.points as f64
            );
        }
    }
    let t = Instant::now();
    let name = args
        .scan
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned());
    let entities = [NamedEntity {
        name,
        entity: Entity::Surface(fit.surface.clone()),
    }];
    match ext.as_str() {
        "json" => vclay::io::write_named_model(&args.out, &entities)?,
        "step" | "stp" => vclay::io::step::write_step(&args.out, &entities)?,
        _ => vclay::io::iges::write_iges(&args.out, &entities)?,
    }
    let write_s = t.elapsed().as_secs_f64();
    let mut report = serde_json::to_value(&fit.report)?;
    report["input"] = args.scan.display().to_string().into();
    report["output"] = args.out.display().to_string().into();
    report["timings"]["read"] = read_s.into();
    report["timings"]["write"] = write_s.into();
    report["timings"]["command"] = t0.elapsed().as_secs_f64().into();
    let text = serde_json::to_string_pretty(&report)?;
    if let Some(r) = &args.report {
        vclay::io::write_atomic(r, |w| writeln!(w, "{text}"))?;
    }
    println!("{text}");
    Ok(())
}
