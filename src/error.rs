//! The application's error: the engine's (and renderer's) error, plus the failures only
//! the application has (a window or headset runtime that cannot be used, an output that
//! cannot be written, a run over its budget), each with its process exit code.

use std::path::{Path, PathBuf};

/// Exit code for bad input or an unusable device (clear error, never a panic).
pub const EXIT_INPUT: i32 = 2;
/// Exit code for a run that finished but did not fit its frame budget.
pub const EXIT_OVER_BUDGET: i32 = 3;
/// Exit code for a run ended by Ctrl-C (SIGINT): the shell's code for such a process.
pub const EXIT_INTERRUPTED: i32 = 130;

/// Every failure the application reports; each maps to a process exit code
/// ([`Error::exit_code`]).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The engine's or the renderer's error (bad input with its file and line, no usable
    /// GPU, a GPU failure, a frame graph fault, an interrupted build).
    #[error(transparent)]
    Engine(#[from] vrao_ao::Error),
    /// Something other than the GPU that a run needs cannot be used: a desktop window
    /// (no display), an OpenXR runtime (none installed, a broken manifest). Not the GPU's
    /// fault, so never called "no usable GPU"; the message names the cause.
    #[error("{0}")]
    Unavailable(String),
    /// Writing an output failed.
    #[error("{}: {message}", path.display())]
    Output {
        /// The file that could not be written.
        path: PathBuf,
        /// Why, as the OS or encoder said it.
        message: String,
    },
    /// The run finished but did not fit its frame budget (`vrao budget`).
    #[error("{0}")]
    OverBudget(String),
    /// The peer `vrao peer` compares with failed, hung, or wrote what it should not.
    #[error("the peer: {0}")]
    Peer(String),
}

impl Error {
    /// Malformed or missing input with no file to name.
    pub fn input(message: impl Into<String>) -> Self {
        Error::Engine(vrao_ao::Error::input(message))
    }
    /// Malformed input in `file`.
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        Error::Engine(vrao_ao::Error::in_file(file, message))
    }
    /// Malformed input at `line` (1-based) of `file`.
    pub fn at_line(file: &Path, line: usize, message: impl Into<String>) -> Self {
        Error::Engine(vrao_ao::Error::at_line(file, line, message))
    }
    /// A GPU operation failed while running.
    pub fn gpu(message: impl Into<String>) -> Self {
        Error::Engine(vrao_ao::Error::Gpu(message.into()))
    }
    /// No usable GPU (or none for what the run asks of it).
    pub fn device(message: impl Into<String>) -> Self {
        Error::Engine(vrao_ao::Error::Device(message.into()))
    }
    /// The engine's error inside, if this is one.
    pub fn engine(&self) -> Option<&vrao_ao::Error> {
        match self {
            Error::Engine(e) => Some(e),
            _ => None,
        }
    }
    /// Whether this is bad input (the engine's `Error::Input`).
    pub fn is_input(&self) -> bool {
        matches!(self, Error::Engine(vrao_ao::Error::Input { .. }))
    }
    /// The process exit code for this error: 2 bad input/device/output, 1 GPU failure, 3 over
    /// budget, 130 interrupted.
    pub fn exit_code(&self) -> i32 {
        use vrao_ao::Error as E;
        match self {
            // An output that cannot be written is the path the user gave (or its disk).
            Error::Engine(E::Input { .. } | E::Device(_)) | Error::Unavailable(_) | Error::Output { .. } => EXIT_INPUT,
            Error::Engine(E::Gpu(_) | E::Plan(_)) | Error::Peer(_) => 1,
            Error::OverBudget(_) => EXIT_OVER_BUDGET,
            Error::Engine(E::Interrupted) => EXIT_INTERRUPTED,
        }
    }
}

impl From<vrao_render::files::FileError> for Error {
    fn from(e: vrao_render::files::FileError) -> Self {
        Error::Engine(e.into())
    }
}

impl From<vrao_ao::InvalidFov> for Error {
    fn from(e: vrao_ao::InvalidFov) -> Self {
        Error::Engine(e.into())
    }
}

/// The application's result type, with [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_the_kind_of_failure_and_messages_stay_the_engines() {
        let f = Path::new("a/scene.toml");
        assert_eq!(Error::at_line(f, 3, "bad key").to_string(), "a/scene.toml:3: bad key");
        assert_eq!(Error::at_line(f, 3, "bad key").exit_code(), EXIT_INPUT);
        assert_eq!(Error::Unavailable("no display".into()).to_string(), "no display");
        assert_eq!(Error::Unavailable("no display".into()).exit_code(), EXIT_INPUT);
        assert_eq!(Error::from(vrao_ao::Error::Device("none".into())).exit_code(), EXIT_INPUT);
        assert_eq!(Error::gpu("lost").to_string(), "GPU error: lost");
        assert_eq!(Error::gpu("lost").exit_code(), 1);
        let out = Error::Output { path: PathBuf::from("o.png"), message: "denied".into() };
        assert_eq!((out.to_string().as_str(), out.exit_code()), ("o.png: denied", EXIT_INPUT));
        assert_eq!(Error::OverBudget("over".into()).exit_code(), EXIT_OVER_BUDGET);
        assert_eq!(Error::from(vrao_ao::Error::Interrupted).exit_code(), EXIT_INTERRUPTED);
    }
}
