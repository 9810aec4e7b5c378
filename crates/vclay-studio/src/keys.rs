//! The studio's keyboard shortcuts: one table, read by the key handler
//! (`Studio::shortcuts`) and by the help overlay (F1 or ?), so the two never disagree.
//!
//! The habits are Blender sculpt mode's and SculptGL's where they fit: `[` and `]` shrink and
//! grow the brush, X / Y / Z toggle symmetry, F frames the model, Space runs or pauses, one
//! letter per tool. Keys act only while no dialog is open and no text field has the keyboard
//! focus (a path typed in the open dialog is not a stream of tool changes).

use egui::Key;

use crate::app::Tool;

/// The letter that picks a tool (only the tools the model offers answer to it).
pub fn tool_key(t: Tool) -> Key {
    match t {
        Tool::Rope => Key::R,
        Tool::Force => Key::G,
        Tool::Fix => Key::H,
        Tool::Free => Key::U,
        Tool::Smooth => Key::S,
        Tool::Extrude => Key::E,
        Tool::DeleteCell => Key::D,
        Tool::SculptFace => Key::B,
        Tool::Paint => Key::P,
        Tool::ControlPoint => Key::C,
        Tool::FfdPoint => Key::M,
        Tool::PdeLocal => Key::L,
        Tool::Orbit => Key::O,
    }
}

/// Factor by which `[` and `]` shrink and grow the brush.
pub const BRUSH_STEP: f64 = 1.25;

/// The shortcuts that are not tool letters: (keys, what they do), in the help's order.
pub const SHORTCUTS: [(&str, &str); 20] = [
    ("F1 or ?", "this help (Esc closes it)"),
    ("Space", "run / pause the simulation"),
    ("F", "frame the model"),
    ("[  ]", "shrink / grow the brush"),
    (
        "X  Y  Z",
        "symmetry across x / y / z (through the model's centre)",
    ),
    (
        "K",
        "sculpt (what you pull stays) / elastic (it springs back)",
    ),
    ("1  3  7  0", "front / side / top / iso view"),
    ("W", "wireframe on / off"),
    ("N", "control net on / off"),
    ("Ctrl+Z", "undo (a whole stroke or drag is one step)"),
    ("Ctrl+Shift+Z, Ctrl+Y", "redo"),
    ("Ctrl+S", "save the session"),
    ("Ctrl+Shift+S", "save the session as (a new file)"),
    ("Ctrl+O", "open a file"),
    ("drag (empty space)", "orbit"),
    ("Shift+drag, middle drag", "pan"),
    ("wheel", "zoom"),
    ("double click", "frame the model (as F)"),
    (
        "Alt+drag (rope)",
        "move the rope's end along the view direction",
    ),
    (
        "Ctrl+click",
        "pin an FFD point / set a control point's weight",
    ),
];

/// The key's label as the help shows it.
pub fn key_label(k: Key) -> &'static str {
    k.name()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tool_keys_differ_from_each_other_and_from_the_other_shortcuts() {
        let taken = [
            Key::F,
            Key::K,
            Key::X,
            Key::Y,
            Key::Z,
            Key::W,
            Key::N,
            Key::Space,
        ];
        let mut seen = Vec::new();
        for t in Tool::ALL {
            let k = tool_key(t);
            assert!(!taken.contains(&k), "{t:?}: {k:?} is another shortcut");
            assert!(!seen.contains(&k), "{t:?}: {k:?} taken twice");
            seen.push(k);
        }
    }
}
