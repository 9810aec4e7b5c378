//! STL reading (ASCII and binary, detected by content) and writing.

use super::{Ctx, Welder, facet_normal, fmt_f64};
use crate::error::{IoError, MeshLocation, quote};
use std::io::Write;
use vclay_core::{TriMesh, Vec3};

/// Binary STL header; it must not start with `solid`, or naive readers take the file for ASCII.
const HEADER: &[u8] = b"vclay binary STL";

pub(super) fn write_binary(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    let mut header = [b' '; 80];
    header[..HEADER.len()].copy_from_slice(HEADER);
    w.write_all(&header)?;
    let count = u32::try_from(mesh.triangles.len()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "binary STL holds at most 2^32 - 1 triangles",
        )
    })?;
    w.write_all(&count.to_le_bytes())?;
    for t in &mesh.triangles {
        let n = facet_normal(mesh, t);
        let mut rec = [0u8; 50];
        let vals = std::iter::once(n).chain(t.iter().map(|&i| mesh.positions[i as usize]));
        for (k, v) in vals.enumerate() {
            for c in 0..3 {
                let off = 12 * k + 4 * c;
                rec[off..off + 4].copy_from_slice(&(v[c] as f32).to_le_bytes());
            }
        }
        w.write_all(&rec)?;
    }
    Ok(())
}

pub(super) fn write_ascii(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(w, "solid vclay")?;
    for t in &mesh.triangles {
        let n = facet_normal(mesh, t);
        writeln!(
            w,
            "  facet normal {} {} {}",
            fmt_f64(n.x),
            fmt_f64(n.y),
            fmt_f64(n.z)
        )?;
        writeln!(w, "    outer loop")?;
        for &i in t {
            let p = mesh.positions[i as usize];
            writeln!(
                w,
                "      vertex {} {} {}",
                fmt_f64(p.x),
                fmt_f64(p.y),
                fmt_f64(p.z)
            )?;
        }
        writeln!(w, "    endloop")?;
        writeln!(w, "  endfacet")?;
    }
    writeln!(w, "endsolid vclay")?;
    Ok(())
}

/// Whether the bytes look like ASCII STL: `solid` first (after blanks) and no NUL byte (binary
/// STL always has some: the attribute words and the high bytes of the triangle count).
fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    bytes[start..].starts_with(b"solid") && !bytes.contains(&0)
}

pub(super) fn read(bytes: &[u8], ctx: &Ctx) -> Result<TriMesh, IoError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ctx.err(MeshLocation::File, "no vertices (the file is empty)"));
    }
    let declared = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize);
    let size_matches = declared
        .is_some_and(|n| n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()));
    if looks_ascii(bytes) {
        return read_ascii(bytes, ctx);
    }
    if size_matches {
        return read_binary(bytes, ctx);
    }
    match declared {
        Some(n) => Err(ctx.err(
            MeshLocation::File,
            format!(
                "not ASCII STL and not binary STL: the binary header declares {n} triangles, which take {} bytes, but the file has {} bytes",
                (n as u128) * 50 + 84,
                bytes.len()
            ),
        )),
        None => Err(ctx.err(
            MeshLocation::File,
            format!(
                "not ASCII STL (no leading \"solid\") and too short for binary STL ({} bytes, at least 84 needed)",
                bytes.len()
            ),
        )),
    }
}

fn read_binary(bytes: &[u8], ctx: &Ctx) -> Result<TriMesh, IoError> {
    let mut weld = Welder::default();
    for (t, rec) in bytes[84..].chunks_exact(50).enumerate() {
        let f = |k: usize| {
            let o = 12 + 4 * k;
            f64::from(f32::from_le_bytes([
                rec[o],
                rec[o + 1],
                rec[o + 2],
                rec[o + 3],
            ]))
        };
        let c = [0, 1, 2].map(|v| Vec3::new(f(3 * v), f(3 * v + 1), f(3 * v + 2)));
        if let Some(v) = c.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(ctx.element(
                "facet",
                t,
                format!("vertex {v} has a non-finite coordinate"),
            ));
        }
        weld.triangle(c);
    }
    Ok(weld.mesh)
}

/// Where the ASCII parser is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Before `solid` or after `endsolid`.
    Outside,
    /// Inside a solid, between facets.
    Solid,
    /// After `facet normal ...`, before `outer loop`.
    Facet,
    /// Inside `outer loop`.
    Loop,
    /// After `endloop`, before `endfacet`.
    EndLoop,
}

fn read_ascii(bytes: &[u8], ctx: &Ctx) -> Result<TriMesh, IoError> {
    let text = String::from_utf8_lossy(bytes);
    let mut weld = Welder::default();
    let mut state = State::Outside;
    let mut corners: Vec<Vec3> = Vec::with_capacity(3);
    let mut last_line = 0;
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let toks: Vec<&str> = raw.split_whitespace().collect();
        let Some(&kw) = toks.first() else {
            continue;
        };
        last_line = line;
        let unexpected =
            |expected: &str| ctx.line(line, format!("expected {expected}, found {}", quote(kw)));
        state = match (state, kw) {
            (State::Outside, "solid") => State::Solid,
            (State::Outside, _) => return Err(unexpected("\"solid\"")),
            (State::Solid, "facet") => State::Facet,
            (State::Solid, "endsolid") => State::Outside,
            (State::Solid, _) => return Err(unexpected("\"facet\" or \"endsolid\"")),
            (State::Facet, "outer") => {
                corners.clear();
                State::Loop
            }
            (State::Facet, _) => return Err(unexpected("\"outer loop\"")),
            (State::Loop, "vertex") => {
                corners.push(vertex(ctx, line, &toks[1..])?);
                State::Loop
            }
            (State::Loop, "endloop") => {
                if corners.len() < 3 {
                    return Err(ctx.line(
                        line,
                        format!(
                            "facet has {} vertices; at least 3 are needed",
                            corners.len()
                        ),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    weld.triangle([corners[0], corners[k], corners[k + 1]]);
                }
                State::EndLoop
            }
            (State::Loop, _) => return Err(unexpected("\"vertex\" or \"endloop\"")),
            (State::EndLoop, "endfacet") => State::Solid,
            (State::EndLoop, _) => return Err(unexpected("\"endfacet\"")),
        };
    }
    match state {
        // A missing final `endsolid` is common and harmless.
        State::Outside | State::Solid => Ok(weld.mesh),
        _ => Err(ctx.line(
            last_line,
            "file ends inside a facet (missing \"endloop\" or \"endfacet\")",
        )),
    }
}

fn vertex(ctx: &Ctx, line: usize, args: &[&str]) -> Result<Vec3, IoError> {
    if args.len() != 3 {
        return Err(ctx.line(
            line,
            format!("vertex needs 3 coordinates, found {}", args.len()),
        ));
    }
    let mut c = [0.0; 3];
    for (k, t) in args.iter().enumerate() {
        let x: f64 = t.parse().map_err(|_| {
            ctx.line(
                line,
                format!("vertex coordinate {} is not a number", quote(t)),
            )
        })?;
        if !x.is_finite() {
            return Err(ctx.line(line, format!("vertex has a non-finite coordinate ({t})")));
        }
        c[k] = x;
    }
    Ok(Vec3::new(c[0], c[1], c[2]))
}
