//! The library's error type, by actor: I/O, the file, the caller's limits, the caller's parameters.

use thiserror::Error as ThisError;

/// Everything that can go wrong in qcs.
#[derive(Debug, ThisError)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing failed.
    #[error("i/o error: {0}")]
    Io(#[from] std::io::Error),
    /// The file breaks the format (see `spec/format.md`).
    #[error("malformed file: {0}")]
    Format(#[from] crate::container::FormatError),
    /// The file or request is valid but exceeds the configured [`crate::Limits`].
    #[error("limit exceeded: {0}")]
    Limits(#[from] crate::limits::LimitError),
    /// The bytes end inside the header: there is nothing to draw yet.
    #[error("need more data: the header is incomplete")]
    NeedMoreData,
    /// A parameter given by the caller is out of range.
    #[error("invalid parameter: {0}")]
    Parameter(String),
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
