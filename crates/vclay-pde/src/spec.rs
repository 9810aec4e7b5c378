//! The PDE spec file (JSON or TOML): boundary conditions per component, shape functions, rho, eta, N,
//! the collocation grid, the v range, side conditions and local deformations, for one or more
//! patches. The format is documented in `docs/formats.md` ("PDE surface specs").
//!
//! A spec is read into [`SpecFile`] (serde, unknown fields rejected) and compiled by
//! [`PdeModel::from_spec`]: parameters are substituted, expressions parsed (errors name the
//! field path and the column), boundary functions split into basic functions (eq 3), and every
//! patch checked for well-posedness ([`PdePatch::new`]).

use crate::basis::{split, split_u_polynomial};
use crate::error::PdeError;
use crate::expr::{Expr, ExprError, ExprErrorKind, Var, is_reserved_name};
use crate::patch::{
    BasicFunction, Collocation, Component, Continuity, Field, LocalDeformation, PdePatch,
    ShapeFunctions, SideCondition, Sides,
};
use crate::spectral::{DEFAULT_FOURIER_TERMS, MAX_FOURIER_TERMS, Method};
use crate::trial::PatchKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Default N (the paper's section III uses N = 7).
pub const DEFAULT_TRIAL_TERMS: usize = 7;
/// Default shape function b_i (the biharmonic-like choice of section IV: b = d = 1, c = 2).
pub const DEFAULT_B: f64 = 1.0;
/// Default shape function c_i.
pub const DEFAULT_C: f64 = 2.0;
/// Default shape function d_i.
pub const DEFAULT_D: f64 = 1.0;
/// Default density rho (static problem).
pub const DEFAULT_RHO: f64 = 0.0;
/// Default damping eta (static problem).
pub const DEFAULT_ETA: f64 = 0.0;
/// Default smallest collocation count per direction (6 x 6 = 36, the paper's M).
pub const DEFAULT_MIN_COLLOCATION: usize = 6;

/// The basic function `g` with its derivatives, their size bounded (issue 17); `place` is
/// the component's field path.
fn basic_function(g: Expr, place: &str) -> Result<BasicFunction, PdeError> {
    let text = g.to_string();
    BasicFunction::try_new(g).map_err(|e| PdeError::InvalidValue {
        place: place.to_string(),
        message: format!(
            "basic function '{}': {}",
            crate::expr::shorten(&text, 80),
            e.kind_text()
        ),
    })
}

/// Most collocation points per patch (`nu * nv`): a million.
pub const MAX_COLLOCATION_POINTS: usize = 1_000_000;

/// Most entries of one component's dense collocation matrix (points x unknown constants):
/// 2 x 10^7, 160 MB of `f64` (the QR works on a copy).
pub const MAX_COLLOCATION_ENTRIES: usize = 20_000_000;

/// `message` prefixed with the key it is about (`params.lambda: invalid type: ...`), so that
/// serde's messages never come bare (issue 17); `.` (the document) and `""` add nothing.
fn keyed(key: &str, message: &str) -> String {
    if key.is_empty() || key == "." {
        message.to_string()
    } else {
        format!("{key}: {message}")
    }
}

/// The names the `solver` key accepts.
pub const SOLVERS: [&str; 3] = ["collocation", "fourier", "pseudospectral"];

/// A number or an expression text.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "a number or an expression string")]
pub enum Value {
    /// A number.
    Num(f64),
    /// An expression (see [`crate::expr`]).
    Text(String),
}

impl From<f64> for Value {
    fn from(x: f64) -> Self {
        Value::Num(x)
    }
}

impl From<&str> for Value {
    fn from(s: &str) -> Self {
        Value::Text(s.to_string())
    }
}

/// One value for all three components, or one per component.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "a number, an expression string or an array of 3 of them [x, y, z]"
)]
pub enum PerComponent {
    /// The same for x, y, z.
    One(Value),
    /// x, y, z.
    Three([Value; 3]),
}

/// Collocation points: a count M (arranged as square as possible) or a grid `[nu, nv]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "a point count or a grid [nu, nv]")]
pub enum CollocationSpec {
    /// M points.
    Count(usize),
    /// nu x nv points.
    Grid([usize; 2]),
}

/// Shape functions b, c, d (eq 1, 29); each defaults to [`DEFAULT_B`], [`DEFAULT_C`],
/// [`DEFAULT_D`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// b_i.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<PerComponent>,
    /// c_i.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c: Option<PerComponent>,
    /// d_i.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d: Option<PerComponent>,
}

/// Boundary conditions (2) of one component: functions of v and t.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// x_i at u = 0 (G_i1).
    pub u0: Value,
    /// dx_i/du at u = 0 (G_i2).
    pub du0: Value,
    /// x_i at u = 1 (G_i3); absent for a three-sided patch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u1: Option<Value>,
    /// dx_i/du at u = 1 (G_i4); absent for a three-sided patch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub du1: Option<Value>,
    /// Extra basic functions of v and t with coefficient 0 in every boundary condition: more
    /// freedom for the PDE where side conditions fix some constants (eq 35, 37).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub basics: Vec<Value>,
}

/// Side conditions of one component (eq 33): polynomials in u with coefficients in t.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideSpec {
    /// x_i at v = v0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0: Option<Value>,
    /// dx_i/dv at v = v0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dv0: Option<Value>,
    /// x_i at v = v1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v1: Option<Value>,
    /// dx_i/dv at v = v1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dv1: Option<Value>,
}

/// Side conditions for x, y, z.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SidesSpec {
    /// x component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<SideSpec>,
    /// y component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<SideSpec>,
    /// z component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<SideSpec>,
}

/// A local deformation (section VI-A, eq 30-32).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalSpec {
    /// `[u1, u2]`.
    pub u: [Value; 2],
    /// `[v1, v2]`.
    pub v: [Value; 2],
    /// `"G0"` (eq 31) or `"G1"` (eq 32).
    pub continuity: String,
    /// p_1, p_2, p_3 as expressions in u, v, t.
    pub p: [Value; 3],
}

/// One patch. Settings given here override the file's top-level ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchSpec {
    /// Name (default `patch<k>`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// N.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trial_terms: Option<usize>,
    /// Collocation points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collocation: Option<CollocationSpec>,
    /// `[v0, v1]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_range: Option<[Value; 2]>,
    /// Shape functions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<ShapeSpec>,
    /// Density.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rho: Option<Value>,
    /// Damping.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta: Option<Value>,
    /// x boundary conditions.
    pub x: BoundarySpec,
    /// y boundary conditions.
    pub y: BoundarySpec,
    /// z boundary conditions.
    pub z: BoundarySpec,
    /// Side conditions (three- and four-sided patches).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sides: Option<SidesSpec>,
    /// Local deformations.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub local: Vec<LocalSpec>,
    /// Solver: `"collocation"` (default), `"fourier"` or `"pseudospectral"` ([`SOLVERS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<String>,
    /// N of the spectral solvers (default [`DEFAULT_FOURIER_TERMS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fourier_terms: Option<usize>,
}

/// A spec file: shared settings and parameters, and the patches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecFile {
    /// Model name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free text (which figure it reproduces, ...).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Named numbers usable in every expression.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, f64>,
    /// N for all patches (default [`DEFAULT_TRIAL_TERMS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trial_terms: Option<usize>,
    /// Collocation points for all patches (default: a grid of at least 6 x 6 with
    /// J (N - 3) + 2 rows and 2 J columns, J the largest number of basic functions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collocation: Option<CollocationSpec>,
    /// `[v0, v1]` for all patches (default `[0, 2*pi]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_range: Option<[Value; 2]>,
    /// Shape functions for all patches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<ShapeSpec>,
    /// Density for all patches (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rho: Option<Value>,
    /// Damping for all patches (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta: Option<Value>,
    /// Solver for all patches: `"collocation"` (default), `"fourier"` or `"pseudospectral"`
    /// (section III's comparison, eq 19-23; see [`crate::spectral`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<String>,
    /// N (Fourier terms) of the spectral solvers for all patches (default
    /// [`DEFAULT_FOURIER_TERMS`], at most [`MAX_FOURIER_TERMS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fourier_terms: Option<usize>,
    /// The patches.
    pub patches: Vec<PatchSpec>,
}

/// A compiled spec: named patches, ready to solve.
#[derive(Clone, Debug, PartialEq)]
pub struct PdeModel {
    /// Model name.
    pub name: String,
    /// The patches.
    pub patches: Vec<PdePatch>,
}

impl PdeModel {
    /// Reads and compiles a spec file: TOML if the name ends in `.toml`, JSON otherwise.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, PdeError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| PdeError::Spec {
            place: path.display().to_string(),
            message: format!("cannot read: {e}"),
        })?;
        let name = path.display().to_string();
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
        {
            Self::from_toml(&text, &name)
        } else {
            Self::from_json(&text, &name)
        }
    }

    /// Parses and compiles a spec from TOML text (the same fields as JSON); `source` names it
    /// in errors.
    pub fn from_toml(text: &str, source: &str) -> Result<Self, PdeError> {
        let toml_err = |e: &toml::de::Error, key: &str| {
            let (line, col) = e
                .span()
                .map_or((1, 1), |s| vclay_core::text::line_column(text, s.start));
            PdeError::Spec {
                place: format!("{source}:{line}:{col}"),
                message: keyed(key, e.message().trim()),
            }
        };
        let de = toml::Deserializer::parse(text).map_err(|e| toml_err(&e, ""))?;
        let spec: SpecFile = serde_path_to_error::deserialize(de)
            .map_err(|e| toml_err(e.inner(), &e.path().to_string()))?;
        Self::from_spec(&spec)
    }

    /// Parses and compiles a spec from JSON text; `source` names it in errors.
    pub fn from_json(text: &str, source: &str) -> Result<Self, PdeError> {
        let json_err = |e: &serde_json::Error, key: &str| {
            let msg = e.to_string();
            let suffix = format!(" at line {} column {}", e.line(), e.column());
            PdeError::Spec {
                place: format!("{source}:{}:{}", e.line(), e.column()),
                message: keyed(key, msg.strip_suffix(&suffix).unwrap_or(&msg)),
            }
        };
        let mut de = serde_json::Deserializer::from_str(text);
        let spec: SpecFile = serde_path_to_error::deserialize(&mut de)
            .map_err(|e| json_err(e.inner(), &e.path().to_string()))?;
        de.end().map_err(|e| json_err(&e, ""))?;
        Self::from_spec(&spec)
    }

    /// Compiles a spec.
    pub fn from_spec(spec: &SpecFile) -> Result<Self, PdeError> {
        for name in spec.params.keys() {
            if is_reserved_name(name)
                || !name
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_alphabetic() || c == '_')
                || !name.chars().all(|c| c.is_alphanumeric() || c == '_')
            {
                return Err(PdeError::InvalidValue {
                    place: format!("params.{name}"),
                    message: "parameter names must be identifiers other than u, v, t, pi and \
                              function names"
                        .into(),
                });
            }
        }
        for (name, x) in &spec.params {
            if !x.is_finite() {
                return Err(PdeError::InvalidValue {
                    place: format!("params.{name}"),
                    message: format!("{x} is not finite"),
                });
            }
        }
        if spec.patches.is_empty() {
            return Err(PdeError::InvalidValue {
                place: "patches".into(),
                message: "a spec needs at least one patch".into(),
            });
        }
        let cx = Ctx {
            params: &spec.params,
        };
        let patches = spec
            .patches
            .iter()
            .enumerate()
            .map(|(k, p)| cx.patch(spec, k, p))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PdeModel {
            name: spec.name.clone().unwrap_or_else(|| "pde".into()),
            patches,
        })
    }
}

struct Ctx<'a> {
    params: &'a BTreeMap<String, f64>,
}

/// Column (1-based) of the first occurrence of the name `name` as a whole word in `text`.
fn name_column(text: &str, name: &str) -> usize {
    let chars: Vec<char> = text.chars().collect();
    let n: Vec<char> = name.chars().collect();
    let is_id = |c: char| c.is_alphanumeric() || c == '_';
    for k in 0..chars.len() {
        if chars[k..].starts_with(&n)
            && (k == 0 || !is_id(chars[k - 1]))
            && chars.get(k + n.len()).is_none_or(|&c| !is_id(c))
        {
            return k + 1;
        }
    }
    1
}

impl Ctx<'_> {
    /// Parses a value; `forbidden` lists variables it must not use, with the reason.
    fn expr(
        &self,
        value: &Value,
        place: &str,
        forbidden: &[(Var, &'static str)],
    ) -> Result<Expr, PdeError> {
        let text = match value {
            Value::Num(x) => {
                if !x.is_finite() {
                    return Err(PdeError::InvalidValue {
                        place: place.into(),
                        message: format!("{x} is not finite"),
                    });
                }
                return Ok(Expr::Num(*x));
            }
            Value::Text(s) => s,
        };
        let lookup = |n: &str| self.params.get(n).copied();
        let wrap = |error: ExprError| PdeError::Expression {
            place: place.into(),
            pointer: error.pointer(text),
            error,
        };
        let e = Expr::parse_with(text, &lookup).map_err(wrap)?;
        for &(var, why) in forbidden {
            if e.depends_on(var) {
                let name = match var {
                    Var::U => "u",
                    Var::V => "v",
                    Var::T => "t",
                };
                return Err(wrap(ExprError {
                    column: name_column(text, name),
                    kind: ExprErrorKind::VariableNotAllowed(why),
                }));
            }
        }
        Ok(e)
    }

    fn number(&self, value: &Value, place: &str) -> Result<f64, PdeError> {
        let e = self.expr(
            value,
            place,
            &[
                (Var::U, "a range bound must be a number, not depend on u"),
                (Var::V, "a range bound must be a number, not depend on v"),
                (Var::T, "a range bound must be a number, not depend on t"),
            ],
        )?;
        match e.as_number() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(PdeError::InvalidValue {
                place: place.into(),
                message: "must evaluate to a finite number".into(),
            }),
        }
    }

    fn field(&self, value: &Value, place: &str) -> Result<Field, PdeError> {
        Ok(Field::from_expr(self.expr(value, place, &[])?))
    }

    fn per_component(
        &self,
        v: Option<&PerComponent>,
        default: f64,
        place: &str,
    ) -> Result<[Field; 3], PdeError> {
        Ok(match v {
            None => [
                Field::Const(default),
                Field::Const(default),
                Field::Const(default),
            ],
            Some(PerComponent::One(x)) => {
                let f = self.field(x, place)?;
                [f.clone(), f.clone(), f]
            }
            Some(PerComponent::Three(xs)) => [
                self.field(&xs[0], &format!("{place}[0]"))?,
                self.field(&xs[1], &format!("{place}[1]"))?,
                self.field(&xs[2], &format!("{place}[2]"))?,
            ],
        })
    }

    fn patch(&self, file: &SpecFile, k: usize, p: &PatchSpec) -> Result<PdePatch, PdeError> {
        let place = format!("patches[{k}]");
        let name = p.name.clone().unwrap_or_else(|| format!("patch{k}"));
        let n_max = p
            .trial_terms
            .or(file.trial_terms)
            .unwrap_or(DEFAULT_TRIAL_TERMS);
        let v_range = match p.v_range.as_ref().or(file.v_range.as_ref()) {
            None => (0.0, std::f64::consts::TAU),
            Some([a, b]) => (
                self.number(a, &format!("{place}.v_range[0]"))?,
                self.number(b, &format!("{place}.v_range[1]"))?,
            ),
        };
        let shape = p.shape.as_ref().or(file.shape.as_ref());
        let sp = format!("{place}.shape");
        let bs = self.per_component(
            shape.and_then(|s| s.b.as_ref()),
            DEFAULT_B,
            &format!("{sp}.b"),
        )?;
        let cs = self.per_component(
            shape.and_then(|s| s.c.as_ref()),
            DEFAULT_C,
            &format!("{sp}.c"),
        )?;
        let ds = self.per_component(
            shape.and_then(|s| s.d.as_ref()),
            DEFAULT_D,
            &format!("{sp}.d"),
        )?;
        let rho = match p.rho.as_ref().or(file.rho.as_ref()) {
            None => Field::Const(DEFAULT_RHO),
            Some(v) => self.field(v, &format!("{place}.rho"))?,
        };
        let eta = match p.eta.as_ref().or(file.eta.as_ref()) {
            None => Field::Const(DEFAULT_ETA),
            Some(v) => self.field(v, &format!("{place}.eta"))?,
        };
        let bounds = [&p.x, &p.y, &p.z];
        let ends: Vec<bool> = bounds
            .iter()
            .zip(["x", "y", "z"])
            .map(|(b, c)| match (&b.u1, &b.du1) {
                (Some(_), Some(_)) => Ok(true),
                (None, None) => Ok(false),
                _ => Err(PdeError::InvalidValue {
                    place: format!("{place}.{c}"),
                    message: "give both u1 and du1 (a patch with conditions at u = 1), or neither \
                              (a three-sided patch, eq 36)"
                        .into(),
                }),
            })
            .collect::<Result<_, _>>()?;
        let kind = if ends.iter().all(|&e| e) {
            PatchKind::TwoEnds
        } else if ends.iter().all(|&e| !e) {
            PatchKind::OneEnd
        } else {
            return Err(PdeError::InvalidValue {
                place: place.clone(),
                message: "either all of x, y, z have u1/du1 conditions or none does".into(),
            });
        };
        let no_u: [(Var, &'static str); 1] = [(
            Var::U,
            "a boundary function at u = 0 or u = 1 depends on v and t only, not on u",
        )];
        let sides = p.sides.clone().unwrap_or_default();
        let side_specs = [&sides.x, &sides.y, &sides.z];
        let mut comps = Vec::with_capacity(3);
        for (i, c) in ["x", "y", "z"].into_iter().enumerate() {
            let b = bounds[i];
            let cp = format!("{place}.{c}");
            let mut conds = vec![(&b.u0, "u0"), (&b.du0, "du0")];
            if let (Some(u1), Some(du1)) = (&b.u1, &b.du1) {
                conds.push((u1, "u1"));
                conds.push((du1, "du1"));
            }
            let mut keys: Vec<String> = Vec::new();
            let mut basics: Vec<BasicFunction> = Vec::new();
            let mut coefficients: Vec<[f64; 4]> = Vec::new();
            for (kk, (val, field)) in conds.iter().enumerate() {
                let e = self.expr(val, &format!("{cp}.{field}"), &no_u)?;
                for (coef, term) in split(&e) {
                    let key = term.key();
                    let j = match keys.iter().position(|x| *x == key) {
                        Some(j) => j,
                        None => {
                            keys.push(key);
                            basics.push(basic_function(term.basic(), &cp)?);
                            coefficients.push([0.0; 4]);
                            keys.len() - 1
                        }
                    };
                    coefficients[j][kk] += coef;
                }
            }
            for (q, val) in b.basics.iter().enumerate() {
                let e = self.expr(val, &format!("{cp}.basics[{q}]"), &no_u)?;
                for (_, term) in split(&e) {
                    let key = term.key();
                    if !keys.contains(&key) {
                        keys.push(key);
                        basics.push(basic_function(term.basic(), &cp)?);
                        coefficients.push([0.0; 4]);
                    }
                }
            }
            let side = match side_specs[i] {
                None => Sides::default(),
                Some(s) => {
                    let sp = format!("{place}.sides.{c}");
                    let one = |v: &Option<Value>,
                               f: &str|
                     -> Result<Option<SideCondition>, PdeError> {
                        let Some(v) = v else { return Ok(None) };
                        let fp = format!("{sp}.{f}");
                        let e = self.expr(
                            v,
                            &fp,
                            &[(Var::V, "a side condition is a polynomial in u with coefficients in t; it cannot depend on v")],
                        )?;
                        let coefficients = split_u_polynomial(&e).map_err(|term| {
                            PdeError::InvalidValue {
                                place: fp.clone(),
                                message: format!(
                                    "side conditions must be polynomials in u (eq 34); the term '{term}' is not a power of u times a function of t"
                                ),
                            }
                        })?;
                        if coefficients.len() > n_max + 1 {
                            return Err(PdeError::InvalidValue {
                                place: fp.clone(),
                                message: format!(
                                    "the polynomial has degree {} but the solution has trial powers up to N = {n_max}; raise trial_terms",
                                    coefficients.len() - 1
                                ),
                            });
                        }
                        Ok(Some(SideCondition {
                            place: fp,
                            coefficients,
                        }))
                    };
                    Sides {
                        v0: one(&s.v0, "v0")?,
                        dv0: one(&s.dv0, "dv0")?,
                        v1: one(&s.v1, "v1")?,
                        dv1: one(&s.dv1, "dv1")?,
                    }
                }
            };
            comps.push(Component {
                basics,
                coefficients,
                shape: ShapeFunctions {
                    b: bs[i].clone(),
                    c: cs[i].clone(),
                    d: ds[i].clone(),
                },
                sides: side,
            });
        }
        let jmax = comps.iter().map(|c| c.basics.len()).max().unwrap_or(1);
        let per_basic = n_max.saturating_sub(kind.first_unknown_power() - 1);
        let collocation = match p.collocation.as_ref().or(file.collocation.as_ref()) {
            // Rows along u: enough for all J (N - 3) constants of a component even when its
            // basic functions share one shape in v at an instant (cos v, t^2 cos v, t^3 cos v
            // of eq 28 span only cos v), where only the u direction tells them apart.
            None => Collocation {
                nu: DEFAULT_MIN_COLLOCATION.max(jmax * per_basic + 2),
                nv: DEFAULT_MIN_COLLOCATION.max(2 * jmax),
            },
            Some(CollocationSpec::Count(m)) => Collocation::from_count(*m),
            Some(CollocationSpec::Grid([nu, nv])) => Collocation { nu: *nu, nv: *nv },
        };
        // Issue 17: the dense collocation matrix (points x unknowns per component) is checked
        // before anything is assembled (100000 x 100000 points, or 2,000 basic functions with
        // the default grid, asked for terabytes).
        let points = collocation.nu as f64 * collocation.nv as f64;
        let unknowns = (jmax * per_basic).max(1) as f64;
        if points > MAX_COLLOCATION_POINTS as f64
            || points * unknowns > MAX_COLLOCATION_ENTRIES as f64
        {
            let given = p.collocation.is_some() || file.collocation.is_some();
            return Err(PdeError::InvalidValue {
                place: if given {
                    format!("{place}.collocation")
                } else {
                    place.clone()
                },
                message: format!(
                    "{} x {} collocation points and {} unknown constants ({jmax} basic \
                     functions x {per_basic} trial terms) make a {:.2e}-entry matrix; the \
                     limits are {MAX_COLLOCATION_POINTS} points and {MAX_COLLOCATION_ENTRIES} \
                     entries ({} MB){}",
                    collocation.nu,
                    collocation.nv,
                    jmax * per_basic,
                    points * unknowns,
                    MAX_COLLOCATION_ENTRIES * 8 / 1_000_000,
                    if given {
                        ""
                    } else {
                        "; use fewer basic functions"
                    }
                ),
            });
        }
        let mut local = Vec::with_capacity(p.local.len());
        for (q, l) in p.local.iter().enumerate() {
            let lp = format!("{place}.local[{q}]");
            let continuity = match l.continuity.as_str() {
                "G0" | "g0" => Continuity::G0,
                "G1" | "g1" => Continuity::G1,
                other => {
                    return Err(PdeError::InvalidValue {
                        place: format!("{lp}.continuity"),
                        message: format!("'{other}' is not \"G0\" (eq 31) or \"G1\" (eq 32)"),
                    });
                }
            };
            local.push(LocalDeformation {
                u_range: (
                    self.number(&l.u[0], &format!("{lp}.u[0]"))?,
                    self.number(&l.u[1], &format!("{lp}.u[1]"))?,
                ),
                v_range: (
                    self.number(&l.v[0], &format!("{lp}.v[0]"))?,
                    self.number(&l.v[1], &format!("{lp}.v[1]"))?,
                ),
                continuity,
                p: [
                    self.field(&l.p[0], &format!("{lp}.p[0]"))?,
                    self.field(&l.p[1], &format!("{lp}.p[1]"))?,
                    self.field(&l.p[2], &format!("{lp}.p[2]"))?,
                ],
            });
        }
        let [cx, cy, cz]: [Component; 3] =
            comps.try_into().map_err(|_| PdeError::InvalidValue {
                place: place.clone(),
                message: "three components expected".into(),
            })?;
        let method = self.method(file, p, &place)?;
        let mut patch = PdePatch::new(
            name,
            kind,
            n_max,
            [cx, cy, cz],
            rho,
            eta,
            v_range,
            collocation,
            local,
        )?;
        if method != Method::Collocation {
            check_spectral(&patch, p, &place, method)?;
        }
        patch.method = method;
        Ok(patch)
    }

    /// The `solver` and `fourier_terms` keys (the patch's over the file's), sizes checked.
    fn method(&self, file: &SpecFile, p: &PatchSpec, place: &str) -> Result<Method, PdeError> {
        let (name, name_place) = match (&p.solver, &file.solver) {
            (Some(s), _) => (s.as_str(), format!("{place}.solver")),
            (None, Some(s)) => (s.as_str(), "solver".to_string()),
            (None, None) => ("collocation", String::new()),
        };
        let (terms, terms_place) = match (p.fourier_terms, file.fourier_terms) {
            (Some(n), _) => (n, format!("{place}.fourier_terms")),
            (None, Some(n)) => (n, "fourier_terms".to_string()),
            (None, None) => (DEFAULT_FOURIER_TERMS, String::new()),
        };
        let spectral = name != "collocation";
        if spectral && !(1..=MAX_FOURIER_TERMS).contains(&terms) {
            return Err(PdeError::InvalidValue {
                place: terms_place,
                message: format!(
                    "{terms} Fourier terms; expected 1 to {MAX_FOURIER_TERMS} (N of eq 19-21)"
                ),
            });
        }
        match name {
            "collocation" => Ok(Method::Collocation),
            "fourier" => Ok(Method::Fourier { terms }),
            "pseudospectral" => Ok(Method::Pseudospectral { terms }),
            other => Err(PdeError::InvalidValue {
                place: name_place,
                message: format!(
                    "unknown solver '{other}'; expected one of {}",
                    SOLVERS.join(", ")
                ),
            }),
        }
    }
}

/// The conditions of the Fourier-series and pseudospectral solvers ([`crate::spectral`]):
/// constant shape functions with `b != 0`, no density or damping, conditions at both ends, no
/// side conditions or local deformations. Errors name the field.
fn check_spectral(
    patch: &PdePatch,
    p: &PatchSpec,
    place: &str,
    method: Method,
) -> Result<(), PdeError> {
    let why = |field: String, what: &str| PdeError::InvalidValue {
        place: field,
        message: format!(
            "the {} solver (Bloor and Wilson's, eq 19-23) needs {what}; use \"solver\": \"collocation\"",
            method.name()
        ),
    };
    if patch.kind() != PatchKind::TwoEnds {
        return Err(why(
            place.to_string(),
            "conditions at u = 0 and u = 1 (not a three-sided patch)",
        ));
    }
    if p.sides.is_some() {
        return Err(why(format!("{place}.sides"), "no side conditions"));
    }
    if !patch.local.is_empty() {
        return Err(why(format!("{place}.local"), "no local deformations"));
    }
    for (i, c) in patch.components.iter().enumerate() {
        for (key, f) in [("b", &c.shape.b), ("c", &c.shape.c), ("d", &c.shape.d)] {
            match f.as_const() {
                None => {
                    return Err(why(
                        format!("{place}.shape.{key}"),
                        "constant shape functions (one ODE per Fourier mode)",
                    ));
                }
                Some(x) if key == "b" && x == 0.0 => {
                    return Err(why(
                        format!("{place}.shape.b"),
                        &format!("b != 0 (component {i} has b = 0, no fourth-order ODE)"),
                    ));
                }
                Some(_) => {}
            }
        }
    }
    for (key, f) in [("rho", &patch.rho), ("eta", &patch.eta)] {
        if f.as_const() != Some(0.0) {
            return Err(why(
                format!("{place}.{key}"),
                "a static PDE (rho = eta = 0)",
            ));
        }
    }
    Ok(())
}
