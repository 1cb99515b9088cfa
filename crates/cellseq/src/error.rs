//! Library errors.

use thiserror::Error;

/// Everything that can go wrong in the library.
#[derive(Debug, Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{file}: {cause}")]
    Io {
        /// The file.
        file: String,
        /// The cause (shown in the message, not chained again as a `source`, so a report
        /// names it once).
        cause: std::io::Error,
    },
    /// A text file is malformed at a line.
    #[error("{file}:{line}: {msg}")]
    Parse {
        /// The file.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// The file parses but its content is not a valid instance or solution.
    #[error("{file}: {msg}")]
    Invalid {
        /// The file (or `<memory>`).
        file: String,
        /// What is wrong.
        msg: String,
    },
    /// An unknown solver name.
    #[error("unknown solver '{name}' (known: {known})")]
    UnknownSolver {
        /// The name asked for.
        name: String,
        /// Comma-separated list of known solvers.
        known: String,
    },
    /// A bad solver or generator parameter.
    #[error("{0}")]
    Param(String),
    /// A solver gave up (memory limit, unsupported instance, …).
    #[error("solver '{solver}': {msg}")]
    Solver {
        /// The solver.
        solver: String,
        /// Why.
        msg: String,
    },
}

impl Error {
    /// An [`Error::Invalid`] for a file.
    pub fn invalid(file: impl Into<String>, msg: impl Into<String>) -> Error {
        Error::Invalid {
            file: file.into(),
            msg: msg.into(),
        }
    }
    /// An [`Error::Parse`] at a line.
    pub fn parse(file: impl Into<String>, line: usize, msg: impl Into<String>) -> Error {
        Error::Parse {
            file: file.into(),
            line,
            msg: msg.into(),
        }
    }
    /// An [`Error::Io`].
    pub fn io(file: impl Into<String>, cause: std::io::Error) -> Error {
        Error::Io {
            file: file.into(),
            cause,
        }
    }
}

/// Library result.
pub type Result<T> = std::result::Result<T, Error>;
