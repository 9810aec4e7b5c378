//! Models that say what they take: every [`crate::Edit`] as data ([`ToolSpec`]: its action,
//! what it acts on, its keys with units, ranges and a one-line help), written once here. Each
//! kind lists the actions it takes ([`crate::Model::tools`]); [`crate::Model::accepts`], the
//! session's "does not apply" error, the studio's tool palette, Python's `Session.tools()` and
//! the kinds column of `docs/formats.md` section 9 (checked by a test) all follow from that list.

use serde::Serialize;

use crate::model::ModelKind;

/// What a tool acts on: how a front end aims it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Target {
    /// A point of the model (the model point nearest a position, or a D-NURBS material point):
    /// a front end picks it under the cursor.
    ModelPoint,
    /// The data points within a radius of a position (a brush).
    Region,
    /// Control points: by id, by a box of rest positions, or the one nearest a position.
    ControlPoints,
    /// A boundary face of the control lattice.
    Face,
    /// A control cell.
    Cell,
    /// Points of the embedded object (FFD), moved exactly.
    EmbeddedPoints,
    /// A rectangle of a patch's parameter domain (PDE local deformation).
    PatchRegion,
    /// The whole model (fields, material, time stepping, named parameters).
    Whole,
    /// A tool or constraint already on the model, by name.
    Named,
}

/// One key of a tool.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct KeySpec {
    /// The key as files and [`crate::Edit`] spell it.
    pub name: &'static str,
    /// What it holds: `"vec3"`, `"number"`, `"integer"`, `"name"`, `"param"` (`[u, v]`),
    /// `"interval"` (`[a, b]`), `"list"`, `"text"`.
    pub value: &'static str,
    /// Unit (`"length"`, `"s"`, `"force"`, ...; `""` where none).
    pub unit: &'static str,
    /// Smallest valid value of a number (or of each component).
    pub min: f64,
    /// Largest valid value.
    pub max: f64,
    /// Whether the tool needs it.
    pub required: bool,
    /// One line.
    pub help: &'static str,
}

/// A tool: one [`crate::Edit`] action as data.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToolSpec {
    /// The `action`.
    pub action: &'static str,
    /// What it acts on.
    pub acts_on: Target,
    /// Its keys.
    pub keys: Vec<KeySpec>,
    /// One line.
    pub help: &'static str,
}

const INF: f64 = f64::INFINITY;

const fn key(
    name: &'static str,
    value: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    required: bool,
    help: &'static str,
) -> KeySpec {
    KeySpec {
        name,
        value,
        unit,
        min,
        max,
        required,
        help,
    }
}

const NAME: KeySpec = key(
    "name",
    "name",
    "",
    0.0,
    0.0,
    false,
    "tool name (default: action<N>)",
);
const UNTIL: KeySpec = key(
    "until",
    "number",
    "s",
    0.0,
    INF,
    false,
    "time it is removed",
);
const NEAR: KeySpec = key(
    "near",
    "vec3",
    "length",
    -INF,
    INF,
    false,
    "the nearest one to this position (current shape)",
);
const PARAM: KeySpec = key(
    "param",
    "param",
    "",
    -INF,
    INF,
    false,
    "D-NURBS material point [u, v]",
);

fn selection() -> Vec<KeySpec> {
    vec![
        key("points", "list", "", 0.0, INF, false, "control point ids"),
        key(
            "min",
            "vec3",
            "length",
            -INF,
            INF,
            false,
            "box corner (rest positions)",
        ),
        key(
            "max",
            "vec3",
            "length",
            -INF,
            INF,
            false,
            "box corner (rest positions)",
        ),
        NEAR,
    ]
}

/// Every action, in the order of `docs/formats.md` section 9.
pub const ACTIONS: [&str; 24] = [
    "rope",
    "move-rope",
    "force",
    "region-force",
    "gravity",
    "inflate",
    "repel",
    "data",
    "release",
    "fix",
    "free",
    "material",
    "extrude",
    "delete-cell",
    "plastic-reset",
    "stop",
    "move-point",
    "set-weight",
    "ffd-move",
    "pde-set",
    "pde-local",
    "set",
    "integrator",
    "constraint",
];

/// The description of `action` (`None` for a name that is no action).
pub fn tool(action: &str) -> Option<ToolSpec> {
    use Target::*;
    let (acts_on, keys, help): (Target, Vec<KeySpec>, &'static str) = match action {
        "rope" => (
            ModelPoint,
            vec![
                key(
                    "from",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    true,
                    "where it grabs, and the cursor's start",
                ),
                PARAM,
                key(
                    "to",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    false,
                    "cursor end position",
                ),
                key(
                    "until",
                    "number",
                    "s",
                    0.0,
                    INF,
                    false,
                    "time the cursor reaches `to`",
                ),
                key(
                    "velocity",
                    "vec3",
                    "length/s",
                    -INF,
                    INF,
                    false,
                    "cursor velocity (not with `to`)",
                ),
                key(
                    "release",
                    "number",
                    "s",
                    0.0,
                    INF,
                    false,
                    "time the rope is removed",
                ),
                key(
                    "stiffness",
                    "number",
                    "force/length",
                    0.0,
                    INF,
                    false,
                    "spring stiffness (> 0)",
                ),
                key(
                    "length",
                    "number",
                    "length",
                    0.0,
                    INF,
                    false,
                    "no force below this length (solids)",
                ),
                key(
                    "kernel",
                    "number",
                    "param",
                    0.0,
                    INF,
                    false,
                    "D-NURBS Gaussian width (> 0)",
                ),
                key(
                    "start",
                    "number",
                    "s",
                    0.0,
                    INF,
                    false,
                    "time the cursor starts moving",
                ),
                NAME,
            ],
            "a spring that only pulls a model point towards a cursor",
        ),
        "move-rope" => (
            Named,
            vec![
                key("name", "name", "", 0.0, 0.0, true, "the rope"),
                key(
                    "to",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    true,
                    "new cursor position",
                ),
            ],
            "moves a rope's cursor (a drag)",
        ),
        "force" => (
            ModelPoint,
            vec![
                NEAR,
                PARAM,
                key("force", "vec3", "force", -INF, INF, true, "the force"),
                UNTIL,
                NAME,
            ],
            "a constant force on one model point",
        ),
        "region-force" => (
            Region,
            vec![
                key("center", "vec3", "length", -INF, INF, true, "brush centre"),
                key("radius", "number", "length", 0.0, INF, true, "brush radius"),
                key(
                    "force",
                    "vec3",
                    "force",
                    -INF,
                    INF,
                    true,
                    "total force, shared",
                ),
                UNTIL,
                NAME,
            ],
            "a total force shared by the data points within a radius",
        ),
        "gravity" => (
            Whole,
            vec![
                key("g", "vec3", "length/s^2", -INF, INF, true, "acceleration"),
                UNTIL,
                NAME,
            ],
            "gravity; an existing name changes its strength",
        ),
        "inflate" => (
            Whole,
            vec![
                key(
                    "pressure",
                    "number",
                    "force/area",
                    -INF,
                    INF,
                    true,
                    "pressure (negative deflates)",
                ),
                UNTIL,
                NAME,
            ],
            "pressure on the boundary surface",
        ),
        "repel" => (
            Whole,
            vec![
                key(
                    "center",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    true,
                    "the repelling point",
                ),
                key(
                    "strength",
                    "number",
                    "force*length^2",
                    -INF,
                    INF,
                    true,
                    "strength (negative attracts)",
                ),
                key(
                    "core",
                    "number",
                    "length",
                    0.0,
                    INF,
                    false,
                    "core radius (> 0, default 0.1)",
                ),
                UNTIL,
                NAME,
            ],
            "repulsion from a point in space",
        ),
        "data" => (
            Whole,
            vec![
                key(
                    "points",
                    "list",
                    "length",
                    -INF,
                    INF,
                    true,
                    "data points (at most 2,000)",
                ),
                key(
                    "stiffness",
                    "number",
                    "force/length",
                    0.0,
                    INF,
                    false,
                    "spring stiffness (> 0)",
                ),
                NAME,
            ],
            "data points, each pulling the nearest model point (fitting)",
        ),
        "release" => (
            Named,
            vec![key(
                "name",
                "name",
                "",
                0.0,
                0.0,
                true,
                "the tool, constraint or deformation",
            )],
            "removes a tool, constraint or local deformation",
        ),
        "fix" => (ControlPoints, selection(), "fixes control points"),
        "free" => (ControlPoints, selection(), "frees control points"),
        "material" => (
            Whole,
            vec![
                key(
                    "cells",
                    "list",
                    "",
                    0.0,
                    INF,
                    false,
                    "control cells (solids)",
                ),
                key(
                    "min",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    false,
                    "box corner (cells whose centroid is inside)",
                ),
                key("max", "vec3", "length", -INF, INF, false, "box corner"),
                key(
                    "density",
                    "number",
                    "mass/volume",
                    0.0,
                    INF,
                    false,
                    "solids: density (> 0)",
                ),
                key(
                    "damping",
                    "number",
                    "1/s",
                    0.0,
                    INF,
                    false,
                    "solids: damping",
                ),
                key(
                    "edge_stiffness",
                    "number",
                    "force/length",
                    0.0,
                    INF,
                    false,
                    "solids: edge springs",
                ),
                key(
                    "virtual_stiffness",
                    "number",
                    "force/length",
                    0.0,
                    INF,
                    false,
                    "solids: virtual springs",
                ),
                key(
                    "anisotropy",
                    "vec3",
                    "",
                    0.0,
                    INF,
                    false,
                    "solids: stiffness scale per axis (> 0)",
                ),
                key(
                    "mu",
                    "number",
                    "mass/area",
                    0.0,
                    INF,
                    false,
                    "D-NURBS: mass density",
                ),
                key(
                    "gamma",
                    "number",
                    "1/s",
                    0.0,
                    INF,
                    false,
                    "D-NURBS: damping density",
                ),
                key(
                    "alpha",
                    "number",
                    "force",
                    0.0,
                    INF,
                    false,
                    "D-NURBS: tension",
                ),
                key(
                    "beta",
                    "number",
                    "force*length^2",
                    0.0,
                    INF,
                    false,
                    "D-NURBS: rigidity",
                ),
            ],
            "changes the material (solids: per control cell)",
        ),
        "extrude" => (
            Face,
            vec![
                key("face", "integer", "", 0.0, INF, false, "face id"),
                NEAR,
                key(
                    "factor",
                    "number",
                    "",
                    0.0,
                    INF,
                    false,
                    "length relative to the face size (default 1)",
                ),
            ],
            "extrudes a boundary face into a new cell",
        ),
        "delete-cell" => (
            Cell,
            vec![key("cell", "integer", "", 0.0, INF, false, "cell id"), NEAR],
            "deletes a control cell (trimming)",
        ),
        "plastic-reset" => (Whole, vec![], "the current shape becomes the rest shape"),
        "stop" => (Whole, vec![], "zeroes all velocities"),
        "move-point" => (
            ControlPoints,
            vec![
                key("index", "integer", "", 0.0, INF, true, "control point"),
                key("to", "vec3", "length", -INF, INF, true, "new position"),
            ],
            "moves a control point directly",
        ),
        "set-weight" => (
            ControlPoints,
            vec![
                key("index", "integer", "", 0.0, INF, true, "control point"),
                key("weight", "number", "", 0.0, INF, true, "new weight (> 0)"),
            ],
            "sets a control point's weight",
        ),
        "ffd-move" => (
            EmbeddedPoints,
            vec![key(
                "moves",
                "list",
                "length",
                -INF,
                INF,
                true,
                "[{from, to}, ...] (at most 1,000)",
            )],
            "moves embedded points exactly to targets (direct FFD)",
        ),
        "pde-set" => (
            Whole,
            vec![
                key(
                    "name",
                    "name",
                    "",
                    0.0,
                    0.0,
                    true,
                    "a boundary constant, or `t`",
                ),
                key("value", "number", "", -INF, INF, true, "its value"),
            ],
            "sets a boundary-function constant or the time",
        ),
        "pde-local" => (
            PatchRegion,
            vec![
                key(
                    "name",
                    "name",
                    "",
                    0.0,
                    0.0,
                    true,
                    "name of the deformation",
                ),
                key(
                    "patch",
                    "integer",
                    "",
                    0.0,
                    INF,
                    false,
                    "patch index (default 0)",
                ),
                key(
                    "u",
                    "interval",
                    "param",
                    0.0,
                    1.0,
                    true,
                    "[u1, u2] inside [0, 1]",
                ),
                key("v", "interval", "param", -INF, INF, true, "[v1, v2]"),
                key(
                    "continuity",
                    "text",
                    "",
                    0.0,
                    0.0,
                    false,
                    "\"G0\" or \"G1\" (default)",
                ),
                key("p", "vec3", "length", -INF, INF, true, "amplitude"),
            ],
            "a local deformation of a PDE patch",
        ),
        "set" => (
            Whole,
            vec![
                key(
                    "name",
                    "name",
                    "",
                    0.0,
                    0.0,
                    true,
                    "a parameter the model lists",
                ),
                key(
                    "value",
                    "number",
                    "",
                    -INF,
                    INF,
                    true,
                    "its value (within the parameter's range)",
                ),
            ],
            "sets a model or simulation parameter",
        ),
        "integrator" => (
            Whole,
            vec![
                key(
                    "integrator",
                    "text",
                    "",
                    0.0,
                    0.0,
                    false,
                    "solids: symplectic, explicit or implicit",
                ),
                key("dt", "number", "s", 0.0, INF, false, "time step (> 0)"),
            ],
            "switches integrator or time step",
        ),
        "constraint" => (
            ModelPoint,
            vec![
                key(
                    "type",
                    "text",
                    "",
                    0.0,
                    0.0,
                    true,
                    "\"point\" or \"normal\"",
                ),
                key(
                    "param",
                    "param",
                    "",
                    -INF,
                    INF,
                    true,
                    "material point [u, v]",
                ),
                key(
                    "target",
                    "vec3",
                    "length",
                    -INF,
                    INF,
                    false,
                    "point constraint: the position",
                ),
                key(
                    "normal",
                    "vec3",
                    "",
                    -INF,
                    INF,
                    false,
                    "normal constraint: the direction",
                ),
                NAME,
            ],
            "a geometric constraint (point or normal)",
        ),
        _ => return None,
    };
    Some(ToolSpec {
        action: ACTIONS
            .iter()
            .copied()
            .find(|a| *a == action)
            .expect("every described action is listed"),
        acts_on,
        keys,
        help,
    })
}

const SOLID: &[&str] = &[
    "rope",
    "move-rope",
    "force",
    "region-force",
    "gravity",
    "inflate",
    "release",
    "fix",
    "free",
    "material",
    "plastic-reset",
    "stop",
    "move-point",
    "set",
    "integrator",
];
const SUBDIVISION: &[&str] = &[
    "rope",
    "move-rope",
    "force",
    "region-force",
    "gravity",
    "inflate",
    "release",
    "fix",
    "free",
    "material",
    "extrude",
    "delete-cell",
    "plastic-reset",
    "stop",
    "move-point",
    "set",
    "integrator",
];
const DNURBS_SURFACE: &[&str] = &[
    "rope",
    "move-rope",
    "force",
    "gravity",
    "inflate",
    "repel",
    "data",
    "release",
    "fix",
    "free",
    "material",
    "plastic-reset",
    "stop",
    "move-point",
    "set-weight",
    "set",
    "integrator",
    "constraint",
];
const DNURBS_CURVE: &[&str] = &[
    "rope",
    "move-rope",
    "force",
    "gravity",
    "repel",
    "data",
    "release",
    "fix",
    "free",
    "material",
    "plastic-reset",
    "stop",
    "move-point",
    "set-weight",
    "set",
    "integrator",
    "constraint",
];

/// The actions a model of `kind` takes. A model may still refuse one with a reason (the
/// frozen-weight D-NURBS engine holds its weights and has no constraints).
pub fn actions(kind: ModelKind) -> &'static [&'static str] {
    match kind {
        ModelKind::SubdivisionSolid => SUBDIVISION,
        ModelKind::BsplineSolid => SOLID,
        ModelKind::DnurbsSurface | ModelKind::DnurbsSwung => DNURBS_SURFACE,
        ModelKind::DnurbsCurve => DNURBS_CURVE,
        ModelKind::Ffd => &["ffd-move", "move-point", "set-weight", "set"],
        ModelKind::PdeSurface => &["pde-set", "pde-local", "release", "set"],
        ModelKind::DnurbsTriangular => &["set"],
        ModelKind::DnurbsPatches => &[
            "rope",
            "move-rope",
            "force",
            "release",
            "fix",
            "free",
            "set",
        ],
    }
}

/// The descriptions of `actions` (each must be an action), with every key.
pub fn tools(actions: &[&str]) -> Vec<ToolSpec> {
    actions.iter().filter_map(|a| tool(a)).collect()
}

/// Keys of an action that a kind does not take.
fn keys_not_taken(kind: ModelKind, action: &str) -> &'static [&'static str] {
    let solid = matches!(kind, ModelKind::SubdivisionSolid | ModelKind::BsplineSolid);
    const DNURBS_MATERIAL: &[&str] = &[
        "cells",
        "min",
        "max",
        "density",
        "damping",
        "edge_stiffness",
        "virtual_stiffness",
        "anisotropy",
    ];
    match (action, kind) {
        ("rope", _) if solid => &["param", "kernel"],
        ("rope", ModelKind::DnurbsPatches) => &["velocity", "length", "kernel"],
        ("rope", _) => &["length"],
        ("force", _) if solid => &["param"],
        ("integrator", _) if !solid => &["integrator"],
        ("material", _) if solid => &["mu", "gamma", "alpha", "beta"],
        ("material", _) => DNURBS_MATERIAL,
        _ => &[],
    }
}

/// What a model of `kind` takes: its [`actions`] described with the keys the kind takes
/// (solids' ropes have no material point `param`, D-NURBS ropes no `length`; a solid's
/// `material` acts on control cells, a D-NURBS's on the whole model).
pub fn tools_for(kind: ModelKind) -> Vec<ToolSpec> {
    let solid = matches!(kind, ModelKind::SubdivisionSolid | ModelKind::BsplineSolid);
    actions(kind)
        .iter()
        .filter_map(|a| tool(a))
        .map(|mut t| {
            let skip = keys_not_taken(kind, t.action);
            t.keys.retain(|k| !skip.contains(&k.name));
            if t.action == "material" && solid {
                t.acts_on = Target::Cell;
            }
            t
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_edit_action_is_described() {
        for a in ACTIONS {
            let t = tool(a).unwrap_or_else(|| panic!("{a}"));
            assert_eq!(t.action, a);
            for k in &t.keys {
                assert!(k.min <= k.max, "{a}.{}", k.name);
            }
        }
        assert!(tool("paint").is_none());
        for k in ModelKind::ALL {
            assert_eq!(tools_for(k).len(), actions(k).len(), "{k}");
        }
        let rope = |k| {
            tools_for(k)
                .into_iter()
                .find(|t| t.action == "rope")
                .unwrap()
        };
        let has = |t: &ToolSpec, key: &str| t.keys.iter().any(|k| k.name == key);
        assert!(has(&rope(ModelKind::DnurbsSurface), "param"));
        assert!(!has(&rope(ModelKind::SubdivisionSolid), "param"));
        assert!(has(&rope(ModelKind::SubdivisionSolid), "length"));
    }
}
