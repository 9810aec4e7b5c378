//! # vclay-session
//!
//! The session layer under every front end (`vclay run`, the studio, the Python module): a
//! [`Session`] holds named models of every kind vclay has behind one interface ([`Model`]),
//! applies edits as serializable [`Command`]s with undo and redo, saves and loads whole
//! sessions bit for bit ([`file`]), and reads the one scenario format ([`scenario`]): initial
//! models plus a timeline of commands.
//!
//! | kind | kernel | paper |
//! | --- | --- | --- |
//! | `dnurbs-curve`, `dnurbs-surface`, `dnurbs-swung` | `vclay_dynamics` | `d-nurbs.txt` sections 4-7 |
//! | `subdivision-solid`, `bspline-solid` | `vclay_solids` | `subdivision-solids-journal.txt` eqs 3-10 |
//! | `ffd` | `vclay_ffd` | `ffd-direct-manipulation.txt` eqs 7, 12 |
//! | `pde-surface` | `vclay_pde` | `dynamic-pde-surfaces.txt` eqs 1-5 |
//!
//! Limitations: the undo history is not saved in session files (the command log is); models in
//! one session do not interact.
#![warn(missing_docs)]

pub mod command;
pub mod describe;
pub mod error;
pub mod file;
pub mod limits;
pub mod model;
pub mod models;
pub mod open;
pub mod pick;
pub mod run;
pub mod scenario;
pub mod session;
mod smooth;
pub mod tools;

pub use command::{Command, Edit, PointMove, Selection};
pub use describe::{KeySpec, Target, ToolSpec};
pub use error::SessionError;
pub use model::{
    Applied, Element, Energy, FieldSpec, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray,
    Snapshot, StepReport, Undo,
};
pub use models::ModelSpec;
pub use open::{FileKind, Opened, open};
pub use session::{LogEntry, Session, Timed};
pub use vclay_core::Plasticity;
