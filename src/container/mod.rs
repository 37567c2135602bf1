//! The `.qcs` byte format (spec/format.md).

use thiserror::Error as ThisError;

/// A violation of the byte format.
#[derive(Debug, Clone, PartialEq, Eq, ThisError)]
#[non_exhaustive]
pub enum FormatError {
    /// The file does not start with the qcs magic.
    #[error("not a qcs file (bad magic)")]
    BadMagic,
}
