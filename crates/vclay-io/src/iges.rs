//! IGES 5.3 export of NURBS curves (entity 126) and surfaces (entity 128): the older alternative to
//! STEP ([`crate::step`]).
//!
//! **What.** Each curve becomes a Rational B-Spline Curve (type 126) and each surface a Rational
//! B-Spline Surface (type 128), with all knots (not distinct values and multiplicities), weights
//! and control points; `PROP3` says whether the entity is polynomial (all weights 1). Volumes are
//! written as their six boundary surfaces ([`crate::step::volume_boundary_surfaces`]). Units are
//! millimetres.
//!
//! **How.** Fixed 80-column records: Start (S), Global (G), Directory Entry (D, two lines per
//! entity), Parameter Data (P, columns 1-64 data and 66-72 the entity's directory pointer) and
//! Terminate (T), each line numbered in columns 74-80 (IGES 5.3 chapter 2). IGES stores surface
//! weights and points with the first (u) index fastest, so vclay's nets (v fastest) are
//! transposed. Reals use the shortest round-trip form (`1.`, `0.25`, `1.5E-7`), so values survive
//! bit for bit.
//!
//! **Limitations.** Export only; untrimmed geometry; no colours, levels or names beyond the
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
    Item {
        kind: 126,
        label: label.into(),
        params: p,
    }
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
    Item {
        kind: 128,
        label: label.into(),
        params: p,
    }
}

/// A numbered 80-column line: 72 columns of data, the section letter, a 7-digit sequence number.
fn line(out: &mut String, data: &str, section: char, seq: usize) {
    let _ = writeln!(out, "{data:<72}{section}{seq:>7}");
}

/// Formats entities as an IGES 5.3 file. `file_name` goes into the global section.
pub fn to_iges_string(entities: &[NamedEntity], file_name: &str) -> Result<String, IoError> {
    if entities.is_empty() {
        return Err(IoError::EmptyModel);
    }
    let mut items = Vec::new();
    for (i, e) in entities.iter().enumerate() {
        let label = e.name.clone().unwrap_or_else(|| format!("E{i}"));
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
        "1.E-7".into(),
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
                it.kind, 0, 0, 0, 0, 0, 0, "00000000"
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
                0,
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

/// Writes entities as an IGES file, atomically.
pub fn write_iges(path: impl AsRef<Path>, entities: &[NamedEntity]) -> Result<(), IoError> {
    crate::util::write_named_text(path.as_ref(), |name| to_iges_string(entities, name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use vclay_core::Vec3;
    use vclay_spline::NurbsCurve;

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
