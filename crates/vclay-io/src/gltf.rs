//! glTF 2.0 binary (`.glb`) export of triangle meshes with normals, and of vertex animation as
//! morph targets; a reader for the subset it writes.
//!
//! **What.** [`write_glb`] writes one node per [`GlbMesh`]: positions and unit normals as 32-bit
//! floats, 32-bit indices, a clay-coloured PBR material. A mesh with a [`MorphAnimation`] gets
//! one morph target per frame (position and normal displacements from the base mesh) and an
//! animation whose `weights` channel is the one-hot vector `e_k` at `times[k]` with LINEAR
//! interpolation, so playback blends linearly from frame to frame. Blender imports the targets as
//! shape keys (named `frame 0`, `frame 1`, ... through `extras.targetNames`) and the animation as
//! their keyframes.
//!
//! **Axes.** vclay models are z-up; glTF is y-up (glTF 2.0 section 3.4: +y up, +z forward,
//! right-handed). The writer converts coordinates, not a node transform: every position, normal
//! and morph-target displacement `(x, y, z)` is written as `(x, z, -y)` (a rotation by -90
//! degrees about x, [`to_y_up`]), so a torus lying in vclay's xy plane lies flat on Blender's
//! floor and every viewer shows it upright without having to apply node transforms. The reader
//! applies the inverse `(x, y, z) -> (x, -z, y)` ([`from_y_up`]) to every file (all glTF is
//! y-up), so a vclay round trip gives back the coordinates: the permutation and sign change are
//! exact in floating point, only the f32 rounding remains.
//!
//! **How.** The JSON chunk is padded with spaces and the binary chunk with zeros to 4 bytes
//! (glTF 2.0 section 4.4); every accessor starts at a multiple of 4; `POSITION` accessors carry
//! `min`/`max` computed from the stored 32-bit values, as the specification requires.
//!
//! **Limitations.** Coordinates are rounded to `f32` (the glTF vertex format): about 7 significant
//! digits. One morph target per frame grows the file linearly with the frame count; keep
//! animations to tens of frames. [`read_glb`] reads triangle meshes (mode 4, float positions,
//! optional float normals, u8/u16/u32 indices, no sparse accessors) and ignores materials,
//! morph targets, animations and node transforms.

use crate::error::IoError;
use serde_json::{Value, json};
use std::path::Path;
use vclay_core::{TriMesh, Vec3};

const GLB_MAGIC: u32 = 0x4654_6C67; // "glTF"
const CHUNK_JSON: u32 = 0x4E4F_534A; // "JSON"
const CHUNK_BIN: u32 = 0x004E_4942; // "BIN\0"
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Vertex animation: the mesh's vertex positions at several times.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphAnimation {
    /// Strictly increasing times in seconds, one per frame.
    pub times: Vec<f64>,
    /// Vertex positions of each frame (same count and order as the mesh's vertices).
    pub frames: Vec<Vec<Vec3>>,
}

/// One mesh of a glTF file.
#[derive(Clone, Debug, PartialEq)]
pub struct GlbMesh {
    /// Node and mesh name.
    pub name: String,
    /// The triangles (normals are computed when absent).
    pub mesh: TriMesh,
    /// Base colour (linear RGBA in [0, 1]).
    pub color: [f64; 4],
    /// Optional vertex animation as morph targets.
    pub animation: Option<MorphAnimation>,
}

impl GlbMesh {
    /// A static mesh in the default clay colour.
    pub fn new(name: impl Into<String>, mesh: TriMesh) -> Self {
        GlbMesh {
            name: name.into(),
            mesh,
            color: [0.58, 0.2, 0.1, 1.0],
            animation: None,
        }
    }
}

fn err(path: &str, message: impl Into<String>) -> IoError {
    IoError::Structure {
        path: path.into(),
        message: message.into(),
    }
}

/// vclay's z-up coordinates to glTF's y-up ones: `(x, y, z) -> (x, z, -y)`, the rotation by
/// -90 degrees about x (exact: a permutation and a sign change).
pub fn to_y_up(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.z, -v.y)
}

/// glTF's y-up coordinates to vclay's z-up ones, the inverse of [`to_y_up`]:
/// `(x, y, z) -> (x, -z, y)`.
pub fn from_y_up(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.z, v.y)
}

fn y_up(v: &[Vec3]) -> Vec<Vec3> {
    v.iter().copied().map(to_y_up).collect()
}

/// Unit normals of `positions` under the triangles of `mesh` (zero normals become +z).
fn unit_normals(mesh: &TriMesh, positions: &[Vec3]) -> Vec<Vec3> {
    let mut m = TriMesh {
        positions: positions.to_vec(),
        normals: Vec::new(),
        triangles: mesh.triangles.clone(),
    };
    m.compute_normals();
    fix_normals(m.normals)
}

fn fix_normals(ns: Vec<Vec3>) -> Vec<Vec3> {
    ns.into_iter()
        .map(|n| {
            let l = n.norm();
            if l.is_finite() && l > 1e-12 {
                n / l
            } else {
                Vec3::z()
            }
        })
        .collect()
}

/// Builder of the binary chunk and the accessor/bufferView lists.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    /// A VEC3 float accessor; `with_bounds` adds min/max (required for POSITION).
    fn vec3(&mut self, v: &[Vec3], with_bounds: bool, target: Option<u32>) -> usize {
        let f: Vec<[f32; 3]> = v
            .iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect();
        let data: Vec<u8> = f.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&data, target);
        let mut a =
            json!({"bufferView": view, "componentType": FLOAT, "count": v.len(), "type": "VEC3"});
        if with_bounds {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for p in &f {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn scalars(&mut self, v: &[f32], with_bounds: bool) -> usize {
        let data: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&data, None);
        let mut a =
            json!({"bufferView": view, "componentType": FLOAT, "count": v.len(), "type": "SCALAR"});
        if with_bounds {
            a["min"] = json!([v.iter().copied().fold(f32::INFINITY, f32::min)]);
            a["max"] = json!([v.iter().copied().fold(f32::NEG_INFINITY, f32::max)]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let data: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let view = self.view(&data, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * tris.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }
}

/// The meshes as GLB bytes. Every mesh is validated; animations must have one frame per time,
/// strictly increasing finite times and one position per vertex in every frame.
pub fn to_glb(meshes: &[GlbMesh]) -> Result<Vec<u8>, IoError> {
    if meshes.is_empty() {
        return Err(IoError::EmptyModel);
    }
    let mut bin = Bin::default();
    let (mut nodes, mut jmeshes, mut materials, mut animations) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, m) in meshes.iter().enumerate() {
        let place = format!("meshes[{i}] ({})", m.name);
        m.mesh
            .validate()
            .map_err(|e| err(&place, format!("invalid mesh: {e}")))?;
        // glTF stores f32: a larger coordinate would be written as `inf` (issue 17).
        let max = f64::from(f32::MAX);
        if let Some(v) = m
            .mesh
            .positions
            .iter()
            .chain(&m.mesh.normals)
            .position(|p| p.iter().any(|c| c.is_nan() || c.abs() > max))
        {
            return Err(err(
                &place,
                format!(
                    "vertex or normal {v} has a coordinate beyond glTF's 32-bit floats \
                     (about 3.4e38)"
                ),
            ));
        }
        if m.mesh.triangles.is_empty() {
            return Err(err(&place, "mesh has no triangles"));
        }
        if m.color.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(err(&place, format!("colour {:?} outside [0, 1]", m.color)));
        }
        let base = &m.mesh.positions;
        let normals = if m.mesh.normals.len() == base.len() {
            fix_normals(m.mesh.normals.clone())
        } else {
            unit_normals(&m.mesh, base)
        };
        let pos = bin.vec3(&y_up(base), true, Some(ARRAY_BUFFER));
        let nor = bin.vec3(&y_up(&normals), false, Some(ARRAY_BUFFER));
        let idx = bin.indices(&m.mesh.triangles);
        let mut prim = json!({"attributes": {"POSITION": pos, "NORMAL": nor}, "indices": idx, "material": i, "mode": 4});
        let mut jm = json!({"name": m.name, "primitives": []});
        if let Some(a) = &m.animation {
            check_animation(a, base.len(), &place)?;
            let mut targets = Vec::new();
            for f in &a.frames {
                let dp: Vec<Vec3> = f.iter().zip(base).map(|(p, b)| p - b).collect();
                let dn: Vec<Vec3> = unit_normals(&m.mesh, f)
                    .iter()
                    .zip(&normals)
                    .map(|(n, b)| n - b)
                    .collect();
                let tp = bin.vec3(&y_up(&dp), true, Some(ARRAY_BUFFER));
                let tn = bin.vec3(&y_up(&dn), false, Some(ARRAY_BUFFER));
                targets.push(json!({"POSITION": tp, "NORMAL": tn}));
            }
            let n = a.frames.len();
            prim["targets"] = Value::Array(targets);
            jm["weights"] = json!(vec![0.0; n]);
            jm["extras"] =
                json!({"targetNames": (0..n).map(|k| format!("frame {k}")).collect::<Vec<_>>()});
            let times: Vec<f32> = a.times.iter().map(|&t| t as f32).collect();
            let input = bin.scalars(&times, true);
            let mut w = vec![0f32; n * n];
            for k in 0..n {
                w[k * n + k] = 1.0;
            }
            let output = bin.scalars(&w, false);
            animations.push(json!({
                "name": format!("{} motion", m.name),
                "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}],
                "channels": [{"sampler": 0, "target": {"node": i, "path": "weights"}}]
            }));
        }
        jm["primitives"] = json!([prim]);
        jmeshes.push(jm);
        nodes.push(json!({"name": m.name, "mesh": i}));
        materials.push(json!({
            "name": format!("{} material", m.name),
            "pbrMetallicRoughness": {"baseColorFactor": m.color, "metallicFactor": 0.0, "roughnessFactor": 0.6},
            "doubleSided": true
        }));
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("vclay ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": (0..meshes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": jmeshes,
        "materials": materials,
        "accessors": bin.accessors,
        "bufferViews": bin.views,
        "buffers": [{"byteLength": bin.bytes.len()}],
    });
    if !animations.is_empty() {
        doc["animations"] = Value::Array(animations);
    }
    let mut text = serde_json::to_vec(&doc).map_err(|e| err("glb", e.to_string()))?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.bytes.len();
    let total32 = u32::try_from(total).map_err(|_| err("glb", "file larger than 4 GiB"))?;
    let mut out = Vec::with_capacity(total);
    for w in [GLB_MAGIC, 2, total32, text.len() as u32, CHUNK_JSON] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
    out.extend_from_slice(&bin.bytes);
    Ok(out)
}

fn check_animation(a: &MorphAnimation, nv: usize, place: &str) -> Result<(), IoError> {
    if a.frames.is_empty() || a.frames.len() != a.times.len() {
        return Err(err(
            place,
            format!(
                "animation has {} frames and {} times (need the same, at least 1)",
                a.frames.len(),
                a.times.len()
            ),
        ));
    }
    for (k, t) in a.times.iter().enumerate() {
        if !t.is_finite() || (k > 0 && *t as f32 <= a.times[k - 1] as f32) {
            return Err(err(
                place,
                format!("animation time {k} ({t}) is not finite or not increasing"),
            ));
        }
    }
    for (k, f) in a.frames.iter().enumerate() {
        if f.len() != nv {
            return Err(err(
                place,
                format!(
                    "animation frame {k} has {} positions for {nv} vertices",
                    f.len()
                ),
            ));
        }
        if let Some(v) = f.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(err(
                place,
                format!("animation frame {k}, vertex {v}: non-finite position"),
            ));
        }
    }
    Ok(())
}

/// Writes meshes as a `.glb` file, atomically.
pub fn write_glb(path: impl AsRef<Path>, meshes: &[GlbMesh]) -> Result<(), IoError> {
    let path = path.as_ref();
    let bytes = to_glb(meshes).map_err(|e| e.in_file(path))?;
    crate::util::write_atomic(path, |w| w.write_all(&bytes))
}

/// Reads the triangle meshes of a `.glb` file (one [`TriMesh`] per primitive, in mesh order).
pub fn read_glb(path: impl AsRef<Path>) -> Result<Vec<TriMesh>, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
    decode_glb(&bytes).map_err(|e| e.in_file(path))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// Decodes GLB bytes into triangle meshes (see [`read_glb`] for the subset read).
pub fn decode_glb(b: &[u8]) -> Result<Vec<TriMesh>, IoError> {
    let hdr = |m: &str| err("glb header", m);
    if u32_at(b, 0) != Some(GLB_MAGIC) {
        return Err(hdr("not a binary glTF file (magic \"glTF\" missing)"));
    }
    if u32_at(b, 4) != Some(2) {
        return Err(hdr("only glTF version 2 is supported"));
    }
    let jlen = u32_at(b, 12).ok_or_else(|| hdr("truncated"))? as usize;
    if u32_at(b, 16) != Some(CHUNK_JSON) {
        return Err(hdr("first chunk is not JSON"));
    }
    let jtext = b
        .get(20..20 + jlen)
        .ok_or_else(|| hdr("JSON chunk truncated"))?;
    // The strict reader of the model files: a key written twice in one object is an error
    // (issue 17), like any other invalid JSON.
    let jtext =
        std::str::from_utf8(jtext).map_err(|e| err("glb JSON chunk", format!("not UTF-8: {e}")))?;
    let doc: Value = crate::json::parse(jtext)
        .map_err(|e| err("glb JSON chunk", format!("invalid JSON: {e}")))?;
    let bin: &[u8] = match u32_at(b, 20 + jlen) {
        Some(blen) => {
            if u32_at(b, 24 + jlen) != Some(CHUNK_BIN) {
                return Err(hdr("second chunk is not BIN"));
            }
            b.get(28 + jlen..28 + jlen + blen as usize)
                .ok_or_else(|| hdr("BIN chunk truncated"))?
        }
        None => &[],
    };
    let accessor = |idx: &Value, place: &str| -> Result<(Vec<f64>, usize), IoError> {
        let i = idx
            .as_u64()
            .ok_or_else(|| err(place, "accessor index is not an integer"))?
            as usize;
        let ap = format!("accessors[{i}]");
        let a = doc["accessors"]
            .get(i)
            .ok_or_else(|| err(place, format!("accessor {i} does not exist")))?;
        if a.get("sparse").is_some() {
            return Err(err(&ap, "sparse accessors are not supported"));
        }
        let count = a["count"]
            .as_u64()
            .ok_or_else(|| err(&ap, "missing count"))? as usize;
        let ncomp = match a["type"].as_str() {
            Some("SCALAR") => 1,
            Some("VEC3") => 3,
            other => return Err(err(&ap, format!("unsupported type {other:?}"))),
        };
        let ct = a["componentType"].as_u64().unwrap_or(0) as u32;
        let size = match ct {
            5121 => 1,
            5123 => 2,
            5125 | 5126 => 4,
            _ => return Err(err(&ap, format!("unsupported componentType {ct}"))),
        };
        let vi = a["bufferView"]
            .as_u64()
            .ok_or_else(|| err(&ap, "missing bufferView"))? as usize;
        let vp = format!("bufferViews[{vi}]");
        let v = doc["bufferViews"]
            .get(vi)
            .ok_or_else(|| err(&ap, format!("bufferView {vi} does not exist")))?;
        if v["buffer"].as_u64() != Some(0) {
            return Err(err(&vp, "only the GLB binary buffer 0 is supported"));
        }
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let stride = v["byteStride"]
            .as_u64()
            .map_or(ncomp * size, |s| s as usize);
        // Issue 17: `count` comes from the file; check it against the buffer before allocating
        // (a count of 4e9 over a few bytes was taken at face value).
        if stride < ncomp * size {
            return Err(err(
                &vp,
                format!(
                    "byteStride {stride} is smaller than one element ({} bytes)",
                    ncomp * size
                ),
            ));
        }
        let end = count
            .checked_sub(1)
            .map(|last| {
                last.checked_mul(stride)
                    .and_then(|x| x.checked_add(start))
                    .and_then(|x| x.checked_add(ncomp * size))
            })
            .unwrap_or(Some(start));
        if end.is_none_or(|end| end > bin.len()) {
            return Err(err(
                &ap,
                format!(
                    "count {count} does not fit in the binary buffer of {} bytes",
                    bin.len()
                ),
            ));
        }
        let mut out = Vec::with_capacity(count * ncomp);
        for e in 0..count {
            for c in 0..ncomp {
                let at = start + e * stride + c * size;
                let s = bin
                    .get(at..at + size)
                    .ok_or_else(|| err(&ap, format!("element {e} lies outside the buffer")))?;
                let x = match ct {
                    5121 => s[0] as f64,
                    5123 => u16::from_le_bytes([s[0], s[1]]) as f64,
                    5125 => u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as f64,
                    _ => f32::from_le_bytes([s[0], s[1], s[2], s[3]]) as f64,
                };
                out.push(x);
            }
        }
        Ok((out, ncomp))
    };
    // glTF is y-up: back to vclay's z-up.
    let vecs = |v: Vec<f64>| -> Vec<Vec3> {
        v.chunks_exact(3)
            .map(|c| from_y_up(Vec3::new(c[0], c[1], c[2])))
            .collect()
    };
    let mut out = Vec::new();
    let meshes = doc["meshes"].as_array().cloned().unwrap_or_default();
    for (mi, m) in meshes.iter().enumerate() {
        let prims = m["primitives"].as_array().cloned().unwrap_or_default();
        for (pi, p) in prims.iter().enumerate() {
            let place = format!("meshes[{mi}].primitives[{pi}]");
            if p["mode"].as_u64().unwrap_or(4) != 4 {
                return Err(err(&place, "only triangle primitives (mode 4) are read"));
            }
            let (pos, _) = accessor(&p["attributes"]["POSITION"], &place)?;
            let mut mesh = TriMesh {
                positions: vecs(pos),
                ..TriMesh::default()
            };
            if let Some(n) = p["attributes"].get("NORMAL") {
                mesh.normals = vecs(accessor(n, &place)?.0);
            }
            let nv = mesh.positions.len();
            let idx: Vec<u32> = match p.get("indices") {
                Some(i) => accessor(i, &place)?.0.iter().map(|&x| x as u32).collect(),
                None => (0..nv as u32).collect(),
            };
            if !idx.len().is_multiple_of(3) {
                return Err(err(
                    &place,
                    format!("{} indices, not a multiple of 3", idx.len()),
                ));
            }
            mesh.triangles = idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            mesh.validate()
                .map_err(|e| err(&place, format!("invalid mesh: {e}")))?;
            out.push(mesh);
        }
    }
    if out.is_empty() {
        return Err(err("meshes", "the file holds no triangle mesh"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vclay_core::MeshSink;

    fn tetra() -> TriMesh {
        let mut m = TriMesh::new();
        for p in [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ] {
            m.add_vertex(p, None);
        }
        for t in [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]] {
            m.add_triangle(t);
        }
        m
    }

    #[test]
    fn glb_round_trip_positions_normals_indices() {
        let mut m = tetra();
        m.compute_normals();
        let bytes = to_glb(&[GlbMesh::new("tet", m.clone())]).unwrap();
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(u32_at(&bytes, 8).unwrap() as usize, bytes.len());
        let back = decode_glb(&bytes).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!(back[0].triangles, m.triangles);
        for (a, b) in back[0].positions.iter().zip(&m.positions) {
            assert!((a - b).norm() < 1e-7);
        }
        for (a, b) in back[0].normals.iter().zip(&m.normals) {
            assert!((a - b).norm() < 1e-6);
        }
    }

    /// The file is y-up: vclay's z axis is glTF's y axis (POSITION max of a tetrahedron with
    /// its apex at z = 1 is y = 1), its y axis is glTF's -z; reading undoes it exactly.
    #[test]
    fn z_up_is_written_y_up_and_read_back() {
        let m = tetra();
        let bytes = to_glb(&[GlbMesh::new("tet", m.clone())]).unwrap();
        let jlen = u32_at(&bytes, 12).unwrap() as usize;
        let doc: Value = serde_json::from_slice(&bytes[20..20 + jlen]).unwrap();
        let pos = &doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize];
        assert_eq!(pos["max"], json!([1.0, 1.0, 0.0]));
        assert_eq!(pos["min"], json!([0.0, 0.0, -1.0]));
        let back = decode_glb(&bytes).unwrap();
        assert_eq!(back[0].positions, m.positions);
        for v in [Vec3::new(1.5, -2.25, 3.0), Vec3::new(-0.1, 0.2, -0.3)] {
            assert_eq!(from_y_up(to_y_up(v)), v);
            assert_eq!(to_y_up(Vec3::z()), Vec3::y());
        }
    }

    #[test]
    fn morph_animation_has_one_target_per_frame_and_one_hot_weights() {
        let m = tetra();
        let frames: Vec<Vec<Vec3>> = (0..3)
            .map(|k| {
                m.positions
                    .iter()
                    .map(|p| p * (1.0 + 0.5 * k as f64))
                    .collect()
            })
            .collect();
        let g = GlbMesh {
            animation: Some(MorphAnimation {
                times: vec![0.0, 0.5, 1.0],
                frames,
            }),
            ..GlbMesh::new("grow", m)
        };
        let bytes = to_glb(std::slice::from_ref(&g)).unwrap();
        let jlen = u32_at(&bytes, 12).unwrap() as usize;
        let doc: Value = serde_json::from_slice(&bytes[20..20 + jlen]).unwrap();
        assert_eq!(
            doc["meshes"][0]["primitives"][0]["targets"]
                .as_array()
                .unwrap()
                .len(),
            3
        );
        assert_eq!(
            doc["animations"][0]["channels"][0]["target"]["path"],
            "weights"
        );
        // Target 2 moves vertex 1 from (1,0,0) to (2,0,0): max x displacement is 1.
        let t2 = doc["meshes"][0]["primitives"][0]["targets"][2]["POSITION"]
            .as_u64()
            .unwrap();
        assert_eq!(doc["accessors"][t2 as usize]["max"][0], 1.0);
        // Bad animation: frame count differs from time count.
        let mut bad = g;
        bad.animation.as_mut().unwrap().times.pop();
        let e = to_glb(&[bad]).unwrap_err().to_string();
        assert!(
            e.contains("meshes[0] (grow)") && e.contains("3 frames and 2 times"),
            "{e}"
        );
    }

    #[test]
    fn a_key_written_twice_in_the_json_chunk_is_an_error() {
        let bytes = to_glb(&[GlbMesh::new("t", tetra())]).unwrap();
        let jlen = u32_at(&bytes, 12).unwrap() as usize;
        let json = std::str::from_utf8(&bytes[20..20 + jlen])
            .unwrap()
            .trim_end();
        assert!(json.starts_with('{'));
        // The same document with `"scene": 0` written twice at the top, re-packed (the JSON
        // chunk padded with spaces to 4 bytes, the BIN chunk as it was).
        let twice = format!("{{\"scene\":0,\"scene\":0,{}", &json[1..]);
        let mut j = twice.into_bytes();
        while j.len() % 4 != 0 {
            j.push(b' ');
        }
        let bin = &bytes[20 + jlen..];
        let total = 12 + 8 + j.len() + bin.len();
        let mut glb = Vec::with_capacity(total);
        glb.extend_from_slice(&bytes[..8]);
        glb.extend_from_slice(&(total as u32).to_le_bytes());
        glb.extend_from_slice(&(j.len() as u32).to_le_bytes());
        glb.extend_from_slice(&bytes[16..20]);
        glb.extend_from_slice(&j);
        glb.extend_from_slice(bin);
        let e = decode_glb(&glb).unwrap_err().to_string();
        assert!(e.contains("duplicate key") && e.contains("scene"), "{e}");
        // The original reads.
        assert!(decode_glb(&bytes).is_ok());
    }

    #[test]
    fn corrupt_glb_is_an_error() {
        let bytes = to_glb(&[GlbMesh::new("t", tetra())]).unwrap();
        assert!(decode_glb(&bytes[..40]).is_err());
        assert!(decode_glb(b"not a glb file at all").is_err());
    }
}
