//! The error type of the session layer.

/// A kernel error kept as the cause of a [`SessionError`] (`std::error::Error::source`).
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Everything that can go wrong in a session: a command that cannot apply, a model error, a
/// file that cannot be read. Every variant names the place (command, model, file and line).
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// A command cannot apply; the session is unchanged.
    #[error("command `{command}` on model `{model}`: {reason}")]
    Command {
        /// The command's name (its `action`).
        command: String,
        /// The model it was addressed to.
        model: String,
        /// Why it cannot apply.
        reason: String,
        /// The kernel error behind `reason`, if one is.
        #[source]
        source: Option<Cause>,
    },
    /// No model of that name.
    #[error("no model named `{name}` (the session has: {known})")]
    NoSuchModel {
        /// The name given.
        name: String,
        /// The models' names, comma separated.
        known: String,
    },
    /// A model of the kernel failed (building, stepping, exporting).
    #[error("model `{model}`: {what}")]
    Model {
        /// The model's name ("" while it is being built).
        model: String,
        /// The kernel's message.
        what: String,
        /// The kernel error behind `what`, if one is.
        #[source]
        source: Option<Cause>,
    },
    /// The simulation diverged; the model is left at its last good state.
    #[error("model `{model}` diverged: {what}")]
    Diverged {
        /// The model's name.
        model: String,
        /// The kernel's message (step, reason, suggested time step).
        what: String,
        /// The kernel's divergence error.
        #[source]
        source: Option<Cause>,
    },
    /// A scenario or session file is invalid: file, line (0 when unknown), key, message.
    #[error("{file}:{line}: {key}: {what}")]
    File {
        /// File name as given.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key or entry at fault.
        key: String,
        /// What is wrong.
        what: String,
    },
    /// Work over a limit, refused before it started (a run's energy table and frame list
    /// over the memory limit).
    #[error("{0}")]
    OverLimit(#[from] crate::limits::OverLimit),
    /// Reading or writing a file failed.
    #[error("{path}: {what}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        what: String,
        /// The I/O or format error behind `what`, if one is.
        #[source]
        source: Option<Cause>,
    },
    /// A file vclay reads, but not as a session: what it is and which commands take it.
    #[error("{path}: {what}, not a session; use {commands}")]
    NotASession {
        /// The path.
        path: String,
        /// What the file is ("a point cloud").
        what: String,
        /// The commands that take it.
        commands: String,
    },
    /// Nothing to undo or redo.
    #[error("nothing to {0}")]
    History(&'static str),
}

impl SessionError {
    /// A command error.
    pub fn command(
        command: impl Into<String>,
        model: impl Into<String>,
        reason: impl std::fmt::Display,
    ) -> Self {
        SessionError::Command {
            command: command.into(),
            model: model.into(),
            reason: reason.to_string(),
            source: None,
        }
    }

    /// A command error caused by a kernel error `e` (kept as the source).
    pub fn command_from<E: std::error::Error + Send + Sync + 'static>(e: E) -> Self {
        SessionError::Command {
            command: String::new(),
            model: String::new(),
            reason: e.to_string(),
            source: Some(Box::new(e)),
        }
    }

    /// A model error caused by a kernel error `e` (kept as the source; the session fills in
    /// the model name).
    pub fn kernel<E: std::error::Error + Send + Sync + 'static>(e: E) -> Self {
        SessionError::Model {
            model: String::new(),
            what: e.to_string(),
            source: Some(Box::new(e)),
        }
    }

    /// The same error addressed to command `command` on model `model` (a model's refusal of
    /// an edit, or any other error while applying it), keeping its cause.
    pub fn in_command(self, command: &str, model: &str) -> Self {
        match self {
            SessionError::Command { reason, source, .. } => SessionError::Command {
                command: command.to_string(),
                model: model.to_string(),
                reason,
                source,
            },
            other => SessionError::Command {
                command: command.to_string(),
                model: model.to_string(),
                reason: other.to_string(),
                source: Some(Box::new(other)),
            },
        }
    }

    /// A model error (the session fills in the model name where it knows it).
    pub fn model(what: impl std::fmt::Display) -> Self {
        SessionError::Model {
            model: String::new(),
            what: what.to_string(),
            source: None,
        }
    }

    /// The same error with the model's name filled in where it was left empty.
    pub fn in_model(self, name: &str) -> Self {
        match self {
            SessionError::Model {
                model,
                what,
                source,
            } if model.is_empty() => SessionError::Model {
                model: name.to_string(),
                what,
                source,
            },
            SessionError::Command {
                command,
                model,
                reason,
                source,
            } if model.is_empty() => SessionError::Command {
                command,
                model: name.to_string(),
                reason,
                source,
            },
            SessionError::Diverged {
                model,
                what,
                source,
            } if model.is_empty() => SessionError::Diverged {
                model: name.to_string(),
                what,
                source,
            },
            e => e,
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path, what: impl std::fmt::Display) -> Self {
        SessionError::Io {
            path: path.display().to_string(),
            what: what.to_string(),
            source: None,
        }
    }

    /// An I/O or format error `e` on `path` (kept as the source).
    pub fn io_from<E: std::error::Error + Send + Sync + 'static>(
        path: &std::path::Path,
        e: E,
    ) -> Self {
        SessionError::Io {
            path: path.display().to_string(),
            what: e.to_string(),
            source: Some(Box::new(e)),
        }
    }
}

impl SessionError {
    /// A divergence reported by a kernel (kept as the source).
    pub fn diverged<E: std::error::Error + Send + Sync + 'static>(e: E) -> Self {
        SessionError::Diverged {
            model: String::new(),
            what: e.to_string(),
            source: Some(Box::new(e)),
        }
    }
}

impl From<vclay_dynamics::DynamicsError> for SessionError {
    /// Divergence stays divergence; any other D-NURBS error is a model error. Both keep the
    /// kernel error as the source.
    fn from(e: vclay_dynamics::DynamicsError) -> Self {
        match e {
            vclay_dynamics::DynamicsError::Diverged { .. } => SessionError::diverged(e),
            e => SessionError::kernel(e),
        }
    }
}

impl From<vclay_solids::SolidsError> for SessionError {
    /// As for [`vclay_dynamics::DynamicsError`].
    fn from(e: vclay_solids::SolidsError) -> Self {
        match e {
            vclay_solids::SolidsError::Diverged { .. } => SessionError::diverged(e),
            e => SessionError::kernel(e),
        }
    }
}
