//! The engine's error type. A program around the engine wraps it in its own (vrao's
//! application adds its exit codes and its own failures).

use std::path::{Path, PathBuf};

/// Every failure the engine (and a renderer built on it) reports.
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
    /// A GPU operation failed while running (validation, lost device, readback).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// The frame graph could not plan a frame: a pass reads what nothing before it
    /// provides, or a requested output has no producer. A fault in vrao (or in a pass an
    /// embedder added), not in the input or the GPU.
    #[error("frame graph: {0}")]
    Plan(String),
    /// Building was cut short by the caller's cancellation token
    /// (`Gpu::cancel_builds_on`, of the renderer's face).
    #[error("interrupted")]
    Interrupted,
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
}

/// The engine's result type, with [`Error`] as the default error.
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
        assert_eq!(Error::Gpu("lost".into()).to_string(), "GPU error: lost");
        assert_eq!(Error::Plan("no producer".into()).to_string(), "frame graph: no producer");
    }
}
