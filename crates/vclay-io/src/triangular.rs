//! The JSON format of triangular NURBS surfaces (DMS splines over a triangulated domain,
//! `d-nurbs.txt` section 4.4, eqs 10-11).
//!
//! **What.** One object (documented with an example in `docs/formats.md`):
//!
//! ```text
//! {"type": "triangular-nurbs", "name": "edge",
//!  "degree": n,
//!  "domain": {"vertices": [[u, v], ...], "triangles": [[i, j, k], ...]},
//!  "knot_clouds": [[[u, v] x (n + 1)], ...]      (optional; one per vertex, first = the vertex)
//!  "cloud_radius": 0.1,                            (optional, only without knot_clouds)
//!  "control_points": [[x, y, z], ...],
//!  "weights": [w, ...],                            (optional, all 1)
//!  "control_map": [c, ...] | "bezier-net"}          (optional: basis function -> control point)
//! ```
//! Basis function `t * (n+1)(n+2)/2 + k` belongs to triangle `t` and the `k`-th multi-index
//! `beta` (`beta_0` descending, then `beta_1` descending). Without `control_map` there is one
//! control point per basis function; `"bezier-net"` joins the functions at the same Bezier
//! domain point (the paper's continuous net). Without `knot_clouds` the clouds are placed by
//! [`KnotClouds::around_vertices`] with `cloud_radius` (default
//! [`vclay_spline::triangular::DEFAULT_CLOUD_RADIUS`]).
//!
//! **How.** As `model.rs`: the text is parsed to a JSON tree (line and column on syntax errors),
//! converted by hand with the JSON path in every structural error, then validated by
//! `vclay-spline` (triangulation, clouds, counts), whose errors name the triangle, vertex or
//! control point. Sizes are checked against [`MAX_TRIANGLES`] before anything is built.
//!
//! **Limitations.** One surface per file; numbers are written in shortest exact form, so a
//! written surface reads back bit for bit when its clouds are written (they always are).

use crate::error::{IoError, quote};
use crate::json::{self, JsonPath};
use serde_json::{Map, Value};
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::simplex::Point2;
use vclay_spline::triangular::{
    DEFAULT_CLOUD_RADIUS, KnotClouds, MAX_TRIANGLES, TriangularBasis, TriangularNurbs,
    Triangulation,
};

/// The `"type"` string.
pub const TRIANGULAR_TYPE: &str = "triangular-nurbs";

const FIELDS: [&str; 9] = [
    "type",
    "name",
    "degree",
    "domain",
    "knot_clouds",
    "cloud_radius",
    "control_points",
    "weights",
    "control_map",
];

/// A triangular NURBS with its optional name.
#[derive(Clone, Debug)]
pub struct NamedTriangular {
    /// The `"name"` field.
    pub name: Option<String>,
    /// The surface.
    pub surface: TriangularNurbs,
}

/// Whether JSON text is a triangular NURBS file (its top-level `"type"` is
/// [`TRIANGULAR_TYPE`]); cheap enough to choose a reader.
pub fn is_triangular(text: &str) -> bool {
    let head: String = text.chars().take(4096).collect();
    head.contains(&format!("\"{TRIANGULAR_TYPE}\""))
        && json::parse(text)
            .is_ok_and(|v| v.get("type").and_then(Value::as_str) == Some(TRIANGULAR_TYPE))
}

/// Reads a triangular NURBS file.
pub fn read_triangular(path: impl AsRef<Path>) -> Result<NamedTriangular, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::file(path, e))?;
    parse_triangular(&text).map_err(|e| e.in_file(path))
}

fn points2(v: &Value, path: &JsonPath) -> Result<Vec<Point2>, IoError> {
    json::array(v, path, "an array of [u, v] points")?
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let p = path.index(i);
            match x.as_array() {
                Some(a) if a.len() == 2 => Ok([
                    json::number(&a[0], &p.index(0))?,
                    json::number(&a[1], &p.index(1))?,
                ]),
                _ => Err(p.expected("an array of 2 numbers", x)),
            }
        })
        .collect()
}

fn check_count(path: &JsonPath, what: &str, n: usize, max: usize) -> Result<(), IoError> {
    if n > max {
        return Err(path.error(format!("{n} {what}, more than the limit {max}")));
    }
    Ok(())
}

/// Parses a triangular NURBS from JSON text.
pub fn parse_triangular(text: &str) -> Result<NamedTriangular, IoError> {
    let v = json::parse(text)?;
    let path = JsonPath::entity(0);
    let Value::Object(obj) = &v else {
        return Err(path.expected("a triangular-nurbs object", &v));
    };
    for k in obj.keys() {
        if !FIELDS.contains(&k.as_str()) {
            return Err(path.error(format!(
                "unknown field {} (allowed: {})",
                quote(k),
                FIELDS.join(", ")
            )));
        }
    }
    let field = |k: &str| -> Result<&Value, IoError> {
        obj.get(k)
            .ok_or_else(|| path.error(format!("missing field \"{k}\"")))
    };
    match field("type")? {
        Value::String(s) if s == TRIANGULAR_TYPE => {}
        other => return Err(path.key("type").expected("\"triangular-nurbs\"", other)),
    }
    let name = match obj.get("name") {
        None => None,
        Some(Value::String(s)) => Some(s.clone()),
        Some(other) => return Err(path.key("name").expected("a string", other)),
    };
    let degree = json::integer(field("degree")?, &path.key("degree"))?;
    let dp = path.key("domain");
    let Value::Object(dom) = field("domain")? else {
        return Err(dp.expected(
            "an object with \"vertices\" and \"triangles\"",
            field("domain")?,
        ));
    };
    for k in dom.keys() {
        if k != "vertices" && k != "triangles" {
            return Err(dp.error(format!(
                "unknown field {} (allowed: vertices, triangles)",
                quote(k)
            )));
        }
    }
    let vp = dp.key("vertices");
    let tp = dp.key("triangles");
    let vs = dom
        .get("vertices")
        .ok_or_else(|| dp.error("missing field \"vertices\""))?;
    let ts = dom
        .get("triangles")
        .ok_or_else(|| dp.error("missing field \"triangles\""))?;
    check_count(
        &vp,
        "vertices",
        json::array(vs, &vp, "an array")?.len(),
        3 * MAX_TRIANGLES,
    )?;
    check_count(
        &tp,
        "triangles",
        json::array(ts, &tp, "an array")?.len(),
        MAX_TRIANGLES,
    )?;
    let vertices = points2(vs, &vp)?;
    let triangles: Vec<[usize; 3]> = json::array(ts, &tp, "an array of [i, j, k]")?
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let p = tp.index(i);
            match x.as_array() {
                Some(a) if a.len() == 3 => Ok([
                    json::integer(&a[0], &p.index(0))?,
                    json::integer(&a[1], &p.index(1))?,
                    json::integer(&a[2], &p.index(2))?,
                ]),
                _ => Err(p.expected("an array of 3 vertex indices", x)),
            }
        })
        .collect::<Result<_, _>>()?;
    let wrap = |e: vclay_spline::triangular::TriangularError| IoError::Entity {
        index: 0,
        kind: TRIANGULAR_TYPE,
        source: e.into(),
    };
    let domain = Triangulation::new(vertices, triangles).map_err(wrap)?;
    let clouds = match (obj.get("knot_clouds"), obj.get("cloud_radius")) {
        (Some(_), Some(_)) => {
            return Err(path.error("give either \"knot_clouds\" or \"cloud_radius\", not both"));
        }
        (Some(c), None) => {
            let cp = path.key("knot_clouds");
            let list = json::array(c, &cp, "an array of knot clouds")?;
            check_count(&cp, "knot clouds", list.len(), 3 * MAX_TRIANGLES)?;
            KnotClouds {
                clouds: list
                    .iter()
                    .enumerate()
                    .map(|(i, x)| points2(x, &cp.index(i)))
                    .collect::<Result<_, _>>()?,
            }
        }
        (None, r) => {
            let radius = match r {
                Some(x) => json::number(x, &path.key("cloud_radius"))?,
                None => DEFAULT_CLOUD_RADIUS,
            };
            if !(radius > 0.0 && radius < 0.5) {
                return Err(path
                    .key("cloud_radius")
                    .error(format!("{radius} must be in (0, 0.5)")));
            }
            KnotClouds::around_vertices(&domain, degree, radius).map_err(wrap)?
        }
    };
    let basis = TriangularBasis::new(degree, domain, clouds).map_err(wrap)?;
    let cp = path.key("control_points");
    let pts = json::array(
        field("control_points")?,
        &cp,
        "an array of points [x, y, z]",
    )?;
    check_count(&cp, "control points", pts.len(), basis.len())?;
    let points: Vec<Vec3> = pts
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let p = cp.index(i);
            match x.as_array() {
                Some(a) if a.len() == 3 => Ok(Vec3::new(
                    json::number(&a[0], &p.index(0))?,
                    json::number(&a[1], &p.index(1))?,
                    json::number(&a[2], &p.index(2))?,
                )),
                _ => Err(p.expected("an array of 3 numbers", x)),
            }
        })
        .collect::<Result<_, _>>()?;
    let weights = match obj.get("weights") {
        Some(w) => {
            let wp = path.key("weights");
            json::array(w, &wp, "an array of numbers")?
                .iter()
                .enumerate()
                .map(|(i, x)| json::number(x, &wp.index(i)))
                .collect::<Result<Vec<f64>, _>>()?
        }
        None => vec![1.0; points.len()],
    };
    let map = match obj.get("control_map") {
        None => None,
        Some(Value::String(s)) if s == "bezier-net" => Some(basis.bezier_net_map().0),
        Some(m) => {
            let mp = path.key("control_map");
            let a = json::array(
                m,
                &mp,
                "an array of control point indices or \"bezier-net\"",
            )?;
            check_count(&mp, "entries", a.len(), basis.len())?;
            Some(
                a.iter()
                    .enumerate()
                    .map(|(i, x)| json::integer(x, &mp.index(i)))
                    .collect::<Result<_, _>>()?,
            )
        }
    };
    let surface = TriangularNurbs::new(basis, points, weights, map).map_err(wrap)?;
    Ok(NamedTriangular { name, surface })
}

fn num(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

fn p2(p: &Point2) -> Value {
    Value::Array(vec![num(p[0]), num(p[1])])
}

/// The JSON of a triangular NURBS (clouds always written, so it reads back exactly).
pub fn triangular_to_json(s: &TriangularNurbs, name: Option<&str>) -> Value {
    let b = s.basis();
    let mut m = Map::new();
    m.insert("type".into(), Value::String(TRIANGULAR_TYPE.into()));
    if let Some(n) = name {
        m.insert("name".into(), Value::String(n.into()));
    }
    m.insert("degree".into(), Value::from(b.degree()));
    let mut d = Map::new();
    d.insert(
        "vertices".into(),
        Value::Array(b.domain().vertices().iter().map(p2).collect()),
    );
    d.insert(
        "triangles".into(),
        Value::Array(
            b.domain()
                .triangles()
                .iter()
                .map(|t| Value::from(t.to_vec()))
                .collect(),
        ),
    );
    m.insert("domain".into(), Value::Object(d));
    m.insert(
        "knot_clouds".into(),
        Value::Array(
            b.clouds()
                .clouds
                .iter()
                .map(|c| Value::Array(c.iter().map(p2).collect()))
                .collect(),
        ),
    );
    m.insert(
        "control_points".into(),
        Value::Array(
            s.control_points()
                .iter()
                .map(|p| Value::Array(vec![num(p.x), num(p.y), num(p.z)]))
                .collect(),
        ),
    );
    if s.weights().iter().any(|&w| w != 1.0) {
        m.insert(
            "weights".into(),
            Value::Array(s.weights().iter().map(|&w| num(w)).collect()),
        );
    }
    if s.control_map().iter().enumerate().any(|(i, &c)| i != c) {
        m.insert("control_map".into(), Value::from(s.control_map().to_vec()));
    }
    Value::Object(m)
}

/// Writes a triangular NURBS file (atomically).
pub fn write_triangular(
    path: impl AsRef<Path>,
    s: &TriangularNurbs,
    name: Option<&str>,
) -> Result<(), IoError> {
    let text = json::pretty(&triangular_to_json(s, name));
    crate::util::write_atomic(path.as_ref(), |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const EDGE: &str = r#"{"type": "triangular-nurbs", "name": "strip", "degree": 2,
      "domain": {"vertices": [[0,0],[0,1],[1,0],[1,1]], "triangles": [[0,2,3],[0,3,1]]},
      "control_points": [[0,0,0],[0.5,0,0],[1,0,0],[0,0.5,0],[0.5,0.5,0.2],[1,0.5,0],[0,1,0],[0.5,1,0],[1,1,0]],
      "control_map": "bezier-net"}"#;

    #[test]
    fn reads_writes_and_reads_back() {
        let t = parse_triangular(EDGE).unwrap();
        assert_eq!(t.name.as_deref(), Some("strip"));
        assert_eq!(t.surface.control_points().len(), 9);
        let text = json::pretty(&triangular_to_json(&t.surface, t.name.as_deref()));
        assert!(is_triangular(&text));
        let back = parse_triangular(&text).unwrap();
        for x in [[0.3, 0.2], [0.7, 0.9]] {
            assert_eq!(back.surface.point(x).unwrap(), t.surface.point(x).unwrap());
        }
    }

    #[test]
    fn errors_are_located() {
        let bad = EDGE.replace("[0,3,1]", "[0,3,7]");
        let e = parse_triangular(&bad).unwrap_err().to_string();
        assert!(e.contains("triangle 1") && e.contains("vertex 7"), "{e}");
        let bad = EDGE.replace("[0.5,0.5,0.2]", "[0.5,\"x\",0.2]");
        let e = parse_triangular(&bad).unwrap_err().to_string();
        assert!(e.contains("control_points[4][1]"), "{e}");
        let bad = EDGE.replace("\"degree\": 2", "\"degree\": 2, \"weight\": 1");
        let e = parse_triangular(&bad).unwrap_err().to_string();
        assert!(e.contains("unknown field"), "{e}");
        let bad = EDGE.replace(",[1,1,0]],", "],");
        let e = parse_triangular(&bad).unwrap_err().to_string();
        assert!(e.contains("control"), "{e}");
    }
}
