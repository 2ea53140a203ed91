//! One error type for the library; the CLI maps it to exit codes.

use std::path::{Path, PathBuf};

/// Exit code for bad input or an unusable device (clear error, never a panic).
pub const EXIT_INPUT: i32 = 2;
/// Exit code for a run that finished but did not fit its frame budget.
pub const EXIT_OVER_BUDGET: i32 = 3;
/// Exit code for a run ended by Ctrl-C (SIGINT): the shell's code for such a process.
pub const EXIT_INTERRUPTED: i32 = 130;

/// Every failure vrao reports; each maps to a process exit code ([`Error::exit_code`]).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed or missing input. `file` and `line` name the place when known.
    #[error("{}", place(file.as_deref(), *line, message))]
    Input {
        /// The file the input came from, when there was one.
        file: Option<PathBuf>,
        /// The 1-based line in `file`, when known.
        line: Option<usize>,
        /// What is wrong, for the user.
        message: String,
    },
    /// No usable GPU adapter or device.
    #[error("no usable GPU: {0}")]
    Device(String),
    /// Something other than the GPU that a run needs cannot be used: a desktop window
    /// (no display), an OpenXR runtime (none installed, a broken manifest). Not the GPU's
    /// fault, so never called "no usable GPU"; the message names the cause.
    #[error("{0}")]
    Unavailable(String),
    /// A GPU operation failed while running (validation, lost device, readback).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// Writing an output failed.
    #[error("{}: {message}", path.display())]
    Output {
        /// The file that could not be written.
        path: PathBuf,
        /// Why, as the OS or encoder said it.
        message: String,
    },
    /// The frame graph could not plan a frame: a pass reads what nothing before it
    /// provides, or a requested output has no producer. A fault in vrao (or in a pass an
    /// embedder added), not in the input or the GPU.
    #[error("frame graph: {0}")]
    Plan(String),
    /// Building was cut short by the caller's cancellation token
    /// ([`crate::gpu::Gpu::cancel_builds_on`]).
    #[error("interrupted")]
    Interrupted,
    /// The run finished but did not fit its frame budget (`vrao budget`).
    #[error("{0}")]
    OverBudget(String),
}

/// "file:line: message", "file: message" or "message", as much as is known.
fn place(file: Option<&Path>, line: Option<usize>, message: &str) -> String {
    match (file, line) {
        (Some(file), Some(line)) => format!("{}:{line}: {message}", file.display()),
        (Some(file), None) => format!("{}: {message}", file.display()),
        (None, _) => message.to_string(),
    }
}

impl Error {
    /// Malformed or missing input with no file to name.
    pub fn input(message: impl Into<String>) -> Self {
        Error::Input { file: None, line: None, message: message.into() }
    }
    /// Malformed input in `file`.
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        Error::Input { file: Some(file.to_path_buf()), line: None, message: message.into() }
    }
    /// Malformed input at `line` (1-based) of `file`.
    pub fn at_line(file: &Path, line: usize, message: impl Into<String>) -> Self {
        Error::Input { file: Some(file.to_path_buf()), line: Some(line), message: message.into() }
    }
    /// The process exit code for this error: 2 bad input/device/output, 1 GPU failure, 3 over
    /// budget, 130 interrupted.
    pub fn exit_code(&self) -> i32 {
        match self {
            // An output that cannot be written is the path the user gave (or its disk).
            Error::Input { .. } | Error::Device(_) | Error::Unavailable(_) | Error::Output { .. } => EXIT_INPUT,
            Error::Gpu(_) | Error::Plan(_) => 1,
            Error::OverBudget(_) => EXIT_OVER_BUDGET,
            Error::Interrupted => EXIT_INTERRUPTED,
        }
    }
}

/// vrao's result type, with [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_place_when_known() {
        let f = Path::new("a/scene.toml");
        assert_eq!(Error::at_line(f, 3, "bad key").to_string(), "a/scene.toml:3: bad key");
        assert_eq!(Error::in_file(f, "missing").to_string(), "a/scene.toml: missing");
        assert_eq!(Error::input("plain").to_string(), "plain");
        assert_eq!(Error::Device("none".into()).to_string(), "no usable GPU: none");
        assert_eq!(Error::Unavailable("no display".into()).to_string(), "no display");
        assert_eq!(Error::Unavailable("no display".into()).exit_code(), EXIT_INPUT);
        assert_eq!(Error::Gpu("lost".into()).to_string(), "GPU error: lost");
        let out = Error::Output { path: PathBuf::from("o.png"), message: "denied".into() };
        assert_eq!(out.to_string(), "o.png: denied");
        assert_eq!(Error::OverBudget("over".into()).to_string(), "over");
    }
}
