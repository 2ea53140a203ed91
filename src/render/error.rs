//! One error type for the library; the CLI maps it to exit codes.

use std::fmt;
use std::path::{Path, PathBuf};

/// Exit code for bad input or an unusable device (clear error, never a panic).
pub const EXIT_INPUT: i32 = 2;
/// Exit code for a run that finished but did not fit its frame budget.
pub const EXIT_OVER_BUDGET: i32 = 3;

#[derive(Debug)]
pub enum Error {
    /// Malformed or missing input. `file` and `line` name the place when known.
    Input { file: Option<PathBuf>, line: Option<usize>, message: String },
    /// No usable GPU adapter or device.
    Device(String),
    /// A GPU operation failed while running (validation, lost device, readback).
    Gpu(String),
    /// Writing an output failed.
    Output { path: PathBuf, message: String },
    /// The run finished but did not fit its frame budget (`vrao budget`).
    OverBudget(String),
}

impl Error {
    pub fn input(message: impl Into<String>) -> Self {
        Error::Input { file: None, line: None, message: message.into() }
    }
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        Error::Input { file: Some(file.to_path_buf()), line: None, message: message.into() }
    }
    pub fn at_line(file: &Path, line: usize, message: impl Into<String>) -> Self {
        Error::Input { file: Some(file.to_path_buf()), line: Some(line), message: message.into() }
    }
    pub fn exit_code(&self) -> i32 {
        match self {
            // An output that cannot be written is the path the user gave (or its disk).
            Error::Input { .. } | Error::Device(_) | Error::Output { .. } => EXIT_INPUT,
            Error::Gpu(_) => 1,
            Error::OverBudget(_) => EXIT_OVER_BUDGET,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input { file: Some(file), line: Some(line), message } => {
                write!(f, "{}:{}: {}", file.display(), line, message)
            }
            Error::Input { file: Some(file), line: None, message } => {
                write!(f, "{}: {}", file.display(), message)
            }
            Error::Input { file: None, message, .. } => write!(f, "{message}"),
            Error::Device(m) => write!(f, "no usable GPU: {m}"),
            Error::Gpu(m) => write!(f, "GPU error: {m}"),
            Error::Output { path, message } => write!(f, "{}: {}", path.display(), message),
            Error::OverBudget(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T, E = Error> = std::result::Result<T, E>;
