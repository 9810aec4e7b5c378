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
    /// A face of a CAD part (a trimmed B-rep face), hit through the part's surface.
    PartFace,
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
    /// The values a `"text"` key takes (empty: any text).
    pub choices: &'static [&'static str],
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
        choices: &[],
    }
}

/// The region force's falloff names (`vclay_solids::Falloff`), constant first (the default).
pub const FALLOFFS: &[&str] = &["constant", "smooth", "linear", "sphere", "sharp"];

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

#[rustfmt::skip]
const SELECTION: &[KeySpec] = &[
    key("points", "list", "", 0.0, INF, false, "control point ids"),
    key("min", "vec3", "length", -INF, INF, false, "box corner (rest positions)"),
    key("max", "vec3", "length", -INF, INF, false, "box corner (rest positions)"),
    NEAR,
    key("radius", "number", "length", 0.0, INF, false, "with `near`: every point within it, current positions (a brush)"),
];

#[rustfmt::skip]
const SMOOTH_KEYS: &[KeySpec] = &[
    key("near", "vec3", "length", -INF, INF, true, "brush centre (current positions)"),
    key("radius", "number", "length", 0.0, INF, true, "brush radius (0: the nearest point)"),
    key("strength", "number", "", 0.0, 1.0, false, "share of the step to the neighbours' mean (0.5)"),
];

/// Every action, in the order of `docs/formats.md` section 9.
#[rustfmt::skip]
pub const ACTIONS: [&str; 26] = [
    "rope", "move-rope", "force", "region-force", "gravity", "inflate", "repel", "data",
    "release", "fix", "free", "smooth", "material", "extrude", "delete-cell", "sculpt-face", "plastic-reset", "stop",
    "move-point", "set-weight", "ffd-move", "pde-set", "pde-local", "set", "integrator",
    "constraint",
];

#[rustfmt::skip]
const ROPE_KEYS: &[KeySpec] = &[
    key("from", "vec3", "length", -INF, INF, true, "where it grabs, and the cursor's start"),
    PARAM,
    key("to", "vec3", "length", -INF, INF, false, "cursor end position"),
    key("until", "number", "s", 0.0, INF, false, "time the cursor reaches `to`"),
    key("velocity", "vec3", "length/s", -INF, INF, false, "cursor velocity (not with `to`)"),
    key("release", "number", "s", 0.0, INF, false, "time the rope is removed"),
    key("stiffness", "number", "force/length", 0.0, INF, false, "spring stiffness (> 0)"),
    key("length", "number", "length", 0.0, INF, false, "no force below this length (solids)"),
    key("kernel", "number", "param", 0.0, INF, false, "D-NURBS Gaussian width (> 0)"),
    key("start", "number", "s", 0.0, INF, false, "time the cursor starts moving"),
    NAME,
];

#[rustfmt::skip]
const MOVE_ROPE_KEYS: &[KeySpec] = &[
    key("name", "name", "", 0.0, 0.0, true, "the rope"),
    key("to", "vec3", "length", -INF, INF, true, "new cursor position"),
];

#[rustfmt::skip]
const FORCE_KEYS: &[KeySpec] = &[
    NEAR,
    PARAM,
    key("force", "vec3", "force", -INF, INF, true, "the force"),
    UNTIL,
    NAME,
];

#[rustfmt::skip]
const REGION_FORCE_KEYS: &[KeySpec] = &[
    key("center", "vec3", "length", -INF, INF, true, "brush centre"),
    key("radius", "number", "length", 0.0, INF, true, "brush radius"),
    key("force", "vec3", "force", -INF, INF, true, "total force, shared"),
    UNTIL,
    KeySpec {
        choices: FALLOFFS,
        ..key("falloff", "text", "", 0.0, 0.0, false, "how the share falls off from the centre")
    },
    NAME,
];

#[rustfmt::skip]
const GRAVITY_KEYS: &[KeySpec] = &[
    key("g", "vec3", "length/s^2", -INF, INF, true, "acceleration"),
    UNTIL,
    NAME,
];

#[rustfmt::skip]
const INFLATE_KEYS: &[KeySpec] = &[
    key("pressure", "number", "force/area", -INF, INF, true, "pressure (negative deflates)"),
    UNTIL,
    NAME,
];

#[rustfmt::skip]
const REPEL_KEYS: &[KeySpec] = &[
    key("center", "vec3", "length", -INF, INF, true, "the repelling point"),
    key("strength", "number", "force*length^2", -INF, INF, true, "strength (negative attracts)"),
    key("core", "number", "length", 0.0, INF, false, "core radius (> 0, default 0.1)"),
    UNTIL,
    NAME,
];

#[rustfmt::skip]
const DATA_KEYS: &[KeySpec] = &[
    key("points", "list", "length", -INF, INF, true, "data points (at most 2,000)"),
    key("stiffness", "number", "force/length", 0.0, INF, false, "spring stiffness (> 0)"),
    NAME,
];

#[rustfmt::skip]
const RELEASE_KEYS: &[KeySpec] = &[
    key("name", "name", "", 0.0, 0.0, true, "the tool, constraint or deformation"),
];

#[rustfmt::skip]
const MATERIAL_KEYS: &[KeySpec] = &[
    key("cells", "list", "", 0.0, INF, false, "control cells (solids)"),
    key("min", "vec3", "length", -INF, INF, false, "box corner (cells whose centroid is inside)"),
    key("max", "vec3", "length", -INF, INF, false, "box corner"),
    key("density", "number", "mass/volume", 0.0, INF, false, "solids: density (> 0)"),
    key("damping", "number", "1/s", 0.0, INF, false, "solids: damping"),
    key("edge_stiffness", "number", "force/length", 0.0, INF, false, "solids: edge springs"),
    key("virtual_stiffness", "number", "force/length", 0.0, INF, false, "solids: virtual springs"),
    key("anisotropy", "vec3", "", 0.0, INF, false, "solids: stiffness scale per axis (> 0)"),
    key("mu", "number", "mass/area", 0.0, INF, false, "D-NURBS: mass density"),
    key("gamma", "number", "1/s", 0.0, INF, false, "D-NURBS: damping density"),
    key("alpha", "number", "force", 0.0, INF, false, "D-NURBS: tension"),
    key("beta", "number", "force*length^2", 0.0, INF, false, "D-NURBS: rigidity"),
];

#[rustfmt::skip]
const EXTRUDE_KEYS: &[KeySpec] = &[
    key("face", "integer", "", 0.0, INF, false, "face id"),
    NEAR,
    key("factor", "number", "", 0.0, INF, false, "length relative to the face size (default 1)"),
];

#[rustfmt::skip]
const SCULPT_FACE_KEYS: &[KeySpec] = &[
    key("face", "integer", "", 0.0, INF, false, "face index in the sculpted shell"),
    NEAR,
];

#[rustfmt::skip]
const DELETE_CELL_KEYS: &[KeySpec] = &[
    key("cell", "integer", "", 0.0, INF, false, "cell id"),
    NEAR,
];

#[rustfmt::skip]
const PLASTIC_RESET_KEYS: &[KeySpec] = &[

];

#[rustfmt::skip]
const STOP_KEYS: &[KeySpec] = &[

];

#[rustfmt::skip]
const MOVE_POINT_KEYS: &[KeySpec] = &[
    key("index", "integer", "", 0.0, INF, true, "control point"),
    key("to", "vec3", "length", -INF, INF, true, "new position"),
];

#[rustfmt::skip]
const SET_WEIGHT_KEYS: &[KeySpec] = &[
    key("index", "integer", "", 0.0, INF, true, "control point"),
    key("weight", "number", "", 0.0, INF, true, "new weight (> 0)"),
];

#[rustfmt::skip]
const FFD_MOVE_KEYS: &[KeySpec] = &[
    key("moves", "list", "length", -INF, INF, true, "[{from, to}, ...] (at most 1,000)"),
];

#[rustfmt::skip]
const PDE_SET_KEYS: &[KeySpec] = &[
    key("name", "name", "", 0.0, 0.0, true, "a boundary constant, or `t`"),
    key("value", "number", "", -INF, INF, true, "its value"),
];

#[rustfmt::skip]
const PDE_LOCAL_KEYS: &[KeySpec] = &[
    key("name", "name", "", 0.0, 0.0, true, "name of the deformation"),
    key("patch", "integer", "", 0.0, INF, false, "patch index (default 0)"),
    key("u", "interval", "param", 0.0, 1.0, true, "[u1, u2] inside [0, 1]"),
    key("v", "interval", "param", -INF, INF, true, "[v1, v2]"),
    key("continuity", "text", "", 0.0, 0.0, false, "\"G0\" or \"G1\" (default)"),
    key("p", "vec3", "length", -INF, INF, true, "amplitude"),
];

#[rustfmt::skip]
const SET_KEYS: &[KeySpec] = &[
    key("name", "name", "", 0.0, 0.0, true, "a parameter the model lists"),
    key("value", "number", "", -INF, INF, true, "its value (within the parameter's range)"),
];

#[rustfmt::skip]
const INTEGRATOR_KEYS: &[KeySpec] = &[
    key("integrator", "text", "", 0.0, 0.0, false, "solids: symplectic, explicit or implicit"),
    key("dt", "number", "s", 0.0, INF, false, "time step (> 0)"),
];

#[rustfmt::skip]
const CONSTRAINT_KEYS: &[KeySpec] = &[
    key("type", "text", "", 0.0, 0.0, true, "\"point\" or \"normal\""),
    key("param", "param", "", -INF, INF, true, "material point [u, v]"),
    key("target", "vec3", "length", -INF, INF, false, "point constraint: the position"),
    key("normal", "vec3", "", -INF, INF, false, "normal constraint: the direction"),
    NAME,
];

/// The description of `action` (`None` for a name that is no action).
pub fn tool(action: &str) -> Option<ToolSpec> {
    use Target::*;
    #[rustfmt::skip]
    let (acts_on, keys, help): (Target, &[KeySpec], &'static str) = match action {
        "rope" => (ModelPoint, ROPE_KEYS, "a spring that only pulls a model point towards a cursor"),
        "move-rope" => (Named, MOVE_ROPE_KEYS, "moves a rope's cursor (a drag)"),
        "force" => (ModelPoint, FORCE_KEYS, "a constant force on one model point"),
        "region-force" => (Region, REGION_FORCE_KEYS, "a total force shared by the data points within a radius"),
        "gravity" => (Whole, GRAVITY_KEYS, "gravity; an existing name changes its strength"),
        "inflate" => (Whole, INFLATE_KEYS, "pressure on the boundary surface"),
        "repel" => (Whole, REPEL_KEYS, "repulsion from a point in space"),
        "data" => (Whole, DATA_KEYS, "data points, each pulling the nearest model point (fitting)"),
        "release" => (Named, RELEASE_KEYS, "removes a tool, constraint or local deformation"),
        "fix" => (ControlPoints, SELECTION, "fixes control points"),
        "smooth" => (ControlPoints, SMOOTH_KEYS, "smooths the rest shape under a brush; the clay settles to it"),
        "free" => (ControlPoints, SELECTION, "frees control points"),
        "material" => (Whole, MATERIAL_KEYS, "changes the material (solids: per control cell)"),
        "extrude" => (Face, EXTRUDE_KEYS, "extrudes a boundary face into a new cell"),
        "delete-cell" => (Cell, DELETE_CELL_KEYS, "deletes a control cell (trimming)"),
        "sculpt-face" => (PartFace, SCULPT_FACE_KEYS, "chooses the face of a CAD part that is sculpted"),
        "plastic-reset" => (Whole, PLASTIC_RESET_KEYS, "the current shape becomes the rest shape"),
        "stop" => (Whole, STOP_KEYS, "zeroes all velocities"),
        "move-point" => (ControlPoints, MOVE_POINT_KEYS, "moves a control point directly"),
        "set-weight" => (ControlPoints, SET_WEIGHT_KEYS, "sets a control point's weight"),
        "ffd-move" => (EmbeddedPoints, FFD_MOVE_KEYS, "moves embedded points exactly to targets (direct FFD)"),
        "pde-set" => (Whole, PDE_SET_KEYS, "sets a boundary-function constant or the time"),
        "pde-local" => (PatchRegion, PDE_LOCAL_KEYS, "a local deformation of a PDE patch"),
        "set" => (Whole, SET_KEYS, "sets a model or simulation parameter"),
        "integrator" => (Whole, INTEGRATOR_KEYS, "switches integrator or time step"),
        "constraint" => (ModelPoint, CONSTRAINT_KEYS, "a geometric constraint (point or normal)"),
        _ => return None,
    };
    Some(ToolSpec {
        action: ACTIONS.iter().copied().find(|a| *a == action)?,
        acts_on,
        keys: keys.to_vec(),
        help,
    })
}

/// What a subdivision solid takes; a B-spline solid takes the same but for the topology edits.
#[rustfmt::skip]
const SUBDIVISION: &[&str] = &[
    "rope", "move-rope", "force", "region-force", "gravity", "inflate", "release", "fix",
    "free", "smooth", "material", "extrude", "delete-cell", "plastic-reset", "stop", "move-point", "set",
    "integrator",
];
/// What a D-NURBS surface takes; a curve takes the same but for inflation (it has no inside).
#[rustfmt::skip]
const DNURBS_SURFACE: &[&str] = &[
    "rope", "move-rope", "force", "gravity", "inflate", "repel", "data", "release", "fix",
    "free", "smooth", "material", "plastic-reset", "stop", "move-point", "set-weight", "set",
    "integrator", "constraint",
];

/// The actions a model of `kind` takes, in the order of [`ACTIONS`]. A model may still refuse
/// one with a reason (the frozen-weight D-NURBS engine holds its weights and has no
/// constraints).
pub fn actions(kind: ModelKind) -> Vec<&'static str> {
    let but = |list: &[&'static str], not: &[&str]| -> Vec<&'static str> {
        list.iter().copied().filter(|a| !not.contains(a)).collect()
    };
    match kind {
        ModelKind::SubdivisionSolid => SUBDIVISION.to_vec(),
        ModelKind::BsplineSolid => but(SUBDIVISION, &["extrude", "delete-cell"]),
        ModelKind::DnurbsSurface => DNURBS_SURFACE.to_vec(),
        // A swung surface's coordinates are its two curves' (eq 7), not the net it shows.
        ModelKind::DnurbsSwung => but(DNURBS_SURFACE, &["smooth"]),
        ModelKind::DnurbsCurve => but(DNURBS_SURFACE, &["inflate"]),
        ModelKind::Ffd => vec!["ffd-move", "move-point", "set-weight", "set"],
        ModelKind::PdeSurface => vec!["pde-set", "pde-local", "release", "set"],
        ModelKind::DnurbsTriangular => vec!["set"],
        // A CAD part's face: a D-NURBS surface whose weights are held (set-weight) and which
        // has no inside of its own (inflate) and fits no data.
        ModelKind::CadPart => {
            let face = but(DNURBS_SURFACE, &["inflate", "data", "set-weight"]);
            ACTIONS
                .into_iter()
                .filter(|a| *a == "sculpt-face" || face.contains(a))
                .collect()
        }
        ModelKind::DnurbsPatches => but(
            DNURBS_SURFACE,
            &[
                "smooth",
                "gravity",
                "inflate",
                "repel",
                "data",
                "material",
                "plastic-reset",
                "stop",
                "move-point",
                "set-weight",
                "integrator",
                "constraint",
            ],
        ),
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
        .into_iter()
        .filter_map(tool)
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
    #[test]
    fn the_falloff_choices_are_the_kernels() {
        let kernel: Vec<&str> = vclay_solids::Falloff::ALL.map(|f| f.name()).to_vec();
        assert_eq!(super::FALLOFFS, kernel.as_slice());
    }

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
