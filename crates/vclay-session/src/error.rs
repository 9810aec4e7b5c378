//! The error type of the session layer.

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
    },
    /// The simulation diverged; the model is left at its last good state.
    #[error("model `{model}` diverged: {what}")]
    Diverged {
        /// The model's name.
        model: String,
        /// The kernel's message (step, reason, suggested time step).
        what: String,
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
    /// Reading or writing a file failed.
    #[error("{path}: {what}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        what: String,
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
        }
    }

    /// A model error (the session fills in the model name where it knows it).
    pub fn model(what: impl std::fmt::Display) -> Self {
        SessionError::Model {
            model: String::new(),
            what: what.to_string(),
        }
    }

    /// The same error with the model's name filled in where it was left empty.
    pub fn in_model(self, name: &str) -> Self {
        match self {
            SessionError::Model { model, what } if model.is_empty() => SessionError::Model {
                model: name.to_string(),
                what,
            },
            SessionError::Command {
                command,
                model,
                reason,
            } if model.is_empty() => SessionError::Command {
                command,
                model: name.to_string(),
                reason,
            },
            SessionError::Diverged { model, what } if model.is_empty() => SessionError::Diverged {
                model: name.to_string(),
                what,
            },
            e => e,
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path, what: impl std::fmt::Display) -> Self {
        SessionError::Io {
            path: path.display().to_string(),
            what: what.to_string(),
        }
    }
}
