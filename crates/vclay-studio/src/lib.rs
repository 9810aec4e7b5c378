//! # vclay-studio
//!
//! The interactive studio (`vclay studio [FILE]`, binary `vclay-studio`): every model kind of
//! the session layer in a window with a 3D viewport, the papers' tools by mouse, live
//! parameters, undo/redo, session files, autosave and recovery.
//!
//! Layers: [`worker`] owns the [`vclay_session::Session`] on a simulation thread and is the only
//! code that touches models (through the session layer's commands); [`app`] is the UI (egui)
//! that sends requests and draws frames; [`render`] turns frames into GPU buffers and draws
//! them with OpenGL (eframe's glow backend, which Mesa's llvmpipe runs without a GPU);
//! [`camera`] is the orbit camera and the mouse ray; [`load`] opens files and the built-in
//! models; [`bench`] runs the frame loop headless; [`text`] rounds numbers in log lines;
//! [`native`] asks the desktop's file chooser; [`keys`] is the shortcut table (keys and the help overlay); [`pick`] finds the surface under
//! the mouse on the UI thread (brush circle, handles); [`symmetry`] mirrors tool actions.
//!
//! Limitations: one undo snapshot per cursor move (the session layer's undo records), so cursor
//! moves are coalesced ([`worker::DRAG_INTERVAL`]); file dialogs are the desktop's own where it
//! has a chooser program ([`native`]), else text fields.
#![warn(missing_docs)]

pub mod app;
pub mod bench;
pub mod camera;
pub mod keys;
pub mod load;
pub mod native;
pub mod pick;
pub mod recent;
pub mod render;
pub mod symmetry;
pub mod text;
pub mod worker;

pub use app::{Options, Studio, Tool};
