//! IGES 5.3 export of NURBS curves (entity 126) and surfaces (entity 128): the older alternative to
//! STEP ([`crate::step`]).
//!
//! **What.** Each curve becomes a Rational B-Spline Curve (type 126) and each surface a Rational
//! B-Spline Surface (type 128), with all knots (not distinct values and multiplicities), weights
//! and control points; `PROP3` says whether the entity is polynomial (all weights 1). Units are
//! millimetres. Two layouts ([`IgesLayout`]): with topology ([`write_iges`]), each closed
//! surface or volume boundary ([`crate::brep`]) is a Manifold Solid B-Rep Object (186) of a
//! closed Shell (514 form 1) of Faces (510), each bounded by one Loop (508) of edges from an Edge
//! List (504; edge geometry as 126 curves) between vertices of a Vertex List (502); the shell's
//! orientation flags make the faces point outward; an open surface is an open Shell (514 form
//! 2). Loose ([`to_iges_string`]): independent 126 and 128 entities, a volume as its six
//! boundary surfaces ([`crate::step::volume_boundary_surfaces`]).
//!
//! **How.** Fixed 80-column records: Start (S), Global (G), Directory Entry (D, two lines per
//! entity), Parameter Data (P, columns 1-64 data and 66-72 the entity's directory pointer) and
//! Terminate (T), each line numbered in columns 74-80 (IGES 5.3 chapter 2). IGES stores surface
//! weights and points with the first (u) index fastest, so vclay's nets (v fastest) are
//! transposed. Reals use the shortest round-trip form (`1.`, `0.25`, `1.5E-7`), so values survive
//! bit for bit.
//!
//! **Limitations.** Untrimmed faces; loops carry no parameter-space curves; poles (collapsed
//! boundary sides) are left out of the loops as in STEP; no colours, levels or names beyond the
//! 8-character entity label.

use crate::error::IoError;
use crate::model::{Entity, NamedEntity};
use crate::step::{step_real as real, volume_boundary_surfaces};
use std::fmt::Write as _;
use std::path::Path;
use vclay_spline::NurbsSurface;

/// A Hollerith string `nHtext` (printable ASCII only).
fn hollerith(s: &str) -> String {
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
    format!("{}H{clean}", clean.len())
}

/// Splits `;`-terminated, `,`-separated tokens into lines of at most `width` characters without
/// breaking a token.
fn wrap(tokens: &[String], width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    let n = tokens.len();
    for (k, t) in tokens.iter().enumerate() {
        let piece = format!("{t}{}", if k + 1 == n { ';' } else { ',' });
        if !cur.is_empty() && cur.len() + piece.len() > width {
            lines.push(std::mem::take(&mut cur));
        }
        cur.push_str(&piece);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// One entity to write: type, form, label and parameter tokens (without the type).
struct Item {
    kind: u32,
    label: String,
    params: Vec<String>,
    /// Form number (directory entry field 15).
    form: u32,
    /// Whether another entity owns this one (status "01": physically dependent).
    dependent: bool,
    /// A curve in a surface's parameter space (entity use flag "05": 2D parametric).
    parametric: bool,
}

impl Item {
    fn new(kind: u32, label: &str, params: Vec<String>) -> Self {
        Item {
            kind,
            label: label.into(),
            params,
            form: 0,
            dependent: false,
            parametric: false,
        }
    }
}

fn curve_item(c: &vclay_spline::NurbsCurve, label: &str) -> Item {
    let n = c.control_points().len();
    let polynomial = c.weights().iter().all(|&w| w == 1.0);
    let d = vclay_spline::ParametricCurve::domain(c);
    let pts = c.control_points();
    // Planar in z = const? Then PROP1 = 1 with normal (0, 0, 1).
    let planar = pts.iter().all(|p| p.z == pts[0].z);
    let mut p = vec![
        (n - 1).to_string(),
        c.degree().to_string(),
        u8::from(planar).to_string(),
        "0".into(),
        u8::from(polynomial).to_string(),
        "0".into(),
    ];
    p.extend(c.knots().as_slice().iter().map(|&k| real(k)));
    p.extend(c.weights().iter().map(|&w| real(w)));
    for q in pts {
        p.extend([real(q.x), real(q.y), real(q.z)]);
    }
    p.extend([real(d.min), real(d.max)]);
    p.extend(if planar {
        ["0.", "0.", "1."].map(String::from)
    } else {
        ["0.", "0.", "0."].map(String::from)
    });
    Item::new(126, label, p)
}

fn surface_item(s: &NurbsSurface, label: &str) -> Item {
    let [nu, nv] = s.dims();
    let [pu, pv] = s.degree();
    let polynomial = s.weights().iter().all(|&w| w == 1.0);
    let dom = vclay_spline::ParametricSurface::domain(s);
    let mut p = vec![
        (nu - 1).to_string(),
        (nv - 1).to_string(),
        pu.to_string(),
        pv.to_string(),
        "0".into(),
        "0".into(),
        u8::from(polynomial).to_string(),
        "0".into(),
        "0".into(),
    ];
    p.extend(s.knots()[0].as_slice().iter().map(|&k| real(k)));
    p.extend(s.knots()[1].as_slice().iter().map(|&k| real(k)));
    // u index fastest.
    for j in 0..nv {
        for i in 0..nu {
            p.push(real(s.weights()[i * nv + j]));
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let q = s.control_point(i, j);
            p.extend([real(q.x), real(q.y), real(q.z)]);
        }
    }
    p.extend([
        real(dom[0].min),
        real(dom[0].max),
        real(dom[1].min),
        real(dom[1].max),
    ]);
    Item::new(128, label, p)
}

/// A numbered 80-column line: 72 columns of data, the section letter, a 7-digit sequence number.
fn line(out: &mut String, data: &str, section: char, seq: usize) {
    let _ = writeln!(out, "{data:<72}{section}{seq:>7}");
}

/// How [`to_iges_string_as`] lays out the geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IgesLayout {
    /// Topology (IGES 5.3 section 4.148-4.151, entities 502-514 and 186): each closed surface
    /// and each volume's boundary as a Manifold Solid B-Rep Object (186) over a closed Shell
    /// (514 form 1) of Faces (510) bounded by Loops (508) of edges from an Edge List (504) with
    /// their vertices in a Vertex List (502), edge geometry as 126 curves; each open surface as
    /// an open Shell (514 form 2); curves as independent 126 entities (see [`crate::brep`]).
    #[default]
    Brep,
    /// Topology as in [`IgesLayout::Brep`], but all surfaces and volume boundary faces of the
    /// model joined into one shell along their coinciding boundaries (a solid when it closes),
    /// as [`crate::step::StepLayout::JoinedBrep`]. Curves stay loose.
    JoinedBrep,
    /// Loose geometry: independent 126 curves and 128 surfaces (a volume's six boundary
    /// surfaces), no topology.
    Loose,
}

/// The entity at 0-based item index `k` has directory entry (DE) pointer `2k + 1`.
fn de(k: usize) -> String {
    (2 * k + 1).to_string()
}

/// Appends the items of one shell: surfaces, vertex list, edge curves, edge list, loops and
/// faces, the shell and, when closed, the solid (the last item is the top entity).
fn shell_items(items: &mut Vec<Item>, shell: &crate::brep::Shell, label: &str) {
    use crate::brep::LoopItem;
    let dep = |mut it: Item, form: u32| {
        it.dependent = true;
        it.form = form;
        it
    };
    // The faces' surfaces first (a reader meets the geometry before the topology).
    let first_surface = items.len();
    for f in &shell.faces {
        items.push(dep(surface_item(&f.surface, label), 0));
    }
    // Vertex list (502 form 1): n, then x y z for each vertex.
    let mut vp = vec![shell.vertices.len().to_string()];
    for v in &shell.vertices {
        vp.extend([real(v.point.x), real(v.point.y), real(v.point.z)]);
    }
    let vlist = items.len();
    items.push(dep(Item::new(502, label, vp), 1));
    // Edge curves, then the edge list (504 form 1): n, then curve, start and end vertices.
    let first_curve = items.len();
    for e in &shell.edges {
        items.push(dep(curve_item(&e.curve, label), 0));
    }
    let mut ep = vec![shell.edges.len().to_string()];
    for (k, e) in shell.edges.iter().enumerate() {
        ep.extend([
            de(first_curve + k),
            de(vlist),
            (e.start + 1).to_string(),
            de(vlist),
            (e.end + 1).to_string(),
        ]);
    }
    let elist = items.len();
    items.push(dep(Item::new(504, label, ep), 1));
    // Faces: surface, loop (508 form 1: n, then per edge type 0, edge list, 1-based index,
    // orientation, no parameter-space curves), face (510 form 1: surface, one outer loop).
    let mut faces = Vec::with_capacity(shell.faces.len());
    for (k, f) in shell.faces.iter().enumerate() {
        let surf = first_surface + k;
        // IGES loops run counter-clockwise about the surface normal whatever the face's
        // orientation in the shell (holes clockwise): undo the reversal of a face with
        // `same_sense == false`. A trimmed face (issue 30) has its holes as more loops.
        let mut loop_ids = Vec::new();
        for l in f.loops() {
            let mut bound = l.clone();
            if !f.same_sense {
                bound.reverse();
            }
            let edges: Vec<(usize, bool, Option<usize>)> = bound
                .iter()
                .filter_map(|item| match *item {
                    LoopItem::Edge {
                        edge,
                        forward,
                        pcurve,
                    } => Some((edge, forward == f.same_sense, pcurve)),
                    LoopItem::Pole { .. } => None,
                })
                .collect();
            // Each use's pcurve (trimmed faces) as a 2D parametric 126 curve, when every pcurve
            // of the face is exact (OpenCASCADE's IGES reader trusts them; a polyline standing
            // for a curve on an angle direction is left for the reader to project).
            let with_pcurves =
                edges.iter().all(|e| e.2.is_some()) && crate::trimmed::pcurves_exact(f);
            let mut pc_ids = Vec::new();
            if with_pcurves {
                for &(_, _, k) in &edges {
                    let mut it = curve_item(&f.pcurves[k.unwrap_or(0)], label);
                    it.dependent = true;
                    it.parametric = true;
                    pc_ids.push(items.len());
                    items.push(it);
                }
            }
            let mut lp = vec![edges.len().to_string()];
            for (n, (edge, forward, _)) in edges.into_iter().enumerate() {
                lp.extend([
                    "0".into(),
                    de(elist),
                    (edge + 1).to_string(),
                    u8::from(forward).to_string(),
                ]);
                match pc_ids.get(n) {
                    Some(&c) => lp.extend(["1".into(), "0".into(), de(c)]),
                    None => lp.push("0".into()),
                }
            }
            loop_ids.push(items.len());
            items.push(dep(Item::new(508, label, lp), 1));
        }
        let fid = items.len();
        let mut fp = vec![de(surf), loop_ids.len().to_string(), "1".into()];
        fp.extend(loop_ids.iter().map(|&l| de(l)));
        items.push(dep(Item::new(510, label, fp), 1));
        faces.push((fid, f.same_sense));
    }
    // Shell (514): n, then face and orientation (1: the face normal is the surface normal).
    let mut sp = vec![faces.len().to_string()];
    for (fid, same) in faces {
        sp.extend([de(fid), u8::from(same).to_string()]);
    }
    let sid = items.len();
    let form = if shell.closed { 1 } else { 2 };
    let mut sh = Item::new(514, label, sp);
    sh.form = form;
    sh.dependent = shell.closed;
    items.push(sh);
    if shell.closed {
        // Manifold solid (186): shell, shell orientation, no void shells.
        items.push(Item::new(186, label, vec![de(sid), "1".into(), "0".into()]));
    }
}

/// Formats entities as an IGES 5.3 file with loose geometry ([`IgesLayout::Loose`]): the same
/// as `to_iges_string_as(entities, file_name, IgesLayout::Loose)`. `file_name` goes into the
/// global section.
pub fn to_iges_string(entities: &[NamedEntity], file_name: &str) -> Result<String, IoError> {
    to_iges_string_as(entities, file_name, IgesLayout::Loose)
}

/// Formats entities as an IGES 5.3 file in the given layout. `file_name` goes into the global
/// section.
pub fn to_iges_string_as(
    entities: &[NamedEntity],
    file_name: &str,
    layout: IgesLayout,
) -> Result<String, IoError> {
    to_iges_string_trimmed(entities, &[], file_name, layout)
}

/// Formats a trimmed model ([`crate::trimmed`]) as an IGES 5.3 file: each shell of `shells` as
/// a 186 solid (closed) or 514 shell of 510 faces with their outer and inner 508 loops, each
/// edge use with its pcurve as a 2D parametric 126 curve, the entities that are no face's
/// surface as `layout` says.
pub fn to_iges_string_trimmed(
    entities: &[NamedEntity],
    shells: &[crate::brep::Shell],
    file_name: &str,
    layout: IgesLayout,
) -> Result<String, IoError> {
    if entities.is_empty() {
        return Err(IoError::EmptyModel);
    }
    let on_face: std::collections::HashSet<usize> = shells
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
    let mut items = Vec::new();
    let mut tolerance: f64 = 1e-7;
    for (k, shell) in shells.iter().enumerate() {
        tolerance = tolerance.max(10.0 * shell.tolerance);
        shell_items(&mut items, shell, &format!("SHELL{k}"));
    }
    let joined = match layout {
        IgesLayout::JoinedBrep => crate::brep::joined_shell(entities)?,
        _ => None,
    };
    if let Some(shell) = &joined {
        tolerance = tolerance.max(10.0 * shell.tolerance);
        shell_items(&mut items, shell, "SHELL");
    }
    for (i, e) in entities.iter().enumerate() {
        let label = e.name.clone().unwrap_or_else(|| format!("E{i}"));
        let shell = match (&e.entity, layout) {
            (Entity::Curve(_), _) | (_, IgesLayout::Loose) => None,
            (_, IgesLayout::JoinedBrep) => continue,
            (Entity::Surface(s), IgesLayout::Brep) => Some(crate::brep::Shell::of_surface(s)),
            (Entity::Volume(v), IgesLayout::Brep) => Some(crate::brep::Shell::of_volume(v)),
        };
        if let Some(shell) = shell {
            let shell = shell.map_err(|err| IoError::Structure {
                path: format!("entities[{i}]"),
                message: format!("IGES B-rep export: {err}"),
            })?;
            tolerance = tolerance.max(10.0 * shell.tolerance);
            shell_items(&mut items, &shell, &label);
            continue;
        }
        match &e.entity {
            Entity::Curve(c) => items.push(curve_item(c, &label)),
            Entity::Surface(s) => items.push(surface_item(s, &label)),
            Entity::Volume(v) => {
                let faces = volume_boundary_surfaces(v).ok_or_else(|| IoError::Structure {
                    path: format!("entities[{i}]"),
                    message: "IGES export of a volume needs clamped knot vectors (its boundary \
                              surfaces are written)"
                        .into(),
                })?;
                for (f, s) in faces.iter().enumerate() {
                    items.push(surface_item(s, &format!("{label}F{f}")));
                }
            }
        }
    }
    let mut out = String::new();
    line(
        &mut out,
        "vclay NURBS export (IGES 5.3, entities 126 and 128)",
        'S',
        1,
    );
    let stamp = crate::step::timestamp()
        .replace(['-', ':'], "")
        .replace('T', ".");
    let global: Vec<String> = vec![
        "1H,".into(),
        "1H;".into(),
        hollerith("vclay"),
        hollerith(file_name),
        hollerith("vclay"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith("vclay"),
        "1.".into(),
        "2".into(),
        hollerith("MM"),
        "1".into(),
        "1.".into(),
        hollerith(&stamp),
        real(tolerance),
        "0.".into(),
        hollerith("vclay"),
        hollerith("vclay"),
        "11".into(),
        "0".into(),
    ];
    // The global section's first two tokens are the delimiters themselves.
    let glines = wrap(&global, 72);
    for (k, g) in glines.iter().enumerate() {
        line(&mut out, g, 'G', k + 1);
    }
    // Parameter data first (to know pointers), then directory entries.
    let mut pdata = String::new();
    let mut dir = String::new();
    let mut pseq = 1;
    for (k, it) in items.iter().enumerate() {
        let de = 2 * k + 1;
        let mut tokens = vec![it.kind.to_string()];
        tokens.extend(it.params.iter().cloned());
        let plines = wrap(&tokens, 64);
        let first = pseq;
        for pl in &plines {
            let _ = writeln!(pdata, "{pl:<64} {de:>7}P{pseq:>7}");
            pseq += 1;
        }
        let label: String = it
            .label
            .chars()
            .filter(|c| c.is_ascii_graphic())
            .take(8)
            .collect();
        line(
            &mut dir,
            &format!(
                "{:>8}{first:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
                it.kind,
                0,
                0,
                0,
                0,
                0,
                0,
                match (it.dependent, it.parametric) {
                    (_, true) => "00010500",
                    (true, false) => "00010000",
                    (false, false) => "00000000",
                }
            ),
            'D',
            de,
        );
        line(
            &mut dir,
            &format!(
                "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{label:>8}{:>8}",
                it.kind,
                0,
                0,
                plines.len(),
                it.form,
                "",
                "",
                0
            ),
            'D',
            de + 1,
        );
    }
    out.push_str(&dir);
    out.push_str(&pdata);
    line(
        &mut out,
        &format!(
            "S{:>7}G{:>7}D{:>7}P{:>7}",
            1,
            glines.len(),
            2 * items.len(),
            pseq - 1
        ),
        'T',
        1,
    );
    Ok(out)
}

/// Writes entities as an IGES file, atomically, with topology ([`IgesLayout::Brep`]): closed
/// surfaces and volumes as solids (186), open surfaces as open shells (514).
pub fn write_iges(path: impl AsRef<Path>, entities: &[NamedEntity]) -> Result<(), IoError> {
    write_iges_as(path, entities, IgesLayout::Brep)
}

/// Writes entities as an IGES file in the given layout, atomically.
pub fn write_iges_as(
    path: impl AsRef<Path>,
    entities: &[NamedEntity],
    layout: IgesLayout,
) -> Result<(), IoError> {
    crate::util::write_named_text(path.as_ref(), |name| {
        to_iges_string_as(entities, name, layout)
    })
}

/// Writes a trimmed model as an IGES 5.3 file, atomically ([`to_iges_string_trimmed`]).
pub fn write_iges_trimmed(
    path: impl AsRef<Path>,
    entities: &[NamedEntity],
    shells: &[crate::brep::Shell],
    layout: IgesLayout,
) -> Result<(), IoError> {
    crate::util::write_named_text(path.as_ref(), |name| {
        to_iges_string_trimmed(entities, shells, name, layout)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use vclay_core::Vec3;
    use vclay_spline::NurbsCurve;

    /// Parameter tokens of every entity by DE pointer, and the (type, form) of each.
    fn parse(text: &str) -> std::collections::BTreeMap<usize, (u32, u32, Vec<String>)> {
        let mut params: std::collections::BTreeMap<usize, String> = Default::default();
        let mut dir: std::collections::BTreeMap<usize, (u32, u32)> = Default::default();
        let lines: Vec<&str> = text.lines().collect();
        for (k, l) in lines.iter().enumerate() {
            assert_eq!(l.len(), 80, "{l:?}");
            match &l[72..73] {
                "P" => params
                    .entry(l[64..72].trim().parse().unwrap())
                    .or_default()
                    .push_str(l[..64].trim_end()),
                "D" if l[73..].trim().parse::<usize>().unwrap() % 2 == 1 => {
                    let de = l[73..].trim().parse().unwrap();
                    let kind = l[..8].trim().parse().unwrap();
                    let form = lines[k + 1][32..40].trim().parse().unwrap();
                    dir.insert(de, (kind, form));
                }
                _ => {}
            }
        }
        dir.into_iter()
            .map(|(de, (kind, form))| {
                let p = params[&de].trim_end_matches(';');
                let toks: Vec<String> = p.split(',').map(String::from).collect();
                assert_eq!(toks[0], kind.to_string());
                (de, (kind, form, toks[1..].to_vec()))
            })
            .collect()
    }

    #[test]
    fn closed_models_are_manifold_solid_breps() {
        let vol = vclay_spline::NurbsVolume::box_lattice(
            [1, 2, 2],
            [2, 3, 4],
            Vec3::zeros(),
            Vec3::new(1.0, 2.0, 3.0),
        )
        .unwrap();
        for (entity, counts) in [
            (
                Entity::Surface(NurbsSurface::torus(2.0, 0.5).unwrap()),
                [1, 2, 1],
            ),
            (
                Entity::Surface(NurbsSurface::sphere(1.0).unwrap()),
                [1, 1, 2],
            ),
            (Entity::Volume(vol), [6, 12, 8]),
        ] {
            let text = to_iges_string_as(&[entity.into()], "b.igs", IgesLayout::Brep).unwrap();
            let ents = parse(&text);
            let of = |k: u32| ents.iter().filter(|(_, e)| e.0 == k).collect::<Vec<_>>();
            let num = |s: &String| s.parse::<usize>().unwrap();
            assert_eq!(of(186).len(), 1);
            let solid = &of(186)[0].1.2;
            let shell = &ents[&num(&solid[0])];
            assert_eq!((shell.0, shell.1), (514, 1), "a closed shell");
            let nfaces = num(&shell.2[0]);
            assert_eq!(nfaces, counts[0]);
            assert_eq!(of(126).len(), counts[1], "one curve per edge");
            let vlist = &of(502)[0].1.2;
            assert_eq!(num(&vlist[0]), counts[2]);
            // Every edge is used twice, once in each direction about the outward normals.
            let mut uses = vec![(0, 0); counts[1]];
            for f in 0..nfaces {
                let face = &ents[&num(&shell.2[1 + 2 * f])];
                let outward_is_surface_normal = shell.2[2 + 2 * f] == "1";
                assert_eq!(face.0, 510);
                let lp = &ents[&num(&face.2[3])];
                assert_eq!(lp.0, 508);
                for e in lp.2[1..].chunks(5) {
                    assert_eq!(e[0], "0");
                    let forward = (e[3] == "1") == outward_is_surface_normal;
                    let u = &mut uses[num(&e[2]) - 1];
                    if forward { u.0 += 1 } else { u.1 += 1 }
                }
            }
            assert!(uses.iter().all(|&u| u == (1, 1)), "{uses:?}");
        }
    }

    #[test]
    fn records_are_80_columns_and_parameters_complete() {
        let torus = NurbsSurface::torus(2.0, 0.5).unwrap();
        let c = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap();
        let text = to_iges_string(
            &[Entity::Surface(torus).into(), Entity::Curve(c).into()],
            "t.igs",
        )
        .unwrap();
        for (k, l) in text.lines().enumerate() {
            assert_eq!(l.len(), 80, "line {k}: {l:?}");
        }
        let d: Vec<&str> = text.lines().filter(|l| &l[72..73] == "D").collect();
        assert_eq!(d.len(), 4);
        assert_eq!(d[0][..8].trim(), "128");
        assert_eq!(d[2][..8].trim(), "126");
        // Join the surface's parameter data and count the tokens:
        // 10 header + 12 + 12 knots + 81 weights + 243 coordinates + 4 parameters.
        let p: String = text
            .lines()
            .filter(|l| &l[72..73] == "P" && l[64..72].trim() == "1")
            .map(|l| l[..64].trim_end().to_string())
            .collect();
        assert!(p.ends_with(';'));
        assert_eq!(
            p.trim_end_matches(';').split(',').count(),
            10 + 24 + 81 + 243 + 4
        );
        assert!(p.starts_with("128,8,8,2,2,0,0,0,0,0,0.,0.,0.,0.25,"), "{p}");
        let t = text.lines().last().unwrap();
        assert!(t.starts_with("S      1G"), "{t}");
    }
}
