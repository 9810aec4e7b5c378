//! The NURBS-Python (geomdl) JSON exchange format, read and write.
//!
//! **What.** geomdl's `exchange.export_json` writes
//!
//! ```text
//! {"shape": {"type": "curve" | "surface" | "volume", "count": n, "data": [ ... ]}}
//! ```
//!
//! where each datum is `{"type": "spline", "rational": bool, "dimension": 2|3, "degree": p,
//! "knotvector": U, "control_points": {"points": [[x, y, z], ...], "weights": [w, ...]}}` for a
//! curve, with `degree_u`, `degree_v`, `knotvector_u`, `knotvector_v`, `size_u`, `size_v` for a
//! surface and additionally `degree_w`, `knotvector_w`, `size_w` for a volume. Points are
//! Cartesian (not weighted). One file holds entities of one parametric dimension.
//!
//! **How.** Control point order: geomdl surfaces run `v` fastest (`index = j + size_v * i`),
//! which is vclay's order; geomdl volumes run `v` fastest, then `u`, then `w`
//! (`index = j + size_v * (i + size_u * k)`), while vclay runs `w` fastest, so volume nets are
//! reordered both ways. 2D points (`dimension` 2) get `z = 0`. Optional fields `name`, `delta`,
//! `id`, `reversed` are accepted; `name` is kept.
//!
//! **Limitations.** Trim curves (`trims`) and freeform (`"type": "freeform"`) shapes are
//! rejected with an error rather than silently dropped. The Jinja2 template feature of geomdl is
//! not supported.

use crate::error::{IoError, quote};
use crate::json::{self, JsonPath};
use crate::model::{Entity, NamedEntity};
use serde_json::{Map, Value, json};
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{KnotVector, NurbsCurve, NurbsSurface, NurbsVolume, SplineError};

const SHAPE_TYPES: [&str; 3] = ["curve", "surface", "volume"];
const AXES: [&str; 3] = ["u", "v", "w"];

/// Whether parsed JSON looks like a geomdl document (a top-level `"shape"` object).
pub fn is_geomdl(text: &str) -> bool {
    serde_json::from_str::<Value>(text)
        .ok()
        .is_some_and(|v| v.get("shape").is_some_and(Value::is_object))
}

/// Parses a geomdl JSON document.
pub fn parse_geomdl(text: &str) -> Result<Vec<NamedEntity>, IoError> {
    let root = json::parse(text)?;
    let top = JsonPath::default();
    let shape_path = top.key("shape");
    let shape = root
        .get("shape")
        .ok_or_else(|| top.error("missing field \"shape\" (not a geomdl JSON document)"))?;
    let tpath = shape_path.key("type");
    let kind = match shape.get("type") {
        Some(Value::String(s)) => SHAPE_TYPES.iter().position(|t| t == s).ok_or_else(|| {
            tpath.error(format!(
                "unknown shape type {}, expected \"curve\", \"surface\" or \"volume\"",
                quote(s)
            ))
        })?,
        Some(other) => return Err(tpath.expected("a string", other)),
        None => return Err(shape_path.error("missing field \"type\"")),
    };
    let dpath = shape_path.key("data");
    let data = json::array(
        shape
            .get("data")
            .ok_or_else(|| shape_path.error("missing field \"data\""))?,
        &dpath,
        "an array of shapes",
    )?;
    if data.is_empty() {
        return Err(IoError::EmptyModel);
    }
    if let Some(c) = shape.get("count") {
        let n = json::integer(c, &shape_path.key("count"))?;
        if n != data.len() {
            return Err(shape_path
                .key("count")
                .error(format!("count is {n} but data holds {} shapes", data.len())));
        }
    }
    data.iter()
        .enumerate()
        .map(|(i, d)| parse_shape(d, kind, i, &dpath.index(i)))
        .collect()
}

/// Reads a geomdl JSON file. Errors name the file.
pub fn read_geomdl(path: impl AsRef<Path>) -> Result<Vec<NamedEntity>, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::file(path, e))?;
    parse_geomdl(&text).map_err(|e| e.in_file(path))
}

fn field<'a>(obj: &'a Map<String, Value>, k: &str, path: &JsonPath) -> Result<&'a Value, IoError> {
    obj.get(k)
        .ok_or_else(|| path.error(format!("missing field \"{k}\"")))
}

fn numbers(v: &Value, path: &JsonPath) -> Result<Vec<f64>, IoError> {
    json::array(v, path, "an array of numbers")?
        .iter()
        .enumerate()
        .map(|(i, x)| json::number(x, &path.index(i)))
        .collect()
}

fn parse_shape(
    v: &Value,
    kind: usize,
    index: usize,
    path: &JsonPath,
) -> Result<NamedEntity, IoError> {
    let Value::Object(obj) = v else {
        return Err(path.expected("a shape object", v));
    };
    match obj.get("type") {
        None => {}
        Some(Value::String(s)) if s == "spline" => {}
        Some(other) => {
            return Err(path.key("type").error(format!(
                "only \"spline\" shapes are supported, found {}",
                json::describe(other)
            )));
        }
    }
    if obj.contains_key("trims") {
        return Err(path
            .key("trims")
            .error("trimmed surfaces are not supported"));
    }
    let name = match obj.get("name") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) => Some(s.clone()),
        Some(other) => return Err(path.key("name").expected("a string", other)),
    };
    let cpath = path.key("control_points");
    let cp = field(obj, "control_points", path)?;
    let Value::Object(cpo) = cp else {
        return Err(cpath.expected("an object with \"points\" and optional \"weights\"", cp));
    };
    let ppath = cpath.key("points");
    let pts = json::array(field(cpo, "points", &cpath)?, &ppath, "an array of points")?
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let pp = ppath.index(i);
            let c = numbers(p, &pp)?;
            match c.len() {
                2 => Ok(Vec3::new(c[0], c[1], 0.0)),
                3 => Ok(Vec3::new(c[0], c[1], c[2])),
                n => Err(pp.error(format!("expected 2 or 3 coordinates, found {n}"))),
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let weights = cpo
        .get("weights")
        .map(|w| numbers(w, &cpath.key("weights")))
        .transpose()?;
    if let Some(w) = &weights
        && w.len() != pts.len()
    {
        return Err(cpath.key("weights").error(format!(
            "{} weights for {} control points",
            w.len(),
            pts.len()
        )));
    }
    let weights = weights.unwrap_or_else(|| vec![1.0; pts.len()]);
    let kind_name = crate::model::ENTITY_TYPES[kind];
    let wrap = |source: SplineError| IoError::Entity {
        index,
        kind: kind_name,
        source,
    };
    let entity = if kind == 0 {
        let p = json::integer(field(obj, "degree", path)?, &path.key("degree"))?;
        let kv = numbers(field(obj, "knotvector", path)?, &path.key("knotvector"))?;
        Entity::Curve(NurbsCurve::new(p, kv, pts, Some(weights)).map_err(wrap)?)
    } else {
        let n = kind + 1;
        let mut kvs = Vec::with_capacity(n);
        let mut dims = Vec::with_capacity(n);
        for a in 0..n {
            let ax = AXES[a];
            let (dk, kk, sk) = (
                format!("degree_{ax}"),
                format!("knotvector_{ax}"),
                format!("size_{ax}"),
            );
            let p = json::integer(field(obj, &dk, path)?, &path.key(&dk))?;
            let size = json::integer(field(obj, &sk, path)?, &path.key(&sk))?;
            let k = numbers(field(obj, &kk, path)?, &path.key(&kk))?;
            kvs.push(
                KnotVector::new(k, p, size)
                    .map_err(|source| wrap(SplineError::Knots { axis: a, source }))?,
            );
            dims.push(size);
        }
        let total: usize = dims.iter().product();
        if total != pts.len() {
            return Err(ppath.error(format!(
                "{} control points, but the sizes {dims:?} need {total}",
                pts.len()
            )));
        }
        if kind == 1 {
            let [ku, kv]: [KnotVector; 2] = kvs.try_into().expect("two knot vectors");
            Entity::Surface(NurbsSurface::from_flat([ku, kv], pts, weights).map_err(wrap)?)
        } else {
            // geomdl index j + nv * (i + nu * k)  ->  vclay index (i * nv + j) * nw + k.
            let (nu, nv, nw) = (dims[0], dims[1], dims[2]);
            let mut p2 = vec![Vec3::zeros(); total];
            let mut w2 = vec![0.0; total];
            for k in 0..nw {
                for i in 0..nu {
                    for j in 0..nv {
                        let g = j + nv * (i + nu * k);
                        let v = (i * nv + j) * nw + k;
                        p2[v] = pts[g];
                        w2[v] = weights[g];
                    }
                }
            }
            let [a, b, c]: [KnotVector; 3] = kvs.try_into().expect("three knot vectors");
            Entity::Volume(NurbsVolume::from_flat([a, b, c], p2, w2).map_err(wrap)?)
        }
    };
    Ok(NamedEntity { name, entity })
}

fn pt(p: &Vec3) -> Value {
    json!([p.x, p.y, p.z])
}

/// The entities as a geomdl JSON document. All must have the same parametric dimension (a
/// geomdl file holds curves, surfaces or volumes, not a mix).
pub fn to_geomdl_json(entities: &[NamedEntity]) -> Result<Value, IoError> {
    let Some(first) = entities.first() else {
        return Err(IoError::EmptyModel);
    };
    let kind = first.entity.param_dims() - 1;
    let mut data = Vec::with_capacity(entities.len());
    for (i, e) in entities.iter().enumerate() {
        if e.entity.param_dims() - 1 != kind {
            return Err(IoError::Structure {
                path: format!("entities[{i}]"),
                message: format!(
                    "a geomdl file holds one kind of shape: entity 0 is a {}, entity {i} a {}",
                    SHAPE_TYPES[kind],
                    SHAPE_TYPES[e.entity.param_dims() - 1]
                ),
            });
        }
        let mut m = Map::new();
        m.insert("type".into(), json!("spline"));
        let (points, weights): (Vec<Vec3>, Vec<f64>) = match &e.entity {
            Entity::Curve(c) => {
                m.insert("degree".into(), json!(c.degree()));
                m.insert("knotvector".into(), json!(c.knots().as_slice()));
                (c.control_points().to_vec(), c.weights().to_vec())
            }
            Entity::Surface(s) => {
                for a in 0..2 {
                    m.insert(format!("degree_{}", AXES[a]), json!(s.degree()[a]));
                    m.insert(
                        format!("knotvector_{}", AXES[a]),
                        json!(s.knots()[a].as_slice()),
                    );
                    m.insert(format!("size_{}", AXES[a]), json!(s.dims()[a]));
                }
                (s.control_points().to_vec(), s.weights().to_vec())
            }
            Entity::Volume(v) => {
                for a in 0..3 {
                    m.insert(format!("degree_{}", AXES[a]), json!(v.degree()[a]));
                    m.insert(
                        format!("knotvector_{}", AXES[a]),
                        json!(v.knots()[a].as_slice()),
                    );
                    m.insert(format!("size_{}", AXES[a]), json!(v.dims()[a]));
                }
                let [nu, nv, nw] = v.dims();
                let mut p = Vec::with_capacity(nu * nv * nw);
                let mut w = Vec::with_capacity(nu * nv * nw);
                for k in 0..nw {
                    for i in 0..nu {
                        for j in 0..nv {
                            let idx = (i * nv + j) * nw + k;
                            p.push(v.control_points()[idx]);
                            w.push(v.weights()[idx]);
                        }
                    }
                }
                (p, w)
            }
        };
        let rational = weights.iter().any(|&w| w != 1.0);
        m.insert("rational".into(), json!(rational));
        m.insert("dimension".into(), json!(3));
        let mut cp = Map::new();
        cp.insert(
            "points".into(),
            Value::Array(points.iter().map(pt).collect()),
        );
        if rational {
            cp.insert("weights".into(), json!(weights));
        }
        m.insert("control_points".into(), Value::Object(cp));
        if let Some(n) = &e.name {
            m.insert("name".into(), json!(n));
        }
        data.push(Value::Object(m));
    }
    Ok(json!({"shape": {"type": SHAPE_TYPES[kind], "count": data.len(), "data": data}}))
}

/// Writes entities as a geomdl JSON file, atomically.
pub fn write_geomdl(path: impl AsRef<Path>, entities: &[NamedEntity]) -> Result<(), IoError> {
    let path = path.as_ref();
    let v = to_geomdl_json(entities).map_err(|e| e.in_file(path))?;
    let text = json::pretty(&v);
    crate::util::write_atomic(path, |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::parse_named_model;

    fn sample_volume() -> NurbsVolume {
        let mut v = NurbsVolume::box_lattice(
            [1, 2, 1],
            [2, 3, 4],
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 3.0),
        )
        .unwrap();
        let w: Vec<f64> = (0..v.weights().len())
            .map(|k| 1.0 + 0.1 * k as f64)
            .collect();
        v.set_weights(w).unwrap();
        v
    }

    #[test]
    fn round_trip_curves_surfaces_volumes_bit_for_bit() {
        let torus = NurbsSurface::torus(2.0, 0.5).unwrap();
        let circle = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.5).unwrap();
        for ents in [
            vec![NamedEntity {
                name: Some("torus".into()),
                entity: Entity::Surface(torus),
            }],
            vec![Entity::Curve(circle).into()],
            vec![Entity::Volume(sample_volume()).into()],
        ] {
            let text = json::pretty(&to_geomdl_json(&ents).unwrap());
            assert!(is_geomdl(&text));
            assert_eq!(parse_geomdl(&text).unwrap(), ents);
        }
    }

    #[test]
    fn volume_order_follows_geomdl() {
        let v = sample_volume();
        let j = to_geomdl_json(&[Entity::Volume(v.clone()).into()]).unwrap();
        let pts = &j["shape"]["data"][0]["control_points"]["points"];
        // geomdl index 1 = (i 0, j 1, k 0); vclay's (0, 1, 0) is at index nw = 4.
        let p = v.control_point(0, 1, 0);
        assert_eq!(pts[1], json!([p.x, p.y, p.z]));
        let p = v.control_point(1, 0, 0);
        assert_eq!(pts[3], json!([p.x, p.y, p.z]));
    }

    #[test]
    fn geomdl_sample_reads_with_2d_points_and_errors_name_places() {
        let text = r#"{"shape": {"type": "curve", "count": 1, "data": [{"type": "spline",
          "rational": false, "dimension": 2, "degree": 2, "knotvector": [0, 0, 0, 1, 1, 1],
          "control_points": {"points": [[0, 0], [1, 2], [2, 0]]}, "delta": 0.01, "name": "arc"}]}}"#;
        let e = parse_geomdl(text).unwrap();
        assert_eq!(e[0].name.as_deref(), Some("arc"));
        let Entity::Curve(c) = &e[0].entity else {
            panic!()
        };
        assert_eq!(c.control_points()[1], Vec3::new(1.0, 2.0, 0.0));
        let bad = text.replace("[1, 2]", "[1, \"x\"]");
        let msg = parse_geomdl(&bad).unwrap_err().to_string();
        assert!(
            msg.contains("shape.data[0].control_points.points[1][1]"),
            "{msg}"
        );
        let bad = text.replace("[0, 0, 0, 1, 1, 1]", "[0, 0, 1, 1, 1]");
        let msg = parse_geomdl(&bad).unwrap_err().to_string();
        assert!(msg.contains("entity 0"), "{msg}");
        // A vclay model is not geomdl.
        let m = crate::model::to_json_string(&[e[0].entity.clone()]);
        assert!(!is_geomdl(&m));
        assert!(parse_named_model(&m).is_ok());
        assert!(parse_geomdl(&m).unwrap_err().to_string().contains("shape"));
    }

    #[test]
    fn mixed_kinds_are_refused() {
        let ents = vec![
            Entity::Curve(NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap())
                .into(),
            Entity::Volume(sample_volume()).into(),
        ];
        let e = to_geomdl_json(&ents).unwrap_err().to_string();
        assert!(e.contains("entities[1]"), "{e}");
    }
}
