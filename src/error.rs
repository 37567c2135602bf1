//! The library's error type, split by who is to blame: the environment (I/O), the file
//! (format), the caller's limits, the caller's arguments, the caller's use of a stateful
//! object, and the machine's memory.
//!
//! A variant that wraps another error ([`Error::Io`], [`Error::Format`], [`Error::Limits`])
//! says only what kind of failure it is and gives the wrapped error as its
//! [`source`](std::error::Error::source): print the chain to see the whole story.
//!
//! ```
//! use std::error::Error as _;
//! let err = qcs::decode(b"qc\xE0", &Default::default()).unwrap_err();
//! assert_eq!(err.to_string(), "malformed file");
//! let cause = err.source().expect("the format error");
//! assert!(cause.to_string().starts_with("unsupported format version 7"), "{cause}");
//! ```

use thiserror::Error as ThisError;

/// Everything that can go wrong in qcs, by who is to blame.
#[derive(Debug, ThisError)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing failed. Blame: the environment (the reader or writer given).
    #[error("i/o error")]
    Io(#[from] std::io::Error),
    /// The file breaks the format (see `spec/format.md`). Blame: the file.
    #[error("malformed file")]
    Format(#[from] crate::container::FormatError),
    /// The file or request is valid but exceeds the configured [`crate::Limits`]. Blame:
    /// nobody's fault; the caller's limits refuse it.
    #[error("limit exceeded")]
    Limits(#[from] crate::limits::LimitError),
    /// The bytes given end inside the header: there is nothing to draw yet.
    ///
    /// Not an error in a streaming context: feed more bytes. It is an error only where no
    /// more will come (a one-shot [`crate::decode`] of a prefix that short); a caller who
    /// shows prefixes shows nothing, or a neutral picture, for it (the `qcs` command line
    /// draws neutral grey).
    #[error("the bytes given end inside the header: nothing to draw yet")]
    NeedMoreData,
    /// An argument the caller gave is outside what the function accepts: an option out of
    /// range, an empty output size, a buffer whose length does not match the image, a header
    /// the format forbids. Blame: the caller's arguments.
    #[error("invalid {name}: {value}, expected {expected}")]
    InvalidArgument {
        /// What the argument is, as the API names it (e.g. `"EncodeOptions::first_level"`,
        /// `"output size"`).
        name: &'static str,
        /// The value given.
        value: String,
        /// What would have been accepted.
        expected: String,
    },
    /// A stateful object was called out of turn: a
    /// `ContainerWriter` given a level, layer or profile
    /// it cannot take at that point (or finished early), a level decoder given bytes before
    /// its level began. Blame: the caller's code.
    #[error("{object}: {reason}")]
    Misuse {
        /// The object misused (e.g. `"ContainerWriter::write_layer"`).
        object: &'static str,
        /// What is out of turn.
        reason: String,
    },
    /// A parser or decoder was fed again after it returned an error: its first error poisons
    /// it for good, and that first error is the one to report. Blame: the caller's code.
    #[error("{object} used again after it returned an error")]
    Poisoned {
        /// The object (e.g. `"StreamDecoder"`).
        object: &'static str,
    },
    /// A request needs an allocation larger than the address space holds (e.g. a render of
    /// `u32::MAX × u32::MAX` pixels with [`crate::Limits::none`]). Blame: the request, for this
    /// machine.
    #[error("out of memory: {bytes} bytes needed")]
    OutOfMemory {
        /// The bytes the allocation needs (saturated at `u64::MAX`).
        bytes: u64,
    },
}

impl Error {
    /// An [`Error::InvalidArgument`].
    pub(crate) fn invalid(
        name: &'static str,
        value: impl std::fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidArgument {
            name,
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// An [`Error::Misuse`].
    pub(crate) fn misuse(object: &'static str, reason: impl Into<String>) -> Self {
        Error::Misuse {
            object,
            reason: reason.into(),
        }
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
