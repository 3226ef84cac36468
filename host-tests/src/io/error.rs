//! Errors of bad input: a file, a line and a reason (exit status 1 in the command line).

use std::path::Path;

/// Bad input: which file, which line (if any), and why.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// A problem at a line of a file.
    #[error("{file}:{line}: {reason}")]
    At {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A problem with a whole file.
    #[error("{file}: {reason}")]
    File {
        /// File name.
        file: String,
        /// What is wrong.
        reason: String,
    },
}

impl InputError {
    /// An error at a line.
    pub fn at(file: &str, line: usize, reason: impl Into<String>) -> InputError {
        InputError::At { file: file.to_string(), line, reason: reason.into() }
    }

    /// An error about a whole file.
    pub fn file(file: &str, reason: impl Into<String>) -> InputError {
        InputError::File { file: file.to_string(), reason: reason.into() }
    }

    /// An I/O error on a path.
    pub fn io(path: &Path, e: std::io::Error) -> InputError {
        InputError::file(&path.display().to_string(), e.to_string())
    }
}
