//! The host's error: one line that names the problem.

use std::fmt;

/// An error the command line reports as one line and a non-zero exit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error(String);

impl Error {
    /// An error with this message (no trailing period, no newline).
    pub fn new(message: impl Into<String>) -> Self {
        let message: String = message.into();
        Self(message.replace('\n', " "))
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

/// Result with the host's error.
pub type Result<T> = std::result::Result<T, Error>;
