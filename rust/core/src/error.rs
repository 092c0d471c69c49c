//! Errors of the core crate.
//!
//! One [`enum@Error`] for everything that can go wrong in the core; every variant names the
//! field or argument and the value at fault. The Python binding maps each variant to one
//! exception class (all `ValueError` subclasses), the CLI prints it to stderr.

use std::path::PathBuf;

/// Everything that can go wrong in the core.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scenario field holds a value that makes no sense.
    #[error("invalid scenario: field `{field}` = {value}: {reason}")]
    InvalidScenario {
        /// Dotted path of the field, e.g. `rewards.step_penalty`.
        field: String,
        /// The offending value, as written.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The scenario text is not valid JSON or does not match the schema
    /// (unknown field, wrong type, missing field).
    #[error("scenario could not be parsed: {0}")]
    ScenarioParse(String),
    /// No scenario file and no built-in scenario has that name.
    #[error(
        "scenario `{name}` not found: not a file, not generated:SEED, and not one of the built-in scenarios ({known})"
    )]
    ScenarioNotFound {
        /// The name or path asked for.
        name: String,
        /// Comma-separated list of built-in names.
        known: String,
    },
    /// A function argument is out of its domain.
    #[error("invalid argument `{name}` = {value}: {reason}")]
    InvalidArgument {
        /// Argument name.
        name: String,
        /// The offending value.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// A saved Q-table does not fit the scenario it is loaded for.
    #[error("Q-table does not match: {0}")]
    QTableMismatch(String),
    /// Reading or writing a file failed.
    #[error("I/O error on `{path}`: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidScenario`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl ToString,
        reason: impl Into<String>,
    ) -> Self {
        Error::InvalidScenario {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`Error::InvalidArgument`].
    pub fn argument(
        name: impl Into<String>,
        value: impl ToString,
        reason: impl Into<String>,
    ) -> Self {
        Error::InvalidArgument {
            name: name.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// Result alias of the core crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
