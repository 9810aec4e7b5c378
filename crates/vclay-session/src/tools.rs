//! Named tools and their schedules, shared by every model kind: a tool's name, the kernel's
//! handle for it, a cursor path (a rope whose cursor moves by itself) and a release time.
//! Before each step a model asks [`ToolTable::due`] which tools expire and where the moving
//! cursors are now.

use serde::{Deserialize, Serialize};
use vclay_core::Vec3;

use crate::command::{RopeRequest, V3};

/// How a rope's cursor moves by itself.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "path", rename_all = "kebab-case")]
pub enum CursorPath {
    /// From `from` at time `start` to `to` at time `end`, linearly, then stays.
    Linear {
        /// Start position.
        from: V3,
        /// End position.
        to: V3,
        /// Start time.
        start: f64,
        /// End time.
        end: f64,
    },
    /// At `from + velocity t` at time `t`.
    Velocity {
        /// Position at time 0.
        from: V3,
        /// Velocity.
        velocity: V3,
    },
}

impl CursorPath {
    /// The cursor at time `t`.
    pub fn at(&self, t: f64) -> Vec3 {
        match *self {
            CursorPath::Linear {
                from,
                to,
                start,
                end,
            } => {
                let (from, to) = (v3(from), v3(to));
                let s = if end > start {
                    ((t - start) / (end - start)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                from + (to - from) * s
            }
            CursorPath::Velocity { from, velocity } => v3(from) + v3(velocity) * t,
        }
    }
}

/// One named tool.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScheduledTool {
    /// Name.
    pub name: String,
    /// The action that made it (`rope`, `force`, ...).
    pub action: String,
    /// The kernel's handle (solids: tool id; D-NURBS: an id the model maps to its forces).
    pub handle: usize,
    /// A moving cursor (ropes), moved before each step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<CursorPath>,
    /// Release time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release: Option<f64>,
}

/// The named tools of one model.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ToolTable {
    /// Tools in the order they were added.
    pub tools: Vec<ScheduledTool>,
}

/// What is due before a step.
#[derive(Debug, Default)]
pub struct Due {
    /// Tools whose release time has come (already removed from the table).
    pub expired: Vec<ScheduledTool>,
    /// Cursor positions of the moving ropes: `(handle, position)`.
    pub cursors: Vec<(usize, Vec3)>,
}

impl ToolTable {
    /// The tool named `name`.
    pub fn get(&self, name: &str) -> Option<&ScheduledTool> {
        self.tools.iter().find(|t| t.name == name)
    }

    /// The tool named `name`, mutably.
    pub fn get_mut(&mut self, name: &str) -> Option<&mut ScheduledTool> {
        self.tools.iter_mut().find(|t| t.name == name)
    }

    /// Removes and returns the tool named `name`.
    pub fn remove(&mut self, name: &str) -> Option<ScheduledTool> {
        let i = self.tools.iter().position(|t| t.name == name)?;
        Some(self.tools.remove(i))
    }

    /// The name for a new tool: `name` if given (an error if taken), else `what` followed by
    /// the handle.
    pub fn label(&self, name: Option<&str>, what: &str, handle: usize) -> Result<String, String> {
        match name {
            Some(n) if self.get(n).is_some() => Err(format!(
                "a tool named `{n}` is already active (release it first)"
            )),
            Some("") => Err("a tool name must not be empty".into()),
            Some(n) => Ok(n.to_string()),
            None => {
                let mut label = format!("{what}{handle}");
                let mut k = 1;
                while self.get(&label).is_some() {
                    label = format!("{what}{handle}_{k}");
                    k += 1;
                }
                Ok(label)
            }
        }
    }

    /// Adds a tool entry (its forces already attached under `handle`).
    pub fn track(
        &mut self,
        name: &str,
        action: &str,
        handle: usize,
        path: Option<CursorPath>,
        release: Option<f64>,
    ) {
        self.tools.push(ScheduledTool {
            name: name.to_string(),
            action: action.to_string(),
            handle,
            path,
            release,
        });
    }

    /// The handle of the rope named `name` (an error names what the name is if not a rope).
    pub fn rope(&self, name: &str) -> Result<usize, String> {
        let t = self
            .get(name)
            .ok_or_else(|| format!("no active rope named `{name}`"))?;
        if t.action != "rope" {
            return Err(format!("`{name}` is a {}, not a rope", t.action));
        }
        Ok(t.handle)
    }

    /// Removes the tools released at or before `t + dt / 2` and returns them with the cursor
    /// positions of the remaining moving ropes at `t` (the order the scenario runner has always
    /// used: commands of the step first, then expiry, then cursors).
    pub fn due(&mut self, t: f64, dt: f64) -> Due {
        let mut due = Due::default();
        let limit = t + 0.5 * dt;
        let mut k = 0;
        while k < self.tools.len() {
            if self.tools[k].release.is_some_and(|r| r <= limit) {
                due.expired.push(self.tools.remove(k));
            } else {
                k += 1;
            }
        }
        for tool in &self.tools {
            if let Some(p) = &tool.path {
                due.cursors.push((tool.handle, p.at(t)));
            }
        }
        due
    }
}

/// A `Vec3` from an array.
pub fn v3(a: V3) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// An array from a `Vec3`.
pub fn a3(v: &Vec3) -> V3 {
    [v.x, v.y, v.z]
}

/// The control net of a model, as the shared fix/free tool sees it (D-NURBS curves, surfaces,
/// swung surfaces and patches; subdivision and B-spline solids).
pub(crate) trait ControlNet {
    /// The control points at the current state.
    fn current_points(&self) -> Vec<Vec3>;
    /// The control points of the rest shape.
    fn rest_points(&self) -> Vec<Vec3>;
    /// Whether control point `i` is fixed.
    fn is_fixed(&self, i: usize) -> bool;
    /// Fixes or frees control points `ids` (all or none: on an error nothing changed).
    fn set_fixed(&mut self, ids: &[usize], fix: bool) -> Result<(), crate::SessionError>;
}

/// The control points a `fix`/`free` selection names ([`crate::Edit::Fix`]): ids (`points`);
/// a box of **rest** positions (`min`/`max`, as the file format says, so a scenario's box
/// means the same points whatever has moved); or what a person points at, by **current**
/// position: the point nearest `near`, or, with `radius`, every point within `radius` of it
/// (a brush). The one rule for every kind.
pub(crate) fn select_points<N: ControlNet + ?Sized>(
    net: &N,
    sel: &crate::command::Selection,
) -> Result<Vec<usize>, String> {
    let current = net.current_points();
    let n = current.len();
    if let Some(p) = &sel.points {
        if let Some(&i) = p.iter().find(|&&i| i >= n) {
            return Err(format!("control point {i} does not exist (there are {n})"));
        }
        return Ok(p.clone());
    }
    if let (Some(lo), Some(hi)) = (sel.min, sel.max) {
        let rest = net.rest_points();
        return Ok((0..n)
            .filter(|&i| (0..3).all(|a| rest[i][a] >= lo[a] && rest[i][a] <= hi[a]))
            .collect());
    }
    let Some(x) = sel.near else {
        return Ok(Vec::new());
    };
    let x = v3(x);
    Ok(match sel.radius {
        Some(r) => (0..n).filter(|&i| (current[i] - x).norm() <= r).collect(),
        None => (0..n)
            .min_by(|&a, &b| (current[a] - x).norm().total_cmp(&(current[b] - x).norm()))
            .into_iter()
            .collect(),
    })
}

/// What [`fix_or_free`] did.
pub(crate) struct FixResult {
    /// The points selected.
    pub selected: Vec<usize>,
    /// The exact inverse: free (or fix) the points whose state changed.
    pub inverse: crate::Edit,
}

/// The log line of a [`fix_or_free`]: "fixed 3 control points" or "freed 3 control points".
pub(crate) fn fixed_message(edit: &crate::Edit, r: &FixResult) -> String {
    let fix = matches!(edit, crate::Edit::Fix { .. });
    format!(
        "{} {} control points",
        if fix { "fixed" } else { "freed" },
        r.selected.len()
    )
}

/// Applies a [`crate::Edit::Fix`] or [`crate::Edit::Free`] to `net`: the selection of
/// [`select_points`], then the change; returns what was selected and the exact inverse.
pub(crate) fn fix_or_free<N: ControlNet + ?Sized>(
    net: &mut N,
    edit: &crate::Edit,
) -> Result<FixResult, crate::SessionError> {
    use crate::Edit;
    let (fix, sel) = match edit {
        Edit::Fix(sel) => (true, sel),
        Edit::Free(sel) => (false, sel),
        _ => return Err(crate::SessionError::model("not a fix or free edit")),
    };
    let selected = select_points(net, sel).map_err(|e| crate::SessionError::command("", "", e))?;
    let changed: Vec<usize> = selected
        .iter()
        .copied()
        .filter(|&i| net.is_fixed(i) != fix)
        .collect();
    net.set_fixed(&selected, fix)?;
    let ids = crate::command::Selection::ids(changed);
    let inverse = if fix { Edit::Free(ids) } else { Edit::Fix(ids) };
    Ok(FixResult { selected, inverse })
}

fn cmd(reason: impl std::fmt::Display) -> crate::SessionError {
    crate::SessionError::command("", "", reason)
}

/// A model whose tools a [`ToolTable`] names, as the shared `rope`, `move-rope`, `force`,
/// `release` and field-tool (`gravity`, `inflate`, ...) edits see it ([`tool_edit`],
/// [`field_tool`]): D-NURBS curves and surfaces (a handle is a slot of force descriptions) and
/// solids (a handle is the kernel's tool id). The kind attaches and detaches forces; the
/// naming, the schedule (cursor paths, release times) and the messages are shared.
pub(crate) trait ToolHost {
    /// A field tool's force (gravity, inflation, repulsion), as the kind describes it.
    type Field;
    /// The named tools.
    fn table(&self) -> &ToolTable;
    /// The named tools, mutably.
    fn table_mut(&mut self) -> &mut ToolTable;
    /// The name for a new tool: [`ToolTable::label`] (kinds with other named things add their
    /// own rule).
    fn label(&self, name: Option<&str>, what: &str, handle: usize) -> Result<String, String> {
        self.table().label(name, what, handle)
    }
    /// Attaches the spring of a rope; returns its handle, its cursor path and where it holds
    /// (`"to data point 3"`, `"at material point [0.5, 0.5]"`).
    fn attach_rope(
        &mut self,
        rope: &RopeRequest,
    ) -> Result<(usize, Option<CursorPath>, String), crate::SessionError>;
    /// Attaches the force of an [`crate::Edit::Force`]; returns its handle and where it acts
    /// (`"on data point 3"`, `"at material point [0.5, 0.5]"`).
    fn attach_force(&mut self, edit: &crate::Edit) -> Result<(usize, String), crate::SessionError>;
    /// Attaches a field tool's force; returns its handle.
    fn attach_field(&mut self, field: Self::Field) -> Result<usize, crate::SessionError>;
    /// Replaces the force of field tool `handle`; returns the handle it has now.
    fn replace_field(
        &mut self,
        handle: usize,
        field: Self::Field,
    ) -> Result<usize, crate::SessionError>;
    /// Moves the cursor of rope `handle` to `to` (it stops following its path).
    fn move_cursor(&mut self, handle: usize, to: V3) -> Result<(), crate::SessionError>;
    /// Removes the forces of tool `handle`.
    fn detach(&mut self, handle: usize);
    /// Takes back tool `handle` just attached (its name was refused): as if never attached.
    fn take_back(&mut self, handle: usize) {
        self.detach(handle);
    }
    /// Releases something named `name` that is not a tool (D-NURBS constraints); the error
    /// when there is none.
    fn release_other(&mut self, name: &str) -> Result<(), crate::SessionError> {
        Err(cmd(format!("no active tool named `{name}`")))
    }
}

/// Whether `edit` is one of [`tool_edit`]'s: `rope`, `move-rope`, `force` or `release`.
pub(crate) fn is_tool_edit(edit: &crate::Edit) -> bool {
    use crate::Edit;
    matches!(
        edit,
        Edit::Rope { .. } | Edit::MoveRope { .. } | Edit::Force { .. } | Edit::Release { .. }
    )
}

/// The [`ToolHost`] accessors of a kind whose [`ToolTable`] is the field named (a path of
/// fields: `tools`, `ed.tools`): inside `impl ToolHost for Kind`.
macro_rules! tool_table {
    ($($field:ident).+) => {
        fn table(&self) -> &$crate::tools::ToolTable {
            &self.$($field).+
        }
        fn table_mut(&mut self) -> &mut $crate::tools::ToolTable {
            &mut self.$($field).+
        }
    };
}
pub(crate) use tool_table;

/// The name of tool `handle` just attached; if refused, the tool is taken back.
fn name_new<H: ToolHost + ?Sized>(
    host: &mut H,
    name: Option<&str>,
    what: &str,
    handle: usize,
) -> Result<String, crate::SessionError> {
    host.label(name, what, handle).map_err(|e| {
        host.take_back(handle);
        cmd(e)
    })
}

/// Applies `rope`, `move-rope`, `force` or `release` to `host` (the one implementation for
/// every kind with a [`ToolTable`]); returns the log line.
pub(crate) fn tool_edit<H: ToolHost + ?Sized>(
    host: &mut H,
    edit: &crate::Edit,
) -> Result<String, crate::SessionError> {
    use crate::Edit;
    match edit {
        Edit::Rope { .. } => {
            let (rope, name, release) = RopeRequest::of(edit).expect("a rope");
            let (h, path, at) = host.attach_rope(&rope)?;
            let label = name_new(host, name, "rope", h)?;
            host.table_mut().track(&label, "rope", h, path, release);
            Ok(format!("rope `{label}` attached {at}"))
        }
        Edit::MoveRope { name, to } => {
            let h = host.table().rope(name).map_err(cmd)?;
            host.move_cursor(h, *to)?;
            host.table_mut().get_mut(name).expect("present").path = None;
            Ok(format!("rope `{name}` cursor at {to:?}"))
        }
        Edit::Force { name, until, .. } => {
            let (h, at) = host.attach_force(edit)?;
            let label = name_new(host, name.as_deref(), "force", h)?;
            host.table_mut().track(&label, "force", h, None, *until);
            Ok(format!("force `{label}` {at}"))
        }
        Edit::Release { name } => {
            match host.table_mut().remove(name) {
                Some(t) => host.detach(t.handle),
                None => host.release_other(name)?,
            }
            Ok(format!("released `{name}`"))
        }
        _ => Err(crate::models::misrouted()),
    }
}

/// A field tool (`gravity`, `inflate`, `repel`): a tool named `name` that exists already
/// (of the same action) changes its force, else a new tool starts; `until` is its release
/// time (kept when not given for an existing tool). Returns the log line.
pub(crate) fn field_tool<H: ToolHost + ?Sized>(
    host: &mut H,
    name: &Option<String>,
    action: &str,
    field: H::Field,
    until: Option<f64>,
) -> Result<String, crate::SessionError> {
    if let Some(n) = name
        && let Some(t) = host.table().get(n).cloned()
    {
        if t.action != action {
            return Err(cmd(format!(
                "the tool `{n}` is a {}, not {action}",
                t.action
            )));
        }
        let h = host.replace_field(t.handle, field)?;
        let e = host.table_mut().get_mut(n).expect("present");
        e.handle = h;
        e.release = until.or(e.release);
        return Ok(format!("{action} `{n}` changed"));
    }
    let h = host.attach_field(field)?;
    let label = name_new(host, name.as_deref(), action, h)?;
    host.table_mut().track(&label, action, h, None, until);
    Ok(format!("{action} `{label}` on"))
}
