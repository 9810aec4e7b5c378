//! `vclay convert IN OUT [--samples N]`: between file formats, chosen by extension.
//!
//! Read: vclay model JSON and geomdl JSON (`.json`, told apart by content: geomdl has a
//! top-level `"shape"`), STEP (`.step`, `.stp`, `.p21`) and IGES (`.igs`, `.iges`) B-spline
//! curves and surfaces (what is not read is printed as a warning unless `--quiet`), meshes
//! (`.obj`, `.stl`, `.ply`, `.glb`), `.vtu` lattices as their boundary mesh, and
//! subdivision-solid lattices (`.ovm`) as the bicubic
//! patches of their boundary limit surface (joined into one B-rep shell in STEP/IGES: a solid
//! when the patches close up).
//! Write: vclay model (`.json`), geomdl (`.geomdl.json`), STEP (`.step`, `.stp`) and IGES
//! (`.igs`, `.iges`) with exact NURBS geometry as B-reps: a closed surface or a volume's boundary
//! as a solid, an open surface as an open shell (`--loose`: loose surfaces and curves,
//! `GEOMETRIC_SET` / entities 126 and 128, no topology),
//! meshes (`.obj`, `.stl`, `.ply`, `.glb`: models are tessellated, curves are left out).
//! A mesh cannot become exact geometry: mesh to model, geomdl, STEP or IGES is refused.

use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};
use vclay::TriMesh;
use vclay::io::brep::BrepSummary;
use vclay::io::brep::Shell;
use vclay::io::geomdl::{is_geomdl, parse_geomdl, write_geomdl};
use vclay::io::gltf::{GlbMesh, read_glb, write_glb};
use vclay::io::iges::{IgesLayout, write_iges_trimmed};
use vclay::io::mesh::{read_mesh, write_mesh};
use vclay::io::model::{
    Entity, NamedEntity, import_model, parse_trimmed_model, write_trimmed_model,
};
use vclay::io::step::{StepLayout, write_step_trimmed};
use vclay::io::step_read::{TrimmedFace, tessellate_trimmed};
use vclay::spline::{tessellate_surface, tessellate_volume_boundary};

/// Arguments of `vclay convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input file (.json model or geomdl, .step/.stp, .igs/.iges, .obj, .stl, .ply, .glb, or a
    /// lattice .ovm: the limit surface as bicubic patches, or a lattice .vtu: its boundary mesh).
    pub input: PathBuf,
    /// Output file (.json, .geomdl.json, .step/.stp, .igs/.iges, .obj, .stl, .ply, .glb).
    pub output: PathBuf,
    /// Tessellation samples per parametric axis when a model becomes a mesh.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::limits::parse_count, default_value_t = 48)]
    pub samples: usize,
    /// STEP and IGES: write loose surfaces and curves (a GEOMETRIC_SET; IGES 126/128) instead of
    /// B-rep solids and shells.
    #[arg(long)]
    pub loose: bool,
    /// STEP and IGES: join all surfaces (and volume boundary faces) into one shell along their
    /// coinciding boundaries, a solid when they close up (the default for a lattice .ovm, whose
    /// limit surface is many patches); without it each surface is its own shell.
    #[arg(long, conflicts_with = "loose")]
    pub join: bool,
}

/// What a file held.
pub enum Loaded {
    /// Exact geometry (model or geomdl JSON).
    Entities(Vec<NamedEntity>),
    /// Triangle meshes.
    Meshes(Vec<TriMesh>),
    /// A B-rep of trimmed faces: its surfaces (exact, whole), a STEP file's faces' trimming
    /// loops as read (applied when it is tessellated, [`trimmed_mesh`], issue 20) and the
    /// trimmed shells (issue 30: written back to STEP and JSON with their trims).
    Trimmed(Vec<NamedEntity>, Vec<TrimmedFace>, Vec<Shell>),
}

fn ext_of(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.ends_with(".geomdl.json") {
        return "geomdl.json".into();
    }
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Domain-triangle subdivision level of triangular NURBS (`"type": "triangular-nurbs"`) when
/// they are tessellated for OBJ, glTF or pictures (`level^2` triangles per domain triangle).
pub const TRIANGULAR_TESSELLATION_LEVEL: usize = 8;

/// A triangular NURBS file tessellated ([`TRIANGULAR_TESSELLATION_LEVEL`]).
fn triangular_mesh(path: &Path, text: &str) -> Result<TriMesh> {
    let t = vclay::io::triangular::parse_triangular(text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let mut mesh = TriMesh::new();
    t.surface
        .tessellate(TRIANGULAR_TESSELLATION_LEVEL, &mut mesh)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(mesh)
}

/// Reads any supported input, choosing by extension (and, for .json, by content).
pub fn read_any(path: &Path) -> Result<Loaded> {
    match ext_of(path).as_str() {
        "json" | "geomdl.json" => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            if vclay::io::triangular::is_triangular(&text) {
                return Ok(Loaded::Meshes(vec![triangular_mesh(path, &text)?]));
            }
            let (ents, shells) = if is_geomdl(&text) {
                parse_geomdl(&text).map(|e| (e, Vec::new()))
            } else {
                parse_trimmed_model(&text)
            }
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            if shells.is_empty() {
                Ok(Loaded::Entities(ents))
            } else {
                Ok(Loaded::Trimmed(ents, Vec::new(), shells))
            }
        }
        "step" | "stp" | "p21" | "igs" | "iges" => {
            let imported = import_model(path)?;
            if !crate::quiet() {
                for w in &imported.warnings {
                    eprintln!("vclay: warning: {}: {w}", path.display());
                }
            }
            if imported.faces.is_empty() && imported.shells.is_empty() {
                Ok(Loaded::Entities(imported.entities))
            } else {
                Ok(Loaded::Trimmed(
                    imported.entities,
                    imported.faces,
                    imported.shells,
                ))
            }
        }
        "ovm" => Ok(Loaded::Entities(lattice_patches(path)?)),
        "vtu" => Ok(Loaded::Meshes(vec![vtu_boundary(path)?])),
        "glb" => Ok(Loaded::Meshes(read_glb(path)?)),
        "obj" | "stl" | "ply" => Ok(Loaded::Meshes(vec![read_mesh(path)?])),
        other => bail!(
            "{}: unknown input format {}; expected .json (vclay or geomdl model), .step, .stp, .igs, .iges, .obj, .stl, .ply, .glb, .ovm or .vtu",
            path.display(),
            if other.is_empty() {
                "(no extension)".to_string()
            } else {
                format!("\".{other}\"")
            }
        ),
    }
}

/// The boundary limit surface of the subdivision solid whose control lattice is `path` (smooth
/// boundary rule) as bicubic patches (`vclay_lattice::boundary_patches`, issue 20): exact in
/// regular regions, least-squares fitted near extraordinary points; the fit error is printed.
pub fn lattice_patches(path: &Path) -> Result<Vec<NamedEntity>> {
    use vclay::lattice::limit_surface::DEFAULT_PATCH_SAMPLE_LEVELS as LEVELS;
    use vclay::lattice::{BoundaryRule, Features, SubdivisionRules, boundary_patches};
    let lattice = vclay::lattice::formats::ovm::read(path)?;
    // The patches subdivide the whole solid to the sample level, one more when a boundary face
    // is not a quad (as `boundary_patches` decides).
    lattice.build_adjacency();
    let levels = LEVELS
        + usize::from(
            lattice
                .boundary_faces()
                .any(|f| lattice.face_vertices(f).len() != 4),
        );
    let cells = lattice.num_cells() as f64 * 8f64.powi(levels as i32);
    crate::limits::check_memory(
        &format!(
            "{}: limit patches of {} cells ({levels} sample levels, {cells:.3e} cells)",
            path.display(),
            lattice.num_cells()
        ),
        vclay::session::limits::limit_patch_bytes(lattice.num_cells(), levels),
    )?;
    let features = Features::none(&lattice);
    let p = boundary_patches(
        &lattice,
        &features,
        SubdivisionRules::new(BoundaryRule::Smooth),
        LEVELS,
    )
    .with_context(|| format!("{}: boundary limit patches", path.display()))?;
    if !crate::quiet() {
        let exact = p.exact.iter().filter(|&&e| e).count();
        eprintln!(
            "vclay convert: {}: {} bicubic patches of the limit surface ({exact} exact, {} fitted); fit error at the level-{} limit points: max {:.3e}, mean {:.3e} of the bounding-box diagonal",
            path.display(),
            p.patches.len(),
            p.patches.len() - exact,
            p.sample_level,
            p.max_error,
            p.mean_error
        );
    }
    Ok(p.patches
        .into_iter()
        .zip(p.exact)
        .zip(p.faces)
        .map(|((s, exact), f)| NamedEntity {
            name: Some(format!(
                "limit patch of boundary {f} ({})",
                if exact { "exact" } else { "fitted" }
            )),
            entity: Entity::Surface(s),
        })
        .collect())
}

/// The boundary of a `.vtu` lattice (as `vclay subdivide` and `vclay run` write them; read by
/// `vclay_lattice::formats::vtu::read`, issue 20) as a triangle mesh: its faces with one cell,
/// oriented outward, fan-triangulated (`vclay_lattice::boundary_mesh`), with vertex normals.
pub fn vtu_boundary(path: &Path) -> Result<TriMesh> {
    let lattice = vclay::lattice::formats::vtu::read(path)?;
    let mut mesh = vclay::lattice::boundary_mesh(&lattice);
    if mesh.triangles.is_empty() {
        bail!("{}: the lattice has no boundary faces", path.display());
    }
    mesh.compute_normals();
    Ok(mesh)
}

/// Tessellates a STEP B-rep with its trimming applied (issue 20): each face's surface on
/// `samples x samples` through `step_read::tessellate_trimmed` (triangles outside the face's
/// loops dropped), the other entities as [`tessellate_entities`] does. The mesh's size is
/// checked against `--max-memory` first.
///
/// When the model has trimmed shells (issue 30), they are meshed instead by
/// `trimmed::tessellate_shell` (each edge sampled once, so a solid gives a closed mesh; spacing
/// `size / min(samples, 64)`: its triangulation is quadratic in the points of a face).
pub fn trimmed_mesh(
    entities: &[NamedEntity],
    faces: &[TrimmedFace],
    shells: &[Shell],
    samples: usize,
) -> Result<TriMesh> {
    if !shells.is_empty() {
        let on_face: std::collections::HashSet<usize> = shells
            .iter()
            .flat_map(|s| s.faces.iter().filter_map(|f| f.entity))
            .collect();
        let rest: Vec<NamedEntity> = entities
            .iter()
            .enumerate()
            .filter(|(i, e)| !on_face.contains(i) && !matches!(e.entity, Entity::Curve(_)))
            .map(|(_, e)| e.clone())
            .collect();
        let mut mesh = if rest.is_empty() {
            TriMesh::new()
        } else {
            tessellate_entities(&rest, samples)?
        };
        for (k, sh) in shells.iter().enumerate() {
            let m = vclay::io::trimmed::tessellate_shell(sh, samples.min(64))
                .map_err(|e| anyhow::anyhow!("shell {k}: {e}"))?;
            mesh.append(&m);
        }
        if mesh.triangles.is_empty() {
            bail!("the trimmed faces have no triangles");
        }
        return Ok(mesh);
    }
    let on_face: std::collections::HashSet<usize> = faces.iter().map(|f| f.entity).collect();
    let vertices = (samples as f64).powi(2) * faces.len() as f64;
    crate::limits::check_memory(
        &format!(
            "--samples {samples} ({} trimmed faces, about {vertices:.3e} vertices)",
            faces.len()
        ),
        vertices * crate::limits::BYTES_PER_MESH_VERTEX,
    )?;
    let rest: Vec<NamedEntity> = entities
        .iter()
        .enumerate()
        .filter(|(i, e)| !on_face.contains(i) && !matches!(e.entity, Entity::Curve(_)))
        .map(|(_, e)| e.clone())
        .collect();
    let mut mesh = if rest.is_empty() {
        TriMesh::new()
    } else {
        tessellate_entities(&rest, samples)?
    };
    for f in faces {
        let Some(Entity::Surface(s)) = entities.get(f.entity).map(|e| &e.entity) else {
            continue;
        };
        let m = tessellate_trimmed(f, s, [samples; 2])
            .map_err(|e| anyhow::anyhow!("face #{}: {e}", f.step_id))?;
        mesh.append(&m);
    }
    if mesh.triangles.is_empty() {
        bail!("no face has triangles inside its trimming loops");
    }
    Ok(mesh)
}

/// Tessellates the surfaces and volume boundaries of a model into one mesh.
///
/// The mesh's size (`samples^2` vertices per surface, `6 samples^2` per volume) is checked
/// against `--max-memory` first.
pub fn tessellate_entities(ents: &[NamedEntity], samples: usize) -> Result<TriMesh> {
    let s2 = (samples as f64).powi(2);
    let vertices: f64 = ents
        .iter()
        .map(|e| match &e.entity {
            Entity::Curve(_) => 0.0,
            Entity::Surface(_) => s2,
            Entity::Volume(_) => 6.0 * s2,
        })
        .sum();
    crate::limits::check_memory(
        &format!("--samples {samples} (a mesh of about {vertices:.3e} vertices)"),
        vertices * crate::limits::BYTES_PER_MESH_VERTEX,
    )?;
    let mut mesh = TriMesh::new();
    for (i, e) in ents.iter().enumerate() {
        let mut m = TriMesh::new();
        match &e.entity {
            Entity::Curve(_) => continue,
            Entity::Surface(s) => tessellate_surface(s, [samples; 2], &mut m),
            Entity::Volume(v) => tessellate_volume_boundary(v, [samples; 3], &mut m),
        }
        .with_context(|| format!("tessellating entity {i}"))?;
        mesh.append(&m);
    }
    if mesh.triangles.is_empty() {
        bail!("the model holds only curves: nothing to tessellate into a mesh");
    }
    Ok(mesh)
}

/// The trimmed shells of what was read (none but for a B-rep of trimmed faces).
fn shells_of(input: &Loaded) -> &[Shell] {
    match input {
        Loaded::Trimmed(_, _, s) => s,
        _ => &[],
    }
}

/// Runs `vclay convert`.
pub fn run(args: &ConvertArgs) -> Result<()> {
    if args.samples < 2 {
        bail!("--samples must be at least 2");
    }
    let input = read_any(&args.input)?;
    let out = &args.output;
    let ext = ext_of(out);
    let mesh_of = |input: &Loaded| -> Result<TriMesh> {
        match input {
            Loaded::Entities(e) => tessellate_entities(e, args.samples),
            Loaded::Trimmed(e, f, s) => trimmed_mesh(e, f, s, args.samples),
            Loaded::Meshes(ms) => {
                let mut all = TriMesh::new();
                for m in ms {
                    all.append(m);
                }
                Ok(all)
            }
        }
    };
    let exact = |input: &Loaded| -> Result<Vec<NamedEntity>> {
        match input {
            Loaded::Entities(e) | Loaded::Trimmed(e, _, _) => Ok(e.clone()),
            Loaded::Meshes(_) => bail!(
                "{} is a mesh; it cannot be converted to exact NURBS geometry ({})",
                args.input.display(),
                out.display()
            ),
        }
    };
    match ext.as_str() {
        "geomdl.json" => write_geomdl(out, &exact(&input)?)?,
        "json" => write_trimmed_model(out, &exact(&input)?, shells_of(&input))?,
        "step" | "stp" | "igs" | "iges" => {
            let entities = exact(&input)?;
            let trimmed = if args.loose || args.join {
                &[][..]
            } else {
                shells_of(&input)
            };
            let iges = matches!(ext.as_str(), "igs" | "iges");
            // The limit patches of a lattice form one surface: joined into one shell.
            let join = !args.loose && (args.join || ext_of(&args.input) == "ovm");
            let (step, igs) = match (args.loose, join) {
                (true, _) => (StepLayout::GeometricSet, IgesLayout::Loose),
                (false, true) => (StepLayout::JoinedBrep, IgesLayout::JoinedBrep),
                (false, false) => (StepLayout::Brep, IgesLayout::Brep),
            };
            if iges {
                write_iges_trimmed(out, &entities, trimmed, igs)?;
            } else {
                write_step_trimmed(out, &entities, trimmed, step)?;
            }
            if !args.loose && !crate::quiet() {
                let on_face: std::collections::HashSet<usize> = trimmed
                    .iter()
                    .flat_map(|s| s.faces.iter().filter_map(|f| f.entity))
                    .collect();
                let rest: Vec<NamedEntity> = entities
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| !on_face.contains(i))
                    .map(|(_, e)| e.clone())
                    .collect();
                let mut b = if join {
                    BrepSummary::joined(&rest)?
                } else {
                    BrepSummary::of(&rest)?
                };
                for s in trimmed {
                    if s.closed {
                        b.solids += 1;
                    } else {
                        b.open_shells += 1;
                    }
                }
                eprintln!(
                    "vclay convert: {} solid(s), {} open shell(s), {} curve(s)",
                    b.solids, b.open_shells, b.curves
                );
            }
        }
        "obj" | "stl" | "ply" => write_mesh(out, &mesh_of(&input)?)?,
        "glb" => {
            let name = args
                .input
                .file_stem()
                .map_or("vclay".into(), |s| s.to_string_lossy().into_owned());
            write_glb(out, &[GlbMesh::new(name, mesh_of(&input)?)])?
        }
        other => bail!(
            "{}: unknown output format {}; expected .json, .geomdl.json, .step, .stp, .igs, .iges, .obj, .stl, .ply or .glb",
            out.display(),
            if other.is_empty() {
                "(no extension)".to_string()
            } else {
                format!("\".{other}\"")
            }
        ),
    }
    if !crate::quiet() {
        eprintln!(
            "vclay convert: {} -> {}",
            args.input.display(),
            out.display()
        );
    }
    if crate::verbose() {
        let bytes = std::fs::metadata(out).map_or(0, |m| m.len());
        eprintln!(
            "vclay convert: {bytes} bytes written; memory limit {} (--max-memory)",
            crate::limits::human(crate::limits::max_memory() as f64)
        );
    }
    Ok(())
}
