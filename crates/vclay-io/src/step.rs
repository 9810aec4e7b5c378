//! STEP (ISO 10303-21, AP214 "automotive design" schema) export of NURBS curves and surfaces as
//! exact B-spline geometry.
//!
//! **What.** Each curve becomes a `B_SPLINE_CURVE_WITH_KNOTS` and each surface a
//! `B_SPLINE_SURFACE_WITH_KNOTS`; rational ones become the complex entities
//! `(BOUNDED_CURVE() B_SPLINE_CURVE(..) B_SPLINE_CURVE_WITH_KNOTS(..) CURVE()
//! GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_CURVE(..) REPRESENTATION_ITEM(''))` and
//! `(BOUNDED_SURFACE() B_SPLINE_SURFACE(..) B_SPLINE_SURFACE_WITH_KNOTS(..)
//! GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(..) REPRESENTATION_ITEM('')
//! SURFACE())` (ISO 10303-42 section 4.4, the form OpenCASCADE writes). Knots are written as
//! distinct values with multiplicities, control points as `CARTESIAN_POINT`s (surface nets as a
//! list of rows along u), weights as given, attached to one product, in millimetres.
//!
//! Two layouts ([`StepLayout`]):
//!
//! - **B-rep** ([`write_step`], [`StepLayout::Brep`]): each surface and each volume's boundary
//!   becomes a shell of `ADVANCED_FACE`s ([`crate::brep`]: corners merged into `VERTEX_POINT`s,
//!   coinciding boundary curves into shared `EDGE_CURVE`s with their exact B-spline curve,
//!   `FACE_OUTER_BOUND` `EDGE_LOOP`s of `ORIENTED_EDGE`s, faces oriented outward with
//!   `same_sense`). A closed shell (torus, sphere, swung sphere, closed D-NURBS surface, the six
//!   faces of a volume) is a `CLOSED_SHELL` of a `MANIFOLD_SOLID_BREP` in an
//!   `ADVANCED_BREP_SHAPE_REPRESENTATION` (ISO 10303-514 advanced B-rep); an open one an
//!   `OPEN_SHELL` of a `SHELL_BASED_SURFACE_MODEL` in a `MANIFOLD_SURFACE_SHAPE_REPRESENTATION`.
//!   A seam edge appears twice in its face's loop with opposite orientations. A pole (a boundary
//!   side that collapses to a point) has no edge: the loop passes through the pole's vertex, as
//!   OpenCASCADE expects (it adds its degenerated edge on reading). When a model mixes solids,
//!   open shells and curves, each kind has its representation and a `SHAPE_REPRESENTATION` of
//!   the product is related to each by a `SHAPE_REPRESENTATION_RELATIONSHIP`. The uncertainty
//!   of the context is `max(1e-7, 10 x closure tolerance)`.
//! - **Geometric set** ([`to_step_string`], [`StepLayout::GeometricSet`]): all geometry in one
//!   `GEOMETRIC_SET` of a `GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION` (or a
//!   `GEOMETRIC_CURVE_SET` of a `GEOMETRICALLY_BOUNDED_WIREFRAME_SHAPE_REPRESENTATION` when
//!   there are only curves), a volume as its six boundary surfaces; no topology.
//!
//! **How.** Reals are printed in Rust's shortest round-trip form with a mandatory decimal point
//! (`1.`, `0.25`, `1.5E-7`), so a reader recovers every `f64` bit for bit. Checked against
//! OpenCASCADE by `bench/check_step.sh` (points to 1e-9; solids valid by BRepCheck, volume to
//! 1e-6, faces oriented outward).
//!
//! - **Trimmed B-rep** ([`to_step_string_trimmed`], issue 30): the shells of a trimmed model
//!   ([`crate::trimmed`]) as solids (or open shells) of trimmed faces: outer `FACE_OUTER_BOUND`,
//!   holes as `FACE_BOUND`s, shared edges whose geometry is a `SURFACE_CURVE` (a `SEAM_CURVE`
//!   for a seam) with a `PCURVE` per use, 2D B-splines in the surfaces' NURBS parameters.
//!   Checked by `bench/check_trimmed.py` (valid solid, face count, volume and area to 1e-6).
//!
//! **Limitations.** Faces of whole surfaces carry no parameter-space curves (`PCURVE`s; readers
//! project the edge curves, which are exact iso-boundaries). Boundaries that close up only with a different parametrization are not
//! merged (an open shell; see [`crate::brep`]). Names are reduced to printable ASCII.

use crate::brep::{LoopItem, Shell};
use crate::error::IoError;
use crate::model::{Entity, NamedEntity};
use std::fmt::Write as _;
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{KnotVector, NurbsCurve, NurbsSurface, NurbsVolume};

/// A real in STEP syntax: shortest round-trip digits, always with a decimal point.
pub fn step_real(x: f64) -> String {
    let s = format!("{x:?}");
    let (mant, exp) = match s.split_once('e') {
        Some((m, e)) => (m.to_string(), Some(e.to_string())),
        None => (s, None),
    };
    let mant = if mant.contains('.') {
        mant.trim_end_matches('0').to_string()
    } else {
        mant + "."
    };
    match exp {
        Some(e) => format!("{mant}E{e}"),
        None => mant,
    }
}

fn step_string(s: &str) -> String {
    let clean: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_graphic() || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("'{}'", clean.replace('\'', "''").replace('\\', "\\\\"))
}

/// Writer state: entity numbering and the DATA section text.
struct Data {
    next: usize,
    text: String,
}

impl Data {
    fn add(&mut self, body: &str) -> usize {
        let id = self.next;
        self.next += 1;
        let _ = writeln!(self.text, "#{id}={body};");
        id
    }

    fn point(&mut self, p: &Vec3) -> usize {
        self.add(&format!(
            "CARTESIAN_POINT('',({},{},{}))",
            step_real(p.x),
            step_real(p.y),
            step_real(p.z)
        ))
    }
}

fn refs(ids: &[usize]) -> String {
    ids.iter()
        .map(|i| format!("#{i}"))
        .collect::<Vec<_>>()
        .join(",")
}

fn reals(xs: &[f64]) -> String {
    xs.iter()
        .map(|&x| step_real(x))
        .collect::<Vec<_>>()
        .join(",")
}

/// `(multiplicities, distinct knots)` lists.
fn knot_lists(k: &KnotVector) -> (String, String) {
    let d = k.distinct();
    let mults = d
        .iter()
        .map(|(_, m)| m.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let vals: Vec<f64> = d.iter().map(|(v, _)| *v).collect();
    (format!("({mults})"), format!("({})", reals(&vals)))
}

fn write_curve(
    d: &mut Data,
    name: &str,
    degree: usize,
    knots: &KnotVector,
    pts: &[Vec3],
    w: &[f64],
) -> usize {
    let ids: Vec<usize> = pts.iter().map(|p| d.point(p)).collect();
    let (m, k) = knot_lists(knots);
    let cps = refs(&ids);
    if w.iter().all(|&x| x == 1.0) {
        d.add(&format!(
            "B_SPLINE_CURVE_WITH_KNOTS({},{degree},({cps}),.UNSPECIFIED.,.F.,.F.,{m},{k},.UNSPECIFIED.)",
            step_string(name)
        ))
    } else {
        d.add(&format!(
            "( BOUNDED_CURVE() B_SPLINE_CURVE({degree},({cps}),.UNSPECIFIED.,.F.,.F.) \
             B_SPLINE_CURVE_WITH_KNOTS({m},{k},.UNSPECIFIED.) CURVE() GEOMETRIC_REPRESENTATION_ITEM() \
             RATIONAL_B_SPLINE_CURVE(({})) REPRESENTATION_ITEM({}) )",
            reals(w),
            step_string(name)
        ))
    }
}

fn write_surface(d: &mut Data, name: &str, s: &NurbsSurface) -> usize {
    let [nu, nv] = s.dims();
    let [p, q] = s.degree();
    let ids: Vec<usize> = s.control_points().iter().map(|x| d.point(x)).collect();
    let net = ids
        .chunks(nv)
        .map(|row| format!("({})", refs(row)))
        .collect::<Vec<_>>()
        .join(",");
    debug_assert_eq!(ids.len(), nu * nv);
    let (mu, ku) = knot_lists(&s.knots()[0]);
    let (mv, kv) = knot_lists(&s.knots()[1]);
    let w = s.weights();
    if w.iter().all(|&x| x == 1.0) {
        d.add(&format!(
            "B_SPLINE_SURFACE_WITH_KNOTS({},{p},{q},({net}),.UNSPECIFIED.,.F.,.F.,.F.,{mu},{mv},{ku},{kv},.UNSPECIFIED.)",
            step_string(name)
        ))
    } else {
        let wn = w
            .chunks(nv)
            .map(|row| format!("({})", reals(row)))
            .collect::<Vec<_>>()
            .join(",");
        d.add(&format!(
            "( BOUNDED_SURFACE() B_SPLINE_SURFACE({p},{q},({net}),.UNSPECIFIED.,.F.,.F.,.F.) \
             B_SPLINE_SURFACE_WITH_KNOTS({mu},{mv},{ku},{kv},.UNSPECIFIED.) \
             GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(({wn})) \
             REPRESENTATION_ITEM({}) SURFACE() )",
            step_string(name)
        ))
    }
}

/// The six boundary surfaces of a volume with clamped knot vectors (exact), in the order
/// u = min, u = max, v = min, v = max, w = min, w = max; `None` when a knot vector is not
/// clamped.
pub fn volume_boundary_surfaces(v: &NurbsVolume) -> Option<Vec<NurbsSurface>> {
    if !v.knots().iter().all(KnotVector::is_clamped) {
        return None;
    }
    let dims = v.dims();
    let mut out = Vec::with_capacity(6);
    for axis in 0..3 {
        let (a1, a2) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        for side in [0, dims[axis] - 1] {
            let mut pts = Vec::with_capacity(dims[a1] * dims[a2]);
            let mut ws = Vec::with_capacity(dims[a1] * dims[a2]);
            for i in 0..dims[a1] {
                for j in 0..dims[a2] {
                    let mut idx = [0; 3];
                    idx[axis] = side;
                    idx[a1] = i;
                    idx[a2] = j;
                    let flat = (idx[0] * dims[1] + idx[1]) * dims[2] + idx[2];
                    pts.push(v.control_points()[flat]);
                    ws.push(v.weights()[flat]);
                }
            }
            let knots = [v.knots()[a1].clone(), v.knots()[a2].clone()];
            out.push(NurbsSurface::from_flat(knots, pts, ws).ok()?);
        }
    }
    Some(out)
}

/// How [`to_step_string_as`] lays out the geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepLayout {
    /// Topology: each closed surface and each volume's boundary as a `MANIFOLD_SOLID_BREP`
    /// (a `CLOSED_SHELL` of `ADVANCED_FACE`s sharing `EDGE_CURVE`s and `VERTEX_POINT`s) of an
    /// `ADVANCED_BREP_SHAPE_REPRESENTATION`, each open surface as the face of an `OPEN_SHELL`
    /// in a `SHELL_BASED_SURFACE_MODEL` of a `MANIFOLD_SURFACE_SHAPE_REPRESENTATION`; curves in
    /// a `GEOMETRIC_CURVE_SET` (see [`crate::brep`] for the topology and its tolerance).
    #[default]
    Brep,
    /// Topology as in [`StepLayout::Brep`], but all surfaces of the model and the boundary faces
    /// of its volumes joined into one shell along their coinciding boundaries (a solid when it
    /// closes): for a surface made of patches, such as the bicubic patches of a subdivision
    /// solid's limit surface. Curves stay loose.
    JoinedBrep,
    /// Loose geometry: every surface (and each volume's six boundary surfaces) in one
    /// `GEOMETRIC_SET`, no topology (the layout of vclay before B-rep export).
    GeometricSet,
}

/// Formats entities as a STEP AP214 file with loose geometry ([`StepLayout::GeometricSet`]):
/// the same as `to_step_string_as(entities, file_name, StepLayout::GeometricSet)`.
/// `file_name` goes into the header.
pub fn to_step_string(entities: &[NamedEntity], file_name: &str) -> Result<String, IoError> {
    to_step_string_as(entities, file_name, StepLayout::GeometricSet)
}

/// The shells of a surface or volume entity (`None` for a curve).
fn entity_shell(e: &Entity, i: usize) -> Result<Option<Shell>, IoError> {
    let in_entity = |err: IoError| IoError::Structure {
        path: format!("entities[{i}]"),
        message: format!("STEP B-rep export: {err}"),
    };
    match e {
        Entity::Curve(_) => Ok(None),
        Entity::Surface(s) => Shell::of_surface(s).map(Some).map_err(in_entity),
        Entity::Volume(v) => Shell::of_volume(v).map(Some).map_err(in_entity),
    }
}

/// Writes a 2D curve (a pcurve, points `(u, v, 0)`) as a B-spline with 2D points.
fn write_curve_2d(d: &mut Data, c: &NurbsCurve) -> usize {
    let ids: Vec<usize> = c
        .control_points()
        .iter()
        .map(|p| {
            d.add(&format!(
                "CARTESIAN_POINT('',({},{}))",
                step_real(p.x),
                step_real(p.y)
            ))
        })
        .collect();
    let (m, k) = knot_lists(c.knots());
    let cps = refs(&ids);
    let degree = c.degree();
    if c.weights().iter().all(|&x| x == 1.0) {
        d.add(&format!(
            "B_SPLINE_CURVE_WITH_KNOTS('',{degree},({cps}),.UNSPECIFIED.,.F.,.F.,{m},{k},.UNSPECIFIED.)"
        ))
    } else {
        d.add(&format!(
            "( BOUNDED_CURVE() B_SPLINE_CURVE({degree},({cps}),.UNSPECIFIED.,.F.,.F.) \
             B_SPLINE_CURVE_WITH_KNOTS({m},{k},.UNSPECIFIED.) CURVE() GEOMETRIC_REPRESENTATION_ITEM() \
             RATIONAL_B_SPLINE_CURVE(({})) REPRESENTATION_ITEM('') )",
            reals(c.weights())
        ))
    }
}

/// Writes a shell's vertices, edges and faces; returns the `MANIFOLD_SOLID_BREP` (closed) or
/// `SHELL_BASED_SURFACE_MODEL` (open). Trimmed faces ([`crate::trimmed`]) get their holes as
/// `FACE_BOUND`s and, when every use of an edge has a pcurve (`pcurves`), the edge's
/// geometry is a `SURFACE_CURVE` (a `SEAM_CURVE` when both uses are on one face) with a
/// `PCURVE` per use.
fn write_shell(d: &mut Data, name: &str, shell: &Shell, pcurves: bool) -> usize {
    let vids: Vec<usize> = shell
        .vertices
        .iter()
        .map(|v| {
            let p = d.point(&v.point);
            d.add(&format!("VERTEX_POINT('',#{p})"))
        })
        .collect();
    let sids: Vec<usize> = shell
        .faces
        .iter()
        .enumerate()
        .map(|(k, f)| write_surface(d, &format!("{name} face {k}"), &f.surface))
        .collect();
    // The uses of each edge: (face, pcurve) in loop order.
    let mut uses: Vec<Vec<(usize, Option<usize>)>> = vec![Vec::new(); shell.edges.len()];
    for (fi, f) in shell.faces.iter().enumerate() {
        for item in f.loops().flatten() {
            if let LoopItem::Edge { edge, pcurve, .. } = *item {
                uses[edge].push((fi, pcurve));
            }
        }
    }
    let mut ctx2d = None;
    let eids: Vec<usize> = shell
        .edges
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let c = &e.curve;
            let cid = write_curve(
                d,
                &format!("{name} edge {k}"),
                c.degree(),
                c.knots(),
                c.control_points(),
                c.weights(),
            );
            let u = &uses[k];
            let geometry = if pcurves && !u.is_empty() && u.iter().all(|x| x.1.is_some()) {
                let ctx = *ctx2d.get_or_insert_with(|| {
                    d.add(
                        "( GEOMETRIC_REPRESENTATION_CONTEXT(2) PARAMETRIC_REPRESENTATION_CONTEXT() \
                         REPRESENTATION_CONTEXT('2D SPACE','') )",
                    )
                });
                let pcs: Vec<usize> = u
                    .iter()
                    .map(|&(fi, pk)| {
                        let pc = &shell.faces[fi].pcurves[pk.unwrap_or(0)];
                        let c2 = write_curve_2d(d, pc);
                        let dr = d.add(&format!("DEFINITIONAL_REPRESENTATION('',(#{c2}),#{ctx})"));
                        d.add(&format!("PCURVE('',#{},#{dr})", sids[fi]))
                    })
                    .collect();
                let seam = u.len() == 2 && u[0].0 == u[1].0;
                let kind = if seam { "SEAM_CURVE" } else { "SURFACE_CURVE" };
                d.add(&format!("{kind}('',#{cid},({}),.PCURVE_S1.)", refs(&pcs)))
            } else {
                cid
            };
            d.add(&format!(
                "EDGE_CURVE('',#{},#{},#{geometry},.T.)",
                vids[e.start], vids[e.end]
            ))
        })
        .collect();
    let mut faces = Vec::with_capacity(shell.faces.len());
    for (k, f) in shell.faces.iter().enumerate() {
        let sid = sids[k];
        let mut bounds = Vec::new();
        for (li, l) in f.loops().enumerate() {
            let oes: Vec<usize> = l
                .iter()
                .filter_map(|item| match *item {
                    LoopItem::Edge { edge, forward, .. } => Some(d.add(&format!(
                        "ORIENTED_EDGE('',*,*,#{},{})",
                        eids[edge],
                        logical(forward)
                    ))),
                    // A pole is no edge: the loop passes through its vertex, which the
                    // neighbouring edges share (OpenCASCADE adds its degenerated edge on reading).
                    LoopItem::Pole { .. } => None,
                })
                .collect();
            let lp = d.add(&format!("EDGE_LOOP('',({}))", refs(&oes)));
            let kind = if li == 0 {
                "FACE_OUTER_BOUND"
            } else {
                "FACE_BOUND"
            };
            bounds.push(d.add(&format!("{kind}('',#{lp},.T.)")));
        }
        faces.push(d.add(&format!(
            "ADVANCED_FACE({},({}),#{sid},{})",
            step_string(&format!("{name} face {k}")),
            refs(&bounds),
            logical(f.same_sense)
        )));
    }
    if shell.closed {
        let sh = d.add(&format!("CLOSED_SHELL('',({}))", refs(&faces)));
        d.add(&format!("MANIFOLD_SOLID_BREP({},#{sh})", step_string(name)))
    } else {
        let sh = d.add(&format!("OPEN_SHELL('',({}))", refs(&faces)));
        d.add(&format!(
            "SHELL_BASED_SURFACE_MODEL({},(#{sh}))",
            step_string(name)
        ))
    }
}

fn logical(b: bool) -> &'static str {
    if b { ".T." } else { ".F." }
}

/// Formats entities as a STEP AP214 file in the given layout. `file_name` goes into the header.
pub fn to_step_string_as(
    entities: &[NamedEntity],
    file_name: &str,
    layout: StepLayout,
) -> Result<String, IoError> {
    to_step_string_trimmed(entities, &[], file_name, layout)
}

/// Formats a trimmed model ([`crate::trimmed`]) as a STEP AP214 file: each shell of `shells`
/// as a `MANIFOLD_SOLID_BREP` (closed) or `SHELL_BASED_SURFACE_MODEL` (open) of trimmed
/// `ADVANCED_FACE`s with shared edges and vertices and their pcurves; the entities that are
/// no face's surface as `layout` says. `file_name` goes into the header.
pub fn to_step_string_trimmed(
    entities: &[NamedEntity],
    trimmed: &[Shell],
    file_name: &str,
    layout: StepLayout,
) -> Result<String, IoError> {
    if entities.is_empty() {
        return Err(IoError::EmptyModel);
    }
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
    let entities = &rest[..];
    let shells: Vec<Option<Shell>> = match layout {
        StepLayout::Brep => entities
            .iter()
            .enumerate()
            .map(|(i, e)| entity_shell(&e.entity, i))
            .collect::<Result<_, _>>()?,
        StepLayout::GeometricSet | StepLayout::JoinedBrep => vec![None; entities.len()],
    };
    let joined = match layout {
        StepLayout::JoinedBrep => crate::brep::joined_shell(entities)?,
        _ => None,
    };
    // CAD's merge tolerance: 1e-7 mm, or ten times the largest closure tolerance used.
    let uncertainty = shells
        .iter()
        .flatten()
        .chain(&joined)
        .chain(trimmed)
        .map(|s| 10.0 * s.tolerance)
        .fold(1e-7, f64::max);
    let mut d = Data {
        next: 1,
        text: String::new(),
    };
    let ctx = d.add("APPLICATION_CONTEXT('core data for automotive mechanical design processes')");
    d.add(&format!(
        "APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{ctx})"
    ));
    let pctx = d.add(&format!("PRODUCT_CONTEXT('',#{ctx},'mechanical')"));
    let prod = d.add(&format!(
        "PRODUCT('vclay','vclay NURBS export','',(#{pctx}))"
    ));
    let pdf = d.add(&format!("PRODUCT_DEFINITION_FORMATION('','',#{prod})"));
    let pdc = d.add(&format!(
        "PRODUCT_DEFINITION_CONTEXT('part definition',#{ctx},'design')"
    ));
    let pd = d.add(&format!("PRODUCT_DEFINITION('design','',#{pdf},#{pdc})"));
    let pds = d.add(&format!("PRODUCT_DEFINITION_SHAPE('','',#{pd})"));
    let len = d.add("( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )");
    let ang = d.add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )");
    let sol = d.add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )");
    let unc = d.add(&format!(
        "UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{len},'distance_accuracy_value','confusion accuracy')",
        step_real(uncertainty)
    ));
    let rctx = d.add(&format!(
        "( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{unc})) \
         GLOBAL_UNIT_ASSIGNED_CONTEXT((#{len},#{ang},#{sol})) \
         REPRESENTATION_CONTEXT('Context #1','3D Context with UNIT and UNCERTAINTY') )"
    ));
    // Representation items by kind: loose curves, loose surfaces, solids, open shells.
    let (mut curves, mut surfaces, mut solids, mut open) = (vec![], vec![], vec![], vec![]);
    for (k, sh) in trimmed.iter().enumerate() {
        let item = write_shell(&mut d, &format!("shell {k}"), sh, true);
        if sh.closed {
            solids.push(item);
        } else {
            open.push(item);
        }
    }
    if let Some(sh) = &joined {
        let item = write_shell(&mut d, "vclay shell", sh, false);
        if sh.closed {
            solids.push(item);
        } else {
            open.push(item);
        }
    }
    for (i, (e, shell)) in entities.iter().zip(&shells).enumerate() {
        let name = e.name.clone().unwrap_or_else(|| format!("entity {i}"));
        if joined.is_some() && !matches!(e.entity, Entity::Curve(_)) {
            continue;
        }
        match (&e.entity, shell) {
            (_, Some(sh)) => {
                let item = write_shell(&mut d, &name, sh, false);
                if sh.closed {
                    solids.push(item);
                } else {
                    open.push(item);
                }
            }
            (Entity::Curve(c), None) => curves.push(write_curve(
                &mut d,
                &name,
                c.degree(),
                c.knots(),
                c.control_points(),
                c.weights(),
            )),
            (Entity::Surface(s), None) => surfaces.push(write_surface(&mut d, &name, s)),
            (Entity::Volume(v), None) => {
                let faces = volume_boundary_surfaces(v).ok_or_else(|| IoError::Structure {
                    path: format!("entities[{i}]"),
                    message: "STEP export of a volume needs clamped knot vectors (its boundary \
                              surfaces are written)"
                        .into(),
                })?;
                for (f, s) in faces.iter().enumerate() {
                    surfaces.push(write_surface(&mut d, &format!("{name} face {f}"), s));
                }
            }
        }
    }
    let mut reps = Vec::new();
    if !surfaces.is_empty() {
        // Loose curves share the surfaces' GEOMETRIC_SET, as before B-rep export.
        let mut items = curves.clone();
        items.extend(&surfaces);
        items.sort_unstable();
        curves.clear();
        let gset = d.add(&format!("GEOMETRIC_SET('',({}))", refs(&items)));
        reps.push(d.add(&format!(
            "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION('vclay',(#{gset}),#{rctx})"
        )));
    }
    if !curves.is_empty() {
        let gset = d.add(&format!("GEOMETRIC_CURVE_SET('',({}))", refs(&curves)));
        reps.push(d.add(&format!(
            "GEOMETRICALLY_BOUNDED_WIREFRAME_SHAPE_REPRESENTATION('vclay',(#{gset}),#{rctx})"
        )));
    }
    if !solids.is_empty() {
        reps.push(d.add(&format!(
            "ADVANCED_BREP_SHAPE_REPRESENTATION('vclay',({}),#{rctx})",
            refs(&solids)
        )));
    }
    if !open.is_empty() {
        reps.push(d.add(&format!(
            "MANIFOLD_SURFACE_SHAPE_REPRESENTATION('vclay',({}),#{rctx})",
            refs(&open)
        )));
    }
    if let [rep] = reps[..] {
        d.add(&format!("SHAPE_DEFINITION_REPRESENTATION(#{pds},#{rep})"));
    } else {
        // Several kinds of representation: one shape representation of the product, related to
        // each of them (ISO 10303-41 shape_representation_relationship).
        let o = d.point(&Vec3::zeros());
        let z = d.add("DIRECTION('',(0.,0.,1.))");
        let x = d.add("DIRECTION('',(1.,0.,0.))");
        let ax = d.add(&format!("AXIS2_PLACEMENT_3D('',#{o},#{z},#{x})"));
        let main = d.add(&format!("SHAPE_REPRESENTATION('vclay',(#{ax}),#{rctx})"));
        d.add(&format!("SHAPE_DEFINITION_REPRESENTATION(#{pds},#{main})"));
        for rep in reps {
            d.add(&format!(
                "SHAPE_REPRESENTATION_RELATIONSHIP('','',#{main},#{rep})"
            ));
        }
    }
    let mut out = String::new();
    out.push_str("ISO-10303-21;\nHEADER;\n");
    out.push_str("FILE_DESCRIPTION(('vclay NURBS export'),'2;1');\n");
    let _ = writeln!(
        out,
        "FILE_NAME({},{},(''),(''),'vclay','vclay','');",
        step_string(file_name),
        step_string(&timestamp())
    );
    out.push_str("FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n");
    out.push_str(&d.text);
    out.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
    Ok(out)
}

/// Writes entities as a STEP AP214 file, atomically, with topology ([`StepLayout::Brep`]):
/// closed surfaces and volumes as solids, open surfaces as open shells.
pub fn write_step(path: impl AsRef<Path>, entities: &[NamedEntity]) -> Result<(), IoError> {
    write_step_as(path, entities, StepLayout::Brep)
}

/// Writes a trimmed model as a STEP AP214 file, atomically ([`to_step_string_trimmed`]).
pub fn write_step_trimmed(
    path: impl AsRef<Path>,
    entities: &[NamedEntity],
    shells: &[Shell],
    layout: StepLayout,
) -> Result<(), IoError> {
    crate::util::write_named_text(path.as_ref(), |name| {
        to_step_string_trimmed(entities, shells, name, layout)
    })
}

/// Writes entities as a STEP AP214 file in the given layout, atomically.
pub fn write_step_as(
    path: impl AsRef<Path>,
    entities: &[NamedEntity],
    layout: StepLayout,
) -> Result<(), IoError> {
    crate::util::write_named_text(path.as_ref(), |name| {
        to_step_string_as(entities, name, layout)
    })
}

/// The current UTC time as `YYYY-MM-DDThh:mm:ss`.
pub(crate) fn timestamp() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use vclay_spline::{NurbsCurve, ParametricSurface};

    #[test]
    fn reals_have_a_decimal_point_and_round_trip() {
        assert_eq!(step_real(1.0), "1.");
        assert_eq!(step_real(-0.25), "-0.25");
        assert_eq!(step_real(1.5e-7), "1.5E-7");
        assert_eq!(step_real(1e300), "1.E300");
        for x in [0.1, 1.0 / 3.0, std::f64::consts::FRAC_1_SQRT_2, -2.5e-12] {
            let s = step_real(x).replace("E", "e");
            assert_eq!(s.parse::<f64>().unwrap(), x);
        }
    }

    #[test]
    fn rational_surface_and_curve_entities() {
        let torus = NurbsSurface::torus(2.0, 0.5).unwrap();
        let line = NurbsCurve::new(
            1,
            vec![0.0, 0.0, 1.0, 1.0],
            vec![Vec3::zeros(), Vec3::x()],
            None,
        )
        .unwrap();
        let s = to_step_string(
            &[
                Entity::Surface(torus.clone()).into(),
                NamedEntity {
                    name: Some("it's a line".into()),
                    entity: Entity::Curve(line),
                },
            ],
            "t.step",
        )
        .unwrap();
        assert!(s.starts_with("ISO-10303-21;"));
        assert!(s.contains("RATIONAL_B_SPLINE_SURFACE(("));
        // Torus: 9 x 9 net, knots 0,0,0,.25,.25,.5,.5,.75,.75,1,1,1 -> multiplicities 3,2,2,2,3.
        assert!(s.contains("B_SPLINE_SURFACE_WITH_KNOTS((3,2,2,2,3),(3,2,2,2,3),(0.,0.25,0.5,0.75,1.),(0.,0.25,0.5,0.75,1.)"), "{s}");
        assert_eq!(s.matches("CARTESIAN_POINT").count(), 81 + 2);
        assert!(s.contains("B_SPLINE_CURVE_WITH_KNOTS('it''s a line',1,("));
        assert!(s.contains("GEOMETRIC_SET('',("));
        // Every #n referenced is defined.
        let defined: std::collections::HashSet<&str> = s
            .lines()
            .filter_map(|l| l.strip_prefix('#').and_then(|r| r.split('=').next()))
            .collect();
        for tok in s.split(|c: char| !(c.is_ascii_digit() || c == '#')) {
            if let Some(n) = tok.strip_prefix('#')
                && !n.is_empty()
            {
                assert!(defined.contains(n), "#{n} undefined");
            }
        }
        assert_eq!(ParametricSurface::domain(&torus)[0].max, 1.0);
    }

    /// `#id -> body` of every entity of a STEP text.
    fn entities_of(s: &str) -> std::collections::HashMap<usize, String> {
        s.lines()
            .filter_map(|l| {
                let (id, body) = l.strip_prefix('#')?.split_once('=')?;
                Some((id.parse().ok()?, body.trim_end_matches(';').to_string()))
            })
            .collect()
    }

    /// The `#n` references of an entity body, in order.
    fn refs_of(body: &str) -> Vec<usize> {
        body.split('#')
            .skip(1)
            .filter_map(|t| {
                let n: String = t.chars().take_while(char::is_ascii_digit).collect();
                n.parse().ok()
            })
            .collect()
    }

    /// Checks the topology of a B-rep STEP text: every edge of a closed shell used twice with
    /// opposite senses, every loop a closed chain of vertices. Returns the counts of
    /// (solids, open shells, faces, edges, vertices).
    fn check_brep_text(s: &str) -> (usize, usize, usize, usize, usize) {
        let ents = entities_of(s);
        let kind = |id: usize| ents[&id].split('(').next().unwrap().to_string();
        let count = |k: &str| {
            ents.values()
                .filter(|b| b.starts_with(&format!("{k}(")))
                .count()
        };
        let mut uses: std::collections::HashMap<usize, (usize, usize)> = Default::default();
        for body in ents.values().filter(|b| b.starts_with("CLOSED_SHELL(")) {
            for face in refs_of(body) {
                assert_eq!(kind(face), "ADVANCED_FACE");
                let fb = refs_of(&ents[&face])[0];
                assert_eq!(kind(fb), "FACE_OUTER_BOUND");
                let lp = refs_of(&ents[&fb])[0];
                assert_eq!(kind(lp), "EDGE_LOOP");
                // Consecutive oriented edges meet at a vertex; the chain closes.
                let mut chain = Vec::new();
                for oe in refs_of(&ents[&lp]) {
                    let body = &ents[&oe];
                    assert!(body.starts_with("ORIENTED_EDGE('',*,*,#"), "{body}");
                    let edge = refs_of(body)[0];
                    let fwd = body.ends_with(".T.)");
                    let e = refs_of(&ents[&edge]);
                    assert_eq!(kind(edge), "EDGE_CURVE");
                    assert_eq!(kind(e[0]), "VERTEX_POINT");
                    let u = uses.entry(edge).or_default();
                    if fwd {
                        u.0 += 1
                    } else {
                        u.1 += 1
                    }
                    chain.push(if fwd { (e[0], e[1]) } else { (e[1], e[0]) });
                }
                for k in 0..chain.len() {
                    assert_eq!(
                        chain[k].1,
                        chain[(k + 1) % chain.len()].0,
                        "loop #{lp} breaks"
                    );
                }
            }
        }
        assert!(uses.values().all(|&u| u == (1, 1)), "{uses:?}");
        (
            count("MANIFOLD_SOLID_BREP"),
            count("OPEN_SHELL"),
            count("ADVANCED_FACE"),
            count("EDGE_CURVE"),
            count("VERTEX_POINT"),
        )
    }

    #[test]
    fn closed_models_are_solids_with_shared_edges() {
        let torus = NurbsSurface::torus(2.0, 0.5).unwrap();
        let sphere = NurbsSurface::sphere(1.0).unwrap();
        let vol = NurbsVolume::box_lattice(
            [1, 2, 2],
            [2, 3, 4],
            Vec3::zeros(),
            Vec3::new(1.0, 2.0, 3.0),
        )
        .unwrap();
        let brep = |e: Entity| to_step_string_as(&[e.into()], "b.step", StepLayout::Brep).unwrap();
        let t = brep(Entity::Surface(torus));
        // One vertex, two seams each used twice: the torus is one face of a closed shell.
        assert_eq!(check_brep_text(&t), (1, 0, 1, 2, 1));
        assert!(t.contains("ADVANCED_BREP_SHAPE_REPRESENTATION('vclay',(#"));
        assert!(!t.contains("GEOMETRIC_SET"));
        // Two poles (no edge) and one seam.
        assert_eq!(
            check_brep_text(&brep(Entity::Surface(sphere))),
            (1, 0, 1, 1, 2)
        );
        // A box: 6 faces, 12 edges, 8 vertices, three faces reversed (inward surface normals).
        let b = brep(Entity::Volume(vol));
        assert_eq!(check_brep_text(&b), (1, 0, 6, 12, 8));
        let reversed = entities_of(&b)
            .values()
            .filter(|e| e.starts_with("ADVANCED_FACE(") && e.ends_with(",.F.)"))
            .count();
        assert_eq!(reversed, 3);
        // An open sheet goes as an open shell in a surface model; with a curve and a solid,
        // three representations hang off one shape representation.
        let pts = (0..9)
            .map(|k| Vec3::new((k / 3) as f64, (k % 3) as f64, 0.0))
            .collect();
        let sheet = NurbsSurface::clamped_uniform([2, 2], [3, 3], pts).unwrap();
        let line = NurbsCurve::new(
            1,
            vec![0., 0., 1., 1.],
            vec![Vec3::zeros(), Vec3::x()],
            None,
        )
        .unwrap();
        let m = to_step_string_as(
            &[
                Entity::Surface(sheet).into(),
                Entity::Curve(line).into(),
                Entity::Surface(NurbsSurface::torus(3.0, 1.0).unwrap()).into(),
            ],
            "m.step",
            StepLayout::Brep,
        )
        .unwrap();
        assert_eq!(check_brep_text(&m), (1, 1, 2, 6, 5));
        assert!(m.contains("SHELL_BASED_SURFACE_MODEL("));
        assert!(m.contains("MANIFOLD_SURFACE_SHAPE_REPRESENTATION("));
        assert_eq!(m.matches("SHAPE_REPRESENTATION_RELATIONSHIP(").count(), 3);
    }

    #[test]
    fn joined_layout_makes_one_solid_of_patches() {
        let v = NurbsVolume::box_lattice([1, 1, 2], [2, 2, 3], Vec3::zeros(), Vec3::repeat(1.0))
            .unwrap();
        let patches: Vec<NamedEntity> = volume_boundary_surfaces(&v)
            .unwrap()
            .into_iter()
            .map(|s| Entity::Surface(s).into())
            .collect();
        let joined = to_step_string_as(&patches, "j.step", StepLayout::JoinedBrep).unwrap();
        assert_eq!(check_brep_text(&joined), (1, 0, 6, 12, 8));
        let separate = to_step_string_as(&patches, "s.step", StepLayout::Brep).unwrap();
        assert_eq!(check_brep_text(&separate), (0, 6, 6, 24, 24));
    }

    #[test]
    fn volume_boundaries_are_exact_faces() {
        let v = NurbsVolume::box_lattice(
            [1, 2, 2],
            [2, 3, 4],
            Vec3::zeros(),
            Vec3::new(1.0, 2.0, 3.0),
        )
        .unwrap();
        let f = volume_boundary_surfaces(&v).unwrap();
        assert_eq!(f.len(), 6);
        use vclay_spline::ParametricVolume;
        let p = f[1].point(0.3, 0.6).unwrap();
        let q = v.point(1.0, 0.3, 0.6).unwrap();
        assert!((p - q).norm() < 1e-14);
        let p = f[4].point(0.2, 0.7).unwrap();
        let q = v.point(0.2, 0.7, 0.0).unwrap();
        assert!((p - q).norm() < 1e-14);
    }
}
