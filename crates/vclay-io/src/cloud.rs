//! Point clouds for `vclay fit`: plain-text `.xyz` files and the vertices of OBJ, STL and PLY
//! files.
//!
//! **`.xyz` (also `.pts`, `.txt`, `.csv`)**: one point per line, `x y z` separated by spaces,
//! tabs or commas; further columns on a line (normals, colours, intensity) are ignored; blank
//! lines and lines starting with `#` or `//` are skipped. A line with fewer than three numbers,
//! a word that is not a number, or a non-finite coordinate (`nan`, `inf`, `1e400`) is an error
//! naming the file, the line and the column: `scan.xyz:17: column 9: "nan" is not a finite
//! number`.
//!
//! **Meshes** (`.obj`, `.stl`, `.ply`): the vertex positions as read by [`crate::mesh`] (faces are
//! read and dropped; a vertex-only PLY or OBJ is fine).
//!
//! Limitations: no header-driven formats (`.las`, `.e57`, `.pcd`); `.pts` files with a leading
//! count line are read with that line rejected (a single number): remove it.

use crate::error::{IoError, MeshLocation, quote};
use std::path::Path;
use vclay_core::Vec3;

/// Extensions read as `.xyz` text.
pub const XYZ_EXTENSIONS: &[&str] = &["xyz", "pts", "txt", "csv"];

/// Whether `path` names a point-cloud file this module reads (by extension, any case).
pub fn is_point_cloud_path(path: impl AsRef<Path>) -> bool {
    let ext = path
        .as_ref()
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    matches!(ext.as_deref(), Some(e) if XYZ_EXTENSIONS.contains(&e) || ["obj", "stl", "ply"].contains(&e))
}

/// Reads the points of a `.xyz` text file or of a mesh file, by extension.
pub fn read_point_cloud(path: impl AsRef<Path>) -> Result<Vec<Vec3>, IoError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some(e) if XYZ_EXTENSIONS.contains(&e) => {
            let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
            parse_xyz(&bytes, path)
        }
        _ => Ok(crate::mesh::read_mesh(path)?.positions),
    }
}

/// Parses `.xyz` text; `name` is the file name used in errors.
pub fn parse_xyz(bytes: &[u8], name: impl AsRef<Path>) -> Result<Vec<Vec3>, IoError> {
    let name = name.as_ref();
    let err = |line: usize, message: String| IoError::Mesh {
        path: name.to_path_buf(),
        location: MeshLocation::Line(line),
        message,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        err(line, "not UTF-8 text".into())
    })?;
    let mut points = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let ln = k + 1;
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') || trimmed.starts_with("//") {
            continue;
        }
        let mut xyz = [0.0f64; 3];
        let mut found = 0;
        let mut col = 0usize;
        for word in line.split(|c: char| c.is_whitespace() || c == ',') {
            let start = col;
            col += word.len() + 1;
            if word.is_empty() {
                continue;
            }
            if found == 3 {
                break;
            }
            let value: f64 = word.parse().map_err(|_| {
                err(
                    ln,
                    format!("column {}: {} is not a number", start + 1, quote(word)),
                )
            })?;
            if !value.is_finite() {
                return Err(err(
                    ln,
                    format!(
                        "column {}: {} is not a finite number",
                        start + 1,
                        quote(word)
                    ),
                ));
            }
            xyz[found] = value;
            found += 1;
        }
        if found < 3 {
            return Err(err(
                ln,
                format!("expected 3 coordinates x y z, found {found}"),
            ));
        }
        points.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
    }
    if points.is_empty() {
        return Err(IoError::Mesh {
            path: name.to_path_buf(),
            location: MeshLocation::File,
            message: "no points".into(),
        });
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_points_with_comments_commas_and_extra_columns() {
        let text = b"# scan\n\n1 2 3\n4,5,6, 0.1, 0.2\n// note\n  7\t8 9 255 255 255\n";
        let p = parse_xyz(text, "a.xyz").unwrap();
        assert_eq!(p.len(), 3);
        assert_eq!(p[1], Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(p[2], Vec3::new(7.0, 8.0, 9.0));
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_xyz(b"1 2 3\n1 nan 3\n", "s.xyz")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "s.xyz:2: column 3: \"nan\" is not a finite number");
        let e = parse_xyz(b"1 2 3\n\n4 5\n", "s.xyz")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "s.xyz:3: expected 3 coordinates x y z, found 2");
        let e = parse_xyz(b"1 2 x3\n", "s.xyz").unwrap_err().to_string();
        assert!(
            e.contains("s.xyz:1: column 5: \"x3\" is not a number"),
            "{e}"
        );
        let e = parse_xyz(b"# only\n", "s.xyz").unwrap_err().to_string();
        assert_eq!(e, "s.xyz: no points");
        let e = parse_xyz(b"1 2 1e400\n", "s.xyz").unwrap_err().to_string();
        assert!(e.contains("not a finite number"), "{e}");
    }

    #[test]
    fn hostile_bytes_give_ok_or_err_never_a_panic() {
        // Seeded byte mutations of a valid file (issue 17's policy for every reader).
        let seed = b"# scan\n0 0 0\n1.5, -2e3, 3\n4 5 6 7 8\n\n-0.25\t1e-7 9\n";
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let alphabet = b"0123456789.eE+-, \t\n#/naifNI\xff\x00";
        for _ in 0..4000 {
            let mut bytes = seed.to_vec();
            for _ in 0..1 + next() % 4 {
                let at = (next() as usize) % (bytes.len() + 1);
                let c = alphabet[(next() as usize) % alphabet.len()];
                match next() % 3 {
                    0 if at < bytes.len() => bytes[at] = c,
                    1 => bytes.insert(at, c),
                    _ => bytes.truncate(at.max(1)),
                }
            }
            if let Ok(p) = parse_xyz(&bytes, "h.xyz") {
                assert!(!p.is_empty() && p.iter().all(|v| v.iter().all(|c| c.is_finite())));
            }
        }
    }

    #[test]
    fn reads_mesh_vertices() {
        let dir = std::env::temp_dir().join(format!("vclay-cloud-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("c.obj");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0.5\n").unwrap();
        let p = read_point_cloud(&obj).unwrap();
        assert_eq!(p.len(), 3);
        let ply = dir.join("c.ply");
        std::fs::write(
            &ply,
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 2 3\n",
        )
        .unwrap();
        assert_eq!(read_point_cloud(&ply).unwrap()[1], Vec3::new(1.0, 2.0, 3.0));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
