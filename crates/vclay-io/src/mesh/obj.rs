//! Wavefront OBJ reading and writing (see the parent module for what is supported).

use super::{Ctx, fmt_f64};
use crate::error::{IoError, quote};
use std::collections::HashMap;
use std::io::Write;
use vclay_core::{TriMesh, Vec3};

pub(super) fn write(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(
        w,
        "# vclay mesh: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", fmt_f64(p.x), fmt_f64(p.y), fmt_f64(p.z))?;
    }
    let normals = !mesh.normals.is_empty();
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", fmt_f64(n.x), fmt_f64(n.y), fmt_f64(n.z))?;
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if normals {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}

/// One face corner: vertex and optional normal, 0-based, with the line it came from.
#[derive(Clone, Copy, Debug)]
struct Corner {
    v: usize,
    vt: Option<usize>,
    vn: Option<usize>,
}

/// Parses the three numbers after `v` or `vn`.
fn coords(ctx: &Ctx, line: usize, what: &str, toks: &[&str]) -> Result<Vec3, IoError> {
    if toks.len() < 3 {
        return Err(ctx.line(
            line,
            format!("{what} needs 3 coordinates, found {}", toks.len()),
        ));
    }
    let mut c = [0.0; 3];
    for (k, t) in toks[..3].iter().enumerate() {
        let x: f64 = t.parse().map_err(|_| {
            ctx.line(
                line,
                format!("{what} coordinate {} is not a number", quote(t)),
            )
        })?;
        if !x.is_finite() {
            return Err(ctx.line(line, format!("{what} has a non-finite coordinate ({t})")));
        }
        c[k] = x;
    }
    Ok(Vec3::new(c[0], c[1], c[2]))
}

/// Resolves a 1-based or negative (relative) OBJ index into a 0-based one. Positive indices are
/// range-checked later (a face may legally precede the vertices it uses in some exporters).
fn resolve(
    ctx: &Ctx,
    line: usize,
    tok: &str,
    what: &str,
    count_so_far: usize,
) -> Result<usize, IoError> {
    let plural = match what {
        "vertex" => "vertices".to_string(),
        w => format!("{w}s"),
    };
    let i: i64 = tok.parse().map_err(|_| {
        ctx.line(
            line,
            format!("face {what} index {} is not an integer", quote(tok)),
        )
    })?;
    if i > 0 {
        usize::try_from(i - 1)
            .map_err(|_| ctx.line(line, format!("face {what} index {i} is too large")))
    } else if i < 0 {
        let back = i.unsigned_abs();
        match usize::try_from(back) {
            Ok(b) if b <= count_so_far => Ok(count_so_far - b),
            _ => Err(ctx.line(
                line,
                format!(
                    "face references {what} {i} (relative) but only {count_so_far} {plural} are defined before it"
                ),
            )),
        }
    } else {
        Err(ctx.line(
            line,
            format!("face references {what} 0; OBJ indices start at 1"),
        ))
    }
}

pub(super) fn read(bytes: &[u8], ctx: &Ctx) -> Result<TriMesh, IoError> {
    let text = String::from_utf8_lossy(bytes);
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut texcoords = 0usize;
    // Faces as (line, corners).
    let mut faces: Vec<(usize, Vec<Corner>)> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let content = raw.split('#').next().unwrap_or("");
        let toks: Vec<&str> = content.split_whitespace().collect();
        let Some((&kw, args)) = toks.split_first() else {
            continue;
        };
        match kw {
            "v" => positions.push(coords(ctx, line, "vertex", args)?),
            "vn" => normals.push(coords(ctx, line, "normal", args)?),
            "vt" => texcoords += 1,
            "f" | "fo" => {
                if args.len() < 3 {
                    return Err(ctx.line(
                        line,
                        format!("face has {} corners; at least 3 are needed", args.len()),
                    ));
                }
                let mut corners = Vec::with_capacity(args.len());
                for a in args {
                    let mut parts = a.split('/');
                    let v = parts.next().unwrap_or("");
                    let vt = parts.next().filter(|s| !s.is_empty());
                    let vn = parts.next().filter(|s| !s.is_empty());
                    if parts.next().is_some() {
                        return Err(ctx.line(
                            line,
                            format!("face corner {} has more than 3 parts (v/vt/vn)", quote(a)),
                        ));
                    }
                    if v.is_empty() {
                        return Err(
                            ctx.line(line, format!("face corner {} has no vertex", quote(a)))
                        );
                    }
                    let v = resolve(ctx, line, v, "vertex", positions.len())?;
                    let vt = vt
                        .map(|s| resolve(ctx, line, s, "texture coordinate", texcoords))
                        .transpose()?;
                    let vn = vn
                        .map(|s| resolve(ctx, line, s, "normal", normals.len()))
                        .transpose()?;
                    corners.push(Corner { v, vt, vn });
                }
                faces.push((line, corners));
            }
            _ => {} // o, g, s, usemtl, mtllib, l, p, vp, ...: not geometry we keep.
        }
    }
    // Range checks against the final counts.
    for (line, corners) in &faces {
        for c in corners {
            if c.v >= positions.len() {
                return Err(ctx.line(
                    *line,
                    format!(
                        "face references vertex {} but only {} vertices are defined",
                        c.v + 1,
                        positions.len()
                    ),
                ));
            }
            if let Some(vt) = c.vt
                && vt >= texcoords
            {
                return Err(ctx.line(
                    *line,
                    format!(
                        "face references texture coordinate {} but only {texcoords} texture coordinates are defined",
                        vt + 1
                    ),
                ));
            }
            if let Some(vn) = c.vn
                && vn >= normals.len()
            {
                return Err(ctx.line(
                    *line,
                    format!(
                        "face references normal {} but only {} normals are defined",
                        vn + 1,
                        normals.len()
                    ),
                ));
            }
        }
    }
    if positions.len() > u32::MAX as usize {
        return Err(ctx.line(1, "more than 2^32 - 1 vertices"));
    }
    let with_normals = !faces.is_empty() && faces.iter().flat_map(|f| &f.1).all(|c| c.vn.is_some());
    let mut mesh = TriMesh {
        positions,
        normals: Vec::new(),
        triangles: Vec::with_capacity(faces.len()),
    };
    if with_normals {
        mesh.normals = vec![Vec3::zeros(); mesh.positions.len()];
    }
    // Normal index assigned to each vertex, and duplicates for vertices used with other normals.
    let mut assigned: Vec<Option<usize>> = vec![None; mesh.positions.len()];
    let mut split: HashMap<(usize, usize), u32> = HashMap::new();
    for (_, corners) in &faces {
        let mut idx = Vec::with_capacity(corners.len());
        for c in corners {
            let i = match (with_normals, c.vn) {
                (true, Some(vn)) => match assigned[c.v] {
                    None => {
                        assigned[c.v] = Some(vn);
                        mesh.normals[c.v] = normals[vn];
                        c.v as u32
                    }
                    Some(a) if a == vn => c.v as u32,
                    Some(_) => *split.entry((c.v, vn)).or_insert_with(|| {
                        mesh.positions.push(mesh.positions[c.v]);
                        mesh.normals.push(normals[vn]);
                        (mesh.positions.len() - 1) as u32
                    }),
                },
                _ => c.v as u32,
            };
            idx.push(i);
        }
        for k in 1..idx.len() - 1 {
            mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
    Ok(mesh)
}
